//! The real-time service over iceoryx2 (zero-copy shared memory).
//!
//! `cablevib serve` runs [`server::run`]: a long-running loop that subscribes to end-effector
//! poses and T_min set-points, runs the real-time [`Estimator`](crate::estimator::Estimator)
//! on the newest pose, publishes an [`EstimateSample`](cablevib_ipc::EstimateSample) that
//! echoes the pose's sequence and timestamp, and answers
//! [`MarginRequest`](cablevib_ipc::MarginRequest)s (f1 − required f1 for the latest pose).
//! Message types, service names and status codes are the `cablevib-ipc` crate's; the port
//! settings every peer uses are in [`ports`].
//!
//! | module | what |
//! |---|---|
//! | [`ports`] | opening the services with one set of settings; the service's and a controller's ports |
//! | [`server`] | the service loop, statistics, signals, real-time settings |
//! | [`schedule`] | T_min schedules (replay); trajectories are [`crate::trajectory`]'s |
//! | [`stats`] | preallocated rings and percentiles |
//! | [`demo`](mod@demo) | `cablevib demo`: service, replay and controller in one process |
//! | [`hold`] | holding f1: the T_min set-point a controller publishes from the margin answers |
//! | [`bench`](mod@bench) | `cablevib bench-ipc`: pose-published → estimate-received latency |
//!
//! # Waiting: spin or event
//!
//! With [`WaitMode::Spin`] the service busy-polls its subscribers (one CPU at 100 %, lowest
//! latency). With [`WaitMode::Event`] it blocks on the event service
//! [`SERVICE_WAKE_SERVICE`](cablevib_ipc::SERVICE_WAKE_SERVICE), which every peer notifies
//! after sending (the helpers in [`ports`] do), and wakes within tens of µs; input from a peer
//! that does not notify is still picked up, at the latest after 50 ms. Either way the
//! service notifies [`SERVICE_WAKE_CONTROLLER`](cablevib_ipc::SERVICE_WAKE_CONTROLLER) after
//! each estimate, so a controller can block too.

#![warn(missing_docs)]
// Standard output through `cablevib::outln!` (an error, not a panic, when it cannot be
// written).
#![warn(clippy::print_stdout)]
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

pub mod bench;
pub mod demo;
pub mod demo_accel;
mod demo_hold;
pub mod demo_shape;
pub mod hold;
pub mod ports;
pub mod rt;
pub mod schedule;
pub mod server;
/// The statistics live in the core (the offline studies use them too).
pub use cablevib::stats;

use core::sync::atomic::AtomicBool;

use clap::ValueEnum;

// The core's modules, under the paths the service's files name (`crate::scene::...`).
use cablevib::{
    alloc_count, estimator, kinematics, measured, modal, output_file, rng, scene, study, trajectory,
};

use crate::estimator::BuildError;
use crate::scene::{Scene, SceneError};
use crate::trajectory::TrajectoryError;

pub use schedule::TminSchedule;

pub use server::{AllocCounter, ServerConfig, ServerReport, StopReason};

/// How a loop waits for its input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum WaitMode {
    /// Busy-poll: lowest latency, one CPU core at 100 %.
    Spin,
    /// Block on an iceoryx2 event that the sender notifies: no CPU while idle, a wake-up costs
    /// tens of µs.
    Event,
}

impl WaitMode {
    /// `"spin"` or `"event"`.
    pub fn as_str(self) -> &'static str {
        match self {
            WaitMode::Spin => "spin",
            WaitMode::Event => "event",
        }
    }
}

impl core::fmt::Display for WaitMode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Errors of the service commands.
#[derive(Debug, thiserror::Error)]
pub enum ServiceError {
    /// Standard output could not be written.
    #[error(transparent)]
    Stdout(#[from] crate::output_file::StdoutError),
    /// The scene could not be loaded.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The trajectory could not be made or read.
    #[error(transparent)]
    Trajectory(#[from] TrajectoryError),
    /// The estimator could not be built for the scene.
    #[error(transparent)]
    Build(#[from] BuildError),
    /// A bad option or input file.
    #[error("{0}")]
    Usage(String),
    /// A peer created a service with another message layout (another schema version).
    #[error("incompatible peer: {0}")]
    IncompatiblePeer(String),
    /// iceoryx2 refused an operation.
    #[error("iceoryx2: {context}: {reason}")]
    Ipc {
        /// What was being done.
        context: String,
        /// iceoryx2's error.
        reason: String,
    },
    /// An existing service was created (by another program) with other limits than cablevib
    /// creates it with; using it could admit impostors or drop messages.
    #[error(
        "service \"{service}\" exists with {setting} = {found}, expected {expected}; another \
         program created it: stop that program, or use another --instance"
    )]
    ServiceSettings {
        /// The iceoryx2 service name.
        service: String,
        /// The static setting that differs.
        setting: &'static str,
        /// Its value in the existing service.
        found: String,
        /// What cablevib needs.
        expected: String,
    },
    /// Another live cablevib service already serves this instance.
    #[error(
        "another cablevib service already serves \"{service}\"; stop it, or give this one \
         another --instance"
    )]
    AlreadyServing {
        /// The margin service both would serve.
        service: String,
    },
    /// SIGINT/SIGTERM arrived before the service was up.
    #[error("interrupted by a signal")]
    Interrupted,
    /// A thread of `demo` or `bench-ipc` panicked.
    #[error("the {0} thread panicked")]
    ThreadPanicked(&'static str),
    /// The other side did not answer in time.
    #[error("timed out: {0}")]
    Timeout(String),
}

