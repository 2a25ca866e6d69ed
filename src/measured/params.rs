//! [`TrackerParams`]: every tunable of the measured-frequency tracker, with finite bounds.

/// Largest window the tracker holds, samples (`window_s × max_sample_rate_hz`): its ring and
/// scratch then take 2.5 × 24 B × this ≈ 16 MB.
pub const MAX_WINDOW_SAMPLES: usize = 1 << 18;

/// Parameters of [`super::VibrationTracker`]. Copy; [`Default`] documents every default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackerParams {
    /// Length T of the analysed window, s, in [0.25, 60]. Default 2 s: resolution 2/T = 1 Hz
    /// between two modes, a statistical limit σ_f/f ≈ √(ζ/(ωT)) (0.5 % at 29 Hz, ζ = 1 %),
    /// and a mode must have at least 4/T = 2 Hz.
    pub window_s: f64,
    /// Half-width b of the search band around each predicted frequency f̂, relative: the
    /// band is [f̂(1 − b), f̂(1 + b)], b in [0.01, 0.5]. Default 0.1: a rope whose effective
    /// EA is 80 % of the catalogue value moves an axial mode by −11 %; a wider band admits
    /// the model's neighbouring modes (the paper robot's second end-effector mode is 9-15 %
    /// above its first along the circle), which then compete for the dominant peak.
    pub band_rel: f64,
    /// How far above the floor (the band's median power away from the largest peak) a peak
    /// must stand, ratio of powers in [2, 1e6]. Default 10 (10 dB): three axes of noise
    /// alone reach it in one bin with probability ~1e-9 (χ² with 6 degrees of freedom).
    pub min_peak_ratio: f64,
    /// Highest input sample rate, Hz, in [10, 100000]: sizes the ring (`window_s ×` this
    /// samples, at most `MAX_WINDOW_SAMPLES`). Default 4000 Hz.
    pub max_sample_rate_hz: f64,
    /// Time between two evaluations, in samples' time, s, in [0.001, 60]. Default 0.1 s.
    pub update_interval_s: f64,
    /// Work per [`super::VibrationTracker::work`] call, in units of one window sample of one
    /// spectrum bin (three multiply-adds and a phasor step), in [64, 1048576]. Default 1024:
    /// about 2-3 µs here.
    pub work_per_poll: u32,
    /// Largest share of missing samples (refused or lost) in an evaluated window, in [0, 0.5];
    /// a single gap longer than this share of the window restarts it. Default 0.01.
    pub max_missing_fraction: f64,
    /// With no sample for this long, s, in [0.001, 60], the input is absent
    /// ([`super::MeasuredStatus::NoInput`]). Default 0.5 s.
    pub silence_s: f64,
}

impl Default for TrackerParams {
    fn default() -> TrackerParams {
        TrackerParams {
            window_s: 2.0,
            band_rel: 0.1,
            min_peak_ratio: 10.0,
            max_sample_rate_hz: 4000.0,
            update_interval_s: 0.1,
            work_per_poll: 1024,
            max_missing_fraction: 0.01,
            silence_s: 0.5,
        }
    }
}

/// A parameter outside its bounds.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ParamsError {
    /// A value outside its documented range (NaN included).
    #[error("{name} = {value} must be in [{lo}, {hi}]")]
    OutOfRange {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// Lower bound.
        lo: f64,
        /// Upper bound.
        hi: f64,
    },
    /// `window_s × max_sample_rate_hz` over `MAX_WINDOW_SAMPLES`.
    #[error("window_s × max_sample_rate_hz = {samples} samples, more than {MAX_WINDOW_SAMPLES}")]
    WindowTooLong {
        /// The samples the window would hold.
        samples: f64,
    },
}

impl TrackerParams {
    /// Checks every bound.
    pub fn validate(&self) -> Result<(), ParamsError> {
        let check = |name, value: f64, lo: f64, hi: f64| {
            if (lo..=hi).contains(&value) {
                Ok(())
            } else {
                Err(ParamsError::OutOfRange {
                    name,
                    value,
                    lo,
                    hi,
                })
            }
        };
        check("window_s", self.window_s, 0.25, 60.0)?;
        check("band_rel", self.band_rel, 0.01, 0.5)?;
        check("min_peak_ratio", self.min_peak_ratio, 2.0, 1e6)?;
        check("max_sample_rate_hz", self.max_sample_rate_hz, 10.0, 1e5)?;
        check("update_interval_s", self.update_interval_s, 0.001, 60.0)?;
        check(
            "work_per_poll",
            f64::from(self.work_per_poll),
            64.0,
            1048576.0,
        )?;
        check("max_missing_fraction", self.max_missing_fraction, 0.0, 0.5)?;
        check("silence_s", self.silence_s, 0.001, 60.0)?;
        let samples = self.window_s * self.max_sample_rate_hz;
        if samples > MAX_WINDOW_SAMPLES as f64 {
            return Err(ParamsError::WindowTooLong { samples });
        }
        Ok(())
    }

    /// The most samples a window holds.
    pub(super) fn window_capacity(&self) -> usize {
        (self.window_s * self.max_sample_rate_hz).ceil() as usize + 1
    }
}
