//! The exact continuous limit (N → ∞) of a sagged cable's linearised dynamics, condensed
//! onto its end: the end dynamic stiffness S(λ), dS/dλ and the blocked-eigenvalue count.
//!
//! ## The problem
//!
//! About the elastic catenary (`crate::elastic_catenary::Catenary`: H, V(s) = V_a + w s,
//! T = √(H² + V²), tangent t = (H, V)/T), with s the unstretched arclength and μ the mass per
//! unstretched length,
//!
//! ```text
//!   −(K(s) u′)′ = λ μ u   on s ∈ [0, L0],  u(0) = 0,
//!   in plane:      K(s) = EA t tᵀ + T/(1 + T/EA) (I − t tᵀ)   (2 × 2, basis (h, up))
//!   out of plane:  k(s) = T/(1 + T/EA)
//! ```
//!
//! With p = K u′ the system is Hamiltonian, y = (u, p), y′ = A(s, λ) y,
//! A = [[0, C(s)], [−λμ I, 0]], whose compliance has the closed form
//! C = K⁻¹ = I/EA + n nᵀ/T (n the unit normal; out of plane c = 1/EA + 1/T). With U, P the
//! solution from U(0) = 0, P(0) = I, the end stiffness is S(λ) = P(L0) U(L0)⁻¹ and the
//! blocked (both ends held) eigenvalues are the λ where U(L0) is singular.
//!
//! ## The method: commutator-free Magnus of order 4 as a chain of exact straight segments
//!
//! The cable is cut into M steps [s_j, s_j+1] of length h. With A₁, A₂ the matrix A at the
//! two Gauss points s_mid ∓ h/(2√3), the 4th-order commutator-free Magnus integrator
//! (Blanes & Moan) is
//!
//! ```text
//!   Φ_step = exp(h (α₂ A₁ + α₁ A₂)) · exp(h (α₁ A₁ + α₂ A₂)),   α₁,₂ = 1/4 ± √3/6.
//! ```
//!
//! Since α₁ + α₂ = ½ and A is linear in (C, λμ), each factor is the exact transfer matrix of
//! a *uniform straight sub-segment* of length h/2, mass μ and constant compliance
//! C̃ = 2(α₁ C₁ + α₂ C₂) (resp. 2(α₂ C₁ + α₁ C₂)): the discrete model is itself a continuous
//! self-adjoint cable with λ-independent piecewise-constant K̃ = C̃⁻¹ > 0. So
//! - its S(λ), dS/dλ and blocked count are exact for that model (each sub-segment's
//!   closed-form dynamic stiffness, a symmetric 2 × 2 Riccati recursion with one division
//!   per node, Wittrick–Williams count: see `propagate`), and the count jumps exactly where
//!   S has its poles, at any λ;
//! - its eigenvalues converge to the true ones as O(h⁴) (the integrator's order);
//! - a uniform straight cable (w = 0) is reproduced exactly (every sub-segment is the cable).
//!
//! C̃'s principal frame and compliances (axial c_a, transverse c_t, out-of-plane c_o) have
//! closed forms: tr N̄ = β₁/T₁ + β₂/T₂, det N̄ = β₁β₂ sin²(θ₂ − θ₁)/(T₁T₂) with
//! sin(θ₂ − θ₁) = H w (s₂ − s₁)/(T₁T₂), so c_a = 1/EA + det/ν_max has no cancellation.
//! α₂ < 0 makes det N̄ < 0: c_a < 1/EA by ~ 0.03 δ²/T (δ the tangent's turn between the
//! Gauss points); the mesh keeps c_a ≥ `AXIAL_MARGIN`/EA.
//!
//! ## Cost
//!
//! `set` precomputes everything λ-independent per sub-segment: the relative rotation of its
//! principal frame (cos, sin, from half-angle formulas: no trigonometric call), q = μ c ℓ²
//! and k = 1/(c ℓ) per direction, μ ℓ, and the largest q of the axial and of the transverse
//! directions. `eval` then picks, once, per direction, the shortest polynomial kernel valid
//! for the largest z = λ q of the cable (`kernel`: z ≤ 4e-3 a division-free series,
//! ≤ 0.1 and ≤ 2.25 Taylor polynomials of cos √z, sin √z/√z; all exact to rounding), so the
//! inner loop has no trigonometry, no sqrt and no branch other than the count; λ beyond the
//! polynomials (a sub-segment phase above 1.5, i.e. above λ_max) falls back to the
//! transfer-matrix form with the library's trigonometry (`transfer`). In plane and out of
//! plane run in one loop (their recursions are independent: the processor overlaps them).
//! `set` also keeps S(0) and dS/dλ(0) (the static stiffness, asked every cycle) from the
//! closed form of `statics`: the sub-segments as springs in series and the consistent mass
//! of the static shape, a sum without divisions per node (the recursion when a capped mesh
//! left a sub-segment with a negative compliance).
//!
//! ## Steps (error model)
//!
//! The coefficients vary with the tangent angle and ln T, both at rate |d(t, ln T)/ds| =
//! w/T; their total variation is ν = ∫ w/T ds = asinh(V_e/H) − asinh(V_a/H) (H > 0) or
//! |ln(V_e/V_a)| (H = 0). Steps are equal in ν (closed form: V(ν) = H sinh(asinh(V_a/H) + ν)),
//! so each carries Δν = ν/M: the steps crowd where the tension is low. Measured against
//! an independent integration (tests/sag/continuous.rs), the relative eigenvalue error is
//! O(M⁻⁴) with, for an eigenvalue whose mode has total transverse phase Φ = ∫ √(λμ c) ds
//! (≈ π per half-wave),
//!
//! ```text
//!   error ≈ C · (Δν)² · (Φ/M)²,   C ≈ 1.3e-3 … 3.4e-3 (out of plane, string-like in plane),
//!                                  C ≲ 0.17 (symmetric in-plane modes, sag-stiffened)
//! ```
//!
//! (the coefficient variation per step times the phase per step, squared: the frozen
//! coefficients' error grows with the oscillation inside a step; the symmetric in-plane
//! modes are the most sensitive to the chain's total axial + geometric compliance, whose
//! error the sub-segments' O(δ²) axial perturbation carries). The rule bounds all modes up
//! to the n_hw-th transverse half-wave, so the first mode's error is typically far below
//! tol: e.g. level cable, λ² ≈ 100, tol 1e-7: M = 75, measured errors ≤ 3.5e-8 over the
//! first seven modes, 4.4e-11 on the first. A real-time caller that only needs the
//! robot's first frequency sets n_hw to the half-waves its λ reaches (M ∝ √n_hw) and
//! a looser tol (M ∝ tol^(−¼)): the rule bounds the worst mode up to n_hw, and the robot's
//! first mode comes out 50 to 500 times better (`SagContinuousParams::realtime`). The rule:
//!
//! ```text
//!   M = max(⌈(C_ERR ν² (n_hw π)² / tol)^¼⌉, ⌈ν / NU_PER_STEP⌉,
//!           steps keeping φ(λ_max) ≤ PHASE_PER_SEGMENT per sub-segment and c_a ≥ margin),
//!   λ_max = (n_hw π)² / (μ (∫ √c_o ds)²)   (n_hw = params.max_halfwaves, tol = params.rel_tol),
//! ```
//!
//! capped at `SAG_CONT_MAX_STEPS` (the set result says when the cap bit). Above λ_max the
//! evaluation stays exact for the discrete model (count and poles consistent), with an error
//! that grows with λ.

