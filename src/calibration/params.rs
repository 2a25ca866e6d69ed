//! The parameters a calibration can fit: their names, units, nominal values and bounds, and
//! how a vector of values makes a scene.
//!
//! | name | unit | what it changes | default bounds |
//! |---|---|---|---|
//! | `ea_factor.i` (`ea_factor`: every cable) | 1 | cable i's EA (free and hidden part) × the factor | [0.1, 10] |
//! | `ea_factor_all` | 1 | every cable's EA × one shared factor | [0.1, 10] |
//! | `hidden_length.i` (`hidden_length`) | m | cable i's hidden length (0: none) | [0, max(10 m, 10 × frame diagonal)] |
//! | `weight_per_length` | N/m | every cable's weight per length (a hidden part of the same rope follows) | [0.1, 10] × nominal |
//! | `ee_mass` | kg | the end-effector's mass | [0.5, 2] × nominal |
//! | `ee_inertia.xx`, `.yy`, `.zz` (`ee_inertia`) | kg·m² | the body-frame inertia's diagonal (rigid) | [0.2, 5] × nominal |
//! | `ee_com.x`, `.y`, `.z` (`ee_com`) | m | the centre of mass's offset from the pose's reference point, body frame (rigid) | ± the longest attachment arm (≥ 0.01 m) |
//! | `pulley_radius` | m | every swivel pulley's radius | [0, max(5 × nominal, 0.1 m)] |
//! | `modal_ratio` | 1 | ζ of every mode | [0, 0.5] |
//! | `rayleigh.alpha`, `rayleigh.beta` (`rayleigh`) | 1/s, s | ζ(ω) = α/(2ω) + βω/2 | [0, 1000] 1/s, [0, 0.1] s |
//!
//! The nominal value (the fit's start, and the centre of an optional prior) is the scene's;
//! a factor's is 1, an unknown damping's 0.01 (ζ) or 0 (α, β). Bounds and nominal values may
//! be set per parameter or per group (`ea_factor` sets every `ea_factor.i`).
//!
//! `ee_com` moves the centre of mass δ (body frame) away from the reference point whose
//! pose the data give: the model's end-effector sits at p + Rδ with attachments b_i − δ, so
//! the cables do not move but the weight's lever arm and the inertia's centre do.

use super::CalibrationError;
use crate::scene::{Damping, HiddenCable, Scene};
use nalgebra::Vector3;

/// One kind of fitted parameter (cable indices 0-based; names 1-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ParamKind {
    /// Factor on cable i's axial rigidity EA (free and hidden cable).
    EaFactor(usize),
    /// One factor on every cable's EA.
    EaFactorAll,
    /// Cable i's hidden length, m.
    HiddenLength(usize),
    /// Every cable's weight per length, N/m.
    WeightPerLength,
    /// End-effector mass, kg.
    EeMass,
    /// Diagonal entry k (0: xx, 1: yy, 2: zz) of the body-frame inertia, kg·m².
    EeInertia(usize),
    /// Component k of the centre of mass's body-frame offset, m.
    EeCom(usize),
    /// Every pulley's radius, m.
    PulleyRadius,
    /// Modal damping ratio ζ.
    ModalRatio,
    /// Rayleigh α, 1/s.
    RayleighAlpha,
    /// Rayleigh β, s.
    RayleighBeta,
}

const AXES: [&str; 3] = ["x", "y", "z"];
const INERTIA: [&str; 3] = ["xx", "yy", "zz"];

/// The names a fit accepts, for messages and help.
pub const PARAMETER_NAMES: &str = "ea_factor, ea_factor.I, ea_factor_all, hidden_length, hidden_length.I, weight_per_length, ee_mass, ee_inertia, ee_inertia.xx|yy|zz, ee_com, ee_com.x|y|z, pulley_radius, modal_ratio, rayleigh, rayleigh.alpha|beta";

impl ParamKind {
    /// The name in reports (`ea_factor.3` for cable index 2).
    pub fn name(&self) -> String {
        match *self {
            ParamKind::EaFactor(i) => format!("ea_factor.{}", i + 1),
            ParamKind::EaFactorAll => "ea_factor_all".into(),
            ParamKind::HiddenLength(i) => format!("hidden_length.{}", i + 1),
            ParamKind::WeightPerLength => "weight_per_length".into(),
            ParamKind::EeMass => "ee_mass".into(),
            ParamKind::EeInertia(k) => format!("ee_inertia.{}", INERTIA[k]),
            ParamKind::EeCom(k) => format!("ee_com.{}", AXES[k]),
            ParamKind::PulleyRadius => "pulley_radius".into(),
            ParamKind::ModalRatio => "modal_ratio".into(),
            ParamKind::RayleighAlpha => "rayleigh.alpha".into(),
            ParamKind::RayleighBeta => "rayleigh.beta".into(),
        }
    }

