//! Input shaping of end-effector paths: ZV, ZVD and EI shapers whose impulse times follow a
//! mode's frequency and damping as they change along the path, offline or online.
//!
//! A shaper convolves the commanded path with a few impulses of amplitudes A_i (Σ A_i = 1)
//! at times t_i, chosen so that the vibration the impulses leave in a damped mode of
//! natural frequency ω and ratio ζ cancels. With K = exp(−ζπ/√(1−ζ²)) and the damped
//! half-period T/2 = π/(ω√(1−ζ²)):
//!
//! | shaper | amplitudes | times |
//! |---|---|---|
//! | ZV | 1/(1+K), K/(1+K) | 0, T/2 |
//! | ZVD | 1/(1+K)², 2K/(1+K)², K²/(1+K)² | 0, T/2, T |
//! | EI (V = V_tol = 5 %) | (1+V)/4, (1−V)K/2, (1+V)K²/4, over their sum | 0, T/2, T |
//!
//! (EI as designed for an undamped mode, its later impulses scaled by K and K² as ZVD's
//! are: the residual at the design frequency is K²V/Σ ≤ V_tol, exactly V_tol undamped.) ZV leaves no residual vibration at the design
//! frequency and ZVD none with a zero slope there too; EI trades a V_tol residual at the
//! design frequency for a wider band below V_tol. [`Impulses::residual_fraction`] is the
//! closed-form residual of each at any frequency (the sensitivity curve).
//!
//! **Time-varying.** [`OnlineShaper::push`] takes one sample of the input path and the mode
//! (frequency, ratio) at the pose the output is at now, and returns the shaped sample
//! y(t) = Σ A_i(t) x(t − t_i(t)) (linear interpolation between input samples; before the
//! first sample, the first sample). The input samples are kept in a ring buffer sized at
//! construction for the longest delay the lowest accepted frequency needs, so `push` does
//! not allocate and is O(impulses). After the input ends, pushing its last sample again
//! lets the output settle; the shaper adds the last impulse time (T/2 for ZV, T for ZVD
//! and EI) to a move. The design frequency follows the one given through a critically
//! damped filter ([`DESIGN_FILTER_S`]), so a jump of the estimate jumps neither the path
//! nor its velocity.

use nalgebra::Vector3;

/// Tolerated residual vibration of the EI shaper at its design frequency (5 %).
pub const EI_V_TOL: f64 = 0.05;
/// Lowest design frequency an [`OnlineShaper`] accepts by default, Hz (its ring buffer holds
/// one period of it).
pub const DEFAULT_MIN_FREQUENCY_HZ: f64 = 0.5;
/// Time constant of the critically damped filter through which an [`OnlineShaper`]'s
/// design frequency follows the one given, s. The estimate's frequency may jump (the
/// end-effector mode passing an avoided crossing moves its character to the neighbouring
/// mode); the impulse times follow it smoothly (the delays' rate continuous), since a
/// jump of a delay is a jump of the path, a jump of its rate a jump of the velocity, and
/// a change of the rate over a time near the mode's period (20 ms on the paper robot's
/// 31 Hz mode) an acceleration bump that excites it by tens of µm. A ramp is followed
/// with a lag of twice this (0.2 s; the paper robot's end-effector mode drifts ~10 %/s on
/// a 0.5 m move in 0.5 s, so the design lags by ~2 %, which ZVD and EI hardly feel).
pub const DESIGN_FILTER_S: f64 = 0.1;
/// Most samples an [`OnlineShaper`]'s ring buffer may hold (the ratio of the sample rate to
/// the lowest design frequency, plus 2).
pub const MAX_RING_SAMPLES: usize = 10_000_000;

/// Which shaper.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShaperKind {
    /// Zero vibration: two impulses, half a damped period apart.
    Zv,
    /// Zero vibration and derivative: three impulses over one damped period.
    Zvd,
    /// Extra insensitive (V_tol = [`EI_V_TOL`]): three impulses over one damped period.
    Ei,
}

