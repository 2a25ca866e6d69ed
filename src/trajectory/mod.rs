//! End-effector trajectories: the paper's circle and sampled `t,x,y,z[,qw,qx,qy,qz]` files.
//!
//! The circle is the one trajectory every benchmark, test, sweep and the demo drive: radius
//! [`CIRCLE_RADIUS_M`] around the scene's default position, in the plane perpendicular to
//! gravity, one revolution per `period_s`, sampled every [`SAMPLE_PERIOD_S`]. Pose k of it
//! is [`circle_pose`] (allocation-free, for per-cycle loops); [`Trajectory::circle`]
//! evaluates the same curve at any time and [`Circle::sampled`] lists one revolution.
//!
//! Trajectory CSV files (`t,x,y,z` or `t,x,y,z,qw,qx,qy,qz`: time, position and optionally
//! the orientation as a unit quaternion) are read by [`Samples`]; the rules are in
//! [`samples`]'s docs. Point-to-point moves with a stop (trapezoidal and S-curve velocity)
//! are [`moves`]; input shaping of a path (ZV, ZVD, EI, time-varying, online) is
//! [`shaping`].

pub mod moves;
pub mod samples;
pub mod shaping;

pub use samples::Samples;

use std::path::Path;

use nalgebra::{Matrix3, Vector3};

use crate::input_file::InputFileError;
use crate::kinematics::{up_frame, Pose};
use crate::scene::Scene;

/// Radius of the paper's circular trajectory, m.
pub const CIRCLE_RADIUS_M: f64 = 0.75;

/// Time per revolution of the circle that the benchmarks and the demo drive by default, s.
pub const CIRCLE_PERIOD_S: f64 = 4.0;

/// Time between consecutive poses of the circle (one control cycle at 1 kHz), s.
pub const SAMPLE_PERIOD_S: f64 = 1e-3;

