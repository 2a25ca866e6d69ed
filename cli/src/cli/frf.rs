//! `cablevib frf`: the receptance H(ω) at the end-effector of one pose over a frequency
//! band ([`crate::modal::frf`]: exact at a complex λ for loss-factor and Rayleigh damping,
//! modal superposition with static correction for modal damping; with sag, the sagged FEM
//! chains at the complex λ, or their structured shapes' modal superposition), as a table, a CSV
//! ([`crate::report::frf`]), a Bode figure and JSON; `--dense` also solves the assembled
//! complex problem at every frequency, `--dense-modal` sums over every mode of the
//! assembled problem ([`super::frf_dense`]), and both print the difference and both times.

use super::args::{damping_label, resolve_scene, SceneArgs};
use super::figure::{self, parse_format};
use super::frf_dense::{self, DenseCheck};
use super::modes::pose_model;
use super::{json_f64, CliError};
use crate::estimator::{Estimator, Tmin};
use crate::kinematics::Pose;
use crate::modal::{frequency_grid, lambda_to_hz, FrfError, ModalBasis, ModalParams, ModalSolver};
use crate::report::csv::{process_command_line, write_csv};
use crate::report::figure::FigureFormat;
use crate::report::frf::{bode_svg, frf_csv, frf_meta, FrfData, COORDS};
use crate::scene::{
    Damping, ElementKind, Scene, MAX_LOSS_FACTOR, MAX_MODAL_RATIO, MAX_RAYLEIGH_ALPHA_PER_S,
    MAX_RAYLEIGH_BETA_S,
};
use crate::study;
use cablevib::outln;
use clap::Args;
use nalgebra::{DMatrix, Matrix6};
use num_complex::Complex64;
use std::path::PathBuf;
use std::time::Instant;

/// Default and largest ratio of the modal-damping basis's cut-off to the band's top: the
/// modes below 4 × `--to-hz` are superposed, the others taken quasi-statically.
const MODAL_CUTOFF_RATIO: f64 = 4.0;
/// Natural frequencies marked and listed: the modes with at least this end-effector
/// participation (1 %).
const MARK_PARTICIPATION: f64 = 0.01;

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

