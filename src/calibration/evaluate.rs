//! The model at the measured poses for one parameter vector: each pose's modes (the
//! structured engine, as `cablevib modes` computes them: [`PoseModel`], its
//! [`ModalSolver::modes`] and [`ModalSolver::mode_shapes`]), the model modes the pairing
//! rules pick, their eigenvalues' analytic derivatives ([`super::energy`]) and the tensions.
//! Poses are evaluated in parallel (rayon), each on its own solver.

use super::data::MeasuredPose;
use super::energy::{energies, sensitivity, tension_mass_derivative, PoseContext};
use super::params::{apply, Applied, FitSpec};
use crate::estimator::{build_models, EndEffector, PoseModel, Tmin};
use crate::kinematics::Geometry;
use crate::kinematics::{rotation_of, Pose};
use crate::modal::{hz_to_lambda, ModalParams, ModalSolver, Mode, ShapeParams};
use crate::tension::{Bound, TensionParams, TensionSolver};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Most modes computed at one pose.
pub const MAX_MODES_PER_POSE: usize = 2000;

/// A pairing rule, resolved: which model mode at the pose a measured mode is compared with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Rule {
    /// The model's mode of this 1-based order.
    Order(usize),
    /// The model's K-th end-effector mode (participation ≥ the threshold), 1-based.
    Ee(usize),
}

impl std::fmt::Display for Rule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Rule::Order(k) => write!(f, "mode {k}"),
            Rule::Ee(k) => write!(f, "ee{k}"),
        }
    }
}

/// What the fit needs at one measured pose.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseTask {
    /// The pose as measured.
    pub pose: MeasuredPose,
    /// The rules of the modes measured there.
    pub rules: Vec<Rule>,
    /// The cables whose tension was measured there (0-based).
    pub cables: Vec<usize>,
    /// Compute every mode up to this frequency, Hz (0: only what the rules need), for the
    /// pairing by frequency.
    pub band_hz: f64,
    /// Look for the rules' modes up to this frequency, Hz (a rule without its mode below it
    /// is unresolved; 0: no limit).
    pub max_hz: f64,
}

impl PoseTask {
    /// The task of `rules` at `pose`, no tension and no band.
    pub fn new(pose: MeasuredPose, rules: Vec<Rule>) -> PoseTask {
        PoseTask {
            pose,
            rules,
            cables: Vec::new(),
            band_hz: 0.0,
            max_hz: 0.0,
        }
    }
}

/// The model mode a rule picked.
#[derive(Debug, Clone, PartialEq)]
pub struct Picked {
    /// λ of its cluster, rad²/s².
    pub lambda: f64,
    /// Its end-effector participation.
    pub participation: f64,
    /// Its 1-based order at the pose (the first of its cluster).
    pub order: usize,
    /// Multiplicity of its cluster.
    pub multiplicity: u32,
    /// dλ/dp per fitted parameter (NaN where the analytic form is missing; empty when not
    /// asked for).
    pub dlambda: Vec<f64>,
}

/// The model at one pose.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseOut {
    /// The modes computed (ascending).
    pub modes: Vec<Mode>,
    /// Per rule: the mode it picked, or None when the model has no such mode.
    pub picked: Vec<Option<Picked>>,
    /// Tensions of the task's cables, N.
    pub tensions_n: Vec<f64>,
    /// dT/dp of the task's cables per parameter (NaN where missing; empty when not asked).
    pub dtension: Vec<Vec<f64>>,
}

/// Evaluation settings shared by every pose.
#[derive(Debug, Clone)]
pub struct Evaluator<'a> {
    /// The scene with the nominal model (element resolved).
    pub base: &'a crate::scene::Scene,
    /// The fitted parameters.
    pub spec: &'a FitSpec,
    /// The poses.
    pub tasks: &'a [PoseTask],
    /// Whether the analytic sensitivities apply (taut fem or massless cables).
    pub analytic: bool,
    /// Modes computed per pose at the last evaluation (the next one's first guess).
    pub hints: &'a [AtomicUsize],
}

