//! CASPR's cables file: `<cables default_cable_set="..">` holding `<cable_set id="..">`s of
//! cables. Read: `cable_ideal` and `cable_linear_spring` (its `<K>`, N, is the cable's
//! axial rigidity: CASPR's stiffness is K/length), each with `name`,
//! `attachment_reference` (`joint` or `com`), `<force_min>`, `<force_max>` (N) and exactly
//! two `<attachment>`s, one on the base (`<link>0</link>`, location in the inertial frame,
//! m) and one on the platform (`<link>1</link>`, location in the link frame, m, from the
//! link-frame origin for `joint` or from the centre of mass for `com`). The base attachment
//! may instead be a swivel pulley: `<base_rotating_pulley>` (`<fixed_location>`, the entry
//! point on the swivel axis, m; `<pulley_radius>`, m; `<cable_entry_vector>`) or
//! `<screw_base_rotating_pulley>` (`<constant_winch_point>`, `<cable_pulley_entry_vector>`,
//! `<pulley_radius>`, and the drum's `<winch_vector>`, `<winch_radius>`,
//! `<winch_groove_width>`, read and checked: the screw drive's outlet motion along the drum
//! is not modelled, the pulley stays at the constant winch point). Other cable types
//! (passive springs, variable-stiffness drives) and multi-segment cables are refused.

use super::xml::At;
use super::CasprError;
use crate::input_file::message_number;
use nalgebra::Vector3;

/// Where a platform attachment location is measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AttachmentReference {
    /// From the link-frame origin (`attachment_reference="joint"`).
    Joint,
    /// From the centre of mass (`attachment_reference="com"`).
    Com,
}

/// One cable as CASPR gives it.
#[derive(Debug, Clone, PartialEq)]
pub struct CasprCable {
    /// The `name` attribute.
    pub name: String,
    /// Anchor on the base, inertial frame, m.
    pub base_m: Vector3<f64>,
    /// Attachment on the platform, link frame, m, measured from `reference`.
    pub platform_m: Vector3<f64>,
    /// What `platform_m` is measured from.
    pub reference: AttachmentReference,
    /// `<force_min>`, N.
    pub force_min_n: f64,
    /// `<force_max>`, N.
    pub force_max_n: f64,
    /// `<K>` of a `cable_linear_spring`, N (axial rigidity EA); None for `cable_ideal`.
    pub k_n: Option<f64>,
    /// The swivel pulley at the base (`base_m` is then its entry point on the axis).
    pub pulley: Option<CasprPulley>,
}

/// A swivel pulley at a cable's base attachment, as CASPR gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CasprPulley {
    /// `<pulley_radius>`, m (≥ 0).
    pub radius_m: f64,
    /// `<cable_entry_vector>` (or `<cable_pulley_entry_vector>`), non-zero, as written.
    pub entry: Vector3<f64>,
    /// A `screw_base_rotating_pulley`: its drum's (winch vector, radius m, groove width m),
    /// read but not modelled (the pulley stays at the constant winch point).
    pub screw: Option<(Vector3<f64>, f64, f64)>,
}

/// The cable types read.
const SUPPORTED_CABLES: &str = "cable_ideal, cable_linear_spring";

/// The set's id and its cables: `wanted`, else the file's `default_cable_set`.
pub(super) fn read_set(
    doc: &roxmltree::Document,
    file: &str,
    wanted: Option<&str>,
) -> Result<(String, Vec<CasprCable>), CasprError> {
    let root = At {
        file,
        node: doc.root_element(),
    };
    if !root.node.has_tag_name("cables") {
        return Err(root.err("expected <cables> as the root element"));
    }
    let sets: Vec<_> = root
        .elements()
        .filter(|n| n.has_tag_name("cable_set"))
        .collect();
    // CASPR selects a set by its id: every set needs one, and no two may share it.
    let mut ids: Vec<&str> = Vec::with_capacity(sets.len());
    for n in &sets {
        let at = root.at(*n);
        let id = at.attr("id")?.trim();
        if id.is_empty() {
            return Err(at.err("empty `id`: CASPR selects cable sets by id"));
        }
        if let Some(j) = ids.iter().position(|i| *i == id) {
            return Err(at.err(format!(
                "cable set id `{}` is also the id of the set on line {}: ids must be unique",
                short(id),
                line_of(&sets[j])
            )));
        }
        ids.push(id);
    }
    let listed = || {
        if ids.is_empty() {
            "none".to_string()
        } else {
            ids.iter().map(|i| short(i)).collect::<Vec<_>>().join(", ")
        }
    };
    let id = match (wanted, root.node.attribute("default_cable_set")) {
        (Some(w), _) => w,
        (None, Some(d)) => d.trim(),
        (None, None) if sets.len() == 1 => ids[0],
        (None, None) => {
            return Err(CasprError::NoCableSet {
                file: file.to_string(),
                line: root.line(),
                element: root.node.tag_name().name().to_string(),
                sets: sets.len(),
                listed: listed(),
            })
        }
    };
    let Some(k) = ids.iter().position(|i| *i == id) else {
        return Err(CasprError::Model {
            file: file.to_string(),
            message: format!("no cable set `{}`; the file has: {}", short(id), listed()),
        });
    };
    let set = root.at(sets[k]);
    let cables = set
        .elements()
        .map(|n| cable(set.at(n)))
        .collect::<Result<Vec<_>, _>>()?;
    Ok((id.to_string(), cables))
}

/// Line (1-based) of an element, for messages.
fn line_of(n: &roxmltree::Node) -> u32 {
    n.document().text_pos_at(n.range().start).row
}

