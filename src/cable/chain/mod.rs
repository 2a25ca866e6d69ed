//! One uniform chain's dynamic stiffness s(λ), s'(λ) and blocked-eigenvalue count: the
//! closed form for N discrete elements (Chebyshev polynomials, O(1) in N), the pivot
//! recurrence it is checked against, and the continuous string or bar (N → ∞).

use super::scalar::ChainScalar;
pub(super) mod supported;

use nalgebra::Matrix3;
use num_complex::Complex64;
use supported::{
    eval_supported, eval_supported_at, supported_end_mass, supported_n_poles, supported_pole,
    Segment,
};

/// Below this (2N − 1)θ, sin((2N−1)θ)/sin θ − (2N − 1) is taken from its θ-series (two
/// terms, exact to rounding there): the direct difference cancels.
const SMALL_ANGLE_SERIES_MAX: f64 = 1e-3;
/// Below this φ, φ cot φ is taken from its series (to φ⁶): the library cot and the
/// derivative cot φ − φ/sin²φ cancel.
const CONTINUOUS_SERIES_MAX_PHI: f64 = 1e-3;

/// How a chain is modelled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ChainKind {
    /// `n_el` equal elements, each with spring `k` (N/m) and consistent mass `m` (kg).
    /// `m = 0`, `n_el = 1` is a massless spring.
    Discrete {
        /// Element spring, N/m.
        k: f64,
        /// Element mass, kg.
        m: f64,
        /// Number of elements.
        n_el: usize,
    },
    /// Continuous string or bar: end stiffness S/L = `k_total` (N/m), mass μL = `m_total` (kg).
    Continuous {
        /// S/L, N/m.
        k_total: f64,
        /// μ L, kg.
        m_total: f64,
    },
    /// A uniform segment whose anchor end is held by another uniform segment fixed at its
    /// far end (the free cable's axial chain on the hidden cable behind its pulley; see
    /// `cable::supported`).
    Supported {
        /// The segment from the junction to the end-effector.
        free: Segment,
        /// The segment from the fixed end (the drum) to the junction.
        hidden: Segment,
    },
}

/// One scalar chain of a cable: its model, its multiplicity (how many identical chains) and
/// the projector onto its end-effector directions (rank = multiplicity).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chain {
    /// The chain's model.
    pub kind: ChainKind,
    /// Number of identical chains (1 or 2).
    pub mult: u32,
    /// Projector P (3 × 3) through which the chain loads the end-effector.
    pub proj: Matrix3<f64>,
}

impl Chain {
    /// A chain that loads nothing (no stiffness, no mass, multiplicity 0): the filler of
    /// preallocated chain tables.
    pub fn idle() -> Chain {
        Chain {
            kind: ChainKind::Discrete {
                k: 0.0,
                m: 0.0,
                n_el: 1,
            },
            mult: 0,
            proj: Matrix3::zeros(),
        }
    }
}

/// Dynamic stiffness of one scalar chain at λ = ω² (rad²/s²); `T` = f64 on the real axis,
/// [`num_complex::Complex64`] at a complex λ ([`Chain::eval_at`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChainEval<T = f64> {
    /// End dynamic stiffness s(λ), N/m.
    pub s: T,
    /// ds/dλ, N/m per rad²/s² (= −kinetic-energy norm of the chain's forced shape, kg).
    pub ds: T,
    /// Number of the chain's blocked (end held) eigenvalues below λ (0 at a complex λ).
    pub below: u32,
}

impl Chain {
    /// Evaluate s(λ), s'(λ) and the blocked count: O(N) recurrence for discrete chains,
    /// closed form for continuous ones. No allocation, bounded loop.
    #[inline]
    pub fn eval(&self, lambda: f64) -> ChainEval {
        match self.kind {
            ChainKind::Discrete { k, m, n_el } => eval_discrete(k, m, n_el, lambda),
            ChainKind::Continuous { k_total, m_total } => eval_continuous(k_total, m_total, lambda),
            ChainKind::Supported { free, hidden } => eval_supported(&free, &hidden, lambda),
        }
    }

