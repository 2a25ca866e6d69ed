//! The record, sample by sample: time checks, decimation, windows.
//!
//! The nominal sample period is the median step of the first [`RATE_PROBE`] samples (kept
//! until then); the rate must be at least [`MIN_RATE_OVER_BAND`] × the band's top. After
//! that every sample is checked as it comes:
//! - a time that is not finite, or not after the previous one (non-monotonic or duplicated
//!   time) → an error naming the sample;
//! - a step longer than 1.5 × the nominal period is a *gap*, and a sample with a non-finite
//!   channel is left out: both end the contiguous run (no lag product straddles them), are
//!   counted in the windows they fall in, and give those windows the status `gap`;
//! - a sample [`Identifier::push_unmatched`] (a response with no measured input at its time,
//!   the `align` module) is left out the same way and counted apart (`unmatched`).
//!
//! Samples left out before the first decimated sample are counted in the first window.
//!
//! The decimated samples go to every window they fall in: the whole record, or windows of
//! `window_s` starting every `window_s × (1 − overlap)` from the first decimated sample. A
//! window is identified as soon as a sample falls past its end (or at the end of the record),
//! so the memory held is the open windows' lag products ([`LagCovariance`]), whatever the
//! record's length: at most ⌈1/(1 − overlap)⌉ windows of `segments` × 2 ×
//! 2p (l² + 2l + 1) numbers (p block rows, l channels), plus the finished windows' results.

use super::covariance::LagCovariance;
use super::decimate::{factor, Decimator};
use super::frf::{Frf, WelchH1};
use super::params::MIN_RATE_OVER_BAND;
use super::window::{identify_io_window, identify_window, IdentifiedMode, WindowStatus};
use super::{DiagramPole, IdentifyError, IdentifyParams};

/// Samples whose median step sets the nominal sample period.
pub const RATE_PROBE: usize = 64;
/// A step longer than this multiple of the nominal period is a gap.
pub const GAP_FACTOR: f64 = 1.5;
/// A window needs at least this many decimated samples per lag of its Hankel matrix.
const SAMPLES_PER_LAG: usize = 10;
/// Input-output data: the Welch segments' longest length, decimated samples (the segment is
/// the largest power of two ≤ this and ≤ a quarter of the window, and ≥ 4 × the impulse
/// response's lags).
pub const MAX_WELCH_LEN: usize = 1024;
/// Input-output data: a window needs at least this many Welch segments.
const MIN_WELCH_SEGMENTS: usize = 2;

/// The result of one window.
#[derive(Debug, Clone)]
pub struct WindowResult {
    /// Window index, from 0.
    pub index: usize,
    /// Start of the window, s (the record's time base).
    pub t_start_s: f64,
    /// End of the window, s (the last sample's time for the last or the whole-record window).
    pub t_end_s: f64,
    /// Decimated samples in the window.
    pub samples: u64,
    /// Sample rate of the identification (after decimation), Hz.
    pub rate_hz: f64,
    /// Status of the window.
    pub status: WindowStatus,
    /// Gaps in time inside the window.
    pub gaps: usize,
    /// Samples left out because a channel was not finite.
    pub nonfinite: usize,
    /// Response samples left out because the measured input had no value at their time
    /// (outside its span, or inside a gap of it; the `align` module).
    pub unmatched: usize,
    /// Modes, ascending.
    pub modes: Vec<IdentifiedMode>,
    /// The stabilisation diagram's poles.
    pub diagram: Vec<DiagramPole>,
    /// Singular values of the scaled Hankel matrix.
    pub singular_values: Vec<f64>,
    /// Input-output data: the H1 estimate and its coherence (kept with the diagram; line k
    /// is at k × `rate_hz` / N Hz).
    pub frf: Option<Frf>,
}

/// What a window accumulates: lag covariances of the outputs (output-only data) or the
/// Welch spectra of outputs and inputs.
#[derive(Debug)]
enum Accum {
    Cov(LagCovariance),
    Io(Box<WelchH1>),
}

impl Accum {
    fn push(&mut self, t_s: f64, v: &[f64]) {
        match self {
            Accum::Cov(c) => c.push(t_s, v),
            Accum::Io(w) => w.push(v),
        }
    }

    fn break_run(&mut self) {
        match self {
            Accum::Cov(c) => c.break_run(),
            Accum::Io(w) => w.break_run(),
        }
    }
}

#[derive(Debug)]
struct Open {
    index: usize,
    start_s: f64,
    end_s: f64,
    acc: Accum,
    taken: u64,
    last_t: Option<f64>,
    last_sample_s: f64,
    /// Σ steps and their count between consecutive decimated samples of one run.
    step_sum: f64,
    steps: u64,
    gaps: usize,
    nonfinite: usize,
    unmatched: usize,
}

