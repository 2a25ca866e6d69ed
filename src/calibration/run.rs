//! [`calibrate`]: checks, pairing at the nominal parameters, the fit (re-paired at the fitted
//! parameters until the pairs hold), the statistics and the report.

use super::data::{MeasuredPose, ModeLabel, SigmaSource};
use super::evaluate::{PoseOut, PoseTask, Rule};
use super::fit::{chi2_upper_tail, levenberg_marquardt, statistics, FitParams};
use super::pairing::{pair, PairingParams, Unpaired};
use super::params::{apply, Applied, FitSpec};
use super::problem::{Layout, Problem};
use super::report::{
    DampingResidual, LeftOutRow, ModeResidual, ParameterResult, Report, TensionResidual,
};
use super::{CalibrationError, Measurements};
use crate::modal::lambda_to_hz;
use crate::scene::{ElementKind, Scene};
use std::collections::HashMap;
use std::time::Instant;

/// Settings of a calibration.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CalibrationParams {
    /// The iteration and its statistics.
    pub fit: FitParams,
    /// The pairing by frequency.
    pub pairing: PairingParams,
}

/// A calibration's answer: the report, the parameter values and the calibrated model.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// What was found.
    pub report: Report,
    /// The fitted values, in the order of the spec's parameters.
    pub values: Vec<f64>,
    /// The calibrated scene (and the centre of mass's offset).
    pub applied: Applied,
}

/// Positions that differ by at most this in every coordinate are one pose, m: a file written
/// with fewer digits (identify's CSV keeps 11 significant) names the same pose as one
/// written in full (the load cells' tensions). Orientations then agree to 1e-9 and T_min to
/// 1e-9 relative.
const SAME_POSE_M: f64 = 1e-6;

/// The grid cell of `p`'s position, [`SAME_POSE_M`] wide (a finite position: checked by the
/// parser; saturating otherwise).
fn pose_cell(p: &MeasuredPose) -> [i64; 3] {
    let c = |v: f64| (v / SAME_POSE_M).round() as i64;
    [c(p.position_m.x), c(p.position_m.y), c(p.position_m.z)]
}

/// `a` and `b` are the same pose (see [`SAME_POSE_M`]).
fn same_pose(a: &MeasuredPose, b: &MeasuredPose) -> bool {
    let near = |x: f64, y: f64, tol: f64| (x - y).abs() <= tol;
    (a.position_m - b.position_m).amax() <= SAME_POSE_M
        && match (a.orientation_wxyz, b.orientation_wxyz) {
            (None, None) => true,
            (Some(p), Some(q)) => (0..4).all(|k| near(p[k], q[k], 1e-9)),
            _ => false,
        }
        && match (a.t_min_n, b.t_min_n) {
            (None, None) => true,
            (Some(x), Some(y)) => near(x, y, 1e-9 * x.abs().max(1.0)),
            _ => false,
        }
}

/// The poses of the data (in order of first appearance), each row's pose index, and the
/// checks a pose must pass before any model is built.
struct Poses {
    list: Vec<MeasuredPose>,
    of_mode: Vec<usize>,
    of_tension: Vec<usize>,
    /// First data line at each pose (for messages).
    first_line: Vec<(String, usize)>,
}

