//! The search for one mode: count brackets, pole probes, safeguarded Newton on a branch.

//!
//! Generic over the condensed problem ([`Condensed`]): where the chains' poles are known
//! (taut) the bracket is narrowed by probes around them; where only the count shows them
//! (sagged) it is bisected while the blocked count differs at its ends, and a bracket
//! narrower than the pole probe with a pole inside reports the mode there.

use super::cluster::{members_residue, participations, residue_participations};
use super::{Member, Mode, SpectrumParams};
use crate::modal::engine::{
    pole_free, quad, Condensed, DynEval, EigD, BRACKET_GROWTH, BRACKET_MIN, COLLAPSE_ULPS,
    NOISE_STEP, SUPERLINEAR_RATIO,
};
use crate::modal::{lambda_to_hz, ModalError};
/// Where the count alone shows the poles (sagged chains) and a mode's cluster probes do
/// not straddle it, they are tried again this many times wider. A partial chain (anchor to
/// an inner node) near its own pole makes the recurrence's 2 × 2 end stiffness huge in one
/// direction, and its rounding (ε times that) lands in the other direction's entries too:
/// D then carries noise far above ε·‖D‖ (measured: 5e-3 N/m on μ₁ of suspended-8 at N = 10
/// at mode 88, λ = 3451.66 rad²/s², where the other eigenvalues are ~5e5 N/m), which puts
/// Newton's root ~6e-11 (relative) from the count's step, beside the default 1e-10 probes.
const NOISY_CLUSTER_PROBE: f64 = 100.0;
/// Evaluations a cycle budget keeps for the end of a mode after its search loops (the
/// cluster's count probes, twice where they are widened, and the residue quotient's two
/// evaluations), so that a cycle never exceeds its budget ...
const CLUSTER_RESERVE: u32 = 6;
/// ... and in its Newton phase, whose root is pole-free: D at the root and the cluster's
/// two count probes. The rarer ends there (the probes widened, the residue quotient where
/// the probes find a pole after all) check the budget themselves and cut the search. Why:
/// a sweep spread over cycles is cut once a cycle, and what the reserve keeps is lost each
/// time (with 6 on the paper robot's continuous sagged sweeps, a fifth of what a cycle
/// leaves them). A mode at a pole is found by the count's bisection, whose reserve stays
/// [`CLUSTER_RESERVE`]: cut at its residue, it would be bisected to the pole again.
const NEWTON_RESERVE: u32 = 3;
/// The same for [`SpectrumSearch::root_in`], which makes no cluster probes: the root's own
/// evaluation and the caller's reading of the mode there (one evaluation, one spare).
const ROOT_RESERVE: u32 = 3;
/// A bracket left by a search the cycle's budget cut is widened by this (relative, on each
/// side) before it is probed again in the next cycle: along the bench's circle a mode's λ
/// moves by ~1e-4 (relative) per 1 ms cycle, so the narrowed bracket of the last cycle
/// would miss it, while a bracket 2e-3 wide still needs only a few Newton steps.
const RESUME_WIDEN: f64 = 1e-3;
/// Relative step of the symmetric residue quotient at a pole (error O(h²) from the other
/// modes, while the cluster's own spread there is below the pole probe, ≪ h).
const RESIDUE_STEP: f64 = 1e-7;
/// The smallest first step (relative) of a bracket grown from the last gap between
/// clusters ([`SpectrumSearch::grow`]): two clusters a hair apart would otherwise start it
/// so small that its doublings cost more than the bisection they save.
const GROW_MIN_STEP: f64 = 1e-3;
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
pub(in crate::modal) struct Cluster {
    lo: Probe,
    hi: Probe,
    start: usize,
    mult: u32,
    parts: [f64; 6],
    /// The roots of the first `presolved` members (solved with the first one).
    lambdas: [f64; 6],
    presolved: usize,
}

/// What a sweep keeps between calls (plain data): the current cluster and the first
/// bracket's scale. A sweep spread over cycles keeps it between them.
#[derive(Debug, Clone, Copy)]
pub(in crate::modal) struct SweepState {
    cl: Cluster,
    /// A scale for the first bracket: the Rayleigh estimate μ₁(0)/(−μ₁'(0)), rad²/s².
    scale: f64,
    /// The distance between the last two clusters found, rad²/s² (NaN before two): the
    /// next mode's bracket grows from it.
    gap: f64,
}

impl SweepState {
    /// Nothing found yet (before [`SpectrumSearch::start`]).
    pub(in crate::modal) fn new() -> SweepState {
        let zero = Probe {
            x: 0.0,
            count: 0,
            below: 0,
        };
        SweepState {
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
            gap: f64::NAN,
        }
    }
}

