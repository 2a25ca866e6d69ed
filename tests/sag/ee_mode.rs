//! The end-effector mode of sagging cables (the lowest mode whose end-effector
//! participation reaches the threshold), from the structured sweep of the sagged spectrum,
//! against the dense sagged reference (`Estimator::dense_modes`: K and M assembled from
//! the same chains, a dense generalized symmetric eigen-solve; independent of D(λ), the
//! count and Newton).
//!
//! Tolerances. λ: 1e-9 relative. The dense solve's own error on a mode is ~ε·λ_max/λ
//! (measured bound of the dense solver; sag_fem_dense.rs), 5e-12 .. 9e-10 on these
//! modes; the structured root is within ~1e-12 where the sagged recurrence is quiet and
//! measured within 3e-10 next to a pole (suspended-8 at N = 10). Participation: 1e-8
//! absolute: a ratio of mode-shape norms, which both solvers read to ~(λ error)·(its
//! conditioning); measured at most 8e-10.
//!
//! Continuous cables have no dense reference (no finite assembly): their end-effector mode
//! is held against the extrapolated FEM in ee_mode_continuous.rs.
use cablevib::alloc_count::thread_allocations;
use cablevib::estimator::{Estimator, Tmin};
use cablevib::kinematics::Pose;
use cablevib::modal::{hz_to_lambda, Mode, CYCLE_EVALUATIONS};
use cablevib::scene::Scene;
use cablevib::stats::percentile;
use cablevib::trajectory::{circle_pose, CIRCLE_PERIOD_S};
use cablevib_testkit::sag_cases::{home, sagged_robots};
use cablevib_testkit::{ee_age, ee_hz, ee_p};

/// λ agreement with the dense reference (module docs).
const LAMBDA_TOL: f64 = 1e-9;
/// Agreement of the low string modes next to a pole, where the sagged recurrence is noisy
/// (see `sagged_modes_next_to_a_noisy_pole_are_found`).
const NOISY_TOL: f64 = 5e-9;
/// Participation agreement (module docs).
const P_TOL: f64 = 1e-8;
/// Participation agreement of a tracked answer: the tracker reads it at its last Newton
/// iterate, within 1e-7 (relative, its answer step) of the root, so it is off by up to
/// 1e-7·|dp/d ln λ| (≲ 10 here; measured 2.2e-8 on suspended-8): 1e-6, the taut tracker's
/// tolerance against the dense reference (tests/model/ee_budget.rs).
const TRACKED_P_TOL: f64 = 1e-6;
/// The same next to an avoided crossing, where the participation moves fast with λ: on the
/// paper's spatial robot with sag |dp/d ln λ| reaches ~20 (measured 1.6e-6 at cycle 700,
/// N = 10), so 1e-7·20 = 2e-6, bounded by 1e-5.
const TRACKED_P_TOL_CROSSING: f64 = 1e-5;

/// The dense reference's end-effector mode of the estimator's last pose: (λ, p, index).
fn dense_ee(est: &Estimator, thr: f64) -> (f64, f64, usize) {
    let d = est.dense_modes(true).unwrap();
    let i = (0..d.lambda.len())
        .find(|&i| d.ee_participation[i] >= thr)
        .expect("a dense mode reaches the threshold");
    (d.lambda[i], d.ee_participation[i], i)
}

/// `est` updated at each of `poses` (named), every ok one a cold answer held against the
/// dense reference: cold, fresh, λ within LAMBDA_TOL and p within P_TOL (module docs).
/// Returns (ok poses, worst λ error, worst p error).
fn cold_answers_against_dense(
    est: &mut Estimator,
    poses: impl IntoIterator<Item = (String, Pose)>,
) -> (usize, f64, f64) {
    let thr = est.params().modal.ee_participation_min;
    let (mut checked, mut worst_l, mut worst_p) = (0, 0.0f64, 0.0f64);
    for (at, pose) in poses {
        let e = *est.update(&pose, Tmin::Scene);
        if !e.is_ok() {
            continue;
        }
        assert!(e.cold_start, "{at}: not cold");
        assert_eq!(ee_age(&e), Some(0), "{at}");
        let (dl, dp, _) = dense_ee(est, thr);
        let err = (hz_to_lambda(ee_hz(&e)) - dl).abs() / dl;
        let perr = (ee_p(&e) - dp).abs();
        assert!(err <= LAMBDA_TOL, "{at}: λ err {err:.1e}");
        assert!(perr <= P_TOL, "{at}: p {} vs dense {dp}", ee_p(&e));
        checked += 1;
        worst_l = worst_l.max(err);
        worst_p = worst_p.max(perr);
    }
    (checked, worst_l, worst_p)
}

