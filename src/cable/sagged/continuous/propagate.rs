//! The λ-dependent half of the continuous sagged cable: a chain of exact uniform straight
//! sub-segments, condensed from the anchor to the end by the Riccati (Möbius) recursion of
//! their transfer matrices, with the Wittrick–Williams count of the blocked eigenvalues.
//!
//! A uniform sub-segment of length ℓ, compliance c (1/stiffness) and mass μ per length has,
//! per principal direction, with z = λ μ c ℓ², C = cos √z, Sn = sin √z / √z (cosh, sinh for
//! z < 0), the transfer matrix of (u, p = k u′):
//!
//! ```text
//!   u₊ = a u + b p,  p₊ = c u + a p,   a = C,  b = c ℓ · Sn,  c = −λ μ ℓ · Sn
//! ```
//!
//! The end stiffness of the cable up to a node, S = P U⁻¹, maps through a sub-segment as
//! S₊ = (c + a S)(a + b S)⁻¹ (a, b, c diagonal in the sub-segment's principal frame). The
//! first sub-segment starts from the fixed anchor (S = ∞): S₁ = a b⁻¹. Wittrick–Williams:
//! the blocked eigenvalues below λ are Σ J₀ (each sub-segment's own fixed-fixed eigenvalues
//! below λ: the n ≥ 1 with nπ < √z per direction) plus the negative eigenvalues of the
//! pivots b⁻¹ a + S at the interior nodes; with b > 0 (√z < π) the pivot has the inertia
//! of a + b^½ S b^½, whose determinant and trace are those of M = a + b S.

use super::Segment;

/// Below this |z| the functions of z are summed as their Taylor series (terms to z⁶; the
/// first omitted term is below 0.1⁷/14! < 1e-18): cos √z, sin √z/√z and the derivative
/// (C − Sn)/(2z), which cancels there, are then exact to rounding.
const SERIES_MAX_Z: f64 = 0.1;
/// Below this z (rad², λ < 0) cosh √z would overflow within the cable: z is clamped (the
/// eval stays finite; λ that negative is far outside any use).
const MIN_Z: f64 = -1.0e4;

/// cos √z, sin √z / √z, d(sin √z / √z)/dz and √z (0 for z ≤ 0).
#[derive(Clone, Copy)]
struct Fz {
    a: f64,
    sn: f64,
    sp: f64,
    phi: f64,
}

#[inline]
fn fz(z: f64) -> Fz {
    if z.abs() < SERIES_MAX_Z {
        // Σ (−z)ⁿ/(2n)!, Σ (−z)ⁿ/(2n+1)!, Σ n (−1)ⁿ zⁿ⁻¹/(2n+1)!
        let a = 1.0
            + z * (-1.0 / 2.0
                + z * (1.0 / 24.0
                    + z * (-1.0 / 720.0
                        + z * (1.0 / 40320.0 + z * (-1.0 / 3628800.0 + z / 479001600.0)))));
        let sn = 1.0
            + z * (-1.0 / 6.0
                + z * (1.0 / 120.0
                    + z * (-1.0 / 5040.0
                        + z * (1.0 / 362880.0 + z * (-1.0 / 39916800.0 + z / 6227020800.0)))));
        let sp = -1.0 / 6.0
            + z * (2.0 / 120.0
                + z * (-3.0 / 5040.0
                    + z * (4.0 / 362880.0 + z * (-5.0 / 39916800.0 + z * 6.0 / 6227020800.0))));
        return Fz {
            a,
            sn,
            sp,
            phi: z.max(0.0).sqrt(),
        };
    }
    if z > 0.0 {
        let phi = z.sqrt();
        let (s, c) = phi.sin_cos();
        let sn = s / phi;
        Fz {
            a: c,
            sn,
            sp: (c - sn) / (2.0 * z),
            phi,
        }
    } else {
        let zc = z.max(MIN_Z);
        let r = (-zc).sqrt();
        let e = r.exp();
        let (ch, sh) = (0.5 * (e + 1.0 / e), 0.5 * (e - 1.0 / e));
        let sn = sh / r;
        Fz {
            a: ch,
            sn,
            sp: (ch - sn) / (2.0 * zc),
            phi: 0.0,
        }
    }
}