    /// SI unit (`"1"` for a ratio).
    pub fn unit(&self) -> &'static str {
        match self {
            ParamKind::EaFactor(_) | ParamKind::EaFactorAll | ParamKind::ModalRatio => "1",
            ParamKind::HiddenLength(_) | ParamKind::EeCom(_) | ParamKind::PulleyRadius => "m",
            ParamKind::WeightPerLength => "N/m",
            ParamKind::EeMass => "kg",
            ParamKind::EeInertia(_) => "kg·m²",
            ParamKind::RayleighAlpha => "1/s",
            ParamKind::RayleighBeta => "s",
        }
    }

    /// Whether the parameter is a damping parameter (fitted to damping ratios only).
    pub fn is_damping(&self) -> bool {
        matches!(
            self,
            ParamKind::ModalRatio | ParamKind::RayleighAlpha | ParamKind::RayleighBeta
        )
    }
}

/// One fitted parameter: kind, name, unit, nominal value, bounds and optional prior.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    /// What it is.
    pub kind: ParamKind,
    /// Its name in reports, e.g. `ea_factor.3`.
    pub name: String,
    /// SI unit.
    pub unit: &'static str,
    /// Nominal value: the fit's start and the prior's centre.
    pub nominal: f64,
    /// Lower bound.
    pub lower: f64,
    /// Upper bound.
    pub upper: f64,
    /// Standard deviation of a Gaussian prior toward the nominal value (None: no prior).
    pub prior_sigma: Option<f64>,
}

/// The parameters of one fit, in the order they were asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct FitSpec {
    /// The parameters (group names expanded).
    pub params: Vec<Parameter>,
}

/// The kinds of a three-component parameter: all three (`r` None) or the one named `r`.
fn components(
    r: Option<&str>,
    names: &[&str; 3],
    kind: fn(usize) -> ParamKind,
    which: &str,
) -> Result<Vec<ParamKind>, String> {
    match r {
        None => Ok((0..3).map(kind).collect()),
        Some(r) => match names.iter().position(|&a| a == r) {
            Some(k) => Ok(vec![kind(k)]),
            None => Err(which.to_string()),
        },
    }
}

/// Parses `name` into the parameter kinds it stands for (a group expands to its members).
fn expand(scene: &Scene, name: &str) -> Result<Vec<ParamKind>, CalibrationError> {
    let n = scene.n_cables();
    let bad = |m: String| CalibrationError::param(name, m);
    let cable = |rest: &str| -> Result<usize, CalibrationError> {
        match rest.parse::<usize>() {
            Ok(i) if (1..=n).contains(&i) => Ok(i - 1),
            _ => Err(bad(format!(
                "`{rest}` is not a cable number of this scene (1..={n})"
            ))),
        }
    };
    let rigid_only = |what: &str| -> Result<(), CalibrationError> {
        if scene.rigid {
            Ok(())
        } else {
            Err(bad(format!(
                "the end-effector is a point mass (effects.rotation = false): it has no {what}"
            )))
        }
    };
    let (head, rest) = match name.split_once('.') {
        Some((h, r)) => (h, Some(r)),
        None => (name, None),
    };
    let kinds = match (head, rest) {
        ("ea_factor", None) => (0..n).map(ParamKind::EaFactor).collect(),
        ("ea_factor", Some(r)) => vec![ParamKind::EaFactor(cable(r)?)],
        ("ea_factor_all", None) => vec![ParamKind::EaFactorAll],
        ("hidden_length", None) => (0..n).map(ParamKind::HiddenLength).collect(),
        ("hidden_length", Some(r)) => vec![ParamKind::HiddenLength(cable(r)?)],
        ("weight_per_length", None) => vec![ParamKind::WeightPerLength],
        ("ee_mass", None) => vec![ParamKind::EeMass],
        ("ee_inertia", r) => {
            rigid_only("inertia")?;
            components(
                r,
                &INERTIA,
                ParamKind::EeInertia,
                "the inertia's entries are xx, yy, zz",
            )
            .map_err(bad)?
        }
        ("ee_com", r) => {
            rigid_only("centre-of-mass offset")?;
            components(
                r,
                &AXES,
                ParamKind::EeCom,
                "the offset's components are x, y, z",
            )
            .map_err(bad)?
        }
        ("pulley_radius", None) => vec![ParamKind::PulleyRadius],
        ("modal_ratio", None) => vec![ParamKind::ModalRatio],
        ("rayleigh", None) => vec![ParamKind::RayleighAlpha, ParamKind::RayleighBeta],
        ("rayleigh", Some("alpha")) => vec![ParamKind::RayleighAlpha],
        ("rayleigh", Some("beta")) => vec![ParamKind::RayleighBeta],
        _ => return Err(bad(format!("unknown parameter (known: {PARAMETER_NAMES})"))),
    };
    Ok(kinds)
}

