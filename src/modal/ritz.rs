//! A cheap update of a mode basis across a small change of pose: subspace iteration
//! warm-started from the previous pose's shapes, with a Rayleigh–Ritz step on the new
//! pose's assembled K and M and a residual bound on every mode kept.
//!
//! **Maths.** With the q columns X of a start block (the previous pose's shapes and a few
//! guard modes above them), one sweep is Y = K⁻¹ M X, then the Ritz pairs of span(Y): the
//! q × q problem K_r v = μ M_r v with K_r = Yᵀ K Y = Yᵀ M X (K Y = M X) and M_r = Yᵀ M Y,
//! solved by the Cholesky factor of M_r and a dense symmetric eigen-solve; the Ritz vectors
//! φ = Y L⁻ᵀ v are M-orthonormal. Each sweep shrinks mode j's error outside the block by
//! λ_j/λ_{q+1}; the previous pose's shapes differ from the new ones by the pose's change,
//! so one or two sweeps suffice for the modes well below the guard.
//!
//! **Check.** Each kept Ritz pair (λ, φ) has the residual r = K φ − λ M φ, and
//! ρ = ‖r‖_{M⁻¹}/λ (with ‖r‖²_{M⁻¹} = rᵀ M⁻¹ r). (λ, φ) is an exact eigenpair of K − r (Mφ)ᵀ
//! (a perturbation of relative size ρ on the mode), an exact eigenvalue lies within ρ λ of
//! λ (so ω within ρ ω / 2), and φ's angle to the exact modes within a relative gap g of λ is
//! at most ρ / g (Davis–Kahan). The caller accepts the update only when every kept mode has
//! ρ ≤ [`RitzParams::max_residual`]; otherwise it falls back to the structured shapes.
//!
//! **Which sweeps are checked.** A check (the block products, the small eigen-solve, the
//! residuals) costs about as much as ten sweeps, so only some sweeps are checked: the first
//! at [`RitzParams::min_sweeps`], which a caller making a sequence of updates predicts from
//! the last one ([`RitzSchedule`]), and after a check that misses the bound the sweep where
//! the contraction a sweep makes (measured between two checks, else
//! [`RitzParams::rate`]) would meet it. A sweep that is not checked only M-normalises the
//! block's columns: the span after s sweeps is span((K⁻¹M)^s X) whether or not the Ritz
//! pairs are formed between sweeps. Each sweep tilts a column towards the lowest modes by
//! about λ_q/λ₁, so after [`MAX_UNCHECKED`] sweeps without a Rayleigh–Ritz step the block
//! is M-orthonormalised (Cholesky-QR, X = Y L⁻ᵀ with LLᵀ = M_r) to keep its columns apart.
//! L⁻¹ is formed once (q³/3; M_r's columns are M-normalised and, within a few sweeps of an
//! orthonormal block, far from parallel, so L is well conditioned), and C = L⁻¹ K_r L⁻ᵀ and
//! the Ritz vectors' coefficients L⁻ᵀ v by matrix products (where triangular solves with q
//! right-hand sides took twice the time).
//!
//! **Cost.** K and M of a chain model are block-tridiagonal per cable with an arrowhead on
//! the end-effector: ordered with the end-effector last their Cholesky factors have the
//! chains' band and `dim` rows whose envelope spans the chains but whose entries are zero
//! except next to each chain's attachment ([`Envelope`]; the solves skip the zeros), O(n) to
//! factor and to solve. With each cable's nodes in its own frame
//! ([`crate::modal::CableFrames`]) every direction is a scalar chain and a chain row of
//! the factor holds one entry beside the diagonal. The problem comes as the rows of K's
//! and M's nonzeros ([`Pencil`], from an assembly's additions without a dense matrix, or
//! from dense matrices). The blocks are held by rows in the factors' order between sweeps,
//! so that the solves and M's products run along a row's q values and the block products
//! take them as they lie. A sweep costs O(n q); a check O(n q² + q³).

use nalgebra::{DMatrix, Dyn, SymmetricEigen};

/// The most sweeps [`RitzParams::max_sweeps`] may ask for.
pub const MAX_SWEEPS: usize = 16;

/// The most sweeps made without a Rayleigh–Ritz step or an M-orthonormalisation between
/// them (module docs). Each sweep multiplies a column's component along mode i by 1/λ_i, so
/// a column starting near a high mode tilts towards the lowest ones by about λ_q/λ₁ a
/// sweep: measured on the paper robot's circle (K = 39, 26 guard modes), 8 sweeps without
/// either made the block's mass matrix lose its positive definiteness at 290 updates;
/// M-orthonormalised every 4, at none.
pub const MAX_UNCHECKED: usize = 4;

/// The most a column may tilt towards the lowest mode between two M-orthonormal blocks
/// (module docs): M_r's condition number then stays within its square, 10¹², whatever the
/// start block, well inside what its Cholesky factor resolves.
pub const MAX_TILT: f64 = 1e6;

/// The sweeps made without an M-orthonormalisation for a block whose λ spread
/// (λ_q/λ₁) is `spread`: the most whose tilt spread^s stays within [`MAX_TILT`], 1 ..=
/// [`MAX_UNCHECKED`].
fn unchecked_limit(spread: Option<f64>) -> usize {
    match spread {
        Some(s) if s > 1.0 && s.is_finite() => {
            ((MAX_TILT.ln() / s.ln()).floor() as usize).clamp(1, MAX_UNCHECKED)
        }
        _ => 1,
    }
}

/// Why an update was not made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RitzError {
    /// K or M (or the block's mass matrix) is not positive definite.
    #[error("{0} is not positive definite")]
    NotPositive(&'static str),
    /// The start block does not fit the matrices.
    #[error("a start block of {rows} rows for a model of {dof} DOF")]
    Size {
        /// The block's rows.
        rows: usize,
        /// The matrices' size.
        dof: usize,
    },
}

