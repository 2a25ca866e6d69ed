//! What the service is told ([`ServerConfig`]) and what it reports when it stops
//! ([`ServerReport`], [`StopReason`]), and the log lines of a run's start and end.

use core::time::Duration;

use crate::scene::Scene;
use iceoryx2::identifiers::UniquePublisherId;

use crate::stats::{Percentiles, SenderCounts, StatusHistogram};
use crate::WaitMode;

/// How the service runs.
#[derive(Debug, Clone)]
pub struct ServerConfig {
    /// Instance name prefixing the service names (see [`cablevib_ipc::ServiceNames::new`]).
    pub instance: String,
    /// Busy-poll or block on the wake-service event.
    pub wait: WaitMode,
    /// Period of the statistics log line; `None` logs none.
    pub stats_period: Option<Duration>,
    /// Stop after this many estimator cycles.
    pub max_cycles: Option<u64>,
    /// Pin the service thread to this CPU.
    pub cpu: Option<usize>,
    /// SCHED_FIFO and mlockall.
    pub realtime: bool,
    /// iceoryx2 node name (shown by `iox2 node list`).
    pub node_name: String,
    /// Check SIGINT/SIGTERM through the node (the process's iceoryx2 signal handler). Turn off
    /// when another thread of the same process owns signal handling.
    pub handle_signals: bool,
    /// Serve iceoryx2's per-loan and per-request allocations from the counting allocator's
    /// constant-time block pool ([`crate::alloc_count::claim_pool`]; default true). Off: from
    /// the system allocator (to measure the difference).
    pub alloc_pool: bool,
}

impl Default for ServerConfig {
    fn default() -> ServerConfig {
        ServerConfig {
            instance: String::new(),
            wait: WaitMode::Spin,
            stats_period: Some(Duration::from_secs(5)),
            max_cycles: None,
            cpu: None,
            realtime: false,
            node_name: "cablevib-serve".into(),
            handle_signals: true,
            alloc_pool: true,
        }
    }
}

/// Why the loop ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// SIGINT or SIGTERM.
    Signal,
    /// The stop flag was set (another thread).
    Requested,
    /// `max_cycles` reached.
    MaxCycles,
}

/// Totals of one run of the service.
#[derive(Debug, Clone)]
pub struct ServerReport {
    /// Why it stopped.
    pub stop: StopReason,
    /// Estimator cycles (= estimates published).
    pub cycles: u64,
    /// Poses received but not estimated because a newer one was queued.
    pub skipped_poses: u64,
    /// Poses never received: overwritten in the subscriber queue ([`crate::ports::POSE_BUFFER`], safe
    /// overflow) before a drain, counted from the gaps in each publisher's pose sequence
    /// (forward only, within [`crate::stats::SEQUENCE_GAP_WINDOW`]). Every pose a connected
    /// publisher that numbers its poses one by one sent after its first received one is
    /// estimated, skipped or overwritten: `cycles + skipped_poses + overwritten_poses` = poses
    /// sent.
    pub overwritten_poses: u64,
    /// Times a publisher's pose sequence went back, repeated or jumped past the window or its
    /// budget (a restarted counter, a broken or hostile publisher): counted here, never as
    /// poses lost.
    pub sequence_resets: u64,
    /// Per pose publisher still tracked at the end: poses received, overwritten (lost) and
    /// resets. For each publisher that numbers its poses one by one from its first received
    /// one, received + overwritten = poses sent; the totals are their sums (plus those of
    /// publishers no longer tracked).
    pub pose_publishers: Vec<SenderCounts<UniquePublisherId>>,
    /// Estimates whose status was not ok.
    pub invalid_inputs: u64,
    /// Estimates per status code (index = wire value; the last slot collects unknown codes).
    pub status_counts: StatusHistogram,
    /// T_min set-points received.
    pub t_min_setpoints: u64,
    /// Margin requests answered.
    pub margin_requests: u64,
    /// iceoryx2 receive/loan/send failures (the loop continues after each).
    pub ipc_errors: u64,
    /// Dead nodes whose stale resources were removed at start.
    pub stale_nodes_removed: usize,
    /// Compute time per cycle over the last [`super::RUN_RING`] cycles, ns.
    pub compute: Percentiles,
    /// Heap allocations from the system allocator on the cycle path (the service thread) per
    /// cycle after the first (0 when no counting allocator is given).
    pub allocations_per_cycle: f64,
    /// Heap allocations from the system allocator in the first cycle: iceoryx2 connecting the
    /// first pose publisher's data segment (once per run).
    pub allocations_first_cycle: u64,
    /// Heap allocations served by the block pool on the cycle path per cycle (iceoryx2's per
    /// loan and per request; 0 without the counting allocator).
    pub pool_allocations_per_cycle: f64,
    /// Of those, the ones iceoryx2 0.10 makes by design per cycle: one per loan (estimate,
    /// margin response) and one per received margin request.
    pub iceoryx2_allocations_per_cycle: f64,
    /// What happened to the vibration samples (taken, refused by kind, lost, filled, window
    /// restarts, abandoned evaluations).
    pub vibration: crate::measured::Counters,
}

/// The log line at the start of a run.
pub(super) fn log_start(scene: &Scene, cfg: &ServerConfig) {
    tracing::info!(
        "serving instance \"{}\" ({}): scene `{}` ({} cables, {} × {} elements/cable), wait {}, T_min {} N, \
         T_max {} N",
        cfg.instance,
        if cfg.instance.trim_matches('/').is_empty() {
            "bare service names".to_string()
        } else {
            format!("services \"{}/cablevib/...\"", cfg.instance.trim_matches('/'))
        },
        scene.name,
        scene.n_cables(),
        scene.model.element.as_str(),
        scene.model.elements_per_cable,
        cfg.wait.as_str(),
        scene.t_min_n,
        scene.t_max_n
    );
}

/// The log line at the end of a run.
pub(super) fn log_stop(reason: StopReason, report: &ServerReport) {
    tracing::info!(
        "stopped ({}): {} cycles, compute {}, skipped poses {}, overwritten poses {}, pose \
         sequence resets {}, invalid inputs {}, margin requests {}, heap allocations per cycle {:.2} from the system allocator \
         ({} in the first cycle: iceoryx2 connecting), {:.2} from the pool (iceoryx2's per loan and \
         per request: {:.2})",
        match reason {
            StopReason::Signal => "signal",
            StopReason::Requested => "stop requested",
            StopReason::MaxCycles => "max cycles reached",
        },
        report.cycles,
        report.compute.display_us(),
        report.skipped_poses,
        report.overwritten_poses,
        report.sequence_resets,
        report.invalid_inputs,
        report.margin_requests,
        report.allocations_per_cycle,
        report.allocations_first_cycle,
        report.pool_allocations_per_cycle,
        report.iceoryx2_allocations_per_cycle
    );
    let v = report.vibration;
    if v.accepted + v.refused() > 0 {
        tracing::info!(
            "vibration samples: {} taken, {} refused (invalid {}, out of order {}, time not \
             increasing {}), {} lost, {} places filled, {} window restarts, {} evaluations \
             overrun",
            v.accepted,
            v.refused(),
            v.invalid,
            v.out_of_order,
            v.time_not_increasing,
            v.lost,
            v.filled,
            v.restarts,
            v.overruns
        );
    }
}
