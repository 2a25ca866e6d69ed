//! Fixed-capacity sample buffers, percentiles and status histograms that never allocate
//! after construction. The one place percentiles and status counts are computed: the
//! service, the benchmarks and the offline sweeps all use it.

use crate::status::{status_str, StatusCode};

/// Slots of a [`StatusHistogram`]: one per wire value below it; the last slot also collects
/// every larger (unknown) wire value.
pub const STATUS_SLOTS: usize = 16;

/// Counts per status code (index = wire value). Copy, no allocation.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StatusHistogram {
    counts: [u64; STATUS_SLOTS],
}

impl StatusHistogram {
    /// Counts one estimate of status `s`.
    pub fn record(&mut self, s: StatusCode) {
        self.record_wire(s.as_u32());
    }

    /// Counts one status given by its wire value (unknown values share the last slot).
    pub fn record_wire(&mut self, code: u32) {
        self.counts[(code as usize).min(STATUS_SLOTS - 1)] += 1;
    }

    /// Adds the counts of `other`.
    pub fn merge(&mut self, other: &StatusHistogram) {
        for (a, b) in self.counts.iter_mut().zip(other.counts) {
            *a += b;
        }
    }

    /// Count of status `s`.
    pub fn count(&self, s: StatusCode) -> u64 {
        self.counts[(s.as_u32() as usize).min(STATUS_SLOTS - 1)]
    }

    /// All counts, index = wire value.
    pub fn counts(&self) -> &[u64; STATUS_SLOTS] {
        &self.counts
    }

    /// Total count.
    pub fn total(&self) -> u64 {
        self.counts.iter().sum()
    }