/// One direction's transfer coefficients (a, b, c) and their λ-derivatives, and √z.
#[derive(Clone, Copy)]
struct Dir {
    a: f64,
    b: f64,
    c: f64,
    da: f64,
    db: f64,
    dc: f64,
    phi: f64,
}

#[inline]
fn dir(q: f64, cl: f64, mul: f64, lambda: f64) -> Dir {
    let z = lambda * q;
    let f = fz(z);
    Dir {
        a: f.a,
        b: cl * f.sn,
        c: -lambda * mul * f.sn,
        da: -0.5 * q * f.sn,
        db: cl * q * f.sp,
        dc: -mul * (f.sn + z * f.sp),
        phi: f.phi,
    }
}

/// The sub-segment's own fixed-fixed eigenvalues below λ in one direction: n ≥ 1, nπ < √z.
#[inline]
fn j0(phi: f64) -> u32 {
    if phi <= 0.0 {
        0
    } else {
        ((phi / std::f64::consts::PI).ceil() - 1.0).max(0.0) as u32
    }
}

/// Replaces an exact zero divisor by a tiny one of the given scale (a pivot that is zero to
/// the last bit: λ on a node's conjugate point; counted as non-negative).
#[inline]
fn nonzero(x: f64, scale: f64) -> f64 {
    if x == 0.0 {
        f64::MIN_POSITIVE.max(f64::EPSILON * f64::EPSILON * scale.abs())
    } else {
        x
    }
}

/// Negative eigenvalues of a symmetric 2 × 2 matrix from its determinant and trace.
#[inline]
fn neg2(det: f64, tr: f64) -> u32 {
    if det < 0.0 {
        1
    } else if det > 0.0 && tr < 0.0 {
        2
    } else if det == 0.0 && tr < 0.0 {
        1
    } else {
        0
    }
}

/// Δᵀ S Δ for symmetric S = [s11, s12, s22] and the rotation Δ = [[c, −s], [s, c]].
#[inline]
fn rotate(m: [f64; 3], c: f64, s: f64) -> [f64; 3] {
    let (cc, ss, cs) = (c * c, s * s, c * s);
    [
        cc * m[0] + 2.0 * cs * m[1] + ss * m[2],
        -cs * m[0] + (cc - ss) * m[1] + cs * m[2],
        ss * m[0] - 2.0 * cs * m[1] + cc * m[2],
    ]
}

