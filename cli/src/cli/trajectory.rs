//! `cablevib trajectory`: f1 and the end-effector mode along the paper's circle or a CSV
//! path, as a CSV and a figure.

use super::args::{resolve_scene, SceneArgs};
use super::figure::{self, parse_format};
use super::{output_paths, CliError};
use crate::report::csv::process_command_line;
use crate::report::figure::FigureFormat;
use crate::report::trajectory::{trajectory_svg, TrajectoryCsv};
use crate::study::trajectory::{self as study, PathSource, TrajectoryConfig};
use crate::trajectory::CIRCLE_RADIUS_M;
use cablevib::outln;
use cablevib::status::StatusCode;
use clap::Args;
use std::path::PathBuf;

/// `cablevib trajectory`: f1 and the end-effector mode along a trajectory.
#[derive(Debug, Args, Clone)]
pub struct TrajectoryArgs {
    /// Scene and overrides.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Trajectory CSV with columns t,x,y,z or t,x,y,z,qw,qx,qy,qz (s, m, unit quaternion;
    /// `#` comments and a header line are skipped). Without quaternion columns every pose
    /// takes the scene's orientation (or --orientation); a point-mass scene ignores them
    /// with a warning. Default: the paper's circle around the scene's position.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Comma-separated T_min values, N, one curve each (default: the scene's T_min).
    #[arg(long = "t-mins", value_delimiter = ',', num_args = 1..)]
    pub t_mins: Vec<f64>,
    /// Circle radius, m (default trajectory only).
    #[arg(long, default_value_t = CIRCLE_RADIUS_M)]
    pub radius_m: f64,
    /// Period of one revolution of the circle, s (poses 1 ms apart).
    #[arg(long, default_value_t = 4.0)]
    pub period_s: f64,
    /// Modes per pose in the CSV: columns f1_hz (as before) and f2_hz .. fK_hz, Hz
    /// (1 ..= 16).
    #[arg(long, default_value_t = 1)]
    pub modes: usize,
    /// Output prefix: writes PREFIX.csv, its metadata PREFIX.csv.json and PREFIX.svg.
    #[arg(long, default_value = "trajectory")]
    pub out: PathBuf,
    /// Write the figure here instead of PREFIX.svg (PREFIX.png, PREFIX.pdf with --format).
    #[arg(long, visible_alias = "figure")]
    pub svg: Option<PathBuf>,
    /// Figure format: svg, png (3 px per SVG px) or pdf (vector, font embedded). Default:
    /// the figure path's extension, else svg; --format wins and sets the file's extension.
    #[arg(long, value_parser = parse_format)]
    pub format: Option<FigureFormat>,
    /// Worker threads, T_min curves spread over them (0: one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Skip the end-effector mode (f1 only).
    #[arg(long)]
    pub no_ee_mode: bool,
    /// No progress bar (it is shown only on a terminal, after a second).
    #[arg(long)]
    pub quiet: bool,
}

impl TrajectoryArgs {
    /// The study configuration of these options.
    pub fn config(&self) -> TrajectoryConfig {
        TrajectoryConfig {
            path: match &self.csv {
                Some(p) => PathSource::Csv(p.clone()),
                None => PathSource::Circle {
                    radius_m: self.radius_m,
                    period_s: self.period_s,
                },
            },
            t_mins_n: self.t_mins.clone(),
            ee_mode: !self.no_ee_mode,
            modes: self.modes,
            threads: self.threads,
            progress: !self.quiet,
        }
    }
}

/// `cablevib trajectory`: writes PREFIX.csv, PREFIX.csv.json and PREFIX.svg.
pub fn run(a: &TrajectoryArgs) -> Result<(), CliError> {
    let s = resolve_scene(&a.scene)?;
    let (csv_path, svg_path, fmt) = output_paths(&a.out, &a.svg, a.format)?;
    // Written chunk by chunk, created with the first chunk (after every row was checked).
    let mut csv: Option<TrajectoryCsv> = None;
    let t = study::run(&s, &a.config(), |c, results| {
        let out = match &mut csv {
            Some(out) => out,
            None => csv.insert(TrajectoryCsv::create(
                &csv_path,
                &s,
                &c.t_mins_n,
                c.total_poses,
                c.modes,
            )?),
        };
        out.chunk(c, results).map_err(CliError::from)
    })?;
    if let Some(out) = csv {
        out.finish(&process_command_line())?;
    }
    if !s.rigid && !t.samples.orientation_wxyz.is_empty() {
        eprintln!(
            "warning: the quaternion columns have no effect: scene `{}` has a point-mass end-effector",
            s.name
        );
    }
    outln!(
        "trajectory: scene {}  {} poses × {} T_min values",
        s.name,
        t.poses,
        t.t_mins_n.len()
    )?;
    for (k, &tm) in t.t_mins_n.iter().enumerate() {
        let c = t.summary(k);
        if c.f1_min_hz.is_finite() {
            outln!(
                "  T_min {tm} N: f1 min {:.4} Hz  max {:.4} Hz  statuses: {}",
                c.f1_min_hz,
                c.f1_max_hz,
                c.counts.summary()
            )?;
            if !a.no_ee_mode {
                super::map::print_ee_mode_missing(
                    c.ee_mode_missing,
                    c.counts.count(StatusCode::Ok),
                )?;
            }
        } else {
            outln!(
                "  T_min {tm} N: no valid estimate  statuses: {}",
                c.counts.summary()
            )?;
        }
    }
    let svg = trajectory_svg(&s, &t, a.radius_m, !a.no_ee_mode);
    figure::write(&svg_path, &svg, fmt)?;
    outln!("  wrote {} and {}", csv_path.display(), svg_path.display())?;
    Ok(())
}
