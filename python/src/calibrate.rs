//! `cablevib.calibrate`: the library's `calibration::calibrate`, what ``cablevib calibrate
//! SCENE --data FILE --fit ... --json`` prints.

use crate::convert::json_to_py;
use crate::error::CablevibError;
use crate::scene::PyScene;
use cablevib::calibration::data::{read_modes, read_tensions};
use cablevib::calibration::{
    calibrate as calibrate_scene, CalibrationParams, FitSpec, SigmaDefaults,
};
use pyo3::prelude::*;
use std::collections::HashMap;
use std::path::PathBuf;

/// The entries of `m` sorted by name, so the first error is the same whatever the dict's
/// order.
fn sorted<T>(m: Option<HashMap<String, T>>) -> Vec<(String, T)> {
    let mut v: Vec<_> = m.unwrap_or_default().into_iter().collect();
    v.sort_by(|a, b| a.0.cmp(&b.0));
    v
}

/// Fits the scene's parameters ``fit`` (names as ``--fit``: ``ea_factor``, ``ea_factor.3``,
/// ``ea_factor_all``, ``hidden_length[.i]``, ``weight_per_length``, ``ee_mass``,
/// ``ee_inertia[.xx|yy|zz]``, ``ee_com[.x|y|z]``, ``pulley_radius``, ``modal_ratio``,
/// ``rayleigh[.alpha|beta]``) to the measured modes in the CSV file ``measurements`` (path;
/// ``cablevib identify``'s CSV as it is), with the measured tensions in ``tensions`` (path)
/// when given. ``sigma_rel``, ``damping_sigma_rel``, ``tension_sigma_rel`` as on the command
/// line; ``bounds`` ({name: (lo, hi)}), ``nominal`` ({name: value}) and ``prior``
/// ({name: sigma}) take a parameter's or a group's name, in SI units.
///
/// Returns what ``cablevib calibrate --json`` prints, as a dict: ``parameters`` (each with
/// ``name``, ``value``, ``std_error`` (None when undetermined), ``determined``, ...),
/// ``correlation``, ``singular_values``, ``undetermined``, ``chi2_per_dof``, ``fits``,
/// ``verdict``, ``residuals`` (per measured mode, before and after), ... Raises
/// CablevibError with the command line's one-line message on bad data or parameters.
#[pyfunction]
#[pyo3(signature = (scene, measurements, fit, tensions = None, sigma_rel = 0.005,
                    damping_sigma_rel = 0.2, tension_sigma_rel = 0.02, bounds = None,
                    nominal = None, prior = None))]
#[allow(clippy::too_many_arguments)]
pub fn calibrate<'py>(
    py: Python<'py>,
    scene: &PyScene,
    measurements: PathBuf,
    fit: Vec<String>,
    tensions: Option<PathBuf>,
    sigma_rel: f64,
    damping_sigma_rel: f64,
    tension_sigma_rel: f64,
    bounds: Option<HashMap<String, (f64, f64)>>,
    nominal: Option<HashMap<String, f64>>,
    prior: Option<HashMap<String, f64>>,
) -> PyResult<Bound<'py, PyAny>> {
    let err = |e: cablevib::calibration::CalibrationError| CablevibError::new_err(e.to_string());
    let s = &scene.inner;
    let names: Vec<&str> = fit.iter().map(String::as_str).collect();
    let mut spec = FitSpec::new(s, &names).map_err(err)?;
    for (name, (lo, hi)) in sorted(bounds) {
        spec.set_bounds(&name, lo, hi).map_err(err)?;
    }
    for (name, v) in sorted(nominal) {
        spec.set_nominal(&name, v).map_err(err)?;
    }
    for (name, v) in sorted(prior) {
        spec.set_prior(&name, v).map_err(err)?;
    }
    spec.check().map_err(err)?;
    let sigma = SigmaDefaults {
        frequency_rel: sigma_rel,
        damping_rel: damping_sigma_rel,
        tension_rel: tension_sigma_rel,
    };
    let report = py
        .detach(|| {
            let mut data = read_modes(&measurements, &sigma)?;
            if let Some(t) = &tensions {
                read_tensions(t, s.n_cables(), &sigma, &mut data)?;
            }
            calibrate_scene(s, &data, &spec, &CalibrationParams::default())
        })
        .map_err(err)?
        .report;
    let value = serde_json::to_value(&report)
        .map_err(|e| CablevibError::new_err(format!("calibration report: {e}")))?;
    json_to_py(py, &value)
}
