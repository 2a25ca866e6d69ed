//! `cablevib monitor` (a running service live in Foxglove, recorded to MCAP), `cablevib replay`
//! (a recording's poses and T_min set-points into a service) and `demo --monitor`. The work is
//! the `cablevib-monitor` crate's.

use cablevib::outln;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use cablevib_monitor::{
    FoxgloveAddr, MonitorConfig, MonitorError, Pace, ReplayConfig, SceneSource,
};
use clap::{Args, ValueEnum};

use super::CliError;
use crate::scene::Scene;

impl From<MonitorError> for CliError {
    fn from(e: MonitorError) -> CliError {
        match e {
            MonitorError::Service(s) => CliError::Service(s),
            other => CliError::Analysis(other.to_string()),
        }
    }
}

/// `cablevib monitor` options.
#[derive(Debug, Clone, Args)]
pub struct MonitorArgs {
    /// Instance of the service to attach to (`--instance` of `cablevib serve`).
    #[arg(long, default_value = "")]
    pub instance: String,
    /// Namespace of the topics (`/cablevib/NAME/estimate`, ...); default: the instance.
    /// `--topics ""` gives the bare topics of the layout in docs/foxglove/.
    #[arg(long, value_name = "NAME")]
    pub topics: Option<String>,
    /// The scene the service estimates (file, or `spatial-paper` / `planar-paper`), for the 3D
    /// view; default: the scene the service names in its attributes (`cablevib.scene`) when it
    /// is a built-in one with the service's element model and elements per cable (otherwise a
    /// line says why there is no 3D view).
    #[arg(long)]
    pub scene: Option<String>,
    /// The scene's effect flags (as given to `serve`).
    #[command(flatten)]
    pub effects: super::args::EffectArgs,
    /// Serve live over the Foxglove WebSocket protocol at PORT, :PORT or HOST:PORT; without a
    /// host it binds 127.0.0.1 only (name 0.0.0.0 or a LAN address to be reachable from other
    /// machines).
    #[arg(long, value_name = "ADDR", default_value = cablevib_monitor::DEFAULT_FOXGLOVE)]
    pub foxglove: String,
    /// Do not serve over WebSocket (record only).
    #[arg(long)]
    pub no_foxglove: bool,
    /// Record to this MCAP file (must not exist).
    #[arg(long, value_name = "FILE.mcap")]
    pub record: Option<PathBuf>,
    /// Required first natural frequency, Hz: estimates carry f1 − required, and the monitor
    /// asks the service for its margin answer at the scene rate.
    #[arg(long)]
    pub required_hz: Option<f64>,
    /// Rate of the 3D scene updates, Hz (estimates are recorded at full rate).
    #[arg(long, default_value_t = 30.0)]
    pub scene_rate_hz: f64,
    /// How long to wait for the service, s.
    #[arg(long, default_value_t = 10.0)]
    pub wait_s: f64,
    /// Stop after this long, s (default: on Ctrl-C / SIGTERM).
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Foxglove viewers that get data at most; a further one is told so and gets none
    /// (counted). Each viewer queues at most 256 messages (a slow one loses its oldest).
    #[arg(long, default_value_t = cablevib_monitor::DEFAULT_MAX_VIEWERS)]
    pub max_viewers: usize,
}

fn duration(what: &str, s: f64) -> Result<Duration, CliError> {
    if !(s.is_finite() && s > 0.0 && s <= 1e9) {
        return Err(CliError::Usage(format!(
            "{what} {s:?} must be in (0, 1e9] s"
        )));
    }
    Ok(Duration::from_secs_f64(s))
}

fn foxglove_addr(s: &str) -> Result<FoxgloveAddr, CliError> {
    let a = FoxgloveAddr::parse(s).map_err(|e| CliError::Usage(e.to_string()))?;
    if a.remote {
        eprintln!(
            "cablevib monitor: serving on {} as asked: reachable from other machines, without \
             authentication",
            a.addr
        );
    }
    Ok(a)
}

