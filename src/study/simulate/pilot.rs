//! How many modes a time response keeps: the fewest whose estimated truncation error on the
//! end-effector's deviation is within a tolerance of its peak.
//!
//! **The estimate.** With the static correction, u_K = F f + Σ_{j≤K} φ_j d_j, d_j = q_j −
//! φ_jᵀf/λ_j the dynamic part of mode j: the modes left out answer with their quasi-static
//! part exactly, and what K modes miss is the dynamic parts of the others. A pilot run of N
//! modes (a basis of 24, 48, 96, … modes at a pose, the whole path's load) gives those of
//! modes K < j ≤ N exactly, for every cluster end K at once (suffix sums of the per-mode
//! dynamic parts at each sample); the modes beyond N are estimated conservatively, the whole
//! residual flexibility F_r(N) = F_ψ − Σ_{j≤N} φ_jψ_jᵀ/λ_j (ψ, F_ψ the load shapes and flexibility
//! of the whole robot's quasi-static inertia, [`crate::modal::quasi_static`]) put at the lowest frequency left
//! out, ω_{N+1}, with that mode's damping ratio (each left-out mode's dynamic part relative
//! to its static one is largest for the lowest of them: below a mode, the load's
//! amplification minus one, (ω_load/ω_j)², falls with ω_j):
//!
//! ```text
//!     e(K) = max_t |Σ_{K<j≤N} φ_j d_j(t)| + e_tail(N),
//!     e_tail(N) = max_t |F_r(N) (x(t) − f(t))|,   ẍ + 2ζω_{N+1}ẋ + ω_{N+1}² x = ω_{N+1}² f,
//! ```
//!
//! x the unit-gain oscillator driven by the load (each end-effector direction). The pilot
//! basis grows until e_tail(N) is within half the tolerance (or it holds every mode of the
//! model, or the most a response takes); K is then the fewest modes, at a cluster's end,
//! with e(K) within the tolerance of the pilot's peak |u_N|. A gap of modes the
//! end-effector hardly moves in (the paper robot's 24 cable modes below its end-effector
//! triplet) does not fool it, as a K-versus-2K comparison would be fooled: while the
//! end-effector modes are beyond N their flexibility is in F_r(N), put at the low frequency
//! of the first cable mode left out, so the pilot grows past them; within N they are exact.
//!
//! **Where K may end.** Along a path the basis is replaced and the motion carried by the
//! mass overlap of the old and new modes ([`super::updates`]); a near-degenerate pair that
//! a cut separates (mode K in the basis, its partner K+1 not) rotates into each other
//! along the path, and every update then drops the share of the kept mode's motion that
//! has turned into the partner (on the paper robot's circle the end-effector pair at
//! 33.75 Hz, exactly degenerate on the symmetry axes: with K = 38 between the two, 4.5 %
//! of the kept mode's mass left the basis at each update across an axis, an error that
//! grows with the update interval). So K ends where the next mode's frequency is at least
//! [`CUT_SEPARATION`] above the last one kept (a *separated* cluster end), the fewest such
//! modes meeting the tolerance; only when no separated end does is any cluster end taken.

use crate::estimator::{EeModalBasis, Estimator};
use crate::modal::response::{ModalResponse, ResponseError, MAX_RESPONSE_MODES};
use crate::scene::Damping;
use nalgebra::{Matrix6, Vector6};

/// Default tolerance on the end-effector's deviation, relative to its peak.
pub const DEFAULT_TOLERANCE: f64 = 1e-3;
/// Smallest accepted tolerance (below it rounding and the reference's own error decide).
pub const MIN_TOLERANCE: f64 = 1e-9;
/// Largest accepted tolerance.
pub const MAX_TOLERANCE: f64 = 0.5;
/// The share of the tolerance the estimate beyond the pilot basis may take.
pub const TAIL_SHARE: f64 = 0.5;
/// The pilot's first basis, modes.
pub(crate) const FIRST_PILOT: usize = 24;
/// The least relative frequency gap ω_{K+1}/ω_K − 1 at a separated cut (module docs): the
/// paper robot's end-effector pairs split by up to 3.4 % along its circle, exactly
/// degenerate on its symmetry axes.
pub const CUT_SEPARATION: f64 = 0.05;

/// The modes kept and what the estimate says of them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeChoice {
    /// Modes kept (at a cluster's end).
    pub modes: usize,
    /// The estimated truncation error e(K) relative to the peak (module docs); 0 when every
    /// mode of the model is kept.
    pub estimate: f64,
    /// Peak |translation| of the deviation with the pilot's largest basis, m.
    pub peak_m: f64,
    /// Whether the estimate is within the tolerance (false: the most modes the response
    /// takes, [`MAX_RESPONSE_MODES`], did not reach it).
    pub met: bool,
    /// Modes of the pilot's basis (its memory: [`crate::study::cost::Work::Simulate`]).
    pub pilot_modes: usize,
}

