//! Measured modes beside the model's: the model's modes at a window's pose, and the pairing
//! of each identified mode with one of them.
//!
//! **Pairing.** The model's modes at the pose (the structured engine's first modes up to
//! [`MODEL_TOP_FACTOR`] × the band's top, one per cluster) that move the end-effector — end-effector participation at least
//! [`MIN_PARTICIPATION`]: a sensor on the platform does not see the others — are the
//! candidates. Identified and model modes are matched one to one, nearest pairs first in
//! |ln(f_model / f_measured)|, within [`MAX_PAIR_RATIO`] (a model off by more is no
//! prediction of that mode). A pair is `ambiguous` when another candidate with at least half
//! the paired mode's participation lies within [`AMBIGUITY_LOG_RATIO`] of the same distance;
//! an identified mode without a candidate is `unpaired`.

use super::StudyError;
use crate::estimator::{Estimator, Tmin};
use crate::kinematics::Pose;
use crate::modal::Mode;

/// Candidates move the end-effector at least this much (participation, 0 ..= 1).
pub const MIN_PARTICIPATION: f64 = 0.01;
/// Largest ratio between a paired model frequency and the measured one (either way).
pub const MAX_PAIR_RATIO: f64 = 1.5;
/// Two candidates whose |ln ratio| to the measured mode differ by less than this are
/// equally near (2 %).
pub const AMBIGUITY_LOG_RATIO: f64 = 0.02;
/// The model's modes are computed up to this multiple of the band's top.
pub const MODEL_TOP_FACTOR: f64 = 1.5;
/// Most model modes computed.
const MAX_MODEL_MODES: usize = 1024;

/// One mode of the model at a pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelMode {
    /// 1-based order of the mode among the model's modes at the pose.
    pub order: usize,
    /// Natural frequency, Hz.
    pub frequency_hz: f64,
    /// End-effector participation (0 ..= 1).
    pub ee_participation: f64,
}

/// How an identified mode was paired.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PairStatus {
    /// Paired with one model mode.
    Ok,
    /// No model mode moving the end-effector within the ratio.
    Unpaired,
    /// Paired, but another model mode is about as near.
    Ambiguous,
}

impl PairStatus {
    /// The word of the CSV's `status` column.
    pub fn as_str(self) -> &'static str {
        match self {
            PairStatus::Ok => "ok",
            PairStatus::Unpaired => "unpaired",
            PairStatus::Ambiguous => "ambiguous",
        }
    }
}

/// The model's modes at `pose` up to [`MODEL_TOP_FACTOR`] × `top_hz` (first of each
/// cluster), with `est` built for the robot's scene.
pub fn model_modes(
    est: &mut Estimator,
    pose: &Pose,
    top_hz: f64,
) -> Result<Vec<ModelMode>, StudyError> {
    let e = est.update(pose, Tmin::Scene);
    if !e.status.is_ok() {
        let why = e.error.map(|x| x.to_string()).unwrap_or_default();
        let p = pose.position_m;
        return Err(StudyError::Build(format!(
            "the model at ({:.4}, {:.4}, {:.4}) m: {} {why}",
            p.x,
            p.y,
            p.z,
            e.status.as_str()
        )));
    }
    let mut k = 32usize;
    loop {
        let mut modes = vec![Mode::default(); k];
        let n = est
            .modes(k, &mut modes)
            .map_err(|e| StudyError::Build(format!("the model's modes: {e}")))?;
        let top = modes[..n].last().map_or(0.0, |m| m.frequency_hz);
        if n < k || top > MODEL_TOP_FACTOR * top_hz || k >= MAX_MODEL_MODES {
            return Ok(modes[..n]
                .iter()
                .enumerate()
                .filter(|(i, m)| m.cluster_start == *i)
                .map(|(i, m)| ModelMode {
                    order: i + 1,
                    frequency_hz: m.frequency_hz,
                    ee_participation: m.ee_participation,
                })
                .collect());
        }
        k *= 2;
    }
}

/// Pair each of `measured_hz` with a model mode (module docs).
pub fn pair(measured_hz: &[f64], model: &[ModelMode]) -> Vec<(Option<ModelMode>, PairStatus)> {
    let cands: Vec<&ModelMode> = model
        .iter()
        .filter(|m| m.ee_participation >= MIN_PARTICIPATION && m.frequency_hz > 0.0)
        .collect();
    let dist = |f: f64, m: &ModelMode| (m.frequency_hz / f).ln().abs();
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for (i, &f) in measured_hz.iter().enumerate() {
        for (j, m) in cands.iter().enumerate() {
            let d = dist(f, m);
            if f > 0.0 && d <= MAX_PAIR_RATIO.ln() {
                pairs.push((d, i, j));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out = vec![(None, PairStatus::Unpaired); measured_hz.len()];
    let mut used = vec![false; cands.len()];
    for (d, i, j) in pairs {
        if out[i].0.is_some() || used[j] {
            continue;
        }
        used[j] = true;
        let m = *cands[j];
        let rival = cands.iter().enumerate().any(|(k, c)| {
            k != j
                && c.ee_participation >= 0.5 * m.ee_participation
                && (dist(measured_hz[i], c) - d).abs() < AMBIGUITY_LOG_RATIO
        });
        let status = if rival {
            PairStatus::Ambiguous
        } else {
            PairStatus::Ok
        };
        out[i] = (Some(m), status);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mm(order: usize, f: f64, p: f64) -> ModelMode {
        ModelMode {
            order,
            frequency_hz: f,
            ee_participation: p,
        }
    }

    #[test]
    fn nearest_participating_mode_one_to_one() {
        let model = [
            mm(1, 5.0, 0.9),
            mm(2, 5.3, 0.001), // a string mode the platform does not feel
            mm(3, 9.0, 0.8),
            mm(4, 9.1, 0.7),
            mm(5, 30.0, 0.6),
        ];
        let got = pair(&[5.2, 9.05, 9.12, 100.0], &model);
        assert_eq!(got[0].0.unwrap().order, 1);
        assert_eq!(got[0].1, PairStatus::Ok);
        // 9.05 and 9.12 take 9.1 (nearest pair first) and 9.0; both have a rival.
        assert_eq!(got[2].0.unwrap().order, 4);
        assert_eq!(got[1].0.unwrap().order, 3);
        assert_eq!(got[1].1, PairStatus::Ambiguous);
        assert_eq!(got[3], (None, PairStatus::Unpaired));
    }
}
