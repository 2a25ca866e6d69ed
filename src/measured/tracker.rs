//! [`VibrationTracker`]: the samples in, the measured frequencies out (module docs of
//! [`super`]).

use super::input::{Counters, PushOutcome, SampleInput};
use super::params::{ParamsError, TrackerParams};
use super::spectrum::{Evaluation, Peak, TRACKS};
use super::{MeasuredStatus, CHANNELS};

/// A measured frequency.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasuredMode {
    /// The peak's frequency, Hz.
    pub frequency_hz: f64,
    /// Its power over the band's floor (dimensionless, ≥ `min_peak_ratio`).
    pub peak_ratio: f64,
    /// The centre of the window it describes, ns (the samples' clock).
    pub window_centre_ns: u64,
    /// The window's length, s.
    pub window_s: f64,
}

/// The latest measurement of both tracks: a frequency, or the status saying why there is
/// none (never [`MeasuredStatus::Ok`] in an `Err`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measured {
    /// The dominant measured frequency near the model's first mode.
    pub first: Result<MeasuredMode, MeasuredStatus>,
    /// The dominant measured frequency near the model's end-effector mode.
    pub ee_mode: Result<MeasuredMode, MeasuredStatus>,
}

impl Measured {
    /// Both tracks without a measurement, for `status`.
    pub const fn none(status: MeasuredStatus) -> Measured {
        Measured {
            first: Err(status),
            ee_mode: Err(status),
        }
    }

    /// The window centre of the measurement (either track), ns.
    pub fn window_centre_ns(&self) -> Option<u64> {
        self.first.or(self.ee_mode).ok().map(|m| m.window_centre_ns)
    }
}

impl MeasuredStatus {
    /// The wire status of a track's answer: `Ok` for a measurement, else its reason.
    pub fn of(r: &Result<MeasuredMode, MeasuredStatus>) -> MeasuredStatus {
        match r {
            Ok(_) => MeasuredStatus::Ok,
            Err(s) => *s,
        }
    }
}

/// The online tracker: a ring of samples, the evaluation in slices, the latest answer. Built
/// once ([`VibrationTracker::new`] allocates everything); no call allocates after that.
#[derive(Debug)]
pub struct VibrationTracker {
    params: TrackerParams,
    input: SampleInput,
    eval: Evaluation,
    model: [Option<f64>; TRACKS],
    latest: Option<(u64, Measured)>,
    /// Run and ring place where the last evaluation's window ended.
    last_end: Option<(u64, u64)>,
    /// Evaluations abandoned (see [`Counters::overruns`]).
    overruns: u64,
}

impl VibrationTracker {
    /// A tracker with `params` (checked): ring and scratch for `window_s ×
    /// max_sample_rate_hz` samples.
    pub fn new(params: TrackerParams) -> Result<VibrationTracker, ParamsError> {
        params.validate()?;
        let window = params.window_capacity();
        let max_fill = ((params.max_missing_fraction * window as f64).floor() as u64).max(1);
        Ok(VibrationTracker {
            params,
            input: SampleInput::new(window + window / 2 + 16, max_fill),
            eval: Evaluation::new(
                window,
                params.max_missing_fraction,
                params.band_rel,
                params.min_peak_ratio,
            ),
            model: [None; TRACKS],
            latest: None,
            last_end: None,
            overruns: 0,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &TrackerParams {
        &self.params
    }

    /// Counts of everything pushed so far.
    pub fn counters(&self) -> Counters {
        let mut c = self.input.counters;
        c.overruns = self.overruns;
        c
    }

    /// One sample: the sender's sequence number and timestamp (ns), accelerations (m/s²,
    /// any frame fixed to the platform). Constant work, plus at most the allowed gap filled.
    pub fn push(
        &mut self,
        sequence: u64,
        timestamp_ns: u64,
        acceleration_m_s2: [f64; CHANNELS],
    ) -> PushOutcome {
        let out = self.input.push(sequence, timestamp_ns, acceleration_m_s2);
        if out == PushOutcome::Restarted {
            self.eval.abort();
            self.latest = None;
            self.last_end = None;
        }
        out
    }

    /// The model's predicted frequencies (Hz) the bands are centred on: the first mode and
    /// the end-effector mode (`None`: not known). Taken by the next evaluation.
    pub fn set_model(&mut self, f1_hz: Option<f64>, ee_mode_hz: Option<f64>) {
        self.model = [f1_hz, ee_mode_hz];
    }

    /// Works at most `work_per_poll` units: starts an evaluation when the window is full and
    /// `update_interval_s` of new samples arrived since the last one, continues the one in
    /// progress. Returns the units done.
    pub fn work(&mut self) -> u32 {
        if self.eval.is_idle() && !self.start_evaluation() {
            return 0;
        }
        let (units, finished, overrun) =
            self.eval.work(&self.input.ring, self.params.work_per_poll);
        if overrun {
            self.overruns += 1;
        } else if finished && self.eval.run_id == self.input.run_id {
            let [a, b] = self.eval.answers();
            let mode = |r: Result<Peak, MeasuredStatus>| {
                r.map(|p| MeasuredMode {
                    frequency_hz: p.frequency_hz,
                    peak_ratio: p.peak_ratio,
                    window_centre_ns: self.eval.centre_ns,
                    window_s: self.eval.window_s(),
                })
            };
            self.latest = Some((
                self.input.run_id,
                Measured {
                    first: mode(a),
                    ee_mode: mode(b),
                },
            ));
        }
        units
    }

    fn start_evaluation(&mut self) -> bool {
        let Some((p, last_ns)) = self.input.timing() else {
            return false;
        };
        let run = self.input.run_id;
        let written = self.input.ring.written;
        let n = (self.params.window_s / p).round();
        if !(n >= 8.0) {
            return false;
        }
        let n = n as u64;
        if written < n {
            return false;
        }
        let interval = (self.params.update_interval_s / p).ceil().max(1.0) as u64;
        if let Some((r, end)) = self.last_end {
            if r == run && written < end + interval {
                return false;
            }
        }
        self.last_end = Some((run, written));
        if n as usize > self.params.window_capacity() {
            self.latest = Some((run, Measured::none(MeasuredStatus::RateTooHigh)));
            return false;
        }
        let half_ns = 0.5 * (n - 1) as f64 * p * 1e9;
        let centre_ns = last_ns.saturating_sub(half_ns as u64);
        self.eval
            .start(&self.input.ring, n as usize, p, centre_ns, run, self.model);
        true
    }

    /// The latest measurement as of `now_ns` (the samples' clock): [`MeasuredStatus::NoInput`]
    /// when no sample arrived within `silence_s`, `Filling` before the first evaluation of the
    /// current window, else the last evaluation's answers.
    pub fn measured(&self, now_ns: u64) -> Measured {
        let silence_ns = (self.params.silence_s * 1e9) as u64;
        match self.input.last_ns() {
            Some(t) if now_ns.saturating_sub(t) <= silence_ns => {}
            _ => return Measured::none(MeasuredStatus::NoInput),
        }
        match self.latest {
            Some((run, m)) if run == self.input.run_id => m,
            _ => Measured::none(MeasuredStatus::Filling),
        }
    }
}
