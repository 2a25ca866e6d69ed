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
//! r_path ṗ and acceleration r_path p̈ + ∂²x/∂p²[ṗ, ṗ]. Both terms load the time response:
//! the first through the load shapes of the end-effector force −M_ee p̈, the second
//! (convective, quadratic in the velocity) through the six second-derivative fields
//! C_de = ∂²x/∂p_d∂p_e of the translations ([`PathFields::second`],
//! [`SECOND_FIELD_PAIRS`], [`convective_input`]; the modal `quasi_static` module). Measured
//! against the exact whole robot, the convective term is 1.9e-3 of the peak on
//! `suspended-8` with sag (0.3 m S-curve in 0.3 s) and 8.1e-3 on the heavy paper robot
//! (0.29 m); with it the response is within 1.1e-8 and 2.9e-7 of the reference
//! (tests/model/sag_path_field.rs). Its share is about the move's length over the cables'
//! (a ~ d/T², ṗ²/L ~ d²/(T² L)), not the speed.
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
//! there): 9e-11 (`suspended-8`), 2e-11 (heavy paper robot; tests/model/sag_path_field.rs).
//! The second derivatives by the fourth-order second difference [−x(p−2h) + 16x(p−h) −
//! 30x(p) + 16x(p+h) − x(p+2h)]/(12h²) along e_d and along (e_d + e_e)/√2 (whose value is
//! (C_dd + 2C_de + C_ee)/2), h = [`PATH_FIELD_SECOND_STEP`] × the longest chord: the solves'
//! convergence enters divided by h², so the larger step (truncation O((h/L)⁴) ≈ 1e-11);
//! measured against the tests' own second differences: 3.8e-6 (`suspended-8`), 7.7e-8
//! (heavy paper robot). Where a cable's bound becomes active or inactive within the
//! stencil the first field is the average of its two sides, and the second holds the
//! kink's jump in slope over the step (a load local to such poses). Cost: 4 tension solves
//! per end-effector DOF, 25 for the second derivatives, per basis. Cables over pulleys or
//! with a hidden cable (whose exit point and hidden part move too) are not covered: those
//! robots keep the end-effector's load alone ([`sag_path_field_applies`]).

use super::{Estimator, EstimatorError};
use crate::kinematics::Pose;
use crate::modal::ModeShapes;
use crate::scene::Scene;
use nalgebra::{Quaternion, UnitQuaternion, Vector3, Vector6};

/// The central difference's step δ relative to the longest chord (m per m; rad for a
/// rigid body's rotations).
pub const PATH_FIELD_STEP: f64 = 1e-4;

/// The second difference's step h relative to the longest chord (m per m): larger than
/// [`PATH_FIELD_STEP`], since the solves' convergence enters divided by h² (module docs).
pub const PATH_FIELD_SECOND_STEP: f64 = 2e-3;

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

