//! [`SagChains`] as the structured solver sees it ([`Condensed`]): every evaluation counted,
//! the pole intervals seen only through the count (while the end-effector tracker runs, a
//! mode's coupling to one chain and that chain's poles too, `pole_view`), the sum rules
//! with their matrix forms.

use super::problem::SagChains;
use crate::modal::engine::{
    sealed, Condensed, Coupling, DynEval, PoleCursor, SumMatrices, SumRules,
};
use nalgebra::{Matrix6, Vector6};
use num_complex::Complex64;

/// How far below zero (relative to max|D(0)|/m_min) the sagged problem is evaluated for its
/// participation total: far enough that the chains' stiffness is ~1e-16 of their mass
/// there relative to the end-effector's static scale, close enough that nothing overflows.
const FAR_BELOW: f64 = 1e16;

impl sealed::Sealed for SagChains {}

impl Condensed for SagChains {
    #[inline]
    fn eval(&mut self, lambda: f64) -> DynEval {
        self.evaluations = self.evaluations.wrapping_add(1);
        self.evaluate_recorded(lambda, true)
    }
    #[inline]
    fn count_eval(&mut self, lambda: f64) -> DynEval {
        self.evaluations = self.evaluations.wrapping_add(1);
        self.evaluate_recorded(lambda, false)
    }
    #[inline]
    fn zero_eval(&mut self) -> DynEval {
        self.static_eval()
    }
    #[inline]
    fn evaluations(&self) -> u32 {
        self.evaluations.wrapping_add(self.pole_evaluations())
    }
    #[inline]
    fn dim(&self) -> usize {
        self.dim
    }
    #[inline]
    fn ee_mass(&self) -> &Matrix6<f64> {
        &self.m6
    }
    #[inline]
    fn total_modes(&self) -> usize {
        SagChains::total_modes(self)
    }
    /// The count alone shows the poles to the searches (the followed poles are not proven
    /// without a count pass over the chains, which costs an evaluation).
    #[inline]
    fn pole_interval(&self, _lambda: f64) -> Option<(f64, f64)> {
        None
    }
    #[inline]
    fn poles_known(&self) -> bool {
        false
    }
    #[inline]
    fn lowest_pole(&self) -> Option<f64> {
        None
    }
    #[inline]
    fn static_eval(&self) -> DynEval {
        SagChains::static_eval(self)
    }
    #[inline]
    fn last_pole_interval(&self) -> Option<(f64, f64)> {
        None
    }
    /// While the end-effector tracker runs, on FEM chains: each chain's poles by its own
    /// count (`pole_view`).
    #[inline]
    fn poles_searched(&self) -> bool {
        self.poles_shown()
    }
    fn next_pole(&self, cursor: &mut PoleCursor, a: f64) -> (f64, usize, usize) {
        self.chain_next_pole(cursor, a)
    }
    fn keyed_pole(&self, c: usize, j: usize) -> Option<f64> {
        (self.poles_shown() && c < self.n).then(|| self.chain_pole(c, j, f64::NAN, false))
    }
    fn coupling(&self, x: f64, dd: &Matrix6<f64>, v: &Vector6<f64>, share_min: f64) -> Coupling {
        if self.poles_shown() {
            self.chain_coupling(x, dd, v, share_min)
        } else {
            (0.0, f64::NAN, false, u32::MAX)
        }
    }
    fn follow_poles(&mut self, left: Option<u32>) {
        self.follow = left.is_some();
        let now = Condensed::evaluations(self);
        self.pole_budget_end = match left {
            Some(l) if l != u32::MAX => Some(now.wrapping_add(l)),
            _ => None,
        };
    }
    /// The traces and, with `evaluate`, the matrix forms: the plain one from one evaluation
    /// far below zero (`SagChains::mass_limit_inverse`), the weighted one's matrix D(0)⁻¹
    /// from the chains' cached static evaluations. Without `evaluate` (or when that
    /// evaluation is not finite) the traces with an unknown total.
    fn sum_rules(&mut self, flex0: f64, evaluate: bool) -> SumRules {
        let m_inf_inv = if evaluate {
            self.mass_limit_inverse()
        } else {
            None
        };
        let Some(m_inf_inv) = m_inf_inv else {
            return SumRules::traces(f64::INFINITY, flex0);
        };
        SumRules {
            total: (self.m6 * m_inf_inv).trace(),
            over_lambda: flex0,
            matrices: Some(SumMatrices {
                m_inf_inv,
                flex: self.static_flexibility(),
                m_sqrt: self.m6_sqrt,
                dim: self.dim,
            }),
        }
    }
    fn d_complex(&self, lambda: Complex64) -> Option<Matrix6<Complex64>> {
        if !self.loaded {
            return None;
        }
        SagChains::d_complex(self, lambda)
    }
    #[inline]
    fn ee_stiffness(&self) -> &Matrix6<f64> {
        &self.k6
    }
    #[inline]
    fn is_loaded(&self) -> bool {
        self.loaded
    }
}