/// One sweep over the spectrum of the loaded problem, ascending.
pub(in crate::modal) struct SpectrumSearch<'a, P: Condensed> {
    p: P,
    params: &'a SpectrumParams,
    st: SweepState,
    /// Evaluation counter at the start of the current mode.
    mode_start: u32,
    /// The evaluation counter at which the caller's cycle budget is spent (with
    /// `cycle_base`; `u32::MAX`: no cycle budget) ...
    cycle_base: u32,
    cycle_budget: u32,
    /// Evaluations kept for the end of a mode (`CLUSTER_RESERVE`, or `ROOT_RESERVE`).
    reserve: u32,
    /// ... and whether it cut the last search (not a failure: the bracket it left in the
    /// error is where to go on).
    pub(in crate::modal) cut: bool,
}

impl<'a, P: Condensed> SpectrumSearch<'a, P> {
    pub(in crate::modal) fn new(p: P, params: &'a SpectrumParams) -> SpectrumSearch<'a, P> {
        Self::resume(p, params, SweepState::new())
    }

    /// A sweep from a kept state (see [`SweepState`]).
    pub(in crate::modal) fn resume(
        p: P,
        params: &'a SpectrumParams,
        st: SweepState,
    ) -> SpectrumSearch<'a, P> {
        SpectrumSearch {
            p,
            params,
            st,
            mode_start: 0,
            cycle_base: 0,
            cycle_budget: u32::MAX,
            reserve: CLUSTER_RESERVE,
            cut: false,
        }
    }

    /// Stop every search after `evaluations` more evaluations (marking [`Self::cut`]).
    pub(in crate::modal) fn set_cycle_budget(&mut self, evaluations: u32) {
        self.cycle_base = self.p.evaluations();
        self.cycle_budget = evaluations;
    }

    /// The state to keep.
    pub(in crate::modal) fn state(&self) -> SweepState {
        self.st
    }

    /// The problem searched.
    pub(in crate::modal) fn problem(&mut self) -> &mut P {
        &mut self.p
    }

    /// Check D(0) > 0 (then J(0) = 0) and take the first bracket's scale.
    pub(in crate::modal) fn start(&mut self) -> Result<(), ModalError> {
        let e = self.p.zero_eval();
        let eg = e.eig();
        if !(eg.values[0] > 0.0) {
            return Err(ModalError::NotPositiveDefinite(eg.values[0]));
        }
        let kin = -quad(&e.dd, &eg.vectors[0], e.dim);
        self.st.scale = if kin > 0.0 {
            eg.values[0] / kin
        } else {
            BRACKET_MIN
        };
        Ok(())
    }

    /// Go on from λ = `x` (rad²/s², after [`Self::start`], before any mode): returns J(x),
    /// the index of the first mode at or above x, from which [`Self::mode`] then goes on
    /// in order (one count probe).
    pub(in crate::modal) fn skip_to(&mut self, x: f64) -> usize {
        let pr = self.probe(x);
        self.st.cl.lo = pr;
        pr.count as usize
    }

