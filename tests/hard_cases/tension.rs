//! Hard cases of the tension distribution: wrenches just inside and just outside the
//! feasible set (active-set solver warm and cold, Clarabel, and the estimator), the
//! structure matrix losing rank, and wide tension ranges on the Clarabel reference.
//!
//! Every test prints what it measured (`cargo test --release --test hard_cases tension -- --nocapture`);
//! docs/hard-cases.md lists the cases, the expected behaviour and these tests. The shared
//! checks and their tolerance (real-time against the dense reference) are in
//! testkit/src/hard_cases.rs.

use cablevib::estimator::Tmin;
use cablevib::estimator::{reference_analysis, Estimator, EstimatorParams, ReferenceError, Status};
use cablevib::kinematics::{Geometry, Pose};
use cablevib::scene::Scene;
use cablevib::tension::{clarabel_reference, TensionError, TensionParams, TensionSolver};
use cablevib_testkit::hard_cases::*;
use cablevib_testkit::{rel, Rng};
use nalgebra::Vector3;

// ---------------------------------------------------------------------------------------
// Wrenches at the boundary of the feasible set
// ---------------------------------------------------------------------------------------

/// The largest s with w0 + s·d in the feasible wrench set {A T : t_min ≤ T ≤ t_max}, a
/// zonotope with centre A·c (c = (t_min + t_max)/2) and generators r·s_i (r = (t_max −
/// t_min)/2). For every normal n, n·w ≤ n·A c + r Σ|n·s_i|; the facets' normals are among
/// the cross products s_i × s_j (and s_i × axis for a planar robot), so the minimum over
/// those candidates is exact. Independent of both solvers.
fn boundary_scale(g: &Geometry, w0: &Vector3<f64>, d: &Vector3<f64>, lo: f64, hi: f64) -> f64 {
    let c = 0.5 * (lo + hi);
    let r = 0.5 * (hi - lo);
    let centre = g.unit.iter().fold(Vector3::zeros(), |a, s| a + s * c);
    let mut normals = Vec::new();
    for i in 0..g.n() {
        for j in i + 1..g.n() {
            normals.push(g.unit[i].cross(&g.unit[j]));
        }
        for ax in [Vector3::x(), Vector3::y(), Vector3::z()] {
            normals.push(g.unit[i].cross(&ax));
        }
    }
    let mut best = f64::INFINITY;
    for n in normals {
        let nn = n.norm();
        if nn < 1e-9 {
            continue;
        }
        for n in [n / nn, -n / nn] {
            let nd = n.dot(d);
            if nd <= 1e-12 {
                continue;
            }
            let h = n.dot(&centre) + r * g.unit.iter().map(|s| n.dot(s).abs()).sum::<f64>();
            best = best.min((h - n.dot(w0)) / nd);
        }
    }
    best
}

