//! The forward model of one pose: geometry → tension distribution → cable models → modal
//! solver loaded → first root. One [`Forward`] owns the cable geometry and one of two
//! models, chosen by the scene's `[effects] sag`:
//!
//! - [`Model::Taut`]: straight chords — the active-set tension distribution, the scene's
//!   element on each chord, the structured solver of `modal` (`taut.rs`);
//! - [`Model::Sagged`]: the cables' elastic catenaries — the sagged tension distribution,
//!   chains about the sagged profiles, the structured solver of `modal::sagged` (`sagged.rs`).
//!
//! The cycle ([`Estimator::update`]) and the inverse T_min query
//! ([`Estimator::t_min_for_f1`]) each own one, so the query leaves the cycle's warm state
//! alone. Nothing here allocates after [`Forward::new`].
//!
//! The pieces of the model that do not depend on how the tensions were found — the
//! geometry at a pose ([`update_geometry`]), the cable models ([`fill_models`]) and the
//! end-effector at the pose ([`EndEffector`]) — are written here once, for the cycle, the
//! dense reference and `cablevib modes` ([`PoseModel`](super::PoseModel)).
//!
//! [`Estimator::update`]: super::Estimator::update
//! [`Estimator::t_min_for_f1`]: super::Estimator::t_min_for_f1

mod sagged;
mod taut;

use super::{EstimatorError, EstimatorParams};
use crate::cable::sagged::SagContinuousParams;
use crate::cable::{CableError, CableModel};
use crate::elastic_catenary::Catenary;
use crate::kinematics::{Geometry, KinematicsError, Pose};
use crate::modal::{
    self, Condensed, ModalError, ModalParams, ModalSolver, Mode, RescanCounts, Root, Solver,
};
use crate::scene::{ElementKind, Scene, MAX_CABLES};
use crate::tension::{SagTensionParams, TensionError, TensionInfo, TensionParams, TensionSolver};
use nalgebra::{DMatrix, Matrix3, Matrix6, Vector3};
use sagged::SagModel;
use taut::TautModel;

/// The parameters of one forward model (the cycle's, or the inverse query's): see
/// [`super::EstimatorParams`], which holds them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct ForwardParams {
    /// The chord tension distribution (taut cables; also the rank check at build).
    pub(super) tension: TensionParams,
    /// The structured solver (both models).
    pub(super) modal: ModalParams,
    /// The sagged tension distribution.
    pub(super) sag_tension: SagTensionParams,
    /// The mesh rule of continuous sagged chains.
    pub(super) sag_continuous: SagContinuousParams,
}

impl ForwardParams {
    /// The cycle's forward model.
    pub(super) fn cycle(p: &EstimatorParams) -> ForwardParams {
        ForwardParams {
            tension: p.tension,
            modal: p.modal,
            sag_tension: p.sag.tension,
            sag_continuous: p.sag.continuous,
        }
    }

    /// The inverse T_min query's forward model: not a cycle, so no per-cycle budget and no
    /// certificate; the query's sagged mesh.
    pub(super) fn t_min_query(p: &EstimatorParams) -> ForwardParams {
        ForwardParams {
            modal: ModalParams {
                certify: false,
                cycle_evaluations: u32::MAX,
                ..p.modal
            },
            sag_continuous: p.sag.t_min_query_continuous,
            ..ForwardParams::cycle(p)
        }
    }
}

/// What a cycle's tension solve reports to the estimate.
#[derive(Debug, Clone, Copy)]
pub(super) struct TensionReport<'a> {
    /// Iterations of the tension solver (SQP iterations when the cables sag).
    pub(super) iterations: u32,
    /// Whether the warm start was accepted.
    pub(super) warm: bool,
    /// The end-effector-end tensions, N (the closest ones after an infeasible solve).
    pub(super) tensions_n: &'a [f64],
}

/// Which model of the cables, with the buffers it (and only it) uses.
// The taut model's solver is ~36 KB of fixed-size buffers, the sagged one's ~8 KB: the
// enum is built once per estimator and never moved on the cycle's path, so the variants
// stay inline (no pointer to follow in every cycle) rather than boxed.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub(super) enum Model {
    /// Straight chords.
    Taut(TautModel),
    /// Cables on their elastic catenaries (`[effects] sag`).
    Sagged(SagModel),
}

