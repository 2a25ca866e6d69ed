//! The mode-shape CSV of `cablevib modes`: one row per node per mode, no comment line.
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

use super::csv::{num, Csv};
use crate::kinematics::Geometry;
use crate::modal::ModeShapes;
use crate::scene::Scene;
use nalgebra::Vector3;

/// The CSV header.
pub const SHAPES_HEADER: &str = "mode,frequency_hz,cable,node,x_m,y_m,z_m,ux,uy,uz";

/// The undeformed positions (m) of cable `i`'s nodes at `fractions` of its chord, anchor to
/// attachment point.
pub fn node_positions(
    scene: &Scene,
    geometry: &Geometry,
    i: usize,
    fractions: &[f64],
) -> Vec<Vector3<f64>> {
    let a = scene.cables[i].anchor_m;
    let end = scene.ee_position_m + geometry.arm_m[i];
    fractions.iter().map(|&t| a + (end - a) * t).collect()
}

/// The CSV text of `shapes` for the pose of `scene` (its `ee_position_m`) with `geometry`.
pub fn shapes_csv(scene: &Scene, geometry: &Geometry, shapes: &ModeShapes) -> String {
    let mut csv = Csv::new(None, SHAPES_HEADER);
    let p = scene.ee_position_m;
    let positions: Vec<Vec<Vector3<f64>>> = (0..shapes.fractions.len())
        .map(|i| node_positions(scene, geometry, i, &shapes.fractions[i]))
        .collect();
    for (k, m) in shapes.modes.iter().enumerate() {
        let head = format!("{},{}", k + 1, num(m.frequency_hz));
        let mut row = |cable: usize, node: usize, x: &Vector3<f64>, u: &Vector3<f64>| {
            csv.row(&format!(
                "{head},{cable},{node},{},{},{},{},{},{}",
                num(x.x),
                num(x.y),
                num(x.z),
                num(u.x),
                num(u.y),
                num(u.z)
            ));
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
    }
    csv.into_string()
}