/// The streaming identifier: [`Identifier::push`] every sample, then [`Identifier::finish`].
#[derive(Debug)]
pub struct Identifier {
    p: IdentifyParams,
    l: usize,
    /// Measured inputs (after the l outputs in each sample).
    m: usize,
    /// The first samples (an empty vector: an unmatched sample).
    probe: Vec<(f64, Vec<f64>)>,
    dt_nominal_s: f64,
    decimator: Option<Decimator>,
    out: Vec<f64>,
    last_t: Option<f64>,
    samples: u64,
    /// Time of the last sample taken.
    prev_t: Option<f64>,
    /// Time of the last decimated sample.
    last_output_s: Option<f64>,
    /// A gap or a left-out sample since the last decimated output, and their counts.
    broken: bool,
    pending_gaps: usize,
    pending_nonfinite: usize,
    pending_unmatched: usize,
    open: Vec<Open>,
    next_start_s: Option<f64>,
    next_index: usize,
    done: Vec<WindowResult>,
    /// Whose stabilisation diagram is kept (`None`: every window's).
    diagram_of: Option<Option<usize>>,
}

impl Identifier {
    /// An identifier of `channels` channels (output-only data).
    pub fn new(channels: usize, p: IdentifyParams) -> Result<Identifier, IdentifyError> {
        Identifier::with_inputs(channels, 0, p)
    }

    /// An identifier of `outputs` measured responses and `inputs` measured forces (each
    /// sample: the outputs, then the inputs); `inputs` 0: output-only data (SSI-cov), else
    /// H1 and its modal fit ([`super::frf`]).
    pub fn with_inputs(
        outputs: usize,
        inputs: usize,
        p: IdentifyParams,
    ) -> Result<Identifier, IdentifyError> {
        if inputs == 0 {
            p.validate(outputs)?;
        } else {
            p.validate_io(outputs, inputs)?;
        }
        Ok(Identifier {
            p,
            l: outputs,
            m: inputs,
            probe: Vec::new(),
            dt_nominal_s: f64::NAN,
            decimator: None,
            out: vec![0.0; outputs + inputs],
            last_t: None,
            samples: 0,
            prev_t: None,
            last_output_s: None,
            broken: false,
            pending_gaps: 0,
            pending_nonfinite: 0,
            pending_unmatched: 0,
            open: Vec::new(),
            next_start_s: None,
            next_index: 0,
            done: Vec::new(),
            diagram_of: None,
        })
    }

    /// Keep the stabilisation diagram (and singular values) of window `w` only, or of none:
    /// a long record's windows then hold their modes alone (≈ 0.1 kB a mode instead of
    /// ≈ 50 kB a diagram).
    pub fn keep_diagram_of(&mut self, w: Option<usize>) {
        self.diagram_of = Some(w);
    }

    /// Nominal sample period of the record, s (NaN before [`RATE_PROBE`] samples).
    pub fn dt_nominal_s(&self) -> f64 {
        self.dt_nominal_s
    }

    /// Samples taken.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// Windows finished so far (taken out).
    pub fn take_finished(&mut self) -> Vec<WindowResult> {
        std::mem::take(&mut self.done)
    }

    /// Take sample `y` (one value per channel) at `t_s`.
    pub fn push(&mut self, t_s: f64, y: &[f64]) -> Result<(), IdentifyError> {
        self.push_checked(t_s, Some(y))
    }

    /// A response sample at `t_s` left out because the measured input has no value there:
    /// its time is checked like any sample's, it ends the contiguous run and is counted in
    /// the windows it falls in ([`WindowResult::unmatched`], status `gap`).
    pub fn push_unmatched(&mut self, t_s: f64) -> Result<(), IdentifyError> {
        self.push_checked(t_s, None)
    }

    fn push_checked(&mut self, t_s: f64, y: Option<&[f64]>) -> Result<(), IdentifyError> {
        let k = self.samples;
        if let Some(y) = y.filter(|y| y.len() != self.l + self.m) {
            return Err(IdentifyError::Input(format!(
                "sample {k}: {} values, expected {} channels",
                y.len(),
                self.l + self.m
            )));
        }
        if !t_s.is_finite() {
            return Err(IdentifyError::Input(format!(
                "sample {k}: time {t_s} is not finite"
            )));
        }
        if let Some(prev) = self.last_t {
            if !(t_s > prev) {
                let what = if t_s == prev {
                    "duplicated"
                } else {
                    "goes back"
                };
                return Err(IdentifyError::Input(format!(
                    "sample {k}: time {t_s} s {what} (previous {prev} s): the time must increase"
                )));
            }
        }
        self.last_t = Some(t_s);
        self.samples += 1;
        if self.decimator.is_none() {
            self.probe
                .push((t_s, y.map_or_else(Vec::new, <[f64]>::to_vec)));
            if self.probe.len() >= RATE_PROBE {
                self.start()?;
            }
            return Ok(());
        }
        self.take(t_s, y);
        Ok(())
    }

