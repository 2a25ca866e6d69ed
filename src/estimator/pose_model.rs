//! [`PoseModel`]: the model of one pose for offline use — geometry, the tensions of the
//! Clarabel reference, the cable models and the end-effector — built from the same pieces
//! as the cycle's forward model ([`super::forward`]). The dense reference
//! ([`super::reference_analysis`]) and `cablevib modes` read it. Allocates.

use super::forward::{fill_models, placeholder_model, update_geometry, EndEffector};
use super::{resolve_auto, ReferenceError, Tmin};
use crate::cable::{up_frame, CableError, CableModel};
use crate::kinematics::{Geometry, Pose};
use crate::modal::{self, ModalSolver};
use crate::scene::{ElementKind, Scene};
use nalgebra::{DMatrix, Matrix6};

/// Build the cable models of a scene for given geometry and tensions (allocates a Vec).
pub fn build_models(
    scene: &Scene,
    geometry: &Geometry,
    tensions_n: &[f64],
) -> Result<Vec<CableModel>, CableError> {
    let frame = up_frame(&scene.gravity_m_s2);
    let mut out = vec![placeholder_model(); scene.n_cables()];
    fill_models(scene, &frame, geometry, tensions_n, &mut out)?;
    Ok(out)
}

/// One pose's model: geometry, tensions (Clarabel reference, N), cable models and the
/// end-effector (mass, world inertia, rotational geometric stiffness of the tensions).
#[derive(Debug, Clone)]
pub struct PoseModel {
    /// The scene (element resolved when it was `auto`).
    pub scene: Scene,
    /// Cable geometry at the pose.
    pub geometry: Geometry,
    /// Tensions, N.
    pub tensions_n: Vec<f64>,
    /// The cable models.
    pub models: Vec<CableModel>,
    /// The end-effector at the pose, holding those tensions.
    pub end_effector: EndEffector,
}

impl PoseModel {
    /// The model of `scene` at its own pose (`ee_position_m`, `ee_orientation_wxyz`) and
    /// each cable's own lower bound (`Tmin::Scene`).
    pub fn new(scene: &Scene) -> Result<PoseModel, ReferenceError> {
        let pose = Pose {
            position_m: scene.ee_position_m,
            orientation_wxyz: scene.ee_orientation_wxyz,
        };
        Self::at(scene, &pose, Tmin::Scene)
    }

    /// The model of `scene` at `pose` with the lower bounds `t_min` (each cable's upper
    /// bound the scene's), the tensions of the Clarabel reference.
    pub fn at(scene: &Scene, pose: &Pose, t_min: Tmin<'_>) -> Result<PoseModel, ReferenceError> {
        let scene = if scene.model.element == ElementKind::Auto {
            resolve_auto(scene)
                .map_err(|e| ReferenceError::Auto(e.to_string()))?
                .0
        } else {
            scene.clone()
        };
        let n = scene.n_cables();
        let mut geometry = Geometry::for_scene(&scene);
        update_geometry(&scene, &mut geometry, pose)?;
        let t_min_n = t_min.per_cable(&scene);
        let t_max_n = super::forward::cable_t_max_n(&scene);
        let tensions_n = crate::tension::clarabel_reference_bounds(
            &geometry,
            &scene.wrench6_n(),
            &t_min_n[..n],
            &t_max_n[..n],
        )?;
        let models = build_models(&scene, &geometry, &tensions_n)?;
        let end_effector = EndEffector::with_tensions(&scene, pose, &geometry, &tensions_n);
        Ok(PoseModel {
            scene,
            geometry,
            tensions_n,
            models,
            end_effector,
        })
    }

    /// 3 (point mass) or 6 (rigid body).
    pub fn dim(&self) -> usize {
        self.end_effector.dim()
    }

    /// Load `solver` with this pose.
    pub fn load(&self, solver: &mut ModalSolver) {
        self.end_effector
            .load(solver, &self.models, &self.geometry.arm_m);
    }

    /// The end-effector's own mass matrix (its leading `dim` block), kg and kg·m².
    pub fn ee_mass(&self) -> Matrix6<f64> {
        self.end_effector.mass6()
    }

    /// The dense K and M (not for continuous cables).
    pub fn dense(&self) -> Result<(DMatrix<f64>, DMatrix<f64>), modal::ModalError> {
        self.end_effector
            .assemble(&self.models, &self.geometry.arm_m)
    }
}
