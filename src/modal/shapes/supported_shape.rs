//! The shape of a supported chain (`cable::supported`: the free cable's axial chain in
//! series with the cable hidden between the pulley and the winch drum) at a given λ: one
//! non-uniform chain held at the drum, so again a one-parameter family.
//!
//! - **Discrete** (hidden: N_h elements k_h, m_h; free: N elements k, m): nodes 0 (drum,
//!   w = 0), 1 … N_h (the junction at the pulley), then the free cable's nodes to the end.
//!   Each node's equation β_l w_{j−1} + (α_l + α_r) w_j + β_r w_{j+1} = 0 (α = k − λm/3,
//!   β = −k − λm/6 of the elements on its left and right) gives w_{j+1} from w_{j−1}, w_j
//!   (β_r < 0 for λ ≥ 0: no division by zero), from w_0 = 0, w_1 = 1; the values are
//!   rescaled on the way so nothing overflows above the cut-off.
//! - **Continuous** (two bars, end stiffnesses K_h, K and masses M_h, M): the hidden bar is
//!   sin(φ_h x), φ_h = √(λM_h/K_h); at the junction the free bar starts with its value
//!   v = sin φ_h and its force F = K_h φ_h cos φ_h, so w(y) = v cos(φy) + F/(Kφ) sin(φy)
//!   (φ = √(λM/K); the linear limits where a bar has no mass).
//!
//! The shape stored is the free cable's part (node 0 the junction, which moves); the hidden
//! cable's part enters the mass moment m_ii only (its nodes are not drawn).

use super::chain_shape::ChainShape;
use crate::cable::Segment;

/// Rescale the discrete recurrence when a value passes this (far from overflow).
pub(super) const RESCALE_ABOVE: f64 = 1e150;

impl ChainShape {
    /// Fill for the supported chain `free` on `hidden` at λ (rad²/s²). False when the two
    /// segments are not both discrete or both continuous (no model builds that).
    pub(super) fn fill_supported(&mut self, free: &Segment, hidden: &Segment, lambda: f64) -> bool {
        match (free.n_el, hidden.n_el) {
            (0, 0) => {
                self.fill_supported_bar(free, hidden, lambda);
                true
            }
            (n, nh) if n > 0 && nh > 0 => {
                self.fill_supported_discrete(free, hidden, lambda);
                true
            }
            _ => false,
        }
    }

    fn fill_supported_discrete(&mut self, free: &Segment, hidden: &Segment, lambda: f64) {
        self.set_continuous(false);
        let (n, nh) = (free.n_el, hidden.n_el);
        let coef = |s: &Segment| (s.k - lambda * s.m / 3.0, -s.k - lambda * s.m / 6.0);
        let (ah, bh) = coef(hidden);
        let (af, bf) = coef(free);
        // All nodes, drum to end: nh + n + 1 values.
        let total = nh + n;
        let mut all = vec![0.0; total + 1];
        all[1] = 1.0;
        for j in 1..total {
            let (al, bl) = if j <= nh { (ah, bh) } else { (af, bf) };
            let (ar, br) = if j < nh { (ah, bh) } else { (af, bf) };
            all[j + 1] = -(bl * all[j - 1] + (al + ar) * all[j]) / br;
            if all[j + 1].abs() > RESCALE_ABOVE {
                let s = 1.0 / all[j + 1].abs();
                all[..=j + 1].iter_mut().for_each(|x| *x *= s);
            }
        }
        let wmax = all.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        if wmax > 0.0 {
            all.iter_mut().for_each(|x| *x /= wmax);
        }
        let mut hidden_ii = 0.0;
        for e in 0..nh {
            let (a, b) = (all[e], all[e + 1]);
            hidden_ii += a * a + a * b + b * b;
        }
        self.w.clear();
        self.w.extend_from_slice(&all[nh..]);
        self.hidden_w.clear();
        self.hidden_w.extend_from_slice(&all[..=nh]);
        let wn1 = self.w[n - 1];
        self.g = self.w[n];
        self.f = af * self.g + bf * wn1;
        self.scale = (af.abs() + bf.abs()).max(f64::MIN_POSITIVE);
        let mut free_ii = 0.0;
        for e in 0..n - 1 {
            let (a, b) = (self.w[e], self.w[e + 1]);
            free_ii += a * a + a * b + b * b;
        }
        self.m_ii = hidden.m / 3.0 * hidden_ii + free.m / 3.0 * (free_ii + wn1 * wn1);
        self.m_ie = free.m / 6.0 * wn1;
        self.m_ee = free.m / 3.0;
    }

