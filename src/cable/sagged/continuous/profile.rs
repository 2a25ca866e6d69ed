//! The validated catenary data the mesh needs: variation ν, nodes equal in ν, and the
//! compliance of the Magnus sub-segments (see the parent module's docs).

use super::{SagContError, Segment, NU_STRAIGHT, VERTICAL_H_RATIO};
use crate::elastic_catenary::Catenary;

/// The catenary's data the mesh needs, validated.
pub(super) struct Profile {
    pub l0: f64,
    pub ea: f64,
    pub w: f64,
    pub h: f64,
    va: f64,
    ve: f64,
    pub mu: f64,
    vertical: bool,
    /// asinh(V_a/H) (0 for a vertical cable).
    asinh_a: f64,
}

/// The tension state at a Gauss point.
pub(super) struct Gauss {
    v: f64,
    pub t: f64,
}

impl Profile {
    pub(super) fn new(cat: &Catenary, mu: f64) -> Result<Profile, SagContError> {
        let ok = |x: f64| x.is_finite() && x > 0.0;
        if !ok(cat.l0_m) {
            return Err(SagContError::BadInput("L0"));
        }
        if !ok(cat.ea_n) {
            return Err(SagContError::BadInput("EA"));
        }
        if !ok(mu) {
            return Err(SagContError::BadInput("mu"));
        }
        if !(cat.w_n_m.is_finite() && cat.w_n_m >= 0.0) {
            return Err(SagContError::BadInput("w"));
        }
        if !(cat.h_n.is_finite() && cat.h_n >= 0.0) {
            return Err(SagContError::BadInput("H"));
        }
        let (va, w, l0) = (cat.v_anchor_n, cat.w_n_m, cat.l0_m);
        let ve = va + w * l0;
        if !(va.is_finite() && ve.is_finite()) {
            return Err(SagContError::BadInput("V_a"));
        }
        let vmin = if va > 0.0 || ve < 0.0 {
            va.abs().min(ve.abs())
        } else {
            0.0
        };
        if cat.h_n == 0.0 && vmin == 0.0 {
            return Err(SagContError::Slack {
                v_anchor_n: va,
                v_end_n: ve,
            });
        }
        let vertical = cat.h_n <= VERTICAL_H_RATIO * vmin;
        Ok(Profile {
            l0,
            ea: cat.ea_n,
            w,
            h: cat.h_n,
            va,
            ve,
            mu,
            vertical,
            asinh_a: if vertical {
                0.0
            } else {
                (va / cat.h_n).asinh()
            },
        })
    }

    /// ν = ∫ w/T ds over the cable, without cancellation.
    pub(super) fn variation(&self) -> f64 {
        if self.w == 0.0 {
            return 0.0;
        }
        if self.vertical {
            let v0 = if self.va > 0.0 { self.va } else { -self.ve };
            return (self.w * self.l0 / v0).ln_1p();
        }
        asinh_diff(
            self.ve / self.h,
            self.va / self.h,
            self.w * self.l0 / self.h,
        )
    }

    /// s where ∫₀ˢ w/T = frac · ν.
    pub(super) fn node_s(&self, nu: f64, frac: f64) -> f64 {
        if nu < NU_STRAIGHT {
            return frac * self.l0;
        }
        let x = frac * nu;
        let s = if self.vertical {
            if self.va > 0.0 {
                self.va * x.exp_m1() / self.w
            } else {
                self.va * (-x).exp_m1() / self.w
            }
        } else {
            // (H/w)(sinh(a + x) − sinh a) = (2H/w) cosh(a + x/2) sinh(x/2)
            2.0 * self.h / self.w * (self.asinh_a + 0.5 * x).cosh() * (0.5 * x).sinh()
        };
        s.clamp(0.0, self.l0)
    }

    pub(super) fn gauss(&self, s: f64) -> Gauss {
        let v = self.va + self.w * s;
        Gauss {
            v,
            t: (self.h * self.h + v * v).sqrt(),
        }
    }

    /// The sub-segment of compliance I/EA + β₁N₁ + β₂N₂ (N = n nᵀ/T) and length ℓ, and its
    /// axial direction's angle in (h, up).
    pub(super) fn segment(
        &self,
        g1: &Gauss,
        g2: &Gauss,
        b1: f64,
        b2: f64,
        sin12: f64,
        l: f64,
    ) -> (Segment, [f64; 2]) {
        let (h, t1, t2) = (self.h, g1.t, g2.t);
        let tr = b1 / t1 + b2 / t2;
        let det = b1 * b2 * sin12 * sin12 / (t1 * t2);
        let big = 0.5 * (tr + (tr * tr - 4.0 * det).max(0.0).sqrt());
        let small = if big > 0.0 { det / big } else { 0.0 };
        // N = [[V², −HV], [−HV, H²]]/T³: the major axis's angle, then the axial one ⟂ to it.
        let (c1, c2) = (b1 / (t1 * t1 * t1), b2 / (t2 * t2 * t2));
        let pq = c1 * (g1.v - h) * (g1.v + h) + c2 * (g2.v - h) * (g2.v + h);
        let r2 = -2.0 * h * (c1 * g1.v + c2 * g2.v);
        let axis = axial_direction(pq, r2);
        let inv_ea = 1.0 / self.ea;
        let c = [inv_ea + small, inv_ea + big, inv_ea + tr];
        let mu = self.mu;
        let seg = Segment {
            rot: [1.0, 0.0],
            q: c.map(|ci| mu * ci * l * l),
            k: c.map(|ci| 1.0 / (ci * l)),
            mul: mu * l,
        };
        (seg, axis)
    }
}

/// The unit axial direction (cos, sin) in (h, up), perpendicular to the major axis of
/// angle ψ = ½ atan2(r2, pq) ∈ (−π/2, π/2], from cos 2ψ, sin 2ψ by the half-angle formulas
/// on the branch without cancellation (no trigonometric call): axial = (sin ψ, −cos ψ).
fn axial_direction(pq: f64, r2: f64) -> [f64; 2] {
    // pq, r2 ~ 1/T: their squares stay far inside the f64 range for any tension.
    let rho = (pq * pq + r2 * r2).sqrt();
    if !(rho > 0.0) {
        // No preferred transverse direction (not reached for T > 0): horizontal axis.
        return [1.0, 0.0];
    }
    let (c2, s2) = (pq / rho, r2 / rho);
    let (c, s) = if c2 >= 0.0 {
        let c = (0.5 * (1.0 + c2)).sqrt();
        (c, s2 / (2.0 * c))
    } else {
        let s = (0.5 * (1.0 - c2)).sqrt().copysign(s2);
        (s2 / (2.0 * s), s)
    };
    [s, -c]
}

/// asinh x − asinh y for x ≥ y with x − y = dxy given, without cancellation.
fn asinh_diff(x: f64, y: f64, dxy: f64) -> f64 {
    if y >= 0.0 {
        let den = x * (1.0 + y * y).sqrt() + y * (1.0 + x * x).sqrt();
        if den == 0.0 {
            return 0.0;
        }
        (dxy * (x + y) / den).asinh()
    } else if x <= 0.0 {
        asinh_diff(-y, -x, dxy)
    } else {
        x.asinh() - y.asinh()
    }
}
