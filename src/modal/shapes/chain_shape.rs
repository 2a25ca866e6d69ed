//! One scalar chain's shape at a given λ: the interior solution of its recurrence with the
//! anchor held, as a function w(j) normalised to max |w| = 1, its end value g = w(N), the
//! end force f it puts on the end-effector per unit amplitude, and its consistent-mass
//! moments. Everything is finite for every λ > 0, at the chain's poles too (there g = 0).

use crate::cable::ChainKind;

/// A chain's shape at one λ, with the anchor at w(0) = 0.
///
/// Discrete chain of N elements (spring k, consistent mass m): the interior equations
/// β w_{j−1} + 2α w_j + β w_{j+1} = 0 (α = k − λm/3, β = −k − λm/6) with w_0 = 0 give
/// w_j ∝ U_{j−1}(c), c = −α/β (Chebyshev polynomials of the second kind): sin(jθ)/sin θ for
/// c = cos θ, (−1)^{j−1} sinh(jφ)/sinh φ for c = −cosh φ (above the cut-off 12k/m).
/// Continuous chain (end stiffness K = S/L, mass M = μL): w(x) ∝ sin(φx), φ = √(λM/K),
/// x ∈ [0, 1] from anchor to end.
#[derive(Debug, Clone, Default)]
pub(in crate::modal) struct ChainShape {
    /// Discrete: w_j for j = 0 ..= N (w_0 = 0, w_N = g). Continuous: empty (closed form).
    pub(super) w: Vec<f64>,
    /// A discrete supported chain's hidden nodes from the drum (0) to the junction (its
    /// w_0), on the same scale as `w`; empty otherwise.
    pub(super) hidden_w: Vec<f64>,
    /// End value w(N) (w(1) for a continuous chain): 0 at a blocked eigenvalue.
    pub(super) g: f64,
    /// End force on the end-effector per unit amplitude, N/m: α w_N + β w_{N−1}
    /// (discrete), K w'(1) (continuous). f/g is the chain's dynamic stiffness s(λ).
    pub(super) f: f64,
    /// Row scale of the chain's end constraint (N/m): a stiffness of the size of f.
    pub(super) scale: f64,
    /// Consistent-mass moments, kg: the bilinear kinetic form of two shapes with interior
    /// amplitudes C, C' and end displacements e, e' is
    /// C C' m_ii + (C e' + e C') m_ie + e e' m_ee.
    pub(super) m_ii: f64,
    /// See `m_ii`.
    pub(super) m_ie: f64,
    /// See `m_ii`.
    pub(super) m_ee: f64,
    /// Continuous only: φ and the amplitude normalisation 1/min(φ, 1).
    phi: f64,
    norm: f64,
    /// Whether the chain is continuous.
    continuous: bool,
    /// Continuous, a supported chain only (`supported_shape`): w(x) = norm·sin(φx) +
    /// cos_coef·cos(φx) (norm·x + cos_coef when φ = 0); 0 otherwise.
    cos_coef: f64,
}

impl ChainShape {
    /// Fill for chain `kind` at λ (rad²/s²). Reuses `self.w`'s storage.
    pub(super) fn fill(&mut self, kind: &ChainKind, lambda: f64) {
        self.hidden_w.clear();
        match *kind {
            ChainKind::Discrete { k, m, n_el } => self.fill_discrete(k, m, n_el.max(1), lambda),
            ChainKind::Continuous { k_total, m_total } => {
                self.fill_continuous(k_total, m_total, lambda)
            }
            ChainKind::Supported { free, hidden } => {
                // A mixed pair is refused before any fill (`mode_shapes`).
                if !self.fill_supported(&free, &hidden, lambda) {
                    self.continuous = false;
                    self.w.clear();
                }
            }
        }
    }

    /// Mark the shape discrete or continuous (`supported_shape`).
    pub(super) fn set_continuous(&mut self, continuous: bool) {
        self.continuous = continuous;
        self.cos_coef = 0.0;
    }

    /// A continuous supported chain's free part: w(x) = sin_coef·sin(φx) + cos_coef·cos(φx).
    pub(super) fn set_bar(&mut self, phi: f64, sin_coef: f64, cos_coef: f64) {
        self.phi = phi;
        self.norm = sin_coef;
        self.cos_coef = cos_coef;
    }

