//! The end-effector's time response to a force on it, by modal superposition of the first
//! K modes with the static correction of the rest (the mode-acceleration method).
//!
//! With the mass-normalised modes (λ_j = ω_j², end-effector part φ_j of dimension 3 or 6)
//! and the viscous ratio ζ_j of each, a force f(t) on the end-effector drives the modal
//! coordinates q̈_j + 2ζ_jω_j q̇_j + ω_j² q_j = φ_jᵀ f, and the end-effector moves
//!
//! ```text
//!     u(t) = Σ_{j≤K} φ_j q_j(t) + (F − Σ_{j≤K} φ_j φ_jᵀ/λ_j) f(t)
//!          = F f(t) + Σ_{j≤K} φ_j (q_j(t) − φ_jᵀ f(t)/λ_j)
//! ```
//!
//! F = D(0)⁻¹ the static flexibility of the end-effector: the modes left out answer
//! quasi-statically (their frequencies far above the load's), so the error falls with K
//! much faster than plain truncation's. The second form is the quasi-static answer plus the
//! kept modes' dynamic parts; [`ModalResponse::displacement_with`] takes F from the caller
//! (a flexibility interpolated between two poses while the modes are held).
//!
//! **Every damping regime exactly.** Each step integrates the modal equations exactly for a
//! force linear between the two samples (first-order hold): with the ramp's particular
//! solution q_p(τ) = (g₀ + bτ)/ω² − 2ζb/ω³, the departure e = q − q_p is free and moves by
//! the transition matrix of [q, q̇]' = A [q, q̇], A = [0 1; −ω² −2σ], σ = ζω:
//!
//! ```text
//!     e^{Ah} = E·I + S·(A + σI),   E = e^{−σh} c(h),  S = e^{−σh} s(h),
//!     ζ < 1 (ω_d = ω√(1−ζ²)):  c = cos ω_d h,  s = sin(ω_d h)/ω_d
//!     ζ = 1:                   c = 1,          s = h
//!     ζ > 1 (μ = ω√(ζ²−1)):    c = cosh μh,    s = sinh(μh)/μ
//! ```
//!
//! The overdamped case is evaluated on its two real poles r₁ = −ω²/(σ+μ) (slow, free of
//! cancellation) and r₂ = −(σ+μ): S = (e^{r₁h} − e^{r₂h})/(2μ) (by `expm1` when 2μh ≤ 1),
//! E = e^{r₂h} + μS, so nothing overflows for the stiffest mode and ζ → 1 from either
//! side meets the critical formula. The 2 × 2 matrix of each mode is computed once per
//! basis and step (the propagator), so a step costs O(K·dim). A step or ramp load is
//! reproduced to rounding whatever the step; no ζ ≥ 0 is refused.
//!
//! **A load on the whole robot.** The force f may stand for a load on every node: with
//! load shapes ψ_j ([`ModalResponse::set_load_shapes`]) mode j's force is ψ_jᵀ f and the
//! quasi-static answer F_ψ f, so u = F_ψ f + Σ φ_j (q_j − ψ_jᵀf/λ_j) (the cables' inertia
//! under f = −M_ee a, the modal `quasi_static` module); by default ψ_j = φ_j and F_ψ = F.
//!
//! [`ModalResponse::set_basis`] changes the modes (the pose moved): the end-effector's
//! dynamic displacement and velocity are carried across, projected on the new modes.
//! Nothing allocates after [`ModalResponse::new`].

use crate::scene::Damping;
use nalgebra::{Matrix6, Vector6};

/// Most modes a [`ModalResponse`] carries.
pub const MAX_RESPONSE_MODES: usize = 256;

/// Why a modal basis is refused.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ResponseError {
    /// A mode's λ is not finite and positive.
    #[error("mode {0}: λ = {1:e} rad²/s² must be finite and > 0")]
    BadLambda(usize, f64),
    /// A mode's damping ratio is not finite and ≥ 0.
    #[error(
        "mode {index} at {frequency_hz:.4} Hz: damping ratio {zeta:.4} must be finite and ≥ 0"
    )]
    BadDamping {
        /// Mode index (from 0).
        index: usize,
        /// Its frequency, Hz.
        frequency_hz: f64,
        /// Its ratio.
        zeta: f64,
    },
    /// Too many modes, or a size mismatch.
    #[error("modal basis: {0}")]
    Size(&'static str),
    /// The static flexibility is not finite.
    #[error(
        "the end-effector's static flexibility is not finite (the static stiffness is singular)"
    )]
    Flexibility,
}

