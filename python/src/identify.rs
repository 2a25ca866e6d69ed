//! `cablevib.identify`: modal parameters from measured vibration on numpy arrays (the
//! library's `identify::identify`, what ``cablevib identify --json`` prints per window,
//! without the model's pairing).

use crate::convert::json_to_py;
use crate::error::CablevibError;
use cablevib::identify::{identify_with_inputs as run, IdentifyParams, WindowResult};
use pyo3::prelude::*;
use serde_json::{json, Value};

/// A finite number as JSON, else null.
fn num(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

/// Modal identification (covariance-driven SSI, stabilisation diagram, clustering, jackknife
/// uncertainty) of a record: ``t`` (N times, s, increasing) and ``channels`` (N × l, or N for
/// one channel; any units, e.g. m/s²).
///
/// ``from_hz``, ``to_hz`` (the band; the sample rate must be at least 2.5 × ``to_hz``),
/// ``max_order``, ``block_rows``, ``frequency_tol``, ``damping_tol``, ``mac_min``,
/// ``max_damping``, ``window`` (s; ``None``: one window), ``overlap`` as the command line's
/// ``--from-hz`` … ``--overlap``. ``inputs`` (N × m, or N; e.g. a measured force in N): the
/// modes come from the H1 estimate and its modal fit, as ``--input``.
///
/// Returns ``{"windows": [{"index", "t_start_s", "t_end_s", "status", "samples", "rate_hz",
/// "gaps", "nonfinite_samples", "modes": [{"frequency_hz", "damping_ratio",
/// "frequency_std_hz", "damping_ratio_std", "frequency_spread_hz", "shape_re", "shape_im",
/// "stable_poles", "order", "coherence" (H1's; None without inputs)}]}]}``, modes ascending. Raises CablevibError with a one-line
/// reason on a bad record (time not increasing, rate too low for the band) or parameter.
#[pyfunction]
#[pyo3(signature = (t, channels, from_hz = 0.5, to_hz = 50.0, max_order = 60, block_rows = None,
                    frequency_tol = 0.01, damping_tol = 0.05, mac_min = 0.98, max_damping = 0.2,
                    window = None, overlap = 0.5, inputs = None))]
#[allow(clippy::too_many_arguments)]
pub fn identify<'py>(
    py: Python<'py>,
    t: &Bound<'py, PyAny>,
    channels: &Bound<'py, PyAny>,
    from_hz: f64,
    to_hz: f64,
    max_order: usize,
    block_rows: Option<usize>,
    frequency_tol: f64,
    damping_tol: f64,
    mac_min: f64,
    max_damping: f64,
    window: Option<f64>,
    overlap: f64,
    inputs: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let np = py.import("numpy")?;
    let f64s = |obj: &Bound<'py, PyAny>| -> PyResult<(Vec<f64>, Vec<usize>)> {
        let a = np.call_method1("ascontiguousarray", (obj, "<f8"))?;
        let shape: Vec<usize> = a.getattr("shape")?.extract()?;
        let bytes: Vec<u8> = a.call_method0("tobytes")?.extract()?;
        let v = bytes
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
            .collect();
        Ok((v, shape))
    };
    let (t, ts) = f64s(t)?;
    let (y, ys) = f64s(channels)?;
    if ts.len() != 1 {
        return Err(CablevibError::new_err(format!(
            "t: a 1-D array expected, got shape {ts:?}"
        )));
    }
    let width = |name: &str, s: &[usize]| match s[..] {
        [n] if n == t.len() => Ok(1),
        [n, l] if n == t.len() => Ok(l),
        _ => Err(CablevibError::new_err(format!(
            "{name}: shape {s:?}, expected ({},) or ({}, {name})",
            t.len(),
            t.len()
        ))),
    };
    let l = width("channels", &ys)?;
    let (u, m) = match inputs {
        Some(obj) => {
            let (u, us) = f64s(obj)?;
            let m = width("inputs", &us)?;
            (u, m)
        }
        None => (Vec::new(), 0),
    };
    let p = IdentifyParams {
        from_hz,
        to_hz,
        max_order,
        block_rows,
        frequency_tol,
        damping_tol,
        mac_min,
        max_damping_ratio: max_damping,
        window_s: window,
        overlap,
        ..IdentifyParams::default()
    };
    let w = py
        .detach(|| run(&t, &y, l, &u, m, &p))
        .map_err(|e| CablevibError::new_err(e.to_string()))?;
    json_to_py(
        py,
        &json!({ "windows": w.iter().map(window_json).collect::<Vec<_>>() }),
    )
}

fn window_json(r: &WindowResult) -> Value {
    let modes: Vec<Value> = r
        .modes
        .iter()
        .map(|m| {
            json!({
                "frequency_hz": num(m.frequency_hz),
                "damping_ratio": num(m.damping_ratio),
                "frequency_std_hz": num(m.frequency_std_hz),
                "damping_ratio_std": num(m.damping_ratio_std),
                "frequency_spread_hz": num(m.frequency_spread_hz),
                "shape_re": m.shape.iter().map(|z| num(z.re)).collect::<Vec<_>>(),
                "shape_im": m.shape.iter().map(|z| num(z.im)).collect::<Vec<_>>(),
                "stable_poles": m.stable_poles,
                "order": m.order,
                "coherence": num(m.coherence),
            })
        })
        .collect();
    json!({
        "index": r.index,
        "t_start_s": num(r.t_start_s),
        "t_end_s": num(r.t_end_s),
        "status": r.status.as_str(),
        "samples": r.samples,
        "rate_hz": num(r.rate_hz),
        "gaps": r.gaps,
        "nonfinite_samples": r.nonfinite,
        "modes": modes,
    })
}
