//! The λ-dependent functions of one uniform sub-segment, per principal direction, at
//! z = λ μ c ℓ² (φ = √z its phase): C = cos √z, Sn = sin √z/√z (cosh, sinh for z < 0),
//! Sp = dSn/dz, and from them x = (C − 1)/Sn = −φ tan(φ/2), h = 1/Sn = φ/sin φ and their
//! z-derivatives (see `propagate` for their use).
//!
//! All are entire (C, Sn, Sp) or analytic for |z| < π² (x, h): on |z| ≤ `Z_MID` they are
//! summed as truncated Taylor polynomials (no sqrt, no trigonometry) whose first omitted
//! term is below 1e-17, i.e. exact to rounding; the evaluation picks, per direction, the
//! shortest polynomial valid for the largest |z| of the cable (`Z_TINY`, `Z_SMALL`: the
//! series of x, h directly, no division; `Z_MID`: C, Sn, Sp, one division). Beyond, `general` uses the
//! library's trigonometry (or exp for z < 0).

/// The 6-term series of x and h (`tiny`) hold for |z| ≤ this.
pub(super) const Z_TINY: f64 = 4e-3;
/// The 10-term series of x and h (`small`) hold for |z| ≤ this, as do the short
/// polynomials of C, Sn, Sp (first omitted terms: C 0.1⁷/14! < 1.2e-18, Sn 0.1⁷/15! <
/// 1e-19, Sp 7·0.1⁶/15! < 6e-19) that cross-check them.
pub(super) const Z_SMALL: f64 = 0.1;
/// Long polynomials hold for |z| ≤ this (φ ≤ 1.5, the mesh's phase bound per sub-segment at
/// λ_max; first omitted terms: C 2.25¹¹/22! < 6.7e-18, Sn 2.25¹¹/23! < 3e-19,
/// Sp 11·2.25¹⁰/23! < 1.5e-18).
pub(super) const Z_MID: f64 = 2.25;
/// Below this z (λ < 0) cosh √z would overflow within the cable: z is clamped (the eval
/// stays finite; λ that negative is far outside any use).
const MIN_Z: f64 = -1.0e4;

/// What the symmetric recursion needs per direction, per unit static stiffness k = 1/(cℓ):
/// x = (C − 1)/Sn = −φ tan(φ/2), h = 1/Sn = φ/sin φ and their z-derivatives
/// (then D = k (x + h), e = k h, dD/dλ = μℓ (x′ + h′), de/dλ = μℓ h′).
#[derive(Clone, Copy)]
pub(super) struct Xh {
    pub x: f64,
    pub h: f64,
    pub dx: f64,
    pub dh: f64,
}

/// Terms of the division-free series of h and x (to z⁹).
const XH_TERMS: usize = 10;

/// The Taylor coefficients of h = 1/Sn and x = (C − 1)/Sn, by series division of the
/// factorial series at compile time: h₀ = 1, hₙ = −Σⱼ₌₁ⁿ sⱼ hₙ₋ⱼ; xₙ = Σⱼ₌₁ⁿ cⱼ hₙ₋ⱼ
/// (sⱼ = (−1)ʲ/(2j+1)!, cⱼ = (−1)ʲ/(2j)!): h = 1 + z/6 + 7z²/360 + …,
/// x = −(z/2 + z²/24 + z³/240 + …). Both have radius π² (φ = π) and coefficients
/// ≈ 2/π²ⁿ (h) and 4/π²ⁿ (x).
const XH_COEF: [[f64; XH_TERMS]; 2] = {
    let mut h = [0.0; XH_TERMS];
    let mut x = [0.0; XH_TERMS];
    h[0] = 1.0;
    let mut n = 1;
    while n < XH_TERMS {
        let (mut hn, mut xn) = (0.0, 0.0);
        let mut j = 1;
        while j <= n {
            hn -= S_COEF[j] * h[n - j];
            xn += C_COEF[j] * h[n - j];
            j += 1;
        }
        h[n] = hn;
        x[n] = xn;
        n += 1;
    }
    [h, x]
};

/// x, h and their derivatives from the first `N` terms of their series (no division).
#[inline(always)]
fn series<const N: usize>(z: f64) -> Xh {
    let (hc, xc) = (&XH_COEF[0][..N], &XH_COEF[1][..N]);
    let d = |c: &[f64]| {
        c.iter()
            .enumerate()
            .skip(1)
            .rev()
            .fold(0.0, |acc, (k, &ck)| acc * z + k as f64 * ck)
    };
    Xh {
        x: horner(xc, z),
        h: horner(hc, z),
        dx: d(xc),
        dh: d(hc),
    }
}

/// |z| ≤ Z_TINY: the series to z⁵ (first omitted terms ≈ 4 (z/π²)⁶ < 2e-20; derivatives
/// 24 z⁵/π¹² < 3e-17).
#[inline(always)]
pub(super) fn tiny(z: f64) -> Xh {
    series::<6>(z)
}