/// The subspace iteration's limits (finite bounds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RitzParams {
    /// Largest relative residual ρ of a kept mode (module docs).
    pub max_residual: f64,
    /// Most sweeps (1 ..= [`MAX_SWEEPS`]).
    pub max_sweeps: usize,
    /// The first sweep whose Ritz pairs are formed and checked (≤ `max_sweeps`; the first
    /// sweeps from a previous pose's shapes cannot meet a small bound). The sweeps before
    /// it only M-normalise the block's columns: the span after s sweeps is
    /// span((K⁻¹M)^s X) with or without a Rayleigh–Ritz step between them, so the small
    /// eigen-solve and the block products are made once, at the check.
    pub min_sweeps: usize,
    /// The contraction of ρ a sweep is expected to make until two checks measure it, in
    /// (0, 1): after a check that misses the bound the next check is made where this
    /// contraction would meet it (at most [`MAX_UNCHECKED`] + 1 sweeps on).
    pub rate: f64,
}

/// When the next update of a sequence first checks its Ritz pairs ([`RitzParams::min_sweeps`]),
/// learned from the last update: the state a caller carries from one update to the next.
///
/// A check costs about as much as ten sweeps (the block products and the small
/// eigen-solve against one envelope solve and one sparse product), so the sweep an update
/// meets the bound at is predicted rather than found by checking every sweep. After each
/// sweep a mode's error shrinks by about the same ratio r (λ_j/λ_{q+1}), so an update that
/// met the bound ρ_max with ρ at its check could have been checked
/// ⌊ln(ρ_max/ρ)/ln(1/r)⌋ sweeps earlier; the next update, a pose change of about the same
/// size away (an interval grows at most twofold from the last), is first checked there, one
/// sweep later ([`RitzSchedule::MARGIN`]) against a larger change, at the second sweep at the
/// earliest. r is the contraction measured between two consecutive checks (its last value;
/// [`RitzSchedule::DEFAULT_RATE`] until one is measured), within [0.02, 0.95].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RitzSchedule {
    first_check: usize,
    rate: f64,
}

impl Default for RitzSchedule {
    fn default() -> Self {
        RitzSchedule {
            first_check: Self::FIRST_CHECK,
            rate: Self::DEFAULT_RATE,
        }
    }
}

impl RitzSchedule {
    /// The first update's first check.
    pub const FIRST_CHECK: usize = 5;
    /// The contraction a sweep is assumed to make until one is measured.
    pub const DEFAULT_RATE: f64 = 0.5;
    /// Sweeps added to the prediction (module docs of the type).
    pub const MARGIN: usize = 1;

    /// The sweep the next update is first checked at.
    pub fn first_check(&self) -> usize {
        self.first_check
    }

    /// The contraction of ρ a sweep is expected to make.
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// Learn from an update made with bound `max_residual`.
    pub fn learn(&mut self, ritz: &Ritz, max_residual: f64) {
        if let Some(r) = ritz.rate.filter(|r| r.is_finite()) {
            self.rate = r.clamp(0.02, 0.95);
        }
        let rho = ritz.max_residual();
        let spare = if rho > 0.0 && rho <= max_residual {
            ((max_residual / rho).ln() / (1.0 / self.rate).ln()).floor() as usize
        } else {
            0
        };
        self.first_check = (ritz.sweeps.saturating_sub(spare) + Self::MARGIN).clamp(2, MAX_SWEEPS);
    }
}

/// The lower triangular Cholesky factor of a symmetric positive definite matrix in a given
/// order, stored by rows from each row's first nonzero (its envelope): no fill outside it.
#[derive(Debug, Clone)]
pub struct Envelope {
    order: Vec<usize>,
    first: Vec<usize>,
    start: Vec<usize>,
    data: Vec<f64>,
}

impl Envelope {
    /// The factor of `a` (symmetric) with its rows and columns taken in `order` (a
    /// permutation of 0..n); None when `a` is not positive definite.
    pub fn factor(a: &DMatrix<f64>, order: &[usize]) -> Option<Envelope> {
        Self::from_rows(&Sparse::from_dense(a, order), order)
    }

    /// The factor of the symmetric matrix whose rows (in the order `order`, columns
    /// ascending) `a` holds; None when it is not positive definite. Each row's entries left
    /// of the diagonal are scattered into its envelope and factored there.
    fn from_rows(a: &Sparse, order: &[usize]) -> Option<Envelope> {
        let n = order.len();
        let mut first = vec![0usize; n];
        let mut start = vec![0usize; n + 1];
        for i in 0..n {
            let row = &a.cols[a.start[i]..a.start[i + 1]];
            first[i] = row.first().map_or(i, |&j| j.min(i));
            start[i + 1] = start[i] + (i + 1 - first[i]);
        }
        let mut data = vec![0.0; start[n]];
        for i in 0..n {
            for e in a.start[i]..a.start[i + 1] {
                let j = a.cols[e];
                if j > i {
                    break;
                }
                data[start[i] + j - first[i]] = a.vals[e];
            }
        }
        for i in 0..n {
            for j in first[i]..=i {
                let lo = first[i].max(first[j]);
                let mut s = data[start[i] + j - first[i]];
                for k in lo..j {
                    s -= data[start[i] + k - first[i]] * data[start[j] + k - first[j]];
                }
                if j == i {
                    if !(s > 0.0) {
                        return None;
                    }
                    data[start[i] + i - first[i]] = s.sqrt();
                } else {
                    data[start[i] + j - first[i]] = s / data[start[j] + j - first[j]];
                }
            }
        }
        Some(Envelope {
            order: order.to_vec(),
            first,
            start,
            data,
        })
    }

