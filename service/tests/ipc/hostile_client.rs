//! A hostile but fair client: the service (`service::server::spawn_thread`, in this process so
//! that its memory is this process's) receives 10⁵ mixed messages over real iceoryx2 — valid
//! poses, NaN/Inf coordinates, non-unit / NaN / zero quaternions, positions outside the frame,
//! T_min set-points that are valid, zero, subnormal, negative, NaN, infinite, above T_max,
//! per-cable with bad counts or values, and random bytes written into `zeroed()` poses and
//! set-points (every bit pattern is a valid value of their u32/u64/f64 fields).
//!
//! Paced: each pose is sent and its estimate (echoing its sequence and timestamp) awaited
//! before the next message, so no pose is skipped and the set-points in force are known.
//! Checked:
//!
//! - every pose is answered, bit for bit, by what a library `Estimator` fed the same cycle
//!   bounds gives; the bounds are modelled here from the service's documented rule, not from
//!   its functions: the newest set-point since the last pose is applied to the next pose
//!   (per-cable values for the first `per_cable_count` cables, its uniform value past them,
//!   all refused when the count exceeds `MAX_CABLES`); a refused one (not finite, below the
//!   smallest normal, above the cable's T_max) is reported on that one estimate and the
//!   previous bounds stay in force;
//! - the status of every bad input, in the estimator's order of checks (`RejectedInput`):
//!   non-finite pose → `InvalidInput`, non-unit quaternion (tolerance 1e-6) →
//!   `NonUnitQuaternion`, a rotation on the point-mass scene (vector part > 1e-3 of the norm:
//!   the valid poses are identity-oriented, the rotated ones refused) → `InvalidInput`,
//!   refused set-point → `TminOutOfRange` (a position outside the
//!   anchors' box is no input error: the tension distribution answers it, and the reference
//!   estimator's answer is compared);
//! - no panic: the service thread returns `Ok` with every pose estimated, none skipped, no
//!   iceoryx2 error, and every set-point received except the oldest of runs longer than the
//!   subscriber's queue (4);
//! - resident memory flat between the end of the warm-up (10 % of the messages) and the end
//!   (bound below).
//!
//! `CABLEVIB_HOSTILE_MESSAGES` changes the message count (default 10⁵).

use cablevib::estimator::Tmin;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use cablevib::estimator::{Estimate, Estimator};
use cablevib::kinematics::Pose;
use cablevib::scene::Scene;
use cablevib_ipc::{
    monotonic_now_ns, EstimateSample, PoseSample, ServiceNames, StatusCode, TminSetpoint,
    MAX_CABLES,
};
use cablevib_service::ports::{create_node, EstimateOutput, PoseInput};
use cablevib_service::server::{spawn_thread, ServerConfig};
use cablevib_service::WaitMode;
use cablevib_testkit::Rng;
use nalgebra::Vector3;

/// Longest wait for one estimate or for the service's ports.
const ANSWER: Duration = Duration::from_secs(10);
/// Queue depth of the service's T_min subscriber (`T_MIN_SETTINGS` in `service::ports`).
const T_MIN_BUFFER: u64 = 4;
/// The estimator's quaternion tolerance (`EstimatorParams::quaternion_tol`).
const QUATERNION_TOL: f64 = 1e-6;
/// The identity's tolerance on a point mass (`kinematics::QUATERNION_INPUT_TOL`, the command
/// line's): a vector part of at most this fraction of the quaternion's norm.
const IDENTITY_TOL: f64 = 1e-3;
/// Resident-memory growth allowed after the warm-up, bytes, besides the compute-time rings
/// (see `rss_bound`): iceoryx2 maps its segments when the ports open, the estimators and
/// rings are allocated before the first message, and the client keeps only counters; what is
/// left is allocator and page-cache noise (thread stacks, the odd heap page), well under
/// 1 MiB. A leak of one allocation per message (10⁵ × ≥ 16 B) exceeds it.
const RSS_SLACK: u64 = 1 << 20;

