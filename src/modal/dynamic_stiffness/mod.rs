//! The loaded problem and its evaluation: D(λ) = Σ_chains s_c(λ) P_c − λ M_ee (+ the
//! rigid body's constant geometric stiffness), its λ-derivative and the chains' blocked
//! count.
//!
//! [`LoadedChains`] is what `load` computes at one pose and nothing on the hot path writes
//! (but for its memo of the supported chains' poles, filled on first use, see `PoleMemo`);
//! [`EvalScratch`] (`eval.rs`) holds the buffers one evaluation writes (and the evaluation
//! counter); `pole_memo.rs` the supported chains' memoized poles.

use super::engine::{DynEval, MAX_CHAINS, SYM3};
use super::RigidParts;
use crate::cable::{supported_pole_near, Segment};
use crate::cable::{CableModel, Chain, ChainKind, BATCH_MAX_ELEMENTS};
use crate::kinematics::attach_map;
use crate::scene::MAX_CABLES;
use nalgebra::{Matrix3, Matrix6};
use num_complex::Complex64;

/// Discrete chains up to this many elements have their blocked eigenvalues tabulated (16
/// bytes each, reserved once per solver); longer chains (up to
/// [`crate::scene::MAX_ELEMENTS_PER_CABLE`]) compute each one by trigonometry.
const POLE_TABLE_MAX_ELEMENTS: usize = 10_000;

mod eval;
mod pole_memo;
mod problem;
#[cfg(test)]
mod tests;

pub(super) use eval::EvalScratch;
use pole_memo::{PoleMemo, SUPPORTED_POLE_MEMO};
pub use problem::TautChains;

/// Largest number of batched evaluations per λ: every chain, and a supported chain's two
/// segments (one supported chain per cable).
const MAX_BATCHED: usize = MAX_CHAINS + MAX_CABLES;

/// Poles of different chains closer than this (relative) are one pole of a scan over the
/// pole intervals.
const POLE_MERGE: f64 = 1e-12;

/// Where one chain (or one segment of a supported chain) takes its value at λ.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Slot {
    /// Its own scalar evaluation.
    Scalar,
    /// Entry j of the batched discrete evaluation.
    Batch(usize),
    /// Entry j of the batched continuous evaluation.
    Cont(usize),
}

/// How one chain is evaluated at λ.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Plan {
    /// A uniform chain, from its slot.
    Uniform(Slot),
    /// A supported chain, combined from its two segments' slots
    /// ([`supported_from_parts`]).
    Supported {
        free: Segment,
        hidden: Segment,
        free_slot: Slot,
        hidden_slot: Slot,
    },
}

