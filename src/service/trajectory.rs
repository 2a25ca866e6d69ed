//! Trajectories to replay (the paper's circle, or a CSV file) and T_min schedules.

use std::path::Path;

use nalgebra::Vector3;

use super::ServiceError;
use crate::scene::Scene;

/// Radius of the paper's circular trajectory, m.
pub const CIRCLE_RADIUS_M: f64 = 0.75;

/// End-effector positions as a function of time.
#[derive(Debug, Clone, PartialEq)]
pub enum Trajectory {
    /// The paper's circle (as [`crate::cli::circle_pose`]): radius [`CIRCLE_RADIUS_M`] around
    /// `center_m`, in the plane perpendicular to gravity spanned by `axes`.
    Circle {
        /// Centre, m (the scene's default position).
        center_m: Vector3<f64>,
        /// Two orthonormal in-plane directions.
        axes: [Vector3<f64>; 2],
        /// Time per revolution, s.
        period_s: f64,
    },
    /// Linear interpolation between the rows of a `t,x,y,z` file (s, m); it ends at the last
    /// row.
    Samples {
        /// Times, s, strictly increasing.
        t_s: Vec<f64>,
        /// Positions, m.
        position_m: Vec<Vector3<f64>>,
    },
}

impl Trajectory {
    /// The paper's circle around `scene`'s default position, `period_s` per revolution.
    pub fn circle(scene: &Scene, period_s: f64) -> Result<Trajectory, ServiceError> {
        if !(period_s.is_finite() && period_s > 0.0) {
            return Err(ServiceError::Usage(format!(
                "circle period {period_s} s must be finite and > 0"
            )));
        }
        let frame = crate::cable::up_frame(&scene.gravity_m_s2);
        Ok(Trajectory::Circle {
            center_m: scene.ee_position_m,
            axes: [frame.column(0).into_owned(), frame.column(1).into_owned()],
            period_s,
        })
    }

    /// Reads a CSV file of `t,x,y,z` rows (s, m). Blank lines, `#` comments and a header line
    /// are skipped; times must increase strictly.
    pub fn from_csv(path: &Path) -> Result<Trajectory, ServiceError> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            ServiceError::Usage(format!("cannot read trajectory {}: {e}", path.display()))
        })?;
        Trajectory::parse_csv(&text, &path.display().to_string())
    }

    /// Parses CSV text of `t,x,y,z` rows (see [`Trajectory::from_csv`]); `origin` names the
    /// source in errors.
    pub fn parse_csv(text: &str, origin: &str) -> Result<Trajectory, ServiceError> {
        let mut t_s = Vec::new();
        let mut position_m = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            let values: Result<Vec<f64>, _> = fields.iter().map(|f| f.parse::<f64>()).collect();
            let values = match values {
                Ok(v) => v,
                Err(_) if t_s.is_empty() && position_m.is_empty() && i == 0 => continue, // header
                Err(e) => {
                    return Err(ServiceError::Usage(format!(
                        "{origin}:{}: `{line}`: {e}",
                        i + 1
                    )))
                }
            };
            if values.len() != 4 || !values.iter().all(|v| v.is_finite()) {
                return Err(ServiceError::Usage(format!(
                    "{origin}:{}: expected four finite numbers t,x,y,z (s, m), got `{line}`",
                    i + 1
                )));
            }
            if let Some(&last) = t_s.last() {
                if values[0] <= last {
                    return Err(ServiceError::Usage(format!(
                        "{origin}:{}: time {} s does not increase (previous {last} s)",
                        i + 1,
                        values[0]
                    )));
                }
            }
            t_s.push(values[0]);
            position_m.push(Vector3::new(values[1], values[2], values[3]));
        }
        if t_s.is_empty() {
            return Err(ServiceError::Usage(format!("{origin}: no t,x,y,z rows")));
        }
        Ok(Trajectory::Samples { t_s, position_m })
    }

    /// The position at time `t_s` (s from the start), m; `None` after the end of a sampled
    /// trajectory. Before the first sample, the first position.
    pub fn position_at(&self, t_s: f64) -> Option<Vector3<f64>> {
        match self {
            Trajectory::Circle {
                center_m,
                axes,
                period_s,
            } => {
                let th = 2.0 * std::f64::consts::PI * t_s / period_s;
                Some(
                    center_m
                        + axes[0] * (CIRCLE_RADIUS_M * th.cos())
                        + axes[1] * (CIRCLE_RADIUS_M * th.sin()),
                )
            }
            Trajectory::Samples {
                t_s: ts,
                position_m,
            } => {
                let t0 = ts[0];
                let t = t0 + t_s;
                if t > *ts.last()? {
                    return None;
                }
                let j = ts.partition_point(|&x| x <= t);
                if j == 0 {
                    return Some(position_m[0]);
                }
                if j >= ts.len() {
                    return Some(position_m[ts.len() - 1]);
                }
                let (ta, tb) = (ts[j - 1], ts[j]);
                let w = (t - ta) / (tb - ta);
                Some(position_m[j - 1] * (1.0 - w) + position_m[j] * w)
            }
        }
    }

    /// Duration of a sampled trajectory, s (`None` for the endless circle).
    pub fn duration_s(&self) -> Option<f64> {
        match self {
            Trajectory::Circle { .. } => None,
            Trajectory::Samples { t_s, .. } => Some(t_s[t_s.len() - 1] - t_s[0]),
        }
    }

    /// One line for a log: what is replayed.
    pub fn describe(&self) -> String {
        match self {
            Trajectory::Circle {
                center_m, period_s, ..
            } => format!(
                "circle r = {CIRCLE_RADIUS_M} m around ({:.3}, {:.3}, {:.3}) m, {period_s} s per \
                 revolution",
                center_m.x, center_m.y, center_m.z
            ),
            Trajectory::Samples { t_s, .. } => format!(
                "{} samples over {:.3} s",
                t_s.len(),
                self.duration_s().unwrap_or(0.0)
            ),
        }
    }
}

