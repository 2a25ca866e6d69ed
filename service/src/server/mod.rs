//! The service loop: poses and T_min set-points in, estimates and margin answers out.
//!
//! One iteration ([`Server::poll`]):
//!
//! 1. drain the pose subscriber, keeping the newest pose (the older ones are *skipped* and
//!    counted); poses that never reached the service because the subscriber queue
//!    ([`POSE_BUFFER`]) overflowed between two drains are *overwritten*, counted from the gaps
//!    in each publisher's pose sequence ([`SequenceGaps`]: forward and within a window only; a
//!    sequence that goes back or jumps is a counted reset, never a wrap-around loss);
//! 2. drain the T_min subscriber; the newest set-point becomes *pending*;
//! 3. if a pose came, apply the pending set-point and estimate the pose, then publish the
//!    estimate and notify the wake-controller event;
//! 4. answer every queued margin request from the latest estimate: f1 and the margin of this
//!    cycle, and the T_min that reaches the requirement from the inverse search, which runs
//!    on a thread of its own (`server/inverse_worker.rs`) on each client's newest request, the
//!    clients served round robin (one client's flood costs only its own answers), so that no
//!    request pattern costs the loop more than a copy per request.
//!
//! Between iterations the loop busy-polls ([`WaitMode::Spin`]) or blocks on the wake-service
//! event ([`WaitMode::Event`]), checks for SIGINT/SIGTERM (iceoryx2's handler, installed by the
//! first `node.wait`) and, once per stats period, logs statistics through `tracing`.
//!
//! Nothing in steps 1–4 allocates except iceoryx2 itself, which in 0.10 allocates a small
//! shared state once per loan (one per published estimate, one per margin response) and once
//! per received request, whatever the service type (no API or configuration avoids it). The
//! service thread holds the counting allocator's block pool ([`crate::alloc_count::claim_pool`])
//! while it runs, so those come from a constant-time pool instead of the system allocator. The
//! heap allocations of the service thread per cycle are counted (with the binary's counting
//! allocator): from the system allocator (0 in the loop) and from the pool, logged next to
//! iceoryx2's expected share, so that a regression shows. Every loop over a queue is bounded. Bad input never
//! stops the loop: the estimate carries the status ([`StatusCode`]) and the next valid pose is
//! answered normally.
//!
//! # T_min set-points
//!
//! A set-point received in one iteration applies to the next pose estimated; a set-point sent
//! before a pose (from the same thread) always applies to that pose, since the poses are
//! drained before the set-points. A per-cable set-point gives each cable its own lower bound
//! (cables past its per-cable values take its uniform value; [`setpoint_bounds`]), passed to
//! [`Estimator::update`] with [`Tmin::PerCable`]. Before any set-point the scene's bounds are in force
//! (`cables[i].t_min`, else `tension.t_min`). A set-point with a value the scene file would
//! refuse (the one rule of [`crate::scene::check_t_min`]: not finite, zero, negative,
//! subnormal, above that cable's T_max — `TminSetpoint::zeroed()` is one) is reported once,
//! as the status [`StatusCode::TminOutOfRange`] of the next estimate, and the previous
//! set-point stays in force for the estimates after it. The inverse T_min query of the margin
//! service stays uniform (one T_min for every cable).

use core::sync::atomic::{AtomicBool, Ordering};
use core::time::Duration;

use cablevib_ipc::{
    monotonic_now_ns, EstimateSample, MarginResponse, MeasuredStatus, PoseSample, ServiceNames,
    StatusCode, TminSetpoint, EE_MODE_AGE_UNKNOWN, EVENT_ID_ESTIMATE, EVENT_ID_MARGIN_RESPONSE,
    MAX_CABLES, MEASURED_AGE_UNKNOWN,
};
use iceoryx2::identifiers::UniquePublisherId;
use iceoryx2::prelude::*;
use nalgebra::Vector3;

use super::ports::{self, Ipc, ServicePorts, MAX_PUBLISHERS, POSE_BUFFER};
use super::rt;
use super::stats::{Ring, SequenceGaps, StatusHistogram};
use super::{ServiceError, WaitMode};
use crate::estimator::{Estimator, Tmin};
use crate::kinematics::Pose;
use crate::measured::{Measured, MeasuredMode, TrackerParams, VibrationTracker};
use crate::scene::{is_valid_t_min, Scene};
use inverse_worker::{ClientSlots, InverseJob, InverseWorker};

