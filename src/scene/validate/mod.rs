//! Validation: the raw scene into a [`Scene`], one function per concern. The first failing
//! check is the error reported, so [`scene_from_raw`] keeps one fixed order: name, gravity,
//! end-effector, tension bounds, model, effects, inertia, orientation, rigid-body cable
//! count, geometric stiffness, cable count, then each cable in turn.
//!
//! `cable`: the checks of one cable (`hidden`: its hidden part behind the pulley);
//! `damping`: `[damping]`; the checks shared by several keys stay here ([`Checker`]).

use super::bounds::{check_t_min, TminRangeError};
use super::parse::{RawArray, RawEffects, RawEndEffector, RawModel, RawScene, RawTension};
use super::{ElementKind, ModelSettings, Scene, SceneError, MAX_CABLES, MAX_ELEMENTS_PER_CABLE};
use crate::input_file::message_number;
use nalgebra::{Matrix3, Vector3};

mod cable;
mod damping;
mod hidden;

use cable::{validate_cable, CableContext};
use damping::validate_damping;

/// Largest accepted |g|, m/s²: far above any planet's, so only a unit mistake exceeds it.
const MAX_GRAVITY_M_S2: f64 = 1e3;
/// Asymmetry of the inertia tensor tolerated, relative to its largest entry (rounding of
/// the printed values, not a real asymmetry).
const INERTIA_SYMMETRY_REL_TOL: f64 = 1e-9;
/// Deviation of the orientation quaternion's norm from 1 tolerated (printed digits).
const QUATERNION_NORM_TOL: f64 = 1e-6;
/// Largest accepted axial rigidity EA, N: well above any real cable, and small enough that
/// EA/l stays a usable stiffness.
const MAX_AXIAL_RIGIDITY_N: f64 = 1e15;

/// Builds errors that name the file, and the checks shared by several keys.
pub(super) struct Checker<'a> {
    pub(super) file: &'a str,
}

impl Checker<'_> {
    /// An [`SceneError::Invalid`] for `key`.
    pub(super) fn inv(&self, key: &str, message: String) -> SceneError {
        SceneError::Invalid {
            file: self.file.to_string(),
            key: key.to_string(),
            message,
        }
    }

    /// The elements of an array of exactly `n` values (`noun` names them in the message).
    fn elements<'v>(
        &self,
        key: &str,
        raw: &'v toml::Value,
        n: usize,
        noun: &str,
    ) -> Result<&'v [toml::Value], SceneError> {
        match raw {
            toml::Value::Array(a) if a.len() == n => Ok(a),
            toml::Value::Array(a) => {
                Err(self.inv(key, format!("expected {n} {noun}, got {}", a.len())))
            }
            other => Err(self.inv(
                key,
                format!("expected an array of {n} {noun}, got {}", a_type(other)),
            )),
        }
    }

    /// A number: a float, or an integer read as a float (as serde reads it into `f64`).
    fn number(&self, key: &str, raw: &toml::Value) -> Result<f64, SceneError> {
        match *raw {
            toml::Value::Float(x) => Ok(x),
            toml::Value::Integer(i) => Ok(i as f64),
            ref other => Err(self.inv(key, format!("expected a number, got {}", a_type(other)))),
        }
    }

    /// An array of exactly `N` numbers (not yet checked for finiteness); an element's error
    /// names it as `key[j]`.
    fn numbers<const N: usize>(
        &self,
        key: &str,
        raw: &toml::Value,
    ) -> Result<[f64; N], SceneError> {
        let mut out = [0.0; N];
        let elements = self.elements(key, raw, N, "numbers")?;
        for (j, (o, x)) in out.iter_mut().zip(elements).enumerate() {
            *o = self.number(&format!("{key}[{j}]"), x)?;
        }
        Ok(out)
    }

    /// Exactly three numbers, all finite.
    fn finite3(&self, key: &str, raw: &RawArray) -> Result<Vector3<f64>, SceneError> {
        let v: [f64; 3] = self.numbers(key, &raw.0)?;
        if v.iter().all(|x| x.is_finite()) {
            Ok(Vector3::new(v[0], v[1], v[2]))
        } else {
            Err(self.inv(key, format!("must be finite, got {v:?}")))
        }
    }

    /// A finite value > 0.
    pub(super) fn positive(&self, key: &str, x: f64) -> Result<f64, SceneError> {
        if x.is_finite() && x > 0.0 {
            Ok(x)
        } else {
            Err(self.inv(key, format!("must be finite and > 0, got {x:?}")))
        }
    }
}

