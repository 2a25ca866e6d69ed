//! The offline reference of the same model: Clarabel for the tensions, dense assembly and
//! a dense generalized eigensolver for every frequency; and the structured solver run once.
//! Allocates: for tests, sweeps and the CLI, never inside the cycle.

use super::pipeline::{fill_models, placeholder_model, update_geometry, wrench6};
use super::{resolve_auto, AnalysisError, BuildError, Estimate, Estimator, Tmin};
use crate::cable::{up_frame, CableError, CableModel};
use crate::kinematics::{Geometry, Pose};
use crate::modal;
use crate::scene::{ElementKind, Scene};
use nalgebra::{Matrix3, Matrix6, Vector3};

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

/// Everything the dense reference computes for one pose.
#[derive(Debug, Clone)]
pub struct ReferenceAnalysis {
    /// Tensions from Clarabel, N.
    pub tensions_n: Vec<f64>,
    /// Every mode (dense).
    pub modes: modal::DenseModes,
    /// Degrees of freedom of the assembled model.
    pub dof: usize,
    /// Static end-effector stiffness, translational block, N/m.
    pub stiffness_n_m: Matrix3<f64>,
    /// Static end-effector stiffness, 6 × 6 for a rigid body (N/m, N/rad, N·m/m, N·m/rad
    /// blocks, as `Estimate::stiffness6`); the translational block and zeros elsewhere for a
    /// point mass.
    pub stiffness6: Matrix6<f64>,
}

/// The offline reference: Clarabel tensions, dense K and M, dense eigen-solve (with
/// participations when `vectors`). For `continuous` scenes use the structured solver.
pub fn reference_analysis(
    scene: &Scene,
    position_m: &Vector3<f64>,
    t_min: Tmin<'_>,
    vectors: bool,
) -> Result<ReferenceAnalysis, AnalysisError> {
    let pose = Pose {
        position_m: *position_m,
        orientation_wxyz: scene.ee_orientation_wxyz,
    };
    reference_analysis_at(scene, &pose, t_min, vectors)
}

/// [`reference_analysis`] at a full pose (orientation matters for a rigid end-effector).
pub fn reference_analysis_at(
    scene: &Scene,
    pose: &Pose,
    t_min: Tmin<'_>,
    vectors: bool,
) -> Result<ReferenceAnalysis, AnalysisError> {
    if scene.model.element == ElementKind::Auto {
        let resolved = resolve_auto(scene)
            .map(|(s, _)| s)
            .map_err(|e| AnalysisError::Auto(e.to_string()))?;
        return reference_analysis_at(&resolved, pose, t_min, vectors);
    }
    let mut g = Geometry::new(scene.n_cables());
    let rot = crate::kinematics::rotation_of(&pose.orientation_wxyz);
    update_geometry(scene, &mut g, pose)?;
    // The lower bounds `t_min` names; each cable's own T_max from the scene.
    let n = scene.n_cables();
    let t_min_n = t_min.per_cable(scene);
    let t_max_n = super::pipeline::cable_t_max_n(scene);
    let t = crate::tension::clarabel_reference_bounds(
        &g,
        &wrench6(scene),
        &t_min_n[..n],
        &t_max_n[..n],
    )?;
    let models = build_models(scene, &g, &t)?;
    let mut ee = Matrix6::zeros();
    ee.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(Matrix3::identity() * scene.ee_mass_kg));
    let (k, m) = if scene.rigid {
        let inertia = rot * scene.ee_inertia_kg_m2 * rot.transpose();
        let kgeo = modal::rigid_geometric_stiffness(&g.unit, &g.arm_m, &t);
        ee.fixed_view_mut::<3, 3>(3, 3).copy_from(&inertia);
        modal::assemble_rigid(&models, scene.ee_mass_kg, &inertia, &g.arm_m, &kgeo)?
    } else {
        modal::assemble(&models, scene.ee_mass_kg)?
    };
    let dof = k.nrows();
    let dim = if scene.rigid { 6 } else { 3 };
    let modes = modal::dense_modes_ee(&k, &m, &ee, dim, vectors)?;
    let stiffness6 = if scene.rigid {
        modal::condense_static(&k, dim)
    } else {
        let mut k6 = Matrix6::zeros();
        k6.fixed_view_mut::<3, 3>(0, 0).copy_from(
            &models
                .iter()
                .fold(Matrix3::zeros(), |a, cm| a + cm.static_stiffness),
        );
        k6
    };
    let stiffness_n_m = stiffness6.fixed_view::<3, 3>(0, 0).into_owned();
    Ok(ReferenceAnalysis {
        tensions_n: t,
        modes,
        dof,
        stiffness_n_m,
        stiffness6,
    })
}

/// The structured solver run once (allocating; for offline use): tensions from the
/// active-set solver, then f1 and the end-effector mode.
pub fn structured_analysis(scene: &Scene, position_m: &Vector3<f64>, t_min: Tmin<'_>) -> Estimate {
    match Estimator::new(scene) {
        Ok(mut est) => *est.update(
            &Pose {
                position_m: *position_m,
                orientation_wxyz: scene.ee_orientation_wxyz,
            },
            t_min,
        ),
        Err(BuildError::DefaultPose { reason, .. }) => {
            let mut e = Estimate::empty(scene.n_cables());
            e.status = reason.status();
            e.error = Some(*reason);
            e
        }
    }
}
