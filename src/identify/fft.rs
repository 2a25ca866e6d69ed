//! The discrete Fourier transform of a power-of-two length: an iterative radix-2
//! Cooley–Tukey FFT in place, X_k = Σ_n x_n e^{∓2πi kn/N} (− forward, + inverse, the inverse
//! not divided by N). N log₂N complex multiply-adds; the twiddles are computed once per
//! transform length ([`Fft::new`]).

use num_complex::Complex64;

/// Largest transform length (2^20 points: 16 MB of complex numbers).
pub const MAX_LEN: usize = 1 << 20;

/// A transform of one power-of-two length.
#[derive(Debug, Clone)]
pub struct Fft {
    n: usize,
    /// e^{−2πi k/N}, k = 0 … N/2 − 1.
    twiddles: Vec<Complex64>,
}

impl Fft {
    /// A transform of length `n` (a power of two, 1 ..= [`MAX_LEN`]); `None` otherwise.
    pub fn new(n: usize) -> Option<Fft> {
        if !n.is_power_of_two() || n > MAX_LEN {
            return None;
        }
        let twiddles = (0..n / 2)
            .map(|k| Complex64::from_polar(1.0, -2.0 * std::f64::consts::PI * k as f64 / n as f64))
            .collect();
        Some(Fft { n, twiddles })
    }

    /// The length.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the length is 0 (never: the smallest transform has length 1).
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Transform `x` (length N) in place: forward (e^{−…}) or inverse (e^{+…}, unscaled).
    pub fn transform(&self, x: &mut [Complex64], inverse: bool) {
        let n = self.n;
        assert_eq!(x.len(), n, "FFT of length {n} given {} points", x.len());
        // Bit-reversal permutation.
        let bits = n.trailing_zeros();
        if bits > 0 {
            for i in 0..n {
                let j = i.reverse_bits() >> (usize::BITS - bits);
                if j > i {
                    x.swap(i, j);
                }
            }
        }
        let mut len = 2;
        while len <= n {
            let step = n / len;
            for start in (0..n).step_by(len) {
                for k in 0..len / 2 {
                    let mut w = self.twiddles[k * step];
                    if inverse {
                        w = w.conj();
                    }
                    let a = x[start + k];
                    let b = x[start + k + len / 2] * w;
                    x[start + k] = a + b;
                    x[start + k + len / 2] = a - b;
                }
            }
            len *= 2;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against the direct sum Σ x_n e^{−2πi kn/N}, and the inverse returns N x.
    #[test]
    fn equals_direct_sum() {
        for n in [1usize, 2, 8, 64] {
            let x: Vec<Complex64> = (0..n)
                .map(|k| Complex64::new((k as f64 * 0.7).sin() + 0.3, (k as f64 * 1.3).cos()))
                .collect();
            let f = Fft::new(n).unwrap();
            let mut y = x.clone();
            f.transform(&mut y, false);
            for (k, yk) in y.iter().enumerate() {
                let d: Complex64 = x
                    .iter()
                    .enumerate()
                    .map(|(j, v)| {
                        v * Complex64::from_polar(
                            1.0,
                            -2.0 * std::f64::consts::PI * (k * j) as f64 / n as f64,
                        )
                    })
                    .sum();
                assert!((yk - d).norm() < 1e-12 * n as f64, "n {n} k {k}");
            }
            f.transform(&mut y, true);
            for (a, b) in y.iter().zip(&x) {
                assert!((a / n as f64 - b).norm() < 1e-13);
            }
        }
        assert!(Fft::new(12).is_none());
    }
}