    /// s(λ) and s'(λ) at a complex λ (the damped frequency response): the pivot recurrence
    /// ([`eval_discrete_recurrence`], O(N)) for discrete chains, φ cot φ for continuous
    /// ones, the same code as the real evaluation instantiated for [`Complex64`]. The
    /// blocked count is 0 (it has no meaning off the real axis).
    pub fn eval_at(&self, lambda: Complex64) -> ChainEval<Complex64> {
        match self.kind {
            ChainKind::Discrete { k, m, n_el } => {
                if n_el <= 1 || m <= 0.0 {
                    ChainEval {
                        s: Complex64::re(k) - lambda * m / 3.0,
                        ds: Complex64::re(-m / 3.0),
                        below: 0,
                    }
                } else {
                    chain_recurrence(k, m, n_el, lambda)
                }
            }
            ChainKind::Continuous { k_total, m_total } => {
                continuous_string(k_total, m_total, lambda)
            }
            ChainKind::Supported { free, hidden } => eval_supported_at(&free, &hidden, lambda),
        }
    }

    /// The chain's end mass in the limit λ → −∞, kg: lim −s(λ)/λ, the Schur complement of
    /// its mass matrix onto the free end (what the end-effector carries of the chain when
    /// the chain's inner nodes are held by infinitely stiff springs). For N consistent-mass
    /// elements of mass m: m/3 + (m/6)·q with q = U_{N−2}(−2)/U_{N−1}(−2)
    /// = −e^{−φ}(1 − e^{−2(N−1)φ})/(1 − e^{−2Nφ}), φ = acosh 2; 0 for a continuous chain
    /// (its end carries no lumped mass).
    pub fn end_mass_kg(&self) -> f64 {
        match self.kind {
            ChainKind::Discrete { m, n_el, .. } => {
                if m <= 0.0 {
                    return 0.0;
                }
                if n_el <= 1 {
                    return m / 3.0;
                }
                m / 3.0 + m / 6.0 * end_mass_q(n_el)
            }
            ChainKind::Continuous { .. } => 0.0,
            ChainKind::Supported { free, hidden } => supported_end_mass(&free, &hidden),
        }
    }

    /// The chain's end mass from its kind, with q = [`end_mass_q`] for its element count
    /// given (the solver computes q once per element count).
    pub fn end_mass_kg_with(&self, q: f64) -> f64 {
        match self.kind {
            ChainKind::Discrete { m, n_el, .. } if m > 0.0 && n_el > 1 => m / 3.0 + m / 6.0 * q,
            _ => self.end_mass_kg(),
        }
    }

    /// The blocked eigenvalues just below and just above λ: (λ_j, λ_{j+1}) with j the number
    /// of blocked eigenvalues ≤ λ (λ_0 = 0; ∞ when there is none above).
    pub fn poles_around(&self, lambda: f64) -> (f64, f64) {
        self.poles_around_with(lambda, |j| self.pole(j))
    }

