//! The frequency response at the end-effector: the receptance H(ω) = [K + iωC − ω²M]⁻¹
//! restricted to the end-effector's coordinates (3 × 3, or 6 × 6 for a rigid body,
//! translations first), m/N (rad/(N·m) in the rotational block).
//!
//! **Loss factor and Rayleigh damping, exactly.** Both damped dynamic stiffnesses are a
//! complex multiple of the undamped one at a complex λ, for the whole assembled problem:
//!
//! ```text
//!     (1 + iη)K − ω²M                = c (K − λM),   c = 1 + iη,    λ = ω²/c
//!     (1 + iωβ)K − (ω² − iωα)M       = c (K − λM),   c = 1 + iωβ,   λ = (ω² − iωα)/c
//! ```
//!
//! so condensing the cables onto the end-effector gives H(ω) = D(λ)⁻¹/c, with D the
//! structured solver's dynamic stiffness evaluated at the complex λ
//! ([`Solver::dynamic_stiffness_at`](super::Solver::dynamic_stiffness_at): the chain
//! recurrences instantiated for complex numbers, every model but the sagged continuous
//! chains). Undamped: H = D(ω²)⁻¹ (infinite on a natural frequency).
//!
//! **Modal damping** (ζ in every mode, no damping matrix): modal superposition over the
//! modes below a cut-off with the residual flexibility of the modes left out (static
//! correction), H(ω) = Σ_r φ_r φ_rᵀ/(λ_r − ω² + 2iζω_rω) + [D(0)⁻¹ − Σ_r φ_r φ_rᵀ/λ_r], with
//! φ_r the end-effector part of the mass-normalised shapes ([`ModalBasis`]). A left-out mode
//! r is taken quasi-statically and undamped: its relative error is ≈ ω²/λ_r + 2ζω/ω_r.
//!
//! Offline: allocates (the modal basis, the dense reference), never on the real-time path.

use super::engine::Condensed;
use super::ModalError;
use crate::input_file::message_number;
use crate::scene::Damping;
use nalgebra::{DMatrix, Matrix6, Vector6};
use num_complex::Complex64;

/// Most frequencies one response is computed at.
pub const MAX_FRF_POINTS: usize = 100_000;
/// Highest frequency of a response, Hz (1 THz). The receptance of every cable model falls
/// as 1/(ω² m) long before it (≈ 1e-28 m/N at 1 THz on the paper's robot); from ≈ 1e24 Hz
/// it underflows to 0 and from ≈ 1e30 Hz ω²M overflows, so that no answer would mean
/// anything there.
pub const MAX_FRF_HZ: f64 = 1e12;
/// Most modes a modal-damping basis holds.
pub const MAX_FRF_MODES: usize = 2000;

/// Errors of the frequency response.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrfError {
    /// The frequency range is not 0 ≤ from < to, finite.
    #[error(
        "frequency range {} .. {} Hz: need finite 0 <= from < to",
        message_number(*from_hz),
        message_number(*to_hz)
    )]
    Range {
        /// Lower end, Hz.
        from_hz: f64,
        /// Upper end, Hz.
        to_hz: f64,
    },
    /// The range ends above [`MAX_FRF_HZ`].
    #[error(
        "frequency range up to {} Hz: above the highest frequency of a response, {} Hz",
        message_number(*.0),
        message_number(MAX_FRF_HZ)
    )]
    TooHigh(f64),
    /// A log-spaced range must start above 0.
    #[error("a log-spaced range needs from > 0 Hz (got {0})")]
    LogFromZero(f64),
    /// The number of frequencies is 0 or above [`MAX_FRF_POINTS`].
    #[error("{0} frequencies: need 1 ..= {MAX_FRF_POINTS}")]
    Points(usize),
    /// Modal damping needs the modal basis ([`ModalBasis`]).
    #[error("modal damping goes by modal superposition: use ModalBasis::receptance")]
    NeedsModes,
    /// The modal basis could not be built.
    #[error("modal basis: {0}")]
    Modes(String),
    /// A modal problem error.
    #[error("{0}")]
    Modal(#[from] ModalError),
    /// The sagged continuous (Magnus) model has no complex form.
    #[error("the sagged continuous model has no damped (complex) form: the frequency response with sag takes the fem element")]
    SagContinuous,
}

