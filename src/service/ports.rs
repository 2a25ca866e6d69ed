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
//! | pose | publish-subscribe | [`POSE_BUFFER`] queued poses per subscriber, history 0, [`MAX_PUBLISHERS`] publishers |
//! | T_min | publish-subscribe | history 1: a (re)started service gets the set-point in force |
//! | estimate | publish-subscribe | [`ESTIMATE_BUFFER`] queued estimates per subscriber, [`ESTIMATE_PUBLISHERS`] publisher |
//! | margin | request-response | [`MARGIN_SERVERS`] server, [`MAX_CLIENTS`] clients, [`MARGIN_ACTIVE_REQUESTS`] active requests per client |
//! | wake/service, wake/controller | event | [`EVENT_PORTS`] listeners and notifiers |
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
    EVENT_ID_ESTIMATE, EVENT_ID_MARGIN_REQUEST, EVENT_ID_MARGIN_RESPONSE, EVENT_ID_POSE,
    EVENT_ID_T_MIN,
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

/// The iceoryx2 service flavour used everywhere: inter-process, shared memory.
pub type Ipc = ipc::Service;

/// How many poses a subscriber queues before the oldest is overwritten. The service drains the
/// queue every cycle and estimates the newest pose only ("latest pose wins").
pub const POSE_BUFFER: usize = 16;
/// How many estimates a subscriber queues before the oldest is overwritten.
pub const ESTIMATE_BUFFER: usize = 16;
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
]);

const fn max_event_id(ids: [usize; 5]) -> usize {
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

/// How long a client started beside the service (demo, benchmark) waits for it to come up.
pub const SERVICE_UP_TIMEOUT: Duration = Duration::from_secs(10);
/// How often [`wait_for_service`] checks.
const SERVICE_UP_POLL: Duration = Duration::from_millis(1);

/// Polls `ready` until it is true. Fails with `stopped()` once `stop` is set, and with
/// [`ServiceError::Timeout`] after [`SERVICE_UP_TIMEOUT`].
pub fn wait_for_service(
    mut ready: impl FnMut() -> bool,
    stop: &core::sync::atomic::AtomicBool,
    stopped: impl FnOnce() -> ServiceError,
) -> Result<(), ServiceError> {
    let deadline = std::time::Instant::now() + SERVICE_UP_TIMEOUT;
    while !ready() {
        if stop.load(core::sync::atomic::Ordering::Acquire) {
            return Err(stopped());
        }
        if std::time::Instant::now() > deadline {
            return Err(ServiceError::Timeout(format!(
                "the service did not come up within {} s",
                SERVICE_UP_TIMEOUT.as_secs()
            )));
        }
        std::thread::sleep(SERVICE_UP_POLL);
    }
    Ok(())
}

/// A validated iceoryx2 service name.
pub fn service_name(name: &str) -> Result<ServiceName, ServiceError> {
    ServiceName::new(name).map_err(|e| ServiceError::Usage(format!("service name `{name}`: {e:?}")))
}

/// Loads iceoryx2's global configuration once. Without a config file iceoryx2 warns that it
/// uses the defaults, on every start of every process; that is the normal case here, so the
/// warning is silenced for this one call (iceoryx2's log level is then set from
/// `IOX2_LOG_LEVEL`, default info).
pub fn load_iceoryx2_config() -> &'static Config {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        set_log_level(LogLevel::Error);
        let _ = Config::global_config();
        set_log_level_from_env_or(LogLevel::Info);
    });
    Config::global_config()
}

/// The configuration cablevib's nodes are created with: the global one, but without
/// iceoryx2's cleanup of every dead node of the user when a node is created or dropped, so
/// that only [`remove_stale_nodes`] cleans up, and only cablevib's nodes. (Opening a service
/// still cleans the dead nodes of that service: they are participants of a cablevib service.)
fn node_config() -> &'static Iceoryx2Config {
    static CONFIG: std::sync::OnceLock<Iceoryx2Config> = std::sync::OnceLock::new();
    CONFIG.get_or_init(|| {
        let mut config = load_iceoryx2_config().clone();
        config.global.node.cleanup_dead_nodes_on_creation = false;
        config.global.node.cleanup_dead_nodes_on_destruction = false;
        config
    })
}

