//! `demo`'s synthetic accelerometer: the simulated vibration of the demo's trajectory, read
//! by a sensor on the platform and published on the vibration service at 1 kHz, so that the
//! measured frequencies of the estimate work on a fresh clone.
//!
//! The response is `study::simulate`'s (modal superposition of the pose's modes along the
//! circle, every mode up to 1.25 × the end-effector mode: on the paper robot 42 modes, the
//! end-effector mode the 39th, above 38 cable modes the platform hardly sees; the scene's damping, or ζ = 1 % in every mode when the scene has none, since an
//! undamped robot under noise rings without bound), with a white-noise force on the
//! end-effector ([`FORCE_NOISE_N`] per sample, standing for the disturbances a real robot
//! feels) besides the path's inertial load. The sensor reads the specific force: the path's
//! acceleration, the deviation's (from the modal state, [`simulate_forced`]'s
//! `acceleration_m_s2`; second differences of the deviation would add the static
//! correction's response to the white force, a broadband acceleration rising as f² that
//! buries the modes) and −g, plus white sensor noise ([`SENSOR_NOISE_M_S2`]).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use cablevib_ipc::{monotonic_now_ns, ServiceNames, VibrationSample};
use nalgebra::Vector3;

use super::ports::{create_node, open_pubsub, VIBRATION_SETTINGS};
use super::ServiceError;
use crate::estimator::{Estimator, Status, Tmin};
use crate::kinematics::Pose;
use crate::modal::response::MAX_RESPONSE_MODES;
use crate::rng::SplitMix64;
use crate::scene::{Damping, Scene};
use crate::study::simulate::{simulate_forced, SampledPath, SimulateConfig};
use crate::trajectory::Trajectory;

/// Sample period of the synthetic sensor, s (1 kHz).
pub const SAMPLE_PERIOD_S: f64 = 1e-3;
/// Standard deviation of the white force on the end-effector, N per sample.
pub const FORCE_NOISE_N: f64 = 2.0;
/// Standard deviation of the sensor's white noise, m/s² per axis (a MEMS accelerometer's
/// 100 µg/√Hz over 500 Hz is 0.022 m/s²).
pub const SENSOR_NOISE_M_S2: f64 = 0.02;
/// Damping ratio in every mode when the scene has none.
pub const DEFAULT_ZETA: f64 = 0.01;
/// Longest accelerometer record, s (it is computed before the demo starts, about 0.35 s per
/// second of record on the paper robot: the mode basis is solved every `UPDATE_EVERY`
/// samples; 24 B per sample).
pub const MAX_SECONDS: f64 = 60.0;
/// Samples between two updates of the modes along the path (0.1 s: the end-effector mode of
/// the paper's circle moves by under 0.05 Hz meanwhile, a third of the tracker's
/// statistical limit).
const UPDATE_EVERY: usize = 100;
/// The modes simulated: every mode up to this multiple of the end-effector mode of the first
/// pose (so the tracker's search band, ±10 % by default, sees the end-effector mode and its
/// neighbours ring; the modes above answer quasi-statically).
const MODES_UP_TO_EE: f64 = 1.25;

/// The number of modes of the first pose of `path` at or below [`MODES_UP_TO_EE`] × its
/// end-effector mode (the first mode alone without one), at most [`MAX_RESPONSE_MODES`].
fn modes_to_simulate(scene: &Scene, first: Vector3<f64>) -> Result<usize, ServiceError> {
    let bad = ServiceError::Accelerometer;
    let mut est = Estimator::new(scene).map_err(|e| bad(e.to_string()))?;
    let e = est.update(&Pose::in_scene(scene, first), Tmin::Scene);
    if e.status != Status::Ok {
        return Err(bad(format!("the first pose: {}", e.status.as_str())));
    }
    let ee_mode_hz = e.ee_mode.map_or(f64::NAN, |m| m.frequency_hz);
    let top = 2.0 * core::f64::consts::PI * MODES_UP_TO_EE * ee_mode_hz;
    if !top.is_finite() {
        return Ok(1);
    }
    let basis = est
        .ee_modal_basis(MAX_RESPONSE_MODES)
        .map_err(|e| bad(e.to_string()))?;
    Ok(basis
        .lambda
        .iter()
        .filter(|&&l| l <= top * top)
        .count()
        .max(1))
}

