//! Does sag matter for a scene that has it off? At one pose, f1 of the continuous chord
//! model (sag off) against f1 of the continuous sagged model (sag on, the N → ∞ limit of
//! the sagged FEM): when they differ by more than the scene's `model.f1_tolerance`, the
//! chord model is the wrong physics for this robot, and `analyze`, `serve` and `map` say
//! so once. Offline: builds two estimators (allocates).

use super::{Estimator, EstimatorParams, Tmin};
use crate::kinematics::Pose;
use crate::scene::{ElementKind, Scene};

/// Why sag should be on, at one pose.
#[derive(Debug, Clone, PartialEq)]
pub struct SagWarning {
    /// Relative change of f1 when the cables sag: |f1,sag − f1,chord| / f1,sag.
    pub f1_change: f64,
    /// f1 of the continuous chord model, Hz.
    pub f1_chord_hz: f64,
    /// f1 of the continuous sagged model, Hz.
    pub f1_sag_hz: f64,
    /// The largest Irvine λ² over the cables (dimensionless).
    pub lambda2_max: f64,
    /// The cable with that λ² (numbered from 1, as in every output).
    pub cable: usize,
    /// The scene's tolerance the change exceeds.
    pub tolerance: f64,
}

impl std::fmt::Display for SagWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "warning: sag is off, but sagging cables change f1 by {:.1e} here ({:.4} → {:.4} Hz, over the tolerance {:.0e}; largest Irvine λ² = {:.3e}, cable {}): set [effects] sag = true (or false, to keep the chord model and this line quiet)",
            self.f1_change,
            self.f1_chord_hz,
            self.f1_sag_hz,
            self.tolerance,
            self.lambda2_max,
            self.cable
        )
    }
}

/// Whether some cable of `scene` has weight to sag under (weight per length > 0 and
/// gravity).
pub fn cables_can_sag(scene: &Scene) -> bool {
    scene.gravity_m_s2.norm() > 0.0 && scene.cables.iter().any(|c| c.mass_per_length_kg_m > 0.0)
}

/// The continuous sagged version of `scene` (sag on whatever the scene says).
pub fn sagged_reference(scene: &Scene) -> Scene {
    let mut s = scene.with_model(ElementKind::Continuous, 1);
    s.model.sag = true;
    s.model.geometric_stiffness = true;
    s
}

/// At `pose` and the scene's T_min: the warning when `scene` has sag off (not chosen
/// explicitly: `[effects] sag = false`, or a front end's sag override, silences it), its cables can sag,
/// and sag changes f1 by more than `model.f1_tolerance`; None otherwise (also when either
/// model has no valid estimate there: nothing to compare).
pub fn sag_warning(scene: &Scene, pose: &Pose) -> Option<SagWarning> {
    if scene.model.sag || scene.model.sag_explicit || !cables_can_sag(scene) {
        return None;
    }
    let mut chord = scene.with_model(ElementKind::Continuous, 1);
    chord.model.geometric_stiffness = true;
    chord.model.sag = false;
    let sagged = sagged_reference(scene);
    let params = EstimatorParams {
        ee_mode: false,
        ..EstimatorParams::default()
    };
    let f1_chord = Estimator::with_params(&chord, params)
        .ok()?
        .update(pose, Tmin::Scene)
        .f1_hz;
    let mut est = Estimator::with_params(&sagged, params).ok()?;
    let f1_sag = est.update(pose, Tmin::Scene).f1_hz;
    let (cable, lambda2_max) = est
        .sag_catenaries()?
        .iter()
        .map(|c| c.irvine_lambda2())
        .enumerate()
        .fold(
            (0, f64::NEG_INFINITY),
            |a, (i, l)| if l > a.1 { (i, l) } else { a },
        );
    let change = (f1_sag - f1_chord).abs() / f1_sag;
    (change.is_finite() && change > scene.model.f1_tolerance).then_some(SagWarning {
        f1_change: change,
        f1_chord_hz: f1_chord,
        f1_sag_hz: f1_sag,
        lambda2_max,
        cable: cable + 1,
        tolerance: scene.model.f1_tolerance,
    })
}
