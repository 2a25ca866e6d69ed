//! The family of catenaries through one chord, parametrised by the unstretched length L0:
//! for each L0 one catenary (Newton on the end force (H, V_e) with the positive definite
//! flexibility F), and its end tension T_e(L0), which falls from +∞ (a short cable
//! stretched) to a minimum at the fold, then rises (a long cable hanging in a loop).
//!
//! The fallback of the end-tension solve marches along this family from a short, taut
//! cable by the factor `MARCH_FACTOR`, each solve warm-started from the previous one:
//! when T_e falls below the target the taut solution is bracketed and bisected; when T_e
//! rises first, the minimum is refined by golden section and the target is TooSlack.

use super::{CableChord, SagError, SagInfo, SagParams};
use crate::elastic_catenary::Catenary;

/// Ratio of successive lengths of the march along the family.
const MARCH_FACTOR: f64 = 1.03;
/// The march starts where the straight cable would carry this multiple of max(T_e, w L).
const SHORT_TENSION_FACTOR: f64 = 4.0;
/// The march ends (no fold found: an error) at this multiple of the chord length.
const LONGEST_FACTOR: f64 = 4.0;
/// Smallest fraction of H kept by one Newton step of the length solve (H stays > 0).
const MIN_H_FRACTION: f64 = 0.1;
/// Golden-section ratio (√5 − 1)/2.
const GOLDEN: f64 = 0.618_033_988_749_895;
/// The bracket of L0 is narrowed to this relative width.
const BRACKET_REL: f64 = 1e-12;

impl CableChord {
    /// The catenary of unstretched length `l0_m` through the chord, from the end force
    /// `start` = (H, V_e) (N); `None` to start from the straight chord at tension
    /// max(EA (L/L0 − 1), w L). Never allocates.
    pub fn solve_length(
        &self,
        l0_m: f64,
        start: Option<(f64, f64)>,
        params: &SagParams,
    ) -> Result<(Catenary, SagInfo), SagError> {
        self.validate()?;
        if !(l0_m > 0.0 && l0_m.is_finite()) {
            return Err(SagError::Invalid {
                what: "unstretched length must be finite and > 0",
            });
        }
        let len = self.length_m();
        let (mut h, mut ve) = start.unwrap_or_else(|| {
            let t = (self.ea_n * (len / l0_m - 1.0))
                .max(self.w_n_m * len)
                .max(f64::MIN_POSITIVE);
            (
                t * self.span_m / len,
                t * self.rise_m / len + 0.5 * self.w_n_m * l0_m,
            )
        });
        let tol = params.tolerance * len;
        let residual = |h: f64, ve: f64| {
            let p = self.catenary(h, ve, l0_m).end_point_m();
            let r = [p[0] - self.span_m, p[1] - self.rise_m];
            let m = r[0].abs().max(r[1].abs());
            (r, if m.is_nan() { f64::INFINITY } else { m })
        };
        let (mut r, mut res) = residual(h, ve);
        for k in 0..params.max_iterations {
            if res <= tol {
                let info = SagInfo {
                    iterations: k,
                    residual_m: res,
                    ..SagInfo::default()
                };
                return Ok((self.catenary(h, ve, l0_m), info));
            }
            let [a, b, c] = self.catenary(h, ve, l0_m).flexibility_m_n();
            let det = a * c - b * b;
            let mut dh = -(c * r[0] - b * r[1]) / det;
            let mut dv = -(-b * r[0] + a * r[1]) / det;
            if self.span_m == 0.0 {
                dh = 0.0;
            } else if h + dh < MIN_H_FRACTION * h {
                let s = (1.0 - MIN_H_FRACTION) * h / -dh;
                dh *= s;
                dv *= s;
            }
            let mut trial = residual(h + dh, ve + dv);
            for _ in 0..params.max_iterations {
                if trial.1 < res {
                    break;
                }
                dh *= 0.5;
                dv *= 0.5;
                trial = residual(h + dh, ve + dv);
            }
            h += dh;
            ve += dv;
            (r, res) = trial;
        }
        if res <= tol {
            let info = SagInfo {
                iterations: params.max_iterations,
                residual_m: res,
                ..SagInfo::default()
            };
            return Ok((self.catenary(h, ve, l0_m), info));
        }
        Err(SagError::NoConvergence {
            iterations: params.max_iterations,
            residual_m: res,
        })
    }