fn collect_poses(scene: &Scene, data: &Measurements) -> Result<Poses, CalibrationError> {
    // Pose indices by grid cell; a pose is looked for in its cell and the 26 around it.
    let mut index: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    let mut p = Poses {
        list: Vec::new(),
        of_mode: Vec::new(),
        of_tension: Vec::new(),
        first_line: Vec::new(),
    };
    let mut add = |pose: &MeasuredPose,
                   file: &str,
                   line: usize|
     -> Result<usize, CalibrationError> {
        let row = |m: String| CalibrationError::Row {
            file: file.to_string(),
            line,
            message: m,
        };
        if let Some(q) = pose.orientation_wxyz {
            if !scene.rigid && q != [1.0, 0.0, 0.0, 0.0] {
                return Err(row(format!(
                    "orientation {q:?} on a point-mass end-effector (the scene has effects.rotation = false)"
                )));
            }
        }
        if let Some(t) = pose.t_min_n {
            scene
                .check_uniform_t_min(t)
                .map_err(|e| row(format!("t_min_n: {e}")))?;
        }
        let c = pose_cell(pose);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let near = [
                        c[0].saturating_add(dx),
                        c[1].saturating_add(dy),
                        c[2].saturating_add(dz),
                    ];
                    if let Some(found) = index
                        .get(&near)
                        .and_then(|v| v.iter().copied().find(|&k| same_pose(&p.list[k], pose)))
                    {
                        return Ok(found);
                    }
                }
            }
        }
        p.list.push(*pose);
        p.first_line.push((file.to_string(), line));
        index.entry(c).or_default().push(p.list.len() - 1);
        Ok(p.list.len() - 1)
    };
    let mut of_mode = Vec::with_capacity(data.modes.len());
    for m in &data.modes {
        of_mode.push(add(&m.pose, &data.origin, m.line)?);
    }
    let mut of_tension = Vec::with_capacity(data.tensions.len());
    let t_origin = data.tension_origin.clone().unwrap_or_default();
    for t in &data.tensions {
        of_tension.push(add(&t.pose, &t_origin, t.line)?);
    }
    p.of_mode = of_mode;
    p.of_tension = of_tension;
    Ok(p)
}