/// `cablevib monitor`: attaches to the service of `--instance` until Ctrl-C / SIGTERM.
pub fn monitor(a: &MonitorArgs) -> Result<(), CliError> {
    let stop = cablevib_monitor::signal::stop_on_signals();
    cablevib_service::init_tracing(cablevib_monitor::LOG_FILTER);
    let scene = match &a.scene {
        Some(name) => {
            let mut s = Scene::load(name)?;
            a.effects.apply(&mut s)?;
            Some(s)
        }
        None => None,
    };
    let mut cfg = MonitorConfig::new(&a.instance);
    if let Some(t) = &a.topics {
        cablevib_ipc::check_instance(t).map_err(|e| CliError::Usage(format!("--topics: {e}")))?;
        cfg.topic_namespace = t.clone();
    }
    cfg.scene_file = a.scene.clone().unwrap_or_default();
    cfg.scene = scene;
    cfg.foxglove = if a.no_foxglove {
        None
    } else {
        Some(foxglove_addr(&a.foxglove)?)
    };
    cfg.record = a.record.clone();
    cfg.required_hz = a.required_hz;
    cfg.scene_rate_hz = a.scene_rate_hz;
    cfg.wait_timeout = duration("--wait-s", a.wait_s)?;
    cfg.duration = a.seconds.map(|s| duration("--seconds", s)).transpose()?;
    if !(1..=MAX_VIEWERS_LIMIT).contains(&a.max_viewers) {
        return Err(CliError::Usage(format!(
            "--max-viewers {} must be in [1, {MAX_VIEWERS_LIMIT}]",
            a.max_viewers
        )));
    }
    cfg.max_viewers = a.max_viewers;
    // Standard output that cannot be written stops the monitor (the recording is closed),
    // and the error is the command's.
    let mut printed = Ok(());
    let report = cablevib_monitor::run(&cfg, stop, |at| {
        printed = attached_lines(a, at);
        if printed.is_err() {
            stop.store(true, Ordering::Release);
        }
    })?;
    printed?;
    outln!("cablevib monitor: {report}")?;
    Ok(())
}

/// The lines `cablevib monitor` prints once attached.
fn attached_lines(a: &MonitorArgs, at: &cablevib_monitor::Attached) -> Result<(), CliError> {
    outln!(
        "cablevib monitor: attached to instance {:?}{}{}",
        a.instance,
        at.url
            .as_ref()
            .map_or(String::new(), |u| format!(", Foxglove at {u}")),
        a.record
            .as_ref()
            .map_or(String::new(), |p| format!(", recording to {}", p.display()))
    )?;
    match &at.scene {
        SceneSource::Given => {}
        SceneSource::Service => outln!(
            "  3D view of the service's scene {:?}",
            at.attributes
                .get(cablevib_ipc::ATTR_SCENE)
                .unwrap_or_default()
        )?,
        SceneSource::None(why) => outln!("  no 3D view: {why}")?,
    }
    Ok(())
}

/// The largest `--max-viewers`: each viewer may hold 256 queued messages (≈ 0.3 MB).
const MAX_VIEWERS_LIMIT: usize = 1024;

/// Pace of `cablevib replay`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PaceArg {
    /// At the recorded timing.
    Recorded,
    /// Each pose after the previous one's estimate (no pose skipped).
    Fast,
}

/// `cablevib replay` options.
#[derive(Debug, Clone, Args)]
pub struct ReplayArgs {
    /// The MCAP recording (of `cablevib monitor --record`).
    #[arg(value_name = "FILE.mcap")]
    pub file: PathBuf,
    /// Instance of the service to replay into.
    #[arg(long, default_value = "")]
    pub instance: String,
    /// recorded: at the recorded timing; fast: each pose after the previous one's estimate.
    #[arg(long, value_enum, default_value_t = PaceArg::Recorded)]
    pub pace: PaceArg,
    /// Send only the poses the recorded service answered (the same sequence of estimated
    /// poses as in the recording).
    #[arg(long)]
    pub answered_only: bool,
    /// Replace the recorded T_min set-points by this uniform T_min, N.
    #[arg(long)]
    pub t_min: Option<f64>,
    /// How long to wait for the service (and, with --pace fast, for each estimate), s.
    #[arg(long, default_value_t = 10.0)]
    pub wait_s: f64,
    /// With --pace recorded: a pause longer than this in the recording is shortened to it
    /// (counted in the summary), s.
    #[arg(long, default_value_t = cablevib_monitor::DEFAULT_MAX_GAP_S)]
    pub max_gap_s: f64,
}

/// `cablevib replay FILE.mcap`.
pub fn replay(a: &ReplayArgs) -> Result<(), CliError> {
    let stop = cablevib_monitor::signal::stop_on_signals();
    cablevib_service::init_tracing("warn");
    let cfg = ReplayConfig {
        file: a.file.clone(),
        instance: a.instance.clone(),
        pace: match a.pace {
            PaceArg::Recorded => Pace::Recorded,
            PaceArg::Fast => Pace::Fast,
        },
        answered_only: a.answered_only,
        t_min_n: a.t_min,
        timeout: duration("--wait-s", a.wait_s)?,
        max_gap: duration("--max-gap-s", a.max_gap_s)?,
    };
    let r = cablevib_monitor::replay::replay(&cfg, stop, |_| {})?;
    outln!(
        "cablevib replay: {} poses and {} T_min set-points sent, {} estimates received ({} ok), \
         {} unanswered, {} pauses shortened to {} s{}",
        r.poses,
        r.t_mins,
        r.estimates,
        r.estimates_ok,
        r.timeouts,
        r.gaps_shortened,
        a.max_gap_s,
        if r.stopped {
            "; stopped by a signal"
        } else {
            ""
        }
    )?;
    Ok(())
}

