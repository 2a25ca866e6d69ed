//! The transfer-matrix form of the condensation, for λ beyond the polynomial kernels (a
//! sub-segment's phase φ > 1.5): robust where a sub-segment nears its own fixed–fixed
//! eigenvalue (sin φ → 0), where the symmetric form's D, e blow up and D² − e² cancels.
//!
//! Per principal direction, with C = cos √z, Sn = sin √z/√z (`kernel::general`), the
//! transfer matrix of (u, p = k u′) is
//!
//! ```text
//!   u₊ = a u + b p,  p₊ = c u + a p,   a = C,  b = c ℓ · Sn,  c = −λ μ ℓ · Sn
//! ```
//!
//! and S = P U⁻¹ maps through a sub-segment as S₊ = (c + a S)(a + b S)⁻¹ (a, b, c diagonal
//! in its principal frame), from S₁ = a b⁻¹ at the fixed anchor. The count is that of the
//! symmetric form (Σ own + the pivots b⁻¹ a + S, whose inertia is that of a + b S when
//! b > 0).

use super::junction::{junction_start, De, Junction};
use super::kernel;
use super::kernel::{neg2, nonzero, rotate};
use super::Segment;

/// One direction's transfer coefficients (a, b, c) and their λ-derivatives, and √z.
#[derive(Clone, Copy)]
struct Dir {
    a: f64,
    b: f64,
    c: f64,
    da: f64,
    db: f64,
    dc: f64,
    own: u32,
}

#[inline]
fn dir(q: f64, k: f64, mul: f64, lambda: f64) -> Dir {
    let z = lambda * q;
    let f = kernel::general(z);
    let cl = 1.0 / k;
    Dir {
        a: f.c,
        b: cl * f.sn,
        c: -lambda * mul * f.sn,
        da: -0.5 * q * f.sn,
        db: cl * q * f.sp,
        dc: -mul * (f.sn + z * f.sp),
        own: f.own,
    }
}

/// A direction's D = a/b, e = 1/b, x = (a − 1)/b and their λ-derivatives (the fixed–fixed
/// dynamic stiffness from the transfer coefficients; `b` nonzero; this form runs at large
/// λ only, where a − 1 has no cancellation).
fn de_of(d: &Dir, b: f64) -> De {
    let r = 1.0 / b;
    De {
        d: d.a * r,
        e: r,
        x: (d.a - 1.0) * r,
        dd: (d.da * b - d.a * d.db) * r * r,
        de: -d.db * r * r,
    }
}

/// In-plane condensation: (S, dS/dλ) in the (h, up) basis and the blocked count;
/// `junction`: the anchor node on the hidden cable (None: fixed).
pub(super) fn eval_in(
    segs: &[Segment],
    final_rot: [f64; 2],
    lambda: f64,
    junction: Option<&Junction>,
) -> ([f64; 3], [f64; 3], u32) {
    let mut s = [0.0; 3];
    let mut ds = [0.0; 3];
    let mut below = 0u32;
    for (i, g) in segs.iter().enumerate() {
        let d1 = dir(g.q[0], g.k[0], g.mul, lambda);
        let d2 = dir(g.q[1], g.k[1], g.mul, lambda);
        below += d1.own + d2.own;
        if i == 0 {
            // From the fixed anchor: S = a b⁻¹ per direction.
            let b1 = nonzero(d1.b, 1.0 / g.k[0]);
            let b2 = nonzero(d2.b, 1.0 / g.k[1]);
            if let Some(j) = junction {
                let (s1, ds1, b) = junction_start(de_of(&d1, b1), de_of(&d2, b2), j);
                (s, ds) = (s1, ds1);
                below += b;
                continue;
            }
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
            let p11 = d1.a / nonzero(d1.b, 1.0 / g.k[0]) + s11;
            let p22 = d2.a / nonzero(d2.b, 1.0 / g.k[1]) + s22;
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
        let d = dir(g.q[2], g.k[2], g.mul, lambda);
        below += d.own;
        if i == 0 {
            let b = nonzero(d.b, 1.0 / g.k[2]);
            s = d.a / b;
            ds = (d.da * b - d.a * d.db) / (b * b);
            continue;
        }
        let m = d.a + d.b * s;
        below += if d.b > 0.0 {
            (m < 0.0) as u32
        } else {
            (d.a / nonzero(d.b, 1.0 / g.k[2]) + s < 0.0) as u32
        };
        let m = nonzero(m, d.a);
        let t = (d.c + d.a * s) / m;
        let dm = d.da + d.db * s + d.b * ds;
        ds = (d.dc + d.da * s + d.a * ds - t * dm) / m;
        s = t;
    }
    (s, ds, below)
}
