//! `cablevib modes`: the lowest natural frequencies of one pose with their mode shapes,
//! from the structured solver (eigenvalues from the spectrum engine, shapes from the
//! chains' closed forms; see [`crate::modal::ModeShapes`]), as a table, a CSV
//! ([`crate::report::shapes_csv`]) and an SVG ([`crate::report::svg::modes`]).

use super::args::{resolve_scene, SceneArgs};
use super::figure::{self, parse_format};
use super::CliError;
pub use crate::estimator::PoseModel;
use crate::modal::{ModeShapes, ShapeParams};
use crate::report::csv::{process_command_line, write_csv};
use crate::report::figure::FigureFormat;
use crate::report::shapes_csv::shapes_csv;
use crate::report::svg::modes::modes_svg;
use crate::scene::Scene;
use crate::study;
use cablevib::outln;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// Most modes the command computes.
const MAX_MODES: usize = 1000;

/// `cablevib modes`.
#[derive(Debug, Args)]
pub struct ModesArgs {
    /// Scene and overrides.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Number of modes (lowest first; a cluster cut by the limit is completed), 1..=1000.
    #[arg(long, default_value_t = 6)]
    pub modes: usize,
    /// Points at which a continuous cable is sampled (anchor and end included), 2..=10001.
    #[arg(long, default_value_t = 41)]
    pub samples: usize,
    /// Write the mode shapes as CSV (mass-normalised, 1/√kg).
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Write the mode shapes as a figure (axonometric view, one panel per mode): SVG, or
    /// PNG / PDF by the extension or --format.
    #[arg(long, visible_alias = "figure")]
    pub svg: Option<PathBuf>,
    /// Figure format: svg, png (3 px per SVG px) or pdf (vector, font embedded). Default:
    /// the figure path's extension, else svg; --format wins and sets the file's extension.
    #[arg(long, value_parser = parse_format)]
    pub format: Option<FigureFormat>,
}

/// The model of `scene` at its own pose ([`PoseModel::new`]: Clarabel tensions, the
/// scene's lower bounds).
pub fn pose_model(scene: &Scene) -> Result<PoseModel, CliError> {
    PoseModel::new(scene).map_err(|e| CliError::Analysis(e.to_string()))
}

/// The lowest `k` modes' shapes of `pose` (clusters completed) from the structured solver
/// ([`study::cost::mode_shapes`]: refused past the memory budget, counting the CSV text when
/// `csv`; an estimate of a long run on stderr and a progress bar on a terminal).
pub fn shapes(
    pose: &PoseModel,
    k: usize,
    params: &ShapeParams,
    csv: bool,
) -> Result<ModeShapes, CliError> {
    let work = study::cost::Work::Modes {
        modes: k,
        continuous_samples: params.continuous_samples,
        csv,
    };
    announce(&study::cost::estimate_cost(&pose.scene, &work))?;
    Ok(study::cost::mode_shapes(
        pose,
        k,
        params,
        csv,
        Some("mode shapes"),
    )?)
}

/// A study's estimate: refused past the memory budget, else a long one announced on stderr
/// ([`study::cost::WorkEstimate::announcement`]).
pub fn announce(e: &study::cost::WorkEstimate) -> Result<(), CliError> {
    e.check_memory().map_err(study::StudyError::from)?;
    if let Some(line) = e.announcement() {
        eprintln!("cablevib: {line}");
    }
    Ok(())
}

/// `cablevib modes`.
pub fn run(a: &ModesArgs) -> Result<(), CliError> {
    if !(1..=MAX_MODES).contains(&a.modes) {
        return Err(CliError::Usage(format!(
            "--modes {}: must be in 1..={MAX_MODES}",
            a.modes
        )));
    }
    let params = ShapeParams {
        continuous_samples: a.samples,
        ..ShapeParams::default()
    };
    params
        .check()
        .map_err(|e| CliError::Usage(format!("--samples {}: {e}", a.samples)))?;
    let s = resolve_scene(&a.scene)?;
    let pose = pose_model(&s)?;
    let t0 = Instant::now();
    let shapes = shapes(&pose, a.modes, &params, a.csv.is_some())?;
    let secs = t0.elapsed().as_secs_f64();
    let sc = &pose.scene;
    let p = sc.ee_position_m;
    outln!(
        "scene {}  position ({:.4}, {:.4}, {:.4}) m  T_min {}  model {} × {}  ({} modes with shapes in {:.1} ms)",
        sc.name,
        p.x,
        p.y,
        p.z,
        sc.t_min_label(),
        sc.model.element.as_str(),
        sc.model.elements_per_cable,
        shapes.modes.len(),
        secs * 1e3
    )?;
    outln!("\n mode   frequency (Hz)   multiplicity   end-effector participation")?;
    for (i, m) in shapes.modes.iter().enumerate() {
        outln!(
            " {:>4}   {:>14.6}   {:>12}   {:>8.4}",
            i + 1,
            m.frequency_hz,
            m.multiplicity,
            m.ee_participation
        )?;
    }
    if let Some(path) = &a.csv {
        write_csv(
            path,
            shapes_csv(sc, &pose.geometry, &shapes, Some("CSV")),
            &process_command_line(),
        )?;
        outln!("\nwrote {}", path.display())?;
    }
    figure::format_needs_svg(&a.svg, a.format)?;
    if let Some(path) = &a.svg {
        let (path, fmt) = figure::target(path, a.format)?;
        let k = a.modes.min(shapes.modes.len());
        figure::write(&path, &modes_svg(sc, &pose.geometry, &shapes, k), fmt)?;
        outln!("wrote {}", path.display())?;
    }
    Ok(())
}