/// The one value every cable shares of `value(cable)`, or an error naming `name`.
fn common(
    scene: &Scene,
    name: &str,
    what: &str,
    value: impl Fn(usize) -> Option<f64>,
) -> Result<f64, CalibrationError> {
    let vals: Vec<(usize, f64)> = (0..scene.n_cables())
        .filter_map(|i| value(i).map(|v| (i, v)))
        .collect();
    let Some(&(_, first)) = vals.first() else {
        return Err(CalibrationError::param(
            name,
            format!("no cable of the scene has {what}"),
        ));
    };
    if let Some(&(i, v)) = vals
        .iter()
        .find(|(_, v)| (v - first).abs() > 1e-12 * first.abs())
    {
        return Err(CalibrationError::param(
            name,
            format!(
                "the cables differ in {what} (cable {}: {first}, cable {}: {v}): one value for all cannot be fitted",
                vals[0].0 + 1,
                i + 1
            ),
        ));
    }
    Ok(first)
}

/// Nominal value and default bounds of `kind` in `scene`.
fn nominal_and_bounds(scene: &Scene, kind: ParamKind) -> Result<(f64, f64, f64), CalibrationError> {
    let name = kind.name();
    let (lo, hi) = scene.frame_bounds_m();
    let diagonal = (hi - lo).norm();
    Ok(match kind {
        ParamKind::EaFactor(_) | ParamKind::EaFactorAll => (1.0, 0.1, 10.0),
        ParamKind::HiddenLength(i) => (
            scene.cables[i].hidden.map_or(0.0, |h| h.length_m),
            0.0,
            (10.0 * diagonal).max(10.0),
        ),
        ParamKind::WeightPerLength => {
            let g = scene.gravity_m_s2.norm();
            if !(g > 0.0) {
                return Err(CalibrationError::param(
                    &name,
                    "the scene has no gravity: weight per length is undefined",
                ));
            }
            let w = common(scene, &name, "weight per length", |i| {
                Some(scene.cables[i].mass_per_length_kg_m * g)
            })?;
            (w, 0.1 * w, 10.0 * w)
        }
        ParamKind::EeMass => (
            scene.ee_mass_kg,
            0.5 * scene.ee_mass_kg,
            2.0 * scene.ee_mass_kg,
        ),
        ParamKind::EeInertia(k) => {
            let v = scene.ee_inertia_kg_m2[(k, k)];
            (v, 0.2 * v, 5.0 * v)
        }
        ParamKind::EeCom(_) => {
            let arm = scene
                .cables
                .iter()
                .map(|c| c.attachment_m.norm())
                .fold(0.01, f64::max);
            (0.0, -arm, arm)
        }
        ParamKind::PulleyRadius => {
            let r = common(scene, &name, "a pulley", |i| {
                scene.cables[i].pulley.map(|p| p.radius_m)
            })?;
            (r, 0.0, (5.0 * r).max(0.1))
        }
        ParamKind::ModalRatio => match scene.damping {
            Damping::ModalRatio { zeta } => (zeta, 0.0, 0.5),
            _ => (0.01, 0.0, 0.5),
        },
        ParamKind::RayleighAlpha => match scene.damping {
            Damping::Rayleigh { alpha_per_s, .. } => (alpha_per_s, 0.0, 1000.0),
            _ => (0.0, 0.0, 1000.0),
        },
        ParamKind::RayleighBeta => match scene.damping {
            Damping::Rayleigh { beta_s, .. } => (beta_s, 0.0, 0.1),
            _ => (0.0, 0.0, 0.1),
        },
    })
}

