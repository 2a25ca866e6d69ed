//! The service commands: `serve` (the long-running iceoryx2 service), `demo` (service,
//! replay and controller in one process) and `bench-ipc` (pose-to-estimate latency). Each
//! turns its options into the service's configuration struct; the work is
//! [`crate::service`]'s.

use super::{AllocCounter, CliError};
use crate::scene::Scene;
use crate::service::{
    BenchIpcConfig, BenchVibration, DemoConfig, ServerConfig, TminSchedule, WaitMode,
};
use cablevib::outln;
use clap::Args;
use std::time::Duration;

/// `cablevib serve` options.
#[derive(Debug, Clone, Args)]
pub struct ServeArgs {
    /// Scene file (TOML), or `spatial-paper` / `planar-paper` for the embedded paper robots
    /// [default: spatial-paper].
    #[arg(value_name = "SCENE", conflicts_with = "scene_option")]
    pub scene: Option<String>,
    /// The scene as an option, the same as SCENE (what `serve` took before SCENE became
    /// positional like in the other commands).
    #[arg(long = "scene", id = "scene_option", value_name = "SCENE")]
    pub scene_option: Option<String>,
    /// The scene's effect flags.
    #[command(flatten)]
    pub effects: super::args::EffectArgs,
    /// Instance name prefixing every service name ("NAME/cablevib/pose", ...), so that several
    /// robots (or tests) share a machine; empty: the bare names.
    #[arg(long, default_value = "")]
    pub instance: String,
    /// spin: busy-poll (lowest latency, one CPU at 100 %); event: block on the wake-service
    /// event that peers notify after sending (tens of µs per wake-up).
    #[arg(long, value_enum, default_value_t = WaitArg::Spin)]
    pub wait: WaitArg,
    /// Pin the service thread to this CPU (0-based); a warning if not permitted.
    #[arg(long)]
    pub cpu: Option<usize>,
    /// Run with SCHED_FIFO (priority 80) and locked memory (mlockall); a warning if not
    /// permitted.
    #[arg(long)]
    pub realtime: bool,
    /// Period of the statistics log line, s (0 = none; else at least 1 ms, at most a day).
    #[arg(long, default_value_t = 5.0)]
    pub stats_period_s: f64,
    /// Stop after this many estimator cycles (tests, benchmarks).
    #[arg(long)]
    pub max_cycles: Option<u64>,
}

/// The scene `serve` runs when neither SCENE nor `--scene` is given.
const DEFAULT_SERVE_SCENE: &str = "spatial-paper";

impl ServeArgs {
    /// The scene asked for: SCENE, else `--scene`, else the spatial paper robot.
    pub fn scene_name(&self) -> &str {
        self.scene
            .as_deref()
            .or(self.scene_option.as_deref())
            .unwrap_or(DEFAULT_SERVE_SCENE)
    }
}

/// `--wait` values: the service's [`WaitMode`]s, as the command line spells them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WaitArg {
    /// Busy-poll: lowest latency, one CPU core at 100 %.
    Spin,
    /// Block on an iceoryx2 event that the sender notifies: no CPU while idle, a wake-up
    /// costs tens of µs.
    Event,
}

impl From<WaitArg> for WaitMode {
    fn from(w: WaitArg) -> Self {
        match w {
            WaitArg::Spin => WaitMode::Spin,
            WaitArg::Event => WaitMode::Event,
        }
    }
}

/// `--vibration` values: the service's [`BenchVibration`]s, as the command line spells them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum VibrationArg {
    /// No vibration sender (the latency without the input).
    Off,
    /// One accelerometer sample (1 kHz sensor) before each pose.
    On,
    /// Both, in alternating blocks of the same run (side by side).
    Both,
}