/// Wrenches scaled to the boundary of the feasible set (found exactly from the zonotope,
/// and again by bisection on the active-set solver, which must agree to 1e-9), then moved
/// 1e-6 (relative) inside and outside: the active-set solver (warm and cold) and Clarabel
/// must each put every wrench on the right side, every time; inside, the tensions satisfy
/// the bounds and A T = w. Then through the estimator: the end-effector mass scaled so its
/// weight sits 1e-6 inside / outside the boundary.
#[test]
fn wrenches_just_inside_and_just_outside_the_feasible_set() {
    let spatial = Scene::default_scene();
    let planar = Scene::planar_paper();
    let mut rng = Rng(0x5EED_0006);
    let mut checked = 0;
    let mut worst_bisect = 0.0f64;
    let mut failures: Vec<String> = Vec::new();
    let poses = [
        (&spatial, Vector3::new(0.0, 0.0, 1.25)),
        (&spatial, Vector3::new(0.3, 0.2, 1.0)),
        (&spatial, Vector3::new(-0.9, 0.7, 2.1)),
        (&planar, Vector3::new(0.0, 0.0, 0.0)),
        (&planar, Vector3::new(0.8, -0.5, 0.0)),
    ];
    for (s, p) in poses {
        let g = geometry(s, &p);
        let (lo, hi) = (s.t_min_n, s.t_max_n);
        let n = s.n_cables();
        let w0 = g
            .unit
            .iter()
            .fold(Vector3::zeros(), |a, u| a + u * (0.5 * (lo + hi)));
        let mut warm = TensionSolver::new(n, TensionParams::default());
        for k in 0..40 {
            let mut d = rng.unit();
            if s.name == "planar-paper" {
                d.z = 0.0;
                d.normalize_mut();
            }
            let sstar = boundary_scale(&g, &w0, &d, lo, hi);
            assert!(sstar.is_finite() && sstar > 0.0, "{sstar}");
            // Bisection on the active-set solver.
            let mut cold = TensionSolver::new(n, TensionParams::default());
            let (mut a, mut b) = (0.0, 2.0 * sstar);
            for _ in 0..80 {
                let m = 0.5 * (a + b);
                if cold.solve(&g, &(w0 + d * m), lo, hi).is_ok() {
                    a = m;
                } else {
                    b = m;
                }
            }
            let eb = rel(0.5 * (a + b), sstar);
            worst_bisect = worst_bisect.max(eb);
            if eb > 1e-9 {
                failures.push(format!(
                    "{} {p:?} dir {k}: bisection boundary {} vs exact {sstar}: {eb:.2e}",
                    s.name,
                    0.5 * (a + b)
                ));
            }
            for (side, f) in [("inside", 1.0 - 1e-6), ("outside", 1.0 + 1e-6)] {
                let w = w0 + d * (sstar * f);
                let label = format!("{} {p:?} dir {k} {side}", s.name);
                let mut fresh = TensionSolver::new(n, TensionParams::default());
                let r_cold = fresh.solve(&g, &w, lo, hi).map(|t| t.to_vec());
                let r_warm = warm.solve(&g, &w, lo, hi).map(|t| t.to_vec());
                let r_cl = clarabel_reference(&g, &w, lo, hi);
                for (who, r) in [
                    ("active-set cold", &r_cold),
                    ("active-set warm", &r_warm),
                    ("clarabel", &r_cl),
                ] {
                    match (side, r) {
                        ("inside", Ok(t)) => {
                            let tol = 1e-9 * hi;
                            let bad_bound = t.iter().any(|&x| x < lo - tol || x > hi + tol);
                            let res = (g.wrench_of(t) - w).amax();
                            if bad_bound || res > 1e-8 * hi {
                                failures.push(format!(
                                    "{label} {who}: tensions {t:?} residual {res:.2e}"
                                ));
                            }
                        }
                        ("outside", Err(TensionError::Infeasible { .. })) => {}
                        (_, r) => failures.push(format!("{label} {who}: wrong side: {r:?}")),
                    }
                }
                checked += 1;
            }
        }
    }
    // Through the estimator: the weight itself at the boundary (centre pose, gravity down).
    let s = &spatial;
    let g = geometry(s, &s.ee_position_m);
    let d = s.gravity_m_s2.normalize();
    let wmax = boundary_scale(&g, &Vector3::zeros(), &d, s.t_min_n, s.t_max_n);
    let m_star = wmax / s.gravity_m_s2.norm();
    for (f, want) in [
        (1.0 - 1e-6, Status::Ok),
        (1.0 + 1e-6, Status::TensionInfeasible),
    ] {
        let mut sc = s.clone();
        sc.ee_mass_kg = m_star * f;
        sc.ee_position_m = Vector3::new(0.0, 0.0, 1.0); // build at a roomier pose
        let mut est = Estimator::new(&sc).unwrap();
        let e = *est.update(&Pose::at(s.ee_position_m), Tmin::Scene);
        if e.status != want {
            failures.push(format!(
                "estimator m = {} kg: {:?} ({:?}), want {want:?}",
                sc.ee_mass_kg, e.status, e.error
            ));
        }
    }
    eprintln!(
        "feasible-set boundary: {checked} wrenches × 3 solvers; bisection vs exact ≤ {worst_bisect:.1e}; m* = {m_star:.6} kg"
    );
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

// ---------------------------------------------------------------------------------------
// Rank loss, wide tension ranges
// ---------------------------------------------------------------------------------------

/// Poses where the structure matrix loses rank. For a point mass, rank 2 means every anchor
/// is in one plane with the end-effector; a scene whose default pose has rank 3 then
/// needs a wrench component out of that plane, which a rank-2 pose cannot produce: the
/// right status is TensionInfeasible (both solvers), never an ok estimate built on a
/// singular structure matrix. The suspended robot rises to its anchor plane: while
/// feasible, ok and equal to dense; tension grows like mg·L/(4δ) and crosses t_max; at
/// and near the plane, infeasible. The planar robot (rank 2 by design) carries no
/// out-of-plane wrench: asking for one is infeasible on f_z.
///
#[test]
fn structure_matrix_losing_rank() {
    let s = suspended_scene();
    let params = EstimatorParams::default();
    let mut seen_ok = 0;
    let mut seen_infeasible = 0;
    for delta in [0.5, 1e-1, 1e-2, 1e-3, 1e-4, 1e-6, 1e-9, 1e-12, 0.0] {
        for x in [0.0, 0.3] {
            let p = Vector3::new(x, 0.1, 2.0 - delta);
            let label = format!("suspended δ {delta:e} x {x}");
            let e = *Estimator::with_params(&s, params)
                .unwrap()
                .update(&Pose::at(p), Tmin::Scene);
            let r = reference_analysis(&s, &p, Tmin::Scene, true);
            match e.status {
                Status::Ok => {
                    seen_ok += 1;
                    assert_sane(&label, &e, &s, s.t_min_n);
                    let r = r.unwrap_or_else(|err| panic!("{label}: dense {err}"));
                    assert_matches_dense(&label, &s, &e, &r);
                }
                Status::TensionInfeasible => {
                    seen_infeasible += 1;
                    assert_no_numbers(&label, &e);
                    assert!(
                        matches!(
                            r,
                            Err(ReferenceError::Tension(TensionError::Infeasible { .. }))
                        ),
                        "{label}: real-time infeasible, dense {:?}",
                        r.map(|r| r.tensions_n)
                    );
                    if delta == 0.0 {
                        let msg = e.error.unwrap().to_string();
                        assert!(msg.contains("f_z"), "{label}: {msg}");
                    }
                }
                other => panic!("{label}: unexpected status {other:?} {:?}", e.error),
            }
            if delta <= 1e-3 {
                assert_eq!(e.status, Status::TensionInfeasible, "{label}");
            }
        }
    }
    assert!(
        seen_ok >= 4 && seen_infeasible >= 8,
        "{seen_ok} {seen_infeasible}"
    );
    // The planar robot: rank 2 everywhere in its plane; an out-of-plane wrench is infeasible.
    let pl = Scene::planar_paper();
    let g = geometry(&pl, &Vector3::new(0.4, -0.3, 0.0));
    let mut ts = TensionSolver::new(4, TensionParams::default());
    ts.solve(&g, &Vector3::new(5.0, -3.0, 0.0), 20.0, 250.0)
        .unwrap();
    assert_eq!(ts.info().rank, 2);
    let w = Vector3::new(5.0, -3.0, 1.0);
    let e = ts.solve(&g, &w, 20.0, 250.0).unwrap_err();
    assert!(e.to_string().contains("f_z"), "{e}");
    assert!(matches!(
        clarabel_reference(&g, &w, 20.0, 250.0),
        Err(TensionError::Infeasible { .. })
    ));
}

/// The tension QP at wide bound ratios (t_min → 0 with t_max fixed, or t_max ≫ t_min): the
/// active-set solver and the Clarabel reference must agree to 1e-9·t_max. (The near-slack
/// and heavy end-effector cases need exactly these ranges; the dense reference takes its
/// tensions from Clarabel.)
#[test]
fn clarabel_reference_handles_wide_tension_ranges() {
    let spatial = Scene::default_scene();
    let planar = Scene::planar_paper();
    let mut failures = Vec::new();
    let cases: Vec<(&Scene, Vector3<f64>, f64, f64, f64)> = vec![
        // (scene, position, ee mass, t_min, t_max)
        (&planar, Vector3::zeros(), 5.0, 1e-3, 250.0),
        (&planar, Vector3::zeros(), 5.0, 1e-1, 250.0),
        (&planar, Vector3::zeros(), 5.0, 1e-6, 250.0),
        (&planar, Vector3::new(0.5, 0.2, 0.0), 5.0, 1e-6, 250.0),
        (&spatial, Vector3::new(0.3, 0.2, 1.0), 30.0, 1e-6, 350.0),
        (&spatial, Vector3::new(0.3, 0.2, 1.0), 1e-3, 60.0, 1e6),
        (&spatial, Vector3::new(0.3, 0.2, 1.0), 10.0, 60.0, 1e6),
        (&spatial, Vector3::new(0.3, 0.2, 1.0), 30.0, 60.0, 1e5),
    ];
    for (s, p, m, lo, hi) in cases {
        let mut sc = s.clone();
        sc.ee_mass_kg = m;
        let g = geometry(&sc, &p);
        let w = sc.wrench_n();
        let mut ts = TensionSolver::new(sc.n_cables(), TensionParams::default());
        let a = ts.solve(&g, &w, lo, hi).unwrap().to_vec();
        match clarabel_reference(&g, &w, lo, hi) {
            Ok(c) => {
                let d = a.iter().zip(&c).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
                if d > 1e-9 * hi {
                    failures.push(format!("{} {p:?} m {m} [{lo:e}, {hi:e}]: differ by {d:.2e} N", s.name));
                }
            }
            Err(e) => failures.push(format!(
                "{} {p:?} m {m} kg, bounds [{lo:e}, {hi:e}] N: clarabel_reference: {e} (active set: {a:.6?})",
                s.name
            )),
        }
    }
    assert!(
        failures.is_empty(),
        "clarabel_reference failed on {} feasible QPs:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// Upper bounds many orders above the load (CASPR's "unbounded" force_max = 9999999999 N):
/// the Clarabel reference must still balance the wrench. Independent check: A T − w formed
/// here from the geometry's unit vectors, relative to the load scale max(|w|, Σ|T_i|), at
/// most 1e-9 (the reference polishes on the KKT system of its active set, exact to a few
/// roundings); and the active-set solver's answer, which does not depend on t_max when no
/// cable reaches it, agrees to 1e-9 of the largest tension.
#[test]
fn clarabel_reference_balances_the_load_with_huge_upper_bounds() {
    let spatial = Scene::default_scene();
    let mut checked = 0;
    for (p, m, lo) in [
        (Vector3::new(0.3, 0.2, 1.0), 1.0, 5.0),
        (Vector3::new(0.0, 0.0, 1.2), 1.0, 5.0),
        (Vector3::new(-0.4, 0.3, 0.8), 3.0, 1.0),
        (Vector3::new(0.3, 0.2, 1.0), 30.0, 60.0),
    ] {
        for hi in [1e7, 9_999_999_999.0, 1e15] {
            let mut sc = spatial.clone();
            sc.ee_mass_kg = m;
            let g = geometry(&sc, &p);
            let w = sc.wrench_n();
            let t = clarabel_reference(&g, &w, lo, hi)
                .unwrap_or_else(|e| panic!("{p:?} m {m} [{lo}, {hi:e}]: {e}"));
            let f = t
                .iter()
                .zip(&g.unit)
                .fold(Vector3::zeros(), |a, (ti, s)| a + s * *ti);
            let scale = w.norm().max(t.iter().map(|x| x.abs()).sum());
            let res = (f - w).norm() / scale;
            assert!(
                res <= 1e-9,
                "{p:?} m {m} [{lo}, {hi:e}]: residual {res:.3e} of the load, tensions {t:.4?}"
            );
            assert!(t.iter().all(|&x| x >= lo && x <= hi), "{t:?}");
            let mut ts = TensionSolver::new(sc.n_cables(), TensionParams::default());
            let a = ts.solve(&g, &w, lo, 350.0).unwrap().to_vec();
            let tmax = a.iter().copied().fold(0.0, f64::max);
            let d = a
                .iter()
                .zip(&t)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            assert!(
                d <= 1e-9 * tmax,
                "{p:?} m {m} [{lo}, {hi:e}]: differ by {d:.2e} N"
            );
            checked += 1;
        }
    }
    println!("{checked} reference answers with t_max up to 1e15 N balanced the load");
}
