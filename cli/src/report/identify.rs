//! `cablevib identify`'s files: the CSV of the identified modes per window (the columns
//! `cablevib calibrate` reads, in their agreed order, then one column per measured channel
//! with the mode shape) and the stabilisation diagram.

use super::csv::{Column, Csv};
use super::svg::axis::Axis;
use super::svg::line_plot::{LinePlot, Mark, Series};
use crate::identify::{Stability, WindowResult};
use serde_json::{Map, Value};

/// The model's prediction beside one identified mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Paired {
    /// The paired model mode's frequency, Hz.
    pub frequency_hz: f64,
    /// Its 1-based order among the model's modes at the pose.
    pub mode: usize,
    /// Its end-effector participation.
    pub ee_participation: f64,
}

/// One window as the files show it: the identification, the window's pose and, per mode,
/// the pairing and the row's status.
#[derive(Debug, Clone)]
pub struct WindowRows<'a> {
    /// The identification of the window.
    pub result: &'a WindowResult,
    /// Mean position, m (`None`: unknown).
    pub position_m: Option<[f64; 3]>,
    /// Mean orientation w, x, y, z (`None`: unknown or a point mass).
    pub orientation_wxyz: Option<[f64; 4]>,
    /// Per mode: the model's prediction (`None`: no scene or no pairing).
    pub paired: Vec<Option<Paired>>,
    /// Per mode: `ok` or why the row is doubtful.
    pub status: Vec<&'static str>,
}

/// A number, or an empty field.
fn num(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() => format!("{v:.10e}"),
        _ => String::new(),
    }
}

