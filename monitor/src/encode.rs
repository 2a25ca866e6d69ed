//! The monitor's JSON channels: each wire message as one JSON object, its JSON Schema (stored in
//! the MCAP file and advertised over the WebSocket), and the way back for `replay`.
//!
//! Numbers are written by `serde_json` in the shortest form that parses back to the same
//! `f64` (and read back with its exact `float_roundtrip` parser), so a value read from a
//! recording is bit for bit the one on the wire. JSON has no NaN or infinity: a non-finite
//! value is written as `null` (an estimate's frequencies are NaN when its status is not ok).
//! Integers (sequences, timestamps in ns) are exact below 2⁵³ in a browser and exact in
//! Python and Rust.

use cablevib_ipc::{
    status_str, EstimateSample, MarginResponse, MeasuredStatus, PoseSample, TminSetpoint,
    MAX_CABLES, MAX_STIFFNESS_DIM, MEASURED_AGE_UNKNOWN,
};
use nalgebra::{Matrix3, SymmetricEigen};
use serde::{Deserialize, Serialize};

/// Schema name of the estimate channel.
pub const SCHEMA_ESTIMATE: &str = "cablevib.Estimate";
/// Schema name of the pose channel.
pub const SCHEMA_POSE: &str = "cablevib.Pose";
/// Schema name of the T_min set-point channel.
pub const SCHEMA_T_MIN: &str = "cablevib.TminSetpoint";
/// Schema name of the margin channel.
pub const SCHEMA_MARGIN: &str = "cablevib.MarginResponse";

/// The schema encoding of the JSON channels (MCAP and Foxglove WebSocket name).
pub const JSON_SCHEMA_ENCODING: &str = "jsonschema";
/// The message encoding of the JSON channels.
pub const JSON_MESSAGE_ENCODING: &str = "json";

/// One estimate as recorded: every field of [`EstimateSample`] (per-cable and stiffness
/// arrays cut to their valid entries), the status's name, the principal stiffnesses, the
/// service's pose → publish latency and the margin against the monitor's required f1.
#[derive(Debug, Clone, Serialize)]
pub struct EstimateRecord {
    /// `sequence` (the service's estimate count).
    pub sequence: u64,
    /// `pose_sequence`.
    pub pose_sequence: u64,
    /// `pose_timestamp_ns`.
    pub pose_timestamp_ns: u64,
    /// `receive_timestamp_ns`.
    pub receive_timestamp_ns: u64,
    /// `publish_timestamp_ns`.
    pub publish_timestamp_ns: u64,
    /// `status` (a status code).
    pub status: u32,
    /// The status code's name (`ok`, ...).
    pub status_name: String,
    /// `cable_count`.
    pub cable_count: u32,
    /// The valid tensions, N.
    pub tensions_n: Vec<f64>,
    /// `f1_hz`.
    pub f1_hz: f64,
    /// `ee_mode_hz`.
    pub ee_mode_hz: f64,
    /// `ee_mode_age_cycles`.
    pub ee_mode_age_cycles: u32,
    /// `f1_hz − required_f1_hz`, Hz (null without `--required-hz` or at a NaN f1).
    pub margin_hz: f64,
    /// The monitor's required f1, Hz (null when not given).
    pub required_f1_hz: f64,
    /// `stiffness_dim`.
    pub stiffness_dim: u32,
    /// The packed `stiffness_dim²` stiffness entries.
    pub stiffness: Vec<f64>,
    /// Eigenvalues of the translational 3×3 block, ascending, N/m.
    pub stiffness_principal_translation_n_m: Vec<f64>,
    /// Eigenvalues of the rotational 3×3 block (6-dimensional stiffness only), ascending,
    /// N·m/rad.
    pub stiffness_principal_rotation_nm_rad: Vec<f64>,
    /// `compute_ns`.
    pub compute_ns: u64,
    /// `publish_timestamp_ns − pose_timestamp_ns`: pose taken → estimate published, ns.
    pub latency_ns: u64,
    /// `eigen_evaluations`.
    pub eigen_evaluations: u32,
    /// `tension_iterations`.
    pub tension_iterations: u32,
    /// `eigen_residual`.
    pub eigen_residual: f64,
    /// `skipped_poses`.
    pub skipped_poses: u64,
    /// `measured_f1_hz`: the measured frequency near f1, Hz (null when not measured).
    pub measured_f1_hz: f64,
    /// `f1_residual_hz`: model − measured, Hz.
    pub f1_residual_hz: f64,
    /// `measured_ee_mode_hz`: the measured frequency near the end-effector mode, Hz.
    pub measured_ee_mode_hz: f64,
    /// `ee_mode_residual_hz`: model − measured, Hz.
    pub ee_mode_residual_hz: f64,
    /// `measured_age_ns` (null when neither frequency is measured).
    pub measured_age_ns: Option<u64>,
    /// `measured_f1_status` (a measured-status code).
    pub measured_f1_status: u32,
    /// Its name (`ok`, `no_input`, ...; `unknown` for a code this build does not know).
    pub measured_f1_status_name: &'static str,
    /// `measured_ee_mode_status`.
    pub measured_ee_mode_status: u32,
    /// Its name.
    pub measured_ee_mode_status_name: &'static str,
    /// `vibration_samples`.
    pub vibration_samples: u64,
    /// `vibration_refused`.
    pub vibration_refused: u64,
    /// `vibration_lost`.
    pub vibration_lost: u64,
}