impl Evaluator<'_> {
    /// Every pose at the parameter values `x`: the picked modes and tensions, and with
    /// `jacobian` their analytic derivatives. The first pose that fails gives its index and
    /// the reason.
    pub fn eval(
        &self,
        x: &[f64],
        jacobian: bool,
    ) -> Result<(Applied, Vec<PoseOut>), (usize, String)> {
        let applied = apply(self.base, self.spec, x);
        let out: Result<Vec<PoseOut>, (usize, String)> = self
            .tasks
            .par_iter()
            .enumerate()
            .map(|(k, task)| {
                let hint = self.hints[k].load(Ordering::Relaxed);
                let (o, used) = eval_pose(
                    &applied,
                    self.spec,
                    x,
                    task,
                    hint,
                    jacobian && self.analytic,
                )
                .map_err(|e| (k, e))?;
                self.hints[k].store(used, Ordering::Relaxed);
                Ok(o)
            })
            .collect();
        Ok((applied, out?))
    }
}

/// The model's pose for a measured one: the reference point moved to the centre of mass.
pub fn model_pose(applied: &Applied, p: &MeasuredPose) -> Pose {
    let q = p
        .orientation_wxyz
        .unwrap_or(applied.scene.ee_orientation_wxyz);
    let r = rotation_of(&q);
    Pose {
        position_m: p.position_m + r * applied.com_offset_m,
        orientation_wxyz: q,
    }
}

/// Index (in `modes`) of the mode `rule` picks, or None.
pub fn resolve(modes: &[Mode], rule: Rule, threshold: f64) -> Option<usize> {
    match rule {
        Rule::Order(k) => (k <= modes.len()).then(|| k - 1),
        Rule::Ee(k) => modes
            .iter()
            .enumerate()
            .filter(|(_, m)| m.ee_participation >= threshold)
            .nth(k - 1)
            .map(|(i, _)| i),
    }
}

/// Whether `modes` (the first `modes.len()` of a model of `total` modes) answer every rule.
fn enough(
    modes: &[Mode],
    total: usize,
    rules: &[Rule],
    (band_lambda, max_lambda): (f64, f64),
    threshold: f64,
) -> bool {
    if modes.len() >= total || modes.last().is_some_and(|m| m.lambda > max_lambda) {
        return true;
    }
    let band = modes.last().is_some_and(|m| m.lambda > band_lambda);
    band && rules
        .iter()
        .all(|&r| resolve(modes, r, threshold).is_some())
}

/// The model of `scene` at `pose` as `cablevib modes` builds it ([`PoseModel`]), with the
/// tensions of the exact active-set solver (rounding-exact, so the model is a smooth function
/// of the parameters down to rounding) and each cable's active bound.
pub fn pose_model(
    scene: &crate::scene::Scene,
    pose: &Pose,
    t_min_n: &[f64],
    t_max_n: &[f64],
) -> Result<(PoseModel, Vec<Bound>), String> {
    let n = scene.n_cables();
    let mut geometry = Geometry::for_scene(scene);
    if scene.rigid {
        geometry.update_rigid(
            scene.cables.iter().map(|c| &c.anchor_m),
            scene.cables.iter().map(|c| &c.attachment_m),
            &pose.position_m,
            &rotation_of(&pose.orientation_wxyz),
        )
    } else {
        geometry.update(scene.cables.iter().map(|c| &c.anchor_m), &pose.position_m)
    }
    .map_err(|e| e.to_string())?;
    let mut solver = TensionSolver::new(n, TensionParams::default());
    let tensions_n = solver
        .solve_wrench_bounds(&geometry, &scene.wrench6_n(), t_min_n, t_max_n)
        .map_err(|e| e.to_string())?
        .to_vec();
    let bounds = solver.bounds().to_vec();
    let models = build_models(scene, &geometry, &tensions_n).map_err(|e| e.to_string())?;
    let end_effector = EndEffector::with_tensions(scene, pose, &geometry, &tensions_n);
    Ok((
        PoseModel {
            scene: scene.clone(),
            geometry,
            tensions_n,
            models,
            end_effector,
        },
        bounds,
    ))
}

