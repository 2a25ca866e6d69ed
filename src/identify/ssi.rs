//! Covariance-driven stochastic subspace identification: covariances → block Hankel matrix
//! → SVD → a state-space model per order → its poles and mode shapes.
//!
//! With the covariances R_i = E[y_k y_{k−i}ᵀ] = C Aⁱ⁻¹ G (i ≥ 1) of the channels scaled to
//! unit variance (D = diag(√R_0), R̃_i = D⁻¹ R_i D⁻¹, so channels of different units weigh
//! alike), the block Hankel matrix H (p l × p l, block (r, c) = R̃_{r+c+1}) factors as
//! O_p Γ_p, the observability and controllability matrices. Its SVD H = U S Vᵀ gives, for an
//! order n, O = U_n S_n^{1/2}; C is its first block row and A solves O↑ A = O↓ (O without
//! its last, first block row) in least squares.
//!
//! All orders are truncations of the one SVD, and so is the least-squares problem: with the
//! QR factorisation O↑ = Q R of the largest order, the first n columns of O↑ are Q_n R_nn,
//! so A_n = R_nn⁻¹ (Qᵀ O↓)_nn for every n from one QR and one product.
//!
//! The eigenvalues μ of A_n are the discrete poles; s = ln μ / Δt, f = |s|/2π,
//! ζ = −Re s / |s|; the mode shape is C ψ for the eigenvector ψ (scaled back by D). Only
//! poles in the band with 0 < ζ ≤ ζ_max and Im s > 0 are kept. Eigenvectors come from the
//! complex Schur form A = Z T Zᴴ by back substitution on T.

use super::covariance::Covariances;
use nalgebra::{DMatrix, DVector};
use num_complex::Complex64;

/// Tolerance and iteration cap of the SVD and Schur iterations (nalgebra's).
const EPS: f64 = 1e-14;
const MAX_ITER: usize = 10_000;

/// One pole of one order.
#[derive(Debug, Clone, PartialEq)]
pub struct Pole {
    /// Model order.
    pub order: usize,
    /// Undamped natural frequency |s|/2π, Hz.
    pub frequency_hz: f64,
    /// Damping ratio −Re s/|s|.
    pub damping_ratio: f64,
    /// Mode shape at the channels, in the scaled channels (unit variance), max |φ| = 1.
    pub shape: Vec<Complex64>,
}

/// The band and damping of the poles kept.
#[derive(Debug, Clone, Copy)]
pub struct PoleFilter {
    /// Band, Hz.
    pub from_hz: f64,
    /// Band, Hz.
    pub to_hz: f64,
    /// Largest damping ratio.
    pub max_damping_ratio: f64,
    /// Sample period of the covariances, s.
    pub dt_s: f64,
}

impl PoleFilter {
    /// The continuous pole of discrete eigenvalue `mu`, if kept: (f Hz, ζ).
    fn keep(&self, mu: Complex64) -> Option<(f64, f64)> {
        if !(mu.im > 0.0) || !(mu.norm() > 0.0) {
            return None;
        }
        let s = mu.ln() / self.dt_s;
        let w = s.norm();
        let f = w / (2.0 * std::f64::consts::PI);
        let z = -s.re / w;
        (f >= self.from_hz && f <= self.to_hz && z > 0.0 && z <= self.max_damping_ratio)
            .then_some((f, z))
    }
}

/// The block Hankel matrix of `p` block rows of the scaled covariances, and the scale D.
pub fn hankel(cov: &Covariances, p: usize, scale: &[f64]) -> DMatrix<f64> {
    let l = cov.channels;
    DMatrix::from_fn(p * l, p * l, |row, col| {
        let (r, a) = (row / l, row % l);
        let (c, b) = (col / l, col % l);
        cov.at(r + c + 1, a, b) / (scale[a] * scale[b])
    })
}

/// The scale of each channel: √R_0(a, a) (1 for a channel without variance).
pub fn channel_scale(cov: &Covariances) -> Vec<f64> {
    (0..cov.channels)
        .map(|a| {
            let v = cov.at(0, a, a);
            if v > 0.0 && v.is_finite() {
                v.sqrt()
            } else {
                1.0
            }
        })
        .collect()
}

/// The SVD of one Hankel matrix and the factors every order shares.
pub struct Subspace {
    l: usize,
    /// O of the largest order (p l × n_max).
    o: DMatrix<f64>,
    /// R of O↑ = Q R.
    r: DMatrix<f64>,
    /// Qᵀ O↓.
    m: DMatrix<f64>,
    /// The right singular vectors times S^{−1/2} (columns of H × n_max): O_j = H_j W for the
    /// jackknife.
    w: DMatrix<f64>,
    /// Singular values, descending.
    pub singular_values: Vec<f64>,
}

