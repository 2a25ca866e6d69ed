//! The identification's tunables, with finite bounds and documented defaults.

use super::IdentifyError;

/// Most measured channels (the lag products cost channels² per sample and lag).
pub const MAX_CHANNELS: usize = 32;
/// Largest model order of the stabilisation diagram.
pub const MAX_ORDER: usize = 200;
/// Most block rows of the Hankel matrix (its side is block rows × channels).
pub const MAX_BLOCK_ROWS: usize = 400;
/// Largest side of the Hankel matrix (its SVD costs side³).
pub const MAX_HANKEL_SIDE: usize = 600;
/// Largest window overlap (a sample feeds at most 1 / (1 − overlap) windows).
pub const MAX_OVERLAP: f64 = 0.9;
/// The sample rate must be at least this multiple of the band's top (after decimation the
/// rate is kept at ≥ 3 × the top, so the anti-aliasing filter's transition lies above it).
pub const MIN_RATE_OVER_BAND: f64 = 2.5;
/// Most segments of the jackknife.
pub const MAX_SEGMENTS: usize = 64;

/// How the modes are identified (SSI-cov, the stabilisation diagram and the clustering).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IdentifyParams {
    /// Lowest frequency of the band, Hz (default 0.5): poles below are not modes.
    pub from_hz: f64,
    /// Highest frequency of the band, Hz (default 50): the record is decimated to about
    /// 3 × this rate after an anti-aliasing filter; poles above are not modes.
    pub to_hz: f64,
    /// Highest model order (even, 4 ..= [`MAX_ORDER`]; default 60): orders 2, 4, …, this.
    pub max_order: usize,
    /// Block rows p of the Hankel matrix (lags 1 … 2p − 1 at the decimated rate); `None`:
    /// max(40, max_order / channels + 2), so the Hankel matrix can hold every order.
    pub block_rows: Option<usize>,
    /// A pole is stable when its frequency moved by at most this fraction from the nearest
    /// pole of the order below (default 0.01).
    pub frequency_tol: f64,
    /// … and its damping ratio by at most this fraction (default 0.05) …
    pub damping_tol: f64,
    /// … and its shape's MAC with that pole is at least this (default 0.98).
    pub mac_min: f64,
    /// Poles with a larger damping ratio are not modes (default 0.2).
    pub max_damping_ratio: f64,
    /// A cluster of stable poles is a mode when it holds poles of at least this fraction of
    /// the orders (default 0.25, at least 3 poles).
    pub min_stable_fraction: f64,
    /// Segments of a window for the jackknife uncertainty (default 8; 2 ..= [`MAX_SEGMENTS`]).
    pub segments: usize,
    /// Window length, s (`None`: the whole record is one window).
    pub window_s: Option<f64>,
    /// Overlap of consecutive windows, a fraction in [0, [`MAX_OVERLAP`]] (default 0.5).
    pub overlap: f64,
}

impl Default for IdentifyParams {
    fn default() -> Self {
        IdentifyParams {
            from_hz: 0.5,
            to_hz: 50.0,
            max_order: 60,
            block_rows: None,
            frequency_tol: 0.01,
            damping_tol: 0.05,
            mac_min: 0.98,
            max_damping_ratio: 0.2,
            min_stable_fraction: 0.25,
            segments: 8,
            window_s: None,
            overlap: 0.5,
        }
    }
}