#[test]
fn sagged_ee_mode_matches_the_dense_reference() {
    for n in [10, 40] {
        for s in sagged_robots(n) {
            let mut est = Estimator::new(&s).unwrap();
            let thr = est.params().modal.ee_participation_min;
            let e = *est.update(&home(&s), Tmin::Scene);
            assert!(e.is_ok(), "{} N {n}: {:?}", s.name, e.error);
            assert_eq!(ee_age(&e), Some(0), "{} N {n}", s.name);
            let (dl, dp, idx) = dense_ee(&est, thr);
            let l = hz_to_lambda(ee_hz(&e));
            let err = (l - dl).abs() / dl;
            eprintln!(
                "{} N {n}: ee mode #{idx} {:.9} Hz, λ rel err {err:.1e}, p {:.6} (dense {dp:.6})",
                s.name,
                ee_hz(&e),
                ee_p(&e)
            );
            // hz_to_lambda(lambda_to_hz(λ)) rounds twice: a few ε.
            assert!(err <= LAMBDA_TOL, "{} N {n}: λ {l} vs dense {dl}", s.name);
            assert!(
                (ee_p(&e) - dp).abs() <= P_TOL,
                "{} N {n}: p {} vs dense {dp}",
                s.name,
                ee_p(&e)
            );
        }
    }
}

/// The first 100 sagged modes of suspended-8 at N = 10: mode 75 sits next to a pole where
/// the sagged recurrence is noisier than the 1e-10 cluster probes, which used to fail with
/// `CountMismatch` (now probed again 100× wider). Each against the dense reference.
#[test]
fn sagged_modes_next_to_a_noisy_pole_are_found() {
    let s = &sagged_robots(10)[0];
    let mut est = Estimator::new(s).unwrap();
    assert!(est.update(&home(s), Tmin::Scene).is_ok());
    first_100_modes_against_dense(&mut est);
}

/// The first 100 modes of `est`'s last pose against the dense reference: within the dense
/// bound (ε·λ_max/λ, ×64 as in sag_fem_dense.rs) or the noise of the sagged recurrence
/// next to a pole, whichever is larger (measured at most 1.7e-9 on suspended-8 at N = 10:
/// mode 90, λ ≈ 3585 rad²/s², participation 0.01; bounded by 5e-9).
fn first_100_modes_against_dense(est: &mut Estimator) {
    let d = est.dense_modes(false).unwrap();
    let mut modes = vec![Mode::default(); 100];
    assert_eq!(est.modes(100, &mut modes).unwrap(), 100);
    for (i, m) in modes.iter().enumerate() {
        let err = (m.lambda - d.lambda[i]).abs() / d.lambda[i];
        let bound = (64.0 * f64::EPSILON * d.lambda_max / d.lambda[i]).max(NOISY_TOL);
        assert!(
            err <= bound,
            "mode {i}: {} vs dense {}",
            m.lambda,
            d.lambda[i]
        );
    }
}