/// `$body` with `$m` bound to the cable model's own part (`&` or `&mut` as `$model` is):
/// the one dispatch on [`Model`] for everything both models answer through [`CableSide`].
macro_rules! with_model {
    ($model:expr, $m:ident => $body:expr) => {
        match $model {
            Model::Taut($m) => $body,
            Model::Sagged($m) => $body,
        }
    };
}

/// What differs between the taut and the sagged model: the tension distribution and the
/// chains' set-up (loading the pose into the structured solver on their condensed problem),
/// the static stiffness and the dense matrices of what they loaded. Everything above (the
/// solver's queries) is written once in [`Forward`] over this trait.
pub(super) trait CableSide {
    /// The condensed problem the model's chains make.
    type Problem: Condensed;
    /// The structured solver, as loaded at the last pose.
    fn solver(&self) -> &Solver<Self::Problem>;
    /// The structured solver (mutable).
    fn solver_mut(&mut self) -> &mut Solver<Self::Problem>;
    /// The solver's evaluation counter when it was last loaded.
    fn loaded_at(&self) -> u32;
    /// Forget the tension solver's warm start.
    fn reset_tensions(&mut self);
    /// Forget every warm start ([`super::Estimator::reset`]).
    fn reset(&mut self);
    /// Info of the last tension solve.
    fn tension_info(&self) -> TensionInfo;
    /// See [`Forward::first_root`]; `g` the geometry at `pose`, `t_max_n` the upper bounds
    /// (N).
    #[allow(clippy::too_many_arguments)]
    fn first_root(
        &mut self,
        scene: &Scene,
        pose: &Pose,
        g: &Geometry,
        t_min_n: &[f64],
        t_max_n: &[f64],
        min_rank: u32,
        warm: Option<f64>,
        on_tensions: impl FnOnce(TensionReport<'_>),
    ) -> Result<Root, EstimatorError>;
    /// See [`Forward::static_stiffness`] (`g`: the geometry of the loaded pose).
    fn static_stiffness(&self, scene: &Scene, g: &Geometry) -> Matrix6<f64>;
    /// See [`Forward::dense_matrices`].
    fn dense_matrices(
        &self,
        scene: &Scene,
        g: &Geometry,
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), ModalError>;
    /// See [`Forward::ee_mode_tracked`]: the solver's tracker.
    fn ee_mode(&mut self, r1: &Root, warm: bool) -> Result<Option<(f64, f64)>, ModalError> {
        Ok(self
            .solver_mut()
            .ee_mode_tracked(r1, warm)?
            .map(|m| (m.lambda, m.ee_participation)))
    }
}

/// Every buffer of one forward evaluation, sized once.
#[derive(Debug, Clone)]
pub(super) struct Forward {
    /// Cable geometry at the current pose (the chords, for both models).
    pub(super) geometry: Geometry,
    /// Each cable's upper tension bound, N (the scene's, fixed).
    t_max_n: [f64; MAX_CABLES],
    /// The model of the cables.
    pub(super) model: Model,
}

impl Forward {
    /// Buffers for the cables of `scene`, the model its `[effects] sag` names (allocates:
    /// set-up only).
    pub(super) fn new(scene: &Scene, params: &ForwardParams) -> Forward {
        Forward {
            geometry: Geometry::for_scene(scene),
            t_max_n: cable_t_max_n(scene),
            model: if scene.model.sag {
                Model::Sagged(SagModel::new(scene, params))
            } else {
                Model::Taut(TautModel::new(scene, params))
            },
        }
    }

    /// Whether the cables sag.
    pub(super) fn is_sagged(&self) -> bool {
        matches!(self.model, Model::Sagged(_))
    }

    /// Cable geometry of `scene` at `pose`.
    pub(super) fn set_pose(&mut self, scene: &Scene, pose: &Pose) -> Result<(), KinematicsError> {
        update_geometry(scene, &mut self.geometry, pose)
    }