/// A piecewise-constant T_min schedule: from time `t_s` on, `t_min_n` (s, N).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TminSchedule {
    steps: Vec<(f64, f64)>,
}

impl TminSchedule {
    /// Parses `"t:N,t:N,..."` (seconds from the start : newtons), e.g. `"0:60,2:80"`.
    /// Times must increase strictly. Values are not range-checked here: the service decides
    /// (and reports `t_min_out_of_range` for a bad one), which a test may want to exercise.
    pub fn parse(text: &str) -> Result<TminSchedule, ServiceError> {
        let mut steps: Vec<(f64, f64)> = Vec::new();
        for item in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (t, v) = item.split_once(':').ok_or_else(|| {
                ServiceError::Usage(format!(
                    "T_min schedule item `{item}`: expected SECONDS:NEWTONS, e.g. 2:80"
                ))
            })?;
            let parse = |x: &str, what: &str| {
                x.trim().parse::<f64>().map_err(|e| {
                    ServiceError::Usage(format!("T_min schedule item `{item}`: {what}: {e}"))
                })
            };
            let (t, v) = (parse(t, "time (s)")?, parse(v, "T_min (N)")?);
            if !(t.is_finite() && t >= 0.0) {
                return Err(ServiceError::Usage(format!(
                    "T_min schedule item `{item}`: time must be finite and ≥ 0 s"
                )));
            }
            if steps.last().is_some_and(|&(last, _)| t <= last) {
                return Err(ServiceError::Usage(format!(
                    "T_min schedule item `{item}`: times must increase"
                )));
            }
            steps.push((t, v));
        }
        Ok(TminSchedule { steps })
    }

    /// The steps (time s, T_min N).
    pub fn steps(&self) -> &[(f64, f64)] {
        &self.steps
    }

    /// Index of the step in force at `t_s`, if any.
    pub fn step_at(&self, t_s: f64) -> Option<usize> {
        let j = self.steps.partition_point(|&(t, _)| t <= t_s);
        j.checked_sub(1)
    }

    /// No steps.
    pub fn is_empty(&self) -> bool {
        self.steps.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_matches_cli_circle_pose() {
        let scene = Scene::default_scene();
        let c = Trajectory::circle(&scene, 4.0).unwrap();
        for k in [0usize, 1, 250, 1000, 3999] {
            let p = c.position_at(k as f64 * 1e-3).unwrap();
            let q = crate::cli::circle_pose(&scene, k, 4.0).position_m;
            assert!((p - q).norm() < 1e-12, "k = {k}: {p} vs {q}");
        }
        assert!(Trajectory::circle(&scene, 0.0).is_err());
    }

    #[test]
    fn csv_interpolates_and_ends() {
        let t = Trajectory::parse_csv("t,x,y,z\n0,0,0,1\n# comment\n1.0, 1, 0, 1\n2,1,2,1\n", "x")
            .unwrap();
        assert_eq!(t.duration_s(), Some(2.0));
        assert_eq!(t.position_at(0.5), Some(Vector3::new(0.5, 0.0, 1.0)));
        assert_eq!(t.position_at(1.5), Some(Vector3::new(1.0, 1.0, 1.0)));
        assert_eq!(t.position_at(2.0), Some(Vector3::new(1.0, 2.0, 1.0)));
        assert_eq!(t.position_at(2.5), None);
        assert!(Trajectory::parse_csv("0,0,0,1\n0,1,1,1\n", "x").is_err());
        assert!(Trajectory::parse_csv("0,0,0\n", "x").is_err());
        assert!(Trajectory::parse_csv("0,0,0,1\nfoo\n", "x").is_err());
        assert!(Trajectory::parse_csv("", "x").is_err());
    }

    #[test]
    fn schedule() {
        let s = TminSchedule::parse("0:60, 2:80,3.5:-1").unwrap();
        assert_eq!(s.steps(), &[(0.0, 60.0), (2.0, 80.0), (3.5, -1.0)]);
        assert_eq!(s.step_at(-0.1), None);
        assert_eq!(s.step_at(0.0), Some(0));
        assert_eq!(s.step_at(2.5), Some(1));
        assert_eq!(s.step_at(10.0), Some(2));
        assert!(TminSchedule::parse("1:60,0:70").is_err());
        assert!(TminSchedule::parse("60").is_err());
        assert!(TminSchedule::parse("a:60").is_err());
        assert!(TminSchedule::parse("").unwrap().is_empty());
    }
}
