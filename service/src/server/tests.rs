//! Unit tests of the service loop's pure parts (set-points, margin answers, counters).
use super::*;
use cablevib_ipc::MarginRequest;

#[test]
fn per_cable_set_points_give_each_cable_its_bound() {
    let s = TminSetpoint::per_cable(1, 0, 50.0, &[10.0, 70.0, 20.0]).unwrap();
    let mut out = [0.0; 5];
    setpoint_bounds(&s, &mut out);
    assert_eq!(
        out,
        [10.0, 70.0, 20.0, 50.0, 50.0],
        "cables without a value use t_min_n"
    );
    let mut bad = s;
    bad.per_cable_count = 99;
    setpoint_bounds(&bad, &mut out);
    assert!(out.iter().all(|t| t.is_nan()));
}

/// More per-cable values than the robot has cables (9 or 16 on 8, the extras NaN, 0 or
/// valid) is refused (every bound NaN → `t_min_out_of_range`), never taken with the extras
/// ignored; exactly 8 is taken.
#[test]
fn per_cable_set_points_for_cables_that_do_not_exist_are_refused() {
    let t_max = [350.0; 8];
    for (count, extra) in [
        (9, f64::NAN),
        (9, 0.0),
        (9, 10.0),
        (16, f64::NAN),
        (16, 10.0),
    ] {
        let mut v = [10.0; 16];
        v[8..].fill(extra);
        let s = TminSetpoint::per_cable(1, 0, 10.0, &v[..count]).unwrap();
        let mut out = [1.0; 8];
        setpoint_bounds(&s, &mut out);
        assert!(
            out.iter().all(|t| t.is_nan()),
            "{count} values, extras {extra}: {out:?}"
        );
        assert!(first_refused(&out, &t_max).is_some());
    }
    let s = TminSetpoint::per_cable(1, 0, 10.0, &[20.0; 8]).unwrap();
    let mut out = [1.0; 8];
    setpoint_bounds(&s, &mut out);
    assert_eq!(out, [20.0; 8]);
    // Not well formed (TminSetpoint::is_well_formed): a NaN uniform value is refused even
    // when every cable has its own value.
    let mut s = s;
    s.t_min_n = f64::NAN;
    setpoint_bounds(&s, &mut out);
    assert!(out.iter().all(|t| t.is_nan()));
}

/// A requirement outside [REQUIRED_F1_MIN_HZ, REQUIRED_F1_MAX_HZ] is refused with
/// `invalid_request`: 5e-324 Hz gave status ok with a margin ratio of +inf.
#[test]
fn degenerate_requirements_are_refused_not_answered_with_infinities() {
    let ok = Latest {
        cycle: 0,
        pose_sequence: 9,
        status: StatusCode::Ok,
        f1_hz: 9.5,
        pose: Pose::at(Vector3::new(0.0, 0.0, 1.25)),
    };
    for f in [5e-324, 1e-9, 1e7, 1e308] {
        let r = margin_response(&MarginRequest::new(1, 0, f), Some(ok), Ok(42.0), 1);
        assert_eq!(r.status_code(), Some(StatusCode::InvalidRequest), "{f}");
        assert!(r.margin_ratio.is_nan() && r.margin_hz.is_nan(), "{f}");
    }
    for f in [
        cablevib_ipc::REQUIRED_F1_MIN_HZ,
        cablevib_ipc::REQUIRED_F1_MAX_HZ,
    ] {
        let r = margin_response(&MarginRequest::new(1, 0, f), Some(ok), Ok(42.0), 1);
        assert!(r.is_ok(), "{f}");
        // Independent: the ratio and margin by their definitions, finite.
        assert_eq!(r.margin_ratio, 9.5 / f);
        assert_eq!(r.margin_hz, 9.5 - f);
        assert!(r.margin_ratio.is_finite() && r.margin_hz.is_finite());
    }
}

#[test]
fn set_points_the_scene_would_refuse_are_refused() {
    let t_max = [350.0; 3];
    assert_eq!(first_refused(&[10.0, 70.0, 20.0], &t_max), None);
    let subnormal = f64::MIN_POSITIVE / 4.0;
    for bad in [0.0, -0.0, subnormal, -3.0, f64::NAN, f64::INFINITY, 351.0] {
        let r = first_refused(&[10.0, bad, 20.0], &t_max);
        assert!(
            r.is_some_and(|v| v.to_bits() == bad.to_bits()),
            "{bad}: {r:?}"
        );
    }
    assert_eq!(
        first_refused(&[200.0], &[100.0]),
        Some(200.0),
        "per-cable t_max"
    );
    let mut out = [1.0; 8];
    setpoint_bounds(&TminSetpoint::zeroed(), &mut out);
    assert_eq!(first_refused(&out, &[350.0; 8]), Some(0.0));
}

