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
/// received one before that one is read (the pose queue, `service::ports::POSE_BUFFER`).
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
    /// The last sequence received.
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
            clock: 0,
            lost: 0,
            resets: 0,
        }
    }
}

impl<K: Copy + Eq, const N: usize> SequenceGaps<K, N> {
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
        let budget = (SEQUENCE_QUEUE_SLACK
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
mod tests {
    use super::*;

    fn naive(v: &[u64], q: f64) -> u64 {
        let mut s = v.to_vec();
        s.sort_unstable();
        percentile(&s, q)
    }

    #[test]
    fn percentile_is_nearest_rank() {
        assert_eq!(percentile(&[], 0.5), 0);
        assert_eq!(percentile(&[7], 0.99), 7);
        assert_eq!(percentile(&[1, 2, 3, 4], 0.5), 3); // round(1.5) = 2
        assert_eq!(percentile(&[1, 2, 3, 4], 1.0), 4);
        assert_eq!(percentile(&[1, 2, 3, 4], 0.0), 1);
    }

    #[test]
    fn status_histogram_counts_and_names() {
        let mut h = StatusHistogram::default();
        h.record(StatusCode::Ok);
        h.record(StatusCode::Ok);
        h.record(StatusCode::OutsideWorkspace);
        h.record_wire(1000);
        let mut g = StatusHistogram::default();
        g.record(StatusCode::OutsideWorkspace);
        h.merge(&g);
        assert_eq!(h.total(), 5);
        assert_eq!(h.count(StatusCode::OutsideWorkspace), 2);
        assert_eq!(h.counts()[STATUS_SLOTS - 1], 1);
        assert!(
            h.summary().starts_with("ok 2, outside_workspace 2"),
            "{}",
            h.summary()
        );
        assert!(!h.summary_not_ok().contains("ok 2"));
        assert_eq!(StatusHistogram::default().summary_not_ok(), "");
    }

    #[test]
    fn percentiles_match_sorting() {
        let mut x: u64 = 12345;
        for n in [1usize, 2, 3, 10, 999, 1000, 1001, 5000] {
            let v: Vec<u64> = (0..n)
                .map(|_| {
                    x = x
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    x >> 40
                })
                .collect();
            let p = Percentiles::of(&mut v.clone());
            assert_eq!(p.count, n);
            assert_eq!(p.p50_ns, naive(&v, 0.5), "n = {n}");
            assert_eq!(p.p99_ns, naive(&v, 0.99), "n = {n}");
            assert_eq!(p.p999_ns, naive(&v, 0.999), "n = {n}");
            assert_eq!(p.max_ns, *v.iter().max().unwrap(), "n = {n}");
        }
        assert_eq!(Percentiles::of(&mut []), Percentiles::default());
    }

    #[test]
    fn ring_keeps_the_most_recent() {
        let mut r = Ring::new(4);
        assert!(r.is_empty());
        for v in 1..=10 {
            r.push(v);
        }
        assert_eq!(r.len(), 4);
        let p = r.percentiles();
        assert_eq!((p.count, p.max_ns), (4, 10));
        assert_eq!(p.p50_ns, naive(&[7, 8, 9, 10], 0.5));
        r.clear();
        r.push(3);
        assert_eq!(r.percentiles().max_ns, 3);
    }

    #[test]
    fn sample_log_never_grows() {
        let mut l = SampleLog::with_capacity(3);
        for v in 0..5 {
            l.push(v);
        }
        assert_eq!((l.len(), l.dropped()), (3, 2));
        assert_eq!(l.samples(), &[0, 1, 2]);
    }

    /// A sender's first message at 0, the later ones of the simple cases 1 s later (a budget
    /// of 10⁷ poses, larger than any gap they make).
    const NOW: u64 = 0;
    const SEC: u64 = 1_000_000_000;

    #[test]
    fn sequence_gaps_in_order_count_nothing() {
        let mut g = SequenceGaps::<u32, 4>::default();
        for seq in 1..=1000 {
            assert_eq!(g.record(7, seq, NOW), 0);
        }
        assert_eq!((g.lost(), g.resets()), (0, 0));
    }

    #[test]
    fn sequence_gaps_count_the_missing_sequences() {
        let mut g = SequenceGaps::<u32, 4>::default();
        assert_eq!(
            g.record(7, 5, NOW),
            0,
            "a sender's first sequence counts nothing"
        );
        assert_eq!(g.record(7, 6, SEC), 0);
        assert_eq!(g.record(7, 10, SEC), 3, "7, 8, 9 never received");
        assert_eq!(g.record(7, 11, SEC), 0);
        assert_eq!(g.record(7, 1011, SEC), 999);
        assert_eq!(g.lost(), 1002);
    }

    #[test]
    fn sequence_gaps_duplicates_and_steps_back_count_nothing() {
        let mut g = SequenceGaps::<u32, 4>::default();
        for seq in [1, 2, 2, 3, 1, 2, 3, 4] {
            g.record(7, seq, NOW);
        }
        assert_eq!(g.lost(), 0, "a duplicate or a step back is no loss");
        assert_eq!(g.resets(), 2);
        // Out of order: 4 missing at 5, then 4 late: it re-bases, and 5 follows it.
        let mut g = SequenceGaps::<u32, 4>::default();
        for seq in [1, 2, 3, 5, 4, 5, 6] {
            g.record(7, seq, NOW);
        }
        assert_eq!(g.lost(), 1);
    }

    #[test]
    fn sequence_gaps_a_restart_is_no_huge_gap() {
        // Same key, counter back to 1 after a long run: nothing, and the next gap is measured
        // from the new base, not from the old one.
        let mut g = SequenceGaps::<u32, 4>::default();
        g.record(7, 1_000_000, NOW);
        assert_eq!(g.record(7, 1, SEC), 0);
        assert_eq!(g.record(7, 2, SEC), 0);
        assert_eq!(g.record(7, 4, SEC), 1);
        assert_eq!(g.lost(), 1);
        // A restarted sender is a new key: a large first sequence is not compared with the
        // old sender's, nor is a small one.
        let mut g = SequenceGaps::<u32, 4>::default();
        g.record(1, 10, NOW);
        assert_eq!(
            g.record(2, u64::MAX - 1, NOW),
            0,
            "new sender, large first sequence"
        );
        assert_eq!(g.record(2, u64::MAX, SEC), 0);
        assert_eq!(g.record(3, 1, NOW), 0);
        assert_eq!(
            g.record(1, 11, SEC),
            0,
            "each sender against its own sequence"
        );
        assert_eq!(g.record(3, 3, SEC), 1);
        assert_eq!(g.lost(), 1);
    }

    /// A hostile sender (sequences 1, 2⁶³, 1, …, u64::MAX, 0, random) counts resets, never
    /// a wrap-around loss (before: "overwritten poses 9223372036854775802"), and leaves an
    /// honest sender's count exact over 10⁵ messages: received + lost = the sequences it sent
    /// from its first received one on, counted independently by the sender loop.
    #[test]
    fn sequence_gaps_hostile_sequences_leave_another_senders_count_exact() {
        let mut g = SequenceGaps::<u32, 4>::default();
        let (mut received, mut first) = (0u64, None);
        let mut honest_seq = 0u64;
        let mut rng = 0x9e37_79b9_7f4a_7c15u64;
        let mut hostile_lost = 0u64;
        for i in 0..100_000u64 {
            // 2 µs per round: the honest sender's burst of at most 20 is 10⁷ per second, the
            // budget's rate.
            let now = i * 2_000;
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            let h = match i % 6 {
                0 | 2 => 1,
                1 => 1 << 63,
                3 => u64::MAX,
                4 => 0,
                _ => rng,
            };
            hostile_lost += g.record(9, h, now);
            // Honest: sends 1 to 20 poses; the queue lets the last 1 to 3 of them through.
            let burst = 1 + rng % 20;
            honest_seq += burst;
            for k in (0..burst.min(1 + (rng >> 32) % 3)).rev() {
                let seq = honest_seq - k;
                first.get_or_insert(seq);
                let _ = g.record(7, seq, now);
                received += 1;
            }
        }
        let (lost, resets) = g.of(7).unwrap();
        assert_eq!(resets, 0, "an honest sender never resets");
        let sent_from_first = honest_seq - first.unwrap() + 1;
        assert_eq!(received + lost, sent_from_first);
        let (h_lost, h_resets) = g.of(9).unwrap();
        assert_eq!(h_lost, hostile_lost);
        assert!(h_resets > 60_000, "{h_resets}");
        // Only the random forward steps within the budget count: at most the slack and the
        // rate over the 0.2 s of the run.
        assert!(
            h_lost <= SEQUENCE_QUEUE_SLACK + 200_000_000 / 100,
            "{h_lost}"
        );
        assert_eq!(g.lost(), lost + h_lost);
        assert_eq!(g.resets(), h_resets);
        // The reported case: 1, 2⁶³, 1 is two resets and no loss.
        let mut g = SequenceGaps::<u32, 4>::default();
        for seq in [1, 1 << 63, 1] {
            assert_eq!(g.record(3, seq, NOW), 0);
        }
        assert_eq!((g.lost(), g.resets()), (0, 2));
        // Within the window a step is a loss; one past it is a reset.
        assert_eq!(
            g.record(3, 2 + SEQUENCE_GAP_WINDOW, SEC),
            SEQUENCE_GAP_WINDOW
        );
        assert_eq!(g.record(3, 3 + 2 * SEQUENCE_GAP_WINDOW + 1, SEC), 0);
        assert_eq!(g.resets(), 3);
    }

    /// A sender stepping its sequence forward by the window on every message (1 µs apart)
    /// counted 2²⁰ lost poses per message, 10¹¹ over 10⁵ messages, in the service's total;
    /// now its losses stay within its budget (16 + 10⁷ per second since its first message:
    /// ~10⁶ here), the steps past it are resets, and another sender's count is untouched.
    #[test]
    fn sequence_gaps_one_sender_cannot_inflate_the_total() {
        let mut g = SequenceGaps::<u32, 4>::default();
        let (mut seq, mut honest) = (0u64, 0u64);
        for i in 0..100_000u64 {
            let now = i * 1_000;
            seq += SEQUENCE_GAP_WINDOW + 1;
            g.record(9, seq, now);
            honest += 1;
            assert_eq!(g.record(7, honest, now), 0);
        }
        let elapsed_ns = 99_999 * 1_000;
        let (lost, resets) = g.of(9).unwrap();
        assert!(lost <= SEQUENCE_QUEUE_SLACK + elapsed_ns / 100, "{lost}");
        assert!(resets > 99_000, "{resets}");
        assert_eq!(g.of(7), Some((0, 0)));
        assert_eq!(g.lost(), lost);
    }

    #[test]
    fn sequence_gaps_evict_the_least_recent_sender() {
        let mut g = SequenceGaps::<u32, 2>::default();
        g.record(1, 1, NOW);
        g.record(2, 1, NOW);
        g.record(1, 2, NOW);
        g.record(3, 100, NOW); // replaces sender 2, heard from least recently
        assert_eq!(g.record(1, 3, NOW), 0, "sender 1 is still tracked");
        assert_eq!(
            g.record(2, 50, NOW),
            0,
            "sender 2 starts over: a first sequence"
        );
        assert_eq!(g.lost(), 0);
    }

    const MS: u64 = 1_000_000;

    #[test]
    fn gap_detector_reports_an_outage_once_at_start_and_at_end() {
        let mut d = GapDetector::new(100 * MS);
        assert_eq!(
            d.poll(10_000 * MS),
            None,
            "nothing before the first message"
        );
        for t in 0..1000 {
            assert_eq!(d.on_message(t * MS), None);
            assert_eq!(d.poll(t * MS + MS / 2), None);
        }
        // Last message at 999 ms; silence until 4300 ms.
        assert_eq!(d.poll(1098 * MS), None);
        assert_eq!(
            d.poll(1099 * MS),
            Some(GapEvent::Started {
                silent_ns: 100 * MS
            })
        );
        assert!(d.in_outage());
        for t in 1100..4300 {
            assert_eq!(d.poll(t * MS), None, "one line per outage start");
        }
        assert_eq!(
            d.on_message(4300 * MS),
            Some(GapEvent::Ended {
                duration_ns: 3301 * MS
            })
        );
        assert_eq!(d.on_message(4301 * MS), None);
        // A second, shorter one that no poll saw start.
        assert_eq!(
            d.on_message(4501 * MS),
            Some(GapEvent::Ended {
                duration_ns: 200 * MS
            })
        );
        // Jitter below the threshold is no outage.
        assert_eq!(d.on_message(4600 * MS), None);
        d.finish(4650 * MS);
        assert_eq!(d.outages(), 2);
        assert_eq!(d.longest_ns(), 3301 * MS);
        assert_eq!(d.total_ns(), 3501 * MS);
        // An outage still going on at the end is counted up to then.
        d.poll(4800 * MS);
        d.finish(5000 * MS);
        assert_eq!((d.outages(), d.longest_ns()), (3, 3301 * MS));
        assert_eq!(d.total_ns(), 3501 * MS + 350 * MS);
    }
}
