//! Mode shapes from the structured solver: for an eigenvalue λ* of multiplicity m (from the
//! Wittrick-Williams count), the m mass-normalised shapes of the whole robot, the
//! end-effector's displacement and every cable's node displacements, without assembling
//! anything of size N.
//!
//! **Chain shapes.** A cable's interior nodes decouple into scalar chains (directions w
//! spanning the range of the chain's projector, one per multiplicity). At a given λ the
//! interior equations of one chain, β y_{j−1} + 2α y_j + β y_{j+1} = 0 (α = k − λm/3,
//! β = −k − λm/6) with the anchor held (y₀ = 0), have a one-parameter family of solutions
//! y_j = C w_j, w_j ∝ U_{j−1}(c) with c = −α/β (sin(jθ)/sin θ for c = cos θ,
//! (−1)^{j−1} sinh(jφ)/sinh φ above the cut-off); a continuous string or bar has
//! w(x) ∝ sin(φx), φ = √(λμL²/S). The amplitude C is a free unknown. The chain's end value
//! is g = w_N and the force it puts on its end node per unit amplitude is
//! f = α w_N + β w_{N−1} (K w'(1) for a continuous chain), so its dynamic stiffness is
//! s(λ) = f/g; w is normalised to max |w| = 1, so f and g are finite at every λ.
//!
//! **Bordered system.** With the end-effector's displacement φ (3 DOF, or 6 for a rigid
//! body: translation, then rotation), b_k = G_iᵀ w_k the end direction of chain copy k of
//! cable i (G_i = I, or [I, −\[r_i\]×] for a rigid body with arm r_i), the free vibration at
//! λ is exactly
//!
//! ```text
//!     (K_ee − λ M_ee) φ + Σ_k f_k C_k b_k = 0          (end-effector equilibrium)
//!     σ_k (b_kᵀ φ − g_k C_k)            = 0  for all k  (the chain ends at the end-effector)
//! ```
//!
//! (σ_k a stiffness of the size of f_k that balances the rows; K_ee is a rigid body's
//! rotational geometric stiffness). Its unknowns are (φ, C_1 … C_n): n = dim + Σ mult, at
//! most 6 + 3·(cables) whatever N is. A solution gives every node (y_j = C w_j inside, the
//! end from φ) and every solution of the full K u = λ M u restricted to the chains is one,
//! so the null space of this small matrix at λ* is the eigenspace, of dimension m. Unlike
//! D(λ), it has no poles: when λ* is a blocked eigenvalue of some chains (identical cables
//! give modes with the end-effector still, 3- and 5-fold clusters on the spatial paper
//! robot), g_k = 0 for them and C_k is simply a free amplitude, the row b_kᵀφ = 0 holding
//! the chain's end. The matrix is not symmetric (a symmetric scaling f_k·row would lose
//! the row where f_k = 0, the chain's own free-end resonance), so the null space is taken
//! from its singular value decomposition: the right singular vectors of the m smallest
//! singular values. λ* is known to a relative δ (≈ 1e-12 from the count's bisection, or the
//! dense solver's ε·λ_max/λ), so those singular values are O(δ·‖A‖) instead of 0 and the
//! subspace is accurate to about σ_m/σ_{m+1}; [`ShapeParams::null_tol`] bounds that ratio
//! (a larger one means the multiplicity given does not match the null space, or λ is too
//! coarse to separate it from a neighbour). Before the SVD the matrix is equilibrated
//! (Ruiz: rows and columns scaled to unit largest entry): the chains' rows range from T/l
//! to EA/l, and unbalanced, the SVD's backward error ε‖A‖ would swamp the soft rows. A
//! cluster that fails the test is repaired the same way for every model (`pipeline`,
//! `near`): modes given apart within 1e-9 that are one eigenvalue are merged; one given as a
//! cluster that is several (modes 1e-10 apart given as one; the catenary model's identical
//! cables differ by ~ε·EA/T) is split by the count from its λ to 1e-8 above, and each
//! part's shapes are taken. A mode still not separated from a given neighbour is a
//! near-cluster. Below the null space's resolution (the paper robot's end-effector triplet
//! 4e-9 apart 1e-6 m off its symmetric pose at N = 10⁵, where the chains' rounding keeps
//! each member's σ_m near 1e-12 and the neighbours' σ_{m+1} near 1e-9) it is taken with its
//! nearest given neighbours, across gaps of at most 1e-6 relative, as one cluster at their
//! multiplicity-weighted mean λ, once the count certifies that the group's span holds
//! exactly its multiplicity and the merged null space is separated (its members'
//! frequencies are then given at the mean, within 5e-7 relative; a caller asking a few
//! clusters at a time keeps such runs together, [`near_runs`]). Farther apart (~5e-6 with
//! sag, up to 1e-3) it is resolved with its neighbours by a symmetric orthonormalisation of
//! each member's own null vectors, each member keeping its λ.
//!
//! **Normalisation.** The consistent mass of the model is block diagonal in the chain
//! coordinates (its 3 × 3 blocks are multiples of I and the chain directions are
//! orthonormal), so φ_aᵀ M φ_b = φ_aᵀ M_ee φ_b +
//! Σ_k [C_a C_b m_ii + (C_a e_b + e_a C_b) m_ie + e_a e_b m_ee] with e = b_kᵀφ the chain's end displacement and the element sums
//! m_ii = (m/3)(Σ_{interior elements} (w_j² + w_j w_{j+1} + w_{j+1}²) + w_{N−1}²),
//! m_ie = (m/6) w_{N−1}, m_ee = m/3 (μL ∫₀¹ w² dx for a continuous chain): exactly the
//! dense M's quadratic form, in O(N) per chain. The m shapes of a cluster are
//! M-orthonormalised (symmetric orthonormalisation with the m × m Gram matrix), then rotated
//! within the cluster to diagonalise the end-effector's mass: the cluster's first shape
//! carries the largest end-effector participation p = φ_eeᵀ M_ee φ_ee (m_ee‖φ_ee‖² for a
//! point mass), the others the rest, and Σ p over the cluster is basis-independent.
//!
//! **Cost.** O(N) per chain for the shapes and moments, one SVD of size dim + Σ mult per
//! cluster, O(N·K) for the node displacements of K modes. Offline: allocates.
//!
//! **Units.** λ in rad²/s²; shapes mass-normalised (φᵀMφ = 1): translations in m/√(kg·m²)
//! = 1/√kg, rotations in rad/(m·√kg); participations dimensionless.
//!
//! **Hidden cables.** A supported chain (the free cable's axial chain on the cable hidden
//! behind its pulley) is one non-uniform chain held at the drum: again a one-parameter
//! family, w from the drum through the junction to the end (`supported_shape`); its hidden
//! part enters m_ii. A sagged chain on a hidden cable (`sagged`) has one more amplitude,
//! the hidden cable's, and the junction's equation one more row.
//!
//! **Layout.** `pipeline`: the one pipeline over a model's bordered system (cluster merge
//! and split), `bordered`: what it does at one λ (null space, normalisation); `near`: its
//! near-cluster repairs; `taut`: the
//! taut chains' system (behind
//! [`ModalSolver::mode_shapes`](crate::modal::ModalSolver::mode_shapes)), `sagged`: the
//! sagging cables' FEM chains' (behind
//! [`SagModalSolver::mode_shapes`](crate::modal::SagModalSolver::mode_shapes));
//! `chain_shape`: one chain's w, f, g and mass moments; `supported_shape`: a supported
//! chain's; `sag_chain_shape`: a sagged FEM chain's solutions. `count`: the lowest
//! eigenvalues and their multiplicities by count bisection
//! ([`Solver::eigen_clusters`](crate::modal::Solver::eigen_clusters)) and the split of a
//! cluster. `influence`: the quasi-static influence field (the nodes' static displacement
//! per unit end-effector motion) in the shapes' layout, taut and sagged.