/// Fits `spec`'s parameters of `scene` to `data`.
pub fn calibrate(
    scene: &Scene,
    data: &Measurements,
    spec: &FitSpec,
    params: &CalibrationParams,
) -> Result<Calibration, CalibrationError> {
    let t0 = Instant::now();
    spec.check()?;
    let mut notes = Vec::new();
    let base = if scene.model.element == ElementKind::Auto {
        let (s, choice) = crate::estimator::resolve_auto(scene)
            .map_err(|e| CalibrationError::Model(format!("element auto: {e}")))?;
        notes.push(format!(
            "element auto resolved to {}",
            s.model.element.as_str()
        ));
        let _ = choice;
        s
    } else {
        scene.clone()
    };
    if base.model.sag {
        return Err(CalibrationError::Sagged);
    }
    let analytic = matches!(base.model.element, ElementKind::Fem | ElementKind::Massless);
    let poses = collect_poses(&base, data)?;
    if base.rigid && data.modes.iter().any(|m| m.pose.orientation_wxyz.is_none()) {
        notes.push(format!(
            "rows without an orientation are at the scene's orientation {:?}",
            base.ee_orientation_wxyz
        ));
    }
    if !data.pairing_hint_lines.is_empty() {
        notes.push(format!(
            "{} rows whose status says how identify paired them with the nominal model ({}): kept, and paired here",
            data.pairing_hint_lines.len(),
            super::data::PAIRING_STATUSES.join(" or ")
        ));
    }
    let fits_damping = spec.params.iter().any(|p| p.kind.is_damping());
    let fits_model = spec.has_stiffness_or_mass();
    let damping_rows: Vec<usize> = if fits_damping {
        (0..data.modes.len())
            .filter(|&r| data.modes[r].damping.is_some())
            .collect()
    } else {
        Vec::new()
    };
    if let Some(p) = spec.params.iter().find(|p| p.kind.is_damping()) {
        if damping_rows.is_empty() {
            return Err(CalibrationError::param(
                &p.name,
                "the data have no measured damping ratio (column damping_ratio) to fit it to",
            ));
        }
    } else if data.modes.iter().any(|m| m.damping.is_some()) {
        notes.push("measured damping ratios not used: no damping parameter fitted (modal_ratio or rayleigh)".into());
    }
    let available =
        data.modes.len() * usize::from(fits_model) + damping_rows.len() + data.tensions.len();
    if spec.params.len() > available {
        return Err(CalibrationError::Problem(format!(
            "{} parameters but only {available} measurements: fit fewer parameters or measure more",
            spec.params.len()
        )));
    }
    // Pairing at the nominal parameters.
    let x0 = spec.nominal();
    let (rules, unpaired, nominal_tasks) = pair_at(&base, spec, data, &poses, &x0, params, true)?;
    let mut left_out: Vec<LeftOutRow> = data
        .left_out
        .iter()
        .map(|l| LeftOutRow {
            line: l.line,
            reason: l.reason.clone(),
        })
        .collect();
    let mut rules = rules;
    let mut unpaired_now = unpaired;
    let mut x = x0.clone();
    let mut rounds = 0;
    let (mut iterations, mut evaluations) = (0, nominal_tasks);
    let mut converged;
    let mut starts = 0;
    let (problem_tasks, layout) = loop {
        rounds += 1;
        let (tasks, layout) = build(
            data,
            &poses,
            &rules,
            &damping_rows,
            fits_model,
            params.pairing.search_factor,
        );
        if spec.params.len() > layout.data_rows() {
            return Err(CalibrationError::Problem(format!(
                "{} parameters but only {} measurements left after pairing ({} left out): fit fewer parameters",
                spec.params.len(),
                layout.data_rows(),
                unpaired_now.len()
            )));
        }
        let mut problem = Problem::new(
            &base,
            spec,
            data,
            tasks.clone(),
            layout.clone(),
            analytic,
            params.fit.difference_step,
        );
        let lower: Vec<f64> = spec.params.iter().map(|p| p.lower).collect();
        let upper: Vec<f64> = spec.params.iter().map(|p| p.upper).collect();
        let scale = scales(spec);
        let bounds = (&lower[..], &upper[..], &scale[..]);
        let (xf, info, tried) = fit_with_restarts(&mut problem, &x, bounds, &params.fit)
            .map_err(|e| CalibrationError::Model(format!("at the nominal parameters: {e}")))?;
        iterations += info.iterations;
        evaluations += problem.evaluations;
        starts += tried;
        converged = info.converged;
        x = xf;
        let relabel = data.modes.iter().any(|m| m.label == ModeLabel::Unlabelled);
        if !relabel || rounds >= params.fit.max_pairing_rounds {
            break (tasks, layout);
        }
        let (new_rules, new_unpaired, e) = pair_at(&base, spec, data, &poses, &x, params, false)?;
        evaluations += e;
        if new_rules == rules {
            break (tasks, layout);
        }
        rules = new_rules;
        unpaired_now = new_unpaired;
    };
    for u in &unpaired_now {
        left_out.push(LeftOutRow {
            line: u.line,
            reason: u.reason.clone(),
        });
    }
    left_out.sort_by_key(|l| l.line);
    // The answer, its statistics and the residuals before and after.
    let mut problem = Problem::new(
        &base,
        spec,
        data,
        problem_tasks,
        layout.clone(),
        analytic,
        params.fit.difference_step,
    );
    let (applied_after, outs_after) = problem.eval(&x, false).map_err(CalibrationError::Model)?;
    let (r_after, j_after) = {
        use super::fit::LeastSquares;
        problem
            .residuals(&x, true)
            .map_err(CalibrationError::Model)?
    };
    let j_after = j_after.expect("asked for");
    let (applied_before, outs_before) =
        problem.eval(&x0, false).map_err(CalibrationError::Model)?;
    let (r_before, _) = problem
        .assemble(&x0, &applied_before, &outs_before, false)
        .map_err(CalibrationError::Model)?;
    evaluations += problem.evaluations;
    let nd = layout.data_rows();
    let j_data = j_after.rows(0, nd).into_owned();
    let prior: Vec<f64> = spec
        .params
        .iter()
        .map(|p| p.prior_sigma.map_or(0.0, |s| 1.0 / (s * s)))
        .collect();
    let range: Vec<f64> = spec.params.iter().map(|p| p.upper - p.lower).collect();
    let scale = scales(spec);
    let stats = statistics(&j_data, &prior, &range, &scale, &params.fit);
    let chi2: f64 = r_after.rows(0, nd).norm_squared();
    let chi2_before: f64 = r_before.rows(0, nd).norm_squared();
    let n_det = stats.determined.iter().filter(|&&d| d).count();
    let dof = nd.saturating_sub(n_det).max(1);
    let p_value = chi2_upper_tail(chi2, dof);
    let fits = p_value >= params.fit.p_min;
    let verdict = verdict(chi2 / dof as f64, p_value, fits, dof);
    let gradient = j_after.transpose() * &r_after;
    let parameters: Vec<ParameterResult> = spec
        .params
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let at_bound =
                (x[k] <= p.lower && gradient[k] > 0.0) || (x[k] >= p.upper && gradient[k] < 0.0);
            ParameterResult {
                name: p.name.clone(),
                unit: p.unit.to_string(),
                value: x[k],
                std_error: stats.std_error[k],
                determined: stats.determined[k],
                data_std_error: stats.data_std[k].is_finite().then_some(stats.data_std[k]),
                nominal: p.nominal,
                lower: p.lower,
                upper: p.upper,
                at_bound,
                prior_sigma: p.prior_sigma,
                sensitivity: sensitivity_method(p.kind, analytic).into(),
            }
        })
        .collect();
    let residuals = mode_residuals(data, &poses, &layout, &outs_before, &outs_after, &rules);
    let nm = layout.modes.len();
    let rms = |r: &nalgebra::DVector<f64>| {
        if nm == 0 {
            0.0
        } else {
            (r.rows(0, nm).norm_squared() / nm as f64).sqrt()
        }
    };
    let damping_residuals = layout
        .damping
        .iter()
        .map(|&row| {
            let m = &data.modes[row];
            let (z, s) = m.damping.expect("damping rows");
            let w = 2.0 * std::f64::consts::PI * m.frequency_hz;
            DampingResidual {
                line: m.line,
                measured: z,
                sigma: s,
                model_before: applied_before.scene.damping.modal_ratio(w),
                model_after: applied_after.scene.damping.modal_ratio(w),
            }
        })
        .collect();
    let tension_residuals = layout
        .tensions
        .iter()
        .map(|&(row, task, c)| {
            let t = &data.tensions[row];
            TensionResidual {
                line: t.line,
                cable: t.cable + 1,
                measured_n: t.tension_n,
                sigma_n: t.sigma_n,
                model_before_n: outs_before[task].tensions_n[c],
                model_after_n: outs_after[task].tensions_n[c],
            }
        })
        .collect();
    let mut sigma_sources = [0usize; 3];
    for &(row, _, _) in &layout.modes {
        sigma_sources[match data.modes[row].sigma_source {
            SigmaSource::Column => 0,
            SigmaSource::IdentifyStd => 1,
            SigmaSource::Relative => 2,
        }] += 1;
    }
    let mut unused_columns = data.unused_columns.clone();
    if let Some(o) = &data.tension_origin {
        unused_columns.extend(
            data.tension_unused_columns
                .iter()
                .map(|c| format!("{c} ({o})")),
        );
    }
    let report = Report {
        scene: base.name.clone(),
        model: format!(
            "{} × {}",
            base.model.element.as_str(),
            base.model.elements_per_cable
        ),
        data: data.origin.clone(),
        tension_data: data.tension_origin.clone(),
        poses: poses.list.len(),
        frequencies: layout.modes.len(),
        damping_ratios: layout.damping.len(),
        tensions: layout.tensions.len(),
        sigma_sources,
        undetermined: parameters
            .iter()
            .filter(|p| !p.determined)
            .map(|p| p.name.clone())
            .collect(),
        parameters,
        correlation: stats.correlation,
        singular_values: stats.singular_values,
        chi2_before,
        chi2,
        dof,
        chi2_per_dof: chi2 / dof as f64,
        chi2_per_dof_before: chi2_before / dof as f64,
        p_value,
        fits,
        verdict,
        rms_normalised_after: rms(&r_after),
        rms_normalised_before: rms(&r_before),
        residuals,
        damping_residuals,
        tension_residuals,
        left_out,
        unused_columns,
        notes,
        iterations,
        evaluations,
        pairing_rounds: rounds,
        starts,
        converged,
        seconds: t0.elapsed().as_secs_f64(),
    };
    Ok(Calibration {
        report,
        applied: apply(&base, spec, &x),
        values: x,
    })
}

