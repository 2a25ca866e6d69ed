//! The link and cables as read into a scene file's text: frames moved to the centre of
//! mass (see the module docs of [`super`]), bounds and materials per cable, and comments
//! that say where every value came from.

use super::bodies::Link;
use super::cables::{AttachmentReference, CasprCable};
use super::{CasprError, ImportOption, ImportOptions, MissingOption};
use crate::input_file::message_number;
use crate::scene::MAX_ELEMENTS_PER_CABLE;
use nalgebra::Vector3;
use std::fmt::Write as _;

/// CASPR's gravity, m/s² (along −z of the inertial frame).
const CASPR_GRAVITY_M_S2: f64 = 9.81;
/// Fewest cables the scene accepts for a rigid (6-DOF) platform.
const MIN_RIGID_CABLES: usize = 6;

/// Where the values came from, for the comments.
pub(super) struct Sources<'a> {
    /// Bodies file name.
    pub bodies: &'a str,
    /// Cables file name.
    pub cables: &'a str,
    /// The cable set used.
    pub cable_set: &'a str,
}

/// Checks the options' ranges (the scene checks them again, naming scene keys).
pub(super) fn check_options(o: &ImportOptions) -> Result<(), CasprError> {
    let positive = |x: f64, what: &str| {
        if x.is_finite() && x > 0.0 {
            Ok(())
        } else {
            Err(CasprError::Options(format!(
                "{what} must be finite and > 0, got {}",
                message_number(x)
            )))
        }
    };
    if let Some(g) = o.weight_per_length_n_m {
        positive(g, "weight per length (N/m)")?;
    }
    if let Some(a) = o.area_m2 {
        positive(a, "area (m²)")?;
    }
    if let Some(e) = o.youngs_modulus_pa {
        positive(e, "Young's modulus (Pa)")?;
    }
    if let Some(t) = o.t_min_n {
        positive(t, "T_min (N)")?;
    }
    if let Some(p) = o.position_m {
        if !p.iter().all(|x| x.is_finite()) {
            return Err(CasprError::Options(format!(
                "position must be finite, got ({}, {}, {})",
                message_number(p.x),
                message_number(p.y),
                message_number(p.z)
            )));
        }
    }
    if !(1..=MAX_ELEMENTS_PER_CABLE).contains(&o.elements_per_cable) {
        return Err(CasprError::Options(format!(
            "elements per cable must be in 1..={MAX_ELEMENTS_PER_CABLE}, got {}",
            o.elements_per_cable
        )));
    }
    Ok(())
}

/// The materials the scene needs from the options, once every one is known to be given.
struct Material {
    /// Weight per length γ, N/m.
    weight_per_length_n_m: f64,
    /// Cross-section A, m².
    area_m2: f64,
}

/// Every option the cable set needs and the caller did not give, reported at once
/// (naming the cables file): weight per length and area always, Young's modulus when a
/// cable is a `cable_ideal`, T_min when a force_min is ≤ 0.
fn material(
    o: &ImportOptions,
    cables: &[CasprCable],
    src: &Sources,
) -> Result<Material, CasprError> {
    let names = |f: &dyn Fn(&CasprCable) -> bool| {
        let hit: Vec<&str> = cables
            .iter()
            .filter(|c| f(c))
            .map(|c| c.name.as_str())
            .collect();
        match hit.as_slice() {
            [] => None,
            [one] => Some(format!("cable `{}`", safe(one))),
            [first, .., last] => Some(format!(
                "{} cables, `{}` … `{}`",
                hit.len(),
                safe(first),
                safe(last)
            )),
        }
    };
    let mut missing = Vec::new();
    let mut need = |option: ImportOption, why: String| missing.push(MissingOption { option, why });
    if o.weight_per_length_n_m.is_none() {
        need(
            ImportOption::WeightPerLength,
            "(N/m: CASPR's cables have no weight)".into(),
        );
    }
    if o.area_m2.is_none() {
        need(ImportOption::Area, "(m²)".into());
    }
    if o.youngs_modulus_pa.is_none() {
        if let Some(who) = names(&|c| c.k_n.is_none()) {
            need(
                ImportOption::YoungsModulus,
                format!("(Pa) for the cable_ideal cables, rigid in CASPR ({who})"),
            );
        }
    }
    if o.t_min_n.is_none() {
        if let Some(who) = names(&|c| !(c.force_min_n > 0.0)) {
            need(
                ImportOption::TMin,
                format!(
                    "(N) for the cables with force_min ≤ 0, slack ones without stiffness ({who})"
                ),
            );
        }
    }
    match (o.weight_per_length_n_m, o.area_m2) {
        (Some(g), Some(a)) if missing.is_empty() => Ok(Material {
            weight_per_length_n_m: g,
            area_m2: a,
        }),
        _ => Err(CasprError::MissingOptions {
            file: src.cables.to_string(),
            cable_set: safe(src.cable_set),
            missing,
        }),
    }
}

