//! Import of robots from CASPR's XML model files (a bodies file and a cables file) into a
//! scene ([`crate::scene`]), for `cablevib import caspr`.
//!
//! What is read: the one moving link ([`bodies`]: joint type and initial pose, mass, centre
//! of mass, inertia) and one cable set ([`cables`]: anchors, platform attachments,
//! force_min and force_max, and the `K` of linear-spring cables). What CASPR does not have
//! comes from [`ImportOptions`]: weight per length, Young's modulus, cross-section, element
//! model, and a T_min for cables whose force_min is 0.
//!
//! ## Frames
//!
//! The scene's end-effector reference point is the **centre of mass** G: the scene applies
//! the weight m·g there and takes the inertia about it. With the link frame's origin O at
//! o (inertial frame, m), its rotation R, the centre of mass r_G (link frame, from O) and a
//! platform attachment location r_A (link frame, from O for `attachment_reference="joint"`,
//! from G for `"com"`):
//!
//! ```text
//!   end_effector.position    = o + R r_G
//!   end_effector.orientation = R (quaternion [w, x, y, z])
//!   cables[i].attachment     = r_A − r_G  (joint)   or   r_A  (com)      (body frame, from G)
//!   cables[i].anchor         = base location (inertial frame, as CASPR gives it)
//! ```
//!
//! so every attachment point lands where CASPR puts it: o + R r_A = position + R·attachment.
//! When every attachment is at G the platform is a point mass (3 DOF, no inertia written);
//! otherwise `effects.rotation = true` (6 DOF, inertia about G, at least 6 cables). A
//! `T_XYZ` joint locks the rotation: the platform is a point mass whose anchors are shifted
//! by the attachment offsets, `anchor = a_i − R (r_A − r_G)`, so every cable runs as in
//! CASPR and only the force rows of the equilibrium count (the joint takes the moment).
//! Gravity is CASPR's, −9.81 m/s² along z; a `PLANAR_XY` joint carries the weight in its
//! plane, so the cables do not (`weight_carried = false`).
//!
//! ## Stiffness and bounds
//!
//! `cable_ideal` cables get EA = E·A from the options; a `cable_linear_spring`'s `K` (N,
//! CASPR's stiffness K/length) is its EA, written as Young's modulus K/A with the
//! option's A. Each cable's force_min and force_max (N) become its t_min and t_max; a
//! force_min of 0 (a cable allowed to go slack) has no tension stiffness, so it needs
//! [`ImportOptions::t_min_n`].

pub mod bodies;
pub mod cables;
mod convert;
mod xml;

pub use crate::input_file::message_number;
pub use bodies::Link;
pub use cables::{AttachmentReference, CasprCable, CasprPulley};

use crate::input_file::{read_text, InputFileError};
use crate::scene::{ElementKind, Scene, SceneError};
use nalgebra::Vector3;
use std::path::Path;

/// Largest CASPR model file read, bytes: the largest of CASPR's own are tens of kB.
pub const MAX_CASPR_FILE_BYTES: u64 = 16 * 1024 * 1024;

