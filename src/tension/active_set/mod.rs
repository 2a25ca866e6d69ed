//! The real-time solver: an exact dual active-set method (Goldfarb-Idnani with H = I) on
//! fixed-size buffers, warm-started from the last active set and polished by the KKT
//! system of the active set it finds.

use super::{Bound, TensionError, TensionInfo, TensionParams, M};
use crate::kinematics::Geometry;
use crate::scene::MAX_CABLES;
use nalgebra::Vector3;

mod closest;
mod cold_start;

/// Floor of a norm used as a scale, so that an all-zero matrix divides by something.
const NORM_FLOOR: f64 = 1e-300;
/// A row of A whose part orthogonal to the rows kept is below this fraction of the largest
/// row norm is linearly dependent (a planar robot's out-of-plane row is exactly zero).
const ROW_INDEPENDENCE_REL: f64 = 1e-10;
/// A dependent row's wrench residual above this fraction of (‖w‖ + T_max·‖A‖) means w is
/// not consistent with it: infeasible, not rounding.
const DEPENDENT_ROW_RESIDUAL_REL: f64 = 1e-9;
/// The polished KKT solution of a cold solve replaces the cold answer when it is optimal
/// within this multiple of the feasibility tolerance (the cold answer carries the
/// iteration's rounding; the polish only fixes it).
const POLISH_ACCEPT_FACTOR: f64 = 1e3;
/// Optimality tolerance of [`TensionSolver::polish`], relative to the problem's scale (N,
/// given by the caller: not T_max, which may be many orders above the load): the
/// reference's bound patterns are guessed from an interior-point answer, so a looser test
/// than the real-time solver's.
const REFERENCE_POLISH_TOL_REL: f64 = 1e-9;
/// Cholesky pivots below this fraction of the largest diagonal entry: the KKT system of
/// the active set is singular (too few free cables to span the rows).
const CHOLESKY_PIVOT_REL: f64 = 1e-13;
/// An active normal whose part orthogonal to the others is below this fraction of its
/// norm is dependent on them: the active set cannot grow by it.
const DEPENDENT_COLUMN_REL: f64 = 1e-12;
/// Entries of R⁻¹Qᵀn_p at or below this are rounding noise, not an active bound limiting
/// the dual step.
const STEP_MULTIPLIER_MIN: f64 = 1e-14;
/// ‖z‖² at or below this: the new normal lies in the span of the active ones, so there is
/// no primal step (only a dual one).
const STEP_DIRECTION_MIN_SQ: f64 = 1e-24;
/// Regularisation ρ of the closest-solution problem: makes it strictly convex, so the
/// reported tensions are unique, without moving the residual noticeably.
const CLOSEST_REGULARISATION: f64 = 1e-9;
/// Projected-gradient (FISTA) steps of the closest solution: a fixed count keeps the
/// infeasible path bounded in time; enough for the residual to settle to a few digits.
const CLOSEST_STEPS: usize = 2000;
/// A closest-solution tension within this fraction of max(1, T_max − T_min) of a bound is
/// reported at that bound.
const CLOSEST_AT_BOUND_REL: f64 = 1e-9;

/// The real-time tension solver: fixed-size buffers, warm start, no allocation in `solve`.
#[derive(Debug, Clone)]
pub struct TensionSolver {
    n: usize,
    params: TensionParams,
    /// Structure matrix rows (only the independent ones are used), A[r][i].
    a: [[f64; MAX_CABLES]; M],
    rows: [usize; M],
    n_rows: usize,
    w: [f64; M],
    /// Per-cable lower bounds T_min,i (N) of the current solve.
    lo: [f64; MAX_CABLES],
    /// Per-cable upper bounds T_max,i (N) of the current solve.
    hi: [f64; MAX_CABLES],
    t: [f64; MAX_CABLES],
    bound: [Bound; MAX_CABLES],
    have_warm: bool,
    // Goldfarb-Idnani work space: active constraint ids (equalities first), Q, R, multipliers.
    active: [usize; MAX_CABLES + M],
    n_active: usize,
    q: [[f64; MAX_CABLES]; MAX_CABLES],
    r: [[f64; MAX_CABLES]; MAX_CABLES],
    u: [f64; MAX_CABLES + M],
    info: TensionInfo,
}

/// Constraint ids in the cold solver: 0..M equality rows, then M + i: T_i ≥ lo, M + n + i: T_i ≤ hi.
const EQ_BASE: usize = 0;

