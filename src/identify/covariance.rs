//! Output covariances at lags, accumulated sample by sample in memory independent of the
//! record's length.
//!
//! For lags i = 0 … L − 1 the accumulator keeps, per segment of the window, the direct sums
//! over the sample pairs (y_k, y_{k−i}) of one contiguous run (a gap or a non-finite sample
//! starts a new run, so no product straddles it):
//!
//! ```text
//!   S_i = Σ y_k y_{k−i}ᵀ,   A_i = Σ y_k,   B_i = Σ y_{k−i},   n_i = number of pairs
//! ```
//!
//! (the pair belongs to the segment of its later sample). The covariance of any set of
//! segments about the set's mean μ is then exact:
//!
//! ```text
//!   R_i = (S_i − A_i μᵀ − μ B_iᵀ + n_i μ μᵀ) / n_i        (R_i = E[y_k y_{k−i}ᵀ])
//! ```
//!
//! A sample costs L (l² + 2l) multiply-adds for l channels. The segments are time slices of
//! equal duration; their number stays between `target` and 2 × `target` (two neighbours merge
//! and the duration doubles when it would exceed that), so a window of unknown length (the
//! whole record) is segmented as evenly as a known one.

/// The sums of one segment.
#[derive(Debug, Clone)]
struct Segment {
    /// S_i, row-major l × l per lag.
    s: Vec<f64>,
    /// A_i (l per lag).
    a: Vec<f64>,
    /// B_i (l per lag).
    b: Vec<f64>,
    /// n_i.
    n: Vec<u64>,
    /// Σ y and the sample count (for the mean).
    sum: Vec<f64>,
    count: u64,
}

impl Segment {
    fn new(lags: usize, l: usize) -> Segment {
        Segment {
            s: vec![0.0; lags * l * l],
            a: vec![0.0; lags * l],
            b: vec![0.0; lags * l],
            n: vec![0; lags],
            sum: vec![0.0; l],
            count: 0,
        }
    }

    fn add(&mut self, o: &Segment) {
        let add = |x: &mut [f64], y: &[f64]| x.iter_mut().zip(y).for_each(|(a, b)| *a += b);
        add(&mut self.s, &o.s);
        add(&mut self.a, &o.a);
        add(&mut self.b, &o.b);
        add(&mut self.sum, &o.sum);
        self.n.iter_mut().zip(&o.n).for_each(|(a, b)| *a += b);
        self.count += o.count;
    }
}

/// Lag products of one window, segmented.
#[derive(Debug, Clone)]
pub struct LagCovariance {
    l: usize,
    lags: usize,
    /// The last `lags` samples, doubled: `ring[(pos + i) l ..]` is y_{k−i}.
    ring: Vec<f64>,
    pos: usize,
    /// Samples of the current contiguous run.
    run: usize,
    segments: Vec<Segment>,
    t0_s: f64,
    segment_s: f64,
    target: usize,
}

/// Covariances R_0 … R_{L−1} of a set of segments (row-major l × l each) and their sample
/// count.
#[derive(Debug, Clone, PartialEq)]
pub struct Covariances {
    /// Channels.
    pub channels: usize,
    /// R_i, lag-major, row-major l × l.
    pub r: Vec<f64>,
    /// Samples in the set.
    pub samples: u64,
}

impl Covariances {
    /// Entry (a, b) of R_i.
    pub fn at(&self, i: usize, a: usize, b: usize) -> f64 {
        let l = self.channels;
        self.r[(i * l + a) * l + b]
    }
}

impl LagCovariance {
    /// An accumulator of `lags` lags (0 … lags − 1) for `l` channels, starting at `t0_s`,
    /// with `target` segments of about `segment_s` each.
    pub fn new(l: usize, lags: usize, t0_s: f64, segment_s: f64, target: usize) -> LagCovariance {
        LagCovariance {
            l,
            lags,
            ring: vec![0.0; 2 * lags * l],
            pos: 0,
            run: 0,
            segments: Vec::new(),
            t0_s,
            segment_s: segment_s.max(f64::MIN_POSITIVE),
            target: target.max(1),
        }
    }

    /// A gap: the next sample starts a new run.
    pub fn break_run(&mut self) {
        self.run = 0;
    }

    /// Samples taken.
    pub fn samples(&self) -> u64 {
        self.segments.iter().map(|s| s.count).sum()
    }

    /// Segments so far.
    pub fn segments(&self) -> usize {
        self.segments.len()
    }

