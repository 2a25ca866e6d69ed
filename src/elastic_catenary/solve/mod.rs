//! The catenary through a given chord for a given end-effector-end tension T_e: the TAUT
//! branch (the one continuous with the straight cable, shortest L0).
//!
//! Unknowns (φ, L0): the end force is T_e (cos φ, sin φ) in (h, up) and the residual is
//! r = P(φ, L0) − (X, Z), m. Newton's Jacobian is J = [F·(−V_e, H) | ∂P/∂L0] with the
//! closed-form flexibility F (`flexibility.rs`). On the taut branch det J < 0 (at w = 0,
//! det J = −L0 (1 + T/EA)); it vanishes at the fold where T_e is smallest along the family
//! of catenaries through the chord, and is positive on the slack branch. A solution is
//! accepted only with det J < 0.
//!
//! Start: a warm catenary, or the shallow estimate (chord angle θ, chord length L): the
//! end tangent tilts up by asin(w L cos θ/(2 T_e)) and L0 = L (1 + (w L cos θ)²/(24 T_e²))
//! /(1 + T_e/EA). Steps are limited (|Δφ| ≤ 0.25 rad, L0 at least halved) and halved until
//! the residual decreases. When Newton fails, the bounded fallback of `family.rs` follows
//! the family of catenaries through the chord by their length: it finds the smallest end
//! tension (TooSlack when T_e is below it) or a bracketed start on the taut branch.
//!
//! A vertical chord (span 0) is solved in closed form: H = 0, and ∫(1 + T/EA) ds = |Z|
//! with T linear in s is a quadratic in L0.

use super::Catenary;

mod family;

/// Largest change of the end angle in one Newton step, rad.
const MAX_ANGLE_STEP_RAD: f64 = 0.25;
/// Smallest fraction of L0 kept by one Newton step (L0 stays positive).
const MIN_LENGTH_FRACTION: f64 = 0.5;
/// Step halvings tried before a Newton step is taken although the residual grew.
const MAX_HALVINGS: u32 = 12;
/// On the slack side (det J ≥ 0) L0 is shortened by this factor toward the taut branch.
const SHORTEN_FACTOR: f64 = 0.9;

/// One cable's chord in its vertical plane and its material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CableChord {
    /// Horizontal span X ≥ 0 from the anchor to the end, m.
    pub span_m: f64,
    /// Rise Z of the end above the anchor, m (negative: the end is below).
    pub rise_m: f64,
    /// Axial rigidity EA > 0, N.
    pub ea_n: f64,
    /// Weight per unstretched length w ≥ 0, N/m.
    pub w_n_m: f64,
}

/// Parameters of the catenary solvers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SagParams {
    /// Newton iterations of one solve (also the fallback's inner solves).
    pub max_iterations: u32,
    /// Converged when the end point is within `tolerance` × chord length of the chord's end
    /// (the closed forms are exact to a few ulps of the chord, so 1e-12 is reachable).
    pub tolerance: f64,
    /// Catenary solves the fallback may spend (golden section and bisection on L0).
    pub max_fallback_solves: u32,
}

impl Default for SagParams {
    fn default() -> Self {
        SagParams {
            max_iterations: 40,
            tolerance: 1e-12,
            max_fallback_solves: 160,
        }
    }
}

/// What a solve did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SagInfo {
    /// Newton iterations (all phases).
    pub iterations: u32,
    /// Largest component of the end point's residual, m.
    pub residual_m: f64,
    /// dφ/dT_e of the end tangent's angle above the horizontal at fixed chord, rad/N.
    pub dphi_dt_end_rad_n: f64,
    /// True when the fallback along the family was needed.
    pub fallback: bool,
}

/// Errors of the catenary solvers.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SagError {
    /// A non-finite or out-of-range input.
    #[error("invalid sagging-cable input: {what}")]
    Invalid {
        /// Which input.
        what: &'static str,
    },
    /// T_e below the smallest end tension of any catenary through the chord.
    #[error("cable too slack: end tension {t_end_n:.6e} N is below {t_end_min_n:.6e} N, the smallest end tension of any catenary through this chord")]
    TooSlack {
        /// The requested end tension, N.
        t_end_n: f64,
        /// The smallest achievable end tension, N.
        t_end_min_n: f64,
    },
    /// The bounded iterations ran out.
    #[error("catenary solve did not converge in {iterations} iterations (end point residual {residual_m:.3e} m)")]
    NoConvergence {
        /// Iterations done.
        iterations: u32,
        /// Residual where it stopped, m.
        residual_m: f64,
    },
}

