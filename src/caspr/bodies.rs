//! CASPR's bodies file: the one moving link (`<link_rigid>`), its joint and initial pose,
//! mass, centre of mass and inertia.
//!
//! The root is `<bodies_system>` holding `<links>`, or `<links>` itself (both occur in
//! CASPR's models); `<operational_spaces>` and the display attributes are not read. The
//! link frame's origin sits at `parent.location + R_parent · q_translation` in the inertial
//! frame; the parent must be the base (`<num>0</num>`), so that is `location + t`.
//! `com_location` r_G is in the link frame, from its origin. An inertia given about the
//! joint (`ref="joint"`) is moved to the centre of mass by the parallel-axis theorem,
//! I_G = I_O − m (|r_G|² I − r_G r_Gᵀ), as CASPR itself does.

use super::xml::At;
use super::CasprError;
use crate::input_file::message_number;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// The platform joint types imported: CASPR's joints that let one link move freely in
/// translation (with or without rotation).
const SUPPORTED_JOINTS: &str = "SPATIAL_EULER_XYZ, T_XYZ, PLANAR_XY";

/// CASPR's other joint types (its `JointType` enumeration): each constrains the link's
/// translation, so the link is not a cable-driven platform this import handles.
const OTHER_CASPR_JOINTS: [&str; 15] = [
    "R_X",
    "R_Y",
    "R_Z",
    "R_AXIS",
    "U_XY",
    "U_YZ",
    "U_XZ",
    "P_X",
    "P_XY",
    "P_XZ",
    "P_AXIS",
    "PLANAR_YZ",
    "PLANAR_XZ",
    "S_EULER_XYZ",
    "S_FIXED_XYZ",
];

/// The one moving link of a CASPR model.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// The link's `name` attribute.
    pub name: String,
    /// The joint type as written, e.g. `SPATIAL_EULER_XYZ`.
    pub joint: String,
    /// True for `PLANAR_XY`: the x-y plane carries the weight (CASPR's gravity is −z).
    pub planar_xy: bool,
    /// True for `T_XYZ`: the joint locks the rotation (the link only translates).
    pub rotation_locked: bool,
    /// Link-frame origin at the initial pose (`q_initial`), inertial frame, m.
    pub origin_m: Vector3<f64>,
    /// Orientation of the link frame at the initial pose.
    pub rotation: UnitQuaternion<f64>,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Centre of mass r_G in the link frame, from its origin, m.
    pub com_m: Vector3<f64>,
    /// Inertia about the centre of mass in link-frame axes, kg·m².
    pub inertia_com_kg_m2: Matrix3<f64>,
}

/// Reads the bodies file's one moving link.
pub(super) fn read_link(doc: &roxmltree::Document, file: &str) -> Result<Link, CasprError> {
    let root = At {
        file,
        node: doc.root_element(),
    };
    let links = match root.node.tag_name().name() {
        "links" => root,
        "bodies_system" => root.child("links")?,
        other => {
            return Err(root.err(format!(
                "expected <bodies_system> or <links> as the root element, got <{other}>"
            )))
        }
    };
    let all: Vec<_> = links.elements().collect();
    if let Some(n) = all.iter().find(|n| !n.has_tag_name("link_rigid")) {
        return Err(links.at(*n).err("only <link_rigid> links are supported"));
    }
    match all.as_slice() {
        [] => Err(links.err("no <link_rigid>: the model has no moving link")),
        [one] => link(links.at(*one)),
        many => Err(CasprError::Model {
            file: file.to_string(),
            message: format!(
                "{} moving links; only a single rigid platform (one <link_rigid>) can be imported",
                many.len()
            ),
        }),
    }
}

