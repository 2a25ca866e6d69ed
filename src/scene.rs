//! Scene files: the description of one robot, parsed from TOML and validated.
//!
//! A scene gives the frame (cable anchors, m), the end-effector (point mass at the
//! centroid where every cable attaches, kg), the cable material (Young's modulus E in Pa,
//! cross-section A in m², weight per length γ in N/m or mass per length μ in kg/m), the
//! tension bounds (N) and the cable model. Gravity (m/s²) converts weight per length to
//! mass per length (μ = γ/|g|) and gives the direction of sag and of the end-effector's
//! weight. Everything is SI. Unknown keys are errors, not silently ignored.
//!
//! [`Scene::from_path`] and [`Scene::from_toml_str`] return a [`SceneError`] that names
//! the file, the key and what is wrong; they never panic.

use nalgebra::Vector3;
use serde::Deserialize;
use std::path::Path;

/// The embedded default scene: the paper's spatial robot (Tables 5-6).
pub const DEFAULT_SCENE_TOML: &str = include_str!("../scenes/spatial_paper.toml");
/// The paper's planar robot (Tables 1-2), embedded for tests and examples.
pub const PLANAR_SCENE_TOML: &str = include_str!("../scenes/planar_paper.toml");
/// A 6-DOF robot: 8 cables, 3 × 3 × 2.5 m frame, box platform with attachment points.
pub const BOX_SCENE_TOML: &str = include_str!("../scenes/box_6dof.toml");

/// Largest number of cables a scene may have (fixed by the IPC message layout).
pub const MAX_CABLES: usize = cablevib_ipc::MAX_CABLES;

/// Largest number of elements per cable accepted (bounds every per-cycle loop).
pub const MAX_ELEMENTS_PER_CABLE: usize = 10_000;

/// Errors from reading or validating a scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{file}: cannot read scene file: {reason}")]
    Io {
        /// File name.
        file: String,
        /// Underlying error.
        reason: std::io::Error,
    },
    /// TOML syntax error, wrong type, missing or unknown key (serde's message names the key).
    #[error("{file}: {message}")]
    Parse {
        /// File name.
        file: String,
        /// What is wrong, with the key and the line.
        message: String,
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
}

/// The cable element model used for the string modes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ElementKind {
    /// Straight two-node truss element with geometric stiffness (paper Eqs. 12-18).
    Fem,
    /// Modified analytical (catenary) element, cancellation-free form (paper Eqs. 19-32, notes.md).
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
}

impl Cable {
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
    /// Off: axial springs only (the paper's ref. [7]).
    pub geometric_stiffness: bool,
    /// Relative f1 error the `auto` model may make (default 1e-3).
    pub f1_tolerance: f64,
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
    /// Lower tension bound, N.
    pub t_min_n: f64,
    /// Upper tension bound, N.
    pub t_max_n: f64,
    /// Cable model.
    pub model: ModelSettings,
    /// Rigid-body end-effector (effect `rotation`): 6 DOF, attachments b_i, inertia.
    pub rigid: bool,
    /// Inertia tensor about the centroid in the body frame, kg·m² (rigid body only).
    pub ee_inertia_kg_m2: nalgebra::Matrix3<f64>,
    /// Default orientation, unit quaternion [w, x, y, z].
    pub ee_orientation_wxyz: [f64; 4],
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    name: String,
    gravity: [f64; 3],
    end_effector: RawEndEffector,
    cable: RawCableDefaults,
    tension: RawTension,
    model: RawModel,
    #[serde(default)]
    effects: Option<RawEffects>,
    cables: Vec<RawCable>,
}

