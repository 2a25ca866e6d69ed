//! The influence field of a sagging robot along a path: how every cable node moves with
//! the end-effector when the winches set each cable's unstretched length the way the
//! sagged tension distribution asks at every pose.
//!
//! **Model.** At a pose p the sagged statics ([`crate::tension::SagTensionSolver`]) give
//! each cable's end tension and elastic catenary through its chord, hence its unstretched
//! length L0(p); the chain's nodes sit on that catenary at s_j = j L0/N
//! (`forward::sagged`), so in world coordinates
//!
//! ```text
//!     x_ij(p) = a_i + x_i(s_j; p) h_i(p) + z_i(s_j; p) up,
//! ```
//!
//! a_i the anchor, (x, z) the catenary's closed form in the cable's vertical plane. The
//! path's field is r_path = ∂x/∂p (per end-effector DOF: translations, then a rigid body's
//! rotations about the world axes), so along a path p(t) the nodes move with velocity
//! r_path ṗ and acceleration r_path p̈ + ∂²x/∂p²[ṗ, ṗ]. The time response takes the first
//! term; the convective one is left out (a load quadratic in the velocity, which the
//! response's end-effector force does not carry): measured against the exact whole robot
//! it is 1.9e-3 of the peak on `suspended-8` with sag (0.3 m S-curve in 0.3 s) and 8.1e-3
//! on the heavy paper robot (0.29 m; tests/model/sag_path_field.rs). Its share is about
//! the move's length over the cables' (a ~ d/T², ṗ²/L ~ d²/(T² L)), not the speed.
//!
//! It differs from the fixed-length field r = [I; −K_ii⁻¹ K_ie] of the linear model's
//! static condensation (`modal::shapes::influence`) wherever a cable sags: holding L0 while
//! the chord changes changes the sag by many times the end-effector's motion, while along
//! the path the winch pays the cable out or in. On a taut cable both are the linear
//! interpolation along the chord.
//!
//! **Derivative.** By the fourth-order central difference of the equilibrium re-solved at
//! p ± δ e_d and p ± 2δ e_d (each a warm-started sagged tension solve from this pose's
//! answer, the cycle's own state untouched): [x(p−2δ) − 8x(p−δ) + 8x(p+δ) − x(p+2δ)]/(12δ),
//! δ = [`PATH_FIELD_STEP`] × the longest chord (rotations: that step in rad). Its
//! truncation error is O((δ/L)⁴) ≈ 1e-16 and the tension solve's convergence
//! (step 1e-11 of the largest tension) leaves ~1e-9 of the field; measured against the
//! tests' own catenaries (Irvine's closed form from cold solves' lengths, differenced
//! there): 9e-11 (`suspended-8`), 2e-11 (heavy paper robot; tests/model/sag_path_field.rs). Where a cable's bound becomes active or inactive
//! within ±2δ of the pose the field is the average of its two sides. Cost: 4 tension solves
//! per end-effector DOF per basis. Cables over pulleys or with a hidden cable (whose exit
//! point and hidden part move too) are not covered: those robots keep the end-effector's
//! load alone ([`sag_path_field_applies`]).

use super::{Estimator, EstimatorError};
use crate::kinematics::Pose;
use crate::modal::ModeShapes;
use crate::scene::Scene;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};

/// The central difference's step δ relative to the longest chord (m per m; rad for a
/// rigid body's rotations).
pub const PATH_FIELD_STEP: f64 = 1e-4;

/// Whether the path's field covers a sagging `scene`: every cable leaves from a fixed
/// anchor (no pulley, no hidden cable). Otherwise a sagging scene's time response takes
/// the end-effector's load alone.
pub fn sag_path_field_applies(scene: &Scene) -> bool {
    scene
        .cables
        .iter()
        .all(|c| c.pulley.is_none() && c.hidden.is_none())
}

/// `pose` moved by `step` along end-effector DOF `d` (translation, then rotation about the
/// world axes for d ≥ 3).
fn shifted(pose: &Pose, d: usize, step: f64) -> Pose {
    let mut out = *pose;
    if d < 3 {
        out.position_m[d] += step;
    } else {
        let [w, x, y, z] = pose.orientation_wxyz;
        let q = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z));
        let r = UnitQuaternion::from_scaled_axis(Vector3::ith(d - 3, step)) * q;
        out.orientation_wxyz = [r.w, r.i, r.j, r.k];
    }
    out
}

impl Estimator {
    /// The path's field of the pose of the last successful cycle (module docs), in the node
    /// lists of `static_field` (the sagged shapes' fixed-length field of the same pose, whose
    /// end-effector entries it keeps); None for taut cables or where
    /// [`sag_path_field_applies`] is false. Allocates (offline).
    pub(super) fn sag_path_field(
        &self,
        static_field: &ModeShapes,
    ) -> Result<Option<ModeShapes>, EstimatorError> {
        if !(self.scene.model.sag && sag_path_field_applies(&self.scene)) {
            return Ok(None);
        }
        let n = self.scene.n_cables();
        let longest = self
            .cycle
            .geometry
            .length_m
            .iter()
            .fold(0.0f64, |a, &l| a.max(l));
        let delta = PATH_FIELD_STEP * longest.max(1.0);
        let pose = self.loaded_pose;
        let t_min = &self.t_min_n[..n];
        let mut out = static_field.clone();
        for (d, mode) in out.modes.iter_mut().enumerate() {
            let step = if d < 3 { delta } else { PATH_FIELD_STEP };
            let mut column: Option<Vec<Vec<Vector3<f64>>>> = None;
            for (k, w) in [(-2.0, 1.0), (-1.0, -8.0), (1.0, 8.0), (2.0, -1.0)] {
                let at = shifted(&pose, d, k * step);
                let Some(nodes) = self.cycle.sag_nodes_at(&self.scene, &at, t_min)? else {
                    return Ok(None);
                };
                let scale = w / (12.0 * step);
                match &mut column {
                    None => {
                        column = Some(
                            nodes
                                .iter()
                                .map(|c| c.iter().map(|x| x * scale).collect())
                                .collect(),
                        )
                    }
                    Some(col) => {
                        for (ci, c) in col.iter_mut().zip(&nodes) {
                            for (y, x) in ci.iter_mut().zip(c) {
                                *y += x * scale;
                            }
                        }
                    }
                }
            }
            let column = column.unwrap_or_default();
            if column.len() != mode.cables.len()
                || column
                    .iter()
                    .zip(&mode.cables)
                    .any(|(a, b)| a.len() != b.len())
            {
                return Ok(None);
            }
            mode.cables = column;
        }
        Ok(Some(out))
    }
}