/// Along the bench's circle (real-time estimator: the cycle's budget of
/// CYCLE_EVALUATIONS evaluations), the sagged end-effector mode is found over the cycles
/// (the end-effector tracker: scans spread over the cycles, then followed and certified by
/// the sum rules where they hold) and reported with its age; no cycle allocates or exceeds its budget; each fresh answer
/// (age 0) is the dense reference's end-effector mode of that cycle's pose.
#[test]
fn tracked_along_the_circle_without_allocation() {
    for s in sagged_robots(10) {
        let mut est = Estimator::realtime(&s).unwrap();
        let thr = est.params().modal.ee_participation_min;
        est.update(&circle_pose(&s, 0, CIRCLE_PERIOD_S), Tmin::Scene);
        let cycles = 1500;
        let (mut fresh, mut n_fresh) = ([0usize; 4], 0);
        let mut known = 0;
        let before = thread_allocations();
        for k in 1..=cycles {
            let e = est.update(&circle_pose(&s, k, CIRCLE_PERIOD_S), Tmin::Scene);
            assert!(e.is_ok(), "{} cycle {k}: {:?}", s.name, e.error);
            assert!(
                e.eigen_evaluations <= CYCLE_EVALUATIONS,
                "{} cycle {k}: {} evaluations",
                s.name,
                e.eigen_evaluations
            );
            if e.ee_mode.is_some() {
                known += 1;
            }
            if ee_age(e) == Some(0) && n_fresh < fresh.len() {
                fresh[n_fresh] = k;
                n_fresh += 1;
            }
        }
        let allocs = thread_allocations() - before;
        assert_eq!(allocs, 0, "{}: {allocs} allocations", s.name);
        let fresh = &fresh[..n_fresh];
        eprintln!(
            "{}: ee mode known on {known}/{cycles} cycles, first fresh answers at {fresh:?}",
            s.name
        );
        assert!(
            !fresh.is_empty(),
            "{}: no answer in {cycles} cycles",
            s.name
        );
        // Check the fresh answers against the dense reference of their pose.
        for &k in fresh {
            let mut est2 = Estimator::realtime(&s).unwrap();
            est2.update(&circle_pose(&s, 0, CIRCLE_PERIOD_S), Tmin::Scene);
            let mut got = None;
            for j in 1..=k {
                let e = est2.update(&circle_pose(&s, j, CIRCLE_PERIOD_S), Tmin::Scene);
                if j == k {
                    got = Some((ee_hz(e), ee_p(e), ee_age(e)));
                }
            }
            let (hz, p, age) = got.unwrap();
            assert_eq!(age, Some(0));
            let (dl, dp, _) = dense_ee(&est2, thr);
            let err = (hz_to_lambda(hz) - dl).abs() / dl;
            assert!(err <= LAMBDA_TOL, "{} cycle {k}: λ err {err:.1e}", s.name);
            assert!(
                (p - dp).abs() <= TRACKED_P_TOL,
                "{} cycle {k}: p {p} vs {dp}",
                s.name
            );
        }
    }
}

/// The spectrum search's cost: the first 100 modes of the paper robot with sag at its home
/// pose (N = 40), each against the dense reference as above, in at most 23 evaluations of
/// D or of the count a mode (counted, deterministic: no timing). Measured 20.7; 25.0
/// before Newton's safeguard read its progress from its steps (it bisected iterations
/// converging from one side, whose bracket does not narrow) and before the brackets grew
/// from the last gap: the bound fails on that code.
#[test]
fn sagged_modes_cost_few_evaluations_each() {
    let s = &sagged_robots(40)[2];
    let mut est = Estimator::new(s).unwrap();
    assert!(est.update(&home(s), Tmin::Scene).is_ok());
    let before = est.sag_modal().unwrap().evaluations();
    first_100_modes_against_dense(&mut est);
    let spent = est.sag_modal().unwrap().evaluations() - before;
    let per_mode = f64::from(spent) / 100.0;
    eprintln!("{}: {spent} evaluations for 100 modes", s.name);
    assert!(per_mode <= 23.0, "{per_mode} evaluations a mode");
}

/// What a run along the circle must show after the first answer (see
/// [`certified_along_the_circle`]).
struct Expect {
    /// Fresh (certified, age 0) answers on at least this many per mille of the warm cycles.
    fresh_permille: usize,
    /// Median evaluations of the fresh cycles, at most.
    max_median: u32,
    /// Uncertified rescans after the first answer, at most.
    max_uncertified: u64,
    /// Participation agreement of the checked answers with the dense reference.
    p_tol: f64,
}

