//! `cablevib calibrate -o`: the calibrated scene file, written as an edit of the scene's own
//! text (toml_edit keeps its comments, order and layout): each fitted value is set where the
//! scene's model reads it, per cable where it is a cable's (`[[cables]] youngs_modulus`,
//! `hidden_length`, …), with the estimate and its standard error in a comment beside it, and
//! a header recording the fit. The text is read back with the scene parser and compared
//! with the calibrated model before it is handed out: a scene that would not read back as
//! the model that was fitted is an error, never a file.

use crate::calibration::{Applied, FitSpec, ParamKind, Report};
use crate::scene::{Damping, Scene};
use nalgebra::Vector3;
use toml_edit::{DocumentMut, Item, TableLike, Value};

/// Why the calibrated scene was not made.
#[derive(Debug, thiserror::Error)]
pub enum CalibratedSceneError {
    /// The scene's text did not parse as TOML (it parsed as a scene before, so this is a
    /// difference between the two parsers).
    #[error("{origin}: the scene's text could not be edited: {message}")]
    Edit {
        /// The scene.
        origin: String,
        /// Why.
        message: String,
    },
    /// The edited text does not read back as the calibrated model.
    #[error("the calibrated scene does not read back as the fitted model ({0}); nothing written")]
    Mismatch(String),
}

/// `x` in full precision as a TOML float.
fn float(x: f64) -> Value {
    Value::from(x)
}

/// A float with a trailing comment.
fn commented(x: f64, comment: &str) -> Item {
    let mut v = float(x);
    v.decor_mut().set_suffix(format!("   # {comment}"));
    Item::Value(v)
}

fn table_mut<'a>(
    doc: &'a mut DocumentMut,
    key: &str,
    origin: &str,
) -> Result<&'a mut dyn TableLike, CalibratedSceneError> {
    doc.get_mut(key)
        .and_then(Item::as_table_like_mut)
        .ok_or_else(|| CalibratedSceneError::Edit {
            origin: origin.into(),
            message: format!("no [{key}] table"),
        })
}

fn cable_mut<'a>(
    doc: &'a mut DocumentMut,
    i: usize,
    origin: &str,
) -> Result<&'a mut toml_edit::Table, CalibratedSceneError> {
    doc.get_mut("cables")
        .and_then(Item::as_array_of_tables_mut)
        .and_then(|a| a.get_mut(i))
        .ok_or_else(|| CalibratedSceneError::Edit {
            origin: origin.into(),
            message: format!("no [[cables]] entry {}", i + 1),
        })
}

/// The fitted value's comment: `calibrated: v ± s (nominal n)`.
fn note(report: &Report, name: &str) -> String {
    match report.parameters.iter().find(|p| p.name == name) {
        Some(p) => match p.std_error {
            Some(s) => format!(
                "calibrated {name} = {:.6} ± {:.2e} (nominal {})",
                p.value, s, p.nominal
            ),
            None => format!(
                "{name} undetermined by the data: kept near its nominal {}",
                p.nominal
            ),
        },
        None => String::new(),
    }
}

