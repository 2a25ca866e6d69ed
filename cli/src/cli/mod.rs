//! The command-line front end: the argument structures of every command and one
//! [`run`] that dispatches them. Each command's file turns its options into the
//! configuration of a study ([`crate::study`]) or of the service ([`crate::service`]),
//! runs it, writes files through [`crate::report`] and prints a summary.
//!
//! | command | module | what |
//! |---|---|---|
//! | `analyze` | [`analyze`](mod@analyze) | tensions and natural frequencies of one pose |
//! | `bench` | [`bench`](mod@bench) | per-cycle latency of the real-time estimator along the circle |
//! | `calibrate` | [`calibrate`](mod@calibrate) | fit the scene's parameters to measured frequencies: report, figure, calibrated scene |
//! | `serve`, `demo`, `bench-ipc` | [`serve`](mod@serve) | the iceoryx2 service, the demo, the IPC latency |
//! | `monitor`, `replay`, `demo --monitor` | [`monitor`](mod@monitor) | Foxglove live view and MCAP recording of a service; replay of a recording |
//! | `accuracy` | [`accuracy`](mod@accuracy) | what accuracy costs: error and time of every model |
//! | `map` | [`map`](mod@map) | f1 over a workspace grid |
//! | `trajectory` | [`trajectory`](mod@trajectory) | f1 along the circle or a CSV path |
//! | `modes` | [`modes`](mod@modes) | the lowest modes with their shapes: table, CSV, SVG |
//! | `frf` | [`frf`](mod@frf) | the end-effector receptance over a band: CSV, Bode figure, JSON |
//! | `simulate` | [`simulate`](mod@simulate) | the end-effector's vibration along a path, unshaped and shaped |
//! | `shape` | [`simulate`](mod@simulate) | a trajectory shaped by ZV / ZVD / EI from the estimated mode |
//! | `sweep-tmin` | [`sweep_tmin`] | f1 against T_min with the √T_min fit |
//! | `sag-compare` | [`sag_compare`](mod@sag_compare) | chord vs sagged cables along a line: f1, k_min, tensions, λ² |
//! | `completions`, `man` | [`completions`](mod@completions) | shell completions and the man page |
//! | `identify` | [`identify`](mod@identify) | modal parameters from a recording (CSV, MCAP / ROS 2), beside the model's |
//! | `import caspr` | [`import`](mod@import) | a scene file from CASPR's XML model files |
//!
//! Functions here return `Result<_, CliError>`; the binary maps errors to a one-line reason
//! and a non-zero exit code.

pub mod accuracy;
pub mod analyze;
pub mod args;
pub mod bench;
pub mod calibrate;
pub mod completions;
pub mod error;
pub mod figure;
pub mod files;
pub mod frf;
pub mod identify;
pub mod import;
pub mod map;
pub mod modes;
pub mod monitor;
pub mod recording;
pub mod sag_compare;
pub mod serve;
pub mod simulate;
pub mod sweep_tmin;
pub mod trajectory;

pub use args::{resolve_scene, SceneArgs};
pub use error::CliError;

use crate::report::figure::FigureFormat;
use crate::report::with_ext;
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};

