//! The sagging cable's statics (`cablevib::elastic_catenary`) against references that share no code
//! with it: the straight stretched cable, the inextensible catenary y = a cosh(x/a), the
//! shallow parabola, Irvine's equivalent modulus, the hanging vertical rope, and the
//! closed-form fold of a level span.
use cablevib::elastic_catenary::{CableChord, Catenary, SagError, SagParams};

fn chord(span: f64, rise: f64, ea: f64, w: f64) -> CableChord {
    CableChord {
        span_m: span,
        rise_m: rise,
        ea_n: ea,
        w_n_m: w,
    }
}

fn solve(c: &CableChord, t: f64) -> Catenary {
    let (cat, info) = c
        .solve_end_tension(t, None, &SagParams::default())
        .unwrap_or_else(|e| panic!("{c:?} T_e {t}: {e}"));
    assert!(info.residual_m <= 1e-12 * c.length_m(), "{info:?}");
    assert!((cat.tension_end_n() - t).abs() <= 1e-14 * t, "{cat:?}");
    cat
}

/// w = 0 at every chord angle (vertical both ways included) and EA/T from 1e2 to 1e9: the
/// straight cable, L0 = L/(1 + T/EA) and (H, V_e) = T (X, Z)/L, to a few ulps (4e-16
/// relative to T and L).
#[test]
fn weightless_cable_is_the_straight_taut_cable() {
    let t = 150.0;
    for k in 0..=12 {
        let ang = -std::f64::consts::FRAC_PI_2 + std::f64::consts::PI * k as f64 / 12.0;
        for ratio in [1e2, 1e5, 1e9] {
            let (x, z) = (2.3 * ang.cos().max(0.0), 2.3 * ang.sin());
            let c = chord(if k == 0 || k == 12 { 0.0 } else { x }, z, ratio * t, 0.0);
            let cat = solve(&c, t);
            let len = c.length_m();
            let l0 = len / (1.0 + t / (ratio * t));
            assert!(
                (cat.l0_m - l0).abs() <= 4e-16 * len,
                "angle {k} EA/T {ratio}: {} vs {l0}",
                cat.l0_m
            );
            assert!((cat.h_n - t * c.span_m / len).abs() <= 4e-16 * t, "{cat:?}");
            assert!(
                (cat.v_end_n() - t * c.rise_m / len).abs() <= 4e-16 * t,
                "{cat:?}"
            );
        }
    }
}

/// The inextensible catenary through two points of y = a cosh(x/a) (a = H/w): H = w a,
/// L0 = a (sinh(x2/a) − sinh(x1/a)), T_e = w a cosh(x2/a). EA = 1e12 T makes the elastic
/// terms ~1e-12 relative, the tolerance 1e-10.
#[test]
fn stiff_cable_is_the_cosh_catenary_through_two_points() {
    let (w, a) = (3.0, 4.0);
    for &(x1, x2) in &[(-2.0, 5.0), (1.0, 6.0), (-6.0, -1.0), (-3.0, 3.0)] {
        let y = |x: f64| a * (x / a).cosh();
        let t_e = w * a * (x2 / a).cosh();
        let c = chord(x2 - x1, y(x2) - y(x1), 1e12 * t_e, w);
        let cat = solve(&c, t_e);
        let l0 = a * ((x2 / a).sinh() - (x1 / a).sinh());
        assert!(
            (cat.h_n - w * a).abs() <= 1e-10 * w * a,
            "({x1}, {x2}): H {} vs {}",
            cat.h_n,
            w * a
        );
        assert!(
            (cat.l0_m - l0).abs() <= 1e-10 * l0,
            "({x1}, {x2}): L0 {} vs {l0}",
            cat.l0_m
        );
        let low_inside = x1 < 0.0 && x2 > 0.0;
        let t_min = if low_inside {
            w * a
        } else {
            w * y(x1.abs().min(x2.abs()))
        };
        assert!(
            (cat.tension_min_n() - t_min).abs() <= 1e-10 * t_min,
            "min {} vs {t_min}",
            cat.tension_min_n()
        );
    }
}

