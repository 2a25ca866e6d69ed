//! Tension distribution with sagging cables: the least Σ T² over the exact sagged
//! equilibrium, each cable pulling along its catenary's end tangent.
//!
//! Cable i hangs as an elastic catenary (`crate::elastic_catenary`) through its chord, anchor a_i →
//! attachment point, with end-effector-end tension T_e,i; it pulls the end-effector with
//! −T_e,i t_i, t_i the world unit end tangent (toward increasing unstretched arclength,
//! i.e. away from the anchor), exactly as the chord model's −T_i s_i. Equilibrium is then
//! A(t) T_e = w with the structure matrix of the tangents (rows t_i and r_i × t_i), and
//!
//! ```text
//!     minimise Σ T_e,i²   subject to   A(t(T_e)) T_e = w,   t_min,i ≤ T_e,i ≤ t_max,i.
//! ```
//!
//! Its answer is the least Σ T_e,i² over the exact sagged equilibrium: each cable's end
//! force f_i(T_i) = T_i a_i(T_i) is a function of its own end tension through its catenary,
//! so the constraint Σ f_i(T_i) = w is nonlinear, and the answer is a KKT point of that
//! problem (stationarity T_i = b_i·λ + ν_i with b_i = df_i/dT_i = a_i + T_i a_i′, ν_i ≥ 0 at
//! T_min and ≤ 0 at T_max, zero for a free cable). It is not the fixed point T = QP(A(T))
//! of the chord QP on the end tangents (stationarity T_i = a_i·λ): that fixed point is not
//! unique where a cable's tangent turns with its tension, and the passes toward it could
//! cycle between two active sets.
//!
//! Method: SQP on the exact constraint (`solve.rs`, `kkt.rs`). Start from the chord QP's
//! tensions (cold) or the last call's end tensions (warm, clamped into the bounds). An
//! iteration: (1) each cable's taut catenary at its T_e,i gives a_i and a_i′
//! (`CableChord::solve_end_tension_tracked`, warm from its last solution); (2) the active-set
//! QP ([`TensionSolver`], warm-started) on the linearised equilibrium, min ½‖T′‖² subject to
//! Σ b_i T′_i = Σ b_i T_i − F(T) and the bounds, gives the active set and a step with the
//! Hessian approximated by I; (3) from that active set, corrected until it is the
//! subproblem's KKT point (at most 2n + 2 sets, `kkt.rs`), the Newton–KKT step with the
//! Lagrangian's exact diagonal Hessian D_i = 1 − λ·b_i′ (b_i′ by the secant of b_i between
//! the iterations of a solve, kept from one call to the next, D_i clamped to [0.05, 1e4],
//! `solve.rs`) replaces it (when no set is found, the D = I step stays); (4) the step is
//! safeguarded by backtracking on the ℓ1 merit ½‖T‖² + ρ‖F(T)‖₁ (ρ at least twice the
//! largest multiplier, at most 12 halvings; steps below 1e-6 of the largest tension are
//! taken in full). Converged when the step is below `step_tol_rel` of the largest
//! tension: the current tensions, with the catenaries and tangents at them, are then the
//! KKT point to that step. At most `max_iterations` iterations, else `NoConvergence`.
//!
//! Plane basis of cable i: up = −g/|g|, h_i the horizontal part of its chord normalised
//! (the first column of `up_frame(g)` for a vertical chord), n_i = h_i × up. With every
//! w_i = 0 the tangents are the chords and the result is the chord solver's.

mod kkt;
mod solve;

use super::{TensionError, TensionParams, TensionSolver};
use crate::elastic_catenary::{CableChord, Catenary, SagError, SagParams, SagTrack};
use crate::kinematics::Geometry;
use nalgebra::{Vector3, Vector6};

/// Parameters of the sagged tension distribution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SagTensionParams {
    /// Largest number of SQP iterations (catenaries, QP, Newton–KKT step, line search).
    pub max_iterations: u32,
    /// Converged when the SQP step is below this fraction of the largest end tension (the
    /// equilibrium residual and the stationarity residual are then of that order).
    pub step_tol_rel: f64,
    /// The catenary solver's parameters.
    pub sag: SagParams,
    /// The QP's parameters.
    pub tension: TensionParams,
}