    /// The smallest end tension of any catenary through the chord, N, and that catenary
    /// (the fold of the family). Bounded by `max_fallback_solves`; never allocates.
    pub fn min_end_tension(&self, params: &SagParams) -> Result<Catenary, SagError> {
        let mut iters = 0;
        match march(self, f64::NEG_INFINITY, params, &mut iters)? {
            March::Fold(c) => Ok(c),
            March::Crossed(..) => Err(SagError::NoConvergence {
                iterations: iters,
                residual_m: f64::NAN,
            }),
        }
    }
}

/// How the march along the family ended.
enum March {
    /// T_e fell below the target between these two catenaries (shorter first).
    Crossed(Catenary, Catenary),
    /// T_e reached its minimum (this catenary) above the target.
    Fold(Catenary),
}

/// A start (φ, L0) on the taut branch for end tension `t`, or TooSlack. Used by the
/// end-tension solve when its Newton iteration failed.
pub(super) fn taut_start(
    chord: &CableChord,
    t: f64,
    params: &SagParams,
    iters: &mut u32,
) -> Result<(f64, f64), SagError> {
    match march(chord, t, params, iters)? {
        March::Fold(c) => Err(SagError::TooSlack {
            t_end_n: t,
            t_end_min_n: c.tension_end_n(),
        }),
        March::Crossed(mut lo, mut hi) => {
            // Bisection on L0: T_e(lo) ≥ t > T_e(hi), T_e decreasing between them.
            let mut budget = params.max_fallback_solves;
            while hi.l0_m - lo.l0_m > BRACKET_REL * hi.l0_m && budget > 0 {
                budget -= 1;
                let mid = 0.5 * (lo.l0_m + hi.l0_m);
                let (c, _) = chord.solve_length(mid, Some((lo.h_n, lo.v_end_n())), params)?;
                *iters += 1;
                if c.tension_end_n() >= t {
                    lo = c;
                } else {
                    hi = c;
                }
            }
            Ok((lo.v_end_n().atan2(lo.h_n), lo.l0_m))
        }
    }
}

/// March from a short taut cable by `MARCH_FACTOR` until T_e < `t` or T_e rises (then
/// refine the fold by golden section).
fn march(
    chord: &CableChord,
    t: f64,
    params: &SagParams,
    iters: &mut u32,
) -> Result<March, SagError> {
    let len = chord.length_m();
    let t_short = SHORT_TENSION_FACTOR * t.max(chord.w_n_m * len).max(f64::MIN_POSITIVE);
    let mut l0 = len / (1.0 + t_short / chord.ea_n);
    let (mut prev, _) = chord.solve_length(l0, None, params)?;
    let mut before: Option<Catenary> = None;
    let mut budget = params.max_fallback_solves;
    while l0 < LONGEST_FACTOR * len && budget > 0 {
        budget -= 1;
        *iters += 1;
        l0 *= MARCH_FACTOR;
        let (c, _) = chord.solve_length(l0, Some((prev.h_n, prev.v_end_n())), params)?;
        if c.tension_end_n() < t {
            return Ok(March::Crossed(prev, c));
        }
        if c.tension_end_n() > prev.tension_end_n() {
            let a = before.unwrap_or(prev);
            return golden(chord, a, c, params, budget, iters).map(March::Fold);
        }
        before = Some(prev);
        prev = c;
    }
    Err(SagError::NoConvergence {
        iterations: *iters,
        residual_m: f64::NAN,
    })
}

/// Golden-section minimum of T_e(L0) between catenaries `a` and `b` (the minimum inside).
fn golden(
    chord: &CableChord,
    a: Catenary,
    b: Catenary,
    params: &SagParams,
    mut budget: u32,
    iters: &mut u32,
) -> Result<Catenary, SagError> {
    let (mut lo, mut hi) = (a.l0_m, b.l0_m);
    let warm = (a.h_n, a.v_end_n());
    let at = |l0: f64| chord.solve_length(l0, Some(warm), params).map(|(c, _)| c);
    let mut c1 = at(hi - GOLDEN * (hi - lo))?;
    let mut c2 = at(lo + GOLDEN * (hi - lo))?;
    while hi - lo > BRACKET_REL.sqrt() * hi && budget > 0 {
        budget -= 1;
        *iters += 1;
        if c1.tension_end_n() <= c2.tension_end_n() {
            hi = c2.l0_m;
            c2 = c1;
            c1 = at(hi - GOLDEN * (hi - lo))?;
        } else {
            lo = c1.l0_m;
            c1 = c2;
            c2 = at(lo + GOLDEN * (hi - lo))?;
        }
    }
    Ok(if c1.tension_end_n() <= c2.tension_end_n() {
        c1
    } else {
        c2
    })
}
