//! Hard cases of the estimator's input: bad values (T_min out of range, NaN / Inf
//! positions, non-unit quaternions, poses far outside or at an anchor) get a status with no
//! numbers and leave nothing stale; poses approaching an anchor converge and are refused
//! below the minimum cable length; the poses of a suspended robot (every anchor at one
//! height) are in its workspace.
//!
//! Every test prints what it measured (`cargo test --release --test hard_cases inputs -- --nocapture`);
//! docs/hard-cases.md lists the cases, the expected behaviour and these tests. The shared
//! checks and their tolerance (real-time against the dense reference) are in
//! testkit/src/hard_cases.rs.

use cablevib::estimator::Tmin;
use cablevib::estimator::{reference_analysis, Estimator, ReferenceError, Status};
use cablevib::kinematics::Pose;
use cablevib::modal::lambda_to_hz;
use cablevib::scene::{ElementKind, Scene, MAX_CABLES, T_MIN_FLOOR_N};
use cablevib::tension::{clarabel_reference_bounds, TensionError};
use cablevib_testkit::ee_hz;
use cablevib_testkit::hard_cases::*;
use cablevib_testkit::rel;
use nalgebra::Vector3;

// ---------------------------------------------------------------------------------------
// Bad inputs
// ---------------------------------------------------------------------------------------

/// T_min > T_max, zero, subnormal, negative, NaN or infinite T_min, NaN / Inf positions, non-unit
/// quaternions: each a status with no numbers, and the next valid input is answered
/// exactly as a fresh estimator answers it (nothing stale, nothing lost).
#[test]
fn bad_inputs_get_a_status_and_the_next_valid_input_is_exact() {
    let s = Scene::default_scene();
    let good = Vector3::new(0.3, 0.2, 1.0);
    let reference = realtime(&s, good, s.t_min_n);
    assert_sane("reference", &reference, &s, s.t_min_n);
    let q = |w: f64, x: f64| Pose {
        position_m: good,
        orientation_wxyz: [w, x, 0.0, 0.0],
    };
    let bad: Vec<(&str, Pose, f64, Status)> = vec![
        (
            "t_min > t_max",
            Pose::at(good),
            s.t_max_n + 1.0,
            Status::TminOutOfRange,
        ),
        ("t_min < 0", Pose::at(good), -1.0, Status::TminOutOfRange),
        ("t_min 0", Pose::at(good), 0.0, Status::TminOutOfRange),
        ("t_min -0", Pose::at(good), -0.0, Status::TminOutOfRange),
        (
            "t_min subnormal",
            Pose::at(good),
            f64::MIN_POSITIVE / 2.0,
            Status::TminOutOfRange,
        ),
        (
            "t_min NaN",
            Pose::at(good),
            f64::NAN,
            Status::TminOutOfRange,
        ),
        (
            "t_min inf",
            Pose::at(good),
            f64::INFINITY,
            Status::TminOutOfRange,
        ),
        (
            "x NaN",
            Pose::at(Vector3::new(f64::NAN, 0.2, 1.0)),
            60.0,
            Status::InvalidInput,
        ),
        (
            "z inf",
            Pose::at(Vector3::new(0.3, 0.2, f64::INFINITY)),
            60.0,
            Status::InvalidInput,
        ),
        (
            "z -inf",
            Pose::at(Vector3::new(0.3, 0.2, f64::NEG_INFINITY)),
            60.0,
            Status::InvalidInput,
        ),
        ("q NaN", q(f64::NAN, 0.0), 60.0, Status::InvalidInput),
        ("q zero", q(0.0, 0.0), 60.0, Status::NonUnitQuaternion),
        ("q 2", q(2.0, 0.0), 60.0, Status::NonUnitQuaternion),
        (
            "q 1+1e-3",
            q(1.0 + 1e-3, 0.0),
            60.0,
            Status::NonUnitQuaternion,
        ),
        (
            "outside",
            Pose::at(Vector3::new(9.0, 0.2, 1.0)),
            60.0,
            Status::TensionInfeasible,
        ),
        (
            "huge",
            Pose::at(Vector3::new(1e300, 0.2, 1.0)),
            60.0,
            Status::TensionInfeasible,
        ),
        (
            "at anchor",
            Pose::at(s.cables[5].anchor_m),
            60.0,
            Status::OutsideWorkspace,
        ),
    ];
    let mut est = Estimator::new(&s).unwrap();
    for (name, pose, t_min, want) in bad {
        // Warm the estimator on a nearby pose first, so a stale value would be available.
        est.update(&Pose::at(good + Vector3::new(1e-3, 0.0, 0.0)), Tmin::Scene);
        let e = *est.update(&pose, Tmin::Uniform(t_min));
        assert_eq!(e.status, want, "{name}: {:?}", e.error);
        assert_no_numbers(name, &e);
        let next = *est.update(&Pose::at(good), Tmin::Scene);
        assert_sane(name, &next, &s, s.t_min_n);
        assert!(
            rel(next.f1_hz, reference.f1_hz) <= 1e-10
                && rel(ee_hz(&next), ee_hz(&reference)) <= 1e-10,
            "{name}: next valid answer {} / {} vs fresh {} / {}",
            next.f1_hz,
            ee_hz(&next),
            reference.f1_hz,
            ee_hz(&reference)
        );
        for (a, b) in next.tensions().iter().zip(reference.tensions()) {
            assert!((a - b).abs() <= 1e-9 * b, "{name}: tensions {a} vs {b}");
        }
    }
}