impl FitSpec {
    /// The parameters named in `names` (groups expanded, in order) with the scene's nominal
    /// values and the default bounds. An unknown name, a name given twice, a parameter the
    /// scene does not have (an inertia on a point mass, a pulley radius without pulleys)
    /// and both damping models at once are errors naming the parameter.
    pub fn new(scene: &Scene, names: &[&str]) -> Result<FitSpec, CalibrationError> {
        let mut params: Vec<Parameter> = Vec::new();
        for raw in names {
            let name = raw.trim();
            if name.is_empty() {
                return Err(CalibrationError::param(raw, "empty parameter name"));
            }
            for kind in expand(scene, name)? {
                if params.iter().any(|p| p.kind == kind) {
                    return Err(CalibrationError::param(
                        &kind.name(),
                        "listed twice in the fit",
                    ));
                }
                let (nominal, lower, upper) = nominal_and_bounds(scene, kind)?;
                params.push(Parameter {
                    kind,
                    name: kind.name(),
                    unit: kind.unit(),
                    nominal,
                    lower,
                    upper,
                    prior_sigma: None,
                });
            }
        }
        if params.is_empty() {
            return Err(CalibrationError::NothingToFit);
        }
        let has = |f: fn(&ParamKind) -> bool| params.iter().any(|p| f(&p.kind));
        if has(|k| *k == ParamKind::ModalRatio)
            && has(|k| matches!(k, ParamKind::RayleighAlpha | ParamKind::RayleighBeta))
        {
            return Err(CalibrationError::param(
                "modal_ratio",
                "fit one damping model, modal_ratio or rayleigh, not both",
            ));
        }
        Ok(FitSpec { params })
    }

    /// The parameters `name` stands for (a parameter's name or its group's), or an error
    /// naming it when it matches none of the fitted ones.
    fn matching(&mut self, name: &str) -> Result<Vec<&mut Parameter>, CalibrationError> {
        let group = format!("{name}.");
        let hits: Vec<&mut Parameter> = self
            .params
            .iter_mut()
            .filter(|p| p.name == name || p.name.starts_with(&group))
            .collect();
        if hits.is_empty() {
            return Err(CalibrationError::NotFitted(name.to_string()));
        }
        Ok(hits)
    }

    /// Sets the bounds of `name` (a parameter or its group): finite, lower < upper.
    pub fn set_bounds(
        &mut self,
        name: &str,
        lower: f64,
        upper: f64,
    ) -> Result<(), CalibrationError> {
        if !(lower.is_finite() && upper.is_finite() && lower < upper) {
            return Err(CalibrationError::param(
                name,
                format!("bounds {lower}:{upper} must be finite with lower < upper"),
            ));
        }
        for p in self.matching(name)? {
            p.lower = lower;
            p.upper = upper;
        }
        Ok(())
    }

    /// Sets the nominal value of `name` (a parameter or its group).
    pub fn set_nominal(&mut self, name: &str, value: f64) -> Result<(), CalibrationError> {
        if !value.is_finite() {
            return Err(CalibrationError::param(
                name,
                format!("nominal value {value} is not finite"),
            ));
        }
        for p in self.matching(name)? {
            p.nominal = value;
        }
        Ok(())
    }

    /// Sets a Gaussian prior of standard deviation `sigma` (the parameter's unit, > 0)
    /// toward the nominal value of `name` (a parameter or its group).
    pub fn set_prior(&mut self, name: &str, sigma: f64) -> Result<(), CalibrationError> {
        if !(sigma.is_finite() && sigma > 0.0) {
            return Err(CalibrationError::param(
                name,
                format!("prior standard deviation {sigma} must be finite and > 0"),
            ));
        }
        for p in self.matching(name)? {
            p.prior_sigma = Some(sigma);
        }
        Ok(())
    }