mod bordered;
mod chain_shape;
mod count;
mod influence;
mod near;
mod pipeline;
mod sag_chain_shape;
mod sagged;
mod supported_shape;
mod taut;

pub(in crate::modal) use count::clusters_by_count;
pub(in crate::modal) use pipeline::mode_shapes;
pub(in crate::modal) use sagged::SagSystem;
pub(in crate::modal) use taut::TautSystem;

pub use near::near_runs;

use super::ModalError;
use nalgebra::{Vector3, Vector6};

/// Largest multiplicity accepted for one eigenvalue (every chain copy of 16 cables at one
/// pole is 48; the bordered system has at most 6 + 3·16 unknowns).
pub const MAX_MULTIPLICITY: u32 = 64;
/// Largest number of sample points along a continuous cable.
pub const MAX_CONTINUOUS_SAMPLES: usize = 10_001;

/// Parameters of the mode-shape recovery (finite bounds everywhere).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShapeParams {
    /// Largest σ_m/σ_{m+1} of the (equilibrated) bordered system accepted for an eigenvalue
    /// of multiplicity m (σ the singular values, ascending): the m-dimensional null space
    /// must be clearly separated. The subspace's error is about this ratio times the
    /// relative error of λ's effect, so it is also a quality measure of the input λ.
    pub null_tol: f64,
    /// Points at which a continuous cable is sampled, anchor and end included (2 ..=
    /// [`MAX_CONTINUOUS_SAMPLES`]).
    pub continuous_samples: usize,
    /// Largest number of QR sweeps of the singular value decomposition.
    pub svd_max_iterations: usize,
    /// Relative width within which the count groups eigenvalues into one cluster: exact
    /// clusters (identical cables) agree to rounding, ~1e-15; distinct modes this close
    /// would leave more than m small singular values in the bordered system (an error)
    /// ([`ModalSolver::eigen_clusters`](crate::modal::ModalSolver::eigen_clusters)).
    pub cluster_rel: f64,
    /// Largest number of count evaluations for one cluster's bisection.
    pub max_bisections: u32,
}