mod junction;
mod kernel;
mod profile;
mod propagate;
mod statics;
mod transfer;

use super::{SagChainError, SagChainEval, SagSupport};
use crate::elastic_catenary::Catenary;
use profile::Profile;

/// Most Magnus steps of one cable (2 sub-segments each): the fixed capacity of the solver.
/// By the error model, 128 steps keep 1e-9 for ν·n_hw ≤ 0.37 (ν ≈ 0.09 up to the 4th
/// transverse half-wave) and 1e-7 for ν·n_hw ≤ 3.7; slacker cables get the cap and a
/// larger error (`capped`).
pub const SAG_CONT_MAX_STEPS: usize = 128;
const MAX_SEGMENTS: usize = 2 * SAG_CONT_MAX_STEPS;

/// Variation ν = ∫ w/T ds per step (rad) at least: the static (λ = 0) error ~ (Δν)⁴ EA/T.
const NU_PER_STEP: f64 = 0.05;
/// The error constant: relative eigenvalue error ≈ C ν² Φ² / M⁴ (Φ the mode's total
/// transverse phase). Measured (tests/sag_continuous `error_constant_study`, M = 8 … 64,
/// nine cables from taut to nearly free): 1.3e-3 … 3.4e-3 for out-of-plane and string-like
/// in-plane modes, up to 0.17 for the symmetric (sag-stiffened) in-plane modes; the rule
/// takes the bound over all, Φ = n_hw π.
const C_ERR: f64 = 0.2;
/// Largest transverse phase across a sub-segment at λ_max (rad).
const PHASE_PER_SEGMENT: f64 = 1.5;
/// Smallest axial compliance of a sub-segment in units of 1/EA (see module docs).
const AXIAL_MARGIN: f64 = 0.5;
/// Mesh cuts at most: each further one re-cuts with more steps when a check fails.
const MESH_PASSES: usize = 4;
/// Below this ν the cable is straight to rounding: equal steps in s.
pub(super) const NU_STRAIGHT: f64 = 1e-12;
/// H below this fraction of min(|V_a|, |V_e|): the cable is vertical (H = 0 formulas).
pub(super) const VERTICAL_H_RATIO: f64 = 1e-100;
/// Magnus weights α₁,₂ = 1/4 ± √3/6 and the Gauss offset 1/(2√3).
const ALPHA1: f64 = 0.25 + 0.288_675_134_594_812_9;
const ALPHA2: f64 = 0.25 - 0.288_675_134_594_812_9;
const GAUSS_HALF: f64 = 0.288_675_134_594_812_9;

