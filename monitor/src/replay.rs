//! `cablevib replay FILE.mcap`: the poses and T_min set-points of a recording, sent to a
//! service, so a run can be re-analysed with another model, T_min or scene.
//!
//! The poses (schema `cablevib.Pose`) and set-points (`cablevib.TminSetpoint`) of the file are
//! merged in the order of their timestamps and sent with their recorded sequence numbers and
//! fresh timestamps (so the service's latencies are today's). Pace:
//!
//! - [`Pace::Recorded`]: each message at its recorded time after the first;
//! - [`Pace::Fast`]: as fast as the service answers: a pose, then its estimate, then the next
//!   pose; the service estimates every pose, none is skipped.
//!
//! With `answered_only` only the poses the recorded service answered are sent (a service
//! busy with one pose skips the ones queued meanwhile): the estimator then sees the same
//! sequence of poses as in the recording, and a service with the same scene gives the same
//! estimates bit for bit (its warm starts follow the same path). `t_min_n` replaces the
//! recorded set-points with one uniform set-point sent first.
//!
//! The file must be a complete MCAP file (a monitor killed before it closed the file leaves one
//! without its summary; the Python `mcap` reader reads it up to its last whole chunk).

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use cablevib_ipc::{monotonic_now_ns, EstimateSample, ServiceNames, TminSetpoint};
use cablevib_service::ports::{create_node, EstimateOutput, PoseInput};
use cablevib_service::WaitMode;

use crate::encode::{PoseRecord, TminRecord, SCHEMA_ESTIMATE, SCHEMA_POSE, SCHEMA_T_MIN};
use crate::MonitorError;

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
}

/// What a replay sent and got back.
#[derive(Debug, Clone, Default)]
pub struct ReplayReport {
    /// Poses sent.
    pub poses: u64,
    /// Set-points sent.
    pub t_mins: u64,
    /// The estimates received, in order.
    pub estimates: Vec<EstimateSample>,
    /// Poses whose estimate did not come within the timeout ([`Pace::Fast`]).
    pub timeouts: u64,
}

/// The content of a recording.
#[derive(Debug, Clone, Default)]
pub struct Recording {
    /// Poses, in file order.
    pub poses: Vec<PoseRecord>,
    /// Set-points, in file order.
    pub t_mins: Vec<TminRecord>,
    /// Estimates as JSON objects, in file order.
    pub estimates: Vec<serde_json::Value>,
}

/// Reads the cablevib channels of MCAP file `path`. Fails with one line on a file that is not
/// a complete MCAP file or holds no cablevib poses.
pub fn read_recording(path: &std::path::Path) -> Result<Recording, MonitorError> {
    let shown = path.display();
    let bad = |what: String| MonitorError::Recording(format!("{shown}: {what}"));
    let bytes = std::fs::read(path).map_err(|e| bad(format!("cannot read: {e}")))?;
    let one_line = |e: &dyn std::fmt::Display| e.to_string().replace('\n', " ");
    if !bytes.starts_with(mcap::MAGIC) {
        return Err(bad("not an MCAP file (no MCAP magic at its start)".into()));
    }
    // The summary is at the end of a complete file: its absence means the file was cut short.
    mcap::Summary::read(&bytes)
        .map_err(|e| bad(format!("not a complete MCAP file ({})", one_line(&e))))?;
    let stream = mcap::MessageStream::new(&bytes)
        .map_err(|e| bad(format!("not an MCAP file ({})", one_line(&e))))?;
    let mut rec = Recording::default();
    for m in stream {
        let m = m.map_err(|e| bad(format!("unreadable MCAP content ({})", one_line(&e))))?;
        let Some(schema) = m.channel.schema.as_ref() else {
            continue;
        };
        let parse = |what: &str| -> Result<serde_json::Value, MonitorError> {
            serde_json::from_slice(&m.data).map_err(|e| {
                bad(format!(
                    "a {what} message on {} is not valid JSON ({e})",
                    m.channel.topic
                ))
            })
        };
        match schema.name.as_str() {
            SCHEMA_POSE => rec
                .poses
                .push(serde_json::from_value(parse("pose")?).map_err(|e| {
                    bad(format!(
                        "a pose on {} does not fit {SCHEMA_POSE} ({e})",
                        m.channel.topic
                    ))
                })?),
            SCHEMA_T_MIN => rec
                .t_mins
                .push(serde_json::from_value(parse("T_min")?).map_err(|e| {
                    bad(format!(
                        "a set-point on {} does not fit {SCHEMA_T_MIN} ({e})",
                        m.channel.topic
                    ))
                })?),
            SCHEMA_ESTIMATE => rec.estimates.push(parse("estimate")?),
            _ => {}
        }
    }
    if rec.poses.is_empty() {
        return Err(bad(format!(
            "no cablevib poses (schema {SCHEMA_POSE}) in this MCAP file: not a `cablevib monitor` recording"
        )));
    }
    Ok(rec)
}

