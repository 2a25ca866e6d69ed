//! Many chains at one λ: the discrete chains of one element count by the Chebyshev
//! recurrence and the continuous chains by a branch-free cot, both in fixed blocks of
//! [`LANES`] chains that vectorize, with an AVX2 build of the same operations (so the same
//! results) chosen at run time.

use super::chain::eval_continuous;
use super::ChainEval;

/// Smallest φ the batched continuous form takes: below it the scalar form's series is
/// used (φ cot φ → 1 loses digits in a quotient of kernels).
const BATCH_PHI_MIN: f64 = 1e-3;
/// Largest φ the batched continuous form takes: the two-part Cody-Waite reduction by π/2
/// is exact only up to about here.
const BATCH_PHI_MAX: f64 = 1e5;

/// Largest element count evaluated by [`eval_discrete_batch`] (above it the closed form
/// is cheaper than the O(N) recurrence).
pub const BATCH_MAX_ELEMENTS: usize = 64;

crate::simd::dispatch! {
    /// Several uniform chains with the same element count `n_el`
    /// (2 ..= [`BATCH_MAX_ELEMENTS`]) at one λ, by the Chebyshev recurrence in differential
    /// form, written chain-innermost so the chains run side by side (no trigonometry, no
    /// division inside the loop).
    ///
    /// With δ = 1 − c = ½λm/(k + λm/6) and U_j = U_j(1 − δ): D_j = U_j − U_{j−1} obeys
    /// D_{j+1} = D_j − 2δU_j, U_{j+1} = U_j + D_{j+1} (U_0 = D_0 = 1), which never forms
    /// 1 − U_{N−2}/U_{N−1} by cancellation. Then s = −λm/2 + (k + λm/6)·D_{N−1}/U_{N−1};
    /// the δ-derivatives follow the same recurrence; the blocked count is the number of
    /// sign changes of U_0 … U_{N−1} (Sturm: LDLᵀ pivots −β U_j/U_{j−1}, a zero counted
    /// positive).
    /// For δ < 3 (every λ ≥ 0) |U_j| ≤ 5^j, so nothing overflows for N ≤ 400.
    /// `k`, `m` (N/m, kg) are per element; results go to `out` (same length).
    ///
    /// Runs the portable body compiled for AVX2 when the CPU has it (the same IEEE
    /// operations in the same order, so bit-identical results).
    pub fn eval_discrete_batch(
        k: &[f64],
        m: &[f64],
        n_el: usize,
        lambda: f64,
        out: &mut [ChainEval],
    ) = batch_generic;
    features ["avx2"];
    tiers discrete_tier;
}

/// Chains per block of the batched evaluations (fixed-size lanes: no per-call clearing of
/// large scratch arrays, loops of constant trip count that vectorize).
const LANES: usize = 8;

#[inline(always)]
fn batch_generic(k: &[f64], m: &[f64], n_el: usize, lambda: f64, out: &mut [ChainEval]) {
    let n = k.len().min(m.len()).min(out.len());
    let mut start = 0;
    while start < n {
        let len = (n - start).min(LANES);
        // Padding lanes: a massless chain (δ = 0), never written out.
        let mut kk = [1.0f64; LANES];
        let mut mm = [0.0f64; LANES];
        kk[..len].copy_from_slice(&k[start..start + len]);
        mm[..len].copy_from_slice(&m[start..start + len]);
        let mut two_delta = [0.0f64; LANES];
        let mut u = [1.0f64; LANES];
        let mut dl = [1.0f64; LANES];
        let mut up = [0.0f64; LANES];
        let mut dp = [0.0f64; LANES];
        let mut below = [0u64; LANES];
        for i in 0..LANES {
            let kp = kk[i] + lambda * mm[i] / 6.0;
            two_delta[i] = lambda * mm[i] / kp;
        }
        for _ in 0..n_el.saturating_sub(1) {
            for i in 0..LANES {
                let t = two_delta[i];
                let dpn = dp[i] - 2.0 * u[i] - t * up[i];
                let dn = dl[i] - t * u[i];
                let un = u[i] + dn;
                up[i] += dpn;
                dp[i] = dpn;
                below[i] += (un.to_bits() ^ u[i].to_bits()) >> 63;
                dl[i] = dn;
                u[i] = un;
            }
        }
        for i in 0..len {
            let (ki, mi) = (kk[i], mm[i]);
            let kp = ki + lambda * mi / 6.0;
            let ratio = dl[i] / u[i];
            let dratio = (dp[i] * u[i] - dl[i] * up[i]) / (u[i] * u[i]);
            let ddelta = 0.5 * mi * ki / (kp * kp);
            out[start + i] = ChainEval {
                s: -0.5 * lambda * mi + kp * ratio,
                ds: -0.5 * mi + mi / 6.0 * ratio + kp * dratio * ddelta,
                below: below[i] as u32,
            };
        }
        start += len;
    }
}