impl Subspace {
    /// SVD of `h` (p l rows; p l columns of covariances, or p m of an impulse response of m
    /// inputs) and the factors up to order `n_max`; `None` when the SVD does not converge or
    /// the Hankel matrix holds less than order `n_max`.
    pub fn new(h: &DMatrix<f64>, l: usize, n_max: usize) -> Option<Subspace> {
        let rows = h.nrows();
        if !h.iter().all(|x| x.is_finite()) {
            return None;
        }
        let svd = nalgebra::linalg::SVD::try_new(h.clone(), true, true, EPS, MAX_ITER)?;
        let (u, vt) = (svd.u?, svd.v_t?);
        let mut idx: Vec<usize> = (0..svd.singular_values.len()).collect();
        idx.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
        let sv: Vec<f64> = idx.iter().map(|&i| svd.singular_values[i]).collect();
        if n_max > rows - l || !(sv.get(n_max - 1).copied().unwrap_or(0.0) > 0.0) {
            return None;
        }
        let o = DMatrix::from_fn(rows, n_max, |i, j| u[(i, idx[j])] * sv[j].sqrt());
        let w = DMatrix::from_fn(h.ncols(), n_max, |i, j| vt[(idx[j], i)] / sv[j].sqrt());
        let up = o.rows(0, rows - l).into_owned();
        let down = o.rows(l, rows - l).into_owned();
        let qr = up.qr();
        let (q, r) = (qr.q(), qr.r());
        let m = q.transpose() * down;
        Some(Subspace {
            l,
            o,
            r,
            m,
            w,
            singular_values: sv,
        })
    }

    /// The poles of order `n` kept by `filter`; `None` when the order's model is singular or
    /// its Schur iteration fails.
    pub fn poles(&self, n: usize, filter: &PoleFilter) -> Option<Vec<Pole>> {
        let rn = self.r.view((0, 0), (n, n));
        let a = rn.solve_upper_triangular(&self.m.view((0, 0), (n, n)).into_owned())?;
        let c = self.o.view((0, 0), (self.l, n)).into_owned();
        poles_of(&a, &c, n, filter)
    }

    /// The poles of order `n` of another Hankel matrix `h` (the same window without one
    /// segment) in this subspace's right singular directions: O = H W_n (to first order the
    /// left singular subspace of `h`), then A, C and the poles as for [`Subspace::poles`].
    pub fn poles_projected(
        &self,
        h: &DMatrix<f64>,
        n: usize,
        filter: &PoleFilter,
    ) -> Option<Vec<Pole>> {
        let rows = h.nrows();
        let l = self.l;
        let o = h * self.w.columns(0, n);
        let up = o.rows(0, rows - l).into_owned();
        let down = o.rows(l, rows - l).into_owned();
        let qr = up.qr();
        let a = qr
            .r()
            .solve_upper_triangular(&(qr.q().transpose() * down))?;
        let c = o.rows(0, l).into_owned();
        poles_of(&a, &c, n, filter)
    }
}

/// The kept poles of the model (A, C) of order `n`.
fn poles_of(
    a: &DMatrix<f64>,
    c: &DMatrix<f64>,
    n: usize,
    filter: &PoleFilter,
) -> Option<Vec<Pole>> {
    if !a.iter().all(|x| x.is_finite()) {
        return None;
    }
    let ac: DMatrix<Complex64> = a.map(|x| Complex64::new(x, 0.0));
    let schur = nalgebra::linalg::Schur::try_new(ac, EPS, MAX_ITER)?;
    let (z, t) = schur.unpack();
    let cc: DMatrix<Complex64> = c.map(|x| Complex64::new(x, 0.0));
    let tnorm = t
        .iter()
        .map(|x| x.norm())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut out = Vec::new();
    for k in 0..n {
        let mu = t[(k, k)];
        let Some((f, zeta)) = filter.keep(mu) else {
            continue;
        };
        // Eigenvector of T for μ = T_kk: x_k = 1, back substitution above it.
        let mut x = DVector::<Complex64>::zeros(n);
        x[k] = Complex64::new(1.0, 0.0);
        for i in (0..k).rev() {
            let mut s = Complex64::new(0.0, 0.0);
            for j in i + 1..=k {
                s += t[(i, j)] * x[j];
            }
            let mut d = t[(i, i)] - mu;
            if d.norm() < 1e-14 * tnorm {
                d = Complex64::new(1e-14 * tnorm, 0.0);
            }
            x[i] = -s / d;
        }
        let psi = &z * x;
        let phi = &cc * psi;
        out.push(Pole {
            order: n,
            frequency_hz: f,
            damping_ratio: zeta,
            shape: normalise(phi.as_slice()),
        });
    }
    Some(out)
}