/// One cable in scene terms.
struct SceneCable {
    /// Anchor, inertial frame, m: CASPR's, or shifted by the attachment offset when the
    /// joint locks the rotation (`anchor_shifted`).
    anchor_m: Vector3<f64>,
    /// True when `anchor_m` is CASPR's anchor minus the rotated attachment offset (T_XYZ).
    anchor_shifted: bool,
    /// Attachment from the centre of mass, body frame, m.
    attachment_m: Vector3<f64>,
    /// Lower bound, N.
    t_min_n: f64,
    /// Upper bound, N.
    t_max_n: f64,
    /// Young's modulus from K/A (linear springs), Pa.
    spring_e_pa: Option<f64>,
}

/// The scene values of each cable, or the first reason one cannot be imported.
///
/// A joint that locks the rotation (T_XYZ) makes the platform a 3-DOF body whose
/// attachment offsets b_i = R (r_A − r_G) never turn: the cable runs from a_i to p + b_i,
/// i.e. from a_i − b_i to p. So the scene is a point mass at p with each anchor shifted to
/// a_i − b_i: the same cable vectors, lengths and directions at every position, the force
/// rows of the equilibrium only (the joint takes the moment).
fn scene_cables(
    cables: &[CasprCable],
    link: &Link,
    o: &ImportOptions,
    m: &Material,
    src: &Sources,
) -> Result<Vec<SceneCable>, CasprError> {
    let model = |message: String| CasprError::Model {
        file: src.cables.to_string(),
        message,
    };
    let mut out = Vec::with_capacity(cables.len());
    for c in cables {
        let attachment_m = match c.reference {
            AttachmentReference::Joint => c.platform_m - link.com_m,
            AttachmentReference::Com => c.platform_m,
        };
        // `material` has refused a force_min ≤ 0 without a T_min option.
        let t_min_n = o.t_min_n.unwrap_or(c.force_min_n);
        if !(c.force_max_n >= t_min_n) {
            return Err(model(format!(
                "cable `{}`: force_max = {} N is below T_min = {} N",
                safe(&c.name),
                message_number(c.force_max_n),
                message_number(t_min_n)
            )));
        }
        let shift = link.rotation_locked && attachment_m != Vector3::zeros();
        let (anchor_m, attachment_m) = if shift {
            (c.base_m - link.rotation * attachment_m, Vector3::zeros())
        } else {
            (c.base_m, attachment_m)
        };
        out.push(SceneCable {
            anchor_m,
            anchor_shifted: shift,
            attachment_m,
            t_min_n,
            t_max_n: c.force_max_n,
            spring_e_pa: c.k_n.map(|k| k / m.area_m2),
        });
    }
    Ok(out)
}