    /// The chord tension distribution at the pose of the last [`Self::set_pose`] for the
    /// lower bounds `t_min_n` (N) and the scene's upper ones, cold, and its structure
    /// matrix's rank (set up before feasibility is decided, so an infeasible pose has it
    /// too). The estimator's build takes the rank its cycles expect from it. Leaves no warm
    /// start behind. The taut model uses its own solver; the sagged one, which has none, a
    /// solver made for the call (allocates: set-up only).
    pub(super) fn chord_tensions(
        &mut self,
        scene: &Scene,
        t_min_n: &[f64],
        params: TensionParams,
    ) -> (Result<(), TensionError>, u32) {
        let n = scene.n_cables();
        let mut own;
        let ts = match &mut self.model {
            Model::Taut(t) => &mut t.tension,
            Model::Sagged(_) => {
                own = TensionSolver::new(n, params);
                &mut own
            }
        };
        let w = scene.wrench6_n();
        let solved = ts
            .solve_wrench_bounds(&self.geometry, &w, t_min_n, &self.t_max_n[..n])
            .map(|_| ());
        let rank = ts.info().rank;
        ts.reset_warm_start();
        (solved, rank)
    }

    /// At the pose of the last [`Self::set_pose`]: solve the tensions for the per-cable
    /// lower bounds `t_min_n` (N, one per cable) and the scene's upper bounds, show the
    /// solver to `on_tensions` (also when the solve failed: an infeasible solve still has
    /// its closest tensions), reject a structure matrix of rank below `min_rank` (0 accepts
    /// any; taut cables), build the cable models, load the modal solver and find the first
    /// root, warm-started from `warm` (λ, rad²/s²), within the modal parameters' per-cycle
    /// budget of D(λ) evaluations. A `Modal` error comes only from the root search, after
    /// the modal solver was loaded; every other error comes before it is loaded.
    pub(super) fn first_root(
        &mut self,
        scene: &Scene,
        pose: &Pose,
        t_min_n: &[f64],
        min_rank: u32,
        warm: Option<f64>,
        on_tensions: impl FnOnce(TensionReport<'_>),
    ) -> Result<Root, EstimatorError> {
        let t_max_n = &self.t_max_n[..scene.n_cables()];
        let g = &self.geometry;
        with_model!(&mut self.model, m => m.first_root(
            scene,
            pose,
            g,
            t_min_n,
            t_max_n,
            min_rank,
            warm,
            on_tensions,
        ))
    }

    /// The sagged equilibrium's nodes at `pose` for the lower bounds `t_min_n` (N, one per
    /// cable) and the scene's upper ones (`SagModel::equilibrium_nodes`), or None for taut
    /// cables. Leaves the cycle's state alone. Allocates (offline).
    pub(super) fn sag_nodes_at(
        &self,
        scene: &Scene,
        pose: &Pose,
        t_min_n: &[f64],
    ) -> Result<Option<Vec<Vec<Vector3<f64>>>>, EstimatorError> {
        let Model::Sagged(s) = &self.model else {
            return Ok(None);
        };
        let mut g = self.geometry.clone();
        update_geometry(scene, &mut g, pose)?;
        let t_max_n = &self.t_max_n[..scene.n_cables()];
        s.equilibrium_nodes(scene, &g, t_min_n, t_max_n).map(Some)
    }

    /// Evaluations of D(λ) since the modal solver was last loaded.
    pub(super) fn evaluations_since_load(&self) -> u32 {
        with_model!(&self.model, m => m.solver().evaluations().wrapping_sub(m.loaded_at()))
    }

    /// A cold start of the cycle: forget the tension solver's warm start and the
    /// end-effector mode's tracking.
    pub(super) fn start_cold(&mut self) {
        with_model!(&mut self.model, m => {
            m.reset_tensions();
            m.solver_mut().reset_tracking();
        })
    }

    /// Forget the tension solver's warm start.
    pub(super) fn reset_tension_warm_start(&mut self) {
        with_model!(&mut self.model, m => m.reset_tensions())
    }

    /// Forget every warm start ([`super::Estimator::reset`]; [`CableSide::reset`]).
    pub(super) fn reset(&mut self) {
        with_model!(&mut self.model, m => m.reset())
    }

    /// The end-effector mode of the loaded pose (λ in rad²/s², participation) within what
    /// is left of the cycle's budget: taut cables track it from the last cycle's
    /// ([`ModalSolver::ee_mode_tracked`]; `r1` this cycle's first root), and so do sagging
    /// cables ([`SagModel::ee_mode`]); `warm` whether the cycle is warm. Ok(None) while the work goes on over the cycles.
    pub(super) fn ee_mode_tracked(
        &mut self,
        r1: &Root,
        warm: bool,
    ) -> Result<Option<(f64, f64)>, ModalError> {
        with_model!(&mut self.model, m => m.ee_mode(r1, warm))
    }

    /// The static end-effector stiffness of the loaded models (3 × 3 or 6 × 6 block, N/m,
    /// N/rad, N·m/rad; NaN when the sagged D(0) fails).
    pub(super) fn static_stiffness(&self, scene: &Scene) -> Matrix6<f64> {
        with_model!(&self.model, m => m.static_stiffness(scene, &self.geometry))
    }

    /// The first `k` natural frequencies of the loaded pose into `out` (see
    /// [`ModalSolver::modes`]).
    pub(super) fn modes(&mut self, k: usize, out: &mut [Mode]) -> Result<usize, ModalError> {
        with_model!(&mut self.model, m => m.solver_mut().modes(k, out))
    }

    /// The end-effector's mass matrix of the loaded pose (kg, kg·m²) and its dimension.
    pub(super) fn ee_mass(&self) -> (Matrix6<f64>, usize) {
        with_model!(&self.model, m => (m.solver().ee_matrices().0, m.solver().dim()))
    }

    /// The assembled K (N/m) and M (kg) of the loaded models (the dense reference's).
    pub(super) fn dense_matrices(
        &self,
        scene: &Scene,
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), ModalError> {
        with_model!(&self.model, m => m.dense_matrices(scene, &self.geometry))
    }

    /// The model's K and M as an assembly's entries (no dense matrix), each cable's
    /// interior nodes in its own frame ([`modal::CableFrames`]); None for sagging cables.
    pub(super) fn assemble_in_cable_frames(
        &self,
        scene: &Scene,
    ) -> Option<Result<modal::CableFrames, ModalError>> {
        match &self.model {
            Model::Taut(t) => Some(t.assemble_in_cable_frames(scene, &self.geometry)),
            Model::Sagged(_) => None,
        }
    }

    /// The degrees of freedom of the loaded model (None for continuous cables): the size
    /// of [`Self::dense_matrices`]' K and M, without assembling them.
    pub(super) fn assembled_dof(&self) -> Option<usize> {
        match &self.model {
            Model::Taut(t) => crate::modal::assembled_dof(&t.models, t.modal.dim()),
            Model::Sagged(s) => (!s.modal.is_continuous()).then(|| {
                let chains = (0..s.modal.loaded_cables()).map(|i| s.modal.chain(i));
                crate::modal::sagged::sagged_assembled_dof(chains, s.modal.dim())
            }),
        }
    }

    /// The taut cable models of the last successful load (none when the cables sag).
    pub(super) fn cable_models(&self) -> &[CableModel] {
        match &self.model {
            Model::Taut(t) => &t.models,
            Model::Sagged(_) => &[],
        }
    }

    /// The taut structured solver (mutable), its cable models and the geometry of the
    /// loaded pose (None when the cables sag): the mode shapes' inputs.
    pub(super) fn taut_shapes_input(
        &mut self,
    ) -> Option<(&mut ModalSolver, &[CableModel], &Geometry)> {
        match &mut self.model {
            Model::Taut(t) => Some((&mut t.modal, &t.models, &self.geometry)),
            Model::Sagged(_) => None,
        }
    }

    /// The sagged structured solver (mutable), each cable's unit horizontal, the unit
    /// vertical and the geometry of the loaded pose (None for taut cables): the sagged
    /// mode shapes' inputs.
    #[allow(clippy::type_complexity)]
    pub(super) fn sag_shapes_input(
        &mut self,
    ) -> Option<(
        &mut crate::modal::SagModalSolver,
        Vec<nalgebra::Vector3<f64>>,
        nalgebra::Vector3<f64>,
        &Geometry,
    )> {
        match &mut self.model {
            Model::Taut(_) => None,
            Model::Sagged(s) => {
                let (h, up) = s.shape_frames();
                Some((&mut s.modal, h, up, &self.geometry))
            }
        }
    }

    /// The sagged structured solver as loaded at the last pose (None for taut cables).
    pub(super) fn sag_modal(&self) -> Option<&crate::modal::SagModalSolver> {
        match &self.model {
            Model::Taut(_) => None,
            Model::Sagged(s) => Some(&s.modal),
        }
    }

    /// [`Self::sag_modal`], mutable: a count or a receptance moves the solver's scratch
    /// and warm starts, not the loaded pose.
    pub(super) fn sag_modal_mut(&mut self) -> Option<&mut crate::modal::SagModalSolver> {
        match &mut self.model {
            Model::Taut(_) => None,
            Model::Sagged(s) => Some(&mut s.modal),
        }
    }

    /// The taut structured solver (None when the cables sag).
    pub(super) fn taut_modal(&self) -> Option<&ModalSolver> {
        match &self.model {
            Model::Taut(t) => Some(&t.modal),
            Model::Sagged(_) => None,
        }
    }

    /// End-effector bookkeeping counters.
    pub(super) fn rescan_counts(&self) -> RescanCounts {
        with_model!(&self.model, m => m.solver().rescan_counts())
    }

    /// Info of the last tension solve (sagged: its SQP iterations, the rest default).
    pub(super) fn tension_info(&self) -> TensionInfo {
        with_model!(&self.model, m => m.tension_info())
    }

    /// Each cable's catenary of the last sagged tension solve (None for taut cables).
    pub(super) fn catenaries(&self) -> Option<&[Catenary]> {
        match &self.model {
            Model::Taut(_) => None,
            Model::Sagged(s) => Some(s.catenaries()),
        }
    }
}

/// Cable geometry of `scene` at `pose`: rigid-body attachments rotated by the pose's
/// orientation, or all cables at the centroid. No allocation.
pub(super) fn update_geometry(
    scene: &Scene,
    g: &mut Geometry,
    pose: &Pose,
) -> Result<(), KinematicsError> {
    if scene.rigid {
        let rot = crate::kinematics::rotation_of(&pose.orientation_wxyz);
        g.update_rigid(
            scene.cables.iter().map(|c| &c.anchor_m),
            scene.cables.iter().map(|c| &c.attachment_m),
            &pose.position_m,
            &rot,
        )
    } else {
        g.update(scene.cables.iter().map(|c| &c.anchor_m), &pose.position_m)
    }
}

/// Each cable's upper tension bound of `scene`, N (entries past its cables unused).
pub(super) fn cable_t_max_n(scene: &Scene) -> [f64; MAX_CABLES] {
    let mut t = [scene.t_max_n; MAX_CABLES];
    for (i, v) in t.iter_mut().enumerate().take(scene.n_cables()) {
        *v = scene.cable_t_max_n(i);
    }
    t
}

/// Cable models of `scene` for geometry `g` and tensions into `out` (`frame`: the scene's
/// up frame, [`crate::cable::up_frame`]). No allocation.
pub(super) fn fill_models(
    scene: &Scene,
    frame: &Matrix3<f64>,
    g: &Geometry,
    tensions_n: &[f64],
    out: &mut [CableModel],
) -> Result<(), CableError> {
    let gn = scene.gravity_m_s2.norm();
    for (i, (c, m)) in scene.cables.iter().zip(out.iter_mut()).enumerate() {
        *m = CableModel::build(
            scene.model.element,
            scene.model.elements_per_cable,
            &g.unit[i],
            g.length_m[i],
            tensions_n[i],
            c.ea_n(),
            c.mass_per_length_kg_m,
            c.mass_per_length_kg_m * gn,
            frame,
            scene.model.geometric_stiffness,
        )?;
        if let Some(h) = axial_behind_exit(c, g, i) {
            // Every element model takes the cable behind the exit point (hidden length plus
            // the pulley's wrapped arc); an error here is an error of the scene.
            m.support_on_hidden(scene.model.element, &g.unit[i], &h)?;
        }
    }
    Ok(())
}

/// The cable behind cable `i`'s exit point at the pose of `g`: its axial length (the
/// hidden cable from the pulley entry to the drum, plus the arc wrapped on the pulley at
/// this pose), EA and mass per length (the hidden cable's; the free cable's for a pulley
/// without a hidden cable: the wrapped arc is the same cable, stretching with the same
/// tension); None when there is neither a hidden cable nor a wrapped arc (no pulley, a
/// pulley of radius 0, or a pose that wraps nothing), and None when its axial compliance
/// l/EA is below [`BEHIND_EXIT_COMPLIANCE_FLOOR`] of the free cable's (its effect on the
/// cable's axial stiffness is below that fraction: taken as 0 exactly, so a tiny radius,
/// hidden length or wrap angle gives the answer without it, continuously). The one place
/// every model (taut and sagged, statics and vibration) takes this length from.
pub(in crate::estimator) fn axial_behind_exit(
    c: &crate::scene::Cable,
    g: &Geometry,
    i: usize,
) -> Option<crate::cable::HiddenAxial> {
    let wrap_m = g.wrap_arc_m(i);
    let behind = match c.hidden {
        Some(h) => crate::cable::HiddenAxial {
            length_m: h.length_m + wrap_m,
            ea_n: h.ea_n(),
            mu_kg_m: h.mass_per_length_kg_m,
        },
        None => crate::cable::HiddenAxial {
            length_m: wrap_m,
            ea_n: c.ea_n(),
            mu_kg_m: c.mass_per_length_kg_m,
        },
    };
    let free_compliance = g.length_m[i] / c.ea_n();
    // Also None for a length of 0 (no hidden cable, nothing wrapped).
    (behind.length_m / behind.ea_n >= BEHIND_EXIT_COMPLIANCE_FLOOR * free_compliance)
        .then_some(behind)
}

/// The smallest axial compliance l/EA of the cable behind a cable's exit point (hidden
/// cable plus wrapped arc), as a fraction of the free cable's L/EA, that the models keep
/// (1e-12). Below it the part behind the exit point is taken as 0 exactly: in series with
/// the free cable it changes the cable's axial stiffness by less than this fraction (the
/// eigenvalue solver's own tolerance, `ModalParams::rel_tol`), so every answer is
/// continuous in the hidden length and the pulley radius down to 0 within it. Kept, such a
/// segment is a spring over 10¹² times stiffer than the free cable on a mass 10¹² times
/// lighter, and the supported chain's products (h², h·s, the segment's k/m) overflow f64
/// below about 1e-145 of it (the paper robot's pulleys at a radius of 1e-150 m): the floor is far
/// above that, and far below any pulley or hidden cable a robot has (1e-12 of a 1 m cable
/// is a picometre).
pub const BEHIND_EXIT_COMPLIANCE_FLOOR: f64 = 1e-12;

/// A valid stand-in cable model (a 1 N/m massless spring) for preallocated model buffers.
pub(super) fn placeholder_model() -> CableModel {
    CableModel::build(
        ElementKind::Massless,
        1,
        &Vector3::x(),
        1.0,
        1.0,
        1.0,
        0.0,
        0.0,
        &Matrix3::identity(),
        true,
    )
    .expect("a unit massless spring is a valid model")
}

/// The end-effector of one pose as the modal solvers and the dense assembly take it: a
/// point mass, or a rigid body with its world inertia R I Rᵀ and the tensions' rotational
/// geometric stiffness, and the swivel pulleys' own stiffness term. Fixed size: no
/// allocation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EndEffector {
    /// A rigid body (else a point mass).
    pub rigid: bool,
    /// Mass, kg.
    pub mass_kg: f64,
    /// World-frame inertia about the centroid, kg·m² (rigid body; zero for a point mass).
    pub inertia_kg_m2: Matrix3<f64>,
    /// Rotational geometric stiffness of the tensions, N·m/rad (rigid body, after
    /// [`Self::with_tensions`]; zero otherwise).
    pub k_geo_rot: Matrix3<f64>,
    /// The swivel pulleys' own stiffness term at the end-effector's DOFs (leading 3 × 3 or
    /// 6 × 6 block; N/m, N/rad, N·m/rad; [`Geometry::pulley_stiffness`] of the tensions,
    /// after [`Self::with_tensions`]; zero without pulleys): the exit points move with the
    /// pose. It carries no mass, so D(λ) takes it at every λ.
    pub k_pulley: Matrix6<f64>,
}

impl EndEffector {
    /// The end-effector of `scene` at `pose`, without the tensions' stiffness.
    pub fn of_body(scene: &Scene, pose: &Pose) -> EndEffector {
        let inertia_kg_m2 = if scene.rigid {
            let rot = crate::kinematics::rotation_of(&pose.orientation_wxyz);
            rot * scene.ee_inertia_kg_m2 * rot.transpose()
        } else {
            Matrix3::zeros()
        };
        EndEffector {
            rigid: scene.rigid,
            mass_kg: scene.ee_mass_kg,
            inertia_kg_m2,
            k_geo_rot: Matrix3::zeros(),
            k_pulley: Matrix6::zeros(),
        }
    }