impl Default for SagTensionParams {
    fn default() -> Self {
        SagTensionParams {
            max_iterations: 60,
            step_tol_rel: 1e-11,
            sag: SagParams::default(),
            tension: TensionParams::default(),
        }
    }
}

/// What the last solve did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SagTensionInfo {
    /// SQP iterations.
    pub iterations: u32,
    /// Catenary sweeps (one per iteration and one per backtracking trial).
    pub sweeps: u32,
    /// Largest |ΔT_e,i| of the last SQP step, N.
    pub step_n: f64,
    /// ‖Σ T_e,i t_i − w_force‖∞ of the reported state, N.
    pub residual_force_n: f64,
    /// ‖Σ T_e,i r_i × t_i − w_moment‖∞ of the reported state, N·m.
    pub residual_moment_n_m: f64,
}

/// Errors of the sagged tension distribution.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SagTensionError {
    /// A cable's tension reaches zero somewhere (its end tension is below what any
    /// catenary through its chord needs).
    #[error("cable {cable} is slack: {reason}")]
    Slack {
        /// Cable index.
        cable: usize,
        /// The catenary solver's diagnosis (TooSlack with both tensions, or a zero tension).
        reason: SagError,
    },
    /// A cable's catenary could not be computed (bad input or no convergence).
    #[error("cable {cable}: {source}")]
    Catenary {
        /// Cable index.
        cable: usize,
        /// The catenary solver's error.
        source: SagError,
    },
    /// The QP failed; `Infeasible` keeps the closest solution in `tensions_n()`.
    #[error(transparent)]
    Tension(#[from] TensionError),
    /// Bad input: slice lengths, non-finite material or gravity.
    #[error("invalid sagged tension input: {what}")]
    Invalid {
        /// Which input.
        what: &'static str,
    },
    /// The SQP did not settle within its iterations.
    #[error("sagged tension distribution did not converge in {iterations} iterations (last step {step_n:.3e} N)")]
    NoConvergence {
        /// Iterations done.
        iterations: u32,
        /// Largest |ΔT_e,i| of the last step, N.
        step_n: f64,
    },
}

/// Each cable's material: EA (N) and weight per unstretched length (N/m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SagCable {
    /// Axial rigidity EA, N.
    pub ea_n: f64,
    /// Weight per unstretched length w ≥ 0, N/m.
    pub w_n_m: f64,
}

impl SagCable {
    /// Every cable of `scene` hanging by its own weight: EA and mass per length times |g|
    /// (allocates: set-up only).
    pub fn of_scene(scene: &crate::scene::Scene) -> Vec<SagCable> {
        let gn = scene.gravity_m_s2.norm();
        scene
            .cables
            .iter()
            .map(|c| SagCable {
                ea_n: c.ea_n(),
                w_n_m: c.mass_per_length_kg_m * gn,
            })
            .collect()
    }
}

/// The sagged tension solver: `new` allocates, `solve` does not.
#[derive(Debug, Clone)]
pub struct SagTensionSolver {
    params: SagTensionParams,
    qp: TensionSolver,
    /// The end tangents' geometry: unit = t_i, arms and lengths copied.
    tangent_geom: Geometry,
    /// The linearised equilibrium handed to the QP: unit = t_i + T_i dt_i/dT_i (not unit).
    lin_geom: Geometry,
    chords: Vec<CableChord>,
    cats: Vec<Catenary>,
    /// Each cable's last solution with its sensitivities (the next solve's start).
    tracks: Vec<Option<SagTrack>>,
    h: Vec<Vector3<f64>>,
    n_out: Vec<Vector3<f64>>,
    up: Vector3<f64>,
    t_end: Vec<f64>,
    /// d t_i/dT_e,i of each cable's world end tangent at its current tension, 1/N.
    dtan: Vec<Vector3<f64>>,
    /// The Newton–KKT step's input (`kkt.rs`).
    kkt: Vec<kkt::KktCable>,
    /// The step's target tensions, N.
    t_new: Vec<f64>,
    /// The tensions at the start of a line search, N.
    t_base: Vec<f64>,
    /// b_i at the start of a line search (for the secant).
    b_prev: Vec<Vector6<f64>>,
    /// db_i/dT_i by the secant, 1/N (kept from call to call).
    db: Vec<Vector6<f64>>,
    /// The last step's multipliers λ (force N, moment N·m per unit).
    lambda: Vector6<f64>,
    have_warm: bool,
    info: SagTensionInfo,
}