/// The scene file's text.
pub(super) fn scene_toml(
    link: &Link,
    cables: &[CasprCable],
    o: &ImportOptions,
    src: &Sources,
) -> Result<String, CasprError> {
    let m = material(o, cables, src)?;
    let sc = scene_cables(cables, link, o, &m, src)?;
    let model = |message: String| CasprError::Model {
        file: src.cables.to_string(),
        message,
    };
    if sc.is_empty() {
        return Err(model(format!(
            "cable set `{}` has no cables",
            src.cable_set
        )));
    }
    let rigid = sc.iter().any(|c| c.attachment_m != Vector3::zeros());
    if rigid && link.planar_xy {
        return Err(model(
            "a PLANAR_XY platform with attachment points off its centre of mass: the scene has no planar rigid body; put them at the centre (a point mass)".into(),
        ));
    }
    if rigid && sc.len() < MIN_RIGID_CABLES {
        return Err(model(format!(
            "attachment points off the centre of mass make the platform a rigid body (6 DOF), which needs at least {MIN_RIGID_CABLES} cables; set `{}` has {}",
            src.cable_set,
            sc.len()
        )));
    }
    let mut t = String::new();
    header(&mut t, link, src);
    if cables.iter().any(|c| c.pulley.is_some()) {
        let _ = writeln!(t, "# {}", super::PULLEY_NOT_MODELLED);
    }
    end_effector(&mut t, link, o, rigid);
    materials_and_model(&mut t, o, &m, &sc, rigid, link.rotation_locked);
    for (c, s) in cables.iter().zip(&sc) {
        cable(&mut t, c, s, o);
    }
    Ok(t)
}

/// Comment header, name and gravity.
fn header(t: &mut String, link: &Link, src: &Sources) {
    let name = if link.name.is_empty() {
        "caspr-import"
    } else {
        &link.name
    };
    let _ = writeln!(
        t,
        "# Imported by `cablevib import caspr` from CASPR's model files:"
    );
    let _ = writeln!(
        t,
        "#   bodies: {} (link \"{}\", joint {})",
        safe(src.bodies),
        safe(&link.name),
        safe(&link.joint)
    );
    let _ = writeln!(
        t,
        "#   cables: {} (cable set \"{}\")",
        safe(src.cables),
        safe(src.cable_set)
    );
    let _ = writeln!(
        t,
        "# Positions are in CASPR's inertial frame (m). The end-effector reference point is"
    );
    let _ = writeln!(
        t,
        "# the platform's centre of mass; attachments are measured from it in the body frame."
    );
    let _ = writeln!(t, "name = {}", toml_string(name));
    let _ = writeln!(
        t,
        "gravity = [0.0, 0.0, {:?}]   # m/s², CASPR's",
        -CASPR_GRAVITY_M_S2
    );
}

/// `[end_effector]`: mass, position, orientation, inertia and weight.
fn end_effector(t: &mut String, link: &Link, o: &ImportOptions, rigid: bool) {
    let origin = o.position_m.unwrap_or(link.origin_m);
    let r = link.rotation;
    let g = origin + r * link.com_m;
    let pose = if o.position_m.is_some() {
        "the position given at import"
    } else {
        "q_initial"
    };
    let _ = writeln!(t, "\n[end_effector]");
    let _ = writeln!(t, "mass = {:?}   # kg, CASPR <mass>", link.mass_kg);
    let _ = writeln!(
        t,
        "# centre of mass at the initial pose: link-frame origin ({pose}) + R·com_location"
    );
    let _ = writeln!(t, "position = {}   # m", vec3(&g));
    let q = r.quaternion();
    let _ = writeln!(
        t,
        "orientation = [{:?}, {:?}, {:?}, {:?}]   # [w, x, y, z], from q_initial",
        q.w, q.i, q.j, q.k
    );
    if rigid {
        let i = &link.inertia_com_kg_m2;
        let row = |k: usize| format!("[{:?}, {:?}, {:?}]", i[(k, 0)], i[(k, 1)], i[(k, 2)]);
        let _ = writeln!(
            t,
            "# kg·m², about the centre of mass, body frame (CASPR <inertia>)"
        );
        let _ = writeln!(t, "inertia = [{}, {}, {}]", row(0), row(1), row(2));
    }
    if link.planar_xy {
        let _ = writeln!(
            t,
            "weight_carried = false   # PLANAR_XY: the x-y plane carries the weight"
        );
    }
}