/// Newton's state at one iterate.
struct Eval {
    cat: Catenary,
    r: [f64; 2],
    res: f64,
    /// Jacobian ∂P/∂(φ, L0), rows x and z.
    j: [[f64; 2]; 2],
    det: f64,
    /// The flexibility ∂P/∂(H, V_e) as [xx, xz, zz], m/N.
    f: [f64; 3],
}

/// A taut solution with what predicts the next one ([`CableChord::solve_end_tension_tracked`]):
/// the chord and end tension it solves, its (φ, L0), Newton's Jacobian J = ∂P/∂(φ, L0) and
/// ∂P/∂T_e at fixed (φ, L0), so a nearby chord (X', Z') and tension T' start Newton from
/// (φ, L0) − J⁻¹ (∂P/∂T_e ΔT − Δ(X, Z)): the first Newton step taken for free.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SagTrack {
    /// The solution.
    pub catenary: Catenary,
    chord: [f64; 2],
    t_end_n: f64,
    phi: f64,
    j: [[f64; 2]; 2],
    det: f64,
    dp_dt: [f64; 2],
}

impl CableChord {
    /// Chord length L, m.
    pub fn length_m(&self) -> f64 {
        super::hypot_fast(self.span_m, self.rise_m)
    }

    pub(super) fn validate(&self) -> Result<(), SagError> {
        if !(self.span_m >= 0.0 && self.span_m.is_finite() && self.rise_m.is_finite()) {
            return Err(SagError::Invalid {
                what: "span must be finite and ≥ 0, rise finite",
            });
        }
        if !(self.length_m() > 0.0) {
            return Err(SagError::Invalid {
                what: "zero chord length",
            });
        }
        if !(self.ea_n > 0.0 && self.ea_n.is_finite()) {
            return Err(SagError::Invalid {
                what: "EA must be finite and > 0",
            });
        }
        if !(self.w_n_m >= 0.0 && self.w_n_m.is_finite()) {
            return Err(SagError::Invalid {
                what: "w must be finite and ≥ 0",
            });
        }
        Ok(())
    }

    pub(super) fn catenary(&self, h_n: f64, v_end_n: f64, l0_m: f64) -> Catenary {
        Catenary {
            l0_m,
            ea_n: self.ea_n,
            w_n_m: self.w_n_m,
            h_n,
            v_anchor_n: v_end_n - self.w_n_m * l0_m,
        }
    }

    fn eval(&self, t: f64, phi: f64, l0: f64) -> Eval {
        let (h, ve) = (t * phi.cos().max(0.0), t * phi.sin());
        let cat = self.catenary(h, ve, l0);
        let end = cat.end_state();
        let p = end.point_m;
        let r = [p[0] - self.span_m, p[1] - self.rise_m];
        let [fxx, fxz, fzz] = end.flexibility_m_n;
        let dl = end.dl0;
        let j = [[-fxx * ve + fxz * h, dl[0]], [-fxz * ve + fzz * h, dl[1]]];
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        let res = r[0].abs().max(r[1].abs());
        Eval {
            cat,
            r,
            res: if res.is_nan() { f64::INFINITY } else { res },
            j,
            det,
            f: [fxx, fxz, fzz],
        }
    }

    /// The shallow start (module docs): (φ, L0).
    fn shallow_start(&self, t: f64) -> (f64, f64) {
        let len = self.length_m();
        let theta = self.rise_m.atan2(self.span_m);
        let across = self.w_n_m * len * theta.cos();
        let tilt = (across / (2.0 * t)).min(1.0).asin();
        let phi = (theta + tilt).min(std::f64::consts::FRAC_PI_2);
        let l0 = len * (1.0 + across * across / (24.0 * t * t)) / (1.0 + t / self.ea_n);
        (phi, l0)
    }

