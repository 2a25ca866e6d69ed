//! `cablevib trajectory`: the CSV of every pose and T_min, and the figure.

use super::csv::{point_columns, point_fields, scene_meta, Column, CsvFile};
use super::ee_curve_differs;
use super::svg::{Axis, LinePlot, Mark, Series, PALETTE};
use super::ReportError;
use crate::estimator::Estimate;
use crate::scene::Scene;
use crate::study::points::{ee_mode_hz, valid, PointResult};
use crate::study::trajectory::{Chunk, TrajectoryStudy};
use serde_json::json;
use std::fmt::Write as _;
use std::path::Path;

/// The CSV's columns and sidecar metadata: one row per pose and T_min (T_min-major), with
/// time and angle, then the columns of [`point_columns`]; `poses` per curve, `modes` per pose.
fn trajectory_columns(
    s: &Scene,
    t_mins_n: &[f64],
    poses: usize,
    modes: usize,
) -> (Vec<Column>, serde_json::Map<String, serde_json::Value>) {
    let mut meta = scene_meta("trajectory", s);
    // The curves' T_min values are `t_mins_n` (and the t_min_n column).
    meta.remove("t_min_n");
    meta.insert("t_mins_n".into(), json!(t_mins_n));
    meta.insert("poses".into(), json!(poses));
    meta.insert("modes".into(), json!(modes));
    meta.insert(
        "order".into(),
        json!("T_min-major: the poses of the first T_min, then of the next"),
    );
    let mut cols = vec![
        Column::new("t_s", "s", "time along the trajectory"),
        Column::new(
            "angle_deg",
            "deg",
            "angle along the circle (NaN for a trajectory read from a CSV)",
        ),
    ];
    cols.extend(point_columns(s.n_cables(), modes, s.rigid));
    (cols, meta)
}

/// The trajectory CSV written chunk by chunk as [`crate::study::trajectory::run`] computes it
/// (curve 0 straight to the file, the other curves to spill files appended at the end), in
/// memory independent of the number of poses.
#[derive(Debug)]
pub struct TrajectoryCsv {
    file: CsvFile,
    rigid: bool,
}

impl TrajectoryCsv {
    /// Creates `path` for `t_mins_n.len()` curves of `poses` poses with `modes` modes each.
    pub fn create(
        path: &Path,
        s: &Scene,
        t_mins_n: &[f64],
        poses: usize,
        modes: usize,
    ) -> Result<TrajectoryCsv, ReportError> {
        let (cols, meta) = trajectory_columns(s, t_mins_n, poses, modes);
        Ok(TrajectoryCsv {
            file: CsvFile::create(path, cols, meta, t_mins_n.len())?,
            rigid: s.rigid,
        })
    }

    /// The rows of one chunk: `results[k]` are curve k's results for the chunk's poses.
    pub fn chunk(&mut self, c: &Chunk, results: &[Vec<PointResult>]) -> Result<(), ReportError> {
        for (k, rows) in results.iter().enumerate() {
            for (i, r) in rows.iter().enumerate() {
                let ang = match c.angle_deg.get(i) {
                    Some(a) => format!("{a}"),
                    None => "NaN".into(),
                };
                let mut row = vec![c.t_s[i].to_string(), ang];
                row.extend(point_fields(r, self.rigid));
                self.file.row(k, row)?;
            }
        }
        Ok(())
    }

    /// Completes the CSV and writes its sidecar.
    pub fn finish(self, command_line: &str) -> Result<(), ReportError> {
        self.file.finish(command_line)
    }
}

/// (x, valid value) of each row.
fn curve(rows: &[PointResult], xs: &[f64], f: fn(&Estimate) -> f64) -> Vec<(f64, f64)> {
    rows.iter()
        .zip(xs)
        .map(|(r, &x)| (x, valid(&r.estimate, f(&r.estimate))))
        .collect()
}

/// The figure: f1 of each T_min (and the end-effector mode where it differs from f1)
/// against the angle along the circle (`radius_m`) or the time.
/// With K modes, f2 .. fK of each T_min are solid lines in its colour, on a log axis.
pub fn trajectory_svg(s: &Scene, t: &TrajectoryStudy, radius_m: f64, ee_mode: bool) -> String {
    let circle = t.is_circle();
    let modes = t.points.first().map_or(1, |p| p.n_modes);
    let xlab = if circle {
        "angle along the circle (deg)"
    } else {
        "t (s)"
    };
    let mut plot = LinePlot::new(
        &format!(
            "{}: {} along the {}",
            s.name,
            if modes > 1 {
                format!("the first {modes} natural frequencies")
            } else {
                "first natural frequency".into()
            },
            if circle {
                format!("circle (r = {} m)", radius_m)
            } else {
                "trajectory".into()
            }
        ),
        if circle {
            Axis::linear(xlab).with_range(0.0, 360.0)
        } else {
            Axis::linear(xlab)
        },
        super::tmin::freq_axis(modes),
    );
    let mut sub = format!(
        "{} × {} elements/cable, T_max {} N",
        s.model.element.as_str(),
        s.model.elements_per_cable,
        s.t_max_n
    );
    let xs = if circle {
        &t.samples.angle_deg
    } else {
        &t.samples.t_s
    };
    for (k, &tm) in t.t_mins_n.iter().enumerate() {
        let rows = t.curve(k);
        let f1 = curve(rows, xs, |e| e.f1_hz);
        let ee = curve(rows, xs, ee_mode_hz);
        let color = PALETTE[k % PALETTE.len()];
        let differs = ee_curve_differs(&f1, &ee);
        plot.series
            .push(Series::new(&format!("f1, T_min = {tm} N"), f1, Mark::Line).color(color));
        if ee_mode && differs {
            plot.series.push(
                Series::new(
                    &format!("end-effector mode, T_min = {tm} N"),
                    ee,
                    Mark::Dashed,
                )
                .color(color),
            );
        }
        for j in 2..=modes {
            let fj: Vec<(f64, f64)> = rows
                .iter()
                .zip(xs)
                .map(|(r, &x)| (x, r.mode_hz(j)))
                .collect();
            // One legend entry for the modes of a T_min.
            let name = if j == 2 {
                format!("f2..f{modes}, T_min = {tm} N")
            } else {
                String::new()
            };
            plot.series
                .push(Series::new(&name, fj, Mark::Line).color(color));
        }
        let c = t.summary(k);
        if c.f1_min_hz.is_finite() {
            let (lo, hi) = (c.f1_min_hz, c.f1_max_hz);
            let _ = write!(sub, "; T_min {tm} N: f1 {lo:.3}–{hi:.3} Hz");
        } else {
            let _ = write!(sub, "; T_min {tm} N: no valid estimate");
        }
        if !c.counts.summary_not_ok().is_empty() {
            let _ = write!(sub, " ({})", c.counts.summary());
        }
    }
    plot.subtitle = sub;
    plot.to_svg()
}
