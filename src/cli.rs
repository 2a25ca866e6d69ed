//! Command-line front end: argument structures and the offline commands (`analyze`, `bench`).
//! The service commands (`serve`, `demo`, `bench-ipc`) live in [`crate::service`].
//!
//! Functions here return `Result<_, CliError>`; the binary maps errors to a one-line reason
//! and a non-zero exit code.

use crate::estimator::{reference_analysis, Estimator, EstimatorParams, Status};
use crate::kinematics::Pose;
use crate::modal::lambda_to_hz;
use crate::scene::{ElementKind, Scene, SceneError};
use crate::service::stats::{percentile, StatusHistogram};
use crate::service::{BenchIpcConfig, DemoConfig, ServerConfig, TminSchedule, WaitMode};
use crate::trajectory::circle_pose;
use clap::{Args, Parser, Subcommand};
use nalgebra::Vector3;
use std::path::Path;
use std::time::Instant;

/// Errors of the command-line tools.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// Bad scene.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Bad option value.
    #[error("{0}")]
    Usage(String),
    /// The analysis failed (infeasible tensions, ...).
    #[error("{0}")]
    Analysis(String),
    /// Output failed.
    #[error("output: {0}")]
    Io(#[from] std::io::Error),
    /// A service command failed.
    #[error(transparent)]
    Service(#[from] crate::service::ServiceError),
}

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
    /// Tensions and natural frequencies of one pose (dense reference, or --realtime).
    Analyze(AnalyzeArgs),
    /// Drive the real-time estimator along the paper's circle and report per-cycle latency.
    Bench(BenchArgs),
    /// Run the long-running iceoryx2 service.
    Serve(ServeArgs),
    /// Run service, replay publisher and controller together on the default scene.
    Demo(DemoArgs),
    /// Measure pose-published → estimate-received latency over iceoryx2.
    BenchIpc(BenchIpcArgs),
    /// What accuracy costs in time: f1 error and per-cycle time of every model, with plots.
    Accuracy(crate::sweep::AccuracyArgs),
    /// f1 over a workspace grid: heat-map SVG and CSV (infeasible points marked).
    Map(crate::sweep::MapArgs),
    /// f1 and the end-effector mode along a trajectory (the paper's circle or a CSV).
    Trajectory(crate::sweep::TrajectoryArgs),
    /// f1 against T_min, with the √T_min fit.
    SweepTmin(crate::sweep::SweepTminArgs),
}

/// Scene and model overrides shared by the offline commands.
#[derive(Debug, Args, Clone)]
pub struct SceneArgs {
    /// Scene file (TOML), or `spatial-paper` / `planar-paper` for the embedded paper robots.
    pub scene: String,
    /// End-effector position x,y,z in m (default: the scene's).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub position: Option<Vector3<f64>>,
    /// Minimum cable tension T_min in N (default: the scene's).
    #[arg(long)]
    pub t_min: Option<f64>,
    /// Elements per cable (default: the scene's).
    #[arg(long)]
    pub elements: Option<usize>,
    /// Element model: fem, catenary, continuous, massless or auto (default: the scene's).
    #[arg(long)]
    pub element: Option<String>,
}

/// `cablevib analyze`.
#[derive(Debug, Args)]
pub struct AnalyzeArgs {
    /// Scene and overrides.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Number of frequencies to print.
    #[arg(long, default_value_t = 10)]
    pub modes: usize,
    /// One JSON object on stdout instead of tables.
    #[arg(long)]
    pub json: bool,
    /// Print what the real-time path computes (f1, end-effector mode, tensions, status).
    #[arg(long)]
    pub realtime: bool,
}

/// `cablevib bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Scene and overrides.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Cycles to time.
    #[arg(long, default_value_t = 20_000)]
    pub cycles: usize,
    /// Period of one revolution of the circle, s (poses are spaced 1 ms apart).
    #[arg(long, default_value_t = 4.0)]
    pub period_s: f64,
    /// Poses on which the dense reference is timed and compared (0 to skip).
    #[arg(long, default_value_t = 8)]
    pub dense_samples: usize,
    /// Skip the end-effector mode (f1 only).
    #[arg(long)]
    pub no_ee_mode: bool,
    /// One JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

