//! Several sagged FEM chains of one element count evaluated in lockstep: the recurrence of
//! [`SagChain::eval`] (module docs) with the chains side by side in blocks of
//! [`SAG_LANES`] (struct of arrays: element j of every chain of a block is one record), so
//! the chains' independent dependency chains fill the pipeline and the SIMD lanes, with
//! AVX-512 / AVX2 builds of the same operations chosen at run time.
//!
//! A chain on a hidden cable ([`SagChain::set_support`]) joins the batch: its lane starts
//! the in-plane recurrence at node 1 from the junction step (`supported`: the hidden
//! segment's end stiffness at λ and the junction's condensation, per lane before the
//! block runs, by the scalar path's own function), where a fixed-anchor lane starts from
//! its first element; elements 2 … N then run in lockstep for every lane.
//!
//! Every lane does exactly the IEEE operations of the scalar recurrence, in the same order
//! (Rust never fuses or reassociates floating-point operations), and the singular-pivot
//! nudge is a select instead of a branch: the results are bit-identical to
//! [`SagChain::eval`], with or without a hidden cable (tests check it). The λ-derivative
//! recurrence is skipped when the caller does not need S' (count-only evaluations): then
//! `ds_in`, `ds_out` are 0.

use super::chain::SagChain;
use super::recurrence::first_form;
use super::supported::junction_start;
use super::{SagChainEval, SagSupport};

/// Chains per block: one AVX-512 register, two AVX2 ones (independent chains per core).
pub const SAG_LANES: usize = 8;

/// Element j of every chain of a block: in-plane [a b; b c] and out-of-plane stiffness.
#[derive(Debug, Clone, Copy)]
struct ElemBlock {
    a: [f64; SAG_LANES],
    b: [f64; SAG_LANES],
    c: [f64; SAG_LANES],
    out: [f64; SAG_LANES],
}

/// A padding lane: a unit spring without mass (positive pivots, never written out).
const PAD: ElemBlock = ElemBlock {
    a: [1.0; SAG_LANES],
    b: [0.0; SAG_LANES],
    c: [1.0; SAG_LANES],
    out: [1.0; SAG_LANES],
};

/// Per-block constants: element mass (kg) and the singular-pivot nudge (N/m) per lane.
#[derive(Debug, Clone, Copy)]
struct LaneConsts {
    mass: [f64; SAG_LANES],
    nudge: [f64; SAG_LANES],
}

/// Each lane's in-plane state at node 1 (S₁ as [a, b, c] in (h, up), S₁′) and its count
/// so far: the first element's, or the junction step's on a hidden cable.
#[derive(Debug, Clone, Copy)]
struct LaneStart {
    s: [[f64; SAG_LANES]; 3],
    ds: [[f64; SAG_LANES]; 3],
    below: [u64; SAG_LANES],
}

/// The chains of one pose packed for lockstep evaluation: `new` allocates, [`Self::pack`]
/// copies without allocating, [`Self::eval_with`] reads.
#[derive(Debug, Clone)]
pub struct SagBatch {
    /// Block-major: block b's element j at `b * n_el + j`.
    elems: Vec<ElemBlock>,
    consts: Vec<LaneConsts>,
    /// Chain i's hidden cable (None: a fixed anchor).
    supports: Vec<Option<SagSupport>>,
    n_chains: usize,
    n_el: usize,
    cap_chains: usize,
    cap_el: usize,
}

impl SagBatch {
    /// Room for `n_chains` chains of up to `n_el_max` elements (the only allocation).
    pub fn new(n_chains: usize, n_el_max: usize) -> SagBatch {
        let blocks = n_chains.div_ceil(SAG_LANES);
        let cap_el = n_el_max.max(1);
        SagBatch {
            elems: vec![PAD; blocks * cap_el],
            consts: vec![
                LaneConsts {
                    mass: [0.0; SAG_LANES],
                    nudge: [0.0; SAG_LANES],
                };
                blocks
            ],
            supports: vec![None; n_chains],
            n_chains: 0,
            n_el: 0,
            cap_chains: n_chains,
            cap_el,
        }
    }

