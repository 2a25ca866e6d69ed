//! The offline reference of the same model: Clarabel for the tensions, dense assembly and
//! a dense generalized eigensolver for every frequency; and the structured solver run once.
//! Allocates: for tests, sweeps and the CLI, never inside the cycle.

use super::{BuildError, Estimate, Estimator, PoseModel, ReferenceError, Status, Tmin};
use crate::kinematics::Pose;
use crate::modal;
use crate::scene::Scene;
use nalgebra::{Matrix3, Matrix6, Vector3};

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
) -> Result<ReferenceAnalysis, ReferenceError> {
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
) -> Result<ReferenceAnalysis, ReferenceError> {
    let pm = PoseModel::at(scene, pose, t_min)?;
    let (k, m) = pm.dense()?;
    let dof = k.nrows();
    let dim = pm.dim();
    let modes = modal::dense_modes_ee(&k, &m, &pm.ee_mass(), dim, vectors)?;
    let stiffness6 = if pm.end_effector.rigid {
        modal::condense_static(&k, dim)
    } else {
        let mut k6 = Matrix6::zeros();
        k6.fixed_view_mut::<3, 3>(0, 0).copy_from(
            &pm.models
                .iter()
                .fold(Matrix3::zeros(), |a, cm| a + cm.static_stiffness),
        );
        k6
    };
    // The pulleys' own term (zero without pulleys): a rigid body's condensed dense K holds
    // it already, a point mass's sum of the models does not.
    let stiffness6 = if pm.geometry.has_pulleys() && !pm.end_effector.rigid {
        stiffness6 + pm.end_effector.k_pulley
    } else {
        stiffness6
    };
    let stiffness_n_m = stiffness6.fixed_view::<3, 3>(0, 0).into_owned();
    Ok(ReferenceAnalysis {
        tensions_n: pm.tensions_n,
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
        // The default parameters are within their bounds (params.rs tests it); a model over
        // the memory budget is refused input.
        Err(BuildError::Params(_) | BuildError::Memory(_)) => {
            let mut e = Estimate::empty(scene.n_cables());
            e.status = Status::InvalidInput;
            e
        }
    }
}