    /// Row `i` of the factor (in the factor's order): the column of its first stored entry
    /// and the entries from there to the diagonal (the diagonal last).
    pub fn row(&self, i: usize) -> (usize, &[f64]) {
        (self.first[i], &self.data[self.start[i]..self.start[i + 1]])
    }

    /// Solve A x = b in place (`b` in the original order), `work` of the same length.
    pub fn solve(&self, b: &mut [f64], work: &mut [f64]) {
        let n = self.order.len();
        for (w, &o) in work.iter_mut().zip(&self.order) {
            *w = b[o];
        }
        for i in 0..n {
            let row = &self.data[self.start[i]..self.start[i + 1]];
            let (off, diag) = row.split_at(row.len() - 1);
            let s: f64 = off
                .iter()
                .zip(&work[self.first[i]..i])
                .map(|(l, w)| l * w)
                .sum();
            work[i] = (work[i] - s) / diag[0];
        }
        for i in (0..n).rev() {
            let row = &self.data[self.start[i]..self.start[i + 1]];
            let (off, diag) = row.split_at(row.len() - 1);
            let wi = work[i] / diag[0];
            work[i] = wi;
            for (w, l) in work[self.first[i]..i].iter_mut().zip(off) {
                *w -= l * wi;
            }
        }
        for (w, &o) in work.iter().zip(&self.order) {
            b[o] = *w;
        }
    }

    /// Solve A X = B in place for `q` right-hand sides held by rows in the factor's order
    /// (`x[i·q + c]` is row i of column c, `x` n·q long): each row of the factor is applied
    /// to the q values of a row together.
    pub fn solve_rows(&self, x: &mut [f64], q: usize) {
        let n = self.order.len();
        debug_assert_eq!(x.len(), n * q);
        for i in 0..n {
            let row = &self.data[self.start[i]..self.start[i + 1]];
            let (off, diag) = row.split_at(row.len() - 1);
            let (done, rest) = x.split_at_mut(i * q);
            let wi = &mut rest[..q];
            // An end-effector row's envelope is mostly exact zeros (a chain fills it only
            // from its node next to the attachment): skipped.
            for (k, l) in off.iter().enumerate().filter(|(_, l)| **l != 0.0) {
                let wk = &done[(self.first[i] + k) * q..(self.first[i] + k + 1) * q];
                for (x, y) in wi.iter_mut().zip(wk) {
                    *x -= l * y;
                }
            }
            let d = 1.0 / diag[0];
            wi.iter_mut().for_each(|x| *x *= d);
        }
        for i in (0..n).rev() {
            let row = &self.data[self.start[i]..self.start[i + 1]];
            let (off, diag) = row.split_at(row.len() - 1);
            let (before, rest) = x.split_at_mut(i * q);
            let wi = &mut rest[..q];
            let d = 1.0 / diag[0];
            wi.iter_mut().for_each(|x| *x *= d);
            for (k, l) in off.iter().enumerate().filter(|(_, l)| **l != 0.0) {
                let at = (self.first[i] + k) * q;
                for (x, y) in before[at..at + q].iter_mut().zip(wi.iter()) {
                    *x -= l * y;
                }
            }
        }
    }
}

/// A symmetric matrix's nonzeros by rows, in a given order of its rows and columns, for
/// products with blocks held by rows.
#[derive(Debug, Clone)]
struct Sparse {
    start: Vec<usize>,
    cols: Vec<usize>,
    vals: Vec<f64>,
}

impl Sparse {
    /// `a`'s nonzeros with its rows and columns taken in `order` (every entry read).
    fn from_dense(a: &DMatrix<f64>, order: &[usize]) -> Sparse {
        let mut s = Sparse {
            start: vec![0],
            cols: Vec::new(),
            vals: Vec::new(),
        };
        for &r in order {
            // Row r of the symmetric `a` is its column r, read as it is stored.
            let col = a.column(r);
            for (j, &c) in order.iter().enumerate() {
                let v = col[c];
                if v != 0.0 {
                    s.cols.push(j);
                    s.vals.push(v);
                }
            }
            s.start.push(s.cols.len());
        }
        s
    }

