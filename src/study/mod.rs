//! Offline studies over the real-time estimator: the analysis of one pose that `analyze`
//! prints ([`analysis`]: the first K modes by the structured engine or the dense reference),
//! frequency maps over a workspace grid
//! ([`map`]), frequencies along a trajectory ([`trajectory`]) and against the minimum tension
//! ([`tmin`]), the chord and the sagged cable model side by side along a line
//! ([`sag_compare`]), the end-effector's vibration along a path and input shaping from
//! the estimated modes ([`simulate`]), and what accuracy costs in time ([`accuracy`], with the dense mode-3
//! convergence study of the paper's Figs. 5 and 10).
//!
//! Every study drives [`Estimator::update`] (the per-cycle path, exact to ~1e-12 against
//! the faithful model) and keeps one result per evaluated point — including the points where
//! the estimator has no valid answer, which keep their status and NaN frequencies. Long
//! studies split their points over a rayon pool ([`points`]: all cores by default, one
//! estimator per worker, results equal bit for bit to one thread's) and show a progress bar
//! with ETA when stderr is a terminal ([`progress`]). What a study costs in memory (checked
//! against the one budget before it allocates) and time (estimated up front) is [`cost`]'s.
//!
//! Studies take plain configuration structs in SI units and return results; rendering and
//! files are the `report` layer's (above this one), option parsing is the command line's.

pub mod accuracy;
pub mod analysis;
pub mod cost;
pub mod identify;
pub mod map;
pub mod points;
pub mod progress;
pub mod sag_compare;
pub mod simulate;
pub mod tmin;
pub mod trajectory;

use crate::estimator::{Estimator, EstimatorParams};
use crate::scene::Scene;
use crate::trajectory::TrajectoryError;

/// Errors of the studies.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// A configuration value out of range.
    #[error("{0}")]
    Usage(String),
    /// The estimator could not be built (the scene's default pose is unsolvable), or the
    /// dense reference failed.
    #[error("{0}")]
    Build(String),
    /// A trajectory could not be made or read.
    #[error(transparent)]
    Trajectory(#[from] TrajectoryError),
    /// The work would need more memory than the one budget (refused before allocating).
    #[error(transparent)]
    Memory(#[from] crate::memory_budget::OverBudget),
}

/// Estimator parameters of a study: the scene's end-effector participation threshold, and
/// the end-effector mode on or off.
pub fn estimator_params(s: &Scene, ee_mode: bool) -> EstimatorParams {
    let mut p = EstimatorParams::default();
    p.modal.ee_participation_min = s.model.ee_participation_min;
    p.ee_mode = ee_mode;
    p
}

fn build(s: &Scene, p: EstimatorParams) -> Result<Estimator, StudyError> {
    Estimator::with_params(s, p).map_err(|e| StudyError::Build(e.to_string()))
}