/// At most 40 characters of a name from the file, control characters as `?`.
fn short(s: &str) -> String {
    let clean: String = s
        .chars()
        .map(|c| if c.is_control() { '?' } else { c })
        .collect();
    if clean.chars().count() > 40 {
        format!("{}…", clean.chars().take(40).collect::<String>())
    } else {
        clean
    }
}

/// One `<cable_ideal>` or `<cable_linear_spring>`.
fn cable(c: At) -> Result<CasprCable, CasprError> {
    let ty = c.node.tag_name().name();
    if ty != "cable_ideal" && ty != "cable_linear_spring" {
        return Err(c.err(format!(
            "cable type <{ty}> is not supported ({SUPPORTED_CABLES})"
        )));
    }
    let name = c.attr("name")?.trim().to_string();
    let reference = match c.attr("attachment_reference")?.trim() {
        "joint" => AttachmentReference::Joint,
        "com" => AttachmentReference::Com,
        other => {
            return Err(c.err(format!(
                "cable `{name}`: attachment_reference=\"{other}\": expected \"joint\" or \"com\""
            )))
        }
    };
    let p = c.child("properties")?;
    let force_min_n = p.number("force_min")?;
    let force_max_n = p.number("force_max")?;
    let k_n = if ty == "cable_linear_spring" {
        let k = p.number("K")?;
        if !(k > 0.0) {
            return Err(p.child("K")?.err(format!(
                "cable `{name}`: K must be > 0 N, got {}",
                message_number(k)
            )));
        }
        Some(k)
    } else {
        None
    };
    let (base_m, platform_m, pulley) = attachments(c.child("attachments")?, &name)?;
    Ok(CasprCable {
        name,
        base_m,
        platform_m,
        reference,
        force_min_n,
        force_max_n,
        k_n,
        pulley,
    })
}

/// The pulley elements read in place of the base attachment.
const PULLEYS: [&str; 2] = ["base_rotating_pulley", "screw_base_rotating_pulley"];

/// A pulley element: its entry point on the swivel axis (m) and the pulley.
fn pulley(at: At, name: &str) -> Result<(Vector3<f64>, CasprPulley), CasprError> {
    let screw = at.node.has_tag_name("screw_base_rotating_pulley");
    let (point_tag, entry_tag) = if screw {
        ("constant_winch_point", "cable_pulley_entry_vector")
    } else {
        ("fixed_location", "cable_entry_vector")
    };
    let point = at.vec3(point_tag)?;
    let radius_m = at.number("pulley_radius")?;
    if !(radius_m >= 0.0) {
        return Err(at.child("pulley_radius")?.err(format!(
            "cable `{name}`: pulley_radius must be >= 0 m, got {}",
            message_number(radius_m)
        )));
    }
    let entry = at.vec3(entry_tag)?;
    if entry == Vector3::zeros() {
        return Err(at
            .child(entry_tag)?
            .err(format!("cable `{name}`: the entry vector must not be zero")));
    }
    let screw = if screw {
        let v = at.vec3("winch_vector")?;
        let r = at.number("winch_radius")?;
        let h = at.number("winch_groove_width")?;
        if !(r > 0.0 && h >= 0.0) {
            return Err(at.err(format!(
                "cable `{name}`: winch_radius must be > 0 m and winch_groove_width >= 0 m, got {} and {}",
                message_number(r),
                message_number(h)
            )));
        }
        Some((v, r, h))
    } else {
        None
    };
    Ok((
        point,
        CasprPulley {
            radius_m,
            entry,
            screw,
        },
    ))
}

/// The base and platform points and the pulley of one cable's `<attachments>`.
type Attachments = (Vector3<f64>, Vector3<f64>, Option<CasprPulley>);

/// `<attachments>`: one location on link 0 (or a pulley, [`PULLEYS`], in its place) and one
/// on link 1, in either order. Any other element is refused by name.
fn attachments(a: At, name: &str) -> Result<Attachments, CasprError> {
    if let Some(other) = a
        .elements()
        .find(|n| !n.has_tag_name("attachment") && !PULLEYS.contains(&n.tag_name().name()))
    {
        let tag = other.tag_name().name();
        let message = if tag.contains("pulley") {
            format!(
                "cable `{name}`: this pulley type is not supported (only {})",
                PULLEYS.join(", ")
            )
        } else {
            format!("cable `{name}`: unexpected element in <attachments>; expected <attachment>")
        };
        return Err(a.at(other).err(message));
    }
    let all: Vec<_> = a.elements().collect();
    if all.len() != 2 {
        return Err(a.err(format!(
            "cable `{name}`: {} attachments; only straight cables from the base (link 0) to the platform (link 1) are supported",
            all.len()
        )));
    }
    let mut base = None;
    let mut platform = None;
    let mut pulley_of = None;
    for n in all {
        let at = a.at(n);
        if !n.has_tag_name("attachment") {
            let (point, p) = pulley(at, name)?;
            if base.replace(point).is_some() {
                return Err(at.err(format!(
                    "cable `{name}`: two base attachments; one must be on link 0 and one on 1"
                )));
            }
            pulley_of = Some(p);
            continue;
        }
        let link = at.number("link")?;
        let loc = at.vec3("location")?;
        let slot = if link == 0.0 {
            &mut base
        } else if link == 1.0 {
            &mut platform
        } else {
            return Err(at.err(format!(
                "cable `{name}`: link {}: expected 0 (base) or 1 (platform)",
                message_number(link)
            )));
        };
        if slot.replace(loc).is_some() {
            return Err(at.err(format!(
                "cable `{name}`: both attachments are on link {}; one must be on 0 and one on 1",
                message_number(link)
            )));
        }
    }
    match (base, platform) {
        (Some(b), Some(p)) => Ok((b, p, pulley_of)),
        _ => Err(a.err(format!(
            "cable `{name}`: needs one attachment on link 0 and one on link 1"
        ))),
    }
}
