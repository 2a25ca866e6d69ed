//! Modal identification from measured vibration: natural frequencies, damping ratios and
//! mode shapes of a recorded output (an accelerometer, an IMU on the platform), with their
//! uncertainty. Pure signal processing on arrays and streams: no scene, no file format (the
//! command line reads the files, the study layer pairs the modes with the model's).
//!
//! **Method: covariance-driven stochastic subspace identification (SSI-cov).** Under
//! broadband (white-noise-like) excitation the output covariances R_i = E[y_{k+i} y_kᵀ] of a
//! linear system are the impulse response of its modes: R_i = C Aⁱ⁻¹ G. The record is
//! decimated to the band ([`decimate`]), its covariances accumulated at lags 0 … 2p − 1 in
//! bounded memory ([`covariance`]), stacked into a block Hankel matrix whose SVD gives a
//! state-space model per order, and the poles of every order ([`ssi`]) form the
//! stabilisation diagram; poles stable in frequency, damping and shape are clustered into
//! modes ([`cluster`]), each with a jackknife uncertainty over the window's segments
//! ([`window`]). [`stream`] takes the record sample by sample, checks its time, and
//! identifies windows as they complete; [`align`] puts a measured input recorded on its own
//! clock onto the responses' clock.
//!
//! **What a record can tell.** For a mode at ω (rad/s) with damping ratio ζ in a record of
//! T seconds, the statistical limits are about σ_f/f ≈ √(ζ/(ωT)) and σ_ζ/ζ ≈ 1/√(ζωT)
//! ([`statistical_limit`]): a 5 Hz mode with ζ = 1 % in 60 s is known to ≈ 0.23 % in
//! frequency and ≈ 23 % in damping, whatever the method.
//!
//! Method, defaults and measured accuracy: `docs/identify.md`.

pub mod align;
pub mod cluster;
pub mod covariance;
pub mod decimate;
pub mod fft;
pub mod frf;
pub mod params;
pub mod ssi;
pub mod stream;
pub mod window;

pub use align::{Aligned, Aligner};
pub use cluster::{DiagramPole, Stability};
pub use params::{IdentifyParams, MAX_CHANNELS, MAX_OVERLAP, MIN_RATE_OVER_BAND};
pub use stream::{Identifier, WindowResult};
pub use window::{IdentifiedMode, WindowStatus};

/// Errors of the identification.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IdentifyError {
    /// A parameter out of its bounds.
    #[error("{0}")]
    Params(String),
    /// The record cannot be identified (time not increasing, too few samples).
    #[error("{0}")]
    Input(String),
    /// The record's sample rate is below [`MIN_RATE_OVER_BAND`] × the band's top
    /// ([`IdentifyParams::to_hz`]).
    #[error("{}", rate_too_low(*.rate_hz, *.to_hz, "to_hz"))]
    RateTooLow {
        /// The record's nominal sample rate (median step), Hz.
        rate_hz: f64,
        /// The band's top asked for, Hz.
        to_hz: f64,
    },
}

impl IdentifyError {
    /// The message with the band's top called `to_hz` (the command line passes its flag);
    /// the `Display` text names the parameter's field, `to_hz`.
    pub fn render(&self, to_hz_name: &str) -> String {
        match self {
            IdentifyError::RateTooLow { rate_hz, to_hz } => {
                rate_too_low(*rate_hz, *to_hz, to_hz_name)
            }
            other => other.to_string(),
        }
    }
}

/// [`IdentifyError::RateTooLow`]'s message, the band's top called `to_hz_name`.
fn rate_too_low(rate_hz: f64, to_hz: f64, to_hz_name: &str) -> String {
    format!(
        "sample rate {rate_hz:.4} Hz is too low for the band up to {to_hz} Hz (needs ≥ {MIN_RATE_OVER_BAND} × the band's top: lower {to_hz_name} to ≤ {:.4} Hz)",
        rate_hz / MIN_RATE_OVER_BAND
    )
}

/// The statistical limits (σ_f/f, σ_ζ/ζ) ≈ (√(ζ/(ωT)), 1/√(ζωT)) of a mode at `frequency_hz`
/// with damping ratio `zeta` in a record of `duration_s` seconds.
pub fn statistical_limit(frequency_hz: f64, zeta: f64, duration_s: f64) -> (f64, f64) {
    let w = 2.0 * std::f64::consts::PI * frequency_hz;
    (
        (zeta / (w * duration_s)).sqrt(),
        1.0 / (zeta * w * duration_s).sqrt(),
    )
}

/// Identify the record `y` (row-major: sample k's channels at `y[k l .. (k + 1) l]`) sampled
/// at times `t_s`: every window's result, in order.
pub fn identify(
    t_s: &[f64],
    y: &[f64],
    channels: usize,
    p: &IdentifyParams,
) -> Result<Vec<WindowResult>, IdentifyError> {
    identify_with_inputs(t_s, y, channels, &[], 0, p)
}

/// As [`identify`], with `inputs` measured inputs `u` (row-major like `y`; 0: output-only
/// SSI-cov, else H1 and its modal fit, [`frf`]).
pub fn identify_with_inputs(
    t_s: &[f64],
    y: &[f64],
    channels: usize,
    u: &[f64],
    inputs: usize,
    p: &IdentifyParams,
) -> Result<Vec<WindowResult>, IdentifyError> {
    if channels == 0 || y.len() != t_s.len() * channels || u.len() != t_s.len() * inputs {
        return Err(IdentifyError::Input(format!(
            "{} values for {} times × {channels} channels, {} for {inputs} inputs",
            y.len(),
            t_s.len(),
            u.len()
        )));
    }
    let mut id = Identifier::with_inputs(channels, inputs, *p)?;
    let mut sample = vec![0.0; channels + inputs];
    for (k, &t) in t_s.iter().enumerate() {
        sample[..channels].copy_from_slice(&y[k * channels..(k + 1) * channels]);
        sample[channels..].copy_from_slice(&u[k * inputs..(k + 1) * inputs]);
        id.push(t, &sample)?;
    }
    id.finish()
}
