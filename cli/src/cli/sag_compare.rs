//! `cablevib sag-compare`: the chord model (sag off) and the sagged model (sag on) of one
//! scene along a line through its pose ([`crate::study::sag_compare`]), as a CSV with its
//! sidecar and a four-panel figure ([`crate::report::sag_compare`]).

use super::args::{parse_interval, resolve_scene, SceneArgs};
use super::figure::{self, parse_format};
use super::{output_paths, CliError};
use crate::report::csv::{process_command_line, write_csv};
use crate::report::figure::FigureFormat;
use crate::report::sag_compare::{sag_compare_csv, sag_compare_svg, statuses};
use crate::scene::ElementKind;
use crate::study::map::Interval;
use crate::study::sag_compare::{self as study, SagCompare, SagCompareConfig};
use cablevib::outln;
use clap::{Args, ValueEnum};
use std::path::PathBuf;
use std::time::Instant;

/// The world axis of the line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LineAxis {
    /// Along x.
    X,
    /// Along y.
    Y,
    /// Along z (give --span-m when the anchors all sit at one height).
    Z,
}

/// `cablevib sag-compare`.
#[derive(Debug, Args, Clone)]
pub struct SagCompareArgs {
    /// Scene and overrides (`--position` moves the line's centre; `--element fem|continuous`
    /// and `--elements` set both models; `--sag` is refused: both models are evaluated).
    #[command(flatten)]
    pub scene: SceneArgs,
    /// World axis of the line through the scene's position.
    #[arg(long, value_enum, default_value = "x")]
    pub axis: LineAxis,
    /// Offsets A,B from the scene's position along the axis, m, each within ±1e6 m
    /// (default: the central 80 % of the anchors' extent along the axis).
    #[arg(long, value_parser = parse_interval, allow_hyphen_values = true, value_name = "A,B")]
    pub span_m: Option<Interval>,
    /// Poses on the line, ends included (2 ..= 10000); each is solved twice.
    #[arg(long, default_value_t = 41)]
    pub points: usize,
    /// Output prefix: writes PREFIX.csv, its metadata PREFIX.csv.json and PREFIX.svg.
    #[arg(long, default_value = "sag-compare")]
    pub out: PathBuf,
    /// Write the figure here instead of PREFIX.svg (PREFIX.png, PREFIX.pdf with --format).
    #[arg(long, visible_alias = "figure")]
    pub svg: Option<PathBuf>,
    /// Figure format: svg, png (3 px per SVG px) or pdf (vector, font embedded). Default:
    /// the figure path's extension, else svg; --format wins and sets the file's extension.
    #[arg(long, value_parser = parse_format)]
    pub format: Option<FigureFormat>,
    /// Worker threads (0: one per core). Any count gives the same numbers, bit for bit.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// No progress bar (it is shown only on a terminal, after a second).
    #[arg(long)]
    pub quiet: bool,
}

impl SagCompareArgs {
    /// The study configuration of these options.
    pub fn config(&self) -> SagCompareConfig {
        SagCompareConfig {
            axis: self.axis as usize,
            span_m: self.span_m,
            points: self.points,
            threads: self.threads,
            progress: !self.quiet,
        }
    }
}

/// `cablevib sag-compare`: writes PREFIX.csv, PREFIX.csv.json and the figure.
pub fn run(a: &SagCompareArgs) -> Result<(), CliError> {
    if a.scene.effects.sag.is_some() {
        return Err(CliError::Usage(
            "--sag: sag-compare evaluates both models (sag false and sag true)".into(),
        ));
    }
    // Resolved with sag on: the element must be one the sagged model has.
    let mut args = a.scene.clone();
    args.effects.sag = Some(true);
    let s = resolve_scene(&args)?;
    if s.model.element == ElementKind::Auto {
        return Err(CliError::Usage(
            "element auto picks a model per scene: give --element fem or --element continuous"
                .into(),
        ));
    }
    let t0 = Instant::now();
    let r = study::compute(&s, &a.config())?;
    let secs = t0.elapsed().as_secs_f64();
    let (csv_path, fig_path, fmt) = output_paths(&a.out, &a.svg, a.format)?;
    write_csv(&csv_path, sag_compare_csv(&s, &r), &process_command_line())?;
    figure::write(&fig_path, &sag_compare_svg(&s, &r), fmt)?;
    print_summary(&s.name, &r, secs)?;
    outln!("  wrote {} and {}", csv_path.display(), fig_path.display())?;
    Ok(())
}

/// Statuses and the ranges of f1 and k_min of both models.
fn print_summary(scene: &str, r: &SagCompare, secs: f64) -> Result<(), CliError> {
    outln!(
        "sag-compare: scene {scene}  {} poses along {} (offsets {} .. {} m) × 2 models in {secs:.2} s ({} threads)",
        r.points.len(),
        r.axis_name(),
        r.span_m.lo,
        r.span_m.hi,
        r.threads
    )?;
    for (name, pick) in [
        (
            "chord ",
            (|q| &q.chord) as fn(&study::ComparePoint) -> &study::ModelPoint,
        ),
        ("sagged", |q| &q.sag),
    ] {
        let range = |f: fn(&study::ModelPoint) -> f64| {
            let v = r.points.iter().map(pick).filter(|m| m.is_ok()).map(f);
            let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
            format!("{lo:.4} .. {hi:.4}")
        };
        outln!(
            "  {name}: f1 {} Hz  k_min {} N/m  largest tension {} N  statuses: {}",
            range(|m| m.f1_hz),
            range(|m| m.stiffness_min_n_m),
            range(study::ModelPoint::tension_max_n),
            statuses(r, pick).summary()
        )?;
    }
    Ok(())
}