/// Errors of the import, each one line naming the file (and the line and element where
/// there is one).
#[derive(Debug, thiserror::Error)]
pub enum CasprError {
    /// A file could not be read (missing, not a regular file, too large, not UTF-8).
    #[error(transparent)]
    Input(#[from] InputFileError),
    /// A DOCTYPE with an internal subset, where a file can declare its own entities, whose
    /// expansion is unbounded: refused before parsing.
    #[error(
        "{file}: a DOCTYPE with an internal subset (`<!DOCTYPE x [...]>`, which can declare \
         entities) is refused: CASPR's files name an external DTD only"
    )]
    InternalDtd {
        /// File name.
        file: String,
    },
    /// Not well-formed XML.
    #[error("{file}: malformed XML: {message}")]
    Xml {
        /// File name.
        file: String,
        /// The XML parser's report (one line, with line and column).
        message: String,
    },
    /// An element is missing, has a bad value or is of an unsupported kind.
    #[error("{file}:{line}: <{element}>: {message}")]
    Element {
        /// File name.
        file: String,
        /// Line of the element (1-based).
        line: u32,
        /// The element's tag.
        element: String,
        /// What is wrong.
        message: String,
    },
    /// The model as a whole cannot be imported (several moving links, no such cable set,
    /// too few cables for a rigid platform).
    #[error("{file}: {message}")]
    Model {
        /// File name.
        file: String,
        /// What is wrong.
        message: String,
    },
    /// Several cable sets, no `default_cable_set` and none chosen
    /// ([`ImportOptions::cable_set`]).
    #[error("{}", no_cable_set(.file, *.line, .element, *.sets, .listed, &ImportOption::name))]
    NoCableSet {
        /// File name.
        file: String,
        /// Line of the element (1-based).
        line: u32,
        /// The element's tag.
        element: String,
        /// Number of cable sets in the file.
        sets: usize,
        /// Their ids, comma-separated.
        listed: String,
    },
    /// Options the cable set needs and that were not given, every one at once, naming the
    /// cables file.
    #[error("{}", missing_options(.file, .cable_set, .missing, &ImportOption::name))]
    MissingOptions {
        /// The cables file's name.
        file: String,
        /// The cable set.
        cable_set: String,
        /// What is missing, in the order of [`ImportOption`].
        missing: Vec<MissingOption>,
    },
    /// An import option is out of range.
    #[error("{0}")]
    Options(String),
    /// The scene written does not validate (a value CASPR allows and the scene does not).
    #[error("imported scene: {0}")]
    Scene(#[from] SceneError),
}

/// An option of the import ([`ImportOptions`]), as the errors that ask for one name it: the
/// library by its field ([`ImportOption::name`]), a front end by its own name
/// ([`CasprError::render`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImportOption {
    /// [`ImportOptions::cable_set`].
    CableSet,
    /// [`ImportOptions::weight_per_length_n_m`].
    WeightPerLength,
    /// [`ImportOptions::area_m2`].
    Area,
    /// [`ImportOptions::youngs_modulus_pa`].
    YoungsModulus,
    /// [`ImportOptions::t_min_n`].
    TMin,
}

impl ImportOption {
    /// The option's field in [`ImportOptions`].
    pub fn name(self) -> &'static str {
        match self {
            ImportOption::CableSet => "cable_set",
            ImportOption::WeightPerLength => "weight_per_length_n_m",
            ImportOption::Area => "area_m2",
            ImportOption::YoungsModulus => "youngs_modulus_pa",
            ImportOption::TMin => "t_min_n",
        }
    }
}

/// An option a cable set needs and was not given.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MissingOption {
    /// The option.
    pub option: ImportOption,
    /// Its unit and why the set needs it (`(Pa) for the cable_ideal cables, …`).
    pub why: String,
}

impl CasprError {
    /// The message with each option called `name(option)` (the command line passes its
    /// flags); equal to the `Display` text with [`ImportOption::name`].
    pub fn render(&self, name: &dyn Fn(ImportOption) -> &'static str) -> String {
        match self {
            CasprError::NoCableSet {
                file,
                line,
                element,
                sets,
                listed,
            } => no_cable_set(file, *line, element, *sets, listed, name),
            CasprError::MissingOptions {
                file,
                cable_set,
                missing,
            } => missing_options(file, cable_set, missing, name),
            other => other.to_string(),
        }
    }
}

/// [`CasprError::NoCableSet`]'s message.
fn no_cable_set(
    file: &str,
    line: u32,
    element: &str,
    sets: usize,
    listed: &str,
    name: &dyn Fn(ImportOption) -> &'static str,
) -> String {
    format!(
        "{file}:{line}: <{element}>: no default_cable_set and {sets} cable sets: pick one with {} ({listed})",
        name(ImportOption::CableSet)
    )
}

