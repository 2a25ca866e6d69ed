//! The taut forward model: straight chords, the active-set tension distribution, the
//! scene's element on each chord, the structured solver of `modal`.

use super::{fill_models, placeholder_model, EndEffector, ForwardParams, TensionReport};
use crate::cable::{up_frame, CableModel};
use crate::estimator::EstimatorError;
use crate::kinematics::{Geometry, Pose};
use crate::modal::{ModalError, ModalSolver, Root};
use crate::scene::Scene;
use crate::tension::TensionSolver;
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

    /// See [`super::Forward::first_root`]; `g` the geometry at `pose`, `t_max_n` the upper
    /// bounds (N).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn first_root(
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

    /// Evaluations of D(λ) since the modal solver was last loaded.
    pub(super) fn evaluations_since_load(&self) -> u32 {
        self.modal.evaluations() - self.loaded_at
    }

    /// The static end-effector stiffness of the loaded models: the closed form for a rigid
    /// body (no evaluation of D(λ) out of the cycle's budget), the models' sum for a point
    /// mass (the translational block, zeros elsewhere).
    pub(super) fn static_stiffness(&self, scene: &Scene) -> Matrix6<f64> {
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
            k6
        }
    }

    /// The dense reference's K (N/m) and M (kg) of exactly the loaded models and
    /// end-effector (`g`: the geometry they were loaded at).
    pub(super) fn dense_matrices(
        &self,
        scene: &Scene,
        g: &Geometry,
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), ModalError> {
        // The loaded constant stiffness (geometric and pulleys' terms) as it is.
        let (m6, k6) = self.modal.ee_matrices();
        let ee = EndEffector {
            rigid: scene.rigid,
            mass_kg: scene.ee_mass_kg,
            inertia_kg_m2: m6.fixed_view::<3, 3>(3, 3).into_owned(),
            k_geo_rot: Matrix3::zeros(),
            k_pulley: k6,
        };
        ee.assemble(&self.models, &g.arm_m)
    }
}
