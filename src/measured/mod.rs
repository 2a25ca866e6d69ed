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
//! # At the band's edges
//!
//! A component just outside the band (the model further off than `band_rel`, or its
//! prediction jumping to a neighbouring mode for a cycle) puts its Hann sidelobes into the
//! band: the first, 2.36/T from it at −31.5 dB, is a local maximum that a clean signal's
//! floor lets stand far above `min_peak_ratio`. Read as a peak it would be a wrong frequency
//! given as ok (a 29.4 Hz sine read as 30.58 Hz with T = 2 s). So the band's peak at f_p,
//! power P_p, is refused as [`MeasuredStatus::OutsideBand`] when a grid point outside the
//! band (in the margins), at f_i with power P_i > P_p, could have leaked it:
//!
//!   P_p ≤ 100 · P_i · L(|f_i − f_p| T),  L(x) = 1 (x ≤ 2), 1/(π x (x² − 1))² (x > 2),
//!
//! L being the envelope of a sinusoid's Hann leakage (within 0.9 dB of each sidelobe's crest,
//! falling as x⁻⁶); the factor 100 covers a grid point a quarter bin off the component (×2.2
//! at the first sidelobe), a damped mode's wider skirt near its main lobe, and the noise on
//! both powers. A component beyond the margins leaks less into the band than into the
//! margin's points, which sample each of its sidelobes there. A peak whose grid point is in
//! the band but whose refined frequency is outside [f̂(1 − b), f̂(1 + b)] is `outside_band`
//! too. So an ok answer is a peak inside the band that no stronger component outside it
//! explains. The price: a stronger component outside the band masks, in the band, a peak
//! weaker than 100 · L of it: −10.6 dB at 2.36/T (1.18 Hz at T = 2 s), −28 dB at 4.4/T,
//! −45.5 dB at 8.5/T.
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
        /// The strongest component of the searched spectrum (the band and its margins of
        /// 2/T) lies outside the search band: the vibration near the prediction is not in
        /// the band (the model is further off than `band_rel`, or a neighbouring mode
        /// dominates), and what the band holds may be its leakage.
        OutsideBand = 9, "outside_band";
    }
}

impl MeasuredStatus {
    /// `true` only for [`MeasuredStatus::Ok`].
    pub const fn is_ok(self) -> bool {
        matches!(self, MeasuredStatus::Ok)
    }
}