impl TensionSolver {
    /// Allocate for `n_cables` (≤ [`MAX_CABLES`]) cables.
    pub fn new(n_cables: usize, params: TensionParams) -> TensionSolver {
        assert!(
            (1..=MAX_CABLES).contains(&n_cables),
            "1..=MAX_CABLES cables"
        );
        TensionSolver {
            n: n_cables,
            params,
            a: [[0.0; MAX_CABLES]; M],
            rows: [0; M],
            n_rows: 0,
            w: [0.0; M],
            lo: [0.0; MAX_CABLES],
            hi: [0.0; MAX_CABLES],
            t: [0.0; MAX_CABLES],
            bound: [Bound::Free; MAX_CABLES],
            have_warm: false,
            active: [0; MAX_CABLES + M],
            n_active: 0,
            q: [[0.0; MAX_CABLES]; MAX_CABLES],
            r: [[0.0; MAX_CABLES]; MAX_CABLES],
            u: [0.0; MAX_CABLES + M],
            info: TensionInfo::default(),
        }
    }

    /// Forget the warm start (the next solve is cold).
    pub fn reset_warm_start(&mut self) {
        self.have_warm = false;
    }

    /// Tensions of the last successful solve (or the closest solution after `Infeasible`), N.
    pub fn tensions_n(&self) -> &[f64] {
        &self.t[..self.n]
    }

    /// Active bounds of the last solve.
    pub fn bounds(&self) -> &[Bound] {
        &self.bound[..self.n]
    }

    /// Information on the last solve.
    pub fn info(&self) -> TensionInfo {
        self.info
    }

    /// Solve for geometry `g`, force `w_n` (N, no moment) and bounds [t_min_n, t_max_n] (N).
    pub fn solve(
        &mut self,
        g: &Geometry,
        w_n: &Vector3<f64>,
        t_min_n: f64,
        t_max_n: f64,
    ) -> Result<&[f64], TensionError> {
        let w = [w_n.x, w_n.y, w_n.z, 0.0, 0.0, 0.0];
        self.solve_wrench(g, &w, t_min_n, t_max_n)
    }

    /// Solve for geometry `g`, wrench `w` = (force N, moment N·m) and bounds
    /// [t_min_n, t_max_n] (N), the same for every cable.
    pub fn solve_wrench(
        &mut self,
        g: &Geometry,
        w_n: &[f64; 6],
        t_min_n: f64,
        t_max_n: f64,
    ) -> Result<&[f64], TensionError> {
        if !bounds_are_valid(t_min_n, t_max_n) {
            self.have_warm = false;
            return Err(TensionError::InvalidBounds { t_min_n, t_max_n });
        }
        self.lo[..self.n].fill(t_min_n);
        self.hi[..self.n].fill(t_max_n);
        self.solve_loaded(g, w_n)
    }

    /// Solve for geometry `g`, wrench `w` = (force N, moment N·m) and per-cable bounds
    /// `t_min_n[i] ≤ T_i ≤ t_max_n[i]` (N; one value per cable). With every lower bound equal
    /// and every upper bound equal this is [`Self::solve_wrench`], bit for bit. No
    /// allocation. A slice of the wrong length or a bound pair that is not finite,
    /// 0 ≤ t_min ≤ t_max is [`TensionError::InvalidBounds`] (with the first bad pair).
    pub fn solve_wrench_bounds(
        &mut self,
        g: &Geometry,
        w_n: &[f64; 6],
        t_min_n: &[f64],
        t_max_n: &[f64],
    ) -> Result<&[f64], TensionError> {
        let n = self.n;
        if let Some(e) = invalid_bounds(n, t_min_n, t_max_n) {
            self.have_warm = false;
            return Err(e);
        }
        self.lo[..n].copy_from_slice(t_min_n);
        self.hi[..n].copy_from_slice(t_max_n);
        self.solve_loaded(g, w_n)
    }

    /// The lower bounds (N) of the last solve, one per cable.
    pub fn lower_bounds_n(&self) -> &[f64] {
        &self.lo[..self.n]
    }

