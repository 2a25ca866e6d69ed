//! `cablevib simulate`: the end-effector's dynamic deviation from its quasi-static pose
//! along a trajectory (the paper's circle, a CSV file or a built-in point-to-point move),
//! unshaped and shaped, as a CSV, a figure and the residual vibration after each stop; and
//! `cablevib shape`: a trajectory CSV shaped by a time-varying ZV / ZVD / EI shaper that
//! follows the estimated mode ([`crate::study::simulate`]).

use super::args::{damping_label, parse_vec3, resolve_scene, SceneArgs};
use super::figure::{self, parse_format};
use super::CliError;
use crate::report::csv::{num, process_command_line, scene_meta, write_csv, Column, Csv};
use crate::report::figure::FigureFormat;
use crate::report::svg::axis::Axis;
use crate::report::svg::line_plot::{LinePlot, Mark, Series};
use crate::scene::{Damping, Scene, MAX_MODAL_RATIO};
use crate::study::simulate::{
    self as study, PathSpec, SampledPath, ShapeMode, SimulateConfig, SimulateResult,
    DEFAULT_MAX_ACCELERATION_M_S2,
};
use crate::trajectory::moves::Profile;
use crate::trajectory::shaping::{Impulses, ShaperKind};
use crate::trajectory::CIRCLE_PERIOD_S;
use cablevib::outln;
use clap::{Args, ValueEnum};
use nalgebra::Vector3;
use std::path::PathBuf;
use std::time::Instant;

use crate::study::simulate::path_spec::MAX_DT_S;

/// Velocity profile of `--move`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ProfileArg {
    /// Constant jerk, no plateaus (continuous acceleration).
    SCurve,
    /// Constant acceleration, cruise, constant deceleration (thirds).
    Trapezoid,
}

/// A shaper on the command line (`none` for the unshaped path).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ShaperArg {
    /// No shaping.
    None,
    /// Zero vibration (two impulses, half a period).
    Zv,
    /// Zero vibration and derivative (three impulses, one period).
    Zvd,
    /// Extra insensitive, 5 % (three impulses, one period).
    Ei,
}

impl ShaperArg {
    fn kind(self) -> Option<ShaperKind> {
        match self {
            ShaperArg::None => None,
            ShaperArg::Zv => Some(ShaperKind::Zv),
            ShaperArg::Zvd => Some(ShaperKind::Zvd),
            ShaperArg::Ei => Some(ShaperKind::Ei),
        }
    }
    fn name(self) -> &'static str {
        self.kind().map_or("unshaped", ShaperKind::as_str)
    }
}

/// Which mode the shaper follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ModeArg {
    /// The end-effector mode (lowest with the scene's participation).
    Ee,
    /// The first mode.
    F1,
}

impl From<ModeArg> for ShapeMode {
    fn from(m: ModeArg) -> ShapeMode {
        match m {
            ModeArg::Ee => ShapeMode::EndEffector,
            ModeArg::F1 => ShapeMode::First,
        }
    }
}

/// The path options shared by `simulate` and `shape`.
#[derive(Debug, Args, Clone)]
pub struct PathArgs {
    /// Trajectory CSV (t,x,y,z; s, m), resampled every --dt; at rest before and after.
    #[arg(long, conflicts_with = "displacement")]
    pub csv: Option<PathBuf>,
    /// A point-to-point move from the scene's position by dx,dy,dz (m), then a stop.
    #[arg(long = "move", value_parser = parse_vec3, allow_hyphen_values = true, value_name = "DX,DY,DZ")]
    pub displacement: Option<Vector3<f64>>,
    /// Time of the --move, s.
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    pub duration: f64,
    /// Velocity profile of the --move.
    #[arg(long, value_enum, default_value_t = ProfileArg::SCurve)]
    pub profile: ProfileArg,
    /// Sample period, s, in (0, 0.1].
    #[arg(long, default_value_t = 1e-3, allow_hyphen_values = true)]
    pub dt: f64,
    /// Damping: every mode's viscous ratio ζ (replaces the scene's [damping]), in [0, 1).
    #[arg(long, allow_hyphen_values = true)]
    pub modal_ratio: Option<f64>,
    /// Largest path acceleration accepted, m/s² (a jump in the path exceeds it).
    #[arg(long, default_value_t = DEFAULT_MAX_ACCELERATION_M_S2, allow_hyphen_values = true)]
    pub max_acceleration: f64,
}