/// The calibrated scene's text: `source` (the scene's text, `origin` its name) edited to the
/// values of `calibrated`, fitted from `base` with `spec`; `header` lines go on top as
/// comments. Read back and compared with the calibrated model first.
pub fn calibrated_scene_toml(
    source: &str,
    origin: &str,
    base: &Scene,
    spec: &FitSpec,
    calibrated: &Applied,
    report: &Report,
    header: &[String],
) -> Result<String, CalibratedSceneError> {
    let edit = |m: String| CalibratedSceneError::Edit {
        origin: origin.into(),
        message: m,
    };
    let mut doc: DocumentMut = source
        .parse()
        .map_err(|e: toml_edit::TomlError| edit(e.to_string()))?;
    let s = &calibrated.scene;
    let has = |f: fn(&ParamKind) -> bool| spec.params.iter().any(|p| f(&p.kind));
    // The model overrides of the command line, so that the file is the model that was fitted.
    {
        let model = table_mut(&mut doc, "model", origin)?;
        if base.model.element.as_str() != model.get("element").and_then(Item::as_str).unwrap_or("")
        {
            model.insert("element", toml_edit::value(base.model.element.as_str()));
        }
        let n = base.model.elements_per_cable as i64;
        if model.get("elements_per_cable").and_then(Item::as_integer) != Some(n) {
            model.insert("elements_per_cable", toml_edit::value(n));
        }
    }
    if base.model.sag_explicit {
        if doc.get("effects").is_none() {
            doc.insert("effects", Item::Table(toml_edit::Table::new()));
        }
        let e = table_mut(&mut doc, "effects", origin)?;
        if e.get("sag").and_then(Item::as_bool) != Some(base.model.sag) {
            e.insert("sag", toml_edit::value(base.model.sag));
        }
    }
    // T_min as the model used it (a --t-min override replaces every cable's).
    let number =
        |i: Option<&Item>| i.and_then(|v| v.as_float().or(v.as_integer().map(|n| n as f64)));
    let tension = table_mut(&mut doc, "tension", origin)?;
    if number(tension.get("t_min")) != Some(base.t_min_n) {
        tension.insert("t_min", Item::Value(float(base.t_min_n)));
    }
    for i in 0..base.n_cables() {
        let c = cable_mut(&mut doc, i, origin)?;
        match base.cables[i].t_min_n {
            Some(t) if number(c.get("t_min")) != Some(t) => {
                c.insert("t_min", Item::Value(float(t)));
            }
            Some(_) => {}
            None => {
                c.remove("t_min");
            }
        }
    }
    // Per-cable material and hidden cables.
    let ea = has(|k| matches!(k, ParamKind::EaFactor(_) | ParamKind::EaFactorAll));
    let hidden = has(|k| matches!(k, ParamKind::HiddenLength(_)));
    let weight = has(|k| *k == ParamKind::WeightPerLength);
    // The fitted γ itself (the model's μ = γ/|g|; μ·|g| need not give γ back to the bit).
    let w = report
        .parameters
        .iter()
        .find(|p| p.name == "weight_per_length")
        .map_or(0.0, |p| p.value);
    if weight {
        let d = table_mut(&mut doc, "cable", origin)?;
        d.remove("mass_per_length");
        d.insert(
            "weight_per_length",
            commented(w, &format!("N/m, {}", note(report, "weight_per_length"))),
        );
    }
    for (i, c) in s.cables.iter().enumerate() {
        let t = cable_mut(&mut doc, i, origin)?;
        if ea {
            let name = format!("ea_factor.{}", i + 1);
            let text = if spec.params.iter().any(|p| p.name == name) {
                note(report, &name)
            } else {
                note(report, "ea_factor_all")
            };
            t.insert(
                "youngs_modulus",
                commented(
                    c.youngs_modulus_pa,
                    &format!("Pa, EA × {:.6}: {text}", calibrated.ea_factor[i]),
                ),
            );
        }
        if weight && (t.contains_key("weight_per_length") || t.contains_key("mass_per_length")) {
            t.remove("mass_per_length");
            t.insert("weight_per_length", Item::Value(float(w)));
        }
        if hidden {
            let name = format!("hidden_length.{}", i + 1);
            let length = c.hidden.map_or(0.0, |h| h.length_m);
            if spec.params.iter().any(|p| p.name == name) {
                t.insert(
                    "hidden_length",
                    commented(length, &format!("m, {}", note(report, &name))),
                );
            }
        }
        // A hidden cable's own material where it differs from the free cable's (the
        // default), or where the file gives it: then the calibrated value.
        if let Some(h) = c.hidden {
            if ea || hidden || weight {
                let own_e = t.contains_key("hidden_youngs_modulus");
                let own_a = t.contains_key("hidden_area");
                let own_mu = t.contains_key("hidden_weight_per_length")
                    || t.contains_key("hidden_mass_per_length");
                if h.youngs_modulus_pa != c.youngs_modulus_pa || own_e {
                    t.insert(
                        "hidden_youngs_modulus",
                        Item::Value(float(h.youngs_modulus_pa)),
                    );
                }
                if h.area_m2 != c.area_m2 || own_a {
                    t.insert("hidden_area", Item::Value(float(h.area_m2)));
                }
                if h.mass_per_length_kg_m != c.mass_per_length_kg_m || own_mu {
                    t.remove("hidden_weight_per_length");
                    t.insert(
                        "hidden_mass_per_length",
                        Item::Value(float(h.mass_per_length_kg_m)),
                    );
                }
            }
        }
    }
    if has(|k| *k == ParamKind::PulleyRadius) {
        let r = s
            .cables
            .iter()
            .find_map(|c| c.pulley.map(|p| p.radius_m))
            .unwrap_or(0.0);
        let set = |p: &mut Item| {
            if let Some(t) = p.as_table_like_mut() {
                t.insert("radius", Item::Value(float(r)));
            }
        };
        if let Some(p) = doc.get_mut("cable").and_then(|c| c.get_mut("pulley")) {
            set(p);
        }
        for i in 0..s.n_cables() {
            if let Some(p) = cable_mut(&mut doc, i, origin)?.get_mut("pulley") {
                set(p);
            }
        }
    }
    // The end-effector.
    {
        let e = table_mut(&mut doc, "end_effector", origin)?;
        if has(|k| *k == ParamKind::EeMass) {
            e.insert(
                "mass",
                commented(s.ee_mass_kg, &format!("kg, {}", note(report, "ee_mass"))),
            );
        }
        if has(|k| matches!(k, ParamKind::EeInertia(_))) {
            let i = &s.ee_inertia_kg_m2;
            let mut rows = toml_edit::Array::new();
            for r in 0..3 {
                let mut row = toml_edit::Array::new();
                for c in 0..3 {
                    row.push(i[(r, c)]);
                }
                rows.push(row);
            }
            let mut v = Value::Array(rows);
            v.decor_mut()
                .set_suffix("   # kg·m², body frame; diagonal calibrated (ee_inertia)");
            e.insert("inertia", Item::Value(v));
        }
        if calibrated.com_offset_m != Vector3::zeros() {
            let rot = crate::kinematics::rotation_of(&s.ee_orientation_wxyz);
            let p = s.ee_position_m + rot * calibrated.com_offset_m;
            let mut v = Value::Array([p.x, p.y, p.z].into_iter().collect());
            v.decor_mut().set_suffix(
                "   # m: the calibrated centre of mass; poses given to this scene are the centre of mass's",
            );
            e.insert("position", Item::Value(v));
        }
    }
    if calibrated.com_offset_m != Vector3::zeros() {
        for (i, c) in s.cables.iter().enumerate() {
            let a = c.attachment_m;
            cable_mut(&mut doc, i, origin)?.insert(
                "attachment",
                Item::Value(Value::Array([a.x, a.y, a.z].into_iter().collect())),
            );
        }
    }
    if has(ParamKind::is_damping) {
        let mut t = toml_edit::Table::new();
        match s.damping {
            Damping::ModalRatio { zeta } => {
                t.insert("modal_ratio", commented(zeta, &note(report, "modal_ratio")));
            }
            Damping::Rayleigh {
                alpha_per_s,
                beta_s,
            } => {
                t.insert(
                    "rayleigh_alpha",
                    commented(
                        alpha_per_s,
                        &format!("1/s, {}", note(report, "rayleigh.alpha")),
                    ),
                );
                t.insert(
                    "rayleigh_beta",
                    commented(beta_s, &format!("s, {}", note(report, "rayleigh.beta"))),
                );
            }
            _ => {}
        }
        doc.insert("damping", Item::Table(t));
    }
    let mut out = String::new();
    for l in header {
        out.push_str("# ");
        out.push_str(l);
        out.push('\n');
    }
    out.push_str(&doc.to_string());
    check_reads_back(&out, calibrated)?;
    Ok(out)
}

/// The text read by the scene parser equals the calibrated model (the end-effector's
/// position aside when the centre of mass moved: there it is the new reference point).
fn check_reads_back(text: &str, calibrated: &Applied) -> Result<(), CalibratedSceneError> {
    let mut back = Scene::from_toml_str(text, "<calibrated scene>")
        .map_err(|e| CalibratedSceneError::Mismatch(e.to_string()))?;
    let want = &calibrated.scene;
    if calibrated.com_offset_m != Vector3::zeros() {
        back.ee_position_m = want.ee_position_m;
    }
    back.model.sag_explicit = want.model.sag_explicit;
    if back != *want {
        let what = if back.cables != want.cables {
            let i = (0..want.n_cables())
                .find(|&i| back.cables.get(i) != Some(&want.cables[i]))
                .unwrap_or(0);
            format!(
                "cable {}: {:?} read back, {:?} fitted",
                i + 1,
                back.cables.get(i),
                want.cables[i]
            )
        } else {
            format!("read back {back:?}")
        };
        return Err(CalibratedSceneError::Mismatch(what));
    }
    Ok(())
}
