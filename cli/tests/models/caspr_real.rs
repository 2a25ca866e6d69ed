//! `cablevib import caspr` on CASPR's own robot files (tests/data/caspr/model_config/, nine
//! robots from CASPR's repository, unchanged; SOURCE.txt and LICENSE.CASPR beside them),
//! every cable set of every robot, plus a T_XYZ variant of XL_Laser made here.
//!
//! For each set, checked against code written here, independent of `src/caspr`:
//!
//! - **Sets with pulleys** (`<base_rotating_pulley>`) import, each pulley at CASPR's
//!   `fixed_location` with its radius and entry vector; at the default pose the exit point,
//!   free length, direction and wrapped arc of every cable equal CASPR's own formulas
//!   (`BaseRotatingPulleyAttachment.ComputePulleyLeavingLocation`: the centre
//!   r_C = r_F + R·unit((v_F × v_FB) × v_F), ρ = R/|r_B − r_C|, the exit point
//!   r_A = r_C + ρ²(r_B − r_C) − ρ√(1 − ρ²) n̂ × (r_B − r_C), the arc R·acos(n1·n2)),
//!   evaluated here, to 1e-12 (m). Their tensions are not checked against the LP here (its
//!   directions are the straight anchor ones).
//! - **Geometry**: the XML is read here with roxmltree (a few lines), CASPR's kinematics
//!   re-derived: link-frame origin o = parent location + q (x y z), R = Rx(α) Ry(β) Rz(γ)
//!   written out with sin and cos (identity for T_XYZ), attachment point P_i = o + R r_A
//!   (`joint`) or o + R (r_G + r_A) (`com`), centre of mass G = o + R r_G. The scene must
//!   put its end-effector at G (1e-12 m: a few roundings of numbers ≤ 10 m), each anchor at
//!   CASPR's a_i exactly (T_XYZ: shifted by the attachment offset, docs/caspr.md) and every
//!   cable vector at P_i − a_i (1e-12 m).
//! - **Bounds**: each cable's t_min / t_max are CASPR's force_min / force_max (exactly), or
//!   the `--t-min` given for sets whose force_min is ≤ 0.
//! - **Default pose, library estimator** (`Estimator::update_with_bounds` with the scene's
//!   own per-cable lower bounds): when ok, the tensions balance the weight with the
//!   structure matrix built here from P_i, a_i and G, Σ T_i u_i + m g = 0 and (6 DOF)
//!   Σ (P_i − G) × T_i u_i = 0, to 1e-9 of m g + Σ T_i (the active-set answer is exact to
//!   rounding), and each T_i is within its own cable's bounds (1e-9 relative); the LP
//!   below must find that problem feasible too (so its "infeasible" means something). When refused
//!   as tension-infeasible or outside-workspace (or at build time), an LP solved here with
//!   Clarabel (feasibility of A T = w, lo ≤ T ≤ hi; no objective) must find no tensions.
//! - **Default pose, printed** (`cablevib analyze --json --sag false`): the same checks on
//!   the printed tensions, or on a refusal the same LP.
//! - **Dense solver** on Example_spatial, whose force_max = 9999999999 N (CASPR's
//!   "unbounded"): `analyze --solver dense --json` prints tensions that balance the load.
//!
//! Material for every import: `--weight-per-length 0.5 --area 1e-5 --youngs-modulus 1e11`,
//! `--t-min 1` only where a force_min is ≤ 0.

use cablevib::caspr::{import_files, ImportOptions};
use cablevib::estimator::{BuildError, Estimator, Status, Tmin};
use cablevib::kinematics::Pose;
use cablevib::scene::{ElementKind, Scene};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, ZeroConeT,
};
use nalgebra::{Matrix3, Vector3};
use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_cablevib");
/// CASPR's gravity, m/s², along −z.
const G: f64 = 9.81;
/// The T_min passed for sets whose force_min is ≤ 0, N.
const T_MIN_OPT: f64 = 1.0;
/// Equilibrium and bound tolerance, relative (see the module docs).
const REL: f64 = 1e-9;
/// Geometry tolerance, m.
const GEOM: f64 = 1e-12;

