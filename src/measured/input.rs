//! Accepting samples: validation, the sample grid from sequence numbers, the period from
//! timestamps, missing samples, and the ring the window is read from (module docs of
//! [`super`]).

use super::CHANNELS;

/// Largest acceleration component accepted, m/s² (10⁵ g: far beyond any sensor on a robot;
/// it keeps every power of the spectrum finite).
pub const MAX_ACCELERATION_M_S2: f64 = 1e6;

/// Counts of what happened to the samples pushed, since the tracker was built. Every sample
/// pushed is in exactly one of `accepted`, `invalid`, `out_of_order`, `time_not_increasing`;
/// `filled` counts the places of the grid that held the previous value instead (the refused
/// ones and the `lost` ones, never received).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counters {
    /// Samples taken into the window.
    pub accepted: u64,
    /// Refused: a component not finite or beyond ±[`MAX_ACCELERATION_M_S2`].
    pub invalid: u64,
    /// Refused: a sequence number not after the previous sample's (duplicate, reordered).
    pub out_of_order: u64,
    /// Refused: a timestamp not after the previous sample's (duplicated or backwards time).
    pub time_not_increasing: u64,
    /// Places of the sample grid never received (sequence gaps not explained by refusals),
    /// those of a gap that restarted the window included.
    pub lost: u64,
    /// Places of the grid filled with the previous value (refused or lost samples).
    pub filled: u64,
    /// Window restarts: a sender restart, timestamps that disagree with the sequence (a
    /// paused sender, a changed rate), a gap longer than the allowed share of the window.
    pub restarts: u64,
    /// Evaluations abandoned because the ring overwrote their window meanwhile (input faster
    /// than the work allowed to read it).
    pub overruns: u64,
}

impl Counters {
    /// Samples refused (invalid, out of order, time not increasing).
    pub fn refused(&self) -> u64 {
        self.invalid + self.out_of_order + self.time_not_increasing
    }
}

/// Why a sample was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// A component not finite or beyond ±[`MAX_ACCELERATION_M_S2`].
    Invalid,
    /// A sequence number not after the previous one.
    OutOfOrder,
    /// A timestamp not after the previous one.
    TimeNotIncreasing,
}

/// What [`super::VibrationTracker::push`] did with a sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PushOutcome {
    /// Taken, after `filled` missing places held the previous value.
    Accepted {
        /// Missing places filled before it.
        filled: u64,
    },
    /// Taken as the first sample of a new window (the old one was dropped).
    Restarted,
    /// Refused and counted.
    Refused(Refusal),
}

/// The ring of samples, indexed by absolute place since the run started.
#[derive(Debug)]
pub(super) struct Ring {
    data: Vec<[f64; CHANNELS]>,
    missing: Vec<bool>,
    /// Places written since the run started.
    pub(super) written: u64,
}

impl Ring {
    pub(super) fn new(capacity: usize) -> Ring {
        Ring {
            data: vec![[0.0; CHANNELS]; capacity],
            missing: vec![false; capacity],
            written: 0,
        }
    }

    pub(super) fn capacity(&self) -> u64 {
        self.data.len() as u64
    }

    fn push(&mut self, x: [f64; CHANNELS], missing: bool) {
        let i = (self.written % self.capacity()) as usize;
        self.data[i] = x;
        self.missing[i] = missing;
        self.written += 1;
    }

    /// Place `at` (absolute): still in the ring when `written − at ≤ capacity`.
    pub(super) fn get(&self, at: u64) -> ([f64; CHANNELS], bool) {
        let i = (at % self.capacity()) as usize;
        (self.data[i], self.missing[i])
    }

    /// Place `at` has not been overwritten.
    pub(super) fn holds(&self, at: u64) -> bool {
        self.written.saturating_sub(at) <= self.capacity()
    }
}

/// The current run: samples on one uniform grid since the last (re)start.
#[derive(Debug, Clone, Copy)]
struct Run {
    first_sequence: u64,
    first_ns: u64,
    last_sequence: u64,
    last_ns: u64,
    last_value: [f64; CHANNELS],
}

impl Run {
    fn start(sequence: u64, t_ns: u64, x: [f64; CHANNELS]) -> Run {
        Run {
            first_sequence: sequence,
            first_ns: t_ns,
            last_sequence: sequence,
            last_ns: t_ns,
            last_value: x,
        }
    }

