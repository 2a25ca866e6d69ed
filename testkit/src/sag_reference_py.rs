//! Calling the independent sagged-cable reference, tests/py/sag_reference.py (numpy + scipy,
//! no code shared with the crate), from Rust tests.
//!
//! The reference runs in a venv under `target/` with pinned numpy and scipy (NUMPY_VERSION,
//! SCIPY_VERSION), created and provisioned on first use; it needs `python3` with the venv
//! module and PyPI. A request is a JSON object (schema: `sag_reference.py --schema` and the
//! module docs of the script); the answer is JSON.
//!
//! For comparisons with the crate: [`reference_at`] takes a scene, a pose and each cable's
//! unstretched length L0 and returns [`RefAnswer`], solved at 80, 160 and 320 elements per
//! cable with the Richardson extrapolation (order 2) of the two finest levels, good to
//! ~1e-8 relative on these scenes. Use [`RefAnswer::extrapolated`] for the continuous
//! (N → ∞) values and [`RefAnswer::at_level`] for the model at a given element count.

use cablevib::scene::Scene;
use serde_json::{json, Value};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;

use crate::pinned_venv;

/// numpy pinned for the reference (wheels for Python 3.11).
pub const NUMPY_VERSION: &str = "2.1.3";
/// scipy pinned for the reference (wheels for Python 3.11, numpy 2.1).
pub const SCIPY_VERSION: &str = "1.14.1";
/// The element counts of the convergence study: Richardson from the two finest, the
/// observed order from all three.
pub const LEVELS: [usize; 3] = [80, 160, 320];

fn manifest() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

/// The reference script.
pub fn script() -> PathBuf {
    manifest().join("tests/py/sag_reference.py")
}

/// The venv's python with the pinned numpy and scipy, created once per test binary.
pub fn venv_python() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(|| {
        pinned_venv::pinned_venv_python(
            &format!("py-sagref-numpy{NUMPY_VERSION}-scipy{SCIPY_VERSION}"),
            &[
                ("numpy", "numpy", NUMPY_VERSION),
                ("scipy", "scipy", SCIPY_VERSION),
            ],
        )
    })
}

/// Run the reference on one request; panics with the script's message on failure.
pub fn run_reference(request: &Value) -> Value {
    let mut child = Command::new(venv_python())
        .arg(script())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run sag_reference.py");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(request.to_string().as_bytes())
        .expect("write request");
    let out = child.wait_with_output().expect("sag_reference.py output");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "sag_reference.py failed: {text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&text).expect("sag_reference.py JSON")
}

/// The request's robot part for a point-mass scene at `position_m` (no L0 yet).
pub fn scene_request(scene: &Scene, position_m: [f64; 3]) -> serde_json::Map<String, Value> {
    assert!(
        !scene.rigid,
        "{}: the reference models a point-mass end-effector only",
        scene.name
    );
    let anchors: Vec<[f64; 3]> = scene
        .cables
        .iter()
        .map(|c| [c.anchor_m.x, c.anchor_m.y, c.anchor_m.z])
        .collect();
    let ea: Vec<f64> = scene.cables.iter().map(|c| c.ea_n()).collect();
    let mu: Vec<f64> = scene
        .cables
        .iter()
        .map(|c| c.mass_per_length_kg_m)
        .collect();
    let g = scene.gravity_m_s2;
    let v = json!({
        "anchors_m": anchors,
        "ee_position_m": position_m,
        "ee_mass_kg": scene.ee_mass_kg,
        "gravity_m_s2": [g.x, g.y, g.z],
        "ea_n": ea,
        "mu_kg_m": mu,
        "ee_weight_carried": scene.weight_carried,
    });
    match v {
        Value::Object(m) => m,
        _ => unreachable!("json! of an object"),
    }
}

/// The reference at `position_m` with each cable's unstretched length `l0_m`, solved at
/// [`LEVELS`] with `modes` frequencies. `scene` is a scene file or an embedded name.
pub fn reference_at(scene: &str, position_m: [f64; 3], l0_m: &[f64], modes: usize) -> RefAnswer {
    let s = Scene::load(scene).unwrap_or_else(|e| panic!("{scene}: {e}"));
    let mut req = scene_request(&s, position_m);
    req.insert("unstretched_lengths_m".into(), json!(l0_m));
    req.insert("modes".into(), json!(modes));
    req.insert("convergence_levels".into(), json!(LEVELS));
    RefAnswer(run_reference(&Value::Object(req)))
}

/// The reference's answer (see the script's docs for every key).
pub struct RefAnswer(pub Value);

impl RefAnswer {
    /// The Richardson-extrapolated (N → ∞) values of `key`: "ee_position_m",
    /// "stiffness_principal_n_m", "tension_ee_n", "tension_anchor_n", "h_n",
    /// "frequencies_hz".
    pub fn extrapolated(&self, key: &str) -> Vec<f64> {
        f64s(&self.0["richardson"]["extrapolated"][key])
    }

    /// The Richardson error estimate of `key` (|extrapolated − finest|), same units.
    pub fn error_estimate(&self, key: &str) -> Vec<f64> {
        f64s(&self.0["richardson"]["error_estimate"][key])
    }

    /// The answer at `elements` per cable (one of [`LEVELS`]).
    pub fn at_level(&self, elements: usize) -> &Value {
        self.0["levels"]
            .as_array()
            .expect("levels")
            .iter()
            .find(|l| l["elements"].as_u64() == Some(elements as u64))
            .unwrap_or_else(|| panic!("no level with {elements} elements"))
    }

    /// Per-cable values of `key` ("tension_ee_n", "tension_anchor_n", "h_n", ...) at a level.
    pub fn cable_values(level: &Value, key: &str) -> Vec<f64> {
        level["cables"]
            .as_array()
            .expect("cables")
            .iter()
            .map(|c| c[key].as_f64().expect("number"))
            .collect()
    }
}

/// A JSON array of numbers.
pub fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("not an array: {v}"))
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}