/// Why a trajectory could not be made or read.
#[derive(Debug, thiserror::Error)]
pub enum TrajectoryError {
    /// A circle parameter is out of range.
    #[error("circle {what} {value:?} must be finite and {bound}")]
    BadCircle {
        /// Which parameter (`radius_m`, `period_s`).
        what: &'static str,
        /// Its value.
        value: f64,
        /// The range it must be in.
        bound: &'static str,
    },
    /// A point-to-point move whose displacement is zero: it would go nowhere.
    #[error("a point-to-point move of zero length goes nowhere: the displacement must not be (0, 0, 0) m")]
    ZeroMove,
    /// The file could not be read: missing, not a regular file, over
    /// [`MAX_TRAJECTORY_BYTES`](crate::input_file::MAX_TRAJECTORY_BYTES) or not UTF-8.
    #[error(transparent)]
    Input(#[from] InputFileError),
    /// A row breaks the CSV rules (see the module docs).
    #[error("{origin}:{line}: {msg}")]
    Row {
        /// The file.
        origin: String,
        /// Line number, from 1.
        line: usize,
        /// What is wrong.
        msg: String,
    },
    /// No data row.
    #[error("{origin}: no data rows (t,x,y,z[,qw,qx,qy,qz])")]
    Empty {
        /// The file.
        origin: String,
    },
}

/// Two orthonormal directions spanning the plane perpendicular to gravity (the first two
/// columns of [`up_frame`]).
fn horizontal_axes(gravity_m_s2: &Vector3<f64>) -> Matrix3<f64> {
    up_frame(gravity_m_s2)
}

/// Pose k of the paper's circle around `s`'s default position: time k·[`SAMPLE_PERIOD_S`],
/// radius [`CIRCLE_RADIUS_M`], `period_s` per revolution, at the scene's orientation.
/// Allocation-free.
pub fn circle_pose(s: &Scene, k: usize, period_s: f64) -> Pose {
    circle_pose_with_radius(s, k, period_s, CIRCLE_RADIUS_M)
}

/// Pose k of the circle of `radius_m` around `s`'s default position (as [`circle_pose`],
/// which is this at [`CIRCLE_RADIUS_M`], bit for bit): for robots whose workspace is far
/// larger than the paper's (the bench's radius). Allocation-free.
pub fn circle_pose_with_radius(s: &Scene, k: usize, period_s: f64, radius_m: f64) -> Pose {
    let frame = horizontal_axes(&s.gravity_m_s2);
    let th = 2.0 * std::f64::consts::PI * (k as f64 * SAMPLE_PERIOD_S) / period_s;
    let p = s.ee_position_m
        + frame.column(0) * (radius_m * th.cos())
        + frame.column(1) * (radius_m * th.sin());
    Pose::in_scene(s, p)
}

/// The paper's circle (any radius) around a centre, in the plane perpendicular to gravity.
#[derive(Debug, Clone, PartialEq)]
pub struct Circle {
    /// Centre, m (the scene's default position).
    pub center_m: Vector3<f64>,
    /// Two orthonormal in-plane directions.
    pub axes: [Vector3<f64>; 2],
    /// Radius, m.
    pub radius_m: f64,
    /// Time per revolution, s.
    pub period_s: f64,
}

impl Circle {
    /// The circle of `radius_m` (≥ 0; 0 holds the centre) around `scene`'s default position,
    /// `period_s` (> 0) per revolution.
    pub fn new(scene: &Scene, radius_m: f64, period_s: f64) -> Result<Circle, TrajectoryError> {
        if !(radius_m.is_finite() && radius_m >= 0.0) {
            let (what, value, bound) = ("radius_m", radius_m, "≥ 0");
            return Err(TrajectoryError::BadCircle { what, value, bound });
        }
        if !(period_s.is_finite() && period_s > 0.0) {
            let (what, value, bound) = ("period_s", period_s, "> 0");
            return Err(TrajectoryError::BadCircle { what, value, bound });
        }
        let frame = horizontal_axes(&scene.gravity_m_s2);
        Ok(Circle {
            center_m: scene.ee_position_m,
            axes: [frame.column(0).into_owned(), frame.column(1).into_owned()],
            radius_m,
            period_s,
        })
    }

    /// The position at time `t_s`, m.
    pub fn position_at(&self, t_s: f64) -> Vector3<f64> {
        let th = 2.0 * std::f64::consts::PI * t_s / self.period_s;
        self.center_m
            + self.axes[0] * (self.radius_m * th.cos())
            + self.axes[1] * (self.radius_m * th.sin())
    }

    /// One revolution (both ends included) at [`SAMPLE_PERIOD_S`], with the angle along the
    /// circle. Each point is the [`circle_pose`] point with its offset from the centre
    /// scaled by radius / [`CIRCLE_RADIUS_M`] (so a sweep at the paper's radius replays
    /// exactly the poses of the benchmarks).
    pub fn sampled(&self, scene: &Scene) -> Samples {
        let n = (self.period_s / SAMPLE_PERIOD_S).round().max(1.0) as usize;
        let mut t = Samples {
            t_s: Vec::with_capacity(n + 1),
            position_m: Vec::with_capacity(n + 1),
            angle_deg: Vec::with_capacity(n + 1),
            orientation_wxyz: Vec::new(),
        };
        for k in 0..=n {
            let (t_s, p, angle_deg) = self.sample(scene, k);
            t.t_s.push(t_s);
            t.position_m.push(p);
            t.angle_deg.push(angle_deg);
        }
        t
    }

    /// Samples in [`Circle::sampled`]: one more than the steps of one revolution.
    pub fn sample_count(&self) -> usize {
        (self.period_s / SAMPLE_PERIOD_S).round().max(1.0) as usize + 1
    }