/// The number of modes at each cluster's end of `basis` (ascending): a cluster is cut
/// nowhere. Structured shapes name their clusters; the dense model's modes are one
/// cluster per λ equal to its neighbour within 1e-9.
pub fn cluster_ends(basis: &EeModalBasis) -> Vec<usize> {
    let n = basis.lambda.len();
    let mut ends = Vec::new();
    for k in 1..=n {
        let same = k < n
            && match &basis.shapes {
                Some(s) => s.modes[k].cluster_start < k,
                None => (basis.lambda[k] - basis.lambda[k - 1]).abs() <= 1e-9 * basis.lambda[k],
            };
        if !same {
            ends.push(k);
        }
    }
    ends
}

/// Whether a cut after the first `k` modes of `basis` is separated (module docs): the
/// basis holds mode k+1 and its frequency is at least [`CUT_SEPARATION`] above mode k's
/// (false past the basis's last mode: its next frequency is not known).
pub fn separated(basis: &EeModalBasis, k: usize) -> bool {
    k > 0
        && k < basis.lambda.len()
        && (basis.lambda[k] / basis.lambda[k - 1]).sqrt() - 1.0 >= CUT_SEPARATION
}

/// e_tail(K) of the module docs, m: the largest |translation| of F_r(K)(x − f) along the
/// loads, x the unit-gain oscillator at ω_{K+1}.
pub fn truncation_estimate(
    basis: &EeModalBasis,
    k: usize,
    damping: &Damping,
    loads: &[Vector6<f64>],
    dt_s: f64,
) -> Result<f64, crate::modal::response::ResponseError> {
    if k >= basis.lambda.len() {
        return Ok(0.0);
    }
    let mut rf = basis.load_flexibility;
    for j in 0..k {
        rf -= basis.phi_ee[j] * basis.load_ee[j].transpose() / basis.lambda[j];
    }
    let dim = basis.dim;
    // The unit-gain oscillator at λ_{K+1} on each direction: mode i has φ = √λ e_i, so its
    // displacement is f_i quasi-statically and displacement_with(f, 0) is x − f.
    let l = basis.lambda[k];
    let lambdas = [l; 6];
    let mut phis = [Vector6::zeros(); 6];
    for (i, p) in phis.iter_mut().enumerate().take(dim) {
        p[i] = l.sqrt();
    }
    let mut r = ModalResponse::new(dim);
    let mut unit = Matrix6::zeros();
    for i in 0..dim {
        unit[(i, i)] = 1.0;
    }
    r.set_basis(&lambdas[..dim], &phis[..dim], damping, &unit, &unit)?;
    let zero = Matrix6::zeros();
    let mut worst = 0.0f64;
    for (i, f) in loads.iter().enumerate() {
        if i > 0 {
            r.step(&loads[i - 1], f, dt_s);
        }
        let dynamic = r.displacement_with(f, &zero);
        let e = rf * dynamic;
        worst = worst.max(e.fixed_rows::<3>(0).norm());
    }
    Ok(worst)
}

/// What a pilot run of a basis found (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Pilot {
    /// Modes of the basis the pilot ran (≥ N).
    pub basis_modes: usize,
    /// N, the modes the pilot ran (a cluster's end).
    pub reference: usize,
    /// e_tail(N), m (0 when the basis holds every mode of the model).
    pub tail_m: f64,
    /// Peak |translation| of u_N, m.
    pub peak_m: f64,
    /// The cluster ends K ≤ N, ascending.
    pub ends: Vec<usize>,
    /// max_t |Σ_{K<j≤N} φ_j d_j(t)| for each of `ends`, m.
    pub differences_m: Vec<f64>,
    /// Whether each of `ends` is separated ([`separated`]).
    pub separated: Vec<bool>,
}

impl Pilot {
    /// e(K) of the module docs for the cluster end `k` ≤ N, m.
    pub fn estimate_m(&self, k: usize) -> Option<f64> {
        let i = self.ends.iter().position(|&e| e == k)?;
        Some(self.differences_m[i] + self.tail_m)
    }

