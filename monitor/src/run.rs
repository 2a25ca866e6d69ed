//! The monitor process: iceoryx2 subscribers in the calling thread, a bounded queue, and a
//! writer thread that encodes and logs to the Foxglove sinks (MCAP file, WebSocket server).

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender, TrySendError};
use std::sync::Arc;
use std::time::{Duration, Instant};

use cablevib::output_file::OutputFile;
use cablevib::scene::Scene;
use cablevib_ipc::{
    monotonic_now_ns, EstimateSample, MarginRequest, MarginResponse, PoseSample, ServiceNames,
    TminSetpoint,
};
use cablevib_service::ports::{
    create_node, open_pubsub, EstimateOutput, MarginClient, PendingMargin, ReadAttributes,
    POSE_SETTINGS, T_MIN_SETTINGS,
};
use cablevib_service::WaitMode;
use foxglove::{
    Channel, ChannelBuilder, Context, McapCompression, McapWriteOptions, PartialMetadata,
    RawChannel, Schema,
};

use crate::addr::FoxgloveAddr;
use crate::encode::{self, EstimateRecord, MarginRecord, PoseRecord, TminRecord};
use crate::scene3d;
use crate::MonitorError;

/// Capacity of the queue between the iceoryx2 thread and the writer, messages (≈ 8 s of
/// estimates and poses at 1 kHz; ≈ 4.5 MB). When it is full the newest message is dropped and
/// counted: the monitor never blocks its subscribers, which would only lose older samples in
/// their iceoryx2 queues instead.
pub const QUEUE_CAPACITY: usize = 16_384;
/// MCAP chunk size, bytes (before compression): at 1 kHz a chunk closes every ≈ 0.3 s, which
/// bounds what a killed monitor loses.
pub const CHUNK_BYTES: u64 = 256 * 1024;
/// How long the iceoryx2 loop blocks on the wake-controller event before it looks again.
const WAKE_WAIT: Duration = Duration::from_millis(20);
/// Poses remembered to draw the one an estimate answers.
const POSE_MEMORY: usize = 256;
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
        }
    }
}

/// Topic of channel `name` of `instance`: `/cablevib/{instance}/{name}` (`/cablevib/{name}`
/// for the bare instance).
pub fn topic(instance: &str, name: &str) -> String {
    let instance = instance.trim_matches('/');
    if instance.is_empty() {
        format!("/cablevib/{name}")
    } else {
        format!("/cablevib/{instance}/{name}")
    }
}

/// Counts of one monitor run.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MonitorReport {
    /// Estimates logged.
    pub estimates: u64,
    /// Poses logged.
    pub poses: u64,
    /// T_min set-points logged.
    pub t_mins: u64,
    /// Margin answers logged.
    pub margins: u64,
    /// Scene updates logged.
    pub scene_updates: u64,
    /// Messages dropped because the queue was full.
    pub dropped: u64,
}

impl core::fmt::Display for MonitorReport {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} estimates, {} poses, {} T_min set-points, {} margin answers, {} scene updates, \
             {} dropped",
            self.estimates, self.poses, self.t_mins, self.margins, self.scene_updates, self.dropped
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
}

/// One message in the queue. Unboxed on purpose: the queue's slots are sized once, and a box
/// per estimate would allocate 1000 times a second.
#[allow(clippy::large_enum_variant)]
enum Record {
    Pose(PoseSample),
    Tmin(TminSetpoint),
    Estimate(EstimateSample),
    Margin(MarginResponse, f64),
}

/// `CLOCK_REALTIME − CLOCK_MONOTONIC` now, ns: maps the messages' monotonic timestamps to the
/// Unix-epoch log times MCAP and Foxglove expect.
fn realtime_offset_ns() -> i128 {
    let real = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as i128);
    real - monotonic_now_ns() as i128
}

fn json_channel(
    ctx: &Arc<Context>,
    topic: &str,
    schema_name: &str,
    schema: String,
) -> Result<Arc<RawChannel>, MonitorError> {
    ChannelBuilder::new(topic)
        .context(ctx)
        .message_encoding(encode::JSON_MESSAGE_ENCODING)
        .schema(Schema::new(
            schema_name,
            encode::JSON_SCHEMA_ENCODING,
            schema.into_bytes(),
        ))
        .build_raw()
        .map_err(|e| MonitorError::Foxglove(format!("channel {topic}: {e}")))
}