#[test]
fn margin_answers() {
    let req = MarginRequest::new(5, 0, 8.0);
    let none = margin_response(&req, None, Ok(f64::NAN), 1);
    assert_eq!(none.status_code(), Some(StatusCode::NoPoseYet));
    let ok = Latest {
        cycle: 0,
        pose_sequence: 9,
        status: StatusCode::Ok,
        f1_hz: 9.5,
        pose: Pose::at(Vector3::new(0.0, 0.0, 1.25)),
    };
    let r = margin_response(&req, Some(ok), Ok(42.0), 1);
    assert!(r.is_ok());
    assert_eq!((r.pose_sequence, r.f1_hz, r.margin_hz), (9, 9.5, 1.5));
    assert_eq!(r.t_min_required_n, 42.0);
    let bad_req = MarginRequest::new(6, 0, -1.0);
    assert_eq!(
        margin_response(&bad_req, None, Ok(f64::NAN), 1).status_code(),
        Some(StatusCode::InvalidRequest)
    );
    let r = margin_response(&bad_req, Some(ok), Ok(f64::NAN), 1);
    assert_eq!(r.status_code(), Some(StatusCode::InvalidRequest));
    assert!(r.margin_hz.is_nan());
    let failed = Latest {
        status: StatusCode::OutsideWorkspace,
        f1_hz: f64::NAN,
        ..ok
    };
    let r = margin_response(&req, Some(failed), Ok(f64::NAN), 1);
    assert_eq!(r.status_code(), Some(StatusCode::OutsideWorkspace));
    assert_eq!(r.pose_sequence, 9);
    assert!(r.f1_hz.is_nan());
    // A failed inverse search is its status (never ok with a NaN T_min); an unreachable
    // requirement is ok with T_min +∞.
    let r = margin_response(&req, Some(ok), Err(StatusCode::CableSlack), 1);
    assert_eq!(r.status_code(), Some(StatusCode::CableSlack));
    assert_eq!(r.pose_sequence, 9);
    assert!(r.f1_hz.is_nan() && r.t_min_required_n.is_nan());
    let r = margin_response(&req, Some(ok), Ok(f64::INFINITY), 1);
    assert!(r.is_ok() && r.t_min_required_n == f64::INFINITY);
}

#[test]
fn the_inverse_answer_carries_failures_as_statuses() {
    use crate::estimator::{EstimatorError, RejectedInput, TminAnswer, TminQueryError};
    use inverse_worker::carried;
    let a = TminAnswer {
        t_min_n: 12.5,
        f1_hz: 9.0,
        evaluations: 30,
        resolution_n: 0.5,
    };
    assert_eq!(carried(Ok(a)), Ok(12.5));
    let unreachable = TminQueryError::Unreachable {
        required_hz: 50.0,
        f1_max_hz: 11.0,
        t_min_n: 88.0,
    };
    assert_eq!(carried(Err(unreachable)), Ok(f64::INFINITY));
    let bad_pose = EstimatorError::Input(RejectedInput::NonFinitePose);
    assert_eq!(
        carried(Err(TminQueryError::Pose(bad_pose))),
        Err(StatusCode::InvalidInput)
    );
    assert_eq!(
        carried(Err(TminQueryError::BadRequirement(f64::NAN))),
        Err(StatusCode::InvalidRequest)
    );
}

/// Seven clients flooding the inverse search with a new requirement at every post and a
/// legitimate client asking a requirement of its own (9.000, 9.001, ... Hz), ten rounds: each
/// of its requirements is answered within 2 SLOTS of the worker's searches (the round robin's
/// bound; a worker serving the flooding slots first never answers it). Each answer is checked
/// independently: the forward estimator at that T_min reaches the requirement (f1 within
/// 1e-6 relative, the search's acceptance).
#[test]
fn one_flooding_margin_client_does_not_starve_another() {
    use inverse_worker::{InverseJob, InverseWorker, SLOTS};
    use std::time::{Duration, Instant};
    let scene = Scene::default_scene();
    let est = Estimator::realtime(&scene).unwrap();
    let pose = Pose {
        position_m: scene.ee_position_m,
        orientation_wxyz: scene.ee_orientation_wxyz,
    };
    let hint_n = min_max(&est.default_t_min_n()[..scene.n_cables()]).1;
    let mut worker = InverseWorker::spawn(&est).unwrap();
    let job = |f: f64| InverseJob {
        pose,
        cycle: 0,
        required_f1_hz: f,
        hint_n,
    };
    // Fairness is counted in the worker's turns, not in wall time: on a loaded machine the
    // worker (niced, resting 19x its search time) may wait long for a core, and that is the
    // machine's doing, not the flood's. Each round the legitimate client asks a requirement
    // of its own and posts it with every flood request (as the loop posts each client's
    // newest request); its answer must come within 2 SLOTS finished searches of the round's
    // start: one search in progress, at most SLOTS - 1 others' turns of the round robin, and
    // at most SLOTS - 1 flooding slots served first once as new clients.
    let (rounds, mut posts) = (10, 0u64);
    let turns_max = 2 * SLOTS as u64;
    let mut answered = Vec::with_capacity(rounds);
    for round in 0..rounds {
        let required = 9.0 + round as f64 * 1e-3;
        let start = worker.searches_done();
        let give_up = Instant::now() + Duration::from_secs(300);
        let answer = loop {
            if let Some(a) = worker.answer(0).filter(|a| a.required_f1_hz == required) {
                break a;
            }
            let turns = worker.searches_done() - start;
            assert!(
                turns <= turns_max,
                "round {round}: no answer to the legitimate client after {turns} searches \
                 (at most {turns_max} expected); {posts} flood posts"
            );
            assert!(
                Instant::now() < give_up,
                "round {round}: the worker finished {turns} searches in 300 s"
            );
            worker.post(0, job(required));
            for slot in 1..SLOTS {
                posts += 1;
                worker.post(slot, job(5.0 + (posts % 4001) as f64 * 1e-3));
            }
        };
        let t = answer.t_min_n.ok().filter(|t| t.is_finite());
        assert!(t.is_some(), "round {round}: {answer:?}");
        answered.push((required, t.unwrap_or(f64::NAN)));
    }
    eprintln!("legitimate client: {rounds} rounds answered; {posts} flood posts");
    let mut check = Estimator::realtime(&scene).unwrap();
    for (required, t_min) in answered {
        let e = *check.update(&pose, Tmin::Uniform(t_min));
        assert!(
            e.is_ok() && e.f1_hz >= required * (1.0 - 1e-6),
            "{t_min} N for {required} Hz: {e:?}"
        );
    }
}
