//! `cablevib import caspr`: a scene file from CASPR's bodies and cables XML files
//! ([`crate::caspr`]).

use super::args::{parse_vec3, ElementArg};
use super::CliError;
use crate::caspr::{import_files, message_number, ImportOptions};
use crate::scene::ElementKind;
use cablevib::outln;
use clap::{Args, Subcommand};
use nalgebra::Vector3;
use std::path::PathBuf;

/// `cablevib import`.
#[derive(Debug, Args)]
pub struct ImportArgs {
    /// The format to import from.
    #[command(subcommand)]
    pub format: ImportFormat,
}

/// Formats `cablevib import` reads.
#[derive(Debug, Subcommand)]
pub enum ImportFormat {
    /// CASPR's XML model: a bodies file (one rigid platform) and a cables file.
    Caspr(CasprArgs),
}

/// `cablevib import caspr`.
#[derive(Debug, Args)]
#[command(after_help = "\
Frames: anchors stay in CASPR's inertial frame (m); the scene's end-effector position is the \
platform's centre of mass and its attachment points are measured from it (docs/caspr.md). \
CASPR has no cable material: --weight-per-length, --area and --youngs-modulus are written \
into the scene and marked as coming from the command line.")]
pub struct CasprArgs {
    /// CASPR bodies file (XML): one <link_rigid> with mass, centre of mass and inertia.
    pub bodies: PathBuf,
    /// CASPR cables file (XML): cable sets of cable_ideal / cable_linear_spring.
    pub cables: PathBuf,
    /// Output scene file (TOML).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Cable set id (default: the file's default_cable_set).
    #[arg(long)]
    pub cable_set: Option<String>,
    /// Cable weight per length, N/m (not in CASPR; required: every missing option is
    /// reported at once).
    #[arg(long)]
    pub weight_per_length: Option<f64>,
    /// Cable cross-section, m² (not in CASPR; required).
    #[arg(long)]
    pub area: Option<f64>,
    /// Young's modulus of cable_ideal cables, Pa (not in CASPR; a cable_linear_spring's
    /// K, N, gives E = K / area instead).
    #[arg(long)]
    pub youngs_modulus: Option<f64>,
    /// Default pose: the platform link frame's origin x,y,z in m, as CASPR's joint
    /// translation (default: the model's q_initial).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub position: Option<Vector3<f64>>,
    /// Lower tension bound of every cable, N (default: each cable's force_min; required
    /// when a force_min is 0).
    #[arg(long)]
    pub t_min: Option<f64>,
    /// Element model written into the scene.
    #[arg(long, value_enum, default_value = "fem")]
    pub element: ElementArg,
    /// Elements per cable written into the scene.
    #[arg(long, default_value_t = 10)]
    pub elements: usize,
}

/// `cablevib import`.
pub fn run(a: &ImportArgs) -> Result<(), CliError> {
    match &a.format {
        ImportFormat::Caspr(c) => caspr(c),
    }
}

/// `cablevib import caspr`: import, validate, write, summarise.
fn caspr(a: &CasprArgs) -> Result<(), CliError> {
    let element = ElementKind::from(a.element);
    let opts = ImportOptions {
        cable_set: a.cable_set.clone(),
        weight_per_length_n_m: a.weight_per_length,
        youngs_modulus_pa: a.youngs_modulus,
        area_m2: a.area,
        position_m: a.position,
        t_min_n: a.t_min,
        element,
        elements_per_cable: a.elements,
    };
    let imported = import_files(&a.bodies, &a.cables, &opts)?;
    crate::output_file::write_whole(&a.output, imported.toml.as_bytes())
        .map_err(|e| CliError::Usage(format!("cannot write the scene: {e}")))?;
    let s = &imported.scene;
    let p = &s.ee_position_m;
    outln!(
        "{}: {} cables (set `{}`), {} kg, {}, centre of mass at [{}, {}, {}] m",
        a.output.display(),
        s.n_cables(),
        imported.cable_set,
        message_number(s.ee_mass_kg),
        if s.rigid {
            "rigid platform (6 DOF)"
        } else if imported.link.rotation_locked {
            "platform with locked rotation (T_XYZ, 3 DOF)"
        } else {
            "point mass (3 DOF)"
        },
        message_number(p.x),
        message_number(p.y),
        message_number(p.z)
    )?;
    if let Some(note) = imported.not_modelled() {
        outln!("{note}")?;
    }
    Ok(())
}
