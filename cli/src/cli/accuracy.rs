//! `cablevib accuracy`: f1 error and per-cycle cost of every model the scene can use; CSVs,
//! figures and this scene's section of accuracy.md.

use super::args::{resolve_scene, SceneArgs};
use super::figure::{self, parse_format};
use super::CliError;
use crate::report::accuracy_doc::{accuracy_markdown, hz, sci, update_section, us};
use crate::report::accuracy_figures::{accuracy_csv, accuracy_svgs, file_stem, mode3_csv};
use crate::report::csv::{sidecar_path, write_csv};
use crate::report::figure::FigureFormat;
use crate::study::accuracy::{self as study, dense_element_counts, AccuracyConfig};
use cablevib::outln;
use clap::Args;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

/// Default of `--period-s`, s.
const DEFAULT_PERIOD_S: f64 = 4.0;
/// Default of `--out-dir`: a directory of its own, not the repository's docs/.
const DEFAULT_OUT_DIR: &str = "accuracy-out";
/// Default of `--rounds`.
const DEFAULT_ROUNDS: usize = 5;
/// Default of `--dense-max`.
const DEFAULT_DENSE_MAX: usize = 40;

/// `cablevib accuracy`: f1 error and per-cycle cost of every model the scene can use.
#[derive(Debug, Args, Clone)]
pub struct AccuracyArgs {
    /// Scene and overrides (pose and T_min of the accuracy study; the model options
    /// are ignored: every model is run).
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output directory: writes OUT/accuracy.md (this scene's section), OUT/img/*.svg (.png, .pdf with --format)
    /// and OUT/data/*.csv. A new directory by default, so that a run from a checkout never
    /// rewrites the repository's docs/ (regenerate those with `--out-dir docs`).
    #[arg(long, default_value = DEFAULT_OUT_DIR)]
    pub out_dir: PathBuf,
    /// Largest number of elements per cable (FEM and catenary).
    #[arg(long, default_value_t = 80)]
    pub max_elements: usize,
    /// Every N from 1 to --max-elements instead of 1,2,3,4,5,6,8,10,12,16,20,25,32,40,50,64,80.
    #[arg(long)]
    pub all_n: bool,
    /// Timed cycles per model along the circle (f1 only and with the end-effector mode).
    #[arg(long, default_value_t = 2000)]
    pub cycles: usize,
    /// Timing rounds over all models; each model reports its fastest round's median.
    #[arg(long, default_value_t = DEFAULT_ROUNDS)]
    pub rounds: usize,
    /// Period of one revolution of the timing circle, s (poses 1 ms apart).
    #[arg(long, default_value_t = DEFAULT_PERIOD_S)]
    pub period_s: f64,
    /// Largest N of the dense mode-3 convergence study (paper Figs. 5 and 10); 0 skips it.
    #[arg(long, default_value_t = DEFAULT_DENSE_MAX)]
    pub dense_max: usize,
    /// Figure format: svg, png (3 px per SVG px) or pdf (vector, font embedded). Default:
    /// the figure path's extension, else svg; --format wins and sets the file's extension.
    #[arg(long, value_parser = parse_format)]
    pub format: Option<FigureFormat>,
}

/// The command that regenerates a section (options at their defaults left out).
fn command_line(a: &AccuracyArgs) -> String {
    let mut c = format!("cablevib accuracy {}", a.scene.scene);
    if let Some(p) = a.scene.position {
        let _ = write!(c, " --position {},{},{}", p.x, p.y, p.z);
    }
    if let Some(t) = a.scene.t_min {
        let _ = write!(c, " --t-min {t}");
    }
    let _ = write!(
        c,
        " --out-dir {} --max-elements {} --cycles {}",
        a.out_dir.display(),
        a.max_elements,
        a.cycles
    );
    if a.all_n {
        c.push_str(" --all-n");
    }
    if a.period_s != DEFAULT_PERIOD_S {
        let _ = write!(c, " --period-s {}", a.period_s);
    }
    if a.rounds != DEFAULT_ROUNDS {
        let _ = write!(c, " --rounds {}", a.rounds);
    }
    if a.dense_max != DEFAULT_DENSE_MAX {
        let _ = write!(c, " --dense-max {}", a.dense_max);
    }
    c
}

/// The figures' parts: OUT/img/accuracy-SCENE-PART.EXT.
const FIGURES: [&str; 3] = ["error-vs-n", "cost", "mode3"];

/// OUT/data/accuracy-SCENE.csv and OUT/data/mode3-SCENE.csv (`stem` the scene's file stem).
fn csv_paths(a: &AccuracyArgs, stem: &str) -> [PathBuf; 2] {
    ["accuracy", "mode3"].map(|k| a.out_dir.join("data").join(format!("{k}-{stem}.csv")))
}

/// OUT/img/accuracy-SCENE-PART.EXT.
fn figure_path(a: &AccuracyArgs, stem: &str, part: &str, fmt: FigureFormat) -> PathBuf {
    let name = format!("accuracy-{stem}-{part}.{}", fmt.ext());
    a.out_dir.join("img").join(name)
}

/// `cablevib accuracy`: writes OUT/data/accuracy-SCENE.csv, OUT/data/mode3-SCENE.csv (each
/// with its `.csv.json` sidecar),
/// OUT/img/accuracy-SCENE-{error-vs-n,cost,mode3}.svg and this scene's section of
/// OUT/accuracy.md.
pub fn run(a: &AccuracyArgs) -> Result<(), CliError> {
    let s = resolve_scene(&a.scene)?;
    // The file names hold the scene's name: checked here, before the work.
    let stem = file_stem(&s.name);
    let fmt = a.format.unwrap_or_default();
    let [accuracy_csv_path, mode3_csv_path] = csv_paths(a, &stem);
    let mut outputs = vec![
        sidecar_path(&accuracy_csv_path),
        sidecar_path(&mode3_csv_path),
        accuracy_csv_path.clone(),
        mode3_csv_path.clone(),
        a.out_dir.join("accuracy.md"),
    ];
    outputs.extend(FIGURES.map(|part| figure_path(a, &stem, part, fmt)));
    super::files::refuse_inputs(&outputs, &[a.scene.input_path()])?;
    let cfg = AccuracyConfig::new(a.max_elements, a.all_n, a.cycles, a.rounds, a.period_s)?;
    let t0 = Instant::now();
    eprintln!(
        "accuracy: {} models × {} cycles × 2 × {} rounds on {}",
        3 + 2 * cfg.element_counts.len(),
        a.cycles,
        a.rounds.max(1),
        s.name
    );
    let r = study::compute(&s, &cfg)?;
    let dense_ns = dense_element_counts(a.dense_max);
    eprintln!(
        "accuracy: real-time study done in {:.1} s; dense mode-3 study for N = {:?}",
        t0.elapsed().as_secs_f64(),
        dense_ns
    );
    let mode3 = study::compute_mode3(&s, &dense_ns)?;
    let cmd = command_line(a);
    write_csv(&accuracy_csv_path, accuracy_csv(&s, &r), &cmd)?;
    if !mode3.is_empty() {
        write_csv(&mode3_csv_path, mode3_csv(&s, &mode3), &cmd)?;
    }
    let (e_n, cost, m3) = accuracy_svgs(&s, &r, &mode3);
    let mut imgs = Vec::new();
    for (part, svg) in FIGURES.into_iter().zip([Some(e_n), Some(cost), m3]) {
        if let Some(svg) = svg {
            let path = figure_path(a, &stem, part, fmt);
            figure::write(&path, &svg, fmt)?;
            imgs.extend(path.file_name().map(|n| n.to_string_lossy().into_owned()));
        }
    }
    let rel: Vec<String> = imgs.iter().map(|i| format!("img/{i}")).collect();
    let body = accuracy_markdown(&s, &r, &mode3, &cmd, a.cycles, a.rounds.max(1), &rel);
    let md = a.out_dir.join("accuracy.md");
    update_section(&md, &s.name, &body)?;
    outln!(
        "accuracy: {}  f1,ref {:.9} Hz  continuous {:.9} Hz  ({:.1} s)",
        s.name,
        r.f1_ref_hz,
        r.f1_continuous_hz,
        t0.elapsed().as_secs_f64()
    )?;
    for x in &r.rows {
        outln!(
            "  {:<34} {:<10} f1 {:>14}  err {:>10}  p50 {:>7} µs  (+EE {:>7} µs)",
            x.label(),
            x.status.as_str(),
            hz(x.f1_hz),
            sci(x.err_ref),
            us(x.f1_ns.0),
            us(x.ee_ns.0)
        )?;
    }
    outln!("  wrote {}", md.display())?;
    Ok(())
}
