//! Scene files: the description of one robot, parsed from TOML and validated.
//!
//! A scene gives the frame (cable anchors, m), the end-effector (point mass at the
//! centroid where every cable attaches, kg), the cable material (Young's modulus E in Pa,
//! cross-section A in m², weight per length γ in N/m or mass per length μ in kg/m), the
//! tension bounds (N) and the cable model. Gravity (m/s²) converts weight per length to
//! mass per length (μ = γ/|g|) and gives the direction of sag and of the end-effector's
//! weight. Everything is SI. Unknown keys are errors, not silently ignored.
//!
//! [`Scene::from_path`], [`Scene::from_toml_str`] and [`Scene::load`] return a
//! [`SceneError`] that names the file, the key and what is wrong; they never panic.
//!
//! The module is split by stage: `parse` (TOML into serde's raw types; [`toml_error`] its
//! errors as one line naming the line and the key), `validate` (raw
//! types into a [`Scene`], one check per concern) and `load` (a file path or the name of an
//! embedded scene).

use nalgebra::Vector3;
use serde::Deserialize;
use std::path::Path;

mod bounds;
mod damping;
mod direction;
use crate::input_file::{InputFileError, MAX_SCENE_BYTES};

mod load;
mod parse;
pub mod toml_error;
mod validate;

pub use bounds::{check_t_min, is_valid_t_min, TminRangeError, T_MIN_FLOOR_N};
pub use damping::{
    Damping, MAX_LOSS_FACTOR, MAX_MODAL_RATIO, MAX_RAYLEIGH_ALPHA_PER_S, MAX_RAYLEIGH_BETA_S,
};
pub use direction::unit_direction;

/// The embedded default scene: the paper's spatial robot (Tables 5-6).
pub const DEFAULT_SCENE_TOML: &str = include_str!("../../scenes/spatial_paper.toml");
/// The paper's planar robot (Tables 1-2), embedded for tests and examples.
pub const PLANAR_SCENE_TOML: &str = include_str!("../../scenes/planar_paper.toml");
/// A 6-DOF robot: 8 cables, 3 × 3 × 2.5 m frame, box platform with attachment points.
pub const BOX_SCENE_TOML: &str = include_str!("../../scenes/box_6dof.toml");

/// Largest number of cables a scene may have; the IPC messages' per-cable arrays
/// (`cablevib-ipc`) have this length.
pub const MAX_CABLES: usize = 16;

/// Largest number of elements per cable accepted. The structured path costs O(1) in it
/// (closed-form chains, a bounded pole table); the dense reference refuses models beyond
/// its memory budget long before.
pub const MAX_ELEMENTS_PER_CABLE: usize = 1_000_000;

/// Errors from reading or validating a scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read: missing, not a regular file, over
    /// [`MAX_SCENE_BYTES`] or not UTF-8.
    #[error(transparent)]
    Input(#[from] InputFileError),
    /// TOML syntax error, wrong type, missing or unknown key, on one line: the line and
    /// column, the key, the toml crate's message ([`toml_error`]).
    #[error("{file}: {report}")]
    Parse {
        /// File name.
        file: String,
        /// Where and what.
        report: toml_error::TomlErrorReport,
    },
    /// A value that parses but is not physically valid.
    #[error("{file}: key `{key}`: {message}")]
    Invalid {
        /// File name.
        file: String,
        /// The offending key, e.g. `cables[2].anchor`.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// [`Scene::load`]: neither an existing file nor the name of an embedded scene.
    #[error("{name}: no such scene file, and not an embedded scene ({})", load::EMBEDDED_NAMES.join(", "))]
    NotFound {
        /// The name or path given.
        name: String,
    },
}

/// The cable element model used for the string modes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ElementKind {
    /// Straight two-node truss element with geometric stiffness (paper Eqs. 12-18).
    Fem,
    /// Modified analytical (catenary) element, cancellation-free form (paper Eqs. 19-32, docs/model.md).
    Catenary,
    /// Continuous taut string / bar (N → ∞ limit of the FEM element), exact dynamic stiffness.
    Continuous,
    /// Massless cables: springs EA/L along and T/L across; end-effector modes only.
    Massless,
    /// Pick the cheapest of the above whose f1 error stays within `model.f1_tolerance`
    /// (resolved when the estimator is built; see `estimator::resolve_auto`).
    Auto,
}

