//! The lowest eigenpairs of a dense symmetric matrix: Householder tridiagonalisation, every
//! eigenvalue by implicit QL on the tridiagonal, the wanted vectors by inverse iteration on
//! the tridiagonal and the back-transform of those vectors only.
//!
//! **Maths.** A = Q T Qᵀ with Q = H₀ H₁ ⋯ H_{n−3}, H_j = I − τ_j v_j v_jᵀ (v_j zero above row
//! j + 1, v_j[j + 1] = 1) and T tridiagonal (diagonal d, off-diagonal e): each step takes
//! p = τ A₂₂ v, w = p − (τ/2)(pᵀv) v and A₂₂ ← A₂₂ − v wᵀ − w vᵀ on the trailing lower
//! triangle, (4/3) n³ flops. T splits where |e_i| ≤ ε (|d_i| + |d_{i+1}|) (a perturbation
//! of T below ε‖T‖); every eigenvalue of each unreduced block follows from implicit QL with
//! Wilkinson's shift, no vectors, O(n²). The vector of an eigenvalue μ of a block is that of
//! inverse iteration (T − μ I) x_{s+1} = x_s with partial pivoting (LAPACK `dstein`'s
//! scheme: a pseudo-random start, the right-hand side scaled so that the solve cannot
//! overflow, tiny pivots replaced by ε‖T‖, converged when the iterate's largest entry has
//! grown past √(0.1/n) and two more sweeps made). A computed vector's component along
//! another eigenvector at a distance g is ≈ ε‖T‖/g (the solve's backward error over the
//! gap), so: eigenvalues within [`GROUP_GAP`] · ‖T‖ of the previous one form a group whose
//! vectors are orthogonalised against the group's earlier ones inside the iteration (each
//! new vector then converges in the complement of the earlier ones: exactly multiple or
//! near-multiple eigenvalues get independent vectors); a value equal to the previous one to
//! 10 ε|μ| is nudged up by that much first. Components along eigenvectors further away
//! than the group gap are at most ε/[`GROUP_GAP`] and are removed afterwards by one
//! Cholesky-QR of each block's vectors (Z ← Z R⁻¹ with RᵀR = ZᵀZ), which mixes vector j with
//! the others by those same small amounts, so each residual stays ≈ ε‖T‖. Finally
//! y = Q z for the wanted columns only, 2 n² k flops.
//!
//! **Cost.** Against a full symmetric QR with vectors ((4/3) n³ for T, (4/3) n³ to form Q,
//! ≈ 6 n³ for the rotations on Q), this is (4/3) n³ + 2 n² k + O(n k²) for the k lowest
//! pairs: on a 219 × 219 matrix with a sagging robot's graded, 8-fold clustered spectrum
//! and k = 150, about 4.2 ms of CPU against nalgebra's 5.9 ms (measured side by side on
//! the shared machine). Where every vector is wanted it does not pay (0.59 ms against
//! 0.47 ms at n = k = 78). Each block's eigenvalues are found by QL from its end of
//! smaller diagonal entry (LAPACK `dsteqr`'s choice of QL or QR), which keeps a graded
//! block's small eigenvalues as accurate relative to themselves as the QR's. **Accuracy.** Backward stable like the QR: eigenvalues within a small multiple of
//! ε‖A‖ of exact, residuals ‖A y − λ y‖ ≈ ε‖A‖, the vectors orthonormal to a small multiple
//! of ε; the unit tests hold them to nalgebra's `SymmetricEigen` on random, graded and
//! clustered matrices.

use nalgebra::DMatrix;

/// Relative gap (of ‖T‖) under which eigenvalues are one group for inverse iteration
/// (module docs: vectors outside a group are then within ε/`GROUP_GAP` ≈ 2·10⁻⁷ of
/// orthogonal before the Cholesky-QR).
pub const GROUP_GAP: f64 = 1e-9;

/// Inverse-iteration sweeps per vector at most (LAPACK's `dstein`: 5).
pub const MAX_SWEEPS: usize = 5;

/// QL iterations per eigenvalue at most.
pub const MAX_QL_ITERATIONS: usize = 60;