fn parse_vec3(s: &str) -> Result<Vector3<f64>, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("`{x}`: {e}")))
        .collect::<Result<_, _>>()?;
    if v.len() != 3 || !v.iter().all(|x| x.is_finite()) {
        return Err(format!("expected three finite numbers X,Y,Z, got `{s}`"));
    }
    Ok(Vector3::new(v[0], v[1], v[2]))
}

/// Load a scene file or an embedded paper scene.
pub fn load_scene(name: &str) -> Result<Scene, CliError> {
    let p = Path::new(name);
    if !p.exists() {
        match name {
            "spatial-paper" | "spatial" | "default" => return Ok(Scene::default_scene()),
            "planar-paper" | "planar" => return Ok(Scene::planar_paper()),
            _ => {}
        }
    }
    Ok(Scene::from_path(p)?)
}

/// Apply the overrides; returns the scene with its position and T_min set.
pub fn resolve_scene(a: &SceneArgs) -> Result<Scene, CliError> {
    let mut s = load_scene(&a.scene)?;
    if let Some(p) = a.position {
        s.ee_position_m = p;
    }
    if let Some(t) = a.t_min {
        if !(t.is_finite() && t >= 0.0 && t <= s.t_max_n) {
            return Err(CliError::Usage(format!(
                "--t-min {t} N must be finite and within [0, t_max = {} N]",
                s.t_max_n
            )));
        }
        s.t_min_n = t;
    }
    let element = match &a.element {
        Some(e) => ElementKind::parse(e).ok_or_else(|| {
            CliError::Usage(format!(
                "--element `{e}`: expected fem, catenary, continuous, massless or auto"
            ))
        })?,
        None => s.model.element,
    };
    let n = a.elements.unwrap_or(s.model.elements_per_cable);
    if n == 0 || n > crate::scene::MAX_ELEMENTS_PER_CABLE {
        return Err(CliError::Usage(format!(
            "--elements {n}: must be in 1..={}",
            crate::scene::MAX_ELEMENTS_PER_CABLE
        )));
    }
    Ok(s.with_model(element, n))
}

fn json_f64(x: f64) -> serde_json::Value {
    if x.is_finite() {
        serde_json::json!(x)
    } else {
        serde_json::Value::Null
    }
}

/// `cablevib analyze`.
pub fn analyze(a: &AnalyzeArgs) -> Result<(), CliError> {
    let s = resolve_scene(&a.scene)?;
    let pos = s.ee_position_m;
    let s = if s.model.element == ElementKind::Auto {
        let (resolved, choice) =
            crate::estimator::resolve_auto(&s).map_err(|e| CliError::Analysis(e.to_string()))?;
        if !a.json {
            println!("{choice}");
        }
        resolved
    } else {
        s
    };
    if a.realtime
        || s.model.element == ElementKind::Continuous
        || s.model.element == ElementKind::Massless
    {
        return analyze_realtime(a, &s);
    }
    let t0 = Instant::now();
    let r = reference_analysis(&s, &pos, s.t_min_n, true)
        .map_err(|e| CliError::Analysis(e.to_string()))?;
    let secs = t0.elapsed().as_secs_f64();
    let k = a.modes.min(r.modes.lambda.len());
    let f: Vec<f64> = r.modes.lambda[..k]
        .iter()
        .map(|&l| lambda_to_hz(l))
        .collect();
    let part = &r.modes.ee_participation[..k];
    if a.json {
        let o = serde_json::json!({
            "scene": s.name,
            "position_m": [pos.x, pos.y, pos.z],
            "t_min_n": s.t_min_n,
            "tensions_n": r.tensions_n,
            "frequencies_hz": f,
            "ee_participation": part,
            "dof": r.dof,
            "element": s.model.element.as_str(),
            "elements_per_cable": s.model.elements_per_cable,
            "stiffness_n_m": r.stiffness_n_m.row_iter().map(|row| row.iter().copied().collect::<Vec<_>>()).collect::<Vec<_>>(),
            "solver": "dense",
            "dense_seconds": secs,
        });
        println!("{o}");
        return Ok(());
    }
    println!(
        "scene {}  position ({:.4}, {:.4}, {:.4}) m  T_min {} N  model {} × {} elements/cable  ({} DOF, dense solve {:.1} ms)",
        s.name,
        pos.x,
        pos.y,
        pos.z,
        s.t_min_n,
        s.model.element.as_str(),
        s.model.elements_per_cable,
        r.dof,
        secs * 1e3
    );
    println!("\n cable   tension (N)");
    for (i, t) in r.tensions_n.iter().enumerate() {
        println!(" {:>5}   {:>11.4}", i, t);
    }
    println!("\n mode   frequency (Hz)   end-effector participation");
    for (i, (fi, p)) in f.iter().zip(part).enumerate() {
        println!(" {:>4}   {:>14.6}   {:>8.4}", i + 1, fi, p);
    }
    Ok(())
}