/// The iteration from `x0` and, when its answer fails the χ² test, from up to
/// [`FitParams::restarts`] more starts drawn within ±[`FitParams::restart_spread`] of each
/// parameter's scale about `x0` (a fixed sequence: the same data give the same answer); the
/// answer with the least cost is kept. Returns it, the info of its iteration and the number
/// of starts tried.
fn fit_with_restarts(
    problem: &mut Problem<'_>,
    x0: &[f64],
    (lower, upper, scale): (&[f64], &[f64], &[f64]),
    params: &FitParams,
) -> Result<(Vec<f64>, super::fit::FitInfo, u32), String> {
    let rows = problem.layout.data_rows();
    let dof = rows.saturating_sub(x0.len()).max(1);
    let data_chi2 = |r: &nalgebra::DVector<f64>| r.rows(0, rows).norm_squared();
    let (mut best_x, r, _, mut best_info) =
        levenberg_marquardt(problem, x0, (lower, upper, scale), params)?;
    let mut best = r.norm_squared();
    let mut tried = 1;
    let mut rng = 0x5EED_CA11_B4A7_E5F1_u64;
    let mut uniform = || {
        // SplitMix64: a fixed, portable sequence.
        rng = rng.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = rng;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut ok = chi2_upper_tail(data_chi2(&r), dof) >= params.p_min;
    for _ in 0..params.restarts {
        if ok {
            break;
        }
        let start: Vec<f64> = (0..x0.len())
            .map(|k| {
                let u = 2.0 * uniform() - 1.0;
                (x0[k] + u * params.restart_spread * scale[k]).clamp(lower[k], upper[k])
            })
            .collect();
        tried += 1;
        let Ok((x, r, _, info)) =
            levenberg_marquardt(problem, &start, (lower, upper, scale), params)
        else {
            continue;
        };
        let c = r.norm_squared();
        if c < best {
            best = c;
            best_x = x;
            best_info = info;
            ok = chi2_upper_tail(data_chi2(&r), dof) >= params.p_min;
        }
    }
    Ok((best_x, best_info, tried))
}

/// Each parameter's scale: min(|nominal|, range), or the range for a nominal of 0.
fn scales(spec: &FitSpec) -> Vec<f64> {
    spec.params
        .iter()
        .map(|p| {
            let r = p.upper - p.lower;
            if p.nominal != 0.0 {
                p.nominal.abs().min(r)
            } else {
                r
            }
        })
        .collect()
}

fn sensitivity_method(kind: super::ParamKind, analytic: bool) -> &'static str {
    use super::ParamKind as K;
    match kind {
        K::ModalRatio | K::RayleighAlpha | K::RayleighBeta => "linear",
        K::EeCom(_) | K::PulleyRadius => "difference",
        _ if analytic => "analytic",
        _ => "difference",
    }
}