/// A level span in the shallow limit: sag d = w X²/(8H) (parabola); the catenary's
/// relative excess over the parabola is (wX/H)²/48 ≈ 2e-6 here, plus T/EA = 1e-6: 1e-5.
#[test]
fn level_shallow_span_has_the_parabolic_sag() {
    let (x, w, t) = (10.0, 1.0, 1000.0);
    let cat = solve(&chord(x, 0.0, 1e9, w), t);
    let d = w * x * x / (8.0 * cat.h_n);
    assert!(
        (cat.sag_m() - d).abs() <= 1e-5 * d,
        "sag {} vs {d}",
        cat.sag_m()
    );
}

/// Irvine's static chord stiffness of a level shallow span: dH/dX at fixed L0 equals
/// E_eq A/L with E_eq = E/(1 + (wL)² EA/(12 T³)) (here the correction is 0.08). The
/// derivative is a central difference of two length solves (step 1e-7 L: truncation 1e-14,
/// rounding ε L/(1e-7 L) ≈ 1e-9); Irvine's formula drops terms of order (wL/T)² and
/// T/EA, both 1e-4: tolerance 5e-4.
#[test]
fn chord_stiffness_is_irvines_equivalent_modulus() {
    let (x, w, t, ea) = (20.0, 0.5, 1000.0, 1e7);
    let p = SagParams::default();
    let cat = solve(&chord(x, 0.0, ea, w), t);
    let dx = 1e-7 * x;
    let h = |span: f64| {
        chord(span, 0.0, ea, w)
            .solve_length(cat.l0_m, Some((cat.h_n, cat.v_end_n())), &p)
            .unwrap()
            .0
            .h_n
    };
    let k = (h(x + dx) - h(x - dx)) / (2.0 * dx);
    let e_eq = ea / (1.0 + (w * x).powi(2) * ea / (12.0 * t.powi(3)));
    let irvine = e_eq / x;
    assert!(
        (k - irvine).abs() <= 5e-4 * irvine,
        "dH/dX {k} vs Irvine {irvine}"
    );
    assert!(
        ((ea / x) - k).abs() > 0.05 * k,
        "the sag correction is visible"
    );
}

/// Vertical rope, anchor above: T(s) = T_e + w (L0 − s), stretched length ∫(1 + T/EA) ds
/// = |Z| (closed-form quadratic, solved here by the textbook root formula); anchor below:
/// T(s) = T_e − w (L0 − s). Tolerance 1e-14 relative. A span of 1e-9 m is continuous
/// with span 0 (the horizontal tension is then ~1e-9 of T: L0 differs by O(span²/L)).
#[test]
fn vertical_rope_hangs_by_its_stretch() {
    let (z, w, ea, t): (f64, f64, f64, f64) = (5.0, 20.0, 1e5, 300.0);
    // (w/2EA) L0² + (1 + T/EA) L0 − z = 0.
    let (a, b) = (w / (2.0 * ea), 1.0 + t / ea);
    let l_above = (-b + (b * b + 4.0 * a * z).sqrt()) / (2.0 * a);
    let above = solve(&chord(0.0, -z, ea, w), t);
    assert!(
        (above.l0_m - l_above).abs() <= 1e-12 * z,
        "{} vs {l_above}",
        above.l0_m
    );
    assert_eq!(above.tension_anchor_n(), t + w * above.l0_m);
    let l_below = (b - (b * b - 4.0 * a * z).sqrt()) / (2.0 * a);
    let below = solve(&chord(0.0, z, ea, w), t);
    assert!(
        (below.l0_m - l_below).abs() <= 1e-10 * z,
        "{} vs {l_below}",
        below.l0_m
    );
    assert_eq!(below.tension_min_n(), t - w * below.l0_m);
    for (sign, vertical) in [(-1.0, above), (1.0, below)] {
        let near = solve(&chord(1e-9, sign * z, ea, w), t);
        assert!(
            (near.l0_m - vertical.l0_m).abs() <= 1e-12 * z,
            "{near:?} vs {vertical:?}"
        );
        assert!(near.h_n < 1e-6 * t && near.h_n > 0.0, "{near:?}");
    }
    // Anchor below with T_e under the rope's weight: too slack, with the numbers.
    let e = chord(0.0, z, ea, w)
        .solve_end_tension(50.0, None, &SagParams::default())
        .unwrap_err();
    match e {
        SagError::TooSlack {
            t_end_n,
            t_end_min_n,
        } => {
            assert_eq!(t_end_n, 50.0);
            assert!((t_end_min_n - w * z).abs() < 1e-2 * w * z, "{e}");
        }
        _ => panic!("{e}"),
    }
}

