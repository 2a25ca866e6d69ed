//! The iceoryx2 ports of every participant, opened with one set of service settings.
//!
//! Whoever comes first creates a service, with the settings below; everybody else opens it
//! and checks its static configuration against the same settings: a service that another
//! program created with other limits (a second estimate publisher allowed, a pose buffer of 1
//! without safe overflow, ...) is refused with [`ServiceError::ServiceSettings`], which names
//! the service, the setting, its value and the expected value. A peer whose payload type
//! differs (another schema version or layout) is refused by iceoryx2 at open time; the error
//! is turned into [`ServiceError::IncompatiblePeer`] with the explanation of
//! [`cablevib_ipc::compat`] (what the service carries, what we expect). `docs/security.md`
//! says what this protects against and what it does not.
//!
//! | service | pattern | created with |
//! |---|---|---|
//! | pose | publish-subscribe | up to [`RECORD_BUFFER`] queued poses per subscriber (the service's own: [`POSE_BUFFER`]), history 0, [`MAX_PUBLISHERS`] publishers |
//! | T_min | publish-subscribe | up to [`RECORD_BUFFER`] queued (the service's own: [`T_MIN_BUFFER`]), history 1: a (re)started service gets the set-point in force |
//! | vibration | publish-subscribe | up to [`RECORD_BUFFER`] queued samples per subscriber (the service's own: [`VIBRATION_BUFFER`]), history 0, [`MAX_PUBLISHERS`] publishers |
//! | estimate | publish-subscribe | up to [`RECORD_BUFFER`] queued estimates per subscriber (a controller's: [`ESTIMATE_BUFFER`]), [`ESTIMATE_PUBLISHERS`] publisher |
//! | margin | request-response | [`MARGIN_SERVERS`] server, [`MAX_CLIENTS`] clients, [`MARGIN_ACTIVE_REQUESTS`] active requests per client |
//! | wake/service, wake/controller | event | [`EVENT_PORTS`] listeners and notifiers |
//!
//! Whoever creates a service defines cablevib's iceoryx2 service attributes on it (schema
//! version, units, cablevib version; `cablevib serve` adds the scene's name and cable model:
//! [`ServiceAttributes`], keys in `cablevib_ipc::attributes`). A service whose schema-version
//! attribute differs from this build's is refused with [`ServiceError::IncompatiblePeer`];
//! peers read the attributes with [`EstimateOutput::attributes`] and friends.
//!
//! Every publish-subscribe and request-response service overflows safely (the newest sample
//! replaces the oldest): the service estimates the newest pose, a controller wants the newest
//! estimate.
//!
//! Every port type here is `!Send` (iceoryx2 ports are bound to the thread that made them):
//! create them in the thread that uses them.

use core::time::Duration;

use cablevib_ipc::{
    explain_publish_subscribe_mismatch, explain_request_response_mismatch, EstimateSample,
    MarginRequest, MarginResponse, Message, PoseSample, ServiceNames, TminSetpoint,
    VibrationSample, EVENT_ID_ESTIMATE, EVENT_ID_MARGIN_REQUEST, EVENT_ID_MARGIN_RESPONSE,
    EVENT_ID_POSE, EVENT_ID_T_MIN, EVENT_ID_VIBRATION,
};
use iceoryx2::config::Config as Iceoryx2Config;
use iceoryx2::node::{NodeState, NodeView};
use iceoryx2::pending_response::PendingResponse;
use iceoryx2::port::client::Client;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::server::Server;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
use iceoryx2::service::builder::event::{EventCreateError, EventOpenError};
use iceoryx2::service::builder::publish_subscribe::{
    PublishSubscribeCreateError, PublishSubscribeOpenError,
};
use iceoryx2::service::builder::request_response::{
    RequestResponseCreateError, RequestResponseOpenError,
};
use iceoryx2::service::port_factory::server::ServerCreateError;
use iceoryx2::service::port_factory::{event, publish_subscribe, request_response};

use super::{ServiceError, WaitMode};

mod attributes;
mod client;
mod node;
mod open;