/// A TOML value's type with its article, for messages ("a string", "an array").
fn a_type(v: &toml::Value) -> String {
    let t = v.type_str();
    let article = if t.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    };
    format!("{article} {t}")
}

/// The key of field `k` of cable `i`, as users write it.
pub(super) fn cable_key(i: usize, k: &str) -> String {
    format!("cables[{i}].{k}")
}

/// Check every value of `raw` and build the scene (`file` names the source in errors).
pub(super) fn scene_from_raw(raw: RawScene, file: &str) -> Result<Scene, SceneError> {
    let ck = Checker { file };
    validate_name(&ck, &raw.name)?;
    let (gravity, g) = validate_gravity(&ck, &raw.gravity)?;
    let (ee_mass, ee_pos) = validate_end_effector(&ck, &raw.end_effector, g)?;
    let (t_min, t_max) = validate_tension_bounds(&ck, &raw.tension)?;
    let (n, part) = validate_model(&ck, &raw.model)?;
    let fx = raw.effects.unwrap_or_default();
    let (element, sag) = validate_effects(&ck, fx, raw.model.element)?;
    let rigid = fx.rotation.unwrap_or(false);
    let inertia = validate_inertia(&ck, rigid, raw.end_effector.inertia.as_ref())?;
    let orientation = validate_orientation(&ck, raw.end_effector.orientation.as_ref())?;
    validate_rigid_cable_count(&ck, rigid, raw.cables.len())?;
    let geometric_stiffness = validate_geometric_stiffness(&ck, fx, element)?;
    validate_cable_count(&ck, raw.cables.len())?;
    let damping = validate_damping(&ck, raw.damping)?;
    let at = CableContext {
        defaults: raw.cable,
        ee_pos,
        ee_position: [ee_pos.x, ee_pos.y, ee_pos.z],
        rigid,
        g,
        t_min_n: t_min,
        t_max_n: t_max,
    };
    let mut cables = Vec::with_capacity(raw.cables.len());
    for (i, c) in raw.cables.iter().enumerate() {
        cables.push(validate_cable(&ck, &at, i, c)?);
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
            elements_per_cable: n,
            ee_participation_min: part,
            geometric_stiffness,
            f1_tolerance: raw.model.f1_tolerance,
            sag,
            sag_explicit: fx.sag.is_some(),
        },
        rigid,
        ee_inertia_kg_m2: inertia,
        ee_orientation_wxyz: orientation,
        damping,
    })
}

/// `name`: not blank.
fn validate_name(ck: &Checker, name: &str) -> Result<(), SceneError> {
    if name.trim().is_empty() {
        return Err(ck.inv("name", "must not be empty".into()));
    }
    Ok(())
}

/// `gravity`: finite and plausible; returns g and |g|.
fn validate_gravity(ck: &Checker, raw: &RawArray) -> Result<(Vector3<f64>, f64), SceneError> {
    let gravity = ck.finite3("gravity", raw)?;
    let g = gravity.norm();
    if g > MAX_GRAVITY_M_S2 {
        return Err(ck.inv(
            "gravity",
            format!("|g| = {} m/s² is implausible (> 1000)", message_number(g)),
        ));
    }
    Ok((gravity, g))
}