/// Why an eigen-solve failed.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SymEigenError {
    /// The matrix is not square.
    #[error("a symmetric eigen-solve of a {rows}x{cols} matrix (square expected)")]
    NotSquare {
        /// Rows.
        rows: usize,
        /// Columns.
        cols: usize,
    },
    /// An entry is NaN or infinite.
    #[error("the matrix has a non-finite entry")]
    NotFinite,
    /// The QL iteration or the inverse iteration ran out of its bound.
    #[error("the tridiagonal {0} did not converge")]
    NoConvergence(&'static str),
}

/// The reduced matrix and every eigenvalue; the vectors on demand
/// ([`SymEigen::lowest_vectors`]).
#[derive(Debug, Clone)]
pub struct SymEigen {
    n: usize,
    /// Column-major n × n: below the subdiagonal, column j holds v_j's entries from row j + 2.
    a: Vec<f64>,
    /// τ_j of each reflector (n − 2 of them; 0 where the column was already reduced).
    tau: Vec<f64>,
    /// T's diagonal.
    d: Vec<f64>,
    /// T's off-diagonal, e[i] = T[i+1, i]; zero where T splits.
    e: Vec<f64>,
    /// Every eigenvalue, ascending.
    values: Vec<f64>,
    /// The unreduced block [start, end) of T each of `values` belongs to.
    block: Vec<(usize, usize)>,
}

impl SymEigen {
    /// Reduce the symmetric `a` (its lower triangle is read) and find every eigenvalue.
    pub fn new(a: DMatrix<f64>) -> Result<SymEigen, SymEigenError> {
        let (rows, cols) = a.shape();
        if rows != cols {
            return Err(SymEigenError::NotSquare { rows, cols });
        }
        let n = rows;
        let a: Vec<f64> = a.data.into();
        for j in 0..n {
            if a[j * n + j..(j + 1) * n].iter().any(|x| !x.is_finite()) {
                return Err(SymEigenError::NotFinite);
            }
        }
        let mut s = SymEigen {
            n,
            a,
            tau: vec![0.0; n.saturating_sub(2)],
            d: vec![0.0; n],
            e: vec![0.0; n.saturating_sub(1)],
            values: Vec::with_capacity(n),
            block: Vec::with_capacity(n),
        };
        s.tridiagonalise();
        s.eigenvalues()?;
        Ok(s)
    }

    /// The matrix's size.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Every eigenvalue, ascending.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The orthonormal eigenvectors (columns) of the lowest `count` eigenvalues (clamped to
    /// the size), in the order of [`SymEigen::values`].
    pub fn lowest_vectors(&self, count: usize) -> Result<DMatrix<f64>, SymEigenError> {
        let n = self.n;
        let count = count.min(n);
        let mut z = DMatrix::<f64>::zeros(n, count);
        // The wanted values of each block, ascending (the order of `values` within a block).
        let mut order: Vec<usize> = (0..count).collect();
        order.sort_by_key(|&c| (self.block[c].0, c));
        let mut tri = TridiagonalLu::new(n);
        let mut x = vec![0.0; n];
        let mut rng = 0x9e37_79b9_7f4a_7c15_u64;
        let mut i = 0;
        while i < order.len() {
            let (b0, b1) = self.block[order[i]];
            let mut j = i;
            while j < order.len() && self.block[order[j]].0 == b0 {
                j += 1;
            }
            self.block_vectors(b0, b1, &order[i..j], &mut z, &mut tri, &mut x, &mut rng)?;
            orthonormalise(&mut z, b0, b1, &order[i..j])?;
            i = j;
        }
        self.back_transform(&mut z);
        Ok(z)
    }

    /// Householder reduction of the lower triangle to T (module docs).
    fn tridiagonalise(&mut self) {
        let n = self.n;
        let mut work = vec![0.0; 2 * n];
        reduce(
            &mut self.a,
            n,
            &mut self.tau,
            &mut self.d,
            &mut self.e,
            &mut work,
        );
    }

