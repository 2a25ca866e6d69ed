//! `cablevib calibrate`: fit a scene's parameters to measured frequencies (and damping
//! ratios and tensions) at many poses ([`crate::calibration`]); print the report (or its
//! JSON), draw measured against model frequency, write the calibrated scene.

use super::args::{resolve_scene, SceneArgs};
use super::figure::{self, parse_format};
use super::CliError;
use crate::calibration::data::{read_modes, read_tensions};
use crate::calibration::{
    calibrate, CalibrationError, CalibrationOption, CalibrationParams, FitSpec, Report,
    SigmaDefaults,
};
use crate::report::calibrated_scene::calibrated_scene_toml;
use crate::report::calibration::calibration_svg;
use crate::report::csv::process_command_line;
use crate::report::figure::FigureFormat;
use crate::scene::Scene;
use cablevib::outln;
use clap::Args;
use std::path::PathBuf;

/// `cablevib calibrate`.
#[derive(Debug, Args)]
pub struct CalibrateArgs {
    /// Scene and model overrides (--element, --elements, --t-min, --sag; the poses come from
    /// the data, so --position and --orientation are refused).
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Measured modes, CSV: x_m,y_m,z_m,frequency_hz and optional qw..qz, t_min_n, sigma_hz,
    /// damping_ratio, mode (ee, eeK or an order); `cablevib identify`'s CSV as it is.
    #[arg(long, value_name = "MEASURED.csv")]
    pub data: PathBuf,
    /// Parameters to fit, comma-separated: ea_factor (every cable; ea_factor.I one),
    /// ea_factor_all, hidden_length[.I], weight_per_length, ee_mass, ee_inertia[.xx|yy|zz],
    /// ee_com[.x|y|z], pulley_radius, modal_ratio, rayleigh[.alpha|beta].
    #[arg(long, value_name = "PARAMS")]
    pub fit: String,
    /// Write the calibrated scene (TOML; never over an input file).
    #[arg(short = 'o', long, value_name = "CALIBRATED.toml")]
    pub output: Option<PathBuf>,
    /// Print the report as JSON on stdout (messages go to stderr).
    #[arg(long)]
    pub json: bool,
    /// Figure of measured against model frequency before and after: SVG, or PNG / PDF by the
    /// extension or --format.
    #[arg(long, visible_alias = "figure")]
    pub svg: Option<PathBuf>,
    /// Figure format: svg, png or pdf.
    #[arg(long, value_parser = parse_format)]
    pub format: Option<FigureFormat>,
    /// Measured cable tensions, CSV: x_m,y_m,z_m,cable,tension_n[,sigma_n] (cable 1-based).
    #[arg(long, value_name = "FILE.csv")]
    pub tensions: Option<PathBuf>,
    /// σ of a frequency relative to it, where the data give neither sigma_hz nor
    /// frequency_std_hz.
    #[arg(long, default_value_t = 0.005)]
    pub sigma_rel: f64,
    /// σ of a damping ratio relative to it, where the data give no damping_ratio_std.
    #[arg(long, default_value_t = 0.2)]
    pub damping_sigma_rel: f64,
    /// σ of a tension relative to it, where the tensions file gives no sigma_n.
    #[arg(long, default_value_t = 0.02)]
    pub tension_sigma_rel: f64,
    /// Bounds, comma-separated NAME=LO:HI (a group name sets each member), in the
    /// parameter's SI unit.
    #[arg(long, value_name = "NAME=LO:HI,...", allow_hyphen_values = true)]
    pub bounds: Option<String>,
    /// Nominal values (the start and the prior's centre), comma-separated NAME=VALUE.
    #[arg(long, value_name = "NAME=VALUE,...", allow_hyphen_values = true)]
    pub nominal: Option<String>,
    /// Gaussian priors toward the nominal values, comma-separated NAME=SIGMA (SI unit).
    #[arg(long, value_name = "NAME=SIGMA,...")]
    pub prior: Option<String>,
}

/// `NAME=VALUE` items of a comma-separated option.
fn assignments<'a>(option: &str, s: &'a str) -> Result<Vec<(&'a str, &'a str)>, CliError> {
    s.split(',')
        .map(|item| {
            item.split_once('=')
                .map(|(n, v)| (n.trim(), v.trim()))
                .ok_or_else(|| CliError::Usage(format!("{option} `{item}`: expected NAME=VALUE")))
        })
        .collect()
}

fn number(option: &str, name: &str, v: &str) -> Result<f64, CliError> {
    v.parse::<f64>()
        .map_err(|_| CliError::Usage(format!("{option} {name}={v}: `{v}` is not a number")))
}

