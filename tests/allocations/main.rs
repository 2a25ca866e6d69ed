//! A counting global allocator proves the per-cycle path allocates nothing: 10,000 cycles
//! along the trajectory (and bad inputs mixed in) make zero heap allocations after the
//! first, for every model including the rigid body; so does the inverse T_min query.
//! The continuation paths (an end-effector scan spread over the cycles by the per-cycle
//! evaluation budget, a warm cycle cut short) are covered by a small budget and by the
//! heavy-cable scene, whose scan takes many cycles.
//! The allocator (`cablevib::alloc_count`) is read per thread, so what the test harness's
//! own threads allocate meanwhile (output capture, the runner) is not charged to the
//! estimator.
use cablevib::alloc_count::thread_allocations;
use cablevib::estimator::Tmin;
use cablevib::estimator::{Estimator, EstimatorParams, TminQueryError};
use cablevib::kinematics::Pose;
use cablevib::modal::CYCLE_EVALUATIONS;
use cablevib::scene::{ElementKind, Scene, MAX_CABLES};
use cablevib::trajectory::{Circle, CIRCLE_RADIUS_M, SAMPLE_PERIOD_S};
use cablevib_testkit::ee_age;
use nalgebra::Vector3;

cablevib_testkit::count_allocations!();

/// A shipped scene file `scenes/NAME.toml`.
fn scene_file(name: &str) -> Scene {
    Scene::load(&format!(
        "{}/scenes/{name}.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

/// The paper's circle around the default position (radius 0.75 m; 0.2 m for the rigid-body
/// robot, whose feasible workspace is smaller), 4 s per turn.
fn circle(s: &Scene) -> Circle {
    let r = if s.rigid { 0.2 } else { CIRCLE_RADIUS_M };
    Circle::new(s, r, 4.0).unwrap()
}

/// The scene with 2.5 m of cable hidden behind every anchor (winches on the floor).
fn hidden(mut s: Scene) -> Scene {
    for c in &mut s.cables {
        c.hidden = Some(cablevib::scene::HiddenCable {
            length_m: 2.5,
            youngs_modulus_pa: c.youngs_modulus_pa,
            area_m2: c.area_m2,
            mass_per_length_kg_m: c.mass_per_length_kg_m,
        });
    }
    s
}

/// Pose k of the circle (one pose per 1 ms), at the scene's default orientation.
fn circle_pose(s: &Scene, c: &Circle, k: usize) -> Pose {
    Pose {
        position_m: c.position_at(k as f64 * SAMPLE_PERIOD_S),
        orientation_wxyz: s.ee_orientation_wxyz,
    }
}

#[test]
fn ten_thousand_cycles_allocate_nothing() {
    for (scene, el, n) in [
        (Scene::default_scene(), ElementKind::Fem, 40),
        (Scene::default_scene(), ElementKind::Catenary, 10),
        (Scene::default_scene(), ElementKind::Continuous, 1),
        (Scene::default_scene(), ElementKind::Massless, 1),
        (Scene::planar_paper(), ElementKind::Fem, 10),
        (Scene::box_6dof(), ElementKind::Fem, 10),
        // Swivel pulleys at every anchor: the paper robot and CAROCA (rigid platform).
        (scene_file("spatial_paper_pulleys"), ElementKind::Fem, 40),
        (
            scene_file("spatial_paper_pulleys"),
            ElementKind::Continuous,
            1,
        ),
        (
            scene_file("caroca_with_rotating_pulleys"),
            ElementKind::Fem,
            10,
        ),
        (hidden(Scene::default_scene()), ElementKind::Fem, 40),
        (hidden(Scene::default_scene()), ElementKind::Continuous, 1),
        (hidden(Scene::default_scene()), ElementKind::Massless, 1),
        (hidden(Scene::default_scene()), ElementKind::Catenary, 10),
        (hidden(Scene::box_6dof()), ElementKind::Fem, 10),
    ] {
        let s = scene.with_model(el, n);
        let c = circle(&s);
        let mut est = Estimator::new(&s).unwrap();
        est.update(&circle_pose(&s, &c, 0), Tmin::Scene);
        let before = thread_allocations();
        let mut ok = 0;
        for k in 1..=10_000 {
            let e = match k % 1000 {
                // Bad inputs on the same path: they must not allocate either.
                17 => est.update(&Pose::at(Vector3::new(f64::NAN, 0.0, 1.0)), Tmin::Scene),
                18 => est.update(&circle_pose(&s, &c, k), Tmin::Uniform(-1.0)),
                19 => est.update(&Pose::at(Vector3::new(9.0, 9.0, 9.0)), Tmin::Scene),
                20 => est.update(&circle_pose(&s, &c, k), Tmin::Uniform(s.t_max_n * 0.99)),
                _ => est.update(&circle_pose(&s, &c, k), Tmin::Scene),
            };
            ok += e.is_ok() as usize;
        }
        // The inverse T_min query (the service's margin answer): answered or unreachable,
        // it allocates nothing either.
        let pose = circle_pose(&s, &c, 5);
        let e = *est.update(&pose, Tmin::Scene);
        assert!(e.is_ok(), "{} {el:?}: {:?}", s.name, e.error);
        let f = e.f1_hz;
        let q = est.t_min_for_f1(&pose, 1.05 * f);
        let after = thread_allocations();
        assert!(
            matches!(q, Ok(_) | Err(TminQueryError::Unreachable { .. })),
            "{q:?}"
        );
        assert_eq!(
            after - before,
            0,
            "{} {el:?}: {} heap allocations in 10,000 cycles",
            s.name,
            after - before
        );
        assert!(ok >= 9_950, "{ok}");
    }
}

/// 2,000 cycles of `s`'s circle, with a NaN pose and an unreachable one at cycles 17 and 19
/// of each thousand, allocate nothing, and at least 1,990 are answers (ok).
fn circle_with_bad_inputs_allocates_nothing(s: &Scene, what: &str) {
    let c = circle(s);
    let mut est = Estimator::new(s).unwrap();
    est.update(&circle_pose(s, &c, 0), Tmin::Scene);
    let before = thread_allocations();
    let mut ok = 0;
    for k in 1..=2_000 {
        let e = match k % 1000 {
            17 => est.update(&Pose::at(Vector3::new(f64::NAN, 0.0, 1.0)), Tmin::Scene),
            19 => est.update(&Pose::at(Vector3::new(9.0, 9.0, 9.0)), Tmin::Scene),
            _ => est.update(&circle_pose(s, &c, k), Tmin::Scene),
        };
        ok += e.is_ok() as usize;
    }
    let after = thread_allocations();
    assert_eq!(
        after - before,
        0,
        "{what}: {} heap allocations in 2,000 cycles",
        after - before
    );
    assert!(ok >= 1_990, "{what}: {ok}");
}

/// Sagging cables on hidden cables, fem and continuous (the sagged chains start at the
/// junction, evaluated one by one): 2,000 cycles along the circle, bad inputs mixed in, allocate nothing; the
/// estimates are answers (ok) on the circle.
#[test]
fn hidden_cables_with_sag_allocate_nothing() {
    for (kind, n) in [
        (ElementKind::Fem, 10),
        (ElementKind::Fem, 40),
        (ElementKind::Continuous, 1),
    ] {
        let mut s = hidden(Scene::default_scene()).with_model(kind, n);
        s.set_sag(true).unwrap();
        circle_with_bad_inputs_allocates_nothing(&s, &format!("sag, hidden, {kind:?} × {n}"));
    }
}

/// Sagging cables on swivel pulleys (the exit point's motion adds its term to the sagged
/// D(λ) at each load): the paper robot (fem × 10, continuous) and CAROCA (rigid, fem × 10),
/// 2,000 cycles along the circle with bad inputs mixed in, allocate nothing.
#[test]
fn pulleys_with_sag_allocate_nothing() {
    for (name, kind, n) in [
        ("spatial_paper_pulleys", ElementKind::Fem, 10),
        ("spatial_paper_pulleys", ElementKind::Continuous, 1),
        ("caroca_with_rotating_pulleys", ElementKind::Fem, 10),
    ] {
        let mut s = scene_file(name).with_model(kind, n);
        s.set_sag(true).unwrap();
        circle_with_bad_inputs_allocates_nothing(&s, &format!("{name} sag {kind:?} × {n}"));
    }
}

/// The continuation paths: with a budget of 12 evaluations per cycle, every rescan and the
/// cold scans are spread over several cycles and warm cycles are cut short now and then; the
/// heavy-cable scene's cold scan (~250 string modes below the end-effector mode) runs over
/// dozens of cycles at the default budget. 3,000 cycles of each allocate nothing.
#[test]
fn continued_scans_allocate_nothing() {
    let heavy = Scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/spatial_heavy_cable.toml"
    ))
    .unwrap();
    for (scene, el, n, budget) in [
        (Scene::default_scene(), ElementKind::Fem, 40, 12),
        (Scene::default_scene(), ElementKind::Continuous, 1, 12),
        (heavy.clone(), ElementKind::Continuous, 1, CYCLE_EVALUATIONS),
        (heavy, ElementKind::Catenary, 40, CYCLE_EVALUATIONS),
    ] {
        let s = scene.with_model(el, n);
        let mut p = EstimatorParams::default();
        p.modal.ee_participation_min = s.model.ee_participation_min;
        p.modal.cycle_evaluations = budget;
        p.modal.max_scan_evaluations = cablevib::modal::SPREAD_SCAN_EVALUATIONS;
        let mut est = Estimator::with_params(&s, p).unwrap();
        let c = Circle::new(&s, 0.1, 4.0).unwrap();
        est.update(&circle_pose(&s, &c, 0), Tmin::Scene);
        let before = thread_allocations();
        let mut continued = 0;
        for k in 1..=3_000 {
            let e = est.update(&circle_pose(&s, &c, k), Tmin::Scene);
            assert!(e.eigen_evaluations <= budget);
            continued += (ee_age(e) != Some(0)) as usize;
        }
        let after = thread_allocations();
        assert_eq!(after - before, 0, "{} {el:?} budget {budget}", s.name);
        assert!(continued > 0, "{} {el:?}: the continuation ran", s.name);
    }
}

/// The per-cable path ([`Estimator::update_with_bounds`], as the service calls it for every
/// set-point): 10,000 cycles with per-cable lower bounds that change every 100 cycles, bad
/// bounds mixed in (a zero, a subnormal, a wrong length), make zero heap allocations.
#[test]
fn per_cable_bounds_allocate_nothing() {
    for (scene, el, n) in [
        (Scene::default_scene(), ElementKind::Fem, 10),
        (Scene::default_scene(), ElementKind::Continuous, 1),
        (Scene::box_6dof(), ElementKind::Fem, 10),
    ] {
        let s = scene.with_model(el, n);
        let nc = s.n_cables();
        let c = circle(&s);
        let mut est = Estimator::new(&s).unwrap();
        let mut bounds = [s.t_min_n; MAX_CABLES];
        est.update(&circle_pose(&s, &c, 0), Tmin::PerCable(&bounds[..nc]));
        let before = thread_allocations();
        let mut ok = 0;
        for k in 1..=10_000 {
            if k % 100 == 0 {
                // A new per-cable set-point: one cable raised by up to 20 %.
                bounds = [s.t_min_n; MAX_CABLES];
                bounds[(k / 100) % nc] = s.t_min_n * (1.0 + 0.002 * (k % 1000) as f64 / 10.0);
            }
            let pose = circle_pose(&s, &c, k);
            let e = match k % 1000 {
                17 => {
                    let mut bad = bounds;
                    bad[1] = 0.0;
                    est.update(&pose, Tmin::PerCable(&bad[..nc]))
                }
                18 => {
                    let mut bad = bounds;
                    bad[0] = f64::MIN_POSITIVE / 2.0;
                    est.update(&pose, Tmin::PerCable(&bad[..nc]))
                }
                19 => est.update(&pose, Tmin::PerCable(&bounds[..nc - 1])),
                _ => est.update(&pose, Tmin::PerCable(&bounds[..nc])),
            };
            ok += e.is_ok() as usize;
        }
        let after = thread_allocations();
        assert_eq!(
            after - before,
            0,
            "{} {el:?}: {} heap allocations in 10,000 per-cable cycles",
            s.name,
            after - before
        );
        assert!(ok >= 9_950, "{} {el:?}: {ok} ok", s.name);
    }
}