impl From<VibrationArg> for BenchVibration {
    fn from(v: VibrationArg) -> Self {
        match v {
            VibrationArg::Off => BenchVibration::Off,
            VibrationArg::On => BenchVibration::On,
            VibrationArg::Both => BenchVibration::Both,
        }
    }
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
    #[arg(long, value_enum, default_value_t = WaitArg::Spin)]
    pub wait: WaitArg,
    /// How the controller waits for estimates and margin answers; event leaves the other CPU
    /// to the replay and the controller (spin only pays off with a free CPU per spinning
    /// thread).
    #[arg(long, value_enum, default_value_t = WaitArg::Event)]
    pub controller_wait: WaitArg,
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
    /// The scene's effect flags.
    #[command(flatten)]
    pub effects: super::args::EffectArgs,
    /// Hold the first natural frequency at or above HZ: the controller publishes the T_min
    /// set-point the margin answers name (raised at once below HZ + 0.1 Hz guard, relaxed at
    /// ≤ 20 N/s when f1 ≥ HZ + 0.25 Hz, between the scene's T_min and the smallest cable
    /// t_max; docs/service.md, "Holding f1"). The summary counts the ok estimates below HZ
    /// after the first answer and compares the mean Σ T² with the fixed T_min that meets HZ
    /// at every pose. The margin is then asked against HZ + guard (--required-hz is unused).
    #[arg(long, value_name = "HZ", conflicts_with = "t_min_schedule")]
    pub hold_f1: Option<f64>,
    /// With --hold-f1: write one CSV row per ok estimate after the first answer (t_s,
    /// pose_sequence, f1_hz, setpoint_n, sum_t2_n2, and the fixed T_min's fixed_t_min_n,
    /// f1_fixed_hz, sum_t2_fixed_n2), and the figures of f1 and T_min against time next to it
    /// (PATH without its extension + -f1.svg and -tmin.svg).
    #[arg(long, value_name = "PATH", requires = "hold_f1")]
    pub hold_csv: Option<std::path::PathBuf>,
    /// Shape the replay's poses online (zv, zvd or ei) at the end-effector mode frequency of
    /// the latest estimate, with the scene's damping there; until the first estimate with an
    /// end-effector mode the poses pass unshaped. The summary adds a line: the shaper, its
    /// mean design frequency, the delay it adds, and the shaped path's peak deviation from the
    /// unshaped one (docs/vibration.md, "Input shaping").
    #[arg(long, value_name = "zv|zvd|ei", value_parser = parse_shaper)]
    pub shape: Option<crate::trajectory::shaping::ShaperKind>,
    /// Without the synthetic accelerometer (by default the simulated vibration of the
    /// trajectory is published on the vibration service and the estimates carry the
    /// measured frequencies; demos over 60 s run without it, since the record is simulated
    /// before the demo starts, about 0.35 s per second).
    #[arg(long)]
    pub no_accelerometer: bool,
    /// A monitor beside the demo (Foxglove, MCAP).
    #[command(flatten)]
    pub monitor: super::monitor::DemoMonitorArgs,
}

/// The shaper named on the command line (`--shape`).
fn parse_shaper(s: &str) -> Result<crate::trajectory::shaping::ShaperKind, String> {
    crate::trajectory::shaping::ShaperKind::from_name(s)
        .ok_or_else(|| format!("unknown shaper {s:?}: zv, zvd or ei"))
}

/// `cablevib bench-ipc` options.
#[derive(Debug, Clone, Args)]
pub struct BenchIpcArgs {
    /// Timed samples per wait mode (after 1000 warm-up samples).
    #[arg(long, default_value_t = 100_000)]
    pub samples: usize,
    /// Wait mode to measure; both when omitted.
    #[arg(long, value_enum)]
    pub wait: Option<WaitArg>,
    /// Pause between a received estimate and the next pose, µs (0: ping-pong).
    #[arg(long, default_value_t = 0)]
    pub gap_us: u64,
    /// Pin the service thread to this CPU and the client to the next one.
    #[arg(long)]
    pub cpu: Option<usize>,
    /// Scene file (TOML), or `spatial-paper` / `planar-paper`.
    #[arg(long, default_value = "spatial-paper")]
    pub scene: String,
    /// The scene's effect flags.
    #[command(flatten)]
    pub effects: super::args::EffectArgs,
    /// One JSON object on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Serve iceoryx2's per-loan and per-request allocations on the service thread from the
    /// constant-time block pool (true, as `serve` does) or from the system allocator (false:
    /// to measure the difference)
    #[arg(long, value_name = "true|false", default_value_t = true, action = clap::ArgAction::Set)]
    pub alloc_pool: bool,
    /// Feed the service's vibration input while measuring: off, on (a 1 kHz accelerometer
    /// sample before each pose), or both in alternating blocks of 2000 poses (the latency
    /// with and without the input, side by side in one run)
    #[arg(long, value_enum, default_value_t = VibrationArg::Off)]
    pub vibration: VibrationArg,
}

/// Longest `--stats-period-s`, s: one line a day is already rarer than anyone watches a log;
/// the bound keeps the period a representable `Duration` (1e300 s is not).
pub const MAX_STATS_PERIOD_S: f64 = 86_400.0;

/// Shortest non-zero `--stats-period-s`, s: a line per millisecond is already more than a log
/// can take (5e-324 s would round to a zero period, a line every cycle).
pub const MIN_STATS_PERIOD_S: f64 = 1e-3;

/// The statistics period of `--stats-period-s` (None for 0).
fn stats_period(s: f64) -> Result<Option<Duration>, CliError> {
    let bad = || {
        CliError::Usage(format!(
            "--stats-period-s {s:?} must be 0 (none) or in [{MIN_STATS_PERIOD_S}, {MAX_STATS_PERIOD_S}] s"
        ))
    };
    if s == 0.0 {
        return Ok(None);
    }
    if !(MIN_STATS_PERIOD_S..=MAX_STATS_PERIOD_S).contains(&s) {
        return Err(bad());
    }
    Duration::try_from_secs_f64(s).map(Some).map_err(|_| bad())
}

/// Scene `name` with the effect flags applied.
fn load_scene(name: &str, effects: &super::args::EffectArgs) -> Result<Scene, CliError> {
    let mut scene = Scene::load(name)?;
    effects.apply(&mut scene)?;
    Ok(scene)
}

