//! `cablevib serve` as a separate process, through real iceoryx2 services.
//!
//! - estimates are bit-for-bit those of the library's `Estimator` fed the same poses and T_min
//!   values (uniform, per-cable, changed mid-way);
//! - every bad input (NaN/Inf pose, non-unit quaternion, position outside the frame, T_min
//!   below 0, above T_max or NaN, infeasible tensions) gets its status and the next valid pose
//!   is answered exactly;
//! - margin requests: no pose yet, invalid request, ok, after a bad pose;
//! - latest pose wins and the skipped ones are counted;
//! - SIGKILL of the service while a publisher runs, then a restart: estimates resume, with the
//!   T_min set-point in force (history); publishers and controllers SIGKILLed and restarted
//!   more often than a service has port slots: dead nodes are cleaned up;
//! - a peer with another message layout gets a clear error; SIGINT/SIGTERM stop cleanly;
//! - a second estimate publisher or margin server is refused while the service runs; a service
//!   pre-created with other limits makes `serve` refuse, naming the setting; a dead node of
//!   another application survives the service's cleanup, a dead cablevib node does not.
//!
//! Each test uses its own instance name (process id + test name), so tests run in parallel;
//! every wait is bounded; child processes are killed by a guard when a test fails. Publisher
//! and controller processes are this test binary re-executed with an environment variable
//! that selects the `helper_*` function (ignored tests that do nothing otherwise).

use cablevib::estimator::Tmin;
use std::io::{BufRead, BufReader, Read};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use cablevib::estimator::{Estimate, Estimator};
use cablevib::kinematics::Pose;
use cablevib::scene::Scene;
use cablevib::trajectory::Trajectory;
use cablevib_ipc::{
    monotonic_now_ns, EstimateSample, MarginRequest, PoseSample, ServiceNames, StatusCode,
    TminSetpoint, EVENT_ID_POSE, IDENTITY_QUATERNION, SCHEMA_VERSION,
};
use cablevib_service::ports::{
    create_node, load_iceoryx2_config, open_event, open_margin, open_pubsub, EstimateOutput,
    MarginClient, PoseInput, ESTIMATE_SETTINGS, MAX_CLIENTS, MAX_NODES, MAX_PUBLISHERS,
    MAX_SUBSCRIBERS, POSE_SETTINGS, T_MIN_SETTINGS,
};
use cablevib_service::WaitMode;
use iceoryx2::node::{NodeState, NodeView};
use iceoryx2::prelude::*;
use nalgebra::Vector3;

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");
/// Longest wait for anything (service start, an answer, an exit).
const TIMEOUT: Duration = Duration::from_secs(20);
/// Longest wait for one estimate.
const ANSWER: Duration = Duration::from_secs(5);

const HELPER_ENV: &str = "CABLEVIB_IPC_TEST_HELPER";
const INSTANCE_ENV: &str = "CABLEVIB_IPC_TEST_INSTANCE";
const SEQ_BASE_ENV: &str = "CABLEVIB_IPC_TEST_SEQ_BASE";

fn instance(test: &str) -> String {
    format!("cvtest_{}_{test}", std::process::id())
}

// ---------------------------------------------------------------------------------------------
// Child processes
// ---------------------------------------------------------------------------------------------

/// A child process, killed (SIGKILL) when dropped; its stderr is collected, and printed when
/// the test fails; its stdout lines are forwarded to a channel.
struct Proc {
    what: String,
    child: Child,
    stderr: Arc<Mutex<String>>,
    stdout: mpsc::Receiver<String>,
}