/// The frequencies of a response: `points` values from `from_hz` to `to_hz` (both
/// included, exactly; one point: `from_hz`), evenly spaced, or geometrically with `log`
/// (evenly in ln f, so that no ratio of the bounds overflows: 1e-310 .. 1 Hz is a valid
/// range). `to_hz` is at most [`MAX_FRF_HZ`].
pub fn frequency_grid(
    from_hz: f64,
    to_hz: f64,
    points: usize,
    log: bool,
) -> Result<Vec<f64>, FrfError> {
    if !(from_hz.is_finite() && to_hz.is_finite() && from_hz >= 0.0 && from_hz < to_hz) {
        return Err(FrfError::Range { from_hz, to_hz });
    }
    if to_hz > MAX_FRF_HZ {
        return Err(FrfError::TooHigh(to_hz));
    }
    if points == 0 || points > MAX_FRF_POINTS {
        return Err(FrfError::Points(points));
    }
    if log && !(from_hz > 0.0) {
        return Err(FrfError::LogFromZero(from_hz));
    }
    let step = |i: usize| i as f64 / (points - 1).max(1) as f64;
    let (ln_from, ln_to) = (from_hz.ln(), to_hz.ln());
    Ok((0..points)
        .map(|i| {
            if i == 0 {
                from_hz
            } else if i == points - 1 {
                to_hz
            } else if log {
                (ln_from + (ln_to - ln_from) * step(i)).exp()
            } else {
                from_hz + (to_hz - from_hz) * step(i)
            }
        })
        .collect())
}

/// (c, λ) of the exact damped forms at ω (rad/s): the damped dynamic stiffness is
/// c·(K − λM). None for modal damping (no damping matrix).
pub fn complex_shift(damping: &Damping, omega_rad_s: f64) -> Option<(Complex64, Complex64)> {
    let w2 = omega_rad_s * omega_rad_s;
    match *damping {
        Damping::None => Some((Complex64::new(1.0, 0.0), Complex64::new(w2, 0.0))),
        Damping::LossFactor { eta } => {
            let c = Complex64::new(1.0, eta);
            Some((c, Complex64::new(w2, 0.0) / c))
        }
        Damping::Rayleigh {
            alpha_per_s,
            beta_s,
        } => {
            let c = Complex64::new(1.0, omega_rad_s * beta_s);
            Some((c, Complex64::new(w2, -omega_rad_s * alpha_per_s) / c))
        }
        Damping::ModalRatio { .. } => None,
    }
}

/// Inverse of the leading `dim` × `dim` block of `d` (3 or 6), embedded in a 6 × 6 (zeros
/// elsewhere); NaN entries when it is singular (a natural frequency of an undamped model).
pub(in crate::modal) fn inverse_block(d: &Matrix6<Complex64>, dim: usize) -> Matrix6<Complex64> {
    let nan = Complex64::new(f64::NAN, f64::NAN);
    let mut out = Matrix6::from_element(Complex64::new(0.0, 0.0));
    if dim == 3 {
        let b = d.fixed_view::<3, 3>(0, 0).into_owned();
        match b.try_inverse() {
            Some(inv) => out.fixed_view_mut::<3, 3>(0, 0).copy_from(&inv),
            None => out.fixed_view_mut::<3, 3>(0, 0).fill(nan),
        }
    } else {
        match d.try_inverse() {
            Some(inv) => out = inv,
            None => out.fill(nan),
        }
    }
    out
}

/// The receptance H(ω) of the loaded problem `p` at ω (rad/s) with loss-factor, Rayleigh or
/// no damping (exact, see the module docs): m/N, the leading `dim` × `dim` block. Undamped
/// from one (counted) real evaluation, damped from D at the complex λ. Modal damping:
/// [`FrfError::NeedsModes`] (see [`ModalBasis`]); a problem without a complex form:
/// [`FrfError::SagContinuous`].
pub(in crate::modal) fn receptance<P: Condensed>(
    p: &mut P,
    damping: &Damping,
    omega_rad_s: f64,
) -> Result<Matrix6<Complex64>, FrfError> {
    let (c, lambda) = complex_shift(damping, omega_rad_s).ok_or(FrfError::NeedsModes)?;
    if !p.is_loaded() {
        return Err(FrfError::Modal(ModalError::NotLoaded));
    }
    let d = if damping.is_none() {
        p.eval(lambda.re).d.map(|x| Complex64::new(x, 0.0))
    } else {
        p.d_complex(lambda).ok_or(FrfError::SagContinuous)?
    };
    Ok(inverse_block(&d, p.dim()) / c)
}

