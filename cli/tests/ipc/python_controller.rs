//! Python peers over iceoryx2, and the service attributes every peer reads.
//!
//! - `ipc-schema/python/cablevib_ipc.py` (the ctypes mirror) has the Rust layout: its
//!   `check_layout.py` compares `ctypes.sizeof`, alignment, type names, every field's offset,
//!   size and element type, and the constants with a JSON export of
//!   `cablevib_ipc::layout::ALL_LAYOUTS` written here;
//! - `examples/python/controller.py` (the file docs/service.md runs) against `cablevib serve` as a
//!   separate process, with poses published from this test: estimates arrive with status ok
//!   and the f1 of the library's `Estimator` for the same pose, margin answers arrive;
//! - `controller.py --hold-f1` holds f1 at a fixed pose with T_min set-points (none of the
//!   estimates after its first answer below the requirement);
//! - a service carrying another schema-version attribute: the Python controller exits with a
//!   one-line error, the Rust ports refuse it;
//! - a Rust client reads the attributes `cablevib serve` defined (scene, cable model, ...).
//!
//! The Python tests create a venv under `target/` and pip-install pinned versions
//! (`iceoryx2==0.10.0` and its pinned dependency `flatbuffers==25.12.19`); they need python3
//! with the venv module and PyPI. Every child process is killed by a guard when a test fails;
//! every wait is bounded.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use cablevib::estimator::Estimator;
use cablevib::estimator::Tmin;
use cablevib::kinematics::Pose;
use cablevib::scene::Scene;
use cablevib_ipc::layout::ALL_LAYOUTS;
use cablevib_ipc::{
    monotonic_now_ns, EstimateSample, MarginRequest, MarginResponse, PoseSample, ServiceNames,
    ATTR_ELEMENTS_PER_CABLE, ATTR_ELEMENT_MODEL, ATTR_SCENE, ATTR_SCHEMA_VERSION, ATTR_UNITS,
    IDENTITY_QUATERNION, MAX_CABLES, MAX_STIFFNESS_DIM, SCHEMA_VERSION, UNITS,
};
use cablevib_service::ports::{
    create_node, EstimateOutput, Ipc, MarginClient, PoseInput, ServiceAttributes, ServicePorts,
};
use cablevib_service::ServiceError;
use iceoryx2::prelude::*;
use iceoryx2::service::attribute::{AttributeKey, AttributeValue};
use serde_json::{json, Value};

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");
/// Pinned Python packages: iceoryx2-python of the crate's version, and the flatbuffers version
/// that iceoryx2 0.10.0 itself pins (installed with `--no-deps`: exactly these two).
const PIP_PACKAGES: [&str; 2] = ["iceoryx2==0.10.0", "flatbuffers==25.12.19"];
/// Longest wait for a child process (venv creation and pip install included).
const TIMEOUT: Duration = Duration::from_secs(300);
/// How long the Python controller runs, s.
const CONTROLLER_SECONDS: &str = "2";
/// Required frequency of the margin requests, Hz.
const REQUIRED_HZ: f64 = 8.0;
/// The service runs the same `Estimator` on the same pose (bit-for-bit equality is shown by
/// cli/tests/ipc/ipc_service.rs) and Python's JSON writes floats with the shortest round-trip repr, so
/// any difference is a defect; 1e-9 Hz only leaves room for the decimal text.
const F1_TOL_HZ: f64 = 1e-9;

fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

fn work_dir() -> PathBuf {
    let dir = root().join("target/python-controller");
    std::fs::create_dir_all(&dir).expect("create target/python-controller");
    dir
}