/// The smallest accepted T_min ([`T_MIN_FLOOR_N`], the smallest normal f64) is accepted by
/// the estimator (no `TminOutOfRange`), and the next T_min below it is not.
#[test]
fn t_min_floor_is_accepted_and_below_it_is_not() {
    let s = Scene::default_scene();
    let mut est = Estimator::new(&s).unwrap();
    let p = Pose::at(s.ee_position_m);
    let below = f64::from_bits(T_MIN_FLOOR_N.to_bits() - 1);
    let e = *est.update(&p, Tmin::Uniform(below));
    assert_eq!(e.status, Status::TminOutOfRange, "{below:e} N");
    let e = *est.update(&p, Tmin::Uniform(T_MIN_FLOOR_N));
    assert_ne!(e.status, Status::TminOutOfRange, "{:?}", e.error);
    println!("t_min = {T_MIN_FLOOR_N:e} N: {:?}", e.status);
}

/// One rule for an orientation on a point-mass end-effector, which has none (the command
/// line refuses `--orientation` there): the estimator's input check refuses a quaternion
/// whose vector part exceeds `QUATERNION_INPUT_TOL` (1e-3) of its norm, with `InvalidInput`
/// and no numbers, in `update` and in the inverse query; the identity (either sign, or within
/// the tolerance) gives the identity's answer bit for bit; a rigid end-effector takes the
/// rotation. Before, `Estimator` and the service estimated the rotated pose as the identity.
/// The service (service/tests/ipc/hostile_client.rs, rotated poses among 10⁵ messages) and Python
/// (python/tests/test_estimator.py) refuse the same poses.
#[test]
fn a_rotation_on_a_point_mass_is_refused_and_the_identity_accepted() {
    use cablevib::kinematics::QUATERNION_INPUT_TOL;
    let s = Scene::default_scene();
    assert!(!s.rigid);
    let mut est = Estimator::new(&s).unwrap();
    let at = |q: [f64; 4]| Pose {
        position_m: s.ee_position_m,
        orientation_wxyz: q,
    };
    let tilt = |v: f64| [(1.0 - v * v).sqrt(), 0.0, v, 0.0];
    let plain = *est.update(&at([1.0, 0.0, 0.0, 0.0]), Tmin::Scene);
    assert!(plain.is_ok());
    for q in [
        tilt(1.1 * QUATERNION_INPUT_TOL),
        tilt(0.5),
        [0.0, 0.0, 0.0, 1.0],
    ] {
        let e = *est.update(&at(q), Tmin::Scene);
        assert_eq!(e.status, Status::InvalidInput, "{q:?}");
        assert!(e.f1_hz.is_nan(), "{q:?}");
        let msg = e.error.unwrap().to_string();
        assert!(msg.contains("point-mass end-effector"), "{msg}");
        let inv = est.t_min_for_f1(&at(q), 5.0).unwrap_err().to_string();
        assert!(inv.contains("point-mass end-effector"), "{inv}");
    }
    for q in [[-1.0, 0.0, 0.0, 0.0], tilt(0.9 * QUATERNION_INPUT_TOL)] {
        let mut fresh = Estimator::new(&s).unwrap();
        let e = *fresh.update(&at(q), Tmin::Scene);
        assert_eq!(e.f1_hz.to_bits(), plain.f1_hz.to_bits(), "{q:?}");
    }
    let rigid = Scene::from_path(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/box_6dof.toml"
    )))
    .unwrap();
    let mut r = Estimator::new(&rigid).unwrap();
    let e = *r.update(
        &Pose {
            position_m: rigid.ee_position_m,
            orientation_wxyz: tilt(0.05),
        },
        Tmin::Scene,
    );
    assert!(e.is_ok(), "{:?}", e.error);
}