fn analyze_realtime(a: &AnalyzeArgs, s: &Scene) -> Result<(), CliError> {
    let mut est = Estimator::new(s).map_err(|e| CliError::Analysis(e.to_string()))?;
    let t0 = Instant::now();
    let e = *est.update(&Pose::at(s.ee_position_m), s.t_min_n);
    let ns = t0.elapsed().as_nanos();
    if a.json {
        let o = serde_json::json!({
            "scene": s.name,
            "status": e.status.as_str(),
            "error": e.error.map(|x| x.to_string()),
            "tensions_n": e.tensions().iter().map(|&x| json_f64(x)).collect::<Vec<_>>(),
            "f1_hz": json_f64(e.f1_hz),
            "f1_ee_participation": json_f64(e.f1_ee_participation),
            "ee_mode_hz": json_f64(e.ee_mode_hz),
            "ee_mode_participation": json_f64(e.ee_mode_participation),
            "stiffness_n_m": e.stiffness_n_m.row_iter().map(|row| row.iter().map(|&x| json_f64(x)).collect::<Vec<_>>()).collect::<Vec<_>>(),
            "element": s.model.element.as_str(),
            "elements_per_cable": s.model.elements_per_cable,
            "eigen_evaluations": e.eigen_evaluations,
            "eigen_residual": json_f64(e.eigen_residual),
            "solver": "realtime",
            "compute_ns": ns as u64,
        });
        println!("{o}");
    } else {
        println!(
            "scene {}  model {} × {}  status {}",
            s.name,
            s.model.element.as_str(),
            s.model.elements_per_cable,
            e.status.as_str()
        );
        if let Some(err) = e.error {
            println!("  reason: {err}");
        }
        for (i, t) in e.tensions().iter().enumerate() {
            println!("  cable {i:>2}: {t:>11.4} N");
        }
        println!(
            "  f1            {:.9} Hz (end-effector participation {:.3e})",
            e.f1_hz, e.f1_ee_participation
        );
        println!(
            "  end-effector  {:.9} Hz (participation {:.4})",
            e.ee_mode_hz, e.ee_mode_participation
        );
        println!(
            "  {} evaluations of D(λ), {:.1} µs (first cycle, cold)",
            e.eigen_evaluations,
            ns as f64 / 1e3
        );
    }
    if e.status != Status::Ok {
        return Err(CliError::Analysis(format!(
            "status {}: {}",
            e.status.as_str(),
            e.error.map(|x| x.to_string()).unwrap_or_default()
        )));
    }
    Ok(())
}

/// Heap allocation counter supplied by the binary's global allocator (0 when none).
pub type AllocCounter = fn() -> u64;