/// The name of a measured-status code (`unknown` for one this build does not know).
fn measured_status_name(code: u32) -> &'static str {
    MeasuredStatus::from_u32(code).map_or("unknown", MeasuredStatus::as_str)
}

/// Eigenvalues (ascending) of the symmetric part of the 3×3 block of `k` (row-major,
/// dimension `dim`) starting at row and column `at`.
fn principal(k: &[f64], dim: usize, at: usize) -> Vec<f64> {
    if dim < at + 3 || k.len() < dim * dim {
        return Vec::new();
    }
    let m =
        Matrix3::from_fn(|r, c| 0.5 * (k[(at + r) * dim + at + c] + k[(at + c) * dim + at + r]));
    if !m.iter().all(|v| v.is_finite()) {
        return vec![f64::NAN; 3];
    }
    let mut v: Vec<f64> = SymmetricEigen::new(m).eigenvalues.iter().copied().collect();
    v.sort_by(f64::total_cmp);
    v
}

impl EstimateRecord {
    /// The record of `e`; `required_f1_hz` is the monitor's requirement (NaN: none).
    pub fn new(e: &EstimateSample, required_f1_hz: f64) -> EstimateRecord {
        let dim = (e.stiffness_dim as usize).min(MAX_STIFFNESS_DIM);
        let stiffness = e.stiffness_matrix().to_vec();
        EstimateRecord {
            sequence: e.sequence,
            pose_sequence: e.pose_sequence,
            pose_timestamp_ns: e.pose_timestamp_ns,
            receive_timestamp_ns: e.receive_timestamp_ns,
            publish_timestamp_ns: e.publish_timestamp_ns,
            status: e.status,
            status_name: status_str(e.status).to_string(),
            cable_count: e.cable_count,
            tensions_n: e.tensions().to_vec(),
            f1_hz: e.f1_hz,
            ee_mode_hz: e.ee_mode_hz,
            ee_mode_age_cycles: e.ee_mode_age_cycles,
            margin_hz: e.f1_hz - required_f1_hz,
            required_f1_hz,
            stiffness_dim: e.stiffness_dim,
            stiffness_principal_translation_n_m: principal(&stiffness, dim, 0),
            stiffness_principal_rotation_nm_rad: if dim == 6 {
                principal(&stiffness, dim, 3)
            } else {
                Vec::new()
            },
            stiffness,
            compute_ns: e.compute_ns,
            latency_ns: e.publish_timestamp_ns.saturating_sub(e.pose_timestamp_ns),
            eigen_evaluations: e.eigen_evaluations,
            tension_iterations: e.tension_iterations,
            eigen_residual: e.eigen_residual,
            skipped_poses: e.skipped_poses,
            measured_f1_hz: e.measured_f1_hz,
            f1_residual_hz: e.f1_residual_hz,
            measured_ee_mode_hz: e.measured_ee_mode_hz,
            ee_mode_residual_hz: e.ee_mode_residual_hz,
            measured_age_ns: (e.measured_age_ns != MEASURED_AGE_UNKNOWN)
                .then_some(e.measured_age_ns),
            measured_f1_status: e.measured_f1_status,
            measured_f1_status_name: measured_status_name(e.measured_f1_status),
            measured_ee_mode_status: e.measured_ee_mode_status,
            measured_ee_mode_status_name: measured_status_name(e.measured_ee_mode_status),
            vibration_samples: e.vibration_samples,
            vibration_refused: e.vibration_refused,
            vibration_lost: e.vibration_lost,
        }
    }
}

