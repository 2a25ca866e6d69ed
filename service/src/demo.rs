//! `cablevib demo`: the service, a replay publisher and a controller, each with its own
//! iceoryx2 node and thread in one process, talking over real shared-memory services.
//!
//! The replay (main thread) publishes the paper's circle at `rate_hz`; the service thread
//! estimates every pose; the controller thread takes every estimate, measures the latency from
//! the pose's timestamp to its arrival, and asks the service for its margin against
//! `required_hz` after each one. A line of progress per second, then a summary.
//! With `hold_f1_hz` the controller also holds f1 with T_min set-points (`demo_hold.rs`)
//! and the summary adds the hold's lines.

use cablevib::outln;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use cablevib_ipc::{
    monotonic_now_ns, MarginRequest, PoseSample, ServiceNames, StatusCode, TminSetpoint,
    IDENTITY_QUATERNION,
};

use super::ports::{create_node, wait_for_service, EstimateOutput, MarginClient, PoseInput};
use super::server::{self, ServerConfig, ServerReport};
use super::stats::{Percentiles, SampleLog};
use super::TminSchedule;
use super::{init_tracing, DemoConfig, ServiceError, ServiceParam, WaitMode};
use crate::scene::Scene;
use cablevib::study::ParamError;

/// Longest demo, s (its logs are preallocated for the whole run).
const MAX_SECONDS: f64 = 3600.0;
/// Highest pose rate, Hz: above it the replay thread cannot keep its schedule.
const MAX_RATE_HZ: f64 = 20_000.0;
/// How long the controller waits for an estimate before it checks `stop` again.
const ESTIMATE_WAIT: Duration = Duration::from_millis(20);
/// A margin query unanswered this long counts as a timeout (five 1 kHz cycles).
const MARGIN_TIMEOUT: Duration = Duration::from_millis(5);
/// Time the last estimates get to arrive after the replay ends.
const DRAIN_TIME: Duration = Duration::from_millis(100);
/// Extra log capacity beyond one entry per pose (estimates of start-up and drain).
const LOG_SLACK: usize = 1000;
/// The replay refreshes its iceoryx2 connections every this many poses (a restarted
/// service is found again within 64 ms at 1 kHz).
const CONNECTION_UPDATE_EVERY: usize = 64;
use crate::trajectory::Trajectory;

/// What the controller saw of one estimate.
#[derive(Debug, Clone, Copy)]
struct Seen {
    pose_sequence: u64,
    status: u32,
    f1_hz: f64,
    ee_mode_hz: f64,
    measured_f1_hz: f64,
    measured_ee_mode_hz: f64,
    measured_status: [u32; 2],
    measured_age_ns: u64,
}

/// Everything the controller thread recorded.
#[derive(Debug)]
struct ControllerLog {
    seen: Vec<Seen>,
    latency: SampleLog,
    margin_rtt: SampleLog,
    /// (pose sequence, margin Hz, status) of each margin answer.
    margins: Vec<(u64, f64, u32)>,
    margin_timeouts: u64,
    /// What the hold (`hold_f1_hz`) recorded.
    hold: Option<super::demo_hold::HoldLog>,
}

/// Shared progress counters (read once per second by the main thread).
#[derive(Debug, Default)]
struct Progress {
    estimates: AtomicU64,
    last_f1_bits: AtomicU64,
    last_margin_bits: AtomicU64,
    max_latency_ns: AtomicU64,
    not_ok: AtomicU64,
    /// The end-effector mode frequency of the latest ok estimate that had one (f64 bits; 0.0,
    /// none yet), for the shaper (`shape`).
    last_ee_mode_bits: AtomicU64,
}

