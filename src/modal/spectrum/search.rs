//! The search for one mode: count brackets, pole probes, safeguarded Newton on a branch.

use super::cluster::{members_residue, participations, residue_participations};
use super::{Mode, SpectrumParams};
use crate::modal::dynamic_stiffness::{quad, DynEval, EigD, EvalScratch, LoadedChains};
use crate::modal::{lambda_to_hz, ModalError};

/// Without a better scale, the first bracket starts here (rad²/s²).
const BRACKET_MIN: f64 = 1e-12;
/// Upper brackets grow by this factor per count probe.
const BRACKET_GROWTH: f64 = 2.0;
/// The bracket counts as collapsed when narrower than this many ε relative to λ.
const COLLAPSE_ULPS: f64 = 4.0;
/// A Newton step below this (relative) that is also below [`SUPERLINEAR_RATIO`] times the
/// previous one shows superlinear convergence: the iterate after it is within ~(step)²
/// (relative) of the root, far below the target, and it is accepted (steps of rounding
/// noise, ~1e-13, end the iteration this way instead of bouncing).
const NOISE_STEP: f64 = 1e-10;
/// See [`NOISE_STEP`]: quadratic convergence shrinks steps far faster than this.
const SUPERLINEAR_RATIO: f64 = 1e-2;
/// Relative step of the symmetric residue quotient at a pole (error O(h²) from the other
/// modes, while the cluster's own spread there is below the pole probe, ≪ h).
const RESIDUE_STEP: f64 = 1e-7;
/// A bracket whose first pole (or lower end) is below this fraction of its upper end is
/// bisected geometrically (√(lo·hi)); narrower ones at the midpoint.
const WIDE_RANGE: f64 = 1e-6;

/// J, the blocked count and λ at one count probe.
#[derive(Debug, Clone, Copy)]
pub(super) struct Probe {
    pub(super) x: f64,
    pub(super) count: u32,
    pub(super) below: u32,
}

/// Where a mode was found. Short-lived, returned once per mode: the large variant's size
/// (one evaluation of D) does not matter.
#[allow(clippy::large_enum_variant)]
enum Found {
    /// At a chain pole (the count steps between the probes around it).
    Pole(f64),
    /// The zero of branch `branch` of D, with the evaluation nearest to it.
    Branch {
        lambda: f64,
        eval: DynEval,
        eig: EigD,
        branch: usize,
    },
}

/// The current cluster: its count probes, first index, multiplicity and participations.
#[derive(Debug, Clone, Copy)]
struct Cluster {
    lo: Probe,
    hi: Probe,
    start: usize,
    mult: u32,
    parts: [f64; 6],
    /// The roots of the first `presolved` members (solved with the first one).
    lambdas: [f64; 6],
    presolved: usize,
}

/// One solved member of a pole-free cluster: its root, the evaluation there, its branch.
pub(super) type Member = (f64, DynEval, EigD, usize);

/// One sweep over the spectrum of the loaded problem, ascending.
pub(super) struct SpectrumSearch<'a> {
    p: &'a LoadedChains,
    s: &'a mut EvalScratch,
    params: &'a SpectrumParams,
    cl: Cluster,
    /// A scale for the first bracket: the Rayleigh estimate μ₁(0)/(−μ₁'(0)), rad²/s².
    scale: f64,
    /// Evaluation counter at the start of the current mode.
    mode_start: u32,
}

