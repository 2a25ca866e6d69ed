//! Decimation to the band: an anti-aliasing low-pass FIR filter evaluated only at the kept
//! samples (every q-th input).
//!
//! The decimation factor is q = ⌊f_s / (3 f_top)⌋ (no decimation when that is < 2), so the
//! decimated rate f_s′ = f_s/q is at least 3 f_top. The filter is a windowed sinc (Blackman
//! window, 20 q + 1 taps, cut-off at f_s′/2): its transition band, about 5.5 f_s / taps ≈
//! 0.28 f_s′ wide, lies between the band's top and f_s′ − f_top, the lowest frequency that
//! folds into the band, and its stop band attenuates by ≥ 70 dB. A FIR filter has no poles,
//! so it adds none to the identified system; it only weights the spectrum (flat to 1e-3 in
//! the band) and delays the output by (taps − 1)/2 input samples, which the output's time
//! stamps account for.

/// Decimation factor for input rate `rate_hz` and band top `to_hz`.
pub fn factor(rate_hz: f64, to_hz: f64) -> usize {
    let q = (rate_hz / (3.0 * to_hz)).floor();
    if q >= 2.0 {
        q.min(1e6) as usize
    } else {
        1
    }
}

/// A streaming decimator of `channels` channels by `q`.
#[derive(Debug, Clone)]
pub struct Decimator {
    q: usize,
    channels: usize,
    taps: Vec<f64>,
    /// Last `taps.len()` inputs, channel-interleaved, doubled so a contiguous slice holds
    /// them newest first.
    ring: Vec<f64>,
    /// Time stamps of the last inputs, as `ring`.
    times: Vec<f64>,
    pos: usize,
    /// Inputs since the last reset.
    filled: usize,
    /// Inputs until the next output.
    phase: usize,
}

impl Decimator {
    /// A decimator by `q` (1: passes samples through).
    pub fn new(q: usize, channels: usize) -> Decimator {
        let taps = if q <= 1 { vec![1.0] } else { design(q) };
        let n = taps.len();
        Decimator {
            q: q.max(1),
            channels,
            taps,
            ring: vec![0.0; 2 * n * channels],
            times: vec![0.0; 2 * n],
            pos: 0,
            filled: 0,
            phase: 0,
        }
    }

    /// The decimation factor.
    pub fn q(&self) -> usize {
        self.q
    }

    /// Forget the history (a gap in the record): no output until the filter is full again.
    pub fn reset(&mut self) {
        self.filled = 0;
        self.phase = 0;
    }

    /// Take one input sample at time `t_s`; returns the time of an output written to `out`
    /// (`channels` values) when this input completes one.
    pub fn push(&mut self, t_s: f64, y: &[f64], out: &mut [f64]) -> Option<f64> {
        let n = self.taps.len();
        let l = self.channels;
        self.pos = (self.pos + n - 1) % n;
        for (k, &v) in y.iter().enumerate().take(l) {
            self.ring[self.pos * l + k] = v;
            self.ring[(self.pos + n) * l + k] = v;
        }
        self.times[self.pos] = t_s;
        self.times[self.pos + n] = t_s;
        self.filled = (self.filled + 1).min(n);
        if self.filled < n {
            return None;
        }
        if self.phase > 0 {
            self.phase -= 1;
            return None;
        }
        self.phase = self.q - 1;
        out[..l].fill(0.0);
        let hist = &self.ring[self.pos * l..(self.pos + n) * l];
        for (i, &h) in self.taps.iter().enumerate() {
            let x = &hist[i * l..(i + 1) * l];
            for k in 0..l {
                out[k] += h * x[k];
            }
        }
        // The symmetric filter's output belongs to its centre tap's time.
        Some(self.times[self.pos + (n - 1) / 2])
    }
}

/// The Blackman-windowed sinc low-pass of 20 q + 1 taps, cut-off at f_s/(2q), unit DC gain.
fn design(q: usize) -> Vec<f64> {
    let n = 20 * q + 1;
    let mid = (n - 1) as f64 / 2.0;
    let fc = 0.5 / q as f64; // cycles per input sample
    let pi = std::f64::consts::PI;
    let mut h: Vec<f64> = (0..n)
        .map(|i| {
            let x = i as f64 - mid;
            let sinc = if x == 0.0 {
                2.0 * fc
            } else {
                (2.0 * pi * fc * x).sin() / (pi * x)
            };
            let w = 0.42 - 0.5 * (2.0 * pi * i as f64 / (n - 1) as f64).cos()
                + 0.08 * (4.0 * pi * i as f64 / (n - 1) as f64).cos();
            sinc * w
        })
        .collect();
    let s: f64 = h.iter().sum();
    for v in &mut h {
        *v /= s;
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    /// |H(f)| of the taps at `f` cycles per input sample.
    fn gain(h: &[f64], f: f64) -> f64 {
        let (mut re, mut im) = (0.0, 0.0);
        for (i, &v) in h.iter().enumerate() {
            let ph = -2.0 * std::f64::consts::PI * f * i as f64;
            re += v * ph.cos();
            im += v * ph.sin();
        }
        (re * re + im * im).sqrt()
    }

    /// The filter is flat in the band (top at 1/3 of the decimated Nyquist… f_s′/3) and
    /// stops what folds into it (≥ f_s′ − top), for the factors the defaults produce.
    #[test]
    fn passband_flat_and_aliases_stopped() {
        for q in [2, 3, 6, 20] {
            let h = design(q);
            let fs2 = 1.0 / q as f64; // decimated rate, cycles per input sample
            let top = fs2 / 3.0;
            for k in 0..=20 {
                let f = top * k as f64 / 20.0;
                assert!(
                    (gain(&h, f) - 1.0).abs() < 1e-3,
                    "q {q} f {f}: {}",
                    gain(&h, f)
                );
            }
            for k in 0..=50 {
                let f = (fs2 - top) + (0.5 - (fs2 - top)) * k as f64 / 50.0;
                assert!(gain(&h, f) < 3e-4, "q {q} f {f}: {}", gain(&h, f));
            }
        }
    }

    #[test]
    fn outputs_every_q_after_warm_up_at_centre_time() {
        let mut d = Decimator::new(3, 1);
        let n = 61;
        let mut out = [0.0];
        let mut times = Vec::new();
        for i in 0..200 {
            if let Some(t) = d.push(i as f64, &[1.0], &mut out) {
                times.push(t);
                assert!((out[0] - 1.0).abs() < 1e-12);
            }
        }
        assert_eq!(times[0], ((n - 1) / 2) as f64);
        assert!(times.windows(2).all(|w| w[1] - w[0] == 3.0));
    }
}
