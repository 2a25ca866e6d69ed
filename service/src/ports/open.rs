//! Opening or creating services with cablevib's settings and attributes, and verifying the
//! static configuration (and schema-version attribute) of a service someone else created.

#[allow(unused_imports)]
use super::*;

/// Settings a publish-subscribe service is created with.
#[derive(Debug, Clone, Copy)]
pub struct PubSubSettings {
    /// The most samples a subscriber may queue (`subscriber_max_buffer_size`); each subscriber
    /// asks for its own queue up to this.
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

/// The attributes of an existing service `name` do not name another schema version.
fn check_attributes(name: &str, attributes: &AttributeSet) -> Result<(), ServiceError> {
    ReadAttributes::from_set(attributes).check_schema(name, false)
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

/// Opens publish-subscribe service `name` carrying `M`, or creates it with `settings` and
/// the [contract attributes](ServiceAttributes::contract).
pub fn open_pubsub<M: Message>(
    node: &Node<Ipc>,
    name: &str,
    settings: PubSubSettings,
) -> Result<publish_subscribe::PortFactory<Ipc, M, ()>, ServiceError> {
    open_pubsub_with(node, name, settings, &ServiceAttributes::contract())
}

/// [`open_pubsub`], creating the service with `attributes`.
pub fn open_pubsub_with<M: Message>(
    node: &Node<Ipc>,
    name: &str,
    settings: PubSubSettings,
    attributes: &ServiceAttributes,
) -> Result<publish_subscribe::PortFactory<Ipc, M, ()>, ServiceError> {
    use PublishSubscribeCreateError as C;
    use PublishSubscribeOpenError as O;
    let sname = service_name(name)?;
    let spec = attributes.specifier()?;
    let open = || match node.service_builder(&sname).publish_subscribe::<M>().open() {
        Ok(f) => verified(f, |f| {
            check_attributes(name, f.attributes())?;
            verify_pubsub(name, f, settings)
        }),
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
        .create_with_attributes(&spec)
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

/// Opens the margin request-response service `name`, or creates it with the
/// [contract attributes](ServiceAttributes::contract).
pub fn open_margin(node: &Node<Ipc>, name: &str) -> Result<MarginFactory, ServiceError> {
    open_margin_with(node, name, &ServiceAttributes::contract())
}

/// [`open_margin`], creating the service with `attributes`.
pub fn open_margin_with(
    node: &Node<Ipc>,
    name: &str,
    attributes: &ServiceAttributes,
) -> Result<MarginFactory, ServiceError> {
    use RequestResponseCreateError as C;
    use RequestResponseOpenError as O;
    let sname = service_name(name)?;
    let spec = attributes.specifier()?;
    let builder = || {
        node.service_builder(&sname)
            .request_response::<MarginRequest, MarginResponse>()
    };
    let open = || match builder().open() {
        Ok(f) => verified(f, |f| {
            check_attributes(name, f.attributes())?;
            verify_margin(name, f)
        }),
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
        .create_with_attributes(&spec)
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

/// Opens event service `name`, or creates it with the
/// [contract attributes](ServiceAttributes::contract).
pub fn open_event(node: &Node<Ipc>, name: &str) -> Result<event::PortFactory<Ipc>, ServiceError> {
    open_event_with(node, name, &ServiceAttributes::contract())
}

/// [`open_event`], creating the service with `attributes`.
pub fn open_event_with(
    node: &Node<Ipc>,
    name: &str,
    attributes: &ServiceAttributes,
) -> Result<event::PortFactory<Ipc>, ServiceError> {
    use EventCreateError as C;
    use EventOpenError as O;
    let sname = service_name(name)?;
    let spec = attributes.specifier()?;
    let open = || match node.service_builder(&sname).event().open() {
        Ok(f) => verified(f, |f| {
            check_attributes(name, f.attributes())?;
            verify_event(name, f)
        }),
        Err(O::DoesNotExist | O::HangsInCreation | O::Interrupt) => Attempt::Retry(None),
        Err(e) => Attempt::Fail(ipc_error(format!("open event service \"{name}\""), e)),
    };
    let create = || match node
        .service_builder(&sname)
        .event()
        .max_nodes(EVENT_NODES)
        .max_listeners(EVENT_PORTS)
        .max_notifiers(EVENT_PORTS)
        .create_with_attributes(&spec)
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
    buffer: RECORD_BUFFER,
    history: 0,
    max_publishers: MAX_PUBLISHERS,
};
/// The vibration service's settings: up to [`RECORD_BUFFER`] samples queued per subscriber
/// (the service's own queue is [`VIBRATION_BUFFER`]; a vibration sender need not notify: the
/// service drains them whenever it wakes, at least every 50 ms).
pub const VIBRATION_SETTINGS: PubSubSettings = PubSubSettings {
    buffer: RECORD_BUFFER,
    history: 0,
    max_publishers: MAX_PUBLISHERS,
};
/// The T_min service's settings.
pub const T_MIN_SETTINGS: PubSubSettings = PubSubSettings {
    buffer: RECORD_BUFFER,
    history: 1,
    max_publishers: MAX_PUBLISHERS,
};
/// The estimate service's settings.
pub const ESTIMATE_SETTINGS: PubSubSettings = PubSubSettings {
    buffer: RECORD_BUFFER,
    history: 0,
    max_publishers: ESTIMATE_PUBLISHERS,
};