    /// Mode `i` (0-based); modes must be asked for in order 0, 1, 2, ...
    pub(in crate::modal) fn mode(&mut self, i: usize) -> Result<Mode, ModalError> {
        self.mode_start = self.p.evaluations();
        let cl = self.st.cl;
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

    /// Mode `i` from the bracket (lo, hi) a cut search left (re-probed here; when it
    /// no longer brackets mode `i`, or `i` belongs to the current cluster, as [`Self::mode`]).
    pub(in crate::modal) fn mode_within(
        &mut self,
        i: usize,
        lo: f64,
        hi: f64,
    ) -> Result<Mode, ModalError> {
        let cl = self.st.cl;
        if cl.mult > 0 && (i as u64) < cl.hi.count as u64 && i >= cl.start {
            return self.mode(i);
        }
        self.mode_start = self.p.evaluations();
        // The pose may have moved since the bracket was narrowed: widen it a little.
        let (lo, hi) = (lo * (1.0 - RESUME_WIDEN), hi * (1.0 + RESUME_WIDEN));
        let Some((a, b)) = self.bracket(i, lo, hi)? else {
            return self.mode(i);
        };
        let found = self.solve(i, a, b)?;
        self.new_cluster(i, found)
    }

    /// The root of mode `i` inside (lo, hi) (rad²/s²), by the count's bisection and Newton
    /// as [`Self::mode`] but without the cluster's probes (the caller reads the mode at the
    /// root); Ok(None) when (lo, hi) does not hold mode `i`, or the mode sits at a chain
    /// pole (no end-effector motion there). Within a cycle's budget it keeps fewer
    /// evaluations for the end than a mode's search (no cluster probes follow): meant for a
    /// search of its own, not inside a sweep.
    pub(in crate::modal) fn root_in(
        &mut self,
        i: usize,
        lo: f64,
        hi: f64,
    ) -> Result<Option<f64>, ModalError> {
        self.mode_start = self.p.evaluations();
        self.reserve = ROOT_RESERVE;
        let Some((a, b)) = self.bracket(i, lo, hi)? else {
            return Ok(None);
        };
        Ok(match self.solve(i, a, b)? {
            Found::Pole(_) => None,
            Found::Branch { lambda, .. } => Some(lambda),
        })
    }

    /// The count probes at `lo` and `hi` when they hold mode `i` (J(lo) ≤ i < J(hi)).
    fn bracket(
        &mut self,
        i: usize,
        lo: f64,
        hi: f64,
    ) -> Result<Option<(Probe, Probe)>, ModalError> {
        self.check_budget(lo, hi)?;
        let a = self.probe(lo);
        self.check_budget(lo, hi)?;
        let b = self.probe(hi);
        Ok((a.count as usize <= i && (b.count as usize) > i).then_some((a, b)))
    }

    /// Count probe at x.
    fn probe(&mut self, x: f64) -> Probe {
        let (count, below) = self.p.count(x);
        Probe { x, count, below }
    }

    /// Cut the search (the budget error with the bracket (lo, hi)) unless `n` more
    /// evaluations fit in the cycle's budget.
    fn room_for(&mut self, n: u32, lo: f64, hi: f64) -> Result<(), ModalError> {
        let now = self.p.evaluations();
        let cycle_used = now.wrapping_sub(self.cycle_base);
        if self.cycle_budget != u32::MAX && cycle_used.saturating_add(n) > self.cycle_budget {
            self.cut = true;
            return Err(ModalError::NoConvergence {
                evaluations: now.wrapping_sub(self.mode_start),
                lo,
                hi,
            });
        }
        Ok(())
    }

    /// The budget error, or nothing.
    fn check_budget(&mut self, lo: f64, hi: f64) -> Result<(), ModalError> {
        self.check_budget_keeping(self.reserve, lo, hi)
    }

    /// [`Self::check_budget`] keeping `reserve` evaluations for the end of the mode.
    fn check_budget_keeping(&mut self, reserve: u32, lo: f64, hi: f64) -> Result<(), ModalError> {
        let now = self.p.evaluations();
        let used = now.wrapping_sub(self.mode_start);
        let cycle_used = now.wrapping_sub(self.cycle_base);
        if self.cycle_budget != u32::MAX && cycle_used.saturating_add(reserve) >= self.cycle_budget
        {
            self.cut = true;
            return Err(ModalError::NoConvergence {
                evaluations: used,
                lo,
                hi,
            });
        }
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
        // From the last gap between clusters (at least GROW_MIN_STEP·λ), doubled at each
        // probe that does not reach mode i, at most the geometric growth: the next mode is
        // usually within a gap or two, and a bracket that narrow saves the count's
        // bisection from λ to 2λ.
        let mut step = if lo.x > 0.0 && self.st.gap > 0.0 {
            self.st.gap.max(GROW_MIN_STEP * lo.x)
        } else {
            f64::NAN
        };
        let mut x = if lo.x > 0.0 {
            if step.is_finite() {
                lo.x + step.min((BRACKET_GROWTH - 1.0) * lo.x)
            } else {
                lo.x * BRACKET_GROWTH
            }
        } else {
            (BRACKET_GROWTH * self.st.scale).max(BRACKET_MIN)
        };
        loop {
            self.check_budget(lo.x, x)?;
            let pr = self.probe(x);
            if pr.count as usize > i {
                return Ok((lo, pr));
            }
            lo = pr;
            if step.is_finite() {
                step *= 2.0;
                x = lo.x + step.min((BRACKET_GROWTH - 1.0) * lo.x);
            } else {
                x *= BRACKET_GROWTH;
            }
        }
    }

    /// Narrow J(lo) ≤ i < J(hi) to the mode: bisection on the count while two or more
    /// distinct poles lie inside, probes around a single pole, Newton once pole-free.
    fn solve(&mut self, i: usize, mut lo: Probe, mut hi: Probe) -> Result<Found, ModalError> {
        let eta = self.params.pole_probe;
        loop {
            self.check_budget(lo.x, hi.x)?;
            let known = self.p.pole_interval(lo.x);
            // The closed-form poles say the bracket is pole-free, but the chains' own
            // count steps inside it: a pole within rounding of an end (near-equal poles of
            // cables a hair apart, 1e-12 relative on a symmetric pose perturbed by
            // 1e-12 m). The count decides, as where it alone shows the poles.
            let disagree = known.is_some_and(|(_, pb)| pb >= hi.x && lo.below != hi.below);
            let (pa, pb) = match known {
                Some(ab) if !disagree => ab,
                _ => {
                    // The bracket is pole-free once the blocked count is the same at both
                    // ends.
                    if lo.below == hi.below {
                        return self.newton(i, lo, hi, 0.0, f64::INFINITY);
                    }
                    if hi.x - lo.x <= eta * hi.x {
                        return Ok(Found::Pole(0.5 * (lo.x + hi.x)));
                    }
                    let mid = self.probe(0.5 * (lo.x + hi.x));
                    if mid.count as usize > i {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                    continue;
                }
            };
            if pb >= hi.x {
                return self.newton(i, lo, hi, pa, pb);
            }
            let (_, pc) = self.p.pole_interval(pb * (1.0 + eta)).unwrap_or((pb, pb));
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
        if branch >= self.p.dim() {
            return Err(ModalError::CountMismatch(lo.x));
        }
        let mut x = 0.5 * (lo.x + hi.x);
        let mut prev_step = f64::INFINITY;
        // The last two steps taken (Newton or bisection), for the safeguard.
        let mut steps = [hi.x - lo.x; 2];
        let reserve = self.reserve.min(NEWTON_RESERVE);
        loop {
            self.check_budget_keeping(reserve, lo.x, hi.x)?;
            let e = self.p.eval(x);
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
            // A converged step may land on a bracket's end: x itself is that end when μ
            // there is a rounding's width from zero.
            let within = xn >= lo.x && xn <= hi.x;
            if mu == 0.0 || collapsed || (within && converged) {
                let lambda = if within { xn } else { x };
                // D' at the root itself: near a pole it changes by 2·step/distance, and the
                // participation reads it (one more evaluation).
                let eval = if lambda != x { self.p.eval(lambda) } else { e };
                return Ok(Found::Branch {
                    lambda,
                    eig: eval.eig(),
                    eval,
                    branch,
                });
            }
            // Bisect when Newton leaves the bracket or its step is not below half the step
            // before last (Numerical Recipes' rtsafe): the progress is read from Newton's
            // own steps, since one converging from one side does not narrow the bracket.
            let slow = step > 0.5 * steps[0];
            x = if inside && !slow {
                prev_step = step;
                steps = [steps[1], step];
                xn
            } else {
                prev_step = f64::INFINITY;
                steps = [steps[1], 0.5 * (hi.x - lo.x)];
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
        let mut lo = self.probe(lambda * (1.0 - d));
        let mut hi = self.probe(lambda * (1.0 + d));
        if !(lo.count as usize <= i && (hi.count as usize) > i)
            && self.p.pole_interval(lambda).is_none()
        {
            // Count-only poles (sagged chains): next to a pole the chains' recurrence
            // carries more noise than the probe's width; probe once more, wider.
            let d = NOISY_CLUSTER_PROBE * d;
            self.room_for(2, lambda * (1.0 - d), lambda * (1.0 + d))?;
            lo = self.probe(lambda * (1.0 - d));
            hi = self.probe(lambda * (1.0 + d));
        }
        if !(lo.count as usize <= i && (hi.count as usize) > i) {
            return Err(ModalError::CountMismatch(lambda));
        }
        let mult = hi.count - i as u32;
        let pole_free = match self.p.pole_interval(lo.x) {
            Some((pa, pb)) => pb > hi.x && pa < lo.x,
            None => lo.below == hi.below,
        };
        let (m6, dim) = (*self.p.ee_mass(), self.p.dim());
        let mut lambdas = [lambda; 6];
        let mut presolved = 0;
        let parts = match found {
            Found::Branch {
                eval, eig, branch, ..
            } if pole_free && branch + mult as usize <= dim => {
                let mut members = [(lambda, eval, eig, branch); 6];
                for k in 1..mult as usize {
                    members[k] = self.member(i + k, lo, hi)?;
                    lambdas[k] = members[k].0;
                }
                presolved = mult as usize;
                participations(&m6, dim, &members_residue(&members[..mult as usize]))
            }
            _ => {
                let h = RESIDUE_STEP;
                self.room_for(2, lo.x, hi.x)?;
                let em = self.p.eval(lambda * (1.0 - h));
                let ep = self.p.eval(lambda * (1.0 + h));
                residue_participations(&m6, dim, lambda, h, &em, &ep)
            }
        };
        let old = self.st.cl;
        if old.mult > 0 && lambda > old.lambdas[0] {
            self.st.gap = lambda - old.lambdas[0];
        }
        self.st.cl = Cluster {
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
        self.mode_start = self.p.evaluations();
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

/// The Newton iterate from x on [`pole_free`], NaN when the derivative is not negative.
fn pole_free_newton(mu: f64, dmu: f64, x: f64, pa: f64, pb: f64) -> f64 {
    let (g, dg) = pole_free(mu, dmu, x, pa, pb);
    if dg < 0.0 {
        x - g / dg
    } else {
        f64::NAN
    }
}