/// A pose as recorded and replayed.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PoseRecord {
    /// `sequence`.
    pub sequence: u64,
    /// `timestamp_ns`.
    pub timestamp_ns: u64,
    /// `position_m`.
    pub position_m: [f64; 3],
    /// `orientation_wxyz`.
    pub orientation_wxyz: [f64; 4],
    /// `flags`.
    pub flags: u32,
}

impl PoseRecord {
    /// The record of `p`.
    pub fn new(p: &PoseSample) -> PoseRecord {
        PoseRecord {
            sequence: p.sequence,
            timestamp_ns: p.timestamp_ns,
            position_m: p.position_m,
            orientation_wxyz: p.orientation_wxyz,
            flags: p.flags,
        }
    }

    /// The wire pose (a non-finite coordinate, recorded as null, cannot be replayed and is
    /// read as NaN, which the service answers with `invalid_input` as it did then).
    pub fn sample(&self) -> PoseSample {
        let mut p = PoseSample::new(
            self.sequence,
            self.timestamp_ns,
            self.position_m,
            self.orientation_wxyz,
        );
        p.flags = self.flags;
        p
    }
}

/// A T_min set-point as recorded and replayed.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TminRecord {
    /// `sequence`.
    pub sequence: u64,
    /// `timestamp_ns`.
    pub timestamp_ns: u64,
    /// `t_min_n`.
    pub t_min_n: f64,
    /// The valid per-cable values, N (empty: uniform).
    pub per_cable_t_min_n: Vec<f64>,
}

impl TminRecord {
    /// The record of `t`.
    pub fn new(t: &TminSetpoint) -> TminRecord {
        TminRecord {
            sequence: t.sequence,
            timestamp_ns: t.timestamp_ns,
            t_min_n: t.t_min_n,
            per_cable_t_min_n: t.per_cable_values().to_vec(),
        }
    }

    /// The wire set-point (`None` with more than `MAX_CABLES` values).
    pub fn sample(&self) -> Option<TminSetpoint> {
        if self.per_cable_t_min_n.len() > MAX_CABLES {
            return None;
        }
        TminSetpoint::per_cable(
            self.sequence,
            self.timestamp_ns,
            self.t_min_n,
            &self.per_cable_t_min_n,
        )
        .ok()
    }
}

/// A margin answer to the monitor's own request, as recorded.
#[derive(Debug, Clone, Serialize)]
pub struct MarginRecord {
    /// `request_sequence`.
    pub request_sequence: u64,
    /// `pose_sequence`.
    pub pose_sequence: u64,
    /// `status`.
    pub status: u32,
    /// The status code's name.
    pub status_name: String,
    /// The required f1 of the request, Hz.
    pub required_f1_hz: f64,
    /// `f1_hz`.
    pub f1_hz: f64,
    /// `margin_hz`.
    pub margin_hz: f64,
    /// `margin_ratio`.
    pub margin_ratio: f64,
    /// `t_min_required_n` (null while unknown or +∞).
    pub t_min_required_n: f64,
    /// `t_min_required_age_cycles`.
    pub t_min_required_age_cycles: u32,
    /// `timestamp_ns`.
    pub timestamp_ns: u64,
}

impl MarginRecord {
    /// The record of `r`, the answer to a request for `required_f1_hz`.
    pub fn new(r: &MarginResponse, required_f1_hz: f64) -> MarginRecord {
        MarginRecord {
            request_sequence: r.request_sequence,
            pose_sequence: r.pose_sequence,
            status: r.status,
            status_name: status_str(r.status).to_string(),
            required_f1_hz,
            f1_hz: r.f1_hz,
            margin_hz: r.margin_hz,
            margin_ratio: r.margin_ratio,
            t_min_required_n: r.t_min_required_n,
            t_min_required_age_cycles: r.t_min_required_age_cycles,
            timestamp_ns: r.timestamp_ns,
        }
    }
}

const NUM: &str = r#"{"type": ["number", "null"]}"#;
const INT: &str = r#"{"type": "integer", "minimum": 0}"#;