/// The robots: CASPR's paths below model_config/, bodies and cables file stems.
const ROBOTS: [&str; 9] = [
    "indev_models/CUHK/CUCableRobot/CUHK_CUCableRobot",
    "indev_models/CUHK/PoCaBot_family/CU_Brick/CU_Brick",
    "indev_models/CUHK/PoCaBot_family/DrainageService/DrainageServiceBot",
    "indev_models/CUHK/PoCaBot_family/XL_Laser/XL_Laser",
    "models/SCDM/spatial_manipulators/CAROCA/CAROCA",
    "models/SCDM/spatial_manipulators/CoGiRo/CoGiRo",
    "models/SCDM/spatial_manipulators/FAST/FAST",
    "models/SCDM/spatial_manipulators/IPAnema_1/IPAnema_1",
    "models/examples/Example_spatial/Example_spatial",
];

fn model_config() -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/..")).join("tests/data/caspr/model_config")
}

fn files(stem: &str) -> (PathBuf, PathBuf) {
    let d = model_config();
    (
        d.join(format!("{stem}_bodies.xml")),
        d.join(format!("{stem}_cables.xml")),
    )
}

fn tmp(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(name)
}

// ---------------------------------------------------------------------------------------
// CASPR's model, read and re-derived here
// ---------------------------------------------------------------------------------------

/// The link as CASPR's kinematics places it at q_initial.
struct Link {
    /// Link-frame origin o, m.
    origin: Vector3<f64>,
    /// Rotation R.
    rot: Matrix3<f64>,
    /// Centre of mass r_G, link frame, m.
    com: Vector3<f64>,
    mass: f64,
    /// T_XYZ: the rotation is locked (force rows only).
    locked: bool,
}

/// One cable of a set: anchor a_i, platform point P_i (inertial frame), bounds.
struct Cable {
    anchor: Vector3<f64>,
    /// A `base_rotating_pulley` at the anchor: (radius m, entry vector).
    pulley: Option<(f64, Vector3<f64>)>,
    point: Vector3<f64>,
    force_min: f64,
    force_max: f64,
}

fn v3(s: &str) -> Vector3<f64> {
    let v: Vec<f64> = s.split_whitespace().map(|w| w.parse().unwrap()).collect();
    assert_eq!(v.len(), 3, "{s}");
    Vector3::new(v[0], v[1], v[2])
}

fn child<'a, 'i>(n: roxmltree::Node<'a, 'i>, tag: &str) -> roxmltree::Node<'a, 'i> {
    n.children()
        .find(|c| c.has_tag_name(tag))
        .unwrap_or_else(|| panic!("no <{tag}> in <{}>", n.tag_name().name()))
}

fn text<'a>(n: roxmltree::Node<'a, '_>, tag: &str) -> &'a str {
    child(n, tag).text().unwrap_or("").trim()
}

/// Rx(α) Ry(β) Rz(γ), written out.
fn euler_xyz(a: f64, b: f64, g: f64) -> Matrix3<f64> {
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, a.cos(), -a.sin(), 0.0, a.sin(), a.cos());
    let ry = Matrix3::new(b.cos(), 0.0, b.sin(), 0.0, 1.0, 0.0, -b.sin(), 0.0, b.cos());
    let rz = Matrix3::new(g.cos(), -g.sin(), 0.0, g.sin(), g.cos(), 0.0, 0.0, 0.0, 1.0);
    rx * ry * rz
}

