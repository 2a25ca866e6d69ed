//! A counting global allocator proves the per-cycle path allocates nothing: 10,000 cycles
//! along the trajectory (and bad inputs mixed in) make zero heap allocations after the
//! first, for every model including the rigid body; so does the inverse T_min query.
//! The allocator counts per thread, so what the test harness's own threads allocate
//! meanwhile (output capture, the runner) is not charged to the estimator.
use cablevib::estimator::{Estimator, TminQueryError};
use cablevib::kinematics::Pose;
use cablevib::scene::{ElementKind, Scene};
use nalgebra::Vector3;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;
thread_local! {
    // Const-initialised: reading it never allocates.
    static COUNT: Cell<u64> = const { Cell::new(0) };
}
fn bump() {
    let _ = COUNT.try_with(|c| c.set(c.get() + 1));
}
/// Heap allocations made by the calling thread so far.
fn allocations() -> u64 {
    COUNT.with(|c| c.get())
}
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        bump();
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        bump();
        unsafe { System.realloc(p, l, n) }
    }
}
#[global_allocator]
static A: Counting = Counting;

/// A circle around the default position (radius 0.75 m like the paper's, 0.2 m for the
/// rigid-body robot whose feasible workspace is smaller), one pose per 1 ms, 4 s per turn.
fn circle_pose(s: &Scene, k: usize, period_s: f64) -> Pose {
    let r = if s.rigid { 0.2 } else { 0.75 };
    let th = 2.0 * std::f64::consts::PI * (k as f64 * 1e-3) / period_s;
    Pose {
        position_m: s.ee_position_m + Vector3::new(r * th.cos(), r * th.sin(), 0.0),
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
    ] {
        let s = scene.with_model(el, n);
        let mut est = Estimator::new(&s).unwrap();
        est.update(&circle_pose(&s, 0, 4.0), s.t_min_n);
        let before = allocations();
        let mut ok = 0;
        for k in 1..=10_000 {
            let e = match k % 1000 {
                // Bad inputs on the same path: they must not allocate either.
                17 => est.update(&Pose::at(Vector3::new(f64::NAN, 0.0, 1.0)), s.t_min_n),
                18 => est.update(&circle_pose(&s, k, 4.0), -1.0),
                19 => est.update(&Pose::at(Vector3::new(9.0, 9.0, 9.0)), s.t_min_n),
                20 => est.update(&circle_pose(&s, k, 4.0), s.t_max_n * 0.99),
                _ => est.update(&circle_pose(&s, k, 4.0), s.t_min_n),
            };
            ok += e.is_ok() as usize;
        }
        // The inverse T_min query (the service's margin answer): answered or unreachable,
        // it allocates nothing either.
        let pose = circle_pose(&s, 5, 4.0);
        let e = *est.update(&pose, s.t_min_n);
        assert!(e.is_ok(), "{} {el:?}: {:?}", s.name, e.error);
        let f = e.f1_hz;
        let q = est.t_min_for_f1(&pose, 1.05 * f);
        let after = allocations();
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