    /// The nominal rate from the probe, the rate check, the decimator; then the probe's
    /// samples are taken.
    fn start(&mut self) -> Result<(), IdentifyError> {
        let mut steps: Vec<f64> = self.probe.windows(2).map(|w| w[1].0 - w[0].0).collect();
        if steps.is_empty() {
            return Err(IdentifyError::Input(format!(
                "{} sample(s): a record needs at least 2",
                self.probe.len()
            )));
        }
        steps.sort_by(f64::total_cmp);
        let dt = steps[steps.len() / 2];
        let rate = 1.0 / dt;
        if rate < MIN_RATE_OVER_BAND * self.p.to_hz {
            return Err(IdentifyError::RateTooLow {
                rate_hz: rate,
                to_hz: self.p.to_hz,
            });
        }
        self.dt_nominal_s = dt;
        self.decimator = Some(Decimator::new(factor(rate, self.p.to_hz), self.l + self.m));
        for (t, y) in std::mem::take(&mut self.probe) {
            self.take(t, (!y.is_empty()).then_some(&y[..]));
        }
        Ok(())
    }

    /// One checked sample after the start (`None`: unmatched): gaps, non-finite values,
    /// decimation.
    fn take(&mut self, t_s: f64, y: Option<&[f64]>) {
        let dec = self.decimator.as_mut().expect("started");
        if let Some(prev) = self.prev_t {
            if t_s - prev > GAP_FACTOR * self.dt_nominal_s {
                dec.reset();
                self.broken = true;
                self.pending_gaps += 1;
            }
        }
        self.prev_t = Some(t_s);
        let Some(y) = y else {
            dec.reset();
            self.broken = true;
            self.pending_unmatched += 1;
            return;
        };
        if y.iter().any(|v| !v.is_finite()) {
            dec.reset();
            self.broken = true;
            self.pending_nonfinite += 1;
            return;
        }
        if let Some(to) = dec.push(t_s, y, &mut self.out) {
            self.output(to);
        }
    }

    /// One decimated sample at `t_s` (in `self.out`).
    fn output(&mut self, t_s: f64) {
        let q = self.decimator.as_ref().map_or(1, |d| d.q());
        let dt = self.dt_nominal_s * q as f64;
        if self.last_output_s.is_none() {
            self.next_start_s = Some(t_s);
        }
        // The span lost since the last decimated sample (a gap, or samples left out and the
        // filter's warm-up after them), counted in every window it touches.
        let lost = if std::mem::take(&mut self.broken) {
            let since = self.last_output_s.unwrap_or(f64::NEG_INFINITY);
            Some((
                since,
                std::mem::take(&mut self.pending_gaps),
                std::mem::take(&mut self.pending_nonfinite),
                std::mem::take(&mut self.pending_unmatched),
            ))
        } else {
            None
        };
        let touch = |w: &mut Open| {
            if let Some((since, g, n, u)) = lost {
                // Before the first decimated sample (`since` −∞): the first window.
                if since < w.end_s && (t_s > w.start_s || since == f64::NEG_INFINITY) {
                    w.gaps += g;
                    w.nonfinite += n;
                    w.unmatched += u;
                }
            }
        };
        // Windows ending at or before t_s are done.
        let (ended, open): (Vec<Open>, Vec<Open>) = std::mem::take(&mut self.open)
            .into_iter()
            .partition(|w| t_s >= w.end_s);
        self.open = open;
        for w in &mut self.open {
            touch(w);
        }
        for mut w in ended {
            touch(&mut w);
            let r = self.finish_window(w, dt);
            self.done.push(r);
        }
        // Open the windows that start at or before t_s.
        while let Some(s) = self.next_start_s {
            if s > t_s {
                break;
            }
            let (end, next) = match self.p.window_s {
                Some(w) => (s + w, Some(s + w * (1.0 - self.p.overlap))),
                None => (f64::INFINITY, None),
            };
            let mut w = Open {
                index: self.next_index,
                start_s: s,
                end_s: end,
                acc: self.accumulator(s, dt),
                taken: 0,
                last_t: None,
                last_sample_s: s,
                step_sum: 0.0,
                steps: 0,
                gaps: 0,
                nonfinite: 0,
                unmatched: 0,
            };
            self.next_index += 1;
            self.next_start_s = next;
            if t_s >= end {
                // A gap covered the whole window.
                touch(&mut w);
                let mut r = self.finish_window(w, dt);
                r.status = WindowStatus::NoData;
                self.done.push(r);
            } else {
                touch(&mut w);
                self.open.push(w);
            }
        }
        for w in &mut self.open {
            if lost.is_some() {
                w.acc.break_run();
                w.last_t = None;
            }
            if let Some(prev) = w.last_t {
                w.step_sum += t_s - prev;
                w.steps += 1;
            }
            w.last_t = Some(t_s);
            w.last_sample_s = t_s;
            w.acc.push(t_s, &self.out);
            w.taken += 1;
        }
        self.last_output_s = Some(t_s);
    }

