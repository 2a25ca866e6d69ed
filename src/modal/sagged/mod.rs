//! The condensed problem of a robot whose cables sag ([`SagChains`], solved by
//! [`SagModalSolver`](crate::modal::SagModalSolver) = the one structured
//! [`Solver`](crate::modal::Solver) on this problem) and its dense reference.
//!
//! **D(λ).** Cable i hangs in the plane (h_i, up), n_i = h_i × up; its chain, condensed
//! onto its end, gives S_in,i(λ) (2 × 2 in (h_i, up)) and s_out,i(λ). With E_i = [h_i up]
//! (3 × 2), the end-effector's dynamic stiffness is
//!
//! ```text
//!     D(λ) = Σ_i [E_i S_in,i Eᵢᵀ + s_out,i n_i n_iᵀ] − λ m I                    (point mass)
//!     D(λ) = Σ_i G_iᵀ [E_i S_in,i Eᵢᵀ + s_out,i n_i n_iᵀ] G_i + K_geo − λ M₆     (rigid body)
//! ```
//!
//! with G_i = [I, −\[r_i\]×] the attachment map of arm r_i and K_geo = Σ_i (f_i·r_i) I −
//! sym(f_i r_iᵀ) the rotational geometric stiffness of the end forces
//! f_i = −(H_i h_i + V_e,i up) (along the end tangent, not the chord). A cable on a swivel
//! pulley adds the pulleys' own term to both, the symmetric part of −S_i(0) X_i (mapped
//! through G_i on a rigid body; X_i its exit point's motion,
//! [`crate::modal::SagModalSolver::set_exit_motion`]), the same at every λ. One evaluation is one O(N)
//! recurrence per cable. The Wittrick–Williams count J(λ) = Σ_i below_i(λ) + (negative
//! eigenvalues of D(λ)) is the exact number of natural frequencies below λ.
//!
//! **Lockstep evaluation.** When every loaded FEM chain has the same element count, `load`
//! packs them into a [`crate::cable::sagged::SagBatch`] and each evaluation runs all the
//! recurrences side by side (bit-identical to one chain after the other,
//! [`SagChains::eval_reference`]); count-only evaluations skip S'.
//!
//! **The searches** (first root, end-effector mode, first K modes, shapes, frequency
//! response) are the solver's, written once for every model (`modal`'s docs). What the
//! sagged problem gives them differently ([`crate::modal::Condensed`], `condensed`): its
//! chains are not uniform, so their blocked eigenvalues (the poles of D) are not known in
//! closed form and the count shows where they are (a search bisects on the blocked count
//! until its bracket is pole-free, a first-root iterate with a pole below it is an upper
//! bound); the static evaluation D(0) comes from each chain's cached S(0) without a counted
//! evaluation; the sum rules' total comes from one evaluation far below zero, with the
//! matrix forms the tracker's certificate bounds one direction by.
//!
//! Files: `problem` (the loaded pose, D(λ)), `load` (setting it up), `condensed` (its view
//! for the searches), `poles` (each chain's poles by its own count, followed between
//! loads), `pole_view` (a mode's coupling to one chain and that chain's poles, which the
//! end-effector tracker's partner searches start from), `dense` (the assembled reference).

mod condensed;
mod dense;
mod load;
mod pole_view;
mod poles;
mod problem;

pub use dense::{assemble_sagged, sagged_assembled_dof, SagDenseCable};
pub use problem::SagChains;

use crate::cable::sagged::{SagChainError, SagContError};
use crate::elastic_catenary::Catenary;
use nalgebra::{Matrix3, Vector3};

/// How one cable of a pose attaches to the end-effector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SagCableFrame {
    /// Unit horizontal h of the cable's plane (from the anchor toward the end), world frame.
    pub h: Vector3<f64>,
    /// Attachment arm from the centroid, world frame, m (rigid end-effector only).
    pub arm_m: Vector3<f64>,
    /// Force of the cable on the end-effector, −(H h + V_e up), N (rigid end-effector
    /// only: its rotational geometric stiffness).
    pub end_force_n: Vector3<f64>,
}

/// One sagging cable of a pose, for `SagModalSolver::load_catenaries`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HangingCable {
    /// The static profile.
    pub catenary: Catenary,
    /// Mass per unstretched length, kg/m.
    pub mu_kg_m: f64,
    /// Unit horizontal h of the cable's plane, world frame.
    pub h: Vector3<f64>,
    /// Attachment arm from the centroid, world frame, m (rigid end-effector only).
    pub arm_m: Vector3<f64>,
}

/// The end-effector: a point mass (3 DOF) or a rigid body (6 DOF).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SagEndEffector {
    /// Point mass, kg.
    Point {
        /// Mass, kg.
        mass_kg: f64,
    },
    /// Rigid body: mass and world-frame inertia about the centroid.
    Rigid {
        /// Mass, kg.
        mass_kg: f64,
        /// Inertia, kg·m².
        inertia_kg_m2: Matrix3<f64>,
    },
}

/// Errors of `SagModalSolver::load`.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SagLoadError {
    /// More cables than the solver was built for.
    #[error("{given} cables, the solver holds {capacity}")]
    CableCount {
        /// Cables given.
        given: usize,
        /// Cables the solver was built for.
        capacity: usize,
    },
    /// Cable i's basis is not orthonormal (h unit and horizontal, up unit) or not finite.
    #[error("cable {0}: its frame is not a finite orthonormal basis")]
    BadFrame(usize),
    /// The end-effector's mass or inertia is not positive definite and finite.
    #[error("end-effector mass or inertia not positive and finite")]
    BadMass,
    /// Cable i's chain could not be set.
    #[error("cable {0}: {1}")]
    Chain(usize, SagChainError),
    /// Cable i's continuous chain could not be set.
    #[error("cable {0}: {1}")]
    Continuous(usize, SagContError),
}