// ---------------------------------------------------------------------------------------
// Per-cable lower bounds
// ---------------------------------------------------------------------------------------

/// Per-cable T_min [10, 100, 10, 100, ...] on the spatial robot: every tension is at least
/// its own cable's bound, the tensions equal the Clarabel reference with the same per-cable
/// bounds to 1e-9 relative, and f1 is below the answer with 100 N on every cable (the old
/// collapse to the largest value). Equal per-cable values give the uniform update bit for
/// bit; a slice of the wrong length or with a zero is `TminOutOfRange`.
#[test]
fn per_cable_t_min_is_honoured_and_matches_the_reference() {
    let s = Scene::default_scene();
    let n = s.n_cables();
    let mut bounds = [10.0; MAX_CABLES];
    for (i, b) in bounds.iter_mut().enumerate().take(n) {
        if i % 2 == 1 {
            *b = 100.0;
        }
    }
    let lo = &bounds[..n];
    let mut est = Estimator::new(&s).unwrap();
    let mut collapsed = Estimator::new(&s).unwrap();
    for p in [
        s.ee_position_m,
        Vector3::new(0.3, 0.2, 1.0),
        Vector3::new(-0.4, 0.1, 1.3),
    ] {
        let pose = Pose::at(p);
        let e = *est.update(&pose, Tmin::PerCable(lo));
        assert!(e.is_ok(), "{p:?}: {:?}", e.error);
        let g = geometry(&s, &p);
        let w = s.wrench_n();
        let r =
            clarabel_reference_bounds(&g, &[w.x, w.y, w.z, 0.0, 0.0, 0.0], lo, &vec![s.t_max_n; n])
                .unwrap();
        for i in 0..n {
            let t = e.tensions()[i];
            assert!(
                t >= lo[i],
                "{p:?}: cable {i} at {t} N below its bound {} N",
                lo[i]
            );
            assert!(
                rel(t, r[i]) <= 1e-9,
                "{p:?}: cable {i}: {t} vs Clarabel {}",
                r[i]
            );
        }
        let old = *collapsed.update(&pose, Tmin::Uniform(100.0));
        assert!(old.is_ok());
        assert!(
            e.f1_hz < old.f1_hz,
            "{p:?}: per-cable f1 {} Hz not below the collapsed {} Hz",
            e.f1_hz,
            old.f1_hz
        );
        println!(
            "{p:?}: per-cable f1 {:.4} Hz (collapsed to 100 N: {:.4} Hz), tensions {:?}",
            e.f1_hz,
            old.f1_hz,
            e.tensions()
        );
    }
    // Equal per-cable values are the uniform update, bit for bit.
    let mut a = Estimator::new(&s).unwrap();
    let mut b = Estimator::new(&s).unwrap();
    for k in 0..50 {
        let pose = Pose::at(Vector3::new(0.01 * k as f64, 0.0, 1.2));
        let x = *a.update(&pose, Tmin::Uniform(70.0));
        let y = *b.update(&pose, Tmin::PerCable(&[70.0; MAX_CABLES][..n]));
        assert_eq!(x.f1_hz.to_bits(), y.f1_hz.to_bits(), "pose {k}");
        assert_eq!(x.tension_iterations, y.tension_iterations, "pose {k}");
        for (t, u) in x.tensions().iter().zip(y.tensions()) {
            assert_eq!(t.to_bits(), u.to_bits(), "pose {k}");
        }
    }
    // Refused like a bad uniform value.
    let pose = Pose::at(s.ee_position_m);
    let e = *est.update(&pose, Tmin::PerCable(&lo[..n - 1]));
    assert_eq!(e.status, Status::TminOutOfRange, "wrong length");
    let mut zero = bounds;
    zero[2] = 0.0;
    let e = *est.update(&pose, Tmin::PerCable(&zero[..n]));
    assert_eq!(e.status, Status::TminOutOfRange, "a zero bound");
    assert_no_numbers("a zero bound", &e);
}