    /// [`Chain::poles_around`] with the blocked eigenvalues taken from `pole`, which must
    /// equal [`Chain::pole`] (a table or memo of them: a supported chain's are found by a
    /// root search).
    #[inline]
    pub fn poles_around_with(&self, lambda: f64, pole: impl Fn(usize) -> f64) -> (f64, f64) {
        let j = match self.kind {
            ChainKind::Discrete { k, m, n_el } => {
                if n_el < 2 || m <= 0.0 || k <= 0.0 {
                    return (0.0, f64::INFINITY);
                }
                let kp = k + lambda * m / 6.0;
                let one_minus_c = 0.5 * lambda * m / kp;
                let one_plus_c = (2.0 * k - lambda * m / 6.0) / kp;
                if one_plus_c <= 0.0 {
                    n_el - 1
                } else {
                    let theta = if one_minus_c <= 1.0 {
                        2.0 * (0.5 * one_minus_c).sqrt().asin()
                    } else {
                        std::f64::consts::PI - 2.0 * (0.5 * one_plus_c).sqrt().asin()
                    };
                    ((n_el as f64 * theta / std::f64::consts::PI).floor() as usize).min(n_el - 1)
                }
            }
            ChainKind::Continuous { k_total, m_total } => {
                if m_total <= 0.0 || k_total <= 0.0 {
                    return (0.0, f64::INFINITY);
                }
                ((lambda * m_total / k_total).max(0.0).sqrt() / std::f64::consts::PI).floor()
                    as usize
            }
            ChainKind::Supported { free, hidden } => {
                if supported_n_poles(&free, &hidden) == 0 {
                    return (0.0, f64::INFINITY);
                }
                // Blocked eigenvalues ≤ λ: the count strictly below, plus one when λ is
                // itself one (the next one up equals λ).
                let j = eval_supported(&free, &hidden, lambda).below as usize;
                if pole(j + 1) <= lambda {
                    j + 1
                } else {
                    j
                }
            }
        };
        let lo = if j == 0 { 0.0 } else { pole(j) };
        (lo, pole(j + 1))
    }

    /// The j-th (1-based) blocked eigenvalue λ_j, rad²/s²; ∞ when it does not exist.
    /// Discrete: λ_j = 6k(1 − cos θ_j) / (m (2 + cos θ_j)), θ_j = jπ/N. Continuous: (jπ)² k/m.
    pub fn pole(&self, j: usize) -> f64 {
        match self.kind {
            ChainKind::Discrete { k, m, n_el } => {
                if n_el < 2 || m <= 0.0 || j == 0 || j >= n_el {
                    return f64::INFINITY;
                }
                let th = j as f64 * std::f64::consts::PI / n_el as f64;
                let one_minus_c = 2.0 * (0.5 * th).sin().powi(2);
                6.0 * k * one_minus_c / (m * (2.0 + th.cos()))
            }
            ChainKind::Continuous { k_total, m_total } => {
                if m_total <= 0.0 || j == 0 {
                    return f64::INFINITY;
                }
                let pj = j as f64 * std::f64::consts::PI;
                pj * pj * k_total / m_total
            }
            ChainKind::Supported { free, hidden } => supported_pole(&free, &hidden, j),
        }
    }
}

