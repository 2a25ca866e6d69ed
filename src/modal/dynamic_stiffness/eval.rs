//! One evaluation of the loaded problem at λ: D(λ), D'(λ) and the blocked count, with the
//! buffers it writes ([`EvalScratch`]).

use super::{LoadedChains, Plan, Slot, MAX_BATCHED};
use crate::cable::{eval_continuous_batch, eval_discrete_batch, supported_from_parts, ChainEval};
use crate::modal::engine::{nearest_keyed_pole, quad, Coupling, DynEval, MAX_CHAINS, SYM3};
use nalgebra::{Matrix6, Vector6};

/// What one evaluation of D(λ) writes: the chains' values at the last λ (and the batched
/// evaluators' outputs), and the count of evaluations. No per-evaluation clearing.
#[derive(Debug, Clone)]
pub(in crate::modal) struct EvalScratch {
    /// Per-chain evaluations at the last λ.
    pub(in crate::modal) chain_eval: [ChainEval; MAX_CHAINS],
    batch_out: [ChainEval; MAX_BATCHED],
    cont_out: [ChainEval; MAX_BATCHED],
    /// Evaluations of D(λ) since the solver was built.
    pub(in crate::modal) evaluations: u32,
}

impl EvalScratch {
    /// Zeroed buffers.
    pub(in crate::modal) fn new() -> EvalScratch {
        let zero = ChainEval {
            s: 0.0,
            ds: 0.0,
            below: 0,
        };
        EvalScratch {
            chain_eval: [zero; MAX_CHAINS],
            batch_out: [zero; MAX_BATCHED],
            cont_out: [zero; MAX_BATCHED],
            evaluations: 0,
        }
    }

    /// Every chain of `p` at λ into `chain_eval`: the batched ones together, the rest one
    /// by one.
    #[inline]
    fn eval_chains(&mut self, p: &LoadedChains, lambda: f64) {
        let nb = p.n_batch;
        if nb > 0 {
            eval_discrete_batch(
                &p.batch_k[..nb],
                &p.batch_m[..nb],
                p.batch_n_el,
                lambda,
                &mut self.batch_out[..nb],
            );
        }
        let nc = p.n_cont;
        if nc > 0 {
            eval_continuous_batch(
                &p.cont_k[..nc],
                &p.cont_m[..nc],
                lambda,
                &mut self.cont_out[..nc],
            );
        }
        let (bo, co) = (&self.batch_out, &self.cont_out);
        let pick = |slot: Slot, scalar: &dyn Fn() -> ChainEval| match slot {
            Slot::Batch(j) => bo[j],
            Slot::Cont(j) => co[j],
            Slot::Scalar => scalar(),
        };
        for (i, o) in self.chain_eval[..p.n_chains].iter_mut().enumerate() {
            *o = match p.plan[i] {
                Plan::Uniform(slot) => pick(slot, &|| p.chains[i].eval(lambda)),
                Plan::Supported {
                    free,
                    hidden,
                    free_slot,
                    hidden_slot,
                } => {
                    let f = pick(free_slot, &|| free.eval(lambda));
                    let h = pick(hidden_slot, &|| hidden.eval(lambda));
                    supported_from_parts(&free, &hidden, f, h, lambda)
                }
            };
        }
    }

