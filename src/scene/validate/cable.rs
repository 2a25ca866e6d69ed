//! `cables[i]`: one cable's anchor, attachment, pulley, tension bounds, material and hidden
//! part, each key from the cable's own table, else from `[cable]`.

use super::{
    cable_key, check_bound_pair, validate_axial_rigidity, weight_or_mass_per_length, Checker,
};
use crate::scene::parse::{RawArray, RawCable, RawCableDefaults, RawPulley};
use crate::scene::{Cable, Pulley, SceneError};
use nalgebra::Vector3;

/// Closest an anchor may be to the end-effector position, m: a cable of zero length has no
/// direction.
const MIN_ANCHOR_DISTANCE_M: f64 = 1e-6;

/// What every cable's checks need from the rest of the scene.
pub(super) struct CableContext {
    /// `[cable]`: values for keys a cable does not give.
    pub(super) defaults: RawCableDefaults,
    /// End-effector position, m.
    pub(super) ee_pos: Vector3<f64>,
    /// The same as written in the file (for the message).
    pub(super) ee_position: [f64; 3],
    /// Rigid end-effector (attachment points allowed).
    pub(super) rigid: bool,
    /// |g|, m/s² (weight per length → mass per length).
    pub(super) g: f64,
    /// `tension.t_min`, N: the lower bound of a cable without its own.
    pub(super) t_min_n: f64,
    /// `tension.t_max`, N: the upper bound of a cable without its own.
    pub(super) t_max_n: f64,
}

/// `cables[i]`: anchor, attachment and material.
pub(super) fn validate_cable(
    ck: &Checker,
    at: &CableContext,
    i: usize,
    c: &RawCable,
) -> Result<Cable, SceneError> {
    let d = &at.defaults;
    let anchor = ck.finite3(&cable_key(i, "anchor"), &c.anchor)?;
    let attachment = validate_attachment(ck, i, c.attachment.as_ref(), at.rigid)?;
    if (anchor - at.ee_pos).norm() < MIN_ANCHOR_DISTANCE_M {
        return Err(ck.inv(
            &cable_key(i, "anchor"),
            format!("coincides with end_effector.position {:?}", at.ee_position),
        ));
    }
    let pick = |own: Option<f64>, def: Option<f64>, name: &str| -> Result<f64, SceneError> {
        match own.or(def) {
            Some(v) => ck.positive(&cable_key(i, name), v),
            None => Err(ck.inv(
                &cable_key(i, name),
                format!("missing: give cable.{name} or cables[{i}].{name}"),
            )),
        }
    };
    let e = pick(c.youngs_modulus, d.youngs_modulus, "youngs_modulus")?;
    let a = pick(c.area, d.area, "area")?;
    let mu = validate_mass_per_length(ck, i, c, d, at.g)?;
    validate_axial_rigidity(ck, i, e * a)?;
    validate_cable_bounds(ck, at, i, c)?;
    let pulley = match (&c.pulley, &d.pulley) {
        (Some(p), _) => Some(validate_pulley(ck, &cable_key(i, "pulley"), p)?),
        (None, Some(p)) => Some(validate_pulley(ck, "cable.pulley", p)?),
        (None, None) => None,
    };
    let hidden = super::hidden::validate_hidden(ck, i, c, d, (e, a, mu), at.g)?;
    Ok(Cable {
        anchor_m: anchor,
        youngs_modulus_pa: e,
        area_m2: a,
        mass_per_length_kg_m: mu,
        attachment_m: attachment,
        t_min_n: c.t_min,
        t_max_n: c.t_max,
        pulley,
        hidden,
    })
}

/// A pulley table (`key`: `cables[i].pulley` or `cable.pulley`): radius finite and ≥ 0,
/// entry direction three finite numbers, not all zero (normalised here).
fn validate_pulley(ck: &Checker, key: &str, p: &RawPulley) -> Result<Pulley, SceneError> {
    if !(p.radius.is_finite() && p.radius >= 0.0) {
        return Err(ck.inv(
            &format!("{key}.radius"),
            format!("must be finite and >= 0 m, got {:?}", p.radius),
        ));
    }
    let dkey = format!("{key}.entry_direction");
    let d = ck.finite3(&dkey, &p.entry_direction)?;
    let Some(entry_unit) = crate::scene::unit_direction(&d) else {
        return Err(ck.inv(
            &dkey,
            format!(
                "must be a non-zero direction (the swivel axis), got {:?}",
                [d.x, d.y, d.z]
            ),
        ));
    };
    Ok(Pulley {
        entry_unit,
        radius_m: p.radius,
    })
}

/// `cables[i].t_min`, `cables[i].t_max` (N, optional): with the scene's bounds for the one
/// not given, a pair by [`check_bound_pair`]; t_min above t_max names the key the cable gave.
fn validate_cable_bounds(
    ck: &Checker,
    at: &CableContext,
    i: usize,
    c: &RawCable,
) -> Result<(), SceneError> {
    if c.t_min.is_none() && c.t_max.is_none() {
        return Ok(());
    }
    let max_key = cable_key(i, "t_max");
    let min_key = if c.t_min.is_some() {
        cable_key(i, "t_min")
    } else {
        max_key.clone()
    };
    check_bound_pair(
        ck,
        &min_key,
        &max_key,
        c.t_min.unwrap_or(at.t_min_n),
        c.t_max.unwrap_or(at.t_max_n),
    )
}

/// `cables[i].attachment`: finite; non-zero only on a rigid end-effector.
fn validate_attachment(
    ck: &Checker,
    i: usize,
    raw: Option<&RawArray>,
    rigid: bool,
) -> Result<Vector3<f64>, SceneError> {
    match raw {
        Some(b) => {
            let b = ck.finite3(&cable_key(i, "attachment"), b)?;
            if !rigid && b.norm() > 0.0 {
                return Err(ck.inv(
                    &cable_key(i, "attachment"),
                    "attachment points need the rigid end-effector: set effects.rotation = true"
                        .into(),
                ));
            }
            Ok(b)
        }
        None => Ok(Vector3::zeros()),
    }
}

/// Mass per length μ (kg/m) of cable `i` from weight or mass per length: the cable's own
/// keys win over the defaults; within one level, both is an error.
fn validate_mass_per_length(
    ck: &Checker,
    i: usize,
    c: &RawCable,
    d: &RawCableDefaults,
    g: f64,
) -> Result<f64, SceneError> {
    let key = |k: &str| cable_key(i, k);
    let (w, m) = if c.weight_per_length.is_some() || c.mass_per_length.is_some() {
        (c.weight_per_length, c.mass_per_length)
    } else {
        (d.weight_per_length, d.mass_per_length)
    };
    let Some(mu) = weight_or_mass_per_length(ck, i, "", w, m, g)? else {
        return Err(ck.inv(
            &key("weight_per_length"),
            "missing: give weight_per_length or mass_per_length".into(),
        ));
    };
    // A usable number also from a mass (a denormal one is positive but useless; a weight's
    // μ is checked above).
    if !(mu.is_normal() && mu > 0.0) {
        return Err(ck.inv(
            &key("mass_per_length"),
            format!("gives a mass per length of {mu:e} kg/m, not a usable positive number"),
        ));
    }
    Ok(mu)
}
