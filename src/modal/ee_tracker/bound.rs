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
//!
//! **Local form** (where the count alone shows the poles). The resolvent's derivative at
//! any σ is a third sum rule, positive term by term:
//!
//! ```text
//!     Σ_k φ_k φ_kᵀ/(λ_k − σ)² = d/dσ D(σ)⁻¹ = D(σ)⁻¹ (−D'(σ)) D(σ)⁻¹
//! ```
//!
//! (D(σ)⁻¹ = Σ φ_k φ_kᵀ/(λ_k − σ), the end-effector block of (K − σM)⁻¹; one evaluation of
//! D at σ). Less the watched modes, h² times its top eigenvalue bounds one unwatched mode in
//! [σ − h, σ + h] (weight (h/(λ_k − σ))² ≥ 1 there), while a mode 2h from σ counts a
//! quarter and one far away almost nothing. So the modes just below the answer are bounded
//! without the participation that avoided crossings move to unwatched modes above it (which
//! the plain and weighted forms count at weights 1 and λ_a/λ_k ≈ 0.7-0.8), and the modes
//! further below by the weighted form at the lower end of that interval instead of λ_a.

use super::EeTracker;
use crate::modal::engine::Condensed;
use crate::modal::first_mode::RootFinder;
use nalgebra::Matrix6;

/// A watched mode nearer the local bound's centre than this fraction of its half-width is
/// not subtracted (its term, weighted (h/(λ_k − σ))², would carry its approximate λ and φ
/// amplified); the bound is then not used.
const LOCAL_CLEARANCE: f64 = 0.25;
/// Halvings of an interval whose local form does not certify (a mode, weak but near the
/// interval's centre, weighs (h/(λ_k − σ))² there; the halves' centres lie elsewhere).
const LOCAL_DEPTH: u32 = 2;
/// The split bound's lowest split, a fraction of the answer's λ: the modes below it are
/// bounded by the weighted form there (the strong modes near the answer then count at
/// ≤ 0.4·λ_a/λ_k) ...
const SPLIT_LOW: f64 = 0.4;
/// ... and the local form covers the rest in this many equal intervals. Along the paper's
/// spatial robot's circle with sag (N = 10 and 40, 3 000 cycles) 0.4 and 3 gave the fewest
/// rescans of the splits tried (0.1-0.6, 2-6 intervals).
const SPLIT_INTERVALS: usize = 3;

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

    /// The certificate's bound over [`Self::unwatched_bound`]'s modes below `l_ans`, split
    /// into [0, l_0], [l_0, l_1], ..., [l_{n−1}, l_ans] (n = [`SPLIT_INTERVALS`], l_0 =
    /// [`SPLIT_LOW`]·l_ans, equal widths): the largest of [`Self::unwatched_bound`] at l_0
    /// and the local form over each interval (module docs; one evaluation of D each, an
    /// interval whose local form reaches `limit` halved up to [`LOCAL_DEPTH`] times). None
    /// when the local form is not available (no matrices, the budget spent, a watched mode
    /// too near a centre, not finite).
    pub(super) fn split_bound<P: Condensed>(
        &self,
        f: &mut RootFinder<'_, P>,
        l_ans: f64,
        limit: f64,
    ) -> Option<f64> {
        let (low, n) = (SPLIT_LOW, SPLIT_INTERVALS);
        let mut b = self.unwatched_bound(low * l_ans);
        let w = (1.0 - low) / n as f64;
        for i in 0..n {
            let lo = l_ans * (low + i as f64 * w);
            let hi = l_ans * (low + (i + 1) as f64 * w);
            let local = self.local_split(f, lo, hi, limit, LOCAL_DEPTH)?;
            b = b.max(local);
        }
        b.is_finite().then_some(b)
    }

    /// The local form over [lo, hi], or where it is not available or reaches `limit`, the
    /// largest over its two halves (their centres clear the watched or unwatched mode that
    /// sat at its centre), `depth` levels down.
    fn local_split<P: Condensed>(
        &self,
        f: &mut RootFinder<'_, P>,
        lo: f64,
        hi: f64,
        limit: f64,
        depth: u32,
    ) -> Option<f64> {
        let b = self.local_bound(f, lo, hi);
        if b.is_some_and(|x| x < limit) || depth == 0 || f.exhausted() {
            return b;
        }
        let mid = 0.5 * (lo + hi);
        let a = self.local_split(f, lo, mid, limit, depth - 1)?;
        Some(a.max(self.local_split(f, mid, hi, limit, depth - 1)?))
    }

    /// The local form over [lo, hi] (module docs).
    fn local_bound<P: Condensed>(
        &self,
        f: &mut RootFinder<'_, P>,
        lo: f64,
        hi: f64,
    ) -> Option<f64> {
        let mx = self.sums.matrices.as_ref()?;
        let (sigma, h) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        let ms = &self.members[..self.n_members];
        if !(h > 0.0) || f.exhausted() {
            return None;
        }
        if ms.iter().any(|m| {
            m.age == 0 && m.phi.is_some() && (m.lambda - sigma).abs() < LOCAL_CLEARANCE * h
        }) {
            return None;
        }
        let e = f.eval(sigma);
        let eg = e.eig();
        let mut inv = Matrix6::zeros();
        for i in 0..eg.n {
            let v = eg.vectors[i];
            inv += v * v.transpose() / eg.values[i];
        }
        let mut r = inv * (-e.dd) * inv;
        for m in ms {
            if let (0, Some(phi)) = (m.age, m.phi) {
                let d = m.lambda - sigma;
                r -= phi * phi.transpose() / (d * d);
            }
        }
        let b = (h * h * mx.top(&r)).max(0.0);
        b.is_finite().then_some(b)
    }
}