    fn fill_supported_bar(&mut self, free: &Segment, hidden: &Segment, lambda: f64) {
        self.set_continuous(true);
        self.w.clear();
        let phase = |s: &Segment| {
            if s.m > 0.0 && lambda > 0.0 {
                (lambda * s.m / s.k).sqrt()
            } else {
                0.0
            }
        };
        let (ph, pf) = (phase(hidden), phase(free));
        // The hidden bar: value and force at the junction, and ∫₀¹ w² (unnormalised).
        let (v, force, int_h) = if ph > 0.0 {
            let (s, c) = ph.sin_cos();
            (s, hidden.k * ph * c, 0.5 - (2.0 * ph).sin() / (4.0 * ph))
        } else {
            (1.0, hidden.k, 1.0 / 3.0)
        };
        // The free bar: w(y) = v cos(φy) + a sin(φy) (φ > 0) or v + a y.
        let (a, g, f, int_f) = if pf > 0.0 {
            let a = force / (free.k * pf);
            let (s, c) = pf.sin_cos();
            let s2 = (2.0 * pf).sin() / (4.0 * pf);
            let int = v * v * (0.5 + s2) + a * a * (0.5 - s2) + v * a * s * s / pf;
            (a, v * c + a * s, free.k * pf * (a * c - v * s), int)
        } else {
            let a = force / free.k;
            (a, v + a, force, v * v + v * a + a * a / 3.0)
        };
        // Normalise to O(1): |w| ≤ √(v² + a²) on the free bar, ≤ 1 on the hidden one.
        let norm = 1.0 / (v * v + a * a).sqrt().max(1.0);
        self.set_bar(pf, a * norm, v * norm);
        self.g = g * norm;
        self.f = f * norm;
        self.scale = free.k * pf.max(1.0) + hidden.k * ph.max(1.0);
        self.m_ii = (hidden.m * int_h + free.m * int_f) * norm * norm;
        self.m_ie = 0.0;
        self.m_ee = 0.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cable::{eval_supported, supported_pole};

    /// f/g of the shape is the supported chain's end stiffness (the two-port formula of
    /// `cable::supported`, an independent evaluator), discrete and continuous, below,
    /// between and above the chain's poles; the discrete shape solves every node's
    /// equation.
    #[test]
    fn supported_shape_gives_the_supported_chains_stiffness() {
        let pairs = [
            (
                Segment {
                    k: 2.0e6,
                    m: 0.03,
                    n_el: 10,
                },
                Segment {
                    k: 1.4e6,
                    m: 0.04,
                    n_el: 10,
                },
            ),
            (
                Segment {
                    k: 1.0e6,
                    m: 0.5,
                    n_el: 0,
                },
                Segment {
                    k: 3.0e6,
                    m: 0.2,
                    n_el: 0,
                },
            ),
            (
                Segment {
                    k: 1.0e6,
                    m: 0.5,
                    n_el: 0,
                },
                Segment {
                    k: 3.0e6,
                    m: 0.0,
                    n_el: 0,
                },
            ),
        ];
        for (free, hidden) in pairs {
            let p1 = supported_pole(&free, &hidden, 1);
            let p1 = if p1.is_finite() { p1 } else { 1e6 };
            for x in [0.3, 0.77, 1.5, 2.9, 7.3] {
                let lambda = x * p1;
                let mut sh = ChainShape::default();
                assert!(sh.fill_supported(&free, &hidden, lambda));
                let s = eval_supported(&free, &hidden, lambda).s;
                let got = sh.f / sh.g;
                assert!(
                    (got - s).abs() <= 1e-8 * (s.abs() + free.k + hidden.k),
                    "{free:?} λ {lambda}: {got} vs {s}"
                );
                assert!(sh.m_ii > 0.0 && sh.m_ii.is_finite());
            }
        }
    }
}