/// `cablevib serve`: loads the scene and runs the service until SIGINT/SIGTERM.
pub fn serve(a: &ServeArgs, allocations: AllocCounter) -> Result<(), CliError> {
    let stats_period = stats_period(a.stats_period_s)?;
    cablevib_ipc::check_instance(&a.instance).map_err(|e| CliError::Usage(e.to_string()))?;
    let scene = load_scene(a.scene_name(), &a.effects)?;
    super::args::warn_if_sag_matters(&scene, None);
    let cfg = ServerConfig {
        instance: a.instance.clone(),
        wait: a.wait.into(),
        stats_period,
        max_cycles: a.max_cycles,
        cpu: a.cpu,
        realtime: a.realtime,
        ..ServerConfig::default()
    };
    crate::service::serve(&scene, &cfg, allocations)?;
    Ok(())
}

/// `cablevib demo`: service, replay publisher and controller on one scene.
pub fn demo(a: &DemoArgs) -> Result<(), CliError> {
    let scene = load_scene(&a.scene, &a.effects)?;
    let t_min_schedule = match &a.t_min_schedule {
        Some(s) => Some(TminSchedule::parse(s)?),
        None => None,
    };
    let cfg = DemoConfig {
        seconds: a.seconds,
        required_hz: a.required_hz,
        wait: a.wait.into(),
        controller_wait: a.controller_wait.into(),
        rate_hz: a.rate_hz,
        period_s: a.period_s,
        t_min_schedule,
        hold_f1_hz: a.hold_f1,
        hold_csv: a.hold_csv.clone(),
        shape: a.shape,
        accelerometer: !a.no_accelerometer,
    };
    let monitor = super::monitor::start_beside_demo(&a.monitor, &scene, &a.scene, a.required_hz)?;
    crate::service::demo(&scene, &cfg)?;
    if let Some(m) = monitor {
        m.finish()?;
    }
    if let (Some(hz), Some(csv)) = (a.hold_f1, &a.hold_csv) {
        hold_figures(csv, hz)?;
    }
    Ok(())
}

/// The figures of the `--hold-csv` record, next to it: PATH without its extension +
/// `-f1.svg` and `-tmin.svg` (none when the demo wrote no record).
fn hold_figures(csv: &std::path::Path, hold_hz: f64) -> Result<(), CliError> {
    let Ok(text) = std::fs::read_to_string(csv) else {
        return Ok(());
    };
    let Some((f1, t_min)) = crate::report::hold::hold_svgs(&text, hold_hz) else {
        return Err(CliError::Usage(format!(
            "{}: not a --hold-csv record",
            csv.display()
        )));
    };
    for (path, svg) in hold_figure_paths(csv).into_iter().zip([f1, t_min]) {
        crate::output_file::write_whole(&path, svg.as_bytes())
            .map_err(|e| CliError::Usage(e.to_string()))?;
        outln!("  hold: figure written to {}", path.display())?;
    }
    Ok(())
}

/// The figures of a `--hold-csv` record: PATH without its extension + `-f1.svg` and
/// `-tmin.svg`.
pub fn hold_figure_paths(csv: &std::path::Path) -> [std::path::PathBuf; 2] {
    let stem = csv.with_extension("");
    ["-f1.svg", "-tmin.svg"].map(|suffix| {
        let mut name = stem.clone().into_os_string();
        name.push(suffix);
        name.into()
    })
}

/// `cablevib bench-ipc`: pose-published → estimate-received latency.
pub fn bench_ipc(a: &BenchIpcArgs) -> Result<(), CliError> {
    let scene = load_scene(&a.scene, &a.effects)?;
    let cfg = BenchIpcConfig {
        samples: a.samples,
        wait: a.wait.map(WaitMode::from),
        gap_us: a.gap_us,
        cpu: a.cpu,
        json: a.json,
        alloc_pool: a.alloc_pool,
        vibration: a.vibration.into(),
    };
    Ok(crate::service::bench_ipc(&scene, &cfg)?)
}

#[cfg(test)]
mod tests {
    use super::super::{Cli, Command};
    use clap::Parser;

    /// `serve` warns "pass --sag true|false": every service command takes it, and the scene
    /// it runs has the effect set (before: `--sag` was an unknown argument to all three).
    #[test]
    fn service_commands_take_the_scene_effect_flags() {
        for (args, on) in [
            (&["cablevib", "serve", "--sag", "false"][..], false),
            (&["cablevib", "serve", "--sag", "true"][..], true),
            (&["cablevib", "demo", "--sag", "true"][..], true),
            (&["cablevib", "bench-ipc", "--sag", "false"][..], false),
        ] {
            let cli = Cli::try_parse_from(args).unwrap_or_else(|e| panic!("{args:?}: {e}"));
            let (name, effects) = match &cli.command {
                Command::Serve(a) => (a.scene_name().to_owned(), a.effects.clone()),
                Command::Demo(a) => (a.scene.clone(), a.effects.clone()),
                Command::BenchIpc(a) => (a.scene.clone(), a.effects.clone()),
                other => panic!("{other:?}"),
            };
            let scene = super::load_scene(&name, &effects).unwrap();
            assert_eq!(scene.model.sag, on, "{args:?}");
            assert!(scene.model.sag_explicit, "{args:?}");
        }
    }
}