impl IdentifyParams {
    /// Refuses values out of their bounds (one line naming the parameter).
    pub fn validate(&self, channels: usize) -> Result<(), IdentifyError> {
        let bad = |what: String| Err(IdentifyError::Params(what));
        if channels == 0 || channels > MAX_CHANNELS {
            return bad(format!(
                "{channels} channels: 1 ..= {MAX_CHANNELS} measured channels are identified"
            ));
        }
        if !(self.from_hz.is_finite() && self.from_hz >= 0.0) {
            return bad(format!("from_hz {}: must be finite and ≥ 0", self.from_hz));
        }
        if !(self.to_hz.is_finite() && self.to_hz > self.from_hz) {
            return bad(format!(
                "to_hz {}: must be finite and > from_hz {}",
                self.to_hz, self.from_hz
            ));
        }
        if self.max_order < 4 || self.max_order > MAX_ORDER || !self.max_order.is_multiple_of(2) {
            return bad(format!(
                "max_order {}: must be even, in 4 ..= {MAX_ORDER}",
                self.max_order
            ));
        }
        let p = self.block_rows(channels);
        if !(2..=MAX_BLOCK_ROWS).contains(&p) || p * channels > MAX_HANKEL_SIDE {
            return bad(format!(
                "block_rows {p}: must be in 2 ..= {MAX_BLOCK_ROWS} with block rows × channels ≤ {MAX_HANKEL_SIDE}"
            ));
        }
        if (p - 1) * channels < self.max_order {
            return bad(format!(
                "block_rows {p} × {channels} channel(s) cannot hold order {}: (block_rows − 1) × channels must be ≥ max_order",
                self.max_order
            ));
        }
        let frac = |x: f64| x.is_finite() && x > 0.0 && x < 1.0;
        if !frac(self.frequency_tol) {
            return bad(format!(
                "frequency_tol {}: must be in (0, 1)",
                self.frequency_tol
            ));
        }
        if !frac(self.damping_tol) {
            return bad(format!(
                "damping_tol {}: must be in (0, 1)",
                self.damping_tol
            ));
        }
        if !frac(self.mac_min) {
            return bad(format!("mac_min {}: must be in (0, 1)", self.mac_min));
        }
        if !frac(self.max_damping_ratio) {
            return bad(format!(
                "max_damping_ratio {}: must be in (0, 1)",
                self.max_damping_ratio
            ));
        }
        if !frac(self.min_stable_fraction) {
            return bad(format!(
                "min_stable_fraction {}: must be in (0, 1)",
                self.min_stable_fraction
            ));
        }
        if self.segments < 2 || self.segments > MAX_SEGMENTS {
            return bad(format!(
                "segments {}: must be in 2 ..= {MAX_SEGMENTS}",
                self.segments
            ));
        }
        if let Some(w) = self.window_s {
            if !(w.is_finite() && w > 0.0) {
                return bad(format!("window {w} s: must be finite and > 0"));
            }
        }
        if !(self.overlap.is_finite() && (0.0..=MAX_OVERLAP).contains(&self.overlap)) {
            return bad(format!(
                "overlap {}: must be in [0, {MAX_OVERLAP}]",
                self.overlap
            ));
        }
        Ok(())
    }

    /// The block rows used for `channels` channels (the given or the default).
    pub fn block_rows(&self, channels: usize) -> usize {
        self.block_rows
            .unwrap_or_else(|| 40.max(self.max_order / channels.max(1) + 2))
    }

    /// The block rows of input-output data of `l` outputs and `m` inputs: the given, or
    /// max(max_order / min(l, m) + 2, min(100, [`MAX_HANKEL_SIDE`] / max(l, m))), so the
    /// impulse response's Hankel matrix (p l × p m) holds every order and its 2p lags
    /// (1.2 s at 166.7 Hz, a 1 kHz record decimated for the default band) span the beat of two modes 1 %
    /// apart at 10 Hz to a tenth (modes that close merged with 40 block rows).
    pub fn block_rows_io(&self, l: usize, m: usize) -> usize {
        self.block_rows.unwrap_or_else(|| {
            (self.max_order / l.min(m).max(1) + 2).max(100.min(MAX_HANKEL_SIDE / l.max(m).max(1)))
        })
    }

    /// [`IdentifyParams::validate`] for `l` outputs and `m` measured inputs (1 ..=
    /// [`MAX_CHANNELS`] together): the Hankel matrix of the impulse response, p l × p m,
    /// must hold every order and each side be ≤ [`MAX_HANKEL_SIDE`].
    pub fn validate_io(&self, l: usize, m: usize) -> Result<(), IdentifyError> {
        self.validate(l)?;
        if m == 0 || l + m > MAX_CHANNELS {
            return Err(IdentifyError::Params(format!(
                "{l} output(s) and {m} input(s): 1 ..= {MAX_CHANNELS} channels in all, at least one input"
            )));
        }
        let p = self.block_rows_io(l, m);
        if !(2..=MAX_BLOCK_ROWS).contains(&p) || p * l.max(m) > MAX_HANKEL_SIDE {
            return Err(IdentifyError::Params(format!(
                "block_rows {p}: must be in 2 ..= {MAX_BLOCK_ROWS} with block rows × max(outputs, inputs) ≤ {MAX_HANKEL_SIDE}"
            )));
        }
        if (p - 1) * l < self.max_order || p * m < self.max_order {
            return Err(IdentifyError::Params(format!(
                "block_rows {p} cannot hold order {} with {l} output(s) and {m} input(s): (block_rows − 1) × outputs and block_rows × inputs must be ≥ max_order",
                self.max_order
            )));
        }
        Ok(())
    }

    /// The orders of the stabilisation diagram: 2, 4, …, `max_order`.
    pub fn orders(&self) -> impl Iterator<Item = usize> {
        (1..=self.max_order / 2).map(|k| 2 * k)
    }
}
