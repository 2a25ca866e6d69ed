//! Frames: a platform whose centre of mass is off the link-frame origin, at a rotated pose,
//! keeps every attachment point where CASPR puts it, and an inertia given about the joint
//! comes back about the centre of mass.

use super::ipanema_opts;
use cablevib::caspr::{import_str, ImportOptions};
use nalgebra::{Matrix3, Vector3};

/// Rx(α) Ry(β) Rz(γ), written out.
fn euler_xyz(a: f64, b: f64, g: f64) -> Matrix3<f64> {
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, a.cos(), -a.sin(), 0.0, a.sin(), a.cos());
    let ry = Matrix3::new(b.cos(), 0.0, b.sin(), 0.0, 1.0, 0.0, -b.sin(), 0.0, b.cos());
    let rz = Matrix3::new(g.cos(), -g.sin(), 0.0, g.sin(), g.cos(), 0.0, 0.0, 0.0, 1.0);
    rx * ry * rz
}

/// A bodies file: one link with `com`, `q_initial`, an inertia given about `inertia_ref`
/// and a parent offset.
fn bodies(com: &str, q: &str, inertia_ref: &str, i: [f64; 6]) -> String {
    format!(
        r#"<?xml version="1.0"?>
<links>
  <link_rigid num="1" name="offset">
    <joint type="SPATIAL_EULER_XYZ" q_initial="{q}"/>
    <physical>
      <mass>12.0</mass>
      <com_location>{com}</com_location>
      <end_location>0 0 0</end_location>
      <inertia ref="{inertia_ref}">
        <Ixx>{}</Ixx><Iyy>{}</Iyy><Izz>{}</Izz><Ixy>{}</Ixy><Ixz>{}</Ixz><Iyz>{}</Iyz>
      </inertia>
    </physical>
    <parent><num>0</num><location>0.5 0.0 0.25</location></parent>
  </link_rigid>
</links>"#,
        i[0], i[1], i[2], i[3], i[4], i[5]
    )
}

/// A cables file: 8 cables of a 3 x 3 x 3 m frame, attachments `platform[i]` measured from
/// `reference`.
fn cables(reference: &str, platform: &[Vector3<f64>; 8]) -> String {
    let mut s = String::from("<cables default_cable_set=\"a\"><cable_set id=\"a\">\n");
    for (i, p) in platform.iter().enumerate() {
        let (x, y) = [(1.5, 1.5), (-1.5, 1.5), (-1.5, -1.5), (1.5, -1.5)][i % 4];
        let z = if i < 4 { 3.0 } else { 0.0 };
        s += &format!(
            r#"<cable_ideal name="c{i}" attachment_reference="{reference}">
  <properties><force_min>20</force_min><force_max>2000</force_max></properties>
  <attachments>
    <attachment><link>1</link><location>{:?} {:?} {:?}</location></attachment>
    <attachment><link>0</link><location>{x} {y} {z}</location></attachment>
  </attachments>
</cable_ideal>
"#,
            p.x, p.y, p.z
        );
    }
    s + "</cable_set></cables>"
}

/// Platform attachments from the link-frame origin (the box corners of a 0.4 x 0.4 x 0.3 m
/// platform whose origin is at its bottom face).
fn box_corners() -> [Vector3<f64>; 8] {
    let c = |x: f64, y: f64, z: f64| Vector3::new(x, y, z);
    [
        c(-0.2, 0.2, 0.3),
        c(0.2, 0.2, 0.3),
        c(0.2, -0.2, 0.3),
        c(-0.2, -0.2, 0.3),
        c(0.2, 0.2, 0.0),
        c(-0.2, 0.2, 0.0),
        c(-0.2, -0.2, 0.0),
        c(0.2, -0.2, 0.0),
    ]
}

#[test]
fn attachments_stay_where_caspr_puts_them_with_an_offset_centre_of_mass() {
    let (a, b, g) = (0.1, -0.05, 0.2);
    let q = format!("0.1 -0.2 1.4 {a} {b} {g}");
    let r_g = Vector3::new(0.03, -0.02, 0.12);
    let com = format!("{:?} {:?} {:?}", r_g.x, r_g.y, r_g.z);
    let i_g = [0.6, 0.5, 0.7, 0.01, -0.02, 0.03];
    let joint = import_str(
        &bodies(&com, &q, "com", i_g),
        "b.xml",
        &cables("joint", &box_corners()),
        "c.xml",
        &ImportOptions {
            t_min_n: None,
            ..ipanema_opts()
        },
    )
    .expect("imports");
    let s = &joint.scene;
    let rot = euler_xyz(a, b, g);
    // Link-frame origin: parent location + q translation.
    let origin = Vector3::new(0.5, 0.0, 0.25) + Vector3::new(0.1, -0.2, 1.4);
    assert!((s.ee_position_m - (origin + rot * r_g)).norm() < 1e-15);
    let r_scene = cablevib::kinematics::rotation_of(&s.ee_orientation_wxyz);
    // Rounding of a few products of numbers ≤ 2: 1e-15 is ~5 ulp of the largest.
    assert!((r_scene - rot).abs().max() < 1e-15);
    for (c, r_a) in s.cables.iter().zip(box_corners()) {
        let world_scene = s.ee_position_m + r_scene * c.attachment_m;
        let world_caspr = origin + rot * r_a;
        assert!((world_scene - world_caspr).norm() < 1e-14, "{c:?}");
    }
    // The same robot with attachments measured from the centre of mass: the same scene.
    let from_com = box_corners().map(|p| p - r_g);
    let com_ref = import_str(
        &bodies(&com, &q, "com", i_g),
        "b.xml",
        &cables("com", &from_com),
        "c.xml",
        &ImportOptions {
            t_min_n: None,
            ..ipanema_opts()
        },
    )
    .expect("imports");
    assert_eq!(com_ref.scene, joint.scene);
}

