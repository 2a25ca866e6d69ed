//! The loaded problem and its evaluation: D(λ) = Σ_chains s_c(λ) P_c − λ M_ee (+ the
//! rigid body's constant geometric stiffness), its λ-derivative and the chains' blocked
//! count.
//!
//! [`LoadedChains`] is what `load` computes at one pose and nothing on the hot path writes
//! (but for its memo of the supported chains' poles, filled on first use, see `PoleMemo`);
//! [`EvalScratch`] holds the buffers one evaluation writes (and the evaluation counter).

use super::RigidParts;
use crate::cable::{
    eval_continuous_batch, eval_discrete_batch, CableModel, Chain, ChainEval, ChainKind,
    BATCH_MAX_ELEMENTS,
};
use crate::cable::{supported_from_parts, supported_pole_near, Segment};
use crate::eig3::eig3;
use crate::kinematics::attach_map;
use crate::scene::MAX_CABLES;
use std::sync::atomic::{AtomicU64, Ordering};

/// Discrete chains up to this many elements have their blocked eigenvalues tabulated (16
/// bytes each, reserved once per solver); longer chains (up to
/// [`crate::scene::MAX_ELEMENTS_PER_CABLE`]) compute each one by trigonometry.
const POLE_TABLE_MAX_ELEMENTS: usize = 10_000;
use nalgebra::{Matrix3, Matrix6, SymmetricEigen, Vector6};
use num_complex::Complex64;

/// (row, column) of the six distinct entries of a symmetric 3 × 3 matrix, in the order
/// both solvers store a point mass's D and D' while summing the chains.
///
/// Why: a point mass's D is a symmetric 3 × 3 block; summing its six distinct entries
/// instead of nine (or 36 in a 6 × 6) is what keeps one evaluation cheap, and the two
/// solvers must agree on the order to share the assembly's conventions.
pub(in crate::modal) const SYM3: [(usize, usize); 6] =
    [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// A supported chain's blocked eigenvalues 1 ..= this many are memoized per load (the
/// engine asks for the lowest few, many times a cycle); higher ones are searched each time.
const SUPPORTED_POLE_MEMO: usize = 16;

/// The loaded supported chains' blocked eigenvalues ([`Chain::pole`], a safeguarded Newton
/// search each), each computed on its first use after `load` and kept until the next:
/// f64 bits, NaN for not yet computed. Atomic (relaxed) so that the loaded problem stays
/// read-only and shareable; fixed size, no allocation. Each search starts from the value
/// the same chain's pole had at the last load where it was computed (`hint`: poses change
/// little from one cycle to the next, so Newton needs two or three steps from there); the
/// search is safeguarded by its bracket, so a stale or foreign hint only costs steps.
#[derive(Debug)]
struct PoleMemo {
    memo: [[AtomicU64; SUPPORTED_POLE_MEMO]; MAX_CHAINS],
    hint: [[f64; SUPPORTED_POLE_MEMO]; MAX_CHAINS],
}

/// The bits of a memo entry not computed yet.
const MEMO_EMPTY: u64 = 0x7ff8_0000_0000_0000; // f64::NAN

impl PoleMemo {
    fn new() -> PoleMemo {
        PoleMemo {
            memo: std::array::from_fn(|_| std::array::from_fn(|_| AtomicU64::new(MEMO_EMPTY))),
            hint: [[f64::NAN; SUPPORTED_POLE_MEMO]; MAX_CHAINS],
        }
    }

    /// Forget chain i's poles (each computed one kept as the next search's start).
    fn clear(&mut self, i: usize) {
        for (e, h) in self.memo[i].iter_mut().zip(&mut self.hint[i]) {
            let bits = *e.get_mut();
            if bits != MEMO_EMPTY {
                *h = f64::from_bits(bits);
            }
            *e.get_mut() = MEMO_EMPTY;
        }
    }

    /// Pole j (1 ..= [`SUPPORTED_POLE_MEMO`]) of chain i, from `compute(hint)` on first use.
    #[inline]
    fn get(&self, i: usize, j: usize, compute: impl FnOnce(f64) -> f64) -> f64 {
        let e = &self.memo[i][j - 1];
        let bits = e.load(Ordering::Relaxed);
        if bits != MEMO_EMPTY {
            return f64::from_bits(bits);
        }
        let v = compute(self.hint[i][j - 1]);
        e.store(v.to_bits(), Ordering::Relaxed);
        v
    }
}

impl Clone for PoleMemo {
    fn clone(&self) -> PoleMemo {
        PoleMemo {
            memo: std::array::from_fn(|i| {
                std::array::from_fn(|j| AtomicU64::new(self.memo[i][j].load(Ordering::Relaxed)))
            }),
            hint: self.hint,
        }
    }
}

/// Largest number of chains (a [`CableModel`] has up to three).
pub(super) const MAX_CHAINS: usize = 3 * MAX_CABLES;

/// Largest number of batched evaluations per λ: every chain, and a supported chain's two
/// segments (one supported chain per cable).
const MAX_BATCHED: usize = MAX_CHAINS + MAX_CABLES;

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

/// D(λ), D'(λ) and the blocked count at one λ. D is 3 × 3 (point mass, in the top-left
/// block) or 6 × 6 (rigid body: translation then rotation).
#[derive(Debug, Clone, Copy)]
pub struct DynEval {
    /// Dynamic stiffness D(λ), N/m (N·m/rad in the rotational block).
    pub d: Matrix6<f64>,
    /// dD/dλ, kg (kg·m² in the rotational block).
    pub dd: Matrix6<f64>,
    /// Σ mult · blocked eigenvalues below λ.
    pub below: u32,
    /// 3 or 6.
    pub dim: usize,
}

impl DynEval {
    /// Sorted eigen-decomposition of D.
    pub fn eig(&self) -> EigD {
        if self.dim == 3 {
            let e = eig3(&self.d.fixed_view::<3, 3>(0, 0).into_owned());
            let mut out = EigD {
                values: [f64::INFINITY; 6],
                vectors: [Vector6::zeros(); 6],
                n: 3,
            };
            for k in 0..3 {
                out.values[k] = e.values[k];
                out.vectors[k]
                    .fixed_rows_mut::<3>(0)
                    .copy_from(&e.vectors[k]);
            }
            out
        } else {
            let e = SymmetricEigen::new(self.d);
            let mut idx = [0usize, 1, 2, 3, 4, 5];
            idx.sort_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j]));
            let mut out = EigD {
                values: [0.0; 6],
                vectors: [Vector6::zeros(); 6],
                n: 6,
            };
            for (k, &i) in idx.iter().enumerate() {
                out.values[k] = e.eigenvalues[i];
                out.vectors[k] = e.eigenvectors.column(i).into_owned();
            }
            out
        }
    }
}