impl Default for ShapeParams {
    fn default() -> Self {
        ShapeParams {
            null_tol: 1e-3,
            continuous_samples: 41,
            svd_max_iterations: 1000,
            cluster_rel: 1e-12,
            max_bisections: 400,
        }
    }
}

/// One mass-normalised mode shape.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeShape {
    /// λ = ω², rad²/s².
    pub lambda: f64,
    /// Natural frequency, Hz.
    pub frequency_hz: f64,
    /// End-effector displacement: translation (1/√kg), then rotation (rad/(m·√kg)) for a
    /// rigid body (zeros for a point mass).
    pub ee: Vector6<f64>,
    /// Node displacements of each cable (1/√kg), anchor (node 0: zero, or the junction's
    /// motion along the cable on a hidden cable) to end-effector; at the fractions
    /// [`ModeShapes::fractions`] of the chord (the hidden cable's own nodes are not drawn).
    pub cables: Vec<Vec<Vector3<f64>>>,
    /// Each cable's hidden cable (behind its pulley, FEM): its nodes' displacement along
    /// it (1/√kg), from the fixed drum to the junction; empty for a cable without one (or
    /// a continuous one, whose hidden part enters the normalisation only).
    pub hidden: Vec<Vec<f64>>,
    /// End-effector participation φ_eeᵀ M_ee φ_ee (0 ..= 1).
    pub ee_participation: f64,
    /// Index (in [`ModeShapes::modes`]) of the first shape of this mode's cluster.
    pub cluster_start: usize,
    /// Multiplicity of λ (shapes in the cluster).
    pub multiplicity: u32,
    /// σ_m/σ_{m+1} of the equilibrated bordered system at λ: how far λ is from an exact
    /// eigenvalue of multiplicity m, relative to the distance to the next one.
    pub null_residual: f64,
}

/// The mode shapes of one pose.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModeShapes {
    /// 3 (point mass) or 6 (rigid body).
    pub dim: usize,
    /// Each cable's node positions as fractions (0 ..= 1) of its chord from the anchor.
    pub fractions: Vec<Vec<f64>>,
    /// The shapes, ascending in λ; a cluster's shapes by descending participation.
    pub modes: Vec<ModeShape>,
    /// Each cable's element mass between its nodes, kg: the consistent mass
    /// (m/6)[2I I; I 2I] of each element of the node lists (a continuous cable's total
    /// mass over its sample intervals, an approximation of its mass there).
    pub element_mass_kg: Vec<f64>,
    /// Each cable's hidden cable's element mass, kg (0 without one).
    pub hidden_element_mass_kg: Vec<f64>,
}

