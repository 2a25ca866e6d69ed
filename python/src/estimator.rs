//! `cablevib.Estimator`: the library's real-time estimator (`cablevib::estimator::Estimator`)
//! driven from Python, one pose per `update`, and its inverse T_min query.

use crate::convert::{array1, floats, matrix3, matrix6, position};
use crate::error::CablevibError;
use crate::scene::PyScene;
use cablevib::estimator::{Estimate, Estimator, Tmin, TminAnswer};
use cablevib::kinematics::Pose;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The real-time estimator of one scene: tensions, end-effector stiffness, f1 and the
/// end-effector mode at each pose, warm-started from the previous call (a sweep along a
/// path costs a few microseconds per pose).
///
/// ``Estimator(scene)`` raises CablevibError when the scene's own default pose cannot be
/// solved (the message is the command line's). An ``auto`` model is resolved here.
/// ``realtime=True`` runs each update as the service does (``EstimatorParams::realtime()``:
/// a budget of D(λ) evaluations per call, the end-effector work that does not fit continued
/// in the next calls, so the end-effector mode of a cold call may be pending), what
/// ``cablevib analyze --realtime`` prints; the default answers every call in full.
#[pyclass(name = "Estimator", module = "cablevib")]
pub struct PyEstimator {
    inner: Estimator,
    /// The estimator as built, before any update: where every chunk of a sweep starts.
    cold: Estimator,
    /// Where the scene it was built from came from (its `scene` pickles as that scene).
    origin: Option<crate::scene::Origin>,
}

#[pymethods]
impl PyEstimator {
    #[new]
    #[pyo3(signature = (scene, realtime = false))]
    fn new(scene: &PyScene, realtime: bool) -> PyResult<Self> {
        let built = if realtime {
            Estimator::realtime(&scene.inner)
        } else {
            Estimator::new(&scene.inner)
        };
        let inner = built.map_err(|e| CablevibError::new_err(e.to_string()))?;
        let cold = inner.clone();
        Ok(PyEstimator {
            inner,
            cold,
            origin: scene.origin.clone(),
        })
    }

    /// One cycle at ``position`` (m, 3 numbers) with ``orientation`` (unit quaternion
    /// [w, x, y, z]; default the scene's) and ``t_min`` (N: one number for every cable, or
    /// one per cable; default the scene's bounds). Returns an Estimate.
    ///
    /// A pose or T_min the estimator refuses (outside the frame, infeasible tensions,
    /// non-finite numbers, T_min out of range) is not an exception: the estimate's
    /// ``status`` says why and its frequencies are NaN. Wrong shapes raise ValueError or
    /// TypeError.
    #[pyo3(signature = (position, orientation = None, t_min = None))]
    fn update(
        &mut self,
        position: &Bound<'_, PyAny>,
        orientation: Option<&Bound<'_, PyAny>>,
        t_min: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyEstimate> {
        let pose = self.pose(position, orientation)?;
        let n = self.inner.scene().n_cables();
        let e = match t_min {
            None => *self.inner.update(&pose, Tmin::Scene),
            Some(t) => match t.extract::<f64>() {
                Ok(uniform) => *self.inner.update(&pose, Tmin::Uniform(uniform)),
                Err(_) => {
                    let per_cable = per_cable_t_min(t, n)?;
                    *self.inner.update(&pose, Tmin::PerCable(&per_cable))
                }
            },
        };
        Ok(PyEstimate { inner: e })
    }

    /// Many poses in one call: ``positions`` (m, shape (n, 3)), ``orientations`` (unit
    /// quaternions [w, x, y, z], shape (n, 4); default the scene's) and ``t_min`` (N, shape
    /// (n,) for one bound per pose or (n, n_cables) for one per cable; default the scene's
    /// bounds). Returns a dict of numpy arrays, one row per pose: ``positions_m``,
    /// ``orientations_wxyz``, ``t_min_n`` (the lowest bound, as the CSVs' column),
    /// ``status_code`` (uint32), ``status`` (str), ``ok`` (bool), ``tensions_n`` (n,
    /// n_cables), ``f1_hz``, ``f1_ee_participation``, ``ee_mode_hz``,
    /// ``ee_mode_participation``, ``stiffness_principal_n_m`` (n, 3: the eigenvalues of the
    /// translational stiffness block, ascending, N/m), ``k_min_n_m`` (its first column); and
    /// ``threads`` and ``chunk_poses`` (ints).
    ///
    /// The GIL is released while the poses run on ``threads`` workers (0: one per core).
    /// The poses are cut into chunks of ``chunk_poses`` consecutive poses; each chunk is
    /// evaluated in order by a copy of this estimator as it was built (warm-started within
    /// the chunk), so the numbers are the same bit for bit for any thread count, and equal
    /// to ``for each chunk: e = Estimator(scene); [e.update(...) for each pose]``. The
    /// estimator's own warm state (``update``) is neither used nor changed. Refused poses
    /// keep their status and NaN frequencies, as ``update``'s.
    #[pyo3(signature = (positions, orientations = None, t_min = None, threads = 0, chunk_poses = crate::sweep::DEFAULT_CHUNK_POSES))]
    fn sweep<'py>(
        &self,
        py: Python<'py>,
        positions: &Bound<'py, PyAny>,
        orientations: Option<&Bound<'py, PyAny>>,
        t_min: Option<&Bound<'py, PyAny>>,
        threads: usize,
        chunk_poses: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        let n = self.cold.scene().n_cables();
        let inp = crate::sweep::input(positions, orientations, t_min, n)?;
        crate::sweep::sweep(py, &self.cold, inp, threads, chunk_poses)
    }