fn verdict(chi2_dof: f64, p: f64, fits: bool, dof: usize) -> String {
    if fits && p > 0.999 && dof >= 5 {
        format!("fits, with a misfit well below the stated noise (χ²/dof = {chi2_dof:.3}): σ may be overstated")
    } else if fits {
        format!("fits: the misfit is within the stated noise (χ²/dof = {chi2_dof:.3}, P(χ² larger) = {p:.3})")
    } else {
        format!(
            "does not fit: the misfit is {:.1}× the stated noise (χ²/dof = {chi2_dof:.3}, P(χ² larger) = {p:.1e}): the model lacks something the robot has, or σ is understated",
            chi2_dof.sqrt()
        )
    }
}

/// The rules of the rows (None: left out), the rows left out and the model evaluations
/// spent.
type Pairs = (Vec<Option<Rule>>, Vec<Unpaired>, u32);

/// Pairs every row at parameters `x`: the rules (None: left out), the unpaired rows and the
/// number of model evaluations spent. A pose the model cannot solve is an error naming the
/// data line (at the nominal parameters) or a model error.
fn pair_at(
    base: &Scene,
    spec: &FitSpec,
    data: &Measurements,
    poses: &Poses,
    x: &[f64],
    params: &CalibrationParams,
    nominal: bool,
) -> Result<Pairs, CalibrationError> {
    // Each pose: the rules of its labelled rows, and the band of its unlabelled ones.
    let mut tasks: Vec<PoseTask> = poses
        .list
        .iter()
        .map(|p| PoseTask::new(*p, Vec::new()))
        .collect();
    for (r, m) in data.modes.iter().enumerate() {
        let t = &mut tasks[poses.of_mode[r]];
        t.max_hz = t.max_hz.max(params.pairing.search_factor * m.frequency_hz);
        match m.label {
            ModeLabel::Order(k) => t.rules.push(Rule::Order(k)),
            ModeLabel::Ee(k) => t.rules.push(Rule::Ee(k)),
            ModeLabel::Unlabelled => {
                t.band_hz = t.band_hz.max(params.pairing.band_factor * m.frequency_hz)
            }
        }
    }
    for (r, t) in data.tensions.iter().enumerate() {
        let task = &mut tasks[poses.of_tension[r]];
        if !task.cables.contains(&t.cable) {
            task.cables.push(t.cable);
        }
    }
    let mut problem = Problem::new(
        base,
        spec,
        data,
        tasks,
        Layout::default(),
        false,
        params.fit.difference_step,
    );
    let outs: Vec<PoseOut> = match problem.eval(x, false) {
        Ok((_, o)) => o,
        Err(e) if nominal => {
            // Name the first data line at the failing pose.
            let k = (0..poses.list.len())
                .find(|&k| {
                    let mut one = Problem::new(
                        base,
                        spec,
                        data,
                        vec![problem.tasks[k].clone()],
                        Layout::default(),
                        false,
                        0.0,
                    );
                    one.eval(x, false).is_err()
                })
                .unwrap_or(0);
            let (file, line) = &poses.first_line[k];
            let p = poses.list[k].position_m;
            return Err(CalibrationError::Row {
                file: file.clone(),
                line: *line,
                message: format!(
                    "the nominal model has no answer at the pose ({}, {}, {}) m: {}",
                    p.x,
                    p.y,
                    p.z,
                    e.split_once(": ").map_or(e.as_str(), |(_, r)| r)
                ),
            });
        }
        Err(e) => return Err(CalibrationError::Model(e)),
    };
    let threshold = base.model.ee_participation_min;
    let (rules, unpaired) = pair(
        &data.modes,
        &poses.of_mode,
        &outs,
        threshold,
        &params.pairing,
    );
    Ok((rules, unpaired, problem.evaluations))
}