    /// `(wire value, count)` of every status seen, in wire-value order.
    pub fn nonzero(&self) -> impl Iterator<Item = (u32, u64)> + '_ {
        self.counts
            .iter()
            .enumerate()
            .filter(|&(_, &c)| c > 0)
            .map(|(i, &c)| (i as u32, c))
    }

    /// `"ok 970, outside_workspace 30"`: every status seen, in wire-value order.
    pub fn summary(&self) -> String {
        self.summary_where(|_| true)
    }

    /// As [`summary`](Self::summary) without `ok`: `""` when every status was ok.
    pub fn summary_not_ok(&self) -> String {
        self.summary_where(|code| code != StatusCode::Ok.as_u32())
    }

    fn summary_where(&self, keep: impl Fn(u32) -> bool) -> String {
        self.nonzero()
            .filter(|&(code, _)| keep(code))
            .map(|(code, c)| format!("{} {c}", status_str(code)))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The `q`-quantile (0 ≤ q ≤ 1) of an ascending sample, by the nearest-rank rule every
/// percentile of this crate uses: the element at index `round((n − 1) q)`. 0 when empty.
pub fn percentile(sorted: &[u64], q: f64) -> u64 {
    if sorted.is_empty() {
        return 0;
    }
    let i = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

/// Percentiles of a set of durations (ns): p50, p99, p99.9 and max.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Percentiles {
    /// Number of samples the percentiles are taken over.
    pub count: usize,
    /// Median, ns.
    pub p50_ns: u64,
    /// 99th percentile, ns.
    pub p99_ns: u64,
    /// 99.9th percentile, ns.
    pub p999_ns: u64,
    /// Largest sample, ns.
    pub max_ns: u64,
}

impl Percentiles {
    /// Percentiles of `samples` (reordered in place; no allocation). Nearest-rank on the
    /// sorted sample: index `round((n − 1) q)`. All zero for an empty slice.
    pub fn of(samples: &mut [u64]) -> Percentiles {
        let n = samples.len();
        if n == 0 {
            return Percentiles::default();
        }
        let rank = |q: f64| (((n - 1) as f64) * q).round() as usize;
        // select_nth_unstable leaves everything above the pivot to its right, so successive
        // selections on the right part give increasing quantiles.
        let i50 = rank(0.5);
        let i99 = rank(0.99).max(i50);
        let i999 = rank(0.999).max(i99);
        let (_, p50, right) = samples.select_nth_unstable(i50);
        let p50 = *p50;
        let mut p99 = p50;
        if i99 > i50 {
            let (_, v, _) = right.select_nth_unstable(i99 - i50 - 1);
            p99 = *v;
        }
        let mut p999 = p99;
        if i999 > i99 {
            let (_, v, _) = samples[i99 + 1..].select_nth_unstable(i999 - i99 - 1);
            p999 = *v;
        }
        let max = samples[i999..].iter().copied().max().unwrap_or(p999);
        Percentiles {
            count: n,
            p50_ns: p50,
            p99_ns: p99,
            p999_ns: p999,
            max_ns: max,
        }
    }

    /// `p50 … µs  p99 … µs  p99.9 … µs  max … µs` for a log or a report.
    pub fn display_us(&self) -> String {
        format!(
            "p50 {:.1} µs  p99 {:.1} µs  p99.9 {:.1} µs  max {:.1} µs",
            self.p50_ns as f64 / 1e3,
            self.p99_ns as f64 / 1e3,
            self.p999_ns as f64 / 1e3,
            self.max_ns as f64 / 1e3
        )
    }
}

/// A ring of the most recent `capacity` durations (ns), with a scratch buffer of the same size
/// for percentiles: both allocated in [`Ring::new`], never again.
#[derive(Debug, Clone)]
pub struct Ring {
    data: Vec<u64>,
    scratch: Vec<u64>,
    next: usize,
    len: usize,
}

impl Ring {
    /// A ring holding up to `capacity` samples (at least 1).
    pub fn new(capacity: usize) -> Ring {
        let capacity = capacity.max(1);
        Ring {
            data: vec![0; capacity],
            scratch: vec![0; capacity],
            next: 0,
            len: 0,
        }
    }

    /// Adds a sample, overwriting the oldest when full.
    #[inline]
    pub fn push(&mut self, v: u64) {
        let cap = self.data.len();
        self.data[self.next] = v;
        self.next = if self.next + 1 == cap {
            0
        } else {
            self.next + 1
        };
        self.len = (self.len + 1).min(cap);
    }

    /// Number of samples held.
    pub fn len(&self) -> usize {
        self.len
    }

    /// No samples held.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Forgets every sample.
    pub fn clear(&mut self) {
        self.next = 0;
        self.len = 0;
    }

    /// Percentiles of the samples held (no allocation).
    pub fn percentiles(&mut self) -> Percentiles {
        let n = self.len;
        let cap = self.data.len();
        let s = &mut self.scratch[..n];
        if n < cap {
            s.copy_from_slice(&self.data[..n]);
        } else {
            s.copy_from_slice(&self.data);
        }
        Percentiles::of(s)
    }
}

/// Every sample of a run, up to a capacity fixed at construction (later ones are counted but
/// not kept).
#[derive(Debug, Clone)]
pub struct SampleLog {
    data: Vec<u64>,
    dropped: u64,
}

impl SampleLog {
    /// Room for `capacity` samples.
    pub fn with_capacity(capacity: usize) -> SampleLog {
        SampleLog {
            data: Vec::with_capacity(capacity),
            dropped: 0,
        }
    }

    /// Records a sample (never reallocates: beyond the capacity it is counted as dropped).
    #[inline]
    pub fn push(&mut self, v: u64) {
        if self.data.len() < self.data.capacity() {
            self.data.push(v);
        } else {
            self.dropped += 1;
        }
    }

    /// Samples recorded.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// Nothing recorded.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Samples that did not fit.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// The samples in recording order.
    pub fn samples(&self) -> &[u64] {
        &self.data
    }

    /// Percentiles of every recorded sample (sorts a copy).
    pub fn percentiles(&self) -> Percentiles {
        let mut v = self.data.clone();
        Percentiles::of(&mut v)
    }
}

/// The largest forward step of one sender's sequence taken as messages lost, 2²⁰ (~10⁶):
/// the poses a sender can send between two drains of the service (a drain at least every
/// 50 ms in event mode, continuously when spinning) beyond the queue's 16: 10⁶ is a stall of
/// one second at 1 MHz, far beyond any pose rate and stall seen. A larger step is not a loss
/// but a sender that jumped its counter (hostile or broken): counted as a reset.
pub const SEQUENCE_GAP_WINDOW: u64 = 1 << 20;

/// The fastest a sender can send, poses per second, for [`SequenceGaps`]' budget: 10⁷ (one
/// pose per 100 ns), above what one iceoryx2 publisher can loan, write and send.
pub const SEQUENCE_MAX_RATE_PER_S: u64 = 10_000_000;

/// Losses a sender may have besides its rate budget: the poses it can queue after its first
/// received one before that one is read (the service's pose queue,
/// `service::ports::POSE_BUFFER`). [`SequenceGaps::with_queue_slack`] sets another (a recorder's
/// longer queue).
pub const SEQUENCE_QUEUE_SLACK: u64 = 16;

/// Poses lost in a queue, counted from the senders' sequence numbers. Every sender increments
/// its sequence by one per message, so a gap between two consecutive sequences received from
/// the same sender (`key`: iceoryx2's publisher id in the service) is that many messages that
/// were sent to us and never received: overwritten in the subscriber queue (safe overflow).
///
/// - The first sequence of a sender counts nothing (what it sent before we were connected
///   never reached our queue). A restarted sender is a new key, so its sequence starting
///   again from 1 (or anywhere) is never compared with its predecessor's.
/// - Gaps count only forward and within [`SEQUENCE_GAP_WINDOW`]. A sequence not above the
///   last one of the same key (a duplicate, or a sender that restarted its counter on the
///   same port), or more than the window above it (a jump), counts no loss: it is a *reset*
///   (counted per sender and in total) and becomes the new base, so the next gap is measured
///   from there. iceoryx2 delivers one publisher's samples in order, so an honest sender
///   never resets; a hostile one (sequences 1, 2⁶³, 1, …) adds at most the window per
///   message to its own count and nothing to any other sender's.
/// - A sender's losses are bounded by what it can have sent: at most
///   [`SEQUENCE_QUEUE_SLACK`] + [`SEQUENCE_MAX_RATE_PER_S`] × the time since its first
///   received sequence. A forward step past that budget is a reset too. So one hostile
///   sender adds at most 16 + 10⁷ per second connected to the total, not a window per
///   message (2²⁰ per message, before), and nothing to another sender's count.
/// - Up to `N` senders are tracked, each with its own counts; a new one beyond that replaces
///   the one heard from least recently (its next sample then counts as a first).
///
/// Fixed capacity, no allocation, O(N) per message.
#[derive(Debug, Clone, Copy)]
pub struct SequenceGaps<K: Copy + Eq, const N: usize> {
    senders: [Option<Sender<K>>; N],
    /// The losses a sender may have besides its rate budget ([`SEQUENCE_QUEUE_SLACK`] by
    /// default).
    queue_slack: u64,
    /// Messages received (any key), for the least-recently-heard eviction.
    clock: u64,
    /// Messages missing between consecutive sequences of one sender, in total.
    lost: u64,
    /// Times a sender's sequence did not advance or jumped past the window, in total.
    resets: u64,
}

/// One tracked sender of [`SequenceGaps`].
#[derive(Debug, Clone, Copy)]
struct Sender<K> {
    key: K,
    /// The first and the last sequence received.
    first: u64,
    last: u64,
    /// When last heard from, in `clock` ticks.
    heard: u64,
    /// When its first sequence was received, ns (monotonic).
    first_ns: u64,
    /// Its messages received, lost and its resets.
    received: u64,
    lost: u64,
    resets: u64,
}

/// One sender's counts in [`SequenceGaps`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SenderCounts<K> {
    /// The sender.
    pub key: K,
    /// The first sequence received from it while tracked.
    pub first: u64,
    /// The last sequence received from it.
    pub last: u64,
    /// Its messages received while tracked.
    pub received: u64,
    /// Its messages missing between consecutive sequences (overwritten).
    pub lost: u64,
    /// Its resets (a sequence back, repeated, or past the window or the budget).
    pub resets: u64,
}