    /// T's splits, and every eigenvalue of each block by implicit QL (module docs).
    fn eigenvalues(&mut self) -> Result<(), SymEigenError> {
        let n = self.n;
        for i in 0..n.saturating_sub(1) {
            if self.e[i].abs() <= f64::EPSILON * (self.d[i].abs() + self.d[i + 1].abs()) {
                self.e[i] = 0.0;
            }
        }
        let mut pairs = Vec::with_capacity(n);
        let mut dd = self.d.clone();
        let mut ee = vec![0.0; n];
        let mut b0 = 0;
        while b0 < n {
            let mut b1 = b0 + 1;
            while b1 < n && self.e[b1 - 1] != 0.0 {
                b1 += 1;
            }
            ee[b0..b1 - 1].copy_from_slice(&self.e[b0..b1 - 1]);
            ee[b1 - 1] = 0.0;
            if dd[b1 - 1].abs() < dd[b0].abs() {
                // QL converges at the top: the block's small end goes there (LAPACK's
                // `dsteqr` choice between QL and QR; graded blocks keep their small
                // eigenvalues' relative accuracy).
                dd[b0..b1].reverse();
                ee[b0..b1 - 1].reverse();
            }
            ql_values(&mut dd[b0..b1], &mut ee[b0..b1])?;
            pairs.extend(dd[b0..b1].iter().map(|&l| (l, (b0, b1))));
            b0 = b1;
        }
        pairs.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1 .0.cmp(&y.1 .0)));
        self.values = pairs.iter().map(|p| p.0).collect();
        self.block = pairs.iter().map(|p| p.1).collect();
        Ok(())
    }

    /// Inverse iteration for the values `cols` (indices into `values`, ascending) of the
    /// block [b0, b1): each vector into its column of `z` (module docs).
    #[allow(clippy::too_many_arguments)]
    fn block_vectors(
        &self,
        b0: usize,
        b1: usize,
        cols: &[usize],
        z: &mut DMatrix<f64>,
        tri: &mut TridiagonalLu,
        x: &mut [f64],
        rng: &mut u64,
    ) -> Result<(), SymEigenError> {
        let bn = b1 - b0;
        if bn == 1 {
            z[(b0, cols[0])] = 1.0;
            return Ok(());
        }
        let (d, e) = (&self.d[b0..b1], &self.e[b0..b1 - 1]);
        let mut norm = 0.0_f64;
        for i in 0..bn {
            let l = if i > 0 { e[i - 1].abs() } else { 0.0 };
            let r = if i + 1 < bn { e[i].abs() } else { 0.0 };
            norm = norm.max(d[i].abs() + l + r);
        }
        let group_gap = GROUP_GAP * norm;
        let grown = (0.1 / bn as f64).sqrt();
        let x = &mut x[..bn];
        let mut previous = f64::NEG_INFINITY;
        let mut group = 0;
        for (g, &c) in cols.iter().enumerate() {
            let mut mu = self.values[c];
            if g > 0 {
                let nudge = 10.0 * (f64::EPSILON * mu).abs();
                if mu - previous < nudge {
                    mu = previous + nudge;
                }
                if (mu - previous).abs() > group_gap {
                    group = g;
                }
            }
            for xi in x.iter_mut() {
                *rng ^= *rng << 13;
                *rng ^= *rng >> 7;
                *rng ^= *rng << 17;
                *xi = (*rng >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
            }
            tri.factor(d, e, mu, f64::EPSILON * norm);
            let mut checks = 0;
            let mut sweeps = 0;
            loop {
                sweeps += 1;
                if sweeps > MAX_SWEEPS + 2 {
                    return Err(SymEigenError::NoConvergence("inverse iteration"));
                }
                let big = x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                if !(big > 0.0 && big.is_finite()) {
                    return Err(SymEigenError::NoConvergence("inverse iteration"));
                }
                let scale = bn as f64 * norm * tri.last_pivot().abs().max(f64::EPSILON) / big;
                x.iter_mut().for_each(|v| *v *= scale);
                tri.solve(x);
                for &o in &cols[group..g] {
                    let zo = &z.as_slice()[o * self.n + b0..o * self.n + b1];
                    let s = dot(zo, x);
                    x.iter_mut().zip(zo).for_each(|(xi, zi)| *xi -= s * zi);
                }
                let big = x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                if big < grown {
                    continue;
                }
                checks += 1;
                if checks >= 3 {
                    break;
                }
            }
            let nrm = dot(x, x).sqrt();
            if !(nrm > 0.0 && nrm.is_finite()) {
                return Err(SymEigenError::NoConvergence("inverse iteration"));
            }
            let zc = &mut z.column_mut(c);
            for (i, xi) in x.iter().enumerate() {
                zc[b0 + i] = xi / nrm;
            }
            previous = mu;
        }
        Ok(())
    }

    /// Z ← Q Z (module docs): the reflectors applied last to first, [`BLOCK`] at a time
    /// as I − V T Vᵀ (the compact WY form, LAPACK's `dlarft`: T upper triangular with
    /// T_ii = τ_i and T[..i, i] = −τ_i T[..i, ..i] V[:, ..i]ᵀ v_i), so that the work is two
    /// matrix products per block.
    fn back_transform(&self, z: &mut DMatrix<f64>) {
        let n = self.n;
        let mut j1 = n.saturating_sub(2);
        while j1 > 0 {
            let j0 = j1.saturating_sub(BLOCK);
            let nb = j1 - j0;
            let r0 = j0 + 1;
            let m = n - r0;
            let mut v = DMatrix::<f64>::zeros(m, nb);
            for i in 0..nb {
                let j = j0 + i;
                v[(i, i)] = 1.0;
                v.column_mut(i).as_mut_slice()[i + 1..]
                    .copy_from_slice(&self.a[j * n + j + 2..(j + 1) * n]);
            }
            let gram = v.transpose() * &v;
            let mut t = DMatrix::<f64>::zeros(nb, nb);
            for i in 0..nb {
                let tau = self.tau[j0 + i];
                t[(i, i)] = tau;
                for r in (0..i).rev() {
                    // T[r, i] = −τ_i Σ_{c=r..i} T[r, c] G[c, i] (T upper triangular).
                    let s: f64 = (r..i).map(|c| t[(r, c)] * gram[(c, i)]).sum();
                    t[(r, i)] = -tau * s;
                }
            }
            let mut zs = z.rows_mut(r0, m);
            let w = t * (v.transpose() * &zs);
            zs.gemm(-1.0, &v, &w, 1.0);
            j1 = j0;
        }
    }
}