    /// The sums of an assembly's additions `list` on `n` rows and columns, K's and M's, in
    /// the order whose position of index i is `pos[i]`: bucketed by row, sorted by column
    /// within a row and summed, the zero sums left out. O(additions).
    fn pair_from_entries(
        n: usize,
        pos: &[usize],
        list: &[crate::modal::Entry],
    ) -> (Sparse, Sparse) {
        let mut start = vec![0usize; n + 1];
        for e in list {
            start[pos[e.row] + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut next = start[..n].to_vec();
        let mut adds = vec![(0usize, 0.0f64, 0.0f64); list.len()];
        for e in list {
            let r = pos[e.row];
            adds[next[r]] = (pos[e.col], e.k, e.m);
            next[r] += 1;
        }
        let empty = || Sparse {
            start: Vec::with_capacity(n + 1),
            cols: Vec::with_capacity(list.len()),
            vals: Vec::with_capacity(list.len()),
        };
        let (mut k, mut m) = (empty(), empty());
        k.start.push(0);
        m.start.push(0);
        for i in 0..n {
            let row = &mut adds[start[i]..start[i + 1]];
            row.sort_unstable_by_key(|&(c, _, _)| c);
            let mut at = 0;
            while at < row.len() {
                let c = row[at].0;
                let (mut vk, mut vm) = (0.0, 0.0);
                while at < row.len() && row[at].0 == c {
                    vk += row[at].1;
                    vm += row[at].2;
                    at += 1;
                }
                for (s, v) in [(&mut k, vk), (&mut m, vm)] {
                    if v != 0.0 {
                        s.cols.push(c);
                        s.vals.push(v);
                    }
                }
            }
            k.start.push(k.cols.len());
            m.start.push(m.cols.len());
        }
        (k, m)
    }

    /// A X into `y` for `q` columns held by rows (as [`Envelope::solve_rows`]).
    fn mul_rows(&self, x: &[f64], y: &mut [f64], q: usize) {
        for (r, yr) in y.chunks_exact_mut(q).enumerate() {
            let (lo, hi) = (self.start[r], self.start[r + 1]);
            if lo == hi {
                yr.fill(0.0);
                continue;
            }
            // The first entry sets the row, the rest add to it.
            let (v, at) = (self.vals[lo], self.cols[lo] * q);
            for (a, b) in yr.iter_mut().zip(&x[at..at + q]) {
                *a = v * b;
            }
            for i in lo + 1..hi {
                let v = self.vals[i];
                let at = self.cols[i] * q;
                for (a, b) in yr.iter_mut().zip(&x[at..at + q]) {
                    *a += v * b;
                }
            }
        }
    }
}

/// The transpose (q × n) of an n × q block held by rows (`data[i·q + c]`): the same
/// numbers by columns. (The blocks are only ever viewed this way, contiguously: nalgebra's
/// products on views with a row stride other than 1 wrote out of bounds at small sizes.)
fn by_rows_transposed(data: &[f64], n: usize, q: usize) -> nalgebra::DMatrixView<'_, f64> {
    nalgebra::DMatrixView::from_slice(data, q, n)
}

/// Bᵀ C for two n × q blocks held by rows (q × q): (Bᵀ)·(Cᵀ)ᵀ, Cᵀ copied by columns.
fn gram_by_rows(b: &[f64], c: &[f64], n: usize, q: usize) -> DMatrix<f64> {
    by_rows_transposed(b, n, q) * by_rows_transposed(c, n, q).transpose()
}

/// `y` (n × `w.ncols()`, held by rows) ← A W, A n × q held by rows: yᵀ = Wᵀ Aᵀ, every
/// operand by columns.
fn product_by_rows<S: nalgebra::Storage<f64, Dyn, Dyn>>(
    a: &[f64],
    n: usize,
    q: usize,
    w: &nalgebra::Matrix<f64, Dyn, Dyn, S>,
    y: &mut Vec<f64>,
) {
    let cols = w.ncols();
    // Every entry is written (β = 0: `y` is not read), so a buffer of the right size is
    // taken as it is.
    y.resize(n * cols, 0.0);
    let mut out = nalgebra::DMatrixViewMut::from_slice(y, cols, n);
    out.gemm(1.0, &w.transpose(), &by_rows_transposed(a, n, q), 0.0);
}

/// `a` ← (a + aᵀ)/2, in place (square).
fn symmetrise(a: &mut DMatrix<f64>) {
    let n = a.nrows();
    for j in 0..n {
        for i in j + 1..n {
            let m = 0.5 * (a[(i, j)] + a[(j, i)]);
            a[(i, j)] = m;
            a[(j, i)] = m;
        }
    }
}

/// L⁻¹ of the lower triangle of `l` (its strict upper triangle is not read), column by
/// column: L x = e_j by forward substitution along L's columns; None when a diagonal entry
/// is not positive.
fn lower_inverse(l: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let q = l.nrows();
    let mut x = DMatrix::zeros(q, q);
    let ls = l.as_slice();
    for (j, col) in x.as_mut_slice().chunks_exact_mut(q.max(1)).enumerate() {
        col[j] = 1.0;
        for k in j..q {
            let d = l[(k, k)];
            if !(d > 0.0) {
                return None;
            }
            let xk = col[k] / d;
            col[k] = xk;
            if xk != 0.0 {
                let lk = &ls[k * q + k + 1..(k + 1) * q];
                for (xi, li) in col[k + 1..].iter_mut().zip(lk) {
                    *xi -= li * xk;
                }
            }
        }
    }
    Some(x)
}

/// The Ritz pairs of the last sweep.
#[derive(Debug, Clone)]
pub struct Ritz {
    /// λ of each Ritz pair, ascending, rad²/s².
    pub lambda: Vec<f64>,
    /// The M-orthonormal Ritz vectors (columns, the assembly's DOF order).
    pub vectors: DMatrix<f64>,
    /// ρ of the first `checked` pairs (module docs).
    pub residual: Vec<f64>,
    /// Sweeps made.
    pub sweeps: usize,
    /// The contraction of ρ a sweep measured between the last two checks,
    /// (ρ_last/ρ_before)^(1/sweeps between them), where two were made.
    pub rate: Option<f64>,
}

impl Ritz {
    /// The largest ρ of the checked pairs.
    pub fn max_residual(&self) -> f64 {
        self.residual.iter().fold(0.0, |m, &r| m.max(r))
    }
}

/// K and M (n × n, symmetric) of a model with `dim` end-effector DOFs first, as the rows of
/// their nonzeros in the factors' order (the end-effector last): what
/// [`subspace_iteration`] works on.
#[derive(Debug, Clone)]
pub struct Pencil {
    order: Vec<usize>,
    k: Sparse,
    m: Sparse,
}

impl Pencil {
    /// The factors' order of a model of `n` DOF with `dim` end-effector DOFs first.
    fn order(n: usize, dim: usize) -> Vec<usize> {
        (dim.min(n)..n).chain(0..dim.min(n)).collect()
    }

    /// From dense K (N/m) and M (kg) of the same size (every entry read: O(n²)).
    pub fn from_dense(k: &DMatrix<f64>, m: &DMatrix<f64>, dim: usize) -> Result<Pencil, RitzError> {
        let n = k.nrows();
        if k.ncols() != n || m.nrows() != n || m.ncols() != n {
            return Err(RitzError::Size {
                rows: m.nrows(),
                dof: n,
            });
        }
        let order = Self::order(n, dim);
        Ok(Pencil {
            k: Sparse::from_dense(k, &order),
            m: Sparse::from_dense(m, &order),
            order,
        })
    }