/// `[cable]`, `[tension]`, `[model]` and `[effects]`.
fn materials_and_model(
    t: &mut String,
    o: &ImportOptions,
    m: &Material,
    sc: &[SceneCable],
    rigid: bool,
    rotation_locked: bool,
) {
    let _ = writeln!(t, "\n[cable]");
    let _ = writeln!(
        t,
        "# Given at import, not from CASPR (its cables have no material):"
    );
    if let Some(e) = o.youngs_modulus_pa {
        let _ = writeln!(t, "youngs_modulus = {e:?}   # Pa");
    }
    let _ = writeln!(t, "area = {:?}   # m²", m.area_m2);
    let _ = writeln!(
        t,
        "weight_per_length = {:?}   # N/m",
        m.weight_per_length_n_m
    );
    let lo = sc.iter().map(|c| c.t_min_n).fold(f64::INFINITY, f64::min);
    let hi = sc
        .iter()
        .map(|c| c.t_max_n)
        .fold(f64::NEG_INFINITY, f64::max);
    let _ = writeln!(t, "\n[tension]");
    let _ = writeln!(
        t,
        "# The loosest of the cables' bounds; each cable's own are in [[cables]]."
    );
    let _ = writeln!(t, "t_min = {lo:?}   # N");
    let _ = writeln!(t, "t_max = {hi:?}   # N");
    let _ = writeln!(t, "\n[model]");
    let _ = writeln!(t, "# Given at import, not from CASPR:");
    let _ = writeln!(t, "element = \"{}\"", o.element.as_str());
    let _ = writeln!(t, "elements_per_cable = {}", o.elements_per_cable);
    let _ = writeln!(t, "\n[effects]");
    let why = if rigid {
        "attachment points off the centre of mass: rigid platform, 6 DOF"
    } else if rotation_locked && sc.iter().any(|c| c.anchor_shifted) {
        "T_XYZ locks the rotation: 3 DOF, force rows only; each anchor is shifted by its attachment offset so the cable runs as in CASPR"
    } else {
        "every attachment at the centre of mass: point mass, 3 DOF"
    };
    let _ = writeln!(t, "rotation = {rigid}   # {why}");
}

/// One `[[cables]]` table.
fn cable(t: &mut String, c: &CasprCable, s: &SceneCable, o: &ImportOptions) {
    let kind = if c.k_n.is_some() {
        "cable_linear_spring"
    } else {
        "cable_ideal"
    };
    let _ = writeln!(t, "\n[[cables]]   # \"{}\" ({kind})", safe(&c.name));
    let base = match &c.pulley {
        None => "link 0 location",
        Some(p) if p.screw.is_some() => "screw pulley's constant_winch_point",
        Some(_) => "pulley's fixed_location",
    };
    if s.anchor_shifted {
        let _ = writeln!(
            t,
            "anchor = {}   # m, CASPR {base} {} minus the attachment offset (T_XYZ)",
            vec3(&s.anchor_m),
            vec3(&c.base_m)
        );
    } else if c.pulley.is_some() {
        let _ = writeln!(t, "anchor = {}   # m, CASPR {base}", vec3(&s.anchor_m));
    } else {
        let _ = writeln!(
            t,
            "anchor = {}   # m, CASPR link 0 location",
            vec3(&s.anchor_m)
        );
    }
    let _ = writeln!(
        t,
        "attachment = {}   # m, from the centre of mass",
        vec3(&s.attachment_m)
    );
    let from = if o.t_min_n.is_some() {
        "given at import"
    } else {
        "CASPR force_min"
    };
    let _ = writeln!(t, "t_min = {:?}   # N, {from}", s.t_min_n);
    let _ = writeln!(t, "t_max = {:?}   # N, CASPR force_max", s.t_max_n);
    if let Some(p) = &c.pulley {
        let _ = writeln!(
            t,
            "pulley = {{ radius = {:?}, entry_direction = {} }}   # m; CASPR {}",
            p.radius_m,
            vec3(&p.entry),
            if p.screw.is_some() {
                "screw_base_rotating_pulley (outlet motion along the drum not modelled)"
            } else {
                "base_rotating_pulley"
            }
        );
    }
    if let (Some(e), Some(k)) = (s.spring_e_pa, c.k_n) {
        let _ = writeln!(
            t,
            "youngs_modulus = {e:?}   # Pa = CASPR K ({k:?} N) / area"
        );
    }
}

/// `[x, y, z]` with every digit needed to read the same numbers back.
fn vec3(v: &Vector3<f64>) -> String {
    format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z)
}

/// `s` as a TOML basic string.
fn toml_string(s: &str) -> String {
    let mut out = String::from("\"");
    for ch in s.chars() {
        match ch {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// `s` for a comment: control characters (a newline would end the comment) as `?`.
fn safe(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_control() { '?' } else { c })
        .collect()
}