enum Item {
    Pose(PoseRecord),
    Tmin(TminSetpoint),
}

/// Replays `cfg.file` into the service of `cfg.instance`.
pub fn replay(cfg: &ReplayConfig, stop: &AtomicBool) -> Result<ReplayReport, MonitorError> {
    cablevib_ipc::check_instance(&cfg.instance).map_err(|e| MonitorError::Usage(e.to_string()))?;
    if let Some(t) = cfg.t_min_n {
        if !(t.is_finite() && t >= 0.0) {
            return Err(MonitorError::Usage(format!(
                "--t-min {t:?} must be finite and ≥ 0 N"
            )));
        }
    }
    let rec = read_recording(&cfg.file)?;
    let answered: BTreeSet<u64> = rec
        .estimates
        .iter()
        .filter_map(|e| e["pose_sequence"].as_u64())
        .collect();
    let mut items: Vec<(u64, Item)> = Vec::with_capacity(rec.poses.len() + rec.t_mins.len());
    for p in rec.poses {
        if !cfg.answered_only || answered.contains(&p.sequence) {
            items.push((p.timestamp_ns, Item::Pose(p)));
        }
    }
    match cfg.t_min_n {
        Some(t) => items.push((0, Item::Tmin(TminSetpoint::uniform(1, 0, t)))),
        None => {
            for t in rec.t_mins {
                let ts = t.timestamp_ns;
                let s = t.sample().ok_or_else(|| {
                    MonitorError::Recording(format!(
                        "{}: a T_min set-point has too many cables",
                        cfg.file.display()
                    ))
                })?;
                items.push((ts, Item::Tmin(s)));
            }
        }
    }
    // Stable: a set-point and a pose with the same timestamp keep their file order.
    items.sort_by_key(|(t, _)| *t);

    let names = ServiceNames::new(&cfg.instance);
    let node = create_node("cablevib-replay")?;
    let input = PoseInput::open(&node, &names)?;
    let output = EstimateOutput::open(&node, &names)?;
    let deadline = Instant::now() + cfg.timeout;
    while !(input.service_connected() && output.service_connected()) {
        if stop.load(Ordering::Acquire) {
            return Ok(ReplayReport::default());
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
    let first_ts = items.iter().map(|(t, _)| *t).find(|t| *t > 0).unwrap_or(0);
    let start = Instant::now();
    for (ts, item) in items {
        if stop.load(Ordering::Acquire) {
            break;
        }
        if cfg.pace == Pace::Recorded && ts > first_ts {
            let due = start + Duration::from_nanos(ts - first_ts);
            let now = Instant::now();
            if due > now {
                std::thread::sleep(due - now);
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
                        match output.wait(WaitMode::Event, Duration::from_millis(20))? {
                            Some(e) => {
                                report.estimates.push(e);
                                if e.pose_sequence == pose.sequence
                                    && e.pose_timestamp_ns == pose.timestamp_ns
                                {
                                    break;
                                }
                            }
                            None if waited.elapsed() > cfg.timeout
                                || stop.load(Ordering::Acquire) =>
                            {
                                report.timeouts += 1;
                                break;
                            }
                            None => {}
                        }
                    }
                } else {
                    while let Some(e) = output.try_receive()? {
                        report.estimates.push(e);
                    }
                }
            }
        }
    }
    // The last estimates.
    let end = Instant::now() + Duration::from_millis(200);
    while Instant::now() < end {
        if let Some(e) = output.wait(WaitMode::Event, Duration::from_millis(20))? {
            report.estimates.push(e);
        }
    }
    Ok(report)
}
