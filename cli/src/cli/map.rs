//! `cablevib map`: f1 (and f2 .. fK, the end-effector mode, the softest static stiffness)
//! over a workspace grid, as a CSV and heat-map figures.

use super::args::{parse_interval, parse_vec3, resolve_scene, SceneArgs};
use super::figure::{self, parse_format};
use super::{output_paths, CliError};
use crate::report::csv::{process_command_line, write_csv};
use crate::report::figure::FigureFormat;
use crate::report::map::{map_csv, map_svg, value_names};
use crate::report::with_ext;
use crate::scene::Scene;
use crate::study::map::{self as study, Interval, MapConfig, MapResult, Shard, Tilt};
use crate::study::points::{ee_mode_missing, MAX_MODES};
use cablevib::outln;
use cablevib::status::StatusCode;
use clap::{Args, ValueEnum};
use nalgebra::Vector3;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The plane of a heat map; the third axis is swept as slices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Plane {
    /// x horizontal, y vertical; slices along z.
    Xy,
    /// x horizontal, z vertical; slices along y.
    Xz,
    /// y horizontal, z vertical; slices along x.
    Yz,
}

impl From<Plane> for study::Plane {
    fn from(p: Plane) -> study::Plane {
        match p {
            Plane::Xy => study::Plane::Xy,
            Plane::Xz => study::Plane::Xz,
            Plane::Yz => study::Plane::Yz,
        }
    }
}

/// Which frequency a heat map shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MapValue {
    /// The first natural frequency of the whole model.
    F1,
    /// The end-effector mode (lowest mode with end-effector participation ≥ threshold).
    EeMode,
}

impl From<MapValue> for study::MapValue {
    fn from(v: MapValue) -> study::MapValue {
        match v {
            MapValue::F1 => study::MapValue::F1,
            MapValue::EeMode => study::MapValue::EeMode,
        }
    }
}

// The --modes help texts of map, trajectory and sweep-tmin say 1 ..= 16.
const _: () = assert!(MAX_MODES == 16, "update the --modes help texts");

/// A value of `--show`: `f1`, `ee-mode`, `fK` (K = 2 ..= 16) or `k-min`.
pub fn parse_shown(text: &str) -> Result<study::MapValue, String> {
    let t = text.trim();
    match t {
        "f1" => return Ok(study::MapValue::F1),
        "ee-mode" => return Ok(study::MapValue::EeMode),
        "k-min" => return Ok(study::MapValue::StiffnessMin),
        _ => {}
    }
    match t.strip_prefix('f').map(str::parse::<usize>) {
        Some(Ok(k)) if (2..=MAX_MODES).contains(&k) => Ok(study::MapValue::Mode(k)),
        _ => Err(format!(
            "`{t}`: expected f1, ee-mode, k-min or fK with K in 2..={MAX_MODES}"
        )),
    }
}

