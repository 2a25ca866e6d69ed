//! The λ-dependent half of the continuous sagged cable: a chain of exact uniform straight
//! sub-segments, condensed from the anchor to the end as a symmetric Riccati recursion, with
//! the Wittrick–Williams count of the blocked eigenvalues.
//!
//! A uniform sub-segment of length ℓ, compliance c and mass μ per length has per principal
//! direction, at z = λ μ c ℓ² (φ = √z), the fixed–fixed dynamic stiffness
//!
//! ```text
//!   [[D, −e], [−e, D]],   D = k φ cot φ = k C/Sn,   e = k φ/sin φ = k/Sn,   k = 1/(c ℓ),
//!   x = D − e = k (C − 1)/Sn,
//!   dD/dλ = μℓ (−½ − g Sp/Sn),  de/dλ = −μℓ Sp/Sn²   (g = C/Sn, Sp = dSn/dz, dC/dz = −Sn/2)
//! ```
//!
//! with C = cos √z, Sn = sin √z/√z from `kernel` (polynomials, no trigonometry). In plane
//! D = diag(D_a, D_t), E = diag(e_a, e_t), X = D − E in the sub-segment's principal frame;
//! out of plane scalars. The end stiffness S of the cable up to node i (anchor fixed),
//! turned into sub-segment i's frame, gives the next one by condensing the node:
//!
//! ```text
//!   S₁ = D₁,   P = X + S,   Q = E + P = D + S  (the node's pivot),
//!   S₊ = D − E Q⁻¹ E = X + Yᵀ P,   Y = Q⁻¹ E,
//!   dS₊/dλ = dD − (dE Y + Yᵀ dE) + Yᵀ dQ Y,   dQ = dD + dS,
//! ```
//!
//! all symmetric 2 × 2 (closed-form inverse: one division per node). The form X + Yᵀ P
//! has no cancellation at small λ (at λ = 0, X = 0 and S₊ = E(E + S)⁻¹S: springs in series),
//! where D − E Q⁻¹ E loses log₁₀(number of sub-segments) digits. Between sub-segments S is
//! turned by the angle between their principal frames (precomputed cos, sin).
//! Wittrick–Williams: the blocked eigenvalues below λ are Σ (each sub-segment's own
//! fixed–fixed eigenvalues below λ) plus the negative eigenvalues of the pivots Q.
//!
//! The kernel is chosen once per evaluation from the largest |z| = |λ| q_max of the cable:
//! below `kernel::Z_MID` (φ ≤ 1.5 everywhere, which the mesh guarantees up to λ_max) this
//! symmetric form with polynomial C, Sn, Sp; beyond, the transfer form (`transfer`), robust
//! where a sub-segment nears its own eigenvalue (Sn → 0, where D² − e² would cancel).

use super::junction::{junction_start, De, Junction};
use super::kernel::{self, neg2, nonzero, rotate, Xh, Z_MID, Z_SMALL, Z_TINY};
use super::{transfer, Segment};
use crate::cable::sagged::SagChainEval;

#[inline(always)]
fn de(f: Xh, k: f64, mul: f64) -> De {
    De {
        d: k * (f.x + f.h),
        e: k * f.h,
        x: k * f.x,
        dd: mul * (f.dx + f.dh),
        de: mul * f.dh,
    }
}

/// Which polynomial holds for |z| ≤ `z`: 0 tiny, 1 small, 2 mid, 3 none.
#[inline(always)]
fn tier(z: f64) -> u8 {
    if z <= Z_TINY {
        0
    } else if z <= Z_SMALL {
        1
    } else if z <= Z_MID {
        2
    } else {
        3
    }
}