/// A node of this name belongs to cablevib (see [`NODE_NAME_PREFIX`]).
pub fn is_cablevib_node(name: &str) -> bool {
    name.starts_with(NODE_NAME_PREFIX)
}

/// Removes the resources (shared memory, ports in every service) that cablevib processes which
/// died without cleaning up (SIGKILL, crash) left behind; dead nodes of other applications
/// (names not starting with [`NODE_NAME_PREFIX`], or without readable details) are left to
/// their owners. Returns how many dead nodes were cleaned and how many could not be
/// (permissions, or another process is cleaning them).
pub fn remove_stale_nodes() -> (usize, usize) {
    let mut dead = Vec::new();
    let listed = Node::<Ipc>::list(load_iceoryx2_config(), |state| {
        if let NodeState::<Ipc>::Dead(view) = state {
            let own = view
                .details()
                .as_ref()
                .is_some_and(|d| is_cablevib_node(d.name().as_str()));
            if own {
                dead.push(view);
            }
        }
        CallbackProgression::Continue
    });
    if let Err(e) = listed {
        tracing::warn!("cannot list iceoryx2 nodes to clean up dead ones: {e:?}");
        return (0, 0);
    }
    let (mut removed, mut failed) = (0, 0);
    for view in dead {
        match view.try_remove_stale_resources() {
            Ok(()) => removed += 1,
            Err(e) => {
                tracing::debug!("stale resources of a dead node not removed: {e:?}");
                failed += 1;
            }
        }
    }
    (removed, failed)
}

/// An iceoryx2 node named `name` (a readable tag for `iox2 node list`; need not be unique).
/// The name must start with [`NODE_NAME_PREFIX`], so that `cablevib serve` cleans up after the
/// node if its process dies.
pub fn create_node(name: &str) -> Result<Node<Ipc>, ServiceError> {
    if !is_cablevib_node(name) {
        return Err(ServiceError::Usage(format!(
            "node name `{name}`: must start with `{NODE_NAME_PREFIX}`"
        )));
    }
    let node_name = NodeName::new(name)
        .map_err(|e| ServiceError::Usage(format!("node name `{name}`: {e:?}")))?;
    NodeBuilder::new()
        .name(&node_name)
        .config(node_config())
        .create::<Ipc>()
        .map_err(|e| ipc_error(format!("create node `{name}`"), e))
}

/// Settings a publish-subscribe service is created with.
#[derive(Debug, Clone, Copy)]
pub struct PubSubSettings {
    /// Queued samples per subscriber.
    pub buffer: usize,
    /// Samples replayed to a late subscriber.
    pub history: usize,
    /// Publishers the service admits.
    pub max_publishers: usize,
}

/// Refuses an existing service whose setting `setting` is `found` where cablevib needs
/// `expected` (`ok` says whether it fits).
fn expect_setting(
    service: &str,
    setting: &'static str,
    found: impl core::fmt::Display,
    expected: impl core::fmt::Display,
    ok: bool,
) -> Result<(), ServiceError> {
    if ok {
        Ok(())
    } else {
        Err(ServiceError::ServiceSettings {
            service: service.to_owned(),
            setting,
            found: found.to_string(),
            expected: expected.to_string(),
        })
    }
}

/// The static configuration of publish-subscribe service `name` is the one cablevib creates
/// it with (`settings`).
fn verify_pubsub<M: Message>(
    name: &str,
    f: &publish_subscribe::PortFactory<Ipc, M, ()>,
    settings: PubSubSettings,
) -> Result<(), ServiceError> {
    let c = f.static_config();
    let exact = |setting, found: usize, expected: usize| {
        expect_setting(name, setting, found, expected, found == expected)
    };
    exact(
        "max_publishers",
        c.max_publishers(),
        settings.max_publishers,
    )?;
    exact("max_subscribers", c.max_subscribers(), MAX_SUBSCRIBERS)?;
    exact("max_nodes", c.max_nodes(), MAX_NODES)?;
    exact(
        "subscriber_max_buffer_size",
        c.subscriber_max_buffer_size(),
        settings.buffer,
    )?;
    exact("history_size", c.history_size(), settings.history)?;
    expect_setting(
        name,
        "safe_overflow",
        c.has_safe_overflow(),
        true,
        c.has_safe_overflow(),
    )
}

