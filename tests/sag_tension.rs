//! The tension distribution with sagging cables (`tension::SagTensionSolver`): weightless
//! cables give the chord solver's tensions, heavy cables are in equilibrium (checked from
//! the catenaries' own end forces and end points, not from the solver's residual), the
//! solve does not allocate, and a timing print (ignored test).
#![allow(clippy::needless_range_loop)] // index loops mirror the per-cable maths
use cablevib::alloc_count::{thread_allocations, CountingAlloc};
use cablevib::kinematics::{rotation_of, Geometry};
use cablevib::scene::Scene;
use cablevib::tension::{
    SagCable, SagTensionError, SagTensionParams, SagTensionSolver, TensionParams, TensionSolver,
};
use nalgebra::Vector3;

#[global_allocator]
static A: CountingAlloc = CountingAlloc;

fn geometry(s: &Scene, p: Vector3<f64>) -> Geometry {
    let mut g = Geometry::new(s.n_cables());
    if s.rigid {
        let rot = rotation_of(&s.ee_orientation_wxyz);
        g.update_rigid(
            s.cables.iter().map(|c| &c.anchor_m),
            s.cables.iter().map(|c| &c.attachment_m),
            &p,
            &rot,
        )
        .unwrap();
    } else {
        g.update(s.cables.iter().map(|c| &c.anchor_m), &p).unwrap();
    }
    g
}

fn wrench6(s: &Scene) -> [f64; 6] {
    let f = s.wrench_n();
    [f.x, f.y, f.z, 0.0, 0.0, 0.0]
}

fn materials(s: &Scene, w_n_m: f64) -> Vec<SagCable> {
    s.cables
        .iter()
        .map(|c| SagCable {
            ea_n: c.ea_n(),
            w_n_m,
        })
        .collect()
}

fn bounds(s: &Scene, t_min: f64) -> (Vec<f64>, Vec<f64>) {
    let n = s.n_cables();
    (vec![t_min; n], (0..n).map(|i| s.cable_t_max_n(i)).collect())
}

/// Weightless cables: the end tangents are the chords, so the tensions are the chord
/// solver's. Both QPs see the same matrix up to the catenary's rounding of the unit vector
/// (a few ulps), so 1e-12 relative (the QP's conditioning is moderate at these poses).
#[test]
fn weightless_cables_give_the_chord_tensions() {
    for s in [Scene::default_scene(), Scene::box_6dof()] {
        let n = s.n_cables();
        let (lo, hi) = bounds(&s, s.t_min_n);
        let mut sag = SagTensionSolver::new(n, SagTensionParams::default());
        let mut chord = TensionSolver::new(n, TensionParams::default());
        let off = if s.rigid { 0.05 } else { 0.3 };
        for p in [
            s.ee_position_m,
            s.ee_position_m + Vector3::new(off, -off / 2.0, off / 3.0),
        ] {
            let g = geometry(&s, p);
            let want = chord
                .solve_wrench_bounds(&g, &wrench6(&s), &lo, &hi)
                .unwrap()
                .to_vec();
            let got = sag
                .solve(
                    &g,
                    &materials(&s, 0.0),
                    &s.gravity_m_s2,
                    &wrench6(&s),
                    &lo,
                    &hi,
                )
                .unwrap()
                .to_vec();
            for i in 0..n {
                assert!(
                    (got[i] - want[i]).abs() <= 1e-12 * want[i],
                    "{p:?} cable {i}: {} vs {}",
                    got[i],
                    want[i]
                );
            }
        }
    }
}

