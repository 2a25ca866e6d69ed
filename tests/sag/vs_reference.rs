//! The crate's sagged model against the independent reference (tests/py/sag_reference.py:
//! a sagged nonlinear equilibrium of corotational truss chains in numpy/scipy, shares no
//! code with the crate), on the large robots: fast-like and suspended-8 (the
//! shipped sagging scenes) and the paper's spatial robot with a 50× heavier cable (t_min
//! 30 N, lower cables very slack), each at its centre and off-centre.
//!
//! How: the crate solves the sagged statics at the pose (tensions on the end tangents) and
//! reports each cable's unstretched length L0; the reference is given exactly those L0 and
//! finds its own equilibrium (Newton on the whole robot from each cable's catenary), then
//! its tangent stiffness and modes, at 80, 160 and 320 elements per cable with the
//! Richardson extrapolation of the two finest (order 2, N → ∞).
//!
//! What is compared with what, and why: the reference's nodes sit at the truss's own
//! discrete equilibrium, ours on the exact catenary, so the two FE models at the same N
//! differ by O(1/N²); both converge to the same continuous problem. So the crate's
//! continuous model and its FEM at N = 160 are compared with the reference's extrapolated
//! (N → ∞) values, whose own error is O(N⁻⁴) (the continuous model agrees with them to
//! ≤ 2e-9; the printed `ref 320` column is |extrapolated − N = 320|, the size of the
//! correction Richardson made, not its remaining error); the difference to the reference's N = 160 level is printed too (it is the two
//! discretisations' O(1/N²) difference, not an error of either).
//!
//! The required bar is 1e-3 relative for f1..f6 (fem at N = 160), f1 (continuous), the
//! static stiffness's principal values and the end-effector-end tensions. The measured
//! differences are far smaller (printed as a table; see the constants for the bars this
//! test holds them to).
//!
//! Mode matching: both sides report their lowest K frequencies sorted ascending and are
//! compared in that order. Symmetric poses have exact multiplets (fast-like's centre:
//! pairs and quadruplets; the heavy robot's centre: pairs 2e-4 apart); within a cluster
//! the order is immaterial (equal values), and distinct clusters are far apart compared to
//! the differences measured, so the sorted lists pair each mode with its counterpart. The
//! reference computes 8 modes so a cluster cut at the 6th mode is still complete there.

use cablevib::scene::{ElementKind, Scene};
use cablevib::study::analysis::AnalysisReport;
use cablevib_testkit::sag_cases::*;
use cablevib_testkit::sag_reference_py::{f64s, run_reference, scene_request, RefAnswer, LEVELS};
use serde_json::{json, Value};

/// The required bar: f1..f6 (fem, N = 160), f1 (continuous), the principal stiffnesses and
/// the end-effector-end tensions within 1e-3 relative of the independent reference.
const ISSUE_BAR: f64 = 1e-3;
/// The continuous model, the tensions and L0 against the reference's extrapolation: the
/// same continuous problem on both sides, so only the reference's Richardson remainder
/// (O(N⁻⁴): the N = 320 correction is ≤ 2e-5, so the remainder ~(2e-5)² scale), the
/// catenary solves (~1e-13) and the eigen-solves (residual ≤ 1e-9) remain; measured
/// ≤ 2e-9. 1e-6 leaves over two decades of margin and still fails on any modelling difference (a wrong mass per length, a
/// stretched instead of an unstretched reference length: O(T/EA) ≈ 1e-4 .. 1e-3 here).
const CONTINUUM_BAR: f64 = 1e-6;
/// Our FEM at N = 160 against the N → ∞ limit: its discretisation error c/N², measured
/// ≤ 6.9e-5 in f and ≤ 3.8e-5 in the principal stiffness (c ≤ 1.8); the bar allows
/// c ≤ 5, still five times tighter than the issue's.
const FEM160_BAR: f64 = 2e-4;
/// The reference's end-effector, given our L0, stays at our pose: its extrapolated
/// equilibrium position within 1e-9 of the longest cable's length (Newton's residual is
/// 1e-10 of the weight; our catenary statics balance to ~1e-12 of it).
const EE_DISPLACEMENT_BAR: f64 = 1e-9;

