//! Fixed-capacity sample buffers, percentiles and status histograms that never allocate
//! after construction. The one place percentiles and status counts are computed: the
//! service, the benchmarks and the offline sweeps all use it.

use cablevib_ipc::{status_str, StatusCode};

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
}
