//! `cablevib.simulate` and `cablevib.shape`: what ``cablevib simulate`` and ``cablevib
//! shape`` write to their CSVs, as numpy arrays, through the same study-layer functions
//! (`study::simulate::PathSpec::sample`, `study::simulate::simulate_shaped`,
//! `study::simulate::shape`).

use crate::analysis::{finite_position, with_overrides};
use crate::convert::{array1, array2};
use crate::error::CablevibError;
use crate::scene::PyScene;
use cablevib::scene::{Damping, Scene, MAX_MODAL_RATIO};
use cablevib::study::simulate::{
    pilot, shape as shape_path, simulate_shaped, PathSpec, SampledPath, ShapeMode, SimulateConfig,
    DEFAULT_MAX_ACCELERATION_M_S2,
};
use cablevib::trajectory::moves::Profile;
use cablevib::trajectory::shaping::ShaperKind;
use cablevib::trajectory::CIRCLE_PERIOD_S;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// The scene with the command line's scene options (`--position`, `--t-min`, `--element`,
/// `--elements`, `--sag`) and damping option (`--modal-ratio`).
fn scene_with(
    scene: &PyScene,
    position: Option<&Bound<'_, PyAny>>,
    t_min: Option<f64>,
    element: Option<&str>,
    elements: Option<usize>,
    sag: Option<bool>,
    modal_ratio: Option<f64>,
) -> PyResult<Scene> {
    let mut s = scene.inner.clone();
    if let Some(p) = position {
        s.ee_position_m = finite_position(p)?;
    }
    let on = sag.unwrap_or(s.model.sag);
    let mut s = with_overrides(s, t_min, element, elements)?;
    if let Some(why) = cablevib::scene::sag_refusal(on, s.model.element) {
        return Err(CablevibError::new_err(format!("sag={on}: {why}")));
    }
    s.model.sag = on;
    s.model.sag_explicit |= sag.is_some();
    if let Some(z) = modal_ratio {
        if !(z.is_finite() && (0.0..MAX_MODAL_RATIO).contains(&z)) {
            return Err(CablevibError::new_err(format!(
                "modal_ratio {z}: must be in [0, {MAX_MODAL_RATIO}) (1 is critical damping)"
            )));
        }
        s.damping = Damping::ModalRatio { zeta: z };
    }
    Ok(s)
}

/// The path of `csv`, `move` (with `duration`, `profile`) or, when `circle` is given and
/// neither is, the circle; sampled every `dt`; `max_acceleration` (m/s²) checked to be
/// finite and > 0 (the path is checked against it by the study).
#[allow(clippy::too_many_arguments)]
fn path_of(
    s: &Scene,
    csv: Option<PathBuf>,
    displacement: Option<&Bound<'_, PyAny>>,
    duration: f64,
    profile: &str,
    dt: f64,
    circle: Option<(f64, f64)>,
    max_acceleration: f64,
) -> PyResult<(SampledPath, String)> {
    if !(max_acceleration.is_finite() && max_acceleration > 0.0) {
        return Err(CablevibError::new_err(format!(
            "max_acceleration {max_acceleration}: must be finite and > 0"
        )));
    }
    let profile = match profile {
        "s-curve" => Profile::SCurve,
        "trapezoid" => Profile::Trapezoid,
        _ => {
            return Err(CablevibError::new_err(format!(
                "profile `{profile}`: expected s-curve or trapezoid"
            )))
        }
    };
    let spec = match (csv, displacement, circle) {
        (Some(_), Some(_), _) => {
            return Err(CablevibError::new_err("give one of csv and move"));
        }
        (Some(c), None, _) => PathSpec::Csv(c),
        (None, Some(d), _) => PathSpec::Move {
            displacement_m: finite_position(d)
                .map_err(|_| CablevibError::new_err("move: expected three finite numbers (m)"))?,
            duration_s: duration,
            profile,
        },
        (None, None, Some((duration_s, period_s))) => PathSpec::Circle {
            duration_s,
            period_s,
        },
        (None, None, None) => {
            return Err(CablevibError::new_err(
                "give a trajectory CSV (or move=(dx, dy, dz)) to shape",
            ));
        }
    };
    spec.sample(s, dt)
        .map_err(|e| CablevibError::new_err(e.to_string()))
}

