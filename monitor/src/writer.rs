//! The monitor's writer thread: encodes each message once, logs it to the record's channels
//! (the MCAP sink's context) and hands a copy to the viewers' thread without waiting
//! ([`crate::viewers`]).

use std::collections::VecDeque;
use std::sync::mpsc::{Receiver, SyncSender, TrySendError};
use std::sync::Arc;

use cablevib::scene::Scene;
use cablevib_ipc::{EstimateSample, MarginResponse, PoseSample, TminSetpoint};
use foxglove::messages::SceneUpdate;
use foxglove::{Channel, ChannelBuilder, Context, PartialMetadata, RawChannel, Schema};

use crate::encode::{self, EstimateRecord, MarginRecord, PoseRecord, TminRecord};
use crate::scene3d;
use crate::MonitorError;

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

/// Poses remembered to draw the one an estimate answers.
const POSE_MEMORY: usize = 256;

/// One message in the queue from the iceoryx2 thread. Unboxed on purpose: the queue's slots
/// are sized once, and a box per estimate would allocate 1000 times a second.
#[allow(clippy::large_enum_variant)]
pub(crate) enum Record {
    Pose(PoseSample),
    Tmin(TminSetpoint),
    Estimate(EstimateSample),
    Margin(MarginResponse, f64),
}

/// The JSON channels.
#[derive(Debug, Clone, Copy)]
pub(crate) enum JsonTopic {
    Estimate,
    Pose,
    Tmin,
    Margin,
}

/// One encoded message for the viewers.
pub(crate) enum Live {
    Json(JsonTopic, Vec<u8>, u64),
    Scene(Box<SceneUpdate>, u64),
}

/// The channels of one Foxglove context (the record's or the viewers').
pub(crate) struct Channels {
    estimate: Arc<RawChannel>,
    pose: Arc<RawChannel>,
    t_min: Arc<RawChannel>,
    margin: Arc<RawChannel>,
    scene: Channel<SceneUpdate>,
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

impl Channels {
    /// The channels of `namespace` in `ctx`.
    pub(crate) fn new(ctx: &Arc<Context>, namespace: &str) -> Result<Channels, MonitorError> {
        Ok(Channels {
            estimate: json_channel(
                ctx,
                &topic(namespace, "estimate"),
                encode::SCHEMA_ESTIMATE,
                encode::estimate_schema(),
            )?,
            pose: json_channel(
                ctx,
                &topic(namespace, "pose"),
                encode::SCHEMA_POSE,
                encode::pose_schema(),
            )?,
            t_min: json_channel(
                ctx,
                &topic(namespace, "t_min"),
                encode::SCHEMA_T_MIN,
                encode::t_min_schema(),
            )?,
            margin: json_channel(
                ctx,
                &topic(namespace, "margin"),
                encode::SCHEMA_MARGIN,
                encode::margin_schema(),
            )?,
            scene: ChannelBuilder::new(topic(namespace, "scene"))
                .context(ctx)
                .build::<SceneUpdate>(),
        })
    }

    fn json(&self, t: JsonTopic) -> &RawChannel {
        match t {
            JsonTopic::Estimate => &self.estimate,
            JsonTopic::Pose => &self.pose,
            JsonTopic::Tmin => &self.t_min,
            JsonTopic::Margin => &self.margin,
        }
    }

    /// Logs a message handed to the viewers.
    pub(crate) fn log_live(&self, live: Live) {
        match live {
            Live::Json(t, bytes, log_time) => self.json(t).log_with_meta(
                &bytes,
                PartialMetadata {
                    log_time: Some(log_time),
                },
            ),
            Live::Scene(u, log_time) => self.scene.log_with_time(&u, log_time),
        }
    }
}

/// The Unix-epoch log time of monotonic time `monotonic_ns`.
pub(crate) fn log_time(monotonic_ns: u64, offset_ns: i128) -> u64 {
    (monotonic_ns as i128 + offset_ns).clamp(0, u64::MAX as i128) as u64
}

/// What the writer logged, per channel, and what the viewers missed.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Written {
    pub estimates: u64,
    pub poses: u64,
    pub t_mins: u64,
    pub margins: u64,
    pub scene_updates: u64,
    /// Messages dropped for the viewers (their queue was full).
    pub viewer_dropped: u64,
}

