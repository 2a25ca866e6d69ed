//! The end-effector mode of continuous (N → ∞) sagged cables as the real-time estimator
//! tracks it along the bench circle (`Estimator::realtime`, the per-cycle budget, 1 ms
//! poses on the r = 0.75 m circle), held against an independent reference: the sagged FEM
//! (`SagChain::set_fem`: corotational truss elements on the exact profile, consistent
//! mass; no code shared with the continuous chain's Magnus propagator) at N = 40, 80 and
//! 160 elements per cable, each solved offline at the same pose (no budget: a cold sweep,
//! equal to the dense sagged reference within 1e-9, tests/sag/ee_mode.rs), extrapolated to
//! N → ∞ by two-level Richardson (1/N², then 1/N⁴: tests/sag/continuous/fem.rs shows the
//! FEM's 1/N² convergence to the continuous chain).
//!
//! Tolerances. The same mode solved offline at the same pose with the offline continuous
//! mesh (`SagContinuousParams::default`, 1e-9 up to four half-waves) is held to
//! [`OFFLINE_REL_TOL`]: the second Richardson level's correction is |r₂ − r₁|/15 ≤ 7.5e-7
//! here and the term it leaves is O(1/N⁶), far smaller; measured ≤ 6.7e-8. This checks the
//! continuous chain itself at the end-effector mode. The real-time continuous mesh (`SagContinuousParams::realtime`) is cut for
//! the cable's first transverse half-wave at 1e-5; its error model (src/cable/sagged/
//! continuous.rs) grows as the mode's phase squared, Φ² ∝ λ, above that: an end-effector
//! mode at k half-waves of its cables carries ~1e-5·k². The answer is held to
//! [`EE_REL_TOL`] relative in λ plus the extrapolation's own spread (|r₂ − r₁| of the two
//! first-level Richardson values, its O(1/N⁴) term): measured 3.2e-4 … 3.8e-4 on
//! fast-like and the paper's robot (mode at ~6 half-waves by the model). Participation:
//! [`P_TOL`] against the FEM at N = 160 (whose own error is O(1/N²) ~ 1e-4; the mesh's
//! error moves the mode's shape as it moves λ): measured ≤ 1.9e-3.
use cablevib::alloc_count::thread_allocations;
use cablevib::estimator::{Estimator, Tmin};
use cablevib::modal::hz_to_lambda;
use cablevib::scene::{ElementKind, Scene};
use cablevib::stats::percentile;
use cablevib::trajectory::{circle_pose, CIRCLE_PERIOD_S};
use cablevib_testkit::sag_cases::{sagged_fem, sagged_robots};
use cablevib_testkit::{ee_age, ee_hz, ee_p};

/// λ agreement of a fresh real-time answer with the extrapolated FEM (module docs).
const EE_REL_TOL: f64 = 1e-3;
/// λ agreement of the offline continuous mesh with the extrapolated FEM (module docs).
const OFFLINE_REL_TOL: f64 = 1e-6;
/// Participation agreement of a fresh real-time answer with the FEM at N = 160.
const P_TOL: f64 = 5e-3;
/// FEM element counts of the reference.
const NS: [usize; 3] = [40, 80, 160];

/// `scene` with continuous sagged cables.
fn continuous(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    s.model.sag = true;
    s.model.element = ElementKind::Continuous;
    s
}

/// The FEM reference's end-effector mode at circle cycle `k`, extrapolated: (λ∞,
/// spread, λ at each N, its participation at the largest N).
fn fem_reference(scene: &Scene, k: usize) -> (f64, f64, [f64; 3], f64) {
    let mut l = [0.0; 3];
    let mut p = 0.0;
    for (j, &n) in NS.iter().enumerate() {
        let s = sagged_fem(scene.clone(), n);
        let mut est = Estimator::new(&s).unwrap();
        let e = *est.update(&circle_pose(&s, k, CIRCLE_PERIOD_S), Tmin::Scene);
        assert!(e.is_ok(), "{} N {n} cycle {k}: {:?}", s.name, e.error);
        assert_eq!(ee_age(&e), Some(0), "{} N {n} cycle {k}", s.name);
        l[j] = hz_to_lambda(ee_hz(&e));
        p = ee_p(&e);
    }
    let r1 = (4.0 * l[1] - l[0]) / 3.0;
    let r2 = (4.0 * l[2] - l[1]) / 3.0;
    ((16.0 * r2 - r1) / 15.0, (r2 - r1).abs(), l, p)
}

