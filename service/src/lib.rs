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
mod error;
pub mod hold;
pub mod ports;
pub mod rt;
pub mod schedule;
pub mod server;
/// The statistics live in the core (the offline studies use them too).
pub use cablevib::stats;

use core::sync::atomic::AtomicBool;

// The core's modules, under the paths the service's files name (`crate::scene::...`).
use cablevib::{
    alloc_count, estimator, kinematics, measured, modal, output_file, rng, scene, study, trajectory,
};

use crate::scene::Scene;

pub use error::{ServiceError, ServiceParam};
pub use schedule::TminSchedule;

pub use server::{AllocCounter, ServerConfig, ServerReport, StopReason};

/// How a loop waits for its input.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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

impl core::str::FromStr for WaitMode {
    type Err = String;
    /// `spin` or `event`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "spin" => Ok(WaitMode::Spin),
            "event" => Ok(WaitMode::Event),
            _ => Err(format!("wait mode `{s}`: expected spin or event")),
        }
    }
}

impl core::fmt::Display for WaitMode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.as_str())
    }
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

/// The IPC bench's vibration option: whether the vibration input is fed while measuring.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
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
