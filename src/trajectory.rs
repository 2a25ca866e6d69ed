//! End-effector trajectories: the paper's circle and sampled `t,x,y,z` files.
//!
//! The circle is the one trajectory every benchmark, test, sweep and the demo drive: radius
//! [`CIRCLE_RADIUS_M`] around the scene's default position, in the plane perpendicular to
//! gravity, one revolution per `period_s`, sampled every [`SAMPLE_PERIOD_S`]. Pose k of it
//! is [`circle_pose`] (allocation-free, for per-cycle loops); [`Trajectory::circle`]
//! evaluates the same curve at any time and [`Circle::sampled`] lists one revolution.
//!
//! ## Trajectory CSV files (one rule set, [`Samples::parse_csv`])
//!
//! - Each data row is `t,x,y,z`: exactly four finite numbers, time in s, position in m.
//! - Times increase strictly from row to row.
//! - Blank lines are skipped; `#` starts a comment that runs to the end of its line.
//! - One header line (a row whose fields are not all numbers) is allowed before the first
//!   data row.
//! - At least one data row.
//!
//! Errors name the file and the line.

use std::path::Path;

use nalgebra::{Matrix3, Vector3};

use crate::input_file::{InputError, MAX_TRAJECTORY_BYTES};
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
    /// The file could not be read: missing, not a regular file, over
    /// [`MAX_TRAJECTORY_BYTES`] or not UTF-8.
    #[error(transparent)]
    Input(#[from] InputError),
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
    #[error("{origin}: no t,x,y,z rows")]
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
/// radius [`CIRCLE_RADIUS_M`], `period_s` per revolution. Allocation-free.
pub fn circle_pose(s: &Scene, k: usize, period_s: f64) -> Pose {
    let frame = horizontal_axes(&s.gravity_m_s2);
    let th = 2.0 * std::f64::consts::PI * (k as f64 * SAMPLE_PERIOD_S) / period_s;
    let p = s.ee_position_m
        + frame.column(0) * (CIRCLE_RADIUS_M * th.cos())
        + frame.column(1) * (CIRCLE_RADIUS_M * th.sin());
    Pose::at(p)
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
        };
        let centre = scene.ee_position_m;
        for k in 0..=n {
            let p = circle_pose(scene, k, self.period_s).position_m;
            let p = centre + (p - centre) * (self.radius_m / CIRCLE_RADIUS_M);
            t.t_s.push(k as f64 * SAMPLE_PERIOD_S);
            t.position_m.push(p);
            t.angle_deg
                .push(360.0 * k as f64 * SAMPLE_PERIOD_S / self.period_s);
        }
        t
    }
}

/// Positions at listed times.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Samples {
    /// Times, s, strictly increasing.
    pub t_s: Vec<f64>,
    /// Positions, m.
    pub position_m: Vec<Vector3<f64>>,
    /// Angle along the circle, degrees (empty unless sampled from a [`Circle`]).
    pub angle_deg: Vec<f64>,
}

impl Samples {
    /// Reads a trajectory CSV file (rules in the module docs; a regular file of at most
    /// [`MAX_TRAJECTORY_BYTES`]).
    pub fn read_csv(path: &Path) -> Result<Samples, TrajectoryError> {
        let text = crate::input_file::read_text(path, "trajectory CSV", MAX_TRAJECTORY_BYTES)?;
        Samples::parse_csv(&text, &path.display().to_string())
    }

    /// Parses trajectory CSV text (rules in the module docs); `origin` names the source in
    /// errors.
    pub fn parse_csv(text: &str, origin: &str) -> Result<Samples, TrajectoryError> {
        let mut s = Samples::default();
        let mut header_seen = false;
        for (i, line) in text.lines().enumerate() {
            let row = |msg: String| TrajectoryError::Row {
                origin: origin.to_string(),
                line: i + 1,
                msg,
            };
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            let values = match fields
                .iter()
                .map(|f| f.parse::<f64>())
                .collect::<Result<Vec<_>, _>>()
            {
                Ok(v) => v,
                Err(_) if s.t_s.is_empty() && !header_seen => {
                    header_seen = true;
                    continue;
                }
                Err(e) => return Err(row(format!("`{line}`: {e}"))),
            };
            if values.len() != 4 || !values.iter().all(|v| v.is_finite()) {
                return Err(row(format!(
                    "expected four finite numbers t,x,y,z (s, m), got `{line}`"
                )));
            }
            if let Some(&last) = s.t_s.last() {
                if values[0] <= last {
                    return Err(row(format!(
                        "time {} s does not increase (previous {last} s)",
                        values[0]
                    )));
                }
            }
            s.t_s.push(values[0]);
            s.position_m
                .push(Vector3::new(values[1], values[2], values[3]));
        }
        if s.t_s.is_empty() {
            return Err(TrajectoryError::Empty {
                origin: origin.to_string(),
            });
        }
        Ok(s)
    }