fn schema(title: &str, fields: &[(&str, String)]) -> String {
    let props: Vec<String> = fields
        .iter()
        .map(|(k, v)| format!("\"{k}\": {v}"))
        .collect();
    let required: Vec<String> = fields.iter().map(|(k, _)| format!("\"{k}\"")).collect();
    format!(
        "{{\"$schema\": \"https://json-schema.org/draft/2020-12/schema\", \"title\": \"{title}\", \
         \"type\": \"object\", \"properties\": {{{}}}, \"required\": [{}]}}",
        props.join(", "),
        required.join(", ")
    )
}

fn array_of(item: &str) -> String {
    format!("{{\"type\": \"array\", \"items\": {item}}}")
}

/// The JSON Schema of [`EstimateRecord`].
pub fn estimate_schema() -> String {
    let n = || NUM.to_owned();
    let i = || INT.to_owned();
    schema(
        SCHEMA_ESTIMATE,
        &[
            ("sequence", i()),
            ("pose_sequence", i()),
            ("pose_timestamp_ns", i()),
            ("receive_timestamp_ns", i()),
            ("publish_timestamp_ns", i()),
            ("status", i()),
            ("status_name", r#"{"type": "string"}"#.into()),
            ("cable_count", i()),
            ("tensions_n", array_of(NUM)),
            ("f1_hz", n()),
            ("ee_mode_hz", n()),
            ("ee_mode_age_cycles", i()),
            ("margin_hz", n()),
            ("required_f1_hz", n()),
            ("stiffness_dim", i()),
            ("stiffness", array_of(NUM)),
            ("stiffness_principal_translation_n_m", array_of(NUM)),
            ("stiffness_principal_rotation_nm_rad", array_of(NUM)),
            ("compute_ns", i()),
            ("latency_ns", i()),
            ("eigen_evaluations", i()),
            ("tension_iterations", i()),
            ("eigen_residual", n()),
            ("skipped_poses", i()),
            ("measured_f1_hz", n()),
            ("f1_residual_hz", n()),
            ("measured_ee_mode_hz", n()),
            ("ee_mode_residual_hz", n()),
            (
                "measured_age_ns",
                r#"{"type": ["integer", "null"], "minimum": 0}"#.into(),
            ),
            ("measured_f1_status", i()),
            ("measured_f1_status_name", r#"{"type": "string"}"#.into()),
            ("measured_ee_mode_status", i()),
            (
                "measured_ee_mode_status_name",
                r#"{"type": "string"}"#.into(),
            ),
            ("vibration_samples", i()),
            ("vibration_refused", i()),
            ("vibration_lost", i()),
        ],
    )
}

/// The JSON Schema of [`PoseRecord`].
pub fn pose_schema() -> String {
    schema(
        SCHEMA_POSE,
        &[
            ("sequence", INT.into()),
            ("timestamp_ns", INT.into()),
            ("position_m", array_of(NUM)),
            ("orientation_wxyz", array_of(NUM)),
            ("flags", INT.into()),
        ],
    )
}

/// The JSON Schema of [`TminRecord`].
pub fn t_min_schema() -> String {
    schema(
        SCHEMA_T_MIN,
        &[
            ("sequence", INT.into()),
            ("timestamp_ns", INT.into()),
            ("t_min_n", NUM.into()),
            ("per_cable_t_min_n", array_of(NUM)),
        ],
    )
}

/// The JSON Schema of [`MarginRecord`].
pub fn margin_schema() -> String {
    let n = || NUM.to_owned();
    let i = || INT.to_owned();
    schema(
        SCHEMA_MARGIN,
        &[
            ("request_sequence", i()),
            ("pose_sequence", i()),
            ("status", i()),
            ("status_name", r#"{"type": "string"}"#.into()),
            ("required_f1_hz", n()),
            ("f1_hz", n()),
            ("margin_hz", n()),
            ("margin_ratio", n()),
            ("t_min_required_n", n()),
            ("t_min_required_age_cycles", i()),
            ("timestamp_ns", i()),
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use cablevib_ipc::StatusCode;

    #[test]
    fn values_round_trip_bit_for_bit_and_nan_is_null() {
        let mut e = EstimateSample::with_status(StatusCode::Ok);
        // Values whose shortest decimal forms are long, and a subnormal.
        let t = [0.1 + 0.2, 1.0 / 3.0, 5e-324, 123456.789e10];
        e.set_tensions(&t).unwrap();
        e.f1_hz = std::f64::consts::PI;
        let k: Vec<f64> = (0..9).map(|i| (i as f64).sqrt()).collect();
        e.set_stiffness(3, &k).unwrap();
        let text = serde_json::to_string(&EstimateRecord::new(&e, f64::NAN)).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        let back: Vec<f64> = v["tensions_n"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        for (a, b) in t.iter().zip(&back) {
            assert_eq!(a.to_bits(), b.to_bits(), "{a} → {b}");
        }
        assert_eq!(v["f1_hz"].as_f64().unwrap().to_bits(), e.f1_hz.to_bits());
        assert!(v["ee_mode_hz"].is_null() && v["margin_hz"].is_null());
        // Without vibration input: the statuses by name, no age.
        assert_eq!(v["measured_ee_mode_status_name"], "no_input");
        assert!(v["measured_age_ns"].is_null() && v["measured_ee_mode_hz"].is_null());
        // A measured end-effector mode, bit for bit, with its age.
        e.measured_ee_mode_hz = 29.0 + 1.0 / 3.0;
        e.ee_mode_residual_hz = -0.1 - 0.2;
        e.measured_age_ns = 1_000_000_007;
        e.measured_ee_mode_status = MeasuredStatus::Ok.as_u32();
        e.measured_f1_status = 99;
        let v = serde_json::to_value(EstimateRecord::new(&e, f64::NAN)).unwrap();
        assert_eq!(
            v["measured_ee_mode_hz"].as_f64().unwrap().to_bits(),
            e.measured_ee_mode_hz.to_bits()
        );
        assert_eq!(
            v["ee_mode_residual_hz"].as_f64().unwrap().to_bits(),
            e.ee_mode_residual_hz.to_bits()
        );
        assert_eq!(v["measured_age_ns"], 1_000_000_007u64);
        assert_eq!(v["measured_ee_mode_status_name"], "ok");
        assert_eq!(v["measured_f1_status_name"], "unknown");
        // The schema is JSON and names exactly the record's fields.
        let schema: serde_json::Value = serde_json::from_str(&estimate_schema()).unwrap();
        let mut fields: Vec<&String> = v.as_object().unwrap().keys().collect();
        let mut props: Vec<&String> = schema["properties"].as_object().unwrap().keys().collect();
        fields.sort();
        props.sort();
        assert_eq!(fields, props);
        let _: serde_json::Value = serde_json::from_str(&margin_schema()).unwrap();
    }

    #[test]
    fn principal_stiffness_of_a_diagonal_block_is_its_diagonal() {
        // Independent check: the eigenvalues of a diagonal matrix are its entries.
        let mut k = [0.0; 36];
        for (i, d) in [3.0, 1.0, 2.0, 30.0, 10.0, 20.0].iter().enumerate() {
            k[i * 6 + i] = *d;
        }
        assert_eq!(principal(&k, 6, 0), vec![1.0, 2.0, 3.0]);
        assert_eq!(principal(&k, 6, 3), vec![10.0, 20.0, 30.0]);
        assert!(principal(&k[..9], 3, 3).is_empty());
    }

    #[test]
    fn the_foxglove_layout_plots_fields_the_estimates_have() {
        // docs/foxglove/cablevib-layout.json names message paths by hand: each must be a field
        // of the schema of its channel (topics of the bare namespace), or a plot stays empty.
        let layout = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../docs/foxglove/cablevib-layout.json"
        ))
        .unwrap();
        let v: serde_json::Value = serde_json::from_str(&layout).unwrap();
        let schemas = [
            (crate::run::topic("", "estimate"), estimate_schema()),
            (crate::run::topic("", "margin"), margin_schema()),
        ];
        let mut checked = 0;
        for panel in v["configById"].as_object().unwrap().values() {
            for path in panel["paths"].as_array().into_iter().flatten() {
                let p = path["value"].as_str().unwrap();
                let (topic, field) = p.split_once('.').unwrap();
                let field = field.split('[').next().unwrap();
                let (_, schema) = schemas
                    .iter()
                    .find(|(t, _)| t == topic)
                    .unwrap_or_else(|| panic!("{p}: no such topic"));
                let s: serde_json::Value = serde_json::from_str(schema).unwrap();
                assert!(
                    s["properties"].get(field).is_some(),
                    "{p}: no field {field}"
                );
                checked += 1;
            }
        }
        assert!(checked >= 4, "{checked}");
        let scene = &v["configById"]["3D!cablevib"]["topics"];
        assert!(scene.get(crate::run::topic("", "scene")).is_some());
    }
}
