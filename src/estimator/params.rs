//! [`EstimatorParams`]: every tunable of the estimator — the solvers of both forward models
//! (taut and sagged cables), the cycle's warm-start and input tolerances — with the two
//! presets: [`EstimatorParams::default`] (offline: every answer complete) and
//! [`EstimatorParams::realtime`] (the cycle as the service, `bench` and the real-time tests
//! run it). [`EstimatorParams::check`] holds each value to finite bounds.

use crate::cable::sagged::SagContinuousParams;
use crate::modal::{ModalParams, CYCLE_EVALUATIONS, SPREAD_SCAN_EVALUATIONS};
use crate::scene::Scene;
use crate::tension::{SagTensionParams, TensionParams};

/// Parameters of the estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimatorParams {
    /// The chord tension distribution (taut cables).
    pub tension: TensionParams,
    /// The structured eigen solver (both models).
    pub modal: ModalParams,
    /// The sagged forward model (`[effects] sag`).
    pub sag: SagModelParams,
    /// A pose step larger than this (m) forces a cold start.
    pub warm_jump_m: f64,
    /// A relative T_min change larger than this forces a cold start.
    pub warm_t_min_change: f64,
    /// Tolerance on the quaternion norm.
    pub quaternion_tol: f64,
    /// Compute the end-effector mode (costs a scan over the string modes below it).
    pub ee_mode: bool,
}

/// Parameters of the sagged forward model (default: each part's default).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SagModelParams {
    /// The sagged tension distribution (a bounded SQP; its `tension` is the QP of each
    /// step). Default: [`SagTensionParams::default`].
    pub tension: SagTensionParams,
    /// The mesh rule of continuous sagged chains in the cycle. Default: the offline rule
    /// ([`SagContinuousParams::default`]: 1e-9 up to four half-waves per cable, for the first
    /// K modes); real time: [`SagContinuousParams::realtime`] (f1 only, which lies within
    /// every cable's first half-wave, to 1e-5).
    pub continuous: SagContinuousParams,
    /// The mesh rule of the inverse T_min query ([`super::Estimator::t_min_for_f1`]), which
    /// is not a cycle: the offline rule in both presets.
    pub t_min_query_continuous: SagContinuousParams,
}

impl Default for EstimatorParams {
    /// The offline preset: no per-cycle budget (every answer of a cycle complete), the
    /// offline sagged mesh; warm start within 5 mm and a 1e-3 relative T_min change;
    /// quaternion norm within 1e-6; the end-effector mode on.
    fn default() -> Self {
        EstimatorParams {
            tension: TensionParams::default(),
            modal: ModalParams::default(),
            sag: SagModelParams::default(),
            warm_jump_m: 0.005,
            warm_t_min_change: 1e-3,
            quaternion_tol: 1e-6,
            ee_mode: true,
        }
    }
}

/// A parameter out of its bounds: its name in [`EstimatorParams`], its value and the range
/// it must lie in.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("estimator parameter {name} = {value:?}: must be in {range}")]
pub struct ParamsError {
    /// Path of the field (e.g. `modal.rel_tol`).
    pub name: &'static str,
    /// Its value (integers converted).
    pub value: f64,
    /// The range, as text.
    pub range: &'static str,
}

impl EstimatorParams {
    /// The real-time preset, the one definition of how the cycle runs under a deadline
    /// (the service, `cablevib bench`, [`super::Estimator::realtime`]): the default with a
    /// per-cycle budget of [`CYCLE_EVALUATIONS`] evaluations of D(λ) (f1 exact first, the
    /// end-effector work that does not fit continued in the next cycles), the spread
    /// scan's bound [`SPREAD_SCAN_EVALUATIONS`], and the real-time mesh of continuous
    /// sagged chains ([`SagContinuousParams::realtime`]).
    pub fn realtime() -> EstimatorParams {
        let d = EstimatorParams::default();
        EstimatorParams {
            modal: ModalParams {
                cycle_evaluations: CYCLE_EVALUATIONS,
                max_scan_evaluations: SPREAD_SCAN_EVALUATIONS,
                ..d.modal
            },
            sag: SagModelParams {
                continuous: SagContinuousParams::realtime(),
                ..d.sag
            },
            ..d
        }
    }

    /// These parameters with `scene`'s end-effector participation threshold
    /// (`model.ee_participation_min`).
    pub fn for_scene(mut self, scene: &Scene) -> EstimatorParams {
        self.modal.ee_participation_min = scene.model.ee_participation_min;
        self
    }