    /// The position at time `t_s` (s from the first sample), m, linear between samples;
    /// the first position before the start, `None` after the last sample.
    pub fn position_at(&self, t_s: f64) -> Option<Vector3<f64>> {
        let ts = &self.t_s;
        let t = ts[0] + t_s;
        if t > *ts.last()? {
            return None;
        }
        let j = ts.partition_point(|&x| x <= t);
        if j == 0 {
            return Some(self.position_m[0]);
        }
        if j >= ts.len() {
            return Some(self.position_m[ts.len() - 1]);
        }
        let (ta, tb) = (ts[j - 1], ts[j]);
        let w = (t - ta) / (tb - ta);
        Some(self.position_m[j - 1] * (1.0 - w) + self.position_m[j] * w)
    }

    /// Time from the first to the last sample, s.
    pub fn duration_s(&self) -> f64 {
        self.t_s[self.t_s.len() - 1] - self.t_s[0]
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

    #[test]
    fn csv_interpolates_and_ends() {
        let t = Samples::parse_csv(
            "t,x,y,z\n0,0,0,1\n# comment\n1.0, 1, 0, 1 # x\n2,1,2,1\n",
            "x",
        )
        .unwrap();
        assert_eq!(t.duration_s(), 2.0);
        assert_eq!(t.position_at(0.5), Some(Vector3::new(0.5, 0.0, 1.0)));
        assert_eq!(t.position_at(1.5), Some(Vector3::new(1.0, 1.0, 1.0)));
        assert_eq!(t.position_at(2.0), Some(Vector3::new(1.0, 2.0, 1.0)));
        assert_eq!(t.position_at(2.5), None);
    }

    #[test]
    fn csv_rules_are_enforced() {
        let bad = [
            ("0,0,0,1\n0,1,1,1\n", "does not increase"),
            ("0,0,0\n", "four finite numbers"),
            ("0,0,0,1,5\n", "four finite numbers"),
            ("0,0,0,nan\n", "four finite numbers"),
            ("0,0,0,1\nfoo\n", "`foo`"),
            ("t,x,y,z\nt,x,y,z\n0,0,0,1\n", "`t,x,y,z`"),
            ("", "no t,x,y,z rows"),
            ("# only a comment\n", "no t,x,y,z rows"),
        ];
        for (text, why) in bad {
            let e = Samples::parse_csv(text, "f.csv").unwrap_err().to_string();
            assert!(e.contains(why) && e.starts_with("f.csv"), "{text:?}: {e}");
        }
    }

    /// `Samples::read_csv` of `path` in a thread, failing the test if it blocks.
    fn read_within_timeout(path: &Path) -> Result<Samples, TrajectoryError> {
        let p = path.to_path_buf();
        crate::input_file::test_files::within_timeout(move || Samples::read_csv(&p))
    }

    #[test]
    fn csv_from_devices_fifos_and_directories_is_refused_without_blocking() {
        use crate::input_file::test_files::{fifo, temp_dir};
        let dir = temp_dir("csv-kinds");
        let fifo = fifo(&dir, "t.csv");
        for (p, kind) in [
            (fifo.as_path(), "FIFO"),
            (Path::new("/dev/zero"), "character device"),
            (Path::new("/dev/urandom"), "character device"),
            (dir.as_path(), "directory"),
        ] {
            let msg = read_within_timeout(p).unwrap_err().to_string();
            let name = p.display().to_string();
            assert!(
                msg.starts_with(&format!("{name}: is a {kind}")) && msg.contains("trajectory CSV"),
                "{msg}"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn csv_over_the_limit_is_refused_and_a_small_file_read() {
        use crate::input_file::test_files::{sparse, temp_dir};
        use crate::input_file::MAX_TRAJECTORY_BYTES;
        let dir = temp_dir("csv-size");
        let big = sparse(&dir, "big.csv", MAX_TRAJECTORY_BYTES + 1);
        let msg = read_within_timeout(&big).unwrap_err().to_string();
        let expected = format!(
            "{}: trajectory CSV is {} bytes, over the limit of {MAX_TRAJECTORY_BYTES} bytes",
            big.display(),
            MAX_TRAJECTORY_BYTES + 1
        );
        assert_eq!(msg, expected);
        let small = dir.join("small.csv");
        std::fs::write(&small, "t,x,y,z\n0,0,0,1\n1,1,0,1\n").unwrap();
        let s = read_within_timeout(&small).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(s.duration_s(), 1.0);
    }
}
