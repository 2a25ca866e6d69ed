//! The service's pose counters add up over real iceoryx2 services: a publisher floods poses
//! much faster than the service drains them, so most are overwritten in the subscriber queue
//! (`POSE_BUFFER`, safe overflow) before the service sees them, and every pose sent is still
//! accounted for exactly once: estimated, skipped (received, a newer one queued) or
//! overwritten (a gap in the pose sequence).
//!
//! The service runs in a thread of this process (`server::spawn_thread`, as the demo does)
//! under an instance name of its own (process id + test name), so that its `ServerReport` can
//! be read; every wait is bounded.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use cablevib::scene::Scene;
use cablevib_ipc::{monotonic_now_ns, PoseSample, ServiceNames, IDENTITY_QUATERNION};
use cablevib_service::ports::{create_node, EstimateOutput, PoseInput};
use cablevib_service::server::{spawn_thread, ServerConfig};
use cablevib_service::WaitMode;

/// Longest wait for anything (service start, an estimate, the thread's end).
const TIMEOUT: Duration = Duration::from_secs(20);
/// Poses in the flood: far more than the queue holds, sent in a few ms while one estimate
/// takes tens of µs, so thousands are overwritten.
const FLOOD_POSES: u64 = 20_000;

/// Waits up to [`TIMEOUT`] for `f` to return `Some`.
fn wait_until<T>(what: &str, mut f: impl FnMut() -> Option<T>) -> T {
    let end = Instant::now() + TIMEOUT;
    loop {
        if let Some(t) = f() {
            return t;
        }
        assert!(Instant::now() < end, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(1));
    }
}

#[test]
fn flooded_poses_are_estimated_skipped_or_overwritten_exactly_once() {
    let instance = format!("cvtest_{}_flood_counters", std::process::id());
    let names = ServiceNames::new(&instance);
    let scene = Scene::default_scene();
    let p = scene.ee_position_m;
    let position = [p.x, p.y, p.z];
    let stop = Arc::new(AtomicBool::new(false));
    let cfg = ServerConfig {
        instance: instance.clone(),
        wait: WaitMode::Event,
        stats_period: None,
        node_name: "cablevib-test-flood-serve".into(),
        handle_signals: false,
        ..ServerConfig::default()
    };
    let service = spawn_thread(scene, cfg, stop.clone()).expect("service thread");

    let node = create_node("cablevib-test-flood").expect("node");
    let input = PoseInput::open(&node, &names).expect("pose input");
    let output = EstimateOutput::open(&node, &names).expect("estimate output");
    wait_until("the service", || {
        input.update_connections();
        (input.service_connected() && output.service_connected()).then_some(())
    });
    let pose = |seq: u64| PoseSample::new(seq, monotonic_now_ns(), position, IDENTITY_QUATERNION);
    let estimate_of = |seq: u64| {
        wait_until(&format!("the estimate of pose {seq}"), || {
            while let Some(e) = output.try_receive().expect("receive") {
                if e.pose_sequence == seq {
                    return Some(e);
                }
            }
            None
        })
    };
    // Pose 1 first, answered: the service has received this publisher's first sequence, so
    // every later pose is in its queue or counted from a gap.
    input.send_pose(&pose(1)).expect("send");
    assert!(estimate_of(1).is_ok());
    for seq in 2..=FLOOD_POSES {
        input.send_pose(&pose(seq)).expect("send");
    }
    // The last pose is never skipped (nothing newer) nor overwritten (nothing after it): its
    // estimate means that every pose sent has been dealt with, so the count is exact.
    let last = estimate_of(FLOOD_POSES);
    assert!(last.is_ok());
    stop.store(true, Ordering::Release);
    let report = service
        .join()
        .expect("service thread panicked")
        .expect("service");

    let accounted = report.cycles + report.skipped_poses + report.overwritten_poses;
    assert_eq!(
        accounted, FLOOD_POSES,
        "every pose estimated, skipped or overwritten exactly once: {report:?}"
    );
    assert!(
        report.overwritten_poses > 0,
        "the flood outran the service: poses were overwritten in the queue ({report:?})"
    );
    assert_eq!(last.skipped_poses, report.skipped_poses);
    eprintln!(
        "{FLOOD_POSES} poses: {} estimated, {} skipped, {} overwritten",
        report.cycles, report.skipped_poses, report.overwritten_poses
    );
}