/// The problem of one pose, as `load` leaves it: the chains, how they attach to the
/// end-effector, its mass, the evaluation plan (batches) and the tabulated poles. Read-only
/// on the hot path but for the supported chains' pole memo.
#[derive(Debug, Clone)]
pub(super) struct LoadedChains {
    pub(super) chains: [Chain; MAX_CHAINS],
    /// Rigid body: each chain's projector through the attachment map, Gᵀ P G (6 × 6).
    pub(super) q6: [Matrix6<f64>; MAX_CHAINS],
    pub(super) n_chains: usize,
    /// End-effector mass, kg.
    pub(super) ee_mass_kg: f64,
    /// 3 (point mass) or 6 (rigid body).
    pub(super) dim: usize,
    /// Rigid-body mass matrix diag(m I, I_world), kg and kg·m².
    pub(super) m6: Matrix6<f64>,
    /// Constant stiffness at the end-effector's DOFs besides the chains: the rigid body's
    /// rotational geometric stiffness (N·m/rad) and what [`Self::add_ee_stiffness`] added
    /// (the pulleys' own term), leading `dim` block.
    pub(super) k6: Matrix6<f64>,
    /// The point mass's block of `k6` as its six distinct entries ([`SYM3`] order).
    k3_sym: [f64; 6],
    /// How each chain takes its value at λ (from which batch entries).
    plan: [Plan; MAX_CHAINS],
    /// Chains (and supported chains' segments) evaluated together by the batched
    /// recurrence: their k and m, and their common element count (0 when there are none).
    batch_k: [f64; MAX_BATCHED],
    batch_m: [f64; MAX_BATCHED],
    n_batch: usize,
    batch_n_el: usize,
    /// Each chain's projector as its six distinct entries ([`SYM3`] order).
    proj_sym: [[f64; 6]; MAX_CHAINS],
    /// The continuous chains and segments, evaluated together ([`eval_continuous_batch`]).
    cont_k: [f64; MAX_BATCHED],
    cont_m: [f64; MAX_BATCHED],
    n_cont: usize,
    /// (1 − cos θ_j, cos θ_j) for θ_j = jπ/N, j = 0 ..= N, of the discrete chains'
    /// common element count N = `pole_tab_n` (the blocked eigenvalues without trigonometry).
    pole_tab: Vec<(f64, f64)>,
    pole_tab_n: usize,
    /// The supported chains' lowest blocked eigenvalues, memoized for this load.
    pole_memo: PoleMemo,
    /// A lower bound of each supported chain's first blocked eigenvalue, rad²/s²
    /// ([`supported_pole1_lower_bound`]; −∞ for the other chains): the pole-interval
    /// queries skip a supported chain's pole search when the bound already lies above the
    /// answer.
    pole1_lb: [f64; MAX_CHAINS],
    /// Σ of the end-effector participation over all modes (sum rule), from `load`.
    pub(super) p_total: f64,
}

impl LoadedChains {
    /// Nothing loaded; the pole table's capacity reserved (the only allocation).
    pub(super) fn new() -> LoadedChains {
        let zero = Chain::idle();
        LoadedChains {
            chains: [zero; MAX_CHAINS],
            q6: [Matrix6::zeros(); MAX_CHAINS],
            n_chains: 0,
            ee_mass_kg: 0.0,
            dim: 3,
            m6: Matrix6::zeros(),
            k6: Matrix6::zeros(),
            k3_sym: [0.0; 6],
            plan: [Plan::Uniform(Slot::Scalar); MAX_CHAINS],
            batch_k: [0.0; MAX_BATCHED],
            batch_m: [0.0; MAX_BATCHED],
            n_batch: 0,
            batch_n_el: 0,
            proj_sym: [[0.0; 6]; MAX_CHAINS],
            cont_k: [0.0; MAX_BATCHED],
            cont_m: [0.0; MAX_BATCHED],
            n_cont: 0,
            pole_tab: Vec::with_capacity(POLE_TABLE_MAX_ELEMENTS + 1),
            pole_tab_n: 0,
            pole_memo: PoleMemo::new(),
            pole1_lb: [f64::NEG_INFINITY; MAX_CHAINS],
            p_total: f64::NAN,
        }
    }

    /// Load the chains of the cable models at one pose (point mass when `rigid` is None).
    /// Chains that contribute nothing (zero spring and zero mass: a switched-off effect)
    /// are not loaded, so they cost nothing per evaluation.
    pub(super) fn load(
        &mut self,
        models: &[CableModel],
        ee_mass_kg: f64,
        rigid: Option<RigidParts<'_>>,
    ) {
        self.load_chains(models, ee_mass_kg, rigid);
        self.p_total = self.sum_rule_total(ee_mass_kg);
        self.fill_pole_table();
        self.plan_batches();
    }