/// The circle `simulate` follows without --csv or --move (`shape` shapes a CSV or a move
/// only, so these are not its options).
#[derive(Debug, Args, Clone)]
pub struct CircleArgs {
    /// Without --csv or --move: seconds of the paper's circle (one revolution per
    /// --period-s).
    #[arg(long, default_value_t = 10.0, allow_hyphen_values = true)]
    pub circle_s: f64,
    /// Period of one revolution of the circle, s.
    #[arg(long, default_value_t = CIRCLE_PERIOD_S, allow_hyphen_values = true)]
    pub period_s: f64,
}

impl PathArgs {
    /// The scene's damping, or --modal-ratio's.
    fn apply_damping(&self, s: &mut Scene) -> Result<(), CliError> {
        if let Some(z) = self.modal_ratio {
            if !(z.is_finite() && (0.0..MAX_MODAL_RATIO).contains(&z)) {
                return Err(CliError::Usage(format!(
                    "--modal-ratio {z}: must be in [0, {MAX_MODAL_RATIO}) (1 is critical damping)"
                )));
            }
            s.damping = Damping::ModalRatio { zeta: z };
        }
        Ok(())
    }

    /// `path` within --max-acceleration (a jump exceeds it), every sample finite.
    fn check(&self, path: &SampledPath) -> Result<(), CliError> {
        if !(self.max_acceleration.is_finite() && self.max_acceleration > 0.0) {
            return Err(CliError::Usage(format!(
                "--max-acceleration {}: must be finite and > 0",
                self.max_acceleration
            )));
        }
        path.check(self.max_acceleration)?;
        Ok(())
    }

    /// The sampled path and a one-line description: the CSV, else the move, else the
    /// `circle` (without one, a usage error).
    fn path(
        &self,
        s: &Scene,
        circle: Option<&CircleArgs>,
    ) -> Result<(SampledPath, String), CliError> {
        // Checked here, for every path, so that the message names the option (a move's own
        // sampling would report it as a sample period).
        if !(self.dt.is_finite() && self.dt > 0.0 && self.dt <= MAX_DT_S) {
            return Err(CliError::Usage(format!(
                "--dt {}: the sample period must be in (0, {MAX_DT_S}] s",
                self.dt
            )));
        }
        let spec = if let Some(csv) = &self.csv {
            PathSpec::Csv(csv.clone())
        } else if let Some(d) = self.displacement {
            if !(self.duration.is_finite() && self.duration > 0.0) {
                return Err(CliError::Usage(format!(
                    "--duration {}: a move takes a finite time > 0 s",
                    self.duration
                )));
            }
            PathSpec::Move {
                displacement_m: d,
                duration_s: self.duration,
                profile: match self.profile {
                    ProfileArg::SCurve => Profile::SCurve,
                    ProfileArg::Trapezoid => Profile::Trapezoid,
                },
            }
        } else if let Some(c) = circle {
            PathSpec::Circle {
                duration_s: c.circle_s,
                period_s: c.period_s,
            }
        } else {
            return Err(CliError::Usage(
                "give a TRAJECTORY CSV (or --move DX,DY,DZ) to shape".into(),
            ));
        };
        Ok(spec.sample(s, self.dt)?)
    }
}

/// `cablevib simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Scene and overrides.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The path.
    #[command(flatten)]
    pub path: PathArgs,
    /// The circle, when the path is neither a CSV nor a move.
    #[command(flatten)]
    pub circle: CircleArgs,
    /// Modes K in the superposition (a cluster cut by K completed), 1..=256; default: the
    /// fewest whose estimated truncation error meets --tolerance.
    #[arg(long)]
    pub modes: Option<usize>,
    /// Samples between two updates of the modes along the path; default: chosen along the
    /// path so that a held basis meets --tolerance.
    #[arg(long)]
    pub update_every: Option<usize>,
    /// Error allowed on the end-effector's deviation, relative to its peak (1e-9..=0.5).
    #[arg(long, default_value_t = study::pilot::DEFAULT_TOLERANCE, allow_hyphen_values = true)]
    pub tolerance: f64,
    /// Time simulated at rest after a path that ends at rest, s.
    #[arg(long, default_value_t = 2.0, allow_hyphen_values = true)]
    pub settle: f64,
    /// Shapers to compare, comma-separated (none, zv, zvd, ei), each following --mode.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "none")]
    pub shaper: Vec<ShaperArg>,
    /// The mode the shapers follow.
    #[arg(long, value_enum, default_value_t = ModeArg::Ee)]
    pub mode: ModeArg,
    /// Output prefix: PREFIX.csv (+ .csv.json) and PREFIX.svg.
    #[arg(long, default_value = "simulate")]
    pub out: PathBuf,
    /// Figure format: svg, png or pdf.
    #[arg(long, value_parser = parse_format)]
    pub format: Option<FigureFormat>,
}