/// Heap allocation counter of the calling thread from the system allocator (the binary's
/// global allocator, e.g. [`crate::alloc_count::thread_system_allocations`]), or a function
/// returning 0.
pub type AllocCounter = fn() -> u64;

/// A counter that counts nothing (when no counting allocator is installed).
pub fn no_allocation_counter() -> u64 {
    0
}

/// Pins the thread and switches to SCHED_FIFO with locked memory when `cfg` asks; a warning
/// for each setting the system does not permit.
fn apply_rt_settings(cfg: &ServerConfig) {
    if let Some(cpu) = cfg.cpu {
        match rt::pin_to_cpu(cpu) {
            Ok(()) => tracing::info!("pinned to CPU {cpu}"),
            Err(e) => tracing::warn!("CPU pinning not applied: {e}"),
        }
    }
    if cfg.realtime {
        match rt::lock_memory() {
            Ok(()) => tracing::info!("memory locked (mlockall)"),
            Err(e) => tracing::warn!("memory not locked: {e}"),
        }
        match rt::set_fifo() {
            Ok(()) => tracing::info!("running with SCHED_FIFO priority {}", rt::FIFO_PRIORITY),
            Err(e) => tracing::warn!("SCHED_FIFO not applied: {e}"),
        }
    }
}

/// Runs the service for `scene` in its own thread (named `cablevib-serve`), as the demo and
/// the IPC benchmark do; when it ends, for any reason, `stop` is set so the other threads
/// stop too. The thread's allocations are counted when the process's global allocator is
/// [`crate::alloc_count::CountingAlloc`] (0 otherwise).
pub fn spawn_thread(
    scene: Scene,
    cfg: ServerConfig,
    stop: std::sync::Arc<AtomicBool>,
) -> Result<std::thread::JoinHandle<Result<ServerReport, ServiceError>>, ServiceError> {
    std::thread::Builder::new()
        .name("cablevib-serve".into())
        .spawn(move || {
            let r = run(
                &scene,
                &cfg,
                &stop,
                crate::alloc_count::thread_system_allocations,
            );
            stop.store(true, Ordering::Release);
            r
        })
        .map_err(|e| ServiceError::Thread {
            what: "service",
            reason: e.to_string(),
        })
}

/// Capacity of the per-period compute-time ring.
pub const PERIOD_RING: usize = 1 << 16;
/// Capacity of the whole-run compute-time ring.
pub const RUN_RING: usize = 1 << 17;
/// Upper bound of samples taken from one queue in one iteration.
const DRAIN_LIMIT: usize = 4 * POSE_BUFFER;
/// Longest block in event mode before the loop checks signals and stats again.
const EVENT_TIMEOUT: Duration = Duration::from_millis(50);

/// The latest estimate, as far as the margin service needs it.
#[derive(Debug, Clone, Copy)]
struct Latest {
    /// The loop's cycle count when it was estimated.
    cycle: u64,
    pose_sequence: u64,
    status: StatusCode,
    f1_hz: f64,
    /// The pose the estimate answers (for the inverse T_min query).
    pose: Pose,
}

/// Counters of one stats period.
#[derive(Debug, Clone, Copy, Default)]
struct PeriodCounters {
    cycles: u64,
    skipped: u64,
    /// Poses lost in the subscriber queue (sequence gaps).
    overwritten: u64,
    invalid: u64,
    margin: u64,
    t_min: u64,
    ipc_errors: u64,
    status: StatusHistogram,
    /// The first refused value of the last refused set-point of the period, N.
    rejected_t_min: Option<f64>,
    allocations: u64,
    /// Allocations served by the pool.
    pool_allocations: u64,
    /// Allocations iceoryx2 0.10 makes by design: one per loan (estimate, margin response) and
    /// one per received request.
    iceoryx2_allocations: u64,
}

