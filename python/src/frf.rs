//! `cablevib.frf`: the end-effector receptance over a frequency band, what
//! ``cablevib frf SCENE --json`` prints: the library's `study::frf::frf`, the one
//! orchestration both call.

use crate::analysis::{finite_position, with_overrides};
use crate::convert::{array1, array3};
use crate::error::CablevibError;
use crate::scene::PyScene;
use cablevib::study::frf::{frf as frf_study, DampingChoice, FrfConfig};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The receptance H(ω) = [K + iωC − ω²M]⁻¹ at the end-effector over a band: what
/// ``cablevib frf SCENE --json`` prints, as a dict with numpy arrays.
///
/// ``from_hz``, ``to_hz``, ``points``, ``log`` as ``--from-hz``, ``--to-hz``, ``--points``,
/// ``--log``; ``position``, ``t_min``, ``element``, ``elements`` as in ``analyze``. Damping:
/// the scene's ``[damping]``, or one of ``loss_factor`` (η), ``rayleigh`` ((α 1/s, β s)),
/// ``modal_ratio`` (ζ), ``undamped=True``.
///
/// With sag (``[effects] sag = true``) the response is the sagged FEM chains' at the sagged
/// tensions of the pose, as on the command line: modal damping by superposition of the
/// sagged shapes, ``element="continuous"`` refused.
///
/// Keys: ``frequencies_hz`` (N), ``receptance_re``, ``receptance_im`` (N × d × d float64
/// arrays, m/N; d = 3, or 6 for a rigid end-effector, translations first; NaN or inf where
/// an undamped response is infinite), ``natural_frequencies_hz`` (the band's natural
/// frequencies whose modes move the end-effector, Hz), ``damping``, ``dim``.
/// Raises CablevibError with the command line's message (the parameter named as here) on a
/// bad range or damping value.
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
    let cfg = FrfConfig {
        from_hz,
        to_hz,
        points,
        log,
        damping: DampingChoice {
            loss_factor,
            rayleigh,
            modal_ratio,
            undamped,
        },
        dense: None,
        progress: None,
    };
    let mut s = scene.inner.clone();
    if let Some(p) = position {
        s.ee_position_m = finite_position(p)?;
    }
    let s = with_overrides(s, t_min, element, elements)?;
    let r = py
        .detach(|| frf_study(&s, &cfg))
        .map_err(|e| CablevibError::new_err(e.to_string()))?;
    let part = |re: bool| -> Vec<f64> {
        let mut v = Vec::with_capacity(r.receptance.len() * r.dim * r.dim);
        for m in &r.receptance {
            for i in 0..r.dim {
                for j in 0..r.dim {
                    v.push(if re { m[(i, j)].re } else { m[(i, j)].im });
                }
            }
        }
        v
    };
    let shape = [r.receptance.len(), r.dim, r.dim];
    let d = PyDict::new(py);
    d.set_item("frequencies_hz", array1(py, &r.frequencies_hz)?)?;
    d.set_item("receptance_re", array3(py, &part(true), shape)?)?;
    d.set_item("receptance_im", array3(py, &part(false), shape)?)?;
    d.set_item("natural_frequencies_hz", array1(py, &r.natural_hz)?)?;
    d.set_item("damping", r.damping.kind_str())?;
    d.set_item("dim", r.dim)?;
    Ok(d.into_any())
}