/// S(λ), dS/dλ and the count of the chain `segs`; `final_rot` turns the last sub-segment's
/// frame into (h, up); `q_max` is the largest q of the axial and of the other directions.
/// `junction`: the anchor node on the hidden cable (None: fixed).
pub(super) fn eval(
    segs: &[Segment],
    final_rot: [f64; 2],
    q_max: [f64; 2],
    lambda: f64,
    junction: Option<&Junction>,
) -> SagChainEval {
    let (za, zt) = (lambda.abs() * q_max[0], lambda.abs() * q_max[1]);
    let j = junction;
    match (tier(za), tier(zt)) {
        (0, 0) => run(segs, final_rot, lambda, j, kernel::tiny, kernel::tiny),
        (0, 1) => run(segs, final_rot, lambda, j, kernel::tiny, kernel::small),
        (0, 2) => run(segs, final_rot, lambda, j, kernel::tiny, kernel::mid),
        (1, 1) => run(segs, final_rot, lambda, j, kernel::small, kernel::small),
        (1, 2) => run(segs, final_rot, lambda, j, kernel::small, kernel::mid),
        (a, t) if a <= 2 && t <= 2 => run(segs, final_rot, lambda, j, kernel::mid, kernel::mid),
        _ => {
            // Beyond the polynomials (or λ not finite): the transfer form.
            let (s_in, ds_in, b_in) = transfer::eval_in(segs, final_rot, lambda, j);
            let (s_out, ds_out, b_out) = transfer::eval_out(segs, lambda);
            SagChainEval {
                s_in,
                ds_in,
                s_out,
                ds_out,
                below: b_in + b_out,
            }
        }
    }
}

/// The three directions' D, e, x of sub-segment `g` at λ.
#[inline(always)]
fn at(g: &Segment, lambda: f64, fa: &impl Fn(f64) -> Xh, ft: &impl Fn(f64) -> Xh) -> [De; 3] {
    let (a, t, o) = (
        fa(lambda * g.q[0]),
        ft(lambda * g.q[1]),
        ft(lambda * g.q[2]),
    );
    [
        de(a, g.k[0], g.mul),
        de(t, g.k[1], g.mul),
        de(o, g.k[2], g.mul),
    ]
}