/// The writer's outputs: the record's channels and, when serving, the viewers' queue.
pub(crate) struct Sinks {
    pub record: Channels,
    pub live: Option<SyncSender<Live>>,
}

impl Sinks {
    fn json<T: serde::Serialize>(
        &self,
        t: JsonTopic,
        value: &T,
        log_time: u64,
        buf: &mut Vec<u8>,
        viewer_dropped: &mut u64,
    ) {
        buf.clear();
        if serde_json::to_writer(&mut *buf, value).is_err() {
            return;
        }
        self.record.json(t).log_with_meta(
            buf,
            PartialMetadata {
                log_time: Some(log_time),
            },
        );
        if let Some(tx) = &self.live {
            offer(tx, Live::Json(t, buf.clone(), log_time), viewer_dropped);
        }
    }
}

/// Hands `live` to the viewers without waiting; counts it when their queue is full.
fn offer(tx: &SyncSender<Live>, live: Live, dropped: &mut u64) {
    match tx.try_send(live) {
        Ok(()) | Err(TrySendError::Disconnected(_)) => {}
        Err(TrySendError::Full(_)) => *dropped += 1,
    }
}

/// The writer thread: encodes every record, logs it with its own timestamp (estimates: their
/// publish time; poses and set-points: their sender's time; margin answers: the service's
/// answer time), and a scene update per `period_ns` of estimate time.
pub(crate) fn write_loop(
    rx: Receiver<Record>,
    out: Sinks,
    scene: Option<Scene>,
    required_hz: f64,
    period_ns: u64,
    offset_ns: i128,
) -> Written {
    let mut w = Written::default();
    let mut buf = Vec::with_capacity(4096);
    let mut recent: VecDeque<PoseSample> = VecDeque::with_capacity(POSE_MEMORY);
    let mut t_min: Option<TminSetpoint> = None;
    let mut next_scene_ns = 0u64;
    let mut dropped = 0u64;
    for r in rx {
        match r {
            Record::Pose(p) => {
                let lt = log_time(p.timestamp_ns, offset_ns);
                out.json(
                    JsonTopic::Pose,
                    &PoseRecord::new(&p),
                    lt,
                    &mut buf,
                    &mut dropped,
                );
                if recent.len() == POSE_MEMORY {
                    recent.pop_front();
                }
                recent.push_back(p);
                w.poses += 1;
            }
            Record::Tmin(t) => {
                let lt = log_time(t.timestamp_ns, offset_ns);
                out.json(
                    JsonTopic::Tmin,
                    &TminRecord::new(&t),
                    lt,
                    &mut buf,
                    &mut dropped,
                );
                t_min = Some(t);
                w.t_mins += 1;
            }
            Record::Margin(m, required) => {
                let lt = log_time(m.timestamp_ns, offset_ns);
                let rec = MarginRecord::new(&m, required);
                out.json(JsonTopic::Margin, &rec, lt, &mut buf, &mut dropped);
                w.margins += 1;
            }
            Record::Estimate(e) => {
                let t = e.publish_timestamp_ns;
                let lt = log_time(t, offset_ns);
                let rec = EstimateRecord::new(&e, required_hz);
                out.json(JsonTopic::Estimate, &rec, lt, &mut buf, &mut dropped);
                w.estimates += 1;
                let Some(scene) = &scene else { continue };
                if t < next_scene_ns {
                    continue;
                }
                // The pose the estimate answers (the newest if it is not remembered).
                let pose = recent
                    .iter()
                    .rev()
                    .find(|p| {
                        p.sequence == e.pose_sequence && p.timestamp_ns == e.pose_timestamp_ns
                    })
                    .or(recent.back());
                if let Some(pose) = pose {
                    let u = scene3d::scene_update(
                        scene,
                        pose,
                        &e,
                        t_min.as_ref(),
                        e.f1_hz - required_hz,
                        scene3d::stamp(lt),
                    );
                    out.record.scene.log_with_time(&u, lt);
                    if let Some(tx) = &out.live {
                        offer(tx, Live::Scene(Box::new(u), lt), &mut dropped);
                    }
                    w.scene_updates += 1;
                    next_scene_ns = t.saturating_add(period_ns);
                }
            }
        }
    }
    w.viewer_dropped = dropped;
    w
}
