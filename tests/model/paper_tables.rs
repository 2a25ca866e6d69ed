//! The paper's Tables 3, 4, 7 and 8 against the faithful values of the stated model
//! (tests/data/paper_tables.json: exact reduced formulation, certified to 1e-32).
//!
//! Dense reference: tolerance 5e-6 relative. A backward-stable dense f64 eigensolver has
//! absolute error ≈ ε·λ_max, i.e. relative ε·λ_max/λ on mode λ: up to ≈2e-6 for the planar
//! robot's 0.48 Hz out-of-plane mode at N = 40 (λ_max/λ₁ ≈ 2.5e10), far less elsewhere.
//! Each entry is also checked against its own computed bound 8·ε·λ_max/λ + 1e-12.
//! Tensions: 1e-9 relative against the exact KKT values (Clarabel run at 1e-13 tolerances).
//!
//! Printed values: every reproduced "By Matlab" number is 1.005312 × the faithful value
//! (docs/model.md section 3), so the faithful model sits ≈0.531% below the printed tables —
//! the same factor for end-effector and string modes, so no physical parameter explains
//! it. `printed_tables_are_0_531_percent_above` checks exactly that, at print precision.
use cablevib::estimator::Tmin;
use cablevib::estimator::{reference_analysis, ReferenceAnalysis};
use cablevib::modal::{dense_relative_accuracy, lambda_to_hz};
use cablevib_testkit::*;

const DENSE_TOL: f64 = 5e-6;

fn check_dense(
    label: &str,
    scene: &cablevib::scene::Scene,
    faithful: &[Option<f64>],
    modes: usize,
) -> f64 {
    let r = reference_analysis(scene, &scene.ee_position_m, Tmin::Scene, false).unwrap();
    check_analysis(label, &r, faithful, modes)
}

/// [`check_dense`] on a dense analysis already made.
fn check_analysis(
    label: &str,
    r: &ReferenceAnalysis,
    faithful: &[Option<f64>],
    modes: usize,
) -> f64 {
    let mut worst = 0.0f64;
    for (i, f) in faithful.iter().enumerate().take(modes) {
        match f {
            Some(f) => {
                let got = lambda_to_hz(r.modes.lambda[i]);
                let e = rel(got, *f);
                let bound =
                    8.0 * dense_relative_accuracy(r.modes.lambda[i], r.modes.lambda_max) + 1e-12;
                assert!(
                    e <= DENSE_TOL,
                    "{label} mode {}: {got} vs {f}: rel {e:.2e}",
                    i + 1
                );
                assert!(
                    e <= bound.max(2e-12),
                    "{label} mode {}: rel {e:.2e} exceeds the solver's own bound {bound:.2e}",
                    i + 1
                );
                worst = worst.max(e);
            }
            None => assert!(
                r.modes.lambda.len() <= i,
                "{label}: model should have only {i} modes"
            ),
        }
    }
    worst
}

#[test]
fn table3_planar_fem_convergence() {
    let t = table(3);
    let mut worst = 0.0f64;
    for (n, s, row) in convergence_rows(&t) {
        worst = worst.max(check_dense(
            &format!("T3 N={n}"),
            &s,
            &f64s(&row["faithful"]),
            10,
        ));
    }
    eprintln!("table 3: worst relative error {worst:.2e}");
}

#[test]
fn table4_planar_fem_and_catenary() {
    let t = table(4);
    let mut worst = 0.0f64;
    for row in t["rows"].as_array().unwrap() {
        let tmin = row["t_min_n"].as_f64().unwrap();
        for (key, el, n) in TABLE4_COLUMNS {
            let s = scene_for(&t, el, n, tmin);
            worst = worst.max(check_dense(
                &format!("T4 {key} {tmin} N"),
                &s,
                &f64s(&row[key]),
                10,
            ));
        }
    }
    eprintln!("table 4: worst relative error {worst:.2e}");
}

#[test]
fn table7_spatial_fem_convergence_modes_1_to_8() {
    let t = table(7);
    let mut worst = 0.0f64;
    for (n, s, row) in convergence_rows(&t) {
        worst = worst.max(check_dense(
            &format!("T7 N={n}"),
            &s,
            &f64s(&row["faithful"]),
            8,
        ));
    }
    eprintln!("table 7: worst relative error {worst:.2e}");
}

#[test]
fn table8_spatial_fem_and_catenary_modes_1_to_8_and_tensions() {
    let t = table(8);
    let mut worst = 0.0f64;
    for row in t["rows"].as_array().unwrap() {
        let tmin = row["t_min_n"].as_f64().unwrap();
        for (key, el) in TABLE8_COLUMNS {
            // One dense analysis (939 DOF) for the modes and the tensions: the scene's T_min
            // is the row's, every cable's.
            let s = scene_for(&t, el, 40, tmin);
            let r = reference_analysis(&s, &s.ee_position_m, Tmin::Uniform(tmin), false).unwrap();
            let label = format!("T8 {key} {tmin} N");
            worst = worst.max(check_analysis(&label, &r, &f64s(&row[key]), 8));
            for (got, want) in r.tensions_n.iter().zip(f64s(&row["tensions"])) {
                assert!(rel(*got, want.unwrap()) < 1e-9, "tension {got} vs {want:?}");
            }
        }
    }
    eprintln!("table 8: worst relative error {worst:.2e}");
}

#[test]
fn printed_tables_are_0_531_percent_above() {
    // Print precision: a value printed with 3 decimals is within 5e-4 Hz of 1.005312 × faithful.
    let t = table(8);
    for row in t["rows"].as_array().unwrap() {
        for (p, f) in f64s(&row["paper_fem"])
            .iter()
            .zip(f64s(&row["faithful_fem_N40"]))
            .take(8)
        {
            let (p, f) = (p.unwrap(), f.unwrap());
            assert!(
                (p - 1.005312 * f).abs() <= 5e-4 + 1e-6 * p,
                "{p} vs 1.005312 × {f}"
            );
            assert!(rel(p, f) > 0.0050 && rel(p, f) < 0.0056);
        }
    }
}
