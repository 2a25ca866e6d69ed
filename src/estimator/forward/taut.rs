//! The taut forward model: straight chords, the active-set tension distribution, the
//! scene's element on each chord, the structured solver of `modal`.

use super::{fill_models, placeholder_model, CableSide, EndEffector, ForwardParams, TensionReport};
use crate::cable::{up_frame, CableModel};
use crate::estimator::EstimatorError;
use crate::kinematics::{Geometry, Pose};
use crate::modal::{ModalError, ModalSolver, Root, TautChains};
use crate::scene::Scene;
use crate::tension::{TensionInfo, TensionSolver};
use nalgebra::{DMatrix, Matrix3, Matrix6};

/// Every buffer of the taut forward model, sized once.
#[derive(Debug, Clone)]
pub(in crate::estimator) struct TautModel {
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
}

impl TautModel {
    /// Buffers for the cables of `scene` (allocates: set-up only).
    pub(super) fn new(scene: &Scene, params: &ForwardParams) -> TautModel {
        let n = scene.n_cables();
        TautModel {
            frame: up_frame(&scene.gravity_m_s2),
            tension: TensionSolver::new(n, params.tension),
            models: vec![placeholder_model(); n],
            modal: ModalSolver::new(params.modal),
            loaded_at: 0,
        }
    }

    /// The end-effector of the dense assembly: the loaded constant stiffness (geometric and
    /// pulleys' terms) as it is.
    fn end_effector(&self, scene: &Scene) -> EndEffector {
        let (m6, k6) = self.modal.ee_matrices();
        EndEffector {
            rigid: scene.rigid,
            mass_kg: scene.ee_mass_kg,
            inertia_kg_m2: m6.fixed_view::<3, 3>(3, 3).into_owned(),
            k_geo_rot: Matrix3::zeros(),
            k_pulley: k6,
        }
    }

    /// K and M as an assembly's entries, each cable's interior nodes in its own frame
    /// ([`crate::modal::CableFrames`]).
    pub(super) fn assemble_in_cable_frames(
        &self,
        scene: &Scene,
        g: &Geometry,
    ) -> Result<crate::modal::CableFrames, ModalError> {
        self.end_effector(scene)
            .assemble_in_cable_frames(&self.models, &g.arm_m)
    }
}

impl CableSide for TautModel {
    type Problem = TautChains;

    fn solver(&self) -> &ModalSolver {
        &self.modal
    }

    fn solver_mut(&mut self) -> &mut ModalSolver {
        &mut self.modal
    }

    fn loaded_at(&self) -> u32 {
        self.loaded_at
    }

    fn reset_tensions(&mut self) {
        self.tension.reset_warm_start();
    }

    /// The tensions' warm start only: the taut first root and tracker start from the next
    /// pose's prediction.
    fn reset(&mut self) {
        self.tension.reset_warm_start();
    }

    fn tension_info(&self) -> TensionInfo {
        self.tension.info()
    }

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
    ) -> Result<Root, EstimatorError> {
        let res = self
            .tension
            .solve_wrench_bounds(g, &scene.wrench6_n(), t_min_n, t_max_n)
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
        fill_models(scene, &self.frame, g, t, &mut self.models)?;
        EndEffector::with_tensions(scene, pose, g, t).load(&mut self.modal, &self.models, &g.arm_m);
        self.loaded_at = self.modal.evaluations();
        self.modal
            .begin_cycle(self.modal.params().cycle_evaluations);
        Ok(self.modal.first_root(warm)?)
    }

    /// The static end-effector stiffness of the loaded models: the closed form for a rigid
    /// body (no evaluation of D(λ) out of the cycle's budget), the models' sum for a point
    /// mass (the translational block, zeros elsewhere) plus the swivel pulleys' term at
    /// the tensions (a rigid body's D(0) holds it already).
    fn static_stiffness(&self, scene: &Scene, g: &Geometry) -> Matrix6<f64> {
        if scene.rigid {
            self.modal
                .static_stiffness()
                .unwrap_or(Matrix6::repeat(f64::NAN))
        } else {
            let mut k = Matrix3::zeros();
            for cm in &self.models {
                k += cm.static_stiffness;
            }
            let mut k6 = Matrix6::zeros();
            k6.fixed_view_mut::<3, 3>(0, 0).copy_from(&k);
            if g.has_pulleys() {
                k6 + g.pulley_stiffness(self.tension.tensions_n(), 3)
            } else {
                k6
            }
        }
    }

    /// The dense reference's K (N/m) and M (kg) of exactly the loaded models and
    /// end-effector (`g`: the geometry they were loaded at).
    fn dense_matrices(
        &self,
        scene: &Scene,
        g: &Geometry,
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), ModalError> {
        self.end_effector(scene).assemble(&self.models, &g.arm_m)
    }
}
