//! `cablevib monitor` and `cablevib replay` end to end: a service (a thread of this test), the
//! `cablevib` binary as the monitor process, this test as the controller; the recording read
//! back with the official Python `mcap` reader and the live server with a Foxglove WebSocket
//! protocol client in Python (a venv under target/ with pinned versions).
//! Area binary of the command-line crate (see tests/README.md at the repository root).

mod completeness;
mod replay_bounds;
mod viewers;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use cablevib::scene::Scene;
use cablevib::trajectory::{Trajectory, CIRCLE_PERIOD_S};
use cablevib_ipc::{
    monotonic_now_ns, EstimateSample, PoseSample, ServiceNames, TminSetpoint, VibrationSample,
    IDENTITY_QUATERNION, MEASURED_AGE_UNKNOWN,
};
use cablevib_monitor::encode::EstimateRecord;
use cablevib_monitor::recording::{read_recording, Recorded};
use cablevib_monitor::replay::{replay, Pace, ReplayConfig};
use cablevib_service::ports::{
    create_node, open_pubsub, wait_for_service, EstimateOutput, PoseInput, VIBRATION_SETTINGS,
};
use cablevib_service::server::{self, ServerConfig, ServerReport};
use cablevib_service::{ServiceError, WaitMode};

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");

fn python() -> PathBuf {
    cablevib_testkit::pinned_venv::pinned_venv_python(
        "py-monitor-mcap1.6.0-ws17.4-pb7.36.2",
        &[
            ("mcap", "mcap", "1.6.0"),
            ("websockets", "websockets", "17.4"),
            ("google.protobuf", "protobuf", "7.36.2"),
            ("lz4", "lz4", "4.4.5"),
        ],
    )
}

fn script(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/monitor")
        .join(name)
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/tmp/monitor-tests");
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(format!("{}-{name}", std::process::id()));
    let _ = std::fs::remove_file(&p);
    p
}

type ServerThread = std::thread::JoinHandle<Result<ServerReport, ServiceError>>;

fn start_service(instance: &str, scene: &Scene) -> (Arc<AtomicBool>, ServerThread) {
    let stop = Arc::new(AtomicBool::new(false));
    let cfg = ServerConfig {
        instance: instance.into(),
        wait: WaitMode::Event,
        stats_period: None,
        node_name: "cablevib-test-serve".into(),
        handle_signals: false,
        ..ServerConfig::default()
    };
    let t = server::spawn_thread(scene.clone(), cfg, stop.clone()).unwrap();
    (stop, t)
}

fn stop_service((stop, t): (Arc<AtomicBool>, ServerThread)) -> ServerReport {
    stop.store(true, Ordering::Release);
    t.join().unwrap().unwrap()
}

/// The monitor process, once it printed its "attached" line (returned).
fn start_monitor(args: &[&str]) -> (Child, String, std::thread::JoinHandle<Vec<String>>) {
    let mut child = Command::new(BIN)
        .arg("monitor")
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    let stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut lines = Vec::new();
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if line.contains("attached") {
                let _ = tx.send(line.clone());
            }
            lines.push(line);
        }
        lines
    });
    let Ok(line) = rx.recv_timeout(Duration::from_secs(60)) else {
        let _ = child.kill();
        let out = child.wait_with_output().unwrap();
        panic!(
            "the monitor did not attach: {}",
            String::from_utf8_lossy(&out.stderr)
        )
    };
    (child, line, reader)
}

fn signal(child: &Child, sig: libc::c_int) {
    // SAFETY: kill(2) on the pid of a child this test spawned and has not reaped.
    unsafe {
        libc::kill(child.id() as libc::pid_t, sig);
    }
}

/// What the controller sent and received.
struct Run {
    poses: Vec<PoseSample>,
    estimates: Vec<EstimateSample>,
}

