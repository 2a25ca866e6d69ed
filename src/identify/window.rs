//! The identification of one window from its lag products: SSI-cov over the orders, the
//! stabilisation diagram, the clusters, and each mode's jackknife uncertainty.
//!
//! **Uncertainty.** The window's segments are dealt into g groups (`segments`, default 8);
//! leaving group j out gives covariances whose Hankel matrix H_(j), projected on the full
//! window's right singular vectors (O_(j) = H_(j) V_n S_n^{−1/2}, the first-order change of
//! the left singular subspace), gives the poles of the mode's order; the pole nearest the
//! mode is its estimate θ_(j). The jackknife variance is (g − 1)/g Σ (θ_(j) − θ̄)².
//! For a mode at ω with damping ζ in a record of T seconds the statistical limit is about
//! σ_f/f ≈ √(ζ/(ωT)) and σ_ζ/ζ ≈ 1/√(ζωT); the jackknife estimates the actual spread.

use super::cluster::{classify, cluster, distance, median, DiagramPole};
use super::covariance::LagCovariance;
use super::frf::{Frf, WelchH1};
use super::ssi::{channel_scale, hankel, normalise, PoleFilter, Subspace};
use super::IdentifyParams;
use nalgebra::DMatrix;
use num_complex::Complex64;

/// Why a window's modes are doubtful or missing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WindowStatus {
    /// Identified from a contiguous, finite record.
    Ok,
    /// Identified, but the window had gaps in time or non-finite samples (left out, counted).
    Gap,
    /// Too few samples for the Hankel matrix's lags (nothing identified).
    Short,
    /// No sample fell in the window (a gap covered it).
    NoData,
    /// The SVD or every order's eigenvalue iteration failed (nothing identified).
    Failed,
}

impl WindowStatus {
    /// The word written in the CSV's `status` column and the JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            WindowStatus::Ok => "ok",
            WindowStatus::Gap => "gap",
            WindowStatus::Short => "short",
            WindowStatus::NoData => "no_data",
            WindowStatus::Failed => "failed",
        }
    }
}

/// One identified mode.
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifiedMode {
    /// Undamped natural frequency, Hz (the median of its cluster).
    pub frequency_hz: f64,
    /// Viscous damping ratio (the median of its cluster).
    pub damping_ratio: f64,
    /// Jackknife standard deviation of the frequency over the window's segments, Hz (NaN
    /// when fewer than 2 segments found the mode).
    pub frequency_std_hz: f64,
    /// Jackknife standard deviation of the damping ratio.
    pub damping_ratio_std: f64,
    /// Standard deviation of the frequencies of the cluster's poles (over the orders), Hz.
    pub frequency_spread_hz: f64,
    /// The mode shape at the measured channels, in their units, rotated so that the largest
    /// entry is real and positive, max |φ| = 1.
    pub shape: Vec<Complex64>,
    /// Poles in the cluster (orders where the mode was stable).
    pub stable_poles: usize,
    /// The model order of the pole whose frequency is the cluster's median.
    pub order: usize,
    /// Segment groups whose leave-one-out estimate found the mode.
    pub jackknife_groups: usize,
    /// Input-output data: the outputs' mean multiple coherence of H1 at the mode's frequency
    /// (NaN for output-only data).
    pub coherence: f64,
}

/// What one window's identification found.
#[derive(Debug, Clone)]
pub struct Identified {
    /// Modes, ascending in frequency.
    pub modes: Vec<IdentifiedMode>,
    /// Every pole of every order with its stability.
    pub diagram: Vec<DiagramPole>,
    /// Singular values of the scaled Hankel matrix, descending.
    pub singular_values: Vec<f64>,
}