/// The sum-rule certificate holds on the sagged path: along suspended-8's circle (N = 10,
/// real-time budget), once the first scan has found the end-effector mode, the warm cycles
/// certify it (counted by the tracker's counters and the answers' ages, not by timing):
/// a fresh answer on at least 95 % of the cycles, at a median of at most 12 evaluations
/// (the first root's 2-3, the watched modes' Newton steps, the plain sum rule's one).
/// Before the matrix form of the bound (`modal::ee_tracker`), the trace form failed here:
/// it counts the two other directions' unwatched participation against the answer, so a
/// failed certificate started a full sweep that took ~200 cycles each time (fresh on 374
/// of 1500 cycles). Since the sweep skips a mode it cannot isolate in three cycles, the
/// first answer comes at cycle 307, at a pose where the watch list needs two rescans
/// (cycles 323 and 371); each is a window rescan of 17 and 26 cycles, not a sweep from
/// zero: at most 2. Certified answers are checked against the dense sagged reference at a
/// few cycles (λ 1e-9, participation 1e-6: module docs). The median counts the chains'
/// pole searches of the partner searches too (one evaluation per evaluation of every
/// chain).
#[test]
fn certified_along_the_circle_on_suspended_8() {
    let expect = Expect {
        fresh_permille: 950,
        max_median: 12,
        max_uncertified: 2,
        p_tol: TRACKED_P_TOL,
    };
    certified_along_the_circle(&sagged_robots(10)[0], &expect);
}

/// The same on the paper's spatial robot with sag (N = 10 and 40). There the participation
/// of the watched modes moves in avoided crossings to unwatched neighbours up to ~1.4× the
/// answer's λ (dense reference), the bound reaches the threshold and the answer is
/// rescanned every ~40-120 cycles. Before the window rescans (`modal::ee_tracker`), each
/// rescan was a sweep from zero of ~150 cycles, and a sweep stuck on a mode next to a pole
/// for hundreds of cycles: fresh answers on 234 of the first 1500 cycles, median 26
/// evaluations (the whole budget). Now each rescan is a window of 9-26 cycles: measured
/// fresh on 80 % (N = 10) and 75 % (N = 40) of the warm cycles, median 8-9 evaluations;
/// required: 70 %, median ≤ 12.
#[test]
fn certified_along_the_circle_on_the_paper_robot_with_sag() {
    let expect = Expect {
        fresh_permille: 700,
        max_median: 12,
        max_uncertified: 40,
        p_tol: TRACKED_P_TOL_CROSSING,
    };
    for n in [10, 40] {
        certified_along_the_circle(&sagged_robots(n)[2], &expect);
    }
}

/// Suspended-8 at N = 40: NOT reached yet. The cold sweep finds the first answer only at
/// cycle ~1200 (≈ 284 modes below it at ~25 evaluations each, within a budget of 32 a
/// cycle); the watch list it leaves certifies 5 cycles (bound 0.43-0.49 against 0.5), and
/// the window rescan's answer is not certified, so the next sweep is from zero again. The
/// leftover's top direction sits low: its plain-to-weighted ratio uᵀR_p u / uᵀR_w u is
/// 280-1100 rad²/s² against the answer's 27 180, i.e. in the many weak cable modes far
/// below the answer (each under the 0.05 a mode needs to be watched), which no window
/// near the answer reaches.
#[test]
#[ignore = "suspended-8 at N = 40 is not certified along the circle yet (see doc)"]
fn certified_along_the_circle_on_suspended_8_at_40_elements() {
    let expect = Expect {
        fresh_permille: 700,
        max_median: 12,
        max_uncertified: 40,
        p_tol: TRACKED_P_TOL,
    };
    certified_along_the_circle(&sagged_robots(40)[0], &expect);
}

