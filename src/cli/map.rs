//! `cablevib map`: f1 over a workspace grid, as a CSV and a heat-map figure.

use super::args::{parse_interval, resolve_scene, SceneArgs};
use super::{output_paths, CliError};
use crate::report::map::{map_csv, map_svg};
use crate::report::write_file;
use crate::scene::Scene;
use crate::study::map::{self as study, Interval, MapConfig, MapResult};
use clap::{Args, ValueEnum};
use std::path::PathBuf;
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
    /// Frequency shown in the heat map (the CSV has both).
    #[arg(long, value_enum, default_value = "f1")]
    pub value: MapValue,
    /// Output prefix: writes PREFIX.csv and PREFIX.svg.
    #[arg(long, default_value = "map")]
    pub out: PathBuf,
    /// Write the figure here instead of PREFIX.svg.
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Worker threads (one estimator each).
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Skip the end-effector mode (f1 only; faster).
    #[arg(long)]
    pub no_ee_mode: bool,
    /// Heat-map panels per row (3-D grids).
    #[arg(long, default_value_t = 4)]
    pub columns: usize,
    /// No progress on stderr.
    #[arg(long)]
    pub quiet: bool,
}

impl MapArgs {
    /// The study configuration of these options.
    pub fn config(&self) -> MapConfig {
        MapConfig {
            ranges_m: [self.x, self.y, self.z],
            step_m: self.step,
            plane: self.plane.into(),
            threads: self.threads,
            ee_mode: !self.no_ee_mode,
            progress: !self.quiet,
        }
    }
}

/// Resolve the scene and compute the map (no files).
pub fn compute(a: &MapArgs) -> Result<(Scene, MapResult), CliError> {
    let s = resolve_scene(&a.scene)?;
    let m = study::compute(&s, &a.config())?;
    Ok((s, m))
}

/// `cablevib map`: writes PREFIX.csv (every grid point, with its status) and PREFIX.svg.
pub fn run(a: &MapArgs) -> Result<(), CliError> {
    let t0 = Instant::now();
    let (s, m) = compute(a)?;
    let secs = t0.elapsed().as_secs_f64();
    let value = a.value.into();
    let (csv_path, svg_path) = output_paths(&a.out, &a.svg);
    write_file(&csv_path, &map_csv(&s, &m))?;
    write_file(&svg_path, &map_svg(&s, &m, value))?;
    println!(
        "map: scene {}  T_min {} N  {} points in {:.2} s ({} threads)  statuses: {}",
        s.name,
        s.t_min_n,
        m.points.len(),
        secs,
        a.threads,
        m.status_counts().summary()
    );
    let name = match a.value {
        MapValue::F1 => "f1",
        MapValue::EeMode => "end-effector mode",
    };
    if let (Some((pmin, fmin)), Some((pmax, fmax))) = (m.min(value), m.max(value)) {
        println!(
            "  {name}: min {fmin:.4} Hz at ({:.3}, {:.3}, {:.3}) m, max {fmax:.4} Hz at ({:.3}, {:.3}, {:.3}) m",
            pmin.x, pmin.y, pmin.z, pmax.x, pmax.y, pmax.z
        );
    }
    println!("  wrote {} and {}", csv_path.display(), svg_path.display());
    Ok(())
}