    fn fill_discrete(&mut self, k: f64, m: f64, n: usize, lambda: f64) {
        self.continuous = false;
        self.cos_coef = 0.0;
        let alpha = k - lambda * m / 3.0;
        let beta = -k - lambda * m / 6.0;
        self.w.clear();
        self.w.resize(n + 1, 0.0);
        let kp = -beta;
        if n == 1 || kp <= 0.0 {
            // One element (or no coupling): the end alone.
            self.w[n] = 1.0;
        } else {
            // 1 − c and 1 + c without cancellation (as in the chain's evaluation).
            let one_minus_c = 0.5 * lambda * m / kp;
            let one_plus_c = (2.0 * k - lambda * m / 6.0) / kp;
            if one_plus_c > 0.0 {
                let theta = if one_minus_c <= 0.0 {
                    0.0
                } else if one_minus_c <= 1.0 {
                    2.0 * (0.5 * one_minus_c).sqrt().asin()
                } else {
                    std::f64::consts::PI - 2.0 * (0.5 * one_plus_c).sqrt().asin()
                };
                let st = theta.sin();
                for (j, wj) in self.w.iter_mut().enumerate() {
                    // sin(jθ)/sin θ → j as θ → 0.
                    *wj = if st > 0.0 {
                        (j as f64 * theta).sin() / st
                    } else {
                        j as f64
                    };
                }
            } else {
                // c = −cosh φ: (−1)^{j−1} sinh(jφ)/sinh(Nφ), scaled to avoid overflow.
                let phi = 2.0 * (0.5 * (-one_plus_c)).sqrt().asinh();
                let nf = n as f64;
                for (j, wj) in self.w.iter_mut().enumerate().skip(1) {
                    let jf = j as f64;
                    let mag = if phi > 0.0 {
                        (-(nf - jf) * phi).exp() * (-(-2.0 * jf * phi).exp_m1())
                            / (-(-2.0 * nf * phi).exp_m1())
                    } else {
                        jf / nf
                    };
                    *wj = if j % 2 == 1 { mag } else { -mag };
                }
            }
        }
        let wmax = self.w.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        if wmax > 0.0 {
            self.w.iter_mut().for_each(|x| *x /= wmax);
        }
        let wn1 = if n >= 2 { self.w[n - 1] } else { 0.0 };
        self.g = self.w[n];
        self.f = alpha * self.g + beta * wn1;
        self.scale = (alpha.abs() + beta.abs()).max(f64::MIN_POSITIVE);
        // Elements 0 .. N−2 are interior (or anchor) on both ends; element N−1 joins node
        // N−1 to the end.
        let mut m_ii = 0.0;
        for e in 0..n.saturating_sub(1) {
            let (a, b) = (self.w[e], self.w[e + 1]);
            m_ii += a * a + a * b + b * b;
        }
        self.m_ii = m / 3.0 * (m_ii + wn1 * wn1);
        self.m_ie = m / 6.0 * wn1;
        self.m_ee = m / 3.0;
    }

    fn fill_continuous(&mut self, k: f64, m: f64, lambda: f64) {
        self.continuous = true;
        self.cos_coef = 0.0;
        self.w.clear();
        if m <= 0.0 || lambda <= 0.0 || k <= 0.0 {
            // Static (linear) shape.
            self.phi = 0.0;
            self.norm = 1.0;
            self.g = 1.0;
            self.f = k - lambda * m / 3.0;
            self.scale = (k.abs() + (lambda * m).abs()).max(f64::MIN_POSITIVE);
            self.m_ii = m / 3.0;
        } else {
            let phi = (lambda * m / k).sqrt();
            let norm = 1.0 / phi.min(1.0);
            let (s, c) = phi.sin_cos();
            self.phi = phi;
            self.norm = norm;
            self.g = s * norm;
            self.f = k * phi * c * norm;
            self.scale = k * phi.max(1.0);
            // ∫₀¹ sin²(φx) dx = 1/2 − sin(2φ)/(4φ).
            self.m_ii = m * norm * norm * (0.5 - (2.0 * phi).sin() / (4.0 * phi));
        }
        self.m_ie = 0.0;
        self.m_ee = 0.0;
    }

    /// w at position x ∈ [0, 1] along a continuous chain (anchor 0, end 1).
    pub(super) fn at(&self, x: f64) -> f64 {
        if !self.continuous {
            return f64::NAN;
        }
        if self.cos_coef != 0.0 {
            if self.phi == 0.0 {
                self.norm * x + self.cos_coef
            } else {
                let (s, c) = (self.phi * x).sin_cos();
                self.norm * s + self.cos_coef * c
            }
        } else if self.phi == 0.0 {
            x
        } else {
            (self.phi * x).sin() * self.norm
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The discrete shape solves the interior recurrence, and f/g is the chain's own
    /// dynamic stiffness (an independent evaluator: the pivot recurrence).
    #[test]
    fn discrete_shape_solves_the_chain() {
        let (k, m, n) = (400.0, 0.01, 12usize);
        let mut sh = ChainShape::default();
        for lambda in [10.0, 3.0e3, 7.1e4, 4.0e5, 6.0e5, 2.0e6] {
            sh.fill(&ChainKind::Discrete { k, m, n_el: n }, lambda);
            let (a, b) = (k - lambda * m / 3.0, -k - lambda * m / 6.0);
            for j in 1..n {
                let r = b * sh.w[j - 1] + 2.0 * a * sh.w[j] + b * sh.w[j + 1];
                assert!(
                    r.abs() < 1e-12 * (a.abs() + b.abs()),
                    "λ {lambda} j {j}: {r}"
                );
            }
            let s = crate::cable::eval_discrete_recurrence(k, m, n, lambda).s;
            // Relative to the larger of |s| and k (s crosses zero).
            assert!(
                (sh.f / sh.g - s).abs() < 1e-9 * (s.abs() + k),
                "λ {lambda}: {} vs {s}",
                sh.f / sh.g
            );
        }
    }
}
