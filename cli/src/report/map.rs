//! `cablevib map`: the CSV of every grid point and the heat-map figure (with contour lines,
//! the frame and the anchors projected on the map's plane).

use super::csv::{point_columns, point_fields, scene_meta, Csv};
use super::svg::{fmt_num, HeatMap, HeatPanel};
use crate::scene::Scene;
use crate::study::map::{max_of, pick, MapResult, MapValue};
use serde_json::json;
use std::fmt::Write as _;

const AXIS_NAMES: [&str; 3] = ["x", "y", "z"];

/// The CSV: one row per grid point, with its status (columns: [`point_columns`]).
pub fn map_csv(s: &Scene, m: &MapResult) -> Csv {
    let mut meta = scene_meta("map", s);
    let (h, v, sl) = m.plane.axes();
    meta.insert(
        "plane".into(),
        json!(format!("{}{}", AXIS_NAMES[h], AXIS_NAMES[v])),
    );
    meta.insert("slice_axis".into(), json!(AXIS_NAMES[sl]));
    if !m.tilts_deg.is_empty() {
        let a = m.tilt_axis;
        meta.insert("tilt_axis".into(), json!([a.x, a.y, a.z]));
        meta.insert("tilts_deg".into(), json!(m.tilts_deg));
    }
    meta.insert("modes".into(), json!(modes_of(m)));
    if let Some(sh) = m.shard {
        meta.insert(
            "shard".into(),
            json!({"index": sh.index, "count": sh.count, "grid_points": m.grid_points}),
        );
    }
    meta.insert(
        "order".into(),
        json!(if m.tilts_deg.is_empty() {
            "slice-major, then the vertical axis, then the horizontal axis"
        } else {
            "tilt-angle-major, then the vertical axis, then the horizontal axis"
        }),
    );
    let mut csv = Csv::new(point_columns(s.n_cables(), modes_of(m), s.rigid), meta);
    for r in &m.points {
        csv.row(point_fields(r, s.rigid));
    }
    csv
}

/// The mode count of a map (its configured count, so an empty shard has the columns of
/// the others).
fn modes_of(m: &MapResult) -> usize {
    m.modes
}

/// Name, unit and file-name part of a shown value.
pub fn value_names(v: MapValue) -> (String, &'static str, String) {
    match v {
        MapValue::F1 => ("first natural frequency".into(), "Hz", "f1".into()),
        MapValue::EeMode => ("end-effector mode".into(), "Hz", "ee-mode".into()),
        MapValue::Mode(k) => (
            format!("natural frequency of mode {k}"),
            "Hz",
            format!("f{k}"),
        ),
        MapValue::StiffnessMin => (
            "smallest static end-effector stiffness".into(),
            "N/m",
            "k-min".into(),
        ),
    }
}

/// One panel per slice; the slice's maximum is marked when there is one slice, or when it is
/// the maximum of the whole grid.
fn panels(m: &MapResult, v: MapValue) -> Vec<HeatMap> {
    let unit = value_names(v).1;
    let (h, vv, _) = m.plane.axes();
    let per = m.axes[h].len() * m.axes[vv].len();
    let gmax = m.max(v);
    let mut maps = Vec::new();
    for k in 0..m.panel_count() {
        let slice = &m.points[k * per..(k + 1) * per];
        let values: Vec<Option<f64>> = slice.iter().map(|p| pick(p, v)).collect();
        let mut markers = Vec::new();
        let smax = max_of(slice, v);
        if let (Some((p, f)), Some((_, g))) = (smax, gmax) {
            let text = if f == g {
                format!("max {} {unit}", fmt_value(f))
            } else {
                fmt_value(f)
            };
            if m.panel_count() == 1 || f == g {
                markers.push((p[h], p[vv], text));
            }
        }
        let bad = values.iter().filter(|x| x.is_none()).count();
        maps.push(HeatMap {
            caption: format!(
                "{}{}",
                panel_name(m, k),
                if bad > 0 {
                    format!(" ({bad} without value)")
                } else {
                    String::new()
                }
            ),
            x: m.axes[h].clone(),
            y: m.axes[vv].clone(),
            values,
            markers,
        });
    }
    maps
}

