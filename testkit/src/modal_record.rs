//! Records of systems with known modes for the identification tests: exact discrete-time
//! integration of each modal oscillator under white-noise forces held over each step, sensor
//! noise at a given signal-to-noise ratio, and the check of identified modes against the
//! known ones. Written independently of the identifier.

use crate::Rng;
use std::f64::consts::PI;

/// A standard normal sample (Box–Muller).
pub fn gauss(r: &mut Rng) -> f64 {
    let u1 = r.next().max(1e-300);
    let u2 = r.next();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// A system by its modes: frequencies (Hz), damping ratios and mass-normalised shapes
/// (`shapes[j][dof]`), of `dofs` degrees of freedom.
pub struct Modal {
    /// Hz.
    pub frequencies_hz: Vec<f64>,
    pub zetas: Vec<f64>,
    pub shapes: Vec<Vec<f64>>,
}

/// What is measured.
#[derive(Clone, Copy, PartialEq)]
pub enum Output {
    Acceleration,
    Displacement,
}

/// A fixed–fixed chain of 5 equal masses m = 2 and springs k: ω_j = 2√(k/m) sin(jπ/12)
/// (k set by `f1_hz`), mass-normalised φ_j(i) = √(2/(6m)) sin(i j π/6) (i = 1 … 5).
pub fn chain(f1_hz: f64, zetas: &[f64]) -> Modal {
    let n = 5;
    let m: f64 = 2.0;
    let s1 = (PI / (2.0 * (n + 1) as f64)).sin();
    Modal {
        frequencies_hz: (1..=n)
            .map(|j| f1_hz * (j as f64 * PI / (2.0 * (n + 1) as f64)).sin() / s1)
            .collect(),
        zetas: zetas.to_vec(),
        shapes: (1..=n)
            .map(|j| {
                (1..=n)
                    .map(|i| {
                        (2.0 / ((n + 1) as f64 * m)).sqrt()
                            * (i as f64 * j as f64 * PI / (n + 1) as f64).sin()
                    })
                    .collect()
            })
            .collect(),
    }
}

/// Two equal oscillators (m = 1.5) coupled to modes 1 % apart, 10 and 10.1 Hz (in-phase and
/// anti-phase shapes on DOFs 1, 2), and a third at 6 Hz on DOF 3; ζ 1 %, 0.8 %, 1 %.
pub fn close_pair() -> Modal {
    let m: f64 = 1.5;
    let a = 1.0 / (2.0 * m).sqrt();
    Modal {
        frequencies_hz: vec![6.0, 10.0, 10.1],
        zetas: vec![0.01, 0.008, 0.01],
        shapes: vec![
            vec![0.0, 0.0, 1.0 / m.sqrt()],
            vec![a, a, 0.0],
            vec![a, -a, 0.0],
        ],
    }
}

/// A record: times and row-major samples of the sensed DOFs (and of the measured forces).
pub struct Record {
    pub t_s: Vec<f64>,
    pub y: Vec<f64>,
    pub channels: usize,
    /// The measured forces, row-major (empty under unmeasured ambient forcing).
    pub u: Vec<f64>,
    pub inputs: usize,
}

impl Record {
    /// Sample k: the outputs, then the inputs.
    pub fn sample(&self, k: usize) -> Vec<f64> {
        let (l, m) = (self.channels, self.inputs);
        [&self.y[k * l..(k + 1) * l], &self.u[k * m..(k + 1) * m]].concat()
    }
}

/// Simulate `duration_s` at `rate_hz` under independent white-noise forces (unit variance,
/// held over each step) on every DOF; measure `sensors` (DOF indices) with white sensor
/// noise at `snr_db` (power ratio per channel).
pub fn simulate(
    m: &Modal,
    sensors: &[usize],
    out: Output,
    rate_hz: f64,
    duration_s: f64,
    snr_db: f64,
    seed: u64,
) -> Record {
    simulate_with(m, sensors, None, out, rate_hz, duration_s, snr_db, seed)
}

/// As [`simulate`], but the white-noise forces (unit variance, held over each step) act on
/// the DOFs `forced` only and are measured exactly (the record's inputs, in that order).
#[allow(clippy::too_many_arguments)]
pub fn simulate_forced(
    m: &Modal,
    sensors: &[usize],
    forced: &[usize],
    out: Output,
    rate_hz: f64,
    duration_s: f64,
    snr_db: f64,
    seed: u64,
) -> Record {
    simulate_with(
        m,
        sensors,
        Some(forced),
        out,
        rate_hz,
        duration_s,
        snr_db,
        seed,
    )
}

#[allow(clippy::too_many_arguments)]
fn simulate_with(
    m: &Modal,
    sensors: &[usize],
    forced: Option<&[usize]>,
    out: Output,
    rate_hz: f64,
    duration_s: f64,
    snr_db: f64,
    seed: u64,
) -> Record {
    let h = 1.0 / rate_hz;
    let n = (duration_s * rate_hz).round() as usize;
    let dofs = m.shapes[0].len();
    let nm = m.frequencies_hz.len();
    // Exact step of q̈ + 2ζω q̇ + ω² q = u for u constant over the step:
    // x⁺ = E (x − [u/ω², 0]) + [u/ω², 0], E = e^{A h} in closed form (underdamped).
    let e: Vec<[f64; 4]> = (0..nm)
        .map(|j| {
            let w = 2.0 * std::f64::consts::PI * m.frequencies_hz[j];
            let z = m.zetas[j];
            let s = z * w;
            let wd = w * (1.0 - z * z).sqrt();
            let (c, sn, ex) = ((wd * h).cos(), (wd * h).sin(), (-s * h).exp());
            [
                ex * (c + s / wd * sn),
                ex * sn / wd,
                -ex * w * w * sn / wd,
                ex * (c - s / wd * sn),
            ]
        })
        .collect();
    let mut r = Rng(seed);
    let mut q = vec![[0.0f64; 2]; nm];
    let mut clean = vec![0.0; n * sensors.len()];
    let mut f = vec![0.0; dofs];
    let nf = forced.map_or(0, |d| d.len());
    let mut uv = vec![0.0; n * nf];
    // Burn-in of 20 s so the record starts in the stationary state.
    let burn = (20.0 * rate_hz) as usize;
    for k in 0..burn + n {
        match forced {
            None => f.iter_mut().for_each(|v| *v = gauss(&mut r)),
            Some(ds) => {
                for (i, &d) in ds.iter().enumerate() {
                    f[d] = gauss(&mut r);
                    if k >= burn {
                        uv[(k - burn) * nf + i] = f[d];
                    }
                }
            }
        }
        let mut y = vec![0.0; sensors.len()];
        for j in 0..nm {
            let u: f64 = (0..dofs).map(|d| m.shapes[j][d] * f[d]).sum();
            let w = 2.0 * std::f64::consts::PI * m.frequencies_hz[j];
            let val = match out {
                Output::Acceleration => u - 2.0 * m.zetas[j] * w * q[j][1] - w * w * q[j][0],
                Output::Displacement => q[j][0],
            };
            for (c, &s) in sensors.iter().enumerate() {
                y[c] += m.shapes[j][s] * val;
            }
            let qs = u / (w * w);
            let (x0, x1) = (q[j][0] - qs, q[j][1]);
            let ej = e[j];
            q[j] = [ej[0] * x0 + ej[1] * x1 + qs, ej[2] * x0 + ej[3] * x1];
        }
        if k >= burn {
            clean[(k - burn) * sensors.len()..(k - burn + 1) * sensors.len()].copy_from_slice(&y);
        }
    }
    let l = sensors.len();
    let mut yv = clean;
    for c in 0..l {
        let var = (0..n).map(|k| yv[k * l + c].powi(2)).sum::<f64>() / n as f64;
        let sd = (var / 10f64.powf(snr_db / 10.0)).sqrt();
        for k in 0..n {
            yv[k * l + c] += sd * gauss(&mut r);
        }
    }
    Record {
        t_s: (0..n).map(|k| k as f64 * h).collect(),
        y: yv,
        channels: l,
        u: uv,
        inputs: nf,
    }
}

/// Check every identified mode set against the known modes with ζ ≥ 0.5 %: each is found,
/// its frequency within max(0.1 %, 3σ_f) and damping within max(10 %, 3σ_ζ) of the truth,
/// σ the record's statistical limit; no extra mode in the band. Returns the largest
/// relative frequency and damping errors, and prints the table.
pub fn check_modes(
    got: &[cablevib::identify::IdentifiedMode],
    truth_hz: &[f64],
    truth_zeta: &[f64],
    duration_s: f64,
) -> (f64, f64) {
    let mut worst = (0.0f64, 0.0f64);
    assert_eq!(
        got.len(),
        truth_hz.len(),
        "identified {:?} vs truth {truth_hz:?}",
        got.iter().map(|m| m.frequency_hz).collect::<Vec<_>>()
    );
    for (j, (&f, &z)) in truth_hz.iter().zip(truth_zeta).enumerate() {
        let m = &got[j];
        let (sf, sz) = cablevib::identify::statistical_limit(f, z, duration_s);
        let ef = (m.frequency_hz - f).abs() / f;
        let ez = (m.damping_ratio - z).abs() / z;
        println!(
            "mode {}: f {:.5} Hz (truth {f:.5}, err {:.3} %, 3σ {:.3} %, jackknife σ {:.3} %)  ζ {:.5} (truth {z:.5}, err {:.1} %, 3σ {:.1} %, jackknife σ {:.1} %)",
            j + 1,
            m.frequency_hz,
            ef * 100.0,
            3.0 * sf * 100.0,
            m.frequency_std_hz / f * 100.0,
            m.damping_ratio,
            ez * 100.0,
            3.0 * sz * 100.0,
            m.damping_ratio_std / z * 100.0
        );
        if z >= 0.005 {
            assert!(
                ef <= (3.0 * sf).max(1e-3),
                "mode {}: frequency error {ef:.2e}",
                j + 1
            );
            assert!(
                ez <= (3.0 * sz).max(0.1),
                "mode {}: damping error {ez:.2e}",
                j + 1
            );
        }
        worst = (
            worst.0.max(ef / (3.0 * sf).max(1e-3)),
            worst.1.max(ez / (3.0 * sz).max(0.1)),
        );
    }
    worst
}
