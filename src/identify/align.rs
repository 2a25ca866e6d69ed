//! A measured input recorded on its own clock (a force sensor's stream beside an IMU's),
//! put on the response stream's clock by linear interpolation.
//!
//! For a response sample at t with input samples (t₀, u₀) and (t₁, u₁) around it,
//! t₀ ≤ t ≤ t₁, the input is u(t) = u₀ + (t − t₀)/(t₁ − t₀) · (u₁ − u₀) (u₀ itself when
//! t = t₀). A response sample gets no input — it is *unmatched*, handed on as such and
//! counted by the identifier in its window — when
//! - t is before the input's first sample or after its last (outside the input's span), or
//! - t₁ − t₀ > [`MAX_INPUT_GAP_PERIODS`] × the input's nominal period (the median step of
//!   its first [`RATE_PROBE`] samples): an input gap, across which a line is no measurement.
//!
//! Linear interpolation of a signal sampled every h is, on the response's clock, the input
//! seen through a short (two-tap) filter: at frequency f its gain is within
//! (π f h)²/2 of 1 (for a sample halfway between two), so 0.12 % at 20 Hz for a 1 kHz input;
//! the phase it adds is a delay shorter than h, which moves the frequency response's
//! residues, not its poles.
//!
//! Both streams arrive interleaved in file order; a response sample waits until the input
//! has passed its time, an input sample until no response before it can come. Memory:
//! at most [`MAX_WAITING`] samples of each stream wait (8 bytes × (1 + channels) each); a
//! stream running further ahead of the other in the file is an error.

use super::stream::RATE_PROBE;
use super::IdentifyError;
use std::collections::VecDeque;

/// An input step longer than this multiple of the input's nominal period is a gap.
pub const MAX_INPUT_GAP_PERIODS: f64 = 2.0;
/// Most samples of either stream held waiting for the other.
pub const MAX_WAITING: usize = 1 << 18;

/// What the aligner hands on for each response sample, in the responses' order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Aligned<'a> {
    /// The response's values, then the inputs interpolated at its time.
    Sample {
        /// Time, s.
        t_s: f64,
        /// Responses then inputs.
        values: &'a [f64],
    },
    /// A response sample with no input at its time (left out, counted).
    Unmatched {
        /// Time, s.
        t_s: f64,
    },
}

/// Samples of one stream: times and their values, row-major.
#[derive(Debug, Default)]
struct Queue {
    t: VecDeque<f64>,
    v: VecDeque<f64>,
    width: usize,
    taken: u64,
    last_t: Option<f64>,
}

impl Queue {
    fn new(width: usize) -> Queue {
        Queue {
            width,
            ..Queue::default()
        }
    }

    fn push(&mut self, t_s: f64, v: &[f64], what: &str) -> Result<(), IdentifyError> {
        let k = self.taken;
        if v.len() != self.width {
            return Err(IdentifyError::Input(format!(
                "{what} sample {k}: {} values, expected {}",
                v.len(),
                self.width
            )));
        }
        if !t_s.is_finite() {
            return Err(IdentifyError::Input(format!(
                "{what} sample {k}: time {t_s} is not finite"
            )));
        }
        if let Some(p) = self.last_t.filter(|&p| !(t_s > p)) {
            return Err(IdentifyError::Input(format!(
                "{what} sample {k}: time {t_s} s {} (previous {p} s): the time must increase",
                if t_s == p { "duplicated" } else { "goes back" }
            )));
        }
        if self.t.len() >= MAX_WAITING {
            return Err(IdentifyError::Input(format!(
                "{what} sample {k}: more than {MAX_WAITING} samples of the {what} stream wait for the other stream (one is far ahead of the other in the file, or the other has no message)"
            )));
        }
        self.last_t = Some(t_s);
        self.taken += 1;
        self.t.push_back(t_s);
        self.v.extend(v.iter().copied());
        Ok(())
    }

    fn pop(&mut self) {
        self.t.pop_front();
        self.v.drain(..self.width);
    }
}