impl ElementKind {
    /// Lower-case name as used in scene files and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            ElementKind::Fem => "fem",
            ElementKind::Catenary => "catenary",
            ElementKind::Continuous => "continuous",
            ElementKind::Massless => "massless",
            ElementKind::Auto => "auto",
        }
    }
    /// Parse a command-line name.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "fem" => Some(Self::Fem),
            "catenary" => Some(Self::Catenary),
            "continuous" => Some(Self::Continuous),
            "massless" => Some(Self::Massless),
            "auto" => Some(Self::Auto),
            _ => None,
        }
    }
    /// True when the model is discretised into N elements per cable.
    pub fn is_discrete(self) -> bool {
        matches!(self, Self::Fem | Self::Catenary)
    }
}

/// Why `sag = on` cannot go with `element`, or None when it can: only `fem`, `continuous`
/// and `auto` have a sagged model (the catenary element sags inside each element on the
/// straight chord; a massless cable has no weight to sag under).
pub fn sag_refusal(on: bool, element: ElementKind) -> Option<&'static str> {
    match (on, element) {
        (true, ElementKind::Massless) => Some(
            "sag needs cable mass (a cable without weight does not sag): use model.element = \"fem\" or \"continuous\"",
        ),
        (true, ElementKind::Catenary) => Some(
            "the catenary element sags only inside each element on the straight chord; on the sagged profile use model.element = \"fem\" or \"continuous\"",
        ),
        _ => None,
    }
}

/// Material and geometry of one cable, SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cable {
    /// Anchor point on the frame, m.
    pub anchor_m: Vector3<f64>,
    /// Young's modulus E, Pa.
    pub youngs_modulus_pa: f64,
    /// Cross-section A, m².
    pub area_m2: f64,
    /// Mass per unit length μ, kg/m.
    pub mass_per_length_kg_m: f64,
    /// Attachment point on the end-effector in its body frame, m (zero for a point mass).
    pub attachment_m: Vector3<f64>,
    /// This cable's own lower tension bound, N (`cables[i].t_min`); None: the scene's
    /// [`Scene::t_min_n`]. See [`Scene::cable_t_min_n`].
    pub t_min_n: Option<f64>,
    /// This cable's own upper tension bound, N (`cables[i].t_max`); None: the scene's
    /// [`Scene::t_max_n`]. See [`Scene::cable_t_max_n`].
    pub t_max_n: Option<f64>,
    /// A swivel pulley at the anchor (`cables[i].pulley`, else `[cable.pulley]`); None: the
    /// cable leaves from the anchor point itself. See [`Pulley`].
    pub pulley: Option<Pulley>,
    /// The cable hidden between the guiding pulley and the winch drum (`hidden_length`):
    /// an axial spring, with its mass, in series with the free cable. None: the cable
    /// starts at a fixed anchor (every scene without `hidden_length`).
    pub hidden: Option<HiddenCable>,
}

/// A swivel pulley at a cable's anchor (the standard model of CASPR's
/// `base_rotating_pulley`). The cable arrives from the winch along the swivel axis, which
/// passes through the anchor (the fixed point where the cable enters the pulley) in the
/// direction [`Self::entry_unit`]; the pulley turns about that axis to keep the attachment
/// point in its plane, and the cable leaves it tangent to its circle of radius
/// [`Self::radius_m`] (the circle touches the axis at the anchor). Kinematics:
/// `kinematics::pulley`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pulley {
    /// Unit direction of the cable entering the pulley at the anchor, along the swivel axis
    /// (`entry_direction`, any non-zero length in the file; CASPR's `cable_entry_vector`).
    pub entry_unit: Vector3<f64>,
    /// Radius of the pulley (to the cable's centre line), m, ≥ 0.
    pub radius_m: f64,
}

impl Cable {
    /// Axial rigidity EA, N.
    pub fn ea_n(&self) -> f64 {
        self.youngs_modulus_pa * self.area_m2
    }
}

/// The cable between the pulley entry and the winch drum, SI units. It carries the free
/// cable's tension; the pulley holds it transversely, so only its axial stretch (and axial
/// inertia) acts on the free cable, as a spring at the free cable's anchor end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HiddenCable {
    /// Length from the pulley entry to the drum, m (> 0).
    pub length_m: f64,
    /// Young's modulus, Pa (`hidden_youngs_modulus`; default the free cable's).
    pub youngs_modulus_pa: f64,
    /// Cross-section, m² (`hidden_area`; default the free cable's).
    pub area_m2: f64,
    /// Mass per length, kg/m (`hidden_mass_per_length` or `hidden_weight_per_length`;
    /// default the free cable's).
    pub mass_per_length_kg_m: f64,
}

impl HiddenCable {
    /// Axial rigidity EA, N.
    pub fn ea_n(&self) -> f64 {
        self.youngs_modulus_pa * self.area_m2
    }
}