/// `[effects]`: which physics the scene asks for; nothing switched off is computed.
#[derive(Debug, Deserialize, Default, Clone, Copy)]
#[serde(deny_unknown_fields)]
struct RawEffects {
    geometric_stiffness: Option<bool>,
    cable_mass: Option<bool>,
    sag: Option<bool>,
    rotation: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEndEffector {
    mass: f64,
    position: [f64; 3],
    inertia: Option<[[f64; 3]; 3]>,
    orientation: Option<[f64; 4]>,
    #[serde(default = "default_true")]
    weight_carried: bool,
}

fn default_true() -> bool {
    true
}

#[derive(Debug, Deserialize, Default, Clone, Copy)]
#[serde(deny_unknown_fields)]
struct RawCableDefaults {
    youngs_modulus: Option<f64>,
    area: Option<f64>,
    weight_per_length: Option<f64>,
    mass_per_length: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTension {
    t_min: f64,
    t_max: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawModel {
    element: ElementKind,
    #[serde(default = "default_elements")]
    elements_per_cable: i64,
    #[serde(default = "default_participation")]
    ee_participation_min: f64,
    #[serde(default = "default_f1_tolerance")]
    f1_tolerance: f64,
}

fn default_f1_tolerance() -> f64 {
    1e-3
}

fn default_elements() -> i64 {
    10
}
fn default_participation() -> f64 {
    0.5
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCable {
    anchor: [f64; 3],
    attachment: Option<[f64; 3]>,
    youngs_modulus: Option<f64>,
    area: Option<f64>,
    weight_per_length: Option<f64>,
    mass_per_length: Option<f64>,
}

impl Scene {
    /// Read and validate a scene file.
    pub fn from_path(path: &Path) -> Result<Scene, SceneError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|reason| SceneError::Io {
            file: file.clone(),
            reason,
        })?;
        Self::from_toml_str(&text, &file)
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

    /// Parse and validate TOML text; `file` names the source in error messages.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Scene, SceneError> {
        let raw: RawScene = toml::from_str(text).map_err(|e| SceneError::Parse {
            file: file.to_string(),
            message: e.to_string().trim_end().replace('\n', " | "),
        })?;
        let inv = |key: &str, message: String| SceneError::Invalid {
            file: file.to_string(),
            key: key.to_string(),
            message,
        };
        let finite3 = |key: &str, v: [f64; 3]| -> Result<Vector3<f64>, SceneError> {
            if v.iter().all(|x| x.is_finite()) {
                Ok(Vector3::new(v[0], v[1], v[2]))
            } else {
                Err(inv(key, format!("must be finite, got {v:?}")))
            }
        };
        let positive = |key: &str, x: f64| -> Result<f64, SceneError> {
            if x.is_finite() && x > 0.0 {
                Ok(x)
            } else {
                Err(inv(key, format!("must be finite and > 0, got {x}")))
            }
        };
        if raw.name.trim().is_empty() {
            return Err(inv("name", "must not be empty".into()));
        }
        let gravity = finite3("gravity", raw.gravity)?;
        let g = gravity.norm();
        if g > 1e3 {
            return Err(inv(
                "gravity",
                format!("|g| = {g} m/s² is implausible (> 1000)"),
            ));
        }
        let ee_mass = positive("end_effector.mass", raw.end_effector.mass)?;
        let ee_pos = finite3("end_effector.position", raw.end_effector.position)?;
        let t_min = raw.tension.t_min;
        let t_max = raw.tension.t_max;
        if !(t_min.is_finite() && t_min > 0.0) {
            return Err(inv(
                "tension.t_min",
                format!("must be finite and > 0 N, got {t_min}"),
            ));
        }
        positive("tension.t_max", t_max)?;
        if t_min > t_max {
            return Err(inv(
                "tension.t_min",
                format!("t_min = {t_min} N exceeds t_max = {t_max} N"),
            ));
        }
        let n = raw.model.elements_per_cable;
        if n < 1 || n as usize > MAX_ELEMENTS_PER_CABLE {
            return Err(inv(
                "model.elements_per_cable",
                format!("must be in 1..={MAX_ELEMENTS_PER_CABLE}, got {n}"),
            ));
        }
        let tol = raw.model.f1_tolerance;
        if !(tol.is_finite() && tol > 0.0 && tol < 1.0) {
            return Err(inv(
                "model.f1_tolerance",
                format!("must be in (0, 1), got {tol}"),
            ));
        }
        let part = raw.model.ee_participation_min;
        if !(part.is_finite() && part > 0.0 && part <= 1.0) {
            return Err(inv(
                "model.ee_participation_min",
                format!("must be in (0, 1], got {part}"),
            ));
        }
        // Effects: cable_mass = false → massless springs; sag = true → catenary element.
        let fx = raw.effects.unwrap_or_default();
        let mut element = raw.model.element;
        if let Some(mass) = fx.cable_mass {
            match (mass, element) {
                (false, _) => element = ElementKind::Massless,
                (true, ElementKind::Massless) => {
                    return Err(inv(
                        "effects.cable_mass",
                        "cable_mass = true contradicts model.element = \"massless\"".into(),
                    ))
                }
                _ => {}
            }
        }
        if let Some(sag) = fx.sag {
            match (sag, element) {
                (true, ElementKind::Fem | ElementKind::Auto) => element = ElementKind::Catenary,
                (true, ElementKind::Catenary) => {}
                (true, other) => {
                    return Err(inv(
                        "effects.sag",
                        format!(
                            "sag needs the catenary element; model.element = \"{}\" cannot sag",
                            other.as_str()
                        ),
                    ))
                }
                (false, ElementKind::Catenary) => {
                    return Err(inv(
                        "effects.sag",
                        "sag = false contradicts model.element = \"catenary\"".into(),
                    ))
                }
                (false, _) => {}
            }
        }
        let rigid = fx.rotation.unwrap_or(false);
        let inertia =
            match (rigid, raw.end_effector.inertia) {
                (true, None) => return Err(inv(
                    "end_effector.inertia",
                    "missing: effects.rotation = true needs the inertia tensor (kg·m², body frame)"
                        .into(),
                )),
                (_, Some(m)) => {
                    let m = nalgebra::Matrix3::from_fn(|r, c| m[r][c]);
                    if !m.iter().all(|x| x.is_finite())
                        || (m - m.transpose()).abs().max() > 1e-9 * m.abs().max()
                    {
                        return Err(inv(
                            "end_effector.inertia",
                            "must be finite and symmetric".into(),
                        ));
                    }
                    if m.cholesky().is_none() {
                        return Err(inv(
                            "end_effector.inertia",
                            "must be positive definite".into(),
                        ));
                    }
                    m
                }
                (false, None) => nalgebra::Matrix3::zeros(),
            };
        let orientation = raw.end_effector.orientation.unwrap_or([1.0, 0.0, 0.0, 0.0]);
        let qn = orientation.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !orientation.iter().all(|x| x.is_finite()) || (qn - 1.0).abs() > 1e-6 {
            return Err(inv(
                "end_effector.orientation",
                format!("must be a unit quaternion [w, x, y, z], norm {qn}"),
            ));
        }
        if rigid && raw.cables.len() < 6 {
            return Err(inv(
                "cables",
                format!(
                    "a rigid end-effector needs at least 6 cables, got {}",
                    raw.cables.len()
                ),
            ));
        }
        let geometric_stiffness = fx.geometric_stiffness.unwrap_or(true);
        if !geometric_stiffness && element != ElementKind::Massless {
            return Err(inv(
                "effects.geometric_stiffness",
                "without geometric stiffness a cable with mass has no transverse stiffness (its string modes are at 0 Hz); \
                 switch it off only with cable_mass = false"
                    .into(),
            ));
        }
        if raw.cables.len() < 2 {
            return Err(inv(
                "cables",
                format!(
                    "at least 2 cables are needed to hold a point mass in a plane (and 4 in space), got {}",
                    raw.cables.len()
                ),
            ));
        }
        if raw.cables.len() > MAX_CABLES {
            return Err(inv(
                "cables",
                format!(
                    "at most {MAX_CABLES} cables are supported, got {}",
                    raw.cables.len()
                ),
            ));
        }
        let d = raw.cable;
        let mut cables = Vec::with_capacity(raw.cables.len());
        for (i, c) in raw.cables.iter().enumerate() {
            let key = |k: &str| format!("cables[{i}].{k}");
            let anchor = finite3(&key("anchor"), c.anchor)?;
            let attachment = match c.attachment {
                Some(b) => {
                    let b = finite3(&key("attachment"), b)?;
                    if !rigid && b.norm() > 0.0 {
                        return Err(inv(
                            &key("attachment"),
                            "attachment points need the rigid end-effector: set effects.rotation = true".into(),
                        ));
                    }
                    b
                }
                None => Vector3::zeros(),
            };
            if (anchor - ee_pos).norm() < 1e-6 {
                return Err(inv(
                    &key("anchor"),
                    format!(
                        "coincides with end_effector.position {:?}",
                        raw.end_effector.position
                    ),
                ));
            }
            let pick =
                |own: Option<f64>, def: Option<f64>, name: &str| -> Result<f64, SceneError> {
                    match own.or(def) {
                        Some(v) => positive(&key(name), v),
                        None => Err(inv(
                            &key(name),
                            format!("missing: give cable.{name} or cables[{i}].{name}"),
                        )),
                    }
                };
            let e = pick(c.youngs_modulus, d.youngs_modulus, "youngs_modulus")?;
            let a = pick(c.area, d.area, "area")?;
            // A cable's own key wins over the defaults; within one level, both is an error.
            let (w, m) = if c.weight_per_length.is_some() || c.mass_per_length.is_some() {
                (c.weight_per_length, c.mass_per_length)
            } else {
                (d.weight_per_length, d.mass_per_length)
            };
            let mu = match (w, m) {
                (Some(_), Some(_)) => {
                    return Err(inv(
                        &key("weight_per_length"),
                        "give weight_per_length or mass_per_length, not both".into(),
                    ))
                }
                (Some(w), None) => {
                    let w = positive(&key("weight_per_length"), w)?;
                    if g <= 0.0 {
                        return Err(inv(
                            &key("weight_per_length"),
                            "needs non-zero gravity to convert to mass; give mass_per_length"
                                .into(),
                        ));
                    }
                    w / g
                }
                (None, Some(m)) => positive(&key("mass_per_length"), m)?,
                (None, None) => {
                    return Err(inv(
                        &key("weight_per_length"),
                        "missing: give weight_per_length or mass_per_length".into(),
                    ))
                }
            };
            // Derived values must be usable numbers too (a denormal weight gives μ = 0, an
            // overflowing E·A gives ∞).
            if !(mu.is_normal() && mu > 0.0) {
                return Err(inv(
                    &key(if w.is_some() {
                        "weight_per_length"
                    } else {
                        "mass_per_length"
                    }),
                    format!("gives a mass per length of {mu:e} kg/m, not a usable positive number"),
                ));
            }
            let ea = e * a;
            if !(ea.is_normal() && ea > 0.0 && ea < 1e15) {
                return Err(inv(
                    &key("area"),
                    format!("youngs_modulus × area = {ea:e} N is not a usable axial rigidity (0 < EA < 1e15 N)"),
                ));
            }
            cables.push(Cable {
                anchor_m: anchor,
                youngs_modulus_pa: e,
                area_m2: a,
                mass_per_length_kg_m: mu,
                attachment_m: attachment,
            });
        }
        Ok(Scene {
            name: raw.name,
            gravity_m_s2: gravity,
            ee_mass_kg: ee_mass,
            ee_position_m: ee_pos,
            weight_carried: raw.end_effector.weight_carried,
            cables,
            t_min_n: t_min,
            t_max_n: t_max,
            model: ModelSettings {
                element,
                elements_per_cable: n as usize,
                ee_participation_min: part,
                geometric_stiffness,
                f1_tolerance: raw.model.f1_tolerance,
            },
            rigid,
            ee_inertia_kg_m2: inertia,
            ee_orientation_wxyz: orientation,
        })
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

    /// Copy with a different element model and element count (command-line overrides).
    pub fn with_model(&self, element: ElementKind, elements_per_cable: usize) -> Scene {
        let mut s = self.clone();
        s.model.element = element;
        if element != ElementKind::Massless {
            s.model.geometric_stiffness = true;
        }
        s.model.elements_per_cable = elements_per_cable.clamp(1, MAX_ELEMENTS_PER_CABLE);
        s
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

    fn err(text: &str) -> String {
        Scene::from_toml_str(text, "t.toml")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn effects_select_the_model() {
        let base = DEFAULT_SCENE_TOML;
        let with = |fx: &str| Scene::from_toml_str(&format!("{base}\n[effects]\n{fx}\n"), "t.toml");
        assert_eq!(
            with("sag = true").unwrap().model.element,
            ElementKind::Catenary
        );
        assert_eq!(
            with("cable_mass = false").unwrap().model.element,
            ElementKind::Massless
        );
        let m = with("cable_mass = false\ngeometric_stiffness = false").unwrap();
        assert!(!m.model.geometric_stiffness);
        let e = with("geometric_stiffness = false").unwrap_err().to_string();
        assert!(e.contains("effects.geometric_stiffness"), "{e}");
        let e = with("rotation = maybe").unwrap_err().to_string();
        assert!(e.contains("rotation"), "{e}");
        let e = with("rotation = true").unwrap_err().to_string();
        assert!(e.contains("end_effector.inertia"), "{e}");
    }

    #[test]
    fn errors_name_file_and_key() {
        let base = DEFAULT_SCENE_TOML;
        let e = err(&base.replace("mass = 30.0", "mass = -1.0"));
        assert!(
            e.contains("t.toml") && e.contains("end_effector.mass"),
            "{e}"
        );
        let e = err(&base.replace("t_min = 60.0", "t_min = 400.0"));
        assert!(e.contains("tension.t_min") && e.contains("exceeds"), "{e}");
        let e = err(&format!("{base}\nbogus = 1\n"));
        assert!(e.contains("bogus"), "{e}");
        let e = err(&base.replace("area = 50.265e-6", "area = \"big\""));
        assert!(e.contains("area"), "{e}");
        let e = err(&base.replace("youngs_modulus = 2.01e10", "youngs_modulus = nan"));
        assert!(e.contains("youngs_modulus"), "{e}");
        let e = err(&base.replace("[0.0, 0.0, 1.25]", "[1.25, 1.25, 2.5]"));
        assert!(
            e.contains("cables[0].anchor") && e.contains("coincides"),
            "{e}"
        );
        let e = err(&base.replace("name = \"spatial-paper\"\n", ""));
        assert!(e.contains("name"), "{e}");
    }
}