impl<'a> SpectrumSearch<'a> {
    pub(super) fn new(
        p: &'a LoadedChains,
        s: &'a mut EvalScratch,
        params: &'a SpectrumParams,
    ) -> SpectrumSearch<'a> {
        let zero = Probe {
            x: 0.0,
            count: 0,
            below: 0,
        };
        SpectrumSearch {
            p,
            s,
            params,
            cl: Cluster {
                lo: zero,
                hi: zero,
                start: 0,
                mult: 0,
                parts: [0.0; 6],
                lambdas: [0.0; 6],
                presolved: 0,
            },
            scale: f64::NAN,
            mode_start: 0,
        }
    }

    /// Check D(0) > 0 (then J(0) = 0) and take the first bracket's scale.
    pub(super) fn start(&mut self) -> Result<(), ModalError> {
        let e = self.s.eval(self.p, 0.0);
        let eg = e.eig();
        if !(eg.values[0] > 0.0) {
            return Err(ModalError::NotPositiveDefinite(eg.values[0]));
        }
        let kin = -quad(&e.dd, &eg.vectors[0], e.dim);
        self.scale = if kin > 0.0 {
            eg.values[0] / kin
        } else {
            BRACKET_MIN
        };
        Ok(())
    }

    /// Mode `i` (0-based); modes must be asked for in order 0, 1, 2, ...
    pub(super) fn mode(&mut self, i: usize) -> Result<Mode, ModalError> {
        self.mode_start = self.s.evaluations;
        let cl = self.cl;
        if cl.mult > 0 && (i as u64) < cl.hi.count as u64 && i >= cl.start {
            let j = i - cl.start;
            let lambda = if j < cl.presolved {
                cl.lambdas[j]
            } else {
                match self.solve(i, cl.lo, cl.hi)? {
                    Found::Pole(x) => x,
                    Found::Branch { lambda, .. } => lambda,
                }
            };
            return Ok(Mode {
                lambda,
                frequency_hz: lambda_to_hz(lambda),
                ee_participation: if j < 6 { cl.parts[j] } else { 0.0 },
                cluster_start: cl.start,
                multiplicity: cl.mult,
            });
        }
        let lo = if cl.mult > 0 { cl.hi } else { cl.lo };
        let (lo, hi) = self.grow(i, lo)?;
        let found = self.solve(i, lo, hi)?;
        self.new_cluster(i, found)
    }

    /// Count probe at x.
    fn probe(&mut self, x: f64) -> Probe {
        let e = self.s.eval(self.p, x);
        Probe {
            x,
            count: e.below + e.eig().negatives() as u32,
            below: e.below,
        }
    }

    /// The budget error, or nothing.
    fn check_budget(&self, lo: f64, hi: f64) -> Result<(), ModalError> {
        let used = self.s.evaluations - self.mode_start;
        if used >= self.params.max_evaluations_per_mode {
            return Err(ModalError::NoConvergence {
                evaluations: used,
                lo,
                hi,
            });
        }
        Ok(())
    }

    /// From `lo` (J(lo) ≤ i) grow an upper bracket hi with J(hi) > i.
    fn grow(&mut self, i: usize, mut lo: Probe) -> Result<(Probe, Probe), ModalError> {
        let mut x = if lo.x > 0.0 {
            lo.x * BRACKET_GROWTH
        } else {
            (BRACKET_GROWTH * self.scale).max(BRACKET_MIN)
        };
        loop {
            self.check_budget(lo.x, x)?;
            let pr = self.probe(x);
            if pr.count as usize > i {
                return Ok((lo, pr));
            }
            lo = pr;
            x *= BRACKET_GROWTH;
        }
    }

    /// Narrow J(lo) ≤ i < J(hi) to the mode: bisection on the count while two or more
    /// distinct poles lie inside, probes around a single pole, Newton once pole-free.
    fn solve(&mut self, i: usize, mut lo: Probe, mut hi: Probe) -> Result<Found, ModalError> {
        let eta = self.params.pole_probe;
        loop {
            self.check_budget(lo.x, hi.x)?;
            let (pa, pb) = self.p.pole_interval(lo.x);
            if pb >= hi.x {
                return self.newton(i, lo, hi, pa, pb);
            }
            let (_, pc) = self.p.pole_interval(pb * (1.0 + eta));
            if pc < hi.x {
                // Bisection; across many decades (a nearly slack cable's string modes far
                // below the others) geometric from the first pole up, so that the count
                // reaches the low poles in a few probes.
                let floor = lo.x.max(pb);
                let x = if floor < WIDE_RANGE * hi.x {
                    (floor.sqrt() * hi.x.sqrt()).max(floor)
                } else {
                    0.5 * (lo.x + hi.x)
                };
                let x = if x > lo.x && x < hi.x {
                    x
                } else {
                    0.5 * (lo.x + hi.x)
                };
                let pr = self.probe(x);
                if pr.count as usize > i {
                    hi = pr;
                } else {
                    lo = pr;
                }
                continue;
            }
            // One distinct pole pb in (lo, hi).
            let x1 = pb * (1.0 - eta);
            if x1 > lo.x {
                let pr = self.probe(x1);
                if pr.count as usize > i {
                    hi = pr;
                    continue;
                }
            }
            let x2 = pb * (1.0 + eta);
            if x2 < hi.x {
                let pr = self.probe(x2);
                if pr.count as usize > i {
                    return Ok(Found::Pole(pb));
                }
                lo = pr;
                continue;
            }
            return Ok(Found::Pole(pb));
        }
    }

    /// Safeguarded Newton on branch i − B of D in the pole-free bracket (lo, hi) between
    /// the poles pa ≤ lo and pb ≥ hi.
    fn newton(
        &mut self,
        i: usize,
        mut lo: Probe,
        mut hi: Probe,
        pa: f64,
        pb: f64,
    ) -> Result<Found, ModalError> {
        let branch = i.checked_sub(lo.below as usize).unwrap_or(usize::MAX);
        if branch >= self.p.dim {
            return Err(ModalError::CountMismatch(lo.x));
        }
        let mut x = 0.5 * (lo.x + hi.x);
        let mut prev_step = f64::INFINITY;
        let mut width = [hi.x - lo.x; 2];
        loop {
            self.check_budget(lo.x, hi.x)?;
            let e = self.s.eval(self.p, x);
            let eg = e.eig();
            let mu = eg.values[branch];
            let dmu = quad(&e.dd, &eg.vectors[branch], e.dim);
            if mu > 0.0 {
                lo.x = x;
            } else if mu < 0.0 {
                hi.x = x;
            }
            let xn = pole_free_newton(mu, dmu, x, pa, pb);
            let inside = xn > lo.x && xn < hi.x;
            let step = (xn - x).abs();
            let collapsed = hi.x - lo.x <= COLLAPSE_ULPS * f64::EPSILON * x;
            let converged = step <= self.params.rel_tol * x
                || (prev_step.is_finite()
                    && step <= NOISE_STEP * x
                    && step <= SUPERLINEAR_RATIO * prev_step);
            if mu == 0.0 || collapsed || (inside && converged) {
                let lambda = if inside { xn } else { x };
                // D' at the root itself: near a pole it changes by 2·step/distance, and the
                // participation reads it (one more evaluation).
                let eval = if lambda != x {
                    self.s.eval(self.p, lambda)
                } else {
                    e
                };
                return Ok(Found::Branch {
                    lambda,
                    eig: eval.eig(),
                    eval,
                    branch,
                });
            }
            // Bisect when Newton leaves the bracket or two steps did not halve it.
            let slow = hi.x - lo.x > 0.5 * width[0];
            width = [width[1], hi.x - lo.x];
            x = if inside && !slow {
                prev_step = step;
                xn
            } else {
                prev_step = f64::INFINITY;
                0.5 * (lo.x + hi.x)
            };
        }
    }

    /// The first mode of a new cluster: its count probes (certificate and multiplicity) and
    /// the cluster's participations.
    fn new_cluster(&mut self, i: usize, found: Found) -> Result<Mode, ModalError> {
        let lambda = match &found {
            Found::Pole(x) => *x,
            Found::Branch { lambda, .. } => *lambda,
        };
        let d = self.params.cluster_probe;
        let lo = self.probe(lambda * (1.0 - d));
        let hi = self.probe(lambda * (1.0 + d));
        if !(lo.count as usize <= i && (hi.count as usize) > i) {
            return Err(ModalError::CountMismatch(lambda));
        }
        let mult = hi.count - i as u32;
        let (pa, pb) = self.p.pole_interval(lo.x);
        let pole_free = pb > hi.x && pa < lo.x;
        let mut lambdas = [lambda; 6];
        let mut presolved = 0;
        let parts = match found {
            Found::Branch {
                eval, eig, branch, ..
            } if pole_free && branch + mult as usize <= self.p.dim => {
                let mut members = [(lambda, eval, eig, branch); 6];
                for k in 1..mult as usize {
                    members[k] = self.member(i + k, lo, hi)?;
                    lambdas[k] = members[k].0;
                }
                presolved = mult as usize;
                participations(self.p, &members_residue(&members[..mult as usize]))
            }
            _ => {
                let h = RESIDUE_STEP;
                let em = self.s.eval(self.p, lambda * (1.0 - h));
                let ep = self.s.eval(self.p, lambda * (1.0 + h));
                residue_participations(self.p, lambda, h, &em, &ep)
            }
        };
        self.cl = Cluster {
            lo,
            hi,
            start: i,
            mult,
            parts,
            lambdas,
            presolved,
        };
        Ok(Mode {
            lambda,
            frequency_hz: lambda_to_hz(lambda),
            ee_participation: parts[0],
            cluster_start: i,
            multiplicity: mult,
        })
    }

    /// Member `i` of a pole-free cluster bracketed by `lo`, `hi` (its own budget).
    fn member(&mut self, i: usize, lo: Probe, hi: Probe) -> Result<Member, ModalError> {
        self.mode_start = self.s.evaluations;
        match self.solve(i, lo, hi)? {
            Found::Branch {
                lambda,
                eval,
                eig,
                branch,
            } => Ok((lambda, eval, eig, branch)),
            Found::Pole(x) => Err(ModalError::CountMismatch(x)),
        }
    }
}

/// The Newton iterate from x for μ(λ)(λ − pa)(pb − λ) (the poles bounding the interval
/// removed; pa = 0 and pb = ∞ add nothing), NaN when the derivative is not negative.
fn pole_free_newton(mu: f64, dmu: f64, x: f64, pa: f64, pb: f64) -> f64 {
    let (mut g, mut dg) = (mu, dmu);
    if pb.is_finite() {
        let w = pb - x;
        (g, dg) = (g * w, dg * w - g);
    }
    if pa > 0.0 {
        let w = x - pa;
        (g, dg) = (g * w, dg * w + g);
    }
    if dg < 0.0 {
        x - g / dg
    } else {
        f64::NAN
    }
}
