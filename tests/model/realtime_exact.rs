//! The real-time path's f1 against the faithful values (1e-9 relative), which a dense f64
//! solver cannot reach on the planar robot (its accuracy there is ε·λ_max/λ ≈ 1e-6).
use cablevib::estimator::Tmin;
use cablevib::estimator::{structured_analysis, Estimator};
use cablevib::kinematics::Pose;
use cablevib::scene::ElementKind;
use cablevib_testkit::*;

const TOL: f64 = 1e-9;

fn check(label: &str, s: &cablevib::scene::Scene, f1: f64) -> f64 {
    let e = structured_analysis(s, &s.ee_position_m, Tmin::Scene);
    assert!(e.is_ok(), "{label}: {:?}", e.error);
    let err = rel(e.f1_hz, f1);
    assert!(
        err < TOL,
        "{label}: f1 {} vs faithful {f1}: {err:.2e}",
        e.f1_hz
    );
    err
}

#[test]
fn f1_equals_faithful_values_of_every_table() {
    let mut worst = 0.0f64;
    for tn in [3, 7] {
        let t = table(tn);
        for (n, s, row) in convergence_rows(&t) {
            worst = worst.max(check(
                &format!("T{tn} N={n}"),
                &s,
                f64s(&row["faithful"])[0].unwrap(),
            ));
        }
    }
    let t = table(4);
    for row in t["rows"].as_array().unwrap() {
        let tmin = row["t_min_n"].as_f64().unwrap();
        for (key, el, n) in TABLE4_COLUMNS {
            let s = scene_for(&t, el, n, tmin);
            worst = worst.max(check(
                &format!("T4 {key} {tmin}"),
                &s,
                f64s(&row[key])[0].unwrap(),
            ));
        }
    }
    let t = table(8);
    for row in t["rows"].as_array().unwrap() {
        let tmin = row["t_min_n"].as_f64().unwrap();
        for (key, el) in TABLE8_COLUMNS {
            let s = scene_for(&t, el, 40, tmin);
            worst = worst.max(check(
                &format!("T8 {key} {tmin}"),
                &s,
                f64s(&row[key])[0].unwrap(),
            ));
        }
    }
    eprintln!("real-time f1 vs faithful: worst relative error {worst:.2e}");
}

#[test]
fn continuous_model_is_the_richardson_limit_of_fem() {
    // FEM with consistent mass converges as O(1/N²): f(N) ≈ f∞ + c/N². Richardson on
    // N = 40, 80: f∞ ≈ (4 f(80) − f(40)) / 3, with an O(1/N⁴) remainder ≈ 1e-8 relative here.
    for base in [
        cablevib::scene::Scene::default_scene(),
        cablevib::scene::Scene::planar_paper(),
    ] {
        let f = |el: ElementKind, n: usize| {
            let s = base.with_model(el, n);
            let mut est = Estimator::new(&s).unwrap();
            let e = *est.update(&Pose::at(s.ee_position_m), Tmin::Scene);
            assert!(e.is_ok(), "{:?}", e.error);
            e.f1_hz
        };
        let (f40, f80, fc) = (
            f(ElementKind::Fem, 40),
            f(ElementKind::Fem, 80),
            f(ElementKind::Continuous, 1),
        );
        let rich = (4.0 * f80 - f40) / 3.0;
        let err = rel(rich, fc);
        eprintln!(
            "{}: FEM40 {f40} FEM80 {f80} Richardson {rich} continuous {fc}: {err:.2e}",
            base.name
        );
        assert!(err < 1e-6, "{err}");
        assert!(f40 > f80 && f80 > fc, "FEM converges from above");
    }
}