/// `v` rotated so that its largest entry is real and positive, scaled to max |v| = 1 (a zero
/// vector is returned unchanged).
pub fn normalise(v: &[Complex64]) -> Vec<Complex64> {
    let big = v
        .iter()
        .copied()
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .unwrap_or_default();
    if !(big.norm() > 0.0) {
        return v.to_vec();
    }
    let rot = big.conj() / (big.norm() * big.norm());
    v.iter().map(|x| x * rot).collect()
}

/// The modal assurance criterion |aᴴb|² / (aᴴa · bᴴb) (0 for a zero vector).
pub fn mac(a: &[Complex64], b: &[Complex64]) -> f64 {
    let ab: Complex64 = a.iter().zip(b).map(|(x, y)| x.conj() * y).sum();
    let aa: f64 = a.iter().map(|x| x.norm_sqr()).sum();
    let bb: f64 = b.iter().map(|x| x.norm_sqr()).sum();
    if aa > 0.0 && bb > 0.0 {
        ab.norm_sqr() / (aa * bb)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The covariances of a known discrete state-space model (R_i = C Aⁱ⁻¹ G): every order
    /// ≥ the model's returns its poles exactly, the truncated-QR shortcut included.
    #[test]
    fn exact_covariances_give_exact_poles() {
        let dt = 0.01;
        // Two modes: 3 Hz ζ 0.02 and 7 Hz ζ 0.01, as a real 4-state A in modal blocks.
        let modes = [(3.0, 0.02), (7.0, 0.01)];
        let mut a = DMatrix::<f64>::zeros(4, 4);
        for (j, &(f, z)) in modes.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * f;
            let s = Complex64::new(-z * w, w * (1.0 - z * z).sqrt());
            let mu = (s * dt).exp();
            a[(2 * j, 2 * j)] = mu.re;
            a[(2 * j, 2 * j + 1)] = mu.im;
            a[(2 * j + 1, 2 * j)] = -mu.im;
            a[(2 * j + 1, 2 * j + 1)] = mu.re;
        }
        let c = DMatrix::from_row_slice(2, 4, &[1.0, 0.3, 0.5, -0.2, 0.4, -0.1, -1.0, 0.6]);
        let g = DMatrix::from_row_slice(4, 2, &[0.7, 0.2, -0.3, 0.5, 0.4, -0.8, 0.1, 0.9]);
        let p = 10;
        let l = 2;
        let mut r = vec![0.0; 2 * p * l * l];
        let mut ak = DMatrix::<f64>::identity(4, 4);
        for i in 1..2 * p {
            let ri = &c * &ak * &g;
            for x in 0..l {
                for y in 0..l {
                    r[(i * l + x) * l + y] = ri[(x, y)];
                }
            }
            ak = &ak * &a;
        }
        let cov = Covariances {
            channels: l,
            r,
            samples: 1,
        };
        let h = hankel(&cov, p, &[1.0, 1.0]);
        let sub = Subspace::new(&h, l, 4).unwrap();
        let filter = PoleFilter {
            from_hz: 0.1,
            to_hz: 40.0,
            max_damping_ratio: 0.5,
            dt_s: dt,
        };
        let poles = sub.poles(4, &filter).unwrap();
        assert_eq!(poles.len(), 2);
        let mut got: Vec<(f64, f64)> = poles
            .iter()
            .map(|p| (p.frequency_hz, p.damping_ratio))
            .collect();
        got.sort_by(|x, y| x.0.total_cmp(&y.0));
        for (g, m) in got.iter().zip(modes) {
            assert!((g.0 - m.0).abs() < 1e-9 * m.0, "{g:?} vs {m:?}");
            assert!((g.1 - m.1).abs() < 1e-8, "{g:?} vs {m:?}");
        }
        // The shape is C ψ: for the 3 Hz mode, the complex column pair of C.
        let p3 = poles
            .iter()
            .find(|p| (p.frequency_hz - 3.0).abs() < 0.1)
            .unwrap();
        let want = normalise(&[Complex64::new(1.0, 0.3), Complex64::new(0.4, -0.1)]);
        let want_conj: Vec<Complex64> = want.iter().map(|x| x.conj()).collect();
        let m = mac(&p3.shape, &want).max(mac(&p3.shape, &want_conj));
        assert!(m > 1.0 - 1e-9, "MAC {m}");
    }
}