fn rss_bytes() -> u64 {
    let pages = std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1)?.parse::<u64>().ok())
        .expect("/proc/self/statm");
    // SAFETY: sysconf has no preconditions.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) }.max(4096) as u64;
    pages * page
}

/// Random bytes over all of `value` (a `#[repr(C)]` message of u32/u64/f64 fields only, no
/// padding: every bit pattern is a valid value).
fn randomize<T: Copy>(value: &mut T, rng: &mut Rng) {
    // SAFETY: see above; the slice covers exactly `value`.
    let bytes = unsafe {
        std::slice::from_raw_parts_mut(value as *mut T as *mut u8, std::mem::size_of::<T>())
    };
    for b in bytes {
        *b = rng.next_u64() as u8;
    }
}

/// The values a hostile sender puts in a T_min field.
fn bad_t_min(rng: &mut Rng, t_max: f64) -> f64 {
    match rng.next_u64() % 7 {
        0 => 0.0,
        1 => -0.0,
        2 => f64::MIN_POSITIVE / 2.0, // subnormal
        3 => -rng.range(1e-3, 1e3),
        4 => f64::NAN,
        5 => f64::INFINITY,
        _ => t_max * (1.0 + rng.range(1e-12, 1.0)),
    }
}

/// A sampled message and what it is (for the counts printed at the end).
enum Msg {
    Pose(PoseSample, &'static str),
    Tmin(TminSetpoint, &'static str),
}

struct Gen<'a> {
    rng: Rng,
    scene: &'a Scene,
    t_max: [f64; MAX_CABLES],
    frame: (Vector3<f64>, Vector3<f64>),
    k: usize,
}

impl Gen<'_> {
    /// A pose near the circle trajectory, identity-oriented (the scene's end-effector is a
    /// point mass, which has no orientation): [1, 0, 0, 0], sometimes −1 or a rotation
    /// within the identity's tolerance.
    fn valid_pose(&mut self) -> ([f64; 3], [f64; 4]) {
        self.k += 1;
        let c = cablevib::trajectory::circle_pose(self.scene, 7 * self.k, 4.0).position_m;
        let r = &mut self.rng;
        let p = [
            c.x + r.range(-0.02, 0.02),
            c.y + r.range(-0.02, 0.02),
            c.z + r.range(-0.02, 0.02),
        ];
        let q = match r.next_u64() % 4 {
            0 => [-1.0, 0.0, 0.0, 0.0],
            1 => rotation(r, 0.0, 0.9 * IDENTITY_TOL),
            _ => [1.0, 0.0, 0.0, 0.0],
        };
        (p, q)
    }

