//! Hard cases of the sagged model, through the estimator, the library analysis
//! and the CLI rather than unit by unit:
//!
//! - `sag = false` is today's model bit for bit (the paper scenes, every element);
//! - γ → 0 equals the chord model to rounding (fed with EA' = EA(1 + T/EA) and
//!   μ' = μ/(1 + T/EA): the sagged model's reference is the unstretched cable, the chord
//!   model's the stretched chord), and the plain chord model to O(T/EA);
//! - a vertical cable (its anchor straight above the end-effector), against the
//!   independent reference (tests/py/sag_reference.py) and its nearly vertical neighbour;
//! - cables whose lowest point lies below both ends, and λ² above 1e4 (ok, finite);
//! - a slack pose: status `cable_slack` (wire code 11), NaN numbers, no panic, in the
//!   library and in `cablevib analyze` (one-line error, nonzero exit);
//! - a fuzz of random poses and T_min: every ok estimate finite, every other one a status
//!   with NaN numbers;
//! - the real-time path with sag allocates nothing per cycle along a circle (counting
//!   allocator), fem and continuous, on the heavy paper robot, fast-like and suspended-8.

use cablevib_testkit::ee_hz;
use cablevib_testkit::without_effects;

use cablevib::alloc_count::thread_allocations;
use cablevib::estimator::Tmin;
use cablevib::estimator::{Estimate, Estimator, Status};
use cablevib::kinematics::Pose;
use cablevib::scene::{ElementKind, Scene};
use cablevib::study::analysis::{analyze, AnalyzeOptions};
use cablevib::trajectory::{Circle, SAMPLE_PERIOD_S};
use cablevib_testkit::sag_cases::*;
use cablevib_testkit::sag_reference_py::{run_reference, scene_request, RefAnswer, LEVELS};
use cablevib_testkit::Rng;
use nalgebra::Vector3;
use serde_json::{json, Value};

const SPATIAL_TOML: &str = include_str!("../../../scenes/spatial_paper.toml");
const PLANAR_TOML: &str = include_str!("../../../scenes/planar_paper.toml");

/// The analysis JSON without its run times (the only fields that may differ run to run).
fn timeless_json(s: &Scene) -> String {
    let opts = AnalyzeOptions::default();
    let r = analyze(s, &opts).unwrap_or_else(|e| panic!("{}: {e}", s.name));
    let mut v = serde_json::to_value(&r).expect("json");
    let o = v.as_object_mut().expect("object");
    o.remove("solve_seconds");
    o.remove("dense_seconds");
    v.to_string()
}

/// The paper scenes without `[effects]` and with `[effects] sag = false` (as the files
/// say it) analyse to the same JSON, every number bit for bit (serde's shortest round-trip text), for every
/// element. (The paper tables themselves: tests/model/paper_tables.rs.)
#[test]
fn sag_false_is_bit_identical_to_no_effects_table() {
    for text in [SPATIAL_TOML, PLANAR_TOML] {
        assert!(text.contains("[effects]\nsag = false"));
        let plain = Scene::from_toml_str(&without_effects(text), "plain").expect("scene");
        let off = Scene::from_toml_str(text, "off").expect("scene");
        assert!(!plain.model.sag && !off.model.sag);
        for (el, n) in [
            (ElementKind::Fem, 40),
            (ElementKind::Catenary, 10),
            (ElementKind::Continuous, 1),
            (ElementKind::Massless, 1),
        ] {
            let (a, b) = (
                timeless_json(&plain.with_model(el, n)),
                timeless_json(&off.with_model(el, n)),
            );
            assert_eq!(a, b, "{} {el:?}", plain.name);
            assert!(a.contains("\"sag\":false") && !a.contains("irvine"), "{a}");
        }
    }
}

// ---------------------------------------------------------------------------------------
// γ → 0

