//! The monitor process: iceoryx2 subscribers in the calling thread (queues of
//! [`RECORD_BUFFER`] samples, every sequence counted: [`crate::completeness`]), a bounded queue,
//! a writer thread that encodes and logs to the record (MCAP file), and a viewers' thread that
//! serves the Foxglove WebSocket from a queue of its own ([`crate::viewers`]).

use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{sync_channel, SyncSender, TrySendError};
use std::time::{Duration, Instant};

use cablevib::output_file::OutputFile;
use cablevib::scene::Scene;
use cablevib_ipc::{monotonic_now_ns, MarginRequest, PoseSample, ServiceNames, TminSetpoint};
pub use cablevib_service::ports::RECORD_BUFFER;
use cablevib_service::ports::{
    create_node, open_pubsub, EstimateOutput, MarginClient, PendingMargin, ReadAttributes,
    POSE_SETTINGS, T_MIN_SETTINGS,
};
use foxglove::{Context, McapCompression, McapWriteOptions};
use iceoryx2::identifiers::UniquePublisherId;

use crate::addr::FoxgloveAddr;
use crate::completeness::{ChannelCompleteness, SequenceCounter};
use crate::viewers::{self, Admission, ViewerReport};
pub use crate::writer::topic;
use crate::writer::{self, Channels, Record, Sinks};
use crate::MonitorError;

/// Capacity of the queue between the iceoryx2 thread and the writer, messages (≈ 8 s of
/// estimates and poses at 1 kHz; ≈ 4.5 MB). When it is full the newest message is dropped and
/// counted per channel: the monitor never blocks its subscribers, which would only lose older
/// samples in their iceoryx2 queues instead.
pub const QUEUE_CAPACITY: usize = 16_384;
/// MCAP chunk size, bytes (before compression): at 1 kHz a chunk closes every ≈ 0.3 s, which
/// bounds what a killed monitor loses.
pub const CHUNK_BYTES: u64 = 256 * 1024;
/// How long the iceoryx2 loop blocks on the wake-controller event before it looks again (the
/// pose and T_min queues hold [`RECORD_BUFFER`] samples: ≈ 2 s at 1 kHz).
const WAKE_WAIT: Duration = Duration::from_millis(20);
/// Samples taken from one queue per pass, so that one flooded queue cannot starve the others.
const DRAIN_LIMIT: usize = RECORD_BUFFER;
/// A margin query of the monitor unanswered this long is abandoned.
const MARGIN_TIMEOUT: Duration = Duration::from_millis(200);

/// What `cablevib monitor` runs.
#[derive(Debug, Clone)]
pub struct MonitorConfig {
    /// Instance of the service (`--instance` of `cablevib serve`).
    pub instance: String,
    /// Namespace of the topics ([`topic`]); by default the instance.
    pub topic_namespace: String,
    /// The scene the service estimates (for the 3D view; `None`: no 3D view).
    pub scene: Option<Scene>,
    /// The scene as named on the command line (metadata).
    pub scene_file: String,
    /// Serve live over the Foxglove WebSocket protocol here (`None`: no server).
    pub foxglove: Option<FoxgloveAddr>,
    /// Record to this MCAP file (created; an existing file is refused).
    pub record: Option<PathBuf>,
    /// Required f1, Hz: estimates carry `margin_hz` against it, and the monitor asks the
    /// service for its margin answer at the scene rate.
    pub required_hz: Option<f64>,
    /// Rate of the 3D scene updates, Hz (estimates are logged at full rate).
    pub scene_rate_hz: f64,
    /// How long to wait for the service to publish.
    pub wait_timeout: Duration,
    /// Stop after this long (`None`: until a signal or `stop`).
    pub duration: Option<Duration>,
    /// Viewers that get data at most ([`crate::viewers`]); further ones are refused.
    pub max_viewers: usize,
}

