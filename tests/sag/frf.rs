//! The receptance of sagging cables (FEM chains on the catenary) at a complex λ
//! ([`cablevib::modal::SagModalSolver::receptance`]: each chain's in-plane 2 × 2
//! and out-of-plane scalar recurrences at complex λ) against an independent reference: a
//! dense complex LU solve of the assembled sagged (1 + iη)K − ω²M and (1 + iωβ)K −
//! (ω² − iωα)M ([`cablevib::modal::sagged::assemble_sagged`]: the world-frame element
//! matrices, sharing only the element data) at each frequency, on suspended-8 (point mass)
//! and the paper's spatial robot with sag (rigid body), N = 10.
//!
//! Tolerance 1e-9 relative (Frobenius) away from resonances: both are backward-stable
//! solves of the same complex matrix, so they differ by ~ε·κ; the frequencies lie at the
//! an even grid, kept where |ω²/λ_r − 1| ≥ 2 % for every dense eigenvalue λ_r.
//! On a resonance the bound is 1e-9·κ, κ ~ 1/η: checked at 1e-7. Measured: away 3.8e-10
//! (suspended-8) and 2.5e-10 (paper robot); on the lowest four resonances 4.1e-9 and 3.4e-10.

use cablevib::modal::dense_receptance;
use cablevib::modal::FrfError;
use cablevib::scene::{Damping, ElementKind, Scene};
use cablevib_testkit::sag_cases::{loaded, sagged_robots};
use nalgebra::Matrix6;
use num_complex::Complex64;

/// Away from resonances: two backward-stable complex solves (module docs).
const AWAY_TOL: f64 = 1e-9;
/// On a resonance: the same, times the condition ~1/η.
const ON_TOL: f64 = 1e-7;

const DAMPINGS: [Damping; 3] = [
    Damping::LossFactor { eta: 0.02 },
    Damping::Rayleigh {
        alpha_per_s: 0.5,
        beta_s: 2e-4,
    },
    Damping::LossFactor { eta: 0.005 },
];

/// suspended-8 (point mass) and the paper's spatial robot with sag (rigid body), FEM × n.
fn scenes(n: usize) -> [Scene; 2] {
    let [suspended, _fast_like, paper] = sagged_robots(n);
    [suspended, paper]
}

fn rel(a: &Matrix6<Complex64>, b: &Matrix6<Complex64>, dim: usize) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for i in 0..dim {
        for j in 0..dim {
            num += (a[(i, j)] - b[(i, j)]).norm_sqr();
            den += b[(i, j)].norm_sqr();
        }
    }
    (num / den).sqrt()
}

/// Closest relative distance |ω²/λ_r − 1| from ω (rad/s) to the model's eigenvalues.
fn nearness(lambda: &[f64], w: f64) -> f64 {
    lambda
        .iter()
        .map(|l| (w * w / l - 1.0).abs())
        .fold(f64::INFINITY, f64::min)
}

/// Frequencies (rad/s) of an even grid on [0, `to`] (`points`) at least [`AWAY`] from
/// every eigenvalue of the dense model.
fn away_from(lambda: &[f64], to: f64, points: usize) -> Vec<f64> {
    (0..points)
        .map(|i| to * i as f64 / (points - 1) as f64)
        .filter(|&w| nearness(lambda, w) >= AWAY)
        .collect()
}

/// "Away from resonances": |ω²/λ_r − 1| ≥ 2 % for every mode r (the sagged robots' modes
/// come in clusters 0.5 % apart, so a midpoint between two is not away).
const AWAY: f64 = 0.02;

/// Sagged FEM, N = 10: structured complex D vs the dense complex solve, away from and on
/// the lowest resonances, loss factor and Rayleigh.
#[test]
fn sagged_receptance_matches_dense_complex_solve() {
    for s in scenes(10) {
        let est = loaded(&s);
        let (k, m) = est.dense_matrices().unwrap();
        let dense = est.dense_modes(false).unwrap();
        let mut sag = est.sag_modal().expect("sagged solver").clone();
        let dim = sag.dim();
        let lam: Vec<f64> = dense.lambda.iter().take(12).copied().collect();
        let away_w = away_from(&dense.lambda, lam[lam.len() - 1].sqrt(), 200);
        let (mut away, mut on) = (0.0f64, 0.0f64);
        for d in &DAMPINGS {
            for &w in &away_w {
                let h = sag.receptance(d, w).unwrap();
                let r = dense_receptance(&k, &m, dim, d, w).unwrap();
                away = away.max(rel(&h, &r, dim));
            }
            for &l in lam.iter().take(4) {
                let w = l.sqrt();
                let h = sag.receptance(d, w).unwrap();
                let r = dense_receptance(&k, &m, dim, d, w).unwrap();
                on = on.max(rel(&h, &r, dim));
            }
        }
        println!(
            "{}: {} DOF, {} frequencies away: worst rel {away:.2e}; on the lowest 4 resonances {on:.2e}",
            s.name,
            k.nrows(),
            away_w.len()
        );
        assert!(away <= AWAY_TOL, "{}: away {away:.3e}", s.name);
        assert!(on <= ON_TOL, "{}: on {on:.3e}", s.name);
    }
}

/// Undamped, away from resonances: one real evaluation of D against the dense solve.
#[test]
fn sagged_undamped_receptance_matches_dense() {
    let s = &scenes(10)[0];
    let est = loaded(s);
    let (k, m) = est.dense_matrices().unwrap();
    let dense = est.dense_modes(false).unwrap();
    let mut sag = est.sag_modal().unwrap().clone();
    let ws = away_from(&dense.lambda, dense.lambda[11].sqrt(), 50);
    assert!(ws.len() >= 10);
    for w in ws {
        let h = sag.receptance(&Damping::None, w).unwrap();
        let r = dense_receptance(&k, &m, 3, &Damping::None, w).unwrap();
        assert!(
            rel(&h, &r, 3) <= AWAY_TOL,
            "{:.3e} at w {w}",
            rel(&h, &r, 3)
        );
    }
}

/// Modal damping (it goes by a modal basis) and the continuous model's damped response are
/// refused, each with its own error.
#[test]
fn sagged_refusals() {
    let s = &scenes(10)[0];
    let est = loaded(s);
    let mut sag = est.sag_modal().unwrap().clone();
    assert_eq!(
        sag.receptance(&Damping::ModalRatio { zeta: 0.01 }, 10.0),
        Err(FrfError::NeedsModes)
    );
    let mut c = s.clone();
    c.model.element = ElementKind::Continuous;
    let est = loaded(&c);
    let mut sag = est.sag_modal().unwrap().clone();
    let e = sag
        .receptance(&Damping::LossFactor { eta: 0.02 }, 10.0)
        .unwrap_err();
    assert_eq!(e, FrfError::SagContinuous);
    assert!(e.to_string().contains("takes the fem element"));
}
