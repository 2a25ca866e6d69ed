//! The first K modes of the sagged problem: count brackets, bisection across poles,
//! safeguarded Newton on one branch of D in a pole-free bracket, clusters from the count.

use super::problem::SagProblem;
use super::SagModalSolver;
use crate::modal::dynamic_stiffness::quad;
use crate::modal::{lambda_to_hz, DynEval, EigD, ModalError, Mode, SpectrumParams};
use nalgebra::{Matrix6, SymmetricEigen};

/// Without a better scale, the first bracket starts here (rad²/s²).
const BRACKET_MIN: f64 = 1e-12;
/// Upper brackets grow by this factor per count probe.
const BRACKET_GROWTH: f64 = 2.0;
/// The bracket counts as collapsed when narrower than this many ε relative to λ.
const COLLAPSE_ULPS: f64 = 4.0;
/// A Newton step below this (relative) and below [`SUPERLINEAR_RATIO`] × the previous one
/// shows superlinear convergence: the next iterate is within ~step² of the root (steps of
/// rounding noise end the iteration this way instead of bouncing).
const NOISE_STEP: f64 = 1e-10;
/// See [`NOISE_STEP`].
const SUPERLINEAR_RATIO: f64 = 1e-2;

/// λ, the count J(λ) and the blocked count there.
#[derive(Debug, Clone, Copy)]
struct Probe {
    x: f64,
    count: u32,
    below: u32,
}

/// A mode found: at a pole, or as the zero of `branch` with the evaluation nearest to it.
/// Short-lived, returned once per mode: the large variant's size does not matter.
#[allow(clippy::large_enum_variant)]
enum Found {
    Pole(f64),
    Branch {
        lambda: f64,
        eval: DynEval,
        eig: EigD,
        branch: usize,
    },
}

/// One ascending sweep over the loaded problem's spectrum.
struct Sweep<'a> {
    p: &'a SagProblem,
    params: &'a SpectrumParams,
    evals: &'a mut u32,
    mode_start: u32,
}

impl SagModalSolver {
    /// The first `k` natural frequencies (ascending) into `out`, [`SpectrumParams::default`].
    /// Returns how many were written: min(k, out.len(), [`Self::total_modes`]).
    pub fn modes(&mut self, k: usize, out: &mut [Mode]) -> Result<usize, ModalError> {
        self.modes_with(k, &SpectrumParams::default(), out)
    }

    /// [`Self::modes`] with explicit parameters (`pole_probe` is the relative width at
    /// which a bisection across a pole stops and reports the mode at the pole).
    pub fn modes_with(
        &mut self,
        k: usize,
        params: &SpectrumParams,
        out: &mut [Mode],
    ) -> Result<usize, ModalError> {
        self.require_loaded()?;
        let n = k.min(out.len()).min(self.problem.total_modes());
        let e0 = self.problem.static_eval();
        let eg0 = e0.eig();
        if !(eg0.values[0] > 0.0) {
            return Err(ModalError::NotPositiveDefinite(eg0.values[0]));
        }
        let kin = -quad(&e0.dd, &eg0.vectors[0], e0.dim);
        let scale = if kin > 0.0 {
            eg0.values[0] / kin
        } else {
            BRACKET_MIN
        };
        let mut s = Sweep {
            p: &self.problem,
            params,
            evals: &mut self.evaluations,
            mode_start: 0,
        };
        let mut lo = Probe {
            x: 0.0,
            count: 0,
            below: 0,
        };
        let mut i = 0;
        while i < n {
            s.mode_start = *s.evals;
            let (a, b) = s.grow(i, lo, scale)?;
            let found = s.solve(i, a, b)?;
            let lambda = match found {
                Found::Pole(x) => x,
                Found::Branch { lambda, .. } => lambda,
            };
            let d = params.cluster_probe;
            let (plo, phi) = (s.probe(lambda * (1.0 - d)), s.probe(lambda * (1.0 + d)));
            let (start, end) = (plo.count as usize, phi.count as usize);
            if !(start <= i && i < end) {
                return Err(ModalError::CountMismatch(lambda));
            }
            let parts = match &found {
                Found::Pole(_) => [0.0; 6],
                Found::Branch {
                    eval, eig, branch, ..
                } => cluster_participations(s.p, eval, eig, *branch, end - i),
            };
            for j in i..end.min(n) {
                let lj = if j == i {
                    lambda
                } else {
                    s.mode_start = *s.evals;
                    match s.solve(j, plo, phi)? {
                        Found::Pole(x) => x,
                        Found::Branch { lambda, .. } => lambda,
                    }
                };
                out[j] = Mode {
                    lambda: lj,
                    frequency_hz: lambda_to_hz(lj),
                    ee_participation: parts.get(j - i).copied().unwrap_or(0.0),
                    cluster_start: start,
                    multiplicity: (end - start) as u32,
                };
            }
            i = end;
            lo = phi;
        }
        Ok(n)
    }
}