    /// A new window's accumulator, the window starting at `start_s`, `dt_s` the decimated
    /// period.
    fn accumulator(&self, start_s: f64, dt_s: f64) -> Accum {
        if self.m == 0 {
            let lags = 2 * self.p.block_rows(self.l);
            let seg = self.p.window_s.map_or(1.0, |w| w / self.p.segments as f64);
            return Accum::Cov(LagCovariance::new(
                self.l,
                lags,
                start_s,
                seg,
                self.p.segments,
            ));
        }
        let lags = 2 * self.p.block_rows_io(self.l, self.m);
        let n_min = (4 * lags).next_power_of_two();
        let quarter = self
            .p
            .window_s
            .map_or(usize::MAX, |w| (w / dt_s / 4.0).max(1.0) as usize);
        let below = |x: usize| 1usize << (usize::BITS - 1 - x.max(1).leading_zeros());
        let n = n_min.max(below(quarter.min(MAX_WELCH_LEN)));
        Accum::Io(Box::new(
            WelchH1::new(self.l, self.m, n, self.p.segments).expect("a power of two ≥ 8"),
        ))
    }

    fn finish_window(&self, w: Open, dt_fallback: f64) -> WindowResult {
        let dt = if w.steps > 0 {
            w.step_sum / w.steps as f64
        } else {
            dt_fallback
        };
        let samples = w.taken;
        let t_end = if w.end_s.is_finite() {
            w.end_s
        } else {
            w.last_sample_s
        };
        let mut r = WindowResult {
            index: w.index,
            t_start_s: w.start_s,
            t_end_s: t_end,
            samples,
            rate_hz: 1.0 / dt,
            status: WindowStatus::Ok,
            gaps: w.gaps,
            nonfinite: w.nonfinite,
            unmatched: w.unmatched,
            modes: Vec::new(),
            diagram: Vec::new(),
            singular_values: Vec::new(),
            frf: None,
        };
        if samples == 0 {
            r.status = WindowStatus::NoData;
            return r;
        }
        let found = match &w.acc {
            Accum::Cov(cov) => {
                let lags = 2 * self.p.block_rows(self.l);
                if (samples as usize) < SAMPLES_PER_LAG * lags {
                    r.status = WindowStatus::Short;
                    return r;
                }
                identify_window(cov, &self.p, self.l, dt).map(|id| (id, None))
            }
            Accum::Io(welch) => {
                if welch.segments() < MIN_WELCH_SEGMENTS {
                    r.status = WindowStatus::Short;
                    return r;
                }
                identify_io_window(welch, &self.p, self.l, self.m, dt)
                    .map(|(id, frf)| (id, Some(frf)))
            }
        };
        match found {
            Ok((id, frf)) => {
                r.modes = id.modes;
                if self.diagram_of.is_none_or(|k| k == Some(w.index)) {
                    r.diagram = id.diagram;
                    r.singular_values = id.singular_values;
                    r.frf = frf;
                }
                if w.gaps > 0 || w.nonfinite > 0 || w.unmatched > 0 {
                    r.status = WindowStatus::Gap;
                }
            }
            Err(s) => r.status = s,
        }
        r
    }

    /// End of the record: the open windows are identified; every window's result, in order.
    pub fn finish(mut self) -> Result<Vec<WindowResult>, IdentifyError> {
        if self.decimator.is_none() {
            if self.probe.len() < 2 {
                return Err(IdentifyError::Input(format!(
                    "{} sample(s): a record needs at least 2",
                    self.probe.len()
                )));
            }
            self.start()?;
        }
        let q = self.decimator.as_ref().map_or(1, |d| d.q());
        let dt = self.dt_nominal_s * q as f64;
        let open = std::mem::take(&mut self.open);
        for mut w in open {
            // Samples left out at the very end.
            if self.broken {
                w.gaps += self.pending_gaps;
                w.nonfinite += self.pending_nonfinite;
                w.unmatched += self.pending_unmatched;
            }
            let r = self.finish_window(w, dt);
            self.done.push(r);
        }
        if self.done.is_empty() {
            return Err(IdentifyError::Input(format!(
                "{} sample(s) at {:.4} Hz: too short to fill the decimation filter",
                self.samples,
                1.0 / self.dt_nominal_s
            )));
        }
        let mut out = self.done;
        out.sort_by_key(|r| r.index);
        Ok(out)
    }
}
