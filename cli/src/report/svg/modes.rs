//! The mode-shape figure of `cablevib modes`: the first K mode shapes of the whole robot,
//! one panel per mode, in an axonometric projection seen from azimuth [`AZIMUTH_DEG`] and
//! elevation [`ELEVATION_DEG`] (screen right = x cos a − y sin a, screen up =
//! z cos e − (x sin a + y cos a) sin e; the same in every panel). Not the isometric view: that
//! one projects the paper robots' upper and lower anchors onto each other.
//!
//! Each panel shows the anchors (squares), the undeformed cables (grey, dashed) and
//! end-effector (grey ring), and the deformed cables and end-effector (coloured), the
//! displacements scaled so that the mode's largest node displacement is
//! [`AMPLITUDE_OF_EXTENT`] of the robot's extent (the mass-normalised amplitudes themselves
//! are in the CSV). A rigid end-effector is drawn as the spokes from its centroid to its
//! attachment points. The panel title gives the mode number, frequency, multiplicity and
//! end-effector participation.

use super::{escape, header, title};
use crate::kinematics::Geometry;
use crate::modal::ModeShapes;
use crate::report::shapes_csv::node_positions;
use crate::scene::Scene;
use nalgebra::Vector3;
use std::fmt::Write as _;

/// The largest displacement of a mode is drawn at this fraction of the robot's extent:
/// large enough to read, small enough to stay a small-displacement picture.
pub const AMPLITUDE_OF_EXTENT: f64 = 0.12;
/// Panel size, px.
const PANEL_W: f64 = 330.0;
const PANEL_H: f64 = 300.0;
/// Panels per row.
const COLUMNS: usize = 3;
/// Colour of the deformed shape.
const DEFORMED: &str = "#D55E00";

/// Azimuth of the view, degrees (rotation about z).
pub const AZIMUTH_DEG: f64 = 30.0;
/// Elevation of the view, degrees (above the x-y plane).
pub const ELEVATION_DEG: f64 = 20.0;

/// Axonometric projection (x, y, z) → (right, up).
fn iso(p: &Vector3<f64>) -> (f64, f64) {
    let (sa, ca) = AZIMUTH_DEG.to_radians().sin_cos();
    let (se, ce) = ELEVATION_DEG.to_radians().sin_cos();
    (p.x * ca - p.y * sa, p.z * ce - (p.x * sa + p.y * ca) * se)
}

/// Maps projected coordinates into one panel.
struct Frame {
    lo: (f64, f64),
    scale: f64,
    origin: (f64, f64),
    h: f64,
}

impl Frame {
    fn px(&self, p: &Vector3<f64>) -> (f64, f64) {
        let (u, v) = iso(p);
        (
            self.origin.0 + (u - self.lo.0) * self.scale,
            self.origin.1 + self.h - (v - self.lo.1) * self.scale,
        )
    }
}

fn polyline(o: &mut String, f: &Frame, pts: &[Vector3<f64>], style: &str) {
    let mut d = String::new();
    for p in pts {
        let (x, y) = f.px(p);
        let _ = write!(d, "{x:.1},{y:.1} ");
    }
    let _ = writeln!(
        o,
        r#"<polyline points="{}" fill="none" {style}/>"#,
        d.trim_end()
    );
}