/// The CSV: one row per identified mode per window (a window without a mode: one row with
/// the mode columns empty and the window's status), modes ascending.
pub fn identify_csv(
    windows: &[WindowRows<'_>],
    channels: &[String],
    meta: Map<String, Value>,
) -> Csv {
    let mut cols = vec![
        Column::new("window", "1", "window index, from 0"),
        Column::new("t_start_s", "s", "start of the window"),
        Column::new("t_end_s", "s", "end of the window"),
        Column::new("x_m", "m", "window's mean end-effector position x (empty: unknown)"),
        Column::new("y_m", "m", "… y"),
        Column::new("z_m", "m", "… z"),
        Column::new("qw", "1", "window's mean orientation, unit quaternion w (empty: unknown)"),
        Column::new("qx", "1", "… x"),
        Column::new("qy", "1", "… y"),
        Column::new("qz", "1", "… z"),
        Column::new(
            "identified_mode",
            "1",
            "1-based order of the identified mode within its window",
        ),
        Column::new("frequency_hz", "Hz", "identified natural frequency"),
        Column::new(
            "frequency_std_hz",
            "Hz",
            "jackknife standard deviation of the frequency over the window's segments",
        ),
        Column::new("damping_ratio", "1", "identified viscous damping ratio"),
        Column::new("damping_ratio_std", "1", "jackknife standard deviation of the damping ratio"),
        Column::new(
            "model_frequency_hz",
            "Hz",
            "the paired model mode's frequency at the window's pose (empty: no scene or unpaired)",
        ),
        Column::new(
            "model_mode",
            "1",
            "1-based order of the paired model mode at the pose (a pairing hint)",
        ),
        Column::new(
            "model_ee_participation",
            "1",
            "end-effector participation of the paired model mode",
        ),
        Column::new(
            "status",
            "",
            "ok, or why the row is doubtful: gap, unpaired, ambiguous, short, no_data, failed, no_modes",
        ),
    ];
    for c in channels {
        cols.push(Column::new(
            format!("shape_{c}"),
            "1",
            format!("mode shape at channel {c} (real part, largest entry 1)"),
        ));
    }
    let mut csv = Csv::new(cols, meta);
    for w in windows {
        let r = w.result;
        let mut head = vec![
            r.index.to_string(),
            num(Some(r.t_start_s)),
            num(Some(r.t_end_s)),
        ];
        let p = w.position_m;
        head.extend((0..3).map(|i| num(p.map(|p| p[i]))));
        let q = w.orientation_wxyz;
        head.extend((0..4).map(|i| num(q.map(|q| q[i]))));
        if r.modes.is_empty() {
            let status = if r.status == crate::identify::WindowStatus::Ok
                || r.status == crate::identify::WindowStatus::Gap
            {
                "no_modes"
            } else {
                r.status.as_str()
            };
            let mut row = head.clone();
            row.extend(std::iter::repeat_n(String::new(), 8));
            row.push(status.into());
            row.extend(std::iter::repeat_n(String::new(), channels.len()));
            csv.row(row);
            continue;
        }
        for (j, m) in r.modes.iter().enumerate() {
            let mut row = head.clone();
            let pm = w.paired.get(j).copied().flatten();
            row.extend([
                (j + 1).to_string(),
                num(Some(m.frequency_hz)),
                num(Some(m.frequency_std_hz)),
                num(Some(m.damping_ratio)),
                num(Some(m.damping_ratio_std)),
                num(pm.map(|p| p.frequency_hz)),
                pm.map_or(String::new(), |p| p.mode.to_string()),
                num(pm.map(|p| p.ee_participation)),
                w.status.get(j).copied().unwrap_or("ok").to_string(),
            ]);
            row.extend(m.shape.iter().map(|z| num(Some(z.re))));
            csv.row(row);
        }
    }
    csv
}

/// The stabilisation diagram of one window: every pole by frequency and order, marked by its
/// stability, the identified modes as vertical lines and the model's paired frequencies
/// dashed.
pub fn stabilisation_svg(
    w: &WindowRows<'_>,
    title: &str,
    subtitle: &str,
    band_hz: (f64, f64),
) -> String {
    let r = w.result;
    let mut plot = LinePlot::new(
        title,
        Axis::linear("frequency [Hz]"),
        Axis::linear("model order"),
    );
    plot.subtitle = subtitle.into();
    let classes = [
        (Stability::New, "new pole", "#bbbbbb"),
        (Stability::Frequency, "stable frequency", "#8fb3d9"),
        (
            Stability::FrequencyDamping,
            "stable frequency, damping",
            "#d9a05b",
        ),
        (
            Stability::FrequencyShape,
            "stable frequency, shape",
            "#a07cc5",
        ),
        (
            Stability::Stable,
            "stable (frequency, damping, shape)",
            "#1f6f3f",
        ),
    ];
    let top = r.diagram.iter().map(|p| p.pole.order).max().unwrap_or(2) as f64;
    for (class, name, color) in classes {
        let pts: Vec<(f64, f64)> = r
            .diagram
            .iter()
            .filter(|p| p.stability == class)
            .map(|p| (p.pole.frequency_hz, p.pole.order as f64))
            .collect();
        if !pts.is_empty() {
            plot.series
                .push(Series::new(name, pts, Mark::Points).color(color));
        }
    }
    for (j, m) in r.modes.iter().enumerate() {
        let name = if j == 0 { "identified modes" } else { "" };
        plot.series.push(
            Series::new(
                name,
                vec![(m.frequency_hz, 0.0), (m.frequency_hz, top)],
                Mark::Line,
            )
            .color("#c0392b"),
        );
    }
    let mut first = true;
    for p in w.paired.iter().flatten() {
        let name = if first {
            "model at the pose (paired)"
        } else {
            ""
        };
        first = false;
        plot.series.push(
            Series::new(
                name,
                vec![(p.frequency_hz, 0.0), (p.frequency_hz, top)],
                Mark::Dashed,
            )
            .color("#555555"),
        );
    }
    plot.x = Axis::linear("frequency [Hz]").with_range(band_hz.0, band_hz.1);
    plot.y = Axis::linear("model order").with_range(0.0, top + 2.0);
    plot.to_svg()
}