impl SagChains {
    /// A counted evaluation; while the poles are shown, each chain's count and S' are kept
    /// (the chains' shares of a mode and the chains' poles next to it).
    #[inline]
    fn evaluate_recorded(&mut self, lambda: f64, derivative: bool) -> DynEval {
        if !self.poles_shown() {
            return self.evaluate_with(lambda, derivative);
        }
        let (mut below, mut ds) = (
            std::mem::take(&mut self.last_below),
            std::mem::take(&mut self.last_ds),
        );
        let e = self.evaluate_into(lambda, derivative, |i, c| {
            below[i] = c.below;
            ds[i] = [c.ds_in[0], c.ds_in[1], c.ds_in[2], c.ds_out];
        });
        self.last_below = below;
        self.last_ds = ds;
        self.last_lambda = lambda;
        e
    }

    /// M_∞⁻¹ = Σ_k φ_k φ_kᵀ (the plain sum rule's matrix form; the identity outside the
    /// leading `dim` block), from one evaluation at σ = −[`FAR_BELOW`]·max|D(0)|/m_min
    /// (m_min the end-effector's smallest mass entry): −D(σ)/σ = M_∞ + (a stiffness)/|σ|,
    /// so the M_∞ it gives is above the true one by a relative ~(the chains' highest
    /// pole)/|σ| (≤ 1e-5 for a thousand elements and a cable a ten-thousandth of the
    /// end-effector's mass), and its inverse below by as much: far inside the tracker's
    /// certificate margin. None when σ or the inverse is not finite.
    fn mass_limit_inverse(&mut self) -> Option<Matrix6<f64>> {
        let dim = self.dim;
        let d0 = self.static_eval().d;
        let k = d0.abs().max();
        let m = (0..dim)
            .map(|j| self.m6[(j, j)])
            .fold(f64::INFINITY, f64::min);
        let sigma = -FAR_BELOW * k / m;
        if !(sigma.is_finite() && sigma < 0.0) {
            return None;
        }
        let d = self.eval(sigma).d * (-1.0 / sigma);
        let mut m_inf = Matrix6::identity();
        m_inf
            .view_mut((0, 0), (dim, dim))
            .copy_from(&d.view((0, 0), (dim, dim)));
        m_inf.try_inverse()
    }

    /// D(0)⁻¹ (its leading `dim` block, zeros elsewhere) from the chains' cached static
    /// evaluations; NaN when D(0) is not positive definite.
    fn static_flexibility(&self) -> Matrix6<f64> {
        let eg = self.static_eval().eig();
        if !(eg.values[0] > 0.0) {
            return Matrix6::repeat(f64::NAN);
        }
        let mut flex = Matrix6::zeros();
        for j in 0..eg.n {
            let v = eg.vectors[j];
            flex += v * v.transpose() / eg.values[j];
        }
        flex
    }
}