impl<K: Copy + Eq, const N: usize> Default for SequenceGaps<K, N> {
    fn default() -> Self {
        SequenceGaps {
            senders: [None; N],
            queue_slack: SEQUENCE_QUEUE_SLACK,
            clock: 0,
            lost: 0,
            resets: 0,
        }
    }
}

impl<K: Copy + Eq, const N: usize> SequenceGaps<K, N> {
    /// No sender yet; a sender may lose `queue_slack` messages besides its rate budget (the
    /// subscriber's queue length).
    pub fn with_queue_slack(queue_slack: u64) -> Self {
        SequenceGaps {
            queue_slack,
            ..SequenceGaps::default()
        }
    }

    /// Records sequence `seq` received from sender `key` at `now_ns` (monotonic); returns
    /// how many of that sender's messages are missing just before it (0 when it follows the
    /// previous one, is the sender's first, or is a reset: not above the last, or a jump past
    /// [`SEQUENCE_GAP_WINDOW`] or past the sender's budget).
    pub fn record(&mut self, key: K, seq: u64, now_ns: u64) -> u64 {
        self.clock += 1;
        let now = self.clock;
        let Some(slot) = self
            .senders
            .iter()
            .position(|s| s.is_some_and(|s| s.key == key))
        else {
            // A free slot, else the sender heard from least recently.
            let i = self
                .senders
                .iter()
                .enumerate()
                .min_by_key(|(_, s)| s.map_or(0, |s| s.heard))
                .map_or(0, |(i, _)| i);
            if let Some(slot) = self.senders.get_mut(i) {
                *slot = Some(Sender {
                    key,
                    first: seq,
                    last: seq,
                    heard: now,
                    first_ns: now_ns,
                    received: 1,
                    lost: 0,
                    resets: 0,
                });
            }
            return 0;
        };
        let Some(s) = self.senders[slot].as_mut() else {
            return 0;
        };
        let last = s.last;
        s.last = seq;
        s.heard = now;
        s.received += 1;
        let budget = (self.queue_slack
            + now_ns.saturating_sub(s.first_ns) / (1_000_000_000 / SEQUENCE_MAX_RATE_PER_S))
            .saturating_sub(s.lost);
        if seq > last && seq - last - 1 <= SEQUENCE_GAP_WINDOW.min(budget) {
            let gap = seq - last - 1;
            s.lost = s.lost.saturating_add(gap);
            self.lost = self.lost.saturating_add(gap);
            gap
        } else {
            s.resets += 1;
            self.resets += 1;
            0
        }
    }

