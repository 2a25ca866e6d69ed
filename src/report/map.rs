//! `cablevib map`: the CSV of every grid point and the heat-map figure.

use super::csv::{point_fields, point_header, scene_comment, Csv};
use super::svg::{fmt_num, HeatMap, HeatPanel};
use crate::scene::Scene;
use crate::study::map::{max_of, pick, MapResult, MapValue};
use std::fmt::Write as _;

const AXIS_NAMES: [&str; 3] = ["x", "y", "z"];

/// The CSV: one row per grid point, with its status.
pub fn map_csv(s: &Scene, m: &MapResult) -> String {
    let comment = format!(
        "{}, T_min {} N, T_max {} N",
        scene_comment("map", s),
        s.t_min_n,
        s.t_max_n,
    );
    let mut csv = Csv::new(Some(&comment), &point_header(s.n_cables()));
    for r in &m.points {
        csv.row(&point_fields(r));
    }
    csv.into_string()
}

/// One panel per slice; the slice's maximum is marked when there is one slice, or when it is
/// the maximum of the whole grid.
fn panels(m: &MapResult, v: MapValue) -> Vec<HeatMap> {
    let (h, vv, sl) = m.plane.axes();
    let per = m.axes[h].len() * m.axes[vv].len();
    let gmax = m.max(v);
    let mut maps = Vec::new();
    for (k, &ws) in m.axes[sl].iter().enumerate() {
        let slice = &m.points[k * per..(k + 1) * per];
        let values: Vec<Option<f64>> = slice.iter().map(|p| pick(&p.estimate, v)).collect();
        let mut markers = Vec::new();
        let smax = max_of(slice, v);
        if let (Some((p, f)), Some((_, g))) = (smax, gmax) {
            let text = if f == g {
                format!("max {f:.3} Hz")
            } else {
                format!("{f:.3}")
            };
            if m.axes[sl].len() == 1 || f == g {
                markers.push((p[h], p[vv], text));
            }
        }
        let bad = values.iter().filter(|x| x.is_none()).count();
        maps.push(HeatMap {
            caption: format!(
                "{} = {} m{}",
                AXIS_NAMES[sl],
                fmt_num(ws),
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

/// The heat-map figure of a map.
pub fn map_svg(s: &Scene, m: &MapResult, v: MapValue) -> String {
    let (h, vv, sl) = m.plane.axes();
    let nh = m.axes[h].len();
    let maps = panels(m, v);
    let counts = m.status_counts();
    let vname = match v {
        MapValue::F1 => "first natural frequency",
        MapValue::EeMode => "end-effector mode",
    };
    let mut sub = format!(
        "{} × {} elements/cable, T_min {} N, T_max {} N, step {} m",
        s.model.element.as_str(),
        s.model.elements_per_cable,
        s.t_min_n,
        s.t_max_n,
        fmt_num(if nh > 1 {
            m.axes[h][1] - m.axes[h][0]
        } else {
            0.0
        })
    );
    if let Some((_, f)) = m.max(v) {
        let _ = write!(sub, "; max {f:.3} Hz");
    }
    if let Some((_, f)) = m.min(v) {
        let _ = write!(sub, ", min {f:.3} Hz");
    }
    let _ = write!(sub, "; {}", counts.summary());
    let single_slice = m.axes[sl].len() == 1;
    HeatPanel {
        title: format!(
            "{}: {vname}{}",
            s.name,
            if single_slice {
                format!(" ({} = {} m)", AXIS_NAMES[sl], fmt_num(m.axes[sl][0]))
            } else {
                String::new()
            }
        ),
        subtitle: sub,
        x_label: format!("{} (m)", AXIS_NAMES[h]),
        y_label: format!("{} (m)", AXIS_NAMES[vv]),
        value_label: "f (Hz)".into(),
        invalid_label: "no valid estimate".into(),
        maps,
        columns: panel_columns(m.axes[sl].len()),
        range: None,
    }
    .to_svg()
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