    /// Sample `k` of [`Circle::sampled`]: time (s), position (m), angle along the circle (deg).
    pub fn sample(&self, scene: &Scene, k: usize) -> (f64, Vector3<f64>, f64) {
        let centre = scene.ee_position_m;
        let p = circle_pose(scene, k, self.period_s).position_m;
        let p = centre + (p - centre) * (self.radius_m / CIRCLE_RADIUS_M);
        (
            k as f64 * SAMPLE_PERIOD_S,
            p,
            360.0 * k as f64 * SAMPLE_PERIOD_S / self.period_s,
        )
    }
}

/// End-effector positions as a function of time: the endless circle or a sampled file.
#[derive(Debug, Clone, PartialEq)]
pub enum Trajectory {
    /// The paper's circle.
    Circle(Circle),
    /// Linear interpolation between samples; it ends at the last one.
    Samples(Samples),
}

impl Trajectory {
    /// The paper's circle ([`CIRCLE_RADIUS_M`]) around `scene`'s default position,
    /// `period_s` per revolution: the curve of [`circle_pose`] at any time.
    pub fn circle(scene: &Scene, period_s: f64) -> Result<Trajectory, TrajectoryError> {
        Ok(Trajectory::Circle(Circle::new(
            scene,
            CIRCLE_RADIUS_M,
            period_s,
        )?))
    }

    /// Reads a trajectory CSV file (rules in the module docs).
    pub fn from_csv(path: &Path) -> Result<Trajectory, TrajectoryError> {
        Ok(Trajectory::Samples(Samples::read_csv(path)?))
    }

    /// The position at time `t_s` (s from the start), m; `None` after the end of a sampled
    /// trajectory.
    pub fn position_at(&self, t_s: f64) -> Option<Vector3<f64>> {
        match self {
            Trajectory::Circle(c) => Some(c.position_at(t_s)),
            Trajectory::Samples(s) => s.position_at(t_s),
        }
    }

    /// The orientation at time `t_s` (s from the start) when the trajectory has one (a CSV
    /// with quaternion columns; slerp between samples), else `None` (the scene's applies).
    pub fn orientation_at(&self, t_s: f64) -> Option<[f64; 4]> {
        match self {
            Trajectory::Circle(_) => None,
            Trajectory::Samples(s) => s.orientation_at(t_s),
        }
    }

    /// Duration of a sampled trajectory, s (`None` for the endless circle).
    pub fn duration_s(&self) -> Option<f64> {
        match self {
            Trajectory::Circle(_) => None,
            Trajectory::Samples(s) => Some(s.duration_s()),
        }
    }

    /// One line for a log: what is replayed.
    pub fn describe(&self) -> String {
        match self {
            Trajectory::Circle(c) => format!(
                "circle r = {} m around ({:.3}, {:.3}, {:.3}) m, {} s per revolution",
                c.radius_m, c.center_m.x, c.center_m.y, c.center_m.z, c.period_s
            ),
            Trajectory::Samples(s) => {
                format!("{} samples over {:.3} s", s.t_s.len(), s.duration_s())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_curve_equals_circle_poses() {
        let scene = Scene::default_scene();
        let c = Trajectory::circle(&scene, 4.0).unwrap();
        for k in [0usize, 1, 250, 1000, 3999] {
            let p = c.position_at(k as f64 * SAMPLE_PERIOD_S).unwrap();
            let q = circle_pose(&scene, k, 4.0).position_m;
            assert_eq!(p, q, "k = {k}");
        }
        assert!(Trajectory::circle(&scene, 0.0).is_err());
        assert!(Circle::new(&scene, f64::NAN, 4.0).is_err());
    }

    #[test]
    fn sampled_circle_at_the_paper_radius_is_centred_and_closed() {
        let scene = Scene::default_scene();
        let s = Circle::new(&scene, CIRCLE_RADIUS_M, 0.2)
            .unwrap()
            .sampled(&scene);
        assert_eq!(s.t_s.len(), 201);
        assert_eq!(s.angle_deg[200], 360.0);
        for p in &s.position_m {
            let r = (p - scene.ee_position_m).norm();
            assert!((r - CIRCLE_RADIUS_M).abs() < 1e-12, "r = {r}");
        }
    }
}
