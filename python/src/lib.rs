//! Python bindings of cablevib (PyO3): the extension module `cablevib._cablevib`, which the
//! package `cablevib` (py/cablevib/__init__.py) re-exports.
//!
//! | Python | Rust |
//! |---|---|
//! | `Scene.load(path_or_name)` | [`cablevib::scene::Scene::load`] |
//! | `analyze(scene, ...)` | [`cablevib::study::analysis::analyze`] (what `cablevib analyze --json` prints) |
//! | `calibrate(scene, measurements, fit=[...])` | [`cablevib::calibration::calibrate`] (what `cablevib calibrate --json` prints) |
//! | `frf(scene, ...)` | [`cablevib::study::frf::frf`] (what `cablevib frf --json` prints) |
//! | `simulate(scene, ...)`, `shape(scene, ...)` | [`cablevib::study::simulate::simulate_shaped`], [`cablevib::study::simulate::shape`] (what `cablevib simulate` and `cablevib shape` write to their CSVs) |
//! | `identify(t, channels, ...)` | [`cablevib::identify::identify`] (what `cablevib identify --json` prints per window, without the model) |
//! | `Estimator(scene).update(...)` | [`cablevib::estimator::Estimator::update`] |
//! | `Estimator.sweep(...)`, `sweep(scene, ...)` | [`cablevib::estimator::Estimator::update`] over many poses on worker threads (`sweep`) |
//! | `Estimator.t_min_for_f1(...)` | [`cablevib::estimator::Estimator::t_min_for_f1`] |
//! | `CablevibError` | every library error, with its `Display` text |
//!
//! Numbers cross as IEEE doubles, unchanged; vectors and matrices come out as float64
//! numpy arrays (SI units, named in every attribute).

mod analysis;
mod calibrate;
mod convert;
mod error;
mod estimator;
mod frf;
mod identify;
mod scene;
mod simulate;
mod sweep;
mod toml_text;

use pyo3::prelude::*;

/// cablevib: tension distribution, stiffness and natural frequencies of cable-driven
/// parallel robots (SI units: m, N, N/m, Hz).
#[pymodule]
#[pyo3(name = "_cablevib")]
fn cablevib_py(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("CablevibError", m.py().get_type::<error::CablevibError>())?;
    m.add_function(wrap_pyfunction!(analysis::analyze, m)?)?;
    m.add_function(wrap_pyfunction!(frf::frf, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate::calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(identify::identify, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::shape, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep_scene, m)?)?;
    m.add_class::<scene::PyScene>()?;
    m.add_class::<estimator::PyEstimator>()?;
    m.add_class::<estimator::PyEstimate>()?;
    m.add_class::<estimator::PyTminAnswer>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