/// The paper's spatial robot with 50× heavier cables (12.55 N/m), t_min 30 N: the force on
/// the end-effector, recomputed from each catenary's own end force −(H h + V_e up) and
/// the (public) plane basis, balances the weight to 1e-9 of it; each catenary ends at its
/// attachment point (1e-12 of the chord); the sag changed the tensions (not the chord
/// answer), the anchor and minimum tensions are consistent.
#[test]
fn heavy_cables_are_in_equilibrium() {
    let s = Scene::default_scene();
    let n = s.n_cables();
    let (lo, hi) = bounds(&s, 30.0);
    let mats = materials(&s, 12.55);
    let mut sag = SagTensionSolver::new(n, SagTensionParams::default());
    let mut chord = TensionSolver::new(n, TensionParams::default());
    let weight = s.wrench_n().norm();
    for p in [
        s.ee_position_m,
        s.ee_position_m + Vector3::new(0.3, 0.2, 0.0),
    ] {
        let g = geometry(&s, p);
        let t = sag
            .solve(&g, &mats, &s.gravity_m_s2, &wrench6(&s), &lo, &hi)
            .unwrap()
            .to_vec();
        let mut force = s.gravity_m_s2 * s.ee_mass_kg;
        for i in 0..n {
            let c = sag.catenaries_of()[i];
            let [h, up, _] = sag.basis(i);
            force -= h * c.h_n + up * c.v_end_n();
            let end = c.end_point_m();
            let chord_vec = g.unit[i] * g.length_m[i];
            let world = h * end[0] + up * end[1];
            assert!(
                (world - chord_vec).amax() <= 1e-12 * g.length_m[i],
                "{p:?} cable {i}: end {world:?} vs {chord_vec:?}"
            );
            // T_e = hypot(T cos φ, T sin φ) returns T to an ulp.
            assert!(
                (c.tension_end_n() - t[i]).abs() <= 4e-16 * t[i],
                "{} vs {}",
                c.tension_end_n(),
                t[i]
            );
            // The catenary's own end tension (equal to T_e to an ulp, above).
            let t_min_along = sag.tension_min_n(i);
            assert!(
                t_min_along <= c.tension_end_n().min(sag.tension_anchor_n(i)),
                "cable {i}: min {t_min_along} N above an end's tension"
            );
        }
        assert!(
            force.amax() <= 1e-9 * weight,
            "{p:?}: residual force {force:?} N"
        );
        assert!(
            sag.info().residual_force_n <= 1e-9 * weight,
            "{:?}",
            sag.info()
        );
        let c = chord
            .solve_wrench_bounds(&g, &wrench6(&s), &lo, &hi)
            .unwrap();
        assert!(
            t.iter().zip(c).any(|(a, b)| (a - b).abs() > 1e-3 * b),
            "sag changed nothing"
        );
    }
}

/// A cable pulled below what its catenary needs is a Slack error naming it: a very heavy
/// cable (1000 N/m on ~2 m) cannot be held at t_min = 1 N.
#[test]
fn a_cable_that_cannot_hold_its_weight_is_slack() {
    let s = Scene::default_scene();
    let n = s.n_cables();
    let lo = vec![1.0; n];
    let mut sag = SagTensionSolver::new(n, SagTensionParams::default());
    let g = geometry(&s, s.ee_position_m);
    let hi_big = vec![1e6; n];
    let e = sag
        .solve(
            &g,
            &materials(&s, 1000.0),
            &s.gravity_m_s2,
            &wrench6(&s),
            &lo,
            &hi_big,
        )
        .unwrap_err();
    assert!(
        matches!(e, SagTensionError::Slack { cable, .. } if cable < n),
        "{e}"
    );
    assert!(e.to_string().contains("slack"), "{e}");
}

/// 1000 solves along a small circle with the heavy cables allocate nothing after the first.
#[test]
fn solve_does_not_allocate() {
    let s = Scene::default_scene();
    let n = s.n_cables();
    let (lo, hi) = bounds(&s, 30.0);
    let mats = materials(&s, 12.55);
    let mut sag = SagTensionSolver::new(n, SagTensionParams::default());
    let mut g = geometry(&s, s.ee_position_m);
    sag.solve(&g, &mats, &s.gravity_m_s2, &wrench6(&s), &lo, &hi)
        .unwrap();
    let before = thread_allocations();
    let mut ok = 0;
    for k in 0..1000 {
        let a = k as f64 * 0.00628;
        let p = s.ee_position_m + Vector3::new(0.3 * a.cos(), 0.3 * a.sin(), 0.0);
        g.update(s.cables.iter().map(|c| &c.anchor_m), &p).unwrap();
        ok += sag
            .solve(&g, &mats, &s.gravity_m_s2, &wrench6(&s), &lo, &hi)
            .is_ok() as usize;
    }
    assert_eq!(thread_allocations() - before, 0);
    assert_eq!(ok, 1000);
}