/// The service: estimator, ports and bookkeeping. Built once; [`Server::poll`] is the cycle.
pub struct Server {
    n_cables: usize,
    estimator: Estimator,
    ports: ServicePorts,
    allocations: AllocCounter,
    /// Each cable's upper bound, N (the scene's).
    t_max_n: [f64; MAX_CABLES],
    /// The lower bounds in force, N, one per cable.
    t_min_n: [f64; MAX_CABLES],
    /// The lower bounds of the current cycle, N (the ones in force, or a refused set-point's
    /// for the one estimate that reports it).
    cycle_t_min_n: [f64; MAX_CABLES],
    /// The inverse T_min search beside the loop.
    inverse: InverseWorker,
    /// Each margin client's slot in the inverse search's mailbox.
    margin_clients: ClientSlots<iceoryx2::identifiers::UniqueClientId>,
    pending_t_min: Option<TminSetpoint>,
    latest: Option<Latest>,
    /// Last pose sequence per publisher, for the poses overwritten in the queue. One slot per
    /// publisher the pose service admits.
    pose_gaps: SequenceGaps<UniquePublisherId, MAX_PUBLISHERS>,
    period: PeriodCounters,
    total: PeriodCounters,
    /// System allocations of the first cycle (not in the counters: iceoryx2 connecting the
    /// first pose publisher's data segment, once).
    first_cycle_allocations: u64,
    period_ring: Ring,
    run_ring: Ring,
    /// The measured frequencies from the vibration input.
    tracker: VibrationTracker,
    /// The latest known model f1 and end-effector mode, Hz (the tracker's band centres).
    model_hz: [Option<f64>; 2],
}

impl Server {
    /// Builds the estimator for `scene` and opens the service's ports on `node`.
    pub fn new(
        scene: &Scene,
        node: &Node<Ipc>,
        names: &ServiceNames,
        allocations: AllocCounter,
    ) -> Result<Server, ServiceError> {
        let estimator = Estimator::realtime(scene)?;
        if let Some(choice) = estimator.auto_choice() {
            tracing::info!("{choice}");
        }
        let ports = ServicePorts::open_with_attributes(
            node,
            names,
            &ports::ServiceAttributes::of_scene(scene),
        )?;
        let n_cables = scene.n_cables().min(MAX_CABLES);
        let mut t_max_n = [scene.t_max_n; MAX_CABLES];
        for (i, t) in t_max_n.iter_mut().enumerate().take(n_cables) {
            *t = scene.cable_t_max_n(i);
        }
        let t_min_n = estimator.default_t_min_n();
        let inverse = InverseWorker::spawn(&estimator).map_err(|e| ServiceError::Thread {
            what: "inverse T_min",
            reason: e.to_string(),
        })?;
        Ok(Server {
            n_cables,
            estimator,
            ports,
            allocations,
            t_max_n,
            t_min_n,
            cycle_t_min_n: t_min_n,
            inverse,
            margin_clients: ClientSlots::default(),
            pending_t_min: None,
            latest: None,
            pose_gaps: SequenceGaps::default(),
            period: PeriodCounters::default(),
            total: PeriodCounters::default(),
            first_cycle_allocations: 0,
            period_ring: Ring::new(PERIOD_RING),
            run_ring: Ring::new(RUN_RING),
            tracker: VibrationTracker::new(TrackerParams::default())?,
            model_hz: [None; 2],
        })
    }

    /// The lower bounds in force, N, one per cable.
    pub fn t_min_n(&self) -> &[f64] {
        &self.t_min_n[..self.n_cables]
    }

    /// The smallest and largest upper bound, N (for the log).
    fn t_max_range_n(&self) -> (f64, f64) {
        min_max(&self.t_max_n[..self.n_cables])
    }

    /// The smallest and largest lower bound in force, N (for the log).
    fn t_min_range_n(&self) -> (f64, f64) {
        min_max(self.t_min_n())
    }