/// Uniform chain in closed form (O(1) in N). With c = −α/β (α = k − λm/3, β = −k − λm/6),
/// the end stiffness is s = α + β U_{N−2}(c)/U_{N−1}(c) (Chebyshev polynomials of the 2nd
/// kind): for c = cos θ, U_{N−2}/U_{N−1} = sin((N−1)θ)/sin(Nθ); for c = −cosh φ (above the
/// chain's cut-off λ > 12k/m), −sinh((N−1)φ)/sinh(Nφ). The blocked count is the number of
/// θ_j = jπ/N below θ. dR/dc = −((2N−1) − sin((2N−1)θ)/sin θ)/(2 sin²(Nθ)), with a series
/// where that difference cancels. θ and φ are computed from 1 − c and 1 + c, which are
/// formed without cancellation.
#[inline]
pub(super) fn eval_discrete(k: f64, m: f64, n_el: usize, lambda: f64) -> ChainEval {
    let alpha = k - lambda * m / 3.0;
    let dalpha = -m / 3.0;
    if n_el <= 1 || m <= 0.0 || k <= 0.0 {
        if n_el <= 1 || m <= 0.0 {
            return ChainEval {
                s: alpha,
                ds: dalpha,
                below: 0,
            };
        }
        return eval_discrete_recurrence(k, m, n_el, lambda);
    }
    let beta = -k - lambda * m / 6.0;
    let dbeta = -m / 6.0;
    let kp = k + lambda * m / 6.0; // = −β > 0
    let one_minus_c = 0.5 * lambda * m / kp;
    let one_plus_c = (2.0 * k - lambda * m / 6.0) / kp;
    let dc = -0.5 * m * k / (kp * kp);
    let nf = n_el as f64;
    let n2 = 2.0 * nf - 1.0;
    // (R, 1 − R, dR/dc, blocked count); s = α + βR = k(1 − R) − λm(1/3 + R/6), with 1 − R
    // formed without cancellation (α + βR loses log₁₀ N digits at small λ).
    let (r, one_minus_r, drdc, below) = if one_plus_c > 0.0 {
        let theta = if one_minus_c <= 1.0 {
            2.0 * (0.5 * one_minus_c).sqrt().asin()
        } else {
            std::f64::consts::PI - 2.0 * (0.5 * one_plus_c).sqrt().asin()
        };
        if theta == 0.0 {
            let r = (nf - 1.0) / nf;
            let drdc = -n2 * (n2 * n2 - 1.0) / (12.0 * nf * nf);
            (r, 1.0 / nf, drdc, 0u32)
        } else {
            // sin θ and cos θ exactly from 1 ∓ c; one sin_cos for Nθ.
            let c = 1.0 - one_minus_c;
            let st = (one_minus_c * one_plus_c).sqrt();
            let (sn, cn) = (nf * theta).sin_cos();
            let sn1 = sn * c - cn * st; // sin((N−1)θ)
            let r = sn1 / sn;
            // 1 − R = (sin Nθ − sin (N−1)θ)/sin Nθ = 2 sin(θ/2) cos((N − ½)θ)/sin Nθ.
            let (sh, ch) = ((0.5 * one_minus_c).sqrt(), (0.5 * one_plus_c).sqrt());
            let one_minus_r = 2.0 * sh * (cn * ch + sn * sh) / sn;
            let diff = if n2 * theta < SMALL_ANGLE_SERIES_MAX {
                let t2 = theta * theta;
                let a = n2 * (n2 * n2 - 1.0);
                a * t2 / 6.0 - a * (3.0 * n2 * n2 - 7.0) * t2 * t2 / 360.0
            } else {
                // sin((2N−1)θ) = sin 2Nθ cos θ − cos 2Nθ sin θ
                let s2 = 2.0 * sn * cn;
                let c2 = 1.0 - 2.0 * sn * sn;
                n2 - (s2 * c - c2 * st) / st
            };
            let drdc = -diff / (2.0 * sn * sn);
            let below = ((nf * theta / std::f64::consts::PI).ceil() as i64 - 1)
                .clamp(0, n_el as i64 - 1) as u32;
            (r, one_minus_r, drdc, below)
        }
    } else {
        // c ≤ −1: c = −cosh φ, cosh φ − 1 = 2 sinh²(φ/2) = −(1 + c).
        let phi = 2.0 * (0.5 * (-one_plus_c)).sqrt().asinh();
        if phi == 0.0 {
            return eval_discrete_recurrence(k, m, n_el, lambda);
        }
        let e = (-phi).exp();
        let e2n = e.powi(2 * n_el as i32);
        let e2n1 = e.powi(2 * (n_el as i32 - 1));
        let r = -e * (1.0 - e2n1) / (1.0 - e2n);
        // dR/dc = ½[(2N−1) − sinh((2N−1)φ)/sinh φ] / sinh²(Nφ), in scaled form.
        let sh = phi.sinh();
        let den = (1.0 - e2n) * (1.0 - e2n);
        let term1 = n2 * 4.0 * e2n / den;
        let term2 = 2.0 * e * (1.0 - e.powi(2 * (2 * n_el as i32 - 1))) / (sh * den);
        (r, 1.0 - r, 0.5 * (term1 - term2), (n_el - 1) as u32)
    };
    ChainEval {
        s: k * one_minus_r - lambda * m * (1.0 / 3.0 + r / 6.0),
        ds: dalpha + dbeta * r + beta * drdc * dc,
        below,
    }
}