/// The streaming aligner: [`Aligner::response`] and [`Aligner::input`] in file order, then
/// [`Aligner::finish`].
#[derive(Debug)]
pub struct Aligner {
    resp: Queue,
    inp: Queue,
    /// The input's nominal period (once [`RATE_PROBE`] steps seen).
    dt_input_s: Option<f64>,
    probe: Vec<f64>,
    out: Vec<f64>,
}

type Emit<'e> = dyn FnMut(Aligned<'_>) -> Result<(), IdentifyError> + 'e;

impl Aligner {
    /// An aligner of `inputs` input channels; the responses have as many channels as the
    /// first response sample (inputs may come before it).
    pub fn new(inputs: usize) -> Aligner {
        Aligner {
            resp: Queue::new(0),
            inp: Queue::new(inputs),
            dt_input_s: None,
            probe: Vec::new(),
            out: Vec::new(),
        }
    }

    /// The input's nominal period, s (once known).
    pub fn input_period_s(&self) -> Option<f64> {
        self.dt_input_s
    }

    /// Input samples taken.
    pub fn inputs(&self) -> u64 {
        self.inp.taken
    }

    /// A response sample.
    pub fn response(
        &mut self,
        t_s: f64,
        y: &[f64],
        emit: &mut Emit<'_>,
    ) -> Result<(), IdentifyError> {
        if self.resp.taken == 0 {
            self.resp.width = y.len();
            self.out = vec![0.0; y.len() + self.inp.width];
        }
        self.resp.push(t_s, y, "response")?;
        self.flush(false, emit)
    }

    /// An input sample.
    pub fn input(&mut self, t_s: f64, u: &[f64], emit: &mut Emit<'_>) -> Result<(), IdentifyError> {
        self.inp.push(t_s, u, "input")?;
        if self.dt_input_s.is_none() {
            self.probe.push(t_s);
            if self.probe.len() > RATE_PROBE {
                self.set_period();
            }
        }
        self.flush(false, emit)
    }

    /// End of both streams: the responses still waiting are matched or unmatched. Returns
    /// the input's nominal period, s (0 with fewer than 2 input samples).
    pub fn finish(mut self, emit: &mut Emit<'_>) -> Result<f64, IdentifyError> {
        if self.dt_input_s.is_none() {
            self.set_period();
        }
        self.flush(true, emit)?;
        Ok(self.dt_input_s.unwrap_or(0.0))
    }

    fn set_period(&mut self) {
        let mut steps: Vec<f64> = self.probe.windows(2).map(|w| w[1] - w[0]).collect();
        steps.sort_by(f64::total_cmp);
        // No input step (one input sample or none): every response is unmatched but one
        // at the very time of the single input sample.
        self.dt_input_s = Some(steps.get(steps.len() / 2).copied().unwrap_or(0.0));
        self.probe = Vec::new();
    }