/// Along `scene`'s circle with continuous sagged cables for `cycles` cycles: no cycle
/// allocates, and the first fresh answer at or after every `every`-th cycle equals the
/// extrapolated FEM within the tolerance. Returns the answers' ages (ok cycles with one)
/// and the cycles without one.
fn check_circle(scene: &Scene, cycles: usize, every: usize) -> (Vec<u64>, usize) {
    let s = continuous(scene);
    let mut est = Estimator::realtime(&s).unwrap();
    est.update(&circle_pose(&s, 0, CIRCLE_PERIOD_S), Tmin::Scene);
    let (mut allocs, mut unknown, mut checked, mut due) = (0, 0, 0, every);
    let mut ages = Vec::with_capacity(cycles);
    let mut worst = 0.0f64;
    for k in 1..=cycles {
        let before = thread_allocations();
        let e = *est.update(&circle_pose(&s, k, CIRCLE_PERIOD_S), Tmin::Scene);
        allocs += thread_allocations() - before;
        assert!(e.is_ok(), "{} cycle {k}: {:?}", s.name, e.error);
        let Some(age) = ee_age(&e) else {
            unknown += 1;
            continue;
        };
        ages.push(u64::from(age));
        if age != 0 || k < due {
            continue;
        }
        due = k + every;
        let l = hz_to_lambda(ee_hz(&e));
        let (r, spread, ls, pf) = fem_reference(scene, k);
        let err = (l - r).abs() / r;
        let off = {
            let mut o = Estimator::new(&s).unwrap();
            let e = *o.update(&circle_pose(&s, k, CIRCLE_PERIOD_S), Tmin::Scene);
            assert_eq!(ee_age(&e), Some(0), "{} offline cycle {k}", s.name);
            hz_to_lambda(ee_hz(&e))
        };
        let off_err = (off - r).abs() / r;
        eprintln!(
            "{} cycle {k}: real time {:.6} Hz (p {:.4}), FEM {:?} Hz → {:.6} Hz (p {pf:.4}, \
             spread {:.1e}); rel err λ {err:.2e}, offline mesh {off_err:.1e}",
            s.name,
            ee_hz(&e),
            ee_p(&e),
            ls.map(|x| x.sqrt() / (2.0 * std::f64::consts::PI)),
            r.sqrt() / (2.0 * std::f64::consts::PI),
            spread / r
        );
        assert!(
            off_err <= OFFLINE_REL_TOL,
            "{} cycle {k}: offline mesh λ {off} vs extrapolated FEM {r} (rel {off_err:.2e})",
            s.name
        );
        assert!(
            (ee_p(&e) - pf).abs() <= P_TOL,
            "{} cycle {k}: p {} vs FEM {pf}",
            s.name,
            ee_p(&e)
        );
        assert!(
            err <= EE_REL_TOL + spread / r,
            "{} cycle {k}: λ {l} vs extrapolated FEM {r} (rel {err:.2e})",
            s.name
        );
        worst = worst.max(err);
        checked += 1;
    }
    assert_eq!(allocs, 0, "{}: {allocs} allocations", s.name);
    ages.sort_unstable();
    if !ages.is_empty() {
        eprintln!(
            "{}: {checked} answers checked (worst λ {worst:.1e}); age p50 {} p99 {} max {}, \
             {unknown} cycles without an answer",
            s.name,
            percentile(&ages, 0.5),
            percentile(&ages, 0.99),
            percentile(&ages, 1.0)
        );
    }
    (ages, unknown)
}

/// fast-like with continuous sagged cables, the circle's first 1000 cycles: answers
/// checked at cycles ≥ 200, 600 (two fresh answers at least).
#[test]
fn continuous_sagged_ee_mode_matches_extrapolated_fem_on_fast_like() {
    let s = &sagged_robots(10)[1];
    let (ages, _) = check_circle(s, 1000, 400);
    assert!(!ages.is_empty(), "{}: no answer", s.name);
}

mod slow {
    use super::*;

    /// The three bench scenes with continuous sagged cables, 3000 cycles as `cablevib
    /// bench`, a fresh answer checked every 500 cycles. suspended-8 has none yet (its
    /// end-effector mode lies ~200 modes up; the count-only sweep does not keep up with the
    /// circle): checked only where answered.
    #[test]
    #[ignore = "slow reference sweep: three FEM sizes per checked pose, 3 scenes × 3000 cycles"]
    fn continuous_sagged_ee_mode_matches_extrapolated_fem_along_the_bench_circles() {
        for s in &sagged_robots(10) {
            check_circle(s, 3000, 500);
        }
    }
}
