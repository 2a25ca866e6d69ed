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
//! | [`trajectory`] | the paper's circle, CSV trajectories, T_min schedules (replay) |
//! | [`stats`] | preallocated rings and percentiles |
//! | [`demo`](mod@demo) | `cablevib demo`: service, replay and controller in one process |
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

pub mod bench;
pub mod demo;
pub mod ports;
pub mod rt;
pub mod server;
pub mod stats;
pub mod trajectory;

use core::sync::atomic::AtomicBool;
use core::time::Duration;

use clap::{Args, ValueEnum};

use crate::cli::CliError;
use crate::estimator::BuildError;

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
    /// The scene could not be loaded.
    #[error(transparent)]
    Scene(#[from] CliError),
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

/// `cablevib serve` options.
#[derive(Debug, Clone, Args)]
pub struct ServeArgs {
    /// Scene file (TOML), or `spatial-paper` / `planar-paper` for the embedded paper robots.
    #[arg(long, default_value = "spatial-paper")]
    pub scene: String,
    /// Instance name prefixing every service name ("NAME/cablevib/pose", ...), so that several
    /// robots (or tests) share a machine; empty: the bare names.
    #[arg(long, default_value = "")]
    pub instance: String,
    /// spin: busy-poll (lowest latency, one CPU at 100 %); event: block on the wake-service
    /// event that peers notify after sending (tens of µs per wake-up).
    #[arg(long, value_enum, default_value_t = WaitMode::Spin)]
    pub wait: WaitMode,
    /// Pin the service thread to this CPU (0-based); a warning if not permitted.
    #[arg(long)]
    pub cpu: Option<usize>,
    /// Run with SCHED_FIFO (priority 80) and locked memory (mlockall); a warning if not
    /// permitted.
    #[arg(long)]
    pub realtime: bool,
    /// Period of the statistics log line, s (0 = none).
    #[arg(long, default_value_t = 5.0)]
    pub stats_period_s: f64,
    /// Stop after this many estimator cycles (tests, benchmarks).
    #[arg(long)]
    pub max_cycles: Option<u64>,
}

/// `cablevib demo` options.
#[derive(Debug, Clone, Args)]
pub struct DemoArgs {
    /// How long the replay publishes poses, s.
    #[arg(long, default_value_t = 5.0)]
    pub seconds: f64,
    /// Required first natural frequency the margin is computed against, Hz.
    #[arg(long, default_value_t = 8.0)]
    pub required_hz: f64,
    /// How the service waits for poses: spin (busy-poll, one CPU) or event.
    #[arg(long, value_enum, default_value_t = WaitMode::Spin)]
    pub wait: WaitMode,
    /// How the controller waits for estimates and margin answers; event leaves the other CPU
    /// to the replay and the controller (spin only pays off with a free CPU per spinning
    /// thread).
    #[arg(long, value_enum, default_value_t = WaitMode::Event)]
    pub controller_wait: WaitMode,
    /// Pose rate, Hz.
    #[arg(long, default_value_t = 1000.0)]
    pub rate_hz: f64,
    /// Time per revolution of the circle, s.
    #[arg(long, default_value_t = 4.0)]
    pub period_s: f64,
    /// T_min schedule SECONDS:NEWTONS,... (e.g. "0:60,3:70"); default: the scene's T_min.
    #[arg(long)]
    pub t_min_schedule: Option<String>,
    /// Scene file (TOML), or `spatial-paper` / `planar-paper`.
    #[arg(long, default_value = "spatial-paper")]
    pub scene: String,
}

/// `cablevib bench-ipc` options.
#[derive(Debug, Clone, Args)]
pub struct BenchIpcArgs {
    /// Timed samples per wait mode (after 1000 warm-up samples).
    #[arg(long, default_value_t = 100_000)]
    pub samples: usize,
    /// Wait mode to measure; both when omitted.
    #[arg(long, value_enum)]
    pub wait: Option<WaitMode>,
    /// Pause between a received estimate and the next pose, µs (0: ping-pong).
    #[arg(long, default_value_t = 0)]
    pub gap_us: u64,
    /// Pin the service thread to this CPU and the client to the next one.
    #[arg(long)]
    pub cpu: Option<usize>,
    /// Scene file (TOML), or `spatial-paper` / `planar-paper`.
    #[arg(long, default_value = "spatial-paper")]
    pub scene: String,
    /// One JSON object on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
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

/// `cablevib serve`: runs the service until SIGINT/SIGTERM (or `--max-cycles`).
pub fn serve(a: &ServeArgs, allocations: fn() -> u64) -> Result<(), ServiceError> {
    init_tracing("info");
    if !(a.stats_period_s.is_finite() && a.stats_period_s >= 0.0) {
        return Err(ServiceError::Usage(format!(
            "--stats-period-s {} must be finite and ≥ 0",
            a.stats_period_s
        )));
    }
    let scene = crate::cli::load_scene(&a.scene)?;
    let cfg = ServerConfig {
        instance: a.instance.clone(),
        wait: a.wait,
        stats_period: (a.stats_period_s > 0.0).then(|| Duration::from_secs_f64(a.stats_period_s)),
        max_cycles: a.max_cycles,
        cpu: a.cpu,
        realtime: a.realtime,
        ..ServerConfig::default()
    };
    let stop = AtomicBool::new(false);
    server::run(&scene, &cfg, &stop, allocations)?;
    Ok(())
}

/// `cablevib demo`: service, replay publisher and controller over real iceoryx2 services.
pub fn demo(a: &DemoArgs) -> Result<(), ServiceError> {
    demo::run(a)
}

/// `cablevib bench-ipc`: pose-published → estimate-received latency in spin and event mode.
pub fn bench_ipc(a: &BenchIpcArgs) -> Result<(), ServiceError> {
    bench::run(a)
}