/// What `cablevib demo` runs (the scene is passed beside it).
#[derive(Debug, Clone)]
pub struct DemoConfig {
    /// How long the replay publishes poses, s.
    pub seconds: f64,
    /// Required first natural frequency the margin is computed against, Hz.
    pub required_hz: f64,
    /// How the service waits for poses.
    pub wait: WaitMode,
    /// How the controller waits for estimates and margin answers.
    pub controller_wait: WaitMode,
    /// Pose rate, Hz.
    pub rate_hz: f64,
    /// Time per revolution of the circle, s.
    pub period_s: f64,
    /// T_min schedule (default: the scene's T_min throughout).
    pub t_min_schedule: Option<TminSchedule>,
    /// Hold f1 at or above this, Hz, with the T_min set-points of [`hold::F1Hold`] (None: the
    /// controller only asks for the margin).
    pub hold_f1_hz: Option<f64>,
    /// With `hold_f1_hz`: write one CSV row per ok estimate after the hold's first answer.
    pub hold_csv: Option<std::path::PathBuf>,
    /// Shape the replay's poses online with this shaper at the live end-effector mode
    /// (None: the poses as the trajectory gives them).
    pub shape: Option<crate::trajectory::shaping::ShaperKind>,
    /// Publish the synthetic accelerometer's samples ([`demo_accel`]) on the vibration
    /// service (demos of at most [`demo_accel::MAX_SECONDS`]).
    pub accelerometer: bool,
}

/// What `cablevib bench-ipc` measures (the scene is passed beside it).
#[derive(Debug, Clone)]
pub struct BenchIpcConfig {
    /// Timed samples per wait mode (after the warm-up samples).
    pub samples: usize,
    /// Wait mode to measure; both when `None`.
    pub wait: Option<WaitMode>,
    /// Pause between a received estimate and the next pose, µs (0: ping-pong).
    pub gap_us: u64,
    /// Pin the service thread to this CPU and the client to the next one.
    pub cpu: Option<usize>,
    /// One JSON object on stdout instead of the table.
    pub json: bool,
    /// The service thread serves iceoryx2's per-loan allocations from the block pool
    /// ([`server::ServerConfig::alloc_pool`]).
    pub alloc_pool: bool,
    /// Without, with, or alternately without and with an accelerometer sample before each
    /// pose.
    pub vibration: BenchVibration,
}

/// `bench-ipc --vibration`: whether the vibration input is fed while measuring.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum BenchVibration {
    /// No vibration sender (the latency without the input).
    #[default]
    Off,
    /// One accelerometer sample (1 kHz sensor) before each pose.
    On,
    /// Both, in alternating blocks of the same run (side by side).
    Both,
}

/// Routes `tracing` (and iceoryx2's logs) to stderr, filtered by `RUST_LOG` (default
/// `default_filter`). Does nothing when a subscriber is already installed.
pub fn init_tracing(default_filter: &str) {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(default_filter));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .with_writer(std::io::stderr)
        .try_init();
}

/// `cablevib serve`: runs the service on `scene` until SIGINT/SIGTERM (or
/// `cfg.max_cycles`).
pub fn serve(
    scene: &Scene,
    cfg: &ServerConfig,
    allocations: fn() -> u64,
) -> Result<ServerReport, ServiceError> {
    init_tracing("info");
    let stop = AtomicBool::new(false);
    server::run(scene, cfg, &stop, allocations)
}

/// `cablevib demo`: service, replay publisher and controller over real iceoryx2 services.
pub fn demo(scene: &Scene, cfg: &DemoConfig) -> Result<(), ServiceError> {
    demo::run(scene, cfg)
}

/// `cablevib bench-ipc`: pose-published → estimate-received latency in spin and event mode.
pub fn bench_ipc(scene: &Scene, cfg: &BenchIpcConfig) -> Result<(), ServiceError> {
    bench::run(scene, cfg)
}