    /// The fewest modes at a separated cluster end (module docs) whose e(K) is within
    /// `tolerance` of the peak, else at any cluster end, and that estimate relative to the
    /// peak; N when none (`met` false).
    fn choice(&self, tolerance: f64) -> ModeChoice {
        let rel = |e: f64| {
            if self.peak_m > 0.0 {
                e / self.peak_m
            } else {
                0.0
            }
        };
        for only_separated in [true, false] {
            for ((&k, &d), &sep) in self
                .ends
                .iter()
                .zip(&self.differences_m)
                .zip(&self.separated)
            {
                if (sep || !only_separated) && d + self.tail_m <= tolerance * self.peak_m {
                    return ModeChoice {
                        modes: k,
                        estimate: rel(d + self.tail_m),
                        peak_m: self.peak_m,
                        met: true,
                        pilot_modes: self.basis_modes,
                    };
                }
            }
        }
        ModeChoice {
            modes: self.reference,
            estimate: rel(self.tail_m),
            peak_m: self.peak_m,
            met: self.tail_m <= tolerance * self.peak_m,
            pilot_modes: self.basis_modes,
        }
    }
}

/// The pilot run of `basis` under the loads `f` (one per sample, `dt_s` apart, linear
/// between them); `complete`: the basis holds every mode of the model. Allocates.
pub fn pilot(
    basis: &EeModalBasis,
    complete: bool,
    damping: &Damping,
    loads: &[Vector6<f64>],
    dt_s: f64,
) -> Result<Pilot, ResponseError> {
    let len = basis.lambda.len();
    let all = cluster_ends(basis);
    // N: every mode when complete (and within the response's limit), else the last
    // cluster end short of the basis's last mode (ω_{N+1} known).
    let whole = complete && len <= MAX_RESPONSE_MODES;
    let reference = all
        .iter()
        .copied()
        .rfind(|&k| k <= MAX_RESPONSE_MODES && (whole || k < len))
        .unwrap_or(0);
    let ends: Vec<usize> = all.into_iter().filter(|&k| k <= reference).collect();
    let mut differences_m = vec![0.0f64; ends.len()];
    let mut peak_m = 0.0f64;
    if reference > 0 {
        let mut r = ModalResponse::new(basis.dim);
        let mut flex = Matrix6::zeros();
        flex.copy_from(&basis.flexibility);
        r.set_basis(
            &basis.lambda[..reference],
            &basis.phi_ee[..reference],
            damping,
            &flex,
            &basis.ee_mass,
        )?;
        r.set_load_shapes(&basis.load_ee[..reference], &basis.load_flexibility)?;
        for (i, f) in loads.iter().enumerate() {
            if i > 0 {
                r.step(&loads[i - 1], f, dt_s);
            }
            peak_m = peak_m.max(r.displacement(f).fixed_rows::<3>(0).norm());
            // Suffix sums Σ_{j ≥ K} of the dynamic parts, read at each cluster end K.
            let mut sum = Vector6::zeros();
            let mut e = ends.len();
            for j in (0..reference).rev() {
                sum += r.dynamic_part(j, f);
                while e > 0 && ends[e - 1] > j {
                    e -= 1;
                }
                if e > 0 && ends[e - 1] == j {
                    let d = &mut differences_m[e - 1];
                    *d = (*d).max(sum.fixed_rows::<3>(0).norm());
                }
            }
        }
    }
    let tail_m = if whole {
        0.0
    } else {
        truncation_estimate(basis, reference, damping, loads, dt_s)?
    };
    let separated = ends.iter().map(|&k| separated(basis, k)).collect();
    Ok(Pilot {
        basis_modes: len,
        reference,
        tail_m,
        peak_m,
        ends,
        differences_m,
        separated,
    })
}

/// The largest pilot basis, modes: the most a response takes, less a cluster's completion.
const PILOT_LIMIT: usize = MAX_RESPONSE_MODES - crate::modal::MAX_MULTIPLICITY as usize;

/// The bases the pilot grows through at one pose when `at_least` modes must be kept: 24,
/// 48, 96, … (the first at least `at_least`) up to `PILOT_LIMIT`.
pub fn pilot_sizes(at_least: usize) -> Vec<usize> {
    let floor = at_least.clamp(1, PILOT_LIMIT);
    let mut asked = FIRST_PILOT.max(floor).min(PILOT_LIMIT);
    let mut out = vec![asked];
    while asked < PILOT_LIMIT {
        asked = (asked * 2).min(PILOT_LIMIT);
        out.push(asked);
    }
    out
}

/// What watches the pilot's growth: the memory of each basis checked before it is built,
/// and a progress bar advanced by each basis's modes.
pub struct Growth<'a> {
    /// Refuses a pilot basis of this many modes past the memory budget.
    pub check: &'a dyn Fn(usize) -> Result<(), crate::memory_budget::OverBudget>,
    /// Advanced by the modes of each basis run ([`pilot_sizes`]' total per pose).
    pub bar: &'a super::super::progress::Progress,
}