    /// Take the sample `y` at `t_s`.
    pub fn push(&mut self, t_s: f64, y: &[f64]) {
        let (l, lags) = (self.l, self.lags);
        let mut k = ((t_s - self.t0_s) / self.segment_s).floor().max(0.0) as usize;
        while k >= 2 * self.target {
            self.merge_pairs();
            k = ((t_s - self.t0_s) / self.segment_s).floor().max(0.0) as usize;
        }
        while self.segments.len() <= k {
            self.segments.push(Segment::new(lags, l));
        }
        self.pos = (self.pos + lags - 1) % lags;
        let p = self.pos;
        self.ring[p * l..(p + 1) * l].copy_from_slice(&y[..l]);
        self.ring[(p + lags) * l..(p + lags + 1) * l].copy_from_slice(&y[..l]);
        self.run += 1;
        let m = self.run.min(lags);
        let seg = &mut self.segments[k];
        for (s, &v) in seg.sum.iter_mut().zip(y) {
            *s += v;
        }
        seg.count += 1;
        let hist = &self.ring[p * l..(p + m) * l];
        for i in 0..m {
            let z = &hist[i * l..(i + 1) * l];
            let s = &mut seg.s[i * l * l..(i + 1) * l * l];
            for a in 0..l {
                let ya = y[a];
                let row = &mut s[a * l..(a + 1) * l];
                for b in 0..l {
                    row[b] += ya * z[b];
                }
            }
            for a in 0..l {
                seg.a[i * l + a] += y[a];
                seg.b[i * l + a] += z[a];
            }
            seg.n[i] += 1;
        }
    }

    fn merge_pairs(&mut self) {
        let old = std::mem::take(&mut self.segments);
        let mut it = old.into_iter();
        while let Some(mut a) = it.next() {
            if let Some(b) = it.next() {
                a.add(&b);
            }
            self.segments.push(a);
        }
        self.segment_s *= 2.0;
    }

    /// The jackknife's groups: the segments dealt into at most `groups` contiguous groups of
    /// nearly equal count (empty segments skipped).
    pub fn groups(&self, groups: usize) -> Vec<std::ops::Range<usize>> {
        let n = self.segments.len();
        let g = groups.min(n).max(1);
        (0..g).map(|j| (j * n / g)..((j + 1) * n / g)).collect()
    }

    /// The covariances of every segment except those in `leave_out`; `None` when a lag has
    /// no pair.
    pub fn covariances(&self, leave_out: std::ops::Range<usize>) -> Option<Covariances> {
        let (l, lags) = (self.l, self.lags);
        let mut t = Segment::new(lags, l);
        for (k, s) in self.segments.iter().enumerate() {
            if !leave_out.contains(&k) {
                t.add(s);
            }
        }
        if t.count == 0 || t.n.contains(&0) {
            return None;
        }
        let mu: Vec<f64> = t.sum.iter().map(|s| s / t.count as f64).collect();
        let mut r = vec![0.0; lags * l * l];
        for i in 0..lags {
            let n = t.n[i] as f64;
            for a in 0..l {
                for b in 0..l {
                    let s = t.s[(i * l + a) * l + b];
                    r[(i * l + a) * l + b] = (s - t.a[i * l + a] * mu[b] - mu[a] * t.b[i * l + b]
                        + n * mu[a] * mu[b])
                        / n;
                }
            }
        }
        Some(Covariances {
            channels: l,
            r,
            samples: t.count,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The accumulated covariances equal the two-pass definition (mean first, then the
    /// products within each contiguous run), with a gap and segment merges on the way.
    #[test]
    fn equals_two_pass_definition() {
        let l = 2;
        let lags = 5;
        let mut c = LagCovariance::new(l, lags, 0.0, 0.01, 2);
        let mut ys = Vec::new();
        let mut runs = vec![0usize];
        for k in 0..300 {
            let y = [
                (k as f64 * 0.37).sin() + 3.0,
                (k as f64 * 0.11).cos() - 1.0 + (k % 7) as f64 * 0.1,
            ];
            if k == 150 {
                c.break_run();
                runs.push(k);
            }
            c.push(k as f64 * 0.001, &y);
            ys.push(y);
        }
        assert!(c.segments() <= 4 && c.segments() >= 2);
        let got = c.covariances(0..0).unwrap();
        let n = ys.len() as f64;
        let mu = [
            ys.iter().map(|y| y[0]).sum::<f64>() / n,
            ys.iter().map(|y| y[1]).sum::<f64>() / n,
        ];
        for i in 0..lags {
            for a in 0..l {
                for b in 0..l {
                    let (mut s, mut cnt) = (0.0, 0.0);
                    for k in 0..ys.len() {
                        let run = *runs.iter().filter(|&&r| r <= k).max().unwrap();
                        if k >= run + i {
                            s += (ys[k][a] - mu[a]) * (ys[k - i][b] - mu[b]);
                            cnt += 1.0;
                        }
                    }
                    let want = s / cnt;
                    assert!(
                        (got.at(i, a, b) - want).abs() < 1e-12,
                        "lag {i} ({a},{b}): {} vs {want}",
                        got.at(i, a, b)
                    );
                }
            }
        }
    }
}
