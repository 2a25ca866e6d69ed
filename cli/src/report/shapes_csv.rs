//! The mode-shape CSV of `cablevib modes` and `cablevib analyze --shapes`: one row per node
//! per mode, one header row, no comment line; scene, model and the columns' units are in the
//! `PATH.json` sidecar ([`super::csv::write_csv`]).
//!
//! ```text
//! mode,frequency_hz,cable,node,x_m,y_m,z_m,ux,uy,uz
//! ```
//!
//! - `mode`: 1, 2, … ascending in frequency (a cluster of multiplicity m is m consecutive
//!   modes with the same frequency, by descending end-effector participation);
//! - `frequency_hz`: the natural frequency, Hz;
//! - `cable`: 1 … n for the cables; 0 for the end-effector;
//! - `node`: for a cable, 0 (anchor) … N (the attachment point on the end-effector), equally
//!   spaced along the chord (a continuous cable: its sample points); for the end-effector,
//!   node 0 is the centroid's translation and, for a rigid body, node 1 its rotation;
//! - `x_m, y_m, z_m`: the node's undeformed position, m (the centroid for both end-effector
//!   rows);
//! - `ux, uy, uz`: the mass-normalised displacement (φᵀMφ = 1 with the model's consistent
//!   mass), 1/√kg; on the rigid body's rotation row the rotation vector, rad/(m·√kg).

use super::csv::{num, scene_meta, Column, Csv};
use crate::kinematics::Geometry;
use crate::modal::ModeShapes;
use crate::scene::Scene;
use crate::study::progress::Progress;
use nalgebra::Vector3;

/// The CSV header.
pub const SHAPES_HEADER: &str = "mode,frequency_hz,cable,node,x_m,y_m,z_m,ux,uy,uz";

/// The undeformed positions (m) of cable `i`'s nodes at `fractions` of its chord, anchor (or
/// its pulley's exit point, `geometry.exit_m`) to attachment point.
pub fn node_positions(
    scene: &Scene,
    geometry: &Geometry,
    i: usize,
    fractions: &[f64],
) -> Vec<Vector3<f64>> {
    let a = geometry.exit_m[i];
    let end = scene.ee_position_m + geometry.arm_m[i];
    fractions.iter().map(|&t| a + (end - a) * t).collect()
}

/// The columns: name, unit, meaning (their names joined are [`SHAPES_HEADER`]).
const SHAPES_COLUMNS: [(&str, &str, &str); 10] = [
    ("mode", "", "mode number, 1 = lowest"),
    ("frequency_hz", "Hz", "natural frequency"),
    ("cable", "", "cable number from 1; 0 = the end-effector"),
    (
        "node",
        "",
        "node from the anchor (0); end-effector: 0 translation, 1 rotation",
    ),
    ("x_m", "m", "undeformed node position x"),
    ("y_m", "m", "undeformed node position y"),
    ("z_m", "m", "undeformed node position z"),
    (
        "ux",
        "1/sqrt(kg)",
        "mass-normalised displacement x (rotation row: rad/(m sqrt(kg)))",
    ),
    ("uy", "1/sqrt(kg)", "mass-normalised displacement y"),
    ("uz", "1/sqrt(kg)", "mass-normalised displacement z"),
];

/// The CSV of `shapes` for the pose of `scene` (its `ee_position_m`) with `geometry`; write
/// it with [`super::csv::write_csv`] (text and sidecar) or take its text with
/// [`Csv::into_parts`]. A progress bar labelled `label` on a terminal (one step per mode).
pub fn shapes_csv(
    scene: &Scene,
    geometry: &Geometry,
    shapes: &ModeShapes,
    label: Option<&str>,
) -> Csv {
    let columns = SHAPES_COLUMNS
        .iter()
        .map(|&(n, u, d)| Column::new(n, u, d))
        .collect();
    let mut meta = scene_meta("modes", scene);
    meta.insert("modes".into(), serde_json::json!(shapes.modes.len()));
    let mut csv = Csv::new(columns, meta);
    let p = scene.ee_position_m;
    let positions: Vec<Vec<Vector3<f64>>> = (0..shapes.fractions.len())
        .map(|i| node_positions(scene, geometry, i, &shapes.fractions[i]))
        .collect();
    // The text of 10⁵ elements per cable is ~0.1 GB per mode (seconds each): a bar per mode.
    let bar = Progress::counting(label, shapes.modes.len(), "modes written");
    for (k, m) in shapes.modes.iter().enumerate() {
        let head = [(k + 1).to_string(), num(m.frequency_hz)];
        let mut row = |cable: usize, node: usize, x: &Vector3<f64>, u: &Vector3<f64>| {
            let (cable, node) = (cable.to_string(), node.to_string());
            let coords = [x.x, x.y, x.z, u.x, u.y, u.z].map(num);
            csv.row(head.iter().chain([&cable, &node]).chain(coords.iter()));
        };
        row(0, 0, &p, &m.ee.fixed_rows::<3>(0).into_owned());
        if shapes.dim == 6 {
            row(0, 1, &p, &m.ee.fixed_rows::<3>(3).into_owned());
        }
        for (i, nodes) in m.cables.iter().enumerate() {
            for (j, u) in nodes.iter().enumerate() {
                row(i + 1, j, &positions[i][j], u);
            }
        }
        bar.advance(1);
    }
    bar.finish();
    csv
}
