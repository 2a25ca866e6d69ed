//! `cablevib frf`: the receptance H(ω) at the end-effector of one pose over a frequency
//! band, computed by [`crate::study::frf`] (the orchestration the Python `frf` calls too),
//! as a table, a CSV ([`crate::report::frf`]), a Bode figure and JSON; `--dense` and
//! `--dense-modal` add the study's dense check and print the difference and both times.

use super::args::{damping_label, resolve_scene, SceneArgs};
use super::figure::{self, parse_format};
use super::{json_f64, CliError};
use crate::report::csv::{process_command_line, write_csv};
use crate::report::figure::FigureFormat;
use crate::report::frf::{bode_svg, frf_csv, frf_meta, FrfData, COORDS};
use crate::study::frf::{
    frequencies, frf_announced, DampingChoice, DenseCheck, DenseCheckKind, FrfConfig,
    MARK_PARTICIPATION,
};
use cablevib::outln;
use clap::Args;
use num_complex::Complex64;
use std::path::PathBuf;

/// `cablevib frf`.
#[derive(Debug, Args)]
pub struct FrfArgs {
    /// Scene and overrides.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Lowest frequency, Hz (≥ 0; > 0 with --log).
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    pub from_hz: f64,
    /// Highest frequency, Hz (> --from-hz).
    #[arg(long, default_value_t = 50.0, allow_hyphen_values = true)]
    pub to_hz: f64,
    /// Number of frequencies, 1..=100000 (both ends included).
    #[arg(long, default_value_t = 1000)]
    pub points: usize,
    /// Geometric spacing (default: even).
    #[arg(long)]
    pub log: bool,
    /// Load directions reported: comma-separated of x, y, z (rx, ry, rz for a rigid body);
    /// default all.
    #[arg(long, value_delimiter = ',')]
    pub input: Vec<String>,
    /// Response directions reported (as --input); default all.
    #[arg(long, value_delimiter = ',')]
    pub output: Vec<String>,
    /// Loss factor η (replaces the scene's [damping]), 0 <= η < 2.
    #[arg(long, allow_hyphen_values = true)]
    pub loss_factor: Option<f64>,
    /// Rayleigh damping α,β (1/s, s; replaces the scene's [damping]).
    #[arg(long, value_parser = parse_vec2, allow_hyphen_values = true, value_name = "ALPHA,BETA")]
    pub rayleigh: Option<(f64, f64)>,
    /// Modal damping ratio ζ in every mode (replaces the scene's [damping]), 0 <= ζ < 1.
    #[arg(long, allow_hyphen_values = true)]
    pub modal_ratio: Option<f64>,
    /// No damping (replaces the scene's [damping]): H is infinite on a natural frequency.
    #[arg(long)]
    pub undamped: bool,
    /// Also solve the assembled dense complex problem at every frequency (fem and catenary;
    /// loss factor, Rayleigh or none): print the largest relative difference and both times.
    #[arg(long)]
    pub dense: bool,
    /// Also the dense reference at every frequency by summation over every mode of the
    /// assembled (K, M) (one dense eigendecomposition; fem and catenary; any damping),
    /// checked by the dense complex LU at --dense-lu-points of the frequencies: print the
    /// largest relative differences and the times.
    #[arg(long, conflicts_with = "dense")]
    pub dense_modal: bool,
    /// With --dense-modal: how many frequencies (evenly spread, both ends included) are
    /// also solved by the dense complex LU; 0 for none.
    #[arg(long, default_value_t = 3, requires = "dense_modal")]
    pub dense_lu_points: usize,
    /// Write the response as CSV (and its .json sidecar).
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Write the Bode figure: SVG, or PNG / PDF by the extension or --format.
    #[arg(long, visible_alias = "figure")]
    pub svg: Option<PathBuf>,
    /// Figure format: svg, png or pdf.
    #[arg(long, value_parser = parse_format)]
    pub format: Option<FigureFormat>,
    /// One JSON object on stdout: frequencies_hz, receptance_re, receptance_im (N × d × d,
    /// m/N, translations first), natural_frequencies_hz, damping.
    #[arg(long)]
    pub json: bool,
}

/// Parse `ALPHA,BETA` (two numbers; the range is checked with the damping).
fn parse_vec2(s: &str) -> Result<(f64, f64), String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("`{x}`: {e}")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [a, b] => Ok((a, b)),
        _ => Err(format!("expected two numbers ALPHA,BETA, got `{s}`")),
    }
}

