//! `cablevib import caspr`: robots from CASPR's XML model files.
//!
//! - The two test robots in tests/data/caspr/ (IPAnema 1, Pott et al. 2013; the planar robot
//!   of Nguyen et al., Tables 1-2) import with the published anchor and attachment
//!   coordinates, mass and inertia (the expected numbers are typed in below from the
//!   papers, not read from the XML).
//! - `analyze` on the imported scene equals `analyze` on a scene written by hand from the
//!   same published values (tests/data/caspr/*.toml) to the last bit: both files must
//!   parse to the same `Scene`, and the analysis of one `Scene` is deterministic.
//! - Frames: a platform whose centre of mass is off the link-frame origin, at a rotated
//!   pose, keeps every attachment point where CASPR puts it (reference: the rotation
//!   matrix Rx(α) Ry(β) Rz(γ) written out with sin and cos here, not nalgebra's
//!   quaternions that the importer uses), and an inertia given about the joint comes back
//!   about the centre of mass.
//! - Hostile inputs give one-line errors naming the file and element; nothing panics.

use cablevib::caspr::{import_files, import_str, CasprError, ImportOptions};
use cablevib::scene::{ElementKind, Scene};
use nalgebra::{Matrix3, Vector3};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/caspr")
        .join(name)
}

fn read(name: &str) -> String {
    std::fs::read_to_string(data(name)).expect("test data")
}

/// The IPAnema test options: a 1.5 mm cable and T_min = 10 N (CASPR's force_min is 0).
fn ipanema_opts() -> ImportOptions {
    ImportOptions {
        cable_set: None,
        weight_per_length_n_m: 0.02,
        youngs_modulus_pa: Some(1.0e11),
        area_m2: 1.767e-6,
        position_m: None,
        t_min_n: Some(10.0),
        element: ElementKind::Fem,
        elements_per_cable: 10,
    }
}

/// The paper's planar cable: E = 2.0e10 Pa, A = π (2 mm)², γ = 0.067 N/m.
fn planar_opts() -> ImportOptions {
    ImportOptions {
        weight_per_length_n_m: 0.067,
        youngs_modulus_pa: Some(2.0e10),
        area_m2: std::f64::consts::PI * 0.002 * 0.002,
        t_min_n: None,
        ..ipanema_opts()
    }
}

fn ipanema(opts: &ImportOptions) -> Result<cablevib::caspr::Imported, CasprError> {
    import_files(
        &data("ipanema1_bodies.xml"),
        &data("ipanema1_cables.xml"),
        opts,
    )
}

#[test]
fn ipanema_imports_the_published_geometry() {
    let s = ipanema(&ipanema_opts()).expect("imports").scene;
    // Pott et al. 2013: winches at (±2, ±1.5) m, upper at z = 2 m, lower at z = 0; the
    // platform's corners at (±0.06, ±0.06, 0) m. Exact: the numbers pass through unchanged.
    let corners = [(-1.0, 1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)];
    for (i, c) in s.cables.iter().enumerate() {
        let (sx, sy) = corners[i % 4];
        let z = if i < 4 { 2.0 } else { 0.0 };
        assert_eq!(c.anchor_m, Vector3::new(2.0 * sx, 1.5 * sy, z), "cable {i}");
        assert_eq!(
            c.attachment_m,
            Vector3::new(0.06 * sx, 0.06 * sy, 0.0),
            "cable {i}"
        );
        assert_eq!((c.t_min_n, c.t_max_n), (Some(10.0), Some(720.0)));
    }
    assert_eq!(s.ee_mass_kg, 25.0);
    assert_eq!(s.ee_inertia_kg_m2, Matrix3::identity() * 14.0);
    assert_eq!(s.ee_position_m, Vector3::new(0.0, 0.0, 1.0));
    assert!(s.rigid && s.weight_carried);
}