#[allow(clippy::too_many_arguments)]
fn controller(
    names: ServiceNames,
    wait: WaitMode,
    required_hz: f64,
    hold: Option<super::hold::HoldParams>,
    capacity: usize,
    stop: Arc<AtomicBool>,
    ready: Arc<AtomicBool>,
    progress: Arc<Progress>,
) -> Result<ControllerLog, ServiceError> {
    let node = create_node("cablevib-demo-controller")?;
    let estimates = EstimateOutput::open(&node, &names)?;
    let margin = MarginClient::open(&node, &names)?;
    let mut hold = hold
        .map(|p| super::demo_hold::DemoHold::open(&node, &names, p, capacity))
        .transpose()?;
    // With a hold the margin is asked against the hold's requirement (+ guard).
    let required_hz = hold.as_ref().map_or(required_hz, |h| h.request_hz());
    ready.store(true, Ordering::Release);
    let mut log = ControllerLog {
        seen: Vec::with_capacity(capacity),
        latency: SampleLog::with_capacity(capacity),
        margin_rtt: SampleLog::with_capacity(capacity),
        margins: Vec::with_capacity(capacity),
        margin_timeouts: 0,
        hold: None,
    };
    let mut request_sequence = 0;
    while !stop.load(Ordering::Acquire) {
        let Some(e) = estimates.wait(wait, ESTIMATE_WAIT)? else {
            continue;
        };
        let latency = monotonic_now_ns().saturating_sub(e.pose_timestamp_ns);
        log.latency.push(latency);
        if log.seen.len() < capacity {
            log.seen.push(Seen {
                pose_sequence: e.pose_sequence,
                status: e.status,
                f1_hz: e.f1_hz,
                ee_mode_hz: e.ee_mode_hz,
                measured_f1_hz: e.measured_f1_hz,
                measured_ee_mode_hz: e.measured_ee_mode_hz,
                measured_status: [e.measured_f1_status, e.measured_ee_mode_status],
                measured_age_ns: e.measured_age_ns,
            });
        }
        if let Some(h) = &mut hold {
            h.on_estimate(&e);
        }
        request_sequence += 1;
        let t0 = monotonic_now_ns();
        let request = MarginRequest::new(request_sequence, t0, required_hz);
        match margin.query(&request, wait, MARGIN_TIMEOUT)? {
            Some(r) => {
                log.margin_rtt.push(monotonic_now_ns().saturating_sub(t0));
                if log.margins.len() < capacity {
                    log.margins.push((r.pose_sequence, r.margin_hz, r.status));
                }
                if let Some(h) = &mut hold {
                    h.on_answer(&r)?;
                }
                progress
                    .last_margin_bits
                    .store(r.margin_hz.to_bits(), Ordering::Relaxed);
            }
            None => log.margin_timeouts += 1,
        }
        progress.estimates.fetch_add(1, Ordering::Relaxed);
        progress
            .last_f1_bits
            .store(e.f1_hz.to_bits(), Ordering::Relaxed);
        progress
            .max_latency_ns
            .fetch_max(latency, Ordering::Relaxed);
        if !e.is_ok() {
            progress.not_ok.fetch_add(1, Ordering::Relaxed);
        } else if e.ee_mode_hz.is_finite() && e.ee_mode_hz > 0.0 {
            progress
                .last_ee_mode_bits
                .store(e.ee_mode_hz.to_bits(), Ordering::Relaxed);
        }
    }
    log.hold = hold.map(super::demo_hold::DemoHold::finish);
    Ok(log)
}