impl Proc {
    fn spawn(what: &str, mut cmd: Command) -> Proc {
        cmd.stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = cmd
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {what}: {e}"));
        let stderr = Arc::new(Mutex::new(String::new()));
        let mut err = child.stderr.take().expect("piped stderr");
        let sink = stderr.clone();
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = err.read(&mut buf) {
                if n == 0 {
                    break;
                }
                sink.lock()
                    .unwrap()
                    .push_str(&String::from_utf8_lossy(&buf[..n]));
            }
        });
        let (tx, rx) = mpsc::channel();
        let out = child.stdout.take().expect("piped stdout");
        std::thread::spawn(move || {
            for line in BufReader::new(out).lines() {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Proc {
            what: what.to_owned(),
            child,
            stderr,
            stdout: rx,
        }
    }

    fn pid(&self) -> i32 {
        self.child.id() as i32
    }

    fn stderr(&self) -> String {
        self.stderr.lock().unwrap().clone()
    }

    /// Panics (with the child's log) if the child has exited.
    fn assert_running(&mut self) {
        if let Ok(Some(status)) = self.child.try_wait() {
            panic!(
                "{} exited unexpectedly ({status}); its stderr:\n{}",
                self.what,
                self.stderr()
            );
        }
    }

    /// Waits up to `timeout` for the child to exit.
    fn wait_exit(&mut self, timeout: Duration) -> ExitStatus {
        let end = Instant::now() + timeout;
        loop {
            if let Some(s) = self.child.try_wait().expect("try_wait") {
                // Let the reader thread collect the last lines.
                std::thread::sleep(Duration::from_millis(50));
                return s;
            }
            assert!(
                Instant::now() < end,
                "{} did not exit within {timeout:?}; its stderr:\n{}",
                self.what,
                self.stderr()
            );
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    fn signal(&self, sig: i32) {
        // SAFETY: kill(2) with the pid of our own child.
        let rc = unsafe { libc::kill(self.pid(), sig) };
        assert_eq!(rc, 0, "kill({}, {sig})", self.pid());
    }

    /// SIGKILL and reap.
    fn kill9(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// The next stdout line, within `timeout`.
    fn next_line(&mut self, timeout: Duration) -> Option<String> {
        self.stdout.recv_timeout(timeout).ok()
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        if std::thread::panicking() {
            eprintln!("---- stderr of {} ----\n{}", self.what, self.stderr());
        }
    }
}

fn spawn_service(instance: &str, wait: WaitMode) -> Proc {
    let mut cmd = Command::new(BIN);
    cmd.args([
        "serve",
        "--instance",
        instance,
        "--wait",
        wait.as_str(),
        "--stats-period-s",
        "0.5",
    ])
    .env("RUST_LOG", "info");
    Proc::spawn(&format!("cablevib serve --instance {instance}"), cmd)
}

/// This test binary, running only the helper `name` (see the `helper_*` tests).
fn spawn_helper(name: &str, instance: &str, seq_base: u64) -> Proc {
    let exe = std::env::current_exe().expect("test executable");
    let mut cmd = Command::new(exe);
    cmd.args([
        "--exact",
        &format!("ipc_service::helper_{name}"),
        "--ignored",
        "--nocapture",
        "--test-threads=1",
    ])
    .env(HELPER_ENV, name)
    .env(INSTANCE_ENV, instance)
    .env(SEQ_BASE_ENV, seq_base.to_string());
    Proc::spawn(&format!("{name} helper (base {seq_base})"), cmd)
}

fn wait_until<T>(
    timeout: Duration,
    what: &str,
    service: &mut Proc,
    mut f: impl FnMut() -> Option<T>,
) -> T {
    let end = Instant::now() + timeout;
    loop {
        if let Some(v) = f() {
            return v;
        }
        service.assert_running();
        assert!(
            Instant::now() < end,
            "timed out after {timeout:?} waiting for {what}"
        );
        std::thread::sleep(Duration::from_millis(1));
    }
}

// ---------------------------------------------------------------------------------------------
// A controller in the test process, and the library reference
// ---------------------------------------------------------------------------------------------

struct Client {
    _node: Node<ipc::Service>,
    input: PoseInput,
    output: EstimateOutput,
    margin: MarginClient,
    sequence: u64,
    t_min_sequence: u64,
}

impl Client {
    /// Opens the ports before the service starts (a subscriber only sees samples sent after it
    /// connected).
    fn new(instance: &str) -> Client {
        let names = ServiceNames::new(instance);
        let node = create_node("cablevib-test-client").expect("node");
        Client {
            input: PoseInput::open(&node, &names).expect("pose input"),
            output: EstimateOutput::open(&node, &names).expect("estimate output"),
            margin: MarginClient::open(&node, &names).expect("margin client"),
            _node: node,
            sequence: 0,
            t_min_sequence: 0,
        }
    }

    fn wait_for(&self, service: &mut Proc) {
        wait_until(TIMEOUT, "the service's ports", service, || {
            (self.input.service_connected()
                && self.output.service_connected()
                && self.margin.service_connected())
            .then_some(())
        });
    }

    /// Sends a pose and returns the estimate that answers it.
    fn estimate(&mut self, position_m: [f64; 3], orientation_wxyz: [f64; 4]) -> EstimateSample {
        self.sequence += 1;
        let pose = PoseSample::new(
            self.sequence,
            monotonic_now_ns(),
            position_m,
            orientation_wxyz,
        );
        self.input.send_pose(&pose).expect("send pose");
        let end = Instant::now() + ANSWER;
        loop {
            let left = end.saturating_duration_since(Instant::now());
            let e = self
                .output
                .wait(WaitMode::Event, left)
                .expect("receive")
                .unwrap_or_else(|| {
                    panic!("no estimate for pose {} within {ANSWER:?}", self.sequence)
                });
            if e.answers(&pose) {
                return e;
            }
        }
    }

    fn t_min(&mut self, setpoint: TminSetpoint) {
        self.t_min_sequence += 1;
        let s = TminSetpoint {
            sequence: self.t_min_sequence,
            timestamp_ns: monotonic_now_ns(),
            ..setpoint
        };
        self.input.send_t_min(&s).expect("send T_min");
    }
}

fn bits(x: f64) -> u64 {
    x.to_bits()
}

/// The estimate carries exactly what the library computed.
fn assert_same(got: &EstimateSample, want: &Estimate, what: &str) {
    assert_eq!(
        got.status_code(),
        Some(want.status),
        "{what}: status (library error: {:?})",
        want.error
    );
    assert_eq!(got.cable_count as usize, want.n_cables, "{what}: cables");
    for (i, (a, b)) in got.tensions().iter().zip(want.tensions()).enumerate() {
        assert_eq!(bits(*a), bits(*b), "{what}: tension {i}: {a} vs {b} N");
    }
    assert_eq!(
        bits(got.f1_hz),
        bits(want.f1_hz),
        "{what}: f1 {} vs {}",
        got.f1_hz,
        want.f1_hz
    );
    // The wire's codes for the end-effector mode: NaN and EE_MODE_AGE_UNKNOWN when absent.
    let (want_hz, want_age) = match want.ee_mode {
        Some(m) => (m.frequency_hz, m.age_cycles),
        None => (f64::NAN, cablevib_ipc::EE_MODE_AGE_UNKNOWN),
    };
    assert_eq!(bits(got.ee_mode_hz), bits(want_hz), "{what}: ee mode");
    assert_eq!(got.ee_mode_age_cycles, want_age, "{what}: ee mode age");
    assert_eq!(got.stiffness_dim, 3, "{what}");
    for r in 0..3 {
        for c in 0..3 {
            assert_eq!(
                bits(got.stiffness_at(r, c).unwrap()),
                bits(want.stiffness.translational_n_m()[(r, c)]),
                "{what}: stiffness ({r}, {c})"
            );
        }
    }
    assert_eq!(
        bits(got.eigen_residual),
        bits(want.eigen_residual),
        "{what}: residual"
    );
    assert_eq!(
        got.eigen_evaluations, want.eigen_evaluations,
        "{what}: evaluations"
    );
    assert_eq!(
        got.tension_iterations, want.tension_iterations,
        "{what}: iterations"
    );
}

fn pose_at(p: [f64; 3], q: [f64; 4]) -> Pose {
    Pose {
        position_m: Vector3::from(p),
        orientation_wxyz: q,
    }
}

fn circle(k: usize) -> [f64; 3] {
    let scene = Scene::default_scene();
    let p = cablevib::trajectory::circle_pose(&scene, k, 4.0).position_m;
    [p.x, p.y, p.z]
}

// ---------------------------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------------------------

#[test]
fn estimates_equal_the_library_bit_for_bit() {
    let inst = instance("bit_equal");
    let mut client = Client::new(&inst);
    let mut service = spawn_service(&inst, WaitMode::Spin);
    client.wait_for(&mut service);
    let scene = Scene::default_scene();
    let mut reference = Estimator::realtime(&scene).expect("estimator");
    let mut t_min_n = [scene.t_min_n; 8];
    let q = IDENTITY_QUATERNION;
    for k in 0..300 {
        if k == 100 {
            t_min_n = [75.0; 8]; // applies to the very next pose
            client.t_min(TminSetpoint::uniform(0, 0, 75.0));
        }
        if k == 200 {
            // Per-cable values: each cable gets its own lower bound.
            let per_cable = [61.0, 64.0, 62.0, 70.0, 60.0, 60.0, 60.0, 63.0];
            client.t_min(TminSetpoint::per_cable(0, 0, 10.0, &per_cable).unwrap());
            t_min_n = per_cable;
        }
        let p = circle(5 * k);
        let got = client.estimate(p, q);
        let want = *reference.update(&pose_at(p, q), Tmin::PerCable(&t_min_n));
        if k >= 200 {
            let t = got.tensions();
            assert!(
                t.iter().zip(&t_min_n).all(|(t, lo)| t >= lo),
                "pose {k}: tensions {t:?} below the per-cable bounds {t_min_n:?}"
            );
        }
        assert!(want.is_ok(), "pose {k}: {:?}", want.error);
        assert_same(&got, &want, &format!("pose {k}"));
        assert_eq!(got.skipped_poses, 0);
        assert!(got.receive_timestamp_ns >= got.pose_timestamp_ns);
        assert!(got.publish_timestamp_ns >= got.receive_timestamp_ns);
        assert!(got.compute_ns > 0);
    }
    service.assert_running();
}

#[test]
fn every_bad_input_gets_its_status_and_the_next_pose_is_answered() {
    let inst = instance("bad_inputs");
    let mut client = Client::new(&inst);
    let mut service = spawn_service(&inst, WaitMode::Event);
    client.wait_for(&mut service);
    let scene = Scene::default_scene();
    let mut reference = Estimator::realtime(&scene).expect("estimator");
    let q = IDENTITY_QUATERNION;
    let good = |k: usize| circle(37 * k);
    let nan = f64::NAN;
    let inf = f64::INFINITY;
    // (what, position, quaternion, T_min set-point to send first, expected status)
    type Case = (&'static str, [f64; 3], [f64; 4], Option<f64>, StatusCode);
    let subnormal = f64::MIN_POSITIVE / 2.0;
    let cases: [Case; 13] = [
        (
            "NaN position",
            [0.1, nan, 1.0],
            q,
            None,
            StatusCode::InvalidInput,
        ),
        (
            "infinite position",
            [inf, 0.0, 1.0],
            q,
            None,
            StatusCode::InvalidInput,
        ),
        (
            "NaN quaternion",
            [0.1, 0.0, 1.0],
            [nan, 0.0, 0.0, 0.0],
            None,
            StatusCode::InvalidInput,
        ),
        (
            "non-unit quaternion",
            [0.1, 0.0, 1.0],
            [1.0, 0.1, 0.0, 0.0],
            None,
            StatusCode::NonUnitQuaternion,
        ),
        (
            "zero quaternion",
            [0.1, 0.0, 1.0],
            [0.0; 4],
            None,
            StatusCode::NonUnitQuaternion,
        ),
        (
            "outside the frame (x): no tensions hold it",
            [2.0, 0.0, 1.25],
            q,
            None,
            StatusCode::TensionInfeasible,
        ),
        (
            "above every anchor: no tensions hold it",
            [0.0, 0.0, 3.0],
            q,
            None,
            StatusCode::TensionInfeasible,
        ),
        (
            "T_min < 0",
            [0.1, 0.0, 1.0],
            q,
            Some(-5.0),
            StatusCode::TminOutOfRange,
        ),
        (
            "T_min > T_max",
            [0.1, 0.0, 1.0],
            q,
            Some(scene.t_max_n + 1.0),
            StatusCode::TminOutOfRange,
        ),
        (
            "T_min NaN",
            [0.1, 0.0, 1.0],
            q,
            Some(nan),
            StatusCode::TminOutOfRange,
        ),
        (
            "T_min 0 (a zeroed set-point)",
            [0.1, 0.0, 1.0],
            q,
            Some(0.0),
            StatusCode::TminOutOfRange,
        ),
        (
            "T_min subnormal",
            [0.1, 0.0, 1.0],
            q,
            Some(subnormal),
            StatusCode::TminOutOfRange,
        ),
        (
            "infeasible: T_min 100 N at the circle's edge",
            [0.75, 0.0, 1.25],
            q,
            Some(100.0),
            StatusCode::TensionInfeasible,
        ),
    ];
    let mut t_min_n = scene.t_min_n;
    let mut k = 0;
    let mut valid = |client: &mut Client, reference: &mut Estimator, t_min_n: f64, what: &str| {
        k += 1;
        let p = good(k);
        let got = client.estimate(p, q);
        let want = *reference.update(&pose_at(p, q), Tmin::Uniform(t_min_n));
        assert!(want.is_ok(), "{what}: {:?}", want.error);
        assert_same(&got, &want, what);
    };
    valid(&mut client, &mut reference, t_min_n, "first valid pose");
    for (what, p, quat, set, status) in cases {
        let mut t_min_for_this = t_min_n;
        if let Some(v) = set {
            client.t_min(TminSetpoint::uniform(0, 0, v));
            t_min_for_this = v;
            if cablevib::scene::is_valid_t_min(v, scene.t_max_n) {
                t_min_n = v; // a valid set-point stays in force
            }
        }
        let got = client.estimate(p, quat);
        assert_eq!(
            got.status_code(),
            Some(status),
            "{what}: got status {}",
            cablevib_ipc::status_str(got.status)
        );
        assert!(
            got.f1_hz.is_nan() && got.ee_mode_hz.is_nan(),
            "{what}: no stale numbers"
        );
        let want = *reference.update(&pose_at(p, quat), Tmin::Uniform(t_min_for_this));
        assert_same(&got, &want, what);
        if status == StatusCode::TensionInfeasible {
            assert!(
                got.tensions().iter().all(|t| t.is_finite()),
                "closest tensions reported"
            );
            // 100 N is infeasible on much of the circle: back to the scene's T_min.
            client.t_min(TminSetpoint::uniform(0, 0, scene.t_min_n));
            t_min_n = scene.t_min_n;
        }
        // A rejected set-point leaves the previous one in force.
        valid(
            &mut client,
            &mut reference,
            t_min_n,
            &format!("valid pose after {what}"),
        );
        service.assert_running();
    }
    // A per-cable set-point with one value the scene would refuse (0 N, as in a zeroed
    // message): refused as a whole for one estimate, the previous bounds stay in force.
    let mut zeroed = TminSetpoint::zeroed();
    zeroed.per_cable_count = 8;
    zeroed.per_cable_t_min_n[..8].fill(scene.t_min_n);
    zeroed.per_cable_t_min_n[3] = 0.0;
    client.t_min(zeroed);
    let got = client.estimate(good(99), q);
    assert_eq!(got.status_code(), Some(StatusCode::TminOutOfRange));
    valid(
        &mut client,
        &mut reference,
        t_min_n,
        "valid pose after a per-cable set-point with a zero",
    );
    // The service counted and logged it all.
    std::thread::sleep(Duration::from_millis(700));
    let log = service.stderr();
    assert!(log.contains("invalid inputs"), "{log}");
    assert!(log.contains("rejected a T_min set-point"), "{log}");
}

#[test]
fn margin_requests_answer_for_the_latest_pose() {
    let inst = instance("margin");
    let mut client = Client::new(&inst);
    let mut service = spawn_service(&inst, WaitMode::Event);
    client.wait_for(&mut service);
    let query = |client: &Client, seq: u64, required: f64| {
        client
            .margin
            .query(
                &MarginRequest::new(seq, monotonic_now_ns(), required),
                WaitMode::Event,
                ANSWER,
            )
            .expect("query")
            .expect("an answer within the timeout")
    };
    // The T_min answer comes from the inverse search beside the loop: the first request for
    // a requirement starts it (NaN, age unknown); repeated, the request gets the answer at
    // this pose (age 0: no pose in between). Unreachable is +∞.
    // Up to 2 s: the worker rests 19× each search's time, at most 0.2 s, so even after a long
    // search (at most 208 forward evaluations) the next answer comes within about a second.
    let settled = |client: &Client, seq: u64, required: f64| {
        for _ in 0..400 {
            let r = query(client, seq, required);
            if r.t_min_required_age_cycles != cablevib_ipc::T_MIN_AGE_UNKNOWN {
                assert_eq!(r.t_min_required_age_cycles, 0, "{r:?}");
                return r;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        query(client, seq, required)
    };
    let r = query(&client, 1, 8.0);
    assert_eq!(r.status_code(), Some(StatusCode::NoPoseYet));
    assert_eq!(r.request_sequence, 1);
    assert!(r.f1_hz.is_nan());

    let e = client.estimate(circle(0), IDENTITY_QUATERNION);
    assert!(e.is_ok());
    let r = settled(&client, 2, 8.0);
    assert!(r.is_ok(), "{r:?}");
    assert_eq!((r.request_sequence, r.pose_sequence), (2, e.pose_sequence));
    assert_eq!(bits(r.f1_hz), bits(e.f1_hz));
    assert_eq!(r.margin_hz, e.f1_hz - 8.0);
    assert_eq!(r.margin_ratio, e.f1_hz / 8.0);
    assert!(r.margin_hz > 0.0, "the paper's robot is above 8 Hz here");
    // The smallest T_min that reaches the requirement, as the library computes it.
    let mut lib =
        cablevib::estimator::Estimator::new(&cablevib::scene::Scene::default_scene()).unwrap();
    let pose = cablevib::kinematics::Pose {
        position_m: nalgebra::Vector3::from(circle(0)),
        orientation_wxyz: IDENTITY_QUATERNION,
    };
    let want = lib
        .t_min_for_f1(&pose, 8.0)
        .expect("8 Hz is reachable")
        .t_min_n;
    assert!(
        (r.t_min_required_n - want).abs() <= 1e-9 * want,
        "{} vs {want}",
        r.t_min_required_n
    );
    assert!(
        r.t_min_required_n < 60.0,
        "8 Hz needs less than the current 60 N"
    );
    let r = settled(&client, 3, 20.0);
    assert!(r.is_ok() && r.margin_hz < 0.0);
    // Here the largest feasible T_min (≈ 88 N) gives ≈ 11 Hz: 20 Hz is unreachable → +∞
    // (a known answer: no T_min; NaN only while none is known).
    assert_eq!(r.t_min_required_age_cycles, 0);
    assert_eq!(
        r.t_min_required_n,
        f64::INFINITY,
        "unreachable: +∞, got {}",
        r.t_min_required_n
    );
    let r = settled(&client, 6, 10.0);
    let want = lib
        .t_min_for_f1(&pose, 10.0)
        .expect("10 Hz is reachable")
        .t_min_n;
    assert!((r.t_min_required_n - want).abs() <= 1e-9 * want && r.t_min_required_n > 60.0);

    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let r = query(&client, 4, bad);
        assert_eq!(
            r.status_code(),
            Some(StatusCode::InvalidRequest),
            "required {bad}"
        );
    }

    let e = client.estimate([2.0, 0.0, 1.0], IDENTITY_QUATERNION);
    assert_eq!(e.status_code(), Some(StatusCode::TensionInfeasible));
    let r = query(&client, 5, 8.0);
    assert_eq!(r.status_code(), Some(StatusCode::TensionInfeasible));
    assert_eq!(r.pose_sequence, e.pose_sequence);
    assert!(r.margin_hz.is_nan());
}

/// Poses at ~1 kHz for `ms` milliseconds, each with a margin request whose required f1 is
/// new (when `flood`): returns (poses sent, estimates received, largest D(λ) evaluation
/// count of an estimate, the estimates' compute times in ns).
fn paced_run(
    client: &mut Client,
    k0: usize,
    ms: usize,
    flood: bool,
) -> (usize, usize, u32, Vec<u64>) {
    let mut pending = std::collections::VecDeque::new();
    let (mut received, mut max_evals, mut compute) = (0, 0, Vec::new());
    let start = Instant::now();
    for k in 0..ms {
        client.sequence += 1;
        let pose = PoseSample::new(
            client.sequence,
            monotonic_now_ns(),
            circle(k0 + k),
            IDENTITY_QUATERNION,
        );
        client.input.send_pose(&pose).expect("send pose");
        if flood {
            // A requirement that changes every request (the worst case for a search that
            // restarts); the last one in flight is dropped first (the client's active
            // requests are limited), answered or not.
            let req = MarginRequest::new(k as u64 + 1, monotonic_now_ns(), 7.0 + 1e-3 * k as f64);
            pending.clear();
            pending.push_back(client.margin.send(&req).expect("send margin request"));
        }
        while let Some(e) = client.output.try_receive().expect("receive") {
            received += 1;
            max_evals = max_evals.max(e.eigen_evaluations);
            compute.push(e.compute_ns);
        }
        // Pace at 1 kHz.
        let due = start + Duration::from_millis(k as u64 + 1);
        while Instant::now() < due {
            std::hint::spin_loop();
        }
    }
    std::thread::sleep(Duration::from_millis(50));
    while let Some(e) = client.output.try_receive().expect("receive") {
        received += 1;
        max_evals = max_evals.max(e.eigen_evaluations);
        compute.push(e.compute_ns);
    }
    compute.sort_unstable();
    (ms, received, max_evals, compute)
}

/// A controller flooding margin requests with a new required f1 each time, beside poses at
/// 1 kHz: the estimate loop keeps its rate (the inverse search runs beside it) and no cycle
/// spends more D(λ) evaluations than the budget. Counts, not timing: the estimates received
/// must be at least half of the poses sent, with and without the flood (a loop running the
/// search inline managed 13 cycles in 3 s; the margin of 2 is for a shared machine).
#[test]
fn margin_flood_keeps_the_estimate_rate() {
    let inst = instance("margin_flood");
    let mut client = Client::new(&inst);
    let mut service = spawn_service(&inst, WaitMode::Event);
    client.wait_for(&mut service);
    let budget = cablevib::modal::CYCLE_EVALUATIONS;
    let quiet = paced_run(&mut client, 0, 1500, false);
    let flood = paced_run(&mut client, 1500, 1500, true);
    let p99 = |v: &[u64]| v.get((v.len().max(1) - 1) * 99 / 100).copied().unwrap_or(0);
    eprintln!(
        "without flood: {} of {} poses estimated, max {} evaluations, compute p99 {} ns; \
         with flood: {} of {}, max {}, p99 {} ns",
        quiet.1,
        quiet.0,
        quiet.2,
        p99(&quiet.3),
        flood.1,
        flood.0,
        flood.2,
        p99(&flood.3)
    );
    for (name, r) in [("quiet", &quiet), ("flood", &flood)] {
        assert!(
            r.2 <= budget,
            "{name}: {} evaluations > budget {budget}",
            r.2
        );
        assert!(
            4 * r.1 >= r.0,
            "{name}: {} estimates for {} poses",
            r.1,
            r.0
        );
    }
    service.assert_running();
}

#[test]
fn latest_pose_wins_and_skipped_poses_are_counted() {
    let inst = instance("latest_wins");
    let names = ServiceNames::new(&inst);
    let client = Client::new(&inst);
    let mut service = spawn_service(&inst, WaitMode::Event);
    client.wait_for(&mut service);
    // A publisher that does not notify: the poses queue until the wake-up below.
    let node = create_node("cablevib-test-quiet").expect("node");
    let quiet = open_pubsub::<PoseSample>(&node, &names.pose, POSE_SETTINGS)
        .expect("pose service")
        .publisher_builder()
        .create()
        .expect("publisher");
    let wake = open_event(&node, &names.wake_service)
        .expect("event")
        .notifier_builder()
        .create()
        .expect("notifier");
    let n = 5u64;
    for seq in 1..=n {
        let p = circle(seq as usize);
        quiet
            .send_copy(PoseSample::new(
                seq,
                monotonic_now_ns(),
                p,
                IDENTITY_QUATERNION,
            ))
            .expect("send");
    }
    wake.notify_with_custom_event_id(EventId::new(EVENT_ID_POSE))
        .expect("notify");
    let mut received = Vec::new();
    let last = wait_until(
        ANSWER,
        "the estimate of the last pose",
        &mut service,
        || {
            while let Some(e) = client.output.try_receive().expect("receive") {
                received.push(e);
            }
            received.last().filter(|e| e.pose_sequence == n).copied()
        },
    );
    assert!(last.is_ok());
    assert_eq!(
        received.len() as u64 + last.skipped_poses,
        n,
        "every pose is either estimated or counted as skipped: {received:?}"
    );
    assert!(
        last.skipped_poses >= 1,
        "poses queued together: only the newest is estimated"
    );
}

#[test]
fn service_killed_and_restarted_while_a_publisher_runs_recovers() {
    let inst = instance("service_restart");
    let names = ServiceNames::new(&inst);
    let scene = Scene::default_scene();
    let t_min_n = 80.0;
    // The publisher: a thread of this process, 1 kHz along the circle, T_min 80 N sent once
    // before any service exists (a restarted service gets it from the history).
    let stop = Arc::new(AtomicBool::new(false));
    let published = Arc::new(AtomicU64::new(0));
    let publisher = {
        let (names, stop, published) = (names.clone(), stop.clone(), published.clone());
        std::thread::spawn(move || {
            let node = create_node("cablevib-test-publisher").expect("node");
            let input = PoseInput::open(&node, &names).expect("input");
            input
                .send_t_min(&TminSetpoint::uniform(1, monotonic_now_ns(), t_min_n))
                .expect("T_min");
            let mut seq = 0u64;
            let start = Instant::now();
            while !stop.load(Ordering::Relaxed) && start.elapsed() < Duration::from_secs(60) {
                seq += 1;
                let p = circle(seq as usize);
                input
                    .send_pose(&PoseSample::new(
                        seq,
                        monotonic_now_ns(),
                        p,
                        IDENTITY_QUATERNION,
                    ))
                    .expect("send");
                published.store(seq, Ordering::Relaxed);
                std::thread::sleep(Duration::from_millis(1));
            }
        })
    };
    struct StopOnDrop(Arc<AtomicBool>);
    impl Drop for StopOnDrop {
        fn drop(&mut self) {
            self.0.store(true, Ordering::Relaxed);
        }
    }
    let _stop_guard = StopOnDrop(stop.clone());

    let node = create_node("cablevib-test-controller").expect("node");
    let output = EstimateOutput::open(&node, &names).expect("output");
    let reference = |seq: u64| {
        let mut est = Estimator::realtime(&scene).expect("estimator");
        *est.update(
            &pose_at(circle(seq as usize), IDENTITY_QUATERNION),
            Tmin::Uniform(t_min_n),
        )
    };
    let scene_default = |seq: u64| {
        let mut est = Estimator::realtime(&scene).expect("estimator");
        *est.update(
            &pose_at(circle(seq as usize), IDENTITY_QUATERNION),
            Tmin::Scene,
        )
    };

    let mut last_seq = 0;
    for round in 0..2 {
        let started_ns = monotonic_now_ns();
        let mut service = spawn_service(&inst, WaitMode::Spin);
        // The first estimate of this service instance: cold start, T_min from the history.
        let first = wait_until(
            TIMEOUT,
            "an estimate of the new service",
            &mut service,
            || {
                while let Some(e) = output.try_receive().expect("receive") {
                    if e.receive_timestamp_ns > started_ns {
                        return Some(e);
                    }
                }
                None
            },
        );
        assert!(first.pose_sequence > last_seq, "round {round}: fresh pose");
        let want = reference(first.pose_sequence);
        assert_same(
            &first,
            &want,
            &format!("round {round}: first estimate (T_min 80 N)"),
        );
        let other = scene_default(first.pose_sequence);
        assert_ne!(
            bits(other.f1_hz),
            bits(want.f1_hz),
            "T_min must matter for this check to mean something"
        );
        // It keeps up with the publisher.
        let target = published.load(Ordering::Relaxed) + 200;
        let e = wait_until(TIMEOUT, "estimates to keep coming", &mut service, || {
            let mut newest = None;
            while let Some(e) = output.try_receive().expect("receive") {
                newest = Some(e);
            }
            newest.filter(|e| e.pose_sequence >= target)
        });
        assert!(e.is_ok(), "{e:?}");
        last_seq = e.pose_sequence;
        if round == 0 {
            service.kill9();
            // Nothing is answered while no service runs.
            std::thread::sleep(Duration::from_millis(100));
            while output.try_receive().expect("receive").is_some() {}
            std::thread::sleep(Duration::from_millis(50));
            assert!(output.try_receive().expect("receive").is_none());
        }
    }
    stop.store(true, Ordering::Relaxed);
    publisher.join().expect("publisher thread");
}

#[test]
fn publishers_and_controllers_killed_and_restarted_recover() {
    let inst = instance("peer_restart");
    let mut service = spawn_service(&inst, WaitMode::Event);
    let names = ServiceNames::new(&inst);
    let node = create_node("cablevib-test-watch").expect("node");
    let output = EstimateOutput::open(&node, &names).expect("output");
    wait_until(TIMEOUT, "the service", &mut service, || {
        output.service_connected().then_some(())
    });
    // More rounds than a service has publisher slots (4): dead ports must be cleaned up.
    for round in 1..=6u64 {
        let base = round * 1_000_000;
        let mut publisher = spawn_helper("publisher", &inst, base);
        let e = wait_until(
            TIMEOUT,
            &format!("an estimate of publisher {round}"),
            &mut service,
            || {
                publisher.assert_running();
                let mut hit = None;
                while let Some(e) = output.try_receive().expect("receive") {
                    if e.pose_sequence > base + 5 && e.pose_sequence < base + 1_000_000 {
                        hit = Some(e);
                    }
                }
                hit
            },
        );
        assert!(e.is_ok(), "round {round}: {e:?}");
        publisher.kill9();
    }
    // Controllers (estimate subscriber + margin client) killed and restarted while a
    // publisher runs.
    let mut publisher = spawn_helper("publisher", &inst, 9_000_000);
    for round in 1..=4 {
        let mut controller = spawn_helper("controller", &inst, 0);
        let mut answers = 0;
        let end = Instant::now() + TIMEOUT;
        while answers < 20 {
            assert!(Instant::now() < end, "controller {round}: too few answers");
            publisher.assert_running();
            service.assert_running();
            let Some(line) = controller.next_line(Duration::from_millis(100)) else {
                controller.assert_running();
                continue;
            };
            // "estimate <sequence> <status> margin <status>"
            if line.starts_with("estimate ") {
                assert!(line.ends_with("ok margin ok"), "controller {round}: {line}");
                answers += 1;
            }
        }
        controller.kill9();
    }
    publisher.kill9();
    service.assert_running();
}

/// A peer built against another schema: same service name, another payload type.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, ZeroCopySend)]
#[type_name("cablevib::PoseSample::v0")]
struct OldPose {
    sequence: u64,
    position_m: [f64; 3],
}

#[test]
fn a_peer_with_another_layout_gets_a_clear_error() {
    // The old peer came first: the service refuses to start, and says why.
    let inst = instance("layout_old_first");
    let names = ServiceNames::new(&inst);
    let node = create_node("cablevib-test-old-peer").expect("node");
    let _old = node
        .service_builder(&names.pose.as_str().try_into().unwrap())
        .publish_subscribe::<OldPose>()
        .open_or_create()
        .expect("old pose service");
    let mut service = spawn_service(&inst, WaitMode::Event);
    let status = service.wait_exit(TIMEOUT);
    assert!(!status.success(), "the service must refuse to run");
    let log = service.stderr();
    assert!(log.contains("incompatible peer"), "{log}");
    assert!(
        log.contains("`cablevib::PoseSample::v0` (32 bytes, align 8)"),
        "{log}"
    );
    assert!(
        log.contains(&format!(
            "`cablevib::PoseSample::v{SCHEMA_VERSION}` (80 bytes, align 8)"
        )),
        "{log}"
    );
    assert!(log.contains("rebuild the other peer"), "{log}");

    // The service came first: the old peer is refused, with the same explanation.
    let inst = instance("layout_service_first");
    let names = ServiceNames::new(&inst);
    let client = Client::new(&inst);
    let mut service = spawn_service(&inst, WaitMode::Event);
    client.wait_for(&mut service);
    let err = open_pubsub::<cablevib_ipc::TminSetpoint>(&node, &names.pose, T_MIN_SETTINGS)
        .expect_err("another payload on the pose service");
    let text = err.to_string();
    assert!(text.contains("incompatible peer"), "{text}");
    assert!(
        text.contains(&format!(
            "carries payload `cablevib::PoseSample::v{SCHEMA_VERSION}`"
        )),
        "{text}"
    );
    assert!(node
        .service_builder(&names.pose.as_str().try_into().unwrap())
        .publish_subscribe::<OldPose>()
        .open()
        .is_err());
    service.assert_running();
}

#[test]
fn sigterm_and_sigint_stop_the_service_cleanly() {
    for (mode, sig, name) in [
        (WaitMode::Spin, libc::SIGTERM, "SIGTERM"),
        (WaitMode::Event, libc::SIGINT, "SIGINT"),
    ] {
        let inst = instance(&format!("signal_{}", mode.as_str()));
        let mut client = Client::new(&inst);
        let mut service = spawn_service(&inst, mode);
        client.wait_for(&mut service);
        assert!(client.estimate(circle(1), IDENTITY_QUATERNION).is_ok());
        service.signal(sig);
        let status = service.wait_exit(TIMEOUT);
        assert!(status.success(), "{mode}: {name} → {status}");
        let log = service.stderr();
        assert!(log.contains("stopped (signal): 1 cycles"), "{mode}: {log}");
    }
}

#[test]
fn max_cycles_and_bad_options() {
    let inst = instance("max_cycles");
    let mut client = Client::new(&inst);
    let mut cmd = Command::new(BIN);
    cmd.args([
        "serve",
        "--instance",
        &inst,
        "--wait",
        "event",
        "--max-cycles",
        "3",
    ]);
    let mut service = Proc::spawn("cablevib serve --max-cycles 3", cmd);
    client.wait_for(&mut service);
    // A second service for the same instance refuses to start (two would answer every pose).
    let mut second = spawn_service(&inst, WaitMode::Event);
    assert!(!second.wait_exit(TIMEOUT).success());
    assert!(
        second
            .stderr()
            .contains("another cablevib service already serves"),
        "{}",
        second.stderr()
    );
    for k in 0..3 {
        assert!(client.estimate(circle(k), IDENTITY_QUATERNION).is_ok());
    }
    assert!(service.wait_exit(TIMEOUT).success());

    let out = Command::new(BIN)
        .args(["serve", "--scene", "/nonexistent/scene.toml"])
        .output()
        .expect("run");
    assert!(!out.status.success());
    assert!(!String::from_utf8_lossy(&out.stderr).is_empty());
}

// ---------------------------------------------------------------------------------------------
// Helper processes (this binary re-executed by the tests above)
// ---------------------------------------------------------------------------------------------

fn helper_env(name: &str) -> Option<(String, u64)> {
    (std::env::var(HELPER_ENV).ok()? == name).then(|| {
        let instance = std::env::var(INSTANCE_ENV).expect("instance");
        let base = std::env::var(SEQ_BASE_ENV)
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(0);
        (instance, base)
    })
}

#[test]
#[ignore = "a helper process of publishers_and_controllers_killed_and_restarted_recover"]
fn helper_publisher() {
    let Some((instance, base)) = helper_env("publisher") else {
        return;
    };
    let names = ServiceNames::new(&instance);
    let node = create_node("cablevib-test-helper-publisher").expect("node");
    let input = PoseInput::open(&node, &names).expect("input");
    let trajectory = Trajectory::circle(&Scene::default_scene(), 4.0).expect("circle");
    let start = Instant::now();
    let mut k = 0u64;
    // Until killed (at most 60 s, so that an orphan never lingers).
    while start.elapsed() < Duration::from_secs(60) {
        k += 1;
        let p = trajectory.position_at(k as f64 * 1e-3).expect("circle");
        input
            .send_pose(&PoseSample::new(
                base + k,
                monotonic_now_ns(),
                [p.x, p.y, p.z],
                IDENTITY_QUATERNION,
            ))
            .expect("send");
        std::thread::sleep(Duration::from_millis(1));
    }
}

#[test]
#[ignore = "a helper process of publishers_and_controllers_killed_and_restarted_recover"]
fn helper_controller() {
    use std::io::Write;
    let Some((instance, _)) = helper_env("controller") else {
        return;
    };
    let names = ServiceNames::new(&instance);
    let node = create_node("cablevib-test-helper-controller").expect("node");
    let output = EstimateOutput::open(&node, &names).expect("output");
    let margin = MarginClient::open(&node, &names).expect("margin");
    let start = Instant::now();
    let mut seq = 0;
    while start.elapsed() < Duration::from_secs(60) {
        let Some(e) = output
            .wait(WaitMode::Event, Duration::from_millis(100))
            .expect("receive")
        else {
            continue;
        };
        seq += 1;
        let r = margin
            .query(
                &MarginRequest::new(seq, monotonic_now_ns(), 8.0),
                WaitMode::Event,
                Duration::from_secs(1),
            )
            .expect("query");
        let margin_status = r.map_or("none".to_string(), |r| {
            cablevib_ipc::status_str(r.status).to_string()
        });
        println!(
            "estimate {} {} margin {margin_status}",
            e.pose_sequence,
            cablevib_ipc::status_str(e.status)
        );
        let _ = std::io::stdout().flush();
    }
}

// ---------------------------------------------------------------------------------------------
// Other programs of the same user (docs/security.md)
// ---------------------------------------------------------------------------------------------

#[test]
fn a_second_estimate_publisher_or_margin_server_is_refused() {
    let inst = instance("impostor");
    let names = ServiceNames::new(&inst);
    let mut client = Client::new(&inst);
    let mut service = spawn_service(&inst, WaitMode::Event);
    client.wait_for(&mut service);
    let node = create_node("cablevib-test-impostor").expect("node");
    let estimate = open_pubsub::<EstimateSample>(&node, &names.estimate, ESTIMATE_SETTINGS)
        .expect("the estimate service");
    assert!(
        estimate.publisher_builder().create().is_err(),
        "a second estimate publisher must not be created"
    );
    let margin = open_margin(&node, &names.margin).expect("the margin service");
    assert!(
        margin.server_builder().create().is_err(),
        "a second margin server must not be created"
    );
    // The real service still answers.
    assert!(client.estimate(circle(1), IDENTITY_QUATERNION).is_ok());
    service.assert_running();
}

/// `cablevib serve` on instance `inst` exits with an error whose log contains `message`.
fn assert_serve_refuses(inst: &str, message: &str) {
    let mut service = spawn_service(inst, WaitMode::Event);
    let status = service.wait_exit(TIMEOUT);
    let log = service.stderr();
    assert!(!status.success(), "the service must refuse to run: {log}");
    assert!(log.contains(message), "expected `{message}` in: {log}");
}

fn iox_name(name: &str) -> ServiceName {
    ServiceName::new(name).expect("service name")
}

#[test]
fn services_pre_created_with_other_limits_make_serve_refuse() {
    let node = create_node("cablevib-test-hostile").expect("node");

    // Pose buffer 1 (our limits otherwise): the newest pose would still win, but a hostile
    // creator chose it; refused.
    let inst = instance("hostile_pose_buffer");
    let names = ServiceNames::new(&inst);
    let _pose = hostile_pubsub::<PoseSample>(&node, &names.pose, MAX_PUBLISHERS, 1, false);
    assert_serve_refuses(
        &inst,
        &format!(
            "service \"{}\" exists with subscriber_max_buffer_size = 1, expected {}",
            names.pose, POSE_SETTINGS.buffer
        ),
    );

    // Pose buffer right, no safe overflow: publishers would block or drop the newest pose.
    let inst = instance("hostile_pose_overflow");
    let names = ServiceNames::new(&inst);
    let _pose = hostile_pubsub::<PoseSample>(
        &node,
        &names.pose,
        MAX_PUBLISHERS,
        POSE_SETTINGS.buffer,
        false,
    );
    assert_serve_refuses(
        &inst,
        &format!(
            "service \"{}\" exists with safe_overflow = false, expected true",
            names.pose
        ),
    );

    // Estimate service admitting 4 publishers: room for impostors.
    let inst = instance("hostile_estimate");
    let names = ServiceNames::new(&inst);
    let _estimate =
        hostile_pubsub::<EstimateSample>(&node, &names.estimate, 4, ESTIMATE_SETTINGS.buffer, true);
    assert_serve_refuses(
        &inst,
        &format!(
            "service \"{}\" exists with max_publishers = 4, expected 1",
            names.estimate
        ),
    );

    // Margin service admitting 2 servers: a second one could answer in the service's name.
    let inst = instance("hostile_margin");
    let names = ServiceNames::new(&inst);
    let _margin = node
        .service_builder(&iox_name(&names.margin))
        .request_response::<MarginRequest, cablevib_ipc::MarginResponse>()
        .max_servers(2)
        .max_clients(MAX_CLIENTS)
        .max_nodes(MAX_NODES)
        .create()
        .expect("hostile margin service");
    assert_serve_refuses(
        &inst,
        &format!(
            "service \"{}\" exists with max_servers = 2, expected 1",
            names.margin
        ),
    );
}

/// A publish-subscribe service carrying `M` created the way another program might: our
/// subscriber and node limits, history 0, and the given publishers, buffer and overflow.
fn hostile_pubsub<M: cablevib_ipc::Message>(
    node: &Node<ipc::Service>,
    name: &str,
    max_publishers: usize,
    buffer: usize,
    safe_overflow: bool,
) -> iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, M, ()> {
    node.service_builder(&iox_name(name))
        .publish_subscribe::<M>()
        .max_publishers(max_publishers)
        .max_subscribers(MAX_SUBSCRIBERS)
        .max_nodes(MAX_NODES)
        .subscriber_max_buffer_size(buffer)
        .history_size(0)
        .enable_safe_overflow(safe_overflow)
        .create()
        .expect("pre-created service")
}

/// The dead nodes named `name`.
fn dead_nodes(name: &str) -> Vec<iceoryx2::node::DeadNodeView<ipc::Service>> {
    let mut dead = Vec::new();
    Node::<ipc::Service>::list(load_iceoryx2_config(), |state| {
        if let NodeState::Dead(view) = state {
            if view
                .details()
                .as_ref()
                .is_some_and(|d| d.name().as_str() == name)
            {
                dead.push(view);
            }
        }
        CallbackProgression::Continue
    })
    .expect("list nodes");
    dead
}

#[test]
fn serve_cleans_only_dead_cablevib_nodes() {
    let inst = instance("foreign_node");
    let foreign = format!("othervendor-{}", std::process::id());
    let own = format!("cablevib-test-dead-{}", std::process::id());
    let mut helper = spawn_helper("nodes", &inst, 0);
    let end = Instant::now() + TIMEOUT;
    while !helper
        .next_line(Duration::from_millis(100))
        .is_some_and(|l| l.ends_with("nodes ready"))
    {
        helper.assert_running();
        assert!(Instant::now() < end, "the helper's nodes did not come up");
    }
    helper.kill9();
    // (The dead cablevib node may already be cleaned by a service of a test running beside.)
    assert_eq!(dead_nodes(&foreign).len(), 1, "the foreign node is dead");

    let mut client = Client::new(&inst);
    let mut service = spawn_service(&inst, WaitMode::Event);
    client.wait_for(&mut service);
    assert!(client.estimate(circle(1), IDENTITY_QUATERNION).is_ok());
    let foreign_left = dead_nodes(&foreign);
    let own_left = dead_nodes(&own).len();
    // Tidy up before asserting, so that a failure leaves nothing behind.
    for view in &foreign_left {
        let _ = view.clone().try_remove_stale_resources();
    }
    assert_eq!(
        foreign_left.len(),
        1,
        "the dead node of another application must be left alone"
    );
    assert_eq!(own_left, 0, "the dead cablevib node must be cleaned up");
    service.assert_running();
}

#[test]
#[ignore = "a helper process of serve_cleans_only_dead_cablevib_nodes"]
fn helper_nodes() {
    use std::io::Write;
    if helper_env("nodes").is_none() {
        return;
    }
    let parent = std::os::unix::process::parent_id();
    // Another application's node, made the way it would make it (iceoryx2's defaults).
    let foreign = NodeBuilder::new()
        .name(&NodeName::new(&format!("othervendor-{parent}")).expect("name"))
        .create::<ipc::Service>()
        .expect("foreign node");
    let own = create_node(&format!("cablevib-test-dead-{parent}")).expect("node");
    println!("nodes ready");
    let _ = std::io::stdout().flush();
    // Until killed (at most 60 s, so that an orphan never lingers).
    std::thread::sleep(Duration::from_secs(60));
    drop((foreign, own));
}