impl ModeShapes {
    /// The mass overlaps O_ji = φ_jᵀ M φ'_i of these shapes (the hidden cables' nodes
    /// included) (j, rows) with `old` (i,
    /// columns), row-major, the mass M of these shapes' cables and `ee_mass` (the
    /// end-effector's, kg and kg·m²) on node lists of the same sizes: at one pose, the
    /// identity for M-orthonormal shapes; across a small change of pose, how each old mode
    /// projects on the new ones. None when the two have different node lists.
    pub fn mass_overlap(
        &self,
        old: &ModeShapes,
        ee_mass: &nalgebra::Matrix6<f64>,
    ) -> Option<Vec<f64>> {
        if !self.same_nodes(old) {
            return None;
        }
        // Each shape as one vector (end-effector, every cable's nodes, the hidden cables'),
        // the old ones times M: the overlaps are one matrix product (the products of the
        // element forms' sums, in another order).
        let Some(first) = self.modes.first().or(old.modes.first()) else {
            return Some(Vec::new());
        };
        let same_layout = |m: &ModeShape| {
            m.cables.len() == first.cables.len()
                && m.hidden.len() == first.hidden.len()
                && m.cables
                    .iter()
                    .zip(&first.cables)
                    .all(|(a, b)| a.len() == b.len())
                && m.hidden
                    .iter()
                    .zip(&first.hidden)
                    .all(|(a, b)| a.len() == b.len())
        };
        if !self.modes.iter().chain(&old.modes).all(same_layout) {
            return Some(self.mass_overlap_by_pairs(old, ee_mass));
        }
        let len = 6
            + 3 * first.cables.iter().map(Vec::len).sum::<usize>()
            + first.hidden.iter().map(Vec::len).sum::<usize>();
        // The product holds both sets again (8 B a value): within its own small cap, else
        // the pairs (which hold nothing more than the shapes: the memory budget's model).
        let bytes = len
            .saturating_mul(self.modes.len() + old.modes.len())
            .saturating_mul(8);
        if bytes > OVERLAP_PRODUCT_BYTES {
            return Some(self.mass_overlap_by_pairs(old, ee_mass));
        }
        // A shape appended to `v` as one column of `len` values, times M or not.
        let flat = |m: &ModeShape, times_mass: bool, v: &mut Vec<f64>| {
            let ee = if times_mass { ee_mass * m.ee } else { m.ee };
            v.extend_from_slice(ee.as_slice());
            for (i, nodes) in m.cables.iter().enumerate() {
                let mass = self.element_mass_kg.get(i).copied().unwrap_or(0.0) / 6.0;
                for j in 0..nodes.len() {
                    let x = if times_mass {
                        consistent_row(nodes, j, |a, b| a + b, |a, c| a * c) * mass
                    } else {
                        nodes[j]
                    };
                    v.extend_from_slice(x.as_slice());
                }
            }
            for (i, nodes) in m.hidden.iter().enumerate() {
                let mass = self.hidden_element_mass_kg.get(i).copied().unwrap_or(0.0) / 6.0;
                for j in 0..nodes.len() {
                    v.push(if times_mass {
                        consistent_row(nodes, j, |a, b| a + b, |a, c| a * c) * mass
                    } else {
                        nodes[j]
                    });
                }
            }
        };
        let fill = |modes: &[ModeShape], times_mass: bool| {
            let mut data = Vec::with_capacity(len * modes.len());
            for m in modes {
                flat(m, times_mass, &mut data);
            }
            nalgebra::DMatrix::from_vec(len, modes.len(), data)
        };
        let a = fill(&self.modes, false);
        let w = fill(&old.modes, true);
        // Oᵀ = Wᵀ A by columns is O row-major (Wᵀ copied, for a blocked product: `tr_mul`'s
        // dot products took 6.6 % of the paper circle's CPU, the blocked product ~2 %).
        Some((w.transpose() * a).data.into())
    }