fn validate(a: &DemoConfig) -> Result<(), ServiceError> {
    let bad = |p: ServiceParam, v: f64, rule: String| {
        Err(ParamError::invalid(p, format!("{v:?}"), rule).into())
    };
    if !(a.seconds.is_finite() && a.seconds > 0.0 && a.seconds <= MAX_SECONDS) {
        let rule = format!("must be in (0, {MAX_SECONDS}] s");
        return bad(ServiceParam::Seconds, a.seconds, rule);
    }
    if !(a.rate_hz.is_finite() && a.rate_hz >= 1.0 && a.rate_hz <= MAX_RATE_HZ) {
        let rule = format!("must be in [1, {MAX_RATE_HZ}] Hz");
        return bad(ServiceParam::RateHz, a.rate_hz, rule);
    }
    if a.hold_f1_hz.is_some() && a.t_min_schedule.is_some() {
        let both = vec![ServiceParam::HoldF1Hz, ServiceParam::TMinSchedule];
        return Err(ParamError::OneOf(both).into());
    }
    if a.hold_csv.is_some() && a.hold_f1_hz.is_none() {
        return Err(ParamError::NotApplicable {
            param: ServiceParam::HoldCsv,
            reason: "records the hold of f1, which is not asked for".into(),
            instead: Some(ServiceParam::HoldF1Hz),
        }
        .into());
    }
    if !(a.required_hz.is_finite() && a.required_hz > 0.0) {
        let rule = "must be finite and > 0 Hz".into();
        return bad(ServiceParam::RequiredHz, a.required_hz, rule);
    }
    Ok(())
}

/// What the demo is about to run.
fn print_header(
    scene: &Scene,
    a: &DemoConfig,
    trajectory: &Trajectory,
    schedule: &TminSchedule,
) -> Result<(), ServiceError> {
    outln!(
        "cablevib demo: {:.1} s on scene `{}` ({} cables, {} × {} elements/cable); the service \
         waits by {}, the controller by {}",
        a.seconds,
        scene.name,
        scene.n_cables(),
        scene.model.element.as_str(),
        scene.model.elements_per_cable,
        a.wait,
        a.controller_wait
    )?;
    outln!(
        "  replay: {}, {} Hz; T_min {}",
        trajectory.describe(),
        a.rate_hz,
        if schedule.is_empty() {
            format!("{} N (the scene's)", scene.t_min_n)
        } else {
            schedule
                .steps()
                .iter()
                .map(|(t, v)| format!("{v} N from {t} s"))
                .collect::<Vec<_>>()
                .join(", ")
        }
    )?;
    Ok(())
}

/// The instance the demo's services run under: `cablevib_demo_{pid}` (a monitor started beside
/// the demo attaches to it).
pub fn instance_name() -> String {
    format!("cablevib_demo_{}", std::process::id())
}