    /// The smallest T_min (N, the same for every cable) for which f1 at ``position`` (m)
    /// reaches ``required_f1_hz`` (Hz), searched within the range of T_min where the model is
    /// ok (a scan of 64 steps, then regula falsi on the first crossing; at most 257 forward
    /// evaluations). Leaves the warm state of ``update`` untouched. Returns a TminAnswer;
    /// raises CablevibError when the requirement is unreachable (the message gives the
    /// largest f1 found and its T_min) or the pose is infeasible at every T_min.
    #[pyo3(signature = (position, required_f1_hz, orientation = None))]
    fn t_min_for_f1(
        &mut self,
        position: &Bound<'_, PyAny>,
        required_f1_hz: f64,
        orientation: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyTminAnswer> {
        let pose = self.pose(position, orientation)?;
        self.inner
            .t_min_for_f1(&pose, required_f1_hz)
            .map(|inner| PyTminAnswer { inner })
            .map_err(|e| CablevibError::new_err(e.to_string()))
    }

    /// Forget every warm start: the next ``update`` starts cold.
    fn reset(&mut self) {
        self.inner.reset();
    }

    /// The scene (with an ``auto`` model resolved to the model picked).
    #[getter]
    fn scene(&self) -> PyScene {
        PyScene {
            inner: self.inner.scene().clone(),
            origin: self.origin.clone(),
        }
    }

    /// What ``element = "auto"`` picked and why (None for an explicit model).
    #[getter]
    fn auto_choice(&self) -> Option<String> {
        self.inner.auto_choice().map(|c| c.to_string())
    }

    fn __repr__(&self) -> String {
        let s = self.inner.scene();
        format!(
            "Estimator(scene={:?}, element={:?}, elements={})",
            s.name,
            s.model.element.as_str(),
            s.model.elements_per_cable
        )
    }
}

impl PyEstimator {
    /// The pose of `position` and `orientation` (default: the scene's orientation; an
    /// orientation on a point-mass scene is refused by the estimator's input check).
    fn pose(
        &self,
        position_obj: &Bound<'_, PyAny>,
        orientation: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Pose> {
        let position_m = position(position_obj)?;
        let orientation_wxyz = match orientation {
            Some(q) => floats::<4>(q, "orientation (unit quaternion w, x, y, z)")?,
            // The scene's (the identity on a point mass, which has no orientation).
            None => Pose::in_scene(self.inner.scene(), position_m).orientation_wxyz,
        };
        Ok(Pose {
            position_m,
            orientation_wxyz,
        })
    }
}

/// One T_min per cable (N) from a sequence of `n` numbers.
fn per_cable_t_min(t: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<f64>> {
    crate::convert::refuse_non_number_sequence(t, "t_min")?;
    let v: Vec<f64> = t.extract().map_err(|_| {
        PyValueError::new_err(format!(
            "t_min: expected a number (N) or {n} numbers, one per cable"
        ))
    })?;
    if v.len() != n {
        return Err(PyValueError::new_err(format!(
            "t_min: expected {n} numbers (N), one per cable, got {}",
            v.len()
        )));
    }
    Ok(v)
}

/// The result of one ``Estimator.update``. Numbers are valid only when ``ok`` (status
/// ``"ok"``); otherwise frequencies and stiffness are NaN, and tensions are NaN except for
/// ``tension_infeasible`` (the closest achievable tensions).
#[pyclass(name = "Estimate", module = "cablevib", frozen)]
pub struct PyEstimate {
    inner: Estimate,
}

#[pymethods]
impl PyEstimate {
    /// Status as a string: ``ok``, ``tension_infeasible``, ``invalid_input``,
    /// ``not_converged``, ``rank_deficient``, ``outside_workspace`` (at an anchor),
    /// ``non_unit_quaternion``, ``t_min_out_of_range``, … (the service's codes).
    #[getter]
    fn status(&self) -> &'static str {
        self.inner.status.as_str()
    }

    /// Status as the service's wire code (0 is ok).
    #[getter]
    fn status_code(&self) -> u32 {
        self.inner.status.as_u32()
    }

    /// True when the status is ok.
    #[getter]
    fn ok(&self) -> bool {
        self.inner.is_ok()
    }

    /// Why the estimate is not ok (the command line's message), None when ok.
    #[getter]
    fn error(&self) -> Option<String> {
        self.inner.error.map(|e| e.to_string())
    }

    /// Cable tensions, N, shape (n_cables,).
    #[getter]
    fn tensions_n<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        array1(py, self.inner.tensions())
    }

