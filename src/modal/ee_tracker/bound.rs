//! The sum-rule bound on the participation of any unwatched mode below the answer.
//!
//! With φ_k the end-effector part of mode k (mass-normalised) and u_k = M_ee^{1/2} φ_k
//! (so p_k = |u_k|²), the modes are complete:
//!
//! ```text
//!     Σ_k φ_k φ_kᵀ     = M_∞⁻¹      (M_∞ = lim −D(λ)/λ as λ → −∞)
//!     Σ_k φ_k φ_kᵀ/λ_k = D(0)⁻¹
//! ```
//!
//! Their traces weighted by M_ee are the plain and the 1/λ-weighted sum rules Σ p_k and
//! Σ p_k/λ_k. Less the watched modes, what is left is what the unwatched ones hold, and
//! one unwatched mode j below the answer λ_a holds at most all of it:
//!
//! - **trace form**: p_j ≤ Σ p_k − Σ_watched p_k and p_j ≤ λ_a (Σ p_k/λ_k − Σ_watched
//!   p_k/λ_k) (λ_j ≤ λ_a);
//! - **matrix form**: u_j u_jᵀ ≼ M_ee^{1/2} (M_∞⁻¹ − Σ_watched φ φᵀ) M_ee^{1/2} = R, so
//!   p_j = |u_j|² ≤ λ_max(R), and likewise with the weighted residual times λ_a and with
//!   the mean of the two.
//!
//! The trace form counts every direction of the end-effector: the unwatched modes of the
//! two (or five) directions other than the answer's add up against it, so it certifies only
//! when the strong modes of every direction are watched, including those far above the
//! answer. The matrix form counts only the most-loaded direction, never more than the trace
//! (R ≽ 0). It needs each counted watched mode's φ (from its Newton step) and the matrices
//! of the pose (`engine::SumMatrices`); where either is missing the trace form alone is used.

use super::EeTracker;

impl EeTracker {
    /// Bound on the participation of any unwatched mode below `l_ans` (rad²/s²): the
    /// smallest of the plain and the 1/λ-weighted sum rules less what the watched modes
    /// followed this cycle hold, in the trace form and, where known, the matrix form (module
    /// docs). This is the certificate.
    pub(super) fn unwatched_bound(&self, l_ans: f64) -> f64 {
        let trace = self.unwatched_bound_with(l_ans, false);
        match self.matrix_bound(l_ans) {
            Some(m) => trace.min(m),
            None => trace,
        }
    }

    /// The trace form of [`Self::unwatched_bound`]; with `stale`, the members not followed
    /// this cycle count too, with their last participation (an estimate for the search
    /// heuristics only).
    pub(super) fn unwatched_bound_with(&self, l_ans: f64, stale: bool) -> f64 {
        let mut sum = 0.0;
        let mut weighted = 0.0;
        for m in &self.members[..self.n_members] {
            if m.age > 0 && !stale {
                continue;
            }
            sum += m.p;
            weighted += m.p / m.lambda;
        }
        let plain = self.sums.total - sum;
        let w = if self.sums.over_lambda.is_finite() && l_ans.is_finite() {
            l_ans * (self.sums.over_lambda - weighted)
        } else {
            f64::INFINITY
        };
        plain.min(w).max(0.0)
    }

    /// The matrix form of the bound over the members followed this cycle; None when the
    /// pose's matrices are not known or a counted member's φ is not.
    fn matrix_bound(&self, l_ans: f64) -> Option<f64> {
        let mx = self.sums.matrices.as_ref()?;
        let mut rp = mx.m_inf_inv;
        let mut rw = mx.flex;
        for m in &self.members[..self.n_members] {
            if m.age > 0 {
                continue;
            }
            let phi = m.phi?;
            let pp = phi * phi.transpose();
            rp -= pp;
            rw -= pp / m.lambda;
        }
        let plain = mx.top(&rp);
        let b = if rw.iter().all(|x| x.is_finite()) && l_ans.is_finite() {
            let rw = rw * l_ans;
            // u_j u_jᵀ ≼ R_p and ≼ λ_a R_w, so also ≼ their mean (weights 1 for the modes
            // below and ½(1 + λ_a/λ_k) above: the strong unwatched modes just above the
            // answer count less than in R_p, the weak low ones less than in λ_a R_w).
            plain.min(mx.top(&rw)).min(mx.top(&((rp + rw) * 0.5)))
        } else {
            plain
        };
        let b = b.max(0.0);
        b.is_finite().then_some(b)
    }
}