/// The static configuration of the margin service `name` is the one cablevib creates it with.
fn verify_margin(name: &str, f: &MarginFactory) -> Result<(), ServiceError> {
    let c = f.static_config();
    let exact = |setting, found: usize, expected: usize| {
        expect_setting(name, setting, found, expected, found == expected)
    };
    exact("max_servers", c.max_servers(), MARGIN_SERVERS)?;
    exact("max_clients", c.max_clients(), MAX_CLIENTS)?;
    exact("max_nodes", c.max_nodes(), MAX_NODES)?;
    exact(
        "max_active_requests_per_client",
        c.max_active_requests_per_client(),
        MARGIN_ACTIVE_REQUESTS,
    )?;
    exact(
        "max_response_buffer_size",
        c.max_response_buffer_size(),
        MARGIN_RESPONSE_BUFFER,
    )?;
    let requests = c.has_safe_overflow_for_requests();
    expect_setting(name, "safe_overflow_for_requests", requests, true, requests)?;
    let responses = c.has_safe_overflow_for_responses();
    expect_setting(
        name,
        "safe_overflow_for_responses",
        responses,
        true,
        responses,
    )
}

/// The static configuration of event service `name` is the one cablevib creates it with.
fn verify_event(name: &str, f: &event::PortFactory<Ipc>) -> Result<(), ServiceError> {
    let c = f.static_config();
    let exact = |setting, found: usize, expected: usize| {
        expect_setting(name, setting, found, expected, found == expected)
    };
    exact("max_listeners", c.max_listeners(), EVENT_PORTS)?;
    exact("max_notifiers", c.max_notifiers(), EVENT_PORTS)?;
    exact("max_nodes", c.max_nodes(), EVENT_NODES)?;
    let ids = c.event_id_max_value();
    expect_setting(
        name,
        "event_id_max_value",
        ids,
        format_args!("at least {EVENT_ID_LARGEST}"),
        ids >= EVENT_ID_LARGEST,
    )
}

/// `Done` when the opened or created service `f` passes `verify`, `Fail` otherwise.
fn verified<F>(f: F, verify: impl FnOnce(&F) -> Result<(), ServiceError>) -> Attempt<F> {
    match verify(&f) {
        Ok(()) => Attempt::Done(f),
        Err(e) => Attempt::Fail(e),
    }
}

/// One try at opening or creating a service.
enum Attempt<F> {
    /// Opened or created.
    Done(F),
    /// Not there yet, or another process is creating it: try again (with iceoryx2's reason
    /// when it said one).
    Retry(Option<String>),
    /// A failure that retrying does not cure.
    Fail(ServiceError),
}

/// Opens service `name`, or creates it: alternates `open` and `create` until one succeeds,
/// for at most [`OPEN_RETRIES`] rounds ([`OPEN_RETRY_SLEEP`] apart), so that two processes
/// starting together end up on one service. `kind` names the service in errors.
fn open_or_create<F>(
    name: &str,
    kind: &str,
    mut open: impl FnMut() -> Attempt<F>,
    mut create: impl FnMut() -> Attempt<F>,
) -> Result<F, ServiceError> {
    let mut last = String::new();
    for _ in 0..OPEN_RETRIES {
        for attempt in [&mut open as &mut dyn FnMut() -> Attempt<F>, &mut create] {
            match attempt() {
                Attempt::Done(f) => return Ok(f),
                Attempt::Retry(reason) => last = reason.unwrap_or(last),
                Attempt::Fail(e) => return Err(e),
            }
        }
        std::thread::sleep(OPEN_RETRY_SLEEP);
    }
    Err(ipc_error(
        format!("open or create {kind} \"{name}\" (gave up after retries)"),
        last,
    ))
}

