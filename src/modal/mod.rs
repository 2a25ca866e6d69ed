//! Natural frequencies: the dense reference and the structured real-time solver.
//!
//! The free vibration problem is K u = λ M u, λ = ω² (rad²/s²), f = ω / 2π (Hz)
//! (paper Eqs. 33-35, with K and M in the right places).
//!
//! **Dense reference** ([`assemble`], [`dense_modes`]): the assembled K and M (3 DOF per
//! interior node plus the end-effector node), reduced to a standard symmetric problem
//! with the Cholesky factor of M, solved by a dense symmetric eigensolver. A backward
//! stable solver has absolute eigenvalue error ≈ ε·λ_max, i.e. relative error
//! ε·λ_max/λ on a mode λ ([`dense_relative_accuracy`]). It needs O(n²) memory and O(n³)
//! time, so assembly refuses n with [`dense_memory_bytes`] above
//! [`DENSE_MEMORY_BUDGET_BYTES`] (2 GiB, ≈ 4 700 DOF). Never on the real-time path.
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
//! **The first K modes** ([`ModalSolver::modes`], module `spectrum`, docs/modes.md): the
//! count J(λ) brackets the k-th eigenvalue; bisection on the count while two or more
//! distinct poles lie in the bracket, count probes at λ_p(1 ∓ 1e-13) around a single pole
//! (a mode exactly on a pole has the end-effector still: identical cables), then safeguarded
//! Newton on branch k − (blocked count) of D with the bounding poles removed, to 1e-14.
//! Multiplicities are the count's step over λ(1 ∓ 1e-10); a cluster's participations are the
//! eigenvalues of M_ee^{1/2} R M_ee^{1/2} with R = Σ_cluster φ_ee φ_eeᵀ (basis-invariant).
//! Each evaluation is O(1) in the element count, so N = 10⁶ costs what N = 10 does.
//!
//! **Sum rules.** With mass-normalised modes φ_k, D(σ)⁻¹ = Σ_k φ_k φ_kᵀ/(λ_k − σ) on the
//! end-effector's coordinates, so Σ_k p_k/λ_k = tr(M_ee D(0)⁻¹), and as σ → −∞,
//! Σ_k p_k = tr(M_ee M_∞⁻¹) with M_∞ = lim −D(σ)/σ: the end-effector's mass plus each
//! chain's end mass (m/3 + (m/6)·U_{N−2}(−2)/U_{N−1}(−2) for N consistent-mass elements of
//! mass m, 0 for a continuous chain). What a set of known modes does not hold bounds the
//! participation of every other mode; [`ModalSolver::ee_mode_tracked`] certifies its answer
//! with it.
//!
//! **Budget.** [`ModalSolver::begin_cycle`] sets a per-cycle budget of D(λ) evaluations
//! ([`ModalParams::cycle_evaluations`]; [`CYCLE_EVALUATIONS`] in real time). Every loop that
//! evaluates D(λ) checks it first, so a cycle never exceeds it: the first root's Newton runs
//! first (a few evaluations), the end-effector tracker gets the rest, and a scan that runs
//! out is a plain-data state ([`ModalSolver::ee_scanning`]) continued from the same pole
//! interval in the next cycle, on that cycle's problem. A scan only discovers the modes to
//! watch; an answer found over several cycles is certified by the sum rules at the pose of
//! the cycle that reports it.
//!
//! **Units** (SI throughout): K and D in N/m (N·m/rad in a rigid body's rotational block),
//! M and D' in kg (kg·m²), λ in rad²/s², f in Hz; participations are dimensionless (0 ..= 1)
//! and Σ_k p_k/λ_k is in s²/rad².
//!
//! **Layout.** `frf`: the frequency response at the end-effector (damped receptance, exact at a complex λ; modal
//! superposition for modal damping). `engine`: the condensed problem behind one trait (taut and sagged) and the
//! constants its searches share. `dense`: the offline reference (refused beyond
//! [`DENSE_MEMORY_BUDGET_BYTES`]). `dynamic_stiffness`: the loaded problem and the
//! evaluation of D(λ). `first_mode`: the first root and its certificate. `ee_tracker`: the
//! end-effector mode, scanned and tracked. `spectrum`: the first K modes
//! ([`ModalSolver::modes`], [`Mode`], [`SpectrumParams`]). `solver`: [`ModalSolver`], which
//! composes them. `mechanism`: a
//! direction the static stiffness does not hold ([`free_direction`]). `sagged`: the sagged
//! problem (chains on their catenaries, not uniform: each chain's poles found by a search on
//! its own count, shown to the end-effector tracker; the other searches use the count) as
//! a [`Condensed`] view for the same first root, tracker and spectrum search, and its
//! dense reference ([`SagModalSolver`]). `response`: the end-effector's time response by
//! modal superposition with the static correction ([`response::ModalResponse`]).
//! `quasi_static`: the inertial load of the quasi-static motion on the whole robot (its
//! participation factors and quasi-static mass, [`quasi_static::QuasiStaticLoad`]).

