//! The sagged solver's fast paths against their references: D(λ) by the chains' lockstep
//! (batched) recurrence against the one-by-one recurrence, the warm first root from a
//! predicted λ against the cold one, and the cycle's evaluation budget. Plus an ignored
//! measurement of ns per element.

use cablevib::cable::sagged::SagSupport;
use cablevib::cable::Segment;
use cablevib::elastic_catenary::{CableChord, SagParams};
use cablevib::modal::sagged::SagCableFrame;
use cablevib::modal::SagModalSolver;
use cablevib::modal::{ModalError, ModalParams};
use cablevib_testkit::sag_robot::*;
use std::time::Instant;

/// The lockstep evaluation does every chain's scalar operations in the same order and
/// sums the cables into D in the same order: tolerance 0 (bit for bit), for 5, 8 and 11
/// cables (a partial block, a full one, one and a partial), a point mass and a rigid body,
/// λ from 0 to far above the lowest poles.
#[test]
fn lockstep_d_equals_one_by_one_bit_for_bit() {
    for n in [5usize, 8, 11] {
        for ee in [point(), rigid()] {
            let cables = robot(n, 0.6, 2.0e5, true);
            let mut s = SagModalSolver::new(ModalParams::default(), n, 40);
            s.load_catenaries(&cables, 40, &up(), &ee).unwrap();
            lockstep_equals_one_by_one(&mut s, n, true);
        }
    }
}

/// As above with every other cable on a hidden cable (the chain's anchor node held by an
/// axial segment of 40 elements, or the continuous bar, along the cable's first chord):
/// the supported chains run in the lockstep batch from their junction step, so D, D' and
/// the count equal the one-by-one recurrence bit for bit (tolerance 0), λ from 0 to far
/// above the lowest poles.
#[test]
fn lockstep_d_with_hidden_cables_equals_one_by_one_bit_for_bit() {
    for n in [5usize, 11] {
        for ee in [point(), rigid()] {
            let cables = robot(n, 0.6, 2.0e5, true);
            let mut s = SagModalSolver::new(ModalParams::default(), n, 40);
            let mut frames = Vec::new();
            for (i, c) in cables.iter().enumerate() {
                let chain = s.chain_mut(i);
                chain.set_fem(&c.catenary, c.mu_kg_m, 40).unwrap();
                if i % 2 == 0 {
                    let nh = if i % 4 == 0 { 40 } else { 0 };
                    let per = if nh == 0 { 1.0 } else { nh as f64 };
                    let support = SagSupport {
                        hidden: Segment {
                            k: 2.0e5 / 2.5 * per,
                            m: c.mu_kg_m * 2.5 / per,
                            n_el: nh,
                        },
                        direction: chain.element(0).chord,
                    };
                    chain.set_support(Some(support)).unwrap();
                }
                frames.push(SagCableFrame {
                    h: c.h,
                    arm_m: c.arm_m,
                    end_force_n: -(c.h * c.catenary.h_n + up() * c.catenary.v_end_n()),
                });
            }
            s.load(&frames, &up(), &ee).unwrap();
            lockstep_equals_one_by_one(&mut s, n, false);
        }
    }
}

/// Along a smooth path, the warm first root from a linear prediction of the last two
/// roots equals the cold one to 1e-11 relative: both stop on a Newton step below
/// rel_tol = 1e-12, or (warm) on a step below newton_accept = 1e-9 whose estimated
/// remaining error (step²/previous step) is below rel_tol; 1e-11 leaves 10× for the two
/// stopping errors and rounding. The warm one never needs more evaluations than the cold.
#[test]
fn warm_first_root_prediction_equals_cold() {
    for ee in [point(), rigid()] {
        let base = robot(8, 0.6, 2.0e5, true);
        let mut cur = base.clone();
        let mut s = SagModalSolver::new(ModalParams::default(), 8, 40);
        let (mut last, mut prev) = (f64::NAN, f64::NAN);
        let (mut warm_e, mut cold_e) = (0u32, 0u32);
        for k in 0..300 {
            pose(&base, k, &mut cur);
            s.load_catenaries(&cur, 40, &up(), &ee).unwrap();
            let pred = if prev.is_finite() {
                2.0 * last - prev
            } else {
                last
            };
            let cold = s.first_root_cold().unwrap();
            let warm = s.first_root(pred.is_finite().then_some(pred)).unwrap();
            let rel = (warm.lambda - cold.lambda).abs() / cold.lambda;
            assert!(
                rel < 1e-11,
                "pose {k}: warm {} cold {} ({rel:.1e})",
                warm.lambda,
                cold.lambda
            );
            (prev, last) = (last, warm.lambda);
            if k > 1 {
                warm_e += warm.evaluations;
                cold_e += cold.evaluations;
            }
        }
        assert!(
            warm_e <= cold_e,
            "warm {warm_e} vs cold {cold_e} evaluations"
        );
        eprintln!("298 poses: warm {warm_e}, cold {cold_e} evaluations");
    }
}