/// A shaper name (`none`, `zv`, `zvd`, `ei`) and a mode name (`ee`, `f1`).
fn shaper_and_mode(shaper: &str, mode: &str) -> PyResult<(Option<ShaperKind>, ShapeMode)> {
    let kind = match shaper {
        "none" => None,
        "zv" => Some(ShaperKind::Zv),
        "zvd" => Some(ShaperKind::Zvd),
        "ei" => Some(ShaperKind::Ei),
        _ => {
            return Err(CablevibError::new_err(format!(
                "shaper `{shaper}`: expected none, zv, zvd or ei"
            )))
        }
    };
    let mode = match mode {
        "ee" => ShapeMode::EndEffector,
        "f1" => ShapeMode::First,
        _ => {
            return Err(CablevibError::new_err(format!(
                "mode `{mode}`: expected ee or f1"
            )))
        }
    };
    Ok((kind, mode))
}

/// Rows of 3-vectors as an (N, 3) float64 array.
fn rows3<'py>(py: Python<'py>, v: &[nalgebra::Vector3<f64>]) -> PyResult<Bound<'py, PyAny>> {
    let rows: Vec<Vec<f64>> = v.iter().map(|x| vec![x.x, x.y, x.z]).collect();
    if rows.is_empty() {
        return crate::convert::asarray(py, pyo3::types::PyList::empty(py).into_any(), "float64");
    }
    array2(py, &rows)
}

/// The end-effector's dynamic deviation from its quasi-static pose along a path: what
/// ``cablevib simulate`` writes to its CSV (one shaper), as numpy arrays.
///
/// The path: ``csv`` (a trajectory file t,x,y,z), else ``move`` ((dx, dy, dz) m from the
/// scene's position, in ``duration`` s, ``profile`` ``"s-curve"`` or ``"trapezoid"``), else
/// the paper's circle for ``circle_s`` s (one revolution per ``period_s``), sampled every
/// ``dt`` s. ``modes``, ``update_every``, ``tolerance``, ``settle``, ``max_acceleration``,
/// ``modal_ratio``, ``shaper`` (``"none"``, ``"zv"``, ``"zvd"``, ``"ei"``) and ``mode``
/// (``"ee"``, ``"f1"``) as the options of the same names; ``position``, ``t_min``,
/// ``element``, ``elements``, ``sag`` as in ``analyze``.
///
/// Keys: ``t_s`` (N), ``deviation_m`` (N × 3, m), ``command_m`` (N × 3, the commanded
/// path, shaped when a shaper is given, m), ``time_added_s``, ``modes``, ``updates``,
/// ``structured``, ``f1_range_hz``, ``accuracy`` (dict), ``stops`` (list of dicts),
/// ``path``. Raises CablevibError with the command line's message.
#[pyfunction]
#[pyo3(signature = (scene, csv = None, r#move = None, duration = 0.5, profile = "s-curve",
                    dt = 1e-3, modal_ratio = None,
                    max_acceleration = DEFAULT_MAX_ACCELERATION_M_S2, circle_s = 10.0,
                    period_s = CIRCLE_PERIOD_S, modes = None, update_every = None,
                    tolerance = pilot::DEFAULT_TOLERANCE, settle = 2.0, shaper = "none",
                    mode = "ee", position = None, t_min = None, element = None,
                    elements = None, sag = None))]