/// Cable model settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelSettings {
    /// Element kind.
    pub element: ElementKind,
    /// Number of equal elements per cable (FEM and catenary).
    pub elements_per_cable: usize,
    /// Smallest share of modal kinetic energy carried by the end-effector's own mass for a
    /// mode to count as an "end-effector mode" (0 < x ≤ 1, default 0.5).
    pub ee_participation_min: f64,
    /// Transverse geometric stiffness T/l of the cables (effect `geometric_stiffness`).
    /// Off: axial springs only (the paper's ref. \[7\]).
    pub geometric_stiffness: bool,
    /// Relative f1 error the `auto` model may make (default 1e-3).
    pub f1_tolerance: f64,
    /// Effect `sag`: every cable hangs on its elastic catenary (statics on the end tangents,
    /// vibration about the sagged profile) with the `fem` or `continuous` element. Off
    /// (the default, and every scene without an `[effects]` table): every cable on its
    /// straight chord.
    pub sag: bool,
    /// Whether `sag` was chosen explicitly (`[effects] sag = …` or a front end's override): then the
    /// warning that sag would matter ([`crate::scene`] users: `estimator::sag_warning`) is
    /// not printed for `sag = false`.
    pub sag_explicit: bool,
}

/// A validated robot description. All fields SI.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// Scene name.
    pub name: String,
    /// Gravity vector, m/s².
    pub gravity_m_s2: Vector3<f64>,
    /// End-effector mass, kg (point mass at the centroid).
    pub ee_mass_kg: f64,
    /// Default end-effector position, m.
    pub ee_position_m: Vector3<f64>,
    /// Whether the cables carry the end-effector's weight (wrench w = m·g) or not (w = 0).
    pub weight_carried: bool,
    /// Cables in order.
    pub cables: Vec<Cable>,
    /// Lower tension bound, N: the default of every cable without its own
    /// ([`Cable::t_min_n`]).
    pub t_min_n: f64,
    /// Upper tension bound, N: the default of every cable without its own
    /// ([`Cable::t_max_n`]).
    pub t_max_n: f64,
    /// Cable model.
    pub model: ModelSettings,
    /// Rigid-body end-effector (effect `rotation`): 6 DOF, attachments b_i, inertia.
    pub rigid: bool,
    /// Inertia tensor about the centroid in the body frame, kg·m² (rigid body only).
    pub ee_inertia_kg_m2: nalgebra::Matrix3<f64>,
    /// Default orientation, unit quaternion [w, x, y, z].
    pub ee_orientation_wxyz: [f64; 4],
    /// Damping (`[damping]`); [`Damping::None`] without the table.
    pub damping: Damping,
}