/// sin r − r and cos r − 1 for |r| ≤ π/4 + 1e-9 (fdlibm's kernel polynomials, error
/// < 1 ulp of sin r and cos r; the differences without cancellation).
#[inline(always)]
#[allow(clippy::excessive_precision)] // fdlibm's coefficients as published
fn sin_cos_kernel(r: f64) -> (f64, f64) {
    const S1: f64 = -1.666_666_666_666_663_243_48e-1;
    const S2: f64 = 8.333_333_333_322_489_461_24e-3;
    const S3: f64 = -1.984_126_982_985_794_931_34e-4;
    const S4: f64 = 2.755_731_370_707_006_767_89e-6;
    const S5: f64 = -2.505_076_025_340_686_341_95e-8;
    const S6: f64 = 1.589_690_995_211_550_102_21e-10;
    const C1: f64 = 4.166_666_666_666_660_190_37e-2;
    const C2: f64 = -1.388_888_888_887_410_957_49e-3;
    const C3: f64 = 2.480_158_728_947_672_941_78e-5;
    const C4: f64 = -2.755_731_435_139_066_330_35e-7;
    const C5: f64 = 2.087_572_321_298_174_827_90e-9;
    const C6: f64 = -1.135_964_755_778_819_482_65e-11;
    let z = r * r;
    let ps = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
    let pc = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    (r * z * (S1 + z * ps), z * pc - 0.5 * z)
}

crate::simd::dispatch! {
    /// [`super::Chain::eval`] of several continuous chains (K, m per chain: `k`, `m`, N/m
    /// and kg) at one λ: one square root of λ, and cot φ from a Cody-Waite reduction by π/2
    /// (two parts; φ ≤ 1e5 here) and fdlibm's polynomial kernels instead of a library
    /// sin/cos per chain, branch-free so that it vectorizes (an AVX2 build is chosen at run
    /// time: the same operations, so the same results). Agrees with the scalar form within
    /// its conditioning (tested). Chains outside 1e-3 ≤ φ ≤ 1e5 (`BATCH_PHI_MIN`,
    /// `BATCH_PHI_MAX`), or with K or m ≤ 0, and λ ≤ 0 take the scalar form.
    pub fn eval_continuous_batch(
        k: &[f64],
        m: &[f64],
        lambda: f64,
        out: &mut [ChainEval],
    ) = continuous_generic;
    features ["avx2"];
    tiers continuous_tier;
}

#[inline(always)]
fn continuous_generic(k: &[f64], m: &[f64], lambda: f64, out: &mut [ChainEval]) {
    let n = k.len().min(m.len()).min(out.len());
    if !(lambda > 0.0) {
        for i in 0..n {
            out[i] = eval_continuous(k[i], m[i], lambda);
        }
        return;
    }
    let sl = lambda.sqrt();
    let mut start = 0;
    while start < n {
        let len = (n - start).min(LANES);
        continuous_block(
            &k[start..start + len],
            &m[start..start + len],
            lambda,
            sl,
            &mut out[start..start + len],
        );
        start += len;
    }
}

