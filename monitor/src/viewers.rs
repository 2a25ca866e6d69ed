//! The Foxglove WebSocket viewers, kept apart from the recording.
//!
//! The viewers have their own Foxglove `Context` (the recording has another), fed by a thread
//! of their own from a bounded queue ([`VIEWER_QUEUE`] messages) that the writer fills without
//! ever waiting: when it is full the message is dropped for the viewers (counted), never for
//! the record. So a slow or hostile viewer costs the record nothing.
//!
//! Bounds per viewer and in total:
//! - at most [`MonitorConfig::max_viewers`](crate::MonitorConfig::max_viewers) viewers get
//!   data (a viewer is a client with at least one subscription); a further one is told so
//!   (a Foxglove status message), gets no data at all (its sink is removed from the viewers'
//!   context: `Context::remove_sink`, public but hidden from the docs in foxglove 0.30; the
//!   monitor tests' 1000-viewer case fails if it stops working) and is counted; the first
//!   refusal is logged, the others only counted;
//! - each admitted viewer's outgoing queue holds at most [`VIEWER_BACKLOG`] messages (the
//!   Foxglove SDK's `message_backlog_size`): a viewer that does not read loses its oldest
//!   messages (the SDK drops them; it logs "outbox for client … full" at most every 30 s and
//!   exposes no count) and keeps at most that many in memory;
//! - a viewer's disconnection is one line on stderr (the SDK's per-message send errors to a
//!   closed socket, hundreds in a few ms, are filtered out: [`LOG_FILTER`]).

use std::collections::{HashMap, HashSet};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use foxglove::websocket::{ChannelView, Client, ClientId, ServerListener, Status};
use foxglove::{Context, SinkId};

use crate::writer::{Channels, Live};

/// Messages queued from the writer to the viewers' thread (≈ 2 s of estimates and poses at
/// 1 kHz); when full, a message is dropped for the viewers only and counted.
pub const VIEWER_QUEUE: usize = 4096;
/// Messages queued per viewer by the Foxglove SDK before its oldest are dropped (≈ 0.13 s of
/// estimates and poses at 1 kHz, ≈ 0.3 MB of JSON).
pub const VIEWER_BACKLOG: usize = 256;
/// Default cap on the viewers that get data.
pub const DEFAULT_MAX_VIEWERS: usize = 16;
/// The `tracing` filter for processes that serve viewers: warnings, without the Foxglove SDK's
/// one error per queued message to a viewer whose socket closed.
pub const LOG_FILTER: &str = "warn,foxglove::websocket::connected_client::poller=off";

/// Raises this process's soft limit of open files to its hard limit (each viewer holds a
/// socket; the Foxglove server stops accepting at the limit). Best effort, once.
pub(crate) fn raise_open_file_limit() {
    // SAFETY: getrlimit/setrlimit with a valid, initialised struct.
    unsafe {
        let mut r = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        if libc::getrlimit(libc::RLIMIT_NOFILE, &mut r) == 0 && r.rlim_cur < r.rlim_max {
            r.rlim_cur = r.rlim_max;
            libc::setrlimit(libc::RLIMIT_NOFILE, &r);
        }
    }
}

/// What the viewers cost and got.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ViewerReport {
    /// Viewers that got data.
    pub admitted: u64,
    /// Viewers refused past the cap (they got no data).
    pub refused: u64,
    /// Messages dropped for the viewers because their queue was full (the record has them).
    pub dropped: u64,
}

#[derive(Default)]
struct AdmissionState {
    /// Admitted viewers and their subscription counts.
    admitted: HashMap<ClientId, usize>,
    refused: HashSet<ClientId>,
    /// Sinks to remove from the viewers' context (done by the viewer thread, not in the
    /// SDK's callback).
    to_remove: Vec<SinkId>,
    admitted_total: u64,
    refused_total: u64,
}

/// The cap on viewers: a `ServerListener` of the Foxglove server.
pub struct Admission {
    max_viewers: usize,
    state: Mutex<AdmissionState>,
}

impl Admission {
    /// A cap of `max_viewers` viewers.
    pub fn new(max_viewers: usize) -> Arc<Admission> {
        Arc::new(Admission {
            max_viewers,
            state: Mutex::new(AdmissionState::default()),
        })
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, AdmissionState> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn report(&self) -> (u64, u64) {
        let s = self.lock();
        (s.admitted_total, s.refused_total)
    }
}

impl ServerListener for Admission {
    fn on_subscribe(&self, client: Client, _channel: ChannelView) {
        let id = client.id();
        let mut s = self.lock();
        if let Some(n) = s.admitted.get_mut(&id) {
            *n += 1;
            return;
        }
        if s.refused.contains(&id) {
            s.to_remove.extend(client.sink_id());
            return;
        }
        if s.admitted.len() < self.max_viewers {
            s.admitted.insert(id, 1);
            s.admitted_total += 1;
            return;
        }
        s.refused.insert(id);
        s.refused_total += 1;
        s.to_remove.extend(client.sink_id());
        if s.refused_total == 1 {
            eprintln!(
                "cablevib monitor: {} viewers get data already (--max-viewers {}): a further \
                 viewer gets none (counted in the summary)",
                s.admitted.len(),
                self.max_viewers
            );
        }
        drop(s);
        client.send_status(Status::error(format!(
            "cablevib monitor: {} viewers already (--max-viewers): this one gets no data",
            self.max_viewers
        )));
    }

    fn on_unsubscribe(&self, client: Client, _channel: ChannelView) {
        let id = client.id();
        let mut s = self.lock();
        if let Some(n) = s.admitted.get_mut(&id) {
            *n = n.saturating_sub(1);
            if *n == 0 {
                s.admitted.remove(&id);
            }
        }
    }

    fn on_client_disconnect(&self) {
        eprintln!("cablevib monitor: a Foxglove viewer disconnected");
    }
}

/// The viewers' thread: logs what the writer hands it to the viewers' channels, and removes
/// refused viewers' sinks, until the writer hangs up. Returns the viewer counts, with
/// `dropped` from the writer.
pub(crate) fn viewer_loop(
    rx: Receiver<Live>,
    ch: Channels,
    ctx: Arc<Context>,
    admission: Arc<Admission>,
) -> ViewerReport {
    loop {
        let sinks = std::mem::take(&mut admission.lock().to_remove);
        for sink in sinks {
            ctx.remove_sink(sink);
        }
        match rx.recv_timeout(Duration::from_millis(50)) {
            Ok(live) => ch.log_live(live),
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => break,
        }
    }
    let (admitted, refused) = admission.report();
    ViewerReport {
        admitted,
        refused,
        dropped: 0,
    }
}
