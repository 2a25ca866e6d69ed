//! The independent sagged-cable reference (tests/py/sag_reference.py: a sagged-equilibrium
//! FE model of a whole robot in numpy/scipy, no code shared with the crate) checked on its
//! own: against closed forms of a single cable written out here (Irvine's shallow-cable
//! frequencies, the inextensible catenary's cosh profile), for its equilibrium residual, its
//! exact tangent, its convergence in the element count (order 2) and the symmetry of a
//! symmetric robot; and the two sagging scenes (scenes/fast_like.toml,
//! scenes/suspended_8.toml) checked with the crate's chord model at their suggested poses.
//!
//! The reference runs in a venv under target/ with pinned numpy and scipy (see
//! testkit/src/sag_reference_py.rs; needs `python3` with venv and PyPI). The helper
//! `reference_at(scene, pose, l0, modes)` is the entry point for comparisons with the
//! crate's sagged model.

use cablevib_testkit::sag_reference_py::{
    f64s, reference_at, run_reference, scene_request, RefAnswer, LEVELS,
};
use serde_json::{json, Value};
use std::f64::consts::PI;

const G: f64 = 9.81;

/// The suggested poses of the sagging scenes: (scene file, centre, off-centre), m.
const SCENE_POSES: [(&str, [f64; 3], [f64; 3]); 2] = [
    ("scenes/fast_like.toml", [0.0, 0.0, 0.0], [60.0, 30.0, 10.0]),
    ("scenes/suspended_8.toml", [0.0, 0.0, 2.0], [4.0, 2.5, 1.5]),
];