fn read_link(xml: &str) -> Link {
    let doc = roxmltree::Document::parse_with_options(
        xml,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .unwrap();
    let l = doc
        .descendants()
        .find(|n| n.has_tag_name("link_rigid"))
        .unwrap();
    let j = child(l, "joint");
    let q: Vec<f64> = j
        .attribute("q_initial")
        .unwrap()
        .split_whitespace()
        .map(|w| w.parse().unwrap())
        .collect();
    let (rot, locked) = match j.attribute("type").unwrap() {
        "SPATIAL_EULER_XYZ" => (euler_xyz(q[3], q[4], q[5]), false),
        "T_XYZ" => (Matrix3::identity(), true),
        other => panic!("joint {other} not in CASPR's robots here"),
    };
    let phys = child(l, "physical");
    Link {
        origin: v3(text(child(l, "parent"), "location")) + Vector3::new(q[0], q[1], q[2]),
        rot,
        com: v3(text(phys, "com_location")),
        mass: text(phys, "mass").parse().unwrap(),
        locked,
    }
}

/// Every cable set: its id and its cables.
fn read_sets(xml: &str, link: &Link) -> Vec<(String, Vec<Cable>)> {
    let doc = roxmltree::Document::parse_with_options(
        xml,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .unwrap();
    let mut out = Vec::new();
    for set in doc
        .root_element()
        .children()
        .filter(|n| n.has_tag_name("cable_set"))
    {
        let id = set.attribute("id").unwrap().to_string();
        let mut cables = Vec::new();
        for c in set.children().filter(|n| n.is_element()) {
            let at = child(c, "attachments");
            let (mut anchor, mut local, mut pulley) = (None, None, None);
            for p in at
                .children()
                .filter(|n| n.has_tag_name("base_rotating_pulley"))
            {
                anchor = Some(v3(text(p, "fixed_location")));
                pulley = Some((
                    text(p, "pulley_radius").trim().parse().unwrap(),
                    v3(text(p, "cable_entry_vector")),
                ));
            }
            for a in at.children().filter(|n| n.has_tag_name("attachment")) {
                let loc = v3(text(a, "location"));
                match text(a, "link") {
                    "0" => anchor = Some(loc),
                    "1" => local = Some(loc),
                    l => panic!("link {l}"),
                }
            }
            let local = local.unwrap();
            let from_origin = match c.attribute("attachment_reference").unwrap() {
                "joint" => local,
                "com" => link.com + local,
                r => panic!("{r}"),
            };
            let p = child(c, "properties");
            cables.push(Cable {
                anchor: anchor.unwrap(),
                pulley,
                point: link.origin + link.rot * from_origin,
                force_min: text(p, "force_min").parse().unwrap(),
                force_max: text(p, "force_max").parse().unwrap(),
            });
        }
        out.push((id, cables));
    }
    out
}

/// The rotation of a unit quaternion [w, x, y, z], written out.
fn quat_matrix(q: [f64; 4]) -> Matrix3<f64> {
    let [w, x, y, z] = q;
    Matrix3::new(
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y - w * z),
        2.0 * (x * z + w * y),
        2.0 * (x * y + w * z),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z - w * x),
        2.0 * (x * z - w * y),
        2.0 * (y * z + w * x),
        1.0 - 2.0 * (x * x + y * y),
    )
}

// ---------------------------------------------------------------------------------------
// Statics, built here
// ---------------------------------------------------------------------------------------

/// The columns of the structure matrix (force of a unit tension on the platform, and its
/// moment about G), and the load to balance w = −(weight, 0): A T = w.
fn statics(link: &Link, cables: &[Cable]) -> (Vec<[f64; 6]>, [f64; 6], usize) {
    let g = link.origin + link.rot * link.com;
    let cols = cables
        .iter()
        .map(|c| {
            let u = (c.anchor - c.point).normalize();
            let m = (c.point - g).cross(&u);
            [u.x, u.y, u.z, m.x, m.y, m.z]
        })
        .collect();
    let w = [0.0, 0.0, link.mass * G, 0.0, 0.0, 0.0];
    let rigid = !link.locked && cables.iter().any(|c| (c.point - g).norm() > 0.0);
    (cols, w, if rigid { 6 } else { 3 })
}

/// max_r |(A T − w)_r| relative to m g + Σ T_i.
fn residual(cols: &[[f64; 6]], w: &[f64; 6], rows: usize, t: &[f64]) -> f64 {
    let scale = w[2].abs() + t.iter().map(|x| x.abs()).sum::<f64>();
    (0..rows)
        .map(|r| {
            let f: f64 = cols.iter().zip(t).map(|(c, ti)| c[r] * ti).sum();
            (f - w[r]).abs()
        })
        .fold(0.0, f64::max)
        / scale
}

