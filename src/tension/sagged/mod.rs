//! Tension distribution with sagging cables: the chord model's QP with each cable's chord
//! direction replaced by its catenary's end tangent.
//!
//! Cable i hangs as an elastic catenary (`crate::sag`) through its chord, anchor a_i →
//! attachment point, with end-effector-end tension T_e,i; it pulls the end-effector with
//! −T_e,i t_i, t_i the world unit end tangent (toward increasing unstretched arclength,
//! i.e. away from the anchor), exactly as the chord model's −T_i s_i. Equilibrium is then
//! A(t) T_e = w with the structure matrix of the tangents (rows t_i and r_i × t_i), and
//!
//! ```text
//!     minimise Σ T_e,i²   subject to   A(t(T_e)) T_e = w,   t_min,i ≤ T_e,i ≤ t_max,i.
//! ```
//!
//! Method: fixed point on the end directions, T = QP(A(T)), accelerated by Newton. Start
//! from the chords (cold) or from the last call's end tensions (warm); a pass is (1) the active-set QP
//! ([`TensionSolver`], itself warm-started) with columns t_i gives new T_e; (2) each
//! cable's taut catenary for its T_e,i (Newton from the first-order prediction of its last
//! solution for the new chord and tension, `CableChord::solve_end_tension_tracked`) gives
//! t_i. Converged when no end direction moved more than `direction_tol_rad` in the last
//! pass, or, before (2), when the QP gave back the tensions the current tangents were
//! solved at (to 1e-12 of the largest, and with a first-order change of direction
//! |dt_i/dT_i|·|ΔT_i| below the tolerance): the current state is then the fixed point and
//! no further catenary sweep is needed. At most `max_iterations` passes. After each
//! unconverged pass, and once from the warm start, Newton's step on the fixed point's
//! optimality system with the QP's active set held (`newton.rs`, which also corrects that
//! active set near a fold) replaces the tensions: one or two passes per warm cycle instead
//! of 4-26 plain ones, and it reaches fixed points that the plain passes move away
//! from (a very slack cable). The reported catenaries, tangents and tensions are those of
//! the last catenary sweep, and the QP on those tangents gives these tensions back to the
//! tolerance.
//!
//! Plane basis of cable i: up = −g/|g|, h_i the horizontal part of its chord normalised
//! (the first column of `up_frame(g)` for a vertical chord), n_i = h_i × up. With every
//! w_i = 0 the tangents are the chords and the result is the chord solver's.

mod newton;
mod solve;

use super::{TensionError, TensionParams, TensionSolver};
use crate::kinematics::Geometry;
use crate::sag::{CableChord, Catenary, SagError, SagParams, SagTrack};
use nalgebra::Vector3;

/// Parameters of the sagged tension distribution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SagTensionParams {
    /// Largest number of fixed-point passes (catenaries + QP).
    pub max_iterations: u32,
    /// Converged when every end tangent moved less than this, rad. 1e-12 rad times the
    /// tensions keeps the equilibrium residual ~1e-12 of the load.
    pub direction_tol_rad: f64,
    /// The catenary solver's parameters.
    pub sag: SagParams,
    /// The QP's parameters.
    pub tension: TensionParams,
    /// Accelerate the passes by Newton's step on the optimality system (`newton.rs`);
    /// off, every pass is the plain fixed-point update.
    pub newton: bool,
}

impl Default for SagTensionParams {
    fn default() -> Self {
        SagTensionParams {
            max_iterations: 60,
            direction_tol_rad: 1e-12,
            sag: SagParams::default(),
            tension: TensionParams::default(),
            newton: true,
        }
    }
}

/// What the last solve did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SagTensionInfo {
    /// Fixed-point passes.
    pub iterations: u32,
    /// Largest end-direction change of the last pass, rad.
    pub direction_change_rad: f64,
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
    /// The fixed point did not settle.
    #[error("sagged tension distribution did not converge in {iterations} passes (end directions still moved {direction_change_rad:.3e} rad)")]
    NoConvergence {
        /// Passes done.
        iterations: u32,
        /// Largest end-direction change of the last pass, rad.
        direction_change_rad: f64,
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
    /// The geometry handed to the QP: unit = end tangents, arms and lengths copied.
    tangent_geom: Geometry,
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
    /// Newton's input and output (`newton.rs`).
    newton_in: Vec<newton::NewtonCable>,
    newton_out: Vec<f64>,
    /// The tensions before Newton's step (restored when its catenaries fail), N.
    t_before: Vec<f64>,
    have_warm: bool,
    info: SagTensionInfo,
}