impl SimulateArgs {
    /// The CSV (PREFIX.csv) and the figure (PREFIX.svg, or the --format's extension).
    pub fn output_paths(&self) -> Result<(PathBuf, PathBuf, FigureFormat), CliError> {
        let (fig, fmt) = figure::target(&self.out.with_extension("svg"), self.format)?;
        Ok((self.out.with_extension("csv"), fig, fmt))
    }
}

/// One run: a shaper, its result, the time it added, its wall time.
struct Run {
    shaper: ShaperArg,
    result: SimulateResult,
    added_s: f64,
    wall_s: f64,
}

/// `cablevib simulate`.
pub fn run(a: &SimulateArgs) -> Result<(), CliError> {
    let mut s = resolve_scene(&a.scene)?;
    a.path.apply_damping(&mut s)?;
    let (path, desc) = a.path.path(&s, Some(&a.circle))?;
    let cfg = SimulateConfig {
        modes: a.modes,
        update_every: a.update_every,
        tolerance: a.tolerance,
        settle_s: a.settle,
        max_acceleration_m_s2: a.path.max_acceleration,
        progress: Some("simulate"),
    };
    a.path.check(&path)?;
    let given = |v: Option<usize>, what: &str| {
        v.map_or(format!("{what} for the tolerance"), |k| k.to_string())
    };
    outln!(
        "scene {}  damping {}  path {desc}  dt {} s  K = {}  modes updated every {} samples  tolerance {:e} of the peak",
        s.name,
        damping_label(&s.damping),
        path.dt_s,
        given(a.modes, "chosen"),
        given(a.update_every, "chosen"),
        a.tolerance
    )?;
    let samples = study::simulated_samples(&path, &cfg);
    let mut cost = crate::study::cost::estimate_cost(&s, &study::simulate_work(samples, &cfg));
    // Every shaper is one more run of the same path (longer by the shaper's delay).
    cost.seconds *= a.shaper.len() as f64;
    super::modes::announce(&cost)?;
    let mut runs = Vec::new();
    for &sh in &a.shaper {
        let t0 = Instant::now();
        let r = study::simulate_shaped(&s, &path, &cfg, sh.kind(), a.mode.into())?;
        let wall_s = t0.elapsed().as_secs_f64();
        runs.push(Run {
            shaper: sh,
            result: r.result,
            added_s: r.added_s,
            wall_s,
        });
    }
    let base = runs
        .iter()
        .find(|r| r.shaper == ShaperArg::None)
        .and_then(|r| r.result.stops.last())
        .map(|st| st.peak_to_peak_max_m());
    outln!(
        "\n shaper     samples   time added (s)   residual p-p (mm)   residual RMS (mm)   reduction   f1 range (Hz)    wall (s)"
    )?;
    for r in &runs {
        let res = &r.result;
        let (pp, rms) = res.stops.last().map_or((f64::NAN, f64::NAN), |st| {
            (st.peak_to_peak_max_m(), st.rms_m)
        });
        let red = base.map_or(f64::NAN, |b| 1.0 - pp / b);
        outln!(
            " {:<9} {:>8}   {:>14.4}   {:>17.5}   {:>17.5}   {:>8.1} %   {:>6.3}-{:<6.3}   {:>8.3}",
            r.shaper.name(),
            res.t_s.len(),
            r.added_s,
            pp * 1e3,
            rms * 1e3,
            red * 100.0,
            res.f1_range_hz.0,
            res.f1_range_hz.1,
            r.wall_s
        )?;
    }
    if let Some(r) = runs.first() {
        let peak = r
            .result
            .deviation_m
            .iter()
            .fold(0.0f64, |m, u| m.max(u.norm()));
        outln!(
            "\n{}: peak |deviation| {:.5} mm, {} stops, {} mode updates, {} modes ({})",
            r.shaper.name(),
            peak * 1e3,
            r.result.stops.len(),
            r.result.updates,
            r.result.modes,
            if r.result.structured {
                "structured engine"
            } else {
                "dense model of the sagged cables"
            }
        )?;
    }
    for r in &runs {
        let acc = &r.result.accuracy;
        outln!(
            "{}: accuracy: K = {} ({}; pilot of {} modes), truncation estimate {:.2e} of the peak ({:.5} mm){}; basis updates {} ({}{}), largest interval estimate {:.2e}, sum {:.2e}",
            r.shaper.name(),
            r.result.modes,
            if acc.modes_chosen { "chosen" } else { "given" },
            acc.pilot_modes,
            acc.modes_estimate,
            acc.peak_m * 1e3,
            if acc.modes_met { "" } else { " — over the tolerance" },
            r.result.updates,
            if acc.updates_chosen { "chosen" } else { "given" },
            // The residual of Rayleigh–Ritz updates only where there are some.
            if acc.ritz_updates > 0 {
                format!(
                    "; {} by Rayleigh–Ritz, largest residual {:.1e}",
                    acc.ritz_updates, acc.ritz_residual
                )
            } else {
                "; none by Rayleigh–Ritz".to_string()
            },
            acc.interval_estimate,
            acc.interval_estimate_sum
        )?;
    }
    if s.model.sag && !cablevib::estimator::sag_path_field_applies(&s) {
        // The path's field of sagging cables covers fixed anchors only (modal::quasi_static).
        outln!("note: cable inertia not applied to sagging cables over pulleys (the end-effector's load alone)")?;
    }
    write_outputs(a, &s, &runs)?;
    Ok(())
}