    /// The mean sample period of the run, s (`None` before its second sample).
    fn period_s(&self) -> Option<f64> {
        let steps = self.last_sequence - self.first_sequence;
        (steps > 0).then(|| (self.last_ns - self.first_ns) as f64 * 1e-9 / steps as f64)
    }
}

/// Validation, the run's grid and the ring.
#[derive(Debug)]
pub(super) struct SampleInput {
    pub(super) ring: Ring,
    run: Option<Run>,
    /// Samples refused since the last accepted one (so a gap they explain is not `lost`).
    refused_pending: u64,
    /// Longest gap filled in place, samples; a longer one restarts the window.
    max_fill: u64,
    pub(super) counters: Counters,
    /// Incremented at every (re)start, so results of an older run are recognised.
    pub(super) run_id: u64,
}

impl SampleInput {
    pub(super) fn new(ring_capacity: usize, max_fill: u64) -> SampleInput {
        SampleInput {
            ring: Ring::new(ring_capacity),
            run: None,
            refused_pending: 0,
            max_fill,
            counters: Counters::default(),
            run_id: 0,
        }
    }

    /// The run's sample period, s, and its newest sample's timestamp, ns.
    pub(super) fn timing(&self) -> Option<(f64, u64)> {
        let run = self.run?;
        Some((run.period_s()?, run.last_ns))
    }

    /// The newest sample's timestamp, ns.
    pub(super) fn last_ns(&self) -> Option<u64> {
        self.run.map(|r| r.last_ns)
    }

    fn restart(&mut self, sequence: u64, t_ns: u64, x: [f64; CHANNELS]) -> PushOutcome {
        if self.run.is_some() {
            self.counters.restarts += 1;
        }
        self.run = Some(Run::start(sequence, t_ns, x));
        self.ring.written = 0;
        self.ring.push(x, false);
        self.refused_pending = 0;
        self.run_id += 1;
        self.counters.accepted += 1;
        PushOutcome::Restarted
    }

    fn refuse(&mut self, why: Refusal) -> PushOutcome {
        match why {
            Refusal::Invalid => self.counters.invalid += 1,
            Refusal::OutOfOrder => self.counters.out_of_order += 1,
            Refusal::TimeNotIncreasing => self.counters.time_not_increasing += 1,
        }
        if why != Refusal::OutOfOrder {
            self.refused_pending += 1;
        }
        PushOutcome::Refused(why)
    }

    /// One sample: sequence number, timestamp (ns), accelerations (m/s²). O(1) work plus at
    /// most `max_fill` places filled.
    pub(super) fn push(&mut self, sequence: u64, t_ns: u64, x: [f64; CHANNELS]) -> PushOutcome {
        if !x.iter().all(|v| v.abs() <= MAX_ACCELERATION_M_S2) {
            return self.refuse(Refusal::Invalid);
        }
        let Some(run) = self.run else {
            return self.restart(sequence, t_ns, x);
        };
        if sequence <= run.last_sequence {
            if sequence < run.last_sequence && t_ns > run.last_ns {
                // The sender started again (its sequence restarted): a new window.
                return self.restart(sequence, t_ns, x);
            }
            return self.refuse(Refusal::OutOfOrder);
        }
        if t_ns <= run.last_ns {
            return self.refuse(Refusal::TimeNotIncreasing);
        }
        let steps = sequence - run.last_sequence;
        let gap = steps - 1;
        // The places skipped and never refused here were never received: counted whether
        // they are filled or the window restarts (a flood that overflowed the queue).
        self.counters.lost += gap.saturating_sub(self.refused_pending);
        if let Some(p) = run.period_s() {
            let ratio = (t_ns - run.last_ns) as f64 * 1e-9 / (steps as f64 * p);
            if !(0.5..=2.0).contains(&ratio) {
                return self.restart(sequence, t_ns, x);
            }
        }
        if gap > self.max_fill {
            return self.restart(sequence, t_ns, x);
        }
        self.counters.filled += gap;
        self.refused_pending = 0;
        for _ in 0..gap {
            self.ring.push(run.last_value, true);
        }
        self.ring.push(x, false);
        self.counters.accepted += 1;
        self.run = Some(Run {
            last_sequence: sequence,
            last_ns: t_ns,
            last_value: x,
            ..run
        });
        PushOutcome::Accepted { filled: gap }
    }
}
