//! Natural frequencies: the dense reference and the structured real-time solver.
//!
//! The free vibration problem is K u = λ M u, λ = ω² (rad²/s²), f = ω / 2π (Hz)
//! (paper Eqs. 33-35, with K and M in the right places).
//!
//! **Dense reference** ([`assemble`], [`dense_modes`]): the assembled K and M (3 DOF per
//! interior node plus the end-effector node), reduced to a standard symmetric problem
//! with the Cholesky factor of M, solved by a dense symmetric eigensolver. A backward
//! stable solver has absolute eigenvalue error ≈ ε·λ_max, i.e. relative error
//! ε·λ_max/λ on a mode λ ([`dense_relative_accuracy`]). Never on the real-time path.
//!
//! **Structured solver** ([`ModalSolver`]): each cable's interior nodes decouple into
//! scalar chains ([`crate::cable::Chain`]); condensing them onto the end-effector gives
//! its 3 × 3 dynamic stiffness
//!
//! ```text
//!     D(λ) = Σ_chains s_c(λ) P_c − λ m_ee I,
//! ```
//!
//! and the Wittrick-Williams count J(λ) = Σ_chains mult_c · (blocked eigenvalues of c
//! below λ) + (negative eigenvalues of D(λ)) is the exact number of natural frequencies
//! below λ. Below the lowest blocked eigenvalue λ_p every eigenvalue of D decreases
//! (D' = −(mass norm) < 0) from D(0) (the static stiffness, positive definite) to −∞, so
//! the first natural frequency is the unique root of the smallest eigenvalue μ₁(D(λ)) on
//! (0, λ_p). It is found by Newton's method on g(λ) = μ₁(λ)(λ_p − λ) (which removes the
//! pole), safeguarded by the bracket, warm-started from the last cycle, and certified by
//! the count. A mode's end-effector participation is m_ee‖v‖² / vᵀ(−D'(λ))v for the null
//! vector v of D(λ): the share of the mode's kinetic-energy norm carried by the
//! end-effector's own mass.
//!
//! **Sum rules.** With mass-normalised modes φ_k, D(σ)⁻¹ = Σ_k φ_k φ_kᵀ/(λ_k − σ) on the
//! end-effector's coordinates, so Σ_k p_k/λ_k = tr(M_ee D(0)⁻¹), and as σ → −∞,
//! Σ_k p_k = tr(M_ee M_∞⁻¹) with M_∞ = lim −D(σ)/σ: the end-effector's mass plus each
//! chain's end mass (m/3 + (m/6)·U_{N−2}(−2)/U_{N−1}(−2) for N consistent-mass elements of
//! mass m, 0 for a continuous chain). What a set of known modes does not hold bounds the
//! participation of every other mode; [`ModalSolver::ee_mode_tracked`] certifies its answer
//! with it.

use crate::cable::{
    eval_continuous_batch, eval_discrete_batch, CableModel, Chain, ChainEval, ChainKind,
    BATCH_MAX_ELEMENTS,
};
use crate::scene::MAX_CABLES;
use nalgebra::{Matrix3, Matrix6, SymmetricEigen, Vector3, Vector6};
use rigid::RigidParts;

mod dense;
mod eig3;
mod error;
mod rigid;

pub use dense::{
    assemble, assemble_rigid, condense_static, dense_modes, dense_modes_ee,
    dense_relative_accuracy, DenseModes,
};
pub use eig3::{eig3, eig3_jacobi, Eig3};
pub use error::ModalError;
pub use rigid::{attach_map, rigid_geometric_stiffness};

/// Convert λ = ω² (rad²/s²) to Hz.
#[inline]
pub fn lambda_to_hz(lambda: f64) -> f64 {
    lambda.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)
}

/// Convert Hz to λ = ω² (rad²/s²).
#[inline]
pub fn hz_to_lambda(f_hz: f64) -> f64 {
    let w = 2.0 * std::f64::consts::PI * f_hz;
    w * w
}

/// Parameters of the structured solver (finite bounds everywhere).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModalParams {
    /// Largest number of D(λ) evaluations for one root.
    pub max_evaluations: u32,
    /// Relative step size at which Newton stops.
    pub rel_tol: f64,
    /// Largest number of pole intervals scanned for the end-effector mode.
    pub max_scan_intervals: u32,
    /// Largest number of D(λ) evaluations one end-effector scan may spend.
    pub max_scan_evaluations: u32,
    /// Smallest end-effector participation of an end-effector mode (0 < x ≤ 1).
    pub ee_participation_min: f64,
    /// Check the first root with the eigenvalue count (two more evaluations) on every cold
    /// start and every 256th warm one.
    pub certify: bool,
    /// Newton accepts its next iterate once a step is below this relative size: with
    /// quadratic convergence the iterate is then within ~(step)² of the root.
    pub newton_accept: f64,
}

impl Default for ModalParams {
    fn default() -> Self {
        ModalParams {
            max_evaluations: 100,
            rel_tol: 1e-12,
            max_scan_intervals: 400,
            max_scan_evaluations: 1500,
            ee_participation_min: 0.5,
            certify: true,
            newton_accept: 1e-9,
        }
    }
}

/// One root found by the structured solver.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Root {
    /// λ = ω², rad²/s².
    pub lambda: f64,
    /// End-effector participation of the mode (0 ..= 1).
    pub ee_participation: f64,
    /// Evaluations of D(λ) spent.
    pub evaluations: u32,
    /// |μ(λ)| / ‖D(λ)‖ at the answer (relative residual of the condensed problem).
    pub residual: f64,
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