/// One pose: returns its output and the number of modes computed.
fn eval_pose(
    applied: &Applied,
    spec: &FitSpec,
    x: &[f64],
    task: &PoseTask,
    hint: usize,
    jacobian: bool,
) -> Result<(PoseOut, usize), String> {
    let scene = &applied.scene;
    let pose = model_pose(applied, &task.pose);
    let t_min = Tmin::from_override(task.pose.t_min_n);
    let t_min_n = t_min.per_cable(scene);
    let t_max_n: Vec<f64> = (0..scene.n_cables())
        .map(|i| scene.cable_t_max_n(i))
        .collect();
    let (pm, bounds) = pose_model(scene, &pose, &t_min_n[..scene.n_cables()], &t_max_n)?;
    let mut solver = ModalSolver::new(ModalParams::default());
    pm.load(&mut solver);
    let threshold = scene.model.ee_participation_min;
    let total = solver.total_modes();
    let band_lambda = if task.band_hz > 0.0 {
        hz_to_lambda(task.band_hz)
    } else {
        0.0
    };
    let max_lambda = if task.max_hz > 0.0 {
        hz_to_lambda(task.max_hz.max(task.band_hz))
    } else {
        f64::INFINITY
    };
    let orders = task
        .rules
        .iter()
        .map(|r| match r {
            Rule::Order(k) => *k,
            Rule::Ee(k) => *k + pm.dim(),
        })
        .max()
        .unwrap_or(1);
    let mut k = hint.max(orders).max(pm.dim()).min(MAX_MODES_PER_POSE);
    let modes = loop {
        let mut buf = vec![Mode::default(); k];
        let got = solver.modes(k, &mut buf).map_err(|e| e.to_string())?;
        buf.truncate(got);
        if enough(
            &buf,
            total,
            &task.rules,
            (band_lambda, max_lambda),
            threshold,
        ) {
            break buf;
        }
        if k >= MAX_MODES_PER_POSE {
            return Err(format!(
                "the rules need more than {MAX_MODES_PER_POSE} modes at this pose"
            ));
        }
        k = (2 * k).min(MAX_MODES_PER_POSE);
    };
    let used = modes.len();
    let dt_dm = if jacobian {
        tension_mass_derivative(&pm, &bounds)
    } else {
        Vec::new()
    };
    let ctx = PoseContext {
        pm: &pm,
        applied,
        rotation: rotation_of(&pose.orientation_wxyz),
        dt_dm: &dt_dm,
    };
    let mut picked = Vec::with_capacity(task.rules.len());
    // Shapes are recovered once per cluster picked.
    let mut cluster_derivs: Vec<(usize, Vec<f64>)> = Vec::new();
    for &rule in &task.rules {
        let Some(i) = resolve(&modes, rule, threshold) else {
            picked.push(None);
            continue;
        };
        let start = modes[i].cluster_start;
        let m = &modes[start];
        let dlambda = if jacobian {
            match cluster_derivs.iter().find(|(s, _)| *s == start) {
                Some((_, d)) => d.clone(),
                None => {
                    let d =
                        cluster_derivative(&mut solver, &ctx, spec, x, m.lambda, m.multiplicity);
                    cluster_derivs.push((start, d.clone()));
                    d
                }
            }
        } else {
            Vec::new()
        };
        picked.push(Some(Picked {
            lambda: m.lambda,
            participation: modes[i].ee_participation,
            order: start + 1,
            multiplicity: m.multiplicity,
            dlambda,
        }));
    }
    let tensions_n = task.cables.iter().map(|&c| pm.tensions_n[c]).collect();
    let dtension = if jacobian {
        task.cables
            .iter()
            .map(|&c| {
                spec.params
                    .iter()
                    .map(|p| match p.kind {
                        super::ParamKind::EeMass => dt_dm[c],
                        super::ParamKind::EeCom(_) | super::ParamKind::PulleyRadius => f64::NAN,
                        _ => 0.0,
                    })
                    .collect()
            })
            .collect()
    } else {
        Vec::new()
    };
    Ok((
        PoseOut {
            modes,
            picked,
            tensions_n,
            dtension,
        },
        used,
    ))
}

/// dλ/dp of the cluster (λ, m): the mean over its shapes of each shape's analytic
/// derivative; NaN for the parameters without one, and for all when the shapes fail.
fn cluster_derivative(
    solver: &mut ModalSolver,
    ctx: &PoseContext<'_>,
    spec: &FitSpec,
    x: &[f64],
    lambda: f64,
    m: u32,
) -> Vec<f64> {
    let nan = vec![f64::NAN; spec.params.len()];
    let Ok(shapes) = solver.mode_shapes(
        &ctx.pm.models,
        &ctx.pm.geometry.arm_m,
        &[(lambda, m)],
        &ShapeParams::default(),
    ) else {
        return nan;
    };
    let mut sum = vec![0.0; spec.params.len()];
    for shape in &shapes.modes {
        let Ok(e) = energies(ctx.pm, shape) else {
            return nan;
        };
        for ((s, p), &v) in sum.iter_mut().zip(&spec.params).zip(x) {
            *s += sensitivity(ctx, &e, p.kind, v).unwrap_or(f64::NAN);
        }
    }
    let count = shapes.modes.len().max(1) as f64;
    sum.iter().map(|s| s / count).collect()
}
