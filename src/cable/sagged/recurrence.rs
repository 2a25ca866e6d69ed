//! The condensation recurrence of a sagged chain (see the module docs): in-plane 2 × 2
//! blocks, out-of-plane scalars, their λ-derivatives and the pivots' negative count.

use super::chain::SagChain;
use super::supported::junction_start;
use super::SagChainEval;
use crate::cable::ChainScalar;
use num_complex::Complex64;

/// A symmetric 2 × 2 matrix [a b; b c] as [a, b, c].
type Sym2<T = f64> = [T; 3];
/// A general 2 × 2 matrix, row-major [[y00, y01], [y10, y11]].
type Mat2<T = f64> = [[T; 2]; 2];

/// Number of negative eigenvalues of the symmetric 2 × 2 matrix `q` with determinant `det`
/// (≠ 0): one when det < 0, both when det > 0 and the diagonal is negative.
#[inline]
fn negatives2<T: ChainScalar>(q: &Sym2<T>, det: T) -> u32 {
    if det.is_negative() {
        1
    } else if q[0].is_negative() {
        2
    } else {
        0
    }
}

/// Y = Q⁻¹ E for symmetric Q (determinant `det` ≠ 0) and E.
#[inline]
fn solve2<T: ChainScalar>(q: &Sym2<T>, det: T, e: &Sym2<T>) -> Mat2<T> {
    let inv = det.recip();
    // Q⁻¹ = [c −b; −b a]/det.
    let (ia, ib, ic) = (q[2] * inv, -q[1] * inv, q[0] * inv);
    [
        [ia * e[0] + ib * e[1], ia * e[1] + ib * e[2]],
        [ib * e[0] + ic * e[1], ib * e[1] + ic * e[2]],
    ]
}

/// Sym(Xᵀ Y) for symmetric X given as [a, b, c] and general Y: the symmetric part of
/// Xᵀ Y = X Y (entries 00, 01 averaged with 10, 11).
#[inline]
fn sym_xy<T: ChainScalar>(x: &Sym2<T>, y: &Mat2<T>) -> Sym2<T> {
    let p00 = x[0] * y[0][0] + x[1] * y[1][0];
    let p01 = x[0] * y[0][1] + x[1] * y[1][1];
    let p10 = x[1] * y[0][0] + x[2] * y[1][0];
    let p11 = x[1] * y[0][1] + x[2] * y[1][1];
    [p00, (p01 + p10) * 0.5, p11]
}

/// Yᵀ X Y for symmetric X and general Y (symmetric result).
#[inline]
fn congruence<T: ChainScalar>(x: &Sym2<T>, y: &Mat2<T>) -> Sym2<T> {
    // X Y columns, then Yᵀ (X Y).
    let xy00 = x[0] * y[0][0] + x[1] * y[1][0];
    let xy10 = x[1] * y[0][0] + x[2] * y[1][0];
    let xy01 = x[0] * y[0][1] + x[1] * y[1][1];
    let xy11 = x[1] * y[0][1] + x[2] * y[1][1];
    [
        y[0][0] * xy00 + y[1][0] * xy10,
        y[0][0] * xy01 + y[1][0] * xy11,
        y[0][1] * xy01 + y[1][1] * xy11,
    ]
}

impl SagChain {
    /// S(λ), S'(λ) and the blocked count of the chain at λ = ω² (rad²/s²). O(N), no
    /// allocation; an empty chain gives zeros.
    pub fn eval(&self, lambda: f64) -> SagChainEval {
        let n = self.n_el();
        if n == 0 {
            return SagChainEval::default();
        }
        let (s_in, ds_in, below_in) = match &self.support {
            None => self.eval_in_plane(lambda),
            Some(sup) => {
                let hidden = Self::hidden_at_real(sup, lambda);
                let first = (self.k_in[0], self.mass_kg, self.nudge);
                let (s, ds, below) = junction_start(first, sup, lambda, hidden);
                self.in_plane_from(lambda, s, ds, below)
            }
        };
        let (s_out, ds_out, below_out) = self.eval_out_of_plane(lambda);
        SagChainEval {
            s_in,
            ds_in,
            s_out,
            ds_out,
            below: below_in + below_out,
        }
    }

    /// S(λ) at a complex λ (the damped frequency response): the same recurrences
    /// instantiated for [`Complex64`]; (in-plane [a, b, c] in (h, up), out-of-plane s), N/m.
    pub fn eval_at(&self, lambda: Complex64) -> ([Complex64; 3], Complex64) {
        if self.n_el() == 0 {
            let z = Complex64::new(0.0, 0.0);
            return ([z; 3], z);
        }
        let s_in = match &self.support {
            None => self.eval_in_plane(lambda).0,
            Some(sup) => {
                let hidden = Self::hidden_at_complex(sup, lambda);
                let first = (self.k_in[0], self.mass_kg, self.nudge);
                let (s, ds, below) = junction_start(first, sup, lambda, hidden);
                self.in_plane_from(lambda, s, ds, below).0
            }
        };
        (s_in, self.eval_out_of_plane(lambda).0)
    }

