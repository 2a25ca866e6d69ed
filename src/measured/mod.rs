//! Measured vibration: the online estimate of the dominant measured frequencies near the
//! model's first mode and end-effector mode, from accelerations sampled on the platform.
//!
//! The service feeds every accelerometer sample to a [`VibrationTracker`] ([`VibrationTracker::push`]),
//! tells it the model's f1 and end-effector mode of the latest estimate
//! ([`VibrationTracker::set_model`]), lets it work a bounded amount per loop iteration
//! ([`VibrationTracker::work`]) and reads the latest result ([`VibrationTracker::measured`]).
//! Nothing here allocates after [`VibrationTracker::new`], no call loops without a bound, and
//! bad input is a counted refusal or a [`MeasuredStatus`], never a panic.
//!
//! # The method: a zoom DFT of a sliding window, centred on the predicted modes
//!
//! Samples x_c(k) (channels c = x, y, z, m/s², at the sender's sample period P) fill a ring.
//! Every `update_interval_s` of new samples an evaluation takes the last N = window_s / P
//! samples, removes each channel's mean m_c (gravity, the path's slow acceleration) and
//! weights them with a periodic Hann window w(k) = ½ − ½ cos(2πk/N); then, for each tracked
//! mode with predicted frequency f̂, it evaluates the summed power spectrum
//!
//!   S(f) = Σ_c |Σ_k w(k) (x_c(k) − m_c) e^{−i2πfkP}|²
//!
//! on a grid over the search band [f̂(1 − b), f̂(1 + b)] (b = `band_rel`), widened by the Hann
//! main lobe (±2/T, T = NP) on each side, with spacing 1/(2T) (twice zero-padded). The sum
//! over the three axes does not depend on how the sensor is turned on the platform. The
//! peak is the largest local maximum inside the search band whose power is at least
//! `min_peak_ratio` times the floor (the median of the grid outside ±2/T of the largest
//! bin): the dominant measured frequency near f̂. (Not the peak nearest f̂: the periodogram
//! of a randomly excited mode has random ripples in its tail, 1/T apart, that stand above
//! the floor.) A neighbouring mode inside the band competes with the tracked one, so the
//! band (`band_rel`) should end before the model's next mode. The peak is refined by a
//! parabola through the logarithm of the three grid powers around it, then by a second
//! parabola through three powers ±¼ of a grid step around that.
//!
//! Why this and not a tracking filter bank or a subspace fit: the grid moves with the model's
//! prediction at no cost (there is no filter state to re-tune, and a band jump is not a
//! transient), the cost of one evaluation is exactly N × (bins) multiply-adds, cut into
//! slices of `work_per_poll` units so that no loop iteration does more; a frequency that
//! moves during the window gives the peak of its window average, which is what a window of
//! length T can tell; and the accuracy has a known limit. For a mode of damping ζ at ω rad/s
//! under broadband excitation, a window of T seconds gives a relative standard deviation
//! σ_f/f ≈ √(ζ/(ωT)) (the statistical limit of a record of length T); for a clean sinusoid
//! the peak location is exact up to the leakage of other components through the Hann
//! sidelobes. Two modes closer than about 2/T (the Hann main lobe) merge into one peak: the
//! window's resolution. A subspace fit would resolve closer modes for more work per update
//! and no simpler bound; a filter bank would need its filter states re-tuned as the model's
//! frequency moves.
//!
//! # Input
//!
//! A sample has the sender's sequence number (incremented by one per sample) and timestamp
//! (ns). The sequence gives the sample's place in the uniform grid; the timestamps give the
//! sample period (their average slope over the run). Per sample:
//! - a component not finite or beyond ±[`MAX_ACCELERATION_M_S2`]: refused (counted
//!   `invalid`); its place becomes a missing sample;
//! - a sequence not after the previous one: refused (`out_of_order`), unless its timestamp
//!   is later, which is a sender restart: the window restarts (`restarts`);
//! - a timestamp not after the previous one: refused (`time_not_increasing`), a missing sample;
//! - a step whose timestamps and sequence numbers disagree (Δt/Δsequence outside [½, 2] of
//!   the period so far: a paused sender, a changed rate) or a gap of more than
//!   `max_missing_fraction` of the window: the window restarts (`restarts`);
//! - a smaller gap in the sequence: the missing samples hold the last value (`filled`; of
//!   them, those never refused here are `lost`).
//!
//! An evaluation whose window holds more than `max_missing_fraction` of missing samples
//! answers [`MeasuredStatus::InputFault`]. The counters ([`Counters`]) account for every
//! sample: none is dropped without one.

mod input;
mod params;
mod spectrum;
mod tracker;

pub use input::{Counters, PushOutcome, Refusal, MAX_ACCELERATION_M_S2};
pub use params::{ParamsError, TrackerParams};
pub use spectrum::MAX_BINS;
pub use tracker::{Measured, MeasuredMode, VibrationTracker};

/// Axes of an acceleration sample (x, y, z).
pub const CHANNELS: usize = 3;

crate::status::status_codes! {
    /// What a tracked measured frequency is, as carried on the wire (`u32`): `Ok` with a
    /// number, every other code without one. The values never change; a receiver treats an
    /// unknown code as "no measurement".
    pub enum MeasuredStatus {
        /// A peak was found: the measured frequency is valid.
        Ok = 0, "ok";
        /// No vibration sample arrived within `silence_s` (or ever): the input is absent.
        NoInput = 1, "no_input";
        /// Samples arrive but the window is not full yet (since the start or a restart), or
        /// its first evaluation is still running.
        Filling = 2, "filling";
        /// No peak in the search band stands `min_peak_ratio` above the floor.
        NoPeak = 3, "no_peak";
        /// The model's frequency for this track is not known (the estimate is not ok, or it
        /// has no end-effector mode): there is no band to search.
        NoModel = 4, "no_model";
        /// The search band reaches above 0.4 × the input's sample rate.
        BandTooHigh = 5, "band_too_high";
        /// The search band reaches below 4/T: the window (T) holds too few periods.
        BandTooLow = 6, "band_too_low";
        /// The window holds more missing samples (refused, lost) than `max_missing_fraction`.
        InputFault = 7, "input_fault";
        /// The input's sample rate is above `max_sample_rate_hz`: the window would not fit.
        RateTooHigh = 8, "rate_too_high";
    }
}

impl MeasuredStatus {
    /// `true` only for [`MeasuredStatus::Ok`].
    pub const fn is_ok(self) -> bool {
        matches!(self, MeasuredStatus::Ok)
    }
}