    /// The taut-branch catenary with end tension `t_end_n`, N. `warm`: a previous solution
    /// (of a nearby chord or tension) to start from. Never allocates.
    pub fn solve_end_tension(
        &self,
        t_end_n: f64,
        warm: Option<&Catenary>,
        params: &SagParams,
    ) -> Result<(Catenary, SagInfo), SagError> {
        self.validate()?;
        if !(t_end_n > 0.0 && t_end_n.is_finite()) {
            return Err(SagError::Invalid {
                what: "end tension must be finite and > 0",
            });
        }
        if self.span_m == 0.0 {
            return self.solve_vertical(t_end_n);
        }
        let start = match warm {
            Some(c) if c.l0_m > 0.0 && c.tension_end_n() > 0.0 => {
                (c.v_end_n().atan2(c.h_n), c.l0_m)
            }
            _ => self.shallow_start(t_end_n),
        };
        let mut iters = 0;
        if let Ok(ok) = self.newton(t_end_n, start, params, &mut iters) {
            return Ok(ok);
        }
        if warm.is_some() {
            if let Ok(ok) = self.newton(t_end_n, self.shallow_start(t_end_n), params, &mut iters) {
                return Ok(ok);
            }
        }
        let (phi, l0) = family::taut_start(self, t_end_n, params, &mut iters)?;
        let (cat, mut info) = self.newton(t_end_n, (phi, l0), params, &mut iters)?;
        info.fallback = true;
        Ok((cat, info))
    }

    /// [`Self::solve_end_tension`] warm-started from a tracked solution (of a nearby chord
    /// and tension): Newton starts from its first-order prediction ([`SagTrack`]), and on
    /// any failure the plain solve from its catenary follows. Returns the solution tracked
    /// for the next call (the same catenary the plain solve converges to, within its
    /// tolerance). Never allocates.
    pub fn solve_end_tension_tracked(
        &self,
        t_end_n: f64,
        warm: Option<&SagTrack>,
        params: &SagParams,
    ) -> Result<(Catenary, SagInfo, SagTrack), SagError> {
        if let Some(start) = warm.and_then(|w| self.predict(w, t_end_n)) {
            let mut iters = 0;
            if self.validate().is_ok() && t_end_n > 0.0 && t_end_n.is_finite() {
                if let Ok(e) = self.newton_eval(t_end_n, start, params, &mut iters) {
                    let info = self.info(t_end_n, &e, iters);
                    return Ok((e.cat, info, self.track(t_end_n, &e)));
                }
            }
        }
        let (cat, info) = self.solve_end_tension(t_end_n, warm.map(|w| &w.catenary), params)?;
        // The fallback's solution, tracked (one more evaluation, off the usual path).
        let phi = cat.v_end_n().atan2(cat.h_n);
        let e = self.eval(t_end_n, phi, cat.l0_m);
        Ok((cat, info, self.track(t_end_n, &e)))
    }

    /// The first-order start from `w` for this chord and `t`: None when it is not usable
    /// (vertical chord, degenerate Jacobian, a step beyond Newton's own limits).
    fn predict(&self, w: &SagTrack, t: f64) -> Option<(f64, f64)> {
        if self.span_m == 0.0 || !(w.det < 0.0) || w.catenary.l0_m <= 0.0 {
            return None;
        }
        let r = [
            w.dp_dt[0] * (t - w.t_end_n) - (self.span_m - w.chord[0]),
            w.dp_dt[1] * (t - w.t_end_n) - (self.rise_m - w.chord[1]),
        ];
        let dphi = -(w.j[1][1] * r[0] - w.j[0][1] * r[1]) / w.det;
        let dl0 = -(-w.j[1][0] * r[0] + w.j[0][0] * r[1]) / w.det;
        let l0 = w.catenary.l0_m;
        let ok = dphi.abs() <= MAX_ANGLE_STEP_RAD
            && dl0 >= -(1.0 - MIN_LENGTH_FRACTION) * l0
            && (dphi + dl0).is_finite();
        ok.then(|| (clamp_angle(w.phi + dphi), l0 + dl0))
    }

    fn track(&self, t: f64, e: &Eval) -> SagTrack {
        SagTrack {
            catenary: e.cat,
            chord: [self.span_m, self.rise_m],
            t_end_n: t,
            phi: e.cat.v_end_n().atan2(e.cat.h_n),
            j: e.j,
            det: e.det,
            dp_dt: Self::dp_dt(t, e),
        }
    }

    /// Damped Newton on (φ, L0) from `start`; `iters` accumulates across calls.
    fn newton(
        &self,
        t: f64,
        start: (f64, f64),
        params: &SagParams,
        iters: &mut u32,
    ) -> Result<(Catenary, SagInfo), SagError> {
        let e = self.newton_eval(t, start, params, iters)?;
        Ok((e.cat, self.info(t, &e, *iters)))
    }