/// Errors of [`SagContinuous::set`].
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SagContError {
    /// A parameter is not finite or out of range (L0, EA, μ > 0; w, H ≥ 0).
    #[error("sagged cable: {0} must be finite and in range")]
    BadInput(&'static str),
    /// The tension vanishes somewhere on the cable (H = 0 with V changing sign, or all zero).
    #[error("sagged cable: the tension vanishes on the cable (H = 0, V from {v_anchor_n} N to {v_end_n} N)")]
    Slack {
        /// V at the anchor, N.
        v_anchor_n: f64,
        /// V at the end, N.
        v_end_n: f64,
    },
}

/// Mesh rule parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SagContinuousParams {
    /// Transverse half-waves along the cable up to which `rel_tol` is kept (sets λ_max).
    pub max_halfwaves: f64,
    /// Relative eigenvalue error aimed at below λ_max (by the error model): 1e-9 by default
    /// (offline); 1e-5 for the real-time path (`realtime`).
    pub rel_tol: f64,
}

impl SagContinuousParams {
    /// The real-time configuration: only f1 is solved per cycle, and f1 lies below every
    /// cable's first blocked (end held) eigenvalue, i.e. within its first transverse
    /// half-wave. The rule's 1e-5 bounds every mode up to that half-wave; the robot's f1
    /// was measured within 1.8e-7 of the offline mesh (1e-9, four half-waves) around the
    /// bench circles of the shipped sag scenes (tests/sag/realtime.rs checks 1e-6), three
    /// orders below the physics' own error (~1e-3), with a third of the steps of 1e-7.
    pub fn realtime() -> SagContinuousParams {
        SagContinuousParams {
            max_halfwaves: 1.0,
            rel_tol: 1e-5,
        }
    }
}

impl Default for SagContinuousParams {
    fn default() -> Self {
        // The robot's search looks at the first few blocked modes of each cable.
        SagContinuousParams {
            max_halfwaves: 4.0,
            rel_tol: 1e-9,
        }
    }
}

/// What [`SagContinuous::set`] chose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SagContMesh {
    /// Magnus steps M (2M sub-segments).
    pub steps: usize,
    /// λ up to which the accuracy rule holds, rad²/s².
    pub lambda_max_rad2_s2: f64,
    /// The rule asked for more than `SAG_CONT_MAX_STEPS`: accuracy below the rule's.
    pub capped: bool,
    /// Total tangent/tension variation ν = ∫ w/T ds.
    pub variation: f64,
}

/// One uniform sub-segment: the λ-independent data of its transfer matrix per direction
/// (axial, transverse, out of plane).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Segment {
    /// (cos, sin) of its principal frame's angle relative to the previous sub-segment's.
    rot: [f64; 2],
    /// μ c ℓ² per direction (z = λ q), s²/rad².
    q: [f64; 3],
    /// 1/(c ℓ) per direction (the static stiffness), N/m.
    k: [f64; 3],
    /// μ ℓ, kg.
    mul: f64,
}

/// The continuous sagged cable: `set` once per pose (no allocation), `eval` at any λ.
#[derive(Debug, Clone)]
pub struct SagContinuous {
    params: SagContinuousParams,
    segs: [Segment; MAX_SEGMENTS],
    n_seg: usize,
    /// (cos θ, sin θ) of the last sub-segment's axial direction in (h, up).
    final_rot: [f64; 2],
    /// Largest q of the axial direction and of the others over the sub-segments (they pick
    /// the kernels per λ), s²/rad².
    q_max: [f64; 2],
    mesh: SagContMesh,
    static_eval: SagChainEval,
    /// The anchor node on the hidden cable (`set_support`), None: fixed.
    support: Option<SagSupport>,
}

