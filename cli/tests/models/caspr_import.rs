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

use cablevib::caspr::{import_files, CasprError, ImportOptions};
use cablevib::scene::{ElementKind, Scene};
use nalgebra::{Matrix3, Vector3};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");

fn data(name: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
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
        weight_per_length_n_m: Some(0.02),
        youngs_modulus_pa: Some(1.0e11),
        area_m2: Some(1.767e-6),
        position_m: None,
        t_min_n: Some(10.0),
        element: ElementKind::Fem,
        elements_per_cable: 10,
    }
}

/// The paper's planar cable: E = 2.0e10 Pa, A = π (2 mm)², γ = 0.067 N/m.
fn planar_opts() -> ImportOptions {
    ImportOptions {
        weight_per_length_n_m: Some(0.067),
        youngs_modulus_pa: Some(2.0e10),
        area_m2: Some(std::f64::consts::PI * 0.002 * 0.002),
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
    assert!(im.toml.contains("Given at import, not from CASPR"));
}

/// `cablevib analyze --json` on `path`, without the fields that name the file or time it.
fn analyze_json(path: &Path) -> serde_json::Value {
    let o = run(&["analyze", path.to_str().unwrap(), "--json", "--modes", "12"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    let m = v.as_object_mut().unwrap();
    for timing in ["solve_seconds", "dense_seconds"] {
        m.remove(timing);
    }
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

mod frames;
mod hostile;

#[test]
fn variants_found_in_caspr_models_are_read() {
    let b = read("ipanema1_bodies.xml");
    let c = read("ipanema1_cables.xml");
    let reference = ipanema(&ipanema_opts()).expect("imports").scene;
    let import = |b: &str, c: &str| {
        cablevib::caspr::import_str(b, "b.xml", c, "c.xml", &ipanema_opts())
            .expect("imports")
            .scene
    };
    // Operational spaces beside the links, and no q_initial (CASPR's default: zero).
    let ops = b.replace(
        "</links>",
        "</links>\n<operational_spaces><operational_set id=\"x\"/></operational_spaces>",
    );
    assert_eq!(import(&ops, &c), reference);
    let at_zero = import(&b.replace(" q_initial=\"0 0 1.0 0 0 0\"", ""), &c);
    assert_eq!(at_zero.ee_position_m, Vector3::zeros());
    // No default_cable_set: the first set is used only when it is the only one.
    let no_default = c.replace(" default_cable_set=\"original\"", "");
    let one_set = no_default[..no_default.find("  <cable_set id=\"springs\">").unwrap()]
        .to_string()
        + "</cables>\n";
    assert_eq!(import(&b, &one_set), reference);
    let e = cablevib::caspr::import_str(&b, "b.xml", &no_default, "c.xml", &ipanema_opts())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("pick one with cable_set (original, springs)"),
        "{e}"
    );
}