/// Up to [`LANES`] continuous chains at λ > 0 (`sl` = √λ).
#[inline(always)]
#[allow(clippy::excessive_precision)] // fdlibm's constants as published
fn continuous_block(k: &[f64], m: &[f64], lambda: f64, sl: f64, out: &mut [ChainEval]) {
    const PIO2_1: f64 = 1.570_796_326_734_125_614_17; // first 33 bits of π/2
    const PIO2_1T: f64 = 6.077_100_506_506_192_249_32e-11; // π/2 − PIO2_1
    let len = k.len().min(LANES);
    // Padding lanes: K = m = 1 (φ = √λ), never written out.
    let mut kk = [1.0f64; LANES];
    let mut mm = [1.0f64; LANES];
    kk[..len].copy_from_slice(&k[..len]);
    mm[..len].copy_from_slice(&m[..len]);
    let mut s = [0.0f64; LANES];
    let mut ds = [0.0f64; LANES];
    let mut below = [0u32; LANES];
    let mut phis = [0.0f64; LANES];
    for i in 0..LANES {
        let (ki, mi) = (kk[i], mm[i]);
        let phi = sl * (mi / ki).sqrt();
        phis[i] = phi;
        // ceil(φ/π) − 1 by truncation (φ > 0; an exact multiple of π counts one less).
        let x = phi * std::f64::consts::FRAC_1_PI;
        let t = x as u32;
        below[i] = if t as f64 == x {
            t.saturating_sub(1)
        } else {
            t
        };
        let qi = (phi * std::f64::consts::FRAC_2_PI + 0.5) as i64;
        let q = qi as f64;
        let r = (phi - q * PIO2_1) - q * PIO2_1T;
        let (sm, cm) = sin_cos_kernel(r);
        let (sr, cr) = (r + sm, 1.0 + cm);
        // φ = qπ/2 + r: cot φ = cot r (q even) or −tan r (q odd); sin²φ likewise.
        let odd = qi & 1 == 1;
        let num = if odd { -sr } else { cr };
        let den = if odd { cr } else { sr };
        let s2 = den * den;
        let cot = num / den;
        s[i] = ki * phi * cot;
        // d(φ cot φ)/dφ = (sin φ cos φ − φ)/sin²φ; for q = 0 (φ = r) the numerator is
        // (sin φ − φ) cos φ + φ (cos φ − 1), two terms of one sign: no cancellation as φ → 0.
        let dnum = if qi == 0 {
            sm * cr + phi * cm
        } else {
            num * den - phi
        };
        ds[i] = dnum / s2 * (0.5 * mi / phi);
    }
    for i in 0..len {
        let ok = k[i] > 0.0 && m[i] > 0.0 && (BATCH_PHI_MIN..=BATCH_PHI_MAX).contains(&phis[i]);
        out[i] = if ok {
            ChainEval {
                s: s[i],
                ds: ds[i],
                below: below[i],
            }
        } else {
            eval_continuous(k[i], m[i], lambda)
        };
    }
}

#[cfg(test)]
mod tests {
    use super::super::chain::{eval_discrete, tests::compare_chain_evals};
    use super::*;

    #[test]
    fn continuous_batch_matches_the_library_sin_cos() {
        // φ from 1e-3 to ~60 (a dozen harmonics), chains of different K/m, against the
        // scalar form (library sin_cos). Tolerance: 1e-13 relative plus the conditioning of
        // s and s' in φ (near a pole both move by ~2φ/|sin φ| ulp when φ moves by one, and
        // the two forms round φ differently); the blocked counts must be equal everywhere.
        let ks = [2.0e3, 5.0e5, 75.0, 1.0e4];
        let ms = [0.25, 0.4, 0.01, 1.0];
        let mut out = [ChainEval {
            s: 0.0,
            ds: 0.0,
            below: 0,
        }; 4];
        let mut worst: f64 = 0.0;
        for step in 0..20000 {
            let lambda = 10f64.powf(-1.0 + 8.0 * step as f64 / 20000.0);
            eval_continuous_batch(&ks, &ms, lambda, &mut out);
            for i in 0..4 {
                let r = eval_continuous(ks[i], ms[i], lambda);
                let b = out[i];
                assert_eq!(b.below, r.below, "λ {lambda} chain {i}");
                let phi = (lambda * ms[i] / ks[i]).sqrt();
                let sn = phi.sin().abs();
                // s and s' near a pole are as sensitive to φ's last bit as ~2φ/|sin φ|.
                let cond = 1e-13 + 8.0 * f64::EPSILON * phi / sn;
                // The scalar form's s' cancels in cot φ − φ/sin²φ for small φ: its own error
                // is ~ε/φ² (the batch form does not cancel there).
                let cond_ds = cond + 8.0 * f64::EPSILON / (phi * phi);
                // s = Kφ cot φ: relative to its scale Kφ where cot φ passes through 0.
                let es = (b.s - r.s).abs() / r.s.abs().max(ks[i] * phi);
                let eds = (b.ds - r.ds).abs() / r.ds.abs().max(ms[i]);
                assert!(
                    es <= cond && eds <= cond_ds,
                    "λ {lambda} chain {i} φ {phi}: s {} vs {} ({es:.1e}), ds {} vs {} ({eds:.1e})",
                    b.s,
                    r.s,
                    b.ds,
                    r.ds
                );
                worst = worst.max(es / cond).max(eds / cond_ds);
            }
        }
        eprintln!("continuous batch vs library: worst difference / tolerance {worst:.2}");
    }