/// In-plane condensation: (S, dS/dλ) in the (h, up) basis and the blocked count.
pub(super) fn eval_in(
    segs: &[Segment],
    final_rot: [f64; 2],
    lambda: f64,
) -> ([f64; 3], [f64; 3], u32) {
    let mut s = [0.0; 3];
    let mut ds = [0.0; 3];
    let mut below = 0u32;
    for (i, g) in segs.iter().enumerate() {
        let d1 = dir(g.q[0], g.cl[0], g.mul, lambda);
        let d2 = dir(g.q[1], g.cl[1], g.mul, lambda);
        below += j0(d1.phi) + j0(d2.phi);
        if i == 0 {
            // From the fixed anchor: S = a b⁻¹ per direction.
            let b1 = nonzero(d1.b, g.cl[0]);
            let b2 = nonzero(d2.b, g.cl[1]);
            s = [d1.a / b1, 0.0, d2.a / b2];
            ds = [
                (d1.da * b1 - d1.a * d1.db) / (b1 * b1),
                0.0,
                (d2.da * b2 - d2.a * d2.db) / (b2 * b2),
            ];
            continue;
        }
        s = rotate(s, g.rot[0], g.rot[1]);
        ds = rotate(ds, g.rot[0], g.rot[1]);
        let (s11, s12, s22) = (s[0], s[1], s[2]);
        let m11 = d1.a + d1.b * s11;
        let m12 = d1.b * s12;
        let m21 = d2.b * s12;
        let m22 = d2.a + d2.b * s22;
        let det = m11 * m22 - m12 * m21;
        below += if d1.b > 0.0 && d2.b > 0.0 {
            neg2(det, m11 + m22)
        } else {
            // Beyond a sub-segment's first own eigenvalue: the pivot b⁻¹a + S itself.
            let p11 = d1.a / nonzero(d1.b, g.cl[0]) + s11;
            let p22 = d2.a / nonzero(d2.b, g.cl[1]) + s22;
            neg2(p11 * p22 - s12 * s12, p11 + p22)
        };
        let det = nonzero(det, m11 * m22);
        let n11 = d1.c + d1.a * s11;
        let n12 = d1.a * s12;
        let n21 = d2.a * s12;
        let n22 = d2.c + d2.a * s22;
        // S₊ = N M⁻¹ (symmetric in exact arithmetic: the off-diagonals are averaged).
        let t11 = (n11 * m22 - n12 * m21) / det;
        let t12 = (n12 * m11 - n11 * m12) / det;
        let t21 = (n21 * m22 - n22 * m21) / det;
        let t22 = (n22 * m11 - n21 * m12) / det;
        // dS₊ = (dN − S₊ dM) M⁻¹.
        let dm11 = d1.da + d1.db * s11 + d1.b * ds[0];
        let dm12 = d1.db * s12 + d1.b * ds[1];
        let dm21 = d2.db * s12 + d2.b * ds[1];
        let dm22 = d2.da + d2.db * s22 + d2.b * ds[2];
        let r11 = d1.dc + d1.da * s11 + d1.a * ds[0] - (t11 * dm11 + t12 * dm21);
        let r12 = d1.da * s12 + d1.a * ds[1] - (t11 * dm12 + t12 * dm22);
        let r21 = d2.da * s12 + d2.a * ds[1] - (t21 * dm11 + t22 * dm21);
        let r22 = d2.dc + d2.da * s22 + d2.a * ds[2] - (t21 * dm12 + t22 * dm22);
        let e11 = (r11 * m22 - r12 * m21) / det;
        let e12 = (r12 * m11 - r11 * m12) / det;
        let e21 = (r21 * m22 - r22 * m21) / det;
        let e22 = (r22 * m11 - r21 * m12) / det;
        s = [t11, 0.5 * (t12 + t21), t22];
        ds = [e11, 0.5 * (e12 + e21), e22];
    }
    // Last sub-segment's frame → (h, up): rotate by −θ.
    let (c, sn) = (final_rot[0], -final_rot[1]);
    (rotate(s, c, sn), rotate(ds, c, sn), below)
}

/// Out-of-plane condensation: (s, ds/dλ) and the blocked count.
pub(super) fn eval_out(segs: &[Segment], lambda: f64) -> (f64, f64, u32) {
    let mut s = 0.0;
    let mut ds = 0.0;
    let mut below = 0u32;
    for (i, g) in segs.iter().enumerate() {
        let d = dir(g.q[2], g.cl[2], g.mul, lambda);
        below += j0(d.phi);
        if i == 0 {
            let b = nonzero(d.b, g.cl[2]);
            s = d.a / b;
            ds = (d.da * b - d.a * d.db) / (b * b);
            continue;
        }
        let m = d.a + d.b * s;
        below += if d.b > 0.0 {
            (m < 0.0) as u32
        } else {
            (d.a / nonzero(d.b, g.cl[2]) + s < 0.0) as u32
        };
        let m = nonzero(m, d.a);
        let t = (d.c + d.a * s) / m;
        let dm = d.da + d.db * s + d.b * ds;
        ds = (d.dc + d.da * s + d.a * ds - t * dm) / m;
        s = t;
    }
    (s, ds, below)
}
