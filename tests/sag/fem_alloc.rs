//! The sagged structured solver allocates nothing after `new`: 1,000 poses loaded from
//! their catenaries (bad inputs mixed in), each with D(λ), the count, the static
//! stiffness, a warm first root and the first 10 modes, for a point mass and a rigid
//! body. Plus an ignored measurement of the evaluation and solve times.

use cablevib::alloc_count::thread_allocations;
use cablevib::modal::sagged::SagEndEffector;
use cablevib::modal::SagModalSolver;
use cablevib::modal::{ModalParams, Mode};
use cablevib_testkit::sag_robot::*;
use std::time::Instant;

#[test]
fn a_thousand_poses_allocate_nothing() {
    for ee in [point(), rigid()] {
        let base = robot(8, 0.6, 2.0e5, true);
        let mut cur = base.clone();
        let mut s = SagModalSolver::new(ModalParams::default(), 8, 40);
        let mut modes = [Mode::default(); 10];
        s.load_catenaries(&base, 40, &up(), &ee).unwrap();
        s.first_root_warm().unwrap();
        let before = thread_allocations();
        let mut ok = 0;
        for k in 1..=1000 {
            pose(&base, k, &mut cur);
            if k % 100 == 17 {
                cur[3].catenary.h_n = f64::NAN;
            }
            let bad_mass = SagEndEffector::Point { mass_kg: -1.0 };
            let e = if k % 100 == 18 { &bad_mass } else { &ee };
            if s.load_catenaries(&cur, 40, &up(), e).is_err() {
                continue;
            }
            let d = s.eval(1.0);
            let _ = s.count_below(d.d[(0, 0)].abs());
            let _ = s.static_stiffness();
            let r = s.first_root_warm();
            let m = s.modes(10, &mut modes);
            ok += (r.is_ok() && m.is_ok()) as usize;
        }
        let after = thread_allocations();
        assert!(ok >= 980, "{ok} poses solved");
        assert_eq!(
            after - before,
            0,
            "{} heap allocations in 1,000 poses",
            after - before
        );
    }
}

#[test]
#[ignore = "measurement: run with --ignored --nocapture on a quiet machine"]
fn measure_evaluation_and_first_root_times() {
    for n_el in [40usize, 160] {
        let base = robot(8, 0.6, 2.0e5, true);
        let mut cur = base.clone();
        let mut s = SagModalSolver::new(ModalParams::default(), 8, n_el);
        s.load_catenaries(&base, n_el, &up(), &point()).unwrap();
        let lam = s.first_root_warm().unwrap().lambda;
        let reps = 20_000;
        let t0 = Instant::now();
        let mut acc = 0.0;
        for i in 0..reps {
            acc += s.eval(lam * (1.0 + 1e-6 * i as f64)).d[(0, 0)];
        }
        let per_eval = t0.elapsed().as_secs_f64() / reps as f64;
        // Warm: along a smooth path (load included), from the last root.
        let poses = 2000;
        let (mut warm_t, mut warm_e) = (0.0, 0u64);
        let (mut cold_t, mut cold_e) = (0.0, 0u64);
        let (mut load_t, mut n_ok) = (0.0, 0);
        for k in 0..poses {
            pose(&base, k, &mut cur);
            let t = Instant::now();
            s.load_catenaries(&cur, n_el, &up(), &point()).unwrap();
            load_t += t.elapsed().as_secs_f64();
            let t = Instant::now();
            let r = s.first_root_warm().unwrap();
            warm_t += t.elapsed().as_secs_f64();
            warm_e += r.evaluations as u64;
            let t = Instant::now();
            let c = s.first_root_cold().unwrap();
            cold_t += t.elapsed().as_secs_f64();
            cold_e += c.evaluations as u64;
            n_ok += ((r.lambda - c.lambda).abs() < 1e-9 * c.lambda) as usize;
        }
        let p = poses as f64;
        eprintln!(
            "8 cables, N = {n_el}: D(λ) {:.2} µs; load {:.2} µs; first root warm {:.2} µs ({:.1} evaluations), cold {:.2} µs ({:.1} evaluations); warm = cold on {n_ok}/{poses} ({acc:.1e})",
            per_eval * 1e6,
            load_t / p * 1e6,
            warm_t / p * 1e6,
            warm_e as f64 / p,
            cold_t / p * 1e6,
            cold_e as f64 / p,
        );
    }
}