/// A scene with per-cable bounds (`cables[i].t_min`, `.t_max`): the estimator uses them as
/// its default bounds, so every tension lies within its own cable's bounds.
#[test]
fn scene_per_cable_bounds_are_the_default() {
    let text = cablevib::scene::DEFAULT_SCENE_TOML;
    let mut n_seen = 0;
    let mut out = String::new();
    for line in text.lines() {
        out.push_str(line);
        out.push('\n');
        if line.trim_start().starts_with("anchor") {
            if n_seen % 2 == 1 {
                out.push_str("t_min = 100.0\n");
            }
            n_seen += 1;
        }
    }
    let s = Scene::from_toml_str(&out, "per-cable.toml").unwrap();
    assert!(s.has_per_cable_bounds(), "{out}");
    let n = s.n_cables();
    let mut est = Estimator::new(&s).unwrap();
    let defaults = est.default_t_min_n();
    let e = *est.update(&Pose::at(s.ee_position_m), Tmin::PerCable(&defaults[..n]));
    assert!(e.is_ok(), "{:?}", e.error);
    for i in 0..n {
        let t = e.tensions()[i];
        assert!(
            t >= s.cable_t_min_n(i) && t <= s.cable_t_max_n(i),
            "cable {i}: {t} N"
        );
    }
    assert!((0..n).any(|i| s.cable_t_min_n(i) == 100.0));
}

// ---------------------------------------------------------------------------------------
// Poses near an anchor, suspended robots
// ---------------------------------------------------------------------------------------