/// One mode of the basis and its step coefficients.
#[derive(Debug, Clone, Copy, Default)]
struct ModeCoef {
    lambda: f64,
    omega: f64,
    zeta: f64,
    phi: Vector6<f64>,
    /// The load shape ψ: the mode's force under the force f is ψᵀf (φ, unless
    /// [`ModalResponse::set_load_shapes`] gave another).
    load: Vector6<f64>,
    /// +1, or −1 when the basis's shape was installed with its sign flipped.
    sign: f64,
    /// The transition matrix e^{Ah} of the free mode (module docs) for the step `h`,
    /// row-major.
    prop: [f64; 4],
    h: f64,
    /// 1/λ and 2ζ/(λω), s² and s³ (the particular solution's coefficients).
    inv_lambda: f64,
    shift_per_rate: f64,
}

/// The modal superposition's state and basis.
#[derive(Debug, Clone)]
pub struct ModalResponse {
    dim: usize,
    n: usize,
    modes: Vec<ModeCoef>,
    q: Vec<f64>,
    v: Vec<f64>,
    /// F − Σ φφᵀ/λ over the modes kept.
    residual_flexibility: Matrix6<f64>,
    /// The force at the end of the last step (N, N·m).
    force: Vector6<f64>,
}

impl ModalResponse {
    /// An empty response of end-effector dimension `dim` (3 or 6), at rest.
    pub fn new(dim: usize) -> ModalResponse {
        ModalResponse {
            dim,
            n: 0,
            modes: vec![ModeCoef::default(); MAX_RESPONSE_MODES],
            q: vec![0.0; MAX_RESPONSE_MODES],
            v: vec![0.0; MAX_RESPONSE_MODES],
            residual_flexibility: Matrix6::zeros(),
            force: Vector6::zeros(),
        }
    }

    /// Modes in the basis.
    pub fn modes(&self) -> usize {
        self.n
    }

    /// Set the basis: `lambda[j]` (rad²/s²) and `phi_ee[j]` (the mass-normalised shape's
    /// end-effector part, first `dim` entries), the ratio of each from `damping`, and the
    /// end-effector's static flexibility `flexibility` (D(0)⁻¹, its `dim` block).
    ///
    /// The state carried across is the end-effector's: its dynamic displacement
    /// u_d = Σ φ_i (q_i − φ_iᵀf/λ_i) (the departure from the quasi-static answer to the
    /// force f of the last step) and its velocity Σ φ_i q̇_i are projected on the new modes
    /// with the end-effector's mass `ee_mass` (q_j = φ_jᵀf/λ_j + φ_jᵀ M_ee u_d, exact for
    /// a mode whose participation is 1, close for the end-effector modes, whose
    /// participation is near it). So a change of frequencies, an exchange of order (modes
    /// crossing) or a rotation inside a near-degenerate cluster does not excite the modes;
    /// what is lost is the motion of the cables' own modes that the end-effector does not
    /// see. Allocation-free.
    pub fn set_basis(
        &mut self,
        lambda: &[f64],
        phi_ee: &[Vector6<f64>],
        damping: &Damping,
        flexibility: &Matrix6<f64>,
        ee_mass: &Matrix6<f64>,
    ) -> Result<(), ResponseError> {
        check_basis(lambda, phi_ee, damping, flexibility)?;
        let f = self.force;
        // The end-effector's dynamic displacement and velocity of the old basis.
        let mut u_dyn = Vector6::zeros();
        let mut v_ee = Vector6::zeros();
        for i in 0..self.n {
            let m = &self.modes[i];
            u_dyn += m.phi * (self.q[i] - m.load.dot(&f) / m.lambda);
            v_ee += m.phi * self.v[i];
        }
        let mu = ee_mass * u_dyn;
        let mv = ee_mass * v_ee;
        let old_n = self.n;
        self.install(lambda, phi_ee, damping, flexibility, |j, phi, old| {
            if j < old_n && phi.dot(&old[j].phi) < 0.0 {
                *phi = -*phi; // the sign of the same index kept, for continuity of output
            }
            (phi.dot(&mu), phi.dot(&mv))
        });
        Ok(())
    }