/// The reference at `position_m` with our `l0_m`, solved at [`LEVELS`] with `modes`.
fn reference_for(scene: &Scene, position_m: [f64; 3], l0_m: &[f64], modes: usize) -> RefAnswer {
    let mut req = scene_request(scene, position_m);
    req.insert("unstretched_lengths_m".into(), json!(l0_m));
    req.insert("modes".into(), json!(modes));
    req.insert("convergence_levels".into(), json!(LEVELS));
    RefAnswer(run_reference(&Value::Object(req)))
}

/// One row of the printed table and what was asserted.
struct Row {
    name: String,
    fem_f: f64,
    fem_f_vs_160: f64,
    cont_f1: f64,
    cont_f: f64,
    fem_k: f64,
    cont_k: f64,
    t_ee: f64,
    t_anchor: f64,
    t_min_h: f64,
    low_points: usize,
    ee_disp: f64,
    ref_err: f64,
}

fn largest(v: &[f64]) -> f64 {
    v.iter().copied().fold(0.0, f64::max)
}

/// Compare at one pose; returns the measured differences (every one asserted).
fn compare(name: &str, scene: &Scene, p: [f64; 3]) -> Row {
    let fem = analyze_at(scene, p, ElementKind::Fem, 160, 6);
    let cont = analyze_at(scene, p, ElementKind::Continuous, 1, 6);
    let l0 = fem.unstretched_length_m.clone().expect("sag fields");
    // The statics do not depend on the element: the same L0 and tensions, bit for bit.
    assert_eq!(cont.unstretched_length_m.as_ref(), Some(&l0), "{name}");
    assert_eq!(cont.tensions_n, fem.tensions_n, "{name}");
    let r = reference_for(scene, p, &l0, 8);
    check_reference_converged(name, &r);
    let f_ref = r.extrapolated("frequencies_hz");
    let f_160 = f64s(&r.at_level(160)["frequencies_hz"]);
    let k_ref = r.extrapolated("stiffness_principal_n_m");
    let low = interior_low_points(name, &fem, &r);
    let row = Row {
        name: name.to_string(),
        fem_f: max_rel(&fem.frequencies_hz, &f_ref),
        fem_f_vs_160: max_rel(&fem.frequencies_hz, &f_160),
        cont_f1: rel(cont.frequencies_hz[0], f_ref[0]),
        cont_f: max_rel(&cont.frequencies_hz, &f_ref),
        fem_k: max_rel(&principal_n_m(&fem), &k_ref),
        cont_k: max_rel(&principal_n_m(&cont), &k_ref),
        t_ee: max_rel(&fem.tensions_n, &r.extrapolated("tension_ee_n")),
        t_anchor: max_rel(
            fem.tensions_anchor_n.as_ref().unwrap(),
            &r.extrapolated("tension_anchor_n"),
        ),
        t_min_h: low.1,
        low_points: low.0,
        ee_disp: ee_displacement(&r, p) / largest(&l0),
        ref_err: ref_error(&r),
    };
    eprintln!("{name}: fem f {:?}", fem.frequencies_hz);
    eprintln!("{name}: ref f {:?}", &f_ref[..6]);
    eprintln!("{name}: cont f {:?}", cont.frequencies_hz);
    eprintln!("{name}: k {:?} vs ref {k_ref:?}", principal_n_m(&fem));
    assert_eq!(fem.frequencies_hz.len(), 6, "{name}");
    assert_eq!(cont.frequencies_hz.len(), 6, "{name}");
    for (what, v, bar) in [
        ("fem f1..f6", row.fem_f, FEM160_BAR),
        ("continuous f1", row.cont_f1, CONTINUUM_BAR),
        ("continuous f1..f6", row.cont_f, CONTINUUM_BAR),
        ("fem principal stiffness", row.fem_k, FEM160_BAR),
        ("continuous principal stiffness", row.cont_k, CONTINUUM_BAR),
        ("end-effector-end tensions", row.t_ee, CONTINUUM_BAR),
        ("anchor-end tensions", row.t_anchor, CONTINUUM_BAR),
        ("smallest tension = H", row.t_min_h, CONTINUUM_BAR),
        (
            "reference ee displacement / L0",
            row.ee_disp,
            EE_DISPLACEMENT_BAR,
        ),
    ] {
        assert!(v <= ISSUE_BAR.min(bar), "{name}: {what} differs by {v:e}");
    }
    row
}