/// Runs `cmd` to completion within [`TIMEOUT`] (killed after it), with its output.
fn run(what: &str, cmd: &mut Command) -> Output {
    let mut child = Guard::spawn(what, cmd);
    let deadline = Instant::now() + TIMEOUT;
    while child.0.try_wait().expect("try_wait").is_none() {
        assert!(
            Instant::now() < deadline,
            "{what} did not finish within {TIMEOUT:?}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let mut out = Output {
        status: child.0.wait().expect("wait"),
        stdout: Vec::new(),
        stderr: Vec::new(),
    };
    child
        .0
        .stdout
        .take()
        .unwrap()
        .read_to_end(&mut out.stdout)
        .unwrap();
    child
        .0
        .stderr
        .take()
        .unwrap()
        .read_to_end(&mut out.stderr)
        .unwrap();
    out
}

/// The venv's python, created and provisioned once per test binary.
fn venv_python() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(|| {
        let venv = work_dir().join("venv");
        let python = venv.join("bin/python");
        if !python.exists() {
            let out = run(
                "python3 -m venv",
                Command::new("python3").arg("-m").arg("venv").arg(&venv),
            );
            assert!(
                out.status.success(),
                "python3 -m venv: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        let out = run(
            "pip install",
            Command::new(&python)
                .args([
                    "-m",
                    "pip",
                    "install",
                    "-q",
                    "--disable-pip-version-check",
                    "--no-deps",
                ])
                .args(PIP_PACKAGES),
        );
        assert!(
            out.status.success(),
            "pip install {PIP_PACKAGES:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        python
    })
}

/// A child process, SIGKILLed when dropped (output piped, read after it ends).
struct Guard(Child);

impl Guard {
    fn spawn(what: &str, cmd: &mut Command) -> Guard {
        let child = cmd
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {what}: {e}"));
        Guard(child)
    }

    /// SIGINT, then up to 10 s for a clean exit (SIGKILL on drop otherwise).
    fn interrupt(&mut self) {
        // SAFETY: kill(2) on our own child's pid; no memory is involved.
        unsafe { libc::kill(self.0.id() as i32, libc::SIGINT) };
        let deadline = Instant::now() + Duration::from_secs(10);
        while self.0.try_wait().expect("try_wait").is_none() && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for Guard {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn instance(test: &str) -> String {
    format!("cvpy_{}_{test}", std::process::id())
}

/// The layout table and constants as JSON, for `check_layout.py`.
fn layout_json() -> Value {
    let structs: Vec<Value> = ALL_LAYOUTS
        .iter()
        .map(|l| {
            let fields: Vec<Value> = l
                .fields
                .iter()
                .map(|f| {
                    json!({
                        "name": f.name, "offset": f.offset, "size": f.size,
                        "elem": f.elem, "len": f.len,
                    })
                })
                .collect();
            json!({
                "rust_name": l.rust_name, "type_name": l.type_name,
                "size": l.size, "align": l.align, "fields": fields,
            })
        })
        .collect();
    json!({
        "structs": structs,
        "constants": {
            "SCHEMA_VERSION": SCHEMA_VERSION,
            "MAX_CABLES": MAX_CABLES,
            "MAX_STIFFNESS_DIM": MAX_STIFFNESS_DIM,
            "ATTR_SCHEMA_VERSION": ATTR_SCHEMA_VERSION,
            "ATTR_SCENE": ATTR_SCENE,
            "UNITS": UNITS,
        },
    })
}

#[test]
fn ctypes_mirror_has_the_rust_layout() {
    let path = work_dir().join("layout.json");
    std::fs::write(&path, layout_json().to_string()).expect("write layout.json");
    let out = run(
        "check_layout.py",
        Command::new(venv_python())
            .arg(root().join("ipc-schema/python/check_layout.py"))
            .arg(&path),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.starts_with(&format!("layout ok: {} structs", ALL_LAYOUTS.len())),
        "{stdout}"
    );
}

/// The pose every test publishes: a point of the paper's circle.
fn test_pose(scene: &Scene) -> [f64; 3] {
    let p = cablevib::trajectory::circle_pose(scene, 700, 4.0).position_m;
    [p.x, p.y, p.z]
}

/// Publishes `position` at ~1 kHz from its own thread (iceoryx2 ports stay in the thread that
/// made them) until `stop` is set.
fn publish_poses(
    inst: &str,
    position: [f64; 3],
    stop: Arc<AtomicBool>,
) -> std::thread::JoinHandle<u64> {
    let names = ServiceNames::new(inst);
    std::thread::spawn(move || {
        let node = create_node("cablevib-test-poses").expect("node");
        let input = PoseInput::open(&node, &names).expect("pose input");
        let mut sequence = 0;
        while !stop.load(Ordering::Acquire) {
            sequence += 1;
            let pose = PoseSample::new(sequence, monotonic_now_ns(), position, IDENTITY_QUATERNION);
            input.send_pose(&pose).expect("send pose");
            std::thread::sleep(Duration::from_millis(1));
        }
        sequence
    })
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= F1_TOL_HZ
}

#[test]
fn python_controller_gets_estimates_and_margins() {
    let python = venv_python();
    let inst = instance("run");
    let scene = Scene::load("spatial-paper").expect("scene");
    let position = test_pose(&scene);
    let pose = Pose {
        position_m: position.into(),
        orientation_wxyz: IDENTITY_QUATERNION,
    };
    let want = *Estimator::new(&scene)
        .expect("estimator")
        .update(&pose, Tmin::Scene);
    assert!(want.is_ok(), "{:?}", want.error);

    let mut service = Guard::spawn(
        "cablevib serve",
        Command::new(BIN)
            .args(["serve", "--scene", "spatial-paper", "--instance", &inst])
            .args([
                "--wait",
                "event",
                "--stats-period-s",
                "0",
                "--max-cycles",
                "200000",
            ]),
    );
    let stop = Arc::new(AtomicBool::new(false));
    let publisher = publish_poses(&inst, position, stop.clone());
    let out = run(
        "controller.py",
        Command::new(python)
            .env_remove("IOX2_LOG_LEVEL")
            .arg(root().join("examples/python/controller.py"))
            .args([
                "--instance",
                &inst,
                "--seconds",
                CONTROLLER_SECONDS,
                "--json",
            ])
            .args(["--connect-timeout-s", "60"])
            .args(["--required-hz", &REQUIRED_HZ.to_string()]),
    );
    stop.store(true, Ordering::Release);
    let poses = publisher.join().expect("publisher");
    service.interrupt();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "controller.py failed:\n{stdout}\n{stderr}"
    );
    let s: Value = serde_json::from_str(stdout.lines().last().unwrap_or(""))
        .unwrap_or_else(|e| panic!("{e}: {stdout}"));
    let lines: Vec<&str> = stdout.lines().collect();
    eprintln!(
        "{poses} poses sent; controller.py said:\n{}",
        lines[..lines.len().saturating_sub(1)].join("\n")
    );

    let estimates = s["estimates"].as_u64().unwrap();
    assert!(estimates > 0, "{s}");
    assert_eq!(
        s["statuses"],
        json!({"ok": estimates}),
        "every estimate of a valid pose is ok"
    );
    for key in ["f1_min_hz", "f1_max_hz"] {
        let f1 = s[key].as_f64().unwrap();
        assert!(
            close(f1, want.f1_hz),
            "{key} {f1} Hz vs the library's {} Hz",
            want.f1_hz
        );
    }
    let margins = s["margins"].as_u64().unwrap();
    assert!(margins > 0, "no margin answer: {s}");
    assert_eq!(s["margin_statuses"], json!({"ok": margins}));
    let m = &s["last_margin"];
    assert!(close(m["f1_hz"].as_f64().unwrap(), want.f1_hz), "{m}");
    assert!(
        close(m["margin_hz"].as_f64().unwrap(), want.f1_hz - REQUIRED_HZ),
        "{m}"
    );
    let a = &s["attributes"];
    assert_eq!(a[ATTR_SCHEMA_VERSION], SCHEMA_VERSION.to_string());
    assert_eq!(a[ATTR_SCENE], scene.name.as_str());
    assert_eq!(a[ATTR_ELEMENT_MODEL], scene.model.element.as_str());
    assert_eq!(
        a[ATTR_ELEMENTS_PER_CABLE],
        scene.model.elements_per_cable.to_string()
    );
    assert_eq!(a[ATTR_UNITS], UNITS);
}

/// `controller.py --hold-f1` against `cablevib serve` at a fixed pose whose f1 at the scene's
/// T_min is 0.3 Hz below the requirement: the Python hold (`examples/python/hold_f1.py`)
/// publishes set-points on the service's T_min topic, the service applies them, and no ok
/// estimate of a pose taken after the first answer is below the requirement. Independent of
/// the service: the library's `Estimator` at the highest set-point published meets the
/// requirement (f1 at a uniform T_min, cold start).
#[test]
fn python_controller_holds_f1() {
    let python = venv_python();
    let inst = instance("hold");
    let scene = Scene::load("spatial-paper").expect("scene");
    let position = test_pose(&scene);
    let pose = Pose {
        position_m: position.into(),
        orientation_wxyz: IDENTITY_QUATERNION,
    };
    let mut estimator = Estimator::new(&scene).expect("estimator");
    let at_scene = estimator.update(&pose, Tmin::Scene).f1_hz;
    let hold_hz = at_scene + 0.3;

    let mut service = Guard::spawn(
        "cablevib serve",
        Command::new(BIN)
            .args(["serve", "--scene", "spatial-paper", "--instance", &inst])
            .args(["--wait", "event", "--stats-period-s", "0"])
            .args(["--max-cycles", "200000"]),
    );
    let stop = Arc::new(AtomicBool::new(false));
    let publisher = publish_poses(&inst, position, stop.clone());
    let out = run(
        "controller.py --hold-f1",
        Command::new(python)
            .env_remove("IOX2_LOG_LEVEL")
            .arg(root().join("examples/python/controller.py"))
            .args([
                "--instance",
                &inst,
                "--seconds",
                CONTROLLER_SECONDS,
                "--json",
            ])
            .args(["--connect-timeout-s", "60"])
            .args(["--hold-f1", &hold_hz.to_string()])
            .args(["--hold-floor-n", &scene.t_min_n.to_string()])
            .args(["--hold-ceiling-n", &scene.t_max_n.to_string()]),
    );
    stop.store(true, Ordering::Release);
    publisher.join().expect("publisher");
    service.interrupt();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "controller.py failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s: Value = serde_json::from_str(stdout.lines().last().unwrap_or(""))
        .unwrap_or_else(|e| panic!("{e}: {stdout}"));
    let h = &s["hold"];
    assert!(h["setpoints"].as_u64().unwrap() >= 1, "{s}");
    assert!(h["counted"].as_u64().unwrap() > 0, "{s}");
    assert_eq!(h["below"].as_u64(), Some(0), "{s}");
    assert!(s["f1_max_hz"].as_f64().unwrap() >= hold_hz, "{s}");
    let highest = h["setpoint_range_n"][1].as_f64().unwrap();
    assert!(highest > scene.t_min_n && highest <= scene.t_max_n, "{s}");
    estimator.reset();
    let e = estimator.update(&pose, Tmin::Uniform(highest));
    assert!(
        e.is_ok() && e.f1_hz >= hold_hz,
        "{} Hz at {highest} N",
        e.f1_hz
    );
}

/// Creates the estimate and margin services of `inst` as a program of schema version "999"
/// would label them (payload types of this build, so only the attribute differs).
fn create_foreign_services(node: &Node<Ipc>, inst: &str) -> impl Sized {
    let names = ServiceNames::new(inst);
    let spec = AttributeSpecifier::new()
        .define(
            &AttributeKey::try_from(ATTR_SCHEMA_VERSION).unwrap(),
            &AttributeValue::try_from("999").unwrap(),
        )
        .unwrap();
    let estimate = node
        .service_builder(&names.estimate.as_str().try_into().unwrap())
        .publish_subscribe::<EstimateSample>()
        .create_with_attributes(&spec)
        .expect("foreign estimate service");
    let margin = node
        .service_builder(&names.margin.as_str().try_into().unwrap())
        .request_response::<MarginRequest, MarginResponse>()
        .create_with_attributes(&spec)
        .expect("foreign margin service");
    (estimate, margin)
}

#[test]
fn another_schema_version_is_refused_with_one_line() {
    let python = venv_python();
    let inst = instance("foreign");
    let node = create_node("cablevib-test-foreign").expect("node");
    let _services = create_foreign_services(&node, &inst);

    let out = run(
        "controller.py",
        Command::new(python)
            .env_remove("IOX2_LOG_LEVEL")
            .arg(root().join("examples/python/controller.py"))
            .args([
                "--instance",
                &inst,
                "--seconds",
                "1",
                "--connect-timeout-s",
                "5",
            ]),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "one line: {stderr}");
    assert!(
        stderr.contains("\"999\"") && stderr.contains(&format!("schema v{SCHEMA_VERSION}")),
        "{stderr}"
    );

    let names = ServiceNames::new(&inst);
    match EstimateOutput::open(&node, &names) {
        Err(ServiceError::IncompatiblePeer(msg)) => assert!(msg.contains("\"999\""), "{msg}"),
        other => panic!("expected IncompatiblePeer, got {:?}", other.err()),
    }
}

#[test]
fn a_rust_client_reads_the_service_attributes() {
    let inst = instance("attributes");
    let names = ServiceNames::new(&inst);
    let scene = Scene::load("planar-paper").expect("scene");
    let service_node = create_node("cablevib-test-service").expect("node");
    let _ports = ServicePorts::open_with_attributes(
        &service_node,
        &names,
        &ServiceAttributes::of_scene(&scene),
    )
    .expect("service ports");

    let node = create_node("cablevib-test-client").expect("node");
    let output = EstimateOutput::open(&node, &names).expect("estimate output");
    let margin = MarginClient::open(&node, &names).expect("margin client");
    let input = PoseInput::open(&node, &names).expect("pose input");
    for (what, a) in [
        ("estimate", output.attributes()),
        ("margin", margin.attributes()),
        ("pose", input.attributes()),
    ] {
        assert_eq!(
            a.get(ATTR_SCHEMA_VERSION),
            Some(SCHEMA_VERSION.to_string().as_str()),
            "{what}: {a}"
        );
        assert_eq!(a.get(ATTR_UNITS), Some(UNITS), "{what}");
        assert_eq!(a.get(ATTR_SCENE), Some(scene.name.as_str()), "{what}");
        assert_eq!(
            a.get(ATTR_ELEMENT_MODEL),
            Some(scene.model.element.as_str()),
            "{what}"
        );
        assert_eq!(
            a.get(ATTR_ELEMENTS_PER_CABLE),
            Some(scene.model.elements_per_cable.to_string().as_str()),
            "{what}"
        );
        a.check_schema(what, true).expect("same schema");
    }
}