    /// [`Self::set_basis`] carrying the whole modal state: the new modal coordinates are
    /// the M-projection of the old modes' motion, q_j = φ_jᵀf/λ_j + Σ_i O_ji d_i and
    /// q̇_j = Σ_i O_ji q̇_i, with d_i = q_i − φ_iᵀf/λ_i the old modes' departure from the
    /// quasi-static answer and O_ji = φ_jᵀ M φ'_i the mass overlap of new mode j with old
    /// mode i over the whole robot (`overlap`, row-major, new × old,
    /// [`crate::modal::ModeShapes::mass_overlap`]). Unlike the end-effector projection, it
    /// keeps the motion of modes the end-effector takes a small part in (the cable-borne
    /// modes of a sagging robot): across a small change of pose O is close to a
    /// permutation with signs, and what is lost is only the old motion outside the new K
    /// modes. Allocation-free.
    pub fn set_basis_projected(
        &mut self,
        lambda: &[f64],
        phi_ee: &[Vector6<f64>],
        damping: &Damping,
        flexibility: &Matrix6<f64>,
        overlap: &[f64],
    ) -> Result<(), ResponseError> {
        check_basis(lambda, phi_ee, damping, flexibility)?;
        let old_n = self.n;
        if overlap.len() != lambda.len() * old_n {
            return Err(ResponseError::Size("the overlap is new modes × old modes"));
        }
        let f = self.force;
        let mut d = [0.0; MAX_RESPONSE_MODES];
        let mut v = [0.0; MAX_RESPONSE_MODES];
        for i in 0..old_n {
            let m = &self.modes[i];
            d[i] = self.q[i] - m.load.dot(&f) / m.lambda;
            v[i] = self.v[i];
        }
        self.install(lambda, phi_ee, damping, flexibility, |j, _, _| {
            let row = &overlap[j * old_n..(j + 1) * old_n];
            let dynamic = row.iter().zip(&d[..old_n]).map(|(o, x)| o * x).sum();
            let vel = row.iter().zip(&v[..old_n]).map(|(o, x)| o * x).sum();
            (dynamic, vel)
        });
        Ok(())
    }

    /// Install the new basis (checked): mode j's shape (its end-effector part, zeroed
    /// beyond `dim`) and its carried dynamic displacement and velocity from
    /// `carry(j, &mut phi, old modes)` (which may flip phi's sign).
    fn install(
        &mut self,
        lambda: &[f64],
        phi_ee: &[Vector6<f64>],
        damping: &Damping,
        flexibility: &Matrix6<f64>,
        mut carry: impl FnMut(usize, &mut Vector6<f64>, &[ModeCoef]) -> (f64, f64),
    ) {
        let f = self.force;
        let mut rf = *flexibility;
        for j in 0..lambda.len() {
            let mut phi = phi_ee[j];
            for r in self.dim..6 {
                phi[r] = 0.0;
            }
            let before = phi;
            let (dynamic, vel) = carry(j, &mut phi, &self.modes);
            let sign = if phi == before { 1.0 } else { -1.0 };
            let l = lambda[j];
            self.q[j] = phi.dot(&f) / l + dynamic;
            self.v[j] = vel;
            let omega = l.sqrt();
            self.modes[j] = ModeCoef {
                lambda: l,
                omega,
                zeta: damping.modal_ratio(omega),
                phi,
                load: phi,
                sign,
                prop: [0.0; 4],
                h: f64::NAN,
                inv_lambda: 0.0,
                shift_per_rate: 0.0,
            };
            rf -= phi * phi.transpose() / l;
        }
        for r in self.dim..6 {
            for c in 0..6 {
                rf[(r, c)] = 0.0;
                rf[(c, r)] = 0.0;
            }
        }
        self.residual_flexibility = rf;
        self.n = lambda.len();
    }

    /// Take each installed mode's force under the force f as ψ_jᵀ f with the load shapes
    /// `load` (one per mode of the basis just set, in its order; first `dim` entries) and
    /// the quasi-static answer as `load_flexibility` · f, the displacement staying
    /// Σ φ_j q_j: a force f that stands for a load on the whole robot
    /// (the modal `quasi_static` module: the cables' inertia under f = −M_ee a). Call it
    /// after [`Self::set_basis`] or [`Self::set_basis_projected`]; the modes' dynamic parts
    /// d_j = q_j − ψ_jᵀf/λ_j are kept. Until then (or with ψ = φ and F) the force acts on
    /// the end-effector alone. Allocation-free.
    pub fn set_load_shapes(
        &mut self,
        load: &[Vector6<f64>],
        load_flexibility: &Matrix6<f64>,
    ) -> Result<(), ResponseError> {
        if load.len() != self.n {
            return Err(ResponseError::Size("one load shape per mode of the basis"));
        }
        if !load_flexibility.iter().all(|x| x.is_finite())
            || !load.iter().all(|p| p.iter().all(|x| x.is_finite()))
        {
            return Err(ResponseError::Flexibility);
        }
        let f = self.force;
        let mut rf = *load_flexibility;
        for (j, l) in load.iter().enumerate() {
            let m = &mut self.modes[j];
            let mut psi = l * m.sign;
            for r in self.dim..6 {
                psi[r] = 0.0;
            }
            self.q[j] += (psi - m.load).dot(&f) / m.lambda;
            m.load = psi;
            rf -= m.phi * psi.transpose() / m.lambda;
        }
        for r in self.dim..6 {
            for c in 0..6 {
                rf[(r, c)] = 0.0;
                rf[(c, r)] = 0.0;
            }
        }
        self.residual_flexibility = rf;
        Ok(())
    }