#[allow(clippy::too_many_arguments)]
pub fn simulate<'py>(
    py: Python<'py>,
    scene: &PyScene,
    csv: Option<PathBuf>,
    r#move: Option<&Bound<'py, PyAny>>,
    duration: f64,
    profile: &str,
    dt: f64,
    modal_ratio: Option<f64>,
    max_acceleration: f64,
    circle_s: f64,
    period_s: f64,
    modes: Option<usize>,
    update_every: Option<usize>,
    tolerance: f64,
    settle: f64,
    shaper: &str,
    mode: &str,
    position: Option<&Bound<'py, PyAny>>,
    t_min: Option<f64>,
    element: Option<&str>,
    elements: Option<usize>,
    sag: Option<bool>,
) -> PyResult<Bound<'py, PyAny>> {
    let s = scene_with(scene, position, t_min, element, elements, sag, modal_ratio)?;
    let (kind, mode) = shaper_and_mode(shaper, mode)?;
    let (path, desc) = path_of(
        &s,
        csv,
        r#move,
        duration,
        profile,
        dt,
        Some((circle_s, period_s)),
        max_acceleration,
    )?;
    let cfg = SimulateConfig {
        modes,
        update_every,
        tolerance,
        settle_s: settle,
        max_acceleration_m_s2: max_acceleration,
        progress: None,
    };
    let run = py
        .detach(|| {
            path.check(max_acceleration)?;
            simulate_shaped(&s, &path, &cfg, kind, mode)
        })
        .map_err(|e| CablevibError::new_err(e.to_string()))?;
    let r = &run.result;
    let d = PyDict::new(py);
    d.set_item("t_s", array1(py, &r.t_s)?)?;
    d.set_item("deviation_m", rows3(py, &r.deviation_m)?)?;
    d.set_item("command_m", rows3(py, &r.command_m)?)?;
    d.set_item("time_added_s", run.added_s)?;
    d.set_item("modes", r.modes)?;
    d.set_item("updates", r.updates)?;
    d.set_item("structured", r.structured)?;
    d.set_item("f1_range_hz", (r.f1_range_hz.0, r.f1_range_hz.1))?;
    let acc = PyDict::new(py);
    acc.set_item("tolerance", r.accuracy.tolerance)?;
    acc.set_item("modes_chosen", r.accuracy.modes_chosen)?;
    acc.set_item("truncation_estimate", r.accuracy.modes_estimate)?;
    acc.set_item("modes_met", r.accuracy.modes_met)?;
    acc.set_item("peak_m", r.accuracy.peak_m)?;
    acc.set_item("update_interval_chosen", r.accuracy.updates_chosen)?;
    acc.set_item("update_interval_estimate", r.accuracy.interval_estimate)?;
    d.set_item("accuracy", acc)?;
    let stops = pyo3::types::PyList::empty(py);
    for st in &r.stops {
        let x = PyDict::new(py);
        x.set_item("t_start_s", st.t_start_s)?;
        x.set_item("t_end_s", st.t_end_s)?;
        x.set_item("peak_to_peak_m", array1(py, st.peak_to_peak_m.as_slice())?)?;
        x.set_item("rms_m", st.rms_m)?;
        stops.append(x)?;
    }
    d.set_item("stops", stops)?;
    d.set_item("path", desc)?;
    Ok(d.into_any())
}

/// A path shaped by a time-varying shaper that follows the estimated mode: what
/// ``cablevib shape`` writes to its CSV, as numpy arrays.
///
/// The path: ``trajectory`` (a CSV file t,x,y,z), else ``move`` ((dx, dy, dz) m from the
/// scene's position, in ``duration`` s with ``profile``), sampled every ``dt`` s.
/// ``shaper`` (``"zv"``, ``"zvd"``, ``"ei"``), ``mode`` (``"ee"``, ``"f1"``),
/// ``modal_ratio`` and ``max_acceleration`` as the options of the same names.
///
/// Keys: ``t_s`` (N), ``path_m`` (N × 3, the shaped positions, m), ``design_hz`` (N, the
/// shaper's design frequency at each sample, Hz), ``time_added_s``, ``path``. Raises
/// CablevibError with the command line's message.
#[pyfunction]
#[pyo3(signature = (scene, trajectory = None, r#move = None, duration = 0.5,
                    profile = "s-curve", dt = 1e-3, modal_ratio = None,
                    max_acceleration = DEFAULT_MAX_ACCELERATION_M_S2, shaper = "zv",
                    mode = "ee"))]
#[allow(clippy::too_many_arguments)]
pub fn shape<'py>(
    py: Python<'py>,
    scene: &PyScene,
    trajectory: Option<PathBuf>,
    r#move: Option<&Bound<'py, PyAny>>,
    duration: f64,
    profile: &str,
    dt: f64,
    modal_ratio: Option<f64>,
    max_acceleration: f64,
    shaper: &str,
    mode: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let s = scene_with(scene, None, None, None, None, None, modal_ratio)?;
    let (kind, mode) = shaper_and_mode(shaper, mode)?;
    let Some(kind) = kind else {
        return Err(CablevibError::new_err("shaper none: nothing to shape"));
    };
    let (path, desc) = path_of(
        &s,
        trajectory,
        r#move,
        duration,
        profile,
        dt,
        None,
        max_acceleration,
    )?;
    let r = py
        .detach(|| {
            path.check(max_acceleration)?;
            shape_path(&s, &path, kind, mode)
        })
        .map_err(|e| CablevibError::new_err(e.to_string()))?;
    let t: Vec<f64> = (0..r.path.positions_m.len())
        .map(|k| k as f64 * path.dt_s)
        .collect();
    let d = PyDict::new(py);
    d.set_item("t_s", array1(py, &t)?)?;
    d.set_item("path_m", rows3(py, &r.path.positions_m)?)?;
    d.set_item("design_hz", array1(py, &r.design_hz)?)?;
    d.set_item("time_added_s", r.added_s)?;
    d.set_item("path", desc)?;
    Ok(d.into_any())
}