/// Feasibility LP with Clarabel: is there T with A T = w (the first `rows` rows) and
/// lo ≤ T ≤ hi? Unknowns scaled by the load so the tolerances are relative. None when
/// Clarabel does not decide.
fn lp_feasible(
    cols: &[[f64; 6]],
    w: &[f64; 6],
    rows: usize,
    lo: &[f64],
    hi: &[f64],
) -> Option<bool> {
    let n = cols.len();
    let s = lo.iter().copied().fold(w[2].abs().max(1.0), f64::max);
    let m = rows + 2 * n;
    let mut a = vec![vec![0.0; n]; m];
    let mut b = vec![0.0; m];
    for r in 0..rows {
        for i in 0..n {
            a[r][i] = cols[i][r];
        }
        b[r] = w[r] / s;
    }
    for i in 0..n {
        a[rows + i][i] = 1.0;
        b[rows + i] = hi[i] / s;
        a[rows + n + i][i] = -1.0;
        b[rows + n + i] = -lo[i] / s;
    }
    let p = CscMatrix::from(&vec![vec![0.0; n]; n]);
    let settings = DefaultSettings {
        verbose: false,
        max_iter: 500,
        ..DefaultSettings::default()
    };
    let cones = [ZeroConeT(rows), NonnegativeConeT(2 * n)];
    let mut solver = DefaultSolver::new(
        &p,
        &vec![0.0; n],
        &CscMatrix::from(&a),
        &b,
        &cones,
        settings,
    )
    .ok()?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => Some(true),
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => Some(false),
        _ => None,
    }
}

// ---------------------------------------------------------------------------------------
// The checks
// ---------------------------------------------------------------------------------------

fn options(set: &str, cables: &[Cable]) -> ImportOptions {
    let slack = cables.iter().any(|c| c.force_min <= 0.0);
    ImportOptions {
        cable_set: Some(set.into()),
        weight_per_length_n_m: Some(0.5),
        youngs_modulus_pa: Some(1e11),
        area_m2: Some(1e-5),
        position_m: None,
        t_min_n: slack.then_some(T_MIN_OPT),
        element: ElementKind::Fem,
        elements_per_cable: 10,
    }
}

/// Geometry and bounds of the imported scene against CASPR's, re-derived here.
fn check_scene(who: &str, s: &Scene, link: &Link, cables: &[Cable], t_min_opt: Option<f64>) {
    let g = link.origin + link.rot * link.com;
    assert!(
        (s.ee_position_m - g).norm() < GEOM,
        "{who}: G {}",
        s.ee_position_m
    );
    assert!((s.ee_mass_kg - link.mass).abs() == 0.0, "{who}: mass");
    let (_, _, rows) = statics(link, cables);
    assert_eq!(s.rigid, rows == 6, "{who}: rigid");
    let r = quat_matrix(s.ee_orientation_wxyz);
    assert!((r - link.rot).abs().max() < 1e-15, "{who}: R");
    assert_eq!(s.n_cables(), cables.len(), "{who}");
    for (i, (sc, c)) in s.cables.iter().zip(cables).enumerate() {
        if link.locked {
            assert_eq!(sc.attachment_m, Vector3::zeros(), "{who} cable {i}");
        } else {
            assert_eq!(sc.anchor_m, c.anchor, "{who} cable {i}: anchor");
            let p = s.ee_position_m + r * sc.attachment_m;
            assert!(
                (p - c.point).norm() < GEOM,
                "{who} cable {i}: {p} vs {}",
                c.point
            );
        }
        let v = s.ee_position_m + r * sc.attachment_m - sc.anchor_m;
        let want = c.point - c.anchor;
        assert!(
            (v - want).norm() < GEOM,
            "{who} cable {i}: cable {v} vs {want}"
        );
        assert_eq!(
            s.cable_t_min_n(i),
            t_min_opt.unwrap_or(c.force_min),
            "{who} cable {i}: t_min"
        );
        assert_eq!(s.cable_t_max_n(i), c.force_max, "{who} cable {i}: t_max");
    }
}

