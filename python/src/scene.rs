//! `cablevib.Scene`: a validated robot description, read-only from Python.

use crate::convert::{array1, array2, vector3};
use crate::error::CablevibError;
use cablevib::scene::Scene;
use pyo3::prelude::*;
use std::path::PathBuf;

/// A validated robot description (SI units throughout), read-only.
///
/// Load one with ``Scene.load("spatial-paper")`` (the names the command line accepts:
/// ``spatial-paper``, ``planar-paper`` or a path to a scene TOML file) or
/// ``Scene.from_toml(text)``.
#[pyclass(name = "Scene", module = "cablevib", frozen)]
#[derive(Clone)]
pub struct PyScene {
    pub inner: Scene,
}

#[pymethods]
impl PyScene {
    /// Load a scene: a path to a scene TOML file (``str`` or ``os.PathLike``), or one of the
    /// embedded names ``spatial-paper`` (also ``spatial``, ``default``) and
    /// ``planar-paper`` (also ``planar``), exactly as the command line's ``SCENE``.
    ///
    /// Raises CablevibError with the command line's message when the file is missing,
    /// unreadable or invalid.
    #[staticmethod]
    fn load(path_or_name: PathBuf) -> PyResult<PyScene> {
        let name = path_or_name.to_str().ok_or_else(|| {
            CablevibError::new_err(format!(
                "{}: the path is not valid UTF-8",
                path_or_name.display()
            ))
        })?;
        let inner = Scene::load(name).map_err(|e| CablevibError::new_err(e.to_string()))?;
        Ok(PyScene { inner })
    }

    /// Parse a scene from TOML text; ``source`` names it in error messages.
    #[staticmethod]
    #[pyo3(signature = (text, source = "<string>"))]
    fn from_toml(text: &str, source: &str) -> PyResult<PyScene> {
        let inner = Scene::from_toml_str(text, source)
            .map_err(|e| CablevibError::new_err(e.to_string()))?;
        Ok(PyScene { inner })
    }

    /// Scene name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }

    /// Number of cables.
    #[getter]
    fn n_cables(&self) -> usize {
        self.inner.n_cables()
    }

    /// Cable element model: ``fem``, ``catenary``, ``continuous``, ``massless`` or ``auto``.
    #[getter]
    fn element(&self) -> &'static str {
        self.inner.model.element.as_str()
    }

    /// Elements per cable (FEM and catenary models).
    #[getter]
    fn elements(&self) -> usize {
        self.inner.model.elements_per_cable
    }

    /// Lower tension bound T_min, N (the default of every cable without its own).
    #[getter]
    fn t_min_n(&self) -> f64 {
        self.inner.t_min_n
    }

    /// Upper tension bound T_max, N (the default of every cable without its own).
    #[getter]
    fn t_max_n(&self) -> f64 {
        self.inner.t_max_n
    }

    /// Each cable's lower tension bound, N, shape (n_cables,).
    #[getter]
    fn cable_t_min_n<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let s = &self.inner;
        let v: Vec<f64> = (0..s.n_cables()).map(|i| s.cable_t_min_n(i)).collect();
        array1(py, &v)
    }

    /// Each cable's upper tension bound, N, shape (n_cables,).
    #[getter]
    fn cable_t_max_n<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let s = &self.inner;
        let v: Vec<f64> = (0..s.n_cables()).map(|i| s.cable_t_max_n(i)).collect();
        array1(py, &v)
    }

    /// Default end-effector position, m, shape (3,).
    #[getter]
    fn ee_position_m<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        vector3(py, &self.inner.ee_position_m)
    }

    /// Default end-effector orientation, unit quaternion [w, x, y, z], shape (4,).
    #[getter]
    fn ee_orientation_wxyz<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        array1(py, &self.inner.ee_orientation_wxyz)
    }

    /// End-effector mass, kg.
    #[getter]
    fn ee_mass_kg(&self) -> f64 {
        self.inner.ee_mass_kg
    }

    /// Gravity vector, m/s², shape (3,).
    #[getter]
    fn gravity_m_s2<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        vector3(py, &self.inner.gravity_m_s2)
    }

    /// Whether the cables carry the end-effector's weight (wrench m·g) or not (zero).
    #[getter]
    fn weight_carried(&self) -> bool {
        self.inner.weight_carried
    }

    /// Rigid-body end-effector (6 DOF) rather than a point mass.
    #[getter]
    fn rigid(&self) -> bool {
        self.inner.rigid
    }

    /// Cable anchors on the frame, m, shape (n_cables, 3).
    #[getter]
    fn anchors_m<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let rows: Vec<Vec<f64>> = self
            .inner
            .cables
            .iter()
            .map(|c| c.anchor_m.iter().copied().collect())
            .collect();
        array2(py, &rows)
    }

    /// Smallest end-effector participation (0 < x ≤ 1) of the "end-effector mode".
    #[getter]
    fn ee_participation_min(&self) -> f64 {
        self.inner.model.ee_participation_min
    }

    /// Relative f1 error the ``auto`` model may make.
    #[getter]
    fn f1_tolerance(&self) -> f64 {
        self.inner.model.f1_tolerance
    }

    fn __repr__(&self) -> String {
        let s = &self.inner;
        let p = s.ee_position_m;
        format!(
            "Scene(name={:?}, n_cables={}, element={:?}, elements={}, t_min_n={}, t_max_n={}, ee_position_m=[{}, {}, {}])",
            s.name,
            s.n_cables(),
            s.model.element.as_str(),
            s.model.elements_per_cable,
            s.t_min_n,
            s.t_max_n,
            p.x,
            p.y,
            p.z
        )
    }
}
