//! The demo's hold (`DemoConfig::hold_f1_hz`): its controller holds f1 at or above it with
//! the T_min set-points of [`F1Hold`] (one implementation with `service/examples/controller.rs`), and
//! the summary measures what that costs against the one fixed T_min that would also meet the
//! requirement at every pose the demo estimated.
//!
//! - The margin query asks for HZ + guard ([`HoldParams::request_hz`]); each answer goes
//!   through [`F1Hold::on_answer`] and a changed set-point is published at once (uniform, the
//!   service applies it from its next cycle).
//! - The count starts at the first answer carrying a T_min (the first set-point, or the first
//!   answer that needed none): an ok estimate counts when its pose was taken by the service
//!   after that (`receive_timestamp_ns`, the same `CLOCK_MONOTONIC` as the controller's), so
//!   the estimates already in flight when the set-point left are not counted.
//! - The fixed T_min: the largest inverse answer ([`Estimator::t_min_for_f1`]) over a subsample
//!   of those poses, then checked by the forward model at every one of them and raised where it
//!   falls short (f1 is not monotone in T_min: docs/inverse.md), never below the floor. Σ T²
//!   at it comes from the same estimator at the same poses.

use cablevib::outln;
use std::io::Write;
use std::path::Path;

use cablevib_ipc::{monotonic_now_ns, EstimateSample, MarginResponse, ServiceNames, TminSetpoint};

use super::hold::{F1Hold, HoldAction, HoldInput, HoldParams};
use super::ports::PoseInput;
use super::{DemoConfig, ServiceError};
use crate::estimator::{Estimator, Tmin};
use crate::kinematics::Pose;
use crate::scene::Scene;
use crate::trajectory::Trajectory;
use iceoryx2::prelude::*;

/// Most inverse queries for the fixed T_min (each a few ms): the forward check at every pose
/// catches what the subsample misses.
const FIXED_QUERIES: usize = 200;
/// Most rounds of raising the fixed T_min where the forward check finds f1 short.
const FIXED_ROUNDS: usize = 50;
/// Relative step of a raise where the inverse answer at the failing pose is already below the
/// fixed T_min (a dip of f1 in T_min).
const FIXED_BUMP: f64 = 1e-3;

/// The hold parameters of a hold at `hold_hz` on `scene`: floor the scene's T_min, ceiling the
/// smallest cable t_max, the default guard, band and rate.
pub(crate) fn params(scene: &Scene, hold_hz: f64) -> Result<HoldParams, ServiceError> {
    let ceiling = (0..scene.n_cables())
        .map(|i| scene.cable_t_max_n(i))
        .fold(f64::INFINITY, f64::min);
    Ok(HoldParams::new(hold_hz, scene.t_min_n, ceiling)?)
}

/// One ok estimate the hold saw.
#[derive(Debug, Clone, Copy)]
struct Seen {
    pose_sequence: u64,
    receive_ns: u64,
    f1_hz: f64,
    sum_t2_n2: f64,
}

/// The demo controller's hold: the state, its T_min publisher and what it recorded.
pub(crate) struct DemoHold {
    hold: F1Hold,
    input: PoseInput,
    sequence: u64,
    /// When the count starts (controller's clock, ns): see the module doc.
    start_ns: Option<u64>,
    seen: Vec<Seen>,
    /// (published at, ns; value, N) of every set-point.
    setpoints: Vec<(u64, f64)>,
    actions: [u64; 7],
}

/// What the hold recorded, for the summary.
#[derive(Debug)]
pub(crate) struct HoldLog {
    params: HoldParams,
    start_ns: Option<u64>,
    seen: Vec<Seen>,
    setpoints: Vec<(u64, f64)>,
    actions: [u64; 7],
}

impl DemoHold {
    /// Opens the T_min publisher on the controller's node; logs preallocated for `capacity`.
    pub(crate) fn open(
        node: &Node<super::ports::Ipc>,
        names: &ServiceNames,
        params: HoldParams,
        capacity: usize,
    ) -> Result<DemoHold, ServiceError> {
        Ok(DemoHold {
            hold: F1Hold::new(params),
            input: PoseInput::open(node, names)?,
            sequence: 0,
            start_ns: None,
            seen: Vec::with_capacity(capacity),
            setpoints: Vec::with_capacity(capacity),
            actions: [0; 7],
        })
    }

    /// The requirement the margin query asks for, Hz.
    pub(crate) fn request_hz(&self) -> f64 {
        self.hold.params().request_hz()
    }