    /// One iteration: newest pose, set-points, estimate + publish, margin requests. Returns
    /// whether anything was received.
    pub fn poll(&mut self) -> bool {
        let a0 = (self.allocations)();
        let p0 = crate::alloc_count::thread_pool_allocations();
        let mut iceoryx2_allocations = 0;

        // Poses first, then set-points: a set-point sent before a pose (by the same sender) is
        // then always seen with that pose, because seeing the pose implies seeing everything
        // its sender wrote before it.
        let mut newest: Option<PoseSample> = None;
        let mut received = 0u64;
        while received < DRAIN_LIMIT as u64 {
            match self.ports.pose.receive() {
                Ok(Some(s)) => {
                    self.period.overwritten += self.pose_gaps.record(
                        s.header().publisher_id(),
                        s.sequence,
                        monotonic_now_ns(),
                    );
                    newest = Some(*s);
                    received += 1;
                }
                Ok(None) => break,
                Err(_) => {
                    self.period.ipc_errors += 1;
                    break;
                }
            }
        }
        let receive_ns = monotonic_now_ns();
        let mut worked = self.drain_t_min();
        let cycle = newest.is_some();
        if let Some(pose) = newest {
            self.period.skipped += received - 1;
            self.cycle(&pose, receive_ns);
            iceoryx2_allocations += 1;
            worked = true;
        }

        let answered = self.answer_margin_requests();
        iceoryx2_allocations += 2 * answered;
        worked |= answered > 0;

        // The vibration input last, after the estimate went out: at most VIBRATION_BUFFER
        // samples and the tracker's bounded slice of work per iteration.
        worked |= self.drain_vibration();

        if cycle {
            let d = (self.allocations)().wrapping_sub(a0);
            if self.cycles() == 1 {
                // iceoryx2 connecting the ports (mapping the first publisher's segment).
                self.first_cycle_allocations = d;
            } else {
                self.period.allocations += d;
            }
            self.period.pool_allocations +=
                crate::alloc_count::thread_pool_allocations().wrapping_sub(p0);
            self.period.iceoryx2_allocations += iceoryx2_allocations;
        }
        worked
    }

    /// Takes the queued vibration samples into the tracker and lets it work one slice.
    fn drain_vibration(&mut self) -> bool {
        let mut any = false;
        for _ in 0..crate::ports::VIBRATION_BUFFER {
            match self.ports.vibration.receive() {
                Ok(Some(s)) => {
                    self.tracker
                        .push(s.sequence, s.timestamp_ns, s.acceleration_m_s2);
                    any = true;
                }
                Ok(None) => break,
                Err(_) => {
                    self.period.ipc_errors += 1;
                    break;
                }
            }
        }
        self.tracker.work() > 0 || any
    }

    fn drain_t_min(&mut self) -> bool {
        let mut any = false;
        for _ in 0..DRAIN_LIMIT {
            match self.ports.t_min.receive() {
                Ok(Some(s)) => {
                    self.pending_t_min = Some(*s);
                    self.period.t_min += 1;
                    any = true;
                }
                Ok(None) => break,
                Err(_) => {
                    self.period.ipc_errors += 1;
                    break;
                }
            }
        }
        any
    }

    /// Loads `cycle_t_min_n` with this cycle's lower bounds: the pending set-point's if valid
    /// (they stay in force), the refused values themselves for this one cycle if not (the
    /// estimator, by the same rule, reports `TminOutOfRange`), otherwise the ones in force.
    fn t_min_for_cycle(&mut self) {
        let n = self.n_cables;
        let Some(s) = self.pending_t_min.take() else {
            self.cycle_t_min_n = self.t_min_n;
            return;
        };
        setpoint_bounds(&s, &mut self.cycle_t_min_n[..n]);
        match first_refused(&self.cycle_t_min_n[..n], &self.t_max_n[..n]) {
            None => self.t_min_n = self.cycle_t_min_n,
            Some(v) => self.period.rejected_t_min = Some(v),
        }
    }