    /// The end-effector's mass (and inertia, geometric stiffness) and the active chains
    /// with their projectors.
    fn load_chains(
        &mut self,
        models: &[CableModel],
        ee_mass_kg: f64,
        rigid: Option<RigidParts<'_>>,
    ) {
        self.n_chains = 0;
        self.ee_mass_kg = ee_mass_kg;
        self.m6 = Matrix6::zeros();
        self.m6
            .fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * ee_mass_kg));
        self.k6 = Matrix6::zeros();
        self.k3_sym = [0.0; 6];
        self.dim = 3;
        if let Some((inertia, _, kgeo)) = rigid {
            self.dim = 6;
            self.m6.fixed_view_mut::<3, 3>(3, 3).copy_from(inertia);
            self.k6.fixed_view_mut::<3, 3>(3, 3).copy_from(kgeo);
        }
        for (i, m) in models.iter().enumerate() {
            let g = rigid.map(|(_, arms, _)| attach_map(&arms[i]));
            for c in &m.chains[..m.n_chains] {
                let idle =
                    matches!(c.kind, ChainKind::Discrete { k, m, .. } if k == 0.0 && m == 0.0);
                if idle || self.n_chains >= MAX_CHAINS {
                    continue;
                }
                self.chains[self.n_chains] = *c;
                self.pole1_lb[self.n_chains] = f64::NEG_INFINITY;
                if let ChainKind::Supported { free, hidden } = c.kind {
                    self.pole_memo.clear(self.n_chains);
                    self.pole1_lb[self.n_chains] = supported_pole1_lower_bound(&free, &hidden);
                }
                for (j, &(r, col)) in SYM3.iter().enumerate() {
                    self.proj_sym[self.n_chains][j] = c.proj[(r, col)];
                }
                if let Some(g) = g {
                    self.q6[self.n_chains] = g.transpose() * c.proj * g;
                }
                self.n_chains += 1;
            }
        }
    }

    /// Sum rule: Σ over all modes of the participation = tr(M_ee M_∞⁻¹), with M_∞ the
    /// end-effector's mass plus every chain's end mass (the λ → −∞ limit of −D(λ)/λ).
    fn sum_rule_total(&self, ee_mass_kg: f64) -> f64 {
        let mut m_inf = self.m6;
        let mut m_inf3 = Matrix3::identity() * ee_mass_kg;
        let mut q_cache = (0usize, 0.0f64);
        for i in 0..self.n_chains {
            let me = match self.chains[i].kind {
                ChainKind::Discrete { n_el, .. } if n_el > 1 => {
                    if q_cache.0 != n_el {
                        q_cache = (n_el, crate::cable::end_mass_q(n_el));
                    }
                    self.chains[i].end_mass_kg_with(q_cache.1)
                }
                _ => self.chains[i].end_mass_kg(),
            };
            if me > 0.0 {
                m_inf += self.q6[i] * me;
                m_inf3 += self.chains[i].proj * me;
            }
        }
        if self.dim == 6 {
            m_inf
                .cholesky()
                .map_or(f64::NAN, |c| (self.m6 * c.inverse()).trace())
        } else {
            // tr(A⁻¹) = (sum of the diagonal cofactors)/det A, A symmetric positive definite.
            let a = &m_inf3;
            let c00 = a[(1, 1)] * a[(2, 2)] - a[(1, 2)] * a[(2, 1)];
            let c11 = a[(0, 0)] * a[(2, 2)] - a[(0, 2)] * a[(2, 0)];
            let c22 = a[(0, 0)] * a[(1, 1)] - a[(0, 1)] * a[(1, 0)];
            let det = a[(0, 0)] * c00 - a[(0, 1)] * (a[(1, 0)] * a[(2, 2)] - a[(1, 2)] * a[(2, 0)])
                + a[(0, 2)] * (a[(1, 0)] * a[(2, 1)] - a[(1, 1)] * a[(2, 0)]);
            if det > 0.0 && c00 > 0.0 && c22 > 0.0 {
                ee_mass_kg * (c00 + c11 + c22) / det
            } else {
                f64::NAN
            }
        }
    }

    /// Pole table for the discrete chains' element count (refilled only when it changes;
    /// the capacity is reserved in `new`).
    fn fill_pole_table(&mut self) {
        let mut n_tab = 0;
        for c in &self.chains[..self.n_chains] {
            if let ChainKind::Discrete { n_el, .. } = c.kind {
                if (2..=POLE_TABLE_MAX_ELEMENTS).contains(&n_el) {
                    n_tab = n_el;
                    break;
                }
            }
        }
        if n_tab != 0 && n_tab != self.pole_tab_n {
            self.pole_tab.clear();
            for j in 0..=n_tab {
                let th = j as f64 * std::f64::consts::PI / n_tab as f64;
                self.pole_tab
                    .push((2.0 * (0.5 * th).sin().powi(2), th.cos()));
            }
            self.pole_tab_n = n_tab;
        }
    }

    /// Batch the discrete chains (and supported chains' discrete segments) of the first
    /// batchable element count, and the continuous chains and segments; the rest are
    /// evaluated one by one.
    fn plan_batches(&mut self) {
        self.n_batch = 0;
        self.n_cont = 0;
        self.batch_n_el = 0;
        let batchable = |k: f64, m: f64, n_el: usize| {
            k > 0.0 && m > 0.0 && (2..=BATCH_MAX_ELEMENTS).contains(&n_el)
        };
        for c in &self.chains[..self.n_chains] {
            let n_el = match c.kind {
                ChainKind::Discrete { k, m, n_el } if batchable(k, m, n_el) => n_el,
                ChainKind::Supported { free, hidden } => {
                    if batchable(free.k, free.m, free.n_el) {
                        free.n_el
                    } else if batchable(hidden.k, hidden.m, hidden.n_el) {
                        hidden.n_el
                    } else {
                        continue;
                    }
                }
                _ => continue,
            };
            self.batch_n_el = n_el;
            break;
        }
        for i in 0..self.n_chains {
            self.plan[i] = match self.chains[i].kind {
                ChainKind::Discrete { k, m, n_el } => Plan::Uniform(self.slot(k, m, n_el)),
                ChainKind::Continuous { k_total, m_total } => {
                    Plan::Uniform(self.slot(k_total, m_total, 0))
                }
                ChainKind::Supported { free, hidden } => Plan::Supported {
                    free,
                    hidden,
                    free_slot: self.slot(free.k, free.m, free.n_el),
                    hidden_slot: self.slot(hidden.k, hidden.m, hidden.n_el),
                },
            };
        }
    }

    /// The batch entry for a uniform chain or segment (spring k, mass m, `n_el` elements;
    /// 0 for the continuous model), appended to its batch, or [`Slot::Scalar`].
    fn slot(&mut self, k: f64, m: f64, n_el: usize) -> Slot {
        if n_el == 0 {
            let j = self.n_cont;
            self.cont_k[j] = k;
            self.cont_m[j] = m;
            self.n_cont += 1;
            Slot::Cont(j)
        } else if k > 0.0 && m > 0.0 && n_el == self.batch_n_el {
            let j = self.n_batch;
            self.batch_k[j] = k;
            self.batch_m[j] = m;
            self.n_batch += 1;
            Slot::Batch(j)
        } else {
            Slot::Scalar
        }
    }

    /// Add a constant stiffness `k` at the end-effector's DOFs (its leading `dim` block;
    /// N/m, N/rad, N·m/rad) to the loaded problem, until the next load: D(λ) and D(0) take
    /// it with the rigid body's geometric stiffness.
    pub(super) fn add_ee_stiffness(&mut self, k: &Matrix6<f64>) {
        let d = self.dim;
        for r in 0..d {
            for c in 0..d {
                self.k6[(r, c)] += k[(r, c)];
            }
        }
        for (j, &(r, c)) in SYM3.iter().enumerate() {
            self.k3_sym[j] = self.k6[(r, c)];
        }
    }

    /// The next distinct pole above `a` over all chains, advancing each chain's pole cursor
    /// `next_pole` past `a` (and first moving it back to the first pole above `a`: the poles
    /// move between the cycles of a scan). Returns the pole and its (chain, number).
    pub(super) fn next_distinct_pole(
        &self,
        next_pole: &mut [usize; MAX_CHAINS],
        a: f64,
    ) -> (f64, usize, usize) {
        let mut b = (f64::INFINITY, 0, 0);
        for i in 0..self.n_chains {
            let mut j = next_pole[i].max(1);
            while j > 1 && self.chain_pole(i, j - 1) > a * (1.0 + POLE_MERGE) {
                j -= 1;
            }
            let mut pole = self.chain_pole(i, j);
            while pole <= a * (1.0 + POLE_MERGE) && pole.is_finite() {
                j += 1;
                pole = self.chain_pole(i, j);
            }
            next_pole[i] = j;
            if pole < b.0 {
                b = (pole, i, j);
            }
        }
        b
    }

    /// Number of natural frequencies of the loaded model: the end-effector's DOF plus every
    /// blocked eigenvalue (`usize::MAX` with a continuous chain).
    pub(super) fn total_modes(&self) -> usize {
        let mut n = self.dim;
        for c in &self.chains[..self.n_chains] {
            match c.kind {
                ChainKind::Continuous { m_total, .. } if m_total > 0.0 => return usize::MAX,
                ChainKind::Discrete { m, n_el, .. } if m > 0.0 => {
                    n += c.mult as usize * (n_el.max(1) - 1);
                }
                ChainKind::Supported { free, hidden } => {
                    let p = crate::cable::supported_n_poles(&free, &hidden);
                    if p >= usize::MAX / 4 {
                        return usize::MAX;
                    }
                    n += c.mult as usize * p;
                }
                _ => {}
            }
        }
        n
    }

    /// Blocked eigenvalue j (1-based; 0 gives 0) of chain i, rad²/s², equal to
    /// [`Chain::pole`] bit for bit (same formula, tabulated cosines; a supported chain's
    /// lowest ones memoized for the load).
    #[inline]
    pub(super) fn chain_pole(&self, i: usize, j: usize) -> f64 {
        if j == 0 {
            return 0.0;
        }
        let c = &self.chains[i];
        if let ChainKind::Discrete { k, m, n_el } = c.kind {
            if n_el == self.pole_tab_n && m > 0.0 && j < n_el {
                let (omc, cth) = self.pole_tab[j];
                return 6.0 * k * omc / (m * (2.0 + cth));
            }
        }
        if let ChainKind::Supported { free, hidden } = c.kind {
            if j <= SUPPORTED_POLE_MEMO {
                return self
                    .pole_memo
                    .get(i, j, |hint| supported_pole_near(&free, &hidden, j, hint));
            }
        }
        c.pole(j)
    }

    /// The pole-free interval (a, b) of D around λ: the nearest blocked eigenvalues of all
    /// chains below and above (0 and ∞ when there are none), rad²/s².
    pub(super) fn pole_interval(&self, lambda: f64) -> (f64, f64) {
        let mut a = 0.0f64;
        let mut b = f64::INFINITY;
        // The chains with closed-form poles first, then the supported ones, each skipped
        // when λ and b lie below its first pole's lower bound (it would give (0, ≥ b)).
        for supported in [false, true] {
            for (i, c) in self.chains[..self.n_chains].iter().enumerate() {
                let lb = self.pole1_lb[i];
                if (lb > f64::NEG_INFINITY) != supported || (lambda < lb && lb >= b) {
                    continue;
                }
                let (lo, hi) = match self.memo_poles_around(i, lambda) {
                    Some(around) => around,
                    None => c.poles_around_with(lambda, |j| self.chain_pole(i, j)),
                };
                a = a.max(lo);
                b = b.min(hi);
            }
        }
        (a, b)
    }

    /// A supported chain's blocked eigenvalues just below and just above λ (as
    /// [`Chain::poles_around`]: the largest ≤ λ, 0 when none, and the next) from its
    /// memoized poles, without evaluating the chain; None for other chains and when λ lies
    /// above the memoized ones.
    #[inline]
    fn memo_poles_around(&self, i: usize, lambda: f64) -> Option<(f64, f64)> {
        if !matches!(self.chains[i].kind, ChainKind::Supported { .. }) {
            return None;
        }
        let mut lo = 0.0;
        for j in 1..=SUPPORTED_POLE_MEMO {
            let p = self.chain_pole(i, j);
            if p > lambda {
                return Some((lo, p));
            }
            lo = p;
        }
        None
    }

    /// The lowest blocked eigenvalue over all chains, rad²/s² (∞ when none).
    pub(super) fn lowest_pole(&self) -> f64 {
        // Tabulated cosines for the discrete chains (no trigonometry per cycle); then the
        // supported chains whose lower bound does not already exclude them.
        let mut low = f64::INFINITY;
        for supported in [false, true] {
            for i in 0..self.n_chains {
                let lb = self.pole1_lb[i];
                if (lb > f64::NEG_INFINITY) == supported && lb < low {
                    low = low.min(self.chain_pole(i, 1));
                }
            }
        }
        low
    }

    /// D(0) from the chains' static end stiffnesses (N elements of spring k in series:
    /// k/N; a continuous chain: S/L), without evaluating the chains; D'(0) is left zero.
    #[inline]
    pub(super) fn static_eval(&self) -> DynEval {
        let mut d = self.k6;
        for i in 0..self.n_chains {
            let c = &self.chains[i];
            let s0 = match c.kind {
                ChainKind::Discrete { k, n_el, .. } => k / n_el.max(1) as f64,
                ChainKind::Continuous { k_total, .. } => k_total,
                ChainKind::Supported { free, hidden } => {
                    crate::cable::supported_static(&free, &hidden)
                }
            };
            if self.dim == 6 {
                d += self.q6[i] * s0;
            } else {
                let mut v = d.fixed_view_mut::<3, 3>(0, 0);
                v += c.proj * s0;
            }
        }
        DynEval {
            d,
            dd: Matrix6::zeros(),
            below: 0,
            dim: self.dim,
        }
    }

    /// D(λ) at a complex λ (the damped frequency response, `frf`): K₆ − λM₆ + Σ_chains
    /// s_c(λ) P_c (P_c through the attachment map for a rigid body), each chain by its
    /// recurrence at complex λ ([`Chain::eval_at`]). Point mass: the leading 3 × 3 block.
    pub(super) fn d_complex(&self, lambda: Complex64) -> Matrix6<Complex64> {
        let re = |x: f64| Complex64::new(x, 0.0);
        let mut d = self.k6.map(re) - self.m6.map(re) * lambda;
        for i in 0..self.n_chains {
            let s = self.chains[i].eval_at(lambda).s;
            if self.dim == 6 {
                d += self.q6[i].map(|x| re(x) * s);
            } else {
                let mut v = d.fixed_view_mut::<3, 3>(0, 0);
                v += self.chains[i].proj.map(|x| re(x) * s);
            }
        }
        d
    }
}

/// A lower bound of a supported chain's first blocked eigenvalue (both ends held), rad²/s²:
/// with C the chain's static compliance end to end and M its total mass,
/// λ₁ ≥ 1/tr(K⁻¹M) ≥ 4/(C M), since K⁻¹ of springs in series is c_i (C − c_j)/C ≤ C/4
/// (c_i the compliance from the drum to node i ≤ node j) and M's entries are ≥ 0 and sum to
/// at most M; half of that is returned (a margin for rounding). ∞ without mass.
fn supported_pole1_lower_bound(free: &Segment, hidden: &Segment) -> f64 {
    let total = |s: &Segment| s.m * s.n_el.max(1) as f64;
    let mass = total(free) + total(hidden);
    if !(mass > 0.0) {
        return f64::INFINITY;
    }
    let compliance = 1.0 / free.static_stiffness() + 1.0 / hidden.static_stiffness();
    let lb = 2.0 / (compliance * mass);
    if lb.is_nan() {
        0.0
    } else {
        lb
    }
}