    /// First natural frequency of the whole model, Hz.
    #[getter]
    fn f1_hz(&self) -> f64 {
        self.inner.f1_hz
    }

    /// End-effector participation of the first mode (0 … 1): the share of the mode's
    /// kinetic-energy norm carried by the end-effector mass.
    #[getter]
    fn f1_ee_participation(&self) -> f64 {
        self.inner.f1_ee_participation
    }

    /// Frequency of the lowest mode whose end-effector participation reaches the scene's
    /// threshold, Hz (the end-effector mode).
    #[getter]
    fn ee_mode_hz(&self) -> f64 {
        self.inner.ee_mode.map_or(f64::NAN, |m| m.frequency_hz)
    }

    /// End-effector participation of the end-effector mode (0 … 1).
    #[getter]
    fn ee_mode_participation(&self) -> f64 {
        self.inner.ee_mode.map_or(f64::NAN, |m| m.participation)
    }

    /// How many cycles old the end-effector mode answer is (0: computed at this pose); None
    /// when no answer is known (`ee_mode_hz` is then NaN).
    #[getter]
    fn ee_mode_age_cycles(&self) -> Option<u32> {
        self.inner.ee_mode.map(|m| m.age_cycles)
    }

    /// Static end-effector stiffness, translational block, N/m, shape (3, 3).
    #[getter]
    fn stiffness_n_m<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        matrix3(py, &self.inner.stiffness.translational_n_m())
    }

