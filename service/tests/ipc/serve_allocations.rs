//! `serve` over 10⁵ cycles makes no heap allocation from the system allocator: iceoryx2
//! 0.10 still allocates a small shared state per loan (each published estimate, each margin
//! response) and per received request (`ChunkMutSharedState::new` builds an `Rc`/`Arc` for
//! every service type), and those come from the constant-time block pool the service
//! thread holds (`alloc_count::claim_pool`), counted apart.
//!
//! The service runs in a thread of this process (`server::spawn_thread`, as the demo does)
//! with this binary's counting allocator, under an instance name of its own; a client sends
//! 10⁵ poses along the paper's circle, each answered before the next, and a margin request
//! every 10th cycle. The counts are the service thread's own (`ServerReport`).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use cablevib::scene::Scene;
use cablevib::trajectory::{Circle, CIRCLE_RADIUS_M, SAMPLE_PERIOD_S};
use cablevib_ipc::{
    monotonic_now_ns, MarginRequest, PoseSample, ServiceNames, IDENTITY_QUATERNION,
};
use cablevib_service::ports::{create_node, EstimateOutput, MarginClient, PoseInput};
use cablevib_service::server::{spawn_thread, ServerConfig};
use cablevib_service::WaitMode;

/// Longest wait for anything (service start, an answer).
const TIMEOUT: Duration = Duration::from_secs(20);
/// Cycles of the run.
const CYCLES: u64 = 100_000;

/// Serves `cycles` poses (a margin request every 10th) with the pool on or off; the report.
fn serve(cycles: u64, alloc_pool: bool) -> cablevib_service::server::ServerReport {
    let _serial = crate::one_server_at_a_time();
    let instance = format!("cvtest_{}_serve_alloc_{alloc_pool}", std::process::id());
    let names = ServiceNames::new(&instance);
    let scene = Scene::default_scene();
    let circle = Circle::new(&scene, CIRCLE_RADIUS_M, 4.0).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let cfg = ServerConfig {
        instance: instance.clone(),
        wait: WaitMode::Event,
        stats_period: None,
        node_name: format!("cablevib-test-alloc-serve-{alloc_pool}"),
        handle_signals: false,
        alloc_pool,
        ..ServerConfig::default()
    };
    let service = spawn_thread(scene, cfg, stop.clone()).expect("service thread");

    let node = create_node(&format!("cablevib-test-alloc-{alloc_pool}")).expect("node");
    let input = PoseInput::open(&node, &names).expect("pose input");
    let output = EstimateOutput::open(&node, &names).expect("estimate output");
    let margin = MarginClient::open(&node, &names).expect("margin client");
    let end = Instant::now() + TIMEOUT;
    loop {
        input.update_connections();
        if input.service_connected() && output.service_connected() && margin.service_connected() {
            break;
        }
        assert!(Instant::now() < end, "the service's ports");
        std::thread::sleep(Duration::from_millis(1));
    }
    let mut margins = 0;
    for seq in 1..=cycles {
        let p = circle.position_at(seq as f64 * SAMPLE_PERIOD_S);
        let pose = PoseSample::new(
            seq,
            monotonic_now_ns(),
            [p.x, p.y, p.z],
            IDENTITY_QUATERNION,
        );
        input.send_pose(&pose).expect("send");
        loop {
            let e = output
                .wait(WaitMode::Event, TIMEOUT)
                .expect("receive")
                .unwrap_or_else(|| panic!("no estimate for pose {seq}"));
            if e.answers(&pose) {
                assert!(e.is_ok(), "pose {seq}: {e:?}");
                break;
            }
        }
        if seq % 10 == 0 {
            let req = MarginRequest::new(seq, monotonic_now_ns(), 8.0);
            let r = margin
                .query(&req, WaitMode::Event, TIMEOUT)
                .expect("query")
                .expect("a margin answer");
            assert_eq!(r.request_sequence, seq);
            margins += 1;
        }
    }
    stop.store(true, Ordering::Release);
    let report = service
        .join()
        .expect("service thread panicked")
        .expect("service");
    eprintln!(
        "pool {alloc_pool}: {} cycles, {margins} margin requests: heap allocations per cycle \
         {:.5} from the system allocator ({} in the first cycle), {:.4} from the pool \
         (iceoryx2's per loan and per request: {:.4})",
        report.cycles,
        report.allocations_per_cycle,
        report.allocations_first_cycle,
        report.pool_allocations_per_cycle,
        report.iceoryx2_allocations_per_cycle
    );
    assert_eq!(report.cycles, cycles);
    assert_eq!(report.margin_requests, margins);
    report
}

#[test]
fn a_hundred_thousand_served_cycles_allocate_nothing_from_the_system() {
    let report = serve(CYCLES, true);
    // The first cycle maps the client's data segments (iceoryx2 connecting its ports, a
    // few tens of allocations once); every cycle after it: none from the system allocator.
    assert_eq!(
        report.allocations_per_cycle, 0.0,
        "allocations from the system allocator on the service thread: {report:?}"
    );
    // The loans are still made, from the pool: one per estimate, two per margin request
    // (the request received, the response loaned). So the count above is not 0 by not
    // counting.
    assert!(
        report.pool_allocations_per_cycle >= 1.0,
        "pool allocations per cycle {}",
        report.pool_allocations_per_cycle
    );
}

#[test]
fn without_the_pool_iceoryx2_allocates_per_loan() {
    // The same service with the pool off (what it was before): iceoryx2's allocations go
    // to the system allocator and are counted there, one per estimate and two per margin
    // request.
    let report = serve(10_000, false);
    assert_eq!(report.pool_allocations_per_cycle, 0.0);
    assert!(
        report.allocations_per_cycle >= 1.0,
        "system allocations per cycle {}",
        report.allocations_per_cycle
    );
}
