//! The measured-frequency tracker (`cablevib::measured`) against signals with known modes.
use cablevib::measured::*;
use cablevib_testkit::vibration::{gaussian, Oscillator};
use cablevib_testkit::Rng;

const FS_HZ: f64 = 1000.0;
const DT_NS: u64 = 1_000_000;

/// Feeds `seconds` of samples from `sample(t_s) -> acceleration` at 1 kHz, working once per
/// sample; calls `each(t_s, tracker)` after every work; returns the largest work of a call.
fn feed(
    tr: &mut VibrationTracker,
    start: u64,
    seconds: f64,
    mut sample: impl FnMut(f64) -> [f64; 3],
    mut each: impl FnMut(f64, &mut VibrationTracker),
) -> u32 {
    let mut most = 0;
    for k in 0..(seconds * FS_HZ) as u64 {
        let seq = start + k;
        let t = seq as f64 / FS_HZ;
        let _ = tr.push(seq, seq * DT_NS, sample(t));
        most = most.max(tr.work());
        each(t, tr);
    }
    most
}

fn two_sines(rng: &mut Rng) -> impl FnMut(f64) -> [f64; 3] + '_ {
    use core::f64::consts::PI;
    move |t| {
        [
            0.5 * (2.0 * PI * 9.3 * t).sin() + 0.02 * gaussian(rng),
            0.3 * (2.0 * PI * 29.4 * t + 1.0).sin() + 0.02 * gaussian(rng),
            9.81 + 0.02 * gaussian(rng),
        ]
    }
}

fn frequency(r: Result<MeasuredMode, MeasuredStatus>) -> f64 {
    r.map(|m| m.frequency_hz).unwrap_or(f64::NAN)
}

#[test]
fn clean_sinusoids_are_found_to_the_noise_limit() {
    // Reference: the frequencies the signal was made with (9.3 Hz on x, 29.4 Hz on y, gravity
    // and noise σ = 0.02 m/s² on every axis); the model's predictions are 3 % and 2 % off.
    // Tolerance 5 mHz: the Cramér-Rao bound of one sinusoid's frequency over N = 2000 samples
    // at amplitude/σ = 15 is √(6σ²/(A²N³))/(2πP) = 0.3 mHz; Hann weighting costs under a
    // factor 1.5, the other sinusoid leaks through the Hann sidelobes (40 bins away) at
    // ~1e-5 of its amplitude. So 5 mHz is over 10× the noise limit and far below a bin
    // (0.5 Hz).
    let mut tr = VibrationTracker::new(TrackerParams::default()).unwrap();
    tr.set_model(Some(9.0), Some(30.0));
    let mut rng = Rng(7);
    let mut last = Measured::none(MeasuredStatus::NoInput);
    feed(&mut tr, 1, 6.0, two_sines(&mut rng), |t, tr| {
        last = tr.measured((t * 1e9) as u64);
    });
    let (f1, ee) = (frequency(last.first), frequency(last.ee_mode));
    assert!((f1 - 9.3).abs() < 5e-3, "{last:?}");
    assert!((ee - 29.4).abs() < 5e-3, "{last:?}");
    let m = last.first.unwrap();
    assert!(
        m.peak_ratio >= 10.0 && (m.window_s - 2.0).abs() < 1e-9,
        "{m:?}"
    );
    assert_eq!(tr.counters().accepted, 6000);
    assert_eq!(tr.counters().refused(), 0);
}

/// The sweep test's signal: a single mode of damping ζ = 1 % whose natural frequency moves
/// linearly from 27 to 31 Hz over 60 s (around the paper robot's end-effector mode), under
/// white-noise force, plus sensor noise 20 dB below the response on every axis and gravity
/// on z.
struct Sweep {
    rng: Rng,
    osc: Oscillator,
}

const SWEEP_S: f64 = 60.0;
const ZETA: f64 = 0.01;

fn sweep_hz(t: f64) -> f64 {
    27.0 + 4.0 * t / SWEEP_S
}