/// Every level of the reference converged with no negative eigenvalue (a stable
/// equilibrium).
fn check_reference_converged(name: &str, r: &RefAnswer) {
    for n in LEVELS {
        let lv = r.at_level(n);
        assert_eq!(lv["converged"], json!(true), "{name} n = {n}");
        assert_eq!(
            lv["eigen"]["negative_eigenvalues"],
            json!(0),
            "{name} n = {n}"
        );
    }
}

/// The largest relative Richardson error estimate of the reference over the compared keys.
fn ref_error(r: &RefAnswer) -> f64 {
    let mut worst = 0.0f64;
    for key in ["frequencies_hz", "stiffness_principal_n_m", "tension_ee_n"] {
        let (v, e) = (r.extrapolated(key), r.error_estimate(key));
        for (x, d) in v.iter().zip(&e).take(6) {
            worst = worst.max(d / x.abs());
        }
    }
    worst
}

/// A smallest tension this far (relative) below both end tensions is an interior low point,
/// not rounding between the QP's T_e and the catenary's end tension.
const INTERIOR_LOW_REL: f64 = 1e-9;

/// Cables whose lowest point lies inside (our smallest tension below both end tensions):
/// that smallest tension is H, checked against the reference's extrapolated H. Returns the
/// how many and the largest relative difference.
fn interior_low_points(name: &str, fem: &AnalysisReport, r: &RefAnswer) -> (usize, f64) {
    let (t_min, t_a) = (
        fem.tensions_min_n.as_ref().unwrap(),
        fem.tensions_anchor_n.as_ref().unwrap(),
    );
    let h = r.extrapolated("h_n");
    let (mut count, mut worst) = (0, 0.0f64);
    for i in 0..t_min.len() {
        // Below both ends by more than rounding: the reported end tension is the QP's T_e,
        // the catenary's own end tension equals it to the statics' 1e-12 tolerance.
        if t_min[i] < t_a[i].min(fem.tensions_n[i]) * (1.0 - INTERIOR_LOW_REL) {
            count += 1;
            eprintln!(
                "{name}: cable {i} low point inside, T_min {} vs H {}",
                t_min[i], h[i]
            );
            worst = worst.max(rel(t_min[i], h[i]));
        }
    }
    (count, worst)
}

/// |extrapolated reference end-effector − our pose|, m.
fn ee_displacement(r: &RefAnswer, p: [f64; 3]) -> f64 {
    let ee = r.extrapolated("ee_position_m");
    (0..3).map(|i| (ee[i] - p[i]).powi(2)).sum::<f64>().sqrt()
}

fn print_table(rows: &[Row]) {
    eprintln!(
        "{:<34} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "case",
        "fem−ref∞",
        "fem−r160",
        "cont f1",
        "cont f",
        "fem k",
        "cont k",
        "T_ee",
        "T_anchor",
        "Tmin=H",
        "ee/L0",
        "ref 320"
    );
    for r in rows {
        eprintln!(
            "{:<34} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e}",
            r.name, r.fem_f, r.fem_f_vs_160, r.cont_f1, r.cont_f, r.fem_k, r.cont_k, r.t_ee,
            r.t_anchor, r.t_min_h, r.ee_disp, r.ref_err
        );
    }
}

fn shipped(name: &str) {
    let (_, centre, off) = SHIPPED_POSES
        .iter()
        .find(|(n, _, _)| *n == name)
        .expect("pose");
    let s = Scene::load(name).expect("scene");
    assert!(s.model.sag, "{name} sags");
    let rows = [
        compare(&format!("{name} centre"), &s, *centre),
        compare(&format!("{name} off-centre"), &s, *off),
    ];
    print_table(&rows);
}

#[test]
fn fast_like_matches_the_reference() {
    shipped("fast-like");
}

#[test]
fn suspended_8_matches_the_reference() {
    shipped("suspended-8");
}

/// The paper's robot with a 50× heavier cable: at the centre the four lower cables hang
/// with their lowest point between their ends (checked: T_min = H there against the
/// reference).
#[test]
fn heavy_paper_robot_matches_the_reference() {
    let s = heavy_paper();
    let rows = [
        compare("heavy paper centre", &s, HEAVY_CENTRE_M),
        compare("heavy paper off-centre", &s, HEAVY_OFF_CENTRE_M),
    ];
    print_table(&rows);
    assert_eq!(
        rows[0].low_points, 4,
        "the lower cables' low points are inside"
    );
}
