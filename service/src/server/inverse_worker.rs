//! The margin service's inverse T_min search, on a thread of its own beside the estimate
//! loop.
//!
//! The search (the smallest uniform T_min reaching a required f1 at a pose,
//! [`Estimator::t_min_for_f1_near`]) needs up to 257 forward evaluations (tension solve and
//! first root each; usually 20 to 80), ~0.3 to 10 ms on the shipped scenes. Run inline it starved the loop; spread over the cycles a requirement that
//! changes every request would restart it before it ends. So it runs here, on its own copy
//! of the estimator (its own buffers; set up once). The mailbox has one slot per margin
//! client ([`SLOTS`], the service's `MAX_CLIENTS`): the loop posts each client's newest
//! (pose, requirement) into that client's slot with `try_lock` (never waits: a busy mailbox
//! keeps the older job) and reads that client's last finished answer the same way. The worker
//! serves the slots with a job round robin, so a client that floods changing requirements
//! only replaces its own job and costs the others at most one search per turn (with one
//! shared slot, one such client took another's finite answers from 394 of 395 to 0). The
//! loop's work per request is a copy in and a copy out; no request pattern reaches the
//! estimate loop. Nothing here allocates after [`InverseWorker::spawn`].

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use crate::estimator::{Estimator, Status as StatusCode, TminAnswer, TminQueryError};
use crate::kinematics::Pose;

/// The worker sleeps at most this long between looks at the mailbox (it is also woken by
/// every posted job).
const IDLE_PARK: Duration = Duration::from_millis(20);
/// After a search the worker rests nineteen times as long as the search took: at most a
/// twentieth of a core, whatever the requests, so that on a machine with few cores it cannot
/// take the estimate loop's (measured on 2 cores under a 1 kHz flood of changing requirements:
/// with a quarter of a core the loop estimated 89 % of the poses, with a twentieth 98 %, as
/// without the flood 99 %). A search takes a few ms (2.4 ms median, 15 ms p99 on the paper
/// robot; 11 and 35 ms with sag: docs/inverse.md), so answers to a requirement that changes
/// every request are up to ~0.1 s old (`t_min_required_age_cycles` says how old).
const REST_PER_WORK: u32 = 19;
/// The longest rest after one search: a rare long search (up to 208 forward evaluations) must
/// not hold back the answer to the next requirement for 19 times as long; searches of up to
/// ~10 ms rest their full 19×.
const MAX_REST: Duration = Duration::from_millis(200);
/// Niceness of the worker thread (Linux: lowest priority), so that the scheduler prefers the
/// estimate loop when both want a core.
const WORKER_NICE: i32 = 19;

/// One search to run: at `pose` (the estimate of cycle `cycle`), for `required_f1_hz`.
#[derive(Debug, Clone, Copy)]
pub struct InverseJob {
    /// The pose, and the loop's cycle count when it was estimated.
    pub pose: Pose,
    pub cycle: u64,
    /// Required first natural frequency, Hz.
    pub required_f1_hz: f64,
    /// The T_min in force, N (the largest of the cables' when they differ): when it already
    /// reaches the requirement, the answer is at most it.
    pub hint_n: f64,
}

/// A finished search for `required_f1_hz` at the pose of cycle `cycle`: `Ok` with the
/// smallest T_min (N), +∞ when no feasible T_min reaches the requirement; or the status of
/// the pose's failure (the forward model failed at every T_min the search tried).
#[derive(Debug, Clone, Copy)]
pub struct InverseAnswer {
    pub required_f1_hz: f64,
    pub cycle: u64,
    pub t_min_n: Result<f64, StatusCode>,
}

/// The answer of the inverse query as the service carries it (see [`InverseAnswer`]).
pub fn carried(r: Result<TminAnswer, TminQueryError>) -> Result<f64, StatusCode> {
    match r {
        Ok(a) => Ok(a.t_min_n),
        Err(TminQueryError::Unreachable { .. }) => Ok(f64::INFINITY),
        Err(TminQueryError::BadRequirement(_)) => Err(StatusCode::InvalidRequest),
        Err(TminQueryError::Pose(e)) => Err(e.status()),
    }
}

/// Slots of the mailbox: one per margin client the service admits.
pub const SLOTS: usize = crate::ports::MAX_CLIENTS;

#[derive(Debug, Default)]
struct Mailbox {
    /// Each slot's newest job not started yet.
    jobs: [Option<InverseJob>; SLOTS],
    /// Each slot's last finished answer.
    answers: [Option<InverseAnswer>; SLOTS],
    /// Searches finished since the worker started (the fairness test counts turns by it,
    /// not by wall time).
    searches: u64,
}

/// The worker thread and its mailbox.
pub struct InverseWorker {
    mailbox: Arc<Mutex<Mailbox>>,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
    /// The last answer read per slot (the loop's copy).
    answers: [Option<InverseAnswer>; SLOTS],
}