/// The fold of a level inextensible span: T_e = w a cosh(X/2a) is smallest where
/// u tanh u = 1, u = X/(2a) (u = 1.19967864025773...): T_min = w X cosh(u)/(2u). Below it
/// the solve is TooSlack and names both tensions; just above it, it finds the taut branch
/// (low point inside, minimum tension H). Tolerance 1e-9 (EA = 1e13 T).
#[test]
fn the_fold_of_a_level_span_is_the_smallest_end_tension() {
    let (x, w) = (10.0, 2.0);
    let mut u: f64 = 1.2;
    for _ in 0..50 {
        u -= (u * u.tanh() - 1.0) / (u.tanh() + u / u.cosh().powi(2));
    }
    let t_min = w * x * u.cosh() / (2.0 * u);
    let c = chord(x, 0.0, 1e13 * t_min, w);
    let fold = c.min_end_tension(&SagParams::default()).unwrap();
    assert!(
        (fold.tension_end_n() - t_min).abs() <= 1e-9 * t_min,
        "{} vs {t_min}",
        fold.tension_end_n()
    );
    match c.solve_end_tension(0.99 * t_min, None, &SagParams::default()) {
        Err(SagError::TooSlack {
            t_end_n,
            t_end_min_n,
        }) => {
            assert_eq!(t_end_n, 0.99 * t_min);
            assert!((t_end_min_n - t_min).abs() <= 1e-9 * t_min);
        }
        other => panic!("{other:?}"),
    }
    let near = solve(&c, 1.01 * t_min);
    assert!(
        near.l0_m < fold.l0_m,
        "taut branch: {} < {}",
        near.l0_m,
        fold.l0_m
    );
    assert!(near.v_anchor_n < 0.0 && near.v_end_n() > 0.0);
    assert_eq!(near.tension_min_n(), near.h_n);
}

/// Irvine's λ² up to 1e4 and beyond, EA/T from 1e2 to 1e9, the end above and below the
/// anchor: every solve converges to the chord (1e-12 L, checked in `solve`), lies on the
/// taut branch (shorter than the fold) and its λ² spans the range.
#[test]
fn slack_and_stiff_cables_converge_on_the_taut_branch() {
    let mut lam_max: f64 = 0.0;
    for &(rise, w) in &[(0.0, 1.0), (3.0, 1.0), (-3.0, 1.0), (-8.0, 5.0)] {
        for ratio in [1e2, 1e4, 1e6, 1e9] {
            for t in [20.0, 60.0, 500.0] {
                let c = chord(8.0, rise, ratio * t, w);
                let fold = c.min_end_tension(&SagParams::default()).unwrap();
                if t < fold.tension_end_n() * 1.001 {
                    continue;
                }
                let cat = solve(&c, t);
                assert!(cat.l0_m < fold.l0_m, "{c:?} {t}: not the taut branch");
                lam_max = lam_max.max(cat.irvine_lambda2());
            }
        }
    }
    assert!(lam_max > 1e4, "λ² reached only {lam_max}");
}