/// The end-effector part of a pose's lowest modes, for modal damping: natural frequencies,
/// mass-normalised end-effector shapes and the residual flexibility of the modes left out.
#[derive(Debug, Clone)]
pub struct ModalBasis {
    /// λ_r = ω_r², rad²/s², ascending.
    pub lambda: Vec<f64>,
    /// φ_r at the end-effector (1/√kg; rotation rad/(m·√kg) for a rigid body).
    pub ee: Vec<Vector6<f64>>,
    /// D(0)⁻¹ − Σ_r φ_r φ_rᵀ/λ_r, m/N: the static flexibility of the modes left out.
    pub residual: Matrix6<f64>,
    /// 3 or 6.
    pub dim: usize,
}

impl ModalBasis {
    /// A basis from given modes: λ_r (rad²/s², > 0), the end-effector parts φ_r of their
    /// mass-normalised shapes and the static flexibility D(0)⁻¹ (its `dim` block, m/N), the
    /// residual D(0)⁻¹ − Σ_r φ_r φ_rᵀ/λ_r. For any engine's shapes (the structured
    /// solver's, [`Solver::modal_basis`](super::Solver::modal_basis), or the dense model's).
    pub fn from_modes(
        lambda: Vec<f64>,
        ee: Vec<Vector6<f64>>,
        flexibility: &Matrix6<f64>,
        dim: usize,
    ) -> Result<ModalBasis, FrfError> {
        if lambda.len() != ee.len() || lambda.len() > MAX_FRF_MODES {
            return Err(FrfError::Modes(format!(
                "{} eigenvalues and {} shapes (at most {MAX_FRF_MODES})",
                lambda.len(),
                ee.len()
            )));
        }
        if !(flexibility.iter().all(|x| x.is_finite())
            && lambda.iter().all(|l| l.is_finite() && *l > 0.0))
        {
            return Err(FrfError::Modes(
                "eigenvalues must be finite and > 0, the flexibility finite".into(),
            ));
        }
        let mut residual = *flexibility;
        for (l, phi) in lambda.iter().zip(&ee) {
            residual -= phi * phi.transpose() / *l;
        }
        Ok(ModalBasis {
            lambda,
            ee,
            residual,
            dim,
        })
    }

    /// H(ω) with the damping ratio ζ in every mode of the basis, m/N.
    pub fn receptance(&self, zeta: f64, omega_rad_s: f64) -> Matrix6<Complex64> {
        let mut h = self.residual.map(|x| Complex64::new(x, 0.0));
        let w = omega_rad_s;
        for (l, phi) in self.lambda.iter().zip(&self.ee) {
            let wr = l.max(0.0).sqrt();
            let den = Complex64::new(l - w * w, 2.0 * zeta * wr * w);
            let outer = phi * phi.transpose();
            h += outer.map(|x| Complex64::new(x, 0.0) / den);
        }
        h
    }
}

/// The dense reference: H(ω) from one complex LU solve of the assembled c(K − λM) (the
/// first `dim` DOF are the end-effector's), for loss-factor, Rayleigh or no damping. O(n³)
/// per frequency; NaN entries when the matrix is singular.
pub fn dense_receptance(
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    dim: usize,
    damping: &Damping,
    omega_rad_s: f64,
) -> Result<Matrix6<Complex64>, FrfError> {
    let w = omega_rad_s;
    let n = k.nrows();
    let mut a = DMatrix::<Complex64>::zeros(n, n);
    let (ck, cm) = match *damping {
        Damping::None => (Complex64::new(1.0, 0.0), Complex64::new(w * w, 0.0)),
        Damping::LossFactor { eta } => (Complex64::new(1.0, eta), Complex64::new(w * w, 0.0)),
        Damping::Rayleigh {
            alpha_per_s,
            beta_s,
        } => (
            Complex64::new(1.0, w * beta_s),
            Complex64::new(w * w, -w * alpha_per_s),
        ),
        Damping::ModalRatio { .. } => return Err(FrfError::NeedsModes),
    };
    for j in 0..n {
        for i in 0..n {
            a[(i, j)] = ck * k[(i, j)] - cm * m[(i, j)];
        }
    }
    let mut rhs = DMatrix::<Complex64>::zeros(n, dim);
    for i in 0..dim {
        rhs[(i, i)] = Complex64::new(1.0, 0.0);
    }
    let mut out = Matrix6::from_element(Complex64::new(0.0, 0.0));
    match a.lu().solve(&rhs) {
        Some(x) => {
            for i in 0..dim {
                for j in 0..dim {
                    out[(i, j)] = x[(i, j)];
                }
            }
        }
        None => out.fill(Complex64::new(f64::NAN, f64::NAN)),
    }
    Ok(out)
}