/// cablevib: tension distribution, stiffness and natural frequencies of cable-driven
/// parallel robots, offline and in real time.
#[derive(Debug, Parser)]
#[command(name = "cablevib", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Tensions and the first K natural frequencies of one pose (structured engine; --solver
    /// dense for the dense reference, --realtime for what the estimator cycle computes).
    Analyze(analyze::AnalyzeArgs),
    /// Drive the real-time estimator along the paper's circle and report per-cycle latency.
    Bench(bench::BenchArgs),
    /// Run the long-running iceoryx2 service.
    Serve(serve::ServeArgs),
    /// Run service, replay publisher and controller together on the default scene.
    Demo(serve::DemoArgs),
    /// Measure pose-published → estimate-received latency over iceoryx2.
    BenchIpc(serve::BenchIpcArgs),
    /// Attach to a running service: live in Foxglove (WebSocket) and recorded to MCAP.
    Monitor(monitor::MonitorArgs),
    /// Replay the poses and T_min set-points of an MCAP recording into a service.
    Replay(monitor::ReplayArgs),
    /// What accuracy costs in time: f1 error and per-cycle time of every model, with plots.
    Accuracy(accuracy::AccuracyArgs),
    /// f1 over a workspace grid: heat-map SVG and CSV (infeasible points marked).
    Map(map::MapArgs),
    /// f1 and the end-effector mode along a trajectory (the paper's circle or a CSV).
    Trajectory(trajectory::TrajectoryArgs),
    /// f1 against T_min, with the √T_min fit.
    SweepTmin(sweep_tmin::SweepTminArgs),
    /// Chord vs sagged cables along a line through the scene's pose: f1, the softest static
    /// stiffness, the largest tension and Irvine's λ² of both models (CSV and figure).
    SagCompare(sag_compare::SagCompareArgs),
    /// Print a shell completion script (bash, zsh, fish, elvish, powershell).
    Completions(completions::CompletionsArgs),
    /// Print the man page (roff): `cablevib man > cablevib.1`.
    Man(completions::ManArgs),
    /// Write a scene file from another tool's robot model (CASPR's XML files).
    Import(import::ImportArgs),
    /// The lowest modes of one pose with their shapes: table, CSV and SVG.
    Modes(modes::ModesArgs),
    /// The end-effector receptance H(ω) over a frequency band (the scene's damping): table,
    /// CSV, Bode figure, JSON.
    Frf(frf::FrfArgs),
    /// The end-effector's dynamic deviation along a trajectory (circle, CSV or a
    /// point-to-point move) by modal superposition, unshaped and shaped: residual vibration
    /// after each stop, CSV and figure.
    Simulate(simulate::SimulateArgs),
    /// Shape a trajectory with a time-varying ZV / ZVD / EI shaper that follows the
    /// estimated end-effector (or first) mode at each pose.
    Shape(simulate::ShapeArgs),
    /// Fit the scene's stiffness, mass and damping parameters to measured frequencies (and
    /// damping ratios and tensions) at many poses: estimates with standard errors, what the
    /// data cannot determine, the χ² verdict, the calibrated scene.
    Calibrate(calibrate::CalibrateArgs),
    /// Modal parameters from measured vibration (CSV or MCAP / ROS 2 bag): frequencies,
    /// damping ratios, shapes and their uncertainty per window by SSI-cov, beside the
    /// model's prediction at the window's pose.
    Identify(identify::IdentifyArgs),
}

/// Heap allocation counter supplied by the binary's global allocator (0 when none).
pub type AllocCounter = fn() -> u64;

/// Run one command; `allocations` counts heap allocations (for `bench` and `serve`). An
/// output that is one of the command's inputs is refused first ([`files`]).
pub fn run(cli: Cli, allocations: AllocCounter) -> Result<(), CliError> {
    let f = files::files(&cli.command)?;
    files::refuse_inputs(&f.outputs, &f.inputs)?;
    match cli.command {
        Command::Analyze(a) => analyze::run(&a),
        Command::Bench(a) => bench::run(&a, allocations),
        Command::Serve(a) => serve::serve(&a, allocations),
        Command::Demo(a) => serve::demo(&a),
        Command::BenchIpc(a) => serve::bench_ipc(&a),
        Command::Monitor(a) => monitor::monitor(&a),
        Command::Replay(a) => monitor::replay(&a),
        Command::Accuracy(a) => accuracy::run(&a),
        Command::Map(a) => map::run(&a),
        Command::Trajectory(a) => trajectory::run(&a),
        Command::SweepTmin(a) => sweep_tmin::run(&a),
        Command::SagCompare(a) => sag_compare::run(&a),
        Command::Completions(a) => completions::completions(&a),
        Command::Man(a) => completions::man(&a),
        Command::Import(a) => import::run(&a),
        Command::Modes(a) => modes::run(&a),
        Command::Frf(a) => frf::run(&a),
        Command::Simulate(a) => simulate::run(&a),
        Command::Shape(a) => simulate::shape(&a),
        Command::Calibrate(a) => calibrate::run(&a),
        Command::Identify(a) => identify::run(&a),
    }
}

/// A finite number as JSON, else `null`.
fn json_f64(x: f64) -> serde_json::Value {
    if x.is_finite() {
        serde_json::json!(x)
    } else {
        serde_json::Value::Null
    }
}

/// The CSV and figure paths of a command: PREFIX.csv, and the figure at `svg` or
/// PREFIX.EXT, in `format` ([`figure::target`]).
fn output_paths(
    out: &Path,
    svg: &Option<PathBuf>,
    format: Option<FigureFormat>,
) -> Result<(PathBuf, PathBuf, FigureFormat), CliError> {
    let (fig, fmt) = match svg {
        Some(p) => figure::target(p, format)?,
        None => {
            let f = format.unwrap_or_default();
            (with_ext(out, f.ext()), f)
        }
    };
    Ok((with_ext(out, "csv"), fig, fmt))
}