impl ShaperKind {
    /// The name on the command line (`zv`, `zvd`, `ei`).
    pub fn as_str(self) -> &'static str {
        match self {
            ShaperKind::Zv => "zv",
            ShaperKind::Zvd => "zvd",
            ShaperKind::Ei => "ei",
        }
    }

    /// The kind named `s` (`zv`, `zvd`, `ei`).
    pub fn from_name(s: &str) -> Option<ShaperKind> {
        match s {
            "zv" => Some(ShaperKind::Zv),
            "zvd" => Some(ShaperKind::Zvd),
            "ei" => Some(ShaperKind::Ei),
            _ => None,
        }
    }

    /// The last impulse time in damped periods (ZV ½, ZVD and EI 1): the time the shaper
    /// adds to a move.
    pub fn duration_periods(self) -> f64 {
        match self {
            ShaperKind::Zv => 0.5,
            ShaperKind::Zvd | ShaperKind::Ei => 1.0,
        }
    }
}

/// Why a shaper could not be designed or built.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ShapingError {
    /// The design frequency is not a finite positive number (or below the ring's bound).
    #[error(
        "shaper design frequency {0:?} Hz must be finite and at least the shaper's lowest ({1} Hz)"
    )]
    BadFrequency(f64, f64),
    /// The damping ratio is not in [0, 1).
    #[error("shaper damping ratio {0:?} must be finite and in [0, 1)")]
    BadDamping(f64),
    /// The sample period is not a finite positive number.
    #[error("sample period {0:?} s must be finite and > 0")]
    BadSamplePeriod(f64),
    /// The ring buffer would be too large.
    #[error("the shaper would need {0} samples of history (sample period / lowest frequency too small; at most {MAX_RING_SAMPLES})")]
    RingTooLarge(usize),
}

/// The impulses of one shaper design: `n` amplitudes (sum 1) and times (s, the first 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impulses {
    /// Number of impulses (2 or 3).
    pub n: usize,
    /// Amplitudes (the first `n`).
    pub amplitude: [f64; 3],
    /// Times, s (the first `n`, ascending, the first 0).
    pub time_s: [f64; 3],
}

impl Impulses {
    /// The impulses of `kind` for a mode of natural frequency `f_hz` (Hz, > 0) and damping
    /// ratio `zeta` (∈ [0, 1)).
    pub fn design(kind: ShaperKind, f_hz: f64, zeta: f64) -> Result<Impulses, ShapingError> {
        if !(f_hz.is_finite() && f_hz > 0.0) {
            return Err(ShapingError::BadFrequency(f_hz, 0.0));
        }
        if !(zeta.is_finite() && (0.0..1.0).contains(&zeta)) {
            return Err(ShapingError::BadDamping(zeta));
        }
        Ok(Self::design_unchecked(kind, f_hz, zeta))
    }

    fn design_unchecked(kind: ShaperKind, f_hz: f64, zeta: f64) -> Impulses {
        let root = (1.0 - zeta * zeta).sqrt();
        let half = 0.5 / (f_hz * root); // π/ω_d
        let k = (-zeta * std::f64::consts::PI / root).exp();
        match kind {
            ShaperKind::Zv => Impulses {
                n: 2,
                amplitude: [1.0 / (1.0 + k), k / (1.0 + k), 0.0],
                time_s: [0.0, half, 0.0],
            },
            ShaperKind::Zvd => {
                let d = (1.0 + k) * (1.0 + k);
                Impulses {
                    n: 3,
                    amplitude: [1.0 / d, 2.0 * k / d, k * k / d],
                    time_s: [0.0, half, 2.0 * half],
                }
            }
            ShaperKind::Ei => {
                let (a, b) = (0.25 * (1.0 + EI_V_TOL), 0.5 * (1.0 - EI_V_TOL));
                let d = a + b * k + a * k * k;
                Impulses {
                    n: 3,
                    amplitude: [a / d, b * k / d, a * k * k / d],
                    time_s: [0.0, half, 2.0 * half],
                }
            }
        }
    }

    /// The last impulse time, s: what the shaper adds to a move.
    pub fn duration_s(&self) -> f64 {
        self.time_s[self.n - 1]
    }

