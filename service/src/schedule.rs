//! T_min schedules: which T_min set-point a replay publishes when.

use super::ServiceError;

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
            let (t, v) = item.split_once(':').ok_or_else(|| ServiceError::Schedule {
                item: item.to_string(),
                reason: "expected SECONDS:NEWTONS, e.g. 2:80".into(),
            })?;
            let parse = |x: &str, what: &str| {
                x.trim().parse::<f64>().map_err(|e| ServiceError::Schedule {
                    item: item.to_string(),
                    reason: format!("{what}: {e}"),
                })
            };
            let (t, v) = (parse(t, "time (s)")?, parse(v, "T_min (N)")?);
            if !(t.is_finite() && t >= 0.0) {
                return Err(ServiceError::Schedule {
                    item: item.to_string(),
                    reason: "time must be finite and ≥ 0 s".into(),
                });
            }
            if steps.last().is_some_and(|&(last, _)| t <= last) {
                return Err(ServiceError::Schedule {
                    item: item.to_string(),
                    reason: "times must increase".into(),
                });
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
