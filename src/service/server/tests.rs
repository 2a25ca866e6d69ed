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
    use crate::estimator::{EstimatorError, InputError, TminAnswer, TminQueryError};
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
    let bad_pose = EstimatorError::Input(InputError::NonFinitePose);
    assert_eq!(
        carried(Err(TminQueryError::Pose(bad_pose))),
        Err(StatusCode::InvalidInput)
    );
    assert_eq!(
        carried(Err(TminQueryError::BadRequirement(f64::NAN))),
        Err(StatusCode::InvalidRequest)
    );
}