    fn cycle(&mut self, p: &PoseSample, receive_ns: u64) {
        self.t_min_for_cycle();
        let n_cables = self.n_cables;
        let pose = Pose {
            position_m: Vector3::new(p.position_m[0], p.position_m[1], p.position_m[2]),
            orientation_wxyz: p.orientation_wxyz,
        };
        let t0 = monotonic_now_ns();
        let e = *self
            .estimator
            .update(&pose, Tmin::PerCable(&self.cycle_t_min_n[..n_cables]));
        let compute_ns = monotonic_now_ns().saturating_sub(t0);

        let n = e.n_cables.min(MAX_CABLES);
        let mut out = EstimateSample::zeroed();
        out.pose_sequence = p.sequence;
        out.pose_timestamp_ns = p.timestamp_ns;
        out.receive_timestamp_ns = receive_ns;
        out.status = e.status.as_u32();
        out.cable_count = n as u32;
        out.tensions_n[..n].copy_from_slice(&e.tensions_n[..n]);
        out.f1_hz = e.f1_hz;
        // The wire's codes for an absent end-effector mode: NaN and EE_MODE_AGE_UNKNOWN.
        (out.ee_mode_hz, out.ee_mode_age_cycles) = match e.ee_mode {
            Some(m) => (m.frequency_hz, m.age_cycles),
            None => (f64::NAN, EE_MODE_AGE_UNKNOWN),
        };
        // 3 × 3 (N/m) for a point mass, 6 × 6 (N/m, N/rad, N·m/m, N·m/rad) for a rigid body.
        let dim = e.stiffness.dim;
        out.stiffness_dim = dim as u32;
        for r in 0..dim {
            for c in 0..dim {
                out.stiffness[dim * r + c] = e.stiffness.k6[(r, c)];
            }
        }
        out.compute_ns = compute_ns;
        out.eigen_evaluations = e.eigen_evaluations;
        out.tension_iterations = e.tension_iterations;
        out.eigen_residual = e.eigen_residual;
        out.skipped_poses = self.total.skipped + self.period.skipped;
        out.sequence = self.cycles() + 1;
        // The measured frequencies: the tracker's latest, beside this estimate's model.
        // The bands follow the latest known model frequencies (an estimate without an
        // end-effector mode leaves the last one in force).
        let known = |f: f64| (e.is_ok() && f.is_finite() && f > 0.0).then_some(f);
        self.model_hz = [
            known(e.f1_hz).or(self.model_hz[0]),
            known(e.ee_mode.map_or(f64::NAN, |m| m.frequency_hz)).or(self.model_hz[1]),
        ];
        self.tracker.set_model(self.model_hz[0], self.model_hz[1]);
        measured_fields(&mut out, &self.tracker.measured(receive_ns), receive_ns);
        let c = self.tracker.counters();
        out.vibration_samples = c.accepted;
        out.vibration_refused = c.refused();
        out.vibration_lost = c.lost;

        match self.ports.estimate.loan_uninit() {
            Ok(sample) => {
                out.publish_timestamp_ns = monotonic_now_ns();
                if sample.write_payload(out).send().is_err() {
                    self.period.ipc_errors += 1;
                }
            }
            Err(_) => self.period.ipc_errors += 1,
        }
        self.ports.notify(EVENT_ID_ESTIMATE);

        self.latest = Some(Latest {
            cycle: self.cycles(),
            pose_sequence: p.sequence,
            status: e.status,
            f1_hz: e.f1_hz,
            pose,
        });
        self.period.cycles += 1;
        self.period.status.record(e.status);
        if !e.is_ok() {
            self.period.invalid += 1;
        }
        self.period_ring.push(compute_ns);
        self.run_ring.push(compute_ns);
    }

    fn answer_margin_requests(&mut self) -> u64 {
        let mut answered = 0;
        for _ in 0..DRAIN_LIMIT {
            let request = match self.ports.margin.receive() {
                Ok(Some(r)) => r,
                Ok(None) => break,
                Err(_) => {
                    self.period.ipc_errors += 1;
                    break;
                }
            };
            let req = *request.payload();
            // Each client has its own slot of the inverse search: its requests replace only
            // its own job, and the search serves the clients round robin.
            let (slot, new_client) = self.margin_clients.slot(request.header().client_id());
            if new_client {
                self.inverse.clear(slot);
            }
            // The smallest T_min reaching the required f1: the inverse thread's last answer
            // when it is for this requirement (with its age in cycles: a T_min, +∞ when
            // unreachable, or the status of a failed search), NaN while there is none; this
            // request becomes the thread's next job, with the T_min in force as its hint (the
            // answer never exceeds it when it already reaches the requirement). A copy in, a
            // copy out: no search here.
            let (t_min_required, age) = match self.latest {
                Some(l) if l.status.is_ok() && req.is_valid() => {
                    let known = self
                        .inverse
                        .answer(slot)
                        .filter(|a| a.required_f1_hz == req.required_f1_hz);
                    self.inverse.post(
                        slot,
                        InverseJob {
                            pose: l.pose,
                            cycle: l.cycle,
                            required_f1_hz: req.required_f1_hz,
                            hint_n: self.t_min_range_n().1,
                        },
                    );
                    match known {
                        Some(a) => {
                            let age = l.cycle.saturating_sub(a.cycle);
                            (a.t_min_n, age.min(u64::from(u32::MAX - 1)) as u32)
                        }
                        None => (Ok(f64::NAN), cablevib_ipc::T_MIN_AGE_UNKNOWN),
                    }
                }
                _ => (Ok(f64::NAN), cablevib_ipc::T_MIN_AGE_UNKNOWN),
            };
            let now = monotonic_now_ns();
            let mut response = margin_response(&req, self.latest, t_min_required, now);
            if response.is_ok() || t_min_required.is_err() {
                response.t_min_required_age_cycles = age;
            }
            if request.send_copy(response).is_err() {
                self.period.ipc_errors += 1;
            }
            answered += 1;
        }
        if answered > 0 {
            self.ports.notify(EVENT_ID_MARGIN_RESPONSE);
            self.period.margin += answered;
        }
        answered
    }