/// The pilot at the estimator's current pose: bases of 24, 48, 96, … modes (at least
/// `at_least`) until e_tail is within [`TAIL_SHARE`] of `tolerance`, or the basis holds
/// every mode of the model, or the most a response takes. A basis the engine cannot give
/// (a high cluster it cannot resolve) ends the growth at the last one it gave; when the
/// first fails, smaller ones are tried down to `at_least` (the estimate says what the
/// pilot could not see: its tail is the conservative bound). Each basis's memory is checked
/// first (`growth`): past the budget the choice of K is refused (`at_least` = 0), while
/// the assessment of a K given (`at_least` > 0) ends its growth at the last basis it ran
/// (its tail the conservative bound again).
fn grown_pilot(
    est: &mut Estimator,
    at_least: usize,
    damping: &Damping,
    loads: &[Vector6<f64>],
    dt_s: f64,
    tolerance: f64,
    growth: Option<&Growth<'_>>,
) -> Result<Pilot, super::StudyError> {
    let build = |e: String| super::StudyError::Build(format!("choosing the modes: {e}"));
    let floor = at_least.clamp(1, PILOT_LIMIT);
    let mut asked = FIRST_PILOT.max(floor).min(PILOT_LIMIT);
    let mut last: Option<Pilot> = None;
    let mut advanced = 0usize;
    let planned: usize = pilot_sizes(at_least).iter().sum();
    let done = |p: Pilot, advanced: usize| {
        if let Some(g) = growth {
            g.bar.advance(planned.saturating_sub(advanced));
        }
        Ok(p)
    };
    loop {
        if let Some(Err(over)) = growth.map(|g| (g.check)(asked)) {
            match last {
                Some(p) if at_least > 0 => return done(p, advanced),
                _ => return Err(over.into()),
            }
        }
        let basis = match est.ee_modal_basis(asked) {
            Ok(b) => b,
            Err(crate::estimator::BasisError::Memory(over)) => return Err(over.into()),
            Err(e) => match last {
                Some(p) => return done(p, advanced),
                None if asked > floor => {
                    asked = (asked / 2).max(floor);
                    continue;
                }
                None => return Err(build(e.to_string())),
            },
        };
        let complete = basis.lambda.len() < asked;
        let p = pilot(&basis, complete, damping, loads, dt_s).map_err(|e| build(e.to_string()))?;
        drop(basis);
        if let Some(g) = growth {
            g.bar.advance(asked);
        }
        advanced += asked;
        let enough = p.reference >= at_least && p.tail_m <= TAIL_SHARE * tolerance * p.peak_m;
        let grown = last.as_ref().is_some_and(|l| l.reference >= p.reference);
        if enough || complete || asked >= PILOT_LIMIT || grown {
            return done(p, advanced);
        }
        last = Some(p);
        asked = (asked * 2).min(PILOT_LIMIT);
    }
}

/// The choice at the estimator's current pose (module docs); `met` false when the most
/// modes a response takes do not reach `tolerance`; `growth` watches the pilot (None: only
/// the shapes' own memory check).
pub fn choose(
    est: &mut Estimator,
    damping: &Damping,
    loads: &[Vector6<f64>],
    dt_s: f64,
    tolerance: f64,
    growth: Option<&Growth<'_>>,
) -> Result<ModeChoice, super::StudyError> {
    Ok(grown_pilot(est, 0, damping, loads, dt_s, tolerance, growth)?.choice(tolerance))
}

/// What the estimate says of `given` modes (a cluster cut completed) at the estimator's
/// current pose: e(K) of the K kept, from a pilot of more modes.
pub fn assess(
    est: &mut Estimator,
    given: usize,
    damping: &Damping,
    loads: &[Vector6<f64>],
    dt_s: f64,
    tolerance: f64,
    growth: Option<&Growth<'_>>,
) -> Result<ModeChoice, super::StudyError> {
    let build = |e: String| super::StudyError::Build(format!("assessing the modes: {e}"));
    if let Some(g) = growth {
        (g.check)(given)?;
    }
    let kept = est
        .ee_modal_basis(given)
        .map_err(|e| build(e.to_string()))?
        .lambda
        .len();
    let p = grown_pilot(est, kept, damping, loads, dt_s, tolerance, growth)?;
    let e = match p.estimate_m(kept) {
        Some(e) => e,
        // Past the pilot (the most a response takes): its tail alone.
        None => p.tail_m,
    };
    let estimate = if p.peak_m > 0.0 { e / p.peak_m } else { 0.0 };
    Ok(ModeChoice {
        modes: given,
        estimate,
        peak_m: p.peak_m,
        met: estimate <= tolerance,
        pilot_modes: p.basis_modes,
    })
}