/// q = U_{N−2}(−2)/U_{N−1}(−2) = −r(1 − r^{2(N−1)})/(1 − r^{2N}), r = 2 − √3, of
/// [`Chain::end_mass_kg`] for N ≥ 2 elements.
pub fn end_mass_q(n_el: usize) -> f64 {
    let r = 2.0 - 3.0f64.sqrt(); // e^{−φ}, φ = acosh 2
    let r2 = r * r;
    -r * (1.0 - r2.powi(n_el as i32 - 1)) / (1.0 - r2.powi(n_el as i32))
}

/// Pivot recurrence of the uniform chain (interior diagonal 2α, off-diagonal β):
/// p₁ = 2α, p_j = 2α − β²/p_{j−1}; s = α − β²/p_{N−1}; negative pivots = blocked count.
/// O(N); the reference for the closed form and the fallback at its singular points.
pub fn eval_discrete_recurrence(k: f64, m: f64, n_el: usize, lambda: f64) -> ChainEval {
    chain_recurrence(k, m, n_el, lambda)
}

/// [`eval_discrete_recurrence`] over the scalar `T` (f64 or complex λ).
#[inline]
pub fn chain_recurrence<T: ChainScalar>(k: f64, m: f64, n_el: usize, lambda: T) -> ChainEval<T> {
    let alpha = T::re(k) - lambda * m / 3.0;
    let dalpha = -m / 3.0;
    if n_el <= 1 {
        return ChainEval {
            s: alpha,
            ds: T::re(dalpha),
            below: 0,
        };
    }
    let beta = T::re(-k) - lambda * m / 6.0;
    let dbeta = -m / 6.0;
    let b2 = beta * beta;
    let db2 = beta * 2.0 * dbeta;
    let tiny = f64::EPSILON * k.abs().max(1e-300);
    let mut p = alpha * 2.0;
    let mut dp = T::re(2.0 * dalpha);
    let mut below = 0u32;
    // One pivot: count it (a zero pivot nudged to `tiny`), then β²/p and its λ-derivative.
    let mut eliminate = |p: T, dp: T| {
        let p = if p.is_zero() { T::re(tiny) } else { p };
        below += p.is_negative() as u32;
        let inv = p.recip();
        let t = b2 * inv;
        (t, (db2 - t * dp) * inv)
    };
    for _ in 1..n_el - 1 {
        let (t, dt) = eliminate(p, dp);
        p = alpha * 2.0 - t;
        dp = T::re(2.0 * dalpha) - dt;
    }
    let (t, dt) = eliminate(p, dp);
    ChainEval {
        s: alpha - t,
        ds: T::re(dalpha) - dt,
        below,
    }
}

/// Fixed-free string/bar: s = K φ cot φ with φ = √(λ m / K) (K = S/L, m = μL).
#[inline]
pub(super) fn eval_continuous(k: f64, m: f64, lambda: f64) -> ChainEval {
    continuous_string(k, m, lambda)
}

/// [`eval_continuous`] over the scalar `T` (f64 or complex λ; φ cot φ is even in φ, so
/// the branch of the square root does not matter off the real axis).
#[inline]
pub(super) fn continuous_string<T: ChainScalar>(k: f64, m: f64, lambda: T) -> ChainEval<T> {
    if m <= 0.0 || lambda.is_nonpositive() {
        return ChainEval {
            s: T::re(k) - lambda * m / 3.0,
            ds: T::re(-m / 3.0),
            below: 0,
        };
    }
    let phi2 = lambda * m / k;
    let phi = phi2.sqrt();
    let below = below_continuous(phi);
    if phi.modulus() < CONTINUOUS_SERIES_MAX_PHI {
        // φ cot φ = 1 − φ²/3 − φ⁴/45 − 2φ⁶/945
        let s =
            (T::re(1.0) - phi2 / 3.0 - phi2 * phi2 / 45.0 - phi2 * 2.0 * phi2 * phi2 / 945.0) * k;
        let ds = (T::re(-1.0 / 3.0) - phi2 * 2.0 / 45.0 - phi2 * 6.0 * phi2 / 945.0) * m;
        return ChainEval { s, ds, below };
    }
    let (sn, cs) = phi.sin_cos();
    let cot = cs / sn;
    let s = phi * k * cot;
    // d(φ cot φ)/dφ = cot φ − φ / sin² φ ; dφ/dλ = φ / (2λ) = m / (2 k φ)
    let dfdphi = cot - phi / (sn * sn);
    let ds = dfdphi * k * m / (phi * (2.0 * k));
    ChainEval { s, ds, below }
}