    /// Logs the period's statistics (if `log`) and starts a new period.
    fn end_period(&mut self, period_s: f64, log: bool) {
        let p = self.period;
        let in_force = display_range(self.t_min_range_n());
        if log {
            let compute = self.period_ring.percentiles();
            let per_cycle = |x: u64| {
                if p.cycles > 0 {
                    x as f64 / p.cycles as f64
                } else {
                    0.0
                }
            };
            tracing::info!(
                "{} cycles in {:.1} s; compute p50 {:.1} µs, p99 {:.1} µs, max {:.1} µs; \
                 skipped poses {} (total {}); overwritten poses {} (total {}); invalid inputs {}{}; T_min set-points {}, in force \
                 {} N; margin requests {}; heap allocations per cycle {:.2} from the system \
                 allocator, {:.2} from the pool (iceoryx2's per loan and per request: {:.2}){}",
                p.cycles,
                period_s,
                compute.p50_ns as f64 / 1e3,
                compute.p99_ns as f64 / 1e3,
                compute.max_ns as f64 / 1e3,
                p.skipped,
                self.total.skipped + p.skipped,
                p.overwritten,
                self.total.overwritten + p.overwritten,
                p.invalid,
                status_breakdown(&p.status),
                p.t_min,
                in_force,
                p.margin,
                per_cycle(p.allocations),
                per_cycle(p.pool_allocations),
                per_cycle(p.iceoryx2_allocations),
                if p.ipc_errors > 0 {
                    format!("; iceoryx2 errors {}", p.ipc_errors)
                } else {
                    String::new()
                }
            );
            if let Some(v) = p.rejected_t_min {
                tracing::warn!(
                    "rejected a T_min set-point with a value of {v:?} N (each must be finite, \
                     ≥ {:e} N and ≤ its cable's t_max, ≤ {} N); {in_force} N stays in force",
                    crate::scene::T_MIN_FLOOR_N,
                    display_range(self.t_max_range_n())
                );
            }
        }
        let t = &mut self.total;
        t.cycles += p.cycles;
        t.skipped += p.skipped;
        t.overwritten += p.overwritten;
        t.invalid += p.invalid;
        t.margin += p.margin;
        t.t_min += p.t_min;
        t.ipc_errors += p.ipc_errors;
        t.allocations += p.allocations;
        t.pool_allocations += p.pool_allocations;
        t.iceoryx2_allocations += p.iceoryx2_allocations;
        t.status.merge(&p.status);
        self.period = PeriodCounters::default();
        self.period_ring.clear();
    }

    fn cycles(&self) -> u64 {
        self.total.cycles + self.period.cycles
    }

    fn report(&mut self, stop: StopReason, stale_nodes_removed: usize) -> ServerReport {
        self.end_period(0.0, false);
        let t = self.total;
        let per = |x: u64| {
            if t.cycles > 0 {
                x as f64 / t.cycles as f64
            } else {
                0.0
            }
        };
        ServerReport {
            stop,
            cycles: t.cycles,
            skipped_poses: t.skipped,
            overwritten_poses: t.overwritten,
            sequence_resets: self.pose_gaps.resets(),
            pose_publishers: self.pose_gaps.senders().collect(),
            invalid_inputs: t.invalid,
            status_counts: t.status,
            t_min_setpoints: t.t_min,
            margin_requests: t.margin,
            ipc_errors: t.ipc_errors,
            stale_nodes_removed,
            compute: self.run_ring.percentiles(),
            allocations_per_cycle: if t.cycles > 1 {
                t.allocations as f64 / (t.cycles - 1) as f64
            } else {
                0.0
            },
            allocations_first_cycle: self.first_cycle_allocations,
            pool_allocations_per_cycle: per(t.pool_allocations),
            iceoryx2_allocations_per_cycle: per(t.iceoryx2_allocations),
            vibration: self.tracker.counters(),
        }
    }
}