    /// [`Self::newton`]'s converged iterate.
    fn newton_eval(
        &self,
        t: f64,
        start: (f64, f64),
        params: &SagParams,
        iters: &mut u32,
    ) -> Result<Eval, SagError> {
        let tol = params.tolerance * self.length_m();
        let (mut phi, mut l0) = start;
        let mut e = self.eval(t, phi, l0);
        for _ in 0..params.max_iterations {
            if e.res <= tol && e.det < 0.0 {
                return Ok(e);
            }
            *iters += 1;
            if !(e.det < 0.0) {
                // Slack side of the fold (or a degenerate Jacobian): shorten toward the taut branch.
                l0 *= SHORTEN_FACTOR;
                e = self.eval(t, phi, l0);
                continue;
            }
            let dphi = -(e.j[1][1] * e.r[0] - e.j[0][1] * e.r[1]) / e.det;
            let dl0 = -(-e.j[1][0] * e.r[0] + e.j[0][0] * e.r[1]) / e.det;
            let mut scale = 1.0f64;
            scale = scale.min(MAX_ANGLE_STEP_RAD / dphi.abs().max(f64::MIN_POSITIVE));
            if dl0 < 0.0 {
                scale = scale.min((1.0 - MIN_LENGTH_FRACTION) * l0 / -dl0);
            }
            let mut trial = self.eval(t, clamp_angle(phi + scale * dphi), l0 + scale * dl0);
            for _ in 0..MAX_HALVINGS {
                if trial.res < e.res {
                    break;
                }
                scale *= 0.5;
                trial = self.eval(t, clamp_angle(phi + scale * dphi), l0 + scale * dl0);
            }
            phi = clamp_angle(phi + scale * dphi);
            l0 += scale * dl0;
            e = trial;
        }
        if e.res <= tol && e.det < 0.0 {
            return Ok(e);
        }
        Err(SagError::NoConvergence {
            iterations: *iters,
            residual_m: e.res,
        })
    }

    /// ∂P/∂T_e at fixed (φ, L0): F (cos φ, sin φ), m/N.
    fn dp_dt(t: f64, e: &Eval) -> [f64; 2] {
        let [fxx, fxz, fzz] = e.f;
        let (c, s) = (e.cat.h_n / t, e.cat.v_end_n() / t);
        [fxx * c + fxz * s, fxz * c + fzz * s]
    }

    /// dφ/dT_e from the implicit function theorem: d(φ, L0)/dT_e = −J⁻¹ F (cos φ, sin φ).
    fn info(&self, t: f64, e: &Eval, iterations: u32) -> SagInfo {
        let b = Self::dp_dt(t, e);
        let dphi = -(e.j[1][1] * b[0] - e.j[0][1] * b[1]) / e.det;
        SagInfo {
            iterations,
            residual_m: e.res,
            dphi_dt_end_rad_n: dphi,
            fallback: false,
        }
    }

    /// Span 0: H = 0 and the quadratic for L0 (module docs), in the stable root form.
    fn solve_vertical(&self, t: f64) -> Result<(Catenary, SagInfo), SagError> {
        let (ea, w, z) = (self.ea_n, self.w_n_m, self.rise_m.abs());
        let b = 1.0 + t / ea;
        let info = SagInfo::default();
        if self.rise_m < 0.0 {
            // Anchor above: T(s) = T_e + w (L0 − s), (w/2EA) L0² + b L0 − |Z| = 0.
            let l0 = 2.0 * z / (b + (b * b + 2.0 * w * z / ea).sqrt());
            return Ok((self.catenary(0.0, -t, l0), info));
        }
        // Anchor below: T(s) = T_e − w (L0 − s), −(w/2EA) L0² + b L0 − Z = 0; the anchor
        // tension T_e − w L0 must stay positive.
        let disc = b * b - 2.0 * w * z / ea;
        let l0 = 2.0 * z / (b + disc.max(0.0).sqrt());
        if disc < 0.0 || !(t - w * l0 > 0.0) {
            let l_min = 2.0 * z / (1.0 + (1.0 + 2.0 * w * z / ea).sqrt());
            return Err(SagError::TooSlack {
                t_end_n: t,
                t_end_min_n: w * l_min,
            });
        }
        Ok((self.catenary(0.0, t, l0), info))
    }
}

fn clamp_angle(phi: f64) -> f64 {
    phi.clamp(-std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2)
}
