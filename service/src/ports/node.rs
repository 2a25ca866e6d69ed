//! Nodes: iceoryx2 configuration, node creation, cleaning up dead cablevib nodes, waiting for
//! the service to come up.

#[allow(unused_imports)]
use super::*;

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
    ServiceName::new(name).map_err(|e| ServiceError::Name {
        what: format!("service name `{name}`"),
        reason: format!("{e:?}"),
    })
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
        return Err(ServiceError::Name {
            what: format!("node name `{name}`"),
            reason: format!("must start with `{NODE_NAME_PREFIX}`"),
        });
    }
    let node_name = NodeName::new(name).map_err(|e| ServiceError::Name {
        what: format!("node name `{name}`"),
        reason: format!("{e:?}"),
    })?;
    NodeBuilder::new()
        .name(&node_name)
        .config(node_config())
        .create::<Ipc>()
        .map_err(|e| ipc_error(format!("create node `{name}`"), e))
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
            Err(ServiceError::Name { .. })
        ));
    }
}