/// The continuous chain's blocked count at φ ≥ 0: ⌈φ/π⌉ − 1 on the real axis, 0 off it.
#[inline]
fn below_continuous<T: ChainScalar>(phi: T) -> u32 {
    if !T::REAL {
        return 0;
    }
    (phi.modulus() / std::f64::consts::PI).ceil() as u32 - 1
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// Compares two evaluators of the uniform chain on a λ grid up to 1.3 × the cut-off
    /// 12k/m, for three (k, m) pairs and the given element counts. s has absolute accuracy
    /// ~ε·N·k (cancellation α + βR), s' relative ε·N²·(pole factor). Returns the worst errors.
    pub(crate) fn compare_chain_evals(
        ns: &[usize],
        f: impl Fn(f64, f64, usize, f64) -> ChainEval,
        g: impl Fn(f64, f64, usize, f64) -> ChainEval,
    ) -> [f64; 2] {
        let mut worst = [0.0f64; 2];
        for &n in ns {
            for &(k, m) in &[(400.0, 0.01), (1.9e7, 1.4e-3), (3.0, 2e-3)] {
                let cut = 12.0 * k / m;
                for i in 0..400 {
                    let lambda = cut * 1.3 * (i as f64 / 400.0).powi(3) + 1e-9 * cut * i as f64;
                    let (a, b) = (f(k, m, n, lambda), g(k, m, n, lambda));
                    assert_eq!(a.below, b.below, "n {n} k {k} λ {lambda}");
                    let es = (a.s - b.s).abs() / (k * (1.0 + b.s.abs() / k));
                    let ed = (a.ds - b.ds).abs() / (m + b.ds.abs());
                    let at = lambda / cut;
                    assert!(
                        es < 1e-11 * n as f64,
                        "s: n {n} λ/cut {at} {} vs {}",
                        a.s,
                        b.s
                    );
                    let tol = 1e-8 * (n * n) as f64;
                    assert!(ed < tol, "ds: n {n} λ/cut {at} {} vs {}", a.ds, b.ds);
                    worst[0] = worst[0].max(es);
                    worst[1] = worst[1].max(ed);
                }
            }
        }
        worst
    }

    #[test]
    fn closed_form_equals_recurrence() {
        let ns = [2usize, 3, 5, 10, 40, 80, 200];
        let w = compare_chain_evals(&ns, eval_discrete, eval_discrete_recurrence);
        eprintln!("closed form vs recurrence: s {:.2e}, s' {:.2e}", w[0], w[1]);
    }

    #[test]
    fn discrete_chain_static_and_poles() {
        let c = Chain {
            kind: ChainKind::Discrete {
                k: 400.0,
                m: 0.01,
                n_el: 8,
            },
            mult: 1,
            proj: Matrix3::identity(),
        };
        let e0 = c.eval(0.0);
        assert!((e0.s - 50.0).abs() < 1e-12);
        for j in 1..8 {
            let p = c.pole(j);
            assert_eq!(c.eval(p * (1.0 - 1e-9)).below, j as u32 - 1);
            assert_eq!(c.eval(p * (1.0 + 1e-9)).below, j as u32);
        }
        // Derivative against a central difference.
        let l = 0.37 * c.pole(1);
        let h = 1e-6 * l;
        let fd = (c.eval(l + h).s - c.eval(l - h).s) / (2.0 * h);
        assert!((fd - c.eval(l).ds).abs() < 1e-6 * fd.abs());
    }

    /// The chain's end stiffness at a complex λ (what the damped frequency response needs)
    /// against an independent dense complex solve: the (N × N) K − λM of the chain with its
    /// anchor fixed, condensed onto the free end as 1/(K − λM)⁻¹_NN (nalgebra's complex
    /// LU). Agreement to 1e-12 relative (both are O(N) rounding away from exact at N ≤ 40).
    #[test]
    fn complex_lambda_matches_dense_condensation() {
        use nalgebra::DMatrix;
        let (k, m) = (400.0, 0.01);
        for n in [2usize, 5, 10, 40] {
            for lambda in [
                Complex64::new(3e4, 1e3),
                Complex64::new(2e5, -4e4),
                Complex64::new(-1e3, 5e2),
                Complex64::new(9e5, 9e3),
            ] {
                let mut a = DMatrix::<Complex64>::zeros(n, n);
                let diag = Complex64::re(2.0 * k) - lambda * (2.0 * m / 3.0);
                let off = Complex64::re(-k) - lambda * (m / 6.0);
                for i in 0..n {
                    a[(i, i)] = diag;
                    if i + 1 < n {
                        a[(i, i + 1)] = off;
                        a[(i + 1, i)] = off;
                    }
                }
                a[(n - 1, n - 1)] = Complex64::re(k) - lambda * (m / 3.0);
                let inv = a.lu().try_inverse().expect("regular");
                let dense = inv[(n - 1, n - 1)].inv();
                let c = Chain {
                    kind: ChainKind::Discrete { k, m, n_el: n },
                    mult: 1,
                    proj: Matrix3::identity(),
                };
                let got = c.eval_at(lambda).s;
                let err = (got - dense).norm() / dense.norm();
                assert!(err < 1e-12, "n {n} λ {lambda}: {got} vs {dense} ({err})");
            }
            // On the real axis the complex instance is the real recurrence (to rounding:
            // complex division rounds differently).
            let l = 0.3 * 12.0 * k / m;
            let (re, cx) = (
                eval_discrete_recurrence(k, m, n, l),
                chain_recurrence(k, m, n, Complex64::re(l)),
            );
            assert!((re.s - cx.s.re).abs() < 1e-13 * re.s.abs() && cx.s.im == 0.0);
            assert!((re.ds - cx.ds.re).abs() < 1e-13 * re.ds.abs(), "n {n}");
        }
    }

    /// The continuous string at a complex λ is the N → ∞ limit of the discrete chain there:
    /// the difference falls as 1/N² (ratio ≈ 4 per doubling).
    #[test]
    fn complex_continuous_is_the_limit_of_the_chain() {
        let (k_total, m_total) = (2.0e3, 0.05);
        let lambda = Complex64::new(1.5e5, 3e3);
        let cont = Chain {
            kind: ChainKind::Continuous { k_total, m_total },
            mult: 1,
            proj: Matrix3::identity(),
        }
        .eval_at(lambda)
        .s;
        let err = |n: usize| {
            let d = Chain {
                kind: ChainKind::Discrete {
                    k: k_total * n as f64,
                    m: m_total / n as f64,
                    n_el: n,
                },
                mult: 1,
                proj: Matrix3::identity(),
            }
            .eval_at(lambda)
            .s;
            (d - cont).norm() / cont.norm()
        };
        let (e1, e2, e3) = (err(100), err(200), err(400));
        assert!(e1 < 1e-2, "{e1}");
        for (a, b) in [(e1, e2), (e2, e3)] {
            assert!((b * 4.0 / a - 1.0).abs() < 0.05, "{a} {b}");
        }
    }
}