impl Sweep {
    fn sample(&mut self, t: f64) -> [f64; 3] {
        let a = self
            .osc
            .step(sweep_hz(t), gaussian(&mut self.rng), 1.0 / FS_HZ);
        // RMS response of a unit-mass mode under force σ_F = 1 per 1 ms step:
        // σ_a² = σ_F²·Δt·ω/(4ζ) = 4.2-4.9 (m/s²)² over the sweep; noise σ = 0.21 m/s² is 20 dB
        // below.
        let noise = 0.21;
        [
            a + noise * gaussian(&mut self.rng),
            noise * gaussian(&mut self.rng),
            9.81 + noise * gaussian(&mut self.rng),
        ]
    }
}

#[test]
fn follows_a_moving_mode_within_the_statistical_limit() {
    // Reference: the oscillator's own natural frequency, averaged over the window each
    // measurement describes (the sweep is linear: its value at the window's centre). The
    // statistical limit of a window of T = 2 s on a mode of damping ζ at ω rad/s is
    // σ_lim = f·√(ζ/(ωT)) (0.15 Hz at 29 Hz); the acceleration peak of a mode sits at
    // ω/√(1 − 2ζ²), 1e-4 relative above ω (3 mHz), and RK4's frequency error is 1e-6. The
    // peak of one Hann periodogram is not an efficient estimator of a randomly excited mode:
    // measured on stationary and swept modes at 29 Hz, windows of 2 s and 8 s, two seeds
    // each, its RMS error is 2.5-3.6 σ_lim and its median |error| 1.3-2.4 σ_lim, with heavy
    // tails (single windows up to 15 σ_lim, when the mode's envelope fades within the
    // window). So: RMS ≤ 4 σ_lim, median |error| ≤ 2.5 σ_lim, and it must follow the sweep:
    // the slope of measured against true over the run within 10 % of 1 (the sweep spans
    // 4 Hz, 26 σ_lim). The model's prediction is 5 % high throughout.
    let mut tr = VibrationTracker::new(TrackerParams::default()).unwrap();
    let mut sig = Sweep {
        rng: Rng(11),
        osc: Oscillator::new(ZETA),
    };
    let mut seen = Vec::new();
    let mut last_centre = None;
    feed(
        &mut tr,
        0,
        SWEEP_S,
        |t| sig.sample(t),
        |t, tr| {
            tr.set_model(Some(1.05 * sweep_hz(t)), None);
            let m = tr.measured((t * 1e9) as u64);
            if let Ok(f) = m.first {
                if last_centre != Some(f.window_centre_ns) {
                    last_centre = Some(f.window_centre_ns);
                    seen.push((f.window_centre_ns as f64 * 1e-9, f.frequency_hz));
                }
            }
        },
    );
    assert!(seen.len() > 400, "{} measurements", seen.len());
    let mut z = Vec::with_capacity(seen.len());
    let (mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0);
    for &(c, f) in &seen {
        let truth = sweep_hz(c);
        let w = 2.0 * core::f64::consts::PI * truth;
        let sigma_lim = truth * (ZETA / (w * 2.0)).sqrt();
        z.push(((f - truth) / sigma_lim).abs());
        sx += truth;
        sy += f;
        sxx += truth * truth;
        sxy += truth * f;
    }
    let n = seen.len() as f64;
    let rms = (z.iter().map(|z| z * z).sum::<f64>() / n).sqrt();
    z.sort_by(f64::total_cmp);
    let median = z[z.len() / 2];
    let slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    eprintln!(
        "{} measurements: RMS {rms:.2}, median {median:.2}, worst {:.2} σ_lim; slope {slope:.4}",
        seen.len(),
        z[z.len() - 1]
    );
    assert!(
        rms <= 4.0 && median <= 2.5,
        "RMS {rms}, median {median} σ_lim"
    );
    assert!((slope - 1.0).abs() <= 0.1, "slope {slope}");
}
