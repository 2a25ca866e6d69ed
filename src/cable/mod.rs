//! Cable element models and their decomposition into scalar chains.
//!
//! Each cable is split into N equal elements from its anchor (node I of the first
//! element) to the end-effector (node J of the last one), 3 translational DOF per node.
//! Every element of a cable has the same chord, tension T (N) and length l = L/N (m), so
//! every element has the same 3 × 3 stiffness block K_c (N/m) and the element matrices
//!
//! ```text
//!     K_e = [ K_c  −K_c ; −K_c  K_c ],      M_e = (μ l / 6) [ 2I  I ; I  2I ]   (Eq. 16)
//! ```
//!
//! - FEM element (Eqs. 16-18): K_c = EA/l · e eᵀ + T/l · (I − e eᵀ) (the sum of K_L and K_G).
//! - Catenary element (Eqs. 19-32) in the cancellation-free form of reference/notes.md:
//!   the flexibility F (m/N) in a local frame whose z axis points up (against gravity),
//!   K_c = −F⁻¹ (F is negative definite in the paper's sign convention), rotated to the
//!   global frame. Uses the chord as unstressed length L0 and the QP tension T0 (Step 3).
//!
//! With K_c = Σ_r k_r v_r v_rᵀ (eigen-decomposition), the cable's interior nodes decouple
//! into scalar *chains*: uniform spring-mass chains with spring k_r (N/m) and consistent
//! element mass m_e = μ l (kg), fixed at the anchor and attached to the end-effector along
//! v_r. The FEM element has one axial chain (k = EA/l, direction e) and a transverse chain
//! of multiplicity 2 (k = T/l, projector I − e eᵀ). See [`Chain`].

use crate::scene::ElementKind;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// Errors of the element models.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum CableError {
    /// Tension not positive and finite.
    #[error("cable tension {0} N must be finite and > 0")]
    BadTension(f64),
    /// The element cannot hang: a vertical element whose tension is below its own weight
    /// (the catenary's low point would need a slack segment).
    #[error("catenary element cannot carry its own weight (tension {tension_n} N, element weight {weight_n} N)")]
    TooSlack {
        /// Tension, N.
        tension_n: f64,
        /// Element weight γ L0, N.
        weight_n: f64,
    },
    /// The flexibility matrix is singular or not definite (numerically broken input).
    #[error("catenary flexibility matrix is not definite")]
    NotDefinite,
    /// The `auto` model must be resolved (estimator::resolve_auto) before use.
    #[error("the auto model is not resolved")]
    Unresolved,
}

/// FEM element stiffness block K_c = EA/l e eᵀ + T/l (I − e eᵀ), N/m.
/// `geometric` = false drops the T/l term (axial springs only, the paper's ref. [7]).
pub fn fem_block(
    e: &Vector3<f64>,
    length_m: f64,
    ea_n: f64,
    tension_n: f64,
    geometric: bool,
) -> Matrix3<f64> {
    let eet = e * e.transpose();
    let kt = if geometric { tension_n / length_m } else { 0.0 };
    eet * (ea_n / length_m) + (Matrix3::identity() - eet) * kt
}