    /// D(λ), D'(λ) and the blocked count of the loaded problem `p`.
    #[inline]
    pub(in crate::modal) fn eval(&mut self, p: &LoadedChains, lambda: f64) -> DynEval {
        self.evaluations += 1;
        self.eval_chains(p, lambda);
        let mut below = 0u32;
        if p.dim == 3 {
            // The six distinct entries of the symmetric 3 × 3 blocks (00 11 22 01 02 12).
            let m = p.ee_mass_kg;
            let k = &p.k3_sym;
            let mut d = [
                k[0] - lambda * m,
                k[1] - lambda * m,
                k[2] - lambda * m,
                k[3],
                k[4],
                k[5],
            ];
            let mut dd = [-m, -m, -m, 0.0, 0.0, 0.0];
            for (i, e) in self.chain_eval[..p.n_chains].iter().enumerate() {
                let pr = &p.proj_sym[i];
                for j in 0..6 {
                    d[j] += pr[j] * e.s;
                    dd[j] += pr[j] * e.ds;
                }
                below += p.chains[i].mult * e.below;
            }
            let mut d6 = Matrix6::zeros();
            let mut dd6 = Matrix6::zeros();
            for (j, &(r, c)) in SYM3.iter().enumerate() {
                d6[(r, c)] = d[j];
                d6[(c, r)] = d[j];
                dd6[(r, c)] = dd[j];
                dd6[(c, r)] = dd[j];
            }
            return DynEval {
                d: d6,
                dd: dd6,
                below,
                dim: 3,
            };
        }
        let mut d = p.k6 - p.m6 * lambda;
        let mut dd = -p.m6;
        for ((c, q), e) in p.chains[..p.n_chains]
            .iter()
            .zip(&p.q6)
            .zip(&self.chain_eval)
        {
            d += q * e.s;
            dd += q * e.ds;
            below += c.mult * e.below;
        }
        DynEval {
            d,
            dd,
            below,
            dim: 6,
        }
    }

    /// The pole-free interval (a, b) of D around the λ of the last evaluation, from the
    /// chains' blocked counts there.
    #[inline]
    pub(in crate::modal) fn last_pole_interval(&self, p: &LoadedChains) -> (f64, f64) {
        let mut a = 0.0f64;
        let mut b = f64::INFINITY;
        // As [`LoadedChains::pole_interval`]: a supported chain below its first pole is
        // skipped when its lower bound lies above b.
        for supported in [false, true] {
            for i in 0..p.n_chains {
                let lb = p.pole1_lb[i];
                let j = self.chain_eval[i].below as usize;
                if (lb > f64::NEG_INFINITY) != supported || (j == 0 && lb >= b) {
                    continue;
                }
                a = a.max(p.chain_pole(i, j));
                b = b.min(p.chain_pole(i, j + 1));
            }
        }
        (a, b)
    }

    /// The chain holding the largest share of the kinetic-energy norm vᵀ(−D'(x))v of the
    /// mode shape v at the last evaluation (at x): (share, that chain's pole nearest x,
    /// whether the pole is above x, the pole's key chain << 16 | pole number). In an avoided
    /// crossing with a string mode of that chain, the share is what the partner across the
    /// pole holds (two-level model).
    #[inline]
    pub(in crate::modal) fn coupling(
        &self,
        p: &LoadedChains,
        x: f64,
        dd: &Matrix6<f64>,
        v: &Vector6<f64>,
    ) -> Coupling {
        let kin = -quad(dd, v, p.dim);
        if !(kin > 0.0) {
            return (0.0, f64::NAN, false, u32::MAX);
        }
        let mut best = (0.0, usize::MAX);
        for i in 0..p.n_chains {
            let w = if p.dim == 3 {
                let (pr, x, y, z) = (&p.chains[i].proj, v[0], v[1], v[2]);
                x * x * pr[(0, 0)]
                    + y * y * pr[(1, 1)]
                    + z * z * pr[(2, 2)]
                    + 2.0 * (x * y * pr[(0, 1)] + x * z * pr[(0, 2)] + y * z * pr[(1, 2)])
            } else {
                quad(&p.q6[i], v, 6)
            };
            let q = -self.chain_eval[i].ds * w;
            if q > best.0 {
                best = (q, i);
            }
        }
        if best.1 == usize::MAX {
            return (0.0, f64::NAN, false, u32::MAX);
        }
        let i = best.1;
        let j = self.chain_eval[i].below as usize;
        let (lo, hi) = (p.chain_pole(i, j), p.chain_pole(i, j + 1));
        nearest_keyed_pole(best.0 / kin, x, i, j, lo, hi)
    }
}