/// The controller: the circle at `rate_hz` for `seconds`, T_min `t_min_at` (time, N) once;
/// takes every estimate. An accelerometer sample (a 29.4 Hz sine, stamped as a sensor at
/// `rate_hz`) goes before each pose, so the estimates carry measured frequencies.
fn control(
    instance: &str,
    scene: &Scene,
    seconds: f64,
    rate_hz: f64,
    t_min_at: Option<(f64, f64)>,
) -> Run {
    let names = ServiceNames::new(instance);
    let node = create_node("cablevib-test-controller").unwrap();
    let input = PoseInput::open(&node, &names).unwrap();
    let output = EstimateOutput::open(&node, &names).unwrap();
    let never = AtomicBool::new(false);
    wait_for_service(
        || input.service_connected() && output.service_connected(),
        &never,
        || ServiceError::Timeout("stopped".into()),
    )
    .unwrap();
    let sensor = open_pubsub::<VibrationSample>(&node, &names.vibration, VIBRATION_SETTINGS)
        .unwrap()
        .publisher_builder()
        .create()
        .unwrap();
    let t0_ns = monotonic_now_ns();
    let mut rng = cablevib::rng::SplitMix64(7);
    let trajectory = Trajectory::circle(scene, CIRCLE_PERIOD_S).unwrap();
    let n = (seconds * rate_hz) as usize;
    let mut run = Run {
        poses: Vec::with_capacity(n),
        estimates: Vec::with_capacity(n),
    };
    let mut t_min_sent = false;
    let start = Instant::now();
    for k in 0..n {
        let t = k as f64 / rate_hz;
        let due = start + Duration::from_secs_f64(t);
        if let Some(d) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(d);
        }
        if let Some((at, v)) = t_min_at {
            if !t_min_sent && t >= at {
                input
                    .send_t_min(&TminSetpoint::uniform(1, monotonic_now_ns(), v))
                    .unwrap();
                t_min_sent = true;
            }
        }
        let a = (2.0 * std::f64::consts::PI * 29.4 * t).sin();
        let mut noise = || 0.02 * rng.normal();
        sensor
            .send_copy(VibrationSample::acceleration(
                k as u64 + 1,
                t0_ns + (t * 1e9) as u64,
                [a + noise(), noise(), 9.81 + noise()],
            ))
            .unwrap();
        let p = trajectory.position_at(t).unwrap();
        let pose = PoseSample::new(
            k as u64 + 1,
            monotonic_now_ns(),
            [p.x, p.y, p.z],
            IDENTITY_QUATERNION,
        );
        input.send_pose(&pose).unwrap();
        run.poses.push(pose);
        while let Some(e) = output.try_receive().unwrap() {
            run.estimates.push(e);
        }
        if k % 64 == 0 {
            input.update_connections();
        }
    }
    let end = Instant::now() + Duration::from_millis(300);
    while Instant::now() < end {
        if let Some(e) = output
            .wait(WaitMode::Event, Duration::from_millis(20))
            .unwrap()
        {
            run.estimates.push(e);
        }
    }
    run
}

/// [`control`] in a thread of its own.
fn control_in_background(
    instance: &str,
    scene: &Scene,
    seconds: f64,
    rate_hz: f64,
) -> std::thread::JoinHandle<Run> {
    let (instance, scene) = (instance.to_owned(), scene.clone());
    std::thread::spawn(move || control(&instance, &scene, seconds, rate_hz, None))
}

/// The child's stderr, read to its end in a thread.
fn stderr_of(child: &mut Child) -> std::thread::JoinHandle<String> {
    let mut e = child.stderr.take().unwrap();
    std::thread::spawn(move || std::io::read_to_string(&mut e).unwrap())
}

fn hex(v: f64) -> String {
    format!("{:016x}", v.to_bits())
}

/// What the controller received, for the Python reader: integers as numbers, floats as their
/// IEEE-754 bit patterns.
fn expected_json(run: &Run) -> String {
    let estimates: Vec<serde_json::Value> = run
        .estimates
        .iter()
        .map(|e| {
            serde_json::json!({
                "sequence": e.sequence,
                "pose_sequence": e.pose_sequence,
                "pose_timestamp_ns": e.pose_timestamp_ns,
                "receive_timestamp_ns": e.receive_timestamp_ns,
                "publish_timestamp_ns": e.publish_timestamp_ns,
                "status": e.status,
                "cable_count": e.cable_count,
                "ee_mode_age_cycles": e.ee_mode_age_cycles,
                "stiffness_dim": e.stiffness_dim,
                "compute_ns": e.compute_ns,
                "eigen_evaluations": e.eigen_evaluations,
                "tension_iterations": e.tension_iterations,
                "skipped_poses": e.skipped_poses,
                "measured_f1_status": e.measured_f1_status,
                "measured_ee_mode_status": e.measured_ee_mode_status,
                "vibration_samples": e.vibration_samples,
                "vibration_refused": e.vibration_refused,
                "vibration_lost": e.vibration_lost,
                "measured_age_ns": (e.measured_age_ns != MEASURED_AGE_UNKNOWN)
                    .then_some(e.measured_age_ns),
                "measured_f1_hz": hex(e.measured_f1_hz),
                "f1_residual_hz": hex(e.f1_residual_hz),
                "measured_ee_mode_hz": hex(e.measured_ee_mode_hz),
                "ee_mode_residual_hz": hex(e.ee_mode_residual_hz),
                "f1_hz": hex(e.f1_hz),
                "ee_mode_hz": hex(e.ee_mode_hz),
                "eigen_residual": hex(e.eigen_residual),
                "tensions_n": e.tensions().iter().map(|v| hex(*v)).collect::<Vec<_>>(),
                "stiffness": e.stiffness_matrix().iter().map(|v| hex(*v)).collect::<Vec<_>>(),
            })
        })
        .collect();
    serde_json::json!({"poses": run.poses.len(), "estimates": estimates}).to_string()
}