    /// Advance by `h_s` (s, > 0) under a force going linearly from `f0` to `f1` (N, and
    /// N·m for a rigid body's moment). Exact for that force, in every damping regime.
    pub fn step(&mut self, f0: &Vector6<f64>, f1: &Vector6<f64>, h_s: f64) {
        self.force = *f1;
        let inv_h = 1.0 / h_s;
        for (m, (q, v)) in self.modes[..self.n]
            .iter_mut()
            .zip(self.q.iter_mut().zip(self.v.iter_mut()))
        {
            if m.h != h_s {
                m.prop = propagator(m.omega, m.zeta, h_s);
                m.h = h_s;
                m.inv_lambda = 1.0 / m.lambda;
                m.shift_per_rate = 2.0 * m.zeta / (m.lambda * m.omega);
            }
            let g0 = m.load.dot(f0);
            let g1 = m.load.dot(f1);
            let b = (g1 - g0) * inv_h;
            // particular solution q_p(τ) = (g0 + bτ)/ω² − 2ζb/ω³, q_p' = b/ω²
            let shift = m.shift_per_rate * b;
            let e0 = *q - (g0 * m.inv_lambda - shift);
            let de0 = *v - b * m.inv_lambda;
            let [p11, p12, p21, p22] = m.prop;
            *q = p11 * e0 + p12 * de0 + (g1 * m.inv_lambda - shift);
            *v = p21 * e0 + p22 * de0 + b * m.inv_lambda;
        }
    }

    /// The end-effector's displacement under the force `f` now (the force of the last
    /// [`Self::step`]'s end): Σ φ_j q_j + (F − Σ φ_jφ_jᵀ/λ_j) f.
    pub fn displacement(&self, f: &Vector6<f64>) -> Vector6<f64> {
        let mut u = self.residual_flexibility * f;
        for j in 0..self.n {
            u += self.modes[j].phi * self.q[j];
        }
        u
    }

    /// The end-effector's displacement under the force `f` now with the static flexibility
    /// `flexibility` in place of the basis's: F f + Σ φ_j (q_j − φ_jᵀf/λ_j) (the quasi-static
    /// answer of that flexibility plus the kept modes' dynamic parts; equal to
    /// [`Self::displacement`] when `flexibility` is the basis's F).
    pub fn displacement_with(&self, f: &Vector6<f64>, flexibility: &Matrix6<f64>) -> Vector6<f64> {
        let mut u = flexibility * f;
        for j in 0..self.n {
            let m = &self.modes[j];
            u += m.phi * (self.q[j] - m.load.dot(f) / m.lambda);
        }
        for r in self.dim..6 {
            u[r] = 0.0;
        }
        u
    }

    /// Mode `j`'s dynamic part of the end-effector's displacement under the force `f` now:
    /// φ_j (q_j − φ_jᵀf/λ_j) (what the mode adds to the quasi-static answer).
    pub fn dynamic_part(&self, j: usize, f: &Vector6<f64>) -> Vector6<f64> {
        let m = &self.modes[j];
        m.phi * (self.q[j] - m.load.dot(f) / m.lambda)
    }

    /// The end-effector's dynamic amplitude in each kept mode, m (rad for rotations):
    /// |φ_j| √(d_j² + (q̇_j/ω_j)²), d_j = q_j − φ_jᵀf/λ_j the departure from the
    /// quasi-static answer to the force `f` now, into `out` (its first [`Self::modes`]
    /// entries). What a change of the mode's frequency by δω puts out of phase at a rate
    /// δω per second.
    pub fn dynamic_amplitudes(&self, f: &Vector6<f64>, out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate().take(self.n) {
            let m = &self.modes[j];
            let d = self.q[j] - m.load.dot(f) / m.lambda;
            let w = self.v[j] / m.omega;
            *o = m.phi.norm() * (d * d + w * w).sqrt();
        }
    }