/// Opens publish-subscribe service `name` carrying `M`, or creates it with `settings`.
pub fn open_pubsub<M: Message>(
    node: &Node<Ipc>,
    name: &str,
    settings: PubSubSettings,
) -> Result<publish_subscribe::PortFactory<Ipc, M, ()>, ServiceError> {
    use PublishSubscribeCreateError as C;
    use PublishSubscribeOpenError as O;
    let sname = service_name(name)?;
    let open = || match node.service_builder(&sname).publish_subscribe::<M>().open() {
        Ok(f) => verified(f, |f| verify_pubsub(name, f, settings)),
        Err(O::IncompatibleTypes) => Attempt::Fail(ServiceError::IncompatiblePeer(
            explain_publish_subscribe_mismatch::<Ipc, M>(name),
        )),
        Err(O::DoesNotExist | O::HangsInCreation | O::IsMarkedForDestruction | O::Interrupt) => {
            Attempt::Retry(None)
        }
        Err(e) => Attempt::Fail(ipc_error(format!("open service \"{name}\""), e)),
    };
    let create = || match node
        .service_builder(&sname)
        .publish_subscribe::<M>()
        .max_publishers(settings.max_publishers)
        .max_subscribers(MAX_SUBSCRIBERS)
        .max_nodes(MAX_NODES)
        .subscriber_max_buffer_size(settings.buffer)
        .history_size(settings.history)
        .enable_safe_overflow(true)
        .create()
    {
        Ok(f) => verified(f, |f| verify_pubsub(name, f, settings)),
        Err(
            e @ (C::AlreadyExists
            | C::IsBeingCreatedByAnotherInstance
            | C::HangsInCreation
            | C::Interrupt),
        ) => Attempt::Retry(Some(format!("{e:?}"))),
        Err(e) => Attempt::Fail(ipc_error(format!("create service \"{name}\""), e)),
    };
    open_or_create(name, "service", open, create)
}

/// The margin request-response service.
pub type MarginFactory = request_response::PortFactory<Ipc, MarginRequest, (), MarginResponse, ()>;

/// Opens the margin request-response service `name`, or creates it.
pub fn open_margin(node: &Node<Ipc>, name: &str) -> Result<MarginFactory, ServiceError> {
    use RequestResponseCreateError as C;
    use RequestResponseOpenError as O;
    let sname = service_name(name)?;
    let builder = || {
        node.service_builder(&sname)
            .request_response::<MarginRequest, MarginResponse>()
    };
    let open = || match builder().open() {
        Ok(f) => verified(f, |f| verify_margin(name, f)),
        Err(O::IncompatibleRequestOrResponseType) => Attempt::Fail(ServiceError::IncompatiblePeer(
            explain_request_response_mismatch::<Ipc, MarginRequest, MarginResponse>(name),
        )),
        Err(O::DoesNotExist | O::HangsInCreation | O::Interrupt) => Attempt::Retry(None),
        Err(e) => Attempt::Fail(ipc_error(format!("open service \"{name}\""), e)),
    };
    let create = || match builder()
        .max_clients(MAX_CLIENTS)
        .max_servers(MARGIN_SERVERS)
        .max_nodes(MAX_NODES)
        .max_active_requests_per_client(MARGIN_ACTIVE_REQUESTS)
        .max_response_buffer_size(MARGIN_RESPONSE_BUFFER)
        .enable_safe_overflow_for_requests(true)
        .enable_safe_overflow_for_responses(true)
        .create()
    {
        Ok(f) => verified(f, |f| verify_margin(name, f)),
        Err(
            e @ (C::AlreadyExists
            | C::IsBeingCreatedByAnotherInstance
            | C::HangsInCreation
            | C::Interrupt),
        ) => Attempt::Retry(Some(format!("{e:?}"))),
        Err(e) => Attempt::Fail(ipc_error(format!("create service \"{name}\""), e)),
    };
    open_or_create(name, "service", open, create)
}

/// Opens event service `name`, or creates it.
pub fn open_event(node: &Node<Ipc>, name: &str) -> Result<event::PortFactory<Ipc>, ServiceError> {
    use EventCreateError as C;
    use EventOpenError as O;
    let sname = service_name(name)?;
    let open = || match node.service_builder(&sname).event().open() {
        Ok(f) => verified(f, |f| verify_event(name, f)),
        Err(O::DoesNotExist | O::HangsInCreation | O::Interrupt) => Attempt::Retry(None),
        Err(e) => Attempt::Fail(ipc_error(format!("open event service \"{name}\""), e)),
    };
    let create = || match node
        .service_builder(&sname)
        .event()
        .max_nodes(EVENT_NODES)
        .max_listeners(EVENT_PORTS)
        .max_notifiers(EVENT_PORTS)
        .create()
    {
        Ok(f) => verified(f, |f| verify_event(name, f)),
        Err(e @ (C::AlreadyExists | C::IsBeingCreatedByAnotherInstance | C::Interrupt)) => {
            Attempt::Retry(Some(format!("{e:?}")))
        }
        Err(e) => Attempt::Fail(ipc_error(format!("create event service \"{name}\""), e)),
    };
    open_or_create(name, "event service", open, create)
}