    /// Hand on every response sample the input has passed (all of them at the end).
    fn flush(&mut self, end: bool, emit: &mut Emit<'_>) -> Result<(), IdentifyError> {
        let Some(dt) = self.dt_input_s else {
            return Ok(());
        };
        let (l, m) = (self.resp.width, self.inp.width);
        while let Some(&t) = self.resp.t.front() {
            let last_in = self.inp.last_t.unwrap_or(f64::NEG_INFINITY);
            if !end && t > last_in {
                break;
            }
            // The inputs before the one at or just before t are no longer needed.
            while self.inp.t.len() >= 2 && self.inp.t[1] <= t {
                self.inp.pop();
            }
            let matched = match (self.inp.t.front().copied(), self.inp.t.get(1).copied()) {
                (Some(t0), _) if t0 == t => Some((0.0, 0)),
                (Some(t0), Some(t1))
                    if t0 < t && t <= t1 && t1 - t0 <= MAX_INPUT_GAP_PERIODS * dt =>
                {
                    Some(((t - t0) / (t1 - t0), 1))
                }
                _ => None,
            };
            match matched {
                Some((w, k)) => {
                    for (o, y) in self.out.iter_mut().zip(self.resp.v.iter().take(l)) {
                        *o = *y;
                    }
                    for j in 0..m {
                        let u0 = self.inp.v[j];
                        let u1 = self.inp.v[k * m + j];
                        self.out[l + j] = if w == 0.0 { u0 } else { u0 + w * (u1 - u0) };
                    }
                    emit(Aligned::Sample {
                        t_s: t,
                        values: &self.out,
                    })?;
                }
                None => emit(Aligned::Unmatched { t_s: t })?,
            }
            self.resp.pop();
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(resp: &[f64], inp: &[(f64, f64)], interleave: bool) -> Vec<(f64, Option<f64>)> {
        let mut got = Vec::new();
        let mut a = Aligner::new(1);
        let mut emit = |x: Aligned<'_>| {
            got.push(match x {
                Aligned::Sample { t_s, values } => (t_s, Some(values[1])),
                Aligned::Unmatched { t_s } => (t_s, None),
            });
            Ok(())
        };
        if interleave {
            // In time order, as a bag's log time interleaves them.
            let (mut i, mut j) = (0, 0);
            while i < resp.len() || j < inp.len() {
                if j >= inp.len() || (i < resp.len() && resp[i] <= inp[j].0) {
                    a.response(resp[i], &[resp[i]], &mut emit).unwrap();
                    i += 1;
                } else {
                    a.input(inp[j].0, &[inp[j].1], &mut emit).unwrap();
                    j += 1;
                }
            }
        } else {
            for &t in resp {
                a.response(t, &[t], &mut emit).unwrap();
            }
            for &(t, u) in inp {
                a.input(t, &[u], &mut emit).unwrap();
            }
        }
        a.finish(&mut emit).unwrap();
        got
    }

    /// A linear input is interpolated exactly (the reference: the line itself); responses
    /// outside the input's span and inside a gap of more than 2 periods are unmatched, in
    /// either file order.
    #[test]
    fn line_exact_and_unmatched_counted() {
        let line = |t: f64| 3.0 - 2.0 * t;
        // Input every 1 ms from 0.3 ms to 99.3 ms but for 41.3 and 42.3 ms (a 3-period gap).
        let inp: Vec<(f64, f64)> = (0..100)
            .map(|k| k as f64 * 1e-3 + 0.3e-3)
            .filter(|t| !(0.041..0.043).contains(t))
            .map(|t| (t, line(t)))
            .collect();
        let resp: Vec<f64> = (0..101).map(|k| k as f64 * 1e-3).collect();
        for interleave in [true, false] {
            let got = run(&resp, &inp, interleave);
            assert_eq!(got.len(), resp.len());
            let unmatched: Vec<f64> = got.iter().filter(|g| g.1.is_none()).map(|g| g.0).collect();
            // t = 0 (before), 41, 42, 43 ms (inside the gap 40.3 … 43.3 ms), 100 ms (after).
            assert_eq!(unmatched.len(), 5, "{unmatched:?}");
            for (t, u) in got.iter().filter_map(|g| g.1.map(|u| (g.0, u))) {
                assert!((u - line(t)).abs() < 1e-12, "{t}: {u}");
            }
        }
    }

    #[test]
    fn input_time_checked_and_waiting_bounded() {
        let mut a = Aligner::new(1);
        let mut emit = |_: Aligned<'_>| Ok(());
        a.input(1.0, &[0.0], &mut emit).unwrap();
        let e = a.input(0.5, &[0.0], &mut emit).unwrap_err();
        assert!(
            e.to_string()
                .contains("input sample 1: time 0.5 s goes back"),
            "{e}"
        );
        let mut a = Aligner::new(1);
        for k in 0..MAX_WAITING {
            a.response(k as f64, &[0.0], &mut emit).unwrap();
        }
        let e = a.response(1e9, &[0.0], &mut emit).unwrap_err();
        assert!(e.to_string().contains("wait for the other stream"), "{e}");
    }
}
