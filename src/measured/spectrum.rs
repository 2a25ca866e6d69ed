//! One evaluation of the window: means, the Hann-weighted copy, the zoom spectrum of each
//! track's band and its peak, cut into slices of bounded work (module docs of [`super`]).

use super::input::Ring;
use super::{MeasuredStatus, CHANNELS};

/// Most grid frequencies per track; a wider band gets a coarser grid (never coarser than
/// needed: the spacing is 1/(2T) unless the band needs more than this many points).
pub const MAX_BINS: usize = 512;

/// Tracks: the first mode, the end-effector mode.
pub(super) const TRACKS: usize = 2;

/// A track's answer of one evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Peak {
    pub(super) frequency_hz: f64,
    pub(super) peak_ratio: f64,
}

/// What one track searches and found.
#[derive(Debug, Clone, Copy)]
struct Track {
    predicted_hz: f64,
    /// Search band, Hz.
    lo_hz: f64,
    hi_hz: f64,
    /// Grid: first frequency and spacing, Hz, and points.
    f0_hz: f64,
    df_hz: f64,
    bins: usize,
    /// The three refinement frequencies, Hz, and the grid point they refine.
    refine_hz: [f64; 3],
    refine_power: [f64; 3],
    peak_bin: usize,
    floor: f64,
    /// The answer (`Err(Filling)` while it is being computed).
    result: Result<Peak, MeasuredStatus>,
}