/// The metadata of a run: scene, model, elements, the service's attributes, the version.
fn metadata(
    cfg: &MonitorConfig,
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
    if let Some(s) = &cfg.scene {
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
    // Subscribers before the service publishes: nothing it sends after this is missed.
    let estimates = EstimateOutput::open(&node, &names)?;
    let poses = open_pubsub::<PoseSample>(&node, &names.pose, POSE_SETTINGS)?
        .subscriber_builder()
        .create()
        .map_err(|e| MonitorError::Foxglove(format!("pose subscriber: {e:?}")))?;
    let t_mins = open_pubsub::<TminSetpoint>(&node, &names.t_min, T_MIN_SETTINGS)?
        .subscriber_builder()
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
    let offset_ns = realtime_offset_ns();
    let meta = metadata(cfg, &attributes, offset_ns);

    // The Foxglove sinks and channels.
    let ctx = Context::new();
    let mcap = match file {
        Some(f) => {
            let options = McapWriteOptions::new()
                .compression(Some(McapCompression::Lz4))
                .chunk_size(Some(CHUNK_BYTES));
            let handle = ctx
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
    let server = match cfg.foxglove {
        Some(a) => {
            let info: HashMap<String, String> = meta.clone().into_iter().collect();
            let started = ctx
                .websocket_server()
                .name(format!("cablevib monitor {}", cfg.instance))
                .bind(a.addr.ip().to_string(), a.addr.port())
                .server_info(info)
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
    let channels = Channels {
        estimate: json_channel(
            &ctx,
            &topic(&cfg.topic_namespace, "estimate"),
            encode::SCHEMA_ESTIMATE,
            encode::estimate_schema(),
        )?,
        pose: json_channel(
            &ctx,
            &topic(&cfg.topic_namespace, "pose"),
            encode::SCHEMA_POSE,
            encode::pose_schema(),
        )?,
        t_min: json_channel(
            &ctx,
            &topic(&cfg.topic_namespace, "t_min"),
            encode::SCHEMA_T_MIN,
            encode::t_min_schema(),
        )?,
        margin: json_channel(
            &ctx,
            &topic(&cfg.topic_namespace, "margin"),
            encode::SCHEMA_MARGIN,
            encode::margin_schema(),
        )?,
        scene: ChannelBuilder::new(topic(&cfg.topic_namespace, "scene"))
            .context(&ctx)
            .build::<foxglove::messages::SceneUpdate>(),
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
    });

    let (tx, rx) = sync_channel::<Record>(QUEUE_CAPACITY);
    let writer = {
        let scene = cfg.scene.clone();
        let required = cfg.required_hz.unwrap_or(f64::NAN);
        let period_ns = (1e9 / cfg.scene_rate_hz) as u64;
        std::thread::Builder::new()
            .name("cablevib-monitor-writer".into())
            .spawn(move || write_loop(rx, channels, scene, required, period_ns, offset_ns))
            .map_err(|e| MonitorError::Foxglove(format!("cannot start the writer thread: {e}")))?
    };

    let mut dropped = 0u64;
    let mut push = |tx: &SyncSender<Record>, r: Record| match tx.try_send(r) {
        Ok(()) => {}
        Err(TrySendError::Full(_)) | Err(TrySendError::Disconnected(_)) => dropped += 1,
    };
    let start = Instant::now();
    let margin_period = Duration::from_secs_f64(1.0 / cfg.scene_rate_hz);
    let mut next_margin = Instant::now();
    let mut pending: Option<(PendingMargin, Instant)> = None;
    let mut request_sequence = 0u64;
    let loop_result: Result<(), MonitorError> = (|| {
        while !stop.load(Ordering::Acquire) && cfg.duration.is_none_or(|d| start.elapsed() < d) {
            let first = estimates.wait(WaitMode::Event, WAKE_WAIT)?;
            // Poses and set-points first: an estimate comes after the pose it answers.
            while let Ok(Some(s)) = t_mins.receive() {
                push(&tx, Record::Tmin(*s));
            }
            while let Ok(Some(s)) = poses.receive() {
                push(&tx, Record::Pose(*s));
            }
            if let Some(e) = first {
                push(&tx, Record::Estimate(e));
                while let Some(e) = estimates.try_receive()? {
                    push(&tx, Record::Estimate(e));
                }
            }
            if let (Some(client), Some(required)) = (&margin, cfg.required_hz) {
                if let Some((p, sent)) = &pending {
                    match p.receive() {
                        Ok(Some(r)) => {
                            push(&tx, Record::Margin(*r, required));
                            pending = None;
                        }
                        _ if sent.elapsed() > MARGIN_TIMEOUT => pending = None,
                        _ => {}
                    }
                }
                if pending.is_none() && Instant::now() >= next_margin && first.is_some() {
                    request_sequence += 1;
                    let request =
                        MarginRequest::new(request_sequence, monotonic_now_ns(), required);
                    pending = Some((client.send(&request)?, Instant::now()));
                    next_margin = Instant::now() + margin_period;
                }
            }
        }
        Ok(())
    })();
    drop(tx);
    let mut report = writer
        .join()
        .map_err(|_| MonitorError::Foxglove("the writer thread panicked".into()))?;
    report.dropped = dropped;
    if let Some(h) = mcap {
        let end = end_metadata(cfg, &loop_result);
        h.write_metadata("cablevib.end", end)
            .map_err(|e| MonitorError::Record(format!("MCAP metadata: {e}")))?;
        h.close()
            .map_err(|e| MonitorError::Record(format!("closing the MCAP file: {e}")))?
            .commit()
            .map_err(|e| MonitorError::Record(format!("the recording: {e}")))?;
    }
    if let Some(s) = server {
        s.stop().wait_blocking();
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

struct Channels {
    estimate: Arc<RawChannel>,
    pose: Arc<RawChannel>,
    t_min: Arc<RawChannel>,
    margin: Arc<RawChannel>,
    scene: Channel<foxglove::messages::SceneUpdate>,
}

fn log_json<T: serde::Serialize>(
    ch: &RawChannel,
    value: &T,
    monotonic_ns: u64,
    offset_ns: i128,
    buf: &mut Vec<u8>,
) {
    buf.clear();
    if serde_json::to_writer(&mut *buf, value).is_ok() {
        ch.log_with_meta(
            buf,
            PartialMetadata {
                log_time: Some(log_time(monotonic_ns, offset_ns)),
            },
        );
    }
}

fn log_time(monotonic_ns: u64, offset_ns: i128) -> u64 {
    (monotonic_ns as i128 + offset_ns).clamp(0, u64::MAX as i128) as u64
}

/// The writer thread: encodes every record, logs it with its own timestamp (estimates: their
/// publish time; poses and set-points: their sender's time; margin answers: the service's
/// answer time), and a scene update per `period_ns` of estimate time.
fn write_loop(
    rx: Receiver<Record>,
    ch: Channels,
    scene: Option<Scene>,
    required_hz: f64,
    period_ns: u64,
    offset_ns: i128,
) -> MonitorReport {
    let mut report = MonitorReport::default();
    let mut buf = Vec::with_capacity(4096);
    let mut recent: VecDeque<PoseSample> = VecDeque::with_capacity(POSE_MEMORY);
    let mut t_min: Option<TminSetpoint> = None;
    let mut next_scene_ns = 0u64;
    for r in rx {
        match r {
            Record::Pose(p) => {
                log_json(
                    &ch.pose,
                    &PoseRecord::new(&p),
                    p.timestamp_ns,
                    offset_ns,
                    &mut buf,
                );
                if recent.len() == POSE_MEMORY {
                    recent.pop_front();
                }
                recent.push_back(p);
                report.poses += 1;
            }
            Record::Tmin(t) => {
                log_json(
                    &ch.t_min,
                    &TminRecord::new(&t),
                    t.timestamp_ns,
                    offset_ns,
                    &mut buf,
                );
                t_min = Some(t);
                report.t_mins += 1;
            }
            Record::Margin(m, required) => {
                log_json(
                    &ch.margin,
                    &MarginRecord::new(&m, required),
                    m.timestamp_ns,
                    offset_ns,
                    &mut buf,
                );
                report.margins += 1;
            }
            Record::Estimate(e) => {
                let t = e.publish_timestamp_ns;
                log_json(
                    &ch.estimate,
                    &EstimateRecord::new(&e, required_hz),
                    t,
                    offset_ns,
                    &mut buf,
                );
                report.estimates += 1;
                if let Some(scene) = &scene {
                    if t >= next_scene_ns {
                        // The pose the estimate answers (the newest if it is not remembered).
                        let pose = recent
                            .iter()
                            .rev()
                            .find(|p| {
                                p.sequence == e.pose_sequence
                                    && p.timestamp_ns == e.pose_timestamp_ns
                            })
                            .or(recent.back());
                        if let Some(pose) = pose {
                            let lt = log_time(t, offset_ns);
                            let u = scene3d::scene_update(
                                scene,
                                pose,
                                &e,
                                t_min.as_ref(),
                                e.f1_hz - required_hz,
                                scene3d::stamp(lt),
                            );
                            ch.scene.log_with_time(&u, lt);
                            report.scene_updates += 1;
                            next_scene_ns = t.saturating_add(period_ns);
                        }
                    }
                }
            }
        }
    }
    report
}