/// The end-effector approaching an anchor (cable length d → 0): a lower corner of the
/// spatial robot (tension-feasible all the way), the two vertical anchors of the
/// five-cable robot, and an upper corner of the spatial robot (tension-infeasible all the
/// way). Expected: the same status for every d ≥ 1e-6 m, ok numbers converging to a limit
/// (|f1(d) − f1(d/10)| ≤ d·f1 per metre), equal to dense where its accuracy allows; below
/// 1e-6 m (MIN_CABLE_LENGTH_M) OutsideWorkspace with no numbers, and the dense reference
/// refuses the pose too.
#[test]
fn poses_approaching_an_anchor() {
    let spatial = Scene::default_scene();
    let vert = vertical_scene("fem", 10);
    // (name, scene, anchor, direction of approach, expected status)
    type Case = (String, Scene, Vector3<f64>, Vector3<f64>, Status);
    let cases: Vec<Case> = vec![
        (
            "spatial lower corner".into(),
            spatial.clone(),
            spatial.cables[4].anchor_m,
            Vector3::new(-1.0, -1.0, 1.0).normalize(),
            Status::Ok,
        ),
        (
            "spatial upper corner".into(),
            spatial.clone(),
            spatial.cables[0].anchor_m,
            Vector3::new(-1.0, -1.0, -1.0).normalize(),
            Status::TensionInfeasible,
        ),
        (
            "vertical top anchor".into(),
            vert.clone(),
            vert.cables[0].anchor_m,
            -Vector3::z(),
            Status::Ok,
        ),
        (
            "vertical bottom anchor".into(),
            vert.clone(),
            vert.cables[1].anchor_m,
            Vector3::z(),
            Status::Ok,
        ),
    ];
    for (name, s0, anchor, dir, expect) in cases {
        for el in [ElementKind::Fem, ElementKind::Catenary] {
            let s = s0.with_model(el, 10);
            let mut prev: Option<(f64, f64)> = None;
            for d in [1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1.0001e-6] {
                let p = anchor + dir * d;
                let label = format!("{name} {} d {d:e}", el.as_str());
                let e = realtime(&s, p, s.t_min_n);
                assert_eq!(e.status, expect, "{label}: {:?}", e.error);
                if expect != Status::Ok {
                    assert_no_numbers(&label, &e);
                    let t = e.tensions();
                    assert!(
                        t.iter()
                            .all(|&x| x >= s.t_min_n - 1e-9 && x <= s.t_max_n + 1e-9),
                        "{label}: closest tensions {t:?} outside the bounds"
                    );
                    let r = reference_analysis(&s, &p, Tmin::Scene, false);
                    assert!(
                        matches!(
                            r,
                            Err(ReferenceError::Tension(TensionError::Infeasible { .. }))
                        ),
                        "{label}: dense {:?}",
                        r.map(|r| r.modes.lambda[0])
                    );
                    continue;
                }
                assert_sane(&label, &e, &s, s.t_min_n);
                if d >= 1e-3 {
                    let r = dense(&s, p, s.t_min_n);
                    assert_matches_dense(&label, &s, &e, &r);
                }
                if let Some((d0, f0)) = prev {
                    let jump = rel(e.f1_hz, f0);
                    assert!(
                        jump <= d0,
                        "{label}: f1 {} vs {f0} at d = {d0:e}: {jump:.2e}",
                        e.f1_hz
                    );
                }
                prev = Some((d, e.f1_hz));
            }
            for d in [0.9999e-6, 1e-9, 0.0] {
                let p = anchor + dir * d;
                let label = format!("{name} {} d {d:e}", el.as_str());
                let e = realtime(&s, p, s.t_min_n);
                assert_eq!(e.status, Status::OutsideWorkspace, "{label}: {:?}", e.error);
                assert_no_numbers(&label, &e);
                assert!(e.tensions().iter().all(|t| t.is_nan()), "{label}");
                assert!(
                    matches!(
                        reference_analysis(&s, &p, Tmin::Scene, false),
                        Err(ReferenceError::Kinematics(_))
                    ),
                    "{label}: dense accepted the pose"
                );
            }
        }
    }
}

/// A suspended robot (every anchor at one height, the end-effector hanging below: the
/// common overhead CDPR) is a valid scene; its default pose and the poses below the anchors
/// are tension-feasible and the dense reference analyses them. The real-time estimator must
/// answer them too, not refuse them as outside the anchors' (flat) bounding box.
#[test]
fn suspended_robot_poses_are_in_the_workspace() {
    let s = suspended_scene();
    let mut refused = Vec::new();
    for p in [
        s.ee_position_m,
        Vector3::new(0.3, -0.2, 1.2),
        Vector3::new(-0.5, 0.5, 0.5),
    ] {
        let r = dense(&s, p, s.t_min_n);
        let e = realtime(&s, p, s.t_min_n);
        if e.status == Status::Ok {
            assert_sane("suspended", &e, &s, s.t_min_n);
            assert_matches_dense(&format!("suspended {p:?}"), &s, &e, &r);
        } else {
            refused.push(format!(
                "{p:?}: {:?} ({}); dense f1 {:.6} Hz",
                e.status,
                e.error.map(|x| x.to_string()).unwrap_or_default(),
                lambda_to_hz(r.modes.lambda[0])
            ));
        }
    }
    assert!(
        refused.is_empty(),
        "feasible poses of the suspended robot refused:\n{}",
        refused.join("\n")
    );
}