    /// [`Self::mass_overlap`] pair by pair (shapes whose node lists differ from mode to
    /// mode: a hidden cable's pair of different lengths is left out).
    fn mass_overlap_by_pairs(
        &self,
        old: &ModeShapes,
        ee_mass: &nalgebra::Matrix6<f64>,
    ) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.modes.len() * old.modes.len());
        for a in &self.modes {
            for b in &old.modes {
                out.push(self.mass_form(a, b, ee_mass));
            }
        }
        out
    }

    /// Whether `old` has these shapes' dimension and node lists.
    fn same_nodes(&self, old: &ModeShapes) -> bool {
        self.dim == old.dim
            && self.fractions.len() == old.fractions.len()
            && self
                .fractions
                .iter()
                .zip(&old.fractions)
                .all(|(a, b)| a.len() == b.len())
    }

    /// aᵀ M b with the mass M of these shapes' cables and `ee_mass` (a hidden cable's pair
    /// of different lengths left out).
    fn mass_form(&self, a: &ModeShape, b: &ModeShape, ee_mass: &nalgebra::Matrix6<f64>) -> f64 {
        let mut s = (a.ee.transpose() * ee_mass * b.ee)[(0, 0)];
        for (i, (ua, ub)) in a.cables.iter().zip(&b.cables).enumerate() {
            let m = self.element_mass_kg.get(i).copied().unwrap_or(0.0);
            s += bordered::element_mass_form(m, ua, ub);
        }
        for (i, (ha, hb)) in a.hidden.iter().zip(&b.hidden).enumerate() {
            if ha.len() == hb.len() {
                let m = self.hidden_element_mass_kg.get(i).copied().unwrap_or(0.0);
                s += m / 6.0 * scalar_mass_form(ha, hb);
            }
        }
        s
    }

    /// Each of `old`'s shapes' squared norm φᵀ M φ under these shapes' mass M (their
    /// cables' element masses and `ee_mass`): 1 at `old`'s own pose for M-orthonormal
    /// shapes; across a change of pose, the change of the cables' element masses (their
    /// lengths) that [`Self::mass_overlap`]'s column sums of squares carry too. None when
    /// the node lists differ.
    pub fn mass_norms_of(
        &self,
        old: &ModeShapes,
        ee_mass: &nalgebra::Matrix6<f64>,
    ) -> Option<Vec<f64>> {
        if !self.same_nodes(old) {
            return None;
        }
        Some(
            old.modes
                .iter()
                .map(|b| self.mass_form(b, b, ee_mass))
                .collect(),
        )
    }
}

/// Largest copy of two shape sets [`ModeShapes::mass_overlap`] makes for its matrix
/// product, bytes.
const OVERLAP_PRODUCT_BYTES: usize = 64 << 20;

/// Row j of 6/m times a chain's consistent mass applied to its nodes `v`: 2v_0 + v_1 at the
/// first node, v_{j−1} + 4v_j + v_{j+1} inside, v_{L−1} + 2v_L at the last (none for a
/// single node: no element).
fn consistent_row<T: Copy>(
    v: &[T],
    j: usize,
    add: impl Fn(T, T) -> T,
    scale: impl Fn(T, f64) -> T,
) -> T {
    let n = v.len();
    if n < 2 {
        return scale(v[j], 0.0);
    }
    let mut x = scale(v[j], if j == 0 || j == n - 1 { 2.0 } else { 4.0 });
    if j > 0 {
        x = add(x, v[j - 1]);
    }
    if j + 1 < n {
        x = add(x, v[j + 1]);
    }
    x
}

/// Σ over the elements of a scalar chain of 2a_j b_j + a_j b_{j+1} + a_{j+1} b_j +
/// 2a_{j+1} b_{j+1} (6/m times its consistent mass's bilinear form).
fn scalar_mass_form(a: &[f64], b: &[f64]) -> f64 {
    (0..a.len().saturating_sub(1))
        .map(|j| 2.0 * a[j] * b[j] + a[j] * b[j + 1] + a[j + 1] * b[j] + 2.0 * a[j + 1] * b[j + 1])
        .sum()
}