    fn next(&mut self) -> Msg {
        let u = self.rng.next();
        let (p, q) = self.valid_pose();
        let pose = |p, q| PoseSample::new(0, monotonic_now_ns(), p, q);
        let r = &mut self.rng;
        let t_max = self.t_max[0];
        let t0 = self.scene.t_min_n;
        match u {
            u if u < 0.36 => Msg::Pose(pose(p, q), "valid pose"),
            u if u < 0.40 => {
                // A rotation past the identity's tolerance (the rotated poses that used to
                // be "valid"): refused on a point mass.
                let q = rotation(r, 1.1 * IDENTITY_TOL, 0.05);
                Msg::Pose(pose(p, q), "rotated pose on a point mass")
            }
            u if u < 0.45 => {
                let mut p = p;
                let bad = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];
                p[(r.next_u64() % 3) as usize] = bad[(r.next_u64() % 3) as usize];
                Msg::Pose(pose(p, q), "NaN/Inf position")
            }
            u if u < 0.50 => {
                // Norm off by 1e-5 .. 1 (well past the 1e-6 tolerance), or the zero quaternion.
                let s = if r.chance(0.1) {
                    0.0
                } else if r.chance(0.5) {
                    1.0 + r.range(1e-5, 1.0)
                } else {
                    1.0 - r.range(1e-5, 1.0)
                };
                Msg::Pose(pose(p, q.map(|x| x * s)), "non-unit quaternion")
            }
            u if u < 0.53 => {
                let mut q = q;
                q[(r.next_u64() % 4) as usize] = if r.chance(0.5) {
                    f64::NAN
                } else {
                    f64::INFINITY
                };
                Msg::Pose(pose(p, q), "NaN/Inf quaternion")
            }
            u if u < 0.58 => {
                // Past a face of the anchors' box along an axis that is not flat.
                let (lo, hi) = self.frame;
                let axes: Vec<usize> = (0..3).filter(|&i| hi[i] - lo[i] > 1e-6).collect();
                let i = axes[(r.next_u64() as usize) % axes.len()];
                let mut p = p;
                let d = if r.chance(0.1) {
                    1e300
                } else {
                    r.range(1e-3, 2.0)
                };
                p[i] = if r.chance(0.5) { hi[i] + d } else { lo[i] - d };
                Msg::Pose(pose(p, q), "position outside the frame")
            }
            u if u < 0.65 => {
                let mut s = PoseSample::zeroed();
                randomize(&mut s, r);
                Msg::Pose(s, "random-byte pose")
            }
            u if u < 0.75 => {
                // Valid: mostly near the scene's T_min, sometimes at the extremes of the rule.
                let v = match r.next_u64() % 10 {
                    0 => f64::MIN_POSITIVE,
                    1 => t_max,
                    2 => r.range(1e-9, 1.0),
                    _ => t0 * r.range(0.5, 2.0),
                };
                Msg::Tmin(TminSetpoint::uniform(0, 0, v), "valid uniform T_min")
            }
            u if u < 0.83 => Msg::Tmin(
                TminSetpoint::uniform(0, 0, bad_t_min(r, t_max)),
                "refused uniform T_min",
            ),
            u if u < 0.88 => {
                let count = 1 + (r.next_u64() as usize) % MAX_CABLES;
                let v: Vec<f64> = (0..count).map(|_| t0 * r.range(0.5, 2.0)).collect();
                let s = TminSetpoint::per_cable(0, 0, t0 * r.range(0.5, 2.0), &v).unwrap();
                Msg::Tmin(s, "valid per-cable T_min")
            }
            u if u < 0.91 => {
                let mut s = TminSetpoint::per_cable(0, 0, t0, &[t0; MAX_CABLES]).unwrap();
                s.per_cable_count = match r.next_u64() % 3 {
                    0 => MAX_CABLES as u32 + 1,
                    1 => u32::MAX,
                    _ => MAX_CABLES as u32 + 1 + (r.next_u64() % 1000) as u32,
                };
                Msg::Tmin(s, "per-cable T_min, bad count")
            }
            u if u < 0.95 => {
                let count = 1 + (r.next_u64() as usize) % MAX_CABLES;
                let mut v: Vec<f64> = (0..count).map(|_| t0 * r.range(0.5, 2.0)).collect();
                let i = (r.next_u64() as usize) % count;
                v[i] = bad_t_min(r, t_max);
                let s = TminSetpoint::per_cable(0, 0, t0, &v).unwrap();
                Msg::Tmin(s, "per-cable T_min, bad value")
            }
            _ => {
                let mut s = TminSetpoint::zeroed();
                randomize(&mut s, r);
                if r.chance(0.5) {
                    // A count in range, so the random values themselves are judged.
                    s.per_cable_count %= MAX_CABLES as u32 + 1;
                }
                Msg::Tmin(s, "random-byte T_min")
            }
        }
    }
}