/// Flexibility matrix F (m/N) of the catenary element in its local frame (z up), in the
/// cancellation-free form of reference/notes.md. `f` = (F1, F2, F3) is the force on the
/// element at node I, `l0_m` the unstressed length, `ea_n` = EA, `gamma_n_m` the weight per
/// length γ ≥ 0. Exact for γ = 0 and for vertical elements.
pub fn catenary_flexibility(
    f: &Vector3<f64>,
    l0_m: f64,
    ea_n: f64,
    gamma_n_m: f64,
) -> Result<Matrix3<f64>, CableError> {
    let (f1, f2, f3) = (f.x, f.y, f.z);
    let a = f3;
    let b = f3 - gamma_n_m * l0_m;
    let h2 = f1 * f1 + f2 * f2;
    let ti = (h2 + a * a).sqrt();
    let tj = (h2 + b * b).sqrt();
    let s = ti + tj;
    let q = if a * b >= 0.0 {
        1.0 + (h2 + a * a + b * b) / (ti * tj + a * b)
    } else {
        if h2 <= 0.0 || !(h2 > 1e-24 * (a * a + b * b)) {
            return Err(CableError::TooSlack {
                tension_n: ti,
                weight_n: gamma_n_m * l0_m,
            });
        }
        (h2 + ti * tj - a * b) / h2
    };
    let den = s * ti * tj;
    let b1 = l0_m * q / den;
    let b2 = l0_m * (a + b) / den;
    let x = l0_m * q / s;
    let y = gamma_n_m * x;
    let lam = if y.abs() < 1e-4 {
        let y2 = y * y;
        x * (1.0 - y2 / 6.0 + 3.0 * y2 * y2 / 40.0)
    } else {
        x * (y.asinh() / y)
    };
    let c = l0_m / ea_n;
    let f11 = -c - lam + f1 * f1 * b1;
    let f22 = -c - lam + f2 * f2 * b1;
    let f12 = f1 * f2 * b1;
    let f13 = f1 * b2;
    let f23 = f2 * b2;
    let f33 = -c - h2 * b1;
    let m = Matrix3::new(f11, f12, f13, f12, f22, f23, f13, f23, f33);
    if !m.iter().all(|v| v.is_finite()) {
        return Err(CableError::NotDefinite);
    }
    Ok(m)
}

/// An orthonormal frame whose third column points up (against `gravity`); any frame when
/// gravity is zero (the catenary element is then the rotation-invariant straight limit).
pub fn up_frame(gravity_m_s2: &Vector3<f64>) -> Matrix3<f64> {
    let g = gravity_m_s2.norm();
    let up = if g > 0.0 {
        -gravity_m_s2 / g
    } else {
        Vector3::z()
    };
    // Pick the coordinate axis least aligned with `up` to build x.
    let seed = if up.x.abs() <= up.y.abs() && up.x.abs() <= up.z.abs() {
        Vector3::x()
    } else if up.y.abs() <= up.z.abs() {
        Vector3::y()
    } else {
        Vector3::z()
    };
    let x = (seed - up * up.dot(&seed)).normalize();
    let y = up.cross(&x);
    Matrix3::from_columns(&[x, y, up])
}

/// Catenary element stiffness in modal form: K_c = Σ_r k_r v_r v_rᵀ (N/m, global frame) for
/// an element with chord `chord_m` from node I to node J, tension `t0_n`, EA and weight per
/// length γ, in the frame `frame` from [`up_frame`]. The decomposition is done on
/// G = F + (L0/EA) I in the local frame (F = G − (L0/EA) I shares its eigenvectors), so
/// k_r = 1/(L0/EA − g_r): the transverse stiffnesses (≈ T/L0) come out with relative
/// accuracy ε instead of the ε·EA/T of decomposing K itself.
pub fn catenary_modes(
    chord_m: &Vector3<f64>,
    t0_n: f64,
    ea_n: f64,
    gamma_n_m: f64,
    frame: &Matrix3<f64>,
) -> Result<([f64; 3], [Vector3<f64>; 3]), CableError> {
    if !(t0_n.is_finite() && t0_n > 0.0) {
        return Err(CableError::BadTension(t0_n));
    }
    let l0 = chord_m.norm();
    let local = frame.transpose() * chord_m;
    let f = -local * (t0_n / l0);
    let flex = catenary_flexibility(&f, l0, ea_n, gamma_n_m)?;
    let c = l0 / ea_n;
    let g = flex + Matrix3::identity() * c;
    let eig = SymmetricEigen::new(g);
    let mut k = [0.0; 3];
    let mut v = [Vector3::zeros(); 3];
    for r in 0..3 {
        let d = c - eig.eigenvalues[r];
        if !(d > 0.0 && d.is_finite()) {
            return Err(CableError::NotDefinite);
        }
        k[r] = 1.0 / d;
        v[r] = frame * eig.eigenvectors.column(r);
    }
    Ok((k, v))
}

/// Catenary element stiffness block (N/m, global frame, positive definite): Σ k_r v_r v_rᵀ
/// of [`catenary_modes`].
pub fn catenary_block(
    chord_m: &Vector3<f64>,
    t0_n: f64,
    ea_n: f64,
    gamma_n_m: f64,
    frame: &Matrix3<f64>,
) -> Result<Matrix3<f64>, CableError> {
    let (k, v) = catenary_modes(chord_m, t0_n, ea_n, gamma_n_m, frame)?;
    Ok((0..3).fold(Matrix3::zeros(), |acc, r| {
        acc + v[r] * v[r].transpose() * k[r]
    }))
}

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