/// Along the circle of `s` (1500 cycles, real-time budget): the first answer before cycle
/// 700; after it, fresh answers and their median cost and the uncertified rescans as
/// `expect` says; the first fresh answer at or after cycles 700, 1100 and 1400 (within 100
/// cycles) equal to the dense sagged reference (λ 1e-9, participation 1e-6: module docs).
fn certified_along_the_circle(s: &Scene, expect: &Expect) {
    let cycles = 1500;
    let checks = [700usize, 1100, 1400];
    let mut next_check = 0;
    let mut est = Estimator::realtime(s).unwrap();
    let thr = est.params().modal.ee_participation_min;
    est.update(&circle_pose(s, 0, CIRCLE_PERIOD_S), Tmin::Scene);
    let mut first = None;
    let mut uncertified_then = 0;
    let (mut warm, mut fresh) = (0usize, 0usize);
    let mut evals = Vec::new();
    for k in 1..=cycles {
        let e = *est.update(&circle_pose(s, k, CIRCLE_PERIOD_S), Tmin::Scene);
        assert!(e.is_ok(), "{} cycle {k}: {:?}", s.name, e.error);
        if first.is_none() {
            if ee_age(&e) == Some(0) {
                first = Some(k);
                uncertified_then = est.rescan_counts().uncertified_scans;
            }
            continue;
        }
        warm += 1;
        if ee_age(&e) == Some(0) {
            fresh += 1;
            evals.push(e.eigen_evaluations);
        }
        if next_check < checks.len() && k >= checks[next_check] {
            assert!(
                k < checks[next_check] + 100,
                "{}: no fresh answer in cycles {}..{k}",
                s.name,
                checks[next_check]
            );
            if ee_age(&e) == Some(0) {
                next_check += 1;
                let (dl, dp, _) = dense_ee(&est, thr);
                let err = (hz_to_lambda(ee_hz(&e)) - dl).abs() / dl;
                assert!(err <= LAMBDA_TOL, "{} cycle {k}: λ err {err:.1e}", s.name);
                assert!(
                    (ee_p(&e) - dp).abs() <= expect.p_tol,
                    "{} cycle {k}: p {} vs dense {dp}",
                    s.name,
                    ee_p(&e)
                );
            }
        }
    }
    let first = first.expect("the first scan finds the end-effector mode");
    let c = est.rescan_counts();
    evals.sort_unstable();
    let median = evals.get(evals.len() / 2).copied().unwrap_or(u32::MAX);
    eprintln!(
        "{}: first answer at cycle {first}, then fresh on {fresh}/{warm} cycles, \
         median {median} evaluations; {c:?}",
        s.name
    );
    assert!(
        first < checks[0],
        "{}: first answer at cycle {first}",
        s.name
    );
    assert_eq!(next_check, checks.len(), "{}: dense checks", s.name);
    assert!(
        c.uncertified_scans - uncertified_then <= expect.max_uncertified,
        "{}: uncertified rescans: {c:?}",
        s.name
    );
    assert!(
        1000 * fresh >= expect.fresh_permille * warm,
        "{}: fresh on {fresh}/{warm} warm cycles",
        s.name
    );
    assert!(
        median <= expect.max_median,
        "{}: median {median} evaluations",
        s.name
    );
}

/// The answer's age along suspended-8's circle (N = 10, real-time budget, 3000 cycles as
/// `cablevib bench`): once the first scan has answered, the p99 of the end-effector
/// answer's age over the ok cycles is at most 8 cycles (as for taut cables; a
/// deterministic count of cycles, not a time), no cycle allocates, and every fresh answer
/// (age 0; every 10th here, every one in the slow sweep) equals the dense sagged reference's end-effector mode of its pose (λ 1e-9;
/// participation 1e-5, the tolerance next to an avoided crossing: the answers come from
/// the partner searches' crossings too). The sagged chains' poles, each found by its own
/// chain's count and followed between cycles, give the tracker a strong mode's coupling
/// to one chain and that chain's poles, so it searches the avoided-crossing partners
/// across them; before, the participation moved to modes it did not watch, and each
/// rescan swept the spectrum: age p99 273 cycles (max 300).
#[test]
fn ee_answer_age_p99_along_the_suspended_8_circle() {
    ee_answer_age_p99_along_the_circle(&sagged_robots(10)[0], 10);
}

