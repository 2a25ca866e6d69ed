//! The sagged FEM against physics it shares no code with: Irvine's shallow-cable theory
//! (Irvine, Cable Structures, ch. 3) for a level cable with both ends fixed, and the
//! discretisation's 1/N² convergence on a heavily sagging cable.
//!
//! A chain's blocked (end held) eigenvalues are the fixed-fixed cable's: the λ where its
//! Wittrick–Williams count `below` steps, found here by bisection on the count.

use cablevib::cable::sagged::SagChain;
use cablevib::elastic_catenary::Catenary;
use cablevib::modal::sagged::HangingCable;
use cablevib::modal::SagModalSolver;
use cablevib::modal::{ModalParams, Mode};
use cablevib_testkit::sag_robot::*;
use nalgebra::Vector3;

/// The first `k` blocked eigenvalues of `c` (λ, rad²/s²) by bisection on its count, to
/// 1e-13 relative.
fn poles(c: &SagChain, k: usize) -> Vec<f64> {
    let mut out = Vec::new();
    let mut lo = 0.0f64;
    for j in 0..k as u32 {
        let mut hi = lo.max(1.0) * 2.0;
        while c.eval(hi).below <= j {
            lo = hi;
            hi *= 2.0;
        }
        while hi - lo > 1e-13 * hi {
            let mid = 0.5 * (lo + hi);
            if c.eval(mid).below > j {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        out.push(0.5 * (lo + hi));
    }
    out
}

/// A level cable of span ≈ `span` with sag/span `ratio` and Irvine's λ² ≈ `lambda2`
/// (μ = 1 kg/m): H from the parabola d = wL²/(8H), EA from λ² = (8d/L)² EA/H · L/L_e,
/// V_a = −wL0/2 (symmetric), L0 = span (the profile's own span, used below, differs by
/// O((d/L)², H/EA)).
fn level_cable(span: f64, ratio: f64, lambda2: f64) -> Catenary {
    let w = G;
    let h = w * span / (8.0 * ratio);
    let ea = lambda2 * h * (1.0 + 8.0 * ratio * ratio) / (8.0 * ratio).powi(2);
    Catenary {
        l0_m: span,
        ea_n: ea,
        w_n_m: w,
        h_n: h,
        v_anchor_n: -0.5 * w * span,
    }
}

/// Irvine's symmetric in-plane roots β = ωL/√(H/μ): tan(β/2) = β/2 − (4/λ²)(β/2)³, the k-th
/// on the branch ((2k − 1)π/2, (2k + 1)π/2) of tan, where the difference is increasing.
fn irvine_symmetric(lambda2: f64, k: usize) -> f64 {
    let f = |x: f64| x.tan() - x + 4.0 / lambda2 * x * x * x;
    let pi = std::f64::consts::PI;
    let (mut lo, mut hi) = (
        (2 * k - 1) as f64 * pi / 2.0 + 1e-12,
        (2 * k + 1) as f64 * pi / 2.0 - 1e-12,
    );
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    lo + hi
}

/// Irvine's first `k` fixed-fixed frequencies as β = ωL/√(H/μ), ascending: out of plane
/// nπ; in plane antisymmetric 2nπ; in plane symmetric from [`irvine_symmetric`].
fn irvine_betas(lambda2: f64, k: usize) -> Vec<f64> {
    let pi = std::f64::consts::PI;
    let mut b: Vec<f64> = (1..=k).map(|n| n as f64 * pi).collect();
    b.extend((1..=k).map(|n| 2.0 * n as f64 * pi));
    b.extend((1..=k).map(|n| irvine_symmetric(lambda2, n)));
    b.sort_by(|a, b| a.total_cmp(b));
    b.truncate(k);
    b
}

/// Worst relative error of the FEM's fixed-fixed frequencies against Irvine's first 8.
fn irvine_error(ratio: f64, lambda2: f64) -> f64 {
    let cat = level_cable(10.0, ratio, lambda2);
    let n_el = 400;
    let mut c = SagChain::new(n_el);
    c.set_fem(&cat, 1.0, n_el).unwrap();
    let span = cat.end_point_m()[0];
    // ω = β √(H/m)/L with m the mass per length of the stretched cable, μ/(1 + T/EA)
    // (μ = 1 kg/m is per unstretched length; T ≈ H to the theory's order).
    let m = 1.0 / (1.0 + cat.h_n / cat.ea_n);
    let scale = (cat.h_n / m).sqrt() / span;
    let want = irvine_betas(lambda2, 8);
    let got = poles(&c, 8);
    let mut worst = 0.0f64;
    for (b, l) in want.iter().zip(&got) {
        let w = l.sqrt() / scale;
        worst = worst.max((w - b).abs() / b);
    }
    worst
}

#[test]
fn shallow_level_cable_matches_irvine() {
    // Irvine's theory drops terms of relative order (d/L)² (the tension's rise T/H − 1 ≤
    // 8(d/L)² at the supports, the arc's excess over the span (8/3)(d/L)²) and of order
    // H/EA beyond its own (the stretched geometry); the FEM (N = 400) adds (nπ/N)²/24 ≤ 1e-4
    // on ω for the modes compared. Tolerance: 8(d/L)² + H/EA + 1e-4. Measured: 2.1e-3 at
    // sag/span 1/50 and 1.3e-2 at 1/20 (≈ 5(d/L)² both), 7.6e-2 for the very stretchy
    // λ² = 2 at 1/20 (H/EA = 0.08).
    let mut errs = Vec::new();
    for ratio in [1.0 / 50.0, 1.0 / 20.0] {
        for lambda2 in [2.0, 20.0, 100.0] {
            let err = irvine_error(ratio, lambda2);
            let cat = level_cable(10.0, ratio, lambda2);
            let tol = 8.0 * ratio * ratio + cat.h_n / cat.ea_n + 1e-4;
            eprintln!(
                "sag/span {ratio:.3} λ² {lambda2}: worst ω error {err:.2e} (tolerance {tol:.2e})"
            );
            assert!(
                err < tol,
                "sag/span {ratio} λ² {lambda2}: {err:.3e} ≥ {tol:.3e}"
            );
            errs.push(err);
        }
    }
    // The residual is the theory's own truncation: it scales as (d/L)², (50/20)² = 6.25,
    // at λ² = 20 and 100 (where H/EA is small): at least 4.
    for j in 1..3 {
        assert!(errs[3 + j] > 4.0 * errs[j], "{errs:?}");
    }
}

#[test]
fn heavy_sag_converges_as_one_over_n_squared() {
    // A level cable sagging 1/8 of its span with λ² = 50: the fixed-fixed modes and, on a
    // two-cable robot, the end-effector's modes. Successive differences at N, 2N, 4N, 8N
    // must shrink by 4 (second-order FEM): ratios in [3.6, 4.4] (the O(1/N⁴) term moves
    // them by ~(nπ/N)² ≲ 5 % at N = 20).
    let cat = level_cable(10.0, 1.0 / 8.0, 50.0);
    let ns = [20usize, 40, 80, 160];
    let k = 5;
    let per_n: Vec<Vec<f64>> = ns
        .iter()
        .map(|&n| {
            let mut c = SagChain::new(n);
            c.set_fem(&cat, 1.0, n).unwrap();
            poles(&c, k)
        })
        .collect();
    check_ratios("fixed-fixed", &per_n, k);
    let mirrored = Catenary {
        v_anchor_n: -0.3 * cat.w_n_m * cat.l0_m,
        ..cat
    };
    let cables = [
        HangingCable {
            catenary: cat,
            mu_kg_m: 1.0,
            h: Vector3::x(),
            arm_m: Vector3::zeros(),
        },
        HangingCable {
            catenary: mirrored,
            mu_kg_m: 1.0,
            h: Vector3::new(-0.6, 0.8, 0.0),
            arm_m: Vector3::zeros(),
        },
    ];
    let per_n: Vec<Vec<f64>> = ns
        .iter()
        .map(|&n| {
            let mut s = SagModalSolver::new(ModalParams::default(), 2, n);
            s.load_catenaries(&cables, n, &up(), &point()).unwrap();
            let mut m = vec![Mode::default(); k];
            s.modes(k, &mut m).unwrap();
            m.iter().map(|m| m.lambda).collect()
        })
        .collect();
    check_ratios("robot", &per_n, k);
}

fn check_ratios(what: &str, per_n: &[Vec<f64>], k: usize) {
    for j in 0..k {
        let d: Vec<f64> = (0..per_n.len() - 1)
            .map(|i| per_n[i][j] - per_n[i + 1][j])
            .collect();
        let r: Vec<f64> = (0..d.len() - 1).map(|i| d[i] / d[i + 1]).collect();
        eprintln!(
            "{what} mode {j}: λ {:.6e}, difference ratios {r:.3?}",
            per_n[per_n.len() - 1][j]
        );
        for &x in &r {
            assert!((3.6..=4.4).contains(&x), "{what} mode {j}: ratios {r:?}");
        }
    }
}