/// Errors of the mode-shape recovery.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ShapeError {
    /// An eigenvalue or multiplicity given is not usable.
    #[error("bad eigenvalue {lambda:e} rad²/s² with multiplicity {multiplicity} (must be finite, > 0, multiplicity 1..={MAX_MULTIPLICITY})")]
    BadMode {
        /// λ given, rad²/s².
        lambda: f64,
        /// Multiplicity given.
        multiplicity: u32,
    },
    /// The models do not match what the solver was loaded with.
    #[error("the solver was loaded with {loaded} chains, the models have {given}; load the same models first")]
    NotLoaded {
        /// Chains loaded.
        loaded: usize,
        /// Chains in the models given.
        given: usize,
    },
    /// A rigid end-effector needs one attachment arm per cable.
    #[error("rigid end-effector: {given} attachment arms for {cables} cables")]
    MissingArms {
        /// Arms given.
        given: usize,
        /// Cables.
        cables: usize,
    },
    /// The bordered system has no null space of the given dimension at λ.
    #[error("λ = {lambda:e} rad²/s² is not an eigenvalue of multiplicity {multiplicity}: singular values σ_m/σ_max = {sigma_m:.2e}, σ_(m+1)/σ_max = {sigma_next:.2e}")]
    NotAnEigenvalue {
        /// λ given, rad²/s².
        lambda: f64,
        /// Multiplicity given.
        multiplicity: u32,
        /// σ_m/σ_max.
        sigma_m: f64,
        /// σ_{m+1}/σ_max (∞ when m is the whole system).
        sigma_next: f64,
    },
    /// A hidden cable whose model mixes a discrete and a continuous segment (no element
    /// model builds one).
    #[error("mode shapes of a hidden cable need its free and hidden parts both discrete or both continuous")]
    HiddenCable,
    /// Mode shapes of sagging cables are computed for the FEM chains only.
    #[error("mode shapes of sagging continuous cables are not computed: use the fem element")]
    SagContinuous,
    /// The singular value decomposition did not converge in its bound.
    #[error("singular value decomposition did not converge at λ = {0:e} rad²/s²")]
    Svd(f64),
    /// A parameter is out of its range.
    #[error("bad shape parameter: {0}")]
    BadParams(&'static str),
    /// The eigenvalue count failed.
    #[error(transparent)]
    Modal(#[from] ModalError),
}

impl ShapeParams {
    /// Check the ranges.
    pub fn check(&self) -> Result<(), ShapeError> {
        if !(self.null_tol > 0.0 && self.null_tol < 1.0) {
            return Err(ShapeError::BadParams("null_tol must be in (0, 1)"));
        }
        if !(2..=MAX_CONTINUOUS_SAMPLES).contains(&self.continuous_samples) {
            return Err(ShapeError::BadParams(
                "continuous_samples must be in 2..=10001",
            ));
        }
        if !(1..=100_000).contains(&self.svd_max_iterations) {
            return Err(ShapeError::BadParams(
                "svd_max_iterations must be in 1..=100000",
            ));
        }
        if !(self.cluster_rel > 0.0 && self.cluster_rel < 1e-2) {
            return Err(ShapeError::BadParams("cluster_rel must be in (0, 0.01)"));
        }
        if !(1..=10_000).contains(&self.max_bisections) {
            return Err(ShapeError::BadParams("max_bisections must be in 1..=10000"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod overlap_tests {
    use super::*;

    /// The overlaps as one product equal the element forms summed pair by pair.
    #[test]
    fn mass_overlap_product_equals_the_pairs() {
        let mut seed = 1u64;
        let mut r = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut shapes = |n: usize| ModeShapes {
            dim: 6,
            fractions: vec![vec![0.0; 4], vec![0.0; 2], vec![0.0; 1]],
            modes: (0..n)
                .map(|_| ModeShape {
                    lambda: 1.0,
                    frequency_hz: 0.0,
                    ee: Vector6::from_fn(|_, _| r()),
                    cables: [4, 2, 1]
                        .iter()
                        .map(|&k| (0..k).map(|_| Vector3::new(r(), r(), r())).collect())
                        .collect(),
                    hidden: vec![(0..3).map(|_| r()).collect(), Vec::new(), vec![r()]],
                    ee_participation: 0.0,
                    cluster_start: 0,
                    multiplicity: 1,
                    null_residual: 0.0,
                })
                .collect(),
            element_mass_kg: vec![0.3, 0.7, 1.1],
            hidden_element_mass_kg: vec![0.2, 0.0, 0.5],
        };
        let (a, b) = (shapes(3), shapes(4));
        let ee = nalgebra::Matrix6::from_fn(|i, j| if i == j { 2.0 + i as f64 } else { 0.1 });
        let fast = a.mass_overlap(&b, &ee).unwrap();
        let pairs = a.mass_overlap_by_pairs(&b, &ee);
        assert_eq!(fast.len(), 12);
        for (x, y) in fast.iter().zip(&pairs) {
            assert!((x - y).abs() <= 1e-14 * (1.0 + y.abs()), "{x} vs {y}");
        }
        // The norms under a's masses are the diagonal of b's overlap with itself under
        // them (b's shapes on a's masses, through the product's own path).
        let a = ModeShapes {
            element_mass_kg: vec![0.5, 0.6, 1.3],
            hidden_element_mass_kg: vec![0.1, 0.0, 0.7],
            ..a
        };
        let norms = a.mass_norms_of(&b, &ee).unwrap();
        let b_on_a = ModeShapes {
            element_mass_kg: a.element_mass_kg.clone(),
            hidden_element_mass_kg: a.hidden_element_mass_kg.clone(),
            ..b.clone()
        };
        let own = b_on_a.mass_overlap(&b, &ee).unwrap();
        for (j, n) in norms.iter().enumerate() {
            let d = own[j * 4 + j];
            assert!((n - d).abs() <= 1e-14 * d.abs().max(1.0), "{n} vs {d}");
        }
        assert_eq!(norms.len(), 4);
    }
}