    /// Messages missing between consecutive sequences, in total.
    pub fn lost(&self) -> u64 {
        self.lost
    }

    /// Resets in total: a sender's sequence did not advance (duplicates, counter restarts) or
    /// jumped past [`SEQUENCE_GAP_WINDOW`].
    pub fn resets(&self) -> u64 {
        self.resets
    }

    /// The counts of every tracked sender.
    pub fn senders(&self) -> impl Iterator<Item = SenderCounts<K>> + '_ {
        self.senders.iter().flatten().map(|s| SenderCounts {
            key: s.key,
            first: s.first,
            last: s.last,
            received: s.received,
            lost: s.lost,
            resets: s.resets,
        })
    }

    /// (messages lost, resets) of sender `key` while tracked (None when it is not).
    pub fn of(&self, key: K) -> Option<(u64, u64)> {
        self.senders
            .iter()
            .flatten()
            .find(|s| s.key == key)
            .map(|s| (s.lost, s.resets))
    }
}

/// What [`GapDetector`] saw at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GapEvent {
    /// An outage started: nothing for `silent_ns` (≥ the threshold) since the last message.
    Started {
        /// Time since the last message, ns.
        silent_ns: u64,
    },
    /// Messages resumed after an outage that lasted `duration_ns` (last message before it →
    /// first message after it).
    Ended {
        /// Time without messages, ns.
        duration_ns: u64,
    },
}