/// Reflectors per block of the back-transform ([`SymEigen::back_transform`]).
const BLOCK: usize = 32;

crate::simd::dispatch! {
    /// The reduction of the symmetric `a` (n × n, column-major, lower triangle) to the
    /// tridiagonal (d, e), the reflectors' τ into `tau` and their vectors below `a`'s
    /// subdiagonal (module docs); `work` holds 2n.
    fn reduce(
        a: &mut [f64],
        n: usize,
        tau: &mut [f64],
        d: &mut [f64],
        e: &mut [f64],
        work: &mut [f64],
    ) = reduce_body;
    features ["avx512f", "avx2"];
    tiers reduce_tier;
}

#[inline(always)]
fn reduce_body(
    a: &mut [f64],
    n: usize,
    tau: &mut [f64],
    d: &mut [f64],
    e: &mut [f64],
    work: &mut [f64],
) {
    let (p, v) = work.split_at_mut(n);
    for j in 0..n.saturating_sub(2) {
        let m = n - j - 1;
        let col = j * n + j + 1;
        let (beta, t) = householder(&mut a[col..col + m]);
        tau[j] = t;
        e[j] = beta;
        if t != 0.0 {
            v[..m].copy_from_slice(&a[col..col + m]);
            v[0] = 1.0;
            let (v, p) = (&v[..m], &mut p[..m]);
            let off = (j + 1) * n + j + 1;
            symv_lower(&a[off..], n, m, v, p);
            p.iter_mut().for_each(|x| *x *= t);
            let alpha = -0.5 * t * dot(p, v);
            p.iter_mut().zip(v).for_each(|(pi, vi)| *pi += alpha * vi);
            rank2_lower(&mut a[off..], n, m, v, p);
        }
        d[j] = a[j * n + j];
    }
    if n >= 2 {
        e[n - 2] = a[(n - 2) * n + n - 1];
        d[n - 2] = a[(n - 2) * n + n - 2];
    }
    if n >= 1 {
        d[n - 1] = a[(n - 1) * n + n - 1];
    }
}