    /// Each kept mode's end-effector amplitude split into its free vibration and its forced
    /// part, m (rad for rotations), under the force `f` now ramping at `rate` (N/s, N·m/s):
    /// the ramp's particular solution has d_p = −2ζ b/(λω) and q̇_p = b/λ, b = ψᵀ rate
    /// (module docs), the free part is the rest of the mode's departure from the
    /// quasi-static answer, d − d_p and q̇ − q̇_p. Into `free` and `forced` (their first
    /// [`Self::modes`] entries): |φ_j| √(x² + (ẋ/ω_j)²) of each. A change of the mode's
    /// frequency puts the free part out of phase for as long as it rings, the forced part
    /// only in proportion (its amplitude follows the frequency).
    pub fn ringing_amplitudes(
        &self,
        f: &Vector6<f64>,
        rate: &Vector6<f64>,
        free: &mut [f64],
        forced: &mut [f64],
    ) {
        for (j, (a, b)) in free
            .iter_mut()
            .zip(forced.iter_mut())
            .enumerate()
            .take(self.n)
        {
            let m = &self.modes[j];
            let load_rate = m.load.dot(rate);
            let dp = -2.0 * m.zeta * load_rate / (m.lambda * m.omega);
            let vp = load_rate / m.lambda;
            let d = self.q[j] - m.load.dot(f) / m.lambda - dp;
            let v = self.v[j] - vp;
            let norm = m.phi.norm();
            *a = norm * (d * d + (v / m.omega).powi(2)).sqrt();
            *b = norm * (dp * dp + (vp / m.omega).powi(2)).sqrt();
        }
    }

    /// The basis's λ_j, rad²/s² (its first [`Self::modes`] entries are the modes').
    pub fn lambda(&self, j: usize) -> f64 {
        self.modes[j].lambda
    }

    /// The basis's end-effector shape part φ_j.
    pub fn phi(&self, j: usize) -> &Vector6<f64> {
        &self.modes[j].phi
    }

    /// The basis's load shape ψ_j ([`Self::set_load_shapes`]; φ_j by default).
    pub fn load_shape(&self, j: usize) -> &Vector6<f64> {
        &self.modes[j].load
    }

    /// The end-effector's acceleration under the force `f` now (the force of the last
    /// [`Self::step`]'s end) from the modal state: Σ φ_j q̈_j with q̈_j = φ_jᵀf − 2ζ_jω_j q̇_j −
    /// ω_j² q_j, the modal equations themselves (exact at the sample, whatever the step, and
    /// continuous across [`Self::set_basis`]). The static correction's share (F − Σ φφᵀ/λ) f̈
    /// is left out: it stands for modes above the K kept, which answer quasi-statically only
    /// to a smooth force; a force with content at their frequencies (white noise) would make
    /// its second derivative a spurious broadband acceleration.
    pub fn acceleration(&self, f: &Vector6<f64>) -> Vector6<f64> {
        let mut a = Vector6::zeros();
        for j in 0..self.n {
            let m = &self.modes[j];
            let qdd = m.load.dot(f) - 2.0 * m.zeta * m.omega * self.v[j] - m.lambda * self.q[j];
            a += m.phi * qdd;
        }
        a
    }

    /// Back to rest (no force).
    pub fn reset(&mut self) {
        self.force = Vector6::zeros();
        for j in 0..self.n {
            self.q[j] = 0.0;
            self.v[j] = 0.0;
        }
    }
}

/// The checks of a new basis: sizes, λ finite and > 0, every ratio finite and ≥ 0, the
/// flexibility finite.
fn check_basis(
    lambda: &[f64],
    phi_ee: &[Vector6<f64>],
    damping: &Damping,
    flexibility: &Matrix6<f64>,
) -> Result<(), ResponseError> {
    if lambda.len() != phi_ee.len() {
        return Err(ResponseError::Size("as many shapes as eigenvalues"));
    }
    if lambda.len() > MAX_RESPONSE_MODES {
        return Err(ResponseError::Size("more modes than MAX_RESPONSE_MODES"));
    }
    if !flexibility.iter().all(|x| x.is_finite()) {
        return Err(ResponseError::Flexibility);
    }
    for (j, &l) in lambda.iter().enumerate() {
        if !(l.is_finite() && l > 0.0) {
            return Err(ResponseError::BadLambda(j, l));
        }
        let omega = l.sqrt();
        let zeta = damping.modal_ratio(omega);
        if !(zeta.is_finite() && zeta >= 0.0) {
            return Err(ResponseError::BadDamping {
                index: j,
                frequency_hz: omega / (2.0 * std::f64::consts::PI),
                zeta,
            });
        }
    }
    Ok(())
}