/// The same along the paper's spatial robot's circle with sag (N = 10). There the
/// participation moves in avoided crossings to unwatched modes up to ~1.4× the answer's λ,
/// so the plain and weighted sum rules (which count those at weights 1 and λ_a/λ_k) stopped
/// certifying every ~150 cycles, each time a window rescan of ~20 cycles: age p99 18
/// (max 23) before the split bound and the neighbour searches by the count
/// (`modal::ee_tracker::bound`, `modal::ee_tracker::gap`), p99 8 (max 23) with them, and
/// since the sweeps cost fewer evaluations a mode (the spectrum search's Newton safeguard
/// and brackets) measured p99 0 (max 0).
/// The bound holds the modes below the answer by the resolvent's derivative over three
/// intervals and the weighted rule under 0.4 λ_a: each fresh answer is still checked
/// against the dense sagged reference: every 10th here (a dense solve is ~11 ms, 3000 of
/// them ~33 s), every one in the slow sweep.
#[test]
fn ee_answer_age_p99_along_the_paper_robot_circle_with_sag() {
    ee_answer_age_p99_along_the_circle(&sagged_robots(10)[2], 10);
}

mod slow {
    use super::*;

    #[test]
    #[ignore = "slow reference sweep: every fresh answer along the circle against the dense reference"]
    fn ee_answer_age_p99_along_the_paper_robot_circle_with_sag_every_answer_dense() {
        ee_answer_age_p99_along_the_circle(&sagged_robots(10)[2], 1);
    }

    /// The paper's spatial robot with sag at N = 40 (939 DOF, a dense solve ~0.1 s): age
    /// p99 ≤ 8 cycles as at N = 10, every 25th fresh answer against the dense sagged
    /// reference. Measured p99 0 (max 4); before the sweeps' cheaper modes and the
    /// certificate tried where a window sweep finds its answer, p99 9 (max 19).
    #[test]
    #[ignore = "slow reference sweep: fresh answers along the circle against the dense reference"]
    fn ee_answer_age_p99_along_the_paper_robot_circle_with_sag_at_40_elements() {
        ee_answer_age_p99_along_the_circle(&sagged_robots(40)[2], 25);
    }

    #[test]
    #[ignore = "slow reference sweep: every fresh answer along the circle against the dense reference"]
    fn ee_answer_age_p99_along_the_suspended_8_circle_every_answer_dense() {
        ee_answer_age_p99_along_the_circle(&sagged_robots(10)[0], 1);
    }
}

/// Along `s`'s circle (3000 cycles, real-time estimator): 0 allocations, age p99 ≤ 8
/// cycles, every `dense_every`-th fresh answer equal to the dense sagged reference (see
/// the callers).
fn ee_answer_age_p99_along_the_circle(s: &Scene, dense_every: usize) {
    let cycles = 3000;
    let mut est = Estimator::realtime(s).unwrap();
    let thr = est.params().modal.ee_participation_min;
    est.update(&circle_pose(s, 0, CIRCLE_PERIOD_S), Tmin::Scene);
    let mut ages = Vec::with_capacity(cycles);
    let (mut allocs, mut fresh, mut worst_l, mut worst_p) = (0, 0, 0.0f64, 0.0f64);
    for k in 1..=cycles {
        let before = thread_allocations();
        let e = *est.update(&circle_pose(s, k, CIRCLE_PERIOD_S), Tmin::Scene);
        allocs += thread_allocations() - before;
        assert!(e.is_ok(), "{} cycle {k}: {:?}", s.name, e.error);
        let Some(age) = ee_age(&e) else { continue };
        ages.push(u64::from(age));
        if age == 0 {
            fresh += 1;
            if (fresh - 1) % dense_every != 0 {
                continue;
            }
            let (dl, dp, _) = dense_ee(&est, thr);
            let err = (hz_to_lambda(ee_hz(&e)) - dl).abs() / dl;
            let perr = (ee_p(&e) - dp).abs();
            assert!(err <= LAMBDA_TOL, "{} cycle {k}: λ err {err:.1e}", s.name);
            assert!(
                perr <= TRACKED_P_TOL_CROSSING,
                "{} cycle {k}: p err {perr:.1e}",
                s.name
            );
            worst_l = worst_l.max(err);
            worst_p = worst_p.max(perr);
        }
    }
    assert_eq!(allocs, 0, "{}: {allocs} allocations", s.name);
    ages.sort_unstable();
    assert!(!ages.is_empty(), "{}: no answer in {cycles} cycles", s.name);
    // The bench's percentile (nearest rank).
    let p99 = percentile(&ages, 0.99);
    eprintln!(
        "{}: answers on {}/{cycles} cycles, {fresh} fresh; age p50 {} p99 {p99} max {}; \
         worst against dense: λ {worst_l:.1e}, p {worst_p:.1e}",
        s.name,
        ages.len(),
        percentile(&ages, 0.5),
        percentile(&ages, 1.0)
    );
    assert!(p99 <= 8, "{}: age p99 {p99} cycles", s.name);
}