/// The fields of an estimate that depend on the pose, the T_min and the scene only (not on
/// time), as JSON text: equal text is equal bits (shortest round-trip decimal forms).
fn values(record: &serde_json::Value) -> String {
    let keys = [
        "status",
        "tensions_n",
        "f1_hz",
        "ee_mode_hz",
        "ee_mode_age_cycles",
        "stiffness",
        "eigen_evaluations",
        "tension_iterations",
        "eigen_residual",
    ];
    keys.iter()
        .map(|k| format!("{k}={}", record[*k]))
        .collect::<Vec<_>>()
        .join(" ")
}

fn replay_into_fresh_service(
    file: &Path,
    scene: &Scene,
    tag: &str,
    t_min: Option<f64>,
) -> Vec<EstimateSample> {
    let instance = format!("cvmon_{}_{tag}", std::process::id());
    let service = start_service(&instance, scene);
    let never = AtomicBool::new(false);
    let cfg = ReplayConfig {
        pace: Pace::Fast,
        answered_only: true,
        t_min_n: t_min,
        ..ReplayConfig::new(file.to_owned(), &instance)
    };
    let mut estimates = Vec::new();
    let r = replay(&cfg, &never, |e| estimates.push(*e)).unwrap();
    stop_service(service);
    assert_eq!(r.timeouts, 0);
    assert_eq!(r.estimates, estimates.len() as u64);
    estimates
}

/// The estimates of a recording, as JSON objects, in file order.
fn recorded_estimates(file: &Path) -> Vec<serde_json::Value> {
    read_recording(file)
        .unwrap()
        .filter_map(|m| match m.unwrap() {
            Recorded::Estimate(json) => Some(serde_json::from_slice(&json).unwrap()),
            _ => None,
        })
        .collect()
}