    /// Copy `chains` in (no allocation), with their hidden cables
    /// ([`SagChain::set_support`]). Returns false, and holds nothing, when they do not fit
    /// the batch: more chains or elements than its capacity, an empty chain, or element
    /// counts that differ (the caller then evaluates them one by one).
    pub fn pack(&mut self, chains: &[SagChain]) -> bool {
        self.n_chains = 0;
        self.n_el = 0;
        let n_el = chains.first().map_or(0, SagChain::n_el);
        if chains.len() > self.cap_chains
            || n_el == 0
            || n_el > self.cap_el
            || chains.iter().any(|c| c.n_el() != n_el)
        {
            return false;
        }
        for (b, block) in chains.chunks(SAG_LANES).enumerate() {
            let els = &mut self.elems[b * n_el..(b + 1) * n_el];
            els.fill(PAD);
            let consts = &mut self.consts[b];
            consts.mass = [0.0; SAG_LANES];
            consts.nudge = [0.0; SAG_LANES];
            for (l, chain) in block.iter().enumerate() {
                self.supports[b * SAG_LANES + l] = chain.support;
                consts.mass[l] = chain.mass_kg;
                consts.nudge[l] = chain.nudge;
                for (e, (k, &ko)) in els.iter_mut().zip(chain.k_in.iter().zip(&chain.k_out)) {
                    (e.a[l], e.b[l], e.c[l], e.out[l]) = (k[0], k[1], k[2], ko);
                }
            }
        }
        self.n_chains = chains.len();
        self.n_el = n_el;
        true
    }

    /// Chains packed (0 when the last pack failed).
    pub fn n_chains(&self) -> usize {
        self.n_chains
    }

    /// Every packed chain at λ (rad²/s²): `sink(i, eval)` for chain i in order; S' only
    /// when `derivative` (else 0). No allocation.
    pub fn eval_with(
        &self,
        lambda: f64,
        derivative: bool,
        mut sink: impl FnMut(usize, &SagChainEval),
    ) {
        let mut out = [SagChainEval::default(); SAG_LANES];
        let mut init = LaneStart {
            s: [[0.0; SAG_LANES]; 3],
            ds: [[0.0; SAG_LANES]; 3],
            below: [0; SAG_LANES],
        };
        for (b, consts) in self.consts.iter().enumerate() {
            let start = b * SAG_LANES;
            if start >= self.n_chains {
                break;
            }
            let els = &self.elems[b * self.n_el..(b + 1) * self.n_el];
            let supports = &self.supports[start..(start + SAG_LANES).min(self.n_chains)];
            lane_start(&els[0], consts, supports, lambda, derivative, &mut init);
            eval_block(els, consts, &init, lambda, derivative, &mut out);
            let len = (self.n_chains - start).min(SAG_LANES);
            for (l, e) in out[..len].iter().enumerate() {
                sink(start + l, e);
            }
        }
    }
}

/// Every lane's state at node 1 at λ: the first element's A₁ = k₁ − (λm/3) I (the
/// recurrence's start, module docs of `sagged`), or on a hidden cable the junction step
/// (`supported`) with the hidden segment's end stiffness at λ; S₁′ is 0 unless `derivative`.
#[inline]
fn lane_start(
    e0: &ElemBlock,
    k: &LaneConsts,
    supports: &[Option<SagSupport>],
    lambda: f64,
    derivative: bool,
    init: &mut LaneStart,
) {
    for i in 0..SAG_LANES {
        let m = k.mass[i];
        let d3 = lambda * m / 3.0;
        init.s[0][i] = e0.a[i] - d3;
        init.s[1][i] = e0.b[i];
        init.s[2][i] = e0.c[i] - d3;
        init.ds[0][i] = -m / 3.0;
        init.ds[1][i] = 0.0;
        init.ds[2][i] = -m / 3.0;
        init.below[i] = 0;
    }
    for (i, sup) in supports.iter().enumerate() {
        let Some(sup) = sup else { continue };
        let hidden = SagChain::hidden_at_real(sup, lambda);
        let first = ([e0.a[i], e0.b[i], e0.c[i]], k.mass[i], k.nudge[i]);
        let (s, ds, below) = junction_start(first, sup, lambda, hidden);
        for q in 0..3 {
            init.s[q][i] = s[q];
            init.ds[q][i] = if derivative { ds[q] } else { 0.0 };
        }
        init.below[i] = below as u64;
    }
}