fn write_outputs(a: &SimulateArgs, s: &Scene, runs: &[Run]) -> Result<(), CliError> {
    let mut cols = vec![Column::new("t_s", "s", "time")];
    for r in runs {
        let n = r.shaper.name();
        for ax in ["x", "y", "z"] {
            cols.push(Column::new(
                format!("{n}_dev_{ax}_mm"),
                "mm",
                format!("{n}: end-effector deviation from the quasi-static pose along {ax}"),
            ));
        }
    }
    let mut meta = scene_meta("simulate", s);
    let stops: Vec<serde_json::Value> = runs
        .iter()
        .map(|r| {
            serde_json::json!({
                "shaper": r.shaper.name(),
                "time_added_s": r.added_s,
                "modes": r.result.modes,
                "modes_chosen": r.result.accuracy.modes_chosen,
                "tolerance": r.result.accuracy.tolerance,
                "truncation_estimate": r.result.accuracy.modes_estimate,
                "pilot_modes": r.result.accuracy.pilot_modes,
                "basis_updates": r.result.updates,
                "update_interval_chosen": r.result.accuracy.updates_chosen,
                "update_interval_estimate": r.result.accuracy.interval_estimate,
                "stops": r.result.stops.iter().map(|st| serde_json::json!({
                    "t_start_s": st.t_start_s,
                    "t_end_s": st.t_end_s,
                    "peak_to_peak_mm": [st.peak_to_peak_m.x * 1e3, st.peak_to_peak_m.y * 1e3, st.peak_to_peak_m.z * 1e3],
                    "rms_mm": st.rms_m * 1e3,
                })).collect::<Vec<_>>(),
            })
        })
        .collect();
    meta.insert("residual_vibration".into(), serde_json::Value::Array(stops));
    let mut csv = Csv::new(cols, meta);
    let n = runs.iter().map(|r| r.result.t_s.len()).max().unwrap_or(0);
    let dt = a.path.dt;
    for k in 0..n {
        let mut row = vec![num(k as f64 * dt)];
        for r in runs {
            let d = &r.result.deviation_m;
            let u = d.get(k).or(d.last()).copied().unwrap_or_default();
            row.extend([num(u.x * 1e3), num(u.y * 1e3), num(u.z * 1e3)]);
        }
        csv.row(row);
    }
    let (csv_path, fig, fmt) = a.output_paths()?;
    write_csv(&csv_path, csv, &process_command_line())?;
    outln!("wrote {}", csv_path.display())?;
    let mut plot = LinePlot::new(
        "End-effector deviation from the quasi-static pose",
        Axis::linear("time (s)"),
        Axis::linear("|deviation| (mm)"),
    );
    plot.subtitle = format!("{} · damping {}", s.name, damping_label(&s.damping));
    let stride = (n / 4000).max(1);
    for r in runs {
        let pts = r
            .result
            .t_s
            .iter()
            .zip(&r.result.deviation_m)
            .step_by(stride)
            .map(|(t, u)| (*t, u.norm() * 1e3))
            .collect();
        plot.series
            .push(Series::new(r.shaper.name(), pts, Mark::Line));
    }
    figure::write(&fig, &plot.to_svg(), fmt)?;
    outln!("wrote {}", fig.display())?;
    Ok(())
}

