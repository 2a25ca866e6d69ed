//! Swivel pulleys at the anchors, in closed form.
//!
//! The cable arrives from the winch along the swivel axis, which passes through the anchor F
//! (where the cable enters the pulley) in the unit direction w ([`Pulley::entry_unit`]). The
//! pulley turns about that axis so that its plane contains the attachment point B; its
//! circle of radius R touches the axis at F, its centre C = F + R u on the side of B
//! (u: the unit part of B − F perpendicular to w). The cable wraps the circle from F and
//! leaves it at the tangent point A towards B.
//!
//! In the plane, with x = (B − C)·u, y = (B − C)·w, D² = x² + y² and the free length
//! L = √(D² − R²), the wrap angle φ (the angle the cable turns through on the pulley, in
//! [0, 2π)) solves B − C = R ρ(φ) + L d(φ) with the radial unit ρ(φ) = −cos φ u + sin φ w
//! and the cable's direction d(φ) = cos φ w + sin φ u:
//!
//!   cos φ = (L y − R x)/D²,  sin φ = (L x + R y)/D²,
//!
//! so A = C + R ρ(φ), the unit direction s = d(φ) (exit → attachment) and the wrapped arc
//! R φ. The path length R φ + L is stationary in B's position with gradient s (the exit
//! point slides along the tangent), and its Hessian, the pulley cable's geometric stiffness
//! per newton, is m mᵀ/L + (sin φ / a) n nᵀ with m = ρ(φ) (in the plane, normal to s),
//! n = w × u (the plane's normal) and a = (B − F)·u the attachment's distance from the
//! axis. Without a pulley it is (I − s sᵀ)/L = (m mᵀ + n nᵀ)/L, so the pulley changes
//! the straight cable's stiffness by T (sin φ / a − 1/L) n nᵀ ([`PulleyExit::softening_per_m`]):
//! moving B across the plane swings the plane about the axis, further than it would swing
//! a cable pinned at the exit point.
//!
//! Refused: an attachment on the swivel axis (a < [`MIN_CABLE_LENGTH_M`]: no plane) and an
//! attachment inside the pulley circle or on it (L < [`MIN_CABLE_LENGTH_M`]).

use super::{KinematicsError, MIN_CABLE_LENGTH_M};
use crate::scene::Pulley;
use nalgebra::Vector3;
use std::f64::consts::TAU;

/// Where a swivel pulley's cable leaves it at one pose (all in the world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PulleyExit {
    /// The tangent point A where the free cable starts, m.
    pub exit_m: Vector3<f64>,
    /// Unit direction of the free cable, exit point → attachment point.
    pub unit: Vector3<f64>,
    /// Free length |B − A|, m.
    pub free_length_m: f64,
    /// Wrap angle φ, rad, in [0, 2π): the angle the cable turns through on the pulley.
    pub wrap_rad: f64,
    /// The wrapped arc R φ, m.
    pub wrap_arc_m: f64,
    /// Swivel angle of the pulley plane about the axis, rad, in (−π, π]: the angle of u
    /// from the reference direction [`swivel_reference`] about w.
    pub plane_rad: f64,
    /// Centre C of the pulley circle, m.
    pub centre_m: Vector3<f64>,
    /// Unit normal n = w × u of the pulley plane.
    pub normal: Vector3<f64>,
    /// sin φ / a − 1/L, 1/m (≤ 0): the change of the cable's transverse geometric
    /// stiffness per newton of tension along [`Self::normal`] that the swivelling exit
    /// point makes (module docs).
    pub softening_per_m: f64,
}

impl PulleyExit {
    /// ∂A/∂B, the exit point's motion with the attachment point (3 × 3, dimensionless):
    /// −s (A − C)ᵀ/L + (R (1 − cos φ)/a) n nᵀ. In the plane the exit point slides along the
    /// circle's tangent s as the wrap angle turns (δφ = −ρ(φ)·δB/L, δA = R s δφ); across
    /// it the plane swings about the axis by n·δB/a, carrying A, at R (1 − cos φ) from the
    /// axis, with it. R (1 − cos φ)/a = −L · [`Self::softening_per_m`] (a = R (1 − cos φ)
    /// + L sin φ). Zero for R = 0.
    pub fn exit_jacobian(&self) -> nalgebra::Matrix3<f64> {
        let l = self.free_length_m;
        -self.unit * (self.exit_m - self.centre_m).transpose() / l
            - self.normal * self.normal.transpose() * (l * self.softening_per_m)
    }
}