pub use attributes::{ReadAttributes, ServiceAttributes};
pub use client::{EstimateOutput, MarginClient, PendingMargin, PoseInput};
pub use node::{
    create_node, is_cablevib_node, load_iceoryx2_config, remove_stale_nodes, service_name,
    wait_for_service, SERVICE_UP_TIMEOUT,
};
pub use open::{
    open_event, open_event_with, open_margin, open_margin_with, open_pubsub, open_pubsub_with,
    MarginFactory, PubSubSettings, ESTIMATE_SETTINGS, POSE_SETTINGS, T_MIN_SETTINGS,
    VIBRATION_SETTINGS,
};

/// The iceoryx2 service flavour used everywhere: inter-process, shared memory.
pub type Ipc = ipc::Service;

/// How many poses the service's subscriber queues before the oldest is overwritten. The service
/// drains the queue every cycle and estimates the newest pose only ("latest pose wins").
pub const POSE_BUFFER: usize = 16;
/// How many vibration samples the service queues before the oldest is overwritten (counted
/// from the sequence gaps): 50 ms of a 5 kHz sensor, the longest the service sleeps in
/// an event wait without a wake-up.
pub const VIBRATION_BUFFER: usize = 256;
/// How many T_min set-points the service's subscriber queues (the newest one wins).
pub const T_MIN_BUFFER: usize = 4;
/// How many estimates a controller's subscriber ([`EstimateOutput::open`]) queues before the
/// oldest is overwritten.
pub const ESTIMATE_BUFFER: usize = 16;
/// The most samples one subscriber of the pose, T_min, vibration or estimate service may queue
/// (the services' `subscriber_max_buffer_size`), and what a recorder takes
/// ([`EstimateOutput::open_recorder`], the monitor's pose, T_min and vibration subscribers):
/// 2048, i.e. a recorder may be descheduled ≈ 2 s at 1 kHz (≈ 1 s at 2 kHz) before a sample is
/// overwritten. Each publisher's shared-memory segment is sized for [`MAX_SUBSCRIBERS`] queues
/// of this many samples (≈ 9.8 MB for the estimate publisher, 1.4 MB per pose publisher,
/// 1.2 MB per vibration publisher, of which only the samples in use are touched); the service
/// and the controllers ask for their own short queues ([`POSE_BUFFER`], [`T_MIN_BUFFER`],
/// [`VIBRATION_BUFFER`], [`ESTIMATE_BUFFER`]).
pub const RECORD_BUFFER: usize = 2048;
/// Publishers of the pose and T_min services: one controller or replay at a time; the slack
/// covers killed peers whose ports are not cleaned up yet.
pub const MAX_PUBLISHERS: usize = 4;
/// Publishers of the estimate service: the one `cablevib serve`; a second would be an impostor
/// whose estimates the controller cannot tell from the real ones.
pub const ESTIMATE_PUBLISHERS: usize = 1;
/// Servers of the margin service: the one `cablevib serve`; a second would answer in its name.
pub const MARGIN_SERVERS: usize = 1;
/// Subscribers per publish-subscribe service: the service (pose, T_min) or a controller
/// (estimate), plus `bench-ipc`/monitors beside it, plus slack for killed peers not cleaned up
/// yet.
pub const MAX_SUBSCRIBERS: usize = 8;
/// Margin clients: as many as estimate subscribers (each controller has one of each).
pub const MAX_CLIENTS: usize = MAX_SUBSCRIBERS;
/// Margin requests a client may have in flight (iceoryx2's default; a controller asks one at a
/// time).
pub const MARGIN_ACTIVE_REQUESTS: usize = 4;
/// Responses queued per pending request (iceoryx2's default; the service answers once).
pub const MARGIN_RESPONSE_BUFFER: usize = 2;
/// Nodes per publish-subscribe or request-response service.
pub const MAX_NODES: usize = 16;
/// Nodes per event service: every participant of the instance may notify or listen.
pub const EVENT_NODES: usize = MAX_NODES * 2;
/// Listeners and notifiers per event service (iceoryx2's default): the service and each
/// controller (pose input, estimate output and margin client each have one event port).
pub const EVENT_PORTS: usize = 16;
/// The largest event id a peer sends (the `EVENT_ID_*` of `cablevib-ipc`).
const EVENT_ID_LARGEST: usize = max_event_id([
    EVENT_ID_POSE,
    EVENT_ID_T_MIN,
    EVENT_ID_MARGIN_REQUEST,
    EVENT_ID_ESTIMATE,
    EVENT_ID_MARGIN_RESPONSE,
    EVENT_ID_VIBRATION,
]);