/// `[end_effector]` mass (kg, > 0, with a finite weight m·|g| for `g` = |g|, m/s²) and
/// position (m, finite); its inertia and orientation are checked with the effects that use
/// them.
fn validate_end_effector(
    ck: &Checker,
    raw: &RawEndEffector,
    g: f64,
) -> Result<(f64, Vector3<f64>), SceneError> {
    let ee_mass = ck.positive("end_effector.mass", raw.mass)?;
    if !(ee_mass * g).is_finite() {
        return Err(ck.inv(
            "end_effector.mass",
            format!(
                "{} kg weighs {} kg × {} m/s², which is not a finite force",
                message_number(ee_mass),
                message_number(ee_mass),
                message_number(g)
            ),
        ));
    }
    let ee_pos = ck.finite3("end_effector.position", &raw.position)?;
    Ok((ee_mass, ee_pos))
}

/// `[tension]`: t_min and t_max (N) by [`check_bound_pair`].
fn validate_tension_bounds(ck: &Checker, raw: &RawTension) -> Result<(f64, f64), SceneError> {
    check_bound_pair(ck, "tension.t_min", "tension.t_max", raw.t_min, raw.t_max)?;
    Ok((raw.t_min, raw.t_max))
}

/// A pair of tension bounds (N): t_max finite and > 0, t_min by the crate's one T_min rule
/// ([`check_t_min`]: finite, > 0 and not subnormal, ≤ t_max). Errors name `min_key` or
/// `max_key`.
pub(super) fn check_bound_pair(
    ck: &Checker,
    min_key: &str,
    max_key: &str,
    t_min_n: f64,
    t_max_n: f64,
) -> Result<(), SceneError> {
    if let Err(e @ (TminRangeError::NotFinite { .. } | TminRangeError::BelowFloor { .. })) =
        check_t_min(t_min_n, f64::MAX)
    {
        return Err(ck.inv(min_key, e.to_string()));
    }
    ck.positive(max_key, t_max_n)?;
    check_t_min(t_min_n, t_max_n).map_err(|e| ck.inv(min_key, e.to_string()))
}

/// `[model]`: element count, f1 tolerance and participation threshold in range; returns
/// the element count and the participation threshold.
fn validate_model(ck: &Checker, raw: &RawModel) -> Result<(usize, f64), SceneError> {
    let n = raw.elements_per_cable;
    if n < 1 || n as usize > MAX_ELEMENTS_PER_CABLE {
        return Err(ck.inv(
            "model.elements_per_cable",
            format!("must be in 1..={MAX_ELEMENTS_PER_CABLE}, got {n}"),
        ));
    }
    let tol = raw.f1_tolerance;
    if !(tol.is_finite() && tol > 0.0 && tol < 1.0) {
        return Err(ck.inv(
            "model.f1_tolerance",
            format!("must be in (0, 1), got {tol:?}"),
        ));
    }
    let part = raw.ee_participation_min;
    if !(part.is_finite() && part > 0.0 && part <= 1.0) {
        return Err(ck.inv(
            "model.ee_participation_min",
            format!("must be in (0, 1], got {part:?}"),
        ));
    }
    Ok((n as usize, part))
}

/// `[effects]` against `model.element`: cable_mass = false → massless springs; sag = true
/// keeps `fem`, `continuous` and `auto` and switches them to the sagged profile; a
/// contradiction is an error. Returns the element and whether the cables sag.
fn validate_effects(
    ck: &Checker,
    fx: RawEffects,
    element: ElementKind,
) -> Result<(ElementKind, bool), SceneError> {
    let mut element = element;
    if let Some(mass) = fx.cable_mass {
        match (mass, element) {
            (false, _) => element = ElementKind::Massless,
            (true, ElementKind::Massless) => {
                return Err(ck.inv(
                    "effects.cable_mass",
                    "cable_mass = true contradicts model.element = \"massless\"".into(),
                ))
            }
            _ => {}
        }
    }
    let sag = fx.sag.unwrap_or(false);
    match super::sag_refusal(sag, element) {
        Some(why) => Err(ck.inv("effects.sag", why.into())),
        None => Ok((element, sag)),
    }
}