/// A unit quaternion of a random axis whose vector part has a norm in [lo, hi].
fn rotation(r: &mut Rng, lo: f64, hi: f64) -> [f64; 4] {
    let v = r.unit() * r.range(lo, hi);
    [(1.0 - v.norm_squared()).sqrt(), v.x, v.y, v.z]
}

/// The service's rule, restated: the lower bounds (N) a set-point gives each of the `n`
/// cables, and whether they are accepted. More per-cable values than cables, or a value in
/// use (the uniform one included) that is not finite or is negative, refuses the whole
/// set-point (docs/security.md: `TminSetpoint::is_well_formed` and the cable count).
fn setpoint_rule(s: &TminSetpoint, t_max: &[f64]) -> ([f64; MAX_CABLES], bool) {
    let mut b = [f64::NAN; MAX_CABLES];
    let count = s.per_cable_count as usize;
    let in_use = |v: f64| v.is_finite() && v >= 0.0;
    let well_formed = count <= t_max.len()
        && in_use(s.t_min_n)
        && s.per_cable_t_min_n[..count].iter().all(|&v| in_use(v));
    if well_formed {
        for (i, v) in b.iter_mut().enumerate().take(t_max.len()) {
            *v = if i < s.per_cable_count as usize {
                s.per_cable_t_min_n[i]
            } else {
                s.t_min_n
            };
        }
    }
    let ok = b
        .iter()
        .zip(t_max)
        .all(|(&lo, &hi)| lo.is_finite() && lo >= f64::MIN_POSITIVE && lo <= hi);
    (b, ok)
}

/// The status an input must get before any computation, in the estimator's order of checks
/// (None: the pose passes them and is estimated). The scene's end-effector is a point mass:
/// an orientation other than the identity (vector part over `IDENTITY_TOL` of the norm) is
/// refused, as `analyze` refuses `--orientation` there.
fn input_status(p: &PoseSample, bounds_ok: bool) -> Option<StatusCode> {
    let [w, x, y, z] = p.orientation_wxyz;
    let v = (x * x + y * y + z * z).sqrt();
    if !p.is_finite() {
        Some(StatusCode::InvalidInput)
    } else if !p.has_unit_quaternion(QUATERNION_TOL) {
        Some(StatusCode::NonUnitQuaternion)
    } else if v > IDENTITY_TOL * (w * w + v * v).sqrt() {
        Some(StatusCode::InvalidInput)
    } else if !bounds_ok {
        Some(StatusCode::TminOutOfRange)
    } else {
        None
    }
}

fn bits(x: f64) -> u64 {
    x.to_bits()
}

/// The estimate carries exactly what the library computed.
fn assert_same(got: &EstimateSample, want: &Estimate, what: &dyn Fn() -> String) {
    assert_eq!(got.status_code(), Some(want.status), "{}", what());
    assert_eq!(got.cable_count as usize, want.n_cables, "{}", what());
    for (i, (a, b)) in got.tensions().iter().zip(want.tensions()).enumerate() {
        assert_eq!(bits(*a), bits(*b), "{}: tension {i}: {a} vs {b}", what());
    }
    assert_eq!(bits(got.f1_hz), bits(want.f1_hz), "{}: f1", what());
    // The wire's codes for the end-effector mode: NaN and EE_MODE_AGE_UNKNOWN when absent.
    let (want_hz, want_age) = match want.ee_mode {
        Some(m) => (m.frequency_hz, m.age_cycles),
        None => (f64::NAN, cablevib_ipc::EE_MODE_AGE_UNKNOWN),
    };
    assert_eq!(bits(got.ee_mode_hz), bits(want_hz), "{}", what());
    assert_eq!(got.ee_mode_age_cycles, want_age, "{}", what());
    for r in 0..3 {
        for c in 0..3 {
            assert_eq!(
                bits(got.stiffness_at(r, c).unwrap()),
                bits(want.stiffness.translational_n_m()[(r, c)]),
                "{}: stiffness ({r}, {c})",
                what()
            );
        }
    }
    assert_eq!(
        bits(got.eigen_residual),
        bits(want.eigen_residual),
        "{}",
        what()
    );
    assert_eq!(got.eigen_evaluations, want.eigen_evaluations, "{}", what());
    assert_eq!(
        got.tension_iterations,
        want.tension_iterations,
        "{}",
        what()
    );
}