    /// Largest upper bound of the current solve, N: the scale of the tolerances.
    fn hi_max(&self) -> f64 {
        self.hi[..self.n]
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Whether the current solve's cables have different bounds (reported in errors).
    fn bounds_differ(&self) -> bool {
        let n = self.n;
        let differ = |v: &[f64]| v[..n].iter().any(|x| *x != v[0]);
        n > 0 && (differ(&self.lo) || differ(&self.hi))
    }

    /// Smallest lower bound of the current solve, N (reported in errors).
    fn lo_min(&self) -> f64 {
        self.lo[..self.n]
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }

    /// The solve with the bounds already in `lo`, `hi` (checked).
    fn solve_loaded(&mut self, g: &Geometry, w_n: &[f64; 6]) -> Result<&[f64], TensionError> {
        let n = self.n;
        let t_max_n = self.hi_max();
        if !w_n.iter().all(|x| x.is_finite())
            || g.unit
                .iter()
                .take(n)
                .any(|s| !s.iter().all(|x| x.is_finite()))
            || g.arm_m
                .iter()
                .take(n)
                .any(|s| !s.iter().all(|x| x.is_finite()))
        {
            self.have_warm = false;
            return Err(TensionError::NonFinite);
        }
        self.info = TensionInfo::default();
        let (dependent, scale) = self.setup_rows(g, w_n);
        self.info.rank = self.n_rows as u32;
        let tol = self.params.feasibility_tol * t_max_n.max(1.0);

        let mut solved = false;
        if self.have_warm && self.kkt_solve() && self.kkt_is_optimal(tol) {
            self.info.warm_start_accepted = true;
            solved = true;
        }
        if !solved {
            match self.cold_solve(tol) {
                Ok(()) => {
                    // Polish: exact KKT solve of the active set the cold solve found.
                    let keep = self.t;
                    if !self.kkt_solve() || !self.kkt_is_optimal(tol * POLISH_ACCEPT_FACTOR) {
                        self.t = keep;
                    }
                }
                Err(e) => {
                    self.have_warm = false;
                    if let TensionError::Infeasible { .. } = e {
                        return Err(self.closest_solution(g, w_n));
                    }
                    return Err(e);
                }
            }
        }
        // The answer is exact to rounding; values within the tolerance of a bound are that
        // bound (T_min = 1e-9 N must not come back as −0.0).
        for (i, t) in self.t.iter_mut().enumerate().take(n) {
            *t = t.clamp(self.lo[i], self.hi[i]);
        }
        // Dependent rows (w must be consistent with them).
        let aw = g.wrench_of(&self.t[..n]);
        let am = g.moment_of(&self.t[..n]);
        let wnorm = w_n.iter().map(|x| x * x).sum::<f64>().sqrt();
        let mut res = 0.0f64;
        for r in 0..M {
            let got = if r < 3 { aw[r] } else { am[r - 3] };
            let d = (got - w_n[r]).abs();
            res = res.max(d);
            if dependent[r] && d > DEPENDENT_ROW_RESIDUAL_REL * (wnorm + t_max_n * scale) {
                self.have_warm = false;
                return Err(self.closest_solution(g, w_n));
            }
        }
        self.info.residual_n = res;
        self.have_warm = true;
        Ok(&self.t[..n])
    }

    /// Keep the linearly independent rows of A (Gram-Schmidt on the rows) and their wrench
    /// components; returns which rows were dependent and the largest row norm.
    fn setup_rows(&mut self, g: &Geometry, w_n: &[f64; 6]) -> ([bool; M], f64) {
        let n = self.n;
        let mut basis = [[0.0; MAX_CABLES]; M];
        let mut full = [[0.0; MAX_CABLES]; M];
        for (r, row) in full.iter_mut().enumerate() {
            for i in 0..n {
                row[i] = g.a(r, i);
            }
        }
        let scale = full
            .iter()
            .map(|row| dot(row, row, n).sqrt())
            .fold(0.0, f64::max)
            .max(NORM_FLOOR);
        self.n_rows = 0;
        let mut dependent = [false; M];
        for r in 0..M {
            let mut v = full[r];
            for _pass in 0..2 {
                for b in basis.iter().take(self.n_rows) {
                    let c = dot(b, &v, n);
                    axpy(&mut v, -c, b, n);
                }
            }
            let nv = dot(&v, &v, n).sqrt();
            if nv > ROW_INDEPENDENCE_REL * scale {
                for i in 0..n {
                    basis[self.n_rows][i] = v[i] / nv;
                }
                self.rows[self.n_rows] = r;
                self.a[self.n_rows] = full[r];
                self.w[self.n_rows] = w_n[r];
                self.n_rows += 1;
            } else {
                dependent[r] = true;
            }
        }
        (dependent, scale)
    }

    /// Exact solution for a given bound pattern (the KKT system of that active set), if it
    /// is optimal within a tolerance relative to `scale_n` (N, the size of the tensions and
    /// the wrench): the polish step of [`super::clarabel_reference`]. The bounds (N) are
    /// per cable, of length n.
    pub(super) fn polish(
        &mut self,
        g: &Geometry,
        w_n: &[f64; 6],
        t_min_n: &[f64],
        t_max_n: &[f64],
        pattern: &[Bound],
        scale_n: f64,
    ) -> Option<Vec<f64>> {
        let n = self.n;
        self.lo[..n].copy_from_slice(t_min_n);
        self.hi[..n].copy_from_slice(t_max_n);
        self.setup_rows(g, w_n);
        self.bound[..n].copy_from_slice(pattern);
        let tol = REFERENCE_POLISH_TOL_REL * scale_n.max(1.0);
        if self.kkt_solve() && self.kkt_is_optimal(tol) {
            return Some(
                (0..n)
                    .map(|i| self.t[i].clamp(self.lo[i], self.hi[i]))
                    .collect(),
            );
        }
        // Every cable at T_min: the tensions are fixed; optimal (multipliers ν = 0) when
        // they produce the wrench.
        if pattern.iter().all(|b| *b == Bound::Lower) {
            let t = t_min_n.to_vec();
            let f = g.wrench_of(&t);
            let m = g.moment_of(&t);
            let res = (0..3)
                .map(|r| (f[r] - w_n[r]).abs().max((m[r] - w_n[3 + r]).abs()))
                .fold(0.0, f64::max);
            if res <= tol {
                return Some(t);
            }
        }
        None
    }

    /// Solve the KKT system of the current `bound` pattern; false when it is singular.
    fn kkt_solve(&mut self) -> bool {
        let n = self.n;
        let k = self.n_rows;
        // rhs = w − A_W T_W ; G = A_F A_Fᵀ
        let mut g = [[0.0; M]; M];
        let mut rhs = [0.0; M];
        rhs[..k].copy_from_slice(&self.w[..k]);
        for i in 0..n {
            let fixed = match self.bound[i] {
                Bound::Free => None,
                Bound::Lower => Some(self.lo[i]),
                Bound::Upper => Some(self.hi[i]),
            };
            match fixed {
                Some(v) => {
                    for r in 0..k {
                        rhs[r] -= self.a[r][i] * v;
                    }
                }
                None => {
                    for r in 0..k {
                        for c in 0..k {
                            g[r][c] += self.a[r][i] * self.a[c][i];
                        }
                    }
                }
            }
        }
        let mut nu = rhs;
        if !cholesky_solve(&mut g, &mut nu, k) {
            return false;
        }
        for i in 0..n {
            let atnu: f64 = (0..k).map(|r| self.a[r][i] * nu[r]).sum();
            self.t[i] = match self.bound[i] {
                Bound::Free => atnu,
                Bound::Lower => self.lo[i],
                Bound::Upper => self.hi[i],
            };
            // Store multipliers: reuse u[i] = (Aᵀν)_i.
            self.u[i] = atnu;
        }
        true
    }

    /// Primal and dual feasibility of the last `kkt_solve`.
    fn kkt_is_optimal(&self, tol: f64) -> bool {
        (0..self.n).all(|i| {
            let atnu = self.u[i];
            match self.bound[i] {
                Bound::Free => self.t[i] >= self.lo[i] - tol && self.t[i] <= self.hi[i] + tol,
                Bound::Lower => self.lo[i] - atnu >= -tol,
                Bound::Upper => atnu - self.hi[i] >= -tol,
            }
        }) && self.t[..self.n].iter().all(|x| x.is_finite())
    }

    fn normal(&self, id: usize, out: &mut [f64; MAX_CABLES]) {
        let n = self.n;
        out[..n].iter_mut().for_each(|x| *x = 0.0);
        if id < M {
            out[..n].copy_from_slice(&self.a[id - EQ_BASE][..n]);
        } else if id < M + n {
            out[id - M] = 1.0;
        } else {
            out[id - M - n] = -1.0;
        }
    }

    fn rhs_of(&self, id: usize) -> f64 {
        if id < M {
            self.w[id]
        } else if id < M + self.n {
            self.lo[id - M]
        } else {
            -self.hi[id - M - self.n]
        }
    }

    /// Rebuild Q, R of the active normals by modified Gram-Schmidt with re-orthogonalisation.
    /// Returns false when a column is dependent.
    fn refactor(&mut self) -> bool {
        let n = self.n;
        let mut v = [0.0; MAX_CABLES];
        for k in 0..self.n_active {
            self.normal(self.active[k], &mut v);
            let nrm = dot(&v, &v, n).sqrt();
            for j in 0..k {
                self.r[j][k] = 0.0;
            }
            for _pass in 0..2 {
                for j in 0..k {
                    let c = dot(&self.q[j], &v, n);
                    self.r[j][k] += c;
                    let qj = self.q[j];
                    axpy(&mut v, -c, &qj, n);
                }
            }
            let rkk = dot(&v, &v, n).sqrt();
            if rkk <= DEPENDENT_COLUMN_REL * nrm.max(NORM_FLOOR) {
                return false;
            }
            self.r[k][k] = rkk;
            for i in 0..n {
                self.q[k][i] = v[i] / rkk;
            }
        }
        true
    }

    /// z = (I − QQᵀ) n_p, r = R⁻¹ Qᵀ n_p.
    fn directions(
        &self,
        np: &[f64; MAX_CABLES],
        z: &mut [f64; MAX_CABLES],
        rr: &mut [f64; MAX_CABLES + M],
    ) {
        let n = self.n;
        let q = self.n_active;
        let mut d = [0.0; MAX_CABLES + M];
        *z = *np;
        for _pass in 0..2 {
            for j in 0..q {
                let c = dot(&self.q[j], z, n);
                d[j] += c;
                axpy(z, -c, &self.q[j], n);
            }
        }
        for j in (0..q).rev() {
            let mut s = d[j];
            for k in j + 1..q {
                s -= self.r[j][k] * rr[k];
            }
            rr[j] = s / self.r[j][j];
        }
    }
}

/// One bound pair (N) a box QP accepts: both finite, 0 ≤ t_min ≤ t_max.
pub(super) fn bounds_are_valid(t_min_n: f64, t_max_n: f64) -> bool {
    t_min_n.is_finite() && t_max_n.is_finite() && t_min_n >= 0.0 && t_min_n <= t_max_n
}

/// The error for per-cable bounds (N) that are not `n` valid pairs (the first bad pair, or
/// NaN for a wrong length), None when they are.
pub(super) fn invalid_bounds(n: usize, t_min_n: &[f64], t_max_n: &[f64]) -> Option<TensionError> {
    if t_min_n.len() != n || t_max_n.len() != n {
        return Some(TensionError::InvalidBounds {
            t_min_n: f64::NAN,
            t_max_n: f64::NAN,
        });
    }
    t_min_n
        .iter()
        .zip(t_max_n)
        .find(|(&lo, &hi)| !bounds_are_valid(lo, hi))
        .map(|(&t_min_n, &t_max_n)| TensionError::InvalidBounds { t_min_n, t_max_n })
}

fn dot(a: &[f64; MAX_CABLES], b: &[f64; MAX_CABLES], n: usize) -> f64 {
    let mut s = 0.0;
    for i in 0..n {
        s += a[i] * b[i];
    }
    s
}

fn axpy(y: &mut [f64; MAX_CABLES], alpha: f64, x: &[f64; MAX_CABLES], n: usize) {
    for i in 0..n {
        y[i] += alpha * x[i];
    }
}

/// In-place Cholesky solve of a k × k SPD system; false when not positive definite.
fn cholesky_solve(g: &mut [[f64; M]; M], b: &mut [f64; M], k: usize) -> bool {
    let diag_max = (0..k).map(|i| g[i][i].abs()).fold(0.0, f64::max);
    for j in 0..k {
        let mut d = g[j][j];
        for p in 0..j {
            d -= g[j][p] * g[j][p];
        }
        if !(d > CHOLESKY_PIVOT_REL * diag_max) {
            return false;
        }
        let d = d.sqrt();
        g[j][j] = d;
        for i in j + 1..k {
            let mut s = g[i][j];
            for p in 0..j {
                s -= g[i][p] * g[j][p];
            }
            g[i][j] = s / d;
        }
    }
    for i in 0..k {
        let mut s = b[i];
        for p in 0..i {
            s -= g[i][p] * b[p];
        }
        b[i] = s / g[i][i];
    }
    for i in (0..k).rev() {
        let mut s = b[i];
        for p in i + 1..k {
            s -= g[p][i] * b[p];
        }
        b[i] = s / g[i][i];
    }
    true
}