/// The spatial paper robot with γ = 1e-12 N/m and sag on, against the chord model.
///
/// The sagged cable's sag is ~γL²/(8T) ≈ 1e-15 m and its end directions are the chord's to
/// ~γL/T ≈ 1e-14 rad, so: the tensions equal the chord model's to rounding (1e-12
/// relative: the QP's own rounding ~1e-13 with its conditioning). With EA' = EA(1 + T/EA)
/// and μ' = μ/(1 + T/EA) per cable (T its tension) the chord model is the same linear
/// problem, so the stiffness (relative to its largest entry) and f1..f3 (the end-effector
/// modes; the cables weigh 1e-13 of the end-effector) agree to rounding too (1e-10: the
/// sagged statics go through L0 = L/(1 + T/EA) and back, losing ~ε·EA/T ≈ 1e-12). Against
/// the plain chord model (EA, μ) the frequencies differ by O(T/EA) (≈ 2e-4 here: the axial
/// stiffness EA/L0 vs EA/L), bounded by max T/EA.
#[test]
fn vanishing_weight_is_the_chord_model() {
    let text = SPATIAL_TOML.replacen("weight_per_length = 0.251", "weight_per_length = 1e-12", 1);
    let chord = Scene::from_toml_str(&text, "light").expect("scene");
    let mut sag = chord.clone();
    sag.set_sag(true).expect("fem sags");
    for (el, n) in [(ElementKind::Fem, 40), (ElementKind::Continuous, 1)] {
        for p in [HEAVY_CENTRE_M, [0.3, 0.2, 1.25], [-0.4, 0.1, 0.9]] {
            let rs = analyze_at(&sag, p, el, n, 3);
            let rc = analyze_at(&chord, p, el, n, 3);
            let name = format!("{el:?} at {p:?}");
            assert!(rs.sag && !rc.sag);
            let dt = max_rel(&rs.tensions_n, &rc.tensions_n);
            assert!(dt <= 1e-12, "{name}: tensions {dt:e}");
            // The chord model fed with EA' and μ'.
            let mut fed = chord.clone();
            for (c, t) in fed.cables.iter_mut().zip(&rs.tensions_n) {
                let strain = t / c.ea_n();
                c.youngs_modulus_pa *= 1.0 + strain;
                c.mass_per_length_kg_m /= 1.0 + strain;
            }
            let rf = analyze_at(&fed, p, el, n, 3);
            let kmax = rf
                .stiffness_n_m
                .iter()
                .flatten()
                .fold(0.0f64, |m, x| m.max(x.abs()));
            let dk = rs
                .stiffness_n_m
                .iter()
                .flatten()
                .zip(rf.stiffness_n_m.iter().flatten())
                .map(|(a, b)| (a - b).abs() / kmax)
                .fold(0.0, f64::max);
            let df = max_rel(&rs.frequencies_hz, &rf.frequencies_hz);
            let df_plain = max_rel(&rs.frequencies_hz, &rc.frequencies_hz);
            let strain_max = rs
                .tensions_n
                .iter()
                .zip(&chord.cables)
                .map(|(t, c)| t / c.ea_n())
                .fold(0.0, f64::max);
            eprintln!(
                "{name}: tensions {dt:.1e}, fed chord: k {dk:.1e}, f {df:.1e}; plain chord f {df_plain:.1e} (T/EA ≤ {strain_max:.1e})"
            );
            assert!(dk <= 1e-10, "{name}: stiffness {dk:e}");
            assert!(df <= 1e-10, "{name}: f {df:e}");
            assert!(df_plain <= strain_max, "{name}: plain chord f {df_plain:e}");
        }
    }
}

// ---------------------------------------------------------------------------------------
// A vertical cable

/// suspended-8 with cable 4's anchor moved from the top frame's edge to its centre, right
/// above the pose (0, 0, 2) m: cable 4 hangs vertically there.
fn with_vertical_cable() -> Scene {
    let mut s = Scene::load("suspended-8").expect("scene");
    s.cables[4].anchor_m = Vector3::new(0.0, 0.0, 6.0);
    s
}