impl InverseWorker {
    /// Start the worker with its own copy of `estimator` (allocates: set-up only).
    pub fn spawn(estimator: &Estimator) -> std::io::Result<InverseWorker> {
        let mailbox = Arc::new(Mutex::new(Mailbox::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let mut est = estimator.clone();
        let (m, s) = (mailbox.clone(), stop.clone());
        let handle = std::thread::Builder::new()
            .name("cablevib-inverse".into())
            .spawn(move || worker_loop(&mut est, &m, &s))?;
        Ok(InverseWorker {
            mailbox,
            stop,
            handle: Some(handle),
            answers: [None; SLOTS],
        })
    }

    /// Post `job` into slot `slot` (< [`SLOTS`]; replacing that slot's job not started yet)
    /// and wake the worker; a busy mailbox drops it (the next request posts again). Never
    /// waits.
    pub fn post(&mut self, slot: usize, job: InverseJob) {
        if let Ok(mut m) = self.mailbox.try_lock() {
            if let Some(j) = m.jobs.get_mut(slot) {
                *j = Some(job);
            }
        }
        if let Some(h) = &self.handle {
            h.thread().unpark();
        }
    }

    /// Slot `slot`'s last finished answer (refreshed from the mailbox when it is free).
    /// Never waits.
    pub fn answer(&mut self, slot: usize) -> Option<InverseAnswer> {
        if let Ok(m) = self.mailbox.try_lock() {
            for (mine, theirs) in self.answers.iter_mut().zip(&m.answers) {
                if theirs.is_some() {
                    *mine = *theirs;
                }
            }
        }
        self.answers.get(slot).copied().flatten()
    }

    /// Searches the worker has finished (waits for the mailbox: tests only).
    #[cfg(test)]
    pub fn searches_done(&self) -> u64 {
        self.mailbox.lock().map(|m| m.searches).unwrap_or(0)
    }

    /// Forget slot `slot`'s job and answer (its client is gone; a new one takes the slot).
    /// Never waits: a busy mailbox keeps them, and the new client's answers are told apart by
    /// their requirement.
    pub fn clear(&mut self, slot: usize) {
        if let Ok(mut m) = self.mailbox.try_lock() {
            if slot < SLOTS {
                m.jobs[slot] = None;
                m.answers[slot] = None;
            }
        }
        if let Some(a) = self.answers.get_mut(slot) {
            *a = None;
        }
    }
}

impl Drop for InverseWorker {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(h) = self.handle.take() {
            h.thread().unpark();
            let _ = h.join();
        }
    }
}

/// Take the next slot's job (a slot without any answer yet first, so that a new client's
/// first answer waits for at most one search; otherwise round robin from the slot after the
/// last one served), search, post the answer into that slot; park when idle.
fn worker_loop(est: &mut Estimator, mailbox: &Mutex<Mailbox>, stop: &AtomicBool) {
    lower_priority();
    let mut next = 0;
    while !stop.load(Ordering::Acquire) {
        let job = match mailbox.lock() {
            Ok(mut m) => {
                // A client without any answer yet (a new one) first, then round robin.
                let order = || (0..SLOTS).map(|k| (next + k) % SLOTS);
                let i = order()
                    .find(|&i| m.jobs[i].is_some() && m.answers[i].is_none())
                    .or_else(|| order().find(|&i| m.jobs[i].is_some()));
                i.and_then(|i| m.jobs[i].take().map(|j| (i, j)))
            }
            Err(_) => return,
        };
        let Some((slot, j)) = job else {
            std::thread::park_timeout(IDLE_PARK);
            continue;
        };
        next = (slot + 1) % SLOTS;
        let t0 = std::time::Instant::now();
        let t = carried(est.t_min_for_f1_near(&j.pose, j.required_f1_hz, Some(j.hint_n)));
        let worked = t0.elapsed();
        if let Ok(mut m) = mailbox.lock() {
            m.answers[slot] = Some(InverseAnswer {
                required_f1_hz: j.required_f1_hz,
                cycle: j.cycle,
                t_min_n: t,
            });
            m.searches += 1;
        }
        std::thread::sleep((worked * REST_PER_WORK).min(MAX_REST));
    }
}

/// This thread's niceness to [`WORKER_NICE`] (Linux: per thread); a failure only leaves the
/// default priority.
#[cfg(target_os = "linux")]
fn lower_priority() {
    // SAFETY: setpriority on this thread's own id, no memory passed.
    unsafe {
        let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
        let _ = libc::setpriority(libc::PRIO_PROCESS, tid, WORKER_NICE);
    }
}

/// Elsewhere the worker keeps the default priority (its rest still halves its share).
#[cfg(not(target_os = "linux"))]
fn lower_priority() {}

/// Which mailbox slot each margin client has: up to [`SLOTS`] clients (the service admits no
/// more); a new client beyond that takes the slot of the one heard from least recently (a
/// client that has gone). Fixed size, no allocation, O(SLOTS) per request.
#[derive(Debug, Clone, Copy)]
pub struct ClientSlots<K: Copy + Eq> {
    /// (client, when last heard from in `clock` ticks).
    clients: [Option<(K, u64)>; SLOTS],
    clock: u64,
}

impl<K: Copy + Eq> Default for ClientSlots<K> {
    fn default() -> Self {
        ClientSlots {
            clients: [None; SLOTS],
            clock: 0,
        }
    }
}

impl<K: Copy + Eq> ClientSlots<K> {
    /// The slot of client `key`, and whether it was just given to it (a new client).
    pub fn slot(&mut self, key: K) -> (usize, bool) {
        self.clock += 1;
        let now = self.clock;
        if let Some(i) = self
            .clients
            .iter()
            .position(|c| c.is_some_and(|(k, _)| k == key))
        {
            self.clients[i] = Some((key, now));
            return (i, false);
        }
        let i = self
            .clients
            .iter()
            .enumerate()
            .min_by_key(|(_, c)| c.map_or(0, |(_, t)| t))
            .map_or(0, |(i, _)| i);
        self.clients[i] = Some((key, now));
        (i, true)
    }
}