/// Identify one window (`dt_s` the mean sample period of its decimated samples).
pub fn identify_window(
    cov: &LagCovariance,
    p: &IdentifyParams,
    channels: usize,
    dt_s: f64,
) -> Result<Identified, WindowStatus> {
    let l = channels;
    let rows = p.block_rows(l);
    let full = cov.covariances(0..0).ok_or(WindowStatus::Short)?;
    let scale = channel_scale(&full);
    let h = hankel(&full, rows, &scale);
    // Leave-one-group-out Hankel matrices.
    let groups = cov.groups(p.segments);
    let jack: Vec<DMatrix<f64>> = if groups.len() >= 2 {
        groups
            .iter()
            .filter_map(|g| cov.covariances(g.clone()))
            .map(|c| hankel(&c, rows, &scale))
            .collect()
    } else {
        Vec::new()
    };
    identify_hankel(&h, &jack, &scale, p, dt_s)
}

/// Identify one window of input-output data from its Welch spectra (`l` outputs, `m`
/// inputs): H1 → impulse response → the block Hankel matrix of its Markov parameters
/// (block (r, c) = h̃_{r+c+1}, p l × p m, h̃ = D_y⁻¹ h D_u scaled by the channels' RMS) →
/// the same subspace identification, diagram and clustering as the output-only data (the
/// eigensystem realisation algorithm: SSI-cov's covariances replaced by the impulse
/// response); the jackknife over the groups of segments.
pub fn identify_io_window(
    welch: &WelchH1,
    p: &IdentifyParams,
    l: usize,
    m: usize,
    dt_s: f64,
) -> Result<(Identified, Frf), WindowStatus> {
    let rows = p.block_rows_io(l, m);
    let lags = 2 * rows;
    let full = welch.frf(None).ok_or(WindowStatus::Short)?;
    let h0 = welch.impulse_response(&full, lags);
    // The channels' scale: the RMS of each output's and input's impulse-response entries.
    let rms = |f: &dyn Fn(usize) -> f64, n: usize| {
        let v = ((0..n).map(|i| f(i).powi(2)).sum::<f64>() / n as f64).sqrt();
        if v > 0.0 && v.is_finite() {
            v
        } else {
            1.0
        }
    };
    let dy: Vec<f64> = (0..l)
        .map(|a| rms(&|i| h0[(i / m * l + a) * m + i % m], lags * m))
        .collect();
    let du: Vec<f64> = (0..m)
        .map(|b| 1.0 / rms(&|i| h0[(i / l * l + i % l) * m + b], lags * l))
        .collect();
    let hankel_of = |h: &[f64]| {
        DMatrix::from_fn(rows * l, rows * m, |row, col| {
            let (r, a) = (row / l, row % l);
            let (c, b) = (col / m, col % m);
            h[((r + c + 1) * l + a) * m + b] / dy[a] * du[b]
        })
    };
    let h = hankel_of(&h0);
    let jack: Vec<DMatrix<f64>> = if welch.groups() >= 2 {
        (0..welch.groups())
            .filter_map(|g| welch.frf(Some(g)))
            .map(|f| hankel_of(&welch.impulse_response(&f, lags)))
            .collect()
    } else {
        Vec::new()
    };
    let mut id = identify_hankel(&h, &jack, &dy, p, dt_s)?;
    // Each mode's coherence: the outputs' mean at the nearest line.
    let df = 1.0 / (full.n as f64 * dt_s);
    for md in &mut id.modes {
        let k = ((md.frequency_hz / df).round() as usize).min(full.lines() - 1);
        md.coherence = (0..l).map(|a| full.coherence[k * l + a]).sum::<f64>() / l as f64;
    }
    Ok((id, full))
}

