//! Offline studies over the real-time estimator: the analysis of one pose that `analyze`
//! prints ([`analysis`]: the first K modes by the structured engine or the dense reference),
//! frequency maps over a workspace grid
//! ([`map`]), frequencies along a trajectory ([`trajectory`]) and against the minimum tension
//! ([`tmin`]), the chord and the sagged cable model side by side along a line
//! ([`sag_compare`]), the end-effector's vibration along a path and input shaping from
//! the estimated modes ([`simulate`]), the frequency response of one pose ([`frf`]), and
//! what accuracy costs in time ([`accuracy`], with the dense mode-3 convergence study of the
//! paper's Figs. 5 and 10).
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
//! files are the `report` layer's (above this one), option parsing is the command line's: a
//! refused value names its [`Param`] as the configuration does (`modes`, `period_s`), and a
//! front end renders it with its own names ([`StudyError::render`]).

pub mod accuracy;
pub mod analysis;
pub mod cost;
pub mod frf;
pub mod identify;
pub mod map;
pub mod param;
pub mod points;
pub mod progress;
pub mod sag_compare;
pub mod simulate;
pub mod tmin;
pub mod trajectory;

pub use param::{Param, ParamError, ParamName};

use crate::estimator::{Estimator, EstimatorParams};
use crate::modal::FrfError;
use crate::scene::Scene;
use crate::trajectory::shaping::ShapingError;
use crate::trajectory::TrajectoryError;
use simulate::PathError;

/// Errors of the studies. A refused configuration value names its parameter
/// ([`ParamError`]); [`StudyError::render`] words the message with a front end's names.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// A configuration value refused.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// A sampled path that cannot be simulated or shaped (the whole line, no source below
    /// it).
    #[error("{}", .0.render(&Param::name))]
    Path(PathError),
    /// The estimator could not be built (the scene's default pose is unsolvable), or the
    /// dense reference failed.
    #[error("{0}")]
    Build(String),
    /// The computation of a study failed at its pose (no valid estimate, a modal basis, a
    /// dense check), with what was being done.
    #[error("{0}")]
    Solve(String),
    /// A trajectory could not be made or read.
    #[error(transparent)]
    Trajectory(#[from] TrajectoryError),
    /// The frequency response failed (or has no form for the model).
    #[error(transparent)]
    Frf(#[from] FrfError),
    /// An input shaper could not be built.
    #[error(transparent)]
    Shaping(#[from] ShapingError),
    /// A file changed while it was read twice (count, then values).
    #[error("{path}: the file changed while it was read ({before} rows, then {after})")]
    FileChanged {
        /// The file.
        path: std::path::PathBuf,
        /// Rows at the first reading.
        before: usize,
        /// Rows at the second.
        after: usize,
    },
    /// The work would need more memory than the one budget (refused before allocating).
    #[error(transparent)]
    Memory(#[from] crate::memory_budget::OverBudget),
}

impl From<PathError> for StudyError {
    fn from(e: PathError) -> Self {
        StudyError::Path(e)
    }
}

impl StudyError {
    /// The message with each parameter called `name(param)` (the command line passes its
    /// option names); equal to the `Display` text with [`Param::name`].
    pub fn render(&self, name: &dyn Fn(Param) -> &'static str) -> String {
        match self {
            StudyError::Param(e) => e.render(name),
            StudyError::Path(e) => e.render(name),
            other => other.to_string(),
        }
    }
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