/// Cholesky-QR of the columns `cols` of `z` on the rows [b0, b1) (module docs): nearly
/// orthonormal columns made orthonormal, each mixed with the others by their small overlaps.
fn orthonormalise(
    z: &mut DMatrix<f64>,
    b0: usize,
    b1: usize,
    cols: &[usize],
) -> Result<(), SymEigenError> {
    let k = cols.len();
    if k < 2 {
        return Ok(());
    }
    let block = DMatrix::from_fn(b1 - b0, k, |r, c| z[(b0 + r, cols[c])]);
    let mut l = block.transpose() * &block;
    // L Lᵀ = ZᵀZ (left-looking, by columns), then L⁻¹ in place of the identity below it;
    // Z R⁻¹ with R = Lᵀ is Z (L⁻¹)ᵀ.
    let ls = l.as_mut_slice();
    for j in 0..k {
        for c in 0..j {
            let ljc = ls[c * k + j];
            if ljc != 0.0 {
                let (left, right) = ls.split_at_mut(j * k);
                right[j..k]
                    .iter_mut()
                    .zip(&left[c * k + j..(c + 1) * k])
                    .for_each(|(x, y)| *x -= ljc * y);
            }
        }
        let pivot = ls[j * k + j];
        if !(pivot > 0.0 && pivot.is_finite()) {
            // Not numerically independent (inverse iteration gives near-orthonormal columns:
            // not met in the tests).
            return Err(SymEigenError::NoConvergence(
                "inverse iteration (dependent vectors)",
            ));
        }
        let scale = 1.0 / pivot.sqrt();
        ls[j * k + j..(j + 1) * k]
            .iter_mut()
            .for_each(|x| *x *= scale);
    }
    let mut inverse = DMatrix::<f64>::zeros(k, k);
    for c in 0..k {
        let x = &mut inverse.as_mut_slice()[c * k..(c + 1) * k];
        x[c] = 1.0;
        for j in c..k {
            let xj = x[j] / ls[j * k + j];
            x[j] = xj;
            if xj != 0.0 {
                x[j + 1..]
                    .iter_mut()
                    .zip(&ls[j * k + j + 1..(j + 1) * k])
                    .for_each(|(xi, lij)| *xi -= xj * lij);
            }
        }
    }
    let q = block * inverse.transpose();
    for (c, &col) in cols.iter().enumerate() {
        z.column_mut(col).as_mut_slice()[b0..b1].copy_from_slice(q.column(c).as_slice());
    }
    Ok(())
}

/// The reflector H = I − τ v vᵀ with H x = (β, 0, …): x is overwritten by v (v[0] = 1 left
/// implicit, x[0] ← β); returns (β, τ) (LAPACK's `dlarfg`).
#[inline(always)]
fn householder(x: &mut [f64]) -> (f64, f64) {
    let alpha = x[0];
    let tail = &mut x[1..];
    let big = tail.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if big == 0.0 {
        return (alpha, 0.0);
    }
    let scaled: f64 = tail.iter().map(|v| (v / big) * (v / big)).sum();
    let xnorm = big * scaled.sqrt();
    let beta = -alpha.signum() * alpha.hypot(xnorm);
    let tau = (beta - alpha) / beta;
    let scale = 1.0 / (alpha - beta);
    tail.iter_mut().for_each(|v| *v *= scale);
    x[0] = beta;
    (beta, tau)
}

/// p = A v for the symmetric m × m matrix whose lower triangle starts at `a[0]` with column
/// stride `ld` (one pass over the triangle).
#[inline(always)]
fn symv_lower(a: &[f64], ld: usize, m: usize, v: &[f64], p: &mut [f64]) {
    p.iter_mut().for_each(|x| *x = 0.0);
    for c in 0..m {
        let col = &a[c * ld + c..c * ld + m];
        let vc = v[c];
        let (pc, below) = p[c..].split_first_mut().expect("c < m");
        let vb = &v[c + 1..];
        let cb = &col[1..];
        // The column once as an axpy, once as a dot (it stays in L1 between them).
        below.iter_mut().zip(cb).for_each(|(pi, ci)| *pi += ci * vc);
        let s = dot(cb, vb);
        *pc += col[0] * vc + s;
    }
}

