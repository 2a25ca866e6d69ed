//! `cablevib bench-ipc`: latency from a pose being published to its estimate being received,
//! through real iceoryx2 services, in spin and in event mode.
//!
//! The service runs in its own thread with its own node (as in a separate process: iceoryx2
//! goes through shared memory either way); the client publishes a pose of the paper's circle
//! (1 ms apart along the trajectory, so the estimator's warm start behaves as in operation),
//! waits for the estimate echoing its sequence, and records:
//!
//! - end-to-end: pose timestamp → estimate received (what a controller sees);
//! - compute: the estimator's time, as the service measured it;
//! - IPC overhead: end-to-end − compute;
//! - pose → pickup: pose timestamp → the service took the pose;
//! - estimate publish → received.
//!
//! Ping-pong (one pose in flight), after 1000 warm-up samples.
//!
//! With the vibration input on ([`crate::BenchVibration::On`]) the client also publishes
//! one accelerometer sample before each pose (a 29.4 Hz sine and noise, stamped as a 1 kHz
//! sensor: the service's tracker then does the work of a 1 kHz sensor beside 1 kHz poses),
//! after a warm-up long enough to fill the tracker's window. With
//! [`crate::BenchVibration::Both`] the two alternate in blocks of [`BLOCK`] poses
//! in the same service, so that both see the same machine load; the first [`BLOCK_SETTLE`]
//! poses of a block are not timed (the tracker finishes the evaluation left from an `on`
//! block, after which it has nothing to do until samples come again).

use cablevib::outln;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use cablevib_ipc::{
    monotonic_now_ns, PoseSample, ServiceNames, VibrationSample, IDENTITY_QUATERNION,
};

use super::ports::{
    create_node, open_pubsub, wait_for_service, EstimateOutput, PoseInput, VIBRATION_SETTINGS,
};
use super::rt;
use super::server::{self, ServerConfig};
use super::stats::{Percentiles, SampleLog};
use super::{init_tracing, BenchIpcConfig, BenchVibration, ServiceError, ServiceParam, WaitMode};
use crate::scene::Scene;
use crate::trajectory::{Trajectory, CIRCLE_PERIOD_S, SAMPLE_PERIOD_S};
use cablevib::study::ParamError;

const WARM_UP: usize = 1000;
/// Warm-up with the vibration input: its 2 s window of 1 kHz samples filled, then evaluated.
const WARM_UP_VIBRATION: usize = 3000;
/// Poses per block when the runs with and without the vibration input alternate.
pub const BLOCK: usize = 2000;
/// Poses at the start of a block that are not timed.
pub const BLOCK_SETTLE: usize = 200;
/// The accelerometer's sample period, ns (1 kHz).
const VIBRATION_PERIOD_NS: u64 = 1_000_000;
const ANSWER_TIMEOUT: Duration = Duration::from_secs(1);

/// Results of one wait mode.
#[derive(Debug, Clone)]
pub struct BenchResult {
    /// The wait mode of service and client.
    pub mode: WaitMode,
    /// Whether an accelerometer sample came before each pose.
    pub vibration: bool,
    /// Pose timestamp → estimate received.
    pub end_to_end: Percentiles,
    /// Estimator compute time.
    pub compute: Percentiles,
    /// End-to-end − compute, per sample.
    pub overhead: Percentiles,
    /// Pose timestamp → service took the pose.
    pub pickup: Percentiles,
    /// Estimate publish timestamp → received.
    pub delivery: Percentiles,
    /// Poses without an answer within 1 s.
    pub timeouts: u64,
    /// Wall time of the timed samples, s.
    pub seconds: f64,
}