/// The vertical cable against the independent reference (which treats a cable with no
/// horizontal span on its own branch): the continuous model's f1..f6, principal
/// stiffness and tensions within 1e-6 of the reference's extrapolation (as in
/// tests/sag/vs_reference.rs: measured differences there ≤ 2e-9), fem at N = 160 within
/// 2e-4 (its c/N² discretisation error). And the pose 1e-7 m beside it (a nearly vertical
/// cable on the inclined branch) gives the same answer to 1e-5 (the geometry moves by
/// ~1e-7 of the lengths, and a vertical cable's out-of-plane basis is arbitrary only
/// within its exact degeneracy).
#[test]
fn a_vertical_cable_is_the_limit_of_inclined_ones() {
    let s = with_vertical_cable();
    let p = [0.0, 0.0, 2.0];
    let fem = analyze_at(&s, p, ElementKind::Fem, 160, 6);
    let cont = analyze_at(&s, p, ElementKind::Continuous, 1, 6);
    assert_eq!(
        cont.irvine_lambda2.as_ref().unwrap()[4],
        0.0,
        "vertical: no sag"
    );
    let l0 = cont.unstretched_length_m.clone().unwrap();
    let mut req = scene_request(&s, p);
    req.insert("unstretched_lengths_m".into(), json!(l0));
    req.insert("modes".into(), json!(8));
    req.insert("convergence_levels".into(), json!(LEVELS));
    let r = RefAnswer(run_reference(&Value::Object(req)));
    let f_ref = r.extrapolated("frequencies_hz");
    let k_ref = r.extrapolated("stiffness_principal_n_m");
    let d = [
        max_rel(&cont.frequencies_hz, &f_ref),
        max_rel(&principal_n_m(&cont), &k_ref),
        max_rel(&cont.tensions_n, &r.extrapolated("tension_ee_n")),
        max_rel(&fem.frequencies_hz, &f_ref),
        max_rel(&principal_n_m(&fem), &k_ref),
    ];
    eprintln!(
        "vertical cable vs reference: cont f, k, T {:.1e} {:.1e} {:.1e}; fem f, k {:.1e} {:.1e}",
        d[0], d[1], d[2], d[3], d[4]
    );
    assert!(d[..3].iter().all(|x| *x <= 1e-6), "{d:?}");
    assert!(d[3..].iter().all(|x| *x <= 2e-4), "{d:?}");
    for el in [ElementKind::Fem, ElementKind::Continuous] {
        let (n, exact) = if el == ElementKind::Fem {
            (160, &fem)
        } else {
            (1, &cont)
        };
        let near = analyze_at(&s, [1e-7, 0.0, 2.0], el, n, 6);
        let df = max_rel(&near.frequencies_hz, &exact.frequencies_hz);
        let dk = max_rel(&principal_n_m(&near), &principal_n_m(exact));
        let dt = max_rel(&near.tensions_n, &exact.tensions_n);
        eprintln!("{el:?}: 1e-7 m beside the vertical: f {df:.1e}, k {dk:.1e}, T {dt:.1e}");
        assert!(df.max(dk).max(dt) <= 1e-5, "{el:?}: {df:e} {dk:e} {dt:e}");
    }
}

// ---------------------------------------------------------------------------------------
// Low points inside, λ² ≥ 1e4

fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// The heavy paper robot's centre: the four lower cables' lowest points lie between their
/// ends (smallest tension below both end tensions); suspended-8's off-centre pose has
/// cables with λ² above 1e4. Every number finite, for fem and continuous. (Both are
/// compared with the independent reference in tests/sag/vs_reference.rs, including the
/// interior low point's tension = H.)
#[test]
fn interior_low_points_and_huge_lambda2_are_finite() {
    let heavy = heavy_paper();
    let s8 = Scene::load("suspended-8").expect("scene");
    for (el, n) in [(ElementKind::Fem, 40), (ElementKind::Continuous, 1)] {
        let r = analyze_at(&heavy, HEAVY_CENTRE_M, el, n, 6);
        let (t_min, t_a) = (
            r.tensions_min_n.clone().unwrap(),
            r.tensions_anchor_n.clone().unwrap(),
        );
        let inside: Vec<usize> = (0..8)
            .filter(|&i| t_min[i] < t_a[i].min(r.tensions_n[i]))
            .collect();
        assert_eq!(inside, [4, 5, 6, 7], "{el:?}");
        let r8 = analyze_at(&s8, [4.0, 2.5, 1.5], el, n, 6);
        let l2 = r8.irvine_lambda2.clone().unwrap();
        let l2_max = l2.iter().copied().fold(0.0, f64::max);
        eprintln!("{el:?}: suspended-8 off-centre λ² {l2:?}");
        assert!(l2_max >= 1e4, "{l2:?}");
        for rep in [&r, &r8] {
            let k: Vec<f64> = rep.stiffness_n_m.iter().flatten().copied().collect();
            assert!(all_finite(&rep.frequencies_hz) && all_finite(&k));
            assert!(all_finite(rep.sag_m.as_ref().unwrap()));
            assert!(rep.frequencies_hz.iter().all(|f| *f > 0.0));
        }
    }
}

// ---------------------------------------------------------------------------------------
// Slack