/// Runs the demo and prints its summary.
pub fn run(scene: &Scene, a: &DemoConfig) -> Result<(), ServiceError> {
    validate(a)?;
    // The service's own log lines would interleave with the progress: warnings only.
    init_tracing("warn");
    let trajectory = Trajectory::circle(scene, a.period_s)?;
    let hold = match a.hold_f1_hz {
        Some(hz) => Some(super::demo_hold::params(scene, hz)?),
        None => None,
    };
    let schedule = a.t_min_schedule.clone().unwrap_or_default();
    let instance = instance_name();
    let names = ServiceNames::new(&instance);
    let n_poses = (a.seconds * a.rate_hz).round().max(1.0) as usize;
    let capacity = n_poses + LOG_SLACK;

    print_header(scene, a, &trajectory, &schedule)?;

    let stop = Arc::new(AtomicBool::new(false));
    let controller_ready = Arc::new(AtomicBool::new(false));
    let progress = Arc::new(Progress::default());

    let server_thread = {
        let scene = scene.clone();
        let stop = stop.clone();
        let cfg = ServerConfig {
            instance: instance.clone(),
            wait: a.wait,
            stats_period: None,
            node_name: "cablevib-demo-serve".into(),
            ..ServerConfig::default()
        };
        server::spawn_thread(scene, cfg, stop)?
    };
    let controller_thread = {
        let (names, stop, ready, progress) = (
            names.clone(),
            stop.clone(),
            controller_ready.clone(),
            progress.clone(),
        );
        let (wait, required) = (a.controller_wait, a.required_hz);
        std::thread::Builder::new()
            .name("cablevib-controller".into())
            .spawn(move || {
                let r = controller(
                    names,
                    wait,
                    required,
                    hold,
                    capacity,
                    stop.clone(),
                    ready,
                    progress,
                );
                if r.is_err() {
                    stop.store(true, Ordering::Release);
                }
                r
            })
            .map_err(|e| ServiceError::Thread {
                what: "controller",
                reason: e.to_string(),
            })?
    };

    let mut shape = a
        .shape
        .map(|kind| super::demo_shape::DemoShape::new(kind, a.rate_hz, scene))
        .transpose()?;
    // The synthetic accelerometer starts with the replay, on the same circle.
    let accelerometer =
        if a.accelerometer && a.seconds <= super::demo_accel::MAX_SECONDS {
            let (samples, zeta) = super::demo_accel::record(scene, &trajectory, a.seconds)?;
            outln!(
            "  accelerometer (synthetic): {} samples at 1 kHz, simulated vibration of the circle \
             ({}), white force {} N, sensor noise {} m/s²",
            samples.len(),
            zeta.map_or("the scene's damping".to_owned(), |z| format!("ζ = {z} in every mode")),
            super::demo_accel::FORCE_NOISE_N,
            super::demo_accel::SENSOR_NOISE_M_S2
        )?;
            Some(super::demo_accel::spawn(&names, samples, stop.clone())?)
        } else {
            if a.accelerometer {
                outln!(
                    "  accelerometer (synthetic): off, the demo is longer than its {} s",
                    super::demo_accel::MAX_SECONDS
                )?;
            }
            None
        };
    let replay = replay(
        a,
        &names,
        &trajectory,
        &schedule,
        n_poses,
        &stop,
        &controller_ready,
        &progress,
        shape.as_mut(),
    );
    // Let the last estimates arrive, then stop the others.
    std::thread::sleep(DRAIN_TIME);
    stop.store(true, Ordering::Release);
    let server_report = server_thread
        .join()
        .map_err(|_| ServiceError::ThreadPanicked("service"))?;
    let log = controller_thread
        .join()
        .map_err(|_| ServiceError::ThreadPanicked("controller"))?;
    let sent = replay?;
    if let Some(t) = accelerometer {
        t.join()
            .map_err(|_| ServiceError::ThreadPanicked("accelerometer"))??;
    }
    let server_report = server_report?;
    let log = log?;
    summary(a, &trajectory, sent, &server_report, &log)?;
    if let Some(s) = &shape {
        outln!("{}", s.summary_line())?;
    }
    if let Some(h) = &log.hold {
        super::demo_hold::summary(scene, a, &trajectory, h)?;
    }
    Ok(())
}