/// Dynamic stiffness of one scalar chain at λ = ω² (rad²/s²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChainEval {
    /// End dynamic stiffness s(λ), N/m.
    pub s: f64,
    /// ds/dλ, N/m per rad²/s² (= −kinetic-energy norm of the chain's forced shape, kg).
    pub ds: f64,
    /// Number of the chain's blocked (end held) eigenvalues below λ.
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
        };
        let lo = if j == 0 { 0.0 } else { self.pole(j) };
        (lo, self.pole(j + 1))
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
fn eval_discrete(k: f64, m: f64, n_el: usize, lambda: f64) -> ChainEval {
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
    let (r, drdc, below) = if one_plus_c > 0.0 {
        let theta = if one_minus_c <= 1.0 {
            2.0 * (0.5 * one_minus_c).sqrt().asin()
        } else {
            std::f64::consts::PI - 2.0 * (0.5 * one_plus_c).sqrt().asin()
        };
        if theta == 0.0 {
            let r = (nf - 1.0) / nf;
            let drdc = -n2 * (n2 * n2 - 1.0) / (12.0 * nf * nf);
            (r, drdc, 0u32)
        } else {
            // sin θ and cos θ exactly from 1 ∓ c; one sin_cos for Nθ.
            let c = 1.0 - one_minus_c;
            let st = (one_minus_c * one_plus_c).sqrt();
            let (sn, cn) = (nf * theta).sin_cos();
            let sn1 = sn * c - cn * st; // sin((N−1)θ)
            let r = sn1 / sn;
            let diff = if n2 * theta < 1e-3 {
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
            (r, drdc, below)
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
        (r, 0.5 * (term1 - term2), (n_el - 1) as u32)
    };
    ChainEval {
        s: alpha + beta * r,
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

/// Largest element count evaluated by [`eval_discrete_batch`] (above it the closed form
/// is cheaper than the O(N) recurrence).
pub const BATCH_MAX_ELEMENTS: usize = 64;

/// Several uniform chains with the same element count `n_el` (2 ..= [`BATCH_MAX_ELEMENTS`])
/// at one λ, by the Chebyshev recurrence in differential form, written chain-innermost so
/// the chains run side by side (no trigonometry, no division inside the loop).
///
/// With δ = 1 − c = ½λm/(k + λm/6) and U_j = U_j(1 − δ): D_j = U_j − U_{j−1} obeys
/// D_{j+1} = D_j − 2δU_j, U_{j+1} = U_j + D_{j+1} (U_0 = D_0 = 1), which never forms
/// 1 − U_{N−2}/U_{N−1} by cancellation. Then s = −λm/2 + (k + λm/6)·D_{N−1}/U_{N−1}; the
/// δ-derivatives follow the same recurrence; the blocked count is the number of sign
/// changes of U_0 … U_{N−1} (Sturm: LDLᵀ pivots −β U_j/U_{j−1}, a zero counted positive).
/// For δ < 3 (every λ ≥ 0) |U_j| ≤ 5^j, so nothing overflows for N ≤ 400.
/// `k`, `m` (N/m, kg) are per element; results go to `out` (same length).
pub fn eval_discrete_batch(k: &[f64], m: &[f64], n_el: usize, lambda: f64, out: &mut [ChainEval]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            unsafe { batch_avx2(k, m, n_el, lambda, out) };
            return;
        }
    }
    batch_generic(k, m, n_el, lambda, out);
}

/// [`batch_generic`] compiled for AVX2 (4 lanes); the same IEEE operations in the same
/// order, so bit-identical results.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn batch_avx2(k: &[f64], m: &[f64], n_el: usize, lambda: f64, out: &mut [ChainEval]) {
    batch_generic(k, m, n_el, lambda, out);
}

/// Chains per block of the batched evaluations (fixed-size lanes: no per-call clearing of
/// large scratch arrays, loops of constant trip count that vectorize).
const LANES: usize = 8;

#[inline(always)]
fn batch_generic(k: &[f64], m: &[f64], n_el: usize, lambda: f64, out: &mut [ChainEval]) {
    let n = k.len().min(m.len()).min(out.len());
    let mut start = 0;
    while start < n {
        let len = (n - start).min(LANES);
        // Padding lanes: a massless chain (δ = 0), never written out.
        let mut kk = [1.0f64; LANES];
        let mut mm = [0.0f64; LANES];
        kk[..len].copy_from_slice(&k[start..start + len]);
        mm[..len].copy_from_slice(&m[start..start + len]);
        let mut two_delta = [0.0f64; LANES];
        let mut u = [1.0f64; LANES];
        let mut dl = [1.0f64; LANES];
        let mut up = [0.0f64; LANES];
        let mut dp = [0.0f64; LANES];
        let mut below = [0u64; LANES];
        for i in 0..LANES {
            let kp = kk[i] + lambda * mm[i] / 6.0;
            two_delta[i] = lambda * mm[i] / kp;
        }
        for _ in 0..n_el.saturating_sub(1) {
            for i in 0..LANES {
                let t = two_delta[i];
                let dpn = dp[i] - 2.0 * u[i] - t * up[i];
                let dn = dl[i] - t * u[i];
                let un = u[i] + dn;
                up[i] += dpn;
                dp[i] = dpn;
                below[i] += (un.to_bits() ^ u[i].to_bits()) >> 63;
                dl[i] = dn;
                u[i] = un;
            }
        }
        for i in 0..len {
            let (ki, mi) = (kk[i], mm[i]);
            let kp = ki + lambda * mi / 6.0;
            let ratio = dl[i] / u[i];
            let dratio = (dp[i] * u[i] - dl[i] * up[i]) / (u[i] * u[i]);
            let ddelta = 0.5 * mi * ki / (kp * kp);
            out[start + i] = ChainEval {
                s: -0.5 * lambda * mi + kp * ratio,
                ds: -0.5 * mi + mi / 6.0 * ratio + kp * dratio * ddelta,
                below: below[i] as u32,
            };
        }
        start += len;
    }
}

/// Pivot recurrence of the uniform chain (interior diagonal 2α, off-diagonal β):
/// p₁ = 2α, p_j = 2α − β²/p_{j−1}; s = α − β²/p_{N−1}; negative pivots = blocked count.
/// O(N); the reference for the closed form and the fallback at its singular points.
pub fn eval_discrete_recurrence(k: f64, m: f64, n_el: usize, lambda: f64) -> ChainEval {
    let alpha = k - lambda * m / 3.0;
    let dalpha = -m / 3.0;
    if n_el <= 1 {
        return ChainEval {
            s: alpha,
            ds: dalpha,
            below: 0,
        };
    }
    let beta = -k - lambda * m / 6.0;
    let dbeta = -m / 6.0;
    let b2 = beta * beta;
    let db2 = 2.0 * beta * dbeta;
    let tiny = f64::EPSILON * k.abs().max(1e-300);
    let mut p = 2.0 * alpha;
    let mut dp = 2.0 * dalpha;
    let mut below = 0u32;
    for _ in 1..n_el - 1 {
        if p == 0.0 {
            p = tiny;
        }
        below += (p < 0.0) as u32;
        let inv = 1.0 / p;
        let t = b2 * inv;
        let dt = (db2 - t * dp) * inv;
        p = 2.0 * alpha - t;
        dp = 2.0 * dalpha - dt;
    }
    if p == 0.0 {
        p = tiny;
    }
    below += (p < 0.0) as u32;
    let inv = 1.0 / p;
    let t = b2 * inv;
    let dt = (db2 - t * dp) * inv;
    ChainEval {
        s: alpha - t,
        ds: dalpha - dt,
        below,
    }
}

/// sin r − r and cos r − 1 for |r| ≤ π/4 + 1e-9 (fdlibm's kernel polynomials, error
/// < 1 ulp of sin r and cos r; the differences without cancellation).
#[inline(always)]
#[allow(clippy::excessive_precision)] // fdlibm's coefficients as published
fn sin_cos_kernel(r: f64) -> (f64, f64) {
    const S1: f64 = -1.666_666_666_666_663_243_48e-1;
    const S2: f64 = 8.333_333_333_322_489_461_24e-3;
    const S3: f64 = -1.984_126_982_985_794_931_34e-4;
    const S4: f64 = 2.755_731_370_707_006_767_89e-6;
    const S5: f64 = -2.505_076_025_340_686_341_95e-8;
    const S6: f64 = 1.589_690_995_211_550_102_21e-10;
    const C1: f64 = 4.166_666_666_666_660_190_37e-2;
    const C2: f64 = -1.388_888_888_887_410_957_49e-3;
    const C3: f64 = 2.480_158_728_947_672_941_78e-5;
    const C4: f64 = -2.755_731_435_139_066_330_35e-7;
    const C5: f64 = 2.087_572_321_298_174_827_90e-9;
    const C6: f64 = -1.135_964_755_778_819_482_65e-11;
    let z = r * r;
    let ps = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
    let pc = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    (r * z * (S1 + z * ps), z * pc - 0.5 * z)
}

/// [`Chain::eval`] of several continuous chains (K, m per chain: `k`, `m`, N/m and kg) at
/// one λ: one square root of λ, and cot φ from a Cody-Waite reduction by π/2 (two parts;
/// φ ≤ 1e5 here) and fdlibm's polynomial kernels instead of a library sin/cos per chain,
/// branch-free so that it vectorizes (an AVX2 build is chosen at run time: the same
/// operations, so the same results). Agrees with the scalar form within its conditioning
/// (tested). Chains outside 1e-3 ≤ φ ≤ 1e5, or with K or m ≤ 0, and λ ≤ 0 take the scalar
/// form.
pub fn eval_continuous_batch(k: &[f64], m: &[f64], lambda: f64, out: &mut [ChainEval]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            unsafe { continuous_avx2(k, m, lambda, out) };
            return;
        }
    }
    continuous_generic(k, m, lambda, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn continuous_avx2(k: &[f64], m: &[f64], lambda: f64, out: &mut [ChainEval]) {
    continuous_generic(k, m, lambda, out);
}

#[inline(always)]
fn continuous_generic(k: &[f64], m: &[f64], lambda: f64, out: &mut [ChainEval]) {
    let n = k.len().min(m.len()).min(out.len());
    if !(lambda > 0.0) {
        for i in 0..n {
            out[i] = eval_continuous(k[i], m[i], lambda);
        }
        return;
    }
    let sl = lambda.sqrt();
    let mut start = 0;
    while start < n {
        let len = (n - start).min(LANES);
        continuous_block(
            &k[start..start + len],
            &m[start..start + len],
            lambda,
            sl,
            &mut out[start..start + len],
        );
        start += len;
    }
}

/// Up to [`LANES`] continuous chains at λ > 0 (`sl` = √λ).
#[inline(always)]
#[allow(clippy::excessive_precision)] // fdlibm's constants as published
fn continuous_block(k: &[f64], m: &[f64], lambda: f64, sl: f64, out: &mut [ChainEval]) {
    const PIO2_1: f64 = 1.570_796_326_734_125_614_17; // first 33 bits of π/2
    const PIO2_1T: f64 = 6.077_100_506_506_192_249_32e-11; // π/2 − PIO2_1
    let len = k.len().min(LANES);
    // Padding lanes: K = m = 1 (φ = √λ), never written out.
    let mut kk = [1.0f64; LANES];
    let mut mm = [1.0f64; LANES];
    kk[..len].copy_from_slice(&k[..len]);
    mm[..len].copy_from_slice(&m[..len]);
    let mut s = [0.0f64; LANES];
    let mut ds = [0.0f64; LANES];
    let mut below = [0u32; LANES];
    let mut phis = [0.0f64; LANES];
    for i in 0..LANES {
        let (ki, mi) = (kk[i], mm[i]);
        let phi = sl * (mi / ki).sqrt();
        phis[i] = phi;
        // ceil(φ/π) − 1 by truncation (φ > 0; an exact multiple of π counts one less).
        let x = phi * std::f64::consts::FRAC_1_PI;
        let t = x as u32;
        below[i] = if t as f64 == x {
            t.saturating_sub(1)
        } else {
            t
        };
        let qi = (phi * std::f64::consts::FRAC_2_PI + 0.5) as i64;
        let q = qi as f64;
        let r = (phi - q * PIO2_1) - q * PIO2_1T;
        let (sm, cm) = sin_cos_kernel(r);
        let (sr, cr) = (r + sm, 1.0 + cm);
        // φ = qπ/2 + r: cot φ = cot r (q even) or −tan r (q odd); sin²φ likewise.
        let odd = qi & 1 == 1;
        let num = if odd { -sr } else { cr };
        let den = if odd { cr } else { sr };
        let s2 = den * den;
        let cot = num / den;
        s[i] = ki * phi * cot;
        // d(φ cot φ)/dφ = (sin φ cos φ − φ)/sin²φ; for q = 0 (φ = r) the numerator is
        // (sin φ − φ) cos φ + φ (cos φ − 1), two terms of one sign: no cancellation as φ → 0.
        let dnum = if qi == 0 {
            sm * cr + phi * cm
        } else {
            num * den - phi
        };
        ds[i] = dnum / s2 * (0.5 * mi / phi);
    }
    for i in 0..len {
        let ok = k[i] > 0.0 && m[i] > 0.0 && (1e-3..=1e5).contains(&phis[i]);
        out[i] = if ok {
            ChainEval {
                s: s[i],
                ds: ds[i],
                below: below[i],
            }
        } else {
            eval_continuous(k[i], m[i], lambda)
        };
    }
}

/// Fixed-free string/bar: s = K φ cot φ with φ = √(λ m / K) (K = S/L, m = μL).
#[inline]
fn eval_continuous(k: f64, m: f64, lambda: f64) -> ChainEval {
    if m <= 0.0 || lambda <= 0.0 {
        return ChainEval {
            s: k - lambda * m / 3.0,
            ds: -m / 3.0,
            below: 0,
        };
    }
    let phi2 = lambda * m / k;
    let phi = phi2.sqrt();
    let below = (phi / std::f64::consts::PI).ceil() as u32 - 1;
    if phi < 1e-3 {
        // φ cot φ = 1 − φ²/3 − φ⁴/45 − 2φ⁶/945
        let s = k * (1.0 - phi2 / 3.0 - phi2 * phi2 / 45.0 - 2.0 * phi2 * phi2 * phi2 / 945.0);
        let ds = m * (-1.0 / 3.0 - 2.0 * phi2 / 45.0 - 6.0 * phi2 * phi2 / 945.0);
        return ChainEval { s, ds, below };
    }
    let (sn, cs) = phi.sin_cos();
    let cot = cs / sn;
    let s = k * phi * cot;
    // d(φ cot φ)/dφ = cot φ − φ / sin² φ ; dφ/dλ = φ / (2λ) = m / (2 k φ)
    let dfdphi = cot - phi / (sn * sn);
    let ds = k * dfdphi * m / (2.0 * k * phi);
    ChainEval { s, ds, below }
}

/// The model of one cable at one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CableModel {
    /// Element stiffness block K_c, N/m (global frame). For continuous and massless models,
    /// the block of the whole cable (N = 1).
    pub kc: Matrix3<f64>,
    /// Element mass μ l, kg (0 for massless cables).
    pub element_mass_kg: f64,
    /// Number of elements (1 for continuous and massless models).
    pub n_el: usize,
    /// Up to 3 chains.
    pub chains: [Chain; 3],
    /// Number of valid chains.
    pub n_chains: usize,
    /// Static end stiffness of this cable on the end-effector, N/m.
    pub static_stiffness: Matrix3<f64>,
}