    /// Every tier the CPU has (AVX2) against the portable body, bit for bit (tolerance 0:
    /// the same IEEE operations in the same order), on seeded random chains: 1 to 19 per
    /// call (full and partial blocks), k and m from 1e-150 to 1e150 and from typical ranges,
    /// λ from 1e-30 to 1e30, 0 and negative, every element count the batch takes.
    #[test]
    fn dispatched_tiers_equal_the_portable_body_bit_for_bit() {
        let mut rng = crate::simd::TestRng::new(0x5eed_ba7c);
        let bits = |e: &[ChainEval]| -> Vec<(u64, u64, u32)> {
            e.iter()
                .map(|c| (c.s.to_bits(), c.ds.to_bits(), c.below))
                .collect()
        };
        let zero = ChainEval {
            s: 0.0,
            ds: 0.0,
            below: 0,
        };
        let mut tiers_run = 0;
        for trial in 0..3000 {
            let n = 1 + (rng.next_u64() % 19) as usize;
            let extreme = trial % 3 == 0;
            let (k, m): (Vec<f64>, Vec<f64>) = (0..n)
                .map(|_| {
                    if extreme {
                        (rng.decades(-150.0, 150.0), rng.decades(-150.0, 150.0))
                    } else {
                        (rng.decades(2.0, 9.0), rng.decades(-5.0, 0.0))
                    }
                })
                .unzip();
            let lambda = match trial % 7 {
                0 => 0.0,
                1 => -rng.decades(-3.0, 6.0),
                2 => rng.decades(-30.0, 30.0),
                _ => rng.decades(-2.0, 8.0),
            };
            let n_el = 2 + (rng.next_u64() % (BATCH_MAX_ELEMENTS as u64 - 1)) as usize;
            let mut want = vec![zero; n];
            discrete_tier(0, &k, &m, n_el, lambda, &mut want).unwrap();
            let mut want_c = vec![zero; n];
            continuous_tier(0, &k, &m, lambda, &mut want_c).unwrap();
            for tier in 1..=2 {
                let mut got = vec![zero; n];
                if discrete_tier(tier, &k, &m, n_el, lambda, &mut got).is_some() {
                    tiers_run += 1;
                    assert_eq!(
                        bits(&got),
                        bits(&want),
                        "discrete tier {tier} trial {trial}"
                    );
                }
                let mut got_c = vec![zero; n];
                if continuous_tier(tier, &k, &m, lambda, &mut got_c).is_some() {
                    assert_eq!(
                        bits(&got_c),
                        bits(&want_c),
                        "continuous tier {tier} trial {trial}"
                    );
                }
            }
            let mut got = vec![zero; n];
            eval_discrete_batch(&k, &m, n_el, lambda, &mut got);
            assert_eq!(bits(&got), bits(&want), "discrete dispatched trial {trial}");
            eval_continuous_batch(&k, &m, lambda, &mut got);
            assert_eq!(
                bits(&got),
                bits(&want_c),
                "continuous dispatched trial {trial}"
            );
        }
        eprintln!("discrete batch: {tiers_run} tier runs beside the portable body");
    }

    #[test]
    fn batch_equals_closed_form() {
        // Same grid and tolerances; above the cut-off U_j grows like 5^j.
        let batch = |k: f64, m: f64, n: usize, lambda: f64| {
            let mut out = [ChainEval {
                s: 0.0,
                ds: 0.0,
                below: 0,
            }];
            eval_discrete_batch(&[k], &[m], n, lambda, &mut out);
            out[0]
        };
        let ns = [2usize, 3, 5, 10, 20, 32, 40, 64];
        let w = compare_chain_evals(&ns, batch, eval_discrete);
        eprintln!("batch vs closed form: s {:.2e}, s' {:.2e}", w[0], w[1]);
    }
}
