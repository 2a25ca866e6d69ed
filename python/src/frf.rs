//! `cablevib.frf`: the end-effector receptance over a frequency band, what
//! ``cablevib frf SCENE --json`` prints (the library's `modal::receptance_over`).

use crate::analysis::{finite_position, with_overrides};
use crate::convert::{asarray, json_to_py};
use crate::error::CablevibError;
use crate::scene::PyScene;
use cablevib::estimator::{Estimator, PoseModel, Tmin};
use cablevib::kinematics::Pose;
use cablevib::modal::{frequency_grid, FrfError, ModalParams, ModalSolver};
use cablevib::scene::{
    Damping, ElementKind, Scene, MAX_LOSS_FACTOR, MAX_MODAL_RATIO, MAX_RAYLEIGH_ALPHA_PER_S,
    MAX_RAYLEIGH_BETA_S,
};
use nalgebra::{Complex, Matrix6};
use pyo3::prelude::*;

/// The modal-damping basis's cut-off over the band's top (the command line's).
const MODAL_CUTOFF_RATIO: f64 = 4.0;

/// The receptance H(ω) = [K + iωC − ω²M]⁻¹ at the end-effector over a band: what
/// ``cablevib frf SCENE --json`` prints, as a dict with numpy arrays.
///
/// ``from_hz``, ``to_hz``, ``points``, ``log`` as ``--from-hz``, ``--to-hz``, ``--points``,
/// ``--log``; ``position``, ``t_min``, ``element``, ``elements`` as in ``analyze``. Damping:
/// the scene's ``[damping]``, or one of ``loss_factor`` (η), ``rayleigh`` ((α 1/s, β s)),
/// ``modal_ratio`` (ζ), ``undamped=True``.
///
/// With sag (``[effects] sag = true``) the response is the sagged FEM chains' at the sagged
/// tensions of the pose, as on the command line: ``element="continuous"`` and modal damping
/// are refused there.
///
/// Keys: ``frequencies_hz`` (N), ``receptance_re``, ``receptance_im`` (N × d × d, m/N;
/// d = 3, or 6 for a rigid end-effector, translations first), ``damping``, ``dim``.
/// Raises CablevibError with the command line's message on a bad range or damping value.
#[pyfunction]
#[pyo3(signature = (scene, from_hz = 0.5, to_hz = 50.0, points = 1000, log = false,
                    position = None, t_min = None, element = None, elements = None,
                    loss_factor = None, rayleigh = None, modal_ratio = None, undamped = false))]