/// Sorted eigen-decomposition of D (3 or 6 valid entries).
#[derive(Debug, Clone, Copy)]
pub struct EigD {
    /// Eigenvalues ascending (entries ≥ n are +∞ or unused).
    pub values: [f64; 6],
    /// Matching unit eigenvectors.
    pub vectors: [Vector6<f64>; 6],
    /// Number of valid entries.
    pub n: usize,
}

impl EigD {
    /// Number of negative eigenvalues.
    pub fn negatives(&self) -> usize {
        self.values[..self.n].iter().filter(|&&v| v < 0.0).count()
    }
}

/// vᵀ A v for a symmetric A, over the leading `dim` × `dim` block (3 or 6).
#[inline]
pub(super) fn quad(a: &Matrix6<f64>, v: &Vector6<f64>, dim: usize) -> f64 {
    if dim == 3 {
        let (x, y, z) = (v[0], v[1], v[2]);
        x * x * a[(0, 0)]
            + y * y * a[(1, 1)]
            + z * z * a[(2, 2)]
            + 2.0 * (x * y * a[(0, 1)] + x * z * a[(0, 2)] + y * z * a[(1, 2)])
    } else {
        (v.transpose() * a * v)[(0, 0)]
    }
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

/// What one evaluation of D(λ) writes: the chains' values at the last λ (and the batched
/// evaluators' outputs), and the count of evaluations. No per-evaluation clearing.
#[derive(Debug, Clone)]
pub(super) struct EvalScratch {
    /// Per-chain evaluations at the last λ.
    pub(super) chain_eval: [ChainEval; MAX_CHAINS],
    batch_out: [ChainEval; MAX_BATCHED],
    cont_out: [ChainEval; MAX_BATCHED],
    /// Evaluations of D(λ) since the solver was built.
    pub(super) evaluations: u32,
}

impl EvalScratch {
    /// Zeroed buffers.
    pub(super) fn new() -> EvalScratch {
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
    pub(super) fn eval(&mut self, p: &LoadedChains, lambda: f64) -> DynEval {
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
    pub(super) fn last_pole_interval(&self, p: &LoadedChains) -> (f64, f64) {
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
    pub(super) fn coupling(
        &self,
        p: &LoadedChains,
        x: f64,
        dd: &Matrix6<f64>,
        v: &Vector6<f64>,
    ) -> (f64, f64, bool, u32) {
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
        let lo = p.chain_pole(i, j);
        let hi = p.chain_pole(i, j + 1);
        let up = j == 0 || hi - x < x - lo;
        let jp = if up { j + 1 } else { j };
        (
            best.0 / kin,
            if up { hi } else { lo },
            up,
            (i as u32) << 16 | jp as u32,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cable::Segment;

    /// A cable model with one supported axial chain (free segment of spring `k`).
    fn supported_model(k: f64) -> CableModel {
        let chain = Chain {
            kind: ChainKind::Supported {
                free: Segment {
                    k,
                    m: 0.01,
                    n_el: 40,
                },
                hidden: Segment {
                    k: 3.0e5,
                    m: 0.02,
                    n_el: 25,
                },
            },
            mult: 1,
            proj: Matrix3::identity(),
        };
        CableModel {
            kc: Matrix3::zeros(),
            element_mass_kg: 0.01,
            n_el: 40,
            chains: [chain, Chain::idle(), Chain::idle()],
            n_chains: 1,
            static_stiffness: Matrix3::zeros(),
            hidden: None,
        }
    }

    /// The memoized poles of a supported chain are [`Chain::pole`]'s search: bit for bit
    /// on the first load (the search starts in the bracket's middle), on first use and from
    /// the memo, below and past the memo's size; a new load (another pose) forgets the
    /// previous load's poles and starts each search from them, which finds the same root to
    /// 16ε relative (the search's stopping test: its bracket 4ε wide, Newton's last step
    /// 2ε). The pole intervals equal [`Chain::poles_around`] (no memo) at λ between the
    /// poles and just above them, to the same 16ε.
    #[test]
    fn supported_pole_memo_is_the_search_per_load() {
        let mut p = LoadedChains::new();
        let close = |x: f64, y: f64| x == y || (x - y).abs() <= 16.0 * f64::EPSILON * y;
        let mut worst: f64 = 0.0;
        for (load, k) in [2.0e5, 2.01e5, 3.5e5].into_iter().enumerate() {
            let model = supported_model(k);
            p.load(&[model], 1.0, None);
            let c = model.chains[0];
            for _ in 0..2 {
                for j in 1..=SUPPORTED_POLE_MEMO + 3 {
                    let (m, s) = (p.chain_pole(0, j), c.pole(j));
                    if load == 0 || j > SUPPORTED_POLE_MEMO {
                        assert_eq!(m.to_bits(), s.to_bits(), "k {k} j {j}");
                    }
                    worst = worst.max((m - s).abs() / s / f64::EPSILON);
                    assert!(close(m, s), "k {k} j {j}: {m} vs {s}");
                }
            }
            for j in 1..=SUPPORTED_POLE_MEMO + 2 {
                let pj = c.pole(j);
                for lambda in [pj * (1.0 + 1e-6), 0.5 * (pj + c.pole(j + 1))] {
                    let (a, b) = p.pole_interval(lambda);
                    let (a0, b0) = c.poles_around(lambda);
                    assert!(close(a, a0) && close(b, b0), "k {k} λ {lambda}");
                }
            }
        }
        eprintln!("warm-started pole searches: worst difference {worst:.1} ε");
    }

    /// The lower bound of a supported chain's first blocked eigenvalue holds (against the
    /// search, itself checked against a dense eigen-solve in `cable::supported`) over
    /// stiffness and mass ratios of 1e-4 to 1e4, discrete, continuous and massless hidden
    /// segments; and the pole queries that skip a chain by it answer what the full
    /// computation answers, bit for bit.
    #[test]
    fn first_pole_lower_bound_holds_and_skipping_changes_nothing() {
        let mut rng = crate::simd::TestRng::new(0x0010_b00d);
        for trial in 0..400 {
            let n_f = [0, 1, 2, 10, 40][trial % 5];
            let n_h = if n_f == 0 { 0 } else { [1, 3, 40][trial % 3] };
            let free = Segment {
                k: rng.decades(3.0, 7.0),
                m: rng.decades(-3.0, 0.0),
                n_el: n_f,
            };
            let hidden = Segment {
                k: free.k * rng.decades(-4.0, 4.0),
                m: if trial % 7 == 0 && n_h == 1 {
                    0.0
                } else {
                    free.m * rng.decades(-4.0, 4.0)
                },
                n_el: n_h,
            };
            let lb = supported_pole1_lower_bound(&free, &hidden);
            let p1 = crate::cable::supported_pole(&free, &hidden, 1);
            assert!(
                lb <= p1,
                "trial {trial}: {lb} > {p1} ({free:?}, {hidden:?})"
            );
        }
        // A string-like chain (low first pole) beside a stiff supported chain.
        let mut model = supported_model(2.0e5);
        model.chains[1] = Chain {
            kind: ChainKind::Discrete {
                k: 40.0,
                m: 0.01,
                n_el: 40,
            },
            mult: 2,
            proj: Matrix3::identity(),
        };
        model.n_chains = 2;
        let mut p = LoadedChains::new();
        p.load(&[model], 1.0, None);
        let full = |lambda: f64| {
            let (mut a, mut b) = (0.0f64, f64::INFINITY);
            for i in 0..2 {
                let (lo, hi) = p.chains[i].poles_around(lambda);
                a = a.max(lo);
                b = b.min(hi);
            }
            (a, b)
        };
        assert_eq!(
            p.lowest_pole().to_bits(),
            p.chains[1].pole(1).min(p.chains[0].pole(1)).to_bits()
        );
        let top = p.chains[0].pole(3);
        for i in 0..500 {
            let lambda = top * (i as f64 / 500.0).powi(3);
            assert_eq!(p.pole_interval(lambda), full(lambda), "λ {lambda}");
            let mut s = EvalScratch::new();
            s.eval(&p, lambda);
            let (a, b) = s.last_pole_interval(&p);
            assert!(a <= lambda && lambda <= b, "λ {lambda}: ({a}, {b})");
        }
    }
}