/// Runs the benchmark and prints the results.
pub fn run(scene: &Scene, a: &BenchIpcConfig) -> Result<(), ServiceError> {
    init_tracing("warn");
    if a.samples == 0 {
        return Err(ParamError::invalid(ServiceParam::Samples, 0, "must be > 0").into());
    }
    let modes = match a.wait {
        Some(m) => vec![m],
        None => vec![WaitMode::Spin, WaitMode::Event],
    };
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut results = Vec::new();
    for mode in modes {
        if !a.json {
            eprintln!("measuring {} mode: {} samples ...", mode, a.samples);
        }
        results.extend(bench_mode(scene, mode, a)?);
    }
    if a.json {
        let q = |p: &Percentiles| serde_json::json!({"p50_ns": p.p50_ns, "p99_ns": p.p99_ns, "p999_ns": p.p999_ns, "max_ns": p.max_ns, "count": p.count});
        let o = serde_json::json!({
            "scene": scene.name,
            "samples": a.samples,
            "gap_us": a.gap_us,
            "cpus": cpus,
            "modes": results.iter().map(|r| serde_json::json!({
                "wait": r.mode.as_str(),
                "vibration": r.vibration,
                "end_to_end": q(&r.end_to_end),
                "compute": q(&r.compute),
                "ipc_overhead": q(&r.overhead),
                "pose_to_pickup": q(&r.pickup),
                "publish_to_received": q(&r.delivery),
                "timeouts": r.timeouts,
                "seconds": r.seconds,
            })).collect::<Vec<_>>(),
        });
        outln!("{o}")?;
        return Ok(());
    }
    outln!(
        "cablevib bench-ipc: pose published → estimate received over iceoryx2, scene `{}`, {} \
         samples per mode (ping-pong{}), {} CPUs",
        scene.name,
        a.samples,
        if a.gap_us > 0 {
            format!(", {} µs gap", a.gap_us)
        } else {
            String::new()
        },
        cpus
    )?;
    outln!(
        "  {:<6} {:<9} {:<38} {:>9} {:>9} {:>9} {:>9}",
        "wait",
        "vibration",
        "µs",
        "p50",
        "p99",
        "p99.9",
        "max"
    )?;
    for r in &results {
        for (name, p) in [
            ("end-to-end", &r.end_to_end),
            ("  estimator compute", &r.compute),
            ("  IPC overhead (end-to-end − compute)", &r.overhead),
            ("  pose → taken by the service", &r.pickup),
            ("  estimate publish → received", &r.delivery),
        ] {
            outln!(
                "  {:<6} {:<9} {:<38} {:>9.1} {:>9.1} {:>9.1} {:>9.1}",
                r.mode.as_str(),
                if r.vibration { "on" } else { "off" },
                name,
                p.p50_ns as f64 / 1e3,
                p.p99_ns as f64 / 1e3,
                p.p999_ns as f64 / 1e3,
                p.max_ns as f64 / 1e3
            )?;
        }
        outln!(
            "  {:<6} {:<9} {} samples in {:.2} s, {} unanswered",
            r.mode.as_str(),
            if r.vibration { "on" } else { "off" },
            r.end_to_end.count,
            r.seconds,
            r.timeouts
        )?;
    }
    Ok(())
}

/// Measures one wait mode: a service thread, the client in the calling thread. One result per
/// vibration setting (without first).
pub fn bench_mode(
    scene: &crate::scene::Scene,
    mode: WaitMode,
    a: &BenchIpcConfig,
) -> Result<Vec<BenchResult>, ServiceError> {
    let instance = format!("cablevib_bench_{}_{}", std::process::id(), mode.as_str());
    let names = ServiceNames::new(&instance);
    let stop = Arc::new(AtomicBool::new(false));
    let server_thread = {
        let scene = scene.clone();
        let stop = stop.clone();
        let cfg = ServerConfig {
            instance,
            wait: mode,
            stats_period: None,
            cpu: a.cpu,
            node_name: "cablevib-bench-serve".into(),
            alloc_pool: a.alloc_pool,
            ..ServerConfig::default()
        };
        server::spawn_thread(scene, cfg, stop)?
    };
    let result = client(scene, mode, a, &names, &stop);
    stop.store(true, Ordering::Release);
    let served = server_thread
        .join()
        .map_err(|_| ServiceError::ThreadPanicked("service"))?;
    served?;
    result
}

/// The timed samples of one vibration setting.
struct Logs {
    vibration: bool,
    /// End-to-end, compute, overhead, pickup, delivery.
    logs: [SampleLog; 5],
    timeouts: u64,
    seconds: f64,
}

impl Logs {
    fn result(&self, mode: WaitMode) -> BenchResult {
        BenchResult {
            mode,
            vibration: self.vibration,
            end_to_end: self.logs[0].percentiles(),
            compute: self.logs[1].percentiles(),
            overhead: self.logs[2].percentiles(),
            pickup: self.logs[3].percentiles(),
            delivery: self.logs[4].percentiles(),
            timeouts: self.timeouts,
            seconds: self.seconds,
        }
    }
}