/// The fit's parameters with the options' bounds, nominal values and priors.
fn spec(scene: &Scene, a: &CalibrateArgs) -> Result<FitSpec, CliError> {
    let usage = |e: CalibrationError| CliError::Usage(e.render(&calibration_flag));
    let names: Vec<&str> = a.fit.split(',').collect();
    let mut spec = FitSpec::new(scene, &names).map_err(usage)?;
    if let Some(b) = &a.bounds {
        for (name, v) in assignments("--bounds", b)? {
            let (lo, hi) = v
                .split_once(':')
                .ok_or_else(|| CliError::Usage(format!("--bounds {name}={v}: expected LO:HI")))?;
            spec.set_bounds(
                name,
                number("--bounds", name, lo)?,
                number("--bounds", name, hi)?,
            )
            .map_err(usage)?;
        }
    }
    if let Some(b) = &a.nominal {
        for (name, v) in assignments("--nominal", b)? {
            spec.set_nominal(name, number("--nominal", name, v)?)
                .map_err(usage)?;
        }
    }
    if let Some(b) = &a.prior {
        for (name, v) in assignments("--prior", b)? {
            spec.set_prior(name, number("--prior", name, v)?)
                .map_err(usage)?;
        }
    }
    spec.check().map_err(usage)?;
    Ok(spec)
}

/// `cablevib calibrate`.
pub fn run(a: &CalibrateArgs) -> Result<(), CliError> {
    if a.scene.position.is_some() || a.scene.orientation.is_some() {
        return Err(CliError::Usage(
            "--position/--orientation: calibrate takes every pose from the data file".into(),
        ));
    }
    figure::format_needs_svg(&a.svg, a.format)?;
    let scene = resolve_scene(&a.scene)?;
    let sigma = SigmaDefaults {
        frequency_rel: a.sigma_rel,
        damping_rel: a.damping_sigma_rel,
        tension_rel: a.tension_sigma_rel,
    };
    let analysis = |e: CalibrationError| CliError::Analysis(e.render(&calibration_flag));
    let spec = spec(&scene, a)?;
    let mut data = read_modes(&a.data, &sigma).map_err(analysis)?;
    if let Some(t) = &a.tensions {
        read_tensions(t, scene.n_cables(), &sigma, &mut data).map_err(analysis)?;
    }
    let c = calibrate(&scene, &data, &spec, &CalibrationParams::default()).map_err(analysis)?;
    let r = &c.report;
    if a.json {
        let text =
            serde_json::to_string_pretty(r).map_err(|e| CliError::Analysis(e.to_string()))?;
        outln!("{text}")?;
    } else {
        crate::output_file::stdout_bytes(text_report(r).as_bytes())?;
    }
    // Where the files went: on stdout with the text report, on stderr beside the JSON.
    let say = |m: String| -> Result<(), CliError> {
        if a.json {
            eprintln!("{m}");
        } else {
            outln!("{m}")?;
        }
        Ok(())
    };
    if let Some(path) = &a.svg {
        let (path, fmt) = figure::target(path, a.format)?;
        figure::write(&path, &calibration_svg(r), fmt)?;
        say(format!("wrote {}", path.display()))?;
    }
    if let Some(path) = &a.output {
        let (source, origin) = Scene::source_text(&a.scene.scene)?;
        let header = vec![
            format!("Calibrated by `cablevib calibrate` from {origin}:"),
            format!("  {}", process_command_line()),
            format!(
                "  {} frequencies at {} poses ({}); χ²/dof {:.4} (before {:.4}): {}",
                r.frequencies,
                r.poses,
                r.data,
                r.chi2_per_dof,
                r.chi2_per_dof_before,
                if r.fits {
                    "fits"
                } else {
                    "DOES NOT FIT the stated noise"
                }
            ),
        ]
        .into_iter()
        .chain(r.parameters.iter().map(|p| match p.std_error {
            Some(s) => format!(
                "  {} = {} ± {:.3e}{} (nominal {})",
                p.name,
                p.value,
                s,
                if p.unit == "1" {
                    String::new()
                } else {
                    format!(" {}", p.unit)
                },
                p.nominal
            ),
            None => format!(
                "  {} undetermined by the data (nominal {} kept)",
                p.name, p.nominal
            ),
        }))
        .collect::<Vec<_>>();
        let text = calibrated_scene_toml(&source, &origin, &scene, &spec, &c.applied, r, &header)
            .map_err(|e| CliError::Analysis(e.to_string()))?;
        crate::report::write_file(path, &text)?;
        say(format!("wrote {}", path.display()))?;
    }
    Ok(())
}

