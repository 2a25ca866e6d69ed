//! The controller's side: a pose and T_min publisher, the estimate subscriber, the margin
//! client.

#[allow(unused_imports)]
use super::*;

// ---------------------------------------------------------------------------------------------
// The controller's side
// ---------------------------------------------------------------------------------------------

/// A pose and T_min publisher (what a motion controller or `service/examples/replay.rs` sends), which
/// notifies the wake-service event after each message so that a service waiting on the event
/// mode wakes up.
pub struct PoseInput {
    pose_factory: publish_subscribe::PortFactory<Ipc, PoseSample, ()>,
    pose: Publisher<Ipc, PoseSample, ()>,
    t_min: Publisher<Ipc, TminSetpoint, ()>,
    wake: Notifier<Ipc>,
}

impl PoseInput {
    /// The pose publisher's id (the key of the service's per-publisher sequence counts,
    /// `ServerReport::pose_publishers`).
    pub fn publisher_id(&self) -> iceoryx2::identifiers::UniquePublisherId {
        self.pose.id()
    }

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

    /// The attributes of the pose service (who created it and with which schema).
    pub fn attributes(&self) -> ReadAttributes {
        ReadAttributes::from_set(self.pose_factory.attributes())
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
    /// Opens (or creates) the estimate and wake-controller services of instance `names`, with
    /// a queue of [`ESTIMATE_BUFFER`] estimates (a controller wants the newest).
    pub fn open(node: &Node<Ipc>, names: &ServiceNames) -> Result<EstimateOutput, ServiceError> {
        EstimateOutput::open_with_queue(node, names, ESTIMATE_BUFFER)
    }

    /// [`EstimateOutput::open`] for a recorder, which wants every estimate: a queue of
    /// [`RECORD_BUFFER`] estimates.
    pub fn open_recorder(
        node: &Node<Ipc>,
        names: &ServiceNames,
    ) -> Result<EstimateOutput, ServiceError> {
        EstimateOutput::open_with_queue(node, names, RECORD_BUFFER)
    }

    fn open_with_queue(
        node: &Node<Ipc>,
        names: &ServiceNames,
        queue: usize,
    ) -> Result<EstimateOutput, ServiceError> {
        let estimate_factory =
            open_pubsub::<EstimateSample>(node, &names.estimate, ESTIMATE_SETTINGS)?;
        let subscriber = estimate_factory
            .subscriber_builder()
            .buffer_size(queue)
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
        Ok(self.try_receive_from()?.map(|(e, _)| e))
    }

    /// The next queued estimate with the id of the publisher that sent it (the key of its
    /// [`EstimateSample::sequence`]: a restarted service is another publisher).
    pub fn try_receive_from(
        &self,
    ) -> Result<Option<(EstimateSample, iceoryx2::identifiers::UniquePublisherId)>, ServiceError>
    {
        match self.subscriber.receive() {
            Ok(Some(s)) => Ok(Some((*s, s.header().publisher_id()))),
            Ok(None) => Ok(None),
            Err(e) => Err(ipc_error("receive an estimate", e)),
        }
    }

    /// Blocks up to `timeout` on the wake-controller event (returns at once on a notification
    /// or a signal); receives nothing.
    pub fn wait_event(&self, timeout: Duration) {
        listener_timed_wait(&self.wake, timeout);
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

    /// The attributes of the estimate service: schema version, units, cablevib version, and
    /// the scene's when `cablevib serve` created it.
    pub fn attributes(&self) -> ReadAttributes {
        ReadAttributes::from_set(self.estimate_factory.attributes())
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

    /// The attributes of the margin service.
    pub fn attributes(&self) -> ReadAttributes {
        ReadAttributes::from_set(self.factory.attributes())
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
                listener_timed_wait(wake, (timeout - elapsed).min(Duration::from_millis(10)));
            }
        }
    }
}