/// A 10 s run at 1 kHz recorded by the monitor process and watched live by a Foxglove
/// WebSocket client; the file read back by the Python `mcap` reader (counts, bit-for-bit
/// values, schemas); replayed into a fresh service (same estimates bit for bit; another T_min,
/// other estimates); a cut or foreign file refused by `replay` with one line.
#[test]
fn record_watch_read_back_and_replay() {
    let py = python();
    let scene = Scene::default_scene();
    let instance = format!("cvmon_{}_rt", std::process::id());
    let file = scratch("run.mcap");
    let service = start_service(&instance, &scene);
    let (mut monitor, attached, stdout) = start_monitor(&[
        "--instance",
        &instance,
        "--scene",
        "spatial-paper",
        "--required-hz",
        "8",
        "--foxglove",
        "127.0.0.1:0",
        "--record",
        file.to_str().unwrap(),
    ]);
    let url = attached
        .split("Foxglove at ")
        .nth(1)
        .and_then(|s| s.split(',').next())
        .expect("the attached line names the URL")
        .to_owned();
    // The client runs while the controller below drives the service.
    let ws_client = Command::new(&py)
        .arg(script("ws_client.py"))
        .arg(&url)
        .arg(scene.cable_t_min_n(0).to_string())
        .arg(scene.cable_t_max_n(0).to_string())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let ws = std::thread::spawn(move || ws_client.wait_with_output().unwrap());
    let run = control(
        &instance,
        &scene,
        10.0,
        1000.0,
        Some((5.0, scene.t_min_n + 20.0)),
    );
    signal(&monitor, libc::SIGTERM);
    let status = monitor.wait().unwrap();
    let lines = stdout.join().unwrap();
    let service_report = stop_service(service);
    assert!(status.success(), "monitor: {status:?} {lines:?}");
    let ws = ws.join().unwrap();
    assert!(
        ws.status.success(),
        "WebSocket client: {}{}",
        String::from_utf8_lossy(&ws.stdout),
        String::from_utf8_lossy(&ws.stderr)
    );
    println!("{}", String::from_utf8_lossy(&ws.stdout).trim());
    println!("{}", lines.last().unwrap());
    assert!(run.estimates.len() as u64 == service_report.cycles);

    let expected = scratch("expected.json");
    std::fs::write(&expected, expected_json(&run)).unwrap();
    let out = Command::new(&py)
        .arg(script("check_recording.py"))
        .args(["full", expected.to_str().unwrap(), file.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "Python mcap reader: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    println!("{}", String::from_utf8_lossy(&out.stdout).trim());
    // The record says it is complete, and is: every estimate the service published.
    let c = completeness::completeness_of(&py, &file);
    let m = &c["metadata"]["cablevib.completeness"];
    assert_eq!(
        c["counted"]["estimate"]["messages"].as_u64(),
        Some(service_report.cycles)
    );
    assert_eq!(m["complete"].as_str(), Some("true"), "{c}");
    assert!(
        lines.iter().any(|l| l.contains("record complete")),
        "{lines:?}"
    );

    // Replay: the same scene gives the same estimates, bit for bit.
    let recorded = recorded_estimates(&file);
    let by_seq: std::collections::HashMap<u64, &serde_json::Value> = recorded
        .iter()
        .map(|e| (e["pose_sequence"].as_u64().unwrap(), e))
        .collect();
    let same = replay_into_fresh_service(&file, &scene, "same", None);
    assert_eq!(same.len(), recorded.len());
    for e in &same {
        let again = serde_json::to_value(EstimateRecord::new(e, f64::NAN)).unwrap();
        let then = by_seq[&e.pose_sequence];
        assert_eq!(values(&again), values(then), "pose {}", e.pose_sequence);
    }
    // Another T_min: other tensions (a higher floor moves the distribution).
    let other = replay_into_fresh_service(&file, &scene, "tmin", Some(scene.t_min_n + 50.0));
    assert_eq!(other.len(), recorded.len());
    let differ = other
        .iter()
        .filter(|e| {
            let again = serde_json::to_value(EstimateRecord::new(e, f64::NAN)).unwrap();
            values(&again) != values(by_seq[&e.pose_sequence])
        })
        .count();
    assert!(
        differ * 10 >= other.len() * 9,
        "{differ} of {} differ",
        other.len()
    );
    println!(
        "replay: {} estimates equal bit for bit; with T_min + 50 N {differ} of {} differ",
        same.len(),
        other.len()
    );

    // A cut file and a foreign file: one line each.
    let bytes = std::fs::read(&file).unwrap();
    let cut = scratch("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let foreign = scratch("foreign.mcap");
    std::fs::write(&foreign, "t_s,x_m,y_m,z_m\n0,0.1,0.2,1.0\n").unwrap();
    for (f, says) in [
        (&cut, "not a complete MCAP file"),
        (&foreign, "not an MCAP file"),
    ] {
        let out = Command::new(BIN)
            .arg("replay")
            .arg(f)
            .args(["--instance", "cvmon_nobody", "--wait-s", "1"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(says), "{err}");
    }
}

/// A monitor killed with SIGKILL mid-run leaves its temporary file `FILE.PID.part` (FILE
/// itself is never created: it appears only complete), which the Python `mcap` reader reads
/// up to its last complete chunk.
#[test]
fn killed_monitor_leaves_a_readable_file() {
    let py = python();
    let scene = Scene::default_scene();
    let instance = format!("cvmon_{}_kill", std::process::id());
    let file = scratch("killed.mcap");
    let service = start_service(&instance, &scene);
    let (mut monitor, _, _stdout) = start_monitor(&[
        "--instance",
        &instance,
        "--scene",
        "spatial-paper",
        "--no-foxglove",
        "--record",
        file.to_str().unwrap(),
    ]);
    let run = control(&instance, &scene, 3.0, 1000.0, None);
    let pid = monitor.id();
    signal(&monitor, libc::SIGKILL);
    let _ = monitor.wait();
    stop_service(service);
    assert!(!file.exists(), "{} exists after SIGKILL", file.display());
    let part = PathBuf::from(format!("{}.{pid}.part", file.display()));
    assert!(part.exists(), "no {}", part.display());
    let out = Command::new(&py)
        .arg(script("check_recording.py"))
        .args(["killed", part.to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let read: usize = text
        .split_whitespace()
        .nth(1)
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{text}"));
    // A chunk holds at most 256 KiB of messages (≥ 300 bytes each): at most ~870 messages, i.e.
    // ~440 estimates with their poses, can be in the chunk the kill cut.
    println!("{} estimates sent, {text}", run.estimates.len());
    assert!(
        read > 0 && read + 1000 >= run.estimates.len(),
        "{read} of {} estimates readable",
        run.estimates.len()
    );
}

/// A second monitor on a port in use is refused with a clear line.
#[test]
fn second_monitor_on_the_same_port_is_refused() {
    let scene = Scene::default_scene();
    let instance = format!("cvmon_{}_port", std::process::id());
    let service = start_service(&instance, &scene);
    let port = {
        let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        l.local_addr().unwrap().port()
    };
    let addr = format!("127.0.0.1:{port}");
    let (mut first, _, _stdout) = start_monitor(&["--instance", &instance, "--foxglove", &addr]);
    let second = Command::new(BIN)
        .args(["monitor", "--instance", &instance, "--foxglove", &addr])
        .output()
        .unwrap();
    signal(&first, libc::SIGTERM);
    let _ = first.wait();
    stop_service(service);
    let err = String::from_utf8_lossy(&second.stderr);
    assert!(!second.status.success());
    assert!(
        err.contains("address is in use") && err.contains(&addr),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
}