    /// Full static end-effector stiffness, shape (3, 3) for a point mass (N/m) or (6, 6)
    /// for a rigid body (N/m, N/rad, N·m/rad blocks).
    #[getter]
    fn stiffness<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        matrix6(py, &self.inner.stiffness.k6, self.inner.stiffness.dim)
    }

    /// Evaluations of the dynamic stiffness D(λ) spent in this cycle.
    #[getter]
    fn eigen_evaluations(&self) -> u32 {
        self.inner.eigen_evaluations
    }

    /// Relative residual |μ₁(D(λ₁))| / ‖D‖ of the first root.
    #[getter]
    fn eigen_residual(&self) -> f64 {
        self.inner.eigen_residual
    }

    /// The first-mode iteration started cold (no warm start from the previous pose).
    #[getter]
    fn cold_start(&self) -> bool {
        self.inner.cold_start
    }

    /// Active-set changes of the tension solver in this cycle.
    #[getter]
    fn tension_iterations(&self) -> u32 {
        self.inner.tension_iterations
    }

    /// The tension solver's previous active set was optimal again.
    #[getter]
    fn tension_warm(&self) -> bool {
        self.inner.tension_warm
    }

    /// Every attribute above in a dict (one row of a sweep's table, e.g. for pandas).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("status", self.status())?;
        d.set_item("status_code", self.status_code())?;
        d.set_item("ok", self.ok())?;
        d.set_item("error", self.error())?;
        d.set_item("tensions_n", self.tensions_n(py)?)?;
        d.set_item("f1_hz", self.f1_hz())?;
        d.set_item("f1_ee_participation", self.f1_ee_participation())?;
        d.set_item("ee_mode_hz", self.ee_mode_hz())?;
        d.set_item("ee_mode_participation", self.ee_mode_participation())?;
        d.set_item("ee_mode_age_cycles", self.ee_mode_age_cycles())?;
        d.set_item("stiffness_n_m", self.stiffness_n_m(py)?)?;
        d.set_item("stiffness", self.stiffness(py)?)?;
        d.set_item("eigen_evaluations", self.eigen_evaluations())?;
        d.set_item("eigen_residual", self.eigen_residual())?;
        d.set_item("cold_start", self.cold_start())?;
        d.set_item("tension_iterations", self.tension_iterations())?;
        d.set_item("tension_warm", self.tension_warm())?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        let e = &self.inner;
        format!(
            "Estimate(status={:?}, f1_hz={}, ee_mode_hz={}, tensions_n={:?})",
            e.status.as_str(),
            e.f1_hz,
            self.ee_mode_hz(),
            e.tensions()
        )
    }
}

/// The answer of ``Estimator.t_min_for_f1``.
#[pyclass(name = "TminAnswer", module = "cablevib", frozen)]
pub struct PyTminAnswer {
    inner: TminAnswer,
}

#[pymethods]
impl PyTminAnswer {
    /// The smallest T_min found, N.
    #[getter]
    fn t_min_n(&self) -> f64 {
        self.inner.t_min_n
    }

    /// f1 at that T_min, Hz (at or just above the requirement).
    #[getter]
    fn f1_hz(&self) -> f64 {
        self.inner.f1_hz
    }

    /// Forward evaluations (tensions and f1) spent.
    #[getter]
    fn evaluations(&self) -> u32 {
        self.inner.evaluations
    }

    /// The scan step, N: the answer is the smallest T_min at this resolution (a smaller
    /// one can reach the requirement only on a range narrower than it; 0 when the answer is
    /// the smallest feasible T_min).
    #[getter]
    fn resolution_n(&self) -> f64 {
        self.inner.resolution_n
    }

    fn __repr__(&self) -> String {
        format!(
            "TminAnswer(t_min_n={}, f1_hz={}, evaluations={}, resolution_n={})",
            self.inner.t_min_n, self.inner.f1_hz, self.inner.evaluations, self.inner.resolution_n
        )
    }
}