/// What panel k shows: `z = 1.25 m`, or `tilt 10°` when the map sweeps the orientation.
fn panel_name(m: &MapResult, k: usize) -> String {
    match m.tilts_deg.get(k) {
        Some(a) => format!("tilt {}°", fmt_num(*a)),
        None => {
            let sl = m.plane.axes().2;
            format!("{} = {} m", AXIS_NAMES[sl], fmt_num(m.axes[sl][k]))
        }
    }
}

/// The figure's title suffix: the slice of a one-slice map and the tilt axis.
fn title_suffix(m: &MapResult) -> String {
    let sl = m.plane.axes().2;
    let at = format!("{} = {} m", AXIS_NAMES[sl], fmt_num(m.axes[sl][0]));
    if !m.tilts_deg.is_empty() {
        let a = m.tilt_axis;
        let axis = [a.x, a.y, a.z].map(fmt_num).join(", ");
        format!(" ({at}, tilted about ({axis}))")
    } else if m.axes[sl].len() == 1 {
        format!(" ({at})")
    } else {
        String::new()
    }
}

/// The heat-map figure of a map.
pub fn map_svg(s: &Scene, m: &MapResult, v: MapValue) -> String {
    let (h, vv, _) = m.plane.axes();
    let nh = m.axes[h].len();
    let maps = panels(m, v);
    let counts = m.status_counts();
    let (vname, unit, _) = value_names(v);
    let mut sub = format!(
        "{} × {} elements/cable, T_min {}, T_max {} N, step {} m",
        s.model.element.as_str(),
        s.model.elements_per_cable,
        s.t_min_label(),
        s.t_max_n,
        fmt_num(if nh > 1 {
            m.axes[h][1] - m.axes[h][0]
        } else {
            0.0
        })
    );
    if let Some((_, f)) = m.max(v) {
        let _ = write!(sub, "; max {} {unit}", fmt_value(f));
    }
    if let Some((_, f)) = m.min(v) {
        let _ = write!(sub, ", min {} {unit}", fmt_value(f));
    }
    let _ = write!(sub, "; {}", counts.summary());
    HeatPanel {
        title: format!("{}: {vname}{}", s.name, title_suffix(m)),
        subtitle: sub,
        x_label: format!("{} (m)", AXIS_NAMES[h]),
        y_label: format!("{} (m)", AXIS_NAMES[vv]),
        value_label: if unit == "Hz" {
            "f (Hz)".into()
        } else {
            format!("k_min ({unit})")
        },
        invalid_label: "no valid estimate".into(),
        maps,
        columns: panel_columns(m.panel_count()),
        range: None,
        frame: Some(frame(s, h, vv)),
        anchors: s
            .cables
            .iter()
            .map(|c| (c.anchor_m[h], c.anchor_m[vv]))
            .collect(),
        contours: true,
    }
    .to_svg()
}

/// The frame (the anchors' bounding box) projected on the map's plane, axes `h` and `v`:
/// [x0, y0, x1, y1], m.
fn frame(s: &Scene, h: usize, v: usize) -> [f64; 4] {
    let (lo, hi) = s.frame_bounds_m();
    [lo[h], lo[v], hi[h], hi[v]]
}

/// A shown value: 3 decimals (Hz-sized values keep today's format), or 4 significant
/// digits for large values (stiffnesses, N/m).
fn fmt_value(x: f64) -> String {
    if x.abs() < 1e4 {
        format!("{x:.3}")
    } else {
        format!("{x:.3e}")
    }
}

/// Panels per row for `n` slices: up to 3 in one row, 4 as 2 × 2, then rows of 3 or 4.
fn panel_columns(n: usize) -> usize {
    match n {
        0..=3 => n.max(1),
        4 => 2,
        5..=9 => 3,
        _ => 4,
    }
}