/// `end_effector.inertia`: required by a rigid end-effector; when given, finite, symmetric
/// and positive definite (kg·m²). Zero for a point mass without one.
fn validate_inertia(
    ck: &Checker,
    rigid: bool,
    raw: Option<&RawArray>,
) -> Result<Matrix3<f64>, SceneError> {
    const KEY: &str = "end_effector.inertia";
    let raw = raw.map(|r| inertia_rows(ck, KEY, r)).transpose()?;
    match (rigid, raw) {
        (true, None) => Err(ck.inv(
            KEY,
            "missing: effects.rotation = true needs the inertia tensor (kg·m², body frame)".into(),
        )),
        (_, Some(m)) => {
            let m = Matrix3::from_fn(|r, c| m[r][c]);
            if !m.iter().all(|x| x.is_finite())
                || (m - m.transpose()).abs().max() > INERTIA_SYMMETRY_REL_TOL * m.abs().max()
            {
                return Err(ck.inv(KEY, "must be finite and symmetric".into()));
            }
            if m.cholesky().is_none() {
                return Err(ck.inv(KEY, "must be positive definite".into()));
            }
            Ok(m)
        }
        (false, None) => Ok(Matrix3::zeros()),
    }
}

/// The inertia tensor as written: exactly 3 rows of exactly 3 numbers.
fn inertia_rows(ck: &Checker, key: &str, raw: &RawArray) -> Result<[[f64; 3]; 3], SceneError> {
    let mut m = [[0.0; 3]; 3];
    let rows = ck.elements(key, &raw.0, 3, "rows of 3 numbers")?;
    for (r, (out, row)) in m.iter_mut().zip(rows).enumerate() {
        *out = ck.numbers(&format!("{key}[{r}]"), row)?;
    }
    Ok(m)
}

/// `end_effector.orientation`: a unit quaternion [w, x, y, z] (identity when absent).
fn validate_orientation(ck: &Checker, raw: Option<&RawArray>) -> Result<[f64; 4], SceneError> {
    let orientation = match raw {
        Some(r) => ck.numbers("end_effector.orientation", &r.0)?,
        None => [1.0, 0.0, 0.0, 0.0],
    };
    let qn = orientation.iter().map(|x| x * x).sum::<f64>().sqrt();
    if !orientation.iter().all(|x| x.is_finite()) || (qn - 1.0).abs() > QUATERNION_NORM_TOL {
        return Err(ck.inv(
            "end_effector.orientation",
            format!("must be a unit quaternion [w, x, y, z], norm {qn:?}"),
        ));
    }
    Ok(orientation)
}

/// A rigid end-effector (6 DOF) needs at least 6 cables.
fn validate_rigid_cable_count(ck: &Checker, rigid: bool, n: usize) -> Result<(), SceneError> {
    if rigid && n < 6 {
        return Err(ck.inv(
            "cables",
            format!("a rigid end-effector needs at least 6 cables, got {n}"),
        ));
    }
    Ok(())
}

/// `effects.geometric_stiffness` (default on) may be off only for massless cables.
fn validate_geometric_stiffness(
    ck: &Checker,
    fx: RawEffects,
    element: ElementKind,
) -> Result<bool, SceneError> {
    let geometric_stiffness = fx.geometric_stiffness.unwrap_or(true);
    if !geometric_stiffness && element != ElementKind::Massless {
        return Err(ck.inv(
            "effects.geometric_stiffness",
            "without geometric stiffness a cable with mass has no transverse stiffness (its string modes are at 0 Hz); \
             switch it off only with cable_mass = false"
                .into(),
        ));
    }
    Ok(geometric_stiffness)
}

/// Between 2 and [`MAX_CABLES`] cables.
fn validate_cable_count(ck: &Checker, n: usize) -> Result<(), SceneError> {
    if n < 2 {
        return Err(ck.inv(
            "cables",
            format!(
                "at least 2 cables are needed to hold a point mass in a plane (and 4 in space), got {n}"
            ),
        ));
    }
    if n > MAX_CABLES {
        return Err(ck.inv(
            "cables",
            format!("at most {MAX_CABLES} cables are supported, got {n}"),
        ));
    }
    Ok(())
}

