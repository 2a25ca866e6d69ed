//! How complete a record is, per channel: every message the monitor subscribes to carries its
//! sender's sequence number (a pose's and a set-point's `sequence`, an estimate's `sequence`:
//! the service's estimate count), incremented by one per message, so a gap between two
//! consecutive sequences of one sender is that many messages lost before the monitor read
//! them (overwritten in its iceoryx2 queue). Counted by [`cablevib::stats::SequenceGaps`]
//! (one sender per iceoryx2 publisher: a restarted sender is a new one; a sequence that goes
//! back or jumps is a counted reset, never a loss).
//!
//! A channel's messages are then either recorded, or dropped in the monitor's own queue
//! between its iceoryx2 thread and its writer (counted), so for one sender
//!
//! ```text
//! last − first + 1 = received + lost (sequence gaps)      (no resets)
//! received = recorded + dropped (queue)
//! ```
//!
//! What cannot be counted: messages a sender published before the monitor's first receive
//! from it (the first sequence is in the record: 1 means from the sender's start).

use std::collections::BTreeMap;

use cablevib::stats::SequenceGaps;
use iceoryx2::identifiers::UniquePublisherId;

/// Senders tracked per channel (the pose and T_min services admit 4 publishers, the estimate
/// service 1; the slack covers restarts).
const SENDERS: usize = 8;

/// One sender's sequence range on a channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SenderRange {
    /// The first sequence received from it.
    pub first: u64,
    /// The last sequence received from it.
    pub last: u64,
}

/// The completeness of one channel.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ChannelCompleteness {
    /// Messages read from iceoryx2.
    pub received: u64,
    /// Messages missing between consecutive sequences of a sender (lost in the iceoryx2 queue).
    pub lost_sequence_gap: u64,
    /// Times a sender's sequence went back, repeated or jumped (not counted as losses).
    pub sequence_resets: u64,
    /// Messages read but dropped because the monitor's queue to its writer was full.
    pub dropped_queue: u64,
    /// Messages written to the record (and offered to the viewers).
    pub recorded: u64,
    /// Each sender's first and last sequence, in the order first heard (at most 8).
    pub senders: Vec<SenderRange>,
}

impl ChannelCompleteness {
    /// Messages the channel's senders sent while the monitor listened that are not recorded.
    pub fn missing(&self) -> u64 {
        self.lost_sequence_gap + self.received.saturating_sub(self.recorded)
    }

    /// The metadata entries of channel `name`: `{name}.received`, `.lost_sequence_gap`,
    /// `.sequence_resets`, `.dropped_queue`, `.recorded`, `.first_sequence`,
    /// `.last_sequence` (one value per sender, comma-separated), `.complete` (`true` when
    /// nothing is missing).
    pub fn metadata(&self, name: &str, into: &mut BTreeMap<String, String>) {
        let join = |f: fn(&SenderRange) -> u64| {
            self.senders
                .iter()
                .map(|s| f(s).to_string())
                .collect::<Vec<_>>()
                .join(",")
        };
        for (key, value) in [
            ("received", self.received.to_string()),
            ("lost_sequence_gap", self.lost_sequence_gap.to_string()),
            ("sequence_resets", self.sequence_resets.to_string()),
            ("dropped_queue", self.dropped_queue.to_string()),
            ("recorded", self.recorded.to_string()),
            ("first_sequence", join(|s| s.first)),
            ("last_sequence", join(|s| s.last)),
            ("complete", (self.missing() == 0).to_string()),
        ] {
            into.insert(format!("{name}.{key}"), value);
        }
    }
}

impl core::fmt::Display for ChannelCompleteness {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} recorded, {} lost (sequence gaps), {} dropped (monitor queue)",
            self.recorded, self.lost_sequence_gap, self.dropped_queue
        )?;
        if self.sequence_resets > 0 {
            write!(f, ", {} sequence resets", self.sequence_resets)?;
        }
        match self.senders.as_slice() {
            [] => Ok(()),
            [one] => write!(f, ", sequences {}..{}", one.first, one.last),
            many => write!(f, ", {} senders", many.len()),
        }
    }
}

/// The sequence bookkeeping of one channel, in the monitor's iceoryx2 thread: no allocation
/// per message.
#[derive(Debug, Clone)]
pub struct SequenceCounter {
    gaps: SequenceGaps<UniquePublisherId, SENDERS>,
    /// Senders in the order first heard (keys), for the report's order.
    order: [Option<UniquePublisherId>; SENDERS],
    received: u64,
    dropped_queue: u64,
}

impl SequenceCounter {
    /// A counter for a subscriber whose queue holds `queue` messages.
    pub fn new(queue: usize) -> SequenceCounter {
        SequenceCounter {
            gaps: SequenceGaps::with_queue_slack(queue as u64),
            order: [None; SENDERS],
            received: 0,
            dropped_queue: 0,
        }
    }

    /// Records message `sequence` of `sender`, read at `now_ns` (monotonic).
    pub fn received(&mut self, sender: UniquePublisherId, sequence: u64, now_ns: u64) {
        self.received += 1;
        self.gaps.record(sender, sequence, now_ns);
        if !self.order.contains(&Some(sender)) {
            if let Some(free) = self.order.iter_mut().find(|s| s.is_none()) {
                *free = Some(sender);
            }
        }
    }

    /// One received message was dropped in the monitor's queue.
    pub fn dropped(&mut self) {
        self.dropped_queue += 1;
    }

    /// The channel's completeness, given how many messages the writer recorded.
    pub fn completeness(&self, recorded: u64) -> ChannelCompleteness {
        let senders: Vec<_> = self.gaps.senders().collect();
        let ranges = self
            .order
            .iter()
            .flatten()
            .filter_map(|k| senders.iter().find(|s| s.key == *k))
            .map(|s| SenderRange {
                first: s.first,
                last: s.last,
            })
            .collect();
        ChannelCompleteness {
            received: self.received,
            lost_sequence_gap: self.gaps.lost(),
            sequence_resets: self.gaps.resets(),
            dropped_queue: self.dropped_queue,
            recorded,
            senders: ranges,
        }
    }
}
