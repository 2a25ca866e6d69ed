//! `cablevib analyze`: tensions and natural frequencies of one pose
//! ([`crate::study::analysis::analyze`]: the structured engine by default, `--solver dense`
//! for the dense reference, `--compare-dense` for both), or what the real-time path
//! computes (`--realtime`).

use super::args::{resolve_scene, SceneArgs};
use super::{json_f64, CliError};
use crate::estimator::{BuildError, Estimator, Status, Tmin};
use crate::kinematics::Pose;
use crate::scene::{ElementKind, Scene};
use crate::study::analysis::{
    analyze, assembled_matrices, AnalysisReport, AnalyzeOptions, SolverChoice,
};
use cablevib::outln;
use clap::Args;
use nalgebra::Vector3;
use std::time::Instant;

/// `cablevib analyze`.
#[derive(Debug, Args)]
pub struct AnalyzeArgs {
    /// Scene and overrides.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Number of natural frequencies to print (every model, continuous included; the model
    /// may have fewer).
    #[arg(long, default_value_t = 10)]
    pub modes: usize,
    /// Eigensolver: `structured` (Wittrick-Williams count and Newton on the 3 × 3 or 6 × 6
    /// condensed problem, O(1) in the element count) or `dense` (assembled K and M and a
    /// dense eigensolver, Clarabel tensions; refused above 2 GiB of estimated memory).
    #[arg(long, default_value = "structured", value_parser = parse_solver)]
    pub solver: SolverChoice,
    /// Also solve the same models densely in this process: print both times (the structured
    /// one the median of repeats), their ratio and the largest relative difference of the
    /// eigenvalues next to the dense solver's bound ε·λ_max/λ.
    #[arg(long)]
    pub compare_dense: bool,
    /// Also write the assembled stiffness K (N/m) and mass M (kg) of the structured path's
    /// models to PREFIX.K.mtx and PREFIX.M.mtx (Matrix Market, symmetric, every f64 digit;
    /// DOF order: end-effector first, then each cable's interior nodes from the anchor).
    #[arg(long, value_name = "PREFIX")]
    pub export_matrices: Option<std::path::PathBuf>,
    /// Also write the mode shapes of the first `--modes` modes (clusters completed) to
    /// FILE.csv and its FILE.csv.json sidecar: the columns of `cablevib modes --csv`
    /// (mass-normalised node displacements, 1/√kg). Not with --realtime.
    #[arg(long, value_name = "FILE.csv", conflicts_with = "realtime")]
    pub shapes: Option<std::path::PathBuf>,
    /// One JSON object on stdout instead of tables.
    #[arg(long)]
    pub json: bool,
    /// Print what the real-time path computes in one cold cycle with the service's parameters
    /// (f1, end-effector mode, tensions, status; the end-effector mode may be left for the
    /// next cycles by the per-cycle budget). A pose the estimator refuses (e.g. outside the
    /// workspace) is still printed with its status, then the command exits with code 1
    /// naming that status.
    #[arg(long)]
    pub realtime: bool,
}

/// `cablevib analyze`.
pub fn run(a: &AnalyzeArgs) -> Result<(), CliError> {
    let s = resolve_scene(&a.scene)?;
    let pos = s.ee_position_m;
    let s = if s.model.element == ElementKind::Auto {
        let resolved = match crate::estimator::resolve_auto(&s) {
            Err(BuildError::DefaultPose { .. }) if a.realtime && a.scene.position.is_some() => {
                // --position is not the scene's own pose: the auto model is chosen where the
                // service would choose it, and the requested pose gets its status below.
                crate::estimator::resolve_auto(&at_own_default_pose(a, &s)?)
                    .map(|(r, c)| (at_position(&r, pos), c))
            }
            r => r,
        };
        let (resolved, choice) = resolved.map_err(|e| CliError::Analysis(e.to_string()))?;
        if !a.json {
            outln!("{choice}")?;
        }
        resolved
    } else {
        s
    };
    if a.realtime {
        return analyze_realtime(a, &s);
    }
    let opts = AnalyzeOptions {
        modes: a.modes,
        solver: a.solver,
        compare_dense: a.compare_dense,
    };
    let r = analyze(&s, &opts)?;
    if let Some(prefix) = &a.export_matrices {
        export_matrices(&s, prefix)?;
    }
    if let Some(path) = &a.shapes {
        write_shapes(&s, a.modes, path)?;
    }
    if a.json {
        let o = serde_json::to_string(&r).map_err(|e| CliError::Analysis(e.to_string()))?;
        outln!("{o}")?;
    } else {
        print_report(&r)?;
    }
    super::args::warn_if_sag_matters(&s, None);
    Ok(())
}