/// A first root that does not fit the cycle's budget ([`SagModalSolver::begin_cycle`]) is
/// `NoConvergence`, and the solver spent no more than the budget.
#[test]
fn first_root_stops_at_the_cycle_budget() {
    let cables = robot(8, 0.6, 2.0e5, true);
    for budget in [1u32, 2, 3] {
        let mut s = SagModalSolver::new(ModalParams::default(), 8, 40);
        s.load_catenaries(&cables, 40, &up(), &point()).unwrap();
        s.begin_cycle(budget);
        let before = s.evaluations();
        let r = s.first_root_cold();
        let spent = s.evaluations() - before;
        assert!(spent <= budget, "budget {budget}: spent {spent}");
        match r {
            Err(ModalError::NoConvergence { evaluations, .. }) => assert_eq!(evaluations, spent),
            Ok(r) => assert!(r.evaluations <= budget),
            Err(e) => panic!("budget {budget}: {e}"),
        }
    }
}

/// The tracked catenary solve (Newton from the last solution's first-order prediction)
/// against the plain solve from the shallow start, along a path of chords and tensions
/// (span, rise and T_e all moving, heavy and light cables, anchors above and below): both
/// stop with the end point within 1e-12 of the chord length on the taut branch, so (H,
/// V_e, L0) agree to that residual times the conditioning of the end point in them (≲ 10²
/// here): 1e-10 relative. The tracked one needs fewer Newton iterations in total.
#[test]
fn tracked_catenary_equals_plain_solve() {
    let p = SagParams::default();
    for (w, ea, rise0) in [(4.0, 2.0e5, -1.5), (40.0, 1.0e6, 0.8), (0.5, 5.0e7, -3.0)] {
        let mut track = None;
        let (mut it_tracked, mut it_plain) = (0u32, 0u32);
        for k in 0..500 {
            let t = k as f64 * 1e-3;
            let c = CableChord {
                span_m: 4.0 + 0.3 * (3.0 * t).sin(),
                rise_m: rise0 + 0.2 * (2.0 * t).cos(),
                ea_n: ea,
                w_n_m: w,
            };
            let t_end = 300.0 * (1.0 + 0.1 * (5.0 * t).sin());
            let (a, ia, tr) = c
                .solve_end_tension_tracked(t_end, track.as_ref(), &p)
                .unwrap();
            let (b, ib) = c.solve_end_tension(t_end, None, &p).unwrap();
            track = Some(tr);
            if k > 0 {
                it_tracked += ia.iterations;
                it_plain += ib.iterations;
            }
            for (x, y, what) in [
                (a.h_n, b.h_n, "H"),
                (a.v_end_n(), b.v_end_n(), "V_e"),
                (a.l0_m, b.l0_m, "L0"),
            ] {
                let rel = (x - y).abs() / t_end.max(y.abs());
                let rel = if what == "L0" { (x - y).abs() / y } else { rel };
                assert!(rel < 1e-10, "w {w} step {k} {what}: {x} vs {y} ({rel:.1e})");
            }
        }
        assert!(it_tracked < it_plain, "{it_tracked} vs {it_plain}");
        eprintln!("w {w}: Newton iterations tracked {it_tracked}, plain {it_plain} in 499 solves");
    }
}

#[test]
#[ignore = "measurement: run with --ignored --nocapture on a quiet machine"]
fn measure_ns_per_element() {
    for n_el in [10usize, 40, 160] {
        let cables = robot(8, 0.6, 2.0e5, true);
        let mut s = SagModalSolver::new(ModalParams::default(), 8, n_el);
        s.load_catenaries(&cables, n_el, &up(), &point()).unwrap();
        let lam = s.first_root_cold().unwrap().lambda;
        let reps = 20_000;
        let per = |t: Instant| t.elapsed().as_secs_f64() * 1e9 / (reps * 8 * n_el) as f64;
        let mut acc = 0.0;
        let t = Instant::now();
        for i in 0..reps {
            acc += s.eval_reference(lam * (1.0 + 1e-6 * i as f64)).d[(0, 0)];
        }
        let one = per(t);
        let t = Instant::now();
        for i in 0..reps {
            acc += s.eval(lam * (1.0 + 1e-6 * i as f64)).d[(0, 0)];
        }
        let lock = per(t);
        let t = Instant::now();
        for i in 0..reps {
            acc += s.count_below(lam * (1.0 + 1e-6 * i as f64)) as f64;
        }
        let count = per(t);
        eprintln!(
            "8 cables, N = {n_el}: ns per cable-element: one by one {one:.2}, lockstep {lock:.2}, lockstep count only {count:.2} ({acc:.1e})"
        );
    }
}

/// D, D' and the blocked count of the lockstep evaluation equal the one-by-one reference's
/// bit for bit at 200 λ from 0 to 1000 λ₁ (cubically spaced); with `count`, the count of
/// eigenvalues below λ is the blocked count plus D's negative eigenvalues.
fn lockstep_equals_one_by_one(s: &mut SagModalSolver, n: usize, count: bool) {
    let l1 = s.first_root_cold().unwrap().lambda;
    for i in 0..200 {
        let lambda = l1 * 1e3 * (i as f64 / 200.0).powi(3);
        let (a, b) = (s.eval(lambda), s.eval_reference(lambda));
        assert_eq!(a.below, b.below, "n {n} λ {lambda}");
        for (x, y) in
            a.d.iter()
                .zip(b.d.iter())
                .chain(a.dd.iter().zip(b.dd.iter()))
        {
            assert_eq!(x.to_bits(), y.to_bits(), "n {n} λ {lambda}: {x} vs {y}");
        }
        if count {
            let c = s.count_below(lambda);
            assert_eq!(c, b.below + b.eig().negatives() as u32, "count, λ {lambda}");
        }
    }
}