/// The branch of D(λ) closest to vanishing: the smallest |μ_i| / |μ_i'|.
/// vᵀ A v for a symmetric A, over the leading `dim` × `dim` block (3 or 6).
#[inline]
fn quad(a: &Matrix6<f64>, v: &Vector6<f64>, dim: usize) -> f64 {
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

fn nearest_branch(e: &DynEval, eg: &EigD) -> usize {
    let mut branch = 0;
    let mut best = f64::INFINITY;
    for i in 0..eg.n {
        let v = eg.vectors[i];
        let d = -quad(&e.dd, &v, e.dim);
        let dist = eg.values[i].abs() / d.max(f64::MIN_POSITIVE);
        if dist < best {
            best = dist;
            branch = i;
        }
    }
    branch
}
const MAX_CHAINS: usize = 3 * MAX_CABLES;

/// The structured real-time eigen solver. `new` sizes everything; `load` copies the
/// chains of one pose; the root finders never allocate and are bounded.
#[derive(Debug, Clone)]
pub struct ModalSolver {
    params: ModalParams,
    chains: [Chain; MAX_CHAINS],
    /// Rigid body: each chain's projector through the attachment map, Gᵀ P G (6 × 6).
    q6: [Matrix6<f64>; MAX_CHAINS],
    n_chains: usize,
    ee_mass_kg: f64,
    /// 3 (point mass) or 6 (rigid body).
    dim: usize,
    /// Rigid-body mass matrix diag(m I, I_world), kg and kg·m².
    m6: Matrix6<f64>,
    /// Constant rigid-body geometric stiffness (rotational block), N·m/rad.
    k6: Matrix6<f64>,
    next_pole: [usize; MAX_CHAINS],
    /// Chains evaluated together by the batched recurrence: their indices, k and m, and
    /// their common element count (0 when there are none).
    batch_idx: [usize; MAX_CHAINS],
    batch_k: [f64; MAX_CHAINS],
    batch_m: [f64; MAX_CHAINS],
    n_batch: usize,
    /// Scratch for the batched evaluations (no per-evaluation clearing).
    batch_out: [ChainEval; MAX_CHAINS],
    cont_out: [ChainEval; MAX_CHAINS],
    /// Each chain's projector as its six distinct entries ([`SYM3`] order).
    proj_sym: [[f64; 6]; MAX_CHAINS],
    /// The continuous chains, evaluated together ([`eval_continuous_batch`]).
    cont_idx: [usize; MAX_CHAINS],
    cont_k: [f64; MAX_CHAINS],
    cont_m: [f64; MAX_CHAINS],
    n_cont: usize,
    batch_n_el: usize,
    /// Per-chain evaluations at the last λ.
    chain_eval: [ChainEval; MAX_CHAINS],
    /// (1 − cos θ_j, cos θ_j) for θ_j = jπ/N, j = 0 ..= N, of the discrete chains'
    /// common element count N = `pole_tab_n` (the blocked eigenvalues without trigonometry).
    pole_tab: Vec<(f64, f64)>,
    pole_tab_n: usize,
    evaluations: u32,
    /// Watched modes, ascending in λ and in index.
    members: [Member; MAX_MEMBERS],
    n_members: usize,
    /// Record roots with participation ≥ [`P_ADD`] during a scan.
    recording: bool,
    /// End-effector bookkeeping by kind: [full scans from a cold start, watched modes lost,
    /// full scans because the bound was not certified, neighbour searches, full scans
    /// because no watched mode reached the threshold, watched modes dropped, partner
    /// searches].
    rescans: [u64; 7],
    /// Warm cycles left before a failed full scan is retried.
    ee_skip: u32,
    /// tr(M_ee D(0)⁻¹) = Σ_k p_k/λ_k (s²/rad², the weighted sum rule), from `first_root`.
    flex0: f64,
    /// Neighbour searches so far (orders the watched modes by their last search).
    search_count: u64,
    /// First roots solved (schedules the periodic count certificate).
    roots: u64,
    /// Σ of the end-effector participation over all modes (sum rule), from `load`.
    p_total: f64,
}

/// (row, column) of the six distinct entries of a symmetric 3 × 3 matrix.
const SYM3: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// Largest number of watched modes.
const MAX_MEMBERS: usize = 16;
/// Modes found with at least this participation are watched (the modes of the paper's
/// spatial robot below 0.05 hold at most 0.16 together along the circle, dense reference).
const P_ADD: f64 = 0.05;
/// A watched mode whose participation falls below this is dropped (what it holds then
/// counts against the sum-rule bound).
const P_DROP: f64 = 0.02;
/// When the sum-rule bound on the unwatched modes (counting the watched modes not followed
/// this cycle with their last participation) exceeds this, a spectral neighbour of the
/// watched mode whose participation changed most is searched (ahead of need: the bound
/// must stay below the threshold less [`CERT_MARGIN`]). Most participation moves are caught
/// earlier by the partner searches ([`P_PARTNER`]).
const SEARCH_BOUND: f64 = 0.4;
/// ... and that mode's participation must have changed at least this much since its
/// neighbours were searched (else the one searched longest ago is taken).
const SEARCH_LOSS: f64 = 0.02;
/// A scan from cold goes on past the answer until the bound is below this.
const SCAN_BOUND: f64 = 0.15;
/// Allowance for the participation error of the watched modes followed by one Newton step
/// (their participation is that of the predicted point, within ~1e-5 of the root): the
/// answer is certified when the bound plus this is below the threshold.
const CERT_MARGIN: f64 = 0.05;
/// A watched mode is followed by Newton's method from its prediction until a step is
/// below this (relative, usually the first); its participation is that of the last
/// evaluated point, within ~1e-5 of the root.
const CHEAP_ACCEPT: f64 = 1e-5;
/// A watched mode whose approximate participation is within this of the threshold is
/// solved to full accuracy before it is compared with the threshold.
const P_MARGIN: f64 = 0.02;
/// The answer is taken from its tracking step when that step was below this (relative):
/// Newton's error is then ~step² · λ/w ≤ 1e-14 · λ/w (w the distance to the nearer pole;
/// the warm path equals a cold solve to 1e-10 on every cycle of the circle, tested).
const ANSWER_ACCEPT: f64 = 1e-7;
/// Watched modes below this participation are followed one per cycle (the one followed
/// longest ago); the others every cycle. A mode not followed this cycle does not count in
/// the certificate; when that fails, all are followed before anything is rescanned.
const P_LAZY: f64 = 0.15;
/// A watched mode with at least this participation ...
const P_STRONG: f64 = 0.15;
/// ... whose kinetic energy is at least this much in one chain is mixing with that chain's
/// string mode (an avoided crossing): the partner across the chain's nearest pole is
/// searched and watched (two-level model: it holds about that share).
const P_PARTNER: f64 = 0.03;
/// Partner searches per cycle.
const PARTNER_SEARCHES: usize = 1;
/// Modes a neighbour search may walk past (weak ones) on each side.
const NEIGHBOUR_WALK: usize = 3;
/// Pole intervals a neighbour search may cross.
const NEIGHBOUR_INTERVALS: usize = 4;

/// Evaluation point inset from a pole at x into an interval of width w: never past a
/// quarter of a narrow interval (nearly coincident poles of different chains).
fn inset(w: f64, x: f64) -> f64 {
    (1e-9 * x).min(0.25 * w)
}

/// The predictor of a watched mode: quadratic through its last three λ (linear with two).
fn predict(m: &Member) -> f64 {
    if m.age > 1 {
        // Not followed for a while: linear extrapolation over the gap.
        let x = if m.prev.is_finite() {
            m.lambda + m.age as f64 * (m.lambda - m.prev)
        } else {
            m.lambda
        };
        return if x > 0.0 { x } else { m.lambda };
    }
    if m.prev.is_finite() {
        let x = if m.prev2.is_finite() {
            // Quadratic through the last three cycles.
            3.0 * (m.lambda - m.prev) + m.prev2
        } else {
            2.0 * m.lambda - m.prev
        };
        if x > 0.0 {
            return x;
        }
    }
    m.lambda
}

/// One watched mode.
#[derive(Debug, Clone, Copy, Default)]
struct Member {
    /// λ, rad²/s².
    lambda: f64,
    /// λ one and two cycles earlier (NaN when unknown): the predictor.
    prev: f64,
    prev2: f64,
    /// End-effector participation.
    p: f64,
    /// Participation when the mode's neighbours were last searched (NaN: never).
    p_ref: f64,
    /// When its neighbours were last searched (count of searches).
    searched: u64,
    /// Side of the last neighbour search: 0 none yet, 1 below, 2 above.
    last_side: u8,
    /// Position in the spectrum: modes below it, counted with multiplicity.
    index: u32,
    /// Branch of D (eigenvalue number) that vanishes at the mode.
    branch: usize,
    /// The pole interval that contains it, rad²/s².
    a: f64,
    b: f64,
    /// The chain that holds the largest share of the mode's kinetic-energy norm (after the
    /// end-effector): that share, and the chain's pole nearest the mode (rad²/s²) and
    /// whether it lies above.
    share: f64,
    pole: f64,
    pole_up: bool,
    /// That pole's identity (chain << 16 | pole number).
    pole_key: u32,
    /// The pole whose partner was searched last, and the share then.
    partner_key: u32,
    partner_share: f64,
    /// Relative size of the last Newton step and the residual there.
    step: f64,
    residual: f64,
    /// Cycles since it was last followed (0: this cycle). Only members followed this cycle
    /// count in the certificate.
    age: u32,
}

impl Member {
    /// A newly watched mode (no history yet).
    fn new(lambda: f64, p: f64, index: u32, branch: usize, a: f64, b: f64) -> Member {
        Member {
            lambda,
            prev: f64::NAN,
            prev2: f64::NAN,
            p,
            p_ref: p,
            searched: 0,
            last_side: 0,
            index,
            branch,
            a,
            b,
            share: 0.0,
            pole: f64::NAN,
            pole_up: false,
            pole_key: u32::MAX,
            partner_key: u32::MAX,
            partner_share: 0.0,
            step: f64::INFINITY,
            residual: f64::NAN,
            age: 0,
        }
    }
}

/// A root followed by [`ModalSolver::track_root`].
#[derive(Debug, Clone, Copy)]
struct Tracked {
    root: Root,
    branch: usize,
    index: u32,
    a: f64,
    b: f64,
    /// [`Member::share`], [`Member::pole`], [`Member::pole_up`], [`Member::pole_key`].
    share: f64,
    pole: f64,
    pole_up: bool,
    pole_key: u32,
    /// Relative size of the last Newton step (the root's error is of its square).
    step: f64,
}

impl Tracked {
    fn member(&self, prev: f64) -> Member {
        let r = &self.root;
        let mut m = Member::new(
            r.lambda,
            r.ee_participation,
            self.index,
            self.branch,
            self.a,
            self.b,
        );
        m.prev = prev;
        m.share = self.share;
        m.pole = self.pole;
        m.pole_up = self.pole_up;
        m.pole_key = self.pole_key;
        m.step = self.step;
        m.residual = r.residual;
        m
    }
}

impl ModalSolver {
    /// A solver with the given parameters.
    pub fn new(params: ModalParams) -> ModalSolver {
        let zero = Chain {
            kind: ChainKind::Discrete {
                k: 0.0,
                m: 0.0,
                n_el: 1,
            },
            mult: 0,
            proj: Matrix3::zeros(),
        };
        ModalSolver {
            params,
            chains: [zero; MAX_CHAINS],
            q6: [Matrix6::zeros(); MAX_CHAINS],
            n_chains: 0,
            ee_mass_kg: 0.0,
            dim: 3,
            m6: Matrix6::zeros(),
            k6: Matrix6::zeros(),
            next_pole: [1; MAX_CHAINS],
            batch_idx: [0; MAX_CHAINS],
            batch_k: [0.0; MAX_CHAINS],
            batch_m: [0.0; MAX_CHAINS],
            n_batch: 0,
            proj_sym: [[0.0; 6]; MAX_CHAINS],
            batch_out: [ChainEval {
                s: 0.0,
                ds: 0.0,
                below: 0,
            }; MAX_CHAINS],
            cont_out: [ChainEval {
                s: 0.0,
                ds: 0.0,
                below: 0,
            }; MAX_CHAINS],
            cont_idx: [0; MAX_CHAINS],
            cont_k: [0.0; MAX_CHAINS],
            cont_m: [0.0; MAX_CHAINS],
            n_cont: 0,
            batch_n_el: 0,
            chain_eval: [ChainEval {
                s: 0.0,
                ds: 0.0,
                below: 0,
            }; MAX_CHAINS],
            evaluations: 0,
            pole_tab: Vec::with_capacity(crate::scene::MAX_ELEMENTS_PER_CABLE + 1),
            pole_tab_n: 0,
            members: [Member::default(); MAX_MEMBERS],
            n_members: 0,
            recording: false,
            rescans: [0; 7],
            ee_skip: 0,
            flex0: f64::NAN,
            search_count: 0,
            roots: 0,
            p_total: f64::NAN,
        }
    }

    /// Parameters.
    pub fn params(&self) -> &ModalParams {
        &self.params
    }

    /// Replace the parameters.
    pub fn set_params(&mut self, p: ModalParams) {
        self.params = p;
    }

    /// Load the chains of the cable models at one pose and the end-effector mass (kg).
    /// Chains that contribute nothing (zero spring and zero mass: a switched-off effect)
    /// are not loaded, so they cost nothing per evaluation.
    pub fn load(&mut self, models: &[CableModel], ee_mass_kg: f64) {
        self.load_general(models, ee_mass_kg, None);
    }

    /// Load for a rigid end-effector: cable i's end moves with G_i = [I, −[r_i]×] (arm r_i,
    /// world frame, m); `inertia_kg_m2` is the world-frame inertia about the centroid and
    /// `k_geo_rot` the rotational geometric stiffness (N·m/rad) of the tensions.
    pub fn load_rigid(
        &mut self,
        models: &[CableModel],
        ee_mass_kg: f64,
        inertia_kg_m2: &Matrix3<f64>,
        arms_m: &[Vector3<f64>],
        k_geo_rot: &Matrix3<f64>,
    ) {
        self.load_general(models, ee_mass_kg, Some((inertia_kg_m2, arms_m, k_geo_rot)));
    }

    fn load_general(
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
                for (j, &(r, col)) in SYM3.iter().enumerate() {
                    self.proj_sym[self.n_chains][j] = c.proj[(r, col)];
                }
                if let Some(g) = g {
                    self.q6[self.n_chains] = g.transpose() * c.proj * g;
                }
                self.n_chains += 1;
            }
        }
        // Sum rule: Σ over all modes of the participation = tr(M_ee M_∞⁻¹), with M_∞ the
        // end-effector's mass plus every chain's end mass (the λ → −∞ limit of −D(λ)/λ).
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
        self.p_total = if self.dim == 6 {
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
        };
        // Pole table for the discrete chains' element count (refilled only when it changes;
        // the capacity is reserved in `new`).
        let mut n_tab = 0;
        for c in &self.chains[..self.n_chains] {
            if let ChainKind::Discrete { n_el, .. } = c.kind {
                if (2..=crate::scene::MAX_ELEMENTS_PER_CABLE).contains(&n_el) {
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
        // Batch the discrete chains of the most common small element count.
        self.n_batch = 0;
        self.batch_n_el = 0;
        for c in &self.chains[..self.n_chains] {
            if let ChainKind::Discrete { k, m, n_el } = c.kind {
                if k > 0.0 && m > 0.0 && (2..=BATCH_MAX_ELEMENTS).contains(&n_el) {
                    self.batch_n_el = n_el;
                    break;
                }
            }
        }
        for (i, c) in self.chains[..self.n_chains].iter().enumerate() {
            if let ChainKind::Discrete { k, m, n_el } = c.kind {
                if k > 0.0 && m > 0.0 && n_el == self.batch_n_el {
                    self.batch_idx[self.n_batch] = i;
                    self.batch_k[self.n_batch] = k;
                    self.batch_m[self.n_batch] = m;
                    self.n_batch += 1;
                }
            }
        }
        self.n_cont = 0;
        for (i, c) in self.chains[..self.n_chains].iter().enumerate() {
            if let ChainKind::Continuous { k_total, m_total } = c.kind {
                self.cont_idx[self.n_cont] = i;
                self.cont_k[self.n_cont] = k_total;
                self.cont_m[self.n_cont] = m_total;
                self.n_cont += 1;
            }
        }
    }

    /// Blocked eigenvalue j (1-based; 0 gives 0) of chain i, rad²/s², equal to
    /// [`Chain::pole`] bit for bit (same formula, tabulated cosines).
    #[inline]
    fn chain_pole(&self, i: usize, j: usize) -> f64 {
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
        c.pole(j)
    }

    /// The pole-free interval (a, b) of D around the λ of the last evaluation, from the
    /// chains' blocked counts there.
    fn last_pole_interval(&self) -> (f64, f64) {
        let mut a = 0.0f64;
        let mut b = f64::INFINITY;
        for i in 0..self.n_chains {
            let j = self.chain_eval[i].below as usize;
            a = a.max(self.chain_pole(i, j));
            b = b.min(self.chain_pole(i, j + 1));
        }
        (a, b)
    }

    /// Every chain at λ into `chain_eval`: the batched ones together, the rest one by one.
    #[inline]
    fn eval_chains(&mut self, lambda: f64) {
        let nb = self.n_batch;
        if nb > 0 {
            eval_discrete_batch(
                &self.batch_k[..nb],
                &self.batch_m[..nb],
                self.batch_n_el,
                lambda,
                &mut self.batch_out[..nb],
            );
        }
        let nc = self.n_cont;
        if nc > 0 {
            eval_continuous_batch(
                &self.cont_k[..nc],
                &self.cont_m[..nc],
                lambda,
                &mut self.cont_out[..nc],
            );
        }
        let (mut j, mut jc) = (0, 0);
        for i in 0..self.n_chains {
            if j < nb && self.batch_idx[j] == i {
                self.chain_eval[i] = self.batch_out[j];
                j += 1;
            } else if jc < nc && self.cont_idx[jc] == i {
                self.chain_eval[i] = self.cont_out[jc];
                jc += 1;
            } else {
                self.chain_eval[i] = self.chains[i].eval(lambda);
            }
        }
    }

    /// D(λ), D'(λ) and the blocked count.
    #[inline]
    pub fn eval(&mut self, lambda: f64) -> DynEval {
        self.evaluations += 1;
        self.eval_chains(lambda);
        let mut below = 0u32;
        if self.dim == 3 {
            // The six distinct entries of the symmetric 3 × 3 blocks (00 11 22 01 02 12).
            let m = self.ee_mass_kg;
            let mut d = [-lambda * m, -lambda * m, -lambda * m, 0.0, 0.0, 0.0];
            let mut dd = [-m, -m, -m, 0.0, 0.0, 0.0];
            for (i, e) in self.chain_eval[..self.n_chains].iter().enumerate() {
                let p = &self.proj_sym[i];
                for j in 0..6 {
                    d[j] += p[j] * e.s;
                    dd[j] += p[j] * e.ds;
                }
                below += self.chains[i].mult * e.below;
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
        let mut d = self.k6 - self.m6 * lambda;
        let mut dd = -self.m6;
        for ((c, q), e) in self.chains[..self.n_chains]
            .iter()
            .zip(&self.q6)
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

    /// D(0) from the chains' static end stiffnesses (N elements of spring k in series:
    /// k/N; a continuous chain: S/L), without evaluating the chains; D'(0) is left zero.
    fn static_eval(&self) -> DynEval {
        let mut d = self.k6;
        for i in 0..self.n_chains {
            let c = &self.chains[i];
            let s0 = match c.kind {
                ChainKind::Discrete { k, n_el, .. } => k / n_el.max(1) as f64,
                ChainKind::Continuous { k_total, .. } => k_total,
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

    /// Number of natural frequencies strictly below λ (Wittrick-Williams).
    pub fn count_below(&mut self, lambda: f64) -> u32 {
        let e = self.eval(lambda);
        e.below + e.eig().negatives() as u32
    }

    /// Static end-effector stiffness D(0), translational block, N/m.
    pub fn static_stiffness(&mut self) -> Matrix3<f64> {
        self.eval(0.0).d.fixed_view::<3, 3>(0, 0).into_owned()
    }

    /// Static end-effector stiffness D(0) (6 × 6 for a rigid body; top-left 3 × 3 else).
    pub fn static_stiffness6(&mut self) -> Matrix6<f64> {
        self.eval(0.0).d
    }

    /// The sum of the end-effector participation over all modes of the loaded model,
    /// tr(M_ee M_∞⁻¹) with M_∞ = lim −D(λ)/λ as λ → −∞ (the end-effector's mass plus the
    /// chains' end masses): the modes are complete, so Σ_k p_k = Σ_k φ_kᵀ M_ee φ_k equals it.
    /// `dim` for continuous or massless cables, slightly less for discrete ones.
    pub fn participation_total(&self) -> f64 {
        self.p_total
    }

    /// Σ_k p_k/λ_k over all modes, s²/rad²: tr(M_ee D(0)⁻¹), from the last
    /// [`Self::first_root`] (NaN before it or when D(0) is not positive definite).
    pub fn participation_over_lambda(&self) -> f64 {
        self.flex0
    }

    /// 3 (point mass) or 6 (rigid body).
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The lowest blocked eigenvalue over all chains, rad²/s² (∞ when none).
    pub fn lowest_pole(&self) -> f64 {
        // Tabulated cosines for the discrete chains (no trigonometry per cycle).
        (0..self.n_chains)
            .map(|i| self.chain_pole(i, 1))
            .fold(f64::INFINITY, f64::min)
    }

    /// Participation of the mode at root λ with null vector v (unit): the end-effector's
    /// share vᵀ M_ee v / vᵀ(−D'(λ))v of the mode's kinetic-energy norm.
    fn participation(&self, dd: &Matrix6<f64>, v: &Vector6<f64>) -> f64 {
        let kin = -quad(dd, v, self.dim);
        let own = quad(&self.m6, v, self.dim);
        if kin > 0.0 {
            (own / kin).min(1.0)
        } else {
            0.0
        }
    }

    /// The chain holding the largest share of the kinetic-energy norm vᵀ(−D'(x))v of the
    /// mode shape v at the last evaluation (at x): (share, that chain's pole nearest x,
    /// whether the pole is above x). In an avoided crossing with a string mode of that chain,
    /// the share is what the partner across the pole holds (two-level model).
    fn coupling(&self, x: f64, dd: &Matrix6<f64>, v: &Vector6<f64>) -> (f64, f64, bool, u32) {
        let kin = -quad(dd, v, self.dim);
        if !(kin > 0.0) {
            return (0.0, f64::NAN, false, u32::MAX);
        }
        let mut best = (0.0, usize::MAX);
        for i in 0..self.n_chains {
            let w = if self.dim == 3 {
                let (p, x, y, z) = (&self.chains[i].proj, v[0], v[1], v[2]);
                x * x * p[(0, 0)]
                    + y * y * p[(1, 1)]
                    + z * z * p[(2, 2)]
                    + 2.0 * (x * y * p[(0, 1)] + x * z * p[(0, 2)] + y * z * p[(1, 2)])
            } else {
                quad(&self.q6[i], v, 6)
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
        let lo = self.chain_pole(i, j);
        let hi = self.chain_pole(i, j + 1);
        let up = j == 0 || hi - x < x - lo;
        let jp = if up { j + 1 } else { j };
        (
            best.0 / kin,
            if up { hi } else { lo },
            up,
            (i as u32) << 16 | jp as u32,
        )
    }

    /// Root of the `branch`-th smallest eigenvalue of D on (lo, hi), where it is positive at
    /// lo and negative at hi. `pole_lo` (≤ lo, may be 0) and `pole_hi` (≥ hi, may be ∞) are
    /// the poles bounding the interval; Newton runs on μ(λ)(λ − pole_lo)(pole_hi − λ) to
    /// remove them. `guess` starts the iteration. `fast` accepts an iterate once a Newton
    /// step is below [`ModalParams::newton_accept`] (warm starts), else only below `rel_tol`.
    #[allow(clippy::too_many_arguments)]
    fn branch_root_with(
        &mut self,
        branch: usize,
        mut lo: f64,
        mut hi: f64,
        pole_lo: f64,
        pole_hi: f64,
        guess: f64,
        fast: bool,
    ) -> Result<Root, ModalError> {
        let start = self.evaluations;
        let mut x = if guess > lo && guess < hi {
            guess
        } else if hi.is_finite() {
            0.5 * (lo + hi)
        } else {
            2.0 * lo.max(1.0)
        };
        let tol = self.params.rel_tol;
        loop {
            if self.evaluations - start >= self.params.max_evaluations {
                return Err(ModalError::NoConvergence {
                    evaluations: self.evaluations - start,
                    lo,
                    hi,
                });
            }
            let e = self.eval(x);
            let eg = e.eig();
            let mu = eg.values[branch];
            let v = eg.vectors[branch];
            let dmu = quad(&e.dd, &v, e.dim);
            if mu > 0.0 {
                lo = lo.max(x);
            } else if mu < 0.0 {
                hi = hi.min(x);
            }
            let scale = e.d.abs().max().max(f64::MIN_POSITIVE);
            // Newton on μ(λ)(λ − pole_lo)(pole_hi − λ): the poles bounding the interval
            // removed (pole_lo = 0 and pole_hi = ∞ add nothing).
            let (mut g, mut dg) = (mu, dmu);
            if pole_hi.is_finite() {
                let w = pole_hi - x;
                (g, dg) = (g * w, dg * w - g);
            }
            if pole_lo > 0.0 {
                let w = x - pole_lo;
                (g, dg) = (g * w, dg * w + g);
            }
            let mut xn = if dg < 0.0 { x - g / dg } else { f64::NAN };
            let collapsed = hi.is_finite() && (hi - lo) <= 4.0 * f64::EPSILON * x.abs();
            let step = (xn - x).abs();
            let accept = if fast && self.evaluations - start > 1 {
                self.params.newton_accept
            } else {
                tol
            };
            let done =
                mu == 0.0 || collapsed || (xn.is_finite() && step <= accept.max(tol) * x.abs());
            if done {
                let lambda = if mu == 0.0 || !(xn > lo && xn < hi) && collapsed {
                    x
                } else {
                    xn
                };
                return Ok(Root {
                    lambda,
                    ee_participation: self.participation(&e.dd, &v),
                    evaluations: self.evaluations - start,
                    residual: mu.abs() / scale,
                });
            }
            if !(xn > lo && xn < hi) {
                xn = if hi.is_finite() {
                    0.5 * (lo + hi)
                } else {
                    2.0 * x
                };
            }
            x = xn;
        }
    }

    /// The first natural frequency's λ (rad²/s²), warm-started from `warm` when given.
    pub fn first_root(&mut self, warm: Option<f64>) -> Result<Root, ModalError> {
        let start = self.evaluations;
        // D(0) in closed form on warm starts (each chain's static end stiffness); the full
        // evaluation, with D'(0), only for the cold start's Rayleigh guess.
        let e0 = if warm.is_some() {
            self.static_eval()
        } else {
            self.eval(0.0)
        };
        let eg0 = e0.eig();
        if !(eg0.values[0] > 0.0) {
            self.flex0 = f64::NAN;
            return Err(ModalError::NotPositiveDefinite(eg0.values[0]));
        }
        // Weighted sum rule: Σ_k p_k/λ_k = tr(M_ee D(0)⁻¹).
        self.flex0 = (0..self.dim)
            .map(|j| {
                let v = eg0.vectors[j];
                quad(&self.m6, &v, self.dim) / eg0.values[j]
            })
            .sum();
        let lp = self.lowest_pole();
        let guess = match warm {
            Some(w) if w > 0.0 && w < lp => w,
            _ => {
                // Rayleigh estimate from λ = 0: μ(0)/(−μ'(0)).
                let v = eg0.vectors[0];
                let dmu = -quad(&e0.dd, &v, e0.dim);
                let g = eg0.values[0] / dmu.max(f64::MIN_POSITIVE);
                if lp.is_finite() {
                    g.min(0.999 * lp)
                } else {
                    g
                }
            }
        };
        let mut hi = lp;
        if !lp.is_finite() {
            // No poles: D = K − λ M_d is linear, μ₁ crosses zero; find an upper bracket.
            let mut h = guess.max(1e-12) * 2.0;
            let mut ok = false;
            for _ in 0..200 {
                let e = self.eval(h);
                if e.eig().values[0] < 0.0 {
                    ok = true;
                    break;
                }
                h *= 4.0;
            }
            if !ok {
                return Err(ModalError::NoConvergence {
                    evaluations: self.evaluations - start,
                    lo: 0.0,
                    hi: h,
                });
            }
            hi = h;
        }
        let fast = warm.is_some();
        let mut r = self.branch_root_with(0, 0.0, hi, 0.0, lp, guess, fast)?;
        self.roots += 1;
        if self.params.certify && (!fast || self.roots.is_multiple_of(256)) {
            let mut certified = self.certify_first(r.lambda);
            if !certified && fast {
                // A relaxed warm answer may sit outside the certificate's ±1e-10 probe in
                // an ill-conditioned case: solve strictly before reporting anything.
                r = self.branch_root_with(0, 0.0, hi, 0.0, lp, r.lambda, false)?;
                certified = self.certify_first(r.lambda);
            }
            if !certified {
                return Err(ModalError::CountMismatch(r.lambda));
            }
        }
        r.evaluations = self.evaluations - start;
        Ok(r)
    }

    /// The Wittrick-Williams certificate of a first root: no eigenvalue below λ(1 − 1e-10),
    /// at least one below λ(1 + 1e-10).
    fn certify_first(&mut self, lambda: f64) -> bool {
        self.count_below(lambda * (1.0 - 1e-10)) == 0
            && self.count_below(lambda * (1.0 + 1e-10)) > 0
    }

    /// The lowest mode whose end-effector participation is at least
    /// [`ModalParams::ee_participation_min`]: scans the intervals between the chains'
    /// blocked eigenvalues in ascending order and solves for each root of D in them.
    /// `first` is the already-known first root (not solved again).
    pub fn ee_mode(&mut self, first: &Root) -> Result<Root, ModalError> {
        if first.ee_participation >= self.params.ee_participation_min {
            return Ok(*first);
        }
        self.ee_scan(0.0, first.lambda, f64::INFINITY)
    }

    /// Scan upward from the pole interval containing `start` (rad²/s²) for the first root
    /// with participation ≥ the threshold, skipping roots at or below `skip_to`, and giving up
    /// above `limit`. While recording, every root with participation ≥ [`P_ADD`] is watched
    /// and the scan goes on past the answer until the sum-rule bound is below [`SCAN_BOUND`]
    /// (within the same bounds); the answer is the same.
    fn ee_scan(&mut self, start: f64, skip_to: f64, limit: f64) -> Result<Root, ModalError> {
        let begin = self.evaluations;
        let thr = self.params.ee_participation_min;
        let mut best: Option<Root> = None;
        let mut answer: Option<Root> = None;
        let mut a = 0.0f64;
        for i in 0..self.n_chains {
            let (lo, _) = self.chains[i].poles_around(start);
            a = a.max(lo);
            self.next_pole[i] = 1;
        }
        'scan: for _ in 0..self.params.max_scan_intervals {
            if self.evaluations - begin > self.params.max_scan_evaluations {
                break;
            }
            // Next distinct pole above a.
            let mut b = f64::INFINITY;
            for i in 0..self.n_chains {
                let mut j = self.next_pole[i];
                let mut p = self.chains[i].pole(j);
                while p <= a * (1.0 + 1e-12) && p.is_finite() {
                    j += 1;
                    p = self.chains[i].pole(j);
                }
                self.next_pole[i] = j;
                b = b.min(p);
            }
            if a > limit {
                break;
            }
            // Evaluation points just inside (a, b): never past the middle of a narrow
            // interval (nearly coincident poles of different chains).
            let lo = if a == 0.0 { 0.0 } else { a + inset(b - a, a) };
            let hi_eval = if b.is_finite() {
                b - inset(b - a, b)
            } else {
                f64::INFINITY
            };
            let skip_interval = b.is_finite() && hi_eval <= skip_to * (1.0 + 1e-9);
            if !skip_interval {
                // Blocked count of the interval (index of its lowest root).
                let mut below = 0;
                let na = if a == 0.0 {
                    0
                } else {
                    let e = self.eval(lo);
                    below = e.below;
                    e.eig().negatives()
                };
                let nb = if b.is_finite() {
                    let e = self.eval(hi_eval);
                    below = e.below;
                    e.eig().negatives()
                } else {
                    self.dim
                };
                for branch in na..nb {
                    let hi = if b.is_finite() {
                        hi_eval
                    } else {
                        f64::INFINITY
                    };
                    let guess = if hi.is_finite() {
                        0.5 * (lo + hi)
                    } else {
                        2.0 * lo.max(skip_to).max(1.0)
                    };
                    let mut r = match self.branch_root_with(branch, lo, hi, 0.0, b, guess, true) {
                        Ok(r) => r,
                        // Collecting past the answer: keep what was found.
                        Err(_) if answer.is_some() => break 'scan,
                        Err(e) => return Err(e),
                    };
                    if r.lambda <= skip_to * (1.0 + 1e-9) {
                        continue;
                    }
                    if self.recording && r.ee_participation >= P_ADD {
                        self.insert_member(Member::new(
                            r.lambda,
                            r.ee_participation,
                            below + branch as u32,
                            branch,
                            a,
                            b,
                        ));
                    }
                    if answer.is_none() && r.ee_participation >= thr {
                        r.evaluations = self.evaluations - begin;
                        if !self.recording {
                            return Ok(r);
                        }
                        answer = Some(r);
                    }
                    if let Some(ans) = answer {
                        if self.unwatched_bound(ans.lambda) < SCAN_BOUND
                            || self.n_members == MAX_MEMBERS
                        {
                            break 'scan;
                        }
                    }
                    if best.is_none_or(|b| r.ee_participation > b.ee_participation) {
                        best = Some(r);
                    }
                }
            }
            if !b.is_finite() {
                break;
            }
            a = b;
        }
        if let Some(mut r) = answer {
            r.evaluations = self.evaluations - begin;
            return Ok(r);
        }
        // No mode reaches the threshold within the bounds: the most end-effector-like mode
        // found (its participation, below the threshold, says so).
        match best {
            Some(mut r) => {
                r.evaluations = self.evaluations - begin;
                Ok(r)
            }
            None => Err(ModalError::NoEeMode(self.params.max_scan_intervals)),
        }
    }

    /// The pole-free interval (a, b) of D around λ: the nearest blocked eigenvalues of all
    /// chains below and above (0 and ∞ when there are none).
    pub fn pole_interval(&self, lambda: f64) -> (f64, f64) {
        let mut a = 0.0f64;
        let mut b = f64::INFINITY;
        for c in &self.chains[..self.n_chains] {
            let (lo, hi) = c.poles_around(lambda);
            a = a.max(lo);
            b = b.min(hi);
        }
        (a, b)
    }

    /// Forget the tracked end-effector mode (the next [`Self::ee_mode_tracked`] scans).
    pub fn reset_tracking(&mut self) {
        self.n_members = 0;
        self.ee_skip = 0;
    }

    /// The end-effector mode, tracked from the last cycle when `warm`.
    ///
    /// **Certificate.** The modes are complete, so the end-effector participation summed
    /// over all of them is [`Self::participation_total`] (sum rule), and weighted by 1/λ it
    /// is tr(M_ee D(0)⁻¹) (the static flexibility, known from the first root). If a set W of
    /// distinct modes with known participation is *watched*, every other mode holds at most
    /// Σ_all p − Σ_W p, and every other mode below λ_A at most λ_A (tr(M_ee D(0)⁻¹) −
    /// Σ_W p_k/λ_k). When the smaller bound is below the threshold, the lowest watched mode
    /// that reaches the threshold is the end-effector mode: no unwatched mode can be.
    ///
    /// **Tracking.** A scan from cold watches every mode it meets with participation ≥ 0.05
    /// and goes on past the answer until the bound is below 0.15. A warm cycle follows the
    /// watched modes from their predictions (quadratic through the last three cycles) by
    /// Newton's method on their branch of D with both bounding poles removed, until a step is
    /// below 1e-5 (relative); the answer, and a mode within 0.02 of the threshold, to full
    /// accuracy (a tracking step below 1e-7 already is). Modes with participation ≥ 0.15 are
    /// followed every cycle, weaker ones one per cycle (the one followed longest ago): a
    /// mode not followed this cycle does not count in the bound, and when the bound does not
    /// certify, all are followed before anything is rescanned. Each mode's index in the
    /// spectrum (the blocked count of its pole interval plus its branch) keeps the watched
    /// modes distinct and carries its history.
    ///
    /// **Avoided crossings.** Along a trajectory the string modes of the cables pass through
    /// the end-effector modes and the participation moves between modes. Each strong watched
    /// mode (≥ 0.15) reads, from its own last evaluation, the chain that holds the largest
    /// share σ of its kinetic-energy norm vᵀ(−D')v; with σ ≥ 0.03 it is mixing with that
    /// chain's string mode, and a two-level model (the mode and the string mode across the
    /// chain's nearest pole P) places the partner at λ − (λ − P)/(1 − σ), holding about σ.
    /// The partner is found by Newton from there and watched before the participation moves
    /// (at most one such search per cycle, and once per pole until σ doubles). When the bound
    /// still exceeds 0.4, a spectral neighbour (index ± 1) of the watched mode whose
    /// participation changed most is searched across up to 4 pole intervals. Modes below 0.02
    /// are dropped. When the bound plus an allowance of 0.05 for the participations read
    /// within 1e-5 of the root is not below the threshold, or no watched mode reaches it, the
    /// band from 10 % below the lowest watched mode is scanned again, and everything from zero
    /// if that does not certify.
    ///
    /// The heuristics (what to watch, where to search) only decide the cost: the answer
    /// returned by a warm cycle is always certified by the bound.
    pub fn ee_mode_tracked(&mut self, first: &Root, warm: bool) -> Result<Root, ModalError> {
        let start = self.evaluations;
        let thr = self.params.ee_participation_min;
        if first.ee_participation >= thr {
            self.n_members = 0;
            self.ee_skip = 0;
            return Ok(*first);
        }
        if !warm {
            self.ee_skip = 0;
        } else if self.ee_skip > 0 {
            // Weak episode: no mode reached the threshold at the last full scan; follow the
            // most end-effector-like mode and rescan fully every 16 cycles.
            self.ee_skip -= 1;
            if self.n_members == 1 {
                let m = self.members[0];
                let pred = predict(&m);
                let exact = self.params.newton_accept;
                if let Some(t) = self.track_root(pred, exact) {
                    if (t.root.lambda - pred).abs() <= 2e-3 * m.lambda {
                        self.members[0] = t.member(m.lambda);
                        if t.root.ee_participation < thr {
                            let mut r = t.root;
                            r.evaluations = self.evaluations - start;
                            return Ok(r);
                        }
                    }
                }
            }
            self.ee_skip = 0;
            self.n_members = 0;
        }
        let mut reason = 0;
        if warm && self.n_members > 0 {
            match self.track_watched(thr) {
                Ok(mut r) => {
                    r.evaluations = self.evaluations - start;
                    return Ok(r);
                }
                Err(why) => reason = why,
            }
        }
        self.rescans[reason] += 1;
        if reason != 0 && self.n_members > 0 {
            // Rescan from 10 % below the lowest watched mode (the watched modes are those
            // the participation moves among); the modes below stay unwatched and covered by
            // the bound. Certified, this is the answer; else scan from zero.
            let window = 0.9 * self.members[0].lambda;
            if let Some(mut r) = self.partial_rescan(first, window, thr) {
                r.evaluations = self.evaluations - start;
                return Ok(r);
            }
        }
        self.n_members = 0;
        self.recording = true;
        if first.ee_participation >= P_ADD {
            self.watch_first(first);
        }
        let r = self.ee_mode(first);
        self.recording = false;
        let mut r = match r {
            Ok(r) => r,
            Err(e) => {
                self.n_members = 0;
                return Err(e);
            }
        };
        if r.ee_participation < thr {
            // Weak: watch only this mode until the next full scan.
            let (a, b) = self.pole_interval(r.lambda);
            self.members[0] = Member::new(r.lambda, r.ee_participation, 0, 0, a, b);
            self.n_members = 1;
            self.ee_skip = 16;
        }
        r.evaluations = self.evaluations - start;
        Ok(r)
    }

    /// Watch the first root: branch 0 below the lowest pole, index 0.
    fn watch_first(&mut self, first: &Root) {
        let lp = self.lowest_pole();
        self.insert_member(Member::new(
            first.lambda,
            first.ee_participation,
            0,
            0,
            0.0,
            lp,
        ));
    }

    /// Scan from `window` (rad²/s²) upward, watching what it finds (and the first root when
    /// it has participation); Some(answer) only when the bound certifies it.
    fn partial_rescan(&mut self, first: &Root, window: f64, thr: f64) -> Option<Root> {
        self.n_members = 0;
        if first.ee_participation >= P_ADD && first.lambda < window {
            self.watch_first(first);
        }
        self.recording = true;
        let r = self.ee_scan(window, window * (1.0 - 1e-12), f64::INFINITY);
        self.recording = false;
        let r = r.ok()?;
        if r.ee_participation >= thr && self.unwatched_bound(r.lambda) + CERT_MARGIN < thr {
            Some(r)
        } else {
            self.n_members = 0;
            None
        }
    }

    /// Counters of the end-effector bookkeeping: [full scans from a cold start, watched
    /// modes lost, full scans because the sum-rule bound was not certified, neighbour
    /// searches, full scans because no watched mode reached the threshold, watched modes
    /// dropped (participation below 0.02), partner searches (avoided crossings ahead)].
    pub fn rescan_counts(&self) -> [u64; 7] {
        self.rescans
    }

    /// Bound on the participation of any unwatched mode below `l_ans` (rad²/s²): the smaller
    /// of the plain and the 1/λ-weighted sum rules less what the watched modes hold.
    fn unwatched_bound(&self, l_ans: f64) -> f64 {
        self.unwatched_bound_with(l_ans, false)
    }

    /// [`Self::unwatched_bound`]; with `stale`, the members not followed this cycle count
    /// too, with their last participation (an estimate for the search heuristics only).
    fn unwatched_bound_with(&self, l_ans: f64, stale: bool) -> f64 {
        let mut sum = 0.0;
        let mut weighted = 0.0;
        for m in &self.members[..self.n_members] {
            if m.age > 0 && !stale {
                continue;
            }
            sum += m.p;
            weighted += m.p / m.lambda;
        }
        let plain = self.p_total - sum;
        let w = if self.flex0.is_finite() && l_ans.is_finite() {
            l_ans * (self.flex0 - weighted)
        } else {
            f64::INFINITY
        };
        plain.min(w).max(0.0)
    }

    /// Insert a watched mode in index order; a mode already watched (same index) is
    /// replaced. When full, the weakest watched mode gives way to a stronger one.
    fn insert_member(&mut self, m: Member) {
        let n = self.n_members;
        let pos = self.members[..n].partition_point(|x| x.index < m.index);
        if pos < n && self.members[pos].index == m.index {
            self.members[pos] = m;
            return;
        }
        if n == MAX_MEMBERS {
            let (weak, wp) =
                self.members[..n]
                    .iter()
                    .enumerate()
                    .fold(
                        (0, f64::INFINITY),
                        |acc, (i, x)| {
                            if x.p < acc.1 {
                                (i, x.p)
                            } else {
                                acc
                            }
                        },
                    );
            if wp >= m.p {
                return;
            }
            self.remove_member(weak);
            self.insert_member(m);
            return;
        }
        let mut i = n;
        while i > pos {
            self.members[i] = self.members[i - 1];
            i -= 1;
        }
        self.members[pos] = m;
        self.n_members += 1;
    }

    fn remove_member(&mut self, i: usize) {
        for k in i..self.n_members - 1 {
            self.members[k] = self.members[k + 1];
        }
        self.n_members -= 1;
    }

    /// One warm cycle of the watched modes; Err(reason) when a full scan is needed.
    fn track_watched(&mut self, thr: f64) -> Result<Root, usize> {
        self.follow_members(false);
        self.partners_and_answer(thr)
    }

    /// Follow the watched modes one step: every one with participation ≥ [`P_LAZY`] and
    /// the weak one followed longest ago (`stale_only`: those not followed this cycle).
    /// Then keep them in index order, distinct, and drop the weak ones.
    fn follow_members(&mut self, stale_only: bool) {
        let mut rr = usize::MAX;
        if !stale_only {
            let mut oldest = 0;
            for (k, m) in self.members[..self.n_members].iter_mut().enumerate() {
                m.age += 1;
                if m.p < P_LAZY && m.age > oldest {
                    oldest = m.age;
                    rr = k;
                }
            }
        }
        let mut i = 0;
        while i < self.n_members {
            let m = self.members[i];
            let follow = if stale_only {
                m.age > 0
            } else {
                m.p >= P_LAZY || i == rr
            };
            if !follow {
                i += 1;
                continue;
            }
            let pred = predict(&m);
            match self.track_root(pred, CHEAP_ACCEPT) {
                Some(t) => {
                    // A root far from the prediction is another mode that Newton converged
                    // to: still a mode, but without a history.
                    let jumped =
                        t.index != m.index || (t.root.lambda - pred).abs() > 2e-2 * m.lambda;
                    let mut n = t.member(if jumped { f64::NAN } else { m.lambda });
                    if !jumped {
                        n.p_ref = m.p_ref;
                        n.searched = m.searched;
                        n.last_side = m.last_side;
                        n.partner_key = m.partner_key;
                        n.partner_share = m.partner_share;
                        if m.age > 1 {
                            // The λ one cycle ago, interpolated over the gap.
                            n.prev = t.root.lambda - (t.root.lambda - m.lambda) / m.age as f64;
                            n.prev2 = f64::NAN;
                        } else {
                            n.prev2 = m.prev;
                        }
                    }
                    self.members[i] = n;
                    i += 1;
                }
                None => {
                    self.rescans[1] += 1;
                    self.remove_member(i);
                }
            }
        }
        // Keep them in index order and distinct (two that converged to one mode are one).
        for i in 1..self.n_members {
            let mut k = i;
            while k > 0 && self.members[k - 1].index > self.members[k].index {
                self.members.swap(k - 1, k);
                k -= 1;
            }
        }
        let mut i = 1;
        while i < self.n_members {
            if self.members[i].index == self.members[i - 1].index {
                // Keep the one followed this cycle.
                let stale = if self.members[i].age > 0 { i } else { i - 1 };
                self.remove_member(stale);
            } else {
                i += 1;
            }
        }
        let mut i = 0;
        while i < self.n_members {
            if self.members[i].age == 0 && self.members[i].p < P_DROP {
                self.rescans[5] += 1;
                self.remove_member(i);
            } else {
                i += 1;
            }
        }
    }

    /// The rest of a warm cycle after [`Self::follow_members`]: partners of strong modes,
    /// the answer, neighbour searches, the certificate.
    fn partners_and_answer(&mut self, thr: f64) -> Result<Root, usize> {
        // Avoided crossings ahead: a strong watched mode that shares enough of its kinetic
        // energy with one chain is mixing with that chain's string mode, which sits just
        // across the chain's nearest pole; watch it before the participation moves there.
        let mut searches = 0;
        let mut i = 0;
        while i < self.n_members && searches < PARTNER_SEARCHES {
            let m = self.members[i];
            i += 1;
            if m.age > 0 || m.p < P_STRONG || m.share < P_PARTNER || !m.pole.is_finite() {
                continue;
            }
            // Two-level model (the mode and the chain's string mode): the partner sits at
            // λ_m − (λ_m − pole)/(1 − share), across the pole.
            let pred = m.lambda - (m.lambda - m.pole) / (1.0 - m.share).max(0.05);
            let reach = 2.0 * (pred - m.pole).abs() + 1e-6 * m.pole;
            let watched = self.members[..self.n_members].iter().any(|x| {
                (if m.pole_up {
                    x.lambda > m.pole
                } else {
                    x.lambda < m.pole
                }) && (x.lambda - m.pole).abs() <= reach
                    && x.p >= 0.5 * m.share
            });
            if watched || (m.pole_key == m.partner_key && m.share < 2.0 * m.partner_share) {
                continue;
            }
            self.members[i - 1].partner_key = m.pole_key;
            self.members[i - 1].partner_share = m.share;
            searches += 1;
            self.rescans[6] += 1;
            if let Some(t) = self.partner(m.pole, m.pole_up, pred) {
                let known = self.members[..self.n_members]
                    .iter()
                    .any(|x| x.index == t.index);
                if !known && t.root.ee_participation >= P_DROP {
                    self.insert_member(t.member(f64::NAN));
                    // Restart: insertion shifted the members.
                    i = 0;
                }
            }
        }
        let mut answer = self.select_answer(thr)?;
        if self.unwatched_bound_with(answer.lambda, true) > SEARCH_BOUND {
            // Search the neighbours of the watched mode whose participation changed most
            // since its neighbours were last searched (first those never searched): a
            // flood fill towards the participation the watched modes miss.
            let mut pick = None;
            let mut change = SEARCH_LOSS;
            let mut oldest = (u64::MAX, 0);
            for (k, m) in self.members[..self.n_members].iter().enumerate() {
                let c = if m.p_ref.is_nan() {
                    f64::INFINITY
                } else {
                    (m.p - m.p_ref).abs()
                };
                if c >= change {
                    change = c;
                    pick = Some(k);
                }
                if m.searched < oldest.0 {
                    oldest = (m.searched, k);
                }
            }
            // Nothing changed: the one searched longest ago.
            let k = pick.unwrap_or(oldest.1);
            {
                self.rescans[3] += 1;
                self.search_count += 1;
                let m = self.members[k];
                // One side per search: first towards the nearer pole (an avoided crossing
                // partner sits across it), then alternately.
                let up = match m.last_side {
                    0 => m.b - m.lambda < m.lambda - m.a,
                    1 => false,
                    _ => true,
                };
                self.members[k].last_side = if up { 2 } else { 1 };
                // Both sides searched: the mode is settled until its participation changes.
                if m.last_side != 0 {
                    self.members[k].p_ref = m.p;
                }
                self.members[k].searched = self.search_count;
                {
                    // Walk past weak modes (up to NEIGHBOUR_WALK) to the first one worth
                    // watching.
                    let mut from = m;
                    for _ in 0..NEIGHBOUR_WALK {
                        let target = if up {
                            from.index + 1
                        } else if from.index > 0 {
                            from.index - 1
                        } else {
                            break;
                        };
                        if self.members[..self.n_members]
                            .iter()
                            .any(|x| x.index == target)
                        {
                            break;
                        }
                        let Some(t) = self.neighbour(&from, up) else {
                            break;
                        };
                        let mut n = t.member(f64::NAN);
                        if t.root.ee_participation >= P_ADD {
                            n.p_ref = f64::NAN;
                            self.insert_member(n);
                            break;
                        }
                        from = n;
                    }
                }
                answer = self.select_answer(thr)?;
            }
        }
        if self.unwatched_bound(answer.lambda) + CERT_MARGIN >= thr {
            if self.members[..self.n_members].iter().all(|m| m.age == 0) {
                return Err(2);
            }
            // Follow the rest too before giving up.
            self.follow_members(true);
            answer = self.select_answer(thr)?;
            if self.unwatched_bound(answer.lambda) + CERT_MARGIN >= thr {
                return Err(2);
            }
        }
        Ok(answer)
    }

    /// The lowest watched mode with participation ≥ the threshold, solved to full accuracy
    /// (and so is any watched mode below it within [`P_MARGIN`] of the threshold);
    /// Err(4) when there is none, Err(1) when an exact solve fails.
    fn select_answer(&mut self, thr: f64) -> Result<Root, usize> {
        let exact = self.params.newton_accept;
        for i in 0..self.n_members {
            let m = self.members[i];
            if m.age > 0 || m.p < thr - P_MARGIN {
                continue;
            }
            if m.step <= ANSWER_ACCEPT {
                // Followed this cycle by a Newton step this small: λ is within ~step² of
                // the root already.
                if m.p >= thr {
                    return Ok(Root {
                        lambda: m.lambda,
                        ee_participation: m.p,
                        evaluations: 0,
                        residual: m.residual,
                    });
                }
                continue;
            }
            let t = self.track_root(m.lambda, exact).ok_or(1usize)?;
            if t.index != m.index {
                return Err(1);
            }
            self.members[i].lambda = t.root.lambda;
            self.members[i].p = t.root.ee_participation;
            self.members[i].step = t.step;
            self.members[i].residual = t.root.residual;
            if t.root.ee_participation >= thr {
                return Ok(t.root);
            }
        }
        Err(4)
    }

    /// The spectral neighbour of watched mode `m`: the mode of index m.index + 1 (`up`) or
    /// m.index − 1 (or the first beyond the modes sitting exactly at a pole, which have no
    /// participation), searched across at most [`NEIGHBOUR_INTERVALS`] pole intervals; None when
    /// it is not found there. In a pole interval (a, b) with blocked count B the roots are
    /// those of branches j with D's j-th eigenvalue positive at a⁺ and negative at b⁻, in
    /// order, and the root of branch j has index B + j.
    fn neighbour(&mut self, m: &Member, up: bool) -> Option<Tracked> {
        let mut target = if up {
            m.index + 1
        } else {
            m.index.checked_sub(1)?
        };
        let (mut a, mut b) = (m.a, m.b);
        let mut below = m.index.checked_sub(m.branch as u32)?;
        // The end of the interval where the target's branch is known to have the right sign
        // (≥ 0 below the root when going up, ≤ 0 above it when going down).
        let mut known = m.lambda;
        for _ in 0..NEIGHBOUR_INTERVALS {
            if target >= below && ((target - below) as usize) < self.dim {
                let j = (target - below) as usize;
                // The other end: b⁻ (∞ when there is no pole above: D → −λ M_∞ there) or
                // a⁺ (0 when a = 0: D(0) is positive definite).
                let other = if up {
                    b.is_finite().then(|| b - inset(b - a, b))
                } else {
                    (a > 0.0).then(|| a + inset(b - a, a))
                };
                let holds = match other {
                    None => true,
                    Some(x) => {
                        let v = self.eval(x).eig().values[j];
                        if up {
                            v < 0.0
                        } else {
                            v > 0.0
                        }
                    }
                };
                if holds {
                    let (lo, hi) = if up {
                        (known, other.unwrap_or(f64::INFINITY))
                    } else {
                        (other.unwrap_or(0.0), known)
                    };
                    let guess = if hi.is_finite() {
                        0.5 * (lo + hi)
                    } else {
                        2.0 * lo.max(1.0)
                    };
                    let r = self.branch_root_with(j, lo, hi, a, b, guess, true).ok()?;
                    return Some(Tracked {
                        root: r,
                        branch: j,
                        index: target,
                        a,
                        b,
                        share: 0.0,
                        pole: f64::NAN,
                        pole_up: false,
                        pole_key: u32::MAX,
                        step: 0.0,
                    });
                }
            }
            // Not in this interval: the next one in the search direction.
            let x = if up {
                if !b.is_finite() {
                    return None;
                }
                b + inset(b - a, b)
            } else {
                if a == 0.0 {
                    return None;
                }
                a - inset(b - a, a)
            };
            let e = self.eval(x);
            (a, b) = self.last_pole_interval();
            if !(x > a && x < b) {
                return None;
            }
            below = e.below;
            let count = below + e.eig().negatives() as u32;
            // Modes between x and the pole just crossed sit at that pole (several chains
            // blocked at one λ: the end-effector is still in them, participation 0): the
            // neighbour is the next mode beyond them.
            if up && count > target {
                target = count;
            } else if !up && count <= target {
                target = count.checked_sub(1)?;
            }
            known = x;
        }
        None
    }

    /// The partner of a watched mode in an avoided crossing: the mode across `pole`
    /// (rad²/s²; above it when `up`) nearest `pred` (the two-level model's estimate), by
    /// [`Self::track_root`] from `pred` (or from just across the pole when `pred` is on the
    /// wrong side). Whatever mode it converges to is a root with its index counted afresh.
    fn partner(&mut self, pole: f64, up: bool, pred: f64) -> Option<Tracked> {
        let x = if up {
            pred.max(pole * (1.0 + 1e-9))
        } else {
            pred.min(pole * (1.0 - 1e-9))
        };
        self.track_root(x, CHEAP_ACCEPT)
    }

    /// Newton from `l0` on the branch of D closest to vanishing there, kept inside the pole
    /// interval of l0; None when it leaves it or does not converge in the bound. The next
    /// iterate is accepted once a step is below `accept` (relative; the iterate is then
    /// within ~step² of the root). Returns the root, its branch, its pole interval, its index
    /// in the spectrum (the interval's blocked count plus the branch) and, for a mode with
    /// participation ≥ [`P_STRONG`], the chain it shares most energy with.
    fn track_root(&mut self, l0: f64, accept: f64) -> Option<Tracked> {
        let mut x = l0;
        let mut e = self.eval(x);
        let (mut a, mut b) = self.last_pole_interval();
        if !(x > a && x < b) {
            return None;
        }
        let mut eg = e.eig();
        let mut branch = nearest_branch(&e, &eg);
        let mut hopped = false;
        let mut it = 0;
        while it < self.params.max_evaluations.min(12) {
            let v = eg.vectors[branch];
            let mu = eg.values[branch];
            let dmu = quad(&e.dd, &v, e.dim);
            // Newton on μ(λ)(λ − a)(b − λ): both poles removed (a = 0 and b = ∞ add nothing).
            let (mut g, mut dg) = (mu, dmu);
            if b.is_finite() {
                let w = b - x;
                (g, dg) = (g * w, dg * w - g);
            }
            if a > 0.0 {
                let w = x - a;
                (g, dg) = (g * w, dg * w + g);
            }
            if !(dg < 0.0) {
                return None;
            }
            let xn = x - g / dg;
            if !(xn > a && xn < b) {
                // A weakly coupled pole passed through the mode since the last cycle: follow
                // it into the neighbouring interval, once, from the mirror point.
                if hopped {
                    return None;
                }
                hopped = true;
                x = if xn >= b { b + (b - x) } else { a - (x - a) };
                if !(x > 0.0) {
                    return None;
                }
                e = self.eval(x);
                (a, b) = self.last_pole_interval();
                if !(x > a && x < b) {
                    return None;
                }
                eg = e.eig();
                branch = nearest_branch(&e, &eg);
                it += 1;
                continue;
            }
            if mu == 0.0 || (xn - x).abs() <= accept.max(self.params.rel_tol) * x {
                let scale = e.d.abs().max().max(f64::MIN_POSITIVE);
                let p = self.participation(&e.dd, &v);
                let (share, pole, pole_up, pole_key) = if p >= P_STRONG {
                    self.coupling(x, &e.dd, &v)
                } else {
                    (0.0, f64::NAN, false, u32::MAX)
                };
                return Some(Tracked {
                    root: Root {
                        lambda: xn,
                        ee_participation: p,
                        evaluations: 0,
                        residual: mu.abs() / scale,
                    },
                    branch,
                    index: e.below + branch as u32,
                    a,
                    b,
                    share,
                    pole,
                    pole_up,
                    pole_key,
                    step: (xn - x).abs() / x,
                });
            }
            x = xn;
            e = self.eval(x);
            eg = e.eig();
            it += 1;
        }
        None
    }

    /// Evaluations of D(λ) since the solver was built (a counter for statistics).
    pub fn evaluations(&self) -> u32 {
        self.evaluations
    }
}