#[allow(clippy::too_many_arguments)]
pub fn frf<'py>(
    py: Python<'py>,
    scene: &PyScene,
    from_hz: f64,
    to_hz: f64,
    points: usize,
    log: bool,
    position: Option<&Bound<'py, PyAny>>,
    t_min: Option<f64>,
    element: Option<&str>,
    elements: Option<usize>,
    loss_factor: Option<f64>,
    rayleigh: Option<(f64, f64)>,
    modal_ratio: Option<f64>,
    undamped: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let freqs = frequency_grid(from_hz, to_hz, points, log)
        .map_err(|e| CablevibError::new_err(format!("from_hz/to_hz/points: {e}")))?;
    let mut s = scene.inner.clone();
    if let Some(p) = position {
        s.ee_position_m = finite_position(p)?;
    }
    let s = with_overrides(s, t_min, element, elements)?;
    let given = [
        loss_factor.is_some(),
        rayleigh.is_some(),
        modal_ratio.is_some(),
        undamped,
    ];
    if given.iter().filter(|&&g| g).count() > 1 {
        return Err(CablevibError::new_err(
            "give one of loss_factor, rayleigh, modal_ratio, undamped",
        ));
    }
    let check = |name: &str, v: f64, max: f64| {
        if v.is_finite() && v >= 0.0 && v < max {
            Ok(v)
        } else {
            Err(CablevibError::new_err(format!(
                "{name} {v}: must be finite, >= 0 and < {max}"
            )))
        }
    };
    let damping = if let Some(eta) = loss_factor {
        Damping::LossFactor {
            eta: check("loss_factor", eta, MAX_LOSS_FACTOR)?,
        }
    } else if let Some((a, b)) = rayleigh {
        Damping::Rayleigh {
            alpha_per_s: check("rayleigh alpha", a, MAX_RAYLEIGH_ALPHA_PER_S)?,
            beta_s: check("rayleigh beta", b, MAX_RAYLEIGH_BETA_S)?,
        }
    } else if let Some(z) = modal_ratio {
        Damping::ModalRatio {
            zeta: check("modal_ratio", z, MAX_MODAL_RATIO)?,
        }
    } else if undamped {
        Damping::None
    } else {
        s.damping
    };
    let h = py
        .detach(|| -> Result<_, String> {
            if s.model.sag {
                return sagged(&s, &damping, &freqs);
            }
            let pose = PoseModel::new(&s).map_err(|e| e.to_string())?;
            let mut solver = ModalSolver::new(ModalParams::default());
            pose.load(&mut solver);
            // The command line's computation, its memory checked first (the one budget).
            let h = cablevib::study::cost::receptance(
                &pose,
                &mut solver,
                &damping,
                &freqs,
                MODAL_CUTOFF_RATIO * to_hz,
                None,
            )
            .map_err(|e| e.to_string())?;
            Ok((h, pose.dim()))
        })
        .map_err(CablevibError::new_err)?;
    let (h, dim) = h;
    let num = |x: f64| {
        if x.is_finite() {
            serde_json::json!(x)
        } else {
            serde_json::Value::Null
        }
    };
    let cube = |re: bool| -> serde_json::Value {
        h.iter()
            .map(|m| {
                (0..dim)
                    .map(|i| {
                        (0..dim)
                            .map(|j| num(if re { m[(i, j)].re } else { m[(i, j)].im }))
                            .collect::<Vec<_>>()
                    })
                    .collect::<Vec<_>>()
            })
            .collect::<Vec<_>>()
            .into()
    };
    let value = serde_json::json!({
        "frequencies_hz": freqs,
        "receptance_re": cube(true),
        "receptance_im": cube(false),
        "damping": damping.kind_str(),
        "dim": dim,
    });
    let out = json_to_py(py, &value)?;
    // The cubes arrive as lists of N d × d arrays: one float64 array of shape (N, d, d),
    // as the stub says.
    let d = out.cast::<pyo3::types::PyDict>()?;
    for key in ["receptance_re", "receptance_im"] {
        if let Some(v) = d.get_item(key)? {
            d.set_item(key, asarray(py, v, "float64")?)?;
        }
    }
    Ok(out)
}

/// The receptance at one frequency, m/N (the leading `dim` × `dim` block).
type Receptance = Matrix6<Complex<f64>>;

/// Sagging cables, as ``cablevib frf`` does them: the sagged tension solve at the scene's
/// pose, then the sagged solver's condensed D at the complex λ of each frequency (FEM
/// chains; loss factor, Rayleigh or no damping).
fn sagged(s: &Scene, damping: &Damping, freqs: &[f64]) -> Result<(Vec<Receptance>, usize), String> {
    if s.model.element == ElementKind::Continuous {
        return Err(FrfError::SagContinuous.to_string());
    }
    if let Damping::ModalRatio { .. } = damping {
        return Err(FrfError::SagModalDamping.to_string());
    }
    let mut est = Estimator::new(s).map_err(|e| e.to_string())?;
    let pose = Pose::in_scene(s, s.ee_position_m);
    let e = *est.update(&pose, Tmin::Scene);
    if !e.status.is_ok() {
        let why = e.error.map(|x| x.to_string()).unwrap_or_default();
        return Err(format!("sagged pose: {why}"));
    }
    let mut sag = est.sag_modal().cloned().ok_or("no sagged pose loaded")?;
    let h = sag
        .receptance_over(damping, freqs)
        .map_err(|e| e.to_string())?;
    Ok((h, sag.dim()))
}