fn assert_not_ok_is_nan(e: &Estimate, what: &str) {
    assert!(e.status != Status::Ok && e.error.is_some(), "{what}");
    assert!(e.f1_hz.is_nan() && ee_hz(e).is_nan(), "{what}: {e:?}");
    assert!(
        e.stiffness.translational_n_m().iter().all(|x| x.is_nan()),
        "{what}: {e:?}"
    );
}

fn assert_ok_is_finite(e: &Estimate, what: &str) {
    assert!(e.error.is_none(), "{what}");
    assert!(e.f1_hz.is_finite() && e.f1_hz > 0.0, "{what}: {e:?}");
    assert!(all_finite(e.tensions()), "{what}: {e:?}");
    assert!(e.tensions().iter().all(|t| *t > 0.0), "{what}: {e:?}");
    assert!(
        e.stiffness
            .translational_n_m()
            .iter()
            .all(|x| x.is_finite()),
        "{what}: {e:?}"
    );
}

/// The heavy robot at (+0.5, −0.3, +0.2) m from its centre: cable 5 cannot stay taut.
/// The estimator reports `cable_slack` (wire code 11) with NaN numbers and recovers at the
/// next feasible pose; `cablevib analyze` fails with one line and a nonzero exit, and with
/// `--realtime` names the status.
#[test]
fn a_slack_pose_is_a_status() {
    let heavy = heavy_paper();
    for (el, n) in [(ElementKind::Fem, 40), (ElementKind::Continuous, 1)] {
        let s = heavy.with_model(el, n);
        let mut est = Estimator::new(&s).expect("builds at the centre");
        assert_ok_is_finite(
            est.update(&Pose::at(HEAVY_CENTRE_M.into()), Tmin::Scene),
            "centre",
        );
        let e = *est.update(&Pose::at(HEAVY_SLACK_M.into()), Tmin::Scene);
        assert_eq!(e.status, Status::CableSlack, "{el:?}: {:?}", e.error);
        assert_eq!(e.status as u32, 11);
        assert_not_ok_is_nan(&e, "slack");
        let e = *est.update(&Pose::at(HEAVY_OFF_CENTRE_M.into()), Tmin::Scene);
        assert_ok_is_finite(&e, "after the slack pose");
    }
    let file = format!("{}/heavy_paper_sag.toml", env!("CARGO_TARGET_TMPDIR"));
    std::fs::write(&file, heavy_paper_toml()).expect("write scene");
    let p = HEAVY_SLACK_M.map(|x| x.to_string()).join(",");
    for (extra, needle) in [(None, "slack"), (Some("--realtime"), "cable_slack")] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_cablevib"))
            .args(["analyze", &file, "--json", "--position", &p])
            .args(extra)
            .output()
            .expect("run cablevib");
        let err = String::from_utf8_lossy(&out.stderr);
        eprintln!("analyze {extra:?}: {err}");
        assert!(!out.status.success(), "{extra:?}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(needle), "{err}");
    }
}

// ---------------------------------------------------------------------------------------
// Fuzz

/// 300 random poses in each robot's anchor box (10 % inside each face; suspended-8, whose
/// anchors are all at z = 6 m: heights 0.5 .. 5 m) with a random T_min
/// (log-uniform from 1e-3 to 2 × the scene's t_min, so from very slack to infeasible),
/// fem and continuous: no panic; every ok estimate finite with positive tensions; every
/// other one a status, an error and NaN numbers. Both kinds must occur (else the fuzz
/// tested nothing).
/// The fuzz's box: the anchors' box 10 % inside each face; a suspended robot (every anchor
/// at one height) from 0.5 m above the floor to 1 m below its anchors.
fn sample_box(s: &Scene) -> (Vector3<f64>, Vector3<f64>) {
    let (lo, hi) = s.frame_bounds_m();
    let m = 0.1 * (hi - lo);
    let (mut a, mut b) = (lo + m, hi - m);
    if hi.z - lo.z < 1.0 {
        (a.z, b.z) = (0.5, hi.z - 1.0);
    }
    (a, b)
}

