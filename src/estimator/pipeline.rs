//! The forward model of one pose, shared by the cycle ([`Estimator::update`]) and the
//! inverse T_min query ([`Estimator::t_min_for_f1`]): tension distribution → cable models →
//! modal solver loaded → first root. Each caller owns one [`Pipeline`] (the inverse query
//! its own, so it leaves the cycle's warm state alone). Nothing here allocates after
//! [`Pipeline::new`].
//!
//! [`Estimator::update`]: super::Estimator::update
//! [`Estimator::t_min_for_f1`]: super::Estimator::t_min_for_f1

use super::sagged::{SagPipeline, TensionReport};
use super::EstimatorError;
use crate::cable::{CableError, CableModel};
use crate::kinematics::{Geometry, KinematicsError, Pose};
use crate::modal::{self, ModalParams, ModalSolver, Root};
use crate::scene::{ElementKind, Scene, MAX_CABLES};
use crate::tension::{TensionParams, TensionSolver};
use nalgebra::{Matrix3, Vector3};

/// Every buffer of one forward evaluation, sized once.
#[derive(Debug, Clone)]
pub(super) struct Pipeline {
    /// Cable geometry at the current pose.
    pub(super) geometry: Geometry,
    /// The active-set tension solver (keeps its warm start between calls).
    pub(super) tension: TensionSolver,
    /// The cable models of the last successful load.
    pub(super) models: Vec<CableModel>,
    /// The structured eigen solver, loaded with `models`.
    pub(super) modal: ModalSolver,
    /// The scene's up frame (columns: two horizontal axes, then up), for the cable models.
    frame: Matrix3<f64>,
    /// `modal`'s evaluation counter when it was last loaded.
    loaded_at: u32,
    /// Each cable's upper tension bound, N (the scene's, fixed).
    t_max_n: [f64; MAX_CABLES],
    /// The sagged forward model (`[effects] sag`): used instead of `tension`, `models` and
    /// `modal` when present.
    pub(super) sag: Option<SagPipeline>,
}

impl Pipeline {
    /// Buffers for the cables of `scene` with its up frame (allocates: set-up only).
    pub(super) fn new(
        scene: &Scene,
        frame: Matrix3<f64>,
        tension: TensionParams,
        modal: ModalParams,
    ) -> Pipeline {
        let n = scene.n_cables();
        Pipeline {
            frame,
            t_max_n: cable_t_max_n(scene),
            geometry: Geometry::new(n),
            tension: TensionSolver::new(n, tension),
            models: vec![placeholder_model(); n],
            modal: ModalSolver::new(modal),
            loaded_at: 0,
            sag: scene
                .model
                .sag
                .then(|| SagPipeline::new(scene, tension, modal)),
        }
    }

    /// Cable geometry of `scene` at `pose`.
    pub(super) fn set_pose(&mut self, scene: &Scene, pose: &Pose) -> Result<(), KinematicsError> {
        update_geometry(scene, &mut self.geometry, pose)
    }

    /// At the pose of the last [`Self::set_pose`]: solve the tensions for the per-cable
    /// lower bounds `t_min_n` (N, one per cable) and the scene's upper bounds, show the solver to `on_tensions` (also when the solve failed: an
    /// infeasible solve still has its closest tensions), reject a structure matrix of rank
    /// below `min_rank` (0 accepts any), build the cable models, load the modal solver and
    /// find the first root, warm-started from `warm` (λ, rad²/s²), within the modal parameters'
    /// per-cycle budget of D(λ) evaluations (the modal solver's cycle budget from here on). A `Modal` error comes
    /// only from the root search, after the modal solver was loaded; every other error comes
    /// before it is loaded.
    pub(super) fn first_root(
        &mut self,
        scene: &Scene,
        pose: &Pose,
        t_min_n: &[f64],
        min_rank: u32,
        warm: Option<f64>,
        on_tensions: impl FnOnce(TensionReport<'_>),
    ) -> Result<Root, EstimatorError> {
        let n = scene.n_cables();
        if let Some(sag) = self.sag.as_mut() {
            let t_max = &self.t_max_n[..n];
            let g = &self.geometry;
            return sag.first_root(scene, pose, g, t_min_n, t_max, warm, on_tensions);
        }
        let res = self
            .tension
            .solve_wrench_bounds(&self.geometry, &wrench6(scene), t_min_n, &self.t_max_n[..n])
            .map(|_| ());
        let info = self.tension.info();
        on_tensions(TensionReport {
            iterations: info.iterations,
            warm: info.warm_start_accepted,
            tensions_n: self.tension.tensions_n(),
        });
        res?;
        let rank = self.tension.info().rank;
        if rank < min_rank {
            return Err(EstimatorError::RankDeficient {
                rank,
                expected: min_rank,
            });
        }
        let t = self.tension.tensions_n();
        fill_models(scene, &self.frame, &self.geometry, t, &mut self.models)?;
        load_modal(
            scene,
            &mut self.modal,
            &self.models,
            &self.geometry,
            t,
            pose,
        );
        self.loaded_at = self.modal.evaluations();
        self.modal
            .begin_cycle(self.modal.params().cycle_evaluations);
        Ok(self.modal.first_root(warm)?)
    }

    /// Evaluations of D(λ) since the modal solver was last loaded.
    pub(super) fn evaluations_since_load(&self) -> u32 {
        match &self.sag {
            Some(sag) => sag.evaluations_since_load(),
            None => self.modal.evaluations() - self.loaded_at,
        }
    }

    /// Forget the tension solver's warm start (and the sagged model's).
    pub(super) fn reset_tension_warm_start(&mut self) {
        self.tension.reset_warm_start();
        if let Some(sag) = self.sag.as_mut() {
            sag.reset_warm_start();
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

/// The wrench the cables carry as (force N, moment N·m).
pub(super) fn wrench6(scene: &Scene) -> [f64; 6] {
    let f = scene.wrench_n();
    [f.x, f.y, f.z, 0.0, 0.0, 0.0]
}

/// Cable models of `scene` for geometry `g` and tensions into `out`. No allocation.
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
    }
    Ok(())
}

/// Load `modal` with the models: a point mass, or a rigid body at `pose` (world inertia
/// R I Rᵀ and the tensions' rotational geometric stiffness). No allocation.
fn load_modal(
    scene: &Scene,
    modal: &mut ModalSolver,
    models: &[CableModel],
    g: &Geometry,
    tensions_n: &[f64],
    pose: &Pose,
) {
    if scene.rigid {
        let rot = crate::kinematics::rotation_of(&pose.orientation_wxyz);
        let inertia = rot * scene.ee_inertia_kg_m2 * rot.transpose();
        let kgeo = modal::rigid_geometric_stiffness(&g.unit, &g.arm_m, tensions_n);
        modal.load_rigid(models, scene.ee_mass_kg, &inertia, &g.arm_m, &kgeo);
    } else {
        modal.load(models, scene.ee_mass_kg);
    }
}

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