/// `cablevib map`: first natural frequency over a workspace grid.
#[derive(Debug, Args, Clone)]
pub struct MapArgs {
    /// Scene and overrides (`--t-min` sets the map's T_min; `--position` the coordinate
    /// of an axis given no range).
    #[command(flatten)]
    pub scene: SceneArgs,
    /// x range MIN,MAX or a single value, m (default: the central 80 % of the frame
    /// for a plane axis, the scene's position for the slice axis).
    #[arg(long, value_parser = parse_interval, allow_hyphen_values = true)]
    pub x: Option<Interval>,
    /// y range MIN,MAX or a single value, m.
    #[arg(long, value_parser = parse_interval, allow_hyphen_values = true)]
    pub y: Option<Interval>,
    /// z range MIN,MAX or a single value, m.
    #[arg(long, value_parser = parse_interval, allow_hyphen_values = true)]
    pub z: Option<Interval>,
    /// Grid step, m (all axes).
    #[arg(long, default_value_t = 0.1)]
    pub step: f64,
    /// Plane of the heat map; a range on the third axis gives one panel per slice.
    #[arg(long, value_enum, default_value = "xy")]
    pub plane: Plane,
    /// Frequency shown in the main heat map, PREFIX.svg (the CSV has both).
    #[arg(long, value_enum, default_value = "f1")]
    pub value: MapValue,
    /// Modes per grid point in the CSV: columns f1_hz (as before) and f2_hz .. fK_hz, Hz
    /// (1 ..= 16).
    #[arg(long, default_value_t = 1)]
    pub modes: usize,
    /// More heat maps, comma-separated, each written next to the main figure as
    /// PREFIX-NAME.svg (or, with --svg FILE.svg, FILE-NAME.svg): fK (the K-th natural frequency, Hz; needs K <= --modes), k-min (the smallest
    /// principal value of the static end-effector stiffness, N/m), f1, ee-mode.
    #[arg(long, value_delimiter = ',', value_parser = parse_shown)]
    pub show: Vec<study::MapValue>,
    /// Output prefix: writes PREFIX.csv, its metadata PREFIX.csv.json and PREFIX.svg.
    #[arg(long, default_value = "map")]
    pub out: PathBuf,
    /// Write the figure here instead of PREFIX.svg (PREFIX.png, PREFIX.pdf with --format).
    #[arg(long, visible_alias = "figure")]
    pub svg: Option<PathBuf>,
    /// Figure format: svg, png (3 px per SVG px) or pdf (vector, font embedded). Default:
    /// the figure path's extension, else svg; --format wins and sets the file's extension.
    #[arg(long, value_parser = parse_format)]
    pub format: Option<FigureFormat>,
    /// Worker threads, one estimator each (0: one per core). Any count gives the same
    /// numbers, bit for bit.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Sweep the orientation (rigid end-effectors only; a point-mass scene refuses it): one
    /// panel per angle MIN,MAX (degrees; or a single angle), the scene's orientation (or
    /// --orientation) turned about --tilt-axis by each angle. The slice axis then takes a
    /// single value.
    #[arg(long, value_parser = parse_interval, allow_hyphen_values = true, value_name = "MIN,MAX")]
    pub tilt_deg: Option<Interval>,
    /// Rotation axis of --tilt-deg in the world frame, X,Y,Z (any length).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, default_value = "1,0,0", requires = "tilt_deg")]
    pub tilt_axis: Vector3<f64>,
    /// Angle step of --tilt-deg, degrees.
    #[arg(long, default_value_t = 10.0, requires = "tilt_deg")]
    pub tilt_step_deg: f64,
    /// Skip the end-effector mode (f1 only; faster).
    #[arg(long)]
    pub no_ee_mode: bool,
    /// Heat-map panels per row (3-D grids).
    #[arg(long, default_value_t = 4)]
    pub columns: usize,
    /// No progress bar (it is shown only on a terminal, after a second).
    #[arg(long)]
    pub quiet: bool,
    /// Evaluate shard I of N only (1 <= I <= N), e.g. one task of a batch scheduler's array
    /// job: a contiguous, balanced run of the grid's rows. Writes PREFIX.csv and its sidecar
    /// (no figures: a shard holds part of the grid); the shards' CSVs, in order and with the
    /// header kept from the first only, are the unsharded CSV byte for byte.
    #[arg(long, value_name = "I/N", conflicts_with_all = ["svg", "format", "show"])]
    pub shard: Option<String>,
}

impl MapArgs {
    /// The study configuration of these options (a bad `--shard` is a one-line usage error).
    pub fn config(&self) -> Result<MapConfig, CliError> {
        let shard = match &self.shard {
            Some(t) => Some(Shard::parse(t).map_err(|e| CliError::Usage(format!("--shard {e}")))?),
            None => None,
        };
        Ok(MapConfig {
            ranges_m: [self.x, self.y, self.z],
            step_m: self.step,
            plane: self.plane.into(),
            threads: self.threads,
            ee_mode: !self.no_ee_mode,
            modes: self.modes,
            progress: !self.quiet,
            tilt: self.tilt_deg.map(|range_deg| Tilt {
                axis: self.tilt_axis,
                range_deg,
                step_deg: self.tilt_step_deg,
            }),
            shard,
        })
    }
}

/// A `--show fK` with K above `--modes`, as a usage error.
fn check_shown(a: &MapArgs) -> Result<(), CliError> {
    for v in &a.show {
        if let study::MapValue::Mode(k) = *v {
            if k > a.modes {
                let msg = format!("--show f{k} needs --modes {k} or more (got {})", a.modes);
                return Err(CliError::Usage(msg));
            }
        }
    }
    Ok(())
}