/// The shapes of the first `modes` modes of `s` at its pose (the `cablevib modes` pipeline)
/// as a CSV with its sidecar.
fn write_shapes(s: &Scene, modes: usize, path: &std::path::Path) -> Result<(), CliError> {
    use crate::report::csv::{process_command_line, write_csv};
    let pose = super::modes::pose_model(s)?;
    let params = crate::modal::ShapeParams::default();
    let shapes = super::modes::shapes(&pose, modes, &params, true)?;
    let csv =
        crate::report::shapes_csv::shapes_csv(&pose.scene, &pose.geometry, &shapes, Some("CSV"));
    Ok(write_csv(path, csv, &process_command_line())?)
}

/// The files of `--export-matrices PREFIX`: PREFIX.K.mtx and PREFIX.M.mtx.
pub fn matrix_paths(prefix: &std::path::Path) -> [std::path::PathBuf; 2] {
    ["K", "M"].map(|name| {
        let mut path = prefix.as_os_str().to_owned();
        path.push(format!(".{name}.mtx"));
        path.into()
    })
}

/// K and M of the structured path's models as PREFIX.K.mtx and PREFIX.M.mtx.
fn export_matrices(s: &Scene, prefix: &std::path::Path) -> Result<(), CliError> {
    let (k, m) = assembled_matrices(s)?;
    for (path, a) in matrix_paths(prefix).iter().zip([&k, &m]) {
        let text = matrix_market(a);
        crate::output_file::write_whole(path, text.as_bytes())
            .map_err(|e| CliError::Analysis(format!("--export-matrices {e}")))?;
    }
    Ok(())
}

/// The lower triangle of a symmetric matrix in Matrix Market coordinate format, with
/// shortest round-trip f64 values.
fn matrix_market(a: &nalgebra::DMatrix<f64>) -> String {
    use std::fmt::Write;
    let mut entries = String::new();
    let mut nnz = 0usize;
    for j in 0..a.ncols() {
        for i in j..a.nrows() {
            let v = a[(i, j)];
            if v != 0.0 {
                nnz += 1;
                let _ = writeln!(entries, "{} {} {v:?}", i + 1, j + 1);
            }
        }
    }
    format!(
        "%%MatrixMarket matrix coordinate real symmetric\n{} {} {nnz}\n{entries}",
        a.nrows(),
        a.ncols()
    )
}

/// `structured` or `dense`.
fn parse_solver(s: &str) -> Result<SolverChoice, String> {
    match s {
        "structured" => Ok(SolverChoice::Structured),
        "dense" => Ok(SolverChoice::Dense),
        _ => Err(format!("`{s}`: expected structured or dense")),
    }
}

/// The report as tables.
fn print_report(r: &AnalysisReport) -> Result<(), CliError> {
    let p = r.position_m;
    let dof = r
        .dof
        .map_or("continuous".to_string(), |d| format!("{d} DOF"));
    outln!(
        "scene {}  position ({:.4}, {:.4}, {:.4}) m  T_min {}  model {} × {} elements/cable  ({dof}, {} solve {:.3} ms)",
        r.scene, p[0], p[1], p[2], r.t_min_label, r.element, r.elements_per_cable, r.solver,
        r.solve_seconds * 1e3
    )?;
    if r.stiffness_n_m.len() == 6 {
        // A rigid end-effector: its orientation is part of the pose.
        let q = r.orientation_wxyz;
        outln!(
            "orientation (w, x, y, z) ({}, {}, {}, {})",
            q[0],
            q[1],
            q[2],
            q[3]
        )?;
    }
    outln!("\n cable   tension (N)")?;
    for (i, t) in r.tensions_n.iter().enumerate() {
        outln!(" {:>5}   {:>11.4}", i + 1, t)?;
    }
    outln!("\n mode   frequency (Hz)   end-effector participation   multiplicity")?;
    for (i, (fi, pi)) in r.frequencies_hz.iter().zip(&r.ee_participation).enumerate() {
        let m = r
            .multiplicity
            .as_ref()
            .map_or(String::new(), |m| m[i].to_string());
        outln!(" {:>4}   {:>14.9}   {:>26.6}   {:>12}", i + 1, fi, pi, m)?;
    }
    if let Some(c) = &r.compare_dense {
        outln!(
            "\nstructured {:.3} ms (median), dense {:.3} ms on the same models: ratio {:.0}×; \
             largest relative difference of λ {:.2e} (dense bound ε·λ_max/λ there {:.2e}), of \
             cluster participations {:.2e}",
            c.structured_seconds * 1e3,
            c.dense_seconds * 1e3,
            c.speedup,
            c.max_rel_diff_lambda,
            c.dense_bound_there,
            c.max_abs_diff_cluster_participation
        )?;
    }
    Ok(())
}