impl MonitorConfig {
    /// A monitor of `instance` with no server, no recording, 30 Hz scene updates, a 10 s wait.
    pub fn new(instance: &str) -> MonitorConfig {
        MonitorConfig {
            instance: instance.to_owned(),
            topic_namespace: instance.to_owned(),
            scene: None,
            scene_file: String::new(),
            foxglove: None,
            record: None,
            required_hz: None,
            scene_rate_hz: 30.0,
            wait_timeout: Duration::from_secs(10),
            duration: None,
            max_viewers: viewers::DEFAULT_MAX_VIEWERS,
        }
    }
}

/// Counts of one monitor run: how complete the record is, per channel.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MonitorReport {
    /// The estimates.
    pub estimate: ChannelCompleteness,
    /// The poses.
    pub pose: ChannelCompleteness,
    /// The T_min set-points.
    pub t_min: ChannelCompleteness,
    /// Margin answers logged.
    pub margins: u64,
    /// Scene updates logged.
    pub scene_updates: u64,
    /// Margin answers dropped because the monitor's queue was full.
    pub margins_dropped: u64,
    /// The viewers.
    pub viewers: ViewerReport,
}

impl MonitorReport {
    /// Every estimate, pose and set-point received is recorded and no sequence gap was seen.
    pub fn complete(&self) -> bool {
        [&self.estimate, &self.pose, &self.t_min]
            .iter()
            .all(|c| c.missing() == 0)
    }

    /// The completeness entries of the MCAP metadata record `cablevib.completeness`.
    pub fn metadata(&self) -> BTreeMap<String, String> {
        let mut m = BTreeMap::new();
        self.estimate.metadata("estimate", &mut m);
        self.pose.metadata("pose", &mut m);
        self.t_min.metadata("t_min", &mut m);
        m.insert("margin.recorded".into(), self.margins.to_string());
        m.insert(
            "margin.dropped_queue".into(),
            self.margins_dropped.to_string(),
        );
        m.insert("scene.recorded".into(), self.scene_updates.to_string());
        m.insert("complete".into(), self.complete().to_string());
        m
    }
}

impl core::fmt::Display for MonitorReport {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.complete() {
            writeln!(
                f,
                "record complete: every estimate, pose and T_min set-point sent while the \
                 monitor listened is recorded"
            )?;
        } else {
            writeln!(
                f,
                "record INCOMPLETE: {} estimates, {} poses, {} T_min set-points missing",
                self.estimate.missing(),
                self.pose.missing(),
                self.t_min.missing()
            )?;
        }
        writeln!(f, "  estimates: {}", self.estimate)?;
        writeln!(f, "  poses: {}", self.pose)?;
        writeln!(f, "  T_min set-points: {}", self.t_min)?;
        write!(
            f,
            "  {} margin answers, {} scene updates; viewers: {} served, {} refused, {} \
             messages dropped for the viewers",
            self.margins,
            self.scene_updates,
            self.viewers.admitted,
            self.viewers.refused,
            self.viewers.dropped
        )
    }
}

/// What the monitor tells its caller once it is attached.
#[derive(Debug, Clone)]
pub struct Attached {
    /// The WebSocket URL (when serving).
    pub url: Option<String>,
    /// The port the server listens on (when serving; the OS's choice for port 0).
    pub port: Option<u16>,
    /// The estimate service's attributes.
    pub attributes: ReadAttributes,
    /// Where the scene of the 3D view comes from.
    pub scene: SceneSource,
}

/// Where the scene of the 3D view comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SceneSource {
    /// The caller's (`--scene`).
    Given,
    /// The one the service names in its attributes (`cablevib.scene`).
    Service,
    /// None: no 3D view, for this reason.
    None(String),
}

/// `CLOCK_REALTIME − CLOCK_MONOTONIC` now, ns: maps the messages' monotonic timestamps to the
/// Unix-epoch log times MCAP and Foxglove expect.
fn realtime_offset_ns() -> i128 {
    let real = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as i128);
    real - monotonic_now_ns() as i128
}