#[test]
fn inertia_about_the_joint_is_moved_to_the_centre_of_mass() {
    let m = 12.0;
    let r = Vector3::new(0.03, -0.02, 0.12);
    let i_g = Matrix3::new(0.6, 0.01, -0.02, 0.01, 0.5, 0.03, -0.02, 0.03, 0.7);
    // Parallel axes, written out element by element.
    let mut i_o = i_g;
    for (j, k) in [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)] {
        let d = if j == k { r.norm_squared() } else { 0.0 };
        i_o[(j, k)] += m * (d - r[j] * r[k]);
        i_o[(k, j)] = i_o[(j, k)];
    }
    let six = [
        i_o[(0, 0)],
        i_o[(1, 1)],
        i_o[(2, 2)],
        i_o[(0, 1)],
        i_o[(0, 2)],
        i_o[(1, 2)],
    ];
    let com = format!("{:?} {:?} {:?}", r.x, r.y, r.z);
    let im = import_str(
        &bodies(&com, "0 0 1.4 0 0 0", "joint", six),
        "b.xml",
        &cables("joint", &box_corners()),
        "c.xml",
        &ImportOptions {
            t_min_n: None,
            ..ipanema_opts()
        },
    )
    .expect("imports");
    // Two roundings of numbers ≤ 0.7 each way: 1e-15 absolute.
    assert!((im.scene.ee_inertia_kg_m2 - i_g).abs().max() < 1e-15);
}

/// CASPR's translational joint T_XYZ locks the rotation: the platform is a point mass whose
/// anchors are shifted by the attachment offsets, so each cable vector p − anchor is CASPR's
/// o + r_A − a_i (o = parent location + q, written out here) at the default pose and at any
/// other position. Names CASPR cannot load (TRANSLATIONAL_XYZ, SPATIAL_QUATERNION) and
/// CASPR joints that constrain the translation are refused, one line naming the file,
/// line and element.
#[test]
fn t_xyz_locks_the_rotation_and_other_joint_names_are_refused() {
    let opts = ImportOptions {
        t_min_n: None,
        ..ipanema_opts()
    };
    let i_g = [0.6, 0.5, 0.7, 0.0, 0.0, 0.0];
    let import = |bodies: String| {
        import_str(
            &bodies,
            "b.xml",
            &cables("joint", &box_corners()),
            "c.xml",
            &opts,
        )
    };
    let com = Vector3::new(0.03, -0.02, 0.12);
    let com_s = "0.03 -0.02 0.12";
    let tr = bodies(com_s, "0.1 0.2 1.4", "com", i_g).replace("SPATIAL_EULER_XYZ", "T_XYZ");
    let im = import(tr).expect("T_XYZ imports");
    let s = &im.scene;
    assert!(!s.rigid, "a locked rotation is a 3-DOF platform");
    assert_eq!(s.ee_orientation_wxyz, [1.0, 0.0, 0.0, 0.0]);
    assert!(im.toml.contains("T_XYZ locks the rotation"), "{}", im.toml);
    // Parent location (0.5, 0, 0.25) + q, each sum exact to within one rounding.
    let o = Vector3::new(0.5 + 0.1, 0.0 + 0.2, 0.25 + 1.4);
    assert!((s.ee_position_m - (o + com)).norm() < 1e-15);
    for (i, c) in s.cables.iter().enumerate() {
        let (x, y) = [(1.5, 1.5), (-1.5, 1.5), (-1.5, -1.5), (1.5, -1.5)][i % 4];
        let a = Vector3::new(x, y, if i < 4 { 3.0 } else { 0.0 });
        assert_eq!(c.attachment_m, Vector3::zeros());
        // At the default pose and 0.3 m away: the cable runs from CASPR's anchor to o + r_A.
        for d in [Vector3::zeros(), Vector3::new(0.3, -0.2, 0.1)] {
            let caspr = (o + d + box_corners()[i]) - a;
            let scene = (s.ee_position_m + d) - c.anchor_m;
            assert!(
                (scene - caspr).norm() < 1e-14,
                "cable {i}: {scene} vs {caspr}"
            );
        }
    }
    // Names CASPR's JointType does not have, and CASPR joints that are not platforms.
    for (ty, q, needle) in [
        (
            "TRANSLATIONAL_XYZ",
            "0.1 0.2 1.4",
            "CASPR's translational joint is T_XYZ",
        ),
        (
            "SPATIAL_QUATERNION",
            "0.1 0.2 1.4 1 0 0 0",
            "no quaternion joint",
        ),
        ("S_EULER_XYZ", "0 0 0", "constrains the link's translation"),
        ("R_Z", "0", "constrains the link's translation"),
    ] {
        let e = import(bodies(com_s, q, "com", i_g).replace("SPATIAL_EULER_XYZ", ty))
            .expect_err(ty)
            .to_string();
        assert!(e.starts_with("b.xml:4: <joint>:"), "{e}");
        assert!(e.contains(needle) && e.contains(ty), "{e}");
        assert!(e.contains("SPATIAL_EULER_XYZ, T_XYZ, PLANAR_XY"), "{e}");
        assert_eq!(e.lines().count(), 1, "{e}");
    }
}