/// A ← A − v wᵀ − w vᵀ on the lower triangle (layout of [`symv_lower`]).
#[inline(always)]
fn rank2_lower(a: &mut [f64], ld: usize, m: usize, v: &[f64], w: &[f64]) {
    for c in 0..m {
        let col = &mut a[c * ld + c..c * ld + m];
        let (vc, wc) = (v[c], w[c]);
        for ((ai, vi), wi) in col.iter_mut().zip(&v[c..]).zip(&w[c..]) {
            *ai -= vi * wc + wi * vc;
        }
    }
}

/// Partial sums per lane in the kernels' reductions (one AVX-512 register of f64).
const LANES: usize = 8;

/// The lanes' sum, pairwise.
#[inline(always)]
fn lane_sum(acc: &[f64; LANES]) -> f64 {
    ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]))
}

/// xᵀy with [`LANES`] partial sums.
#[inline(always)]
fn dot(x: &[f64], y: &[f64]) -> f64 {
    let chunks = x.len() / LANES * LANES;
    let mut acc = [0.0; LANES];
    for (a, b) in x[..chunks]
        .chunks_exact(LANES)
        .zip(y[..chunks].chunks_exact(LANES))
    {
        for t in 0..LANES {
            acc[t] += a[t] * b[t];
        }
    }
    let mut s = lane_sum(&acc);
    for i in chunks..x.len() {
        s += x[i] * y[i];
    }
    s
}

/// Every eigenvalue of the unreduced tridiagonal (d, e) (e[i] = T[i+1, i], the last entry
/// unused) by implicit QL with Wilkinson's shift, no vectors; `d` ← the eigenvalues.
fn ql_values(d: &mut [f64], e: &mut [f64]) -> Result<(), SymEigenError> {
    let n = d.len();
    for l in 0..n {
        let mut iterations = 0;
        loop {
            let mut m = l;
            while m + 1 < n {
                if e[m].abs() <= f64::EPSILON * (d[m].abs() + d[m + 1].abs()) {
                    break;
                }
                m += 1;
            }
            if m == l {
                break;
            }
            iterations += 1;
            if iterations > MAX_QL_ITERATIONS {
                return Err(SymEigenError::NoConvergence("QL iteration"));
            }
            let mut g = (d[l + 1] - d[l]) / (2.0 * e[l]);
            let mut r = norm2(g, 1.0);
            g = d[m] - d[l] + e[l] / (g + r.copysign(g));
            let (mut s, mut c, mut p) = (1.0, 1.0, 0.0);
            let mut i = m;
            let mut underflow = false;
            while i > l {
                i -= 1;
                let f = s * e[i];
                let b = c * e[i];
                r = norm2(f, g);
                e[i + 1] = r;
                if r == 0.0 {
                    d[i + 1] -= p;
                    e[m] = 0.0;
                    underflow = true;
                    break;
                }
                s = f / r;
                c = g / r;
                g = d[i + 1] - p;
                r = (d[i] - g) * s + 2.0 * c * b;
                p = s * r;
                d[i + 1] = g + p;
                g = c * r - b;
            }
            if underflow {
                continue;
            }
            d[l] -= p;
            e[l] = g;
            e[m] = 0.0;
        }
    }
    Ok(())
}

/// √(a² + b²), without the library `hypot`'s cost where the squares cannot over- or
/// underflow (|a|, |b| within 2^±500), with it elsewhere.
fn norm2(a: f64, b: f64) -> f64 {
    let m = a.abs().max(b.abs());
    if m < 3.0e150 && m > 3.0e-150 {
        (a * a + b * b).sqrt()
    } else {
        a.hypot(b)
    }
}

/// T − μ I = P L U of a tridiagonal with partial pivoting (U with two superdiagonals), for
/// repeated solves; scratch reused across vectors.
#[derive(Debug, Clone)]
struct TridiagonalLu {
    /// The factored block's size.
    n: usize,
    u0: Vec<f64>,
    u1: Vec<f64>,
    u2: Vec<f64>,
    l: Vec<f64>,
    /// 1 where rows i and i + 1 were swapped, else 0 (a select by exact products: no branch).
    swap: Vec<f64>,
    /// The forward step as carry ← α carry + β x_{i+1}: (1, −l) swapped, (−l, 1) not (the
    /// products by ±1 exact: the same sums as the branches).
    alpha: Vec<f64>,
    beta: Vec<f64>,
    /// 1 / u0, u1 / u0 and u2 / u0 (the back substitution's scaled rows: one product and
    /// one difference on its chain per row).
    inv: Vec<f64>,
    c1: Vec<f64>,
    c2: Vec<f64>,
}