impl Track {
    const fn empty() -> Track {
        Track {
            predicted_hz: f64::NAN,
            lo_hz: 0.0,
            hi_hz: 0.0,
            f0_hz: 0.0,
            df_hz: 0.0,
            bins: 0,
            refine_hz: [0.0; 3],
            refine_power: [0.0; 3],
            peak_bin: 0,
            floor: 0.0,
            result: Err(MeasuredStatus::Filling),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    Idle,
    /// Summing the window's channels (and its missing places) up to sample `k`.
    Mean {
        k: usize,
    },
    /// Copying the window, mean removed and Hann-weighted, up to sample `k`.
    Copy {
        k: usize,
    },
    /// Power of frequency `j` of track `track`'s grid (or of its refinement), summed up to
    /// sample `k`.
    Bins {
        track: usize,
        refine: bool,
        j: usize,
        k: usize,
    },
}

/// One evaluation's data and state; owned by the tracker, sized once.
#[derive(Debug)]
pub(super) struct Evaluation {
    phase: Phase,
    /// Absolute ring place of the window's oldest sample, and its length.
    start: u64,
    n: usize,
    period_s: f64,
    /// The window's centre, ns (sender's clock), and its run.
    pub(super) centre_ns: u64,
    pub(super) run_id: u64,
    sums: [f64; CHANNELS],
    missing: usize,
    means: [f64; CHANNELS],
    max_missing_fraction: f64,
    band_rel: f64,
    min_peak_ratio: f64,
    scratch: Vec<[f64; CHANNELS]>,
    power: [Vec<f64>; TRACKS],
    median_scratch: Vec<f64>,
    /// Partial sums of the bin in progress (re, im per channel).
    acc: [[f64; 2]; CHANNELS],
    tracks: [Track; TRACKS],
    /// Track 1 predicts the same frequency as track 0: it takes track 0's answer.
    same: bool,
}

/// Power of one frequency, summed over channels, for samples `k0..k1` of `x` (period `p`
/// s), added to `acc`.
fn accumulate(x: &[[f64; CHANNELS]], f_hz: f64, p: f64, k0: usize, acc: &mut [[f64; 2]; CHANNELS]) {
    let theta = -2.0 * core::f64::consts::PI * f_hz * p;
    let (s0, c0) = (theta * k0 as f64).sin_cos();
    let (ws, wc) = theta.sin_cos();
    let (mut zr, mut zi) = (c0, s0);
    for s in x {
        for c in 0..CHANNELS {
            acc[c][0] += s[c] * zr;
            acc[c][1] += s[c] * zi;
        }
        let r = zr * wc - zi * ws;
        zi = zr * ws + zi * wc;
        zr = r;
    }
}

/// How far above the Hann leakage bound ([`hann_leakage`]) of a stronger component outside
/// the band a peak in the band must stand to be a mode of its own: 100 (20 dB). The bound is
/// a clean sinusoid's, tight to 1 dB at each sidelobe's crest; the margin covers a damped
/// mode's wider skirt near its main lobe and the noise on both powers.
const LEAKAGE_MARGIN: f64 = 100.0;

/// The Hann window's leakage: an upper bound of the power a sinusoid puts at `x` bins (1/T)
/// from its frequency, relative to its peak power. Inside the main lobe (`x ≤ 2`) 1; beyond,
/// the envelope of |W(x)/W(0)|² = (sinc x / (1 − x²))²: 1/(π x (x² − 1))² (−31.5 dB at the
/// first sidelobe's crest, x ≈ 2.36, falling as x⁻⁶).
fn hann_leakage(x: f64) -> f64 {
    if x <= 2.0 {
        1.0
    } else {
        let a = core::f64::consts::PI * x * (x * x - 1.0);
        1.0 / (a * a)
    }
}

/// The offset, within ±`bound`, of the vertex of the parabola through (−1, a), (0, b),
/// (1, c): 0 when it is not a maximum or a value is not finite.
fn vertex(a: f64, b: f64, c: f64, bound: f64) -> f64 {
    let den = a - 2.0 * b + c;
    let d = 0.5 * (a - c) / den;
    if den < 0.0 && d.is_finite() {
        d.clamp(-bound, bound)
    } else {
        0.0
    }
}

impl Evaluation {
    pub(super) fn new(
        window_capacity: usize,
        max_missing_fraction: f64,
        band_rel: f64,
        min_peak_ratio: f64,
    ) -> Evaluation {
        Evaluation {
            phase: Phase::Idle,
            start: 0,
            n: 0,
            period_s: 0.0,
            centre_ns: 0,
            run_id: 0,
            sums: [0.0; CHANNELS],
            missing: 0,
            means: [0.0; CHANNELS],
            max_missing_fraction,
            band_rel,
            min_peak_ratio,
            scratch: vec![[0.0; CHANNELS]; window_capacity],
            power: [vec![0.0; MAX_BINS], vec![0.0; MAX_BINS]],
            median_scratch: vec![0.0; MAX_BINS],
            acc: [[0.0; 2]; CHANNELS],
            tracks: [Track::empty(); TRACKS],
            same: false,
        }
    }

    /// The window's length, s.
    pub(super) fn window_s(&self) -> f64 {
        self.n as f64 * self.period_s
    }

    pub(super) fn is_idle(&self) -> bool {
        self.phase == Phase::Idle
    }

    pub(super) fn abort(&mut self) {
        self.phase = Phase::Idle;
    }

    /// Starts an evaluation of the `n` places ending at the ring's newest, of period `p` s,
    /// centred at `centre_ns`, for the predicted frequencies `predicted` (Hz).
    pub(super) fn start(
        &mut self,
        ring: &Ring,
        n: usize,
        p: f64,
        centre_ns: u64,
        run_id: u64,
        predicted: [Option<f64>; TRACKS],
    ) {
        self.start = ring.written - n as u64;
        self.n = n;
        self.period_s = p;
        self.centre_ns = centre_ns;
        self.run_id = run_id;
        self.sums = [0.0; CHANNELS];
        self.missing = 0;
        for (t, f) in self.tracks.iter_mut().zip(predicted) {
            *t = Track::empty();
            t.predicted_hz = f.unwrap_or(f64::NAN);
        }
        let (f0, f1) = (self.tracks[0].predicted_hz, self.tracks[1].predicted_hz);
        self.same = f0 == f1;
        self.phase = Phase::Mean { k: 0 };
    }

    /// The answers once the evaluation is over (`None` while it runs).
    pub(super) fn answers(&self) -> [Result<Peak, MeasuredStatus>; TRACKS] {
        [self.tracks[0].result, self.tracks[1].result]
    }

    /// Works up to `budget` units (one window sample of one pass or one frequency each).
    /// Returns (units done, finished now). Abandons the evaluation (`overrun`) when the ring
    /// overwrote its window before the copy was taken.
    pub(super) fn work(&mut self, ring: &Ring, budget: u32) -> (u32, bool, bool) {
        let mut left = budget as usize;
        let n = self.n;
        while left > 0 {
            match self.phase {
                Phase::Idle => break,
                Phase::Mean { k } | Phase::Copy { k } if !ring.holds(self.start) => {
                    let _ = k;
                    self.phase = Phase::Idle;
                    return ((budget as usize - left) as u32, false, true);
                }
                Phase::Mean { k } => {
                    let k1 = (k + left).min(n);
                    for i in k..k1 {
                        let (x, missing) = ring.get(self.start + i as u64);
                        for c in 0..CHANNELS {
                            self.sums[c] += x[c];
                        }
                        self.missing += missing as usize;
                    }
                    left -= k1 - k;
                    if k1 == n {
                        for c in 0..CHANNELS {
                            self.means[c] = self.sums[c] / n as f64;
                        }
                        self.phase = Phase::Copy { k: 0 };
                    } else {
                        self.phase = Phase::Mean { k: k1 };
                    }
                }
                Phase::Copy { k } => {
                    let k1 = (k + left).min(n);
                    // cos(2πi/n) by rotation from the slice's first sample.
                    let step = 2.0 * core::f64::consts::PI / n as f64;
                    let (ws, wc) = step.sin_cos();
                    let (mut s, mut co) = (step * k as f64).sin_cos();
                    for i in k..k1 {
                        let (x, _) = ring.get(self.start + i as u64);
                        let w = 0.5 - 0.5 * co;
                        for c in 0..CHANNELS {
                            self.scratch[i][c] = w * (x[c] - self.means[c]);
                        }
                        let r = co * wc - s * ws;
                        s = co * ws + s * wc;
                        co = r;
                    }
                    left -= k1 - k;
                    if k1 == n {
                        self.begin_tracks();
                    } else {
                        self.phase = Phase::Copy { k: k1 };
                    }
                }
                Phase::Bins {
                    track,
                    refine,
                    j,
                    k,
                } => {
                    let t = &self.tracks[track];
                    let f = if refine {
                        t.refine_hz[j]
                    } else {
                        t.f0_hz + j as f64 * t.df_hz
                    };
                    let k1 = (k + left).min(n);
                    accumulate(&self.scratch[k..k1], f, self.period_s, k, &mut self.acc);
                    left -= k1 - k;
                    if k1 < n {
                        self.phase = Phase::Bins {
                            track,
                            refine,
                            j,
                            k: k1,
                        };
                        continue;
                    }
                    let p: f64 = self.acc.iter().map(|a| a[0] * a[0] + a[1] * a[1]).sum();
                    self.acc = [[0.0; 2]; CHANNELS];
                    if refine {
                        self.tracks[track].refine_power[j] = p;
                        if j + 1 < 3 {
                            self.phase = Phase::Bins {
                                track,
                                refine,
                                j: j + 1,
                                k: 0,
                            };
                        } else {
                            self.finish_track(track);
                        }
                    } else {
                        self.power[track][j] = p;
                        if j + 1 < self.tracks[track].bins {
                            self.phase = Phase::Bins {
                                track,
                                refine,
                                j: j + 1,
                                k: 0,
                            };
                        } else {
                            self.pick_peak(track);
                        }
                    }
                }
            }
        }
        let done = (budget as usize - left) as u32;
        (done, self.phase == Phase::Idle, false)
    }

    /// After the copy: the missing-sample check, each track's band and grid, the first bins.
    fn begin_tracks(&mut self) {
        let n = self.n as f64;
        let t_s = n * self.period_s;
        let fault = self.missing as f64 > self.max_missing_fraction * n;
        let nyquist_use = 0.4 / self.period_s;
        for tr in self.tracks.iter_mut() {
            let f = tr.predicted_hz;
            tr.lo_hz = f * (1.0 - self.band_rel);
            tr.hi_hz = f * (1.0 + self.band_rel);
            tr.result = if fault {
                Err(MeasuredStatus::InputFault)
            } else if !(f.is_finite() && f > 0.0) {
                Err(MeasuredStatus::NoModel)
            } else if tr.hi_hz > nyquist_use {
                Err(MeasuredStatus::BandTooHigh)
            } else if tr.lo_hz < 4.0 / t_s {
                Err(MeasuredStatus::BandTooLow)
            } else {
                let lo = (tr.lo_hz - 2.0 / t_s).max(1.0 / t_s);
                let hi = tr.hi_hz + 2.0 / t_s;
                let df = (0.5 / t_s).max((hi - lo) / (MAX_BINS - 1) as f64);
                tr.f0_hz = lo;
                tr.df_hz = df;
                tr.bins = (((hi - lo) / df).floor() as usize + 1).min(MAX_BINS);
                Err(MeasuredStatus::Filling)
            };
        }
        self.next_track(0);
    }

    /// Starts the grid of the first track from `track` on that still needs one; idle when
    /// none does.
    fn next_track(&mut self, track: usize) {
        for t in track..TRACKS {
            if t == 1 && self.same {
                self.tracks[1].result = self.tracks[0].result;
                continue;
            }
            if self.tracks[t].result == Err(MeasuredStatus::Filling) {
                self.phase = Phase::Bins {
                    track: t,
                    refine: false,
                    j: 0,
                    k: 0,
                };
                return;
            }
        }
        self.phase = Phase::Idle;
    }

    /// The grid is complete: the floor, the band's dominant peak, whether a stronger
    /// component outside the band could have leaked it, the refinement points.
    fn pick_peak(&mut self, track: usize) {
        let t_s = self.n as f64 * self.period_s;
        let tr = self.tracks[track];
        let power = &self.power[track][..tr.bins];
        let f_of = |j: usize| tr.f0_hz + j as f64 * tr.df_hz;
        let mut largest = 0;
        for j in 1..power.len() {
            if power[j] > power[largest] {
                largest = j;
            }
        }
        // The floor: the median of the grid away from the largest peak's main lobe.
        let mut m = 0;
        for j in 0..power.len() {
            if (f_of(j) - f_of(largest)).abs() > 2.0 / t_s {
                self.median_scratch[m] = power[j];
                m += 1;
            }
        }
        if m < 3 {
            m = power.len();
            self.median_scratch[..m].copy_from_slice(power);
        }
        let (_, floor, _) = self.median_scratch[..m].select_nth_unstable_by(m / 2, f64::total_cmp);
        let floor = *floor;
        let mut best: Option<usize> = None;
        for j in 1..power.len().saturating_sub(1) {
            let f = f_of(j);
            let local_max = power[j] > power[j - 1] && power[j] >= power[j + 1];
            let stands = power[j] > 0.0 && power[j] >= self.min_peak_ratio * floor;
            if local_max && stands && f >= tr.lo_hz && f <= tr.hi_hz {
                // The dominant peak: the largest. (The nearest to the prediction would take
                // the random ripples of a randomly excited mode's tail, or a sidelobe.)
                if best.is_none_or(|b| power[j] > power[b]) {
                    best = Some(j);
                }
            }
        }
        let Some(j) = best else {
            self.tracks[track].result = Err(MeasuredStatus::NoPeak);
            self.next_track(track + 1);
            return;
        };
        // A stronger component outside the band (in its margins) whose Hann leakage could
        // make this peak: the band holds no mode of its own that the window can tell.
        let leaked = (0..power.len()).any(|i| {
            let f = f_of(i);
            let outside = f < tr.lo_hz || f > tr.hi_hz;
            outside
                && power[i] > power[j]
                && power[j] <= LEAKAGE_MARGIN * power[i] * hann_leakage((f - f_of(j)).abs() * t_s)
        });
        if leaked {
            self.tracks[track].result = Err(MeasuredStatus::OutsideBand);
            self.next_track(track + 1);
            return;
        }
        let d = vertex(power[j - 1].ln(), power[j].ln(), power[j + 1].ln(), 0.5);
        let centre = f_of(j) + d * tr.df_hz;
        let h = 0.25 * tr.df_hz;
        let t = &mut self.tracks[track];
        t.peak_bin = j;
        t.floor = floor;
        t.refine_hz = [centre - h, centre, centre + h];
        self.phase = Phase::Bins {
            track,
            refine: true,
            j: 0,
            k: 0,
        };
    }

    /// The refinement powers are in: the answer.
    fn finish_track(&mut self, track: usize) {
        let t = &mut self.tracks[track];
        let [a, b, c] = t.refine_power;
        let d = vertex(a.ln(), b.ln(), c.ln(), 1.0);
        let h = t.refine_hz[1] - t.refine_hz[0];
        let peak = self.power[track][t.peak_bin].max(b);
        let frequency_hz = t.refine_hz[1] + d * h;
        // A peak whose grid point is in the band but which lies, located, just outside it.
        t.result = if (t.lo_hz..=t.hi_hz).contains(&frequency_hz) {
            Ok(Peak {
                frequency_hz,
                peak_ratio: if t.floor > 0.0 {
                    peak / t.floor
                } else {
                    f64::INFINITY
                },
            })
        } else {
            Err(MeasuredStatus::OutsideBand)
        };
        self.next_track(track + 1);
    }
}