/// The fit's tasks and rows for the rules: one task per pose with the distinct rules of its
/// rows and its measured cables.
fn build(
    data: &Measurements,
    poses: &Poses,
    rules: &[Option<Rule>],
    damping_rows: &[usize],
    fits_model: bool,
    search_factor: f64,
) -> (Vec<PoseTask>, Layout) {
    let mut tasks: Vec<PoseTask> = poses
        .list
        .iter()
        .map(|p| PoseTask::new(*p, Vec::new()))
        .collect();
    let mut layout = Layout::default();
    for (r, rule) in rules.iter().enumerate() {
        let Some(rule) = rule else { continue };
        let k = poses.of_mode[r];
        let t = &mut tasks[k];
        t.max_hz = t.max_hz.max(search_factor * data.modes[r].frequency_hz);
        let i = match t.rules.iter().position(|q| q == rule) {
            Some(i) => i,
            None => {
                t.rules.push(*rule);
                t.rules.len() - 1
            }
        };
        if fits_model {
            layout.modes.push((r, k, i));
        }
    }
    layout.damping = damping_rows
        .iter()
        .copied()
        .filter(|&r| rules[r].is_some())
        .collect();
    for (r, tr) in data.tensions.iter().enumerate() {
        let k = poses.of_tension[r];
        let t = &mut tasks[k];
        let c = match t.cables.iter().position(|&c| c == tr.cable) {
            Some(c) => c,
            None => {
                t.cables.push(tr.cable);
                t.cables.len() - 1
            }
        };
        layout.tensions.push((r, k, c));
    }
    (tasks, layout)
}

