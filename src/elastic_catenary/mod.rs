//! Statics of sagging cables: the elastic catenary (Irvine) of one cable in its vertical
//! plane, in cancellation-free closed forms.
//!
//! ## Coordinates and conventions
//!
//! A cable hangs in the vertical plane through its anchor A and its end point P on the
//! end-effector. Plane coordinates: x horizontal from A toward P (unit h), z up (unit
//! up = −g/|g|); the out-of-plane unit is n = h × up. For a vertical cable (span 0) h is
//! any horizontal unit (the first column of `kinematics::up_frame(g)` by convention of the
//! callers). s ∈ [0, L0] is the UNSTRETCHED arclength from the anchor (s = 0) to the end
//! (s = L0). w ≥ 0 is the weight per unstretched length (N/m), EA the axial rigidity (N).
//!
//! The tension vector along the tangent toward increasing s is F(s) = (H, V(s)) in
//! (h, up): H ≥ 0 is constant (no horizontal load), V(s) = V_a + w s grows with s (V_a, the
//! value at the anchor, is positive up), and T(s) = √(H² + V(s)²). The cable pulls the
//! end-effector with −(H h + V_e up), V_e = V(L0); its end tension is T_e = T(L0), its
//! anchor tension T_a = T(0); the smallest tension along it is min(T_a, T_e), or H when the
//! low point is inside (V_a < 0 < V_e).
//!
//! ## The elastic catenary
//!
//! A stretched element ds(1 + T/EA) lies along F/T, so (Irvine, Cable Structures, ch. 2)
//!
//! ```text
//!   x(s) = H s/EA + (H/w) [asinh(V(s)/H) − asinh(V_a/H)]
//!   z(s) = (V_a s + w s²/2)/EA + (1/w) [T(s) − T_a]
//! ```
//!
//! Both brackets cancel catastrophically as w → 0 (they are O(w s) differences divided by
//! w) and the first is 0·∞ at H = 0. The forms used instead (see `catenary.rs`):
//!
//! ```text
//!   (1/w)[T(s) − T_a] = s (V_a + V)/(T + T_a)                        (difference of squares)
//!   (H/w)[asinh(V/H) − asinh(V_a/H)] = H s q · log1p(u)/u,  u = w s q,
//!       q = (T_a + T + V_a + V) / ((T_a + T)(T_a + V_a))   when V_a ≥ 0,
//!       q = (T_a + T − V_a − V) / ((T_a + T)(T − V))       when V ≤ 0,
//!   (H/w)[asinh(V/H) + asinh(−V_a/H)]   (two positive terms)  when V_a < 0 < V,
//! ```
//!
//! with log1p(u)/u = 1 − u/2 + u²/3 − u³/4 for u < 1e-4. Every term is a sum of
//! like-signed quantities, so x and z are accurate to a few ulps for any w ≥ 0, any H ≥ 0
//! (H = 0: a vertical cable, x = 0) and either sign of V. At w = 0 they give the straight
//! stretched cable x = s(1 + T/EA) H/T, z = s(1 + T/EA) V/T.
//!
//! ## Solving for a chord
//!
//! [`CableChord::solve_end_tension`] finds the catenary through a chord (span X ≥ 0, rise
//! Z) whose end-effector-end tension is T_e, on the taut branch (shortest L0, continuous
//! with the straight cable); [`CableChord::solve_length`] the one of a given L0;
//! [`CableChord::min_end_tension`] the fold of the family, below whose end tension no
//! catenary reaches the chord ([`SagError::TooSlack`]). Files: `catenary` (closed forms),
//! `flexibility` (∂(X, Z)/∂(H, V_e), ∂(X, Z)/∂L0, the end stiffness), `solve` (the
//! end-tension Newton), `family` (the length solve and the fallback along the family).
//!
//! ## Derived quantities
//!
//! - sag: the largest distance of the profile from its chord A→P, m, at the point where
//!   the tangent is parallel to the chord (V(s*) = H Z/X).
//! - Irvine's λ² for an inclined chord of length L, span X and rise Z (Irvine's inclined-cable
//!   form: the weight's component across the chord w X/L and the chord tension H L/X):
//!   λ² = (w X² / (H L))² · X EA / (H L_e), L_e = L (1 + 8 (d/L)²), d = sag. For a level
//!   span it is the textbook (wL/H)² L/(H L_e/EA); for a vertical cable it is 0 (no sag).

mod catenary;
mod elements;
mod flexibility;
mod solve;

pub use catenary::Catenary;
pub use elements::CatenaryElements;
pub use flexibility::EndState;

/// √(a² + b²) by one square root where a² + b² neither overflows nor leaves the normal
/// range (every force and length of a cable), else the library's `hypot`: within ~1 ulp
/// like `hypot`, at a fifth of its cost on the per-cycle path.
#[inline]
pub(crate) fn hypot_fast(a: f64, b: f64) -> f64 {
    let s = a * a + b * b;
    if s > HYPOT_SQUARE_MIN && s < HYPOT_SQUARE_MAX {
        s.sqrt()
    } else {
        a.hypot(b)
    }
}

/// The squared range where [`hypot_fast`] squares: normal numbers, far from overflow.
const HYPOT_SQUARE_MIN: f64 = 1e-290;
const HYPOT_SQUARE_MAX: f64 = 1e290;
pub use solve::{CableChord, SagError, SagInfo, SagParams, SagTrack};
