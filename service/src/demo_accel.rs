//! `demo`'s synthetic accelerometer: the simulated vibration of the demo's trajectory, read
//! by a sensor on the platform and published on the vibration service at 1 kHz, so that the
//! measured frequencies of the estimate work on a fresh clone.
//!
//! The response is `study::simulate`'s (modal superposition of the pose's modes along the
//! circle, the scene's damping, or ζ = 1 % in every mode when the scene has none, since an
//! undamped robot under noise rings without bound), with a white-noise force on the
//! end-effector ([`FORCE_NOISE_N`] per sample, standing for the disturbances a real robot
//! feels) besides the path's inertial load. The sensor reads the specific force: the path's
//! acceleration, the deviation's (second differences at 1 kHz: 0.3 % low in amplitude at
//! 29 Hz, no frequency error) and −g, plus white sensor noise ([`SENSOR_NOISE_M_S2`]).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use cablevib_ipc::{monotonic_now_ns, ServiceNames, VibrationSample};
use nalgebra::Vector3;

use super::ports::{create_node, open_pubsub, VIBRATION_SETTINGS};
use super::ServiceError;
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
/// Longest accelerometer record, s (it is computed before the demo starts: 60 B per sample).
pub const MAX_SECONDS: f64 = 600.0;
/// Samples between two updates of the modes along the path (50 ms: the end-effector mode
/// moves by under 0.1 Hz meanwhile on the paper's circle).
const UPDATE_EVERY: usize = 50;

/// SplitMix64 and Box-Muller: deterministic standard normal numbers.
struct Noise(u64);
impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        (-2.0 * u1.ln()).sqrt() * (2.0 * core::f64::consts::PI * self.uniform()).cos()
    }
}

/// The accelerometer's samples along `trajectory` for `seconds`, m/s², and the damping
/// ratio used (None: the scene's own damping).
pub fn record(
    scene: &Scene,
    trajectory: &Trajectory,
    seconds: f64,
) -> Result<(Vec<[f64; 3]>, Option<f64>), ServiceError> {
    let mut scene = scene.clone();
    let zeta = scene.damping.is_none().then_some(DEFAULT_ZETA);
    if let Some(z) = zeta {
        scene.damping = Damping::ModalRatio { zeta: z };
    }
    let bad = |e: crate::study::StudyError| ServiceError::Usage(format!("accelerometer: {e}"));
    let path =
        SampledPath::from_trajectory(trajectory, seconds, SAMPLE_PERIOD_S, false).map_err(bad)?;
    let cfg = SimulateConfig {
        update_every: UPDATE_EVERY,
        ..SimulateConfig::default()
    };
    let mut noise = Noise(0x5eed);
    let r = simulate_forced(&scene, &path, &cfg, |_| {
        Vector3::new(noise.normal(), noise.normal(), noise.normal()) * FORCE_NOISE_N
    })
    .map_err(bad)?;
    let u = &r.deviation_m;
    let h2 = SAMPLE_PERIOD_S * SAMPLE_PERIOD_S;
    let g = scene.gravity_m_s2;
    let out = (0..u.len())
        .map(|k| {
            let (a, b) = (k.saturating_sub(1), (k + 1).min(u.len() - 1));
            let dev = if a + 2 == b {
                (u[b] - 2.0 * u[k] + u[a]) / h2
            } else {
                Vector3::zeros()
            };
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
        .map_err(|e| ServiceError::Usage(format!("cannot start the accelerometer thread: {e}")))
}