const fn max_event_id(ids: [usize; 6]) -> usize {
    let mut max = 0;
    let mut i = 0;
    while i < ids.len() {
        if ids[i] > max {
            max = ids[i];
        }
        i += 1;
    }
    max
}

/// Every cablevib node name starts with this, so that `cablevib serve` cleans up the dead
/// nodes of cablevib processes and leaves other iceoryx2 applications' alone.
pub const NODE_NAME_PREFIX: &str = "cablevib";

/// How long [`open_pubsub`] and friends retry while another process is creating the same
/// service.
const OPEN_RETRIES: usize = 200;
const OPEN_RETRY_SLEEP: Duration = Duration::from_millis(5);

/// The shortest wait handed to iceoryx2's `Listener::timed_wait`: 1 µs. Its Unix-datagram
/// implementation sets `SO_RCVTIMEO` from the duration's whole microseconds, and a zero
/// timeout there means "no timeout": a wait under 1 µs (the remainder of a timeout, computed
/// just before it ran out) blocked until the next notification, forever on a quiet service.
pub const MIN_LISTENER_WAIT: Duration = Duration::from_micros(1);

/// Waits on `listener` for up to `timeout` (at least [`MIN_LISTENER_WAIT`]), discarding the
/// event ids: returns on a notification, a signal or the timeout. Every timed wait of
/// cablevib goes through here.
pub fn listener_timed_wait(listener: &Listener<Ipc>, timeout: Duration) {
    let _ = listener.timed_wait(|_| {}, timeout.max(MIN_LISTENER_WAIT));
}

fn ipc_error(context: impl Into<String>, reason: impl core::fmt::Debug) -> ServiceError {
    ServiceError::Ipc {
        context: context.into(),
        reason: format!("{reason:?}"),
    }
}

/// How long a starting service waits for a dead predecessor's margin server to be cleaned
/// up before it concludes that a live service holds the instance.
const STALE_SERVER_GRACE: Duration = Duration::from_secs(2);
/// How often it checks meanwhile.
const STALE_SERVER_POLL: Duration = Duration::from_millis(20);

// ---------------------------------------------------------------------------------------------
// The service's side
// ---------------------------------------------------------------------------------------------

/// What `cablevib serve` opens: pose and T_min subscribers, estimate publisher, margin server,
/// a listener on the wake-service event and a notifier on the wake-controller event.
///
/// The pose subscriber is created last, so a peer that sees a subscriber on the pose service
/// ([`PoseInput::service_connected`]) knows every other port of the service exists.
pub struct ServicePorts {
    /// Estimates, to the controller.
    pub estimate: Publisher<Ipc, EstimateSample, ()>,
    /// Margin requests, from the controller.
    pub margin: Server<Ipc, MarginRequest, (), MarginResponse, ()>,
    /// Woken by peers after they send something (used by the event wait).
    pub wake_in: Listener<Ipc>,
    /// Wakes controllers after an estimate or a margin response.
    pub wake_out: Notifier<Ipc>,
    /// T_min set-points, from the controller.
    pub t_min: Subscriber<Ipc, TminSetpoint, ()>,
    /// Vibration samples, from a sensor on the platform (optional).
    pub vibration: Subscriber<Ipc, VibrationSample, ()>,
    /// Poses, from the controller.
    pub pose: Subscriber<Ipc, PoseSample, ()>,
}

impl ServicePorts {
    /// Opens (or creates) every service of instance `names` and the service's ports.
    ///
    /// Fails with [`ServiceError::AlreadyServing`] when another live cablevib service serves
    /// the same instance (two would publish two estimates per pose).
    pub fn open(node: &Node<Ipc>, names: &ServiceNames) -> Result<ServicePorts, ServiceError> {
        ServicePorts::open_with_attributes(node, names, &ServiceAttributes::contract())
    }