#[test]
fn hostile_client_gets_exact_answers_and_the_service_stays_flat() {
    let _serial = crate::one_server_at_a_time();
    let total: usize = std::env::var("CABLEVIB_HOSTILE_MESSAGES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(100_000);
    let warm_up = total / 10;
    let inst = format!("cvtest_{}_hostile", std::process::id());
    let names = ServiceNames::new(&inst);
    let node = create_node("cablevib-hostile-client").expect("node");
    let input = PoseInput::open(&node, &names).expect("pose input");
    let output = EstimateOutput::open(&node, &names).expect("estimate output");

    let scene = Scene::default_scene();
    let stop = Arc::new(AtomicBool::new(false));
    let cfg = ServerConfig {
        instance: inst.clone(),
        wait: WaitMode::Event,
        stats_period: None,
        node_name: "cablevib-hostile-serve".into(),
        handle_signals: false,
        ..ServerConfig::default()
    };
    let service = spawn_thread(scene.clone(), cfg, stop.clone()).expect("service thread");
    let end = Instant::now() + ANSWER;
    while !(input.service_connected() && output.service_connected()) {
        assert!(!service.is_finished(), "the service thread ended at start");
        assert!(Instant::now() < end, "the service's ports did not open");
        std::thread::sleep(Duration::from_millis(1));
    }

    let mut reference = Estimator::realtime(&scene).expect("estimator");
    let n = scene.n_cables();
    let mut t_max = [f64::INFINITY; MAX_CABLES];
    for (i, t) in t_max.iter_mut().enumerate().take(n) {
        *t = scene.cable_t_max_n(i);
    }
    let mut gen = Gen {
        rng: Rng(0x05ee_d405_711e),
        scene: &scene,
        t_max,
        frame: scene.frame_bounds_m(),
        k: 0,
    };
    let mut in_force = reference.default_t_min_n();
    let mut pending: Option<TminSetpoint> = None;
    // Set-points sent since the last pose, and the fewest the service can have received.
    let (mut run, mut received_at_least) = (0u64, 0u64);
    let (mut poses, mut setpoints) = (0u64, 0u64);
    let mut kinds: Vec<(&'static str, u64)> = Vec::new();
    let mut statuses = [0u64; 16];
    let mut rss_warm = 0;
    let (mut cycles_warm, mut t_warm) = (0, Instant::now());
    let t_start = Instant::now();

    for m in 0..total {
        if m == warm_up {
            rss_warm = rss_bytes();
            cycles_warm = poses;
            t_warm = Instant::now();
        }
        let msg = if m + 1 == total {
            // The last message is a pose, so every set-point before it has been taken.
            let (p, q) = gen.valid_pose();
            Msg::Pose(PoseSample::new(0, monotonic_now_ns(), p, q), "valid pose")
        } else {
            gen.next()
        };
        let kind = match &msg {
            Msg::Pose(_, k) | Msg::Tmin(_, k) => *k,
        };
        match kinds.iter_mut().find(|(k, _)| *k == kind) {
            Some((_, c)) => *c += 1,
            None => kinds.push((kind, 1)),
        }
        match msg {
            Msg::Tmin(mut s, _) => {
                setpoints += 1;
                run += 1;
                s.sequence = setpoints;
                input.send_t_min(&s).expect("send T_min");
                pending = Some(s);
            }
            Msg::Pose(mut p, kind) => {
                poses += 1;
                received_at_least += run.min(T_MIN_BUFFER);
                run = 0;
                p.sequence = poses; // the answer is matched on it (and the timestamp)
                let (bounds, ok) = match pending.take() {
                    Some(s) => {
                        let (b, ok) = setpoint_rule(&s, &t_max[..n]);
                        if ok {
                            in_force = b;
                        }
                        (b, ok)
                    }
                    None => (in_force, true),
                };
                input.send_pose(&p).expect("send pose");
                // Paced: nothing else is in flight, so the next estimate must answer this pose.
                let got = output
                    .wait(WaitMode::Event, ANSWER)
                    .expect("receive")
                    .unwrap_or_else(|| {
                        assert!(!service.is_finished(), "the service thread ended");
                        panic!("no estimate for message {m} ({kind}) within {ANSWER:?}")
                    });
                assert!(
                    got.answers(&p),
                    "message {m}: an estimate for pose {} while pose {} is awaited",
                    got.pose_sequence,
                    p.sequence
                );
                let pose = Pose {
                    position_m: Vector3::from(p.position_m),
                    orientation_wxyz: p.orientation_wxyz,
                };
                let want = reference.update(&pose, Tmin::PerCable(&bounds[..n]));
                let what = || format!("message {m} ({kind}: {p:?}, bounds {:?})", &bounds[..n]);
                if let Some(status) = input_status(&p, ok) {
                    assert_eq!(got.status_code(), Some(status), "{}", what());
                }
                assert_same(&got, want, &what);
                assert_eq!(got.skipped_poses, 0, "{}", what());
                statuses[(got.status as usize).min(15)] += 1;
            }
        }
    }
    let elapsed = t_start.elapsed();
    let rss_end = rss_bytes();

    stop.store(true, Ordering::Release);
    let report = service
        .join()
        .expect("the service thread panicked")
        .expect("the service returned an error");
    assert_eq!(report.cycles, poses, "every pose estimated");
    assert_eq!(report.skipped_poses, 0);
    // A run of set-points longer than the subscriber's buffer loses its oldest ones unless the
    // service drains in between (by design: only the newest counts, and the bit-for-bit
    // answers above show it is the one applied).
    assert!(
        (received_at_least..=setpoints).contains(&report.t_min_setpoints),
        "{} set-points received, {received_at_least}..={setpoints} expected",
        report.t_min_setpoints
    );
    assert_eq!(report.ipc_errors, 0);

    // The service's two compute-time rings (`PERIOD_RING` and `RUN_RING` entries of 8 bytes,
    // zero-initialised, so their pages become resident as they fill: 16 B per cycle at most)
    // are the only memory it touches in proportion to the cycles, by design and bounded.
    let cycles_after = poses - cycles_warm;
    let rss_bound = RSS_SLACK + 16 * cycles_after;
    let growth = rss_end.saturating_sub(rss_warm);
    kinds.sort();
    for (k, c) in &kinds {
        println!("{c:>7} {k}");
    }
    let named: Vec<String> = statuses
        .iter()
        .enumerate()
        .filter(|(_, &c)| c > 0)
        .map(|(s, c)| match StatusCode::from_u32(s as u32) {
            Some(code) => format!("{code:?} {c}"),
            None => format!("code {s} {c}"),
        })
        .collect();
    println!(
        "{total} messages ({poses} poses, {setpoints} T_min set-points) in {:.1} s \
         ({:.1} s after the warm-up); statuses: {}; RSS {} KiB after the warm-up, {} KiB at \
         the end, growth {} KiB (the rings' share at most {} KiB; bound {} KiB)",
        elapsed.as_secs_f64(),
        t_warm.elapsed().as_secs_f64(),
        named.join(", "),
        rss_warm / 1024,
        rss_end / 1024,
        growth / 1024,
        16 * cycles_after / 1024,
        rss_bound / 1024
    );
    assert!(
        growth <= rss_bound,
        "resident memory grew by {growth} B after the warm-up (bound {rss_bound} B)"
    );
}