/// |z| ≤ Z_SMALL: the series to z⁹ (first omitted terms ≈ 4 (z/π²)¹⁰ < 5e-20; derivatives
/// 40 z⁹/π²⁰ < 5e-18).
#[inline(always)]
pub(super) fn small(z: f64) -> Xh {
    series::<XH_TERMS>(z)
}

/// x, h and derivatives from C − 1, Sn, Sp (one division): h′ = −Sp/Sn²,
/// x′ = d((C − 1)/Sn)/dz = −½ − x Sp/Sn (with dC/dz = −Sn/2).
#[inline(always)]
fn xh(f: Csp) -> Xh {
    // Sn ≥ sin 1.5/1.5 > 0.66 on the polynomials' range: no zero divisor.
    let r = 1.0 / f.sn;
    let x = f.cm1 * r;
    Xh {
        x,
        h: r,
        dx: -0.5 - x * f.sp * r,
        dh: -f.sp * r * r,
    }
}

/// |z| ≤ Z_SMALL, through C, Sn, Sp (the cross-check of `small`).
/// Replaces an exact zero divisor by a tiny one of the given scale (a pivot that is zero to
/// the last bit: λ on a node's conjugate point; counted as non-negative).
#[inline(always)]
pub(super) fn nonzero(x: f64, scale: f64) -> f64 {
    if x == 0.0 {
        f64::MIN_POSITIVE.max(f64::EPSILON * f64::EPSILON * scale.abs())
    } else {
        x
    }
}

/// Negative eigenvalues of a symmetric 2 × 2 matrix from its determinant and trace.
#[inline(always)]
pub(super) fn neg2(det: f64, tr: f64) -> u32 {
    if det < 0.0 {
        1
    } else if tr < 0.0 {
        // det > 0: both negative; det = 0: one zero, one negative.
        if det > 0.0 {
            2
        } else {
            1
        }
    } else {
        0
    }
}

/// Δᵀ S Δ for symmetric S = [s11, s12, s22] and the rotation Δ = [[c, −s], [s, c]].
#[inline(always)]
pub(super) fn rotate(m: [f64; 3], c: f64, s: f64) -> [f64; 3] {
    let (cc, ss, cs) = (c * c, s * s, c * s);
    let x = cs * (m[2] - m[0]);
    [
        cc * m[0] + 2.0 * cs * m[1] + ss * m[2],
        x + (cc - ss) * m[1],
        ss * m[0] - 2.0 * cs * m[1] + cc * m[2],
    ]
}

#[cfg(test)]
pub(super) fn small_div(z: f64) -> Xh {
    xh(small_csp(z))
}

/// |z| ≤ Z_MID.
#[inline(always)]
pub(super) fn mid(z: f64) -> Xh {
    xh(mid_csp(z))
}

/// C = cos √z, C − 1 (formed without cancellation), Sn = sin √z/√z, Sp = dSn/dz, and the
/// sub-segment's own fixed–fixed eigenvalues below z (n ≥ 1 with nπ < √z).
#[derive(Clone, Copy)]
pub(super) struct Csp {
    pub c: f64,
    pub cm1: f64,
    pub sn: f64,
    pub sp: f64,
    pub own: u32,
}

