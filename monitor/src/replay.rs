//! `cablevib replay FILE.mcap`: the poses and T_min set-points of a recording, sent to a
//! service, so a run can be re-analysed with another model, T_min or scene.
//!
//! The recording is streamed ([`crate::recording`]: chunk by chunk, bounded memory whatever its
//! length). Its poses (schema `cablevib.Pose`) and set-points (`cablevib.TminSetpoint`) are
//! sent in the order of their timestamps, sorted within a window of [`REORDER_WINDOW`]
//! messages of the file (the monitor writes them in the order it read them, at most a few
//! queue lengths apart from timestamp order), with their recorded sequence numbers and fresh
//! timestamps (so the service's latencies are today's). Pace:
//!
//! - [`Pace::Recorded`]: each message at its recorded time after the previous one, a pause
//!   longer than [`ReplayConfig::max_gap`] (default [`DEFAULT_MAX_GAP_S`]) shortened to it
//!   (counted: [`ReplayReport::gaps_shortened`]); the waits are cut into slices of at most
//!   [`SLEEP_SLICE`], so SIGINT/SIGTERM stop the replay within one slice;
//! - [`Pace::Fast`]: as fast as the service answers: a pose, then its estimate, then the next
//!   pose; the service estimates every pose, none is skipped.
//!
//! With `answered_only` only the poses the recorded service answered are sent (a service
//! busy with one pose skips the ones queued meanwhile): an estimate answers a pose when it
//! lies within [`REORDER_WINDOW`] messages of it in the file (the monitor records an estimate
//! right after its pose). The estimator then sees the same sequence of poses as in the
//! recording, and a service with the same scene gives the same estimates bit for bit (its warm
//! starts follow the same path). `t_min_n` replaces the recorded set-points with one uniform
//! set-point sent first.

use std::cmp::Ordering as CmpOrdering;
use std::collections::{BinaryHeap, HashMap, VecDeque};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use cablevib_ipc::{monotonic_now_ns, EstimateSample, ServiceNames, TminSetpoint};
use cablevib_service::ports::{create_node, EstimateOutput, PoseInput};
use cablevib_service::WaitMode;

use crate::encode::PoseRecord;
use crate::recording::{read_recording, Recorded, RecordingReader};
use crate::MonitorError;

/// Messages of the file sorted by timestamp at a time, and the distance (in messages) within
/// which an estimate is matched to its pose for `answered_only`.
pub const REORDER_WINDOW: usize = 8192;
/// Default longest pause kept from the recording, s.
pub const DEFAULT_MAX_GAP_S: f64 = 1.0;
/// Longest single sleep of the replay: a stop (SIGINT/SIGTERM) is seen within it.
pub const SLEEP_SLICE: Duration = Duration::from_millis(20);

/// How to time the replay.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pace {
    /// At the recorded timing.
    Recorded,
    /// Each pose after the estimate of the previous one.
    Fast,
}

/// What `cablevib replay` does.
#[derive(Debug, Clone)]
pub struct ReplayConfig {
    /// The recording.
    pub file: PathBuf,
    /// The instance of the service to replay into.
    pub instance: String,
    /// Timing.
    pub pace: Pace,
    /// Send only the poses the recorded service answered.
    pub answered_only: bool,
    /// Replace the recorded T_min set-points by this uniform one, N.
    pub t_min_n: Option<f64>,
    /// How long to wait for the service, and for one estimate in [`Pace::Fast`].
    pub timeout: Duration,
    /// The longest pause kept from the recording ([`Pace::Recorded`]); a longer one is
    /// shortened to it.
    pub max_gap: Duration,
}

impl ReplayConfig {
    /// A replay of `file` into `instance` at the recorded pace, every pose, the recorded
    /// set-points, a 10 s timeout and pauses of at most [`DEFAULT_MAX_GAP_S`].
    pub fn new(file: PathBuf, instance: &str) -> ReplayConfig {
        ReplayConfig {
            file,
            instance: instance.to_owned(),
            pace: Pace::Recorded,
            answered_only: false,
            t_min_n: None,
            timeout: Duration::from_secs(10),
            max_gap: Duration::from_secs_f64(DEFAULT_MAX_GAP_S),
        }
    }
}

/// What a replay sent and got back.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ReplayReport {
    /// Poses sent.
    pub poses: u64,
    /// Set-points sent.
    pub t_mins: u64,
    /// Estimates received.
    pub estimates: u64,
    /// Of which with status ok.
    pub estimates_ok: u64,
    /// Poses whose estimate did not come within the timeout ([`Pace::Fast`]).
    pub timeouts: u64,
    /// Pauses of the recording longer than the maximum, shortened to it ([`Pace::Recorded`]).
    pub gaps_shortened: u64,
    /// The replay stopped on a signal (or the caller's stop flag) before the end.
    pub stopped: bool,
}

