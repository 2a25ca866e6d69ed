//! `cablevib monitor` and `cablevib replay`: see a running service live in Foxglove, keep its
//! record as MCAP, and replay a record into a service.
//!
//! The monitor is one more iceoryx2 participant of an instance, in its own process: a
//! subscriber of the pose, T_min and estimate services (and, with a required f1, a margin
//! client asking a few times a second), so the service's real-time loop is the same with or
//! without it. Its subscribers queue [`RECORD_BUFFER`] samples each; every message carries its
//! sender's sequence number, so every message lost before the monitor read it is counted
//! ([`completeness`]). Its iceoryx2 thread only copies samples into a bounded queue
//! ([`QUEUE_CAPACITY`]; when full the newest sample is dropped and counted); a writer thread
//! encodes them ([`encode`]: JSON with a JSON Schema per channel; [`scene3d`]: Foxglove's
//! `SceneUpdate`) and logs them through the official Foxglove SDK to the record, an MCAP file
//! (`--record`, LZ4 chunks of [`CHUNK_BYTES`], metadata records `cablevib` and, when closed,
//! [`COMPLETENESS_METADATA`]). The Foxglove WebSocket viewers (`--foxglove`, loopback by
//! default, [`addr`]) have a context, a thread and a queue of their own ([`viewers`]: a cap
//! on viewers, a bound per viewer), so no viewer can slow or shorten the record.
//!
//! | topic | schema | rate |
//! |---|---|---|
//! | `/cablevib/{instance}/estimate` | `cablevib.Estimate` (JSON) | every estimate |
//! | `/cablevib/{instance}/pose` | `cablevib.Pose` (JSON) | every pose |
//! | `/cablevib/{instance}/t_min` | `cablevib.TminSetpoint` (JSON) | every set-point |
//! | `/cablevib/{instance}/margin` | `cablevib.MarginResponse` (JSON) | the monitor's own queries, scene rate |
//! | `/cablevib/{instance}/scene` | `foxglove.SceneUpdate` (protobuf) | `--scene-rate-hz` (30) |
//!
//! Log times are the messages' own `CLOCK_MONOTONIC` timestamps (estimate: publish time;
//! pose, set-point: sender's time; margin: answer time) moved to the Unix epoch by one offset
//! taken at start (metadata `log_time_minus_monotonic_ns`); the payloads keep the raw values.
//!
//! [`replay`](mod@replay) streams the poses and set-points of a recording ([`recording`]:
//! chunk by chunk, bounded memory) and sends them to a service, at the recorded timing (pauses
//! bounded) or as fast as the service answers.

#![warn(missing_docs)]

pub mod addr;
pub mod completeness;
pub mod encode;
pub mod recording;
pub mod replay;
pub mod run;
pub mod scene3d;
pub mod signal;
pub mod viewers;
mod writer;

pub use addr::{FoxgloveAddr, DEFAULT_FOXGLOVE};
pub use completeness::ChannelCompleteness;
pub use replay::{Pace, ReplayConfig, ReplayReport, DEFAULT_MAX_GAP_S};
pub use run::{
    run, topic, Attached, MonitorConfig, MonitorReport, SceneSource, CHUNK_BYTES,
    COMPLETENESS_METADATA, QUEUE_CAPACITY, RECORD_BUFFER,
};
pub use viewers::{ViewerReport, DEFAULT_MAX_VIEWERS, LOG_FILTER};

use cablevib_service::ServiceError;

/// Errors of the monitor and the replay.
#[derive(Debug, thiserror::Error)]
pub enum MonitorError {
    /// A bad option.
    #[error("{0}")]
    Usage(String),
    /// iceoryx2 or the service ports failed.
    #[error(transparent)]
    Service(#[from] ServiceError),
    /// No cablevib service published on the instance in time.
    #[error(
        "no cablevib service publishes on instance {instance:?} after {seconds} s: start \
         `cablevib serve --instance {instance}` (or check the instance name)"
    )]
    NoService {
        /// The instance.
        instance: String,
        /// How long the monitor waited, s.
        seconds: f64,
    },
    /// The WebSocket port is taken (another monitor, or another program).
    #[error(
        "cannot serve Foxglove on {addr}: the address is in use (another cablevib monitor?); \
         stop it, or pass --foxglove with another port"
    )]
    PortInUse {
        /// The address.
        addr: String,
    },
    /// The Foxglove SDK failed.
    #[error("foxglove: {0}")]
    Foxglove(String),
    /// The recording could not be written.
    #[error("{0}")]
    Record(String),
    /// A recording to replay could not be read.
    #[error("{0}")]
    Recording(String),
}
