//! A simulation as a user states it, the one orchestration behind `cablevib simulate`,
//! `cablevib shape` and the Python package's `simulate` and `shape`: the path (a CSV file,
//! a point-to-point move from the scene's position, or the paper's circle) sampled every
//! `dt`, and a run optionally shaped first.

use super::{shape, simulate, SampledPath, ShapeMode, SimulateConfig, SimulateResult};
use crate::scene::Scene;
use crate::study::{Param, ParamError, StudyError};
use crate::trajectory::moves::{Move, Profile};
use crate::trajectory::shaping::ShaperKind;
use crate::trajectory::{Samples, Trajectory};
use nalgebra::Vector3;
use std::path::PathBuf;

/// Largest sample period, s (the study's own bound on a sampled path).
pub const MAX_DT_S: f64 = 0.1;

/// Where the path comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum PathSpec {
    /// A trajectory CSV (t,x,y,z; s, m), resampled every dt; at rest before and after.
    Csv(PathBuf),
    /// A move from the scene's end-effector position by `displacement_m` in `duration_s`
    /// with `profile`, then a stop.
    Move {
        /// The move, m.
        displacement_m: Vector3<f64>,
        /// Its time, s (finite, > 0).
        duration_s: f64,
        /// Its velocity profile.
        profile: Profile,
    },
    /// The paper's circle for `duration_s`, one revolution per `period_s` (already moving
    /// at both ends).
    Circle {
        /// Time followed, s.
        duration_s: f64,
        /// One revolution, s.
        period_s: f64,
    },
}

impl PathSpec {
    /// The path sampled every `dt_s` (in (0, [`MAX_DT_S`]]) in `scene`, and a one-line
    /// description of it.
    pub fn sample(&self, scene: &Scene, dt_s: f64) -> Result<(SampledPath, String), StudyError> {
        if !(dt_s.is_finite() && dt_s > 0.0 && dt_s <= MAX_DT_S) {
            return Err(ParamError::invalid(
                Param::DtS,
                dt_s,
                format!("the sample period must be in (0, {MAX_DT_S}] s"),
            )
            .into());
        }
        match self {
            PathSpec::Csv(csv) => {
                let samples = Samples::read_csv(csv)?;
                let p = SampledPath::from_samples(&samples, dt_s)?;
                Ok((p, format!("{} ({})", csv.display(), samples.t_s.len())))
            }
            PathSpec::Move {
                displacement_m: d,
                duration_s,
                profile,
            } => {
                if !(duration_s.is_finite() && *duration_s > 0.0) {
                    return Err(ParamError::invalid(
                        Param::DurationS,
                        duration_s,
                        "a move takes a finite time > 0 s",
                    )
                    .into());
                }
                let mv = Move::new(scene.ee_position_m, *d, *duration_s, *profile)?;
                let samples = mv.sampled(dt_s, 0.0)?;
                let p = SampledPath {
                    dt_s,
                    positions_m: samples.position_m,
                    at_rest_ends: true,
                };
                let desc = format!(
                    "move ({:.3}, {:.3}, {:.3}) m in {} s, {}",
                    d.x,
                    d.y,
                    d.z,
                    duration_s,
                    profile.as_str()
                );
                Ok((p, desc))
            }
            PathSpec::Circle {
                duration_s,
                period_s,
            } => {
                let t = Trajectory::circle(scene, *period_s)?;
                let p = SampledPath::from_trajectory(&t, *duration_s, dt_s, false)?;
                Ok((p, format!("{} for {} s", t.describe(), duration_s)))
            }
        }
    }
}

/// What [`simulate_shaped`] computed.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapedRun {
    /// The path simulated: `path`, or its shaped version.
    pub path: SampledPath,
    /// The simulation along it.
    pub result: SimulateResult,
    /// Time the shaper added, s (0 unshaped).
    pub added_s: f64,
}

/// [`simulate`] along `path`, first shaped by `shaper` following `mode`
/// ([`shape`]) when one is given.
pub fn simulate_shaped(
    scene: &Scene,
    path: &SampledPath,
    cfg: &SimulateConfig,
    shaper: Option<ShaperKind>,
    mode: ShapeMode,
) -> Result<ShapedRun, StudyError> {
    let (path, added_s) = match shaper {
        None => (path.clone(), 0.0),
        Some(kind) => {
            let r = shape(scene, path, kind, mode)?;
            (r.path, r.added_s)
        }
    };
    let result = simulate(scene, &path, cfg)?;
    Ok(ShapedRun {
        path,
        result,
        added_s,
    })
}