enum Item {
    Pose(PoseRecord),
    Tmin(TminSetpoint),
}

/// A message waiting in the reorder window, ordered by (timestamp, file position).
struct Queued {
    ts: u64,
    index: u64,
    item: Item,
}

impl PartialEq for Queued {
    fn eq(&self, other: &Self) -> bool {
        (self.ts, self.index) == (other.ts, other.index)
    }
}
impl Eq for Queued {}
impl PartialOrd for Queued {
    fn partial_cmp(&self, other: &Self) -> Option<CmpOrdering> {
        Some(self.cmp(other))
    }
}
impl Ord for Queued {
    /// Reversed: the heap's top is the earliest.
    fn cmp(&self, other: &Self) -> CmpOrdering {
        (other.ts, other.index).cmp(&(self.ts, self.index))
    }
}

/// The estimates' pose sequences seen in the last `2 × REORDER_WINDOW` messages.
#[derive(Default)]
struct RecentAnswers {
    order: VecDeque<u64>,
    count: HashMap<u64, u32>,
}

impl RecentAnswers {
    fn push(&mut self, sequence: u64) {
        if self.order.len() == 2 * REORDER_WINDOW {
            if let Some(old) = self.order.pop_front() {
                if let Some(c) = self.count.get_mut(&old) {
                    *c -= 1;
                    if *c == 0 {
                        self.count.remove(&old);
                    }
                }
            }
        }
        self.order.push_back(sequence);
        *self.count.entry(sequence).or_insert(0) += 1;
    }

    fn contains(&self, sequence: u64) -> bool {
        self.count.contains_key(&sequence)
    }
}

/// The file's poses and set-points in timestamp order (within the window).
struct Ordered {
    reader: RecordingReader,
    heap: BinaryHeap<Queued>,
    answers: RecentAnswers,
    index: u64,
    t_min_override: bool,
    answered_only: bool,
    done: bool,
    poses_read: u64,
}

impl Ordered {
    /// Reads until the window is full or the file ends.
    fn fill(&mut self) -> Result<(), MonitorError> {
        while !self.done && self.heap.len() <= REORDER_WINDOW {
            let Some(m) = self.reader.next() else {
                self.done = true;
                break;
            };
            self.index += 1;
            let (ts, item) = match m? {
                Recorded::Pose(p) => {
                    self.poses_read += 1;
                    (p.timestamp_ns, Item::Pose(p))
                }
                Recorded::Tmin(_) if self.t_min_override => continue,
                Recorded::Tmin(t) => {
                    let s = t.sample().ok_or_else(|| {
                        self.reader_error("a T_min set-point has too many cables")
                    })?;
                    (t.timestamp_ns, Item::Tmin(s))
                }
                Recorded::Estimate(json) => {
                    if self.answered_only {
                        #[derive(serde::Deserialize)]
                        struct Answers {
                            pose_sequence: u64,
                        }
                        if let Ok(a) = serde_json::from_slice::<Answers>(&json) {
                            self.answers.push(a.pose_sequence);
                        }
                    }
                    continue;
                }
            };
            self.heap.push(Queued {
                ts,
                index: self.index,
                item,
            });
        }
        Ok(())
    }

    fn reader_error(&self, what: &str) -> MonitorError {
        MonitorError::Recording(format!("{what} in the recording"))
    }

    /// The next message to send, `None` at the end.
    fn next(&mut self) -> Result<Option<(u64, Item)>, MonitorError> {
        loop {
            self.fill()?;
            let Some(q) = self.heap.pop() else {
                return Ok(None);
            };
            if let Item::Pose(p) = &q.item {
                if self.answered_only && !self.answers.contains(p.sequence) {
                    continue;
                }
            }
            return Ok(Some((q.ts, q.item)));
        }
    }
}

/// Sleeps until `due`, in slices of at most [`SLEEP_SLICE`]; false when `stop` was set.
fn sleep_until(due: Instant, stop: &AtomicBool) -> bool {
    loop {
        if stop.load(Ordering::Acquire) {
            return false;
        }
        let now = Instant::now();
        if now >= due {
            return true;
        }
        std::thread::sleep((due - now).min(SLEEP_SLICE));
    }
}