/// The text report.
pub fn text_report(r: &Report) -> String {
    use std::fmt::Write;
    let mut o = String::new();
    let _ = writeln!(
        o,
        "calibrate {} ({}): {} measured frequencies at {} poses from {}{}",
        r.scene,
        r.model,
        r.frequencies,
        r.poses,
        r.data,
        r.tension_data.as_ref().map_or(String::new(), |t| format!(
            ", {} tensions from {t}",
            r.tensions
        ))
    );
    if r.damping_ratios > 0 {
        let _ = writeln!(o, "  {} measured damping ratios", r.damping_ratios);
    }
    let [col, std, rel] = r.sigma_sources;
    let _ = writeln!(o, "  σ of the frequencies: {col} from sigma_hz, {std} from frequency_std_hz, {rel} from --sigma-rel");
    if !r.unused_columns.is_empty() {
        let _ = writeln!(o, "  not used: {}", r.unused_columns.join(", "));
    }
    for n in &r.notes {
        let _ = writeln!(o, "  note: {n}");
    }
    if !r.left_out.is_empty() {
        let _ = writeln!(o, "  left out of the fit: {} rows", r.left_out.len());
        for l in &r.left_out {
            let _ = writeln!(o, "    line {}: {}", l.line, l.reason);
        }
    }
    let _ = writeln!(
        o,
        "  fit: {} parameters, {} iterations, {} model evaluations, {} start(s), {:.2} s{}",
        r.parameters.len(),
        r.iterations,
        r.evaluations,
        r.starts,
        r.seconds,
        if r.converged {
            ""
        } else {
            " (iteration bound reached)"
        }
    );
    let _ = writeln!(
        o,
        "\n parameter            value        std error   nominal      unit   sensitivity"
    );
    for p in &r.parameters {
        let err = match (p.determined, p.std_error) {
            (true, Some(s)) => format!("{s:<11.4e}"),
            _ => "undetermined".to_string(),
        };
        let _ = writeln!(
            o,
            " {:<18} {:>12.6} {:<12} {:<12} {:<6} {}{}",
            p.name,
            p.value,
            err,
            p.nominal,
            p.unit,
            p.sensitivity,
            if p.at_bound { "  (at its bound)" } else { "" }
        );
    }
    if !r.undetermined.is_empty() {
        let _ = writeln!(
            o,
            "\n undetermined (the data cannot tell them: standard error from the data alone ≥ half the parameter's scale): {}",
            r.undetermined.join(", ")
        );
    }
    let _ = writeln!(
        o,
        "\n χ²/dof {:.4} after, {:.4} before ({} dof); RMS (model − measured)/σ {:.3} after, {:.3} before",
        r.chi2_per_dof, r.chi2_per_dof_before, r.dof, r.rms_normalised_after, r.rms_normalised_before
    );
    let _ = writeln!(o, " verdict: {}", r.verdict);
    let sv: Vec<String> = r
        .singular_values
        .iter()
        .map(|v| format!("{v:.3e}"))
        .collect();
    let _ = writeln!(
        o,
        " singular values of the scaled Jacobian: {}",
        sv.join(" ")
    );
    let mut strong = Vec::new();
    for (i, row) in r.correlation.iter().enumerate() {
        for (j, c) in row.iter().enumerate().skip(i + 1) {
            if let Some(c) = c {
                if c.abs() >= 0.8 {
                    strong.push(format!(
                        "{}~{} {c:+.3}",
                        r.parameters[i].name, r.parameters[j].name
                    ));
                }
            }
        }
    }
    if !strong.is_empty() {
        let _ = writeln!(
            o,
            " strong correlations (|r| ≥ 0.8; --json has the matrix): {}",
            strong.join(", ")
        );
    }
    let _ = writeln!(
        o,
        "\n  line  pose  pairing            measured Hz   before Hz (σ)         after Hz (σ)"
    );
    for x in &r.residuals {
        let _ = writeln!(
            o,
            " {:>5} {:>5}  {:<18} {:>11.4}   {:>9.4} ({:>+8.2})   {:>9.4} ({:>+6.2})",
            x.line,
            x.pose + 1,
            x.pairing,
            x.measured_hz,
            x.model_before_hz,
            x.normalised_before,
            x.model_after_hz,
            x.normalised_after
        );
    }
    for x in &r.damping_residuals {
        let _ = writeln!(
            o,
            " line {:>5}: damping ratio {:.5} ± {:.5}, model {:.5} before, {:.5} after",
            x.line, x.measured, x.sigma, x.model_before, x.model_after
        );
    }
    for x in &r.tension_residuals {
        let _ = writeln!(
            o,
            " line {:>5}: cable {} tension {:.3} ± {:.3} N, model {:.3} before, {:.3} after",
            x.line, x.cable, x.measured_n, x.sigma_n, x.model_before_n, x.model_after_n
        );
    }
    o
}

/// The flag that sets a calibration option (`--fit` for [`CalibrationOption::Fit`]).
fn calibration_flag(o: CalibrationOption) -> &'static str {
    match o {
        CalibrationOption::Fit => "--fit",
        CalibrationOption::SagOff => "--sag false",
    }
}
