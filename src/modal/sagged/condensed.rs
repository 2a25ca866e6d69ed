//! [`SagChains`] as the structured solver sees it ([`Condensed`]): every evaluation counted,
//! the poles seen only through the count, the sum rules with their matrix forms.

use super::problem::SagChains;
use crate::modal::engine::{sealed, Condensed, DynEval, SumMatrices, SumRules};
use nalgebra::Matrix6;
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
        self.evaluate_with(lambda, true)
    }
    #[inline]
    fn count_eval(&mut self, lambda: f64) -> DynEval {
        self.evaluations = self.evaluations.wrapping_add(1);
        self.evaluate_with(lambda, false)
    }
    #[inline]
    fn zero_eval(&mut self) -> DynEval {
        self.static_eval()
    }
    #[inline]
    fn evaluations(&self) -> u32 {
        self.evaluations
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
    /// The traces and, with `evaluate`, the matrix forms: the plain one from one evaluation
    /// far below zero ([`SagChains::mass_limit_inverse`]), the weighted one's matrix D(0)⁻¹
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