/// The lower bounds (N) of set-point `s` for the cables of `out` (one entry per cable of the
/// robot), one per cable: its per-cable value, its uniform value past those; every entry NaN
/// when the set-point is malformed, so that it is refused: not
/// [`TminSetpoint::is_well_formed`] (more per-cable values than [`MAX_CABLES`], a value in
/// use not finite or negative), or more per-cable values than the robot has cables (values
/// for cables that do not exist are a client's mistake, never ignored). Does not check the
/// values against the scene's rule (see [`first_refused`]). No allocation.
pub fn setpoint_bounds(s: &TminSetpoint, out: &mut [f64]) {
    if !s.is_well_formed() || s.per_cable_count as usize > out.len() {
        out.fill(f64::NAN);
        return;
    }
    for (i, t) in out.iter_mut().enumerate() {
        *t = s.t_min_for(i);
    }
}

/// The first lower bound (N) of `t_min_n` that the crate's one T_min rule refuses
/// ([`crate::scene::check_t_min`] against the same cable's `t_max_n`, N), None when every
/// one is valid.
pub fn first_refused(t_min_n: &[f64], t_max_n: &[f64]) -> Option<f64> {
    t_min_n
        .iter()
        .zip(t_max_n)
        .find(|(&lo, &hi)| !is_valid_t_min(lo, hi))
        .map(|(&lo, _)| lo)
}

/// (smallest, largest) of `v`.
fn min_max(v: &[f64]) -> (f64, f64) {
    v.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &t| {
            (lo.min(t), hi.max(t))
        })
}

/// `"60"` for equal ends, `"10..100"` otherwise.
fn display_range((lo, hi): (f64, f64)) -> String {
    if lo == hi {
        format!("{lo}")
    } else {
        format!("{lo}..{hi}")
    }
}

/// The answer to margin request `req` given the latest estimate: `InvalidRequest` for a
/// required frequency outside `MarginRequest::is_valid`'s range, `NoPoseYet` before the first estimate,
/// the latest estimate's status when it is not ok, the inverse search's status when it
/// failed at the pose (`t_min_required` an error), otherwise f1 and the margin.
/// `t_min_required` is the smallest T_min (N) reaching the required f1
/// ([`Estimator::t_min_for_f1_near`]): +∞ when unreachable, NaN when not known yet.
fn margin_response(
    req: &cablevib_ipc::MarginRequest,
    latest: Option<Latest>,
    t_min_required: Result<f64, StatusCode>,
    now_ns: u64,
) -> MarginResponse {
    let pose_sequence = latest.map_or(0, |l| l.pose_sequence);
    let status = match (latest, t_min_required) {
        _ if !req.is_valid() => StatusCode::InvalidRequest,
        (None, _) => StatusCode::NoPoseYet,
        (Some(l), Err(failed)) if l.status.is_ok() => failed,
        (Some(l), Ok(t_min_required_n)) if l.status.is_ok() => {
            return MarginResponse::from_f1(
                req,
                pose_sequence,
                l.status,
                l.f1_hz,
                t_min_required_n,
                now_ns,
            )
        }
        (Some(l), _) => l.status,
    };
    let mut r = MarginResponse::with_status(req, status, now_ns);
    r.pose_sequence = pose_sequence;
    r
}