    /// From an assembly's additions ([`crate::modal::Entries`]): O(additions), no dense
    /// matrix.
    pub fn from_entries(entries: &crate::modal::Entries, dim: usize) -> Result<Pencil, RitzError> {
        let n = entries.dof;
        if let Some(e) = entries.list.iter().find(|e| e.row >= n || e.col >= n) {
            return Err(RitzError::Size {
                rows: e.row.max(e.col) + 1,
                dof: n,
            });
        }
        let order = Self::order(n, dim);
        let mut pos = vec![0usize; n];
        for (i, &o) in order.iter().enumerate() {
            pos[o] = i;
        }
        let (k, m) = Sparse::pair_from_entries(n, &pos, &entries.list);
        Ok(Pencil { order, k, m })
    }

    /// The model's DOF.
    pub fn dof(&self) -> usize {
        self.order.len()
    }
}

/// The subspace iteration of the module docs on `pencil`'s K and M (positive definite)
/// from the start block `x` (n × q, the assembly's DOF order): sweeps until the first
/// `checked` Ritz pairs have ρ ≤ `params.max_residual` or `params.max_sweeps` are made.
/// The blocks are held by rows in the factors' order between the sweeps, so that the
/// envelope solves and the sparse products run along a row's q values and the block
/// products take them as they lie.
pub fn subspace_iteration(
    pencil: &Pencil,
    x: DMatrix<f64>,
    checked: usize,
    params: &RitzParams,
) -> Result<Ritz, RitzError> {
    let n = pencil.dof();
    if x.nrows() != n {
        return Err(RitzError::Size {
            rows: x.nrows(),
            dof: n,
        });
    }
    let order = &pencil.order;
    let kf = Envelope::from_rows(&pencil.k, order).ok_or(RitzError::NotPositive("K"))?;
    let mf = Envelope::from_rows(&pencil.m, order).ok_or(RitzError::NotPositive("M"))?;
    let ms = &pencil.m;
    let q = x.ncols();
    let checked = checked.min(q);
    let mut out = Ritz {
        lambda: Vec::new(),
        vectors: DMatrix::zeros(n, q),
        residual: Vec::new(),
        sweeps: 0,
        rate: None,
    };
    let mut last_checked: Option<(usize, f64)> = None;
    // X by rows in the factors' order, and M X.
    let mut y = vec![0.0; n * q];
    for (i, &o) in order.iter().enumerate() {
        for (c, v) in y[i * q..(i + 1) * q].iter_mut().enumerate() {
            *v = x[(o, c)];
        }
    }
    let mut mx = vec![0.0; n * q];
    ms.mul_rows(&y, &mut mx, q);
    let mut my = vec![0.0; n * q];
    let mut norms = vec![0.0; q];
    let (mut kphi, mut mphi, mut r) = (Vec::new(), Vec::new(), Vec::new());
    let sweeps = params.max_sweeps.clamp(1, MAX_SWEEPS);
    let mut next_check = params.min_sweeps.clamp(1, sweeps);
    // The last sweep whose block was M-orthonormalised (by a check or a Cholesky-QR).
    let mut since_rr = 0;
    // λ_q/λ₁ of the block (Ritz values, or before the first check the columns' Rayleigh
    // quotients): how fast an unchecked sweep tilts the columns together.
    let mut spread: Option<f64> = None;
    for sweep in 1..=sweeps {
        // Y = K⁻¹ M X, and M Y.
        y.copy_from_slice(&mx);
        kf.solve_rows(&mut y, q);
        ms.mul_rows(&y, &mut my, q);
        out.sweeps = sweep;
        if sweep < next_check && sweep < sweeps {
            // Before the first check only the span matters: span((K⁻¹M)^s X) is the same
            // with or without a Rayleigh–Ritz step between the sweeps, so the columns are
            // only M-normalised (the start block is near the modes: they stay far from
            // parallel over the few sweeps before a check). Y itself is not kept: the next
            // sweep starts from M Y.
            norms.fill(0.0);
            for (yr, mr) in y.chunks_exact(q).zip(my.chunks_exact(q)) {
                for ((s, a), b) in norms.iter_mut().zip(yr).zip(mr) {
                    *s += a * b;
                }
            }
            if spread.is_none() {
                // The columns' Rayleigh quotients yᵀKy / yᵀMy (K Y = M X): the block's
                // spread of λ before any Ritz value is known.
                // Summed along the rows as they lie (a column's values are q apart).
                let mut yky = vec![0.0; q];
                for (yr, xr) in y.chunks_exact(q).zip(mx.chunks_exact(q)) {
                    for ((s, a), b) in yky.iter_mut().zip(yr).zip(xr) {
                        *s += a * b;
                    }
                }
                let mut lo = f64::INFINITY;
                let mut hi = 0.0f64;
                for (&k, &ymy) in yky.iter().zip(&norms) {
                    let rq = k / ymy;
                    lo = lo.min(rq);
                    hi = hi.max(rq);
                }
                spread = Some(hi / lo);
            }
            for s in norms.iter_mut() {
                if !(*s > 0.0 && s.is_finite()) {
                    return Err(RitzError::NotPositive("the block's M"));
                }
                *s = 1.0 / s.sqrt();
            }
            if sweep - since_rr < unchecked_limit(spread) {
                for mr in my.chunks_exact_mut(q) {
                    for (a, s) in mr.iter_mut().zip(&norms) {
                        *a *= s;
                    }
                }
                std::mem::swap(&mut mx, &mut my);
            } else {
                // M-orthonormalise the block (Cholesky-QR, X = Y L⁻ᵀ with L Lᵀ = Yᵀ M Y):
                // the columns are kept apart at a third of a check's cost.
                let mut mr = gram_by_rows(&y, &my, n, q);
                symmetrise(&mut mr);
                let linv = mr
                    .cholesky()
                    .and_then(|c| lower_inverse(c.l_dirty()))
                    .ok_or(RitzError::NotPositive("the block's M"))?;
                product_by_rows(&my, n, q, &linv.transpose(), &mut mx);
                since_rr = sweep;
            }
            continue;
        }
        // K_r = Yᵀ K Y = Yᵀ M X, M_r = Yᵀ M Y (symmetric up to rounding), blocked matrix
        // products (Yᵀ by columns is Y by rows).
        let mut kr = gram_by_rows(&y, &mx, n, q);
        let mut mr = gram_by_rows(&y, &my, n, q);
        symmetrise(&mut kr);
        symmetrise(&mut mr);
        let chol = mr
            .cholesky()
            .ok_or(RitzError::NotPositive("the block's M"))?;
        // C = L⁻¹ K_r L⁻ᵀ with L⁻¹ formed once (q³/3) and applied by matrix products.
        let linv = lower_inverse(chol.l_dirty()).ok_or(RitzError::NotPositive("the block's M"))?;
        let t = &linv * &kr;
        // L⁻¹ (L⁻¹ K_r)ᵀ = L⁻¹ K_r L⁻ᵀ, K_r symmetric.
        let mut c = &linv * t.transpose();
        symmetrise(&mut c);
        let eig = SymmetricEigen::new(c);
        let mut idx: Vec<usize> = (0..q).collect();
        idx.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let v = DMatrix::from_fn(q, q, |r, c| eig.eigenvectors[(r, idx[c])]);
        // W = L⁻ᵀ V.
        let w = linv.transpose() * &v;
        out.lambda = idx.iter().map(|&i| eig.eigenvalues[i]).collect();
        if let (Some(&lo), Some(&hi)) = (out.lambda.first(), out.lambda.last()) {
            spread = Some(hi / lo);
        }
        // The checked pairs' residuals: M Φ = M Y W; K Φ = K Y W = M X W.
        let wc = w.columns(0, checked);
        product_by_rows(&mx, n, q, &wc, &mut kphi);
        product_by_rows(&my, n, q, &wc, &mut mphi);
        for (kr, mr) in kphi
            .chunks_exact_mut(checked)
            .zip(mphi.chunks_exact(checked))
        {
            for ((a, b), lam) in kr.iter_mut().zip(mr).zip(&out.lambda) {
                *a -= lam * b;
            }
        }
        r.clone_from(&kphi);
        mf.solve_rows(&mut r, checked);
        norms[..checked].fill(0.0);
        for (r0, ri) in kphi.chunks_exact(checked).zip(r.chunks_exact(checked)) {
            for ((s, a), b) in norms.iter_mut().zip(r0).zip(ri) {
                *s += a * b;
            }
        }
        out.residual.clear();
        out.residual
            .extend(norms[..checked].iter().zip(&out.lambda).map(|(&s, &lam)| {
                if lam > 0.0 {
                    s.max(0.0).sqrt() / lam
                } else {
                    f64::INFINITY
                }
            }));
        let rho = out.max_residual();
        out.rate = last_checked
            .filter(|&(_, r)| r > 0.0 && rho > 0.0)
            .map(|(s, r)| (rho / r).powf(1.0 / (sweep - s) as f64));
        last_checked = Some((sweep, rho));
        if rho <= params.max_residual || sweep == sweeps {
            // Φ = Y W, back in the assembly's order.
            product_by_rows(&y, n, q, &w, &mut kphi);
            for (i, &o) in order.iter().enumerate() {
                for (c, v) in kphi[i * q..(i + 1) * q].iter().enumerate() {
                    out.vectors[(o, c)] = *v;
                }
            }
            break;
        }
        // The next check where the contraction (measured, else the caller's) meets the
        // bound, at most MAX_UNCHECKED sweeps on.
        let rate = out.rate.unwrap_or(params.rate).clamp(0.02, 0.95);
        let jump = ((rho / params.max_residual).ln() / (1.0 / rate).ln()).ceil();
        next_check = sweep + (jump as usize).max(1);
        // The next sweep's M X = M Y W.
        product_by_rows(&my, n, q, &w, &mut mx);
        since_rr = sweep;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envelope_solves_an_arrowhead() {
        // A chain of 5 DOF coupled to one last "end-effector" DOF placed first.
        let n = 6;
        let mut a = DMatrix::<f64>::zeros(n, n);
        for i in 1..n {
            a[(i, i)] = 4.0;
            if i + 1 < n {
                a[(i, i + 1)] = -1.0;
                a[(i + 1, i)] = -1.0;
            }
        }
        a[(0, 0)] = 3.0;
        a[(0, n - 1)] = -1.0;
        a[(n - 1, 0)] = -1.0;
        let order: Vec<usize> = (1..n).chain(0..1).collect();
        let f = Envelope::factor(&a, &order).expect("SPD");
        let b: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let mut x = b.clone();
        let mut w = vec![0.0; n];
        f.solve(&mut x, &mut w);
        let r = &a * nalgebra::DVector::from_column_slice(&x)
            - nalgebra::DVector::from_column_slice(&b);
        assert!(r.norm() < 1e-12, "{r}");
        // Two right-hand sides at once, held by rows in the factor's order: the same.
        let mut bb: Vec<f64> = order.iter().flat_map(|&o| [b[o], 2.0 * b[o]]).collect();
        f.solve_rows(&mut bb, 2);
        for (i, &o) in order.iter().enumerate() {
            assert!((bb[2 * i] - x[o]).abs() < 1e-14 && (bb[2 * i + 1] - 2.0 * x[o]).abs() < 1e-13);
        }
        // Not positive definite: refused.
        let neg = -a;
        assert!(Envelope::factor(&neg, &order).is_none());
    }

    /// The sparse rows (from the dense matrix, and from an assembly's additions split,
    /// scrambled and with zeros) and the envelope factored from them, on a matrix of 23 DOF
    /// with bands and an arrowhead, in three orders (the end-effector last; reversed;
    /// interleaved): the factor solves A x = b (residual against the dense product), the
    /// sparse product equals the dense one, and both constructions give the same rows.
    #[test]
    fn envelope_and_sparse_rows_in_any_order_match_the_dense_matrix() {
        let n = 23;
        let mut a = DMatrix::<f64>::zeros(n, n);
        for i in 0..n {
            a[(i, i)] = 6.0 + i as f64 * 0.1;
            for (d, v) in [(1, -1.0), (3, -0.5)] {
                if i + d < n && i >= 2 {
                    a[(i, i + d)] = v;
                    a[(i + d, i)] = v;
                }
            }
        }
        for i in 2..n {
            if i % 7 == 0 || i == n - 1 {
                a[(0, i)] = -0.7;
                a[(i, 0)] = -0.7;
                a[(1, i)] = 0.4;
                a[(i, 1)] = 0.4;
            }
        }
        let orders: [Vec<usize>; 3] = [
            (2..n).chain(0..2).collect(),
            (0..n).rev().collect(),
            (0..n).step_by(2).chain((1..n).step_by(2)).collect(),
        ];
        for order in &orders {
            let f = Envelope::factor(&a, order).expect("SPD");
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
            let (mut x, mut w) = (b.clone(), vec![0.0; n]);
            f.solve(&mut x, &mut w);
            let r = &a * nalgebra::DVector::from_column_slice(&x)
                - nalgebra::DVector::from_column_slice(&b);
            assert!(r.amax() < 1e-13, "{order:?}: residual {}", r.amax());
            let s = Sparse::from_dense(&a, order);
            // The same rows from an assembly's additions: each entry split in two parts
            // added in a scrambled order, zeros added too, M = 2 A alongside.
            let mut list = Vec::new();
            for idx in (0..n * n).map(|t| (t * 7 + 3) % (n * n)) {
                let (r, c) = (idx % n, idx / n);
                let v = a[(r, c)];
                for part in [0.25 * v, 0.75 * v] {
                    list.push(crate::modal::Entry {
                        row: r,
                        col: c,
                        k: part,
                        m: 2.0 * part,
                    });
                }
            }
            let mut pos = vec![0; n];
            for (i, &o) in order.iter().enumerate() {
                pos[o] = i;
            }
            let (sk, sm) = Sparse::pair_from_entries(n, &pos, &list);
            assert_eq!((&sk.start, &sk.cols), (&s.start, &s.cols), "{order:?}");
            assert_eq!((&sm.start, &sm.cols), (&s.start, &s.cols), "{order:?}");
            for ((vk, vm), v) in sk.vals.iter().zip(&sm.vals).zip(&s.vals) {
                assert!(
                    (vk - v).abs() <= 1e-15 * v.abs() && (vm - 2.0 * v).abs() <= 2e-15 * v.abs()
                );
            }
            let q = 3;
            let xs: Vec<f64> = (0..n * q).map(|i| (i as f64 * 0.61).cos()).collect();
            let mut y = vec![0.0; n * q];
            s.mul_rows(&xs, &mut y, q);
            for (i, &oi) in order.iter().enumerate() {
                for c in 0..q {
                    let want: f64 = order
                        .iter()
                        .enumerate()
                        .map(|(j, &oj)| a[(oi, oj)] * xs[j * q + c])
                        .sum();
                    assert!((y[i * q + c] - want).abs() < 1e-13, "{order:?}: row {i}");
                }
            }
        }
    }

    /// A fixed-fixed string of `n` interior nodes (a chain's band) with one "end-effector"
    /// DOF placed first and coupled to the last node: K (N/m) and its consistent M (kg).
    fn string_with_mass(n: usize) -> (DMatrix<f64>, DMatrix<f64>) {
        let dof = n + 1;
        let (mut k, mut m) = (DMatrix::zeros(dof, dof), DMatrix::zeros(dof, dof));
        // Nodes: 0 = anchor (fixed), 1..=n interior (DOF 1..=n), n + 1 = the end-effector.
        let at = |j: usize| match j {
            0 => None,
            j if j == n + 1 => Some(0),
            j => Some(j),
        };
        for el in 0..=n {
            let stiff = 1.0e3 * (1.0 + 0.1 * (el % 3) as f64);
            let mass = 0.05 * (1.0 + 0.05 * (el % 4) as f64);
            for (a, b, sk, sm) in [
                (el, el, stiff, mass / 3.0),
                (el + 1, el + 1, stiff, mass / 3.0),
                (el, el + 1, -stiff, mass / 6.0),
                (el + 1, el, -stiff, mass / 6.0),
            ] {
                if let (Some(r), Some(c)) = (at(a), at(b)) {
                    k[(r, c)] += sk;
                    m[(r, c)] += sm;
                }
            }
        }
        m[(0, 0)] += 2.0;
        (k, m)
    }

    /// The generalized eigenpairs of (K, M) by a dense solve (M = LLᵀ, L⁻¹KL⁻ᵀ's symmetric
    /// eigen-solve): the reference, no subspace iteration.
    fn dense_pairs(k: &DMatrix<f64>, m: &DMatrix<f64>) -> (Vec<f64>, DMatrix<f64>) {
        let l = m.clone().cholesky().expect("M SPD").l();
        let li = l.clone().try_inverse().expect("L invertible");
        let c = &li * k * li.transpose();
        let e = SymmetricEigen::new(0.5 * (&c + c.transpose()));
        let mut idx: Vec<usize> = (0..e.eigenvalues.len()).collect();
        idx.sort_by(|&a, &b| e.eigenvalues[a].total_cmp(&e.eigenvalues[b]));
        let lam = idx.iter().map(|&i| e.eigenvalues[i]).collect();
        let v = DMatrix::from_fn(c.nrows(), idx.len(), |r, j| e.eigenvectors[(r, idx[j])]);
        (lam, li.transpose() * v)
    }

    /// Checked first at the 12th sweep (eleven sweeps with no Rayleigh–Ritz step), from the
    /// modes of a stiffer string: the block is M-orthonormalised every [`MAX_UNCHECKED`]
    /// sweeps, so its columns stay apart and the Ritz values meet the dense reference within
    /// their own residual bound (Weinstein: |λ − λ_exact| ≤ ρλ). Without the
    /// orthonormalisation the block's mass matrix lost its positive definiteness here
    /// (λ_q/λ₁ ≈ 300 a sweep).
    #[test]
    fn a_late_first_check_keeps_the_block_apart_and_meets_the_dense_reference() {
        let (k, m) = string_with_mass(60);
        let (lam, _) = dense_pairs(&k, &m);
        let (_, start) = dense_pairs(&(&k * 1.02), &m);
        let q = 14;
        let checked = 10;
        let params = RitzParams {
            max_residual: 1e-9,
            max_sweeps: MAX_SWEEPS,
            min_sweeps: 12,
            rate: 0.5,
        };
        let x = start.columns(0, q).into_owned();
        // The stiffer string's modes are this one's shapes exactly (K scaled): perturb the
        // start so that there is something to converge.
        let x = DMatrix::from_fn(x.nrows(), q, |r, c| {
            x[(r, c)] * (1.0 + 0.01 * ((r * 7 + c) % 5) as f64)
        });
        let pencil = Pencil::from_dense(&k, &m, 1).expect("square");
        let r = subspace_iteration(&pencil, x, checked, &params).expect("iteration");
        assert!(r.sweeps >= 12, "checked at sweep {}", r.sweeps);
        let rho = r.max_residual();
        assert!(rho <= 1e-9, "ρ {rho:.2e}");
        for j in 0..checked {
            let rel = (r.lambda[j] - lam[j]).abs() / lam[j];
            assert!(
                rel <= rho.max(1e-13),
                "mode {j}: {} vs {}: {rel:.2e}",
                r.lambda[j],
                lam[j]
            );
        }
        // M-orthonormal Ritz vectors.
        let g = r.vectors.transpose() * &m * &r.vectors;
        let off = (g - DMatrix::identity(q, q)).amax();
        assert!(off <= 1e-10, "Φᵀ M Φ off the identity by {off:.2e}");
    }

    /// The schedule's prediction: an update that met ρ_max = 1e-5 with ρ = 1e-7 at its
    /// fifth sweep, contracting 10× a sweep, could have been checked two sweeps earlier;
    /// the next is first checked there plus the margin. One that missed the bound keeps
    /// its sweeps plus the margin; the first check never falls below the second sweep.
    #[test]
    fn the_schedule_predicts_the_first_check_from_the_last_update() {
        let ritz = |sweeps, rho, rate| Ritz {
            lambda: vec![1.0],
            vectors: DMatrix::zeros(1, 1),
            residual: vec![rho],
            sweeps,
            rate,
        };
        let mut s = RitzSchedule::default();
        assert_eq!(s.first_check(), RitzSchedule::FIRST_CHECK);
        s.learn(&ritz(5, 1e-7, Some(0.1)), 1e-5);
        assert_eq!(s.first_check(), 5 - 2 + RitzSchedule::MARGIN);
        assert_eq!(s.rate(), 0.1);
        // No new rate measured: the last one is kept.
        s.learn(&ritz(3, 9e-6, None), 1e-5);
        assert_eq!(s.first_check(), 3 + RitzSchedule::MARGIN);
        assert_eq!(s.rate(), 0.1);
        // Missed (the structured shapes take over): its sweeps, plus the margin.
        s.learn(&ritz(7, 2e-5, Some(0.9)), 1e-5);
        assert_eq!(s.first_check(), 7 + RitzSchedule::MARGIN);
        assert_eq!(s.rate(), 0.9);
        // Far below the bound: at the second sweep at the earliest.
        s.learn(&ritz(2, 1e-12, Some(0.1)), 1e-5);
        assert_eq!(s.first_check(), 2);
    }

    /// The products on blocks held by rows equal nalgebra's on the same matrices by
    /// columns, small sizes (nalgebra's own loops) and large (matrixmultiply) alike.
    #[test]
    fn products_by_rows_equal_the_plain_products() {
        for (n, q, cols) in [(5, 3, 2), (7, 1, 1), (40, 12, 9), (219, 52, 39)] {
            let a = DMatrix::from_fn(n, q, |r, c| ((r * 31 + c * 17) % 13) as f64 - 6.0);
            let w = DMatrix::from_fn(q, cols, |r, c| ((r * 7 + c * 5) % 11) as f64 - 5.0);
            let rows: Vec<f64> = (0..n)
                .flat_map(|r| (0..q).map(move |c| (r, c)))
                .map(|(r, c)| a[(r, c)])
                .collect();
            let mut y = vec![1.0; 3];
            product_by_rows(&rows, n, q, &w, &mut y);
            let plain = &a * &w;
            for r in 0..n {
                for c in 0..cols {
                    assert_eq!(
                        y[r * cols + c],
                        plain[(r, c)],
                        "{n}x{q}x{cols} at ({r}, {c})"
                    );
                }
            }
            let b: Vec<f64> = rows.iter().map(|v| 0.5 * v + 1.0).collect();
            let bm = a.map(|v| 0.5 * v + 1.0);
            assert_eq!(
                gram_by_rows(&rows, &b, n, q),
                a.transpose() * &bm,
                "{n}x{q}"
            );
        }
    }
}
