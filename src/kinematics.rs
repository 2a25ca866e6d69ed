//! Kinematics of a CDPR (paper Eqs. 1-5): cable lengths, unit vectors and the structure
//! matrix at one pose.
//!
//! For cable i with anchor a_i, end-effector position p and attachment arm r_i (the
//! attachment point relative to the centroid, world frame), the cable vector is
//! l_i = p + r_i − a_i (anchor → attachment point), its length L_i = ‖l_i‖ (m) and its unit
//! vector s_i = l_i / L_i. The structure matrix A = Jᵀ has columns s_i (force rows) and
//! r_i × s_i (moment rows), and static equilibrium reads A T = w, with w the wrench the
//! cables carry (N, N·m): m·g and no moment when they carry the end-effector's weight. (A
//! cable pulls the end-effector towards its anchor, i.e. with force −T_i s_i; equilibrium
//! −Σ T_i s_i + m g = 0 gives Σ T_i s_i = m g.)
//!
//! A point-mass end-effector has every r_i = 0, so its moment rows vanish and A is 3 × n. A
//! rigid one (scene effect `rotation`) has r_i = R b_i, with b_i in its body frame and R its
//! orientation ([`Geometry::update_rigid`]).
//!
//! A cable with a swivel pulley at its anchor ([`crate::scene::Pulley`]) starts its free
//! length at the pulley's exit point instead ([`pulley`]): s_i, L_i and the fixed end of the
//! free cable ([`Geometry::exit_m`]) are the exit point's, and the wrapped arc
//! ([`Geometry::wrap_arc_m`]) is the cable between the anchor and the exit point. A
//! geometry made with [`Geometry::for_scene`] knows the scene's pulleys; one made with
//! [`Geometry::new`] has none.

pub mod pulley;
pub mod rigid;

use crate::scene::Pulley;
use nalgebra::{Matrix3, Matrix6, Vector3};
pub use pulley::{pulley_exit, PulleyExit};
pub use rigid::{attach_map, rigid_geometric_stiffness};

/// End-effector pose: position (m) and orientation (unit quaternion w, x, y, z).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Position of the centroid, m.
    pub position_m: Vector3<f64>,
    /// Orientation as a unit quaternion [w, x, y, z] (ignored by point-mass scenes, but validated).
    pub orientation_wxyz: [f64; 4],
}

impl Pose {
    /// A pose at `position_m` with identity orientation.
    pub fn at(position_m: Vector3<f64>) -> Pose {
        Pose {
            position_m,
            orientation_wxyz: [1.0, 0.0, 0.0, 0.0],
        }
    }
    /// A pose at `position_m` with the orientation of scene `s` (its `ee_orientation_wxyz`:
    /// the scene file's, or a caller's override).
    pub fn in_scene(s: &crate::scene::Scene, position_m: Vector3<f64>) -> Pose {
        Pose {
            position_m,
            // A point mass has no orientation: the identity, whatever the scene file says.
            orientation_wxyz: if s.rigid {
                s.ee_orientation_wxyz
            } else {
                [1.0, 0.0, 0.0, 0.0]
            },
        }
    }
    /// Every component finite.
    pub fn is_finite(&self) -> bool {
        self.position_m.iter().all(|x| x.is_finite())
            && self.orientation_wxyz.iter().all(|x| x.is_finite())
    }
    /// The quaternion's norm is 1 within `tol`.
    pub fn has_unit_quaternion(&self, tol: f64) -> bool {
        let n2: f64 = self.orientation_wxyz.iter().map(|q| q * q).sum();
        (n2.sqrt() - 1.0).abs() <= tol
    }
    /// The orientation is the identity (no rotation) within [`QUATERNION_INPUT_TOL`]: the
    /// quaternion's vector part is at most that fraction of its norm (a rotation of at most
    /// 2·asin(1e-3) ≈ 0.11°; q and −q alike). The one rule of what "an orientation" is on a
    /// point-mass end-effector, which has none: anything else is refused there.
    pub fn has_identity_orientation(&self) -> bool {
        let [w, x, y, z] = self.orientation_wxyz;
        let v = (x * x + y * y + z * z).sqrt();
        v <= QUATERNION_INPUT_TOL * (w * w + v * v).sqrt()
    }
}