fn scene_path(rel: &str) -> String {
    format!("{}/{rel}", concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

/// `cablevib analyze SCENE --position P --json` (the crate's chord model) parsed.
fn analyze(scene: &str, p: [f64; 3]) -> Value {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_cablevib"))
        .args(["analyze", scene, "--json", "--position"])
        .arg(format!("{},{},{}", p[0], p[1], p[2]))
        .output()
        .expect("run cablevib");
    assert!(
        out.status.success(),
        "analyze {scene} at {p:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("analyze JSON")
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

// ---------------------------------------------------------------------------------------
// A single level cable against Irvine's linear theory

/// Irvine's symmetric in-plane roots: tan(β/2) = β/2 − (4/λ²)(β/2)³, the k-th in
/// ((2k+1)π, (2k+3)π) (between two poles of tan(β/2), where the left side rises from −∞ to
/// +∞ and the right side is finite), by bisection to rounding.
fn irvine_symmetric_beta(lambda2: f64, k: usize) -> f64 {
    let f = |b: f64| (b / 2.0).tan() - b / 2.0 + 4.0 / lambda2 * (b / 2.0).powi(3);
    let (mut lo, mut hi) = (
        (2 * k + 1) as f64 * PI + 1e-12,
        (2 * k + 3) as f64 * PI - 1e-12,
    );
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Relative differences of the reference's first 8 frequencies of a level cable of span
/// L = 100 m, H ≈ 1000 N and sag ratio d/L at λ² ≈ 20 from Irvine's shallow-cable theory:
/// out of plane f = k/(2L) √(H/m); in plane antisymmetric f = k/L √(H/m), symmetric
/// f = β/(2πL) √(H/m) with m the mass per unit span, λ² = (m g L/H)² L EA/(H L_e),
/// L_e = L (1 + 8 (d/L)²), d = m g L²/(8H). H is the reference's own (extrapolated).
fn irvine_differences(sag_ratio: f64) -> Vec<f64> {
    let (span, h_target, lambda2) = (100.0, 1000.0, 20.0);
    let w = 8.0 * h_target * sag_ratio / span;
    // λ² = 64 (d/L)² EA/H for a shallow cable: choose EA for λ² ≈ 20.
    let ea = h_target * lambda2 / (64.0 * sag_ratio * sag_ratio);
    // The shallow cable's length L (1 + 8/3 (d/L)²), less the stretch H/EA: any nearby
    // L0 will do, the closed forms use the reference's own H.
    let l0 = span * (1.0 + 8.0 / 3.0 * sag_ratio * sag_ratio - h_target / ea);
    let req = json!({
        "anchors_m": [[0.0, 0.0, 0.0]], "ee_position_m": [span, 0.0, 0.0], "end_fixed": true,
        "gravity_m_s2": [0.0, 0.0, -G], "ea_n": ea, "mu_kg_m": w / G,
        "unstretched_lengths_m": l0, "modes": 8, "convergence_levels": LEVELS,
    });
    let a = RefAnswer(run_reference(&req));
    let f = a.extrapolated("frequencies_hz");
    let h = a.extrapolated("h_n")[0];
    let share = f64s(&a.0["eigen"]["plane_normal_share"]);
    let m = w / G * l0 / span;
    let c = (h / m).sqrt();
    let d = m * G * span * span / (8.0 * h);
    let le = span * (1.0 + 8.0 * (d / span).powi(2));
    let l2 = (m * G * span / h).powi(2) * span * ea / (h * le);
    let mut in_plane: Vec<f64> = (0..3)
        .map(|k| irvine_symmetric_beta(l2, k) / (2.0 * PI * span) * c)
        .chain((1..=4).map(|k| k as f64 / span * c))
        .collect();
    in_plane.sort_by(f64::total_cmp);
    let (mut io, mut ii) = (0, 0);
    let mut out = Vec::new();
    for (fj, s) in f.iter().zip(&share) {
        // Out-of-plane modes carry all their kinetic energy normal to the cable's plane
        // (the directions decouple exactly for a level cable), in-plane modes none.
        assert!(*s < 1e-9 || *s > 1.0 - 1e-9, "mixed mode: share {s}");
        let irvine = if *s > 0.5 {
            io += 1;
            io as f64 / (2.0 * span) * c
        } else {
            ii += 1;
            in_plane[ii - 1]
        };
        eprintln!("d/L {sag_ratio}: λ² {l2:.4} f {fj:.9} Hz vs Irvine {irvine:.9}, share {s:.3}");
        out.push((fj - irvine) / irvine);
    }
    out
}

/// Irvine's theory is the leading order of a shallow cable as d/L → 0 at fixed λ²; what it
/// neglects is O((d/L)²) (measured: |difference| ≤ 3.9 (d/L)² for the first 8 modes, the
/// in-plane antisymmetric mode the largest). So: at d/L = 1/400 every one of the first 8
/// frequencies is within 5 (d/L)² = 3.1e-5 of Irvine's, and halving d/L divides each
/// difference by 4 (within ±20 %: the Richardson-extrapolated FE error, ≲ 1e-9, and the
/// next order (d/L)⁴ stay far below). A reference with a wrong mass, tension or
/// elasticity would miss both.
#[test]
fn a_shallow_level_cable_has_irvines_frequencies() {
    let coarse = irvine_differences(1.0 / 400.0);
    let fine = irvine_differences(1.0 / 800.0);
    for (j, (a, b)) in coarse.iter().zip(&fine).enumerate() {
        let bound = 5.0 * (1.0f64 / 400.0).powi(2);
        eprintln!(
            "mode {j}: {a:+.3e} at d/L = 1/400, {b:+.3e} at 1/800, ratio {:.3}",
            a / b
        );
        assert!(a.abs() <= bound, "mode {j}: {a:e} > {bound:e}");
        assert!((3.2..=4.8).contains(&(a / b)), "mode {j}: ratio {}", a / b);
    }
}

// ---------------------------------------------------------------------------------------
// A deep, inclined, nearly inextensible cable against the cosh profile

/// The inextensible catenary of length l0 from (0, 0) to (x, z): (a = H/w, u₁) with
/// √(l0² − z²) = 2a sinh(x/(2a)) (bisection in a) and u₁ the anchor's parameter; the point
/// at arclength s is (a (u − u₁), a (cosh u − cosh u₁)) with sinh u = sinh u₁ + s/a.
fn cosh_catenary(x: f64, z: f64, l0: f64) -> (f64, f64) {
    let target = (l0 * l0 - z * z).sqrt();
    let g = |a: f64| 2.0 * a * (x / (2.0 * a)).sinh() - target;
    let (mut lo, mut hi) = (x / 50.0, 1e3 * x);
    assert!(g(lo) > 0.0 && g(hi) < 0.0, "bracket");
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let a = 0.5 * (lo + hi);
    let mid = (z / (2.0 * a * (x / (2.0 * a)).sinh())).asinh();
    (a, mid - x / (2.0 * a))
}

/// A cable of L0 = 130 m between supports 100 m apart and 20 m apart in height (sag ~ 30 %
/// of the span), EA = 1e9 N ≈ 2.5e7 × its tension: the elastic stretch moves the profile by
/// ~T/EA relative (≲ 1e-7 · L0 after the deep-sag amplification, measured H shift 1.5e-7 at
/// EA = 1e8 vs 1e9). The reference's nodes at s = k L0/80, Richardson-extrapolated over 80,
/// 160, 320 elements, lie on the cosh profile at the same arclength within 1e-6 · L0, and
/// its H within 1e-6 of w a.
#[test]
fn a_deep_stiff_cable_hangs_on_the_cosh_curve() {
    let (x, z, l0, w, ea) = (100.0, 20.0, 130.0, 1.0, 1e9);
    let req = json!({
        "anchors_m": [[0.0, 0.0, 0.0]], "ee_position_m": [x, 0.0, z], "end_fixed": true,
        "gravity_m_s2": [0.0, 0.0, -G], "ea_n": ea, "mu_kg_m": w / G,
        "unstretched_lengths_m": l0, "modes": 0, "convergence_levels": LEVELS,
        "return_nodes": true,
    });
    let ans = RefAnswer(run_reference(&req));
    for n in LEVELS {
        let lv = ans.at_level(n);
        assert_eq!(
            lv["converged"],
            json!(true),
            "{n}: {}",
            lv["residual_history_n"]
        );
    }
    let nodes = |n: usize| -> Vec<Vec<f64>> {
        ans.at_level(n)["nodes_m"][0]
            .as_array()
            .expect("nodes")
            .iter()
            .map(f64s)
            .collect()
    };
    let (n160, n320) = (nodes(160), nodes(320));
    let (a, u1) = cosh_catenary(x, z, l0);
    let mut worst = 0.0f64;
    for k in 0..=80 {
        let s = l0 * k as f64 / 80.0;
        let u = (u1.sinh() + s / a).asinh();
        let exact = [a * (u - u1), 0.0, a * (u.cosh() - u1.cosh())];
        for i in 0..3 {
            // Order-2 Richardson of the two finest levels (the same point s on both).
            let p = n320[4 * k][i] + (n320[4 * k][i] - n160[2 * k][i]) / 3.0;
            worst = worst.max((p - exact[i]).abs() / l0);
        }
    }
    let h = ans.extrapolated("h_n")[0];
    eprintln!(
        "cosh profile: worst node {worst:.2e} L0, H {h} vs w a {}",
        w * a
    );
    assert!(worst <= 1e-6, "profile off by {worst:e} L0");
    assert!(rel(h, w * a) <= 1e-6, "H {h} vs {}", w * a);
}

// ---------------------------------------------------------------------------------------
// Whole robots: the sagging scenes at their suggested poses

/// The reference for `scene` at `p` with L0 chosen so the continuous catenaries balance the
/// end-effector at p, nearest (relative least squares) to the chord model's tensions.
fn balanced_reference(scene: &str, p: [f64; 3], modes: usize) -> (RefAnswer, Vec<f64>) {
    let chord = f64s(&analyze(scene, p)["tensions_n"]);
    let s = cablevib::scene::Scene::load(scene).expect("scene");
    let mut req = scene_request(&s, p);
    req.insert("end_tensions_n".into(), json!(chord));
    req.insert("modes".into(), json!(modes));
    req.insert("convergence_levels".into(), json!(LEVELS));
    req.insert("tangent_check".into(), json!(true));
    (RefAnswer(run_reference(&Value::Object(req))), chord)
}

/// Every level converged to its stated residual with an exact tangent, and every quantity
/// converges at order 2 in the element count (the FE of a smooth problem; observed 2 ± 0.05
/// wherever the level differences are above rounding).
fn check_levels(name: &str, a: &RefAnswer) {
    for n in LEVELS {
        let lv = a.at_level(n);
        let (r, tol) = (
            lv["residual_max_n"].as_f64().unwrap(),
            lv["residual_tol_n"].as_f64().unwrap(),
        );
        assert_eq!(lv["converged"], json!(true), "{name} {n}: {r} > {tol}");
        assert!(r <= tol, "{name} {n}: residual {r} > {tol}");
        // Central differences of R at a relative step 1e-6: truncation ~1e-12, rounding
        // ~ε/1e-6 ≈ 2e-10 of the forces.
        let fd = lv["tangent_fd_rel_diff"].as_f64().unwrap();
        assert!(fd <= 1e-7, "{name} {n}: tangent vs differences {fd:e}");
        assert_eq!(lv["eigen"]["negative_eigenvalues"], json!(0), "{name} {n}");
        eprintln!(
            "{name} n = {n}: {} Newton steps, residual {r:.2e} N (tol {tol:.2e}), {:.3} s",
            lv["newton_iterations"], lv["time_s"]["total"]
        );
    }
    let orders = a.0["richardson"]["observed_order"]
        .as_object()
        .expect("orders");
    for (key, ps) in orders {
        if key == "ee_position_m" {
            continue; // ~0 by construction at the balanced pose (checked below)
        }
        for (j, p) in ps.as_array().unwrap().iter().enumerate() {
            let p = p.as_f64().expect("order");
            assert!((p - 2.0).abs() <= 0.05, "{name}: {key}[{j}] order {p}");
        }
    }
}

/// At a pose where the continuous catenaries balance the end-effector (L0 chosen so), the
/// FE model's equilibrium converges to that pose and to the catenaries' end tensions: an
/// independent check of the FE (discrete chains, Newton) against the elastic catenary
/// closed form (Irvine's, solved per cable): extrapolated position within 1e-9 of the
/// span, tensions within 1e-7 relative (Richardson leaves O(N⁻⁴) ≈ 1e-9 here).
#[test]
fn sagging_robots_converge_to_their_balanced_poses() {
    for (file, centre, off) in SCENE_POSES {
        let scene = scene_path(file);
        for p in [centre, off] {
            let (a, chord) = balanced_reference(&scene, p, 10);
            let name = format!("{file} at {p:?}");
            check_levels(&name, &a);
            let ee = a.extrapolated("ee_position_m");
            let span = 100.0f64.max(p.iter().map(|x| x.abs()).fold(0.0, f64::max));
            for i in 0..3 {
                assert!((ee[i] - p[i]).abs() <= 1e-9 * span, "{name}: ee {ee:?}");
            }
            let chosen = f64s(&a.0["chosen"]["end_tensions_n"]);
            let t = a.extrapolated("tension_ee_n");
            for (i, (ti, ci)) in t.iter().zip(&chosen).enumerate() {
                assert!(rel(*ti, *ci) <= 1e-7, "{name}: cable {i} {ti} vs {ci}");
            }
            eprintln!("{name}: chord tensions {chord:?}\n  sagged {t:?}");
            eprintln!("  L0 {}", a.0["chosen"]["unstretched_lengths_m"]);
            eprintln!("  f {:?}", a.extrapolated("frequencies_hz"));
            eprintln!("  k {:?}", a.extrapolated("stiffness_principal_n_m"));
            eprintln!("  wall {:.2} s", a.0["wall_time_s"].as_f64().unwrap());
        }
    }
}

/// The fast-like robot at its centre is symmetric under rotations by 60° about the vertical:
/// six equal tensions (to 1e-9 relative: Newton's residual 1e-10 of the weight, the
/// catenary solves to ~1e-13) and two equal lateral principal stiffnesses (1e-8).
#[test]
fn the_fast_like_centre_is_symmetric() {
    let scene = scene_path("scenes/fast_like.toml");
    let s = cablevib::scene::Scene::load(&scene).expect("scene");
    let mut req = scene_request(&s, [0.0; 3]);
    req.insert("end_tensions_n".into(), json!(vec![88426.0; 6]));
    req.insert("modes".into(), json!(6));
    req.insert("elements".into(), json!(160));
    req.insert("dense_check".into(), json!(true));
    let a = run_reference(&Value::Object(req));
    let cables = a["cables"].as_array().unwrap();
    let t0 = cables[0]["tension_ee_n"].as_f64().unwrap();
    for c in cables {
        assert!(rel(c["tension_ee_n"].as_f64().unwrap(), t0) <= 1e-9, "{c}");
        assert!(
            rel(
                c["tension_anchor_n"].as_f64().unwrap(),
                cables[0]["tension_anchor_n"].as_f64().unwrap()
            ) <= 1e-9
        );
    }
    let k = f64s(&a["stiffness_principal_n_m"]);
    let kz = a["stiffness_matrix_n_m"][2][2].as_f64().unwrap();
    eprintln!("fast-like centre: T {t0} N, k {k:?} N/m, kzz {kz}");
    // The lateral pair: the two principal values other than the vertical one.
    let lateral: Vec<f64> = k.iter().copied().filter(|x| rel(*x, kz) > 1e-6).collect();
    assert_eq!(lateral.len(), 2, "{k:?} vs kzz {kz}");
    assert!(rel(lateral[0], lateral[1]) <= 1e-8, "{lateral:?}");
    // The sparse shift-invert eigensolver against a dense one on the same matrices (dense
    // relative accuracy ~ε λ_max/λ ≈ 1e-9 here).
    let dd = a["eigen"]["dense_max_rel_diff"].as_f64().unwrap();
    assert!(dd <= 1e-7, "eigsh vs dense {dd:e}");
}

/// The comparison helper `reference_at` (scene by embedded name, pose, L0) reproduces the
/// balanced answer when given the L0 the balance chose: the same model on the same input,
/// so tensions, stiffness and frequencies agree to rounding (1e-9 relative).
#[test]
fn reference_at_takes_a_scene_name_a_pose_and_l0() {
    let p = [4.0, 2.5, 1.5];
    let (balanced, _) = balanced_reference(&scene_path("scenes/suspended_8.toml"), p, 4);
    let l0 = f64s(&balanced.0["chosen"]["unstretched_lengths_m"]);
    let a = reference_at("suspended-8", p, &l0, 4);
    for key in [
        "tension_ee_n",
        "tension_anchor_n",
        "stiffness_principal_n_m",
        "frequencies_hz",
    ] {
        for (x, y) in a.extrapolated(key).iter().zip(balanced.extrapolated(key)) {
            assert!(rel(*x, y) <= 1e-9, "{key}: {x} vs {y}");
        }
    }
    let lv = a.at_level(160);
    assert_eq!(RefAnswer::cable_values(lv, "tension_ee_n").len(), 8);
}

/// The scenes load in the crate and their suggested poses are tension-feasible in the
/// chord model with every tension inside the scene's bounds.
#[test]
fn the_sagging_scenes_are_feasible_in_the_chord_model() {
    for (file, centre, off) in SCENE_POSES {
        let scene = scene_path(file);
        let s = cablevib::scene::Scene::load(&scene).expect("scene");
        for p in [centre, off] {
            let t = f64s(&analyze(&scene, p)["tensions_n"]);
            assert_eq!(t.len(), s.n_cables());
            for ti in &t {
                assert!(
                    *ti >= s.t_min_n * (1.0 - 1e-9) && *ti <= s.t_max_n,
                    "{file} {p:?}: {t:?}"
                );
            }
        }
    }
}
