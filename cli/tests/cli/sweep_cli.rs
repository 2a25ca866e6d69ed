//! The sweep commands' argument structs as stand-alone parsers, so that tests build their
//! options from the same command lines a user types (`MapCli::try_parse_from([...])`).
//! Included by path from the sweep tests (it needs none of `common`'s other helpers).

use cablevib_cli::cli::accuracy::AccuracyArgs;
use cablevib_cli::cli::map::MapArgs;
use cablevib_cli::cli::sag_compare::SagCompareArgs;
use cablevib_cli::cli::sweep_tmin::SweepTminArgs;
use cablevib_cli::cli::trajectory::TrajectoryArgs;
use clap::Parser;

/// `cablevib map` options.
#[derive(Parser)]
pub struct MapCli {
    #[command(flatten)]
    pub a: MapArgs,
}
/// `cablevib trajectory` options.
#[derive(Parser)]
pub struct TrajCli {
    #[command(flatten)]
    pub a: TrajectoryArgs,
}
/// `cablevib sweep-tmin` options.
#[derive(Parser)]
pub struct TminCli {
    #[command(flatten)]
    pub a: SweepTminArgs,
}
/// `cablevib accuracy` options.
#[derive(Parser)]
pub struct AccCli {
    #[command(flatten)]
    pub a: AccuracyArgs,
}
/// `cablevib sag-compare` options.
#[derive(Parser)]
pub struct SagCli {
    #[command(flatten)]
    pub a: SagCompareArgs,
}