/// Errors of the kinematics.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum KinematicsError {
    /// A cable is shorter than the minimum length (the pose is at an anchor).
    #[error("cable {cable} is {length_m:.3e} m long (< {min_m:.1e} m): the end-effector is at its anchor")]
    CableTooShort {
        /// Cable index.
        cable: usize,
        /// Its length, m.
        length_m: f64,
        /// The smallest accepted length, m.
        min_m: f64,
    },
    /// A non-finite position.
    #[error("non-finite position")]
    NonFinite,
    /// A cable's attachment point is on its pulley's swivel axis: the pulley plane is not
    /// defined.
    #[error("cable {cable}: the attachment point is {distance_m:.3e} m from its pulley's swivel axis (< {min_m:.1e} m): the pulley plane is not defined")]
    AlongSwivelAxis {
        /// Cable index.
        cable: usize,
        /// The attachment point's distance from the axis, m.
        distance_m: f64,
        /// The smallest accepted distance, m.
        min_m: f64,
    },
    /// A cable's attachment point is inside its pulley's circle (or on it): no tangent.
    #[error("cable {cable}: the attachment point is inside its pulley's circle (free length {free_length_m:.3e} m < {min_m:.1e} m)")]
    InsidePulley {
        /// Cable index.
        cable: usize,
        /// The free length from the tangent point, m (0 inside the circle).
        free_length_m: f64,
        /// The smallest accepted free length, m.
        min_m: f64,
    },
}

/// Cable geometry at one pose, preallocated for a fixed number of cables.
#[derive(Debug, Clone)]
pub struct Geometry {
    /// Unit vectors s_i (anchor → attachment point).
    pub unit: Vec<Vector3<f64>>,
    /// Cable chord lengths L_i, m.
    pub length_m: Vec<f64>,
    /// Attachment points relative to the centroid in the world frame, r_i = R b_i, m
    /// (zero for a point mass). The structure matrix's moment rows are r_i × s_i.
    pub arm_m: Vec<Vector3<f64>>,
    /// The fixed end of each free cable, m: its anchor, or its pulley's exit point.
    pub exit_m: Vec<Vector3<f64>>,
    /// Each cable's pulley (None: the cable leaves from its anchor).
    pulleys: Vec<Option<Pulley>>,
    /// Each cable's pulley at the pose (meaningful where `pulleys` has one).
    exits: Vec<Option<PulleyExit>>,
}

/// Rotation matrix of a unit quaternion [w, x, y, z] (normalised first).
pub fn rotation_of(q_wxyz: &[f64; 4]) -> nalgebra::Matrix3<f64> {
    let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        q_wxyz[0], q_wxyz[1], q_wxyz[2], q_wxyz[3],
    ));
    q.to_rotation_matrix().into_inner()
}

/// Largest |‖q‖ − 1| accepted for an orientation given on the command line or in a
/// trajectory file ([`unit_quaternion`]): quaternions printed with 4 significant digits pass
/// (cos 45° written 0.7071 gives |‖q‖ − 1| ≈ 1e-5), a quaternion that is not meant to be a
/// unit one (a typo, Euler angles, a missing component) does not.
pub const QUATERNION_INPUT_TOL: f64 = 1e-3;

/// Why an orientation given by a user is refused.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum QuaternionError {
    /// A component is NaN or infinite.
    #[error("orientation w,x,y,z must be four finite numbers, got {0:?}")]
    NonFinite([f64; 4]),
    /// The norm is not 1 within [`QUATERNION_INPUT_TOL`].
    #[error("orientation w,x,y,z {q:?} has norm {norm}: a unit quaternion needs |norm − 1| <= {QUATERNION_INPUT_TOL}")]
    NotUnit {
        /// The quaternion as given.
        q: [f64; 4],
        /// Its norm.
        norm: f64,
    },
}

