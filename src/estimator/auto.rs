//! `element = "auto"`: pick the cheapest cable model whose f1 matches a converged reference
//! within the scene's tolerance. Offline: runs at build time and allocates.

use super::sag_check::{cables_can_sag, sagged_reference};
use super::{BuildError, Estimator, EstimatorError, EstimatorParams, RejectedInput, Tmin};
use crate::kinematics::{Geometry, Pose};
use crate::scene::{ElementKind, Scene};
use crate::trajectory::{Circle, CIRCLE_RADIUS_M};
use nalgebra::Vector3;

/// Elements per cable of the reference (catenary) model: converged in f1 well below any
/// tolerance a scene sets.
const REF_N: usize = 64;
/// Sample poses on the paper's circle (radius [`CIRCLE_RADIUS_M`] around the default pose,
/// the span over which the pick must hold), π/4 apart.
const CIRCLE_POSES: u32 = 8;

/// What `element = "auto"` picked, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct AutoChoice {
    /// The model picked.
    pub element: ElementKind,
    /// Elements per cable of the pick (1 for massless and continuous).
    pub elements_per_cable: usize,
    /// Its largest relative f1 error against the reference over the sample poses.
    pub predicted_error: f64,
    /// The tolerance it had to meet.
    pub tolerance: f64,
    /// Every candidate tried, cheapest first: (model, N, largest relative f1 error).
    pub candidates: Vec<(ElementKind, usize, f64)>,
    /// The reference: the continuous sagged model when some cable can sag (weight per
    /// length > 0), else the catenary element with [`Self::reference_elements`] elements.
    pub reference: String,
    /// Elements per cable of the catenary reference (cables that cannot sag).
    pub reference_elements: usize,
    /// Whether the pick is the sagged model (`[effects] sag`).
    pub sag: bool,
    /// Each cable's Irvine λ² at the default pose on the sagged reference (empty when no
    /// cable can sag or the sagged model has no estimate there).
    pub irvine_lambda2_per_cable: Vec<f64>,
    /// Sample poses used (the default pose and feasible poses on the 0.75 m circle).
    pub poses: usize,
    /// Largest Irvine parameter λ² = (γ⊥ L / T)² · EA / T over the cables at the default
    /// pose (sag matters when it is not ≪ 1).
    pub irvine_lambda2: f64,
    /// Total cable mass over end-effector mass.
    pub mass_ratio: f64,
}

impl std::fmt::Display for AutoChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = |el: ElementKind, n: usize| model_name(el, n, false);
        write!(
            f,
            "auto picked {}: predicted f1 error {:.2e} (tolerance {:.1e}; largest over {} poses against {}; Irvine λ² ≤ {:.2e}, cable/end-effector mass ratio {:.3}). Tried:",
            model_name(self.element, self.elements_per_cable, self.sag),
            self.predicted_error,
            self.tolerance,
            self.poses,
            self.reference,
            self.irvine_lambda2,
            self.mass_ratio
        )?;
        for (el, n, err) in &self.candidates {
            write!(f, " {} {:.2e};", name(*el, *n), err)?;
        }
        if self.sag && self.candidates.len() < CHORD_CANDIDATES + 1 {
            write!(f, " continuous with sag (the reference)")?;
        }
        Ok(())
    }
}