/// `demo --monitor` options.
#[derive(Debug, Clone, Args)]
pub struct DemoMonitorArgs {
    /// Run `cablevib monitor` beside the demo (Foxglove at --foxglove; --record to keep it).
    #[arg(long)]
    pub monitor: bool,
    /// The monitor's Foxglove WebSocket address (see `cablevib monitor --help`).
    #[arg(long, value_name = "ADDR", default_value = cablevib_monitor::DEFAULT_FOXGLOVE, requires = "monitor")]
    pub foxglove: String,
    /// The monitor records the demo to this MCAP file.
    #[arg(long, value_name = "FILE.mcap", requires = "monitor")]
    pub record: Option<PathBuf>,
}

/// A monitor running beside the demo.
pub struct DemoMonitor {
    done: Arc<AtomicBool>,
    thread: std::thread::JoinHandle<Result<cablevib_monitor::MonitorReport, MonitorError>>,
}

/// Starts the monitor on the demo's instance in a thread of this process, with the demo's
/// scene. It subscribes as the demo's service starts, so it may miss the first estimates.
/// Ctrl-C or SIGTERM closes the recording and ends the process.
pub fn start_beside_demo(
    a: &DemoMonitorArgs,
    scene: &Scene,
    scene_file: &str,
    required_hz: f64,
) -> Result<Option<DemoMonitor>, CliError> {
    if !a.monitor {
        return Ok(None);
    }
    let signal = cablevib_monitor::signal::stop_on_signals();
    cablevib_service::init_tracing(cablevib_monitor::LOG_FILTER);
    let mut cfg = MonitorConfig::new(&crate::service::demo::instance_name());
    // The bare topics, which the layout in docs/foxglove/ shows.
    cfg.topic_namespace = String::new();
    cfg.scene = Some(scene.clone());
    cfg.scene_file = scene_file.to_owned();
    cfg.foxglove = Some(foxglove_addr(&a.foxglove)?);
    cfg.record = a.record.clone();
    cfg.required_hz = Some(required_hz);
    let done = Arc::new(AtomicBool::new(false));
    let stop = Arc::new(AtomicBool::new(false));
    let thread = {
        let (done, stop) = (done.clone(), stop.clone());
        let record = a.record.clone();
        std::thread::Builder::new()
            .name("cablevib-monitor".into())
            .spawn(move || {
                // The demo's own lines report a standard output that cannot be written.
                let r = cablevib_monitor::run(&cfg, &stop, |at| {
                    let _ = outln!(
                        "  monitor: Foxglove at {}{}",
                        at.url.clone().unwrap_or_default(),
                        record
                            .as_ref()
                            .map_or(String::new(), |p| format!(", recording to {}", p.display()))
                    );
                });
                if signal.load(Ordering::Acquire) && !done.load(Ordering::Acquire) {
                    match &r {
                        Ok(report) => {
                            let _ = outln!("  monitor: {report}");
                        }
                        Err(e) => eprintln!("cablevib: monitor: {e}"),
                    }
                    std::process::exit(130);
                }
                r
            })?
    };
    // Ctrl-C / SIGTERM: stop the monitor (the file is closed), then end the process.
    {
        let (done, stop) = (done.clone(), stop.clone());
        std::thread::Builder::new()
            .name("cablevib-monitor-signal".into())
            .spawn(move || {
                while !done.load(Ordering::Acquire) {
                    if signal.load(Ordering::Acquire) {
                        stop.store(true, Ordering::Release);
                        return;
                    }
                    std::thread::sleep(Duration::from_millis(20));
                }
                stop.store(true, Ordering::Release);
            })?;
    }
    Ok(Some(DemoMonitor { done, thread }))
}

impl DemoMonitor {
    /// Stops the monitor after the demo and prints its counts.
    pub fn finish(self) -> Result<(), CliError> {
        self.done.store(true, Ordering::Release);
        let report = self
            .thread
            .join()
            .map_err(|_| CliError::Analysis("the monitor thread panicked".into()))??;
        outln!("  monitor: {report}")?;
        Ok(())
    }
}