/// Outages of a periodic stream (e.g. the estimates at 1 kHz): no message for at least
/// `threshold_ns`. Fed the time of every message ([`GapDetector::on_message`]) and polled
/// while waiting ([`GapDetector::poll`]); each outage is reported once when it starts and
/// once when it ends, and counted (number, longest, total). Nothing is an outage before the
/// first message. No allocation.
#[derive(Debug, Clone, Copy)]
pub struct GapDetector {
    threshold_ns: u64,
    last_ns: Option<u64>,
    in_outage: bool,
    outages: u64,
    longest_ns: u64,
    total_ns: u64,
}

impl GapDetector {
    /// An outage is `threshold_ns` or more without a message.
    pub fn new(threshold_ns: u64) -> GapDetector {
        GapDetector {
            threshold_ns: threshold_ns.max(1),
            last_ns: None,
            in_outage: false,
            outages: 0,
            longest_ns: 0,
            total_ns: 0,
        }
    }

    /// The outage threshold, ns.
    pub fn threshold_ns(&self) -> u64 {
        self.threshold_ns
    }

    /// No message received yet at `now_ns`: reports the start of an outage once.
    pub fn poll(&mut self, now_ns: u64) -> Option<GapEvent> {
        let last = self.last_ns?;
        let silent_ns = now_ns.saturating_sub(last);
        if !self.in_outage && silent_ns >= self.threshold_ns {
            self.in_outage = true;
            return Some(GapEvent::Started { silent_ns });
        }
        None
    }

    /// A message received at `now_ns`. Reports the end of an outage (which it also counts;
    /// a gap of at least the threshold that no poll saw start counts as well, with no start
    /// reported: [`GapEvent::Ended`] is returned all the same).
    pub fn on_message(&mut self, now_ns: u64) -> Option<GapEvent> {
        let event = self.last_ns.and_then(|last| {
            let duration_ns = now_ns.saturating_sub(last);
            if self.in_outage || duration_ns >= self.threshold_ns {
                self.record(duration_ns);
                Some(GapEvent::Ended { duration_ns })
            } else {
                None
            }
        });
        self.in_outage = false;
        self.last_ns = Some(now_ns);
        event
    }

    /// Ends the observation at `now_ns`: an outage still going on is counted (up to now).
    pub fn finish(&mut self, now_ns: u64) {
        if let Some(last) = self.last_ns {
            let silent_ns = now_ns.saturating_sub(last);
            if self.in_outage || silent_ns >= self.threshold_ns {
                self.record(silent_ns);
            }
            self.in_outage = false;
            self.last_ns = Some(now_ns);
        }
    }

    fn record(&mut self, duration_ns: u64) {
        self.outages += 1;
        self.longest_ns = self.longest_ns.max(duration_ns);
        self.total_ns += duration_ns;
    }

    /// Outages counted (ended, or cut by [`GapDetector::finish`]).
    pub fn outages(&self) -> u64 {
        self.outages
    }

    /// The longest outage, ns (0 without any).
    pub fn longest_ns(&self) -> u64 {
        self.longest_ns
    }

    /// All outages together, ns.
    pub fn total_ns(&self) -> u64 {
        self.total_ns
    }

    /// Whether an outage is going on (started, not ended).
    pub fn in_outage(&self) -> bool {
        self.in_outage
    }
}

#[cfg(test)]
mod tests;
