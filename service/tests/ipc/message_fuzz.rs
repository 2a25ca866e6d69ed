//! Garbage messages: random bytes reinterpreted as the #[repr(C)] input messages (every bit
//! pattern is a valid value of their u32/u64/f64 fields), mapped to the estimator exactly as
//! the service maps them (`service::server`: pose fields → `Pose`, set-point →
//! `setpoint_bounds` then `update_with_bounds`, margin request → `is_valid` then `t_min_for_f1`). Each must give a
//! status — never a panic, never a NaN in an estimate marked ok — and the next valid pose
//! must be answered exactly as a fresh estimator answers it.
use cablevib::estimator::Estimator;
use cablevib::estimator::Tmin;
use cablevib::kinematics::Pose;
use cablevib::scene::Scene;
use cablevib_ipc::{MarginRequest, PoseSample, TminSetpoint};
use cablevib_service::server::setpoint_bounds;
use cablevib_testkit::ee_hz;
use nalgebra::Vector3;
use proptest::prelude::*;

fn from_bytes<T: Copy>(bytes: &[u8]) -> T {
    assert_eq!(bytes.len(), std::mem::size_of::<T>());
    // SAFETY: T is a #[repr(C)] Copy type of u32/u64/f64 fields (asserted layouts in
    // cablevib-ipc, no padding, no bool/enum fields): every bit pattern is a valid value.
    unsafe { std::ptr::read_unaligned(bytes.as_ptr() as *const T) }
}

fn pose_of(p: &PoseSample) -> Pose {
    Pose {
        position_m: Vector3::new(p.position_m[0], p.position_m[1], p.position_m[2]),
        orientation_wxyz: p.orientation_wxyz,
    }
}

/// Byte patterns that hit the interesting values: random bytes, or fields made of NaN,
/// ±Inf, huge, tiny, negative and ordinary values.
fn special_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(f64::NEG_INFINITY),
        Just(1e308),
        Just(-1e308),
        Just(5e-324),
        Just(0.0),
        Just(-0.0),
        -10.0..10.0f64,
        any::<f64>(),
    ]
}

fn pose_bytes() -> impl Strategy<Value = Vec<u8>> {
    let n = std::mem::size_of::<PoseSample>();
    prop_oneof![
        proptest::collection::vec(any::<u8>(), n),
        (any::<u64>(), proptest::collection::vec(special_f64(), 7)).prop_map(|(seq, v)| {
            let mut p = PoseSample::zeroed();
            p.sequence = seq;
            p.position_m = [v[0], v[1], v[2]];
            p.orientation_wxyz = [v[3], v[4], v[5], v[6]];
            let b: [u8; std::mem::size_of::<PoseSample>()] = unsafe { std::mem::transmute(p) };
            b.to_vec()
        }),
        // Valid poses in the frame: the ok path is fuzzed too. Identity-oriented (either
        // sign): the scene's end-effector is a point mass, where a rotation is refused.
        (
            -1.0..1.0f64,
            -1.0..1.0f64,
            0.3..2.2f64,
            proptest::collection::vec(-1.0..1.0f64, 4)
        )
            .prop_map(|(x, y, z, q)| {
                let w = if q[0] < 0.0 { -1.0 } else { 1.0 };
                let p = PoseSample::new(1, 0, [x, y, z], [w, 0.0, 0.0, 0.0]);
                let b: [u8; std::mem::size_of::<PoseSample>()] = unsafe { std::mem::transmute(p) };
                b.to_vec()
            }),
    ]
}

static OK: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
static ALL: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn garbage_messages_get_a_status_and_lose_nothing(
        pose in pose_bytes(),
        tmin in proptest::collection::vec(any::<u8>(), std::mem::size_of::<TminSetpoint>()),
        tmin_value in special_f64(),
        margin in proptest::collection::vec(any::<u8>(), std::mem::size_of::<MarginRequest>()),
        required in special_f64(),
    ) {
        let scene = Scene::default_scene().with_model(cablevib::scene::ElementKind::Fem, 10);
        let mut est = Estimator::new(&scene).unwrap();
        let p: PoseSample = from_bytes(&pose);
        // A set-point: random bytes, a uniform one with a special value, or a valid one.
        let s: TminSetpoint = match tmin[0] % 3 {
            0 => from_bytes(&tmin),
            1 => TminSetpoint::uniform(1, 0, tmin_value),
            _ => TminSetpoint::uniform(1, 0, 40.0 + f64::from(tmin[1]) / 4.0),
        };
        let mut t_min = [0.0; cablevib::scene::MAX_CABLES];
        let n = scene.n_cables();
        setpoint_bounds(&s, &mut t_min[..n]);
        let e = *est.update(&pose_of(&p), Tmin::PerCable(&t_min[..n]));
        ALL.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        if e.is_ok() {
            OK.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            prop_assert!(e.f1_hz.is_finite() && e.f1_hz > 0.0);
            prop_assert!(e.tensions().iter().all(|t| t.is_finite()));
            prop_assert!(e.ee_mode.is_some_and(|m| m.frequency_hz.is_finite()));
        } else {
            prop_assert!(e.f1_hz.is_nan(), "a non-ok estimate carries no frequency");
        }
        // A margin request of garbage: validated first, as the service does.
        let mut m: MarginRequest = from_bytes(&margin);
        if margin[0] % 2 == 0 {
            m.required_f1_hz = required;
        }
        if m.is_valid() && e.is_ok() {
            let _ = est.t_min_for_f1(&pose_of(&p), m.required_f1_hz);
        }
        // The next valid pose is answered exactly as by a fresh estimator.
        let good = Pose::at(Vector3::new(0.21, -0.13, 1.1));
        let next = *est.update(&good, Tmin::Uniform(60.0));
        let mut fresh = Estimator::new(&scene).unwrap();
        let want = *fresh.update(&good, Tmin::Uniform(60.0));
        prop_assert!(next.is_ok() && want.is_ok());
        prop_assert!((next.f1_hz - want.f1_hz).abs() <= 1e-11 * want.f1_hz);
        let (next_ee, want_ee) = (ee_hz(&next), ee_hz(&want));
        prop_assert!((next_ee - want_ee).abs() <= 1e-10 * want_ee);
        for (a, b) in next.tensions().iter().zip(want.tensions()) {
            prop_assert!((a - b).abs() <= 1e-9 * b);
        }
    }
}

#[test]
fn the_fuzz_reaches_the_ok_path() {
    // Runs after (or alongside) the property: at least some garbage-free cases must be ok,
    // or the property above would only ever test the rejection paths.
    garbage_messages_get_a_status_and_lose_nothing();
    let (ok, all) = (
        OK.load(std::sync::atomic::Ordering::Relaxed),
        ALL.load(std::sync::atomic::Ordering::Relaxed),
    );
    assert!(all >= 400 && ok >= 20, "{ok} ok of {all} cases");
    eprintln!("{ok} ok estimates of {all} fuzzed messages");
}