/// Resolve the scene and compute the map (no files).
pub fn compute(a: &MapArgs) -> Result<(Scene, MapResult), CliError> {
    check_shown(a)?;
    let cfg = a.config()?;
    let s = resolve_scene(&a.scene)?;
    let m = study::compute(&s, &cfg)?;
    super::args::warn_if_sag_matters(&s, None);
    Ok((s, m))
}

/// `cablevib map`: writes PREFIX.csv (every grid point, with its status), its metadata
/// PREFIX.csv.json, PREFIX.svg and one PREFIX-NAME.svg per `--show` value.
pub fn run(a: &MapArgs) -> Result<(), CliError> {
    let t0 = Instant::now();
    let (s, m) = compute(a)?;
    let secs = t0.elapsed().as_secs_f64();
    let value = a.value.into();
    let (csv_path, svg_path, fmt) = output_paths(&a.out, &a.svg, a.format)?;
    write_csv(&csv_path, map_csv(&s, &m), &process_command_line())?;
    let mut written = vec![csv_path.display().to_string()];
    if m.shard.is_none() {
        figure::write(&svg_path, &map_svg(&s, &m, value), fmt)?;
        written.push(svg_path.display().to_string());
        for &v in &a.show {
            let p = shown_path(&svg_path, &value_names(v).2, fmt);
            figure::write(&p, &map_svg(&s, &m, v), fmt)?;
            written.push(p.display().to_string());
        }
    }
    let of_grid = match m.shard {
        Some(sh) => format!(
            " (shard {}/{} of {} grid points; no figures)",
            sh.index, sh.count, m.grid_points
        ),
        None => String::new(),
    };
    outln!(
        "map: scene {}  T_min {}  {} points{of_grid} in {:.2} s ({} threads)  statuses: {}",
        s.name,
        s.t_min_label(),
        m.points.len(),
        secs,
        m.threads,
        m.status_counts().summary()
    )?;
    for v in std::iter::once(value).chain(a.show.iter().copied()) {
        print_range(&m, v)?;
    }
    if !a.no_ee_mode {
        let missing = m.points.iter().filter(|p| ee_mode_missing(&p.estimate));
        print_ee_mode_missing(missing.count(), m.status_counts().count(StatusCode::Ok))?;
    }
    outln!("  wrote {}", written.join(", "))?;
    Ok(())
}

/// One line when `missing` of the `ok` estimates carry no end-effector mode (their
/// `ee_mode_hz` is NaN): none reached the participation threshold within the scan's bounds.
pub fn print_ee_mode_missing(missing: usize, ok: u64) -> Result<(), CliError> {
    if missing > 0 {
        outln!(
            "  end-effector mode: none found within the scan's bounds at {missing} of {ok} ok points (ee_mode_hz NaN there)"
        )?;
    }
    Ok(())
}

/// The figure of a `--show` value next to the main figure: `DIR/NAME.EXT` →
/// `DIR/NAME-PART.EXT` (`map.svg` → `map-k-min.svg`), EXT the format's.
pub fn shown_path(main: &Path, part: &str, fmt: FigureFormat) -> PathBuf {
    let stem = match main.extension() {
        Some(e) if e == fmt.ext() => main.with_extension(""),
        _ => main.to_path_buf(),
    };
    let mut prefix = stem.into_os_string();
    prefix.push(format!("-{part}"));
    with_ext(Path::new(&prefix), fmt.ext())
}

/// The smallest and largest valid value `v` of the map, and where.
fn print_range(m: &MapResult, v: study::MapValue) -> Result<(), CliError> {
    let (_, unit, part) = value_names(v);
    let name = if v == study::MapValue::EeMode {
        "end-effector mode".to_string()
    } else {
        part
    };
    if let (Some((pmin, fmin)), Some((pmax, fmax))) = (m.min(v), m.max(v)) {
        outln!(
            "  {name}: min {fmin:.4} {unit} at ({:.3}, {:.3}, {:.3}) m, max {fmax:.4} {unit} at ({:.3}, {:.3}, {:.3}) m",
            pmin.x, pmin.y, pmin.z, pmax.x, pmax.y, pmax.z
        )?;
    }
    Ok(())
}