/// The metadata of a run: scene, model, elements, the service's attributes, the version.
fn metadata(
    cfg: &MonitorConfig,
    scene: Option<&Scene>,
    attributes: &ReadAttributes,
    offset_ns: i128,
) -> BTreeMap<String, String> {
    let mut m = BTreeMap::new();
    m.insert(
        "cablevib.monitor_version".into(),
        env!("CARGO_PKG_VERSION").into(),
    );
    m.insert("instance".into(), cfg.instance.clone());
    m.insert("scene_file".into(), cfg.scene_file.clone());
    if let Some(s) = scene {
        m.insert("scene".into(), s.name.clone());
        m.insert("model".into(), s.model.element.as_str().into());
        m.insert(
            "elements_per_cable".into(),
            s.model.elements_per_cable.to_string(),
        );
        m.insert("cables".into(), s.n_cables().to_string());
        m.insert("rigid".into(), s.rigid.to_string());
        m.insert("sag".into(), s.model.sag.to_string());
    }
    if let Some(r) = cfg.required_hz {
        m.insert("required_f1_hz".into(), format!("{r:?}"));
    }
    m.insert("log_time_minus_monotonic_ns".into(), offset_ns.to_string());
    for (k, v) in &attributes.pairs {
        m.insert(format!("service.{k}"), v.clone());
    }
    m
}