#[test]
fn planar_imports_the_published_geometry() {
    let im = import_files(
        &data("planar_nguyen_bodies.xml"),
        &data("planar_nguyen_cables.xml"),
        &planar_opts(),
    )
    .expect("imports");
    let s = im.scene;
    let anchors = [(1.25, 1.25), (-1.25, 1.25), (-1.25, -1.25), (1.25, -1.25)];
    for (c, (x, y)) in s.cables.iter().zip(anchors) {
        assert_eq!(c.anchor_m, Vector3::new(x, y, 0.0));
        assert_eq!(c.attachment_m, Vector3::zeros());
        assert_eq!((c.t_min_n, c.t_max_n), (Some(20.0), Some(250.0)));
    }
    assert_eq!(s.ee_mass_kg, 5.0);
    // Point mass in a horizontal plane: 3 DOF, the plane carries the weight.
    assert!(!s.rigid && !s.weight_carried);
    assert!(im.toml.contains("From the command line, not from CASPR"));
}

/// `cablevib analyze --json` on `path`, without the fields that name the file or time it.
fn analyze_json(path: &Path) -> serde_json::Value {
    let o = run(&["analyze", path.to_str().unwrap(), "--json", "--modes", "12"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    let m = v.as_object_mut().unwrap();
    m.remove("dense_seconds");
    v
}

/// Import through the command line into target/, check the file against the hand-written
/// scene, and compare `analyze`.
fn cli_import_matches_hand_written(bodies: &str, cables: &str, flags: &[&str], hand: &str) {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("{hand}.imported.toml"));
    let (b, c) = (data(bodies), data(cables));
    let mut args = vec!["import", "caspr", b.to_str().unwrap(), c.to_str().unwrap()];
    args.extend_from_slice(flags);
    args.extend_from_slice(&["-o", out.to_str().unwrap()]);
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let imported = Scene::from_path(&out).expect("imported scene validates");
    let by_hand = Scene::from_path(&data(hand)).expect("hand-written scene validates");
    assert_eq!(imported, by_hand);
    // Bitwise: identical scenes, deterministic dense analysis.
    assert_eq!(analyze_json(&out), analyze_json(&data(hand)));
}

#[test]
fn analyze_of_imported_ipanema_equals_the_hand_written_scene() {
    let flags = [
        "--weight-per-length",
        "0.02",
        "--area",
        "1.767e-6",
        "--youngs-modulus",
        "1.0e11",
        "--t-min",
        "10",
    ];
    cli_import_matches_hand_written(
        "ipanema1_bodies.xml",
        "ipanema1_cables.xml",
        &flags,
        "ipanema1.toml",
    );
}

#[test]
fn analyze_of_imported_planar_equals_the_hand_written_scene() {
    let flags = [
        "--weight-per-length",
        "0.067",
        "--area",
        "1.2566370614359172e-5",
        "--youngs-modulus",
        "2.0e10",
    ];
    cli_import_matches_hand_written(
        "planar_nguyen_bodies.xml",
        "planar_nguyen_cables.xml",
        &flags,
        "planar_nguyen.toml",
    );
}

#[test]
fn linear_spring_k_is_the_axial_rigidity() {
    let opts = ImportOptions {
        cable_set: Some("springs".into()),
        youngs_modulus_pa: None,
        ..ipanema_opts()
    };
    let s = ipanema(&opts).expect("imports").scene;
    for c in &s.cables {
        // E = K / A written with 17 digits, times A again: within 2 ulp of K = 150000 N.
        let rel = (c.ea_n() - 150_000.0).abs() / 150_000.0;
        assert!(rel <= 2.0 * f64::EPSILON, "EA = {}", c.ea_n());
    }
}

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

fn run(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("the binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The error of importing `bodies` and `cables` (texts) with `opts`.
fn err_of(bodies: &str, cables: &str, opts: &ImportOptions) -> String {
    let e = import_str(bodies, "b.xml", cables, "c.xml", opts)
        .expect_err("must be refused")
        .to_string();
    assert_eq!(e.lines().count(), 1, "one line: {e}");
    e
}

#[test]
fn hostile_inputs_give_one_line_errors_naming_file_and_element() {
    let b = read("ipanema1_bodies.xml");
    let c = read("ipanema1_cables.xml");
    let o = ipanema_opts();
    let cases: Vec<(String, String, ImportOptions, &[&str])> = vec![
        // Malformed XML: truncated.
        (
            first_half(&b),
            c.clone(),
            o.clone(),
            &["b.xml", "malformed XML"],
        ),
        (
            b.clone(),
            "<cables><cable_set".into(),
            o.clone(),
            &["c.xml", "malformed XML"],
        ),
        // Two moving links.
        (
            b.replace("</links>", &format!("{}</links>", link_block(&b))),
            c.clone(),
            o.clone(),
            &["b.xml", "2 moving links"],
        ),
        // A cable set that does not exist.
        (
            b.clone(),
            c.clone(),
            ImportOptions {
                cable_set: Some("nope".into()),
                ..o.clone()
            },
            &["c.xml", "no cable set `nope`", "original, springs"],
        ),
        // NaN and other non-numbers.
        (
            b.clone(),
            c.replacen("-2.0 1.5 2.0", "-2.0 NaN 2.0", 1),
            o.clone(),
            &["c.xml:", "<location>", "`NaN` is not a finite number"],
        ),
        (
            b.replace("<mass>25.0</mass>", "<mass>inf</mass>"),
            c.clone(),
            o.clone(),
            &["b.xml:", "<mass>", "not a finite number"],
        ),
        (
            b.replace("<Ixx>14.0</Ixx>", "<Ixx>heavy</Ixx>"),
            c.clone(),
            o.clone(),
            &["b.xml:", "<Ixx>", "`heavy` is not a number"],
        ),
        (
            b.clone(),
            c.replacen("-2.0 1.5 2.0", "-2.0 1.5", 1),
            o.clone(),
            &["c.xml:", "<location>", "expected 3 numbers"],
        ),
        // Missing attributes and elements.
        (
            b.clone(),
            c.replacen(" attachment_reference=\"joint\"", "", 1),
            o.clone(),
            &[
                "c.xml:",
                "<cable_ideal>",
                "missing attribute `attachment_reference`",
            ],
        ),
        (
            b.clone(),
            c.replacen("<force_max>720.0</force_max>", "", 1),
            o.clone(),
            &["c.xml:", "<properties>", "missing <force_max>"],
        ),
        (
            b.replace("<com_location>0.0 0.0 0.0</com_location>", ""),
            c.clone(),
            o.clone(),
            &["b.xml:", "<physical>", "missing <com_location>"],
        ),
        // Unsupported joint and cable types.
        (
            b.replace("SPATIAL_EULER_XYZ", "REVOLUTE_Z"),
            c.clone(),
            o.clone(),
            &["b.xml:", "<joint>", "REVOLUTE_Z"],
        ),
        (
            b.clone(),
            c.replacen("cable_ideal", "cable_passive_linear_spring", 2),
            o.clone(),
            &["c.xml:", "cable_passive_linear_spring", "not supported"],
        ),
        // A cable attached to the base at both ends.
        (
            b.clone(),
            c.replacen("<link>1</link>", "<link>0</link>", 1),
            o.clone(),
            &["c.xml:", "both attachments are on link 0"],
        ),
        // CASPR's force_min of 0 without --t-min; cable_ideal without a Young's modulus.
        (
            b.clone(),
            c.clone(),
            ImportOptions {
                t_min_n: None,
                ..o.clone()
            },
            &["c.xml", "cable `cable 1`", "force_min = 0", "--t-min"],
        ),
        (
            b.clone(),
            c.clone(),
            ImportOptions {
                youngs_modulus_pa: None,
                ..o.clone()
            },
            &["cable `cable 1`", "--youngs-modulus"],
        ),
        (
            b.clone(),
            c.clone(),
            ImportOptions {
                area_m2: f64::NAN,
                ..o.clone()
            },
            &["area", "NaN"],
        ),
        // Off-centre attachments with too few cables for a rigid platform.
        (
            b.clone(),
            four_cables(&c),
            o.clone(),
            &["c.xml", "at least 6 cables", "has 4"],
        ),
        // Entity expansion is bounded by the XML parser.
        (laughs(), c.clone(), o.clone(), &["b.xml", "malformed XML"]),
    ];
    for (bodies, cables, opts, needles) in cases {
        let e = err_of(&bodies, &cables, &opts);
        for n in needles {
            assert!(e.contains(n), "`{n}` not in: {e}");
        }
    }
}

/// The first half of `s` (cut at a character boundary).
fn first_half(s: &str) -> String {
    let mut k = s.len() / 2;
    while !s.is_char_boundary(k) {
        k -= 1;
    }
    s[..k].to_string()
}

/// The `<link_rigid>` element of a bodies file (to make a second one).
fn link_block(b: &str) -> String {
    let start = b.find("<link_rigid").unwrap();
    let end = b.find("</link_rigid>").unwrap() + "</link_rigid>".len();
    b[start..end].replace("num=\"1\"", "num=\"2\"")
}

/// The IPAnema cables file with its default set cut to the first four cables.
fn four_cables(c: &str) -> String {
    let mut out = c.to_string();
    for k in 5..=8 {
        let open = format!("<cable_ideal name=\"cable {k}\"");
        let start = out.find(&open).unwrap();
        let end = start + out[start..].find("</cable_ideal>").unwrap() + "</cable_ideal>".len();
        out.replace_range(start..end, "");
    }
    out
}

/// Nested entities whose expansion would be 10⁹ characters.
fn laughs() -> String {
    let mut s = String::from("<?xml version=\"1.0\"?>\n<!DOCTYPE lolz [\n<!ENTITY l0 \"lol\">\n");
    for k in 1..=9 {
        let prev = format!("&l{};", k - 1).repeat(10);
        s += &format!("<!ENTITY l{k} \"{prev}\">\n");
    }
    s + "]>\n<links>&l9;</links>"
}

#[test]
fn cli_errors_are_one_line_and_the_output_analyzes() {
    let b = data("ipanema1_bodies.xml");
    let c = data("ipanema1_cables.xml");
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli_ipanema.toml");
    let base = [
        "import",
        "caspr",
        b.to_str().unwrap(),
        c.to_str().unwrap(),
        "--weight-per-length",
        "0.02",
        "--area",
        "1.767e-6",
        "--youngs-modulus",
        "1e11",
        "-o",
        out.to_str().unwrap(),
    ];
    // force_min = 0 and no --t-min: refused, one line, no file written.
    let _ = std::fs::remove_file(&out);
    let o = run(&base);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    assert!(e.contains("--t-min") && !out.exists(), "{e}");
    // Unknown set: the error lists the available ones.
    let mut args = base.to_vec();
    args.extend_from_slice(&["--t-min", "10", "--cable-set", "x"]);
    let o = run(&args);
    let e = stderr(&o);
    assert!(
        o.status.code() == Some(1) && e.contains("original, springs"),
        "{e}"
    );
    // A missing file.
    let o = run(&[
        "import",
        "caspr",
        "/nonexistent.xml",
        c.to_str().unwrap(),
        "--weight-per-length",
        "1",
        "--area",
        "1e-6",
        "-o",
        "/dev/null",
    ]);
    let e = stderr(&o);
    assert!(
        o.status.code() == Some(1) && e.contains("/nonexistent.xml"),
        "{e}"
    );
    // --position moves the link frame; the result analyzes at the new pose.
    let mut args = base.to_vec();
    args.extend_from_slice(&["--t-min", "10", "--position", "0.3,-0.2,1.1"]);
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = Scene::from_path(&out).unwrap();
    assert_eq!(s.ee_position_m, Vector3::new(0.3, -0.2, 1.1));
    let o = run(&["analyze", out.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn names_with_quotes_and_newlines_cannot_break_the_scene_file() {
    // XML character references put a newline and quotes into the names; the scene's name
    // must stay one TOML string and the cable name one comment line.
    let b = read("ipanema1_bodies.xml")
        .replace("name=\"IPAnema 1\"", "name=\"x&#10;t_max = 1 # &quot;\\\"");
    let c = read("ipanema1_cables.xml").replace("name=\"cable 1\"", "name=\"c&#10;[[cables]]\"");
    let im = import_str(&b, "b.xml", &c, "c.xml", &ipanema_opts()).expect("imports");
    assert_eq!(im.scene.name, "x\nt_max = 1 # \"\\");
    assert_eq!(im.scene.n_cables(), 8);
}
