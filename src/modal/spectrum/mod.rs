//! The first K natural frequencies of the loaded problem by the structured engine.
//!
//! **Count.** The Wittrick-Williams count J(λ) = Σ_chains mult_c · (blocked eigenvalues of
//! c below λ) + (negative eigenvalues of D(λ)) is the exact number of natural frequencies
//! strictly below λ. The k-th eigenvalue λ_k (0-based) is the unique point where J steps
//! past k: J(lo) ≤ k < J(hi) brackets it, for every model (discrete, continuous, massless,
//! rigid 6-DOF end-effector), with no tolerance involved.
//!
//! **Bracketing.** The bracket starts at the end of the previous cluster (0 for the first
//! mode, where J(0) = 0 because D(0) is positive definite) and grows until J(hi) > k: from
//! the distance between the last two clusters (at least 1e-3 of λ), doubled at each probe
//! that does not reach mode k, at most doubling λ (geometrically before two clusters are
//! known). It is narrowed by bisection on the count while it holds two or more distinct
//! chain poles (blocked eigenvalues). With one pole P inside, the count is probed at
//! P(1 ∓ η) (η = [`SpectrumParams::pole_probe`]): if the step of J happens between the two
//! probes, λ_k = P — a mode with the end-effector still (identical cables give such modes:
//! combinations of their blocked modes whose end forces cancel). Otherwise the bracket
//! shrinks to one side of the pole.
//!
//! **Convergence.** In a pole-free bracket (a, b) the blocked count is a constant B and the
//! eigenvalues of D(λ) decrease monotonically (D' is minus a mass matrix), so λ_k is the
//! zero of the branch μ_{k−B}(λ) of D's sorted eigenvalues. Newton's method runs on
//! g(λ) = μ(λ)(λ − P_lo)(P_hi − λ), the bounding poles removed as in the first-root solver,
//! with μ' = vᵀD'v (v the unit eigenvector), safeguarded by the bracket (bisection whenever
//! a step leaves it or is not below half the step before last, as Numerical Recipes'
//! `rtsafe`: Newton converging from one side does not narrow the bracket, so its progress
//! is read from its steps), and stops when a step is below
//! [`SpectrumParams::rel_tol`] (1e-14 relative by default), or below 1e-10 and 100× below
//! the previous Newton step (superlinear convergence seen: the next iterate is within
//! ~step² of the root; rounding noise ends the iteration this way). D is then evaluated at
//! the root itself. Each mode has a finite evaluation budget
//! ([`SpectrumParams::max_evaluations_per_mode`]); exceeding it is
//! [`ModalError::NoConvergence`].
//!
//! **Multiplicities** come from the count: a mode's cluster is [J(λ(1 − δ)), J(λ(1 + δ)))
//! with δ = [`SpectrumParams::cluster_probe`] (1e-10 relative by default), which also
//! certifies the mode's index (the mode must lie in its cluster, else
//! [`ModalError::CountMismatch`]). Each member is still solved on its own branch.
//!
//! **Participation** of a cluster. With mass-normalised modes φ_j, the end-effector block
//! of the residue of D(σ)⁻¹ at the cluster's λ is R = Σ_{j∈cluster} φ_j,ee φ_j,eeᵀ; it
//! does not depend on the basis chosen inside a degenerate eigenspace, and neither do the
//! eigenvalues of M_ee^{1/2} R M_ee^{1/2}: the participations of the basis that
//! diagonalises the end-effector's kinetic energy inside the eigenspace. Their sum
//! tr(M_ee R) is the cluster's total participation (what a dense solver's arbitrary basis
//! gives when summed over the cluster). In a pole-free interval, with V the unit
//! eigenvectors of D(λ) of the cluster's branches and G = Vᵀ(−D'(λ))V, R = V G⁻¹ Vᵀ; a
//! simple mode gets m_ee‖v‖²/vᵀ(−D')v as before; members whose roots agree to 1e-12 share
//! one V, members of a split cluster each contribute at their own root. At a pole R is the symmetric difference
//! quotient ½[(λ − σ₋)D(σ₋)⁻¹ + (λ − σ₊)D(σ₊)⁻¹] at σ± = λ(1 ± h) (error O(h²)); pure
//! chain modes (end-effector still) get participation 0. Members beyond the rank of R get 0.
//!
//! Cost: a few tens of evaluations of D(λ) per mode, each O(1) in the element count N
//! (closed-form chains), so K modes cost the same at N = 10 and N = 10⁶.

mod cluster;
mod search;

use super::engine::{Condensed, DynEval, EigD};
use super::ModalError;
pub(in crate::modal) use search::{SpectrumSearch, SweepState};

/// One solved member of a pole-free cluster: its root, the evaluation there, its branch.
type Member = (f64, DynEval, EigD, usize);

/// One natural frequency of the loaded problem.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Mode {
    /// λ = ω², rad²/s².
    pub lambda: f64,
    /// f = √λ / 2π, Hz.
    pub frequency_hz: f64,
    /// End-effector participation (0 ..= 1): m_ee‖v‖² / vᵀ(−D′)v for a simple mode; inside
    /// a cluster, the basis-invariant participations (see the module docs).
    pub ee_participation: f64,
    /// Index of the first mode of this mode's cluster.
    pub cluster_start: usize,
    /// Number of modes in the cluster (from the count).
    pub multiplicity: u32,
}

/// Bounds and tolerances of [`Solver::modes_with`](crate::modal::Solver::modes_with)
/// (finite everywhere).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpectrumParams {
    /// Largest number of D(λ) evaluations spent on one mode (bracket, pole probes, Newton,
    /// cluster count and participation).
    pub max_evaluations_per_mode: u32,
    /// Newton stops once a step is below this size relative to λ.
    pub rel_tol: f64,
    /// Relative half-width of the count probes around a chain pole: a mode found between
    /// them is reported at the pole.
    pub pole_probe: f64,
    /// Relative half-width of the count probes that define a mode's cluster.
    pub cluster_probe: f64,
}

impl Default for SpectrumParams {
    fn default() -> Self {
        SpectrumParams {
            // Bisection over ~60 halvings of a factor-2 bracket plus Newton's ~10 and the
            // probes: 200 is a bound that a healthy problem never meets.
            max_evaluations_per_mode: 200,
            rel_tol: 1e-14,
            // Far below the 1e-13 target accuracy, far above the rounding of λ near a pole.
            pole_probe: 1e-13,
            // The certificate's probe of the first-root solver.
            cluster_probe: 1e-10,
        }
    }
}

/// The first `k` natural frequencies of problem `p` (ascending) into `out`: min(k,
/// out.len(), the number of modes) of them, that number returned.
pub(in crate::modal) fn modes_into<P: Condensed>(
    p: P,
    k: usize,
    params: &SpectrumParams,
    out: &mut [Mode],
) -> Result<usize, ModalError> {
    let n = k.min(out.len()).min(p.total_modes());
    let mut s = SpectrumSearch::new(p, params);
    s.start()?;
    for (i, slot) in out[..n].iter_mut().enumerate() {
        *slot = s.mode(i)?;
    }
    Ok(n)
}