/// The pose service's settings.
pub const POSE_SETTINGS: PubSubSettings = PubSubSettings {
    buffer: POSE_BUFFER,
    history: 0,
    max_publishers: MAX_PUBLISHERS,
};
/// The T_min service's settings.
pub const T_MIN_SETTINGS: PubSubSettings = PubSubSettings {
    buffer: 4,
    history: 1,
    max_publishers: MAX_PUBLISHERS,
};
/// The estimate service's settings.
pub const ESTIMATE_SETTINGS: PubSubSettings = PubSubSettings {
    buffer: ESTIMATE_BUFFER,
    history: 0,
    max_publishers: ESTIMATE_PUBLISHERS,
};

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
    /// Woken by peers after they send something (used in `--wait event`).
    pub wake_in: Listener<Ipc>,
    /// Wakes controllers after an estimate or a margin response.
    pub wake_out: Notifier<Ipc>,
    /// T_min set-points, from the controller.
    pub t_min: Subscriber<Ipc, TminSetpoint, ()>,
    /// Poses, from the controller.
    pub pose: Subscriber<Ipc, PoseSample, ()>,
}

impl ServicePorts {
    /// Opens (or creates) every service of instance `names` and the service's ports.
    ///
    /// Fails with [`ServiceError::AlreadyServing`] when another live cablevib service serves
    /// the same instance (two would publish two estimates per pose).
    pub fn open(node: &Node<Ipc>, names: &ServiceNames) -> Result<ServicePorts, ServiceError> {
        let margin_factory = open_margin(node, &names.margin)?;
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
        let estimate = open_pubsub::<EstimateSample>(node, &names.estimate, ESTIMATE_SETTINGS)?
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
        let wake_in = open_event(node, &names.wake_service)?
            .listener_builder()
            .create()
            .map_err(|e| ipc_error("create the wake-service listener", e))?;
        let wake_out = open_event(node, &names.wake_controller)?
            .notifier_builder()
            .create()
            .map_err(|e| ipc_error("create the wake-controller notifier", e))?;
        let t_min = open_pubsub::<TminSetpoint>(node, &names.t_min, T_MIN_SETTINGS)?
            .subscriber_builder()
            .create()
            .map_err(|e| ipc_error("create the T_min subscriber", e))?;
        let pose = open_pubsub::<PoseSample>(node, &names.pose, POSE_SETTINGS)?
            .subscriber_builder()
            .create()
            .map_err(|e| ipc_error("create the pose subscriber", e))?;
        Ok(ServicePorts {
            estimate,
            margin,
            wake_in,
            wake_out,
            t_min,
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

// ---------------------------------------------------------------------------------------------
// The controller's side
// ---------------------------------------------------------------------------------------------

/// A pose and T_min publisher (what a motion controller or `examples/replay.rs` sends), which
/// notifies the wake-service event after each message so that a service in `--wait event`
/// mode wakes up.
pub struct PoseInput {
    pose_factory: publish_subscribe::PortFactory<Ipc, PoseSample, ()>,
    pose: Publisher<Ipc, PoseSample, ()>,
    t_min: Publisher<Ipc, TminSetpoint, ()>,
    wake: Notifier<Ipc>,
}

impl PoseInput {
    /// Opens (or creates) the pose, T_min and wake-service services of instance `names`.
    pub fn open(node: &Node<Ipc>, names: &ServiceNames) -> Result<PoseInput, ServiceError> {
        let pose_factory = open_pubsub::<PoseSample>(node, &names.pose, POSE_SETTINGS)?;
        let pose = pose_factory
            .publisher_builder()
            .create()
            .map_err(|e| ipc_error("create the pose publisher", e))?;
        let t_min = open_pubsub::<TminSetpoint>(node, &names.t_min, T_MIN_SETTINGS)?
            .publisher_builder()
            .create()
            .map_err(|e| ipc_error("create the T_min publisher", e))?;
        let wake = open_event(node, &names.wake_service)?
            .notifier_builder()
            .create()
            .map_err(|e| ipc_error("create the wake-service notifier", e))?;
        Ok(PoseInput {
            pose_factory,
            pose,
            t_min,
            wake,
        })
    }

    /// Publishes `pose` and wakes the service. The only heap allocation is iceoryx2's one per
    /// loan. A service that (re)started since the last call first gets the T_min set-point in
    /// force (history), so that it applies to this pose.
    pub fn send_pose(&self, pose: &PoseSample) -> Result<(), ServiceError> {
        let _ = self.t_min.update_connections();
        let sample = self
            .pose
            .loan_uninit()
            .map_err(|e| ipc_error("loan a pose sample", e))?;
        sample
            .write_payload(*pose)
            .send()
            .map_err(|e| ipc_error("send a pose", e))?;
        let _ = self
            .wake
            .notify_with_custom_event_id(EventId::new(EVENT_ID_POSE));
        Ok(())
    }

    /// Publishes a T_min set-point and wakes the service; it applies to the next pose sent. A
    /// service that (re)starts later receives the last set-point (history) with the next pose
    /// sent through [`PoseInput::send_pose`].
    pub fn send_t_min(&self, setpoint: &TminSetpoint) -> Result<(), ServiceError> {
        self.t_min
            .send_copy(*setpoint)
            .map_err(|e| ipc_error("send a T_min set-point", e))?;
        let _ = self
            .wake
            .notify_with_custom_event_id(EventId::new(EVENT_ID_T_MIN));
        Ok(())
    }

    /// Connects to services that started since the last send and delivers them the last T_min
    /// set-point (history). [`PoseInput::send_pose`] does it too; call this when no poses are
    /// sent (it is cheap when nothing changed).
    pub fn update_connections(&self) {
        let _ = self.t_min.update_connections();
        let _ = self.pose.update_connections();
    }

    /// A cablevib service is subscribed to the poses (it has opened all its ports).
    pub fn service_connected(&self) -> bool {
        self.pose_factory.dynamic_config().number_of_subscribers() > 0
    }
}

/// An estimate subscriber with a listener on the wake-controller event.
pub struct EstimateOutput {
    estimate_factory: publish_subscribe::PortFactory<Ipc, EstimateSample, ()>,
    subscriber: Subscriber<Ipc, EstimateSample, ()>,
    wake: Listener<Ipc>,
}

impl EstimateOutput {
    /// Opens (or creates) the estimate and wake-controller services of instance `names`.
    pub fn open(node: &Node<Ipc>, names: &ServiceNames) -> Result<EstimateOutput, ServiceError> {
        let estimate_factory =
            open_pubsub::<EstimateSample>(node, &names.estimate, ESTIMATE_SETTINGS)?;
        let subscriber = estimate_factory
            .subscriber_builder()
            .create()
            .map_err(|e| ipc_error("create the estimate subscriber", e))?;
        let wake = open_event(node, &names.wake_controller)?
            .listener_builder()
            .create()
            .map_err(|e| ipc_error("create the wake-controller listener", e))?;
        Ok(EstimateOutput {
            estimate_factory,
            subscriber,
            wake,
        })
    }

    /// The next queued estimate, if any.
    pub fn try_receive(&self) -> Result<Option<EstimateSample>, ServiceError> {
        match self.subscriber.receive() {
            Ok(Some(s)) => Ok(Some(*s)),
            Ok(None) => Ok(None),
            Err(e) => Err(ipc_error("receive an estimate", e)),
        }
    }

    /// Waits up to `timeout` for the next estimate: busy-polling ([`WaitMode::Spin`]) or
    /// blocking on the wake-controller event ([`WaitMode::Event`]). `None` on timeout.
    pub fn wait(
        &self,
        mode: WaitMode,
        timeout: Duration,
    ) -> Result<Option<EstimateSample>, ServiceError> {
        wait_for(mode, &self.wake, timeout, || self.try_receive())
    }

    /// A cablevib service publishes estimates.
    pub fn service_connected(&self) -> bool {
        self.estimate_factory
            .dynamic_config()
            .number_of_publishers()
            > 0
    }
}

/// A margin client: sends [`MarginRequest`]s and waits for the [`MarginResponse`].
pub struct MarginClient {
    factory: MarginFactory,
    client: Client<Ipc, MarginRequest, (), MarginResponse, ()>,
    wake_service: Notifier<Ipc>,
    wake: Listener<Ipc>,
}

/// A margin request in flight.
pub type PendingMargin = PendingResponse<Ipc, MarginRequest, (), MarginResponse, ()>;

impl MarginClient {
    /// Opens (or creates) the margin and wake services of instance `names`.
    pub fn open(node: &Node<Ipc>, names: &ServiceNames) -> Result<MarginClient, ServiceError> {
        let factory = open_margin(node, &names.margin)?;
        let client = factory
            .client_builder()
            .create()
            .map_err(|e| ipc_error("create the margin client", e))?;
        let wake_service = open_event(node, &names.wake_service)?
            .notifier_builder()
            .create()
            .map_err(|e| ipc_error("create the wake-service notifier", e))?;
        let wake = open_event(node, &names.wake_controller)?
            .listener_builder()
            .create()
            .map_err(|e| ipc_error("create the wake-controller listener", e))?;
        Ok(MarginClient {
            factory,
            client,
            wake_service,
            wake,
        })
    }

    /// Sends `request` and wakes the service; the answer comes on the returned handle.
    pub fn send(&self, request: &MarginRequest) -> Result<PendingMargin, ServiceError> {
        let pending = self
            .client
            .send_copy(*request)
            .map_err(|e| ipc_error("send a margin request", e))?;
        let _ = self
            .wake_service
            .notify_with_custom_event_id(EventId::new(EVENT_ID_MARGIN_REQUEST));
        Ok(pending)
    }

    /// Sends `request` and waits up to `timeout` for its answer (`None` on timeout, e.g. when
    /// no service runs).
    pub fn query(
        &self,
        request: &MarginRequest,
        mode: WaitMode,
        timeout: Duration,
    ) -> Result<Option<MarginResponse>, ServiceError> {
        let pending = self.send(request)?;
        wait_for(mode, &self.wake, timeout, || match pending.receive() {
            Ok(Some(r)) => Ok(Some(*r)),
            Ok(None) => Ok(None),
            Err(e) => Err(ipc_error("receive a margin response", e)),
        })
    }

    /// A cablevib service serves margin requests.
    pub fn service_connected(&self) -> bool {
        self.factory.dynamic_config().number_of_servers() > 0
    }
}

/// Polls `poll` until it yields a value or `timeout` passes, between polls spinning or
/// blocking on `wake`.
fn wait_for<T>(
    mode: WaitMode,
    wake: &Listener<Ipc>,
    timeout: Duration,
    mut poll: impl FnMut() -> Result<Option<T>, ServiceError>,
) -> Result<Option<T>, ServiceError> {
    let start = std::time::Instant::now();
    loop {
        if let Some(v) = poll()? {
            return Ok(Some(v));
        }
        let elapsed = start.elapsed();
        if elapsed >= timeout {
            return Ok(None);
        }
        match mode {
            WaitMode::Spin => core::hint::spin_loop(),
            WaitMode::Event => {
                // Wakes on any notification (or spuriously on a signal); poll again either way.
                let _ = wake.timed_wait(|_| {}, (timeout - elapsed).min(Duration::from_millis(10)));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_cablevib_node_names_are_own() {
        for own in [
            "cablevib-serve",
            "cablevib-controller",
            "cablevib-test-client",
        ] {
            assert!(is_cablevib_node(own), "{own}");
        }
        for other in [
            "othervendor-serve",
            "iox2-node",
            "",
            "Cablevib-serve",
            "x-cablevib",
        ] {
            assert!(!is_cablevib_node(other), "{other}");
        }
    }

    #[test]
    fn nodes_must_carry_the_prefix() {
        assert!(matches!(
            create_node("controller"),
            Err(ServiceError::Usage(_))
        ));
    }
}
