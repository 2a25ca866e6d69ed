//! `cablevib.analyze`: the library's `study::analysis::analyze`, the function behind
//! `cablevib analyze --json`, with the command line's scene overrides.

use crate::convert::{floats, json_to_py, position};
use crate::error::CablevibError;
use crate::scene::PyScene;
use cablevib::kinematics::unit_quaternion;
use cablevib::scene::{ElementKind, Scene, MAX_ELEMENTS_PER_CABLE};
use cablevib::study::analysis::{analyze as analyze_scene, AnalyzeOptions, SolverChoice};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// The analysis of one pose: what ``cablevib analyze SCENE --json`` prints, as a dict.
///
/// ``position`` (m, 3 numbers), ``orientation`` (unit quaternion w, x, y, z: rigid
/// end-effectors only, normalised when its norm is 1 within 1e-3), ``t_min`` (N, every cable), ``element`` (``fem``,
/// ``catenary``, ``continuous``, ``massless`` or ``auto``) and ``elements`` (per cable)
/// override the scene's, as ``--position``, ``--orientation``, ``--t-min``, ``--element`` and ``--elements``
/// do; ``modes`` is the number of natural frequencies; ``solver`` is ``structured``
/// (default) or ``dense`` (the dense reference); ``compare_dense`` also solves the same
/// models densely and reports both (``--compare-dense``).
///
/// Keys, units in their names: ``scene``, ``position_m``, ``orientation_wxyz``, ``t_min_n``,
/// ``tensions_n``, ``frequencies_hz`` (ascending), ``ee_participation``, ``multiplicity``,
/// ``cluster_start``, ``dof``, ``element``, ``elements_per_cable``, ``stiffness_n_m``
/// (3 × 3 N/m for a point mass; 6 × 6 for a rigid end-effector: N/m, N/rad, N·m/m, N·m/rad
/// blocks), ``solver``, ``solve_seconds``, ``dense_seconds``, ``compare_dense``, ``sag``;
/// with sagging cables also ``tensions_anchor_n``, ``tensions_min_n`` (N), ``sag_m`` (m),
/// ``irvine_lambda2`` and ``unstretched_length_m`` (m), one per cable. ``sag`` (True or
/// False) overrides the scene's ``[effects] sag`` as ``--sag`` does. Numeric
/// lists are numpy arrays (float64, int64 for counts and indices); absent values are None.
/// Every number equals the command line's.
///
/// Raises CablevibError with the command line's message when the pose has no valid answer
/// (infeasible tensions, outside the frame, …) or an override is out of range.
#[pyfunction]
#[pyo3(signature = (scene, position = None, t_min = None, element = None, elements = None,
                    modes = 10, solver = "structured", compare_dense = false,
                    orientation = None, sag = None))]
#[allow(clippy::too_many_arguments)]
pub fn analyze<'py>(
    py: Python<'py>,
    scene: &PyScene,
    position: Option<&Bound<'py, PyAny>>,
    t_min: Option<f64>,
    element: Option<&str>,
    elements: Option<usize>,
    modes: usize,
    solver: &str,
    compare_dense: bool,
    orientation: Option<&Bound<'py, PyAny>>,
    sag: Option<bool>,
) -> PyResult<Bound<'py, PyAny>> {
    let mut s = scene.inner.clone();
    if let Some(p) = position {
        s.ee_position_m = finite_position(p)?;
    }
    if let Some(q) = orientation {
        set_orientation(&mut s, q)?;
    }
    let on = sag.unwrap_or(s.model.sag);
    let mut s = with_overrides(s, t_min, element, elements)?;
    // The command line's rule: an element without a sagged model refuses sag.
    if let Some(why) = cablevib::scene::sag_refusal(on, s.model.element) {
        return Err(CablevibError::new_err(format!("sag={on}: {why}")));
    }
    s.model.sag = on;
    let opts = AnalyzeOptions {
        modes,
        solver: solver_choice(solver)?,
        compare_dense,
    };
    let report = py
        .detach(|| analyze_scene(&s, &opts))
        .map_err(|e| CablevibError::new_err(e.to_string()))?;
    let value = serde_json::to_value(&report)
        .map_err(|e| CablevibError::new_err(format!("analysis report: {e}")))?;
    json_to_py(py, &value)
}

/// A position (m) whose three components are finite, as `--position` requires.
pub(crate) fn finite_position(p: &Bound<'_, PyAny>) -> PyResult<nalgebra::Vector3<f64>> {
    let v = position(p)?;
    if !v.iter().all(|x| x.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "position: expected three finite numbers (m), got [{}, {}, {}]",
            v.x, v.y, v.z
        )));
    }
    Ok(v)
}

/// `--orientation`'s rule (`cli::args::set_orientation`): a unit quaternion within
/// `kinematics::QUATERNION_INPUT_TOL`, normalised; a point-mass scene refuses it.
fn set_orientation(s: &mut Scene, q: &Bound<'_, PyAny>) -> PyResult<()> {
    let q = floats::<4>(q, "orientation (unit quaternion w, x, y, z)")?;
    let q = unit_quaternion(q).map_err(|e| CablevibError::new_err(e.to_string()))?;
    if !s.rigid {
        return Err(CablevibError::new_err(format!(
            "orientation: scene `{}` has a point-mass end-effector, where orientation has no effect (a rigid one has `effects = [\"rotation\"]`)",
            s.name
        )));
    }
    s.ee_orientation_wxyz = q;
    Ok(())
}

/// The command line's overrides (`cli::args::resolve_scene`) on a loaded scene, with its
/// rules and messages, the option named as the Python argument (`t_min` for `--t-min`).
pub(crate) fn with_overrides(
    mut s: Scene,
    t_min: Option<f64>,
    element: Option<&str>,
    elements: Option<usize>,
) -> PyResult<Scene> {
    if let Some(t) = t_min {
        // The one T_min rule of scene files and set-points; per-cable values are replaced.
        s.set_uniform_t_min(t)
            .map_err(|e| CablevibError::new_err(format!("t_min: {e}")))?;
    }
    let element = match element {
        Some(e) => ElementKind::parse(e).ok_or_else(|| {
            CablevibError::new_err(format!(
                "element `{e}`: expected fem, catenary, continuous, massless or auto"
            ))
        })?,
        None => s.model.element,
    };
    let n = elements.unwrap_or(s.model.elements_per_cable);
    if n == 0 || n > MAX_ELEMENTS_PER_CABLE {
        return Err(CablevibError::new_err(format!(
            "elements {n}: must be in 1..={MAX_ELEMENTS_PER_CABLE}"
        )));
    }
    Ok(s.with_model(element, n))
}

/// `structured` or `dense`.
fn solver_choice(s: &str) -> PyResult<SolverChoice> {
    match s {
        "structured" => Ok(SolverChoice::Structured),
        "dense" => Ok(SolverChoice::Dense),
        _ => Err(CablevibError::new_err(format!(
            "solver `{s}`: expected structured or dense"
        ))),
    }
}