    /// The residual vibration these impulses leave in a mode of frequency `f_hz` and ratio
    /// `zeta`, as a fraction of what one unit impulse leaves (the sensitivity curve):
    /// e^{−ζω t_n} |Σ A_i e^{ζω t_i} e^{i ω_d t_i}|, ω_d = ω√(1−ζ²) (closed form).
    pub fn residual_fraction(&self, f_hz: f64, zeta: f64) -> f64 {
        let w = 2.0 * std::f64::consts::PI * f_hz;
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let tn = self.duration_s();
        let (mut c, mut s) = (0.0, 0.0);
        for i in 0..self.n {
            let e = self.amplitude[i] * (zeta * w * (self.time_s[i] - tn)).exp();
            c += e * (wd * self.time_s[i]).cos();
            s += e * (wd * self.time_s[i]).sin();
        }
        (c * c + s * s).sqrt()
    }
}

/// A time-varying shaper for a path sampled every `dt`: a bounded ring of past input
/// samples, no allocation after [`OnlineShaper::new`].
#[derive(Debug, Clone)]
pub struct OnlineShaper {
    kind: ShaperKind,
    dt_s: f64,
    min_frequency_hz: f64,
    /// Past inputs, newest at `head`.
    ring: Vec<Vector3<f64>>,
    head: usize,
    /// Samples pushed so far (saturating at the ring's length).
    filled: usize,
    /// The last valid design (frequency Hz, ratio), if any.
    last_design: Option<(f64, f64)>,
    /// The design filter's state: ln f and its rate (1/s).
    log_f: f64,
    log_f_rate: f64,
}

