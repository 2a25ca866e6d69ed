//! Derivatives of a catenary's end point: with respect to the end force at fixed
//! unstretched length (the flexibility, m/N) and to the unstretched length at fixed end
//! force. Both feed the solvers' Newton steps and the cable's static stiffness.
//!
//! With the end force (H, V_e), V_a = V_e − w L0, T_a = T(0), T_e = T(L0):
//!
//! ```text
//!   ∂X/∂H   = L0/EA + A − D          A = [asinh(V_e/H) − asinh(V_a/H)]/w
//!   ∂X/∂V_e = ∂Z/∂H = −H L0 (V_a + V_e) / (T_a T_e (T_a + T_e))
//!   ∂Z/∂V_e = L0/EA + D              D = [V_e/T_e − V_a/T_a]/w
//!   ∂(X, Z)/∂L0 = (1 + T_a/EA) (H, V_a)/T_a      (length added at the anchor)
//! ```
//!
//! D without cancellation: (V_e T_a − V_a T_e)/(w T_a T_e) directly when V_a < 0 < V_e
//! (two positive terms), else H² L0 (V_a + V_e)/(T_a T_e (V_e T_a + V_a T_e)) (from
//! (V_e T_a)² − (V_a T_e)² = H² w L0 (V_a + V_e)). A is the stable x-form of the module
//! docs divided by H. A − D → L0 V²/T³ as w → 0 is a difference: its absolute error is a
//! few ulps of L0/T, which matters only beside L0/EA when the cable is nearly horizontal
//! and EA/T ≳ 1e8 (relative error ~ ε EA/T in ∂X/∂H).

use super::catenary::end_parts;
use super::Catenary;

/// What a Newton step on a catenary's end point needs, from one evaluation of its closed
/// forms ([`Catenary::end_state`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EndState {
    /// The end point (x, z), m ([`Catenary::end_point_m`]).
    pub point_m: [f64; 2],
    /// The flexibility ∂(X, Z)/∂(H, V_e) as [xx, xz, zz], m/N ([`Catenary::flexibility_m_n`]).
    pub flexibility_m_n: [f64; 3],
    /// ∂(X, Z)/∂L0 ([`Catenary::end_point_dl0`]).
    pub dl0: [f64; 2],
}

impl Catenary {
    /// D = [V_e/T_e − V_a/T_a]/w, m/N (see the file docs); L0 H²/T³ in the limit w → 0.
    /// `ta`, `te`: the end tensions T_a, T_e, N.
    fn d_term(&self, ta: f64, te: f64) -> f64 {
        let (h, w, l0) = (self.h_n, self.w_n_m, self.l0_m);
        let (va, ve) = (self.v_anchor_n, self.v_end_n());
        if va < 0.0 && ve > 0.0 {
            return (ve * ta - va * te) / (w * ta * te);
        }
        let den = ve * ta + va * te;
        if den == 0.0 {
            // V_a = V_e = 0: a horizontal weightless cable, D = L0 H²/H³.
            return l0 / h;
        }
        h * h * l0 * (va + ve) / (ta * te * den)
    }

    /// The end point's flexibility ∂(X, Z)/∂(H, V_e) at fixed L0 as [xx, xz, zz], m/N
    /// (symmetric). Infinite or NaN entries when an end tension is 0 (a slack end).
    pub fn flexibility_m_n(&self) -> [f64; 3] {
        self.end_state().flexibility_m_n
    }

    /// ∂(X, Z)/∂L0 at fixed end force, dimensionless: the stretched anchor tangent
    /// (1 + T_a/EA)(H, V_a)/T_a.
    pub fn end_point_dl0(&self) -> [f64; 2] {
        self.dl0_at(self.tension_anchor_n())
    }

    /// [`Self::end_point_dl0`] with the anchor tension `ta`, N.
    fn dl0_at(&self, ta: f64) -> [f64; 2] {
        let k = (1.0 + ta / self.ea_n) / ta;
        [k * self.h_n, k * self.v_anchor_n]
    }

    /// The end point, its flexibility and its derivative along L0 together: each bit for
    /// bit its own method's, at the cost of one end point (the tensions and the logarithm
    /// of the x-form are shared; a Newton step on the end point needs all three).
    pub fn end_state(&self) -> EndState {
        let (h, l0, ea) = (self.h_n, self.l0_m, self.ea_n);
        let (point_m, [ta, te], a) = end_parts(self);
        let d = self.d_term(ta, te);
        let xz = -h * l0 * (self.v_anchor_n + self.v_end_n()) / (ta * te * (ta + te));
        EndState {
            point_m,
            flexibility_m_n: [l0 / ea + (a - d), xz, l0 / ea + d],
            dl0: self.dl0_at(ta),
        }
    }