/// CASPR's `ComputePulleyLeavingLocation`, written out from its source: entry point r_F,
/// entry vector v_F, platform point r_B, radius R → (exit point r_A, arc, centre r_C).
fn caspr_pulley_exit(
    r_f: Vector3<f64>,
    v_f: Vector3<f64>,
    r_b: Vector3<f64>,
    r: f64,
) -> (Vector3<f64>, f64, Vector3<f64>) {
    let v_fb = r_b - r_f;
    let n_plane = v_f.cross(&v_fb);
    let n_plane_unit = n_plane / n_plane.norm();
    let v_fc = n_plane.cross(&v_f);
    let r_c = r_f + r * v_fc / v_fc.norm();
    let rho = r / (r_b - r_c).norm();
    let r_a = r_c + rho * rho * (r_b - r_c)
        - rho * (1.0 - rho * rho).sqrt() * n_plane_unit.cross(&(r_b - r_c));
    let n1 = (r_f - r_c) / (r_f - r_c).norm();
    let n2 = (r_a - r_c) / (r_a - r_c).norm();
    (r_a, r * n1.dot(&n2).acos(), r_c)
}

/// The scene's pulley geometry at its default pose against [`caspr_pulley_exit`] (1e-12 m);
/// the smallest and largest wrapped arc, m.
fn check_pulleys(who: &str, s: &Scene, cables: &[Cable]) -> (f64, f64) {
    use cablevib::kinematics::{rotation_of, Geometry};
    let mut g = Geometry::for_scene(s);
    let rot = rotation_of(&s.ee_orientation_wxyz);
    let anchors = s.cables.iter().map(|c| &c.anchor_m);
    if s.rigid {
        let b = s.cables.iter().map(|c| &c.attachment_m);
        g.update_rigid(anchors, b, &s.ee_position_m, &rot)
    } else {
        g.update(anchors, &s.ee_position_m)
    }
    .unwrap_or_else(|e| panic!("{who}: {e}"));
    let mut arcs = (f64::INFINITY, 0.0f64);
    for (i, c) in cables.iter().enumerate() {
        let (r, v) = c.pulley.expect("every cable of the set has a pulley");
        let (r_a, arc, _) = caspr_pulley_exit(c.anchor, v, c.point, r);
        let e = g.pulley_exit(i).expect("imported with its pulley");
        assert!(
            (e.exit_m - r_a).norm() < GEOM,
            "{who} cable {i}: exit {} vs CASPR {r_a}",
            e.exit_m
        );
        assert!((g.wrap_arc_m(i) - arc).abs() < GEOM, "{who} cable {i}: arc");
        let l = (c.point - r_a).norm();
        assert!((g.free_length_m(i) - l).abs() < GEOM, "{who} cable {i}: L");
        assert!(
            (g.unit[i] - (c.point - r_a) / l).norm() < GEOM,
            "{who} cable {i}: direction"
        );
        arcs = (arcs.0.min(arc), arcs.1.max(arc));
    }
    arcs
}

/// What one check of tensions found, for the summary.
#[derive(Debug)]
enum Outcome {
    /// Tensions balanced and within their bounds (the relative residual).
    Balanced(f64),
    /// Refused, and the LP agrees it is infeasible.
    RefusedInfeasible,
    /// Another status, which the LP does not judge (printed in the summary).
    Other(String),
}