/// Solve time with the heavy cables at the centre and off-centre, cold and warm
/// (`cargo test --release --test sag_tension -- --ignored --nocapture`). No assert on time.
#[test]
#[ignore]
fn timing_heavy_cables() {
    let s = Scene::default_scene();
    let n = s.n_cables();
    let (lo, hi) = bounds(&s, 30.0);
    let mats = materials(&s, 12.55);
    for (name, p) in [
        ("centre", s.ee_position_m),
        ("off-centre", s.ee_position_m + Vector3::new(0.3, 0.2, 0.0)),
    ] {
        let g = geometry(&s, p);
        let mut sag = SagTensionSolver::new(n, SagTensionParams::default());
        let reps = 2000;
        let t0 = std::time::Instant::now();
        for _ in 0..reps {
            sag.reset_warm_start();
            sag.solve(&g, &mats, &s.gravity_m_s2, &wrench6(&s), &lo, &hi)
                .unwrap();
        }
        let cold = t0.elapsed().as_secs_f64() / reps as f64;
        let cold_it = sag.info().iterations;
        let t0 = std::time::Instant::now();
        for _ in 0..reps {
            sag.solve(&g, &mats, &s.gravity_m_s2, &wrench6(&s), &lo, &hi)
                .unwrap();
        }
        let warm = t0.elapsed().as_secs_f64() / reps as f64;
        println!(
            "{name}: cold {:.1} µs ({cold_it} passes), warm {:.1} µs ({} passes), tensions {:?}",
            cold * 1e6,
            warm * 1e6,
            sag.info().iterations,
            sag.tensions_n()
        );
    }
}

/// Newton's step on the optimality system (`SagTensionParams::newton`, the default) finds
/// the fixed point of the plain passes, in fewer passes: along a 0.2 m circle of 40 poses
/// (warm-started as in the real-time path) on the heavy-cable spatial robot, the rigid
/// box with heavy cables (moment rows) and the suspended 8-cable scene, the end tensions
/// agree with the plain passes' to 1e-9 relative (both stop when no end direction moves
/// by 1e-12 rad; a direction error δ changes the tensions by ~δ times the QP's condition
/// number, which stays below 1e3 at these poses), and Newton needs at most half of the
/// passes in total.
#[test]
fn newton_passes_find_the_plain_fixed_point() {
    let suspended = Scene::load("scenes/suspended_8.toml").unwrap();
    let cases = [
        (Scene::default_scene(), Some(12.55), 30.0),
        (Scene::box_6dof(), Some(2.0), Scene::box_6dof().t_min_n),
        (suspended.clone(), None, suspended.t_min_n),
    ];
    for (s, w, t_min) in cases {
        let n = s.n_cables();
        let (lo, hi) = bounds(&s, t_min);
        let mats: Vec<SagCable> = match w {
            Some(w) => materials(&s, w),
            None => SagCable::of_scene(&s),
        };
        let plain_params = SagTensionParams {
            newton: false,
            ..SagTensionParams::default()
        };
        let mut newton = SagTensionSolver::new(n, SagTensionParams::default());
        let mut plain = SagTensionSolver::new(n, plain_params);
        let (mut passes_newton, mut passes_plain) = (0, 0);
        let r = if s.rigid { 0.05 } else { 0.2 };
        for k in 0..40 {
            let a = k as f64 * std::f64::consts::TAU / 40.0;
            let p = s.ee_position_m + Vector3::new(r * a.cos(), r * a.sin(), 0.0);
            let g = geometry(&s, p);
            let args = (&g, &mats[..], &s.gravity_m_s2, &wrench6(&s));
            let tn = newton
                .solve(args.0, args.1, args.2, args.3, &lo, &hi)
                .unwrap()
                .to_vec();
            let tp = plain
                .solve(args.0, args.1, args.2, args.3, &lo, &hi)
                .unwrap()
                .to_vec();
            passes_newton += newton.info().iterations;
            passes_plain += plain.info().iterations;
            for i in 0..n {
                assert!(
                    (tn[i] - tp[i]).abs() <= 1e-9 * tp[i],
                    "{} pose {k} cable {i}: Newton {} N vs plain {} N",
                    s.name,
                    tn[i],
                    tp[i]
                );
            }
        }
        eprintln!(
            "{}: passes {passes_newton} with Newton, {passes_plain} plain",
            s.name
        );
        assert!(
            2 * passes_newton <= passes_plain,
            "{}: {passes_newton} passes with Newton, {passes_plain} without",
            s.name
        );
    }
}