    /// Every parameter's nominal value inside its bounds, and the bounds inside what the
    /// scene accepts (lengths, radii and damping ≥ 0, factors, masses and weights > 0).
    pub fn check(&self) -> Result<(), CalibrationError> {
        for p in &self.params {
            if !(p.lower <= p.nominal && p.nominal <= p.upper) {
                return Err(CalibrationError::param(
                    &p.name,
                    format!(
                        "the bounds [{}, {}] {} exclude the nominal value {}",
                        p.lower, p.upper, p.unit, p.nominal
                    ),
                ));
            }
            let positive = matches!(
                p.kind,
                ParamKind::EaFactor(_)
                    | ParamKind::EaFactorAll
                    | ParamKind::WeightPerLength
                    | ParamKind::EeMass
                    | ParamKind::EeInertia(_)
            );
            let non_negative = matches!(
                p.kind,
                ParamKind::HiddenLength(_)
                    | ParamKind::PulleyRadius
                    | ParamKind::ModalRatio
                    | ParamKind::RayleighAlpha
                    | ParamKind::RayleighBeta
            );
            if (positive && !(p.lower > 0.0)) || (non_negative && !(p.lower >= 0.0)) {
                return Err(CalibrationError::param(
                    &p.name,
                    format!(
                        "lower bound {} must be {} 0",
                        p.lower,
                        if positive { ">" } else { ">=" }
                    ),
                ));
            }
            let max = match p.kind {
                ParamKind::ModalRatio => Some(crate::scene::MAX_MODAL_RATIO),
                ParamKind::RayleighAlpha => Some(crate::scene::MAX_RAYLEIGH_ALPHA_PER_S),
                ParamKind::RayleighBeta => Some(crate::scene::MAX_RAYLEIGH_BETA_S),
                _ => None,
            };
            if let Some(max) = max {
                if !(p.upper < max) {
                    return Err(CalibrationError::param(
                        &p.name,
                        format!("upper bound {} must be below {max}", p.upper),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The nominal values, in order.
    pub fn nominal(&self) -> Vec<f64> {
        self.params.iter().map(|p| p.nominal).collect()
    }

    /// Whether any parameter changes the frequencies (not only the damping).
    pub fn has_stiffness_or_mass(&self) -> bool {
        self.params.iter().any(|p| !p.kind.is_damping())
    }
}

/// The model of one parameter vector: the scene it makes and the centre of mass's
/// body-frame offset (m) to add to every measured pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Applied {
    /// The scene with the parameters' values.
    pub scene: Scene,
    /// Body-frame offset δ of the centre of mass from the data's reference point, m.
    pub com_offset_m: Vector3<f64>,
    /// Each cable's EA factor (the product of `ea_factor.i` and `ea_factor_all`).
    pub ea_factor: Vec<f64>,
}

/// The scene `base` with the values `x` of `spec`'s parameters (in order).
pub fn apply(base: &Scene, spec: &FitSpec, x: &[f64]) -> Applied {
    let mut s = base.clone();
    let n = s.n_cables();
    let mut factor = vec![1.0; n];
    let mut all = 1.0;
    let mut com = Vector3::zeros();
    let g = base.gravity_m_s2.norm();
    for (p, &v) in spec.params.iter().zip(x) {
        match p.kind {
            ParamKind::EaFactor(i) => factor[i] *= v,
            ParamKind::EaFactorAll => all *= v,
            ParamKind::HiddenLength(i) => {
                let free = &base.cables[i];
                s.cables[i].hidden = if v > 0.0 {
                    let h = free.hidden.unwrap_or(HiddenCable {
                        length_m: v,
                        youngs_modulus_pa: free.youngs_modulus_pa,
                        area_m2: free.area_m2,
                        mass_per_length_kg_m: free.mass_per_length_kg_m,
                    });
                    Some(HiddenCable { length_m: v, ..h })
                } else {
                    None
                };
            }
            ParamKind::WeightPerLength => {
                let mu = v / g;
                for (c, b) in s.cables.iter_mut().zip(&base.cables) {
                    c.mass_per_length_kg_m = mu;
                    if let Some(h) = c.hidden.as_mut() {
                        if h.mass_per_length_kg_m == b.mass_per_length_kg_m {
                            h.mass_per_length_kg_m = mu;
                        }
                    }
                }
            }
            ParamKind::EeMass => s.ee_mass_kg = v,
            ParamKind::EeInertia(k) => s.ee_inertia_kg_m2[(k, k)] = v,
            ParamKind::EeCom(k) => com[k] = v,
            ParamKind::PulleyRadius => {
                for c in &mut s.cables {
                    if let Some(p) = c.pulley.as_mut() {
                        p.radius_m = v;
                    }
                }
            }
            ParamKind::ModalRatio => s.damping = Damping::ModalRatio { zeta: v },
            ParamKind::RayleighAlpha | ParamKind::RayleighBeta => {
                let (mut a, mut b) = match s.damping {
                    Damping::Rayleigh {
                        alpha_per_s,
                        beta_s,
                    } => (alpha_per_s, beta_s),
                    _ => (0.0, 0.0),
                };
                if p.kind == ParamKind::RayleighAlpha {
                    a = v;
                } else {
                    b = v;
                }
                s.damping = Damping::Rayleigh {
                    alpha_per_s: a,
                    beta_s: b,
                };
            }
        }
    }
    for (i, c) in s.cables.iter_mut().enumerate() {
        factor[i] *= all;
        c.youngs_modulus_pa *= factor[i];
        if let Some(h) = c.hidden.as_mut() {
            h.youngs_modulus_pa *= factor[i];
        }
        c.attachment_m -= com;
    }
    Applied {
        scene: s,
        com_offset_m: com,
        ea_factor: factor,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(spec: &FitSpec) -> Vec<String> {
        spec.params.iter().map(|p| p.name.clone()).collect()
    }

    #[test]
    fn groups_expand_and_unknown_names_are_named() {
        let s = Scene::default_scene();
        let f = FitSpec::new(&s, &["ea_factor", "ee_mass", "hidden_length.3"]).unwrap();
        assert_eq!(f.params.len(), 10);
        assert_eq!(names(&f)[0], "ea_factor.1");
        assert_eq!(names(&f)[9], "hidden_length.3");
        for (bad, needle) in [
            ("ea_fctor", "parameter `ea_fctor`: unknown parameter"),
            ("ea_factor.9", "parameter `ea_factor.9`"),
            ("ea_factor.0", "parameter `ea_factor.0`"),
            ("ee_inertia", "point mass"),
            ("pulley_radius", "no cable of the scene has a pulley"),
        ] {
            let e = FitSpec::new(&s, &[bad]).unwrap_err().to_string();
            assert!(e.contains(needle), "{bad}: {e}");
            assert!(!e.contains('\n'));
        }
        let e = FitSpec::new(&s, &["ea_factor", "ea_factor.2"]).unwrap_err();
        assert!(e.to_string().contains("`ea_factor.2`: listed twice"), "{e}");
        let e = FitSpec::new(&s, &["modal_ratio", "rayleigh.beta"]).unwrap_err();
        assert!(e.to_string().contains("not both"), "{e}");
    }

    #[test]
    fn bounds_that_exclude_the_nominal_are_refused_naming_the_parameter() {
        let s = Scene::default_scene();
        let mut f = FitSpec::new(&s, &["ee_mass", "ea_factor"]).unwrap();
        f.set_bounds("ea_factor", 0.5, 1.5).unwrap();
        assert!(f.params.iter().skip(1).all(|p| p.lower == 0.5));
        f.check().unwrap();
        f.set_bounds("ee_mass", 31.0, 40.0).unwrap();
        let e = f.check().unwrap_err().to_string();
        assert!(
            e.starts_with(
                "parameter `ee_mass`: the bounds [31, 40] kg exclude the nominal value 30"
            ),
            "{e}"
        );
        let e = f.set_bounds("hidden_length", 0.0, 1.0).unwrap_err();
        // The library names its own option (`fit`); a front end renders its flag.
        assert_eq!(
            e.to_string(),
            "parameter `hidden_length`: is not among the fitted parameters (add it to fit)"
        );
        assert!(e.render(&|_| "--fit").ends_with("(add it to --fit)"), "{e}");
        assert!(f.set_bounds("ee_mass", 2.0, 1.0).is_err());
        assert!(f.set_prior("ee_mass", 0.0).is_err());
    }

    #[test]
    fn apply_scales_free_and_hidden_ea_and_sets_hidden_lengths() {
        let s = Scene::default_scene();
        let f = FitSpec::new(
            &s,
            &["ea_factor.2", "ea_factor_all", "hidden_length.2", "ee_mass"],
        )
        .unwrap();
        let a = apply(&s, &f, &[0.5, 2.0, 1.5, 33.0]);
        let c = &a.scene.cables[1];
        assert_eq!(c.youngs_modulus_pa, s.cables[1].youngs_modulus_pa);
        let h = c.hidden.unwrap();
        assert_eq!(h.length_m, 1.5);
        assert_eq!(h.ea_n(), s.cables[1].ea_n());
        assert_eq!(a.scene.cables[0].ea_n(), 2.0 * s.cables[0].ea_n());
        assert_eq!(a.scene.ee_mass_kg, 33.0);
        // Zero hidden length: no hidden cable; the nominal values give the scene back.
        let a = apply(&s, &f, &[1.0, 1.0, 0.0, 30.0]);
        assert_eq!(a.scene, s);
    }
}