impl SagContinuous {
    /// A solver with the given rule parameters (holds a straight placeholder cable).
    pub fn new(params: SagContinuousParams) -> SagContinuous {
        SagContinuous {
            params,
            segs: [Segment::default(); MAX_SEGMENTS],
            n_seg: 0,
            final_rot: [1.0, 0.0],
            q_max: [0.0; 2],
            static_eval: SagChainEval::default(),
            support: None,
            mesh: SagContMesh {
                steps: 0,
                lambda_max_rad2_s2: 0.0,
                capped: false,
                variation: 0.0,
            },
        }
    }

    /// Precompute the mesh of cable `cat` with mass `mu_kg_m` per unstretched length by the
    /// step rule of the module docs. No allocation, bounded work (≤ MESH_PASSES cuts).
    pub fn set(&mut self, cat: &Catenary, mu_kg_m: f64) -> Result<SagContMesh, SagContError> {
        self.set_steps(cat, mu_kg_m, None)
    }

    /// As [`set`](Self::set) with exactly `steps` Magnus steps (clamped to 1..=MAX): for
    /// convergence studies.
    pub fn set_with_steps(
        &mut self,
        cat: &Catenary,
        mu_kg_m: f64,
        steps: usize,
    ) -> Result<SagContMesh, SagContError> {
        self.set_steps(cat, mu_kg_m, Some(steps))
    }

    /// The sub-segments of the last `set` (tests).
    #[cfg(test)]
    fn segments(&self) -> &[Segment] {
        &self.segs[..self.n_seg]
    }

    /// The mesh chosen by the last successful `set`.
    pub fn mesh(&self) -> SagContMesh {
        self.mesh
    }

    /// S(λ), dS/dλ and the blocked count at λ = ω² (rad²/s²). No allocation; O(M).
    pub fn eval(&self, lambda: f64) -> SagChainEval {
        let segs = &self.segs[..self.n_seg];
        let junction = match (&self.support, segs.first()) {
            (Some(sup), Some(first)) => {
                let e = sup.hidden.eval(lambda);
                let ([dc, ds], [c0, s0]) = (sup.direction, first.rot);
                Some(junction::Junction {
                    dir: [dc * c0 + ds * s0, ds * c0 - dc * s0],
                    h: e.s,
                    dh: e.ds,
                    below: e.below,
                })
            }
            _ => None,
        };
        propagate::eval(segs, self.final_rot, self.q_max, lambda, junction.as_ref())
    }

    /// Put the cable's anchor node on the hidden cable `support` (None: the anchor fixed),
    /// as [`SagChain::set_support`](super::SagChain::set_support) does for the FEM chain:
    /// the first sub-segment's start moves along `support.direction` held by the hidden
    /// segment (an exact axial bar when its `n_el` is 0). Call after `set` (which clears
    /// the support); refreshes the static evaluation. No allocation.
    pub fn set_support(&mut self, support: Option<SagSupport>) -> Result<(), SagChainError> {
        SagSupport::check(support.as_ref())?;
        self.support = support;
        self.static_eval = if support.is_some() {
            self.eval(0.0)
        } else {
            let segs = &self.segs[..self.n_seg];
            statics::static_eval(segs, self.final_rot).unwrap_or_else(|| self.eval(0.0))
        };
        Ok(())
    }

    /// The cable's support (None: the anchor is fixed).
    pub fn support(&self) -> Option<SagSupport> {
        self.support
    }

    /// The static end stiffness S(0) (computed by `set`, `statics`): s_in (N/m, (h, up))
    /// and s_out (N/m); the derivatives are those at λ = 0 (kg). Equal to `eval(0.0)` to
    /// rounding.
    pub fn static_eval(&self) -> SagChainEval {
        self.static_eval
    }