/// The six second-derivative fields' order (the convective input's,
/// [`convective_input`]): xx, yy, zz, xy, xz, yz.
pub const SECOND_FIELD_PAIRS: [(usize, usize); 6] =
    [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// The convective input of a path's velocity `v` (m/s) in [`SECOND_FIELD_PAIRS`]' order,
/// m²/s²: [v_x², v_y², v_z², 2v_xv_y, 2v_xv_z, 2v_yv_z], so that ∂²x/∂p²[v, v] =
/// Σ_i C_i w_i with C_i the second field's entries.
pub fn convective_input(v: &Vector3<f64>) -> [f64; 6] {
    [
        v.x * v.x,
        v.y * v.y,
        v.z * v.z,
        2.0 * v.x * v.y,
        2.0 * v.x * v.z,
        2.0 * v.y * v.z,
    ]
}

/// Every cable's node list.
type Nodes = Vec<Vec<Vector3<f64>>>;

/// The fields of `Estimator::sag_path_fields`.
#[derive(Debug, Clone, PartialEq)]
pub struct PathFields {
    /// r_path = ∂x/∂p, one entry of `modes` per end-effector DOF.
    pub first: ModeShapes,
    /// ∂²x/∂p_d∂p_e per pair of [`SECOND_FIELD_PAIRS`] (six entries of `modes`, every node
    /// in 1/m; the end-effector's entries zero: it follows the path).
    pub second: ModeShapes,
}

impl Estimator {
    /// Σ_k w_k x(poses_k) over the re-solved equilibria (module docs), or None where a
    /// pose has no sagged nodes or node lists differ from `like`'s.
    fn node_combination(
        &self,
        poses: &[(Pose, f64)],
        like: &[Vec<Vector3<f64>>],
    ) -> Result<Option<Nodes>, EstimatorError> {
        let n = self.scene.n_cables();
        let t_min = &self.t_min_n[..n];
        let mut out: Nodes = like
            .iter()
            .map(|c| vec![Vector3::zeros(); c.len()])
            .collect();
        for (at, w) in poses {
            let Some(nodes) = self.cycle.sag_nodes_at(&self.scene, at, t_min)? else {
                return Ok(None);
            };
            if nodes.len() != out.len() || nodes.iter().zip(&out).any(|(a, b)| a.len() != b.len()) {
                return Ok(None);
            }
            for (ci, c) in out.iter_mut().zip(&nodes) {
                for (y, x) in ci.iter_mut().zip(c) {
                    *y += x * *w;
                }
            }
        }
        Ok(Some(out))
    }

    /// The path's field and its second derivative at the pose of the last successful cycle
    /// (module docs), in the node lists of `static_field` (the sagged shapes' fixed-length
    /// field of the same pose, whose end-effector entries the first field keeps); None for
    /// taut cables or where [`sag_path_field_applies`] is false. Allocates (offline).
    pub(super) fn sag_path_fields(
        &self,
        static_field: &ModeShapes,
    ) -> Result<Option<PathFields>, EstimatorError> {
        if !(self.scene.model.sag && sag_path_field_applies(&self.scene)) {
            return Ok(None);
        }
        let longest = self
            .cycle
            .geometry
            .length_m
            .iter()
            .fold(0.0f64, |a, &l| a.max(l));
        let delta = PATH_FIELD_STEP * longest.max(1.0);
        let pose = self.loaded_pose;
        let Some(like) = static_field.modes.first().map(|m| m.cables.clone()) else {
            return Ok(None);
        };
        let mut first = static_field.clone();
        for (d, mode) in first.modes.iter_mut().enumerate() {
            let step = if d < 3 { delta } else { PATH_FIELD_STEP };
            let poses = FIRST.map(|(k, w)| (shifted(&pose, d, k * step), w / (12.0 * step)));
            let Some(column) = self.node_combination(&poses, &like)? else {
                return Ok(None);
            };
            mode.cables = column;
        }
        // The second derivatives: along e_d (d = e) and along (e_d + e_e)/√2, whose
        // second derivative is (C_dd + 2 C_de + C_ee)/2 (polarisation).
        let mut second = static_field.clone();
        let template = second.modes[0].clone();
        second.modes = vec![template; SECOND_FIELD_PAIRS.len()];
        let h = PATH_FIELD_SECOND_STEP * longest.max(1.0);
        let Some(center) = self.node_combination(&[(pose, 1.0)], &like)? else {
            return Ok(None);
        };
        let mut along = Vec::with_capacity(SECOND_FIELD_PAIRS.len());
        for &(d, e) in &SECOND_FIELD_PAIRS {
            let mut u = Vector3::zeros();
            u[d] += 1.0;
            u[e] += 1.0;
            let u = u.normalize();
            let poses = SECOND.map(|(k, w)| {
                let mut at = pose;
                at.position_m += u * (k * h);
                (at, w / (12.0 * h * h))
            });
            let Some(mut c) = self.node_combination(&poses, &like)? else {
                return Ok(None);
            };
            let w0 = SECOND_CENTER / (12.0 * h * h);
            for (ci, cc) in c.iter_mut().zip(&center) {
                for (y, x) in ci.iter_mut().zip(cc) {
                    *y += x * w0;
                }
            }
            along.push(c);
        }
        for (i, &(d, e)) in SECOND_FIELD_PAIRS.iter().enumerate() {
            let mode = &mut second.modes[i];
            mode.ee = Vector6::zeros();
            mode.cables = along[i].clone();
            if d != e {
                for (ci, cable) in mode.cables.iter_mut().enumerate() {
                    for (j, x) in cable.iter_mut().enumerate() {
                        *x -= (along[d][ci][j] + along[e][ci][j]) * 0.5;
                    }
                }
            }
        }
        Ok(Some(PathFields { first, second }))
    }
}

/// The first derivative's stencil (module docs): offsets in steps, weights × 12 step.
const FIRST: [(f64, f64); 4] = [(-2.0, 1.0), (-1.0, -8.0), (1.0, 8.0), (2.0, -1.0)];

/// The second derivative's stencil off the pose: offsets in steps, weights × 12 step².
const SECOND: [(f64, f64); 4] = [(-2.0, -1.0), (-1.0, 16.0), (1.0, 16.0), (2.0, -1.0)];

/// The second derivative's weight of the pose itself (× 12 step²).
const SECOND_CENTER: f64 = -30.0;