    /// [`ServicePorts::open`], creating the services that do not exist yet with `attributes`
    /// (`cablevib serve` passes [`ServiceAttributes::of_scene`]).
    pub fn open_with_attributes(
        node: &Node<Ipc>,
        names: &ServiceNames,
        attributes: &ServiceAttributes,
    ) -> Result<ServicePorts, ServiceError> {
        let margin_factory = open_margin_with(node, &names.margin, attributes)?;
        // The service admits one server. A server port of a process that died counts until its
        // stale resources are removed; another process may be removing them right now, so give
        // that a moment.
        let deadline = std::time::Instant::now() + STALE_SERVER_GRACE;
        let margin = loop {
            match margin_factory.server_builder().create() {
                Ok(server) => break server,
                Err(ServerCreateError::ExceedsMaxSupportedServers) => {
                    if std::time::Instant::now() > deadline {
                        return Err(ServiceError::AlreadyServing {
                            service: names.margin.clone(),
                        });
                    }
                    remove_stale_nodes();
                    std::thread::sleep(STALE_SERVER_POLL);
                }
                Err(e) => return Err(ipc_error("create the margin server", e)),
            }
        };
        // The margin server is ours, so a live estimate publisher is not another cablevib
        // service: it is another program publishing estimates in this instance's name.
        let estimate = open_pubsub_with::<EstimateSample>(
            node,
            &names.estimate,
            ESTIMATE_SETTINGS,
            attributes,
        )?
        .publisher_builder()
        .create()
        .map_err(|e| {
            ipc_error(
                format!(
                    "create the estimate publisher of \"{}\" (another process publishes \
                         estimates there?)",
                    names.estimate
                ),
                e,
            )
        })?;
        let wake_in = open_event_with(node, &names.wake_service, attributes)?
            .listener_builder()
            .create()
            .map_err(|e| ipc_error("create the wake-service listener", e))?;
        let wake_out = open_event_with(node, &names.wake_controller, attributes)?
            .notifier_builder()
            .create()
            .map_err(|e| ipc_error("create the wake-controller notifier", e))?;
        let t_min =
            open_pubsub_with::<TminSetpoint>(node, &names.t_min, T_MIN_SETTINGS, attributes)?
                .subscriber_builder()
                .buffer_size(T_MIN_BUFFER)
                .create()
                .map_err(|e| ipc_error("create the T_min subscriber", e))?;
        let vibration = open_pubsub_with::<VibrationSample>(
            node,
            &names.vibration,
            VIBRATION_SETTINGS,
            attributes,
        )?
        .subscriber_builder()
        .buffer_size(VIBRATION_BUFFER)
        .create()
        .map_err(|e| ipc_error("create the vibration subscriber", e))?;
        let pose = open_pubsub_with::<PoseSample>(node, &names.pose, POSE_SETTINGS, attributes)?
            .subscriber_builder()
            .buffer_size(POSE_BUFFER)
            .create()
            .map_err(|e| ipc_error("create the pose subscriber", e))?;
        Ok(ServicePorts {
            estimate,
            margin,
            wake_in,
            wake_out,
            t_min,
            vibration,
            pose,
        })
    }

    /// Wakes controllers waiting on the wake-controller event (`event_id`: one of
    /// `EVENT_ID_ESTIMATE`, `EVENT_ID_MARGIN_RESPONSE`). Failures are ignored: the data has
    /// been delivered already, the event only shortens the controller's wait.
    pub fn notify(&self, event_id: usize) {
        let _ = self
            .wake_out
            .notify_with_custom_event_id(EventId::new(event_id));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wait_shorter_than_a_microsecond_returns() {
        // Before `listener_timed_wait` clamped it, a 500 ns wait was a 0 µs SO_RCVTIMEO, i.e.
        // no timeout: with nobody notifying, the wait never returned (the monitor test's
        // controller hung there). The thread must end; the 60 s bound only decides that the
        // test failed, it measures nothing.
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let node = create_node("cablevib-test-short-wait").unwrap();
            let name = format!("cablevib_test_short_wait_{}", std::process::id());
            let listener = open_event(&node, &name)
                .unwrap()
                .listener_builder()
                .create()
                .unwrap();
            for nanos in [1, 500, 999] {
                listener_timed_wait(&listener, Duration::from_nanos(nanos));
            }
            let _ = tx.send(());
        });
        assert!(
            rx.recv_timeout(Duration::from_secs(60)).is_ok(),
            "a sub-microsecond timed wait did not return"
        );
    }
}