/// `poses` random poses per model of `elements` on each of `scenes` (the heavy-cable paper
/// robot and suspended-8 with sag), each a cold start of the offline estimator (its
/// end-effector mode scanned without a cycle budget): every ok estimate is finite, every
/// other one NaN with a status, and both occur at least max(3, poses/30) times per model.
fn random_poses_check(scenes: &[Scene], poses: usize, elements: &[(ElementKind, usize)]) {
    let mut rng = Rng(13);
    let floor = (poses / 30).max(3);
    for scene in scenes {
        for &(el, n) in elements {
            let s = scene.with_model(el, n);
            let mut est = Estimator::new(&s).expect("estimator");
            let (lo, hi) = sample_box(&s);
            let (mut ok, mut slack, mut other) = (0, 0, 0);
            for _ in 0..poses {
                let p = Vector3::from_fn(|i, _| rng.range(lo[i], hi[i]));
                let t_min = s.t_min_n * 2.0 * 10f64.powf(rng.range(-3.0, 0.0));
                let e = *est.update(&Pose::at(p), Tmin::Uniform(t_min));
                let what = format!("{} {el:?} at {p:?}, T_min {t_min}", s.name);
                if e.is_ok() {
                    assert_ok_is_finite(&e, &what);
                    ok += 1;
                } else {
                    assert_not_ok_is_nan(&e, &what);
                    slack += (e.status == Status::CableSlack) as usize;
                    other += (e.status != Status::CableSlack) as usize;
                }
            }
            eprintln!(
                "{} {el:?}: {ok} ok, {slack} cable_slack, {other} other",
                s.name
            );
            assert!(
                ok >= floor && slack + other >= floor,
                "{ok} {slack} {other}"
            );
        }
    }
}

/// 300 FEM poses per robot, 100 continuous ones on the paper robot and 40 on suspended-8
/// (a continuous cold start scans suspended-8's end-effector mode, the ~200th, at ~12 µs an
/// evaluation: 300 of them took ~2 minutes, the whole quick suite's longest test); the slow
/// sweep runs 300 continuous poses on both.
#[test]
fn random_poses_are_ok_and_finite_or_a_status() {
    let s8 = Scene::load("suspended-8").expect("scene");
    random_poses_check(&[heavy_paper(), s8.clone()], 300, &[(ElementKind::Fem, 20)]);
    random_poses_check(&[heavy_paper()], 100, &[(ElementKind::Continuous, 1)]);
    random_poses_check(&[s8], 40, &[(ElementKind::Continuous, 1)]);
}

mod slow {
    use super::*;

    #[test]
    #[ignore = "slow reference sweep: 300 cold continuous poses per robot"]
    fn random_continuous_poses_are_ok_and_finite_or_a_status() {
        let s8 = Scene::load("suspended-8").expect("scene");
        random_poses_check(&[heavy_paper(), s8], 300, &[(ElementKind::Continuous, 1)]);
    }
}

// ---------------------------------------------------------------------------------------
// Real time: no allocation per cycle

/// Estimator::realtime along a circle around each robot's default pose (radius ~5 % of
/// its size: 0.2 m on the 2.5 m paper cube, 1 m on the 15 m frame, 20 m on the 300 m
/// circle; 4 s per turn, one pose per 1 ms), fem (N = 40) and continuous: after the first
/// cycle, 2,000 cycles make no heap allocation, and (nearly) all of them are ok.
#[test]
fn the_sagged_realtime_path_allocates_nothing() {
    let fast = Scene::load("fast-like").expect("scene");
    let s8 = Scene::load("suspended-8").expect("scene");
    for (scene, radius) in [(heavy_paper(), 0.2), (s8, 1.0), (fast, 20.0)] {
        for (el, n) in [(ElementKind::Fem, 40), (ElementKind::Continuous, 1)] {
            let s = scene.with_model(el, n);
            assert!(s.model.sag);
            let c = Circle::new(&s, radius, 4.0).expect("circle");
            let pose = |k: usize| Pose::at(c.position_at(k as f64 * SAMPLE_PERIOD_S));
            let mut est = Estimator::realtime(&s).expect("estimator");
            est.update(&pose(0), Tmin::Scene);
            let before = thread_allocations();
            let mut ok = 0;
            for k in 1..=2000 {
                ok += est.update(&pose(k), Tmin::Scene).is_ok() as usize;
            }
            let after = thread_allocations();
            eprintln!("{} {el:?}: {ok} of 2000 cycles ok", s.name);
            assert_eq!(after - before, 0, "{} {el:?}: allocations", s.name);
            assert!(ok >= 1990, "{} {el:?}: {ok} ok", s.name);
        }
    }
}