/// A map's points: every one a cold start (0.25 m apart, beyond the warm jump), no cycle
/// budget. The scan walks the intervals between the chains' searched poles, each checked
/// pole-free by the blocked count, and answers as soon as it finds the answer (recording
/// past it only for a warm call that follows). Every answer against the dense reference
/// (LAMBDA_TOL, P_TOL: module docs), on the three sagged robots at N = 10.
///
/// Cost: the evaluations of D of the paper robot with sag at N = 40, a cold start at its
/// home pose (the first root, the poles' searches at one evaluation per n chain
/// evaluations, the scan to the answer): measured 155; the sweep by the count took 1 394
/// (699 to the answer, 28 modes at ~25 evaluations each, then the recording past it).
/// Bounded by 450 (evaluation counts are deterministic: no timing). The grid's first
/// suspended-8 pose failed when the walk was held to the closed-form scan's total of 1 500
/// evaluations (141 intervals, no answer).
#[test]
fn cold_answers_over_a_grid_match_the_dense_reference() {
    for s in sagged_robots(10) {
        let mut est = Estimator::new(&s).unwrap();
        let offsets = [
            (-0.25, -0.25),
            (0.0, -0.25),
            (0.25, 0.0),
            (0.0, 0.0),
            (-0.25, 0.25),
        ];
        let poses = offsets.map(|(dx, dy)| {
            let mut pose = home(&s);
            pose.position_m.x += dx;
            pose.position_m.y += dy;
            (format!("{} ({dx}, {dy})", s.name), pose)
        });
        let (checked, worst, _) = cold_answers_against_dense(&mut est, poses);
        eprintln!(
            "{}: {checked} cold answers, worst λ err {worst:.1e}",
            s.name
        );
        assert!(checked >= 3, "{}: {checked} feasible poses", s.name);
    }
    let s = &sagged_robots(40)[2];
    let mut est = Estimator::new(s).unwrap();
    let e = *est.update(&home(s), Tmin::Scene);
    assert!(
        e.is_ok() && ee_age(&e) == Some(0),
        "{}: {:?}",
        s.name,
        e.error
    );
    eprintln!("{} N 40: {} evaluations", s.name, e.eigen_evaluations);
    assert!(
        e.eigen_evaluations <= 450,
        "{}: {}",
        s.name,
        e.eigen_evaluations
    );
}