crate::simd::dispatch! {
    /// One block, [`block_body`] compiled for the widest instruction set the CPU has
    /// (AVX-512F: one register per lane array; AVX2), with the same results.
    fn eval_block(
        els: &[ElemBlock],
        k: &LaneConsts,
        init: &LaneStart,
        lambda: f64,
        derivative: bool,
        out: &mut [SagChainEval; SAG_LANES],
    ) = block_body;
    features ["avx512f", "avx2"];
    tiers block_tier;
}

/// [`block`] with or without the λ-derivative.
#[inline(always)]
fn block_body(
    els: &[ElemBlock],
    k: &LaneConsts,
    init: &LaneStart,
    lambda: f64,
    derivative: bool,
    out: &mut [SagChainEval; SAG_LANES],
) {
    if derivative {
        block::<true>(els, k, init, lambda, out);
    } else {
        block::<false>(els, k, init, lambda, out);
    }
}

/// The recurrence of [`SagChain::eval`] on every lane from its state at node 1 (`init`;
/// `D`: with S'), lane-innermost.
#[inline(always)]
fn block<const D: bool>(
    els: &[ElemBlock],
    k: &LaneConsts,
    init: &LaneStart,
    lambda: f64,
    out: &mut [SagChainEval; SAG_LANES],
) {
    const L: usize = SAG_LANES;
    let m = k.mass;
    let mut d3 = [0.0; L];
    let mut d2 = [0.0; L];
    let mut lm = [0.0; L];
    let mut m3 = [0.0; L];
    let mut m2 = [0.0; L];
    let mut d6 = [0.0; L];
    let mut m6 = [0.0; L];
    for i in 0..L {
        lm[i] = lambda * m[i];
        d3[i] = lambda * m[i] / 3.0;
        d2[i] = lambda * m[i] / 2.0;
        d6[i] = lambda * m[i] / 6.0;
        m3[i] = m[i] / 3.0;
        m2[i] = m[i] / 2.0;
        m6[i] = m[i] / 6.0;
    }
    let e0 = &els[0];
    let [mut s0, mut s1, mut s2] = init.s;
    let [mut ds0, mut ds1, mut ds2] = init.ds;
    let mut so = [0.0; L];
    let mut dso = [0.0; L];
    let (mut neg1, mut neg2, mut nego) = (init.below, [0u64; L], [0u64; L]);
    for i in 0..L {
        so[i] = e0.out[i] - d3[i];
        dso[i] = -m[i] / 3.0;
    }
    for ej in &els[1..] {
        for i in 0..L {
            // In plane: the pivot Q, nudged when exactly singular.
            let mut q0 = s0[i] + ej.a[i] - d3[i];
            let q1 = s1[i] + ej.b[i];
            let mut q2 = s2[i] + ej.c[i] - d3[i];
            let singular = q0 * q2 - q1 * q1 == 0.0;
            if singular {
                q0 += k.nudge[i];
                q2 += k.nudge[i];
            }
            let mut det = q0 * q2 - q1 * q1;
            if singular && det == 0.0 {
                det = k.nudge[i] * k.nudge[i];
            }
            let negative = det < 0.0;
            neg1[i] += negative as u64;
            neg2[i] += (!negative & (q0 < 0.0)) as u64;
            // S_{j+1} = A − X Q⁻¹ X in the form with the smaller terms (`recurrence`'s
            // `first_form`), chosen per lane by a select.
            let first = first_form(
                s0[i].abs() + s2[i].abs() + 2.0 * s1[i].abs(),
                ej.a[i].abs() + ej.c[i].abs(),
            );
            let (a0, a1, a2) = if first {
                (ej.a[i] - d3[i], ej.b[i], ej.c[i] - d3[i])
            } else {
                (s0[i] - lm[i], s1[i], s2[i] - lm[i])
            };
            let (x0, x1, x2) = if first {
                (ej.a[i] + d6[i], ej.b[i], ej.c[i] + d6[i])
            } else {
                (s0[i] - d2[i], s1[i], s2[i] - d2[i])
            };
            let inv = 1.0 / det;
            let (ia, ib, ic) = (q2 * inv, -q1 * inv, q0 * inv);
            let y00 = ia * x0 + ib * x1;
            let y01 = ia * x1 + ib * x2;
            let y10 = ib * x0 + ic * x1;
            let y11 = ib * x1 + ic * x2;
            let p00 = x0 * y00 + x1 * y10;
            let p01 = x0 * y01 + x1 * y11;
            let p10 = x1 * y00 + x2 * y10;
            let p11 = x1 * y01 + x2 * y11;
            if D {
                let (dq0, dq1, dq2) = (ds0[i] - m3[i], ds1[i], ds2[i] - m3[i]);
                let (da0, da1, da2) = if first {
                    (-m3[i], 0.0, -m3[i])
                } else {
                    (ds0[i] - m[i], ds1[i], ds2[i] - m[i])
                };
                let (dx0, dx1, dx2) = if first {
                    (m6[i], 0.0, m6[i])
                } else {
                    (ds0[i] - m2[i], ds1[i], ds2[i] - m2[i])
                };
                let dxy0 = dx0 * y00 + dx1 * y10;
                let dxy01 = dx0 * y01 + dx1 * y11;
                let dxy10 = dx1 * y00 + dx2 * y10;
                let dxy1 = 0.5 * (dxy01 + dxy10);
                let dxy2 = dx1 * y01 + dx2 * y11;
                let xy00 = dq0 * y00 + dq1 * y10;
                let xy10 = dq1 * y00 + dq2 * y10;
                let xy01 = dq0 * y01 + dq1 * y11;
                let xy11 = dq1 * y01 + dq2 * y11;
                let yqy0 = y00 * xy00 + y10 * xy10;
                let yqy1 = y00 * xy01 + y10 * xy11;
                let yqy2 = y01 * xy01 + y11 * xy11;
                ds0[i] = da0 - 2.0 * dxy0 + yqy0;
                ds1[i] = da1 - 2.0 * dxy1 + yqy1;
                ds2[i] = da2 - 2.0 * dxy2 + yqy2;
            }
            s0[i] = a0 - p00;
            s1[i] = a1 - 0.5 * (p01 + p10);
            s2[i] = a2 - p11;
            // Out of plane: the scalar string.
            let mut qo = so[i] + ej.out[i] - d3[i];
            if qo == 0.0 {
                qo = k.nudge[i];
            }
            nego[i] += (qo < 0.0) as u64;
            let first = first_form(so[i].abs(), ej.out[i].abs());
            let (ao, xo) = if first {
                (ej.out[i] - d3[i], ej.out[i] + d6[i])
            } else {
                (so[i] - lm[i], so[i] - d2[i])
            };
            let yo = xo / qo;
            if D {
                let dqo = dso[i] - m3[i];
                let (dao, dxo) = if first {
                    (-m3[i], m6[i])
                } else {
                    (dso[i] - m[i], dso[i] - m2[i])
                };
                dso[i] = dao - 2.0 * dxo * yo + dqo * yo * yo;
            }
            so[i] = ao - xo * yo;
        }
    }
    for i in 0..L {
        let keep = if D { 1.0 } else { 0.0 };
        out[i] = SagChainEval {
            s_in: [s0[i], s1[i], s2[i]],
            ds_in: [keep * ds0[i], keep * ds1[i], keep * ds2[i]],
            s_out: so[i],
            ds_out: keep * dso[i],
            below: (neg1[i] + 2 * neg2[i] + nego[i]) as u32,
        };
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::test_chain;
    use super::*;
    use crate::simd::TestRng;

    fn bits(e: &[SagChainEval; SAG_LANES]) -> Vec<[u64; 9]> {
        e.iter()
            .map(|c| {
                [
                    c.s_in[0],
                    c.s_in[1],
                    c.s_in[2],
                    c.s_out,
                    c.ds_in[0],
                    c.ds_in[1],
                    c.ds_in[2],
                    c.ds_out,
                    c.below as f64,
                ]
                .map(f64::to_bits)
            })
            .collect()
    }

    /// Every tier the CPU has (AVX-512F, AVX2) against the portable body, bit for bit
    /// (tolerance 0: the same IEEE operations in the same order), with and without S', on
    /// seeded random blocks: packed sagged chains (curved profiles, 1 to 40 elements, every
    /// other chain of every fourth trial on a hidden cable) and raw element blocks whose
    /// stiffnesses, masses and nudges range from 1e-150 to 1e150.
    #[test]
    fn dispatched_tiers_equal_the_portable_body_bit_for_bit() {
        let mut rng = TestRng::new(0x5a66_ba7c);
        let mut tiers_run = 0;
        for trial in 0..400 {
            let n_el = 1 + (rng.next_u64() % 40) as usize;
            let mut batch = SagBatch::new(SAG_LANES, n_el);
            if trial % 2 == 0 {
                let chains: Vec<SagChain> = (0..1 + trial % SAG_LANES)
                    .map(|l| {
                        let mut c = test_chain(n_el, rng.decades(3.0, 9.0), rng.decades(-3.0, 1.0));
                        if trial % 4 == 0 && l % 2 == 0 {
                            let angle = rng.unit() * 3.0 - 1.5;
                            let sup = SagSupport {
                                hidden: crate::cable::Segment {
                                    k: rng.decades(3.0, 9.0),
                                    m: rng.decades(-3.0, 1.0),
                                    n_el: (rng.next_u64() % 41) as usize,
                                },
                                direction: [angle.cos(), angle.sin()],
                            };
                            c.set_support(Some(sup)).unwrap();
                        }
                        c
                    })
                    .collect();
                assert!(batch.pack(&chains));
            } else {
                for e in &mut batch.elems[..n_el] {
                    for l in 0..SAG_LANES {
                        let sign = rng.sign();
                        e.a[l] = rng.decades(-150.0, 150.0);
                        e.b[l] = sign * rng.decades(-150.0, 150.0);
                        e.c[l] = rng.decades(-150.0, 150.0);
                        e.out[l] = rng.decades(-150.0, 150.0);
                    }
                }
                for l in 0..SAG_LANES {
                    batch.consts[0].mass[l] = rng.decades(-150.0, 150.0);
                    batch.consts[0].nudge[l] = rng.decades(-150.0, 150.0);
                }
            }
            let els = &batch.elems[..n_el];
            let consts = &batch.consts[0];
            let supports = &batch.supports[..batch.n_chains.min(SAG_LANES)];
            for _ in 0..8 {
                let lambda = if trial % 4 == 1 {
                    rng.decades(-30.0, 30.0)
                } else {
                    rng.decades(-1.0, 7.0)
                };
                for derivative in [true, false] {
                    let mut init = LaneStart {
                        s: [[0.0; SAG_LANES]; 3],
                        ds: [[0.0; SAG_LANES]; 3],
                        below: [0; SAG_LANES],
                    };
                    lane_start(&els[0], consts, supports, lambda, derivative, &mut init);
                    let init = &init;
                    let mut want = [SagChainEval::default(); SAG_LANES];
                    block_tier(0, els, consts, init, lambda, derivative, &mut want).unwrap();
                    for tier in 1..=2 {
                        let mut got = [SagChainEval::default(); SAG_LANES];
                        let r = block_tier(tier, els, consts, init, lambda, derivative, &mut got);
                        if r.is_some() {
                            tiers_run += 1;
                            assert_eq!(bits(&got), bits(&want), "tier {tier} trial {trial}");
                        }
                    }
                    let mut got = [SagChainEval::default(); SAG_LANES];
                    eval_block(els, consts, init, lambda, derivative, &mut got);
                    assert_eq!(bits(&got), bits(&want), "dispatched, trial {trial}");
                }
            }
        }
        eprintln!("sagged block: {tiers_run} tier runs beside the portable body");
    }
}