    /// The in-plane 2 × 2 recurrence: (S_N, S'_N, negative pivot eigenvalues).
    pub(super) fn eval_in_plane<T: ChainScalar>(&self, lambda: T) -> (Sym2<T>, Sym2<T>, u32) {
        let m = self.mass_kg;
        let d3 = lambda * m / 3.0;
        let k = &self.k_in;
        let re = T::re;
        let s = [re(k[0][0]) - d3, re(k[0][1]), re(k[0][2]) - d3];
        let ds = [re(-m / 3.0), re(0.0), re(-m / 3.0)];
        self.in_plane_from(lambda, s, ds, 0)
    }

    /// The in-plane recurrence from node 1's S₁, S₁′ and count `below` (the fixed anchor's
    /// or the junction's, `supported`): (S_N, S'_N, count).
    pub(super) fn in_plane_from<T: ChainScalar>(
        &self,
        lambda: T,
        mut s: Sym2<T>,
        mut ds: Sym2<T>,
        mut below: u32,
    ) -> (Sym2<T>, Sym2<T>, u32) {
        let m = self.mass_kg;
        let (d3, d6) = (lambda * m / 3.0, lambda * m / 6.0);
        let k = &self.k_in;
        let re = T::re;
        for kj in &k[1..] {
            let mut q = [
                s[0] + re(kj[0]) - d3,
                s[1] + re(kj[1]),
                s[2] + re(kj[2]) - d3,
            ];
            let dq = [ds[0] - re(m / 3.0), ds[1], ds[2] - re(m / 3.0)];
            let mut det = q[0] * q[2] - q[1] * q[1];
            if det.is_zero() {
                q[0] = q[0] + re(self.nudge);
                q[2] = q[2] + re(self.nudge);
                det = q[0] * q[2] - q[1] * q[1];
                if det.is_zero() {
                    det = re(self.nudge * self.nudge);
                }
            }
            below += negatives2(&q, det);
            // S_{j+1} = A − X Q⁻¹ X in the form with the smaller terms (module docs).
            let first = first_form(
                s[0].modulus() + s[2].modulus() + 2.0 * s[1].modulus(),
                kj[0].abs() + kj[2].abs(),
            );
            let (a, x, da, dx) = if first {
                (
                    [re(kj[0]) - d3, re(kj[1]), re(kj[2]) - d3],
                    [re(kj[0]) + d6, re(kj[1]), re(kj[2]) + d6],
                    [re(-m / 3.0), re(0.0), re(-m / 3.0)],
                    [re(m / 6.0), re(0.0), re(m / 6.0)],
                )
            } else {
                let lm = lambda * m;
                let d2 = lambda * m / 2.0;
                (
                    [s[0] - lm, s[1], s[2] - lm],
                    [s[0] - d2, s[1], s[2] - d2],
                    [ds[0] - re(m), ds[1], ds[2] - re(m)],
                    [ds[0] - re(m / 2.0), ds[1], ds[2] - re(m / 2.0)],
                )
            };
            let y = solve2(&q, det, &x);
            let xqx = sym_xy(&x, &y);
            let dxy = sym_xy(&dx, &y);
            let yqy = congruence(&dq, &y);
            s = [a[0] - xqx[0], a[1] - xqx[1], a[2] - xqx[2]];
            ds = [
                da[0] - dxy[0] * 2.0 + yqy[0],
                da[1] - dxy[1] * 2.0 + yqy[1],
                da[2] - dxy[2] * 2.0 + yqy[2],
            ];
        }
        (s, ds, below)
    }

    /// The out-of-plane scalar recurrence: (s_N, s'_N, negative pivots).
    fn eval_out_of_plane<T: ChainScalar>(&self, lambda: T) -> (T, T, u32) {
        let m = self.mass_kg;
        let (d3, d6) = (lambda * m / 3.0, lambda * m / 6.0);
        let k = &self.k_out;
        let re = T::re;
        let mut s = re(k[0]) - d3;
        let mut ds = re(-m / 3.0);
        let mut below = 0u32;
        for &kj in &k[1..] {
            let mut q = s + re(kj) - d3;
            if q.is_zero() {
                q = re(self.nudge);
            }
            below += q.is_negative() as u32;
            let dq = ds - re(m / 3.0);
            let (a, x, da, dx) = if first_form(s.modulus(), kj.abs()) {
                (re(kj) - d3, re(kj) + d6, re(-m / 3.0), re(m / 6.0))
            } else {
                (
                    s - lambda * m,
                    s - lambda * m / 2.0,
                    ds - re(m),
                    ds - re(m / 2.0),
                )
            };
            let y = x / q;
            s = a - x * y;
            ds = da - dx * 2.0 * y + dq * y * y;
        }
        (s, ds, below)
    }
}

/// Whether a step of the recurrence takes the first form S_{j+1} = A − B Q⁻¹ B (module
/// docs) rather than the second, S_j − λm I − E Q⁻¹ E: when the partial chain's end
/// stiffness `s_size` (a norm of S_j, N/m) exceeds the element's `k_size` (its trace,
/// N/m). Both are the same Schur complement; each loses digits where its own terms are
/// large: the second next to a partial chain's pole (S_j large, E Q⁻¹ E ≈ S_j cancels
/// against S_j: measured 7.6e-1 relative on S next to a sagged cable's axial pole, and a
/// blocked count that flips back and forth over 1e-8 of λ), the first in the static range
/// (B Q⁻¹ B ≈ k cancels against A ≈ k). Taking the form whose terms are smaller keeps
/// the rounding at ε·min(|S_j|, |k|).
#[inline(always)]
pub(super) fn first_form(s_size: f64, k_size: f64) -> bool {
    s_size > k_size
}