fn client(
    scene: &crate::scene::Scene,
    mode: WaitMode,
    a: &BenchIpcConfig,
    names: &ServiceNames,
    stop: &AtomicBool,
) -> Result<Vec<BenchResult>, ServiceError> {
    if let Some(cpu) = a.cpu {
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        if let Err(e) = rt::pin_to_cpu((cpu + 1) % cpus) {
            tracing::warn!("client not pinned: {e}");
        }
    }
    let node = create_node("cablevib-bench-client")?;
    let input = PoseInput::open(&node, names)?;
    let output = EstimateOutput::open(&node, names)?;
    let settings: &[bool] = match a.vibration {
        BenchVibration::Off => &[false],
        BenchVibration::On => &[true],
        BenchVibration::Both => &[false, true],
    };
    let sensor = if settings.contains(&true) {
        Some(
            open_pubsub::<VibrationSample>(&node, &names.vibration, VIBRATION_SETTINGS)?
                .publisher_builder()
                .create()
                .map_err(|e| ServiceError::Ipc {
                    context: "create the vibration publisher".into(),
                    reason: format!("{e:?}"),
                })?,
        )
    } else {
        None
    };
    wait_for_service(
        || input.service_connected() && output.service_connected(),
        stop,
        || ServiceError::Timeout("stopped before the service came up".into()),
    )?;
    let trajectory = Trajectory::circle(scene, CIRCLE_PERIOD_S)?;
    let n = a.samples;
    let mut runs: Vec<Logs> = settings
        .iter()
        .map(|&vibration| Logs {
            vibration,
            logs: core::array::from_fn(|_| SampleLog::with_capacity(n)),
            timeouts: 0,
            seconds: 0.0,
        })
        .collect();
    let warm_up = if sensor.is_some() {
        WARM_UP_VIBRATION
    } else {
        WARM_UP
    };
    let mut rng = crate::rng::SplitMix64(1);
    let t0_ns = monotonic_now_ns();
    let mut vibration_sequence = 0u64;
    let mut block_start = Instant::now();
    let mut k = 0usize;
    loop {
        // Warm-up with the input on when it is measured at all; then blocks of BLOCK poses,
        // the settings in turn (a single setting: one block as long as needed).
        let (run, timed) = if k < warm_up {
            (settings.len() - 1, false)
        } else {
            let i = k - warm_up;
            let in_block = if settings.len() > 1 {
                i % BLOCK
            } else {
                i + BLOCK_SETTLE
            };
            ((i / BLOCK) % settings.len(), in_block >= BLOCK_SETTLE)
        };
        if timed && runs[run].logs[0].len() + runs[run].timeouts as usize >= n {
            if runs
                .iter()
                .all(|r| r.logs[0].len() + r.timeouts as usize >= n)
            {
                break;
            }
            k += 1;
            continue;
        }
        if stop.load(Ordering::Acquire) {
            break;
        }
        if timed && (k == warm_up || (k - warm_up) % BLOCK == BLOCK_SETTLE) {
            block_start = Instant::now();
        }
        if let (Some(sensor), true) = (&sensor, runs[run].vibration) {
            vibration_sequence += 1;
            let t_s = vibration_sequence as f64 * VIBRATION_PERIOD_NS as f64 * 1e-9;
            let x = (2.0 * core::f64::consts::PI * 29.4 * t_s).sin() + 0.02 * rng.normal();
            sensor
                .send_copy(VibrationSample::acceleration(
                    vibration_sequence,
                    t0_ns + vibration_sequence * VIBRATION_PERIOD_NS,
                    [x, 0.02 * rng.normal(), 9.81 + 0.02 * rng.normal()],
                ))
                .map_err(|e| ServiceError::Ipc {
                    context: "send a vibration sample".into(),
                    reason: format!("{e:?}"),
                })?;
        }
        let p = trajectory
            .position_at(k as f64 * SAMPLE_PERIOD_S)
            .unwrap_or(scene.ee_position_m);
        let sequence = k as u64 + 1;
        k += 1;
        let pose = PoseSample::new(
            sequence,
            monotonic_now_ns(),
            [p.x, p.y, p.z],
            IDENTITY_QUATERNION,
        );
        input.send_pose(&pose)?;
        let answer = loop {
            match output.wait(mode, ANSWER_TIMEOUT)? {
                Some(e) if e.pose_sequence == sequence => break Some(e),
                Some(_) => continue, // an answer to an earlier (timed-out) pose
                None => break None,
            }
        };
        let received_ns = monotonic_now_ns();
        let r = &mut runs[run];
        match answer {
            None if timed => r.timeouts += 1,
            Some(e) if timed => {
                let e2e = received_ns.saturating_sub(pose.timestamp_ns);
                r.logs[0].push(e2e);
                r.logs[1].push(e.compute_ns);
                r.logs[2].push(e2e.saturating_sub(e.compute_ns));
                r.logs[3].push(e.receive_timestamp_ns.saturating_sub(pose.timestamp_ns));
                r.logs[4].push(received_ns.saturating_sub(e.publish_timestamp_ns));
            }
            _ => {}
        }
        if a.gap_us > 0 {
            let until = Instant::now() + Duration::from_micros(a.gap_us);
            while Instant::now() < until {
                core::hint::spin_loop();
            }
        }
        let block_end = settings.len() > 1 && (k - warm_up.min(k)).is_multiple_of(BLOCK);
        if timed && (block_end || r.logs[0].len() + r.timeouts as usize >= n) {
            r.seconds += block_start.elapsed().as_secs_f64();
            block_start = Instant::now();
        }
    }
    Ok(runs.iter().map(|r| r.result(mode)).collect())
}