/// Publishes the trajectory from the calling thread; returns the number of poses sent.
#[allow(clippy::too_many_arguments)]
fn replay(
    a: &DemoConfig,
    names: &ServiceNames,
    trajectory: &Trajectory,
    schedule: &TminSchedule,
    n_poses: usize,
    stop: &AtomicBool,
    controller_ready: &AtomicBool,
    progress: &Progress,
    mut shape: Option<&mut super::demo_shape::DemoShape>,
) -> Result<u64, ServiceError> {
    let node = create_node("cablevib-demo-replay")?;
    let input = PoseInput::open(&node, names)?;
    wait_for_service(
        || input.service_connected() && controller_ready.load(Ordering::Acquire),
        stop,
        || ServiceError::DemoNotStarted,
    )?;
    let start = Instant::now();
    let mut step = None;
    let mut sent = 0u64;
    let mut next_progress = 1.0;
    let mut last_estimates = 0;
    for k in 0..n_poses {
        if stop.load(Ordering::Acquire) {
            break;
        }
        let t_s = k as f64 / a.rate_hz;
        let due = start + Duration::from_secs_f64(t_s);
        let now = Instant::now();
        if due > now {
            std::thread::sleep(due - now);
        }
        let current = schedule.step_at(t_s);
        if current != step {
            if let Some(i) = current {
                let (_, v) = schedule.steps()[i];
                input.send_t_min(&TminSetpoint::uniform(i as u64 + 1, monotonic_now_ns(), v))?;
            }
            step = current;
        }
        let Some(mut p) = trajectory.position_at(t_s) else {
            break;
        };
        if let Some(s) = shape.as_deref_mut() {
            let ee_hz = f64::from_bits(progress.last_ee_mode_bits.load(Ordering::Relaxed));
            p = s.push(p, ee_hz);
        }
        // A CSV's quaternion columns, else the identity.
        let q = trajectory
            .orientation_at(t_s)
            .unwrap_or(IDENTITY_QUATERNION);
        let pose = PoseSample::new(k as u64 + 1, monotonic_now_ns(), [p.x, p.y, p.z], q);
        input.send_pose(&pose)?;
        sent += 1;
        if t_s + 1.0 / a.rate_hz >= next_progress {
            let n = progress.estimates.load(Ordering::Relaxed);
            let f1 = f64::from_bits(progress.last_f1_bits.load(Ordering::Relaxed));
            let margin = f64::from_bits(progress.last_margin_bits.load(Ordering::Relaxed));
            let max_lat = progress.max_latency_ns.swap(0, Ordering::Relaxed);
            outln!(
                "  t = {:>4.1} s  poses {:>6}  estimates {:>6} (+{:>4})  f1 {:.4} Hz  margin \
                 {:+.4} Hz  worst latency this second {:.1} µs  not ok {}",
                next_progress,
                sent,
                n,
                n - last_estimates,
                f1,
                margin,
                max_lat as f64 / 1e3,
                progress.not_ok.load(Ordering::Relaxed)
            )?;
            last_estimates = n;
            next_progress += 1.0;
        }
        if k % CONNECTION_UPDATE_EVERY == 0 {
            input.update_connections();
        }
    }
    Ok(sent)
}

fn summary(
    a: &DemoConfig,
    trajectory: &Trajectory,
    sent: u64,
    service: &ServerReport,
    log: &ControllerLog,
) -> Result<(), ServiceError> {
    let where_ = |seq: u64| {
        let t = (seq.saturating_sub(1)) as f64 / a.rate_hz;
        match trajectory.position_at(t) {
            Some(p) => format!(
                "t = {t:.3} s, at ({:.3}, {:.3}, {:.3}) m",
                p.x + 0.0,
                p.y + 0.0,
                p.z + 0.0
            ),
            None => format!("t = {t:.3} s"),
        }
    };
    outln!("summary")?;
    outln!(
        "  service: {} poses published, {} estimated ({} skipped as stale, {} overwritten in \
         the queue before the service drained them), estimator compute {}",
        sent,
        service.cycles,
        service.skipped_poses,
        service.overwritten_poses,
        service.compute.display_us()
    )?;
    let ok: Vec<&Seen> = log
        .seen
        .iter()
        .filter(|s| s.status == StatusCode::Ok.as_u32())
        .collect();
    let min = ok.iter().min_by(|x, y| x.f1_hz.total_cmp(&y.f1_hz));
    let max = ok.iter().max_by(|x, y| x.f1_hz.total_cmp(&y.f1_hz));
    if let (Some(min), Some(max)) = (min, max) {
        outln!(
            "  first natural frequency f1 along the trajectory: min {:.4} Hz ({}), max {:.4} Hz \
             ({})",
            min.f1_hz,
            where_(min.pose_sequence),
            max.f1_hz,
            where_(max.pose_sequence)
        )?;
        let ee: Vec<f64> = ok
            .iter()
            .map(|s| s.ee_mode_hz)
            .filter(|x| x.is_finite())
            .collect();
        if !ee.is_empty() {
            let lo = ee.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = ee.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            outln!("  end-effector mode frequency: {lo:.4} … {hi:.4} Hz")?;
        }
        measured_summary(&ok)?;
    } else {
        outln!("  no valid estimate was received")?;
    }
    let answered: Vec<&(u64, f64, u32)> = log
        .margins
        .iter()
        .filter(|m| m.2 == StatusCode::Ok.as_u32())
        .collect();
    if let Some(worst) = answered.iter().min_by(|x, y| x.1.total_cmp(&y.1)) {
        let below = answered.iter().filter(|m| m.1 < 0.0).count();
        outln!(
            "  margin f1 − {:.2} Hz (required): worst {:+.4} Hz ({}); below the requirement in \
             {} of {} answers{}",
            log.hold.as_ref().map_or(a.required_hz, |h| h.request_hz()),
            worst.1,
            where_(worst.0),
            below,
            answered.len(),
            if log.margin_timeouts > 0 {
                format!(
                    ", {} queries unanswered within {} ms",
                    log.margin_timeouts,
                    MARGIN_TIMEOUT.as_millis()
                )
            } else {
                String::new()
            }
        )?;
    }
    outln!(
        "  estimates per status: {}",
        service.status_counts.summary()
    )?;
    let lat: Percentiles = log.latency.percentiles();
    outln!(
        "  latency pose published → estimate received by the controller ({} estimates): {}",
        lat.count,
        lat.display_us()
    )?;
    let rtt = log.margin_rtt.percentiles();
    outln!(
        "  margin query round trip ({} queries): {}",
        rtt.count,
        rtt.display_us()
    )?;
    Ok(())
}