/// `cablevib bench`.
pub fn bench(a: &BenchArgs, allocations: AllocCounter) -> Result<(), CliError> {
    let s = resolve_scene(&a.scene)?;
    if a.cycles == 0 || !(a.period_s.is_finite() && a.period_s > 0.0) {
        return Err(CliError::Usage(
            "--cycles must be > 0 and --period-s finite and > 0".into(),
        ));
    }
    let mut p = EstimatorParams::default();
    p.modal.ee_participation_min = s.model.ee_participation_min;
    p.ee_mode = !a.no_ee_mode;
    let mut est = Estimator::with_params(&s, p).map_err(|e| CliError::Analysis(e.to_string()))?;
    // Warm-up cycle (cold start), then timed cycles.
    est.update(&circle_pose(&s, 0, a.period_s), s.t_min_n);
    let mut ns = Vec::with_capacity(a.cycles);
    let mut evals = Vec::with_capacity(a.cycles);
    let mut statuses = StatusHistogram::default();
    let mut f1_min = (f64::INFINITY, 0usize);
    let mut f1_max = (f64::NEG_INFINITY, 0usize);
    let alloc0 = allocations();
    for k in 1..=a.cycles {
        let pose = circle_pose(&s, k, a.period_s);
        let t0 = Instant::now();
        let e = est.update(&pose, s.t_min_n);
        let dt = t0.elapsed().as_nanos() as u64;
        ns.push(dt);
        evals.push(e.eigen_evaluations);
        statuses.record(e.status);
        if e.is_ok() {
            if e.f1_hz < f1_min.0 {
                f1_min = (e.f1_hz, k);
            }
            if e.f1_hz > f1_max.0 {
                f1_max = (e.f1_hz, k);
            }
        }
    }
    let allocs = allocations() - alloc0;
    ns.sort_unstable();
    evals.sort_unstable();
    let q = |x: f64| percentile(&ns, x);
    // Dense reference on a sample of poses, timed in the same run.
    let mut dense_ns = Vec::new();
    let mut max_rel_err_f1 = 0.0f64;
    let mut max_rel_err_ee = 0.0f64;
    let mut rt_on_samples = Vec::new();
    if s.model.element.is_discrete() {
        for j in 0..a.dense_samples {
            let k = 1 + j * (a.cycles / a.dense_samples.max(1)).max(1);
            let pose = circle_pose(&s, k, a.period_s);
            let t0 = Instant::now();
            let r = reference_analysis(&s, &pose.position_m, s.t_min_n, true);
            let dt = t0.elapsed().as_nanos() as u64;
            let Ok(r) = r else { continue };
            dense_ns.push(dt);
            let mut cold =
                Estimator::with_params(&s, p).map_err(|e| CliError::Analysis(e.to_string()))?;
            let t1 = Instant::now();
            let e = *cold.update(&pose, s.t_min_n);
            rt_on_samples.push(t1.elapsed().as_nanos() as u64);
            if e.is_ok() {
                max_rel_err_f1 =
                    max_rel_err_f1.max((e.f1_hz - lambda_to_hz(r.modes.lambda[0])).abs() / e.f1_hz);
                if let Some((_, l)) = r.modes.first_ee_mode(p.modal.ee_participation_min) {
                    if e.ee_mode_hz.is_finite() {
                        max_rel_err_ee = max_rel_err_ee
                            .max((e.ee_mode_hz - lambda_to_hz(l)).abs() / e.ee_mode_hz);
                    }
                }
            }
        }
    }
    dense_ns.sort_unstable();
    let dense_median = percentile(&dense_ns, 0.5);
    let p50 = q(0.5);
    let ratio = if p50 > 0 {
        dense_median as f64 / p50 as f64
    } else {
        f64::NAN
    };
    let per_cycle_allocs = allocs as f64 / a.cycles as f64;
    let names: Vec<(String, usize)> = statuses
        .nonzero()
        .map(|(code, c)| (cablevib_ipc::status_str(code).to_string(), c as usize))
        .collect();
    if a.json {
        let o = serde_json::json!({
            "scene": s.name,
            "element": s.model.element.as_str(),
            "elements_per_cable": s.model.elements_per_cable,
            "ee_mode": p.ee_mode,
            "cycles": a.cycles,
            "p50_ns": p50, "p90_ns": q(0.9), "p99_ns": q(0.99), "p999_ns": q(0.999), "max_ns": q(1.0),
            "eigen_evaluations_p50": percentile(&evals.iter().map(|&x| x as u64).collect::<Vec<_>>(), 0.5),
            "eigen_evaluations_max": evals.last().copied().unwrap_or(0),
            "allocations_per_cycle": per_cycle_allocs,
            "allocations_total": allocs,
            "dense_samples": dense_ns.len(),
            "dense_median_ns": dense_median,
            "dense_to_realtime_p50_ratio": json_f64(ratio),
            "max_rel_err_f1": max_rel_err_f1,
            "max_rel_err_ee_mode": max_rel_err_ee,
            "f1_min_hz": json_f64(f1_min.0), "f1_max_hz": json_f64(f1_max.0),
            "statuses": names.iter().map(|(n, c)| serde_json::json!({"status": n, "count": c})).collect::<Vec<_>>(),
        });
        println!("{o}");
    } else {
        println!(
            "scene {}  model {} × {}  {} cycles along the r = 0.75 m circle ({} s per revolution, 1 ms spacing){}",
            s.name,
            s.model.element.as_str(),
            s.model.elements_per_cable,
            a.cycles,
            a.period_s,
            if p.ee_mode { "" } else { ", f1 only" }
        );
        println!(
            "  per-cycle compute: p50 {} ns  p90 {} ns  p99 {} ns  p99.9 {} ns  max {} ns",
            p50,
            q(0.9),
            q(0.99),
            q(0.999),
            q(1.0)
        );
        let ev: Vec<u64> = evals.iter().map(|&x| x as u64).collect();
        println!(
            "  D(λ) evaluations per cycle: p50 {}  p90 {}  p99 {}  max {}",
            percentile(&ev, 0.5),
            percentile(&ev, 0.9),
            percentile(&ev, 0.99),
            percentile(&ev, 1.0)
        );
        println!(
            "  heap allocations: {allocs} in {} cycles ({per_cycle_allocs} per cycle)",
            a.cycles
        );
        println!("  statuses: {names:?}");
        let rc = est.rescan_counts();
        println!(
            "  end-effector mode bookkeeping: full scans cold {} uncertified {} none {}; lost {} dropped {}; partner searches {} neighbour searches {}",
            rc.cold_scans,
            rc.uncertified_scans,
            rc.no_mode_scans,
            rc.lost,
            rc.dropped,
            rc.partner_searches,
            rc.neighbour_searches
        );
        if f1_min.0.is_finite() {
            println!(
                "  f1 along the circle: min {:.6} Hz (cycle {}), max {:.6} Hz (cycle {})",
                f1_min.0, f1_min.1, f1_max.0, f1_max.1
            );
        }
        if !dense_ns.is_empty() {
            println!(
                "  dense reference on {} poses: median {:.3} ms  → {:.0}× the real-time p50; max |Δf1|/f1 {:.2e}, max |Δf_ee|/f_ee {:.2e}",
                dense_ns.len(),
                dense_median as f64 / 1e6,
                ratio,
                max_rel_err_f1,
                max_rel_err_ee
            );
        }
    }
    Ok(())
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

/// `cablevib serve`: loads the scene and runs the service until SIGINT/SIGTERM.
pub fn serve(a: &ServeArgs, allocations: AllocCounter) -> Result<(), CliError> {
    if !(a.stats_period_s.is_finite() && a.stats_period_s >= 0.0) {
        return Err(CliError::Usage(format!(
            "--stats-period-s {} must be finite and ≥ 0",
            a.stats_period_s
        )));
    }
    let scene = load_scene(&a.scene)?;
    let cfg = ServerConfig {
        instance: a.instance.clone(),
        wait: a.wait,
        stats_period: (a.stats_period_s > 0.0)
            .then(|| std::time::Duration::from_secs_f64(a.stats_period_s)),
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
    let scene = load_scene(&a.scene)?;
    let t_min_schedule = match &a.t_min_schedule {
        Some(s) => Some(TminSchedule::parse(s)?),
        None => None,
    };
    let cfg = DemoConfig {
        seconds: a.seconds,
        required_hz: a.required_hz,
        wait: a.wait,
        controller_wait: a.controller_wait,
        rate_hz: a.rate_hz,
        period_s: a.period_s,
        t_min_schedule,
    };
    Ok(crate::service::demo(&scene, &cfg)?)
}

/// `cablevib bench-ipc`: pose-published → estimate-received latency.
pub fn bench_ipc(a: &BenchIpcArgs) -> Result<(), CliError> {
    let scene = load_scene(&a.scene)?;
    let cfg = BenchIpcConfig {
        samples: a.samples,
        wait: a.wait,
        gap_us: a.gap_us,
        cpu: a.cpu,
        json: a.json,
    };
    Ok(crate::service::bench_ipc(&scene, &cfg)?)
}
