//! Timings (#[ignore], no timed asserts): the continuous sagged cable beside the taut
//! continuous chain and the sagged FEM chain, in the same run.

use super::{solver_eigenvalue, G};
use cablevib::cable::sagged::{SagContinuous, SagContinuousParams};
use cablevib::elastic_catenary::Catenary;

/// ns per eval (in plane + out of plane) at Irvine's λ² ≈ 1, 100, 1e4, for rel_tol 1e-7
/// (max_halfwaves 1 and 4) and 1e-9 (4), next to the taut continuous chain's eval (axial + transverse) and the sagged
/// FEM chain (`SagChain::set_fem`) at N = 40 and 160, all in the same run, at
/// λ = 0.7 λ₁ and at λ = 0.9 λ₄ (λ_k the continuous cable's blocked eigenvalues). No timed
/// assert.
#[test]
#[ignore]
fn timing_per_eval() {
    use cablevib::cable::sagged::SagChain;
    use cablevib::cable::{Chain, ChainKind};
    use nalgebra::Matrix3;
    use std::hint::black_box;
    use std::time::Instant;
    let level = |ea: f64, w: f64, h: f64| Catenary {
        l0_m: 5.0,
        ea_n: ea,
        w_n_m: w,
        h_n: h,
        v_anchor_n: -2.5 * w,
    };
    let cases = [
        ("λ² ≈ 1", level(5e4, 0.316, 50.0)),
        ("λ² ≈ 100", level(5e4, 3.16, 50.0)),
        ("λ² ≈ 1e4", level(1e5, 2.0, 10.0)),
    ];
    let chain = |k: f64| Chain {
        kind: ChainKind::Continuous {
            k_total: k,
            m_total: 0.5,
        },
        mult: 1,
        proj: Matrix3::identity(),
    };
    const N: usize = 20000;
    // The best of 10 rounds of N/10 evaluations (the machine is shared: the minimum is
    // the least disturbed).
    let time = |f: &dyn Fn(f64) -> f64, lam: f64| {
        let mut best = f64::INFINITY;
        for _ in 0..10 {
            let t = Instant::now();
            let mut acc = 0.0;
            for i in 0..N / 10 {
                acc += f(black_box(lam * (1.0 + 1e-4 * (i % 7) as f64)));
            }
            black_box(acc);
            best = best.min(t.elapsed().as_nanos() as f64 / (N / 10) as f64);
        }
        best
    };
    let (bar, string) = (chain(1e4), chain(10.0));
    let taut = time(&|l| bar.eval(l).s + string.eval(l).s, 50.0);
    eprintln!("taut continuous chain pair (axial + transverse): {taut:.0} ns/eval");
    for (name, cat) in cases {
        let mu = cat.w_n_m / G;
        let lam2 = cat.irvine_lambda2();
        let mut fem = SagChain::new(160);
        let mut sc = SagContinuous::new(SagContinuousParams::default());
        sc.set(&cat, mu).unwrap();
        let (l1, l4) = (solver_eigenvalue(&sc, 1), solver_eigenvalue(&sc, 4));
        let mut line = format!("{name} (λ² {lam2:.1e}), ns/eval at 0.7λ₁ | 0.9λ₄:");
        for n in [40usize, 160] {
            fem.set_fem(&cat, mu, n).unwrap();
            let a = time(&|l| fem.eval(l).s_out, 0.7 * l1);
            let b = time(&|l| fem.eval(l).s_out, 0.9 * l4);
            line += &format!(" FEM N {n}: {a:.0} | {b:.0};");
        }
        for (tol, n_hw) in [(1e-7, 1.0), (1e-7, 4.0), (1e-9, 4.0)] {
            let params = SagContinuousParams {
                rel_tol: tol,
                max_halfwaves: n_hw,
            };
            let mut sc = SagContinuous::new(params);
            let mesh = sc.set(&cat, mu).unwrap();
            let mut set_ns = f64::INFINITY;
            for _ in 0..10 {
                let t = Instant::now();
                for _ in 0..20 {
                    black_box(sc.set(black_box(&cat), mu).unwrap());
                }
                set_ns = set_ns.min(t.elapsed().as_nanos() as f64 / 20.0);
            }
            let a = time(&|l| sc.eval(l).s_out, 0.7 * l1);
            let b = time(&|l| sc.eval(l).s_out, 0.9 * l4);
            let m = mesh.steps;
            line += &format!(
                " cont {tol:.0e} n_hw {n_hw} (M {m}, set {set_ns:.0} ns): {a:.0} | {b:.0};"
            );
        }
        eprintln!("{line}");
    }
}

/// ns per eval against the number of steps M (fixed cost and cost per sub-segment), on the
/// level λ² ≈ 100 cable at 0.7 λ₁. No timed assert.
#[test]
#[ignore]
fn timing_against_steps() {
    use std::hint::black_box;
    use std::time::Instant;
    let cat = Catenary {
        l0_m: 5.0,
        ea_n: 5e4,
        w_n_m: 3.16,
        h_n: 50.0,
        v_anchor_n: -2.5 * 3.16,
    };
    let mu = cat.w_n_m / G;
    let mut sc = SagContinuous::new(SagContinuousParams::default());
    sc.set(&cat, mu).unwrap();
    let lam = 0.7 * solver_eigenvalue(&sc, 1);
    for m in [1usize, 2, 4, 8, 16, 32, 64, 128] {
        sc.set_with_steps(&cat, mu, m).unwrap();
        let mut best = f64::INFINITY;
        for _ in 0..10 {
            let t = Instant::now();
            let mut acc = 0.0;
            for i in 0..2000 {
                acc += sc
                    .eval(black_box(lam * (1.0 + 1e-4 * (i % 7) as f64)))
                    .s_out;
            }
            black_box(acc);
            best = best.min(t.elapsed().as_nanos() as f64 / 2000.0);
        }
        eprintln!(
            "M {m:3}: {best:.0} ns/eval, {:.1} ns per sub-segment",
            best / (2 * m) as f64
        );
    }
}
