//! FEM → continuous: the sagged FEM chain (`SagChain::set_fem`, corotational truss elements
//! on the exact profile, consistent mass: a discretisation independent of the Magnus chain)
//! converges to the continuous cable as 1/N². At N, 2N, 4N elements the differences to the
//! continuous S(λ) and blocked eigenvalues shrink by ≈ 4 per doubling, and the two-level
//! Richardson extrapolation of the FEM (eliminating 1/N², then 1/N⁴) lands on the
//! continuous value.

use super::kth;
use cablevib::cable::sagged::{SagChain, SagChainEval, SagContinuous, SagContinuousParams};
use cablevib::elastic_catenary::Catenary;

/// Element counts N, 2N, 4N.
const NS: [usize; 3] = [40, 80, 160];

/// Richardson of a 1/N² sequence at N, 2N, 4N: two levels (1/N², then 1/N⁴).
fn richardson(x: [f64; 3]) -> f64 {
    let r1 = (4.0 * x[1] - x[0]) / 3.0;
    let r2 = (4.0 * x[2] - x[1]) / 3.0;
    (16.0 * r2 - r1) / 15.0
}

/// The quantities compared: S_in (3), s_out at λ = λ₁/2, and the first four blocked
/// eigenvalues.
fn quantities(eval: impl Fn(f64) -> SagChainEval, lam_half: f64) -> Vec<f64> {
    let e = eval(lam_half);
    let mut v = vec![e.s_in[0], e.s_in[1], e.s_in[2], e.s_out];
    for k in 1..=4 {
        v.push(kth(|l| eval(l).below, k));
    }
    v
}

/// A moderately (λ² ≈ 12, low point inside) and a heavily (level, λ² ≈ 8e3, d/L ≈ 0.1)
/// sagging cable. The continuous reference at 128 steps is good to ~1e-10 (the convergence
/// study). Asserted: the ratio of successive differences in [3.9, 4.1] (1/N² with its
/// next term 1/N⁴: ratio 4(1 + O(1/N²)), N ≥ 40; measured 3.997 … 4.006) where the
/// difference is above 1e-10 (the reference's own error), and the Richardson value within
/// 1e-8 relative (its remaining term is O(1/N⁶); measured ≤ 1.1e-9).
#[test]
fn fem_converges_to_continuous_as_one_over_n_squared() {
    let cases = [
        (
            "moderate",
            Catenary {
                l0_m: 4.0,
                ea_n: 5e4,
                w_n_m: 0.1 * 9.81,
                h_n: 40.0,
                v_anchor_n: -1.2,
            },
            0.1,
        ),
        (
            "heavy",
            Catenary {
                l0_m: 5.0,
                ea_n: 1e5,
                w_n_m: 2.0,
                h_n: 10.0,
                v_anchor_n: -5.0,
            },
            2.0 / 9.81,
        ),
    ];
    for (name, cat, mu) in cases {
        let mut sc = SagContinuous::new(SagContinuousParams::default());
        sc.set_with_steps(&cat, mu, 128).unwrap();
        let lam_half = 0.5 * kth(|l| sc.eval(l).below, 1);
        let cont = quantities(|l| sc.eval(l), lam_half);
        let mut fem = SagChain::new(NS[2]);
        let runs: Vec<Vec<f64>> = NS
            .iter()
            .map(|&n| {
                fem.set_fem(&cat, mu, n).unwrap();
                quantities(|l| fem.eval(l), lam_half)
            })
            .collect();
        let names = ["S_hh", "S_hu", "S_uu", "s_out", "λ1", "λ2", "λ3", "λ4"];
        for (i, q) in names.iter().enumerate() {
            let scale = if i < 4 {
                cont[..4].iter().map(|x| x.abs()).fold(0.0, f64::max)
            } else {
                cont[i]
            };
            let d: Vec<f64> = runs.iter().map(|r| (r[i] - cont[i]) / scale).collect();
            let rich = richardson([runs[0][i], runs[1][i], runs[2][i]]);
            let rerr = (rich - cont[i]).abs() / scale;
            eprintln!(
                "{name} {q}: Δ at N {:?}: {:.2e} {:.2e} {:.2e}, ratios {:.3} {:.3}, Richardson {rerr:.1e}",
                NS,
                d[0],
                d[1],
                d[2],
                d[0] / d[1],
                d[1] / d[2]
            );
            for j in 0..2 {
                if d[j + 1].abs() > 1e-10 {
                    let r = d[j] / d[j + 1];
                    assert!((3.9..=4.1).contains(&r), "{name} {q}: ratio {r}");
                }
            }
            assert!(rerr <= 1e-8, "{name} {q}: Richardson {rerr:.1e}");
        }
    }
}