/// A map's rows: one estimator walks each row of cold points (a grid step apart, beyond
/// the warm jump), as `map` does, so every point's pole searches start from the previous
/// point's poles, scaled by the move of the pole below (`SagPoles::get`), and every scan
/// walks the intervals between those poles with its secant starts and weak roots. Every
/// answer against the dense reference (LAMBDA_TOL, P_TOL: module docs), on the three
/// sagged robots at N = 10: 3 rows of 9 points each.
///
/// Cost: the evaluations of D (pole searches at one per n chain evaluations) over a row of
/// the paper robot with sag at N = 40 (9 points 0.25 m apart, 7 feasible): measured 1 529;
/// 1 953 before the secant start removed only the poles a branch has (it started each root
/// next to the interval's lower pole: 6.3 evaluations a root), weak roots were read at a
/// 1e-5 step, and the pole searches started scaled and stopped at a 1e-8 step (~7 chain
/// evaluations a pole); 1 654 before a root next to an end where its branch stays finite
/// started at that end's Newton step and the pole searches started scaled by the chain's
/// string scale. Bounded by 1 600 (deterministic counts, no timing), which the code before
/// failed.
#[test]
fn map_rows_of_cold_answers_match_the_dense_reference() {
    for (s, step_m) in sagged_robots(10).iter().zip([0.5, 10.0, 0.25]) {
        let (mut checked, mut worst_l, mut worst_p) = (0, 0.0f64, 0.0f64);
        for row in -1..=1 {
            let mut est = Estimator::new(s).unwrap();
            let poses = (-4..=4).map(|col| {
                let mut pose = home(s);
                pose.position_m.x += col as f64 * step_m;
                pose.position_m.y += row as f64 * step_m;
                (format!("{} ({col}, {row})", s.name), pose)
            });
            let (c, l, p) = cold_answers_against_dense(&mut est, poses);
            checked += c;
            worst_l = worst_l.max(l);
            worst_p = worst_p.max(p);
        }
        eprintln!(
            "{}: {checked} cold answers along rows, worst λ err {worst_l:.1e}, p err {worst_p:.1e}",
            s.name
        );
        assert!(checked >= 9, "{}: {checked} feasible points", s.name);
    }
    // A map's row of the paper robot with sag at N = 40 (every point cold, 0.25 m apart).
    let s = &sagged_robots(40)[2];
    let mut est = Estimator::new(s).unwrap();
    let (mut total, mut points) = (0, 0);
    for col in -4..=4 {
        let mut pose = home(s);
        pose.position_m.x += 0.25 * col as f64;
        let e = *est.update(&pose, Tmin::Scene);
        if e.is_ok() {
            assert_eq!(ee_age(&e), Some(0), "{} ({col}, 0)", s.name);
            total += e.eigen_evaluations;
            points += 1;
        }
    }
    eprintln!("{} N 40: {total} evaluations over {points} points", s.name);
    assert!(points >= 5, "{}: {points} feasible points", s.name);
    assert!(total <= 1600, "{}: {total}", s.name);
}

/// An end-effector mode deep in a large sagging robot's spectrum: suspended-8 at N = 40
/// (939 modes) at (−3, 3.6, 2) m, where the dense reference's most end-effector-like modes
/// are #433 (p 0.366) and #448 (p 0.439) and none reaches the scene's 0.5. With the
/// threshold at 0.35 and 0.4 the answers are those two modes, past the 400 pole intervals
/// a cold scan used to stop at (it then reported none). Each held to the dense reference
/// (LAMBDA_TOL, P_TOL: module docs). At 0.5 the estimator reports no end-effector mode, as
/// the dense reference has none: the scan stops once the plain sum rule leaves less than
/// the threshold to the modes above it.
#[test]
fn ee_mode_past_400_pole_intervals_matches_the_dense_reference() {
    let mut s = sagged_robots(40)[0].clone();
    let mut pose = home(&s);
    pose.position_m.x = -3.0;
    pose.position_m.y = 3.6;
    for (thr, want) in [(0.35, Some(433)), (0.4, Some(448)), (0.5, None)] {
        s.model.ee_participation_min = thr;
        let mut est = Estimator::new(&s).unwrap();
        let e = *est.update(&pose, Tmin::Scene);
        assert!(e.is_ok(), "{} thr {thr}: {:?}", s.name, e.error);
        let d = est.dense_modes(true).unwrap();
        let idx = (0..d.lambda.len()).find(|&i| d.ee_participation[i] >= thr);
        assert_eq!(idx, want, "{} thr {thr}: dense answer", s.name);
        let Some(i) = idx else {
            assert!(e.ee_mode.is_none(), "{} thr {thr}: {:?}", s.name, e.ee_mode);
            continue;
        };
        let (dl, dp) = (d.lambda[i], d.ee_participation[i]);
        assert_eq!(ee_age(&e), Some(0), "{} thr {thr}: {:?}", s.name, e.error);
        let err = (hz_to_lambda(ee_hz(&e)) - dl).abs() / dl;
        let perr = (ee_p(&e) - dp).abs();
        eprintln!(
            "{} thr {thr}: mode #{i}, λ err {err:.1e}, p err {perr:.1e}, {} evaluations",
            s.name, e.eigen_evaluations
        );
        assert!(err <= LAMBDA_TOL, "{} thr {thr}: λ err {err:.1e}", s.name);
        assert!(
            perr <= P_TOL,
            "{} thr {thr}: p {} vs {dp}",
            s.name,
            ee_p(&e)
        );
    }
}