/// The orientation rule of the command line and trajectory files: four finite numbers
/// w, x, y, z whose norm is 1 within [`QUATERNION_INPUT_TOL`], returned divided by their
/// norm (an exact unit quaternion such as [1, 0, 0, 0] is returned unchanged).
pub fn unit_quaternion(q: [f64; 4]) -> Result<[f64; 4], QuaternionError> {
    if !q.iter().all(|x| x.is_finite()) {
        return Err(QuaternionError::NonFinite(q));
    }
    let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    if !((norm - 1.0).abs() <= QUATERNION_INPUT_TOL) {
        return Err(QuaternionError::NotUnit { q, norm });
    }
    Ok(if norm == 1.0 { q } else { q.map(|x| x / norm) })
}

/// The orientation `q_wxyz` turned by `angle_rad` about the world axis `axis` (any
/// non-zero length): R(axis, angle) · R(q), as a unit quaternion [w, x, y, z].
pub fn rotated_about(q_wxyz: &[f64; 4], axis: &Vector3<f64>, angle_rad: f64) -> [f64; 4] {
    use nalgebra::{Quaternion, Unit, UnitQuaternion};
    let base = UnitQuaternion::from_quaternion(Quaternion::new(
        q_wxyz[0], q_wxyz[1], q_wxyz[2], q_wxyz[3],
    ));
    let turn = UnitQuaternion::from_axis_angle(&Unit::new_normalize(*axis), angle_rad);
    let r = (turn * base).into_inner();
    [r.w, r.i, r.j, r.k]
}

/// Smallest cable length accepted, m. Below it the element stiffness EA/L is meaningless.
pub const MIN_CABLE_LENGTH_M: f64 = 1e-6;

impl Geometry {
    /// Allocate for `n` cables.
    pub fn new(n: usize) -> Geometry {
        Geometry {
            unit: vec![Vector3::zeros(); n],
            length_m: vec![0.0; n],
            arm_m: vec![Vector3::zeros(); n],
            exit_m: vec![Vector3::zeros(); n],
            pulleys: vec![None; n],
            exits: vec![None; n],
        }
    }

    /// Allocate for the cables of `scene`, with their pulleys.
    pub fn for_scene(scene: &crate::scene::Scene) -> Geometry {
        let mut g = Geometry::new(scene.n_cables());
        for (p, c) in g.pulleys.iter_mut().zip(&scene.cables) {
            *p = c.pulley;
        }
        g
    }

    /// Whether some cable has a pulley.
    pub fn has_pulleys(&self) -> bool {
        self.pulleys.iter().any(|p| p.is_some())
    }

    /// Cable `i`'s pulley at the last successful update (None without a pulley).
    pub fn pulley_exit(&self, i: usize) -> Option<&PulleyExit> {
        self.exits[i].as_ref()
    }

    /// Free length of cable `i`, m: from its anchor, or from its pulley's exit point
    /// (= `length_m[i]`).
    pub fn free_length_m(&self, i: usize) -> f64 {
        self.length_m[i]
    }

    /// The cable wrapped on cable `i`'s pulley, m: radius × wrap angle (0 without a
    /// pulley). Together with the free length it is the cable's length from the anchor.
    pub fn wrap_arc_m(&self, i: usize) -> f64 {
        self.exits[i].map_or(0.0, |e| e.wrap_arc_m)
    }

    /// Wrap angle of cable `i`'s pulley, rad (0 without a pulley).
    pub fn wrap_rad(&self, i: usize) -> f64 {
        self.exits[i].map_or(0.0, |e| e.wrap_rad)
    }