/// The reference direction of the swivel angle: the unit vector perpendicular to `w` built
/// from the coordinate axis least aligned with it (x first), and the third axis w × e1.
pub fn swivel_reference(w: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let seed = if w.x.abs() <= w.y.abs() && w.x.abs() <= w.z.abs() {
        Vector3::x()
    } else if w.y.abs() <= w.z.abs() {
        Vector3::y()
    } else {
        Vector3::z()
    };
    let e1 = (seed - w * w.dot(&seed)).normalize();
    (e1, w.cross(&e1))
}

/// The exit of cable `cable`'s pulley `p` at anchor `anchor_m` (the entry point F on the
/// swivel axis) towards the attachment point `attach_m` (world, m). Closed form, no
/// allocation; refused poses per the module docs.
pub fn pulley_exit(
    cable: usize,
    anchor_m: &Vector3<f64>,
    p: &Pulley,
    attach_m: &Vector3<f64>,
) -> Result<PulleyExit, KinematicsError> {
    let w = p.entry_unit;
    let r = p.radius_m;
    let v = attach_m - anchor_m;
    let along = v.dot(&w);
    let perp = v - w * along;
    let a = perp.norm();
    if a.is_nan() || a < MIN_CABLE_LENGTH_M {
        return Err(KinematicsError::AlongSwivelAxis {
            cable,
            distance_m: a,
            min_m: MIN_CABLE_LENGTH_M,
        });
    }
    let u = perp / a;
    let centre_m = anchor_m + u * r;
    let x = a - r;
    let y = along;
    let d2 = x * x + y * y;
    let l2 = d2 - r * r;
    let l = l2.max(0.0).sqrt();
    if !(l >= MIN_CABLE_LENGTH_M) {
        return Err(KinematicsError::InsidePulley {
            cable,
            free_length_m: l,
            min_m: MIN_CABLE_LENGTH_M,
        });
    }
    let cos_phi = (l * y - r * x) / d2;
    let sin_phi = (l * x + r * y) / d2;
    let mut phi = sin_phi.atan2(cos_phi);
    if phi < 0.0 {
        phi += TAU;
    }
    if phi >= TAU {
        phi = 0.0;
    }
    let radial = -u * cos_phi + w * sin_phi;
    let unit = w * cos_phi + u * sin_phi;
    let normal = w.cross(&u);
    let (e1, e2) = swivel_reference(&w);
    Ok(PulleyExit {
        exit_m: centre_m + radial * r,
        unit,
        free_length_m: l,
        wrap_rad: phi,
        wrap_arc_m: r * phi,
        plane_rad: u.dot(&e2).atan2(u.dot(&e1)),
        centre_m,
        normal,
        softening_per_m: sin_phi / a - 1.0 / l,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;
    use std::f64::consts::PI;

    /// A small deterministic generator (xorshift), uniform in [0, 1).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn unit(&mut self) -> Vector3<f64> {
            loop {
                let v = Vector3::new(self.next(), self.next(), self.next()) * 2.0
                    - Vector3::repeat(1.0);
                let n = v.norm();
                if n > 0.1 && n <= 1.0 {
                    return v / n;
                }
            }
        }
    }

    /// The independent construction: the circle in the plane of the axis and B, walked from
    /// the entry point F in the cable's turning sense; the exit is the first point where the
    /// path length R θ + |B − P(θ)| stops growing (its derivative R (1 − cos α) is zero:
    /// the segment to B is tangent), i.e. where (B − P)·(P − C) turns from negative (B
    /// hidden behind the pulley) to zero — found by a scan and bisection to the last bit.
    /// Returns (exit point, wrap angle).
    fn exit_by_bisection(
        f: &Vector3<f64>,
        w: &Vector3<f64>,
        r: f64,
        b: &Vector3<f64>,
    ) -> (Vector3<f64>, f64) {
        let v = b - f;
        let u = (v - w * v.dot(w)).normalize();
        let c = f + u * r;
        let p = |t: f64| c + (-u * t.cos() + w * t.sin()) * r;
        let g = |t: f64| (b - p(t)).dot(&(p(t) - c));
        let steps = 4096;
        let mut lo = 0.0;
        let mut hi = f64::NAN;
        for k in 1..=steps {
            let t = TAU * k as f64 / steps as f64;
            if g(t) >= 0.0 {
                hi = t;
                break;
            }
            lo = t;
        }
        assert!(hi.is_finite(), "no tangent point found");
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if g(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        // The path length is stationary there: its derivative R (1 − cos α) (α: the angle
        // between the segment and the circle's tangent) vanishes, to the central
        // difference's own error (h = 1e-5: ~1e-10 · R).
        let path = |t: f64| r * t + (b - p(t)).norm();
        let t = 0.5 * (lo + hi);
        let h = 1e-5;
        assert!(((path(t + h) - path(t - h)) / (2.0 * h)).abs() < 1e-8 * r.max(1e-3));
        (p(t), t)
    }

    #[test]
    fn closed_form_equals_the_path_length_minimum_construction() {
        // 2000 random pulleys (axis, radius 0.01-0.3 m) and attachment points 0.4-3 m away
        // in every direction (wraps from ~0 to nearly 2π). Tolerance 1e-12 (m, rad): both
        // sides are accurate to a few ulps of the 1-3 m coordinates.
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mut max_wrap: f64 = 0.0;
        let mut checked = 0;
        for _ in 0..2000 {
            let w = rng.unit();
            let f = rng.unit() * 2.0;
            let r = 0.01 + 0.29 * rng.next();
            let b = f + rng.unit() * (0.4 + 2.6 * rng.next());
            let p = Pulley {
                entry_unit: w,
                radius_m: r,
            };
            // A point inside the circle (possible up to 0.6 m from F) has no tangent.
            let Ok(e) = pulley_exit(0, &f, &p, &b) else {
                assert!((b - (f + (b - f - w * (b - f).dot(&w)).normalize() * r)).norm() <= r);
                continue;
            };
            checked += 1;
            let (a_ref, phi_ref) = exit_by_bisection(&f, &w, r, &b);
            let l_ref = (b - a_ref).norm();
            assert!((e.exit_m - a_ref).norm() < 1e-12, "{e:?} vs {a_ref}");
            assert!(
                (e.wrap_rad - phi_ref).abs() < 1e-12,
                "{} vs {phi_ref}",
                e.wrap_rad
            );
            assert!((e.free_length_m - l_ref).abs() < 1e-12);
            assert!((e.unit - (b - a_ref) / l_ref).norm() < 1e-12);
            assert!((e.wrap_arc_m - r * phi_ref).abs() < 1e-12);
            assert!((e.unit.norm() - 1.0).abs() < 1e-14);
            max_wrap = max_wrap.max(e.wrap_rad);
        }
        assert!(
            max_wrap > 1.25 * PI,
            "the sample reaches wraps beyond π: {max_wrap}"
        );
        assert!(checked > 1900, "{checked}");
    }

    #[test]
    fn radius_zero_is_the_anchor() {
        // R = 0: the exit point is the anchor exactly, the direction and length those of the
        // straight chord to rounding (a few ulps), the wrap arc 0.
        let mut rng = Rng(12345);
        for _ in 0..500 {
            let w = rng.unit();
            let f = rng.unit() * 2.0;
            let b = f + rng.unit() * (0.4 + 2.6 * rng.next());
            let p = Pulley {
                entry_unit: w,
                radius_m: 0.0,
            };
            let e = pulley_exit(0, &f, &p, &b).unwrap();
            let l = (b - f).norm();
            assert_eq!(e.exit_m, f);
            assert_eq!(e.wrap_arc_m, 0.0);
            assert!((e.free_length_m - l).abs() <= 4.0 * f64::EPSILON * l);
            assert!((e.unit - (b - f) / l).norm() <= 4.0 * f64::EPSILON);
            assert!(e.softening_per_m.abs() <= 1e-14 / l);
        }
    }

    #[test]
    fn the_stiffness_term_is_the_derivative_of_the_direction() {
        // ∂s/∂B = m mᵀ/L + (sin φ / a) n nᵀ = (I − s sᵀ)/L + softening n nᵀ against central
        // differences of the closed form (h = 1e-6 m: truncation ~h²·|s'''| ~ 1e-12, rounding
        // ~1e-16/h = 1e-10, so 1e-8 relative to 1/L).
        let mut rng = Rng(777);
        for _ in 0..200 {
            let w = rng.unit();
            let f = Vector3::zeros();
            let r = 0.02 + 0.2 * rng.next();
            let b = rng.unit() * (0.5 + 2.0 * rng.next());
            let p = Pulley {
                entry_unit: w,
                radius_m: r,
            };
            let Ok(e) = pulley_exit(0, &f, &p, &b) else {
                continue;
            };
            let h = 1e-6;
            let mut fd = Matrix3::zeros();
            for j in 0..3 {
                let mut d = Vector3::zeros();
                d[j] = h;
                let sp = pulley_exit(0, &f, &p, &(b + d)).unwrap().unit;
                let sm = pulley_exit(0, &f, &p, &(b - d)).unwrap().unit;
                fd.set_column(j, &((sp - sm) / (2.0 * h)));
            }
            let s = e.unit;
            let k = (Matrix3::identity() - s * s.transpose()) / e.free_length_m
                + e.normal * e.normal.transpose() * e.softening_per_m;
            assert!((fd - k).norm() < 1e-8 / e.free_length_m, "{fd} vs {k}");
            assert!(e.softening_per_m <= 0.0);
        }
    }

    #[test]
    fn the_exit_jacobian_is_the_derivative_of_the_exit_point() {
        // ∂A/∂B in closed form against central differences of the closed-form exit point
        // (h = 1e-6 m: truncation ~h²·R/L² ~ 1e-13, rounding ~1e-16·|A|/h ~ 1e-10; 1e-8).
        let mut rng = Rng(4242);
        let mut seen = 0;
        for _ in 0..200 {
            let w = rng.unit();
            let f = rng.unit();
            let r = 0.02 + 0.2 * rng.next();
            let b = f + rng.unit() * (0.5 + 2.0 * rng.next());
            let p = Pulley {
                entry_unit: w,
                radius_m: r,
            };
            let Ok(e) = pulley_exit(0, &f, &p, &b) else {
                continue;
            };
            let h = 1e-6;
            let mut fd = Matrix3::zeros();
            for j in 0..3 {
                let d = Vector3::ith(j, h);
                let ap = pulley_exit(0, &f, &p, &(b + d)).unwrap().exit_m;
                let am = pulley_exit(0, &f, &p, &(b - d)).unwrap().exit_m;
                fd.set_column(j, &((ap - am) / (2.0 * h)));
            }
            let k = e.exit_jacobian();
            assert!((fd - k).norm() < 1e-8, "{fd} vs {k}");
            seen += 1;
        }
        assert!(seen > 150, "{seen}");
    }

    #[test]
    fn refused_poses_are_named() {
        let p = Pulley {
            entry_unit: Vector3::z(),
            radius_m: 0.1,
        };
        let f = Vector3::zeros();
        // On the swivel axis.
        assert!(matches!(
            pulley_exit(3, &f, &p, &Vector3::new(0.0, 0.0, -1.0)),
            Err(KinematicsError::AlongSwivelAxis { cable: 3, .. })
        ));
        // Inside the circle (centre (0.05, 0, 0) for a point 0.05 m off the axis).
        assert!(matches!(
            pulley_exit(1, &f, &p, &Vector3::new(0.05, 0.0, 0.02)),
            Err(KinematicsError::InsidePulley { cable: 1, .. })
        ));
        // Just outside it: accepted.
        assert!(pulley_exit(1, &f, &p, &Vector3::new(0.25, 0.0, 0.0)).is_ok());
    }
}