/// The SVG of the first `k` shapes of `shapes` for the pose of `scene` with `geometry`.
pub fn modes_svg(scene: &Scene, geometry: &Geometry, shapes: &ModeShapes, k: usize) -> String {
    let k = k.min(shapes.modes.len()).max(1);
    let rows = k.div_ceil(COLUMNS);
    let cols = k.min(COLUMNS);
    let w = PANEL_W * cols as f64;
    let sub = format!(
        "model {} × {} elements/cable; view from azimuth {AZIMUTH_DEG}°, elevation {ELEVATION_DEG}°; displacements scaled to {:.0} % of the robot's extent",
        scene.model.element.as_str(),
        scene.model.elements_per_cable,
        100.0 * AMPLITUDE_OF_EXTENT
    );
    let mut body = String::new();
    let top = title(&mut body, w, &format!("Mode shapes: {}", scene.name), &sub);
    let h = top + PANEL_H * rows as f64 + 10.0;
    let mut o = header(w, h);
    o.push_str(&body);
    let p = scene.ee_position_m;
    let undeformed: Vec<Vec<Vector3<f64>>> = (0..shapes.fractions.len())
        .map(|i| node_positions(scene, geometry, i, &shapes.fractions[i]))
        .collect();
    let mut all: Vec<Vector3<f64>> = undeformed.iter().flatten().copied().collect();
    all.push(p);
    let (mut lo, mut hi) = (
        (f64::INFINITY, f64::INFINITY),
        (f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    let (mut bmin, mut bmax) = (all[0], all[0]);
    for q in &all {
        let (u, v) = iso(q);
        lo = (lo.0.min(u), lo.1.min(v));
        hi = (hi.0.max(u), hi.1.max(v));
        bmin = bmin.inf(q);
        bmax = bmax.sup(q);
    }
    let extent = (bmax - bmin).norm().max(1e-9);
    let amp = AMPLITUDE_OF_EXTENT * extent;
    let pad = amp * 1.2;
    lo = (lo.0 - pad, lo.1 - pad);
    hi = (hi.0 + pad, hi.1 + pad);
    let (iw, ih) = (PANEL_W - 30.0, PANEL_H - 50.0);
    let scale = (iw / (hi.0 - lo.0)).min(ih / (hi.1 - lo.1));
    for (idx, m) in shapes.modes.iter().take(k).enumerate() {
        let (r, c) = (idx / COLUMNS, idx % COLUMNS);
        let (x0, y0) = (c as f64 * PANEL_W, top + r as f64 * PANEL_H);
        let f = Frame {
            lo,
            scale,
            origin: (x0 + 15.0 + (iw - (hi.0 - lo.0) * scale) / 2.0, y0 + 35.0),
            h: (hi.1 - lo.1) * scale,
        };
        let mult = if m.multiplicity > 1 {
            format!(" (×{})", m.multiplicity)
        } else {
            String::new()
        };
        let _ = writeln!(
            o,
            r#"<text x="{:.1}" y="{:.1}" font-size="13" text-anchor="middle">{}</text>"#,
            x0 + PANEL_W / 2.0,
            y0 + 20.0,
            escape(&format!(
                "mode {}: {:.4} Hz{mult}, p_ee = {:.3}",
                idx + 1,
                m.frequency_hz,
                m.ee_participation
            ))
        );
        let umax = m
            .cables
            .iter()
            .flatten()
            .map(|u| u.norm())
            .fold(m.ee.fixed_rows::<3>(0).norm(), f64::max);
        let s = if umax > 0.0 { amp / umax } else { 0.0 };
        panel(&mut o, &f, &undeformed, m, p, s);
    }
    o.push_str("</svg>\n");
    o
}

/// One panel: anchors, undeformed and deformed cables and end-effector.
fn panel(
    o: &mut String,
    f: &Frame,
    undeformed: &[Vec<Vector3<f64>>],
    m: &crate::modal::ModeShape,
    p: Vector3<f64>,
    s: f64,
) {
    for nodes in undeformed {
        polyline(
            o,
            f,
            &[nodes[0], nodes[nodes.len() - 1]],
            r##"stroke="#999" stroke-width="1" stroke-dasharray="4 3""##,
        );
        let (ax, ay) = f.px(&nodes[0]);
        let _ = writeln!(
            o,
            r##"<rect x="{:.1}" y="{:.1}" width="6" height="6" fill="#333"/>"##,
            ax - 3.0,
            ay - 3.0
        );
    }
    let (ex, ey) = f.px(&p);
    let _ = writeln!(
        o,
        r##"<circle cx="{ex:.1}" cy="{ey:.1}" r="5" fill="none" stroke="#999" stroke-width="1.5"/>"##
    );
    let pd = p + m.ee.fixed_rows::<3>(0) * s;
    for (nodes, u) in undeformed.iter().zip(&m.cables) {
        let pts: Vec<Vector3<f64>> = nodes.iter().zip(u).map(|(x, d)| x + d * s).collect();
        polyline(
            o,
            f,
            &pts,
            &format!(r#"stroke="{DEFORMED}" stroke-width="1.5""#),
        );
        // Spoke from the centroid to the attachment point (a point where they coincide).
        polyline(
            o,
            f,
            &[pd, pts[pts.len() - 1]],
            &format!(r#"stroke="{DEFORMED}" stroke-width="1""#),
        );
    }
    let (dx, dy) = f.px(&pd);
    let _ = writeln!(
        o,
        r#"<circle cx="{dx:.1}" cy="{dy:.1}" r="4.5" fill="{DEFORMED}"/>"#
    );
}