    /// The pulleys' own term of the static stiffness for tensions `t_n` (N), N/m, N/rad,
    /// N·m/rad: Σ_i T_i (sin φ_i / a_i − 1/L_i) G_iᵀ n_i n_iᵀ G_i with G_i = \[I, −\[r_i\]×\]
    /// (`dim` 3: the translational block only), to add to the stiffness of cables pinned at
    /// their exit points ([`pulley`] module docs). Zero without pulleys. No allocation.
    pub fn pulley_stiffness(&self, t_n: &[f64], dim: usize) -> Matrix6<f64> {
        let mut k = Matrix6::zeros();
        for (i, e) in self.exits.iter().enumerate() {
            let Some(e) = e else { continue };
            let c = t_n[i] * e.softening_per_m;
            let n = e.normal;
            // δB = δp + δθ × r, so n·δB = n·δp + (r × n)·δθ.
            let rn = self.arm_m[i].cross(&n);
            let g6 = nalgebra::Vector6::new(n.x, n.y, n.z, rn.x, rn.y, rn.z);
            k += g6 * g6.transpose() * c;
        }
        if dim == 3 {
            k.fixed_view_mut::<3, 3>(3, 3).fill(0.0);
            k.fixed_view_mut::<3, 3>(0, 3).fill(0.0);
            k.fixed_view_mut::<3, 3>(3, 0).fill(0.0);
        }
        k
    }

    /// Number of cables.
    pub fn n(&self) -> usize {
        self.unit.len()
    }

    /// Recompute for anchors `anchors_m` and end-effector position `p_m`. No allocation.
    pub fn update<'a>(
        &mut self,
        anchors_m: impl Iterator<Item = &'a Vector3<f64>>,
        p_m: &Vector3<f64>,
    ) -> Result<(), KinematicsError> {
        if !p_m.iter().all(|x| x.is_finite()) {
            return Err(KinematicsError::NonFinite);
        }
        for (i, a) in anchors_m.enumerate().take(self.unit.len()) {
            if let Some(pulley) = &self.pulleys[i] {
                let e = pulley_exit(i, a, pulley, &(p_m + self.arm_m[i]))?;
                self.length_m[i] = e.free_length_m;
                self.unit[i] = e.unit;
                self.exit_m[i] = e.exit_m;
                self.exits[i] = Some(e);
                continue;
            }
            self.exit_m[i] = *a;
            let l = p_m + self.arm_m[i] - a;
            let len = l.norm();
            if len.is_nan() || len < MIN_CABLE_LENGTH_M {
                return Err(KinematicsError::CableTooShort {
                    cable: i,
                    length_m: len,
                    min_m: MIN_CABLE_LENGTH_M,
                });
            }
            self.length_m[i] = len;
            self.unit[i] = l / len;
        }
        Ok(())
    }

    /// Recompute for a rigid end-effector: attachment points `attach_body_m` (body frame)
    /// rotated by `rot` (body → world). No allocation.
    pub fn update_rigid<'a>(
        &mut self,
        anchors_m: impl Iterator<Item = &'a Vector3<f64>>,
        attach_body_m: impl Iterator<Item = &'a Vector3<f64>>,
        p_m: &Vector3<f64>,
        rot: &nalgebra::Matrix3<f64>,
    ) -> Result<(), KinematicsError> {
        for (arm, b) in self.arm_m.iter_mut().zip(attach_body_m) {
            *arm = rot * b;
        }
        self.update(anchors_m, p_m)
    }

    /// Structure matrix entry A[r, i]: s_i\[r\] for r < 3, (r_i × s_i)[r − 3] for r ≥ 3.
    pub fn a(&self, r: usize, i: usize) -> f64 {
        if r < 3 {
            self.unit[i][r]
        } else {
            self.arm_m[i].cross(&self.unit[i])[r - 3]
        }
    }

    /// Moment of the tensions about the centroid, Σ T_i r_i × s_i, N·m.
    pub fn moment_of(&self, t_n: &[f64]) -> Vector3<f64> {
        self.unit
            .iter()
            .zip(&self.arm_m)
            .zip(t_n)
            .fold(Vector3::zeros(), |acc, ((s, r), t)| acc + r.cross(s) * *t)
    }

    /// A·T, N.
    pub fn wrench_of(&self, t_n: &[f64]) -> Vector3<f64> {
        self.unit
            .iter()
            .zip(t_n)
            .fold(Vector3::zeros(), |acc, (s, t)| acc + s * *t)
    }
}