impl OnlineShaper {
    /// A shaper of `kind` for samples `dt_s` apart (s) and design frequencies down to
    /// `min_frequency_hz` (Hz; lower ones are raised to it): the ring holds
    /// ⌈T_max/dt⌉ + 2 samples, T_max = 1/(min_frequency_hz·√(1−0.99²)), so any ratio
    /// below 0.99 fits.
    pub fn new(
        kind: ShaperKind,
        dt_s: f64,
        min_frequency_hz: f64,
    ) -> Result<OnlineShaper, ShapingError> {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(ShapingError::BadSamplePeriod(dt_s));
        }
        if !(min_frequency_hz.is_finite() && min_frequency_hz > 0.0) {
            return Err(ShapingError::BadFrequency(min_frequency_hz, 0.0));
        }
        let t_max = 1.0 / (min_frequency_hz * (1.0f64 - 0.99 * 0.99).sqrt());
        let len = (t_max / dt_s).ceil() + 2.0;
        if !(len < MAX_RING_SAMPLES as f64) {
            return Err(ShapingError::RingTooLarge(
                len.min(usize::MAX as f64) as usize
            ));
        }
        Ok(OnlineShaper {
            kind,
            dt_s,
            min_frequency_hz,
            ring: vec![Vector3::zeros(); len as usize],
            head: 0,
            filled: 0,
            last_design: None,
            log_f: 0.0,
            log_f_rate: 0.0,
        })
    }

    /// The shaper kind.
    pub fn kind(&self) -> ShaperKind {
        self.kind
    }

    /// Forget the history (the next sample starts a new path).
    pub fn reset(&mut self) {
        self.filled = 0;
        self.head = 0;
        self.last_design = None;
        self.log_f = 0.0;
        self.log_f_rate = 0.0;
    }

    /// The design in use: the last valid (frequency Hz, ratio) given to [`Self::push`].
    pub fn design(&self) -> Option<(f64, f64)> {
        self.last_design
    }

    /// Push input sample `x` (the path at this sample's time) with the mode at the current
    /// pose, (`f_hz`, `zeta`); returns the shaped sample. A frequency that is not a finite
    /// positive number or a ratio outside [0, 0.99] keeps the last valid design (the
    /// estimate of this cycle had none); before any valid design, the input passes
    /// through. Frequencies below the shaper's lowest are raised to it; the design
    /// frequency follows the one given through a critically damped filter of time
    /// constant [`DESIGN_FILTER_S`] (the first is taken as given). No allocation.
    pub fn push(&mut self, x: Vector3<f64>, f_hz: f64, zeta: f64) -> Vector3<f64> {
        if self.filled == 0 {
            // A path starts at rest at its first sample: fill the history with it.
            for v in self.ring.iter_mut() {
                *v = x;
            }
            self.filled = 1;
            self.head = 0;
        } else {
            self.head = (self.head + 1) % self.ring.len();
            self.ring[self.head] = x;
            self.filled = (self.filled + 1).min(self.ring.len());
        }
        if f_hz.is_finite() && f_hz > 0.0 && zeta.is_finite() && (0.0..=0.99).contains(&zeta) {
            let target = f_hz.max(self.min_frequency_hz).ln();
            if self.last_design.is_none() {
                self.log_f = target;
                self.log_f_rate = 0.0;
            } else {
                // critically damped, semi-implicit Euler (stable: w·dt ≤ 0.5)
                let w = (1.0 / DESIGN_FILTER_S).min(0.5 / self.dt_s);
                let acc = w * w * (target - self.log_f) - 2.0 * w * self.log_f_rate;
                self.log_f_rate += acc * self.dt_s;
                self.log_f += self.log_f_rate * self.dt_s;
            }
            self.last_design = Some((self.log_f.exp().max(self.min_frequency_hz), zeta));
        }
        let Some((f, z)) = self.last_design else {
            return x;
        };
        let imp = Impulses::design_unchecked(self.kind, f, z);
        let mut y = Vector3::zeros();
        for i in 0..imp.n {
            y += self.delayed(imp.time_s[i]) * imp.amplitude[i];
        }
        y
    }

    /// The input `delay_s` before the newest sample (linear interpolation; clamped to the
    /// ring's oldest sample, which before the ring fills is the path's first).
    fn delayed(&self, delay_s: f64) -> Vector3<f64> {
        let len = self.ring.len();
        let s = (delay_s / self.dt_s).max(0.0);
        let max_back = (len - 2) as f64;
        let s = s.min(max_back);
        let back = s.floor() as usize;
        let frac = s - back as f64;
        let at = |b: usize| self.ring[(self.head + len - b) % len];
        at(back) * (1.0 - frac) + at(back + 1) * frac
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amplitudes_sum_to_one_and_residual_vanishes_at_design() {
        for kind in [ShaperKind::Zv, ShaperKind::Zvd, ShaperKind::Ei] {
            for zeta in [0.0, 0.01, 0.1] {
                let imp = Impulses::design(kind, 3.0, zeta).unwrap();
                let sum: f64 = imp.amplitude[..imp.n].iter().sum();
                assert!((sum - 1.0).abs() < 1e-15, "{kind:?} {zeta}: {sum}");
                let r = imp.residual_fraction(3.0, zeta);
                match kind {
                    ShaperKind::Ei if zeta == 0.0 => assert!((r - EI_V_TOL).abs() < 1e-12),
                    ShaperKind::Ei => assert!(r > 0.0 && r < EI_V_TOL, "{zeta}: {r}"),
                    _ => assert!(r < 1e-15, "{kind:?} {zeta}: {r}"),
                }
            }
        }
        assert!(Impulses::design(ShaperKind::Zv, f64::NAN, 0.0).is_err());
        assert!(Impulses::design(ShaperKind::Zv, 1.0, 1.0).is_err());
        assert!(Impulses::design(ShaperKind::Zv, 1.0, -0.1).is_err());
    }

    #[test]
    fn zv_undamped_closed_form_residual() {
        // Two half impulses π/ω apart: residual |cos(π r / 2)| at frequency ratio r.
        let imp = Impulses::design(ShaperKind::Zv, 2.0, 0.0).unwrap();
        for r in [0.5, 0.8, 1.2, 2.0] {
            let got = imp.residual_fraction(2.0 * r, 0.0);
            let want = (std::f64::consts::FRAC_PI_2 * r).cos().abs();
            assert!((got - want).abs() < 1e-14, "r {r}: {got} vs {want}");
        }
    }

    #[test]
    fn online_shaper_with_constant_design_is_the_convolution() {
        let dt = 1e-3;
        let mut s = OnlineShaper::new(ShaperKind::Zvd, dt, 1.0).unwrap();
        let imp = Impulses::design(ShaperKind::Zvd, 5.0, 0.02).unwrap();
        let x = |k: usize| Vector3::new((k as f64 * dt).min(0.3), 0.0, 0.0);
        for k in 0..800 {
            let y = s.push(x(k), 5.0, 0.02);
            let mut want = 0.0;
            for i in 0..3 {
                let t = (k as f64 * dt - imp.time_s[i]).max(0.0);
                want += imp.amplitude[i] * t.min(0.3);
            }
            assert!((y.x - want).abs() < 1e-12, "k {k}: {} vs {want}", y.x);
        }
    }
}