/// Σ (−z)ⁿ/(2n)!, Σ (−z)ⁿ/(2n+1)!, Σ n (−1)ⁿ zⁿ⁻¹/(2n+1)! to z⁶ (|z| ≤ Z_SMALL).
#[cfg(test)]
pub(super) fn small_csp(z: f64) -> Csp {
    let cm1 = z
        * (-1.0 / 2.0
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
    Csp {
        c: 1.0 + cm1,
        cm1,
        sn,
        sp,
        own: 0,
    }
}

/// Taylor coefficients of C = Σ cₙ zⁿ, cₙ = (−1)ⁿ/(2n)!, n = 0..=10.
const C_COEF: [f64; 11] = taylor(0);
/// Taylor coefficients of Sn: (−1)ⁿ/(2n+1)!, n = 0..=10.
const S_COEF: [f64; 11] = taylor(1);

/// Taylor coefficients of Sp = dSn/dz: (n + 1) s₍ₙ₊₁₎, n = 0..=9.
const SP_COEF: [f64; 10] = {
    let mut out = [0.0; 10];
    let mut n = 0;
    while n < 10 {
        out[n] = (n + 1) as f64 * S_COEF[n + 1];
        n += 1;
    }
    out
};

/// (−1)ⁿ/(2n + off)! for n = 0..=10.
const fn taylor(off: u64) -> [f64; 11] {
    let mut out = [0.0; 11];
    let mut n = 0;
    while n < 11 {
        let mut f = 1.0;
        let mut k = 2 * n as u64 + off;
        while k > 1 {
            f *= k as f64;
            k -= 1;
        }
        out[n] = if n % 2 == 0 { 1.0 / f } else { -1.0 / f };
        n += 1;
    }
    out
}

#[inline(always)]
fn horner(coef: &[f64], z: f64) -> f64 {
    coef.iter().rev().fold(0.0, |acc, &c| acc * z + c)
}

/// C, Sn to z¹⁰ and Sp to z⁹ (|z| ≤ Z_MID).
#[inline(always)]
pub(super) fn mid_csp(z: f64) -> Csp {
    let cm1 = z * horner(&C_COEF[1..], z);
    Csp {
        c: 1.0 + cm1,
        cm1,
        sn: horner(&S_COEF, z),
        sp: horner(&SP_COEF, z),
        own: 0,
    }
}

/// Any z: the polynomials where they hold, the library's functions beyond.
#[inline]
pub(super) fn general(z: f64) -> Csp {
    if z.abs() <= Z_MID {
        return mid_csp(z);
    }
    if z > 0.0 {
        let phi = z.sqrt();
        let (s, c) = phi.sin_cos();
        let sn = s / phi;
        // The sub-segment's own fixed-fixed eigenvalues below z: n ≥ 1 with nπ < φ.
        let own = ((phi / std::f64::consts::PI).ceil() - 1.0).max(0.0) as u32;
        // 1 − cos φ = 2 sin²(φ/2).
        let sh = (0.5 * phi).sin();
        Csp {
            c,
            cm1: -2.0 * sh * sh,
            sn,
            sp: (c - sn) / (2.0 * z),
            own,
        }
    } else {
        let zc = z.max(MIN_Z);
        let r = (-zc).sqrt();
        let e = r.exp();
        let (ch, sh) = (0.5 * (e + 1.0 / e), 0.5 * (e - 1.0 / e));
        let sn = sh / r;
        // cosh r − 1 = 2 sinh²(r/2).
        let sh2 = (0.5 * r).sinh();
        Csp {
            c: ch,
            cm1: 2.0 * sh2 * sh2,
            sn,
            sp: (ch - sn) / (2.0 * zc),
            own: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The polynomials against the library's trigonometry over their ranges: C and Sn to
    /// 3e-16 absolute, C − 1 to 8e-16 relative (a few roundings on either side: the
    /// reference −2 sin²(φ/2) has ~3 ulp; the truncation is below 1e-17), Sp against
    /// (C − Sn)/(2z) to 1e-13 where that difference loses at most 3 digits (z > 1e-2).
    #[test]
    fn polynomials_match_trigonometry() {
        for i in 1..=400 {
            let z = Z_MID * i as f64 / 400.0;
            let phi = z.sqrt();
            let (s, c) = phi.sin_cos();
            let sn = s / phi;
            let cm1 = -2.0 * (0.5 * phi).sin().powi(2);
            let sp = (c - sn) / (2.0 * z);
            let mut tiers = vec![mid_csp(z), general(z), mid_csp(-z)];
            if z <= Z_SMALL {
                tiers.push(small_csp(z));
            }
            for (j, k) in tiers.into_iter().enumerate() {
                if j == 2 {
                    // Negative z: cosh, sinh.
                    let ch = phi.cosh();
                    assert!((k.c - ch).abs() <= 3e-16 * ch, "z −{z} C");
                    assert!((k.sn - phi.sinh() / phi).abs() <= 3e-16 * ch, "z −{z} Sn");
                    continue;
                }
                assert!((k.c - c).abs() <= 3e-16, "z {z} C");
                assert!((k.cm1 - cm1).abs() <= 8e-16 * cm1.abs(), "z {z} C − 1");
                assert!((k.sn - sn).abs() <= 3e-16, "z {z} Sn");
                if z > 1e-2 {
                    assert!((k.sp - sp).abs() <= 1e-13 * sp.abs(), "z {z} Sp");
                }
            }
        }
    }

    /// The x, h kernels agree where their ranges overlap (z ∈ [−Z_SMALL, Z_SMALL]; the
    /// division-free series against C, Sn, Sp and a division): x, h, x′, h′ to 4e-16
    /// (a few roundings, no cancellation on either side).
    #[test]
    fn kernels_agree_on_overlaps() {
        for i in 0..=400 {
            for z in [Z_SMALL * i as f64 / 400.0, -Z_SMALL * i as f64 / 400.0] {
                let t = small(z);
                let mut others = vec![small_div(z), mid(z)];
                if z.abs() <= Z_TINY {
                    others.push(tiny(z));
                }
                for k in others {
                    assert!((k.x - t.x).abs() <= 4e-16, "z {z} x");
                    assert!((k.h - t.h).abs() <= 4e-16, "z {z} h");
                    assert!((k.dx - t.dx).abs() <= 4e-16, "z {z} x′");
                    assert!((k.dh - t.dh).abs() <= 4e-16, "z {z} h′");
                }
            }
        }
    }
}