/// The seed of the demo's noise (force and sensor).
pub const NOISE_SEED: u64 = 0x5eed;

/// The accelerometer's samples along `trajectory` for `seconds`, m/s², and the damping
/// ratio used (None: the scene's own damping); the noise of [`NOISE_SEED`].
pub fn record(
    scene: &Scene,
    trajectory: &Trajectory,
    seconds: f64,
) -> Result<(Vec<[f64; 3]>, Option<f64>), ServiceError> {
    record_seeded(scene, trajectory, seconds, NOISE_SEED)
}

/// [`record`] with the noise of `seed`.
pub fn record_seeded(
    scene: &Scene,
    trajectory: &Trajectory,
    seconds: f64,
    seed: u64,
) -> Result<(Vec<[f64; 3]>, Option<f64>), ServiceError> {
    let mut scene = scene.clone();
    let zeta = scene.damping.is_none().then_some(DEFAULT_ZETA);
    if let Some(z) = zeta {
        scene.damping = Damping::ModalRatio { zeta: z };
    }
    let bad = |e: crate::study::StudyError| ServiceError::Accelerometer(e.to_string());
    let path =
        SampledPath::from_trajectory(trajectory, seconds, SAMPLE_PERIOD_S, false).map_err(bad)?;
    let cfg = SimulateConfig {
        update_every: Some(UPDATE_EVERY),
        modes: Some(modes_to_simulate(&scene, path.positions_m[0])?),
        ..SimulateConfig::default()
    };
    let mut noise = SplitMix64(seed);
    let r = simulate_forced(&scene, &path, &cfg, |_| {
        Vector3::new(noise.normal(), noise.normal(), noise.normal()) * FORCE_NOISE_N
    })
    .map_err(bad)?;
    let g = scene.gravity_m_s2;
    let out = r
        .acceleration_m_s2
        .iter()
        .enumerate()
        .map(|(k, dev)| {
            let f = path.acceleration(k.min(path.positions_m.len() - 1)) + dev - g;
            [
                f.x + SENSOR_NOISE_M_S2 * noise.normal(),
                f.y + SENSOR_NOISE_M_S2 * noise.normal(),
                f.z + SENSOR_NOISE_M_S2 * noise.normal(),
            ]
        })
        .collect();
    Ok((out, zeta))
}

