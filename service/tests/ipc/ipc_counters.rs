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
    let _serial = crate::one_server_at_a_time();
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

/// Messages the hostile publisher sends in [`a_hostile_publisher_leaves_another_publishers_counts_exact`].
const HOSTILE_POSES: u64 = 100_000;

/// Two publishers of poses into one service: an honest one numbering its poses 1, 2, … and
/// flooding, and a hostile one sending 10⁵ poses with sequences 1, 2⁶³, 1, u64::MAX, 0,
/// random and steps of 2²⁰ (each step within the window counted 2²⁰ lost poses in the total
/// before the budget). Checked from the service's per-publisher counts
/// (`ServerReport::pose_publishers`), against what each publisher sent, counted here:
///
/// - the honest publisher's accounting is exact: received + overwritten = poses sent (every
///   received pose is estimated or skipped, so estimated + skipped + overwritten = sent for
///   it), no reset;
/// - the hostile publisher's counted losses stay within its budget (16 + 10⁷ per second since
///   its first pose, `SEQUENCE_QUEUE_SLACK`, `SEQUENCE_MAX_RATE_PER_S`): it cannot inflate
///   the total by 2²⁰ per message;
/// - the totals are the sums: estimated + skipped = poses received from both, overwritten and
///   resets = the publishers' sums.
#[test]
fn a_hostile_publisher_leaves_another_publishers_counts_exact() {
    let _serial = crate::one_server_at_a_time();
    use cablevib::stats::{SEQUENCE_GAP_WINDOW, SEQUENCE_MAX_RATE_PER_S, SEQUENCE_QUEUE_SLACK};
    let instance = format!("cvtest_{}_two_publishers", std::process::id());
    let names = ServiceNames::new(&instance);
    let scene = Scene::default_scene();
    let p = scene.ee_position_m;
    let position = [p.x, p.y, p.z];
    let stop = Arc::new(AtomicBool::new(false));
    let cfg = ServerConfig {
        instance: instance.clone(),
        wait: WaitMode::Event,
        stats_period: None,
        node_name: "cablevib-test-two-serve".into(),
        handle_signals: false,
        ..ServerConfig::default()
    };
    let service = spawn_thread(scene, cfg, stop.clone()).expect("service thread");
    let node = create_node("cablevib-test-two").expect("node");
    let honest = PoseInput::open(&node, &names).expect("honest pose input");
    let hostile = PoseInput::open(&node, &names).expect("hostile pose input");
    let output = EstimateOutput::open(&node, &names).expect("estimate output");
    wait_until("the service", || {
        honest.update_connections();
        hostile.update_connections();
        (honest.service_connected() && hostile.service_connected() && output.service_connected())
            .then_some(())
    });
    let pose = |seq: u64, t: u64| PoseSample::new(seq, t, position, IDENTITY_QUATERNION);
    let estimate_of = |seq: u64, t: u64| {
        wait_until(&format!("the estimate of pose {seq}"), || {
            while let Some(e) = output.try_receive().expect("receive") {
                if e.pose_sequence == seq && e.pose_timestamp_ns == t {
                    return Some(e);
                }
            }
            None
        })
    };
    // The honest publisher's first pose, answered: every later one is counted.
    let t = monotonic_now_ns();
    honest.send_pose(&pose(1, t)).expect("send");
    estimate_of(1, t);
    let hostile_start_ns = monotonic_now_ns();
    let (mut honest_sent, mut rng, mut step) = (1u64, 0x2545_f491_4f6c_dd1du64, 0u64);
    for i in 0..HOSTILE_POSES {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        let seq = match i % 7 {
            0 | 2 => 1,
            1 => 1 << 63,
            3 => u64::MAX,
            4 => 0,
            5 => rng,
            _ => {
                step += SEQUENCE_GAP_WINDOW + 1;
                step
            }
        };
        hostile
            .send_pose(&pose(seq, monotonic_now_ns()))
            .expect("send");
        if i % 5 == 0 {
            honest_sent += 1;
            honest
                .send_pose(&pose(honest_sent, monotonic_now_ns()))
                .expect("send");
        }
    }
    // The service keeps the newest pose of a drain, whichever queue it came from: the
    // hostile publisher sends markers until one is estimated, which means both queues were
    // drained up to it (an honest pose received after it would have been the newest).
    let mut hostile_sent = HOSTILE_POSES;
    wait_until("a hostile marker estimated", || {
        let t = monotonic_now_ns();
        hostile.send_pose(&pose(7, t)).expect("send");
        hostile_sent += 1;
        let end = Instant::now() + Duration::from_millis(50);
        while Instant::now() < end {
            while let Some(e) = output.try_receive().expect("receive") {
                if e.pose_timestamp_ns == t {
                    return Some(());
                }
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        None
    });
    // The honest publisher's last pose, alone in the queues: its estimate means every pose of
    // both publishers before it has been dealt with.
    honest_sent += 1;
    let t = monotonic_now_ns();
    honest.send_pose(&pose(honest_sent, t)).expect("send");
    estimate_of(honest_sent, t);
    let elapsed_ns = monotonic_now_ns() - hostile_start_ns;
    stop.store(true, Ordering::Release);
    let report = service
        .join()
        .expect("service thread panicked")
        .expect("service");

    let find = |id| {
        *report
            .pose_publishers
            .iter()
            .find(|c| c.key == id)
            .expect("publisher tracked")
    };
    let (h, x) = (find(honest.publisher_id()), find(hostile.publisher_id()));
    assert_eq!(h.resets, 0, "{report:?}");
    assert_eq!(
        h.received + h.lost,
        honest_sent,
        "the honest publisher: estimated + skipped + overwritten = sent ({report:?})"
    );
    let budget = SEQUENCE_QUEUE_SLACK + elapsed_ns / (1_000_000_000 / SEQUENCE_MAX_RATE_PER_S);
    assert!(
        x.lost <= budget,
        "hostile losses {} over the budget {budget}",
        x.lost
    );
    assert!(x.received <= hostile_sent && x.resets > 0, "{x:?}");
    assert_eq!(report.pose_publishers.len(), 2);
    assert_eq!(
        report.cycles + report.skipped_poses,
        h.received + x.received
    );
    assert_eq!(report.overwritten_poses, h.lost + x.lost);
    assert_eq!(report.sequence_resets, x.resets);
    eprintln!(
        "honest: {honest_sent} sent, {} received, {} overwritten; hostile: {hostile_sent} sent, \
         {} received, {} counted lost (budget {budget} over {:.3} s), {} resets",
        h.received,
        h.lost,
        x.received,
        x.lost,
        elapsed_ns as f64 * 1e-9,
        x.resets
    );
}