/// One `<link_rigid>`.
fn link(l: At) -> Result<Link, CasprError> {
    let name = l.node.attribute("name").unwrap_or("").trim().to_string();
    let parent = l.child("parent")?;
    let parent_num = parent.number("num")?;
    if parent_num != 0.0 {
        return Err(parent.err(format!(
            "parent link {}: a single platform must hang from the base (0)",
            message_number(parent_num)
        )));
    }
    let parent_location = parent.vec3("location")?;
    let j = l.child("joint")?;
    let (joint, t, rotation) = joint(j)?;
    let planar_xy = joint == "PLANAR_XY";
    let rotation_locked = joint == "T_XYZ";
    let phys = l.child("physical")?;
    let mass_kg = phys.number("mass")?;
    if !(mass_kg > 0.0) {
        return Err(phys
            .child("mass")?
            .err(format!("must be > 0 kg, got {}", message_number(mass_kg))));
    }
    let com_m = phys.vec3("com_location")?;
    let inertia_com_kg_m2 = inertia(phys.child("inertia")?, mass_kg, &com_m)?;
    Ok(Link {
        name,
        joint,
        planar_xy,
        rotation_locked,
        origin_m: parent_location + t,
        rotation,
        mass_kg,
        com_m,
        inertia_com_kg_m2,
    })
}

/// A joint's type, its initial translation (m) and rotation.
type JointPose = (String, Vector3<f64>, UnitQuaternion<f64>);

/// `<joint type=".." q_initial="..">`: the type, the initial translation and rotation. Only
/// CASPR's own type names are read (its `JointType`); a missing `q_initial` is CASPR's
/// default (zero translation, identity rotation).
fn joint(j: At) -> Result<JointPose, CasprError> {
    let ty = j.attr("type")?.trim().to_string();
    let n = match ty.as_str() {
        "SPATIAL_EULER_XYZ" => 6,
        "T_XYZ" | "PLANAR_XY" => 3,
        other if OTHER_CASPR_JOINTS.contains(&other) => {
            return Err(j.err(format!(
                "CASPR joint `{ty}` constrains the link's translation: not a cable-driven platform ({SUPPORTED_JOINTS} are imported)"
            )))
        }
        _ => {
            let hint = match ty.as_str() {
                "TRANSLATIONAL_XYZ" => " (CASPR's translational joint is T_XYZ)",
                "SPATIAL_QUATERNION" | "SPATIAL" => {
                    " (CASPR's JointType has no quaternion joint; use SPATIAL_EULER_XYZ)"
                }
                _ => "",
            };
            return Err(j.err(format!(
                "joint type `{}` is not one of CASPR's{hint}; {SUPPORTED_JOINTS} are imported",
                short_name(&ty)
            )));
        }
    };
    let q = match j.node.attribute("q_initial") {
        Some(s) => j.numbers(s, n)?,
        None => vec![0.0; n],
    };
    let (t, r) = match ty.as_str() {
        // R = Rx(α) Ry(β) Rz(γ), CASPR's SphericalEulerXYZ.
        "SPATIAL_EULER_XYZ" => (
            Vector3::new(q[0], q[1], q[2]),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), q[3])
                * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), q[4])
                * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), q[5]),
        ),
        // T_XYZ: q = [x, y, z], no rotation (CASPR's TranslationalXYZ).
        "T_XYZ" => (Vector3::new(q[0], q[1], q[2]), UnitQuaternion::identity()),
        // PLANAR_XY: q = [x, y, θ], θ about z.
        _ => (
            Vector3::new(q[0], q[1], 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), q[2]),
        ),
    };
    Ok((ty, t, r))
}

/// At most 40 characters of a name from the file, for messages.
fn short_name(s: &str) -> String {
    if s.chars().count() > 40 {
        format!("{}…", s.chars().take(40).collect::<String>())
    } else {
        s.to_string()
    }
}

/// `<inertia ref="com|joint">` with `Ixx` … `Iyz`: the tensor about the centre of mass.
fn inertia(i: At, m: f64, r_g: &Vector3<f64>) -> Result<Matrix3<f64>, CasprError> {
    let reference = i.attr("ref")?.trim();
    let v = |tag: &str| i.number(tag);
    let (xx, yy, zz) = (v("Ixx")?, v("Iyy")?, v("Izz")?);
    let (xy, xz, yz) = (v("Ixy")?, v("Ixz")?, v("Iyz")?);
    let written = Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz);
    match reference {
        "com" => Ok(written),
        "joint" => {
            Ok(written - m * (Matrix3::identity() * r_g.norm_squared() - r_g * r_g.transpose()))
        }
        other => Err(i.err(format!("ref=\"{other}\": expected \"com\" or \"joint\""))),
    }
}
