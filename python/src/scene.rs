//! `cablevib.Scene`: a validated robot description, read-only from Python.

use crate::convert::{array1, array2, vector3};
use crate::error::CablevibError;
use cablevib::scene::Scene;
use pyo3::exceptions::PyValueError;
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
    /// Where the scene came from, so that it pickles (None: it cannot).
    pub origin: Option<Origin>,
}

/// What rebuilds a scene in another process: an embedded name, or TOML text and the name
/// of its source.
#[derive(Clone)]
pub enum Origin {
    /// `Scene.load(name)` of an embedded scene.
    Embedded(String),
    /// `Scene.from_toml(text, source)`.
    Toml { text: String, source: String },
}

impl PyScene {
    /// A scene from TOML text, remembered so that it pickles.
    pub fn from_text(text: String, source: String) -> PyResult<PyScene> {
        let inner = Scene::from_toml_str(&text, &source)
            .map_err(|e| CablevibError::new_err(e.to_string()))?;
        Ok(PyScene {
            inner,
            origin: Some(Origin::Toml { text, source }),
        })
    }
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
        // A file's text (read again: `Scene::load` read and validated it just now) so that
        // the scene pickles to a process without the file; an embedded scene by its name.
        let origin = if matches!(path_or_name.try_exists(), Ok(true)) {
            std::fs::read_to_string(&path_or_name)
                .ok()
                .map(|text| Origin::Toml {
                    text,
                    source: path_or_name.display().to_string(),
                })
        } else {
            Some(Origin::Embedded(name.to_string()))
        };
        Ok(PyScene { inner, origin })
    }

    /// Parse a scene from TOML text; ``source`` names it in error messages.
    #[staticmethod]
    #[pyo3(signature = (text, source = "<string>".to_string()))]
    fn from_toml(text: String, source: String) -> PyResult<PyScene> {
        PyScene::from_text(text, source)
    }

    /// A scene from arrays, for a design loop that writes no files: ``anchors_m`` (n × 3,
    /// m), ``attachments_m`` (n × 3, m, in the end-effector frame; rigid end-effectors),
    /// ``ee_mass_kg``, ``ee_position_m`` (3), and the optional scene-file keys
    /// (docs/model.md): ``gravity_m_s2`` (default [0, 0, -9.81]), ``ee_orientation_wxyz``,
    /// ``ee_inertia_kg_m2`` (3 × 3), ``weight_carried``, the cable material
    /// ``youngs_modulus_pa``, ``area_m2``, ``weight_per_length_n_m``,
    /// ``mass_per_length_kg_m`` (each one number for every cable or n numbers, one per
    /// cable), ``t_min_n``, ``t_max_n`` (N, every cable's), ``cable_t_min_n``,
    /// ``cable_t_max_n`` (n numbers, one per cable), ``element`` (default ``fem``),
    /// ``elements``, ``ee_participation_min``, ``f1_tolerance``, ``sag``, ``rotation``,
    /// ``geometric_stiffness``, ``cable_mass``.
    ///
    /// The arrays are written as a scene file's TOML text (``Scene.toml``), which is then
    /// read and validated as a scene file is: a value that cannot be built (NaN, too few
    /// cables, a bound out of range, …) raises CablevibError with the message a scene file
    /// with those values gives (its source named ``source``; ``cables[i].anchor`` is row i
    /// of ``anchors_m``); a required argument left out (``t_min_n``) or of the wrong type
    /// (a string for a number, an unknown ``element``) raises CablevibError naming the
    /// argument. An argument with the wrong number of rows (0 rows of ``anchors_m``)
    /// raises ValueError.
    #[staticmethod]
    #[pyo3(signature = (anchors_m, ee_mass_kg, ee_position_m, *, attachments_m = None,
        name = "from-arrays", gravity_m_s2 = None, ee_orientation_wxyz = None,
        ee_inertia_kg_m2 = None, weight_carried = None, youngs_modulus_pa = None,
        area_m2 = None, weight_per_length_n_m = None, mass_per_length_kg_m = None,
        t_min_n = None, t_max_n = None, cable_t_min_n = None, cable_t_max_n = None,
        element = "fem", elements = None, ee_participation_min = None, f1_tolerance = None,
        sag = None, rotation = None, geometric_stiffness = None, cable_mass = None,
        source = "<arrays>"))]
    #[allow(clippy::too_many_arguments)]
    fn from_arrays(
        anchors_m: &Bound<'_, PyAny>,
        ee_mass_kg: &Bound<'_, PyAny>,
        ee_position_m: &Bound<'_, PyAny>,
        attachments_m: Option<&Bound<'_, PyAny>>,
        name: &str,
        gravity_m_s2: Option<&Bound<'_, PyAny>>,
        ee_orientation_wxyz: Option<&Bound<'_, PyAny>>,
        ee_inertia_kg_m2: Option<&Bound<'_, PyAny>>,
        weight_carried: Option<&Bound<'_, PyAny>>,
        youngs_modulus_pa: Option<&Bound<'_, PyAny>>,
        area_m2: Option<&Bound<'_, PyAny>>,
        weight_per_length_n_m: Option<&Bound<'_, PyAny>>,
        mass_per_length_kg_m: Option<&Bound<'_, PyAny>>,
        t_min_n: Option<&Bound<'_, PyAny>>,
        t_max_n: Option<&Bound<'_, PyAny>>,
        cable_t_min_n: Option<&Bound<'_, PyAny>>,
        cable_t_max_n: Option<&Bound<'_, PyAny>>,
        element: &str,
        elements: Option<&Bound<'_, PyAny>>,
        ee_participation_min: Option<&Bound<'_, PyAny>>,
        f1_tolerance: Option<&Bound<'_, PyAny>>,
        sag: Option<&Bound<'_, PyAny>>,
        rotation: Option<&Bound<'_, PyAny>>,
        geometric_stiffness: Option<&Bound<'_, PyAny>>,
        cable_mass: Option<&Bound<'_, PyAny>>,
        source: &str,
    ) -> PyResult<PyScene> {
        use crate::toml_text::{rows, value, Table};
        let anchors = rows(anchors_m, "anchors_m")?;
        let n = anchors.len();
        if n == 0 {
            return Err(PyValueError::new_err(
                "anchors_m: 0 rows: one row (x, y, z in m) per cable",
            ));
        }
        let per_cable = |obj: Option<&Bound<'_, PyAny>>, what: &str| match obj {
            None => Ok(None),
            Some(o) => {
                let r = rows(o, what)?;
                if r.len() != n {
                    return Err(PyValueError::new_err(format!(
                        "{what}: {} values for {n} cables (anchors_m rows)",
                        r.len()
                    )));
                }
                Ok(Some(r))
            }
        };
        let attachments = per_cable(attachments_m, "attachments_m")?;
        let mut top = Table::new("");
        top.raw(
            "name",
            serde_json::to_string(name).map_err(|e| PyValueError::new_err(e.to_string()))?,
        );
        let g = match gravity_m_s2 {
            Some(g) => value(g)?,
            None => "[0.0, 0.0, -9.81]".to_string(),
        };
        top.raw("gravity", g);
        let mut ee = Table::new("end_effector");
        ee.set("mass", Some(ee_mass_kg))?;
        ee.set("position", Some(ee_position_m))?;
        ee.set("orientation", ee_orientation_wxyz)?;
        ee.set("inertia", ee_inertia_kg_m2)?;
        ee.set("weight_carried", weight_carried)?;
        let mut cable = Table::new("cable");
        // A material given as one number is every cable's default; n numbers go per cable.
        let material = [
            ("youngs_modulus", youngs_modulus_pa, "youngs_modulus_pa"),
            ("area", area_m2, "area_m2"),
            (
                "weight_per_length",
                weight_per_length_n_m,
                "weight_per_length_n_m",
            ),
            (
                "mass_per_length",
                mass_per_length_kg_m,
                "mass_per_length_kg_m",
            ),
        ];
        let mut cable_columns = Vec::new();
        for (key, obj, what) in material {
            match obj {
                Some(o) if crate::toml_text::is_sequence(o) => {
                    cable_columns.push((key, per_cable(Some(o), what)?.unwrap_or_default()))
                }
                o => cable.set(key, o)?,
            }
        }
        for (key, obj, what) in [
            ("t_min", cable_t_min_n, "cable_t_min_n"),
            ("t_max", cable_t_max_n, "cable_t_max_n"),
        ] {
            if let Some(r) = per_cable(obj, what)? {
                cable_columns.push((key, r));
            }
        }
        let mut tension = Table::new("tension");
        tension.set("t_min", t_min_n)?;
        tension.set("t_max", t_max_n)?;
        let mut model = Table::new("model");
        model.raw(
            "element",
            serde_json::to_string(element).map_err(|e| PyValueError::new_err(e.to_string()))?,
        );
        model.set("elements_per_cable", elements)?;
        model.set("ee_participation_min", ee_participation_min)?;
        model.set("f1_tolerance", f1_tolerance)?;
        let mut effects = Table::new("effects");
        effects.set("geometric_stiffness", geometric_stiffness)?;
        effects.set("cable_mass", cable_mass)?;
        effects.set("sag", sag)?;
        effects.set("rotation", rotation)?;
        let mut text = top.text();
        for t in [ee, cable, tension, model, effects] {
            if !t.is_empty() || ["end_effector", "cable", "tension", "model"].contains(&t.name) {
                text.push_str(&t.text());
            }
        }
        for (i, a) in anchors.iter().enumerate() {
            text.push_str(&format!("\n[[cables]]\nanchor = {a}\n"));
            if let Some(att) = &attachments {
                text.push_str(&format!("attachment = {}\n", att[i]));
            }
            for (key, col) in &cable_columns {
                text.push_str(&format!("{key} = {}\n", col[i]));
            }
        }
        match Scene::from_toml_str(&text, source) {
            Ok(inner) => Ok(PyScene {
                inner,
                origin: Some(Origin::Toml {
                    text,
                    source: source.to_string(),
                }),
            }),
            Err(e) => Err(CablevibError::new_err(from_arrays_message(&e, source))),
        }
    }

    /// The TOML text this scene was read from (a scene file's, ``from_toml``'s, or what
    /// ``from_arrays`` wrote); None for an embedded scene loaded by name.
    #[getter]
    fn toml(&self) -> Option<String> {
        match &self.origin {
            Some(Origin::Toml { text, .. }) => Some(text.clone()),
            _ => None,
        }
    }

    /// Pickling: an embedded scene by its name, any other by its TOML text (so it crosses
    /// process boundaries, e.g. to a Dask worker, without its file).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let py = slf.py();
        let cls = slf.get_type();
        match &slf.get().origin {
            Some(Origin::Embedded(name)) => Ok((
                cls.getattr("load")?,
                (name.clone(),).into_pyobject(py)?.into_any(),
            )),
            Some(Origin::Toml { text, source }) => Ok((
                cls.getattr("from_toml")?,
                (text.clone(), source.clone()).into_pyobject(py)?.into_any(),
            )),
            None => Err(pyo3::exceptions::PyTypeError::new_err(
                "this scene cannot be pickled: its file could not be read again",
            )),
        }
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