/// The damping asked for: the options, else the scene's; out-of-range values refused.
fn damping(a: &FrfArgs, scene: Damping) -> Result<Damping, CliError> {
    let given = [
        a.loss_factor.is_some(),
        a.rayleigh.is_some(),
        a.modal_ratio.is_some(),
        a.undamped,
    ];
    if given.iter().filter(|&&g| g).count() > 1 {
        let msg = "give one of --loss-factor, --rayleigh, --modal-ratio, --undamped";
        return Err(CliError::Usage(msg.into()));
    }
    let bad = |name: &str, v: f64, max: f64| {
        CliError::Usage(format!("{name} {v}: must be finite, >= 0 and < {max}"))
    };
    let ok = |v: f64, max: f64| v.is_finite() && v >= 0.0 && v < max;
    if let Some(eta) = a.loss_factor {
        if !ok(eta, MAX_LOSS_FACTOR) {
            return Err(bad("--loss-factor", eta, MAX_LOSS_FACTOR));
        }
        return Ok(Damping::LossFactor { eta });
    }
    if let Some((alpha, beta)) = a.rayleigh {
        if !ok(alpha, MAX_RAYLEIGH_ALPHA_PER_S) {
            return Err(bad("--rayleigh alpha", alpha, MAX_RAYLEIGH_ALPHA_PER_S));
        }
        if !ok(beta, MAX_RAYLEIGH_BETA_S) {
            return Err(bad("--rayleigh beta", beta, MAX_RAYLEIGH_BETA_S));
        }
        return Ok(Damping::Rayleigh {
            alpha_per_s: alpha,
            beta_s: beta,
        });
    }
    if let Some(zeta) = a.modal_ratio {
        if !ok(zeta, MAX_MODAL_RATIO) {
            return Err(bad("--modal-ratio", zeta, MAX_MODAL_RATIO));
        }
        return Ok(Damping::ModalRatio { zeta });
    }
    if a.undamped {
        return Ok(Damping::None);
    }
    Ok(scene)
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

/// `cablevib frf`.
pub fn run(a: &FrfArgs) -> Result<(), CliError> {
    let freqs = frequency_grid(a.from_hz, a.to_hz, a.points, a.log)
        .map_err(|e| CliError::Usage(format!("--from-hz/--to-hz/--points: {e}")))?;
    figure::format_needs_svg(&a.svg, a.format)?;
    let s = resolve_scene(&a.scene)?;
    let damping = damping(a, s.damping)?;
    let c = if s.model.sag {
        sagged(a, &s, &damping, &freqs)?
    } else {
        taut(a, &s, &damping, &freqs)?
    };
    let dim = c.dim;
    let outputs = coords(&a.output, dim, "--output")?;
    let inputs = coords(&a.input, dim, "--input")?;
    let (h, natural_hz, structured_s, dense) = (c.h, c.natural_hz, c.structured_s, c.dense);
    let pairs: Vec<(usize, usize)> = outputs
        .iter()
        .flat_map(|&o| inputs.iter().map(move |&i| (o, i)))
        .collect();
    let data = FrfData {
        frequencies_hz: freqs,
        h,
        pairs,
        natural_hz,
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

/// The dense check asked for (`--dense`, `--dense-modal`), or none.
fn dense_check(
    a: &FrfArgs,
    dense: impl FnOnce() -> Result<(DMatrix<f64>, DMatrix<f64>), String>,
    dim: usize,
    damping: &Damping,
    freqs: &[f64],
    h: &[Matrix6<Complex64>],
) -> Result<Option<DenseCheck>, CliError> {
    if !(a.dense || a.dense_modal) {
        return Ok(None);
    }
    if a.dense {
        if let Damping::ModalRatio { .. } = damping {
            let msg = "--dense: modal damping has no damping matrix to assemble (loss factor, Rayleigh or none; --dense-modal covers modal damping)";
            return Err(CliError::Usage(msg.into()));
        }
    }
    let opt = if a.dense { "--dense" } else { "--dense-modal" };
    let (k, m) = dense().map_err(|e| CliError::Analysis(format!("{opt}: {e}")))?;
    if a.dense {
        frf_dense::lu_every(&k, &m, dim, damping, freqs, h).map(Some)
    } else {
        frf_dense::modal_every(&k, &m, dim, damping, freqs, h, a.dense_lu_points).map(Some)
    }
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

/// What one pose's response computation gives the output.
struct Computed {
    scene: Scene,
    dim: usize,
    h: Vec<Matrix6<Complex64>>,
    natural_hz: Vec<f64>,
    structured_s: f64,
    /// --dense / --dense-modal.
    dense: Option<DenseCheck>,
}

/// Taut (chord) cables: the structured solver of the pose model.
fn taut(a: &FrfArgs, s: &Scene, damping: &Damping, freqs: &[f64]) -> Result<Computed, CliError> {
    let pose = pose_model(s)?;
    let dim = pose.dim();
    let mut solver = ModalSolver::new(ModalParams::default());
    pose.load(&mut solver);
    // The natural frequencies in the band whose modes move the end-effector (marked on the
    // figure; the string modes the end-effector hardly feels are left out).
    let n_band = solver.count_below(crate::modal::hz_to_lambda(a.to_hz)) as usize;
    let mut modes = vec![crate::modal::Mode::default(); n_band.min(1000)];
    let nm = solver
        .modes(modes.len(), &mut modes)
        .map_err(|e| CliError::Analysis(e.to_string()))?;
    let natural_hz = marked(a, &modes[..nm]);
    let cutoff_hz = MODAL_CUTOFF_RATIO * a.to_hz;
    let basis_modes = match damping {
        Damping::ModalRatio { .. } => solver.count_below(crate::modal::hz_to_lambda(cutoff_hz)),
        _ => 0,
    };
    announce_frf(&pose.scene, damping, freqs.len(), basis_modes as usize)?;
    let t0 = Instant::now();
    let h = study::cost::receptance(&pose, &mut solver, damping, freqs, cutoff_hz, Some("frf"))?;
    let structured_s = t0.elapsed().as_secs_f64();
    let get = || pose.dense().map_err(|e| e.to_string());
    let dense = dense_check(a, get, dim, damping, freqs, &h)?;
    Ok(Computed {
        scene: pose.scene.clone(),
        dim,
        h,
        natural_hz,
        structured_s,
        dense,
    })
}

/// The up-front estimate of a long response on stderr ([`study::cost::estimate_cost`]).
fn announce_frf(
    s: &Scene,
    damping: &Damping,
    points: usize,
    basis_modes: usize,
) -> Result<(), CliError> {
    let work = study::cost::Work::Frf {
        damping,
        points,
        basis_modes: basis_modes.min(crate::modal::MAX_FRF_MODES),
    };
    super::modes::announce(&study::cost::estimate_cost(s, &work))
}

/// The natural frequencies to mark: first of each cluster, end-effector participation at
/// least [`MARK_PARTICIPATION`], within the band.
fn marked(a: &FrfArgs, modes: &[crate::modal::Mode]) -> Vec<f64> {
    modes
        .iter()
        .enumerate()
        .filter(|(i, m)| m.cluster_start == *i && m.ee_participation >= MARK_PARTICIPATION)
        .map(|(_, m)| lambda_to_hz(m.lambda))
        .filter(|&f| f >= a.from_hz)
        .collect()
}

/// Modal damping with sag: modal superposition of the sagged structured shapes below
/// `cutoff_hz` (the estimator's basis, doubling its size from 16 until a mode lies above
/// the cut-off, at most [`crate::modal::MAX_FRF_MODES`] or the model's `total`) with the
/// residual flexibility of the rest ([`ModalBasis::from_modes`]).
fn sagged_modal(
    est: &mut Estimator,
    zeta: f64,
    cutoff_hz: f64,
    total: usize,
    freqs: &[f64],
) -> Result<Vec<nalgebra::Matrix6<num_complex::Complex64>>, CliError> {
    let cap = crate::modal::MAX_FRF_MODES.min(total).max(1);
    let mut k = 16usize.min(cap);
    let basis = loop {
        let b = est
            .ee_modal_basis(k)
            .map_err(|e| CliError::Analysis(format!("modal basis with sag: {e}")))?;
        let top = b.lambda.last().map_or(0.0, |&l| lambda_to_hz(l));
        if top > cutoff_hz || k >= cap {
            break b;
        }
        k = (2 * k).min(cap);
    };
    let mb = ModalBasis::from_modes(basis.lambda, basis.phi_ee, &basis.flexibility, basis.dim)
        .map_err(|e| CliError::Analysis(e.to_string()))?;
    Ok(freqs
        .iter()
        .map(|&f| mb.receptance(zeta, 2.0 * std::f64::consts::PI * f))
        .collect())
}

/// Most modes searched for the marks with sag (the sagged solver's lowest ones).
const SAG_MARK_MODES: usize = 400;

/// Sagging cables (FEM chains on the catenary): the sagged tension solve at the scene's
/// pose, then the sagged structured solver's D at the complex λ of each frequency.
fn sagged(a: &FrfArgs, s: &Scene, damping: &Damping, freqs: &[f64]) -> Result<Computed, CliError> {
    if s.model.element == ElementKind::Continuous {
        return Err(CliError::Usage(FrfError::SagContinuous.to_string()));
    }
    let mut est = Estimator::new(s).map_err(|e| CliError::Analysis(e.to_string()))?;
    let pose = Pose::in_scene(s, s.ee_position_m);
    let e = *est.update(&pose, Tmin::Scene);
    if !e.status.is_ok() {
        let why = e.error.map(|x| x.to_string()).unwrap_or_default();
        return Err(CliError::Analysis(format!("sagged pose: {why}")));
    }
    // The lowest modes, doubling the count until one lies above the band (the sagged
    // solver has no count query here; the top of its spectrum is not needed).
    let total = s.n_cables() * 3 * s.model.elements_per_cable.saturating_sub(1) + 6;
    let mut k = 16usize;
    let (modes, nm) = loop {
        let mut modes = vec![crate::modal::Mode::default(); k.min(total)];
        let nm = est
            .modes(modes.len(), &mut modes)
            .map_err(|e| CliError::Analysis(e.to_string()))?;
        let top = modes[..nm].last().map_or(0.0, |m| lambda_to_hz(m.lambda));
        if top > a.to_hz || k >= SAG_MARK_MODES.min(total) {
            break (modes, nm);
        }
        k *= 2;
    };
    let mut natural_hz = marked(a, &modes[..nm]);
    natural_hz.retain(|&f| f <= a.to_hz);
    let mut sag = est
        .sag_modal()
        .cloned()
        .ok_or_else(|| CliError::Analysis("no sagged pose loaded".into()))?;
    let dim = sag.dim();
    let t0 = Instant::now();
    let h = if let Damping::ModalRatio { zeta } = *damping {
        sagged_modal(&mut est, zeta, MODAL_CUTOFF_RATIO * a.to_hz, total, freqs)?
    } else {
        announce_frf(s, damping, freqs.len(), 0)?;
        let chunk = study::cost::frf_chunk(s, damping);
        study::cost::in_chunks(Some("frf"), freqs.len(), chunk, |r| {
            sag.receptance_over(damping, &freqs[r])
        })
        .map_err(|e| CliError::Analysis(e.to_string()))?
    };
    let structured_s = t0.elapsed().as_secs_f64();
    let get = || est.dense_matrices().map_err(|e| e.to_string());
    let dense = dense_check(a, get, dim, damping, freqs, &h)?;
    Ok(Computed {
        scene: est.scene().clone(),
        dim,
        h,
        natural_hz,
        structured_s,
        dense,
    })
}