/// Mass per length μ (kg/m) of cable `i` from the one given of `{p}weight_per_length` `w`
/// (N/m, over the gravity `g`, m/s²) and `{p}mass_per_length` `m` (`p` the keys' prefix:
/// `""` for the free cable, `"hidden_"` for its hidden part); None when neither is. Both is
/// an error, a weight needs gravity, and the μ of a weight must be a normal positive number.
pub(super) fn weight_or_mass_per_length(
    ck: &Checker,
    i: usize,
    p: &str,
    w: Option<f64>,
    m: Option<f64>,
    g: f64,
) -> Result<Option<f64>, SceneError> {
    let weight_key = cable_key(i, &format!("{p}weight_per_length"));
    match (w, m) {
        (Some(_), Some(_)) => Err(ck.inv(
            &weight_key,
            format!("give {p}weight_per_length or {p}mass_per_length, not both"),
        )),
        (Some(w), None) => {
            let w = ck.positive(&weight_key, w)?;
            if g <= 0.0 {
                return Err(ck.inv(
                    &weight_key,
                    format!("needs non-zero gravity to convert to mass; give {p}mass_per_length"),
                ));
            }
            let mu = w / g;
            if !(mu.is_normal() && mu > 0.0) {
                return Err(ck.inv(
                    &weight_key,
                    format!("gives a mass per length of {mu:e} kg/m, not a usable positive number"),
                ));
            }
            Ok(Some(mu))
        }
        (None, Some(m)) => Ok(Some(
            ck.positive(&cable_key(i, &format!("{p}mass_per_length")), m)?,
        )),
        (None, None) => Ok(None),
    }
}