/// Tensions (or a refusal) at the default pose, checked: the outcome, or what is wrong.
fn check_tensions(
    who: &str,
    link: &Link,
    cables: &[Cable],
    lo: &[f64],
    result: Result<&[f64], String>,
) -> Result<Outcome, String> {
    let (cols, w, rows) = statics(link, cables);
    let hi: Vec<f64> = cables.iter().map(|c| c.force_max).collect();
    match result {
        Ok(t) => {
            let res = residual(&cols, &w, rows, t);
            if res.is_nan() || res > REL {
                return Err(format!("{who}: residual {res:.3e} of the load, T {t:.4?}"));
            }
            for (i, &ti) in t.iter().enumerate() {
                let tol = REL * ti.abs().max(lo[i]).max(1.0);
                if !(ti >= lo[i] - tol && ti <= hi[i] + tol) {
                    return Err(format!(
                        "{who} cable {}: T {ti:.4} N outside its own bounds [{}, {}] N",
                        i + 1,
                        lo[i],
                        hi[i]
                    ));
                }
            }
            // The LP is the judge of refusals: it must find these tensions' problem feasible.
            if lp_feasible(&cols, &w, rows, lo, &hi) != Some(true) {
                return Err(format!(
                    "{who}: balanced, but the LP does not find it feasible"
                ));
            }
            Ok(Outcome::Balanced(res))
        }
        Err(status) => {
            let refusal = [
                "TensionInfeasible",
                "OutsideWorkspace",
                "tension infeasible",
                "outside the workspace",
                "outside_workspace",
            ]
            .iter()
            .any(|k| status.contains(k));
            if !refusal {
                return Ok(Outcome::Other(status.trim().to_string()));
            }
            match lp_feasible(&cols, &w, rows, lo, &hi) {
                Some(false) => Ok(Outcome::RefusedInfeasible),
                lp => Err(format!(
                    "{who}: refused ({}) but the LP says {}",
                    status.trim(),
                    if lp.is_some() {
                        "feasible"
                    } else {
                        "undecided"
                    }
                )),
            }
        }
    }
}

/// One outcome in a few words, for the summary.
fn describe(r: &Result<Outcome, String>) -> String {
    match r {
        Ok(Outcome::Balanced(res)) => format!("balanced (residual {res:.1e}), within bounds"),
        Ok(Outcome::RefusedInfeasible) => "refused; the LP agrees: infeasible".into(),
        Ok(Outcome::Other(status)) => format!("other status: {status}"),
        Err(_) => "FAILED (below)".into(),
    }
}

/// The library estimator at the scene's default pose with the scene's own lower bounds.
fn estimator_answer(s: &Scene) -> Result<Vec<f64>, String> {
    let pose = Pose {
        position_m: s.ee_position_m,
        orientation_wxyz: s.ee_orientation_wxyz,
    };
    match Estimator::new(s) {
        Ok(mut est) => {
            let e = est.update(&pose, Tmin::Scene);
            if e.status == Status::Ok {
                Ok(e.tensions().to_vec())
            } else {
                Err(format!("{:?}: {:?}", e.status, e.error))
            }
        }
        Err(BuildError::DefaultPose { reason, .. }) => {
            Err(format!("{:?} (build): {reason}", reason.status()))
        }
        Err(e @ (BuildError::Params(_) | BuildError::Memory(_))) => Err(e.to_string()),
    }
}

