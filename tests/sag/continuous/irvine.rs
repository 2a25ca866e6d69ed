//! Irvine's linear theory of a level shallow cable (H. M. Irvine, *Cable Structures*, 1981,
//! ch. 3), written here from its closed forms: no code shared with the solver. Both ends
//! fixed, so the theory's eigenvalues are the solver's blocked eigenvalues (where `below`
//! steps). With m the mass per span length and H the horizontal tension:
//!
//! - out of plane, and in plane antisymmetric: strings, ω_n = (nπ/L) √(H/m);
//! - in plane symmetric: ω = (β/L) √(H/m) with tan(β/2) = β/2 − (4/λ²)(β/2)³;
//! - static chord stiffness: E_eq A/L, E_eq = E/(1 + (wL)² EA/(12 H³)) (Ernst).
//!
//! The theory neglects terms of relative size (d/L)² (the profile's slope, the tension's
//! and the arc length's variation along the span; L_e/L − 1 = 8(d/L)²) and H/EA (the
//! stretch): the tolerances are a multiple of ε = 8(d/L)² + H/EA, the multiple stated
//! per check.

use super::{kth, G};
use cablevib::cable::sagged::{SagContinuous, SagContinuousParams};
use cablevib::elastic_catenary::Catenary;
use std::f64::consts::PI;

/// EA/H of the test cables (stretch 5e-5): λ² then sets the sag, λ² ≈ 64 (d/L)² EA/H.
const EA_OVER_H: f64 = 2e4;

/// A level cable of unstretched length 10 m, μ = 1 kg/m, with Irvine's λ² ≈ `lam2`.
fn level(lam2: f64) -> (Catenary, f64) {
    let (l0, mu) = (10.0, 1.0);
    let w = mu * G;
    let d_over_l = (lam2 / (64.0 * EA_OVER_H)).sqrt();
    let h = w * l0 / (8.0 * d_over_l);
    let cat = Catenary {
        l0_m: l0,
        ea_n: EA_OVER_H * h,
        w_n_m: w,
        h_n: h,
        v_anchor_n: -0.5 * w * l0,
    };
    (cat, mu)
}

/// Span L, sag ratio d/L, mass and weight per span length, Irvine's λ², ε (module docs).
struct Theory {
    span: f64,
    d: f64,
    m: f64,
    lam2: f64,
    eps: f64,
    h: f64,
    ea: f64,
    wm: f64,
}

fn theory(cat: &Catenary, mu: f64) -> Theory {
    let [span, z] = cat.end_point_m();
    assert!(z.abs() <= 1e-9 * span, "not level");
    let d = cat.sag_m() / span;
    let m = mu * cat.l0_m / span;
    let wm = m * G;
    let l_e = span * (1.0 + 8.0 * d * d);
    let lam2 = (wm * span / cat.h_n).powi(2) * span / (cat.h_n * l_e / cat.ea_n);
    Theory {
        span,
        d,
        m,
        lam2,
        eps: 8.0 * d * d + cat.h_n / cat.ea_n,
        h: cat.h_n,
        ea: cat.ea_n,
        wm,
    }
}

/// The k-th root x = β/2 of tan x = x − (4/λ²) x³ on (kπ − π/2, kπ + π/2), by bisection
/// (the difference is increasing there: sec² x − 1 + 12x²/λ² > 0).
fn symmetric_root(lam2: f64, k: u32) -> f64 {
    let f = |x: f64| x.tan() - x + 4.0 / lam2 * x * x * x;
    let (mut lo, mut hi) = ((k as f64 - 0.5) * PI + 1e-12, (k as f64 + 0.5) * PI - 1e-12);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The first `n` theory eigenvalues λ = ω² (out of plane, in-plane antisymmetric and
/// symmetric together), sorted.
fn theory_eigenvalues(t: &Theory, n: usize) -> Vec<f64> {
    let c = t.h / (t.m * t.span * t.span);
    let mut v = Vec::new();
    for k in 1..=n {
        let nk = k as f64 * PI;
        v.push(nk * nk * c); // out of plane
        let a = 2.0 * nk;
        v.push(a * a * c); // in plane antisymmetric (n = 2k)
        let beta = 2.0 * symmetric_root(t.lam2, k as u32);
        v.push(beta * beta * c); // in plane symmetric
    }
    v.sort_by(f64::total_cmp);
    v.truncate(n);
    v
}

/// The first six blocked eigenvalues against the theory for λ² = 0.1 … 1e3 (sag ≤ 1/30 of
/// the span): relative difference ≤ 3ε. Near Irvine's crossovers (λ² = 4π², 16π²) the
/// symmetric mode's β is sensitive to λ² (dβ/dλ² finite), still O(ε).
#[test]
fn level_cable_modes_match_irvine() {
    for lam2_target in [0.1, 1.0, 10.0, 4.0 * PI * PI, 100.0, 1e3] {
        let (cat, mu) = level(lam2_target);
        let t = theory(&cat, mu);
        assert!(t.d <= 1.0 / 30.0, "sag ratio {}", t.d);
        let mut sc = SagContinuous::new(SagContinuousParams::default());
        sc.set(&cat, mu).unwrap();
        let want = theory_eigenvalues(&t, 6);
        let mut line = String::new();
        for (k, &w) in want.iter().enumerate() {
            let got = kth(|l| sc.eval(l).below, k as u32 + 1);
            let err = (got - w).abs() / w;
            line += &format!(" {:.1e}", err / t.eps);
            assert!(
                err <= 3.0 * t.eps,
                "λ² {} mode {}: {got} vs Irvine {w} ({err:.1e}, ε {:.1e})",
                t.lam2,
                k + 1,
                t.eps
            );
        }
        eprintln!(
            "λ² {:.3e}, d/L {:.2e}, ε {:.1e}: |Δλ|/λ in units of ε:{line}",
            t.lam2, t.d, t.eps
        );
    }
}

/// The static chord stiffness (h-h entry of S(0): the chord is horizontal) against
/// Ernst's E_eq A/L: relative difference ≤ 3ε (the same neglected terms).
#[test]
fn static_chord_stiffness_matches_ernst() {
    for lam2_target in [0.1, 1.0, 10.0, 100.0, 1e3] {
        let (cat, mu) = level(lam2_target);
        let t = theory(&cat, mu);
        let mut sc = SagContinuous::new(SagContinuousParams::default());
        sc.set(&cat, mu).unwrap();
        let s = sc.static_eval().s_in[0];
        let h3 = t.h * t.h * t.h;
        let e_eq_a = t.ea / (1.0 + (t.wm * t.span).powi(2) * t.ea / (12.0 * h3));
        let want = e_eq_a / t.span;
        let err = (s - want).abs() / want;
        eprintln!(
            "λ² {:.3e}: S_hh(0) {s:.6e}, Ernst {want:.6e}: {err:.1e} = {:.2} ε",
            t.lam2,
            err / t.eps
        );
        assert!(
            err <= 3.0 * t.eps,
            "λ² {}: {err:.1e} vs ε {:.1e}",
            t.lam2,
            t.eps
        );
        // Also the same number as eval(0) (the recursion; the cached S(0) is the springs-in-
        // series closed form), to 1e-12 of the largest entry.
        let (r, c) = (sc.eval(0.0).s_in, sc.static_eval().s_in);
        let scale = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..3 {
            assert!((r[i] - c[i]).abs() <= 1e-12 * scale, "{r:?} vs {c:?}");
        }
    }
}