/// [`CasprError::MissingOptions`]'s message.
fn missing_options(
    file: &str,
    cable_set: &str,
    missing: &[MissingOption],
    name: &dyn Fn(ImportOption) -> &'static str,
) -> String {
    let each: Vec<String> = missing
        .iter()
        .map(|m| format!("{} {}", name(m.option), m.why))
        .collect();
    format!(
        "{file}: cable set `{cable_set}` needs {} more option{}: {}",
        missing.len(),
        if missing.len() == 1 { "" } else { "s" },
        each.join("; ")
    )
}

/// What the import needs that CASPR's files do not give. All SI.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportOptions {
    /// Cable set id; None: the file's `default_cable_set`.
    pub cable_set: Option<String>,
    /// Cable weight per length γ, N/m (required: None is reported with every other
    /// missing option).
    pub weight_per_length_n_m: Option<f64>,
    /// Young's modulus E of `cable_ideal` cables, Pa (None: the set must have none).
    pub youngs_modulus_pa: Option<f64>,
    /// Cable cross-section A, m² (required, as `weight_per_length_n_m`).
    pub area_m2: Option<f64>,
    /// Link-frame origin of the default pose (CASPR's joint translation), m; None: the
    /// model's `q_initial`.
    pub position_m: Option<Vector3<f64>>,
    /// Lower tension bound for every cable, N; None: each cable's force_min (then every
    /// force_min must be > 0).
    pub t_min_n: Option<f64>,
    /// Element model written into the scene.
    pub element: ElementKind,
    /// Elements per cable written into the scene.
    pub elements_per_cable: usize,
}

/// The result of an import.
#[derive(Debug, Clone)]
pub struct Imported {
    /// The scene file's text (TOML, with comments saying where each value came from).
    pub toml: String,
    /// The same text parsed and validated.
    pub scene: Scene,
    /// The cable set used.
    pub cable_set: String,
    /// The link as read.
    pub link: Link,
    /// The cables as read.
    pub cables: Vec<CasprCable>,
}

/// What an import of cables with pulleys does not model, in one line.
pub const PULLEY_NOT_MODELLED: &str = "pulleys: the swivel geometry is modelled (exit point, free length, wrap); not modelled: pulley inertia and friction, the cable between winch and pulley, and a screw drive's outlet motion along its drum (the pulley stays at constant_winch_point)";

impl Imported {
    /// [`PULLEY_NOT_MODELLED`] when a cable has a pulley, else None.
    pub fn not_modelled(&self) -> Option<&'static str> {
        self.cables
            .iter()
            .any(|c| c.pulley.is_some())
            .then_some(PULLEY_NOT_MODELLED)
    }
}

/// Imports from the two files (read with the crate's bounded reader).
pub fn import_files(
    bodies: &Path,
    cables: &Path,
    opts: &ImportOptions,
) -> Result<Imported, CasprError> {
    let b = read_text(bodies, "CASPR bodies file", MAX_CASPR_FILE_BYTES)?;
    let c = read_text(cables, "CASPR cables file", MAX_CASPR_FILE_BYTES)?;
    import_str(
        &b,
        &bodies.display().to_string(),
        &c,
        &cables.display().to_string(),
        opts,
    )
}

/// Imports from the two files' texts; the names are used in messages and comments.
pub fn import_str(
    bodies_xml: &str,
    bodies_name: &str,
    cables_xml: &str,
    cables_name: &str,
    opts: &ImportOptions,
) -> Result<Imported, CasprError> {
    convert::check_options(opts)?;
    let bdoc = xml::parse(bodies_xml, bodies_name)?;
    let link = bodies::read_link(&bdoc, bodies_name)?;
    let cdoc = xml::parse(cables_xml, cables_name)?;
    let (cable_set, cables) = cables::read_set(&cdoc, cables_name, opts.cable_set.as_deref())?;
    let src = convert::Sources {
        bodies: bodies_name,
        cables: cables_name,
        cable_set: &cable_set,
    };
    let toml = convert::scene_toml(&link, &cables, opts, &src)?;
    let scene = Scene::from_toml_str(&toml, "<imported scene>")?;
    Ok(Imported {
        toml,
        scene,
        cable_set,
        link,
        cables,
    })
}