/// Replays `cfg.file` into the service of `cfg.instance`; `on_estimate` sees every estimate
/// received, in order.
pub fn replay(
    cfg: &ReplayConfig,
    stop: &AtomicBool,
    mut on_estimate: impl FnMut(&EstimateSample),
) -> Result<ReplayReport, MonitorError> {
    cablevib_ipc::check_instance(&cfg.instance).map_err(|e| MonitorError::Usage(e.to_string()))?;
    if let Some(t) = cfg.t_min_n {
        if !(t.is_finite() && t >= 0.0) {
            return Err(MonitorError::Usage(format!(
                "--t-min {t:?} must be finite and ≥ 0 N"
            )));
        }
    }
    if cfg.max_gap.is_zero() {
        return Err(MonitorError::Usage("--max-gap-s must be > 0 s".into()));
    }
    let mut ordered = Ordered {
        reader: read_recording(&cfg.file)?,
        heap: BinaryHeap::new(),
        answers: RecentAnswers::default(),
        index: 0,
        t_min_override: cfg.t_min_n.is_some(),
        answered_only: cfg.answered_only,
        done: false,
        poses_read: 0,
    };
    // A file without poses is refused before anything is sent.
    ordered.fill()?;
    if ordered.poses_read == 0 {
        return Err(MonitorError::Recording(format!(
            "{}: no cablevib poses (schema {}) in this MCAP file{}: not a `cablevib monitor` \
             recording",
            cfg.file.display(),
            crate::encode::SCHEMA_POSE,
            if ordered.done {
                String::new()
            } else {
                format!(" (none among its first {REORDER_WINDOW} cablevib messages)")
            }
        )));
    }

    let names = ServiceNames::new(&cfg.instance);
    let node = create_node("cablevib-replay")?;
    let input = PoseInput::open(&node, &names)?;
    let output = EstimateOutput::open(&node, &names)?;
    let deadline = Instant::now() + cfg.timeout;
    while !(input.service_connected() && output.service_connected()) {
        if stop.load(Ordering::Acquire) {
            return Ok(ReplayReport {
                stopped: true,
                ..ReplayReport::default()
            });
        }
        if Instant::now() > deadline {
            return Err(MonitorError::NoService {
                instance: cfg.instance.clone(),
                seconds: cfg.timeout.as_secs_f64(),
            });
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let mut report = ReplayReport::default();
    let mut got = |e: &EstimateSample, report: &mut ReplayReport| {
        report.estimates += 1;
        report.estimates_ok += u64::from(e.is_ok());
        on_estimate(e);
    };
    if let Some(t) = cfg.t_min_n {
        input.send_t_min(&TminSetpoint::uniform(1, monotonic_now_ns(), t))?;
        report.t_mins += 1;
    }
    // Recorded pace: the replay's clock, the recorded gaps capped at max_gap.
    let start = Instant::now();
    let mut elapsed = Duration::ZERO;
    let mut previous_ts: Option<u64> = None;
    while let Some((ts, item)) = ordered.next()? {
        if stop.load(Ordering::Acquire) {
            report.stopped = true;
            break;
        }
        if cfg.pace == Pace::Recorded {
            if let Some(prev) = previous_ts {
                let mut gap = Duration::from_nanos(ts.saturating_sub(prev));
                if gap > cfg.max_gap {
                    gap = cfg.max_gap;
                    report.gaps_shortened += 1;
                }
                elapsed += gap;
            }
            previous_ts = Some(ts);
            if !sleep_until(start + elapsed, stop) {
                report.stopped = true;
                break;
            }
        }
        match item {
            Item::Tmin(mut s) => {
                s.timestamp_ns = monotonic_now_ns();
                input.send_t_min(&s)?;
                report.t_mins += 1;
            }
            Item::Pose(p) => {
                let mut pose = p.sample();
                pose.timestamp_ns = monotonic_now_ns();
                input.send_pose(&pose)?;
                report.poses += 1;
                if cfg.pace == Pace::Fast {
                    let waited = Instant::now();
                    loop {
                        match output.wait(WaitMode::Event, SLEEP_SLICE)? {
                            Some(e) => {
                                got(&e, &mut report);
                                if e.answers(&pose) {
                                    break;
                                }
                            }
                            None if stop.load(Ordering::Acquire) => {
                                report.stopped = true;
                                break;
                            }
                            None if waited.elapsed() > cfg.timeout => {
                                report.timeouts += 1;
                                break;
                            }
                            None => {}
                        }
                    }
                } else {
                    while let Some(e) = output.try_receive()? {
                        got(&e, &mut report);
                    }
                }
            }
        }
    }
    // The last estimates.
    let end = Instant::now() + Duration::from_millis(200);
    while Instant::now() < end && !stop.load(Ordering::Acquire) {
        if let Some(e) = output.wait(WaitMode::Event, SLEEP_SLICE)? {
            got(&e, &mut report);
        }
    }
    Ok(report)
}