/// `cablevib shape`.
#[derive(Debug, Args)]
pub struct ShapeArgs {
    /// Trajectory CSV to shape (t,x,y,z); or use --move.
    pub trajectory: Option<PathBuf>,
    /// Scene (file, or spatial-paper / planar-paper).
    #[arg(long, default_value = "spatial-paper")]
    pub scene: String,
    /// The path (when no TRAJECTORY is given).
    #[command(flatten)]
    pub path: PathArgs,
    /// Shaper.
    #[arg(long, value_enum, default_value_t = ShaperArg::Zv)]
    pub shaper: ShaperArg,
    /// The mode the shaper follows at each pose.
    #[arg(long, value_enum, default_value_t = ModeArg::Ee)]
    pub mode: ModeArg,
    /// Where to write the shaped trajectory (t,x,y,z).
    #[arg(short = 'o', long)]
    pub output: Option<PathBuf>,
    /// Write the shapers' sensitivity curves (residual vibration against the frequency
    /// ratio, at the damping given) as a figure here.
    #[arg(long)]
    pub sensitivity: Option<PathBuf>,
    /// Figure format: svg, png or pdf.
    #[arg(long, value_parser = parse_format)]
    pub format: Option<FigureFormat>,
}

/// `cablevib shape`.
pub fn shape(a: &ShapeArgs) -> Result<(), CliError> {
    let mut s = Scene::load(&a.scene)?;
    a.path.apply_damping(&mut s)?;
    if let Some(fig) = &a.sensitivity {
        let zeta = s.damping.modal_ratio(2.0 * std::f64::consts::PI * 10.0);
        sensitivity_figure(fig, a.format, zeta)?;
    }
    let Some(kind) = a.shaper.kind() else {
        return Err(CliError::Usage("--shaper none: nothing to shape".into()));
    };
    let mut pa = a.path.clone();
    if let Some(t) = &a.trajectory {
        pa.csv = Some(t.clone());
    } else if pa.csv.is_none() && pa.displacement.is_none() {
        if a.sensitivity.is_some() {
            return Ok(());
        }
        return Err(CliError::Usage(
            "give a TRAJECTORY CSV (or --move DX,DY,DZ) to shape".into(),
        ));
    }
    let Some(out) = &a.output else {
        return Err(CliError::Usage("-o SHAPED.csv is required".into()));
    };
    let (path, desc) = pa.path(&s, None)?;
    // A jump stays a jump when shaped (ZV splits it in two), which no robot follows and
    // `simulate` refuses: refused here too.
    pa.check(&path)?;
    let r = study::shape(&s, &path, kind, a.mode.into())?;
    let (lo, hi) = r
        .design_hz
        .iter()
        .filter(|f| f.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &f| {
            (l.min(f), h.max(f))
        });
    let mut csv = Csv::new(
        vec![
            Column::new("t", "s", "time"),
            Column::new("x", "m", "shaped position x"),
            Column::new("y", "m", "shaped position y"),
            Column::new("z", "m", "shaped position z"),
        ],
        scene_meta("shape", &s),
    );
    for (k, p) in r.path.positions_m.iter().enumerate() {
        csv.row([num(k as f64 * path.dt_s), num(p.x), num(p.y), num(p.z)]);
    }
    write_csv(out, csv, &process_command_line())?;
    outln!(
        "shaped {desc} with {} following the {} mode ({lo:.4}-{hi:.4} Hz, ζ from {}): {} samples, {:.4} s added; wrote {}",
        kind.as_str(),
        match a.mode {
            ModeArg::Ee => "end-effector",
            ModeArg::F1 => "first",
        },
        damping_label(&s.damping),
        r.path.positions_m.len(),
        r.added_s,
        out.display()
    )?;
    Ok(())
}

/// The sensitivity curves of ZV, ZVD and EI at ratio `zeta`: residual fraction against
/// f/f_design from 0.5 to 1.5.
fn sensitivity_figure(
    path: &std::path::Path,
    format: Option<FigureFormat>,
    zeta: f64,
) -> Result<(), CliError> {
    let mut plot = LinePlot::new(
        "Shaper sensitivity: residual vibration against frequency error",
        Axis::linear("actual / design frequency"),
        Axis::linear("residual vibration (% of unshaped)"),
    );
    plot.subtitle = format!("ζ = {zeta} (design and actual)");
    for kind in [ShaperKind::Zv, ShaperKind::Zvd, ShaperKind::Ei] {
        let imp = Impulses::design(kind, 1.0, zeta).map_err(|e| CliError::Usage(e.to_string()))?;
        let pts = (0..=200)
            .map(|i| {
                let r = 0.5 + i as f64 / 200.0;
                (r, 100.0 * imp.residual_fraction(r, zeta))
            })
            .collect();
        plot.series
            .push(Series::new(kind.as_str(), pts, Mark::Line));
    }
    let (fig, fmt) = figure::target(path, format)?;
    figure::write(&fig, &plot.to_svg(), fmt)?;
    outln!("wrote {}", fig.display())?;
    Ok(())
}
