//! `cablevib sweep-tmin`: f1 against T_min at one pose with the √T_min fit, as a CSV and
//! a figure.

use super::args::{parse_pairs, resolve_scene, Pairs, SceneArgs};
use super::figure::{self, parse_format};
use super::{output_paths, CliError};
use crate::report::csv::{process_command_line, write_csv};
use crate::report::figure::FigureFormat;
use crate::report::tmin::{tmin_csv, tmin_svg, Compared};
use crate::study::tmin::{self as study, TminConfig};
use cablevib::outln;
use clap::Args;
use std::path::PathBuf;

/// Two compared T_min values within this many N are the same.
const SAME_TMIN_N: f64 = 1e-9;

/// `cablevib sweep-tmin`: f1 against T_min at one pose, with the fitted a·√T_min.
#[derive(Debug, Args, Clone)]
pub struct SweepTminArgs {
    /// Scene and overrides (`--position` sets the pose).
    #[command(flatten)]
    pub scene: SceneArgs,
    /// First T_min, N (default: the scene's T_min).
    #[arg(long)]
    pub from: Option<f64>,
    /// Last T_min, N (default: twice the first, at most T_max).
    #[arg(long)]
    pub to: Option<f64>,
    /// Number of T_min values (evenly spaced, both ends included).
    #[arg(long, default_value_t = 25)]
    pub steps: usize,
    /// Modes per T_min in the CSV: columns f1_hz (as before) and f2_hz .. fK_hz, Hz
    /// (1 ..= 16).
    #[arg(long, default_value_t = 1)]
    pub modes: usize,
    /// Output prefix: writes PREFIX.csv, its metadata PREFIX.csv.json and PREFIX.svg.
    #[arg(long, default_value = "sweep-tmin")]
    pub out: PathBuf,
    /// Write the figure here instead of PREFIX.svg (PREFIX.png, PREFIX.pdf with --format).
    #[arg(long, visible_alias = "figure")]
    pub svg: Option<PathBuf>,
    /// Figure format: svg, png (3 px per SVG px) or pdf (vector, font embedded). Default:
    /// the figure path's extension, else svg; --format wins and sets the file's extension.
    #[arg(long, value_parser = parse_format)]
    pub format: Option<FigureFormat>,
    /// Skip the end-effector mode (f1 only).
    #[arg(long)]
    pub no_ee_mode: bool,
    /// Points to overlay for comparison, T_MIN:HZ pairs separated by commas
    /// (e.g. a paper's printed values).
    #[arg(long, value_parser = parse_pairs)]
    pub compare: Option<Pairs>,
    /// Legend text of the --compare points.
    #[arg(long, default_value = "compared")]
    pub compare_label: String,
}

/// `cablevib sweep-tmin`: writes PREFIX.csv, PREFIX.csv.json and PREFIX.svg.
pub fn run(a: &SweepTminArgs) -> Result<(), CliError> {
    let s = resolve_scene(&a.scene)?;
    let from = a.from.unwrap_or(s.t_min_n);
    let to = a.to.unwrap_or((2.0 * from).min(s.t_max_n));
    let cfg = TminConfig {
        from_n: from,
        to_n: to,
        steps: a.steps,
        ee_mode: !a.no_ee_mode,
        modes: a.modes,
    };
    let r = study::compute(&s, &cfg)?;
    let (csv_path, svg_path, fmt) = output_paths(&a.out, &a.svg, a.format)?;
    write_csv(&csv_path, tmin_csv(&s, &r), &process_command_line())?;
    let compare = a.compare.as_ref().map(|c| Compared {
        label: &a.compare_label,
        points: &c.0,
    });
    if let Some(c) = &a.compare {
        for &(t, f) in &c.0 {
            let ours = r
                .points
                .iter()
                .find(|p| (p.t_min_n - t).abs() < SAME_TMIN_N && p.estimate.is_ok())
                .map(|p| p.estimate.f1_hz);
            if let Some(o) = ours {
                outln!(
                    "  T_min {t} N: {} {f} Hz, estimator {o:.6} Hz, ratio {:.6}",
                    a.compare_label,
                    f / o
                )?;
            }
        }
    }
    let svg = tmin_svg(&s, &r, (from, to), cfg.ee_mode, compare);
    figure::write(&svg_path, &svg, fmt)?;
    outln!(
        "sweep-tmin: scene {}  T_min {from}..{to} N ({} values)  fit f1 = {:.6}·sqrt(T_min) Hz, max relative deviation {:.2e}  statuses: {}",
        s.name,
        a.steps,
        r.a,
        r.max_rel_residual,
        crate::study::points::status_histogram(&r.points).summary()
    )?;
    outln!("  wrote {} and {}", csv_path.display(), svg_path.display())?;
    Ok(())
}