/// The symmetric recursion with kernel `fa` for the axial direction, `ft` for the others.
#[inline(always)]
fn run(
    segs: &[Segment],
    final_rot: [f64; 2],
    lambda: f64,
    junction: Option<&Junction>,
    fa: impl Fn(f64) -> Xh,
    ft: impl Fn(f64) -> Xh,
) -> SagChainEval {
    let Some((first, rest)) = segs.split_first() else {
        return SagChainEval::default();
    };
    // From the fixed anchor: S₁ = D₁; from the junction: `junction_start`.
    let [a, t, o] = at(first, lambda, &fa, &ft);
    let (mut s, mut ds, mut below) = match junction {
        None => ([a.d, 0.0, t.d], [a.dd, 0.0, t.dd], 0),
        Some(j) => junction_start(a, t, j),
    };
    let (mut so, mut dso) = (o.d, o.dd);
    for g in rest {
        let [a, t, o] = at(g, lambda, &fa, &ft);
        // In plane, in this sub-segment's frame.
        let sr = rotate(s, g.rot[0], g.rot[1]);
        let dsr = rotate(ds, g.rot[0], g.rot[1]);
        let p = [a.x + sr[0], sr[1], t.x + sr[2]];
        let q = [a.e + p[0], p[1], t.e + p[2]];
        let dq = [a.dd + dsr[0], dsr[1], t.dd + dsr[2]];
        let det = q[0] * q[2] - q[1] * q[1];
        below += neg2(det, q[0] + q[2]);
        let r = 1.0 / nonzero(det, q[0] * q[2]);
        // Y = Q⁻¹ E = [[q22 e_a, −q12 e_t], [−q12 e_a, q11 e_t]] / det.
        let (y11, y12) = (q[2] * a.e * r, -q[1] * t.e * r);
        let (y21, y22) = (-q[1] * a.e * r, q[0] * t.e * r);
        s = [
            a.x + y11 * p[0] + y21 * p[1],
            0.5 * (y11 * p[1] + y21 * p[2] + y12 * p[0] + y22 * p[1]),
            t.x + y12 * p[1] + y22 * p[2],
        ];
        // Yᵀ dQ Y, then dD − (dE Y + Yᵀ dE) + Yᵀ dQ Y.
        let (p11, p21) = (dq[0] * y11 + dq[1] * y21, dq[1] * y11 + dq[2] * y21);
        let (p12, p22) = (dq[0] * y12 + dq[1] * y22, dq[1] * y12 + dq[2] * y22);
        ds = [
            a.dd - 2.0 * a.de * y11 + y11 * p11 + y21 * p21,
            -(a.de * y12 + t.de * y21) + y11 * p12 + y21 * p22,
            t.dd - 2.0 * t.de * y22 + y12 * p12 + y22 * p22,
        ];
        // Out of plane.
        let po = o.x + so;
        let qo = o.e + po;
        below += (qo < 0.0) as u32;
        let y = o.e / nonzero(qo, o.d);
        let dqo = o.dd + dso;
        so = o.x + y * po;
        dso = o.dd - 2.0 * o.de * y + dqo * y * y;
    }
    // Last sub-segment's frame → (h, up): rotate by −θ.
    let (c, sn) = (final_rot[0], -final_rot[1]);
    SagChainEval {
        s_in: rotate(s, c, sn),
        ds_in: rotate(ds, c, sn),
        s_out: so,
        ds_out: dso,
        below,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cable::sagged::{SagContinuous, SagContinuousParams};
    use crate::elastic_catenary::Catenary;

    /// The symmetric form with every kernel valid at λ agrees with the transfer form (an
    /// independent algebra of the same sub-segments): S to 1e-11 of the stiffness scale plus
    /// |S|, dS/dλ to 1e-9 of the mass scale plus |dS| (digits lost near the poles the sweep
    /// passes),
    /// the count exactly. λ sweeps up to where the largest sub-segment phase is 1.5; the
    /// anchor fixed and on a hidden cable (the junction step through both forms' D, e).
    /// On the hidden cable S is held to 1e-11 times (1 + |S|/scale) (measured 2.5e-11 of
    /// scale + |S| near a pole); dS/dλ to 1e-9 (mass + |dS|) + `PEAK_LOSS` · peak (the
    /// partial chains' peak dS/dλ, `partial_peak`): next to a blocked eigenvalue of a
    /// partial chain both forms lose digits by rounding, each its own (measured 1.8e-6 of
    /// mass + |dS| between the forms at M = 40, λ = 1.3294e5, with a partial dS of 1e7 kg;
    /// `derivative_matches_richardson_differences` checks each form against differences).
    #[test]
    fn symmetric_form_matches_transfer_form() {
        let cat = Catenary {
            l0_m: 4.0,
            ea_n: 5e4,
            w_n_m: 0.981,
            h_n: 40.0,
            v_anchor_n: -1.2,
        };
        let mu = 0.1;
        let mut sc = SagContinuous::new(SagContinuousParams::default());
        for steps in [3usize, 40] {
            sc.set_with_steps(&cat, mu, steps).unwrap();
            let segs = &sc.segs[..sc.n_seg];
            let top = Z_MID / sc.q_max[1];
            let scale = segs.iter().map(|g| g.k[0]).fold(0.0, f64::max);
            let mass = mu * cat.l0_m;
            // The anchor fixed, and on a hidden cable (an exact bar, 3 m of the same cable).
            let hidden = crate::cable::Segment {
                k: cat.ea_n / 3.0,
                m: mu * 3.0,
                n_el: 0,
            };
            let (mut worst, mut worst_d, mut worst_p) = (0.0f64, 0.0f64, 0.0f64);
            for (i, with) in (0..=300).flat_map(|i| [(i, false), (i, true)]) {
                let lam = top * i as f64 / 300.0;
                let e = hidden.eval(lam);
                let j = Junction {
                    dir: [0.8, -0.6],
                    h: e.s,
                    dh: e.ds,
                    below: e.below,
                };
                let j = with.then_some(&j);
                let (za, zt) = (lam * sc.q_max[0], lam * sc.q_max[1]);
                let (s_in, ds_in, b_in) = transfer::eval_in(segs, sc.final_rot, lam, j);
                let (s_out, ds_out, b_out) = transfer::eval_out(segs, lam);
                let peak = partial_peak(segs, lam, j);
                let mut kernels: Vec<SagChainEval> =
                    vec![run(segs, sc.final_rot, lam, j, kernel::mid, kernel::mid)];
                if zt <= Z_SMALL {
                    kernels.push(run(
                        segs,
                        sc.final_rot,
                        lam,
                        j,
                        kernel::small,
                        kernel::small,
                    ));
                }
                if za <= Z_TINY {
                    kernels.push(run(segs, sc.final_rot, lam, j, kernel::tiny, kernel::mid));
                }
                for e in kernels {
                    assert_eq!(e.below, b_in + b_out, "M {steps} λ {lam}");
                    for j in 0..3 {
                        let near = if with {
                            1.0 + s_in[j].abs() / scale
                        } else {
                            1.0
                        };
                        let tol = 1e-11 * (scale + s_in[j].abs()) * near;
                        let d = (e.s_in[j] - s_in[j]).abs();
                        worst = worst.max(d / (scale + s_in[j].abs()));
                        assert!(d <= tol, "M {steps} {with} λ {lam} S{j}");
                        let tol = 1e-9 * (mass + ds_in[j].abs()) + PEAK_LOSS * peak;
                        let d = (e.ds_in[j] - ds_in[j]).abs();
                        worst_d = worst_d.max(d / (mass + ds_in[j].abs()));
                        worst_p = worst_p.max(d / peak);
                        assert!(d <= tol, "M {steps} {with} λ {lam} dS{j}");
                    }
                    let tol = 1e-11 * (scale + s_out.abs());
                    assert!((e.s_out - s_out).abs() <= tol, "λ {lam} s_out");
                    let tol = 1e-9 * (mass + ds_out.abs());
                    assert!((e.ds_out - ds_out).abs() <= tol, "λ {lam} ds_out");
                }
            }
            eprintln!(
                "M {steps}: worst S {worst:.1e} of scale + |S|, dS {worst_d:.1e} \
                 (at most {worst_p:.1e} of the partial chains' peak dS)"
            );
        }
    }

    /// Digits of dS/dλ lost next to a blocked eigenvalue of a partial chain (the chain from
    /// the anchor to an inner node), per kg of that partial chain's peak dS/dλ: there the
    /// partial dS/dλ is dominated by a rank-one part (the pole's), whose rounding,
    /// ε · |dS_n| in every entry, the next condensation steps multiply by up to
    /// ~(e_a/q_⊥)² in the direction across it. Both forms do this alike, by different
    /// roundings: measured against the Richardson differences, both within 1e-12 · peak
    /// (e.g. M = 40, λ = 1.3294e5: a partial S of 1.5e8 and dS of 1e7 kg at node 31; the
    /// end's dS off by 1.2e-6 (symmetric) and 0.6e-6 (transfer) of mass + |dS|, on either
    /// side of the reference: 5e-13 and 3e-13 · peak; S itself keeps its digits, and away
    /// from those λ both forms are within 1e-9 of the reference). Not a missing term: the
    /// partial chains' own dS/dλ match the differences up to the pole, the loss appears
    /// at the node past it, and it grows with the partial dS, not with M. The two forms
    /// differ by at most 3.5e-12 · peak (M = 3, 20, 40, 301 λ each).
    const PEAK_LOSS: f64 = 1e-11;

    /// The largest entry of dS/dλ of the in-plane partial chains (anchor to node n,
    /// n = 1..M) at λ, kg: large when λ is close to a blocked eigenvalue of a partial chain.
    fn partial_peak(segs: &[Segment], lam: f64, j: Option<&Junction>) -> f64 {
        (1..segs.len())
            .map(|n| run(&segs[..n], [1.0, 0.0], lam, j, kernel::mid, kernel::mid).ds_in)
            .fold(0.0f64, |m, d| {
                m.max(d[0].abs()).max(d[1].abs()).max(d[2].abs())
            })
    }

    /// Each form's dS/dλ against an independent reference: Richardson-extrapolated central
    /// differences of that form's own S(λ), R(h) = (4 D(h/2) − D(h))/3 with
    /// D(h) = (S(λ + h) − S(λ − h))/(2h), h = 1e-4 λ (truncation O(h⁴); S's rounding,
    /// ~1e-12 |S| in the X + YᵀP form, gives ~1e-11 of the mass scale at this h). The
    /// reference's own error is estimated as |R(h) − R(h/2)| and λ where it exceeds 1e-10
    /// of (mass + |dS|) (next to a pole of S, where the differences do not resolve it) are
    /// skipped (at most a fifth of the sweep). Anchor fixed and on a hidden cable (an exact
    /// bar). Tolerance 3e-9 (mass + |dS|) + `PEAK_LOSS` · peak, peak the largest entry of
    /// the partial chains' dS/dλ (`partial_peak`, see `PEAK_LOSS`); 3e-9 since the
    /// reference itself is off by up to 1.1e-9 close to a pole (M = 3, λ = 209, where the
    /// two forms agree to 1.4e-10). A
    /// derivative with the hidden cable's dh/dλ dropped misses the reference by far more
    /// than the tolerance (the check can see a wrong junction term).
    /// One form's (S, dS/dλ) in plane at λ, with the hidden cable's dh/dλ or without.
    type Form<'a> = &'a dyn Fn(f64, bool) -> ([f64; 3], [f64; 3]);

    #[test]
    fn derivative_matches_richardson_differences() {
        let cat = Catenary {
            l0_m: 4.0,
            ea_n: 5e4,
            w_n_m: 0.981,
            h_n: 40.0,
            v_anchor_n: -1.2,
        };
        let mu = 0.1;
        let mass = mu * cat.l0_m;
        let hidden = crate::cable::Segment {
            k: cat.ea_n / 3.0,
            m: mu * 3.0,
            n_el: 0,
        };
        let junction = |lam: f64, with_dh: bool| {
            let e = hidden.eval(lam);
            Junction {
                dir: [0.8, -0.6],
                h: e.s,
                dh: if with_dh { e.ds } else { 0.0 },
                below: e.below,
            }
        };
        let mut sc = SagContinuous::new(SagContinuousParams::default());
        for steps in [3usize, 20, 40] {
            sc.set_with_steps(&cat, mu, steps).unwrap();
            let segs = &sc.segs[..sc.n_seg];
            let top = Z_MID / sc.q_max[1];
            let (mut worst, mut worst_peak, mut skipped, mut broken) = (0.0f64, 0.0f64, 0, 0.0f64);
            let n = 300;
            for i in 1..=n {
                let lam = top * i as f64 / n as f64;
                for with in [false, true] {
                    let j = |l: f64, dh: bool| with.then(|| junction(l, dh));
                    let sym = |l: f64, dh: bool| {
                        let e = run(
                            segs,
                            sc.final_rot,
                            l,
                            j(l, dh).as_ref(),
                            kernel::mid,
                            kernel::mid,
                        );
                        (e.s_in, e.ds_in)
                    };
                    let tra = |l: f64, dh: bool| {
                        let (s, ds, _) =
                            transfer::eval_in(segs, sc.final_rot, l, j(l, dh).as_ref());
                        (s, ds)
                    };
                    let forms: [Form; 2] = [&sym, &tra];
                    let peak = partial_peak(segs, lam, j(lam, true).as_ref());
                    for (f, form) in forms.iter().zip(["symmetric", "transfer"]) {
                        let d = |h: f64| {
                            let (a, b) = (f(lam + h, true).0, f(lam - h, true).0);
                            [0, 1, 2].map(|c| (a[c] - b[c]) / (2.0 * h))
                        };
                        let rich = |h: f64| {
                            let (a, b) = (d(h), d(0.5 * h));
                            [0, 1, 2].map(|c| (4.0 * b[c] - a[c]) / 3.0)
                        };
                        // Steps h = λ/2^k: the consecutive pair that agrees best.
                        let (mut r2, mut est) = ([0.0; 3], f64::INFINITY);
                        let mut prev = rich(0.25 * lam);
                        for k in 3..30 {
                            let r = rich(lam / (1u64 << k) as f64);
                            let e = (0..3)
                                .map(|c| (r[c] - prev[c]).abs() / (mass + r[c].abs()))
                                .fold(0.0, f64::max);
                            if e < est {
                                (r2, est) = (r, e);
                            }
                            prev = r;
                        }
                        let ds = f(lam, true).1;
                        if est > 1e-10 {
                            skipped += 1;
                            continue;
                        }
                        for c in 0..3 {
                            let rel = (ds[c] - r2[c]).abs() / (mass + r2[c].abs());
                            let tol = 3e-9 + PEAK_LOSS * peak / (mass + r2[c].abs());
                            worst = worst.max(rel);
                            worst_peak = worst_peak.max((ds[c] - r2[c]).abs() / peak);
                            assert!(rel <= tol, "M {steps} {form} junction {with} λ {lam} dS{c}: {rel:.2e} > {tol:.2e}");
                        }
                        if with {
                            // The same derivative without the hidden cable's dh/dλ.
                            let ds0 = f(lam, false).1;
                            let rel = (0..3)
                                .map(|c| (ds0[c] - r2[c]).abs() / (mass + r2[c].abs()))
                                .fold(0.0, f64::max);
                            broken = broken.max(rel / (3e-9 + PEAK_LOSS * peak / mass));
                        }
                    }
                }
            }
            eprintln!(
                "M {steps}: worst dS against the differences {worst:.1e} of mass + |dS| \
                 (at most {worst_peak:.1e} of the partial chains' peak dS); {skipped} of {} skipped next to poles; \
                 dropping dh/dλ misses by {broken:.1e} tolerances",
                4 * n
            );
            assert!(skipped <= 4 * n / 5, "M {steps}: {skipped} skipped");
            assert!(
                broken > 100.0,
                "M {steps}: a dropped dh/dλ not seen ({broken:.1e})"
            );
        }
    }
}