    /// The end-effector of `scene` at `pose` holding cables of geometry `g` (at that pose)
    /// with tensions `tensions_n` (N): a rigid body carries their rotational geometric
    /// stiffness ([`crate::kinematics::rigid_geometric_stiffness`]).
    pub fn with_tensions(
        scene: &Scene,
        pose: &Pose,
        g: &Geometry,
        tensions_n: &[f64],
    ) -> EndEffector {
        let mut ee = Self::of_body(scene, pose);
        if ee.rigid {
            ee.k_geo_rot =
                crate::kinematics::rigid_geometric_stiffness(&g.unit, &g.arm_m, tensions_n);
        }
        if g.has_pulleys() {
            ee.k_pulley = g.pulley_stiffness(tensions_n, ee.dim());
        }
        ee
    }

    /// 3 (point mass) or 6 (rigid body).
    pub fn dim(&self) -> usize {
        if self.rigid {
            6
        } else {
            3
        }
    }

    /// The mass matrix (its leading [`Self::dim`] block), kg and kg·m².
    pub fn mass6(&self) -> Matrix6<f64> {
        let mut m = Matrix6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * self.mass_kg));
        if self.rigid {
            m.fixed_view_mut::<3, 3>(3, 3)
                .copy_from(&self.inertia_kg_m2);
        }
        m
    }

    /// Load `solver` with the cable models `models` attached at `arms_m` (m, world frame
    /// from the centroid; rigid body only). No allocation.
    pub fn load(&self, solver: &mut ModalSolver, models: &[CableModel], arms_m: &[Vector3<f64>]) {
        if self.rigid {
            solver.load_rigid(
                models,
                self.mass_kg,
                &self.inertia_kg_m2,
                arms_m,
                &self.k_geo_rot,
            );
        } else {
            solver.load(models, self.mass_kg);
        }
        if self.k_pulley != Matrix6::zeros() {
            solver.add_ee_stiffness(&self.k_pulley);
        }
    }

    /// The dense K (N/m) and M (kg) of the cable models with this end-effector
    /// ([`modal::assemble`], [`modal::assemble_rigid`]; not for continuous cables).
    pub fn assemble(
        &self,
        models: &[CableModel],
        arms_m: &[Vector3<f64>],
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), ModalError> {
        let (mut k, mut m) = if self.rigid {
            modal::assemble_rigid(
                models,
                self.mass_kg,
                &self.inertia_kg_m2,
                arms_m,
                &self.k_geo_rot,
            )?
        } else {
            modal::assemble(models, self.mass_kg)?
        };
        self.add_pulleys(&mut modal::DensePair(&mut k, &mut m));
        Ok((k, m))
    }

    /// [`Self::assemble`] with each cable's interior nodes in its own frame
    /// ([`modal::CableFrames`]).
    pub fn assemble_in_cable_frames(
        &self,
        models: &[CableModel],
        arms_m: &[Vector3<f64>],
    ) -> Result<modal::CableFrames, ModalError> {
        let rigid = self
            .rigid
            .then_some((&self.inertia_kg_m2, arms_m, &self.k_geo_rot));
        let mut a = modal::assemble_in_cable_frames(models, self.mass_kg, rigid)?;
        self.add_pulleys(&mut a.entries);
        Ok(a)
    }

    /// The pulleys' term at the end-effector's DOFs, the first `dim` of an assembly.
    fn add_pulleys<A: modal::Assembly>(&self, out: &mut A) {
        if self.k_pulley != Matrix6::zeros() {
            let d = self.dim();
            for r in 0..d {
                for c in 0..d {
                    out.add(r, c, self.k_pulley[(r, c)], 0.0);
                }
            }
        }
    }
}