/// Each paired frequency row before and after.
fn mode_residuals(
    data: &Measurements,
    poses: &Poses,
    layout: &Layout,
    before: &[PoseOut],
    after: &[PoseOut],
    rules: &[Option<Rule>],
) -> Vec<ModeResidual> {
    layout
        .modes
        .iter()
        .map(|&(row, task, rule)| {
            let m = &data.modes[row];
            let pb = before[task].picked[rule].as_ref();
            let pa = after[task].picked[rule].as_ref();
            let fb = pb.map_or(f64::NAN, |p| lambda_to_hz(p.lambda));
            let fa = pa.map_or(f64::NAN, |p| lambda_to_hz(p.lambda));
            let how = if m.label == ModeLabel::Unlabelled {
                "by frequency"
            } else {
                "given"
            };
            let rule_text = rules[row].map_or("-".to_string(), |r| r.to_string());
            let p = poses.list[poses.of_mode[row]].position_m;
            ModeResidual {
                line: m.line,
                pose: poses.of_mode[row],
                position_m: [p.x, p.y, p.z],
                pairing: format!("{rule_text} ({how})"),
                model_mode_hint: m.model_mode_hint,
                measured_hz: m.frequency_hz,
                sigma_hz: m.sigma_hz,
                model_before_hz: fb,
                model_after_hz: fa,
                normalised_before: (fb - m.frequency_hz) / m.sigma_hz,
                normalised_after: (fa - m.frequency_hz) / m.sigma_hz,
                model_mode_after: pa.map_or(0, |p| p.order),
                multiplicity: pa.map_or(0, |p| p.multiplicity),
                participation_after: pa.map_or(f64::NAN, |p| p.participation),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// A pose written with identify's 11 significant digits is the full-precision one; poses
    /// 2 µm apart, or with and without an orientation, are not.
    #[test]
    fn poses_rounded_by_a_writer_are_one_pose() {
        let full = MeasuredPose {
            position_m: Vector3::new(0.585_067_598_523_7, -0.090_383_794_821_49, 0.814_678),
            orientation_wxyz: None,
            t_min_n: None,
        };
        let rounded = |v: f64| format!("{v:.10e}").parse::<f64>().unwrap();
        let written = MeasuredPose {
            position_m: full.position_m.map(rounded),
            ..full
        };
        assert_ne!(written.position_m, full.position_m);
        assert!(same_pose(&full, &written));
        let d = (pose_cell(&full)[0] - pose_cell(&written)[0]).abs();
        assert!(d <= 1, "neighbouring cells at most");
        let apart = MeasuredPose {
            position_m: full.position_m + Vector3::new(2e-6, 0.0, 0.0),
            ..full
        };
        assert!(!same_pose(&full, &apart));
        let turned = MeasuredPose {
            orientation_wxyz: Some([1.0, 0.0, 0.0, 0.0]),
            ..full
        };
        assert!(!same_pose(&full, &turned));
    }
}