    /// Records an estimate (ok ones only).
    pub(crate) fn on_estimate(&mut self, e: &EstimateSample) {
        if e.is_ok() && self.seen.len() < self.seen.capacity() {
            let n = (e.cable_count as usize).min(e.tensions_n.len());
            self.seen.push(Seen {
                pose_sequence: e.pose_sequence,
                receive_ns: e.receive_timestamp_ns,
                f1_hz: e.f1_hz,
                sum_t2_n2: e.tensions_n[..n].iter().map(|t| t * t).sum(),
            });
        }
    }

    /// Takes a margin answer; publishes the set-point when it changed.
    pub(crate) fn on_answer(&mut self, r: &MarginResponse) -> Result<(), ServiceError> {
        let before = self.hold.setpoint_n();
        let action = self.hold.on_answer(&HoldInput::from(r));
        self.actions[action as usize] += 1;
        let now = self.hold.setpoint_n();
        if now != before {
            self.sequence += 1;
            let t = monotonic_now_ns();
            self.input
                .send_t_min(&TminSetpoint::uniform(self.sequence, t, now))?;
            if self.setpoints.len() < self.setpoints.capacity() {
                self.setpoints.push((t, now));
            }
        }
        if action != HoldAction::NoAnswer && self.start_ns.is_none() {
            self.start_ns = Some(monotonic_now_ns());
        }
        Ok(())
    }

    /// The record, at the end.
    pub(crate) fn finish(self) -> HoldLog {
        HoldLog {
            params: *self.hold.params(),
            start_ns: self.start_ns,
            seen: self.seen,
            setpoints: self.setpoints,
            actions: self.actions,
        }
    }
}

impl HoldLog {
    /// The requirement the margin query asked for, Hz (required + guard).
    pub(crate) fn request_hz(&self) -> f64 {
        self.params.request_hz()
    }
}

/// The fixed T_min meeting `required_hz` at every pose (≥ `floor_n`), with f1 and Σ T² there.
fn fixed_t_min(
    scene: &Scene,
    poses: &[Pose],
    required_hz: f64,
    floor_n: f64,
) -> Result<(f64, Vec<(f64, f64)>), String> {
    let mut est = Estimator::realtime(scene).map_err(|e| e.to_string())?;
    let stride = poses.len().div_ceil(FIXED_QUERIES).max(1);
    let mut t = floor_n;
    for p in poses.iter().step_by(stride) {
        let a = est.t_min_for_f1(p, required_hz).map_err(|e| {
            format!(
                "at ({:.3}, {:.3}, {:.3}) m: {e}",
                p.position_m.x, p.position_m.y, p.position_m.z
            )
        })?;
        t = t.max(a.t_min_n);
    }
    for _ in 0..FIXED_ROUNDS {
        let mut at = Vec::with_capacity(poses.len());
        let mut short = None;
        for p in poses {
            let e = est.update(p, Tmin::Uniform(t));
            if !e.is_ok() || e.f1_hz < required_hz {
                short = Some(*p);
                break;
            }
            let n = e.n_cables;
            at.push((e.f1_hz, e.tensions_n[..n].iter().map(|x| x * x).sum()));
        }
        let Some(p) = short else {
            return Ok((t, at));
        };
        let a = est
            .t_min_for_f1(&p, required_hz)
            .map_err(|e| e.to_string())?;
        t = if a.t_min_n > t {
            a.t_min_n
        } else {
            t * (1.0 + FIXED_BUMP)
        };
        if t > scene.t_max_n {
            return Err(format!(
                "no fixed T_min up to {} N meets it everywhere",
                scene.t_max_n
            ));
        }
    }
    Err(format!("no fixed T_min found in {FIXED_ROUNDS} rounds"))
}