/// The transition matrix e^{Ah} (row-major) of q̈ + 2ζω q̇ + ω² q = 0 over `h` (s), for
/// ω > 0 (rad/s) and any ζ ≥ 0 (module docs: E·I + S·(A + σI)).
pub fn propagator(omega: f64, zeta: f64, h: f64) -> [f64; 4] {
    let sigma = zeta * omega;
    let lambda = omega * omega;
    let (e, s) = if zeta < 1.0 {
        let wd = omega * ((1.0 - zeta) * (1.0 + zeta)).sqrt();
        let decay = (-sigma * h).exp();
        (decay * (wd * h).cos(), decay * (wd * h).sin() / wd)
    } else if zeta == 1.0 {
        let decay = (-sigma * h).exp();
        (decay, decay * h)
    } else {
        let mu = omega * ((zeta - 1.0) * (zeta + 1.0)).sqrt();
        let r1 = -lambda / (sigma + mu); // the slow pole μ − σ, without cancellation
        let r2 = -(sigma + mu);
        let (e1, e2) = ((r1 * h).exp(), (r2 * h).exp());
        let s = if 2.0 * mu * h <= 1.0 {
            e2 * (2.0 * mu * h).exp_m1() / (2.0 * mu)
        } else {
            (e1 - e2) / (2.0 * mu)
        };
        // E = e^{r2 h} + μS, so E ± σS = e^{r2 h} + (μ ± σ)S with μ − σ = r1.
        return [e2 + (mu + sigma) * s, s, -lambda * s, e2 + r1 * s];
    };
    [e + sigma * s, s, -lambda * s, e - sigma * s]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One mode, unit mass: λ = ω², φ = 1 on x, F = 1/λ (no static correction).
    fn single(omega: f64, zeta: f64) -> ModalResponse {
        let mut r = ModalResponse::new(3);
        let mut phi = Vector6::zeros();
        phi[0] = 1.0;
        let mut flex = Matrix6::zeros();
        flex[(0, 0)] = 1.0 / (omega * omega);
        r.set_basis(
            &[omega * omega],
            &[phi],
            &Damping::ModalRatio { zeta },
            &flex,
            &Matrix6::identity(),
        )
        .unwrap();
        r
    }

    #[test]
    fn single_mode_step_and_ramp_match_closed_forms() {
        let (omega, zeta): (f64, f64) = (2.0 * std::f64::consts::PI * 3.0, 0.05);
        let wd = omega * (1.0 - zeta * zeta).sqrt();
        let sigma = zeta * omega;
        // Step of force F0 at t = 0 (a force already F0 on the first interval's start).
        let f0 = 2.0;
        let mut r = single(omega, zeta);
        let mut f = Vector6::zeros();
        f[0] = f0;
        let h = 7e-3; // any step: the integration is exact for piecewise-linear force
        let (mut worst, mut worst_a): (f64, f64) = (0.0, 0.0);
        for k in 1..=400 {
            r.step(&f, &f, h);
            let t = k as f64 * h;
            let want = f0 / (omega * omega)
                * (1.0 - (-sigma * t).exp() * ((wd * t).cos() + sigma / wd * (wd * t).sin()));
            worst = worst.max((r.displacement(&Vector6::zeros())[0] - want).abs());
            // ẍ = F0 e^{−σt}(cos ω_d t − σ/ω_d sin ω_d t) (unit mass; ẍ(0⁺) = F0), the
            // acceleration from the modal state
            let want = f0 * (-sigma * t).exp() * ((wd * t).cos() - sigma / wd * (wd * t).sin());
            worst_a = worst_a.max((r.acceleration(&f)[0] - want).abs());
        }
        assert!(worst < 1e-12 * f0 / (omega * omega), "step: {worst:e}");
        assert!(worst_a < 1e-12 * f0, "step acceleration: {worst_a:e}");
        // Ramp f = c t: x = c/ω² (t − 2ζ/ω + e^{−σt}(2ζ/ω cos ω_d t + (2ζ²−1)/ω_d sin ω_d t)).
        let c = 3.0;
        let mut r = single(omega, zeta);
        let mut worst: f64 = 0.0;
        for k in 1..=400 {
            let (t0, t1) = ((k - 1) as f64 * h, k as f64 * h);
            let mut a = Vector6::zeros();
            let mut b = Vector6::zeros();
            a[0] = c * t0;
            b[0] = c * t1;
            r.step(&a, &b, h);
            let t = t1;
            let e = (-sigma * t).exp();
            let want = c / (omega * omega)
                * (t - 2.0 * zeta / omega
                    + e * (2.0 * zeta / omega * (wd * t).cos()
                        + (2.0 * zeta * zeta - 1.0) / wd * (wd * t).sin()));
            worst = worst.max((r.displacement(&Vector6::zeros())[0] - want).abs());
        }
        assert!(worst < 1e-12 * c / (omega * omega), "ramp: {worst:e}");
    }

    /// Each regime's propagator against e^{Ah} summed as a Taylor series in extended steps
    /// (h split into 2^m pieces, each e^{Ah/2^m} by 30 terms, then squared back: a method
    /// of its own), ζ from 0 to 50, and ζ = 1 ± 1e-9 meeting the critical formula.
    #[test]
    fn propagator_matches_a_series_exponential_in_every_regime() {
        let series = |omega: f64, zeta: f64, h: f64| -> [f64; 4] {
            let a = [0.0, 1.0, -omega * omega, -2.0 * zeta * omega];
            let norm = a.iter().fold(0.0f64, |m, x| m.max(x.abs())) * h;
            let m = (norm.log2().ceil().max(0.0) as i32) + 4;
            let hs = h / 2f64.powi(m);
            let mul = |x: [f64; 4], y: [f64; 4]| {
                [
                    x[0] * y[0] + x[1] * y[2],
                    x[0] * y[1] + x[1] * y[3],
                    x[2] * y[0] + x[3] * y[2],
                    x[2] * y[1] + x[3] * y[3],
                ]
            };
            let ah = a.map(|v| v * hs);
            let mut term = [1.0, 0.0, 0.0, 1.0];
            let mut sum = term;
            for k in 1..30 {
                term = mul(term, ah).map(|v| v / k as f64);
                for i in 0..4 {
                    sum[i] += term[i];
                }
            }
            for _ in 0..m {
                sum = mul(sum, sum);
            }
            sum
        };
        for &(f_hz, h) in &[(3.0, 1e-3), (300.0, 1e-3), (3.0, 0.05)] {
            let omega = 2.0 * std::f64::consts::PI * f_hz;
            for &zeta in &[
                0.0,
                0.02,
                0.7,
                0.999,
                1.0 - 1e-9,
                1.0,
                1.0 + 1e-9,
                1.001,
                1.5,
                7.0,
                50.0,
            ] {
                let p = propagator(omega, zeta, h);
                let r = series(omega, zeta, h);
                // Entries scale as 1, h, ω², 1: compare each relative to its scale.
                let scale = [1.0, 1.0 / omega, omega, 1.0];
                for i in 0..4 {
                    let err = (p[i] - r[i]).abs() / scale[i];
                    assert!(
                        err < 1e-9,
                        "f {f_hz} Hz, ζ {zeta}, h {h}: entry {i}: {} vs {}",
                        p[i],
                        r[i]
                    );
                }
            }
        }
        // A stiff, heavily overdamped mode (the high modes under β = 2e-4, ζ ≈ 1.1e4): the
        // entries written on the two poles r = −σ ± μ directly,
        // e^{Ah}₁₁ = (−r₂e^{r₁h} + r₁e^{r₂h})/(r₁ − r₂), nothing overflowing.
        let omega = 2.0 * std::f64::consts::PI * 3e4;
        let zeta = 0.5 * 2e-4 * omega;
        let h = 1e-3;
        let p = propagator(omega, zeta, h);
        let mu = omega * (zeta * zeta - 1.0).sqrt();
        let (r1, r2) = (-omega * omega / (zeta * omega + mu), -zeta * omega - mu);
        let p11 = (-r2 * (r1 * h).exp() + r1 * (r2 * h).exp()) / (r1 - r2);
        let p12 = ((r1 * h).exp() - (r2 * h).exp()) / (r1 - r2);
        assert!(p.iter().all(|v| v.is_finite()), "{p:?}");
        assert!((p[0] - p11).abs() < 1e-12, "{} vs {p11}", p[0]);
        assert!((p[1] - p12).abs() < 1e-12 * h, "{} vs {p12}", p[1]);
    }

    /// A critically damped and an overdamped mode under a step force: the closed forms
    /// x = F0/ω² (1 − e^{−ωt}(1 + ωt)) and x = F0/ω² (1 − (r₂e^{r₁t} − r₁e^{r₂t})/(r₂ − r₁)).
    #[test]
    fn critical_and_overdamped_steps_match_closed_forms() {
        let omega = 2.0 * std::f64::consts::PI * 5.0;
        let f0 = 3.0;
        for &zeta in &[1.0, 2.5] {
            let mut r = single(omega, zeta);
            let mut f = Vector6::zeros();
            f[0] = f0;
            let mut worst: f64 = 0.0;
            for k in 1..=500 {
                r.step(&f, &f, 2e-3);
                let t = k as f64 * 2e-3;
                let want = if zeta == 1.0 {
                    f0 / (omega * omega) * (1.0 - (-omega * t).exp() * (1.0 + omega * t))
                } else {
                    let mu = omega * (zeta * zeta - 1.0).sqrt();
                    let (r1, r2) = (-zeta * omega + mu, -zeta * omega - mu);
                    f0 / (omega * omega)
                        * (1.0 - (r2 * (r1 * t).exp() - r1 * (r2 * t).exp()) / (r2 - r1))
                };
                worst = worst.max((r.displacement(&Vector6::zeros())[0] - want).abs());
            }
            assert!(worst < 1e-12 * f0 / (omega * omega), "ζ {zeta}: {worst:e}");
        }
    }

    #[test]
    fn bad_modes_are_refused_and_overdamped_ones_taken() {
        let mut r = ModalResponse::new(3);
        let phi = [Vector6::zeros()];
        let flex = Matrix6::zeros();
        // ζ = α/(2ω) = 2.5 at ω = 1: overdamped, taken.
        r.set_basis(
            &[1.0],
            &phi,
            &Damping::Rayleigh {
                alpha_per_s: 5.0,
                beta_s: 0.0,
            },
            &flex,
            &flex,
        )
        .unwrap();
        let err = r
            .set_basis(
                &[1.0],
                &phi,
                &Damping::ModalRatio { zeta: -0.1 },
                &flex,
                &flex,
            )
            .unwrap_err();
        assert!(matches!(err, ResponseError::BadDamping { .. }), "{err}");
        assert!(r
            .set_basis(&[f64::NAN], &phi, &Damping::None, &flex, &flex)
            .is_err());
    }

    /// Re-installing the same basis at a frozen pose must change nothing. Two modes that
    /// the end-effector (1 kg) takes a part 0.2 and 0.3 in (a sagging robot's cable-borne
    /// modes): carried by the mass overlap (here the identity), the response continues
    /// unchanged to rounding; carried by the end-effector's projection, each re-installation
    /// keeps only Σ φφᵀM_ee of the motion, and 20 of them leave under 1e-6 of it (the loss
    /// that made `simulate`'s residual after a stop vanish in 0.1 s on suspended-8 with sag).
    #[test]
    fn reinstalling_the_same_basis_keeps_the_motion_when_projected() {
        let (l0, l1) = (40.0, 90.0);
        let mut p0 = Vector6::zeros();
        let mut p1 = Vector6::zeros();
        p0[0] = 0.2f64.sqrt();
        p1[1] = 0.3f64.sqrt();
        let mut flex = Matrix6::zeros();
        flex[(0, 0)] = 0.2 / l0 + 0.01;
        flex[(1, 1)] = 0.3 / l1 + 0.01;
        flex[(2, 2)] = 0.01;
        let damping = Damping::ModalRatio { zeta: 0.01 };
        let (lam, phi) = ([l0, l1], [p0, p1]);
        let start = |r: &mut ModalResponse| {
            r.set_basis(&lam, &phi, &damping, &flex, &Matrix6::identity())
                .unwrap();
            let mut f = Vector6::zeros();
            f[0] = 3.0;
            f[1] = -2.0;
            r.step(&f, &f, 0.05);
            r.step(&f, &Vector6::zeros(), 0.05);
        };
        let (mut a, mut b, mut c) = (
            ModalResponse::new(3),
            ModalResponse::new(3),
            ModalResponse::new(3),
        );
        start(&mut a);
        start(&mut b);
        start(&mut c);
        let zero = Vector6::zeros();
        let ident = [1.0, 0.0, 0.0, 1.0];
        let (mut worst, mut peak, mut lost) = (0.0f64, 0.0f64, 0.0f64);
        for _ in 0..20 {
            b.set_basis_projected(&lam, &phi, &damping, &flex, &ident)
                .unwrap();
            c.set_basis(&lam, &phi, &damping, &flex, &Matrix6::identity())
                .unwrap();
            for _ in 0..10 {
                a.step(&zero, &zero, 1e-3);
                b.step(&zero, &zero, 1e-3);
                c.step(&zero, &zero, 1e-3);
            }
            let (ua, ub, uc) = (
                a.displacement(&zero),
                b.displacement(&zero),
                c.displacement(&zero),
            );
            worst = worst.max((ua - ub).norm());
            peak = peak.max(ua.norm());
            lost = uc.norm() / ua.norm();
        }
        assert!(worst <= 1e-14 * peak, "projected: {worst:e} of {peak:e}");
        assert!(lost < 1e-6, "the end-effector projection keeps {lost:e}");
    }
}