impl CableModel {
    /// Build the model of a cable with unit vector `e` (anchor → end-effector), length
    /// `length_m`, tension `tension_n`, axial rigidity `ea_n`, mass per length `mu_kg_m`,
    /// weight per length `gamma_n_m` (sag), model `kind` with `n` elements. `frame` is
    /// [`up_frame`] of the scene's gravity. `geometric` = false drops T/l (FEM, massless).
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        kind: ElementKind,
        n: usize,
        e: &Vector3<f64>,
        length_m: f64,
        tension_n: f64,
        ea_n: f64,
        mu_kg_m: f64,
        gamma_n_m: f64,
        frame: &Matrix3<f64>,
        geometric: bool,
    ) -> Result<CableModel, CableError> {
        if !(tension_n.is_finite() && tension_n > 0.0) {
            return Err(CableError::BadTension(tension_n));
        }
        let eet = e * e.transpose();
        let perp = Matrix3::identity() - eet;
        let t_geo = if geometric { tension_n } else { 0.0 };
        let zero_chain = Chain {
            kind: ChainKind::Discrete {
                k: 0.0,
                m: 0.0,
                n_el: 1,
            },
            mult: 0,
            proj: Matrix3::zeros(),
        };
        let mut chains = [zero_chain; 3];
        let (kc, me, nel, nch) = match kind {
            ElementKind::Fem | ElementKind::Massless => {
                let (nel, me) = if kind == ElementKind::Fem {
                    (n.max(1), mu_kg_m * length_m / n.max(1) as f64)
                } else {
                    (1, 0.0)
                };
                let l = length_m / nel as f64;
                chains[0] = Chain {
                    kind: ChainKind::Discrete {
                        k: ea_n / l,
                        m: me,
                        n_el: nel,
                    },
                    mult: 1,
                    proj: eet,
                };
                chains[1] = Chain {
                    kind: ChainKind::Discrete {
                        k: t_geo / l,
                        m: me,
                        n_el: nel,
                    },
                    mult: 2,
                    proj: perp,
                };
                (fem_block(e, l, ea_n, tension_n, geometric), me, nel, 2)
            }
            ElementKind::Continuous => {
                let mt = mu_kg_m * length_m;
                chains[0] = Chain {
                    kind: ChainKind::Continuous {
                        k_total: ea_n / length_m,
                        m_total: mt,
                    },
                    mult: 1,
                    proj: eet,
                };
                chains[1] = Chain {
                    kind: ChainKind::Continuous {
                        k_total: t_geo / length_m,
                        m_total: mt,
                    },
                    mult: 2,
                    proj: perp,
                };
                (fem_block(e, length_m, ea_n, tension_n, geometric), mt, 1, 2)
            }
            ElementKind::Auto => return Err(CableError::Unresolved),
            ElementKind::Catenary => {
                let nel = n.max(1);
                let l = length_m / nel as f64;
                // Chord from node I (anchor side) to node J: along e.
                let (kr, vr) = catenary_modes(&(e * l), tension_n, ea_n, gamma_n_m, frame)?;
                let me = mu_kg_m * l;
                let mut kc = Matrix3::zeros();
                for r in 0..3 {
                    kc += vr[r] * vr[r].transpose() * kr[r];
                    chains[r] = Chain {
                        kind: ChainKind::Discrete {
                            k: kr[r],
                            m: me,
                            n_el: nel,
                        },
                        mult: 1,
                        proj: vr[r] * vr[r].transpose(),
                    };
                }
                (kc, me, nel, 3)
            }
        };
        let mut model = CableModel {
            kc,
            element_mass_kg: me,
            n_el: nel,
            chains,
            n_chains: nch,
            static_stiffness: Matrix3::zeros(),
        };
        let mut ks = Matrix3::zeros();
        for c in &model.chains[..nch] {
            ks += c.proj * c.eval(0.0).s;
        }
        model.static_stiffness = ks;
        Ok(model)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn continuous_batch_matches_the_library_sin_cos() {
        // φ from 1e-3 to ~60 (a dozen harmonics), chains of different K/m, against the
        // scalar form (library sin_cos). Tolerance: 1e-13 relative plus the conditioning of
        // s and s' in φ (near a pole both move by ~2φ/|sin φ| ulp when φ moves by one, and
        // the two forms round φ differently); the blocked counts must be equal everywhere.
        let ks = [2.0e3, 5.0e5, 75.0, 1.0e4];
        let ms = [0.25, 0.4, 0.01, 1.0];
        let mut out = [ChainEval {
            s: 0.0,
            ds: 0.0,
            below: 0,
        }; 4];
        let mut worst: f64 = 0.0;
        for step in 0..20000 {
            let lambda = 10f64.powf(-1.0 + 8.0 * step as f64 / 20000.0);
            eval_continuous_batch(&ks, &ms, lambda, &mut out);
            for i in 0..4 {
                let r = eval_continuous(ks[i], ms[i], lambda);
                let b = out[i];
                assert_eq!(b.below, r.below, "λ {lambda} chain {i}");
                let phi = (lambda * ms[i] / ks[i]).sqrt();
                let sn = phi.sin().abs();
                // s and s' near a pole are as sensitive to φ's last bit as ~2φ/|sin φ|.
                let cond = 1e-13 + 8.0 * f64::EPSILON * phi / sn;
                // The scalar form's s' cancels in cot φ − φ/sin²φ for small φ: its own error
                // is ~ε/φ² (the batch form does not cancel there).
                let cond_ds = cond + 8.0 * f64::EPSILON / (phi * phi);
                // s = Kφ cot φ: relative to its scale Kφ where cot φ passes through 0.
                let es = (b.s - r.s).abs() / r.s.abs().max(ks[i] * phi);
                let eds = (b.ds - r.ds).abs() / r.ds.abs().max(ms[i]);
                assert!(
                    es <= cond && eds <= cond_ds,
                    "λ {lambda} chain {i} φ {phi}: s {} vs {} ({es:.1e}), ds {} vs {} ({eds:.1e})",
                    b.s,
                    r.s,
                    b.ds,
                    r.ds
                );
                worst = worst.max(es / cond).max(eds / cond_ds);
            }
        }
        eprintln!("continuous batch vs library: worst difference / tolerance {worst:.2}");
    }

    #[test]
    fn catenary_tends_to_straight_cable() {
        // γ → 0: K = EA/L0 e eᵀ + T/(L0 (1 + T/EA)) (I − e eᵀ) (notes.md).
        let frame = up_frame(&Vector3::new(0.0, 0.0, -9.81));
        let e = Vector3::new(0.3, -0.5, 0.8).normalize();
        let (l0, t, ea) = (0.25, 120.0, 1.0e6);
        let exact = {
            let eet = e * e.transpose();
            eet * (ea / l0) + (Matrix3::identity() - eet) * (t / (l0 * (1.0 + t / ea)))
        };
        for gamma in [0.0, 1e-15, 1e-12, 1e-9] {
            let k = catenary_block(&(e * l0), t, ea, gamma, &frame).unwrap();
            let err = (k - exact).norm() / exact.norm();
            assert!(err < 1e-12 + gamma * 1e2, "gamma {gamma}: {err}");
        }
    }

    #[test]
    fn vertical_catenary_is_finite_both_ways() {
        let frame = up_frame(&Vector3::new(0.0, 0.0, -9.81));
        for dir in [1.0, -1.0] {
            let e = Vector3::new(0.0, 0.0, dir);
            let k = catenary_block(&(e * 0.5), 100.0, 1e6, 0.25, &frame).unwrap();
            assert!(k.iter().all(|v| v.is_finite()));
            assert!(k.cholesky().is_some());
            // No coupling between horizontal and vertical directions.
            assert!(k[(0, 2)].abs() < 1e-9 * k.norm() && k[(1, 2)].abs() < 1e-9 * k.norm());
        }
    }

    /// Compares two evaluators of the uniform chain on a λ grid up to 1.3 × the cut-off
    /// 12k/m, for three (k, m) pairs and the given element counts. s has absolute accuracy
    /// ~ε·N·k (cancellation α + βR), s' relative ε·N²·(pole factor). Returns the worst errors.
    fn compare_chain_evals(
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
    fn batch_equals_closed_form() {
        // Same grid and tolerances; above the cut-off U_j grows like 5^j.
        let batch = |k: f64, m: f64, n: usize, lambda: f64| {
            let mut out = [ChainEval {
                s: 0.0,
                ds: 0.0,
                below: 0,
            }];
            eval_discrete_batch(&[k], &[m], n, lambda, &mut out);
            out[0]
        };
        let ns = [2usize, 3, 5, 10, 20, 32, 40, 64];
        let w = compare_chain_evals(&ns, batch, eval_discrete);
        eprintln!("batch vs closed form: s {:.2e}, s' {:.2e}", w[0], w[1]);
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
}