/// Prints the hold's summary line; writes the per-estimate CSV when asked.
pub(crate) fn summary(
    scene: &Scene,
    a: &DemoConfig,
    trajectory: &Trajectory,
    log: &HoldLog,
) -> Result<(), ServiceError> {
    let p = log.params;
    let Some(start) = log.start_ns else {
        outln!(
            "  hold f1 ≥ {} Hz: no margin answer carried a T_min; nothing to count",
            p.required_hz
        )?;
        return Ok(());
    };
    let after: Vec<&Seen> = log.seen.iter().filter(|s| s.receive_ns > start).collect();
    let below = after.iter().filter(|s| s.f1_hz < p.required_hz).count();
    let poses: Vec<Pose> = after
        .iter()
        .filter_map(|s| {
            let t = s.pose_sequence.saturating_sub(1) as f64 / a.rate_hz;
            trajectory.position_at(t).map(|x| Pose::in_scene(scene, x))
        })
        .collect();
    let (lo, hi) = log
        .setpoints
        .iter()
        .fold((p.floor_n, p.floor_n), |(l, h), s| (l.min(s.1), h.max(s.1)));
    let f1_min = after.iter().map(|s| s.f1_hz).fold(f64::INFINITY, f64::min);
    let mean_hold = after.iter().map(|s| s.sum_t2_n2).sum::<f64>() / after.len().max(1) as f64;
    outln!(
        "  hold f1 ≥ {} Hz (asks for +{} Hz guard, relaxes above +{} Hz at ≤ {} N/s, T_min in \
         [{}, {}] N): {} set-points ({}..{} N; actions {}); ok estimates below {} Hz after the \
         first answer: {below} of {} (lowest f1 {f1_min:.4} Hz)",
        p.required_hz,
        p.guard_hz,
        p.relax_band_hz,
        p.relax_rate_n_per_s,
        p.floor_n,
        p.ceiling_n,
        log.setpoints.len(),
        fmt_n(lo),
        fmt_n(hi),
        HoldAction::summary(&log.actions),
        p.required_hz,
        after.len(),
    )?;
    if poses.len() != after.len() || poses.is_empty() {
        outln!("  hold: no poses to compare with a fixed T_min")?;
        return no_record(a, "no poses to compare with a fixed T_min");
    }
    match fixed_t_min(scene, &poses, p.required_hz, p.floor_n) {
        Ok((t_fixed, at)) => {
            let mean_fixed = at.iter().map(|x| x.1).sum::<f64>() / at.len() as f64;
            outln!(
                "  hold: mean Σ T² {:.5e} N² under the hold against {:.5e} N² at the fixed T_min \
                 {} N that meets {} Hz at every one of these {} poses ({:+.1} %)",
                mean_hold,
                mean_fixed,
                fmt_n(t_fixed),
                p.required_hz,
                poses.len(),
                100.0 * (mean_hold / mean_fixed - 1.0)
            )?;
            if let Some(path) = &a.hold_csv {
                write_csv(path, a, log, &after, &at, t_fixed).map_err(|e| {
                    ServiceError::HoldRecord {
                        path: path.clone(),
                        reason: e.to_string(),
                    }
                })?;
                outln!("  hold: per-estimate record written to {}", path.display())?;
            }
        }
        Err(e) => {
            outln!("  hold: no fixed T_min to compare with: {e}")?;
            return no_record(a, &format!("no fixed T_min to compare with: {e}"));
        }
    }
    Ok(())
}

/// A requested hold record (`DemoConfig::hold_csv`) that cannot be written is an error (so
/// that nothing reads an older file at that path as this run's record); without the
/// option, nothing to report.
fn no_record(a: &DemoConfig, why: &str) -> Result<(), ServiceError> {
    match &a.hold_csv {
        Some(path) => Err(ServiceError::HoldRecord {
            path: path.clone(),
            reason: format!("no record written: {why}"),
        }),
        None => Ok(()),
    }
}

fn fmt_n(x: f64) -> String {
    format!("{x:.2}")
}

/// One row per ok estimate after the first answer: time, f1, the set-point published last
/// before the service took the pose, Σ T²; f1 and Σ T² at the fixed T_min.
fn write_csv(
    path: &Path,
    a: &DemoConfig,
    log: &HoldLog,
    after: &[&Seen],
    fixed: &[(f64, f64)],
    t_fixed: f64,
) -> std::io::Result<()> {
    // Whole or not at all: a failed run leaves an older record at `path` as it was.
    let mut w = crate::output_file::OutputFile::create(path).map_err(std::io::Error::other)?;
    writeln!(
        w,
        "t_s,pose_sequence,f1_hz,setpoint_n,sum_t2_n2,fixed_t_min_n,f1_fixed_hz,sum_t2_fixed_n2"
    )?;
    for (s, (f1_fixed, t2_fixed)) in after.iter().zip(fixed) {
        let k = log.setpoints.partition_point(|x| x.0 < s.receive_ns);
        let setpoint = if k == 0 {
            log.params.floor_n
        } else {
            log.setpoints[k - 1].1
        };
        writeln!(
            w,
            "{},{},{},{},{},{},{},{}",
            s.pose_sequence.saturating_sub(1) as f64 / a.rate_hz,
            s.pose_sequence,
            s.f1_hz,
            setpoint,
            s.sum_t2_n2,
            t_fixed,
            f1_fixed,
            t2_fixed
        )?;
    }
    w.commit().map_err(std::io::Error::other)
}