/// Runs the monitor until `stop` is set, `cfg.duration` passes or the service does not come
/// up in time. `attached` is called once the subscribers exist and the service publishes.
pub fn run(
    cfg: &MonitorConfig,
    stop: &AtomicBool,
    attached: impl FnOnce(&Attached),
) -> Result<MonitorReport, MonitorError> {
    if !(cfg.scene_rate_hz.is_finite() && cfg.scene_rate_hz > 0.0 && cfg.scene_rate_hz <= 1000.0) {
        return Err(MonitorError::Usage(format!(
            "--scene-rate-hz {:?} must be in (0, 1000]",
            cfg.scene_rate_hz
        )));
    }
    if let Some(r) = cfg.required_hz {
        if !MarginRequest::new(0, 0, r).is_valid() {
            return Err(MonitorError::Usage(format!(
                "--required-hz {r:?} must be in [{}, {}] Hz",
                cablevib_ipc::REQUIRED_F1_MIN_HZ,
                cablevib_ipc::REQUIRED_F1_MAX_HZ
            )));
        }
    }
    cablevib_ipc::check_instance(&cfg.instance).map_err(|e| MonitorError::Usage(e.to_string()))?;
    // The file first: a bad path fails before anything else starts. Recorded under a
    // temporary name beside it, put in place when closed (never over an existing file).
    let file = match &cfg.record {
        Some(p) => Some(
            OutputFile::create_new(p)
                .and_then(OutputFile::unbuffered)
                .map_err(|e| MonitorError::Record(format!("cannot create the recording: {e}")))?,
        ),
        None => None,
    };

    let names = ServiceNames::new(&cfg.instance);
    let node = create_node("cablevib-monitor")?;
    // Subscribers before the service publishes: nothing it sends after this is missed. Each
    // queues RECORD_BUFFER samples, the most the services allow.
    let estimates = EstimateOutput::open_recorder(&node, &names)?;
    let poses = open_pubsub::<PoseSample>(&node, &names.pose, POSE_SETTINGS)?
        .subscriber_builder()
        .buffer_size(RECORD_BUFFER)
        .create()
        .map_err(|e| MonitorError::Foxglove(format!("pose subscriber: {e:?}")))?;
    let t_mins = open_pubsub::<TminSetpoint>(&node, &names.t_min, T_MIN_SETTINGS)?
        .subscriber_builder()
        .buffer_size(RECORD_BUFFER)
        .create()
        .map_err(|e| MonitorError::Foxglove(format!("T_min subscriber: {e:?}")))?;
    let margin = match cfg.required_hz {
        Some(_) => Some(MarginClient::open(&node, &names)?),
        None => None,
    };

    if !estimates.service_connected() {
        eprintln!(
            "cablevib monitor: waiting for the cablevib service of instance {:?} (up to {} s)",
            cfg.instance,
            cfg.wait_timeout.as_secs_f64()
        );
        let deadline = Instant::now() + cfg.wait_timeout;
        while !estimates.service_connected() {
            if stop.load(Ordering::Acquire) {
                return Ok(MonitorReport::default());
            }
            if Instant::now() > deadline {
                return Err(MonitorError::NoService {
                    instance: cfg.instance.clone(),
                    seconds: cfg.wait_timeout.as_secs_f64(),
                });
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }
    let attributes = estimates.attributes();
    let (scene, scene_source) = match &cfg.scene {
        Some(s) => (Some(s.clone()), SceneSource::Given),
        None => match crate::scene3d::scene_of_service(&attributes) {
            Ok(s) => (Some(s), SceneSource::Service),
            Err(why) => (None, SceneSource::None(why)),
        },
    };
    let offset_ns = realtime_offset_ns();
    let meta = metadata(cfg, scene.as_ref(), &attributes, offset_ns);

    // The record: its own Foxglove context, so that nothing a viewer does can slow it.
    let record_ctx = Context::new();
    let mcap = match file {
        Some(f) => {
            let options = McapWriteOptions::new()
                .compression(Some(McapCompression::Lz4))
                .chunk_size(Some(CHUNK_BYTES));
            let handle = record_ctx
                .mcap_writer_with_options(options)
                .create(f)
                .map_err(|e| MonitorError::Record(format!("MCAP writer: {e}")))?;
            handle
                .write_metadata("cablevib", meta.clone())
                .map_err(|e| MonitorError::Record(format!("MCAP metadata: {e}")))?;
            Some(handle)
        }
        None => None,
    };
    let record_channels = Channels::new(&record_ctx, &cfg.topic_namespace)?;
    // The viewers: a context, a server and a thread of their own.
    let viewer_ctx = Context::new();
    let admission = Admission::new(cfg.max_viewers);
    let server = match cfg.foxglove {
        Some(a) => {
            viewers::raise_open_file_limit();
            let info: HashMap<String, String> = meta.clone().into_iter().collect();
            let started = viewer_ctx
                .websocket_server()
                .name(format!("cablevib monitor {}", cfg.instance))
                .bind(a.addr.ip().to_string(), a.addr.port())
                .server_info(info)
                .message_backlog_size(viewers::VIEWER_BACKLOG)
                .listener(admission.clone())
                .start_blocking();
            match started {
                Ok(s) => Some(s),
                Err(foxglove::FoxgloveError::Bind(e))
                    if e.kind() == std::io::ErrorKind::AddrInUse =>
                {
                    return Err(MonitorError::PortInUse {
                        addr: a.addr.to_string(),
                    });
                }
                Err(e) => {
                    return Err(MonitorError::Foxglove(format!(
                        "WebSocket server on {}: {e}",
                        a.addr
                    )))
                }
            }
        }
        None => None,
    };
    let (live_tx, viewer_thread) = match &server {
        Some(_) => {
            let ch = Channels::new(&viewer_ctx, &cfg.topic_namespace)?;
            let (tx, rx) = sync_channel(viewers::VIEWER_QUEUE);
            let (ctx, admission) = (viewer_ctx.clone(), admission.clone());
            let t = std::thread::Builder::new()
                .name("cablevib-monitor-viewers".into())
                .spawn(move || viewers::viewer_loop(rx, ch, ctx, admission))
                .map_err(|e| {
                    MonitorError::Foxglove(format!("cannot start the viewers' thread: {e}"))
                })?;
            (Some(tx), Some(t))
        }
        None => (None, None),
    };
    attached(&Attached {
        url: server.as_ref().map(|s| {
            format!(
                "ws://{}:{}",
                cfg.foxglove
                    .map_or(String::new(), |a| a.addr.ip().to_string()),
                s.port()
            )
        }),
        port: server.as_ref().map(|s| s.port()),
        attributes,
        scene: scene_source,
    });

    let (tx, rx) = sync_channel::<Record>(QUEUE_CAPACITY);
    let writer = {
        let required = cfg.required_hz.unwrap_or(f64::NAN);
        let period_ns = (1e9 / cfg.scene_rate_hz) as u64;
        let sinks = Sinks {
            record: record_channels,
            live: live_tx,
        };
        std::thread::Builder::new()
            .name("cablevib-monitor-writer".into())
            .spawn(move || writer::write_loop(rx, sinks, scene, required, period_ns, offset_ns))
            .map_err(|e| MonitorError::Foxglove(format!("cannot start the writer thread: {e}")))?
    };

    let mut counts = Counters::new();
    let start = Instant::now();
    let margin_period = Duration::from_secs_f64(1.0 / cfg.scene_rate_hz);
    let mut next_margin = Instant::now();
    let mut pending: Option<(PendingMargin, Instant)> = None;
    let mut request_sequence = 0u64;
    let mut margins_dropped = 0u64;
    let loop_result: Result<(), MonitorError> = (|| {
        while !stop.load(Ordering::Acquire) && cfg.duration.is_none_or(|d| start.elapsed() < d) {
            // Set-points and poses first: an estimate comes after the pose it answers.
            let mut got = drain(&tx, &mut counts.t_min, || {
                let s = t_mins.receive().ok().flatten()?;
                Some((Record::Tmin(*s), s.header().publisher_id(), s.sequence))
            });
            got += drain(&tx, &mut counts.pose, || {
                let s = poses.receive().ok().flatten()?;
                Some((Record::Pose(*s), s.header().publisher_id(), s.sequence))
            });
            let mut failed = None;
            let estimated = drain(&tx, &mut counts.estimate, || {
                match estimates.try_receive_from() {
                    Ok(Some((e, from))) => Some((Record::Estimate(e), from, e.sequence)),
                    Ok(None) => None,
                    Err(e) => {
                        failed = Some(e);
                        None
                    }
                }
            });
            if let Some(e) = failed {
                return Err(e.into());
            }
            got += estimated;
            let estimated = estimated > 0;
            if let (Some(client), Some(required)) = (&margin, cfg.required_hz) {
                if let Some((p, sent)) = &pending {
                    match p.receive() {
                        Ok(Some(r)) => {
                            if tx.try_send(Record::Margin(*r, required)).is_err() {
                                margins_dropped += 1;
                            }
                            pending = None;
                        }
                        _ if sent.elapsed() > MARGIN_TIMEOUT => pending = None,
                        _ => {}
                    }
                }
                if pending.is_none() && Instant::now() >= next_margin && estimated {
                    request_sequence += 1;
                    let request =
                        MarginRequest::new(request_sequence, monotonic_now_ns(), required);
                    pending = Some((client.send(&request)?, Instant::now()));
                    next_margin = Instant::now() + margin_period;
                }
            }
            if got == 0 {
                estimates.wait_event(WAKE_WAIT);
            }
        }
        Ok(())
    })();
    drop(tx);
    let written = writer
        .join()
        .map_err(|_| MonitorError::Foxglove("the writer thread panicked".into()))?;
    let mut viewers = match viewer_thread {
        Some(t) => t
            .join()
            .map_err(|_| MonitorError::Foxglove("the viewers' thread panicked".into()))?,
        None => ViewerReport::default(),
    };
    viewers.dropped = written.viewer_dropped;
    let report = MonitorReport {
        estimate: counts.estimate.completeness(written.estimates),
        pose: counts.pose.completeness(written.poses),
        t_min: counts.t_min.completeness(written.t_mins),
        margins: written.margins,
        scene_updates: written.scene_updates,
        margins_dropped,
        viewers,
    };
    if let Some(h) = mcap {
        h.write_metadata(COMPLETENESS_METADATA, report.metadata())
            .map_err(|e| MonitorError::Record(format!("MCAP metadata: {e}")))?;
        let end = end_metadata(cfg, &loop_result);
        h.write_metadata("cablevib.end", end)
            .map_err(|e| MonitorError::Record(format!("MCAP metadata: {e}")))?;
        h.close()
            .map_err(|e| MonitorError::Record(format!("closing the MCAP file: {e}")))?
            .commit()
            .map_err(|e| MonitorError::Record(format!("the recording: {e}")))?;
    }
    if let Some(s) = server {
        // Not a graceful wait: a viewer that does not read would hold it forever (its close
        // frame never leaves). Dropping the handle ends every viewer's connection at once.
        drop(s.stop());
    }
    loop_result?;
    Ok(report)
}

/// The metadata record `cablevib.end`: why the recording stopped (`stopped_by`: `signal`
/// for SIGINT/SIGTERM, `duration`, `stop` when the caller stopped it, `error` with `error`)
/// and whether that cut the run short (`interrupted`).
fn end_metadata(
    cfg: &MonitorConfig,
    loop_result: &Result<(), MonitorError>,
) -> BTreeMap<String, String> {
    let mut m = BTreeMap::new();
    let by = match loop_result {
        Err(e) => {
            m.insert("error".into(), e.to_string());
            "error"
        }
        Ok(()) if crate::signal::received() => "signal",
        Ok(()) if cfg.duration.is_some() => "duration",
        Ok(()) => "stop",
    };
    m.insert("stopped_by".into(), by.into());
    m.insert(
        "interrupted".into(),
        (by == "signal" || by == "error").to_string(),
    );
    m
}

/// Name of the MCAP metadata record written when the recording closes: per channel
/// (`estimate`, `pose`, `t_min`) `received`, `lost_sequence_gap`, `sequence_resets`,
/// `dropped_queue`, `recorded`, `first_sequence`, `last_sequence`, `complete`; and `complete`
/// for the record. A file without it was not closed (a killed monitor).
pub const COMPLETENESS_METADATA: &str = "cablevib.completeness";

/// The sequence counters of the subscribed channels.
struct Counters {
    estimate: SequenceCounter,
    pose: SequenceCounter,
    t_min: SequenceCounter,
}

impl Counters {
    fn new() -> Counters {
        Counters {
            estimate: SequenceCounter::new(RECORD_BUFFER),
            pose: SequenceCounter::new(RECORD_BUFFER),
            t_min: SequenceCounter::new(RECORD_BUFFER),
        }
    }
}

/// Moves up to [`DRAIN_LIMIT`] messages from `next` (the message, its sender, its sequence) to
/// the writer, counting them on `c`; returns how many.
fn drain(
    tx: &SyncSender<Record>,
    c: &mut SequenceCounter,
    mut next: impl FnMut() -> Option<(Record, UniquePublisherId, u64)>,
) -> usize {
    let mut n = 0;
    while n < DRAIN_LIMIT {
        let Some((r, from, sequence)) = next() else {
            break;
        };
        c.received(from, sequence, monotonic_now_ns());
        push(tx, r, c);
        n += 1;
    }
    n
}

/// Queues `r` for the writer without waiting; a full queue drops it, counted on `c`.
fn push(tx: &SyncSender<Record>, r: Record, c: &mut SequenceCounter) {
    match tx.try_send(r) {
        Ok(()) => {}
        Err(TrySendError::Full(_)) | Err(TrySendError::Disconnected(_)) => c.dropped(),
    }
}