/// Publishes `samples` on the vibration service of `names` at 1 kHz from `start_ns` on (each
/// stamped with its sample time), until done or `stop`.
pub fn spawn(
    names: &ServiceNames,
    samples: Vec<[f64; 3]>,
    stop: Arc<AtomicBool>,
) -> Result<std::thread::JoinHandle<Result<u64, ServiceError>>, ServiceError> {
    let name = names.vibration.clone();
    std::thread::Builder::new()
        .name("cablevib-accelerometer".into())
        .spawn(move || {
            let node = create_node("cablevib-demo-accelerometer")?;
            let publisher = open_pubsub::<VibrationSample>(&node, &name, VIBRATION_SETTINGS)?
                .publisher_builder()
                .create()
                .map_err(|e| ServiceError::Ipc {
                    context: "create the vibration publisher".into(),
                    reason: format!("{e:?}"),
                })?;
            let start = monotonic_now_ns();
            let period_ns = (SAMPLE_PERIOD_S * 1e9) as u64;
            let mut sent = 0;
            for (k, a) in samples.iter().enumerate() {
                if stop.load(Ordering::Relaxed) {
                    break;
                }
                let t = start + k as u64 * period_ns;
                while monotonic_now_ns() < t {
                    std::thread::sleep(std::time::Duration::from_micros(200));
                }
                if publisher
                    .send_copy(VibrationSample::acceleration(k as u64 + 1, t, *a))
                    .is_ok()
                {
                    sent += 1;
                }
            }
            Ok(sent)
        })
        .map_err(|e| ServiceError::Thread {
            what: "accelerometer",
            reason: e.to_string(),
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measured::{MeasuredStatus, PushOutcome, TrackerParams, VibrationTracker};

    /// The model's f1 and end-effector mode at time `t_s` of the circle, Hz.
    fn model_at(est: &mut Estimator, scene: &Scene, tr: &Trajectory, t_s: f64) -> (f64, f64) {
        let p = tr.position_at(t_s).expect("on the circle");
        let e = est.update(&Pose::in_scene(scene, p), Tmin::Scene);
        assert_eq!(e.status, Status::Ok);
        (e.f1_hz, e.ee_mode.map_or(f64::NAN, |m| m.frequency_hz))
    }

    /// The model's frequency (`which` 0: f1, 1: end-effector mode) that a window centred at
    /// `c_s` describes: the Hann-weighted mean over the window (every 10 ms) of the model's
    /// values on the mode nearest `measured_hz`. The model's end-effector mode is, at a few
    /// isolated poses of the circle, another mode (its participation threshold picks the
    /// 33.7 Hz pair there): the values within 5 % of the window's median are one group, the
    /// others another, and the group whose median is nearer the measurement is the
    /// reference. Returns (reference, whether it was the minority group).
    fn window_model(
        est: &mut Estimator,
        scene: &Scene,
        circle: &Trajectory,
        c_s: f64,
        window_s: f64,
        which: usize,
        measured_hz: f64,
    ) -> (f64, bool) {
        let pts: Vec<(f64, f64)> = (0..=200)
            .map(|j| {
                let x = j as f64 / 200.0;
                let w = 0.5 - 0.5 * (2.0 * core::f64::consts::PI * x).cos();
                let (f1, ee) = model_at(est, scene, circle, c_s + (x - 0.5) * window_s);
                (w, [f1, ee][which])
            })
            .collect();
        let mut fs: Vec<f64> = pts.iter().map(|p| p.1).collect();
        fs.sort_by(f64::total_cmp);
        let median = fs[fs.len() / 2];
        let main = |f: f64| (f - median).abs() <= 0.05 * median;
        let others: Vec<f64> = fs.iter().copied().filter(|&f| !main(f)).collect();
        let minority = !others.is_empty()
            && (others[others.len() / 2] - measured_hz).abs() < (median - measured_hz).abs();
        let (mut sw, mut sf) = (0.0, 0.0);
        for &(w, f) in &pts {
            if main(f) != minority {
                sw += w;
                sf += w * f;
            }
        }
        (sf / sw, minority)
    }

    /// The model's platform mode nearest `measured_hz` as a window centred at `c_s` sees it:
    /// at 41 poses of the window (every 50 ms), among the first 48 modes those whose
    /// end-effector participation φᵀ M_ee φ is at least the scene's threshold (the modes the
    /// estimator may report as its end-effector mode), the one nearest the measurement; their
    /// Hann-weighted mean, Hz.
    fn platform_mode_near(
        est: &mut Estimator,
        scene: &Scene,
        circle: &Trajectory,
        c_s: f64,
        window_s: f64,
        measured_hz: f64,
    ) -> f64 {
        let (mut sw, mut sf) = (0.0, 0.0);
        for j in 0..=40 {
            let x = j as f64 / 40.0;
            let w = 0.5 - 0.5 * (2.0 * core::f64::consts::PI * x).cos();
            model_at(est, scene, circle, c_s + (x - 0.5) * window_s);
            let b = est.ee_modal_basis(48).unwrap();
            let top = b.lambda.last().unwrap().sqrt() / (2.0 * core::f64::consts::PI);
            assert!(top > measured_hz + 2.0, "48 modes reach {top} Hz only");
            let nearest = b
                .lambda
                .iter()
                .zip(&b.phi_ee)
                .filter(|(_, p)| {
                    (p.transpose() * b.ee_mass * *p)[0] >= scene.model.ee_participation_min
                })
                .map(|(l, _)| l.sqrt() / (2.0 * core::f64::consts::PI))
                .min_by(|a, b| (a - measured_hz).abs().total_cmp(&(b - measured_hz).abs()))
                .expect("a platform mode");
            sw += w;
            sf += w * nearest;
        }
        sf / sw
    }

    /// What the windows of one or more noise realizations measured, pooled.
    #[derive(Debug, Default)]
    struct Pooled {
        /// Windows (with a centre) over every seed.
        windows: usize,
        /// Windows without a peak near the end-effector mode.
        ee_missing: usize,
        /// |measured − reference| / σ_lim of each window with a peak.
        z: Vec<f64>,
        /// Windows within one DFT bin 1/T, and beyond the resolution 2/T.
        within: usize,
        beyond: usize,
        /// Windows whose reference was the model's other platform mode.
        other_mode: usize,
        /// f1: windows with no_peak, and with a peak more than 1/T from the model.
        f1_no_peak: usize,
        f1_far: usize,
    }

    impl Pooled {
        fn rms(&self) -> f64 {
            (self.z.iter().map(|z| z * z).sum::<f64>() / self.z.len() as f64).sqrt()
        }
        fn median(&self) -> f64 {
            let mut z = self.z.clone();
            z.sort_by(f64::total_cmp);
            z[z.len() / 2]
        }
        fn worst(&self) -> f64 {
            self.z.iter().fold(0.0f64, |a, &b| a.max(b))
        }
    }

    /// The demo's accelerometer of the robot `simulated` (noise of `seed`, 20 s of the
    /// demo's circle) through the service's tracker given the model of `scene`, each window
    /// against its reference (test docs), added to `pool`.
    fn measure_seed(scene: &Scene, simulated: &Scene, seed: u64, pool: &mut Pooled) {
        let circle = Trajectory::circle(scene, 4.0).unwrap();
        let seconds = 20.0;
        let (samples, zeta) = record_seeded(simulated, &circle, seconds, seed).unwrap();
        let zeta = zeta.expect("the paper robot has no damping: the demo's ζ");
        let mut est = Estimator::new(scene).unwrap();
        let mut tracker = VibrationTracker::new(TrackerParams::default()).unwrap();
        let window_s = tracker.params().window_s;
        let period_ns = (SAMPLE_PERIOD_S * 1e9) as u64;
        let mut seen = Vec::new();
        let mut last_centre = None;
        for (k, a) in samples.iter().enumerate() {
            let t_ns = k as u64 * period_ns;
            if k % 10 == 0 {
                let (f1, ee) = model_at(&mut est, scene, &circle, k as f64 * SAMPLE_PERIOD_S);
                tracker.set_model(Some(f1), Some(ee));
            }
            let pushed = tracker.push(k as u64 + 1, t_ns, *a);
            assert!(
                k == 0 || matches!(pushed, PushOutcome::Accepted { filled: 0 }),
                "{pushed:?}"
            );
            tracker.work();
            let m = tracker.measured(t_ns);
            let Some(c) = m.window_centre_ns() else {
                continue;
            };
            if last_centre != Some(c) {
                last_centre = Some(c);
                seen.push((c as f64 * 1e-9, m));
            }
        }
        let before = (pool.z.len(), pool.within, pool.other_mode);
        pool.windows += seen.len();
        for (c_s, m) in &seen {
            match m.first {
                Ok(f) => {
                    let (model, _) =
                        window_model(&mut est, scene, &circle, *c_s, window_s, 0, f.frequency_hz);
                    pool.f1_far += usize::from((f.frequency_hz - model).abs() > 1.0 / window_s);
                }
                Err(s) => {
                    assert_eq!(s, MeasuredStatus::NoPeak, "f1 at {c_s} s");
                    pool.f1_no_peak += 1;
                }
            }
            let Ok(f) = m.ee_mode else {
                pool.ee_missing += 1;
                continue;
            };
            let (mut truth, minority) =
                window_model(&mut est, scene, &circle, *c_s, window_s, 1, f.frequency_hz);
            pool.other_mode += usize::from(minority);
            if minority {
                // The tracker's band was centred on the model's other platform mode: the
                // peak is the platform mode nearest it (test docs).
                truth =
                    platform_mode_near(&mut est, scene, &circle, *c_s, window_s, f.frequency_hz);
            }
            let sigma_lim =
                truth * (zeta / (2.0 * core::f64::consts::PI * truth * window_s)).sqrt();
            let err = f.frequency_hz - truth;
            pool.within += usize::from(err.abs() <= 1.0 / window_s);
            pool.beyond += usize::from(err.abs() > 2.0 / window_s);
            pool.z.push((err / sigma_lim).abs());
        }
        let z = &pool.z[before.0..];
        let rms = (z.iter().map(|z| z * z).sum::<f64>() / z.len().max(1) as f64).sqrt();
        eprintln!(
            "seed {seed}: {} windows, {} with a peak: RMS {rms:.2}, worst {:.2} σ_lim, {} within \
             1/T ({} on the model's other mode)",
            seen.len(),
            z.len(),
            z.iter().fold(0.0f64, |a, &b| a.max(b)),
            pool.within - before.1,
            pool.other_mode - before.2,
        );
    }

    /// The pooled bounds (test docs); the failures, if any.
    fn pooled_failures(p: &Pooled) -> Vec<String> {
        let mut out = Vec::new();
        let n = p.z.len() as f64;
        if (p.z.len() as f64) < 0.95 * p.windows as f64 {
            out.push(format!(
                "{} of {} windows have an end-effector peak",
                p.z.len(),
                p.windows
            ));
        }
        if p.rms() > RMS_BOUND {
            out.push(format!("RMS {:.2} σ_lim > {RMS_BOUND}", p.rms()));
        }
        if p.median() > MEDIAN_BOUND {
            out.push(format!("median {:.2} σ_lim > {MEDIAN_BOUND}", p.median()));
        }
        if p.beyond as f64 > BEYOND_SHARE * n {
            out.push(format!("{} of {} windows beyond 2/T", p.beyond, p.z.len()));
        }
        if p.f1_far > 0 {
            out.push(format!(
                "f1 read more than 1/T from the model in {} windows",
                p.f1_far
            ));
        }
        out
    }

    /// Noise realizations pooled: each seed's 20 s hold about 9 independent windows (the
    /// windows advance by 0.1 s and share 95 % of their samples), so one seed's RMS over
    /// them scatters by about ±25 % (χ with 9 degrees of freedom); the quick check pools
    /// seeds 1-2 (about 18 independent windows, ±17 %), the slow sweep seeds 1-6 (about 54,
    /// ±10 %; about 12 s of CPU per seed).
    const QUICK_SEEDS: u64 = 2;
    const SLOW_SEEDS: u64 = 6;
    /// The pooled bounds, σ_lim = f·√(ζ/(ωT)) (test docs): the periodogram peak of a single
    /// randomly excited mode has RMS error 2.5-3.6 σ_lim (tests/measured), neighbouring
    /// modes in the band add to it; the RMS bound is that largest value with the pool's
    /// ±10 % scatter and a margin, the median's the single mode's 1.3-2.4 σ_lim likewise.
    const RMS_BOUND: f64 = 4.0;
    const MEDIAN_BOUND: f64 = 2.5;
    /// Share of windows allowed beyond the resolution 2/T (two modes closer than the Hann
    /// main lobe's half-width merge into one peak): where the model's end-effector mode
    /// jumps to another platform mode within the window, both ring. Such windows come in
    /// runs (successive windows share 95 % of their samples), one run about every 20 s:
    /// seeds 1-2, 6 of 123 (seed 1 alone); seeds 1-6, 8 of 370. The bound allows one run of
    /// up to a window's length per seed pooled.
    const BEYOND_SHARE: f64 = 0.10;

    /// The demo's synthetic accelerometer through the service's tracker, along the demo's
    /// circle (paper robot, 4 s per revolution), 20 s per noise realization, seeds
    /// 1 ..= `seeds` pooled ([`QUICK_SEEDS`] in the quick suite, [`SLOW_SEEDS`] in the slow
    /// sweep).
    ///
    /// Reference: the model's end-effector mode (the estimator at the poses of each window,
    /// averaged as the window sees it: [`window_model`]); it is what the simulation put in,
    /// but the tracker knows only its ±10 % band around the model's value. On this circle the
    /// model's mode varies between 29.05 and 29.69 Hz four times per revolution (a period of
    /// 1 s, shorter than the 2 s window): each window measures the average, 29.44 Hz.
    /// Tolerances on the pooled windows: the statistical limit of a T = 2 s window,
    /// σ_lim = f·√(ζ/(ωT)) = 0.15 Hz (ζ = 1 %, the demo's); [`RMS_BOUND`] and
    /// [`MEDIAN_BOUND`] on the pooled errors, at most [`BEYOND_SHARE`] of the windows
    /// beyond the window's resolution 2/T = 1 Hz, at least 95 % of the windows with a peak.
    /// One seed's windows (about 9 independent ones) are too few for these statistics, and
    /// a bound on every window fails where two modes merge: asserted per seed and per
    /// window, 3 of seeds 1-8 passed (seeds 1, 3 and 6 here each have a window beyond
    /// 2/T, 1.4, 1.02 and 1.2 Hz off). Measured over seeds 1-2: 123 windows, all with a
    /// peak, RMS 2.61, median 1.17, worst 9.24 σ_lim, 111 within 1/T, 6 beyond 2/T; over
    /// seeds 1-6: 370 windows, all with a peak, RMS 2.23, median 0.99, worst 9.24 σ_lim,
    /// 332 within 1/T, 8 beyond 2/T (15 on the model's other mode); f1 no_peak in all.
    ///
    /// Where the model's end-effector mode jumps, within a window, to the platform's second
    /// translational mode (the minority group of [`window_model`]), the tracker's band is
    /// centred on that one and holds the third as well: at 12.68 s the model has 32.95 Hz
    /// (participation 0.93) and 34.12-34.43 Hz (0.63-0.93) there, both platform modes the
    /// white force rings, and the window's periodogram peak is whichever rings harder in
    /// that realization. In such a window the reference is the model's platform mode
    /// nearest the measurement ([`platform_mode_near`]).
    ///
    /// f1 is a cable mode whose end-effector participation (φᵀ M_ee φ of the mass-normalised
    /// shape) is 7e-6: no platform accelerometer sees it. Its track must say so (`no_peak`),
    /// never report a frequency more than 1/T from the model's.
    ///
    /// The bounds fail a robot that does not follow the model:
    /// [`the_pooled_check_fails_a_robot_off_the_model`].
    fn measured_mode_follows_the_model(seeds: u64) {
        let scene = Scene::default_scene();
        let mut est = Estimator::new(&scene).unwrap();
        let circle = Trajectory::circle(&scene, 4.0).unwrap();
        // f1's participation at the first pose
        model_at(&mut est, &scene, &circle, 0.0);
        let b = est.ee_modal_basis(1).unwrap();
        let part = (b.phi_ee[0].transpose() * b.ee_mass * b.phi_ee[0])[0];
        eprintln!("f1's end-effector participation at the first pose: {part:.2e}");
        assert!(part < 1e-4, "{part}");

        let mut pool = Pooled::default();
        for seed in 1..=seeds {
            measure_seed(&scene, &scene, seed, &mut pool);
        }
        eprintln!(
            "pooled over {seeds} seeds: {} windows, {} with a peak: RMS {:.2}, median {:.2}, \
             worst {:.2} σ_lim, {} within 1/T, {} beyond 2/T ({} on the model's other mode); \
             f1 no_peak in {}",
            pool.windows,
            pool.z.len(),
            pool.rms(),
            pool.median(),
            pool.worst(),
            pool.within,
            pool.beyond,
            pool.other_mode,
            pool.f1_no_peak
        );
        let failures = pooled_failures(&pool);
        assert!(failures.is_empty(), "{failures:?}");
    }

    /// [`measured_mode_follows_the_model`] over seeds 1-2.
    #[test]
    fn the_measured_end_effector_mode_follows_the_model_along_the_circle() {
        measured_mode_follows_the_model(QUICK_SEEDS);
    }

    /// The pooled check must fail when the measured mode does not follow the model: the
    /// simulated robot's end-effector 5 % heavier than the model's (its mode about 2.5 %
    /// lower, 0.7 Hz, inside the tracker's ±10 % band and about the resolution 2/T), two
    /// seeds. Measured: RMS 4.36, median 3.99 σ_lim, 10 of 77 windows beyond 2/T.
    #[test]
    fn the_pooled_check_fails_a_robot_off_the_model() {
        let scene = Scene::default_scene();
        let mut heavier = scene.clone();
        heavier.ee_mass_kg *= 1.05;
        let mut pool = Pooled::default();
        for seed in 1..=QUICK_SEEDS {
            measure_seed(&scene, &heavier, seed, &mut pool);
        }
        let failures = pooled_failures(&pool);
        eprintln!(
            "a robot 5 % heavier than the model: RMS {:.2}, median {:.2} σ_lim: {failures:?}",
            pool.rms(),
            pool.median()
        );
        assert!(
            !failures.is_empty(),
            "the check passed a robot off the model"
        );
    }

    mod slow {
        /// [`super::measured_mode_follows_the_model`] over seeds 1-6.
        #[test]
        #[ignore = "slow reference sweep: the demo accelerometer over six noise seeds"]
        fn the_measured_end_effector_mode_follows_the_model_over_six_seeds() {
            super::measured_mode_follows_the_model(super::SLOW_SEEDS);
        }
    }
}