impl Scene {
    /// Read and validate a scene file (a regular file of at most [`MAX_SCENE_BYTES`]).
    pub fn from_path(path: &Path) -> Result<Scene, SceneError> {
        let text = crate::input_file::read_text(path, "scene file", MAX_SCENE_BYTES)?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// The embedded default scene (the paper's spatial robot).
    pub fn default_scene() -> Scene {
        Self::from_toml_str(DEFAULT_SCENE_TOML, "<embedded spatial_paper.toml>")
            .expect("embedded default scene is valid (tested)")
    }

    /// The embedded planar paper scene.
    pub fn planar_paper() -> Scene {
        Self::from_toml_str(PLANAR_SCENE_TOML, "<embedded planar_paper.toml>")
            .expect("embedded planar scene is valid (tested)")
    }

    /// The embedded 6-DOF box-platform robot.
    pub fn box_6dof() -> Scene {
        Self::from_toml_str(BOX_SCENE_TOML, "<embedded box_6dof.toml>")
            .expect("embedded 6-DOF scene is valid (tested)")
    }

    /// Number of cables.
    pub fn n_cables(&self) -> usize {
        self.cables.len()
    }

    /// Lower tension bound of cable `i`, N: its own, else the scene's.
    pub fn cable_t_min_n(&self, i: usize) -> f64 {
        self.cables[i].t_min_n.unwrap_or(self.t_min_n)
    }

    /// Upper tension bound of cable `i`, N: its own, else the scene's.
    pub fn cable_t_max_n(&self, i: usize) -> f64 {
        self.cables[i].t_max_n.unwrap_or(self.t_max_n)
    }

    /// The cables' lower bounds for a one-line summary: `"60 N"` when every cable has the
    /// same, else `"4.06-10 N per cable"` (lowest-highest).
    pub fn t_min_label(&self) -> String {
        let t = (0..self.n_cables()).map(|i| self.cable_t_min_n(i));
        let (lo, hi) = t.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
        if lo == hi || self.n_cables() == 0 {
            format!("{} N", self.t_min_n.min(lo))
        } else {
            format!("{lo}-{hi} N per cable")
        }
    }

    /// Whether some cable has bounds of its own (`cables[i].t_min` or `.t_max`).
    pub fn has_per_cable_bounds(&self) -> bool {
        self.cables
            .iter()
            .any(|c| c.t_min_n.is_some() || c.t_max_n.is_some())
    }

    /// Checks a uniform T_min (N, every cable) against every cable's upper bound by the
    /// crate's one rule ([`check_t_min`]); the check of a command-line override.
    pub fn check_uniform_t_min(&self, t_min_n: f64) -> Result<(), TminRangeError> {
        check_t_min(t_min_n, self.t_max_n)?;
        (0..self.n_cables()).try_for_each(|i| check_t_min(t_min_n, self.cable_t_max_n(i)))
    }

    /// Sets T_min (N) for every cable, per-cable values included, after
    /// [`Self::check_uniform_t_min`]; unchanged on error.
    pub fn set_uniform_t_min(&mut self, t_min_n: f64) -> Result<(), TminRangeError> {
        self.check_uniform_t_min(t_min_n)?;
        self.t_min_n = t_min_n;
        for c in &mut self.cables {
            c.t_min_n = None;
        }
        Ok(())
    }

    /// Weight per length γ = μ|g| of cable `i`, N/m (drives the catenary sag).
    pub fn weight_per_length_n_m(&self, i: usize) -> f64 {
        self.cables[i].mass_per_length_kg_m * self.gravity_m_s2.norm()
    }

    /// The wrench the cables must supply, N: m·g when the weight is carried, else zero.
    pub fn wrench_n(&self) -> Vector3<f64> {
        if self.weight_carried {
            self.gravity_m_s2 * self.ee_mass_kg
        } else {
            Vector3::zeros()
        }
    }

    /// [`Self::wrench_n`] as the wrench the tension distributions take: (force N, moment
    /// N·m) about the centroid, where the weight acts (so the moment is zero).
    pub fn wrench6_n(&self) -> [f64; 6] {
        let f = self.wrench_n();
        [f.x, f.y, f.z, 0.0, 0.0, 0.0]
    }

    /// Whether some cable has a hidden part ([`Cable::hidden`]).
    pub fn has_hidden_cable(&self) -> bool {
        self.cables.iter().any(|c| c.hidden.is_some())
    }

    /// Axis-aligned bounding box of the anchors, m (the frame).
    pub fn frame_bounds_m(&self) -> (Vector3<f64>, Vector3<f64>) {
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        for c in &self.cables {
            lo = lo.inf(&c.anchor_m);
            hi = hi.sup(&c.anchor_m);
        }
        (lo, hi)
    }

    /// Switch the effect `sag` on or off (a command-line override); refused, with the
    /// reason, for the elements that cannot sag ([`sag_refusal`]).
    pub fn set_sag(&mut self, on: bool) -> Result<(), &'static str> {
        match sag_refusal(on, self.model.element) {
            Some(why) => Err(why),
            None => {
                self.model.sag = on;
                self.model.sag_explicit = true;
                Ok(())
            }
        }
    }

    /// Copy with a different element model and element count (command-line overrides).
    /// The effect `sag` is kept where the element has a sagged model and dropped where it
    /// has none (catenary, massless: [`sag_refusal`]).
    pub fn with_model(&self, element: ElementKind, elements_per_cable: usize) -> Scene {
        let mut s = self.clone();
        s.model.element = element;
        s.model.sag = self.model.sag && sag_refusal(true, element).is_none();
        if element != ElementKind::Massless {
            s.model.geometric_stiffness = true;
        }
        s.model.elements_per_cable = elements_per_cable.clamp(1, MAX_ELEMENTS_PER_CABLE);
        s
    }
}

impl Scene {
    /// Parse and validate TOML text; `file` names the source in error messages.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Scene, SceneError> {
        let raw: parse::RawScene = toml::from_str(text).map_err(|e| SceneError::Parse {
            file: file.to_string(),
            report: toml_error::report(text, &e),
        })?;
        validate::scene_from_raw(raw, file)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_scenes_parse() {
        let s = Scene::default_scene();
        assert_eq!(s.n_cables(), 8);
        let p = Scene::planar_paper();
        assert_eq!(p.n_cables(), 4);
        assert!(!p.weight_carried);
        let b = Scene::box_6dof();
        assert!(b.rigid && b.n_cables() == 8);
    }
}