/// Coordinates named in `names` (all `dim` when empty).
fn coords(names: &[String], dim: usize, opt: &str) -> Result<Vec<usize>, CliError> {
    if names.is_empty() {
        return Ok((0..dim).collect());
    }
    let mut out = Vec::new();
    for n in names {
        let i = COORDS[..dim]
            .iter()
            .position(|c| c.eq_ignore_ascii_case(n.trim()))
            .ok_or_else(|| {
                CliError::Usage(format!(
                    "{opt} `{n}`: expected one of {}",
                    COORDS[..dim].join(", ")
                ))
            })?;
        if !out.contains(&i) {
            out.push(i);
        }
    }
    Ok(out)
}

/// The study's configuration of the options.
fn config(a: &FrfArgs) -> FrfConfig {
    FrfConfig {
        from_hz: a.from_hz,
        to_hz: a.to_hz,
        points: a.points,
        log: a.log,
        damping: DampingChoice {
            loss_factor: a.loss_factor,
            rayleigh: a.rayleigh,
            modal_ratio: a.modal_ratio,
            undamped: a.undamped,
        },
        dense: if a.dense {
            Some(DenseCheckKind::Lu)
        } else if a.dense_modal {
            Some(DenseCheckKind::Modal {
                lu_points: a.dense_lu_points,
            })
        } else {
            None
        },
        progress: Some("frf"),
    }
}