/// `cablevib analyze FILE --json --sag false [extra]`: the printed tensions, or the error.
fn printed_answer(file: &Path, extra: &[&str]) -> Result<Vec<f64>, String> {
    let o = Command::new(BIN)
        .args([
            "analyze",
            file.to_str().unwrap(),
            "--json",
            "--sag",
            "false",
        ])
        .args(extra)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    if !o.status.success() {
        return Err(err);
    }
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap_or_else(|e| {
        panic!(
            "{}: not JSON ({e}): {}",
            file.display(),
            String::from_utf8_lossy(&o.stdout)
        )
    });
    Ok(v["tensions_n"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect())
}

/// Imports every set of one robot and checks it: one summary line per set, and what is
/// wrong in `failures` (geometry and bounds of the scene fail at once).
fn check_robot(
    name: &str,
    bodies: &Path,
    cables_file: &Path,
    summary: &mut Vec<String>,
    failures: &mut Vec<String>,
) {
    let link = read_link(&std::fs::read_to_string(bodies).unwrap());
    let sets = read_sets(&std::fs::read_to_string(cables_file).unwrap(), &link);
    assert!(!sets.is_empty(), "{name}");
    for (id, cables) in sets {
        let who = format!("{name} `{id}`");
        let o = options(&id, &cables);
        if cables.iter().any(|c| c.pulley.is_some()) {
            let im = import_files(bodies, cables_file, &o).unwrap_or_else(|e| panic!("{who}: {e}"));
            check_scene(&who, &im.scene, &link, &cables, o.t_min_n);
            let arcs = check_pulleys(&who, &im.scene, &cables);
            assert!(im.not_modelled().is_some(), "{who}");
            summary.push(format!(
                "{who}: {} cables with pulleys, geometry = CASPR's (wrapped arcs {:.4}-{:.4} m)",
                cables.len(),
                arcs.0,
                arcs.1
            ));
            continue;
        }
        let im = import_files(bodies, cables_file, &o).unwrap_or_else(|e| panic!("{who}: {e}"));
        let s = &im.scene;
        check_scene(&who, s, &link, &cables, o.t_min_n);
        let lo: Vec<f64> = (0..s.n_cables()).map(|i| s.cable_t_min_n(i)).collect();
        let lib = check_tensions(
            &format!("{who} (estimator)"),
            &link,
            &cables,
            &lo,
            estimator_answer(s).as_deref().map_err(|e| e.clone()),
        );
        let file = tmp(&format!("caspr_real_{name}_{id}.toml"));
        std::fs::write(&file, &im.toml).unwrap();
        let cli = check_tensions(
            &format!("{who} (analyze)"),
            &link,
            &cables,
            &lo,
            printed_answer(&file, &[]).as_deref().map_err(|e| e.clone()),
        );
        summary.push(format!(
            "{who}: {} cables, {}; estimator: {}; analyze: {}",
            cables.len(),
            if s.rigid { "6 DOF" } else { "3 DOF" },
            describe(&lib),
            describe(&cli)
        ));
        failures.extend(lib.err());
        failures.extend(cli.err());
    }
}

/// Every robot, every set; and the T_XYZ variant of XL_Laser (its bodies file with the
/// joint T_XYZ at the same position), whose sets have attachments off the centre.
#[test]
fn every_caspr_robot_and_cable_set_imports_right() {
    let (mut summary, mut failures) = (Vec::new(), Vec::new());
    for stem in ROBOTS {
        let (b, c) = files(stem);
        let name = Path::new(stem).file_name().unwrap().to_str().unwrap();
        check_robot(name, &b, &c, &mut summary, &mut failures);
    }
    let (b, c) = files(ROBOTS[3]);
    let text = std::fs::read_to_string(&b).unwrap();
    let joint = r#"type="SPATIAL_EULER_XYZ" q_initial="2.0 1.0 2.0 0.0 0.0 0.0""#;
    assert!(text.contains(joint));
    let t_xyz = tmp("XL_Laser_T_XYZ_bodies.xml");
    std::fs::write(
        &t_xyz,
        text.replace(joint, r#"type="T_XYZ" q_initial="2.0 1.0 2.0""#),
    )
    .unwrap();
    check_robot("XL_Laser_T_XYZ", &t_xyz, &c, &mut summary, &mut failures);
    for l in &summary {
        println!("{l}");
    }
    assert_eq!(summary.len(), 35, "9 robots with 30 sets, and 5 T_XYZ sets");
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// `--solver dense` on Example_spatial, every set (force_max = 9999999999 N): exit 0 and
/// printed tensions that balance the load and respect the bounds (checked as above). It
/// printed every cable at 5 N, leaving 0.8 × the weight unbalanced, with exit 0.
#[test]
fn dense_solver_balances_example_spatial_with_unbounded_cables() {
    let (b, c) = files(ROBOTS[8]);
    let link = read_link(&std::fs::read_to_string(&b).unwrap());
    for (id, cables) in read_sets(&std::fs::read_to_string(&c).unwrap(), &link) {
        let im = import_files(&b, &c, &options(&id, &cables)).unwrap();
        let file = tmp(&format!("caspr_real_dense_{id}.toml"));
        std::fs::write(&file, &im.toml).unwrap();
        let who = format!("Example_spatial `{id}` (analyze --solver dense)");
        let t =
            printed_answer(&file, &["--solver", "dense"]).unwrap_or_else(|e| panic!("{who}: {e}"));
        let lo = vec![5.0; cables.len()];
        let out = check_tensions(&who, &link, &cables, &lo, Ok(&t));
        assert!(out.is_ok(), "{}", out.unwrap_err());
        println!("{who}: {}", describe(&out));
    }
}