/// Solve warm along `positions` (m) with `solver` and check every answer without the
/// solver's own convergence test: the reported tensions are the chord QP's answer on the
/// reported end tangents (a fixed point T = QP(A(T)), 1e-9 relative: the tangents stop
/// moving at 1e-12 rad), and the catenaries' end forces balance the load to 1e-9 of it.
fn check_fixed_points_along(s: &Scene, solver: &mut SagTensionSolver, positions: &[Vector3<f64>]) {
    let n = s.n_cables();
    let (lo, hi) = bounds(s, s.t_min_n);
    let mats = SagCable::of_scene(s);
    let mut qp = TensionSolver::new(n, TensionParams::default());
    let weight = s.wrench_n().norm();
    let w = wrench6(s);
    for (k, p) in positions.iter().enumerate() {
        let g = geometry(s, *p);
        let t = solver
            .solve(&g, &mats, &s.gravity_m_s2, &w, &lo, &hi)
            .unwrap_or_else(|e| panic!("pose {k}: {e}"))
            .to_vec();
        let mut tangents = g.clone();
        tangents.unit.copy_from_slice(solver.end_tangents());
        let again = qp.solve_wrench_bounds(&tangents, &w, &lo, &hi).unwrap();
        let mut force = s.gravity_m_s2 * s.ee_mass_kg;
        for i in 0..n {
            assert!(
                (again[i] - t[i]).abs() <= 1e-9 * t[i],
                "pose {k} cable {i}: QP on the end tangents {} N vs {} N",
                again[i],
                t[i]
            );
            let c = solver.catenaries_of()[i];
            let [h, up, _] = solver.basis(i);
            force -= h * c.h_n + up * c.v_end_n();
        }
        assert!(
            force.amax() <= 1e-9 * weight,
            "pose {k}: residual {force:?} N"
        );
    }
}

/// Where a very slack cable's tangent turns fast with its tension, the plain passes move
/// away from the fixed point (suspended-8 along the bench's 1.5 m circle, poses 0-160 ms:
/// they end `NoConvergence` there), and Newton's step reaches it (checked as
/// [`check_fixed_points_along`]).
#[test]
fn newton_reaches_fixed_points_the_plain_passes_leave() {
    let s = Scene::load("scenes/suspended_8.toml").unwrap();
    let positions: Vec<Vector3<f64>> = (0..=160)
        .map(|k| cablevib::trajectory::circle_pose_with_radius(&s, k, 4.0, 1.5).position_m)
        .collect();
    let plain_params = SagTensionParams {
        newton: false,
        ..SagTensionParams::default()
    };
    let mut plain = SagTensionSolver::new(s.n_cables(), plain_params);
    let (lo, hi) = bounds(&s, s.t_min_n);
    let mats = SagCable::of_scene(&s);
    let plain_failures = positions
        .iter()
        .filter(|p| {
            let g = geometry(&s, **p);
            let w = wrench6(&s);
            plain
                .solve(&g, &mats, &s.gravity_m_s2, &w, &lo, &hi)
                .is_err()
        })
        .count();
    assert!(
        plain_failures > 0,
        "the plain passes converged at every pose"
    );
    let mut newton = SagTensionSolver::new(s.n_cables(), SagTensionParams::default());
    check_fixed_points_along(&s, &mut newton, &positions);
}

/// Past a fold of the fixed point the free solution of a cable vanishes and only the one
/// at its bound is left: suspended-8 along the 1 m circle about (−1, 0, 2) m (4 s, 1 ms
/// apart), cable 4's tension falls from 64 N at 836 ms to 59 N at 852 ms, and at 853 ms
/// no free fixed point is left near it. Newton's step with the cable held free then hops
/// around the vanished root (this pose ended `NoConvergence` after 60 passes when the step
/// did not correct its active set); with it the solve puts the cable on T_min and
/// converges. Every pose from 800 to 900 ms is checked as [`check_fixed_points_along`].
#[test]
fn newton_steps_onto_the_bound_past_a_fold() {
    let s = Scene::load("scenes/suspended_8.toml").unwrap();
    let positions: Vec<Vector3<f64>> = (800..=900)
        .map(|k| {
            let th = std::f64::consts::TAU * (k as f64 * 1e-3) / 4.0;
            s.ee_position_m + Vector3::new(th.cos() - 1.0, th.sin(), 0.0)
        })
        .collect();
    let mut solver = SagTensionSolver::new(s.n_cables(), SagTensionParams::default());
    check_fixed_points_along(&s, &mut solver, &positions);
    let (lo, _) = bounds(&s, s.t_min_n);
    assert_eq!(
        solver.tensions_n()[3],
        lo[3],
        "cable 4 ends the path on T_min"
    );
}