/// Writes the measured frequencies `m` into `out` (whose model fields are set): each
/// track's frequency and model − measured residual (NaN when either is absent), its status,
/// and the age of the measured window at `receive_ns`.
pub fn measured_fields(out: &mut EstimateSample, m: &Measured, receive_ns: u64) {
    out.set_measured_none(MeasuredStatus::NoInput);
    let track = |r: &Result<MeasuredMode, MeasuredStatus>, model: f64| match r {
        Ok(mm) => (mm.frequency_hz, model - mm.frequency_hz),
        Err(_) => (f64::NAN, f64::NAN),
    };
    (out.measured_f1_hz, out.f1_residual_hz) = track(&m.first, out.f1_hz);
    (out.measured_ee_mode_hz, out.ee_mode_residual_hz) = track(&m.ee_mode, out.ee_mode_hz);
    out.measured_f1_status = MeasuredStatus::of(&m.first).as_u32();
    out.measured_ee_mode_status = MeasuredStatus::of(&m.ee_mode).as_u32();
    out.measured_age_ns = m
        .window_centre_ns()
        .map_or(MEASURED_AGE_UNKNOWN, |c| receive_ns.saturating_sub(c));
}

/// `" (outside_workspace 3, t_min_out_of_range 1)"`, or `""` when every status was ok.
fn status_breakdown(counts: &StatusHistogram) -> String {
    let parts = counts.summary_not_ok();
    if parts.is_empty() {
        parts
    } else {
        format!(" ({parts})")
    }
}

/// Runs the service for `scene` until a signal (when `cfg.handle_signals`), `stop` is set, or
/// `cfg.max_cycles` cycles. Cleans up resources of dead nodes first.
pub fn run(
    scene: &Scene,
    cfg: &ServerConfig,
    stop: &AtomicBool,
    allocations: AllocCounter,
) -> Result<ServerReport, ServiceError> {
    cablevib_ipc::check_instance(&cfg.instance)?;
    let (removed, failed) = ports::remove_stale_nodes();
    if removed > 0 {
        tracing::info!("removed the stale resources of {removed} dead iceoryx2 node(s)");
    }
    if failed > 0 {
        tracing::warn!("could not remove the stale resources of {failed} dead iceoryx2 node(s)");
    }
    let names = ServiceNames::new(&cfg.instance);
    let node = ports::create_node(&cfg.node_name)?;
    // The first wait installs iceoryx2's SIGINT/SIGTERM handler; a zero wait does not sleep.
    if cfg.handle_signals && node.wait(Duration::ZERO).is_err() {
        return Err(ServiceError::Interrupted);
    }
    let mut server = Server::new(scene, &node, &names, allocations)?;

    apply_rt_settings(cfg);
    log_start(scene, cfg);
    // iceoryx2's per-loan and per-request allocations from here on come from the pool
    // (constant time), when this thread is its only holder and the counting allocator is
    // installed; released when the loop ends.
    let _pool = if cfg.alloc_pool {
        crate::alloc_count::claim_pool()
    } else {
        None
    };
    if cfg.alloc_pool && _pool.is_none() {
        tracing::warn!("the allocation pool is held by another thread: iceoryx2's per-loan allocations use the system allocator");
    }

    let period_ns = cfg
        .stats_period
        .map(|d| d.as_nanos().min(u64::MAX as u128) as u64)
        .unwrap_or(u64::MAX);
    let mut period_start = monotonic_now_ns();
    let reason = loop {
        if stop.load(Ordering::Relaxed) {
            break StopReason::Requested;
        }
        if cfg.handle_signals && node.wait(Duration::ZERO).is_err() {
            break StopReason::Signal;
        }
        if cfg.wait == WaitMode::Event {
            let until_stats = Duration::from_nanos(
                period_ns.saturating_sub(monotonic_now_ns().saturating_sub(period_start)),
            );
            // Returns early on a notification (or a signal); either way we poll next.
            crate::ports::listener_timed_wait(
                &server.ports.wake_in,
                until_stats.min(EVENT_TIMEOUT),
            );
        }
        let worked = server.poll();
        if !worked && cfg.wait == WaitMode::Spin {
            core::hint::spin_loop();
        }
        let now = monotonic_now_ns();
        if now.saturating_sub(period_start) >= period_ns {
            server.end_period((now - period_start) as f64 * 1e-9, true);
            period_start = now;
        }
        if cfg.max_cycles.is_some_and(|m| server.cycles() >= m) {
            break StopReason::MaxCycles;
        }
    };
    let report = server.report(reason, removed);
    log_stop(reason, &report);
    Ok(report)
}

mod config;
mod inverse_worker;
use config::{log_start, log_stop};
pub use config::{ServerConfig, ServerReport, StopReason};
#[cfg(test)]
mod tests;