/// The scene with `position` as its end-effector position.
fn at_position(s: &Scene, position: Vector3<f64>) -> Scene {
    let mut s = s.clone();
    s.ee_position_m = position;
    s
}

/// `s` moved back to the end-effector position of its scene file (before --position).
fn at_own_default_pose(a: &AnalyzeArgs, s: &Scene) -> Result<Scene, CliError> {
    Ok(at_position(s, Scene::load(&a.scene.scene)?.ee_position_m))
}

/// The real-time estimator of `s` at `s.ee_position_m`, with the service's parameters
/// ([`Estimator::realtime`]: `EstimatorParams::realtime()`, its per-cycle evaluation
/// budget). A --position the estimator cannot be built at is not the scene's fault: the
/// estimator is then built at the scene's own pose, as the service builds it, and the
/// requested pose is estimated like any other (its status, e.g. `outside_workspace`, names
/// the real cause).
fn realtime_estimator(a: &AnalyzeArgs, s: &Scene) -> Result<Estimator, CliError> {
    match Estimator::realtime(s) {
        Err(BuildError::DefaultPose { .. }) if a.scene.position.is_some() => {
            Estimator::realtime(&at_own_default_pose(a, s)?)
        }
        r => r,
    }
    .map_err(|e| CliError::Analysis(e.to_string()))
}

/// The published static stiffness as JSON rows: 3 × 3 (N/m) for a point mass, 6 × 6 for a
/// rigid end-effector (N/m, N/rad, N·m/m, N·m/rad blocks; see `AnalysisReport`).
fn stiffness_rows(e: &crate::estimator::Estimate) -> Vec<Vec<serde_json::Value>> {
    let d = e.stiffness.dim;
    (0..d)
        .map(|r| (0..d).map(|c| json_f64(e.stiffness.k6[(r, c)])).collect())
        .collect()
}

fn analyze_realtime(a: &AnalyzeArgs, s: &Scene) -> Result<(), CliError> {
    let mut est = realtime_estimator(a, s)?;
    let t0 = Instant::now();
    let e = *est.update(&Pose::in_scene(s, s.ee_position_m), Tmin::Scene);
    let ns = t0.elapsed().as_nanos();
    // Absent: null in JSON, NaN in the text.
    let ee_hz = e.ee_mode.map_or(f64::NAN, |m| m.frequency_hz);
    let ee_p = e.ee_mode.map_or(f64::NAN, |m| m.participation);
    if a.json {
        let o = serde_json::json!({
            "scene": s.name,
            "status": e.status.as_str(),
            "error": e.error.map(|x| x.to_string()),
            "tensions_n": e.tensions().iter().map(|&x| json_f64(x)).collect::<Vec<_>>(),
            "f1_hz": json_f64(e.f1_hz),
            "f1_ee_participation": json_f64(e.f1_ee_participation),
            "ee_mode_hz": json_f64(ee_hz),
            "ee_mode_participation": json_f64(ee_p),
            "ee_mode_age_cycles": e.ee_mode.map(|m| m.age_cycles),
            "orientation_wxyz": s.ee_orientation_wxyz,
            "stiffness_n_m": stiffness_rows(&e),
            "element": s.model.element.as_str(),
            "elements_per_cable": s.model.elements_per_cable,
            "eigen_evaluations": e.eigen_evaluations,
            "eigen_residual": json_f64(e.eigen_residual),
            "solver": "realtime",
            "compute_ns": ns as u64,
        });
        outln!("{o}")?;
    } else {
        outln!(
            "scene {}  model {} × {}  status {}",
            s.name,
            s.model.element.as_str(),
            s.model.elements_per_cable,
            e.status.as_str()
        )?;
        if let Some(err) = e.error {
            outln!("  reason: {err}")?;
        }
        for (i, t) in e.tensions().iter().enumerate() {
            outln!("  cable {:>2}: {t:>11.4} N", i + 1)?;
        }
        outln!(
            "  f1            {:.9} Hz (end-effector participation {:.3e})",
            e.f1_hz,
            e.f1_ee_participation
        )?;
        outln!(
            "  end-effector  {:.9} Hz (participation {:.4})",
            ee_hz,
            ee_p
        )?;
        outln!(
            "  {} evaluations of D(λ), {:.1} µs (first cycle, cold)",
            e.eigen_evaluations,
            ns as f64 / 1e3
        )?;
    }
    if e.status != Status::Ok {
        return Err(CliError::Analysis(format!(
            "status {}: {}",
            e.status.as_str(),
            e.error.map(|x| x.to_string()).unwrap_or_default()
        )));
    }
    Ok(())
}