/// The argument of `Scene.from_arrays` that a scene-file key was written from
/// (`cables[2].anchor` → `anchors_m[2]`), `None` for a key it does not write.
fn argument_of(key: &str) -> Option<String> {
    let (head, leaf) = key.split_once('.').unwrap_or((key, ""));
    if let Some(i) = head
        .strip_prefix("cables[")
        .and_then(|r| r.strip_suffix(']'))
    {
        let name = match leaf {
            "anchor" => "anchors_m",
            "attachment" => "attachments_m",
            "t_min" => "cable_t_min_n",
            "t_max" => "cable_t_max_n",
            "youngs_modulus" => "youngs_modulus_pa",
            "area" => "area_m2",
            "weight_per_length" => "weight_per_length_n_m",
            "mass_per_length" => "mass_per_length_kg_m",
            _ => return None,
        };
        return Some(format!("{name}[{i}]"));
    }
    let name = match (head, leaf) {
        ("name", "") => "name",
        ("gravity", "") => "gravity_m_s2",
        ("cables", "") => "anchors_m",
        ("end_effector", "mass") => "ee_mass_kg",
        ("end_effector", "position") => "ee_position_m",
        ("end_effector", "orientation") => "ee_orientation_wxyz",
        ("end_effector", "inertia") => "ee_inertia_kg_m2",
        ("end_effector", "weight_carried") => "weight_carried",
        ("cable", "youngs_modulus") => "youngs_modulus_pa",
        ("cable", "area") => "area_m2",
        ("cable", "weight_per_length") => "weight_per_length_n_m",
        ("cable", "mass_per_length") => "mass_per_length_kg_m",
        ("tension", "t_min") => "t_min_n",
        ("tension", "t_max") => "t_max_n",
        ("model", "element") => "element",
        ("model", "elements_per_cable") => "elements",
        ("model", "ee_participation_min") => "ee_participation_min",
        ("model", "f1_tolerance") => "f1_tolerance",
        ("effects", f) if !f.is_empty() => f,
        _ => return None,
    };
    Some(name.to_string())
}

/// The message of a scene `from_arrays` could not build: a TOML error (a missing argument,
/// a wrong type) names the argument instead of a line of the text it wrote; any other error
/// is the scene file's.
fn from_arrays_message(e: &cablevib::scene::SceneError, source: &str) -> String {
    if let cablevib::scene::SceneError::Parse { report, .. } = e {
        if let Some(arg) = report.key.as_deref().and_then(argument_of) {
            return if report.message.starts_with("missing field") {
                format!("{source}: argument `{arg}` is required")
            } else {
                format!("{source}: argument `{arg}`: {}", report.message)
            };
        }
    }
    e.to_string()
}