/// An orthonormal frame whose third column points up (against `gravity`); any frame when
/// gravity is zero (the catenary element is then the rotation-invariant straight limit). The circle
/// trajectory and the catenary element use its first two columns as the horizontal plane.
pub fn up_frame(gravity_m_s2: &Vector3<f64>) -> Matrix3<f64> {
    let g = gravity_m_s2.norm();
    let up = if g > 0.0 {
        -gravity_m_s2 / g
    } else {
        Vector3::z()
    };
    // Pick the coordinate axis least aligned with `up` to build x.
    let seed = if up.x.abs() <= up.y.abs() && up.x.abs() <= up.z.abs() {
        Vector3::x()
    } else if up.y.abs() <= up.z.abs() {
        Vector3::y()
    } else {
        Vector3::z()
    };
    let x = (seed - up * up.dot(&seed)).normalize();
    let y = up.cross(&x);
    Matrix3::from_columns(&[x, y, up])
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn user_quaternions_are_normalised_or_refused() {
        assert_eq!(
            unit_quaternion([1.0, 0.0, 0.0, 0.0]),
            Ok([1.0, 0.0, 0.0, 0.0])
        );
        // A 60° turn printed to four digits (cos 30° = 0.866, |‖q‖ − 1| ≈ 2e-5): accepted,
        // and normalised to 1 within rounding.
        let q = unit_quaternion([0.866, 0.5, 0.0, 0.0]).unwrap();
        let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((n - 1.0).abs() < 4.0 * f64::EPSILON, "{n}");
        assert!(matches!(
            unit_quaternion([1.0, 0.1, 0.0, 0.0]),
            Err(QuaternionError::NotUnit { .. })
        ));
        assert!(matches!(
            unit_quaternion([f64::NAN, 0.0, 0.0, 1.0]),
            Err(QuaternionError::NonFinite(_))
        ));
        assert!(unit_quaternion([0.0; 4]).is_err());
    }

    #[test]
    fn a_quarter_turn_about_z_maps_x_to_y() {
        let q = rotated_about(
            &[1.0, 0.0, 0.0, 0.0],
            &Vector3::new(0.0, 0.0, 2.0),
            FRAC_PI_2,
        );
        let x = rotation_of(&q) * Vector3::x();
        // Closed form: R_z(90°) x = y; rounding of cos(π/2) only.
        assert!((x - Vector3::y()).norm() < 1e-15, "{x}");
    }

    #[test]
    fn center_of_spatial_paper() {
        let s = crate::scene::Scene::default_scene();
        let mut g = Geometry::new(8);
        g.update(s.cables.iter().map(|c| &c.anchor_m), &s.ee_position_m)
            .unwrap();
        let l = (1.25f64 * 1.25 * 3.0).sqrt();
        for i in 0..8 {
            assert!((g.length_m[i] - l).abs() < 1e-15);
        }
        assert!((g.unit[0].z + 1.0 / 3f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn pose_at_anchor_is_an_error() {
        let s = crate::scene::Scene::default_scene();
        let mut g = Geometry::new(8);
        let e = g
            .update(s.cables.iter().map(|c| &c.anchor_m), &s.cables[2].anchor_m)
            .unwrap_err();
        assert!(matches!(e, KinematicsError::CableTooShort { cable: 2, .. }));
    }
}