/// `cablevib frf`.
pub fn run(a: &FrfArgs) -> Result<(), CliError> {
    let cfg = config(a);
    frequencies(&cfg)?;
    figure::format_needs_svg(&a.svg, a.format)?;
    let s = resolve_scene(&a.scene)?;
    // A long response is announced on stderr before it runs (its memory checked first).
    let c = frf_announced(&s, &cfg, |e| {
        if let Some(line) = e.announcement() {
            eprintln!("cablevib: {line}");
        }
    })?;
    let dim = c.dim;
    let outputs = coords(&a.output, dim, "--output")?;
    let inputs = coords(&a.input, dim, "--input")?;
    let (damping, structured_s, dense) = (c.damping, c.structured_s, c.dense);
    let pairs: Vec<(usize, usize)> = outputs
        .iter()
        .flat_map(|&o| inputs.iter().map(move |&i| (o, i)))
        .collect();
    let data = FrfData {
        frequencies_hz: c.frequencies_hz,
        h: c.receptance,
        pairs,
        natural_hz: c.natural_hz,
    };
    let sc = &c.scene;
    let p = sc.ee_position_m;
    if a.json {
        let cube = |part: fn(&Complex64) -> f64| -> Vec<Vec<Vec<serde_json::Value>>> {
            data.h
                .iter()
                .map(|m| {
                    (0..dim)
                        .map(|i| (0..dim).map(|j| json_f64(part(&m[(i, j)]))).collect())
                        .collect()
                })
                .collect()
        };
        let mut o = serde_json::json!({
            "scene": sc.name,
            "position_m": [p.x, p.y, p.z],
            "model": sc.model.element.as_str(),
            "elements_per_cable": sc.model.elements_per_cable,
            "damping": damping.kind_str(),
            "damping_description": damping_label(&damping),
            "dim": dim,
            "coordinates": &COORDS[..dim],
            "frequencies_hz": data.frequencies_hz,
            "receptance_re": cube(|z| z.re),
            "receptance_im": cube(|z| z.im),
            "natural_frequencies_hz": data.natural_hz,
            "natural_frequencies_min_participation": MARK_PARTICIPATION,
            "structured_s": structured_s,
        });
        if let Some(d) = &dense {
            o["dense_method"] = d.method.into();
            o["dense_dof"] = d.dof.into();
            o["dense_max_rel_diff"] = json_f64(d.max_rel_diff);
            o["dense_rel_diff"] = d.rel_diff.iter().map(|&x| json_f64(x)).collect();
            o["dense_s"] = json_f64(d.seconds);
            if let Some(e) = d.eig_seconds {
                o["dense_eig_s"] = json_f64(e);
            }
            if let Some(lu) = &d.lu {
                o["dense_lu_frequencies_hz"] = serde_json::json!(lu.frequencies_hz);
                o["dense_lu_modal_max_rel_diff"] = json_f64(lu.modal_rel_diff);
                o["dense_lu_structured_max_rel_diff"] = json_f64(lu.structured_rel_diff);
                o["dense_lu_s"] = json_f64(lu.seconds);
            }
        }
        outln!("{o}")?;
    } else {
        outln!(
            "scene {}  position ({:.4}, {:.4}, {:.4}) m  model {} × {}  damping: {}",
            sc.name,
            p.x,
            p.y,
            p.z,
            sc.model.element.as_str(),
            sc.model.elements_per_cable,
            damping_label(&damping)
        )?;
        outln!(
            "{} frequencies {} .. {} Hz{} in {:.3} ms ({:.2} µs each)",
            data.frequencies_hz.len(),
            a.from_hz,
            a.to_hz,
            if a.log { " (log)" } else { "" },
            structured_s * 1e3,
            structured_s * 1e6 / data.frequencies_hz.len() as f64
        )?;
        let nat: Vec<String> = data.natural_hz.iter().map(|f| format!("{f:.4}")).collect();
        outln!(
            "natural frequencies in the band with end-effector participation >= {} % (Hz): {}",
            MARK_PARTICIPATION * 100.0,
            nat.join(", ")
        )?;
        for &(o, i) in &data.pairs {
            let (k, peak) = data
                .h
                .iter()
                .map(|m| m[(o, i)].norm())
                .enumerate()
                .fold((0, 0.0f64), |b, (k, v)| if v > b.1 { (k, v) } else { b });
            outln!(
                "  H {}/{}: peak |H| {:.4e} at {:.4} Hz",
                COORDS[o],
                COORDS[i],
                peak,
                data.frequencies_hz[k]
            )?;
        }
        if let Some(d) = &dense {
            print_dense(d, structured_s, data.frequencies_hz.len())?;
        }
    }
    let meta = frf_meta(&sc.name, &damping_label(&damping), &data.natural_hz);
    if let Some(path) = &a.csv {
        write_csv(path, frf_csv(&data, meta), &process_command_line())?;
        if !a.json {
            outln!("wrote {}", path.display())?;
        }
    }
    if let Some(path) = &a.svg {
        let (path, fmt) = figure::target(path, a.format)?;
        let title = format!(
            "Receptance at the end-effector, {} at ({:.2}, {:.2}, {:.2}) m",
            sc.name, p.x, p.y, p.z
        );
        let sub = format!(
            "{} × {}; damping: {}",
            sc.model.element.as_str(),
            sc.model.elements_per_cable,
            damping_label(&damping)
        );
        figure::write(&path, &bode_svg(&data, &title, &sub, a.log), fmt)?;
        if !a.json {
            outln!("wrote {}", path.display())?;
        }
    }
    Ok(())
}

/// The dense check's lines of the text output.
fn print_dense(d: &DenseCheck, structured_s: f64, n: usize) -> Result<(), CliError> {
    let ratio = d.seconds / structured_s.max(1e-12);
    match d.method {
        "lu" => outln!(
            "dense complex LU ({} DOF) at every frequency: {:.3} s; largest relative difference {:.2e}; structured {ratio:.0}× faster",
            d.dof, d.seconds, d.max_rel_diff
        )?,
        _ => {
            outln!(
                "dense modal summation ({} DOF, every mode) at every frequency: {:.3} s ({:.3} s eigendecomposition); largest relative difference {:.2e}; structured {ratio:.0}× faster",
                d.dof,
                d.seconds,
                d.eig_seconds.unwrap_or(f64::NAN),
                d.max_rel_diff
            )?;
            if let Some(lu) = &d.lu {
                let k = lu.frequencies_hz.len();
                let per = lu.seconds / k.max(1) as f64;
                outln!(
                    "dense complex LU at {k} of them ({:.3} s, {:.3} s each): modal summation within {:.2e}, structured within {:.2e}; {n} frequencies by LU would take ≈ {:.0} s, {:.0}× the structured run",
                    lu.seconds,
                    per,
                    lu.modal_rel_diff,
                    lu.structured_rel_diff,
                    per * n as f64,
                    per * n as f64 / structured_s.max(1e-12)
                )?;
            }
        }
    }
    Ok(())
}