/// The subspace identification of a block Hankel matrix `h` (rows scaled by `scale` per
/// output channel), its stabilisation diagram and clusters, and the jackknife over the
/// leave-one-group-out Hankel matrices `jack`.
fn identify_hankel(
    h: &DMatrix<f64>,
    jack: &[DMatrix<f64>],
    scale: &[f64],
    p: &IdentifyParams,
    dt_s: f64,
) -> Result<Identified, WindowStatus> {
    let l = scale.len();
    let sub = Subspace::new(h, l, p.max_order).ok_or(WindowStatus::Failed)?;
    let filter = PoleFilter {
        from_hz: p.from_hz,
        to_hz: p.to_hz,
        max_damping_ratio: p.max_damping_ratio,
        dt_s,
    };
    let mut by_order = Vec::new();
    let mut solved = 0;
    for n in p.orders() {
        match sub.poles(n, &filter) {
            Some(poles) => {
                solved += 1;
                by_order.push(poles);
            }
            None => by_order.push(Vec::new()),
        }
    }
    if solved == 0 {
        return Err(WindowStatus::Failed);
    }
    let orders = by_order.len();
    let diagram = classify(by_order, p);
    let clusters = cluster(&diagram, p, orders);
    let mut cache: Vec<(usize, Vec<Option<Vec<super::ssi::Pole>>>)> = Vec::new();
    let mut modes = Vec::new();
    for c in &clusters {
        let fs: Vec<f64> = c
            .members
            .iter()
            .map(|&i| diagram[i].pole.frequency_hz)
            .collect();
        let f = median(fs.iter().copied());
        let z = median(c.members.iter().map(|&i| diagram[i].pole.damping_ratio));
        let rep = *c
            .members
            .iter()
            .min_by(|&&a, &&b| {
                (diagram[a].pole.frequency_hz - f)
                    .abs()
                    .total_cmp(&(diagram[b].pole.frequency_hz - f).abs())
            })
            .expect("a cluster has members");
        let rep = &diagram[rep].pole;
        let mean = fs.iter().sum::<f64>() / fs.len() as f64;
        let spread = (fs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / fs.len() as f64).sqrt();
        // The jackknife at the representative's order.
        let n = rep.order;
        let k = match cache.iter().position(|(o, _)| *o == n) {
            Some(k) => k,
            None => {
                let poles = jack
                    .iter()
                    .map(|hj| sub.poles_projected(hj, n, &filter))
                    .collect();
                cache.push((n, poles));
                cache.len() - 1
            }
        };
        let mut est: Vec<(f64, f64)> = Vec::new();
        for poles in cache[k].1.iter().flatten() {
            let near = poles
                .iter()
                .min_by(|a, b| distance(a, rep).total_cmp(&distance(b, rep)));
            if let Some(q) = near {
                let df = (q.frequency_hz - rep.frequency_hz).abs() / rep.frequency_hz;
                if df <= 5.0 * p.frequency_tol
                    && super::ssi::mac(&q.shape, &rep.shape) >= 0.5 * p.mac_min
                {
                    est.push((q.frequency_hz, q.damping_ratio));
                }
            }
        }
        let (f_std, z_std) = jackknife_std(&est);
        let phys: Vec<Complex64> = rep.shape.iter().zip(scale).map(|(x, s)| x * s).collect();
        modes.push(IdentifiedMode {
            frequency_hz: f,
            damping_ratio: z,
            frequency_std_hz: f_std,
            damping_ratio_std: z_std,
            frequency_spread_hz: spread,
            shape: normalise(&phys),
            stable_poles: c.members.len(),
            order: n,
            jackknife_groups: est.len(),
            coherence: f64::NAN,
        });
    }
    Ok(Identified {
        modes,
        diagram,
        singular_values: sub.singular_values.clone(),
    })
}

/// The jackknife standard deviations of (f, ζ) from the leave-one-out estimates.
fn jackknife_std(est: &[(f64, f64)]) -> (f64, f64) {
    let g = est.len();
    if g < 2 {
        return (f64::NAN, f64::NAN);
    }
    let gf = g as f64;
    let mf = est.iter().map(|e| e.0).sum::<f64>() / gf;
    let mz = est.iter().map(|e| e.1).sum::<f64>() / gf;
    let vf = (gf - 1.0) / gf * est.iter().map(|e| (e.0 - mf).powi(2)).sum::<f64>();
    let vz = (gf - 1.0) / gf * est.iter().map(|e| (e.1 - mz).powi(2)).sum::<f64>();
    (vf.sqrt(), vz.sqrt())
}