/// EA = youngs_modulus × area of cable `i` must be a usable number (an overflowing E·A
/// gives ∞).
pub(super) fn validate_axial_rigidity(ck: &Checker, i: usize, ea: f64) -> Result<(), SceneError> {
    if !(ea.is_normal() && ea > 0.0 && ea < MAX_AXIAL_RIGIDITY_N) {
        return Err(ck.inv(
            &cable_key(i, "area"),
            format!(
                "youngs_modulus × area = {ea:e} N is not a usable axial rigidity (0 < EA < 1e15 N)"
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::{Damping, DEFAULT_SCENE_TOML};
    use super::*;

    /// A paper scene's text without its `[effects]` table (`sag = false`), so that a test can
    /// append a table of its own.
    fn without_effects(text: &str) -> String {
        let i = text.find("[effects]\n").expect("[effects]");
        let j = i
            + text[i..]
                .find("\n\n")
                .expect("a blank line after [effects]")
            + 2;
        format!("{}{}", &text[..i], &text[j..])
    }

    fn err(text: &str) -> String {
        Scene::from_toml_str(text, "t.toml")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn damping_one_kind_within_bounds() {
        let base = DEFAULT_SCENE_TOML;
        let with = |d: &str| Scene::from_toml_str(&format!("{base}\n[damping]\n{d}\n"), "t.toml");
        assert_eq!(Scene::default_scene().damping, Damping::None);
        assert_eq!(
            with("loss_factor = 0.02").unwrap().damping,
            Damping::LossFactor { eta: 0.02 }
        );
        assert_eq!(
            with("modal_ratio = 0.01").unwrap().damping,
            Damping::ModalRatio { zeta: 0.01 }
        );
        let r = with("rayleigh_beta = 1e-4").unwrap().damping;
        assert_eq!(
            r,
            Damping::Rayleigh {
                alpha_per_s: 0.0,
                beta_s: 1e-4
            }
        );
        // ζ(ω) = α/(2ω) + βω/2: with β alone, 1e-4 · 100 / 2.
        assert_eq!(r.modal_ratio(100.0), 5e-3);
        for (bad, key) in [
            ("modal_ratio = 1.0", "damping.modal_ratio"),
            ("modal_ratio = -0.01", "damping.modal_ratio"),
            ("modal_ratio = nan", "damping.modal_ratio"),
            ("loss_factor = 2.5", "damping.loss_factor"),
            ("rayleigh_alpha = inf", "damping.rayleigh_alpha"),
            ("rayleigh_beta = -1e-3", "damping.rayleigh_beta"),
            ("loss_factor = 0.02\nmodal_ratio = 0.01", "one kind"),
            ("", "empty [damping]"),
        ] {
            let e = with(bad).unwrap_err().to_string();
            assert!(e.contains(key) && !e.contains('\n'), "{bad}: {e}");
        }
        let e = with("zeta = 0.01").unwrap_err().to_string();
        assert!(e.contains("zeta"), "unknown keys are refused: {e}");
    }

    #[test]
    fn effects_select_the_model() {
        let base = &without_effects(DEFAULT_SCENE_TOML);
        let with = |fx: &str| Scene::from_toml_str(&format!("{base}\n[effects]\n{fx}\n"), "t.toml");
        let sagged = with("sag = true").unwrap();
        assert_eq!(sagged.model.element, ElementKind::Fem);
        assert!(sagged.model.sag);
        assert!(
            !Scene::default_scene().model.sag,
            "no [effects]: the chord model"
        );
        let e = with("sag = true\ncable_mass = false")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("effects.sag") && e.contains("does not sag"),
            "{e}"
        );
        let cat = base.replace("element = \"fem\"", "element = \"catenary\"");
        let e = Scene::from_toml_str(&format!("{cat}\n[effects]\nsag = true\n"), "t.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("sags only inside each element"), "{e}");
        let chord = Scene::from_toml_str(&format!("{cat}\n[effects]\nsag = false\n"), "t.toml");
        assert_eq!(chord.unwrap().model.element, ElementKind::Catenary);
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

    /// The first cable's `[[cables]]` table of the default scene with `extra` lines added.
    fn with_first_cable(extra: &str) -> String {
        let base = DEFAULT_SCENE_TOML;
        let anchor = "anchor = [1.25, 1.25, 2.5]";
        assert!(base.contains(anchor));
        base.replacen(anchor, &format!("{anchor}\n{extra}"), 1)
    }

    #[test]
    fn pulleys_parse_default_and_are_checked() {
        assert!(Scene::default_scene()
            .cables
            .iter()
            .all(|c| c.pulley.is_none()));
        let own = "pulley = { radius = 0.05, entry_direction = [0, 0, 2] }";
        let s = Scene::from_toml_str(&with_first_cable(own), "t.toml").unwrap();
        let p = s.cables[0].pulley.unwrap();
        assert_eq!((p.radius_m, p.entry_unit), (0.05, Vector3::z()));
        assert!(s.cables[1].pulley.is_none());
        // `[cable.pulley]` is every other cable's.
        let def = DEFAULT_SCENE_TOML.replacen(
            "[tension]",
            "[cable.pulley]\nradius = 0.02\nentry_direction = [1, 0, 0]\n[tension]",
            1,
        );
        assert!(def.contains("[cable.pulley]"));
        let s = Scene::from_toml_str(&def, "t.toml").unwrap();
        assert!(s.cables.iter().all(|c| c.pulley.unwrap().radius_m == 0.02));
        for (bad, key, what) in [
            (
                "radius = -0.1, entry_direction = [0, 0, 1]",
                "cables[0].pulley.radius",
                ">= 0",
            ),
            (
                "radius = nan, entry_direction = [0, 0, 1]",
                "cables[0].pulley.radius",
                ">= 0",
            ),
            (
                "radius = 0.1, entry_direction = [0, 0, 0]",
                "cables[0].pulley.entry_direction",
                "non-zero",
            ),
            (
                "radius = 0.1, entry_direction = [0, 1]",
                "cables[0].pulley.entry_direction",
                "expected 3",
            ),
            ("radius = 0.1", "pulley", "entry_direction"),
            (
                "radius = 0.1, entry_direction = [0, 0, 1], axis = 1",
                "pulley",
                "axis",
            ),
        ] {
            let e = Scene::from_toml_str(
                &with_first_cable(&format!("pulley = {{ {bad} }}")),
                "t.toml",
            )
            .unwrap_err()
            .to_string();
            assert!(e.contains(key) && e.contains(what), "{bad}: {e}");
        }
    }

    #[test]
    fn per_cable_bounds_parse_and_default_to_the_scene() {
        let s = Scene::from_toml_str(&with_first_cable("t_min = 80.0\nt_max = 300.0"), "t.toml")
            .unwrap();
        assert_eq!((s.cable_t_min_n(0), s.cable_t_max_n(0)), (80.0, 300.0));
        assert_eq!((s.cable_t_min_n(1), s.cable_t_max_n(1)), (60.0, 350.0));
        assert!(s.has_per_cable_bounds());
        let only_max = Scene::from_toml_str(&with_first_cable("t_max = 200.0"), "t.toml").unwrap();
        assert_eq!(
            (only_max.cable_t_min_n(0), only_max.cable_t_max_n(0)),
            (60.0, 200.0)
        );
        assert!(!Scene::default_scene().has_per_cable_bounds());
    }

    #[test]
    fn bad_per_cable_bounds_are_refused_naming_file_and_key() {
        let subnormal = format!("{:e}", f64::MIN_POSITIVE / 2.0);
        for (extra, key, what) in [
            ("t_min = 0.0", "cables[0].t_min", "> 0"),
            ("t_min = -1.0", "cables[0].t_min", "> 0"),
            (
                &format!("t_min = {subnormal}")[..],
                "cables[0].t_min",
                "subnormal",
            ),
            ("t_min = nan", "cables[0].t_min", "finite"),
            ("t_min = inf", "cables[0].t_min", "finite"),
            ("t_max = 0.0", "cables[0].t_max", "> 0"),
            ("t_max = nan", "cables[0].t_max", "finite"),
            ("t_min = 200.0\nt_max = 100.0", "cables[0].t_min", "exceeds"),
            ("t_min = 400.0", "cables[0].t_min", "exceeds"),
            ("t_max = 50.0", "cables[0].t_max", "exceeds"),
            ("t_min = \"big\"", "t_min", "invalid type"),
        ] {
            let e = err(&with_first_cable(extra));
            assert!(
                e.contains("t.toml") && e.contains(key) && e.contains(what),
                "{extra}: {e}"
            );
        }
    }

    #[test]
    fn scene_t_min_obeys_the_one_rule() {
        let base = DEFAULT_SCENE_TOML;
        for bad in ["0.0", "-0.0", "2e-310"] {
            let e = err(&base.replace("t_min = 60.0", &format!("t_min = {bad}")));
            assert!(
                e.contains("t.toml") && e.contains("tension.t_min"),
                "{bad}: {e}"
            );
        }
        let floor = format!("t_min = {:e}", f64::MIN_POSITIVE);
        assert!(Scene::from_toml_str(&base.replace("t_min = 60.0", &floor), "t.toml").is_ok());
    }

    #[test]
    fn a_mass_whose_weight_is_not_finite_is_refused_naming_the_key() {
        let base = DEFAULT_SCENE_TOML;
        let e = err(&base.replace("mass = 30.0", "mass = 1e308"));
        assert!(
            e.contains("t.toml") && e.contains("end_effector.mass") && e.contains("1e308 kg"),
            "{e}"
        );
        assert!(e.len() < 200, "compact numbers: {e}");
        let e = err(&base.replace("[0.0, 0.0, -9.81]", "[0.0, 0.0, -1e100]"));
        assert!(e.contains("gravity") && e.contains("1e100 m/s²"), "{e}");
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
        let e = err(&base.replace(
            "gravity = [0.0, 0.0, -9.81]",
            "gravity = [0, 0, -9.81, 12345, \"junk\", [1]]",
        ));
        assert_eq!(e, "t.toml: key `gravity`: expected 3 numbers, got 6");
        let e = err(&base.replace("[0.0, 0.0, 1.25]", "[0.0, 0.0, 1.25, nan]"));
        assert_eq!(
            e,
            "t.toml: key `end_effector.position`: expected 3 numbers, got 4"
        );
    }
}