    /// The cable's static stiffness at its end, K = F⁻¹ as [xx, xz, zz], N/m, in (h, up)
    /// (end force change per end displacement with the anchor and L0 fixed). `None` when F
    /// is singular or not finite (a slack end).
    pub fn stiffness_n_m(&self) -> Option<[f64; 3]> {
        let [a, b, c] = self.flexibility_m_n();
        let det = a * c - b * b;
        (det > 0.0 && det.is_finite()).then(|| [c / det, -b / det, a / det])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cat(h: f64, va: f64, w: f64) -> Catenary {
        Catenary {
            l0_m: 2.5,
            ea_n: 3e4,
            w_n_m: w,
            h_n: h,
            v_anchor_n: va,
        }
    }

    /// (H, V_a, w) of catenaries with the low point before, inside and after the cable, a
    /// nearly weightless one and a very slack one (`cat`'s L0 and EA).
    const BRANCHES: [(f64, f64, f64); 5] = [
        (40.0, 10.0, 20.0),
        (40.0, -30.0, 20.0),
        (40.0, -90.0, 20.0),
        (40.0, 25.0, 1e-6),
        (3.0, -200.0, 50.0),
    ];

    /// Central differences of the closed-form end point (step 1e-4 of the force, error
    /// O(h²) ≈ 1e-8 relative plus rounding ε X/h ≈ 1e-11) agree with the analytic
    /// flexibility and length derivative to 1e-7 relative, on every branch.
    #[test]
    fn flexibility_equals_finite_differences() {
        for &(h, va, w) in &BRANCHES {
            let c = cat(h, va, w);
            let f = c.flexibility_m_n();
            let scale = f[0].abs().max(f[2].abs());
            let dh = 1e-4 * c.tension_end_n();
            let p = |dh_: f64, dv: f64, dl: f64| {
                let mut d = c;
                d.h_n += dh_;
                d.v_anchor_n += dv - w * dl;
                d.l0_m += dl;
                d.end_point_m()
            };
            let (xp, xm) = (p(dh, 0.0, 0.0), p(-dh, 0.0, 0.0));
            let (vp, vm) = (p(0.0, dh, 0.0), p(0.0, -dh, 0.0));
            let fd = [
                (xp[0] - xm[0]) / (2.0 * dh),
                (vp[0] - vm[0]) / (2.0 * dh),
                (vp[1] - vm[1]) / (2.0 * dh),
            ];
            let fd_zh = (xp[1] - xm[1]) / (2.0 * dh);
            for (k, (a, b)) in f.iter().zip(fd).enumerate() {
                assert!(
                    (a - b).abs() < 1e-7 * scale,
                    "{h} {va} {w}: entry {k}: {a} vs {b}"
                );
            }
            assert!(
                (f[1] - fd_zh).abs() < 1e-7 * scale,
                "symmetry: {} vs {fd_zh}",
                f[1]
            );
            let dl = 1e-5;
            let (lp, lm) = (p(0.0, 0.0, dl), p(0.0, 0.0, -dl));
            let g = c.end_point_dl0();
            for j in 0..2 {
                assert!(
                    (g[j] - (lp[j] - lm[j]) / (2.0 * dl)).abs() < 1e-7,
                    "dl0 {j}: {g:?}"
                );
            }
        }
    }

    /// The shared evaluation of a Newton step is bit for bit the separate closed forms on
    /// every branch (low point before, inside, after; weightless; vertical, H = 0): the end
    /// point against the point at s = L0 (its own code path), ∂/∂L0 against its formula
    /// from the anchor tension, and the flexibility against the finite differences above.
    #[test]
    fn end_state_is_the_separate_forms_bit_for_bit() {
        let more = [(40.0, 25.0, 0.0), (0.0, 25.0, 20.0), (0.0, -80.0, 20.0)];
        for &(h, va, w) in BRANCHES.iter().chain(&more) {
            let c = cat(h, va, w);
            let e = c.end_state();
            assert_eq!(e.point_m, c.point_at_m(c.l0_m), "{h} {va} {w}");
            let ta = c.tension_anchor_n();
            let k = (1.0 + ta / c.ea_n) / ta;
            assert_eq!(e.dl0, [k * h, k * va], "{h} {va} {w}");
            assert_eq!(e.flexibility_m_n, c.flexibility_m_n());
        }
    }

    /// w = 0: the straight cable's stiffness (EA/L0) e eᵀ + T/(L0 (1 + T/EA)) (I − e eᵀ)
    /// (closed form) to 1e-12 relative (A − D cancels to ~ε L0/T, EA/T = 600 here).
    #[test]
    fn weightless_stiffness_is_the_straight_cable() {
        let c = cat(30.0, 40.0, 0.0);
        let k = c.stiffness_n_m().unwrap();
        let t = 50.0;
        let e = [0.6, 0.8];
        let (ka, kt) = (3e4 / 2.5, t / (2.5 * (1.0 + t / 3e4)));
        let exact = [
            ka * e[0] * e[0] + kt * e[1] * e[1],
            (ka - kt) * e[0] * e[1],
            ka * e[1] * e[1] + kt * e[0] * e[0],
        ];
        for j in 0..3 {
            assert!((k[j] - exact[j]).abs() < 1e-12 * ka, "{k:?} vs {exact:?}");
        }
    }
}