impl Sweep<'_> {
    fn probe(&mut self, x: f64) -> Probe {
        *self.evals = self.evals.wrapping_add(1);
        // The count only: no D'.
        let e = self.p.eval_with(x, false);
        Probe {
            x,
            count: e.below + e.eig().negatives() as u32,
            below: e.below,
        }
    }

    fn check_budget(&self, lo: f64, hi: f64) -> Result<(), ModalError> {
        let used = self.evals.wrapping_sub(self.mode_start);
        if used >= self.params.max_evaluations_per_mode {
            return Err(ModalError::NoConvergence {
                evaluations: used,
                lo,
                hi,
            });
        }
        Ok(())
    }

    /// From `lo` (J(lo) ≤ i) grow an upper bracket hi with J(hi) > i.
    fn grow(&mut self, i: usize, mut lo: Probe, scale: f64) -> Result<(Probe, Probe), ModalError> {
        let mut x = if lo.x > 0.0 {
            lo.x * BRACKET_GROWTH
        } else {
            (BRACKET_GROWTH * scale).max(BRACKET_MIN)
        };
        loop {
            self.check_budget(lo.x, x)?;
            let pr = self.probe(x);
            if pr.count as usize > i {
                return Ok((lo, pr));
            }
            lo = pr;
            x *= BRACKET_GROWTH;
        }
    }

    /// Narrow J(lo) ≤ i < J(hi) to mode i: bisection on the count while a pole lies inside
    /// (the blocked count differs at the ends), Newton once the bracket is pole-free.
    fn solve(&mut self, i: usize, mut lo: Probe, mut hi: Probe) -> Result<Found, ModalError> {
        loop {
            self.check_budget(lo.x, hi.x)?;
            if lo.below == hi.below {
                let branch = i - lo.below as usize;
                return self.newton(branch, lo.x, hi.x);
            }
            if hi.x - lo.x <= self.params.pole_probe * hi.x {
                return Ok(Found::Pole(0.5 * (lo.x + hi.x)));
            }
            let mid = self.probe(0.5 * (lo.x + hi.x));
            if mid.count as usize > i {
                hi = mid;
            } else {
                lo = mid;
            }
        }
    }

    /// Zero of branch `branch` of D in the pole-free (lo, hi) (positive at lo, negative at
    /// hi): Newton, bisection whenever a step leaves the bracket or fails to halve it.
    fn newton(&mut self, branch: usize, mut lo: f64, mut hi: f64) -> Result<Found, ModalError> {
        let mut x = 0.5 * (lo + hi);
        let mut last_step = f64::INFINITY;
        loop {
            self.check_budget(lo, hi)?;
            *self.evals = self.evals.wrapping_add(1);
            let e = self.p.eval(x);
            let eg = e.eig();
            let mu = eg.values[branch];
            let dmu = quad(&e.dd, &eg.vectors[branch], e.dim);
            if mu > 0.0 {
                lo = lo.max(x);
            } else if mu < 0.0 {
                hi = hi.min(x);
            }
            let next = if dmu < 0.0 { x - mu / dmu } else { f64::NAN };
            let step = (next - x).abs() / x;
            let collapsed = hi - lo <= COLLAPSE_ULPS * f64::EPSILON * x;
            let converged = step <= self.params.rel_tol
                || (step <= NOISE_STEP && step <= SUPERLINEAR_RATIO * last_step);
            if mu == 0.0 || collapsed || (converged && next > lo && next < hi) {
                let lambda = if mu == 0.0 || !(next > lo && next < hi) {
                    x
                } else {
                    next
                };
                return Ok(Found::Branch {
                    lambda,
                    eval: e,
                    eig: eg,
                    branch,
                });
            }
            let width = hi - lo;
            x = if next > lo && next < hi && (next - x).abs() < 0.5 * width {
                next
            } else {
                0.5 * (lo + hi)
            };
            last_step = step;
        }
    }
}

/// The participations of the `mult` modes of a cluster whose first branch is `branch` at
/// the evaluation `e` (eigen-decomposition `eg`): the eigenvalues (descending) of
/// M^{1/2} V G⁻¹ Vᵀ M^{1/2}, V the branches' unit eigenvectors, G = Vᵀ(−D')V; members beyond
/// D's dimension (at a pole) get 0.
fn cluster_participations(
    p: &SagProblem,
    e: &DynEval,
    eg: &EigD,
    branch: usize,
    mult: usize,
) -> [f64; 6] {
    let mut out = [0.0; 6];
    let r = mult.min(eg.n.saturating_sub(branch));
    if r == 0 {
        return out;
    }
    let mut g = Matrix6::identity();
    for a in 0..r {
        for b in 0..r {
            let (va, vb) = (&eg.vectors[branch + a], &eg.vectors[branch + b]);
            g[(a, b)] = -(va.transpose() * e.dd * vb)[(0, 0)];
        }
    }
    let Some(gi) = g.try_inverse() else {
        return out;
    };
    let mut res = Matrix6::zeros();
    for a in 0..r {
        for b in 0..r {
            res += eg.vectors[branch + a] * eg.vectors[branch + b].transpose() * gi[(a, b)];
        }
    }
    let w = p.m6_sqrt * res * p.m6_sqrt;
    let mut ev = SymmetricEigen::new(w).eigenvalues;
    ev.as_mut_slice().sort_by(|a, b| b.total_cmp(a));
    for j in 0..r {
        out[j] = ev[j].clamp(0.0, 1.0);
    }
    out
}