/// The measured frequencies of the ok estimates: per track, how often measured, the range,
/// model − measured (median and largest magnitude), the median age, the other statuses.
fn measured_summary(ok: &[&Seen]) -> Result<(), ServiceError> {
    use cablevib_ipc::MeasuredStatus;
    for (i, what) in ["f1", "end-effector mode"].into_iter().enumerate() {
        let model = |s: &Seen| [s.f1_hz, s.ee_mode_hz][i];
        let measured = |s: &Seen| [s.measured_f1_hz, s.measured_ee_mode_hz][i];
        let mut res: Vec<f64> = ok
            .iter()
            .filter(|s| s.measured_status[i] == MeasuredStatus::Ok.as_u32())
            .map(|s| model(s) - measured(s))
            .filter(|r| r.is_finite())
            .collect();
        let mut counts = [0u64; 16];
        for s in ok.iter().filter(|s| s.measured_status[i] != 0) {
            counts[(s.measured_status[i] as usize).min(15)] += 1;
        }
        let others: Vec<String> = counts
            .iter()
            .enumerate()
            .filter(|(_, &c)| c > 0)
            .map(|(code, c)| {
                let name = MeasuredStatus::from_u32(code as u32).map_or("unknown", |m| m.as_str());
                format!("{name} {c}")
            })
            .collect();
        if res.is_empty() {
            outln!("  measured near {what}: none ({})", others.join(", "))?;
            continue;
        }
        let lo = ok
            .iter()
            .map(|s| measured(s))
            .filter(|x| x.is_finite())
            .fold(f64::INFINITY, f64::min);
        let hi = ok
            .iter()
            .map(|s| measured(s))
            .filter(|x| x.is_finite())
            .fold(f64::NEG_INFINITY, f64::max);
        res.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
        let median = res[res.len() / 2];
        let worst = res[res.len() - 1];
        let mut ages: Vec<u64> = ok
            .iter()
            .filter(|s| s.measured_status[i] == 0)
            .map(|s| s.measured_age_ns)
            .collect();
        ages.sort_unstable();
        outln!(
            "  measured near {what}: {} of {} estimates, {lo:.3} … {hi:.3} Hz; model − measured: \
             median |{:.3}| Hz, largest {:+.3} Hz; age median {:.2} s{}",
            res.len(),
            ok.len(),
            median.abs(),
            worst,
            ages[ages.len() / 2] as f64 * 1e-9,
            if others.is_empty() {
                String::new()
            } else {
                format!(" (otherwise {})", others.join(", "))
            }
        )?;
    }
    Ok(())
}