    /// Every value within its bounds (each range contains both presets); the first one
    /// outside is the error. [`super::Estimator::with_params`] refuses parameters that fail.
    pub fn check(&self) -> Result<(), ParamsError> {
        let (t, m, s) = (&self.tension, &self.modal, &self.sag);
        let ints: [(&'static str, f64, f64, f64, &'static str); 10] = [
            (
                "tension.max_iterations",
                t.max_iterations as f64,
                1.0,
                1e6,
                "1..=1e6",
            ),
            (
                "modal.max_evaluations",
                m.max_evaluations.into(),
                1.0,
                1e6,
                "1..=1e6",
            ),
            (
                "modal.max_scan_intervals",
                m.max_scan_intervals.into(),
                1.0,
                1e7,
                "1..=1e7",
            ),
            (
                "modal.max_scan_evaluations",
                m.max_scan_evaluations.into(),
                1.0,
                1e7,
                "1..=1e7",
            ),
            (
                "modal.cycle_evaluations",
                m.cycle_evaluations.into(),
                1.0,
                u32::MAX.into(),
                "1..=u32::MAX (u32::MAX: unlimited)",
            ),
            (
                "sag.tension.max_iterations",
                s.tension.max_iterations.into(),
                1.0,
                1e4,
                "1..=1e4",
            ),
            (
                "sag.tension.sag.max_iterations",
                s.tension.sag.max_iterations.into(),
                1.0,
                1e4,
                "1..=1e4",
            ),
            (
                "sag.tension.sag.max_fallback_solves",
                s.tension.sag.max_fallback_solves.into(),
                0.0,
                1e6,
                "0..=1e6",
            ),
            (
                "sag.tension.tension.max_iterations",
                s.tension.tension.max_iterations as f64,
                1.0,
                1e6,
                "1..=1e6",
            ),
            // The norm of a unit quaternion is checked against it: 0.1 already accepts a
            // 10 % error in the rotation's scale.
            (
                "quaternion_tol",
                self.quaternion_tol,
                1e-15,
                0.1,
                "[1e-15, 0.1]",
            ),
        ];
        // Relative tolerances: below 1e-16 is below a double's resolution, above 1e-2 no
        // longer an answer.
        let tol = "[1e-16, 1e-2]";
        let reals: [(&'static str, f64, f64, f64, &'static str); 12] = [
            (
                "tension.feasibility_tol",
                t.feasibility_tol,
                1e-16,
                1e-2,
                tol,
            ),
            ("modal.rel_tol", m.rel_tol, 1e-16, 1e-2, tol),
            ("modal.newton_accept", m.newton_accept, 1e-16, 1e-2, tol),
            (
                "modal.ee_participation_min",
                m.ee_participation_min,
                f64::from_bits(1), // the smallest positive double, as the scene allows
                1.0,
                "(0, 1]",
            ),
            (
                "sag.tension.step_tol_rel",
                s.tension.step_tol_rel,
                1e-16,
                1e-2,
                tol,
            ),
            (
                "sag.tension.sag.tolerance",
                s.tension.sag.tolerance,
                1e-16,
                1e-2,
                tol,
            ),
            (
                "sag.tension.tension.feasibility_tol",
                s.tension.tension.feasibility_tol,
                1e-16,
                1e-2,
                tol,
            ),
            (
                "sag.continuous.rel_tol",
                s.continuous.rel_tol,
                1e-16,
                1e-2,
                tol,
            ),
            (
                "sag.t_min_query_continuous.rel_tol",
                s.t_min_query_continuous.rel_tol,
                1e-16,
                1e-2,
                tol,
            ),
            // Half-waves of a cable's transverse mode the mesh resolves: the first mode
            // needs one; beyond 1000 the step cap decides anyway.
            (
                "sag.continuous.max_halfwaves",
                s.continuous.max_halfwaves,
                1e-3,
                1e3,
                "[1e-3, 1e3]",
            ),
            (
                "sag.t_min_query_continuous.max_halfwaves",
                s.t_min_query_continuous.max_halfwaves,
                1e-3,
                1e3,
                "[1e-3, 1e3]",
            ),
            // 0 m: never warm; a kilometre spans any robot.
            ("warm_jump_m", self.warm_jump_m, 0.0, 1e3, "[0, 1e3] m"),
        ];
        let change = (
            "warm_t_min_change",
            self.warm_t_min_change,
            0.0,
            1e3,
            "[0, 1e3]",
        );
        for (name, value, lo, hi, range) in ints.into_iter().chain(reals).chain([change]) {
            // NaN fails both comparisons.
            if !(value >= lo && value <= hi) {
                return Err(ParamsError { name, value, range });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both presets pass their own check, and the real-time one differs from the default
    /// exactly in the budget, the scan bound and the sagged mesh.
    #[test]
    fn presets_are_valid_and_differ_where_documented() {
        let (d, r) = (EstimatorParams::default(), EstimatorParams::realtime());
        d.check().unwrap();
        r.check().unwrap();
        assert_eq!(r.modal.cycle_evaluations, CYCLE_EVALUATIONS);
        assert_eq!(r.modal.max_scan_evaluations, SPREAD_SCAN_EVALUATIONS);
        assert_eq!(r.sag.continuous, SagContinuousParams::realtime());
        let back = EstimatorParams {
            modal: ModalParams {
                cycle_evaluations: d.modal.cycle_evaluations,
                max_scan_evaluations: d.modal.max_scan_evaluations,
                ..r.modal
            },
            sag: SagModelParams {
                continuous: d.sag.continuous,
                ..r.sag
            },
            ..r
        };
        assert_eq!(back, d);
    }

    /// The sagged continuous mesh is the parameters' choice, independent of the cycle
    /// budget: with the real-time budget and the offline mesh, f1 at the default pose of the sagging
    /// `suspended-8` is bit for bit the offline estimator's (same mesh, same Newton
    /// iterates: the budget only cuts a search, and this one fits), and differs from the
    /// real-time preset's (the real-time mesh, 1e-5 rule, moves f1 by ~1e-7 relative).
    #[test]
    fn the_sagged_mesh_is_chosen_by_the_parameters() {
        use crate::estimator::{Estimator, Tmin};
        use crate::kinematics::Pose;
        use crate::scene::ElementKind;
        let s = Scene::load("scenes/suspended_8.toml")
            .unwrap()
            .with_model(ElementKind::Continuous, 1);
        assert!(s.model.sag);
        let pose = Pose::in_scene(&s, s.ee_position_m);
        let f1 = |p: EstimatorParams| {
            let mut est = Estimator::with_params(&s, p.for_scene(&s)).unwrap();
            let e = *est.update(&pose, Tmin::Scene);
            assert!(e.is_ok(), "{:?}", e.error);
            e.f1_hz
        };
        let offline = f1(EstimatorParams::default());
        let realtime = f1(EstimatorParams::realtime());
        let mut budget_offline_mesh = EstimatorParams::realtime();
        budget_offline_mesh.sag.continuous = SagContinuousParams::default();
        assert_eq!(f1(budget_offline_mesh).to_bits(), offline.to_bits());
        assert_ne!(realtime, offline);
        assert!((realtime - offline).abs() < 1e-6 * offline);
    }

    /// `Estimator::realtime` is the preset with the scene's participation threshold, and
    /// `with_params` refuses parameters out of bounds.
    #[test]
    fn estimators_take_the_preset_and_refuse_bad_params() {
        use crate::estimator::{BuildError, Estimator};
        let s = Scene::default_scene();
        let est = Estimator::realtime(&s).unwrap();
        assert_eq!(*est.params(), EstimatorParams::realtime().for_scene(&s));
        let mut p = EstimatorParams::realtime();
        p.quaternion_tol = 0.0;
        match Estimator::with_params(&s, p) {
            Err(BuildError::Params(e)) => assert_eq!(e.name, "quaternion_tol"),
            other => panic!("{:?}", other.map(|_| ())),
        }
    }

    /// Each kind of bad value is refused with the field's name: NaN, infinite, zero where
    /// it must be positive, above the bound.
    #[test]
    fn out_of_bounds_values_are_named() {
        let name = |change: fn(&mut EstimatorParams)| {
            let mut p = EstimatorParams::realtime();
            change(&mut p);
            p.check().unwrap_err().name
        };
        assert_eq!(name(|p| p.modal.rel_tol = f64::NAN), "modal.rel_tol");
        assert_eq!(name(|p| p.warm_jump_m = f64::INFINITY), "warm_jump_m");
        assert_eq!(
            name(|p| p.modal.cycle_evaluations = 0),
            "modal.cycle_evaluations"
        );
        assert_eq!(
            name(|p| p.sag.continuous.max_halfwaves = 0.0),
            "sag.continuous.max_halfwaves"
        );
        assert_eq!(
            name(|p| p.modal.ee_participation_min = 1.5),
            "modal.ee_participation_min"
        );
        let p = EstimatorParams {
            sag: SagModelParams {
                tension: SagTensionParams {
                    sag: crate::elastic_catenary::SagParams {
                        tolerance: -1e-12,
                        ..Default::default()
                    },
                    ..Default::default()
                },
                ..Default::default()
            },
            ..Default::default()
        };
        let e = p.check().unwrap_err();
        assert_eq!(e.name, "sag.tension.sag.tolerance");
        assert_eq!(
            e.to_string(),
            "estimator parameter sag.tension.sag.tolerance = -1e-12: must be in [1e-16, 1e-2]"
        );
    }
}