mod dense;
mod dynamic_stiffness;
mod ee_tracker;
mod engine;
mod error;
mod first_mode;
mod frf;
mod mechanism;
pub mod quasi_static;
pub mod response;
pub mod ritz;
pub mod sagged;
mod shapes;
mod solver;
mod spectrum;
pub mod standard_form;
pub mod sym_eigen;

pub use dense::{
    assemble, assemble_in_cable_frames, assemble_rigid, assembled_dof, check_dense_budget,
    condense_static, dense_memory_bytes, dense_modes, dense_modes_ee, dense_relative_accuracy,
    Assembly, CableFrames, DenseModes, DensePair, Entries, Entry, DENSE_MEMORY_BUDGET_BYTES,
};
pub use dynamic_stiffness::TautChains;
pub use ee_tracker::RescanCounts;
pub use engine::{Condensed, DynEval, EigD, PoleCursor, SumRules};
pub use error::ModalError;
pub use frf::{
    complex_shift, dense_receptance, frequency_grid, FrfError, ModalBasis, MAX_FRF_HZ,
    MAX_FRF_MODES, MAX_FRF_POINTS,
};
pub use mechanism::{free_direction, may_be_mechanism, MECHANISM_REL};
pub use shapes::{
    near_runs, ModeShape, ModeShapes, ShapeError, ShapeParams, MAX_CONTINUOUS_SAMPLES,
    MAX_MULTIPLICITY,
};
pub use solver::{receptance_over, ModalSolver, SagModalSolver, Solver};
pub use spectrum::{Mode, SpectrumParams};

/// A rigid end-effector's parts: world-frame inertia about the centroid (kg·m²), the
/// attachment arms (m) and the rotational geometric stiffness (N·m/rad).
type RigidParts<'a> = (
    &'a nalgebra::Matrix3<f64>,
    &'a [nalgebra::Vector3<f64>],
    &'a nalgebra::Matrix3<f64>,
);

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

/// The real-time per-cycle budget of D(λ) evaluations. Along the paper's circle (spatial
/// robot, 20,000 cycles, unlimited budget) a warm cycle without a band rescan needs 7-8
/// (median), 13-15 (p99), 16-25 (p99.9) and at most 19-34 (fem × 40, catenary × 40 and × 10,
/// continuous); a cold first root with its certificate about 12. 32 covers all but a few in
/// 10⁵ of them; a band rescan (up to ~190) or a cold scan is spread over the cycles.
pub const CYCLE_EVALUATIONS: u32 = 32;

/// The scan bound ([`ModalParams::max_scan_evaluations`]) of the real-time configuration:
/// a scan spread over the cycles by the budget costs the answer's age, not the cycle's
/// latency, so it may go on longer than an unlimited one-cycle scan (1 500 by default);
/// enough for the ~250 string modes below the end-effector mode of the heavy-cable test
/// scene (tests/data/spatial_heavy_cable.toml).
pub const SPREAD_SCAN_EVALUATIONS: u32 = 4000;

/// Parameters of the structured solver (finite bounds everywhere).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModalParams {
    /// Largest number of D(λ) evaluations for one root.
    pub max_evaluations: u32,
    /// Relative step size at which Newton stops.
    pub rel_tol: f64,
    /// Largest number of pole intervals (or, where the count alone shows the poles, modes)
    /// scanned for the end-effector mode. Without a cycle budget on sagged FEM chains (poles
    /// searched) the scan may pass at least the model's count of modes (its dimension plus
    /// the chains' blocked DOFs; ~940 on suspended-8 at 40 elements), which bounds its pole
    /// intervals: the answer is found wherever it lies, and a scan from zero stops once the
    /// plain sum rule leaves less than the threshold to the modes above.
    pub max_scan_intervals: u32,
    /// Largest number of D(λ) evaluations one end-effector scan may spend (over all the
    /// cycles it is continued in).
    pub max_scan_evaluations: u32,
    /// The per-cycle budget of D(λ) evaluations (first root and end-effector mode
    /// together); the end-effector work that does not fit is continued in the next cycles.
    /// `u32::MAX` (the default: offline analyses want every answer complete): unlimited;
    /// the real-time users (the service, `bench`, `Estimator::realtime` (estimator))
    /// use [`CYCLE_EVALUATIONS`].
    pub cycle_evaluations: u32,
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
            cycle_evaluations: u32::MAX,
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
    /// Relative residual |μ(λ_k)| / (λ_k · max_ij |D'(λ_k)_ij|) at the last iterate λ_k
    /// the solver evaluated (μ: the branch of D that vanishes at the root): the eigenvalue
    /// of D against the size of the inertia term λD' it must cancel (‖D‖ itself vanishes
    /// at a multiple root, so it is no scale). To first order it is the relative distance
    /// of λ_k to the root; `lambda`, one Newton step further, is closer still (≈ its
    /// square). Dimensionless; ≤ the solver's step tolerance on a converged answer.
    pub residual: f64,
}