impl TridiagonalLu {
    fn new(n: usize) -> TridiagonalLu {
        TridiagonalLu {
            n: 0,
            u0: vec![0.0; n],
            u1: vec![0.0; n],
            u2: vec![0.0; n],
            l: vec![0.0; n],
            swap: vec![0.0; n],
            alpha: vec![0.0; n],
            beta: vec![0.0; n],
            inv: vec![0.0; n],
            c1: vec![0.0; n],
            c2: vec![0.0; n],
        }
    }

    /// Factor T − μ I of the block (d, e); pivots smaller than `tiny` are set to ±`tiny`.
    fn factor(&mut self, d: &[f64], e: &[f64], mu: f64, tiny: f64) {
        let n = d.len();
        self.n = n;
        let tiny = if tiny > 0.0 { tiny } else { f64::MIN_POSITIVE };
        // The current row i: (a at column i, c at i + 1; nothing further right).
        let mut a = d[0] - mu;
        let mut c = if n > 1 { e[0] } else { 0.0 };
        for i in 0..n - 1 {
            // The next row: (b at column i, dn at i + 1, en at i + 2). The pivot row is the
            // one of larger entry in column i, the other is eliminated by it.
            let b = e[i];
            let dn = d[i + 1] - mu;
            let en = if i + 2 < n { e[i + 1] } else { 0.0 };
            let swap = a.abs() < b.abs();
            let (pivot, other) = if swap {
                ([b, dn, en], [a, c, 0.0])
            } else {
                ([a, c, 0.0], [b, dn, en])
            };
            let p0 = if pivot[0].abs() < tiny {
                tiny.copysign(pivot[0])
            } else {
                pivot[0]
            };
            let l = other[0] / p0;
            self.u0[i] = p0;
            self.u1[i] = pivot[1];
            self.u2[i] = pivot[2];
            self.swap[i] = if swap { 1.0 } else { 0.0 };
            self.l[i] = l;
            a = other[1] - l * pivot[1];
            c = other[2] - l * pivot[2];
        }
        self.u0[n - 1] = a;
        self.u1[n - 1] = 0.0;
        self.u2[n - 1] = 0.0;
        self.swap[n - 1] = 0.0;
        self.l[n - 1] = 0.0;
        let last = &mut self.u0[n - 1];
        if last.abs() < tiny {
            *last = tiny.copysign(*last);
        }
        for i in 0..n {
            let inv = 1.0 / self.u0[i];
            self.inv[i] = inv;
            self.c1[i] = self.u1[i] * inv;
            self.c2[i] = self.u2[i] * inv;
            let s = self.swap[i];
            self.alpha[i] = s - (1.0 - s) * self.l[i];
            self.beta[i] = (1.0 - s) - s * self.l[i];
        }
    }

    /// The last pivot (its size measures how near μ is to an eigenvalue).
    fn last_pivot(&self) -> f64 {
        self.u0[self.n - 1]
    }

    /// x ← (T − μ I)⁻¹ x with the last factor.
    fn solve(&self, x: &mut [f64]) {
        let n = x.len();
        let mut carry = x[0];
        for i in 0..n - 1 {
            // (x_i, carry) = (carry, x_{i+1} − l carry), or swapped (x_{i+1}, carry − l x_{i+1}).
            let (s, b) = (self.swap[i], x[i + 1]);
            x[i] = s * b + (1.0 - s) * carry;
            carry = self.alpha[i] * carry + self.beta[i] * b;
        }
        x[n - 1] = carry * self.inv[n - 1];
        if n >= 2 {
            x[n - 2] = x[n - 2] * self.inv[n - 2] - self.c1[n - 2] * x[n - 1];
        }
        for i in (0..n.saturating_sub(2)).rev() {
            x[i] = (x[i] * self.inv[i] - self.c2[i] * x[i + 2]) - self.c1[i] * x[i + 1];
        }
    }
}

#[cfg(test)]
mod tests;