    fn set_steps(
        &mut self,
        cat: &Catenary,
        mu: f64,
        forced: Option<usize>,
    ) -> Result<SagContMesh, SagContError> {
        let p = Profile::new(cat, mu)?;
        let nu = p.variation();
        if let Some(m) = forced {
            let m = m.clamp(1, SAG_CONT_MAX_STEPS);
            let lmax = self.cut(&p, nu, m);
            return Ok(self.record(m, lmax, false, nu));
        }
        let phase = self.params.max_halfwaves.max(0.0) * std::f64::consts::PI;
        let tol = self.params.rel_tol.max(f64::EPSILON);
        let m_err = (C_ERR * nu * nu * phase * phase / tol).sqrt().sqrt();
        let m_nu = nu / NU_PER_STEP;
        let wanted = m_err.max(m_nu).ceil();
        let mut m = (wanted.min(1e9) as usize).clamp(1, SAG_CONT_MAX_STEPS);
        let mut lmax = self.cut(&p, nu, m);
        for _ in 1..MESH_PASSES {
            let next = self.steps_needed(&p, m, lmax).min(SAG_CONT_MAX_STEPS);
            if next <= m {
                break;
            }
            m = next;
            lmax = self.cut(&p, nu, m);
        }
        let capped = self.steps_needed(&p, m, lmax) > m || wanted > m as f64;
        Ok(self.record(m, lmax, capped, nu))
    }

    fn record(&mut self, m: usize, lmax: f64, capped: bool, nu: f64) -> SagContMesh {
        self.q_max = self.segs[..self.n_seg].iter().fold([0.0f64; 2], |m, g| {
            [m[0].max(g.q[0]), m[1].max(g.q[1]).max(g.q[2])]
        });
        let segs = &self.segs[..self.n_seg];
        self.support = None;
        self.static_eval =
            statics::static_eval(segs, self.final_rot).unwrap_or_else(|| self.eval(0.0));
        self.mesh = SagContMesh {
            steps: m,
            lambda_max_rad2_s2: lmax,
            capped,
            variation: nu,
        };
        self.mesh
    }

    /// Steps that would satisfy the phase and axial-margin checks on the current cut of m.
    fn steps_needed(&self, p: &Profile, m: usize, lmax: f64) -> usize {
        // Largest φ² = λ q_t and smallest c_a EA (c_a = 1/(k_a ℓ), ℓ = mul/μ); one sqrt each.
        let (mut q_t, mut ca_min) = (0.0f64, f64::INFINITY);
        for g in &self.segs[..self.n_seg] {
            q_t = q_t.max(g.q[1]);
            ca_min = ca_min.min(p.mu / (g.k[0] * g.mul) * p.ea);
        }
        let phase_ratio = (lmax * q_t).sqrt() / PHASE_PER_SEGMENT;
        // c_a = 1/EA − O(δ²): the deficit shrinks as 1/M².
        let margin_ratio = ((1.0 - ca_min).max(0.0) / (1.0 - AXIAL_MARGIN)).sqrt();
        let r = phase_ratio.max(margin_ratio);
        if r <= 1.0 {
            m
        } else {
            ((m as f64) * r * 1.05).ceil() as usize
        }
    }

    /// Cut the cable into m steps equal in ν; returns λ_max of the rule on this cut.
    fn cut(&mut self, p: &Profile, nu: f64, m: usize) -> f64 {
        let mut s0 = 0.0;
        // The previous sub-segment's axial direction (cos, sin) in (h, up).
        let mut prev = [1.0, 0.0];
        let mut root_c = 0.0; // ∫ √c_o ds
        for j in 0..m {
            let s1 = if j + 1 == m {
                p.l0
            } else {
                p.node_s(nu, (j + 1) as f64 / m as f64)
            };
            let h = s1 - s0;
            let d = h * GAUSS_HALF;
            let mid = 0.5 * (s0 + s1);
            let (g1, g2) = (p.gauss(mid - d), p.gauss(mid + d));
            let sin12 = p.h * p.w * (2.0 * d) / (g1.t * g2.t);
            for (k, (b1, b2)) in [(2.0 * ALPHA1, 2.0 * ALPHA2), (2.0 * ALPHA2, 2.0 * ALPHA1)]
                .into_iter()
                .enumerate()
            {
                let (seg, axis) = p.segment(&g1, &g2, b1, b2, sin12, 0.5 * h);
                // The rotation from the previous frame to this one: cos, sin of the difference.
                let rot = [
                    axis[0] * prev[0] + axis[1] * prev[1],
                    axis[1] * prev[0] - axis[0] * prev[1],
                ];
                self.segs[2 * j + k] = Segment { rot, ..seg };
                prev = axis;
                // √c_o ℓ = √(c_o ℓ · ℓ) = √(ℓ / k_o)
                root_c += (0.5 * h / seg.k[2]).sqrt();
            }
            s0 = s1;
        }
        self.n_seg = 2 * m;
        self.final_rot = prev;
        let hw = self.params.max_halfwaves.max(0.0) * std::f64::consts::PI;
        hw * hw / (p.mu * root_c * root_c)
    }
}