/// Resolve `element = "auto"`: evaluate, at the default pose and at feasible poses of the
/// 0.75 m circle, the f1 of each chord candidate in order of per-cycle cost — massless
/// cables, the continuous string (the N → ∞ limit of FEM, at the same cost as any FEM N),
/// the catenary element at N = 4 and 16 — against a converged reference, and pick the
/// first whose largest relative error is within `model.f1_tolerance`. The reference is the
/// continuous sagged model (`[effects] sag`, the N → ∞ limit of the sagged FEM) when some
/// cable can sag (weight per length > 0 and gravity), else the catenary element at N = 64;
/// it is the fallback, so a robot whose cables sag enough gets the sagged model. Reports
/// each cable's Irvine λ² on the sagged reference. Allocates: set-up only.
pub fn resolve_auto(scene: &Scene) -> Result<(Scene, AutoChoice), BuildError> {
    let tol = scene.model.f1_tolerance;
    let chord_reference = scene.with_model(ElementKind::Catenary, REF_N);
    let mut can_sag = cables_can_sag(scene);
    let mut reference = if can_sag {
        sagged_reference(scene)
    } else {
        chord_reference.clone()
    };
    let mut poses = vec![Pose {
        position_m: scene.ee_position_m,
        orientation_wxyz: scene.ee_orientation_wxyz,
    }];
    // One revolution per second: time k/8 s is the angle kπ/4 (exactly, in binary).
    if let Ok(circle) = Circle::new(scene, CIRCLE_RADIUS_M, 1.0) {
        for k in 0..CIRCLE_POSES {
            poses.push(Pose {
                position_m: circle.position_at(k as f64 / CIRCLE_POSES as f64),
                orientation_wxyz: scene.ee_orientation_wxyz,
            });
        }
    }
    let f1_of = |s: &Scene, pose: &Pose| -> Option<f64> {
        let p = EstimatorParams {
            ee_mode: false,
            ..EstimatorParams::default()
        };
        let mut est = Estimator::with_params(s, p).ok()?;
        let e = est.update(pose, Tmin::Scene);
        e.is_ok().then_some(e.f1_hz)
    };
    let refs_of = |r: &Scene| -> Vec<(Pose, f64)> {
        poses
            .iter()
            .filter_map(|pose| f1_of(r, pose).map(|f| (*pose, f)))
            .collect()
    };
    let mut refs = refs_of(&reference);
    if refs.is_empty() && can_sag {
        // The sagged model has no estimate at any sample pose (e.g. a planar robot whose
        // cables' own weight is out of its plane): the chord reference decides.
        can_sag = false;
        reference = chord_reference;
        refs = refs_of(&reference);
    }
    if refs.is_empty() {
        Estimator::with_params(&reference, EstimatorParams::default())?;
        return Err(BuildError::DefaultPose {
            scene: scene.name.clone(),
            position_m: scene.ee_position_m.into(),
            reason: Box::new(EstimatorError::Input(RejectedInput::NoFeasiblePose)),
        });
    }
    let mut massless = scene.with_model(ElementKind::Massless, 1);
    massless.model.geometric_stiffness = true;
    let mut list = [
        massless,
        scene.with_model(ElementKind::Continuous, 1),
        scene.with_model(ElementKind::Catenary, 4),
        scene.with_model(ElementKind::Catenary, 16),
    ];
    for cand in &mut list {
        cand.model.sag = false;
    }
    let mut candidates = Vec::new();
    let mut pick: Option<(Scene, f64)> = None;
    for cand in list {
        let worst = refs
            .iter()
            .map(|(pose, fr)| f1_of(&cand, pose).map_or(f64::INFINITY, |f| (f - fr).abs() / fr))
            .fold(0.0f64, f64::max);
        candidates.push((cand.model.element, cand.model.elements_per_cable, worst));
        if pick.is_none() && worst <= tol {
            pick = Some((cand, worst));
        }
    }
    let (chosen, err) = pick.unwrap_or((reference, 0.0));
    let (mut irvine, cable_mass) = default_pose_diagnostics(scene);
    let per_cable = if can_sag {
        sagged_lambda2(scene)
    } else {
        Vec::new()
    };
    if !per_cable.is_empty() {
        irvine = per_cable.iter().copied().fold(0.0, f64::max);
    }
    let choice = AutoChoice {
        element: chosen.model.element,
        elements_per_cable: chosen.model.elements_per_cable,
        predicted_error: err,
        tolerance: tol,
        candidates,
        reference: if can_sag {
            "continuous with sag".into()
        } else {
            format!("catenary × {REF_N}")
        },
        sag: chosen.model.sag,
        irvine_lambda2_per_cable: per_cable,
        reference_elements: REF_N,
        poses: refs.len(),
        irvine_lambda2: irvine,
        mass_ratio: cable_mass / scene.ee_mass_kg,
    };
    Ok((chosen, choice))
}

/// The chord candidates `auto` tries before the sagged model.
const CHORD_CANDIDATES: usize = 4;

/// The name of a model in the pick's report.
fn model_name(el: ElementKind, n: usize, sag: bool) -> String {
    let base = if el.is_discrete() {
        format!("{} × {n}", el.as_str())
    } else {
        el.as_str().to_string()
    };
    if sag {
        format!("{base} with sag")
    } else {
        base
    }
}

/// Each cable's Irvine λ² at the default pose on the sagged reference (empty when it has
/// no estimate there).
fn sagged_lambda2(scene: &Scene) -> Vec<f64> {
    let reference = sagged_reference(scene);
    let pose = Pose {
        position_m: scene.ee_position_m,
        orientation_wxyz: scene.ee_orientation_wxyz,
    };
    let Ok(mut est) = Estimator::with_params(&reference, EstimatorParams::default()) else {
        return Vec::new();
    };
    if !est.update(&pose, Tmin::Scene).is_ok() {
        return Vec::new();
    }
    est.sag_catenaries()
        .map(|c| c.iter().map(|c| c.irvine_lambda2()).collect())
        .unwrap_or_default()
}

/// At the scene's default pose (Clarabel tensions): the largest Irvine parameter λ² over
/// the cables (0 when the tensions are not available) and the total cable mass, kg.
fn default_pose_diagnostics(scene: &Scene) -> (f64, f64) {
    let mut g = Geometry::for_scene(scene);
    let _ = g.update(
        scene.cables.iter().map(|c| &c.anchor_m),
        &scene.ee_position_m,
    );
    let n = scene.n_cables();
    let (t_min_n, t_max_n) = (
        Tmin::Scene.per_cable(scene),
        super::forward::cable_t_max_n(scene),
    );
    let t = crate::tension::clarabel_reference_bounds(
        &g,
        &scene.wrench6_n(),
        &t_min_n[..n],
        &t_max_n[..n],
    )
    .unwrap_or_default();
    let gn = scene.gravity_m_s2.norm();
    let down = if gn > 0.0 {
        scene.gravity_m_s2 / gn
    } else {
        Vector3::zeros()
    };
    let mut irvine = 0.0f64;
    let mut cable_mass = 0.0;
    for (i, c) in scene.cables.iter().enumerate() {
        let l = g.length_m[i];
        cable_mass += c.mass_per_length_kg_m * l;
        if let Some(&ti) = t.get(i) {
            let s = g.unit[i];
            let perp = (down - s * s.dot(&down)).norm();
            let gam = c.mass_per_length_kg_m * gn * perp;
            irvine = irvine.max((gam * l / ti).powi(2) * c.ea_n() / ti);
        }
    }
    (irvine, cable_mass)
}
