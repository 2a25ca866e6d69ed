//! Tension distribution: the QP of paper Eqs. 9-11 with C = I, c = 0,
//!
//! ```text
//!     minimise ½‖T‖²   subject to   A T = w,   T_min ≤ T_i ≤ T_max,
//! ```
//!
//! with A the 3 × n structure matrix of [`crate::kinematics`] and w the wrench (N).
//! The solution is the point of the feasible polytope closest to the origin.
//!
//! Two solvers:
//!
//! - [`TensionSolver`], the real-time one: an exact dual active-set method (Goldfarb-Idnani,
//!   with H = I) on preallocated fixed-size buffers. It is warm-started from the last active
//!   set: the KKT system of that set is solved and accepted when it is primal and dual
//!   feasible, which along a trajectory is almost every cycle. Every answer, warm or cold, is
//!   polished by solving the KKT system of its active set, so it is exact to rounding.
//!   Iterations are bounded by [`TensionParams::max_iterations`]. `solve(&mut self)` never
//!   allocates.
//! - [`clarabel_reference`]: Clarabel's interior-point solver with tight tolerances, built
//!   fresh per call. Used as the reference in tests and by `cablevib analyze`.
//!
//! An infeasible wrench (outside A·[T_min, T_max]ⁿ) is a [`TensionError::Infeasible`]
//! carrying the closest achievable solution's residual wrench, never a silent clamp.
//! Rows of A that are linearly dependent (a planar robot's out-of-plane row is zero) are
//! dropped when w is consistent with them and reported infeasible when it is not.

use crate::kinematics::Geometry;
use crate::scene::MAX_CABLES;
use nalgebra::Vector3;

/// Largest number of equality rows: force (3) and moment (3).
const M: usize = 6;

/// Parameters of the active-set solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TensionParams {
    /// Largest number of active-set changes in a cold solve.
    pub max_iterations: usize,
    /// Bound violation tolerated, relative to max(1, T_max).
    pub feasibility_tol: f64,
}

impl Default for TensionParams {
    fn default() -> Self {
        TensionParams {
            max_iterations: 200,
            feasibility_tol: 1e-11,
        }
    }
}

/// Which bound a cable sits on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Bound {
    /// Strictly between the bounds.
    #[default]
    Free,
    /// At T_min.
    Lower,
    /// At T_max.
    Upper,
}

/// What a solve did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TensionInfo {
    /// Active-set changes of the cold solve (0 when the warm start was accepted).
    pub iterations: u32,
    /// True when the previous active set was optimal again.
    pub warm_start_accepted: bool,
    /// Rank of the structure matrix (3 for a spatial robot, 2 for a planar one).
    pub rank: u32,
    /// ‖A T − w‖∞ of the answer, N.
    pub residual_n: f64,
}

/// Errors of the tension distribution.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum TensionError {
    /// T_min > T_max, or a bound not finite, or T_min < 0.
    #[error("invalid tension bounds: t_min = {t_min_n} N, t_max = {t_max_n} N (need 0 ≤ t_min ≤ t_max, finite)")]
    InvalidBounds {
        /// Lower bound, N.
        t_min_n: f64,
        /// Upper bound, N.
        t_max_n: f64,
    },
    /// A non-finite wrench or geometry.
    #[error("non-finite wrench or cable geometry")]
    NonFinite,
    /// No tensions within the bounds produce the wrench.
    #[error(
        "tension infeasible: wrench component {} cannot be reached within [{t_min_n}, {t_max_n}] N; \
         closest tensions leave a residual force ({:.4}, {:.4}, {:.4}) N, moment ({:.4}, {:.4}, {:.4}) N·m; \
         cables at t_max: {}, at t_min: {}",
        ["f_x", "f_y", "f_z", "m_x", "m_y", "m_z"][*worst_component], residual_n[0], residual_n[1], residual_n[2],
        residual_n[3], residual_n[4], residual_n[5],
        fmt_mask(*at_upper_mask), fmt_mask(*at_lower_mask)
    )]
    Infeasible {
        /// Index (0-2 = force x, y, z; 3-5 = moment x, y, z) of the largest residual.
        worst_component: usize,
        /// A·T_closest − w: force (N) then moment (N·m).
        residual_n: [f64; 6],
        /// Bit i set: cable i at T_max in the closest solution.
        at_upper_mask: u32,
        /// Bit i set: cable i at T_min in the closest solution.
        at_lower_mask: u32,
        /// Lower bound, N.
        t_min_n: f64,
        /// Upper bound, N.
        t_max_n: f64,
    },
    /// The bounded iteration count ran out (should not happen; reported, not hidden).
    #[error("active-set method did not converge in {iterations} iterations")]
    NotConverged {
        /// Iterations done.
        iterations: u32,
    },
    /// The Clarabel reference stopped without a solution or an infeasibility certificate.
    #[error("Clarabel reference stopped with status {status} after {iterations} iterations")]
    ReferenceFailed {
        /// Clarabel's status.
        status: &'static str,
        /// Iterations done.
        iterations: u32,
    },
}

struct MaskFmt(u32);
impl std::fmt::Display for MaskFmt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.0 == 0 {
            return write!(f, "none");
        }
        let mut first = true;
        for i in 0..32 {
            if self.0 & (1 << i) != 0 {
                if !first {
                    write!(f, ",")?;
                }
                write!(f, "{i}")?;
                first = false;
            }
        }
        Ok(())
    }
}
fn fmt_mask(m: u32) -> MaskFmt {
    MaskFmt(m)
}

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
    lo: f64,
    hi: f64,
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
            lo: 0.0,
            hi: 0.0,
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

    /// Solve for geometry `g`, wrench `w` = (force N, moment N·m) and bounds (N).
    pub fn solve_wrench(
        &mut self,
        g: &Geometry,
        w_n: &[f64; 6],
        t_min_n: f64,
        t_max_n: f64,
    ) -> Result<&[f64], TensionError> {
        let n = self.n;
        if !(t_min_n.is_finite() && t_max_n.is_finite() && t_min_n >= 0.0 && t_min_n <= t_max_n) {
            self.have_warm = false;
            return Err(TensionError::InvalidBounds { t_min_n, t_max_n });
        }
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
        self.lo = t_min_n;
        self.hi = t_max_n;
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
                    if !self.kkt_solve() || !self.kkt_is_optimal(tol * 1e3) {
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
        for t in self.t.iter_mut().take(n) {
            *t = t.clamp(self.lo, self.hi);
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
            if dependent[r] && d > 1e-9 * (wnorm + t_max_n * scale) {
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
            .max(1e-300);
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
            if nv > 1e-10 * scale {
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
    /// is optimal within `tol` (N): the polish step of [`clarabel_reference`].
    fn polish(
        &mut self,
        g: &Geometry,
        w_n: &[f64; 6],
        t_min_n: f64,
        t_max_n: f64,
        pattern: &[Bound],
    ) -> Option<Vec<f64>> {
        self.lo = t_min_n;
        self.hi = t_max_n;
        self.setup_rows(g, w_n);
        self.bound[..self.n].copy_from_slice(pattern);
        let tol = 1e-9 * t_max_n.max(1.0);
        if self.kkt_solve() && self.kkt_is_optimal(tol) {
            return Some(
                self.t[..self.n]
                    .iter()
                    .map(|t| t.clamp(t_min_n, t_max_n))
                    .collect(),
            );
        }
        // Every cable at T_min: the tensions are fixed; optimal (multipliers ν = 0) when
        // they produce the wrench.
        if pattern.iter().all(|b| *b == Bound::Lower) {
            let t = vec![t_min_n; self.n];
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
                Bound::Lower => Some(self.lo),
                Bound::Upper => Some(self.hi),
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
                Bound::Lower => self.lo,
                Bound::Upper => self.hi,
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
                Bound::Free => self.t[i] >= self.lo - tol && self.t[i] <= self.hi + tol,
                Bound::Lower => self.lo - atnu >= -tol,
                Bound::Upper => atnu - self.hi >= -tol,
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
            self.lo
        } else {
            -self.hi
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
            if rkk <= 1e-12 * nrm.max(1e-300) {
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

    fn cold_solve(&mut self, tol: f64) -> Result<(), TensionError> {
        let n = self.n;
        let k = self.n_rows;
        // Start: minimum-norm solution of the equalities, x = Aᵀ (A Aᵀ)⁻¹ w.
        self.n_active = k;
        for j in 0..k {
            self.active[j] = j;
        }
        if !self.refactor() {
            return Err(TensionError::NonFinite);
        }
        // x = Q R⁻ᵀ w, u = R⁻¹ R⁻ᵀ w.
        let mut y = [0.0; M];
        for j in 0..k {
            let mut s = self.w[j];
            for i in 0..j {
                s -= self.r[i][j] * y[i];
            }
            y[j] = s / self.r[j][j];
        }
        let mut x = [0.0; MAX_CABLES];
        for j in 0..k {
            let qj = self.q[j];
            axpy(&mut x, y[j], &qj, n);
        }
        for j in (0..k).rev() {
            let mut s = y[j];
            for i in j + 1..k {
                s -= self.r[j][i] * self.u[i];
            }
            self.u[j] = s / self.r[j][j];
        }
        let mut np = [0.0; MAX_CABLES];
        let mut z = [0.0; MAX_CABLES];
        let mut rr = [0.0; MAX_CABLES + M];
        let mut iters = 0u32;
        loop {
            // Most violated inactive bound.
            let mut p = usize::MAX;
            let mut worst = -tol;
            for i in 0..n {
                let lo_v = x[i] - self.lo;
                let hi_v = self.hi - x[i];
                let is_active = |id: usize| self.active[k..self.n_active].contains(&id);
                if lo_v < worst && !is_active(M + i) {
                    worst = lo_v;
                    p = M + i;
                }
                if hi_v < worst && !is_active(M + n + i) {
                    worst = hi_v;
                    p = M + n + i;
                }
            }
            if p == usize::MAX {
                break;
            }
            self.normal(p, &mut np);
            let bp = self.rhs_of(p);
            let mut up = 0.0;
            loop {
                iters += 1;
                if iters as usize > self.params.max_iterations {
                    self.info.iterations = iters;
                    return Err(TensionError::NotConverged { iterations: iters });
                }
                self.directions(&np, &mut z, &mut rr);
                // Partial step: largest step keeping inequality multipliers ≥ 0.
                let mut t1 = f64::INFINITY;
                let mut kdrop = usize::MAX;
                for j in k..self.n_active {
                    if rr[j] > 1e-14 {
                        let s = self.u[j] / rr[j];
                        if s < t1 {
                            t1 = s;
                            kdrop = j;
                        }
                    }
                }
                let zz = dot(&z, &z, n);
                let sp = dot(&np, &x, n) - bp;
                let t2 = if zz > 1e-24 { -sp / zz } else { f64::INFINITY };
                if !t1.is_finite() && !t2.is_finite() {
                    self.info.iterations = iters;
                    return Err(TensionError::Infeasible {
                        worst_component: 0,
                        residual_n: [0.0; 6],
                        at_upper_mask: 0,
                        at_lower_mask: 0,
                        t_min_n: self.lo,
                        t_max_n: self.hi,
                    });
                }
                let t = t1.min(t2);
                if t2.is_finite() {
                    axpy(&mut x, t, &z, n);
                }
                for j in 0..self.n_active {
                    self.u[j] -= t * rr[j];
                }
                up += t;
                if t2 <= t1 {
                    // Full step: add p.
                    self.active[self.n_active] = p;
                    self.u[self.n_active] = up;
                    self.n_active += 1;
                    if !self.refactor() {
                        self.n_active -= 1;
                        self.refactor();
                        return Err(TensionError::NotConverged { iterations: iters });
                    }
                    break;
                }
                // Partial step: drop kdrop.
                for j in kdrop..self.n_active - 1 {
                    self.active[j] = self.active[j + 1];
                    self.u[j] = self.u[j + 1];
                }
                self.n_active -= 1;
                self.refactor();
            }
        }
        self.info.iterations = iters;
        for i in 0..n {
            self.t[i] = x[i];
            self.bound[i] = Bound::Free;
        }
        for j in k..self.n_active {
            let id = self.active[j];
            if id < M + n {
                self.bound[id - M] = Bound::Lower;
            } else {
                self.bound[id - M - n] = Bound::Upper;
            }
        }
        Ok(())
    }

    /// The closest achievable wrench: min ½‖A T − w‖² + ½ρ‖T‖² over the box, by a bounded
    /// number of projected-gradient (FISTA) steps. Leaves the tensions in `self.t`.
    fn closest_solution(&mut self, g: &Geometry, w_n: &[f64; 6]) -> TensionError {
        let n = self.n;
        let (lo, hi) = (self.lo, self.hi);
        // Lipschitz constant of the gradient: ‖A‖² ≤ trace(AᵀA) = Σ (1 + ‖r_i × s_i‖²).
        let rho = 1e-9;
        let lip = (0..n)
            .map(|i| 1.0 + g.arm_m[i].cross(&g.unit[i]).norm_squared())
            .sum::<f64>()
            + rho;
        let wf = Vector3::new(w_n[0], w_n[1], w_n[2]);
        let wm = Vector3::new(w_n[3], w_n[4], w_n[5]);
        let mut x = [0.0; MAX_CABLES];
        for v in x.iter_mut().take(n) {
            *v = 0.5 * (lo + hi);
        }
        let mut yv = x;
        let mut tk = 1.0f64;
        for _ in 0..2000 {
            let r = g.wrench_of(&yv[..n]) - wf;
            let rm = g.moment_of(&yv[..n]) - wm;
            let mut xn = [0.0; MAX_CABLES];
            for i in 0..n {
                let grad = g.unit[i].dot(&r) + g.arm_m[i].cross(&g.unit[i]).dot(&rm) + rho * yv[i];
                xn[i] = (yv[i] - grad / lip).clamp(lo, hi);
            }
            let tn = 0.5 * (1.0 + (1.0 + 4.0 * tk * tk).sqrt());
            for i in 0..n {
                yv[i] = xn[i] + (tk - 1.0) / tn * (xn[i] - x[i]);
            }
            x = xn;
            tk = tn;
        }
        self.t = x;
        let rf = g.wrench_of(&x[..n]) - wf;
        let rm = g.moment_of(&x[..n]) - wm;
        let r = [rf.x, rf.y, rf.z, rm.x, rm.y, rm.z];
        let mut worst = 0;
        for c in 1..6 {
            if r[c].abs() > r[worst].abs() {
                worst = c;
            }
        }
        let eps = 1e-9 * (hi - lo).max(1.0);
        let mut up = 0u32;
        let mut dn = 0u32;
        for (i, &xi) in x.iter().enumerate().take(n) {
            if xi >= hi - eps {
                up |= 1 << i;
                self.bound[i] = Bound::Upper;
            } else if xi <= lo + eps {
                dn |= 1 << i;
                self.bound[i] = Bound::Lower;
            } else {
                self.bound[i] = Bound::Free;
            }
        }
        TensionError::Infeasible {
            worst_component: worst,
            residual_n: r,
            at_upper_mask: up,
            at_lower_mask: dn,
            t_min_n: lo,
            t_max_n: hi,
        }
    }
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
        if !(d > 1e-13 * diag_max) {
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

/// Reference solution with Clarabel (interior point), built fresh per call: tolerances 1e-13,
/// then with the unknowns scaled by T_max, then Clarabel's defaults, until it solves or
/// certifies infeasibility; the solution is polished by solving the KKT system of the
/// active set Clarabel found (kept only if optimal). Allocates; for tests, `analyze` and
/// cross-checks, not the real-time path. Infeasibility is reported with the same
/// closest-solution analysis as [`TensionSolver`].
pub fn clarabel_reference(
    g: &Geometry,
    w_n: &Vector3<f64>,
    t_min_n: f64,
    t_max_n: f64,
) -> Result<Vec<f64>, TensionError> {
    clarabel_reference_wrench(g, &[w_n.x, w_n.y, w_n.z, 0.0, 0.0, 0.0], t_min_n, t_max_n)
}

/// [`clarabel_reference`] for a full wrench (force N, moment N·m).
pub fn clarabel_reference_wrench(
    g: &Geometry,
    w_n: &[f64; 6],
    t_min_n: f64,
    t_max_n: f64,
) -> Result<Vec<f64>, TensionError> {
    use clarabel::algebra::CscMatrix;
    use clarabel::solver::{
        DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, ZeroConeT,
    };
    let n = g.n();
    if !(t_min_n.is_finite() && t_max_n.is_finite() && t_min_n >= 0.0 && t_min_n <= t_max_n) {
        return Err(TensionError::InvalidBounds { t_min_n, t_max_n });
    }
    if !w_n.iter().all(|x| x.is_finite()) {
        return Err(TensionError::NonFinite);
    }
    // Equality rows that are not identically zero (a planar robot's normal row is; so are
    // a point mass's moment rows).
    let rows: Vec<usize> = (0..6)
        .filter(|&r| (0..n).any(|i| g.a(r, i).abs() > 1e-14))
        .collect();
    for r in 0..6 {
        if !rows.contains(&r) && w_n[r].abs() > 1e-9 {
            let mut s = TensionSolver::new(n, TensionParams::default());
            s.lo = t_min_n;
            s.hi = t_max_n;
            return Err(s.closest_solution(g, w_n));
        }
    }
    let m_eq = rows.len();
    let strict = DefaultSettings {
        verbose: false,
        tol_gap_abs: 1e-13,
        tol_gap_rel: 1e-13,
        tol_feas: 1e-13,
        tol_ktratio: 1e-10,
        max_iter: 200,
        ..DefaultSettings::default()
    };
    let loose = DefaultSettings {
        verbose: false,
        max_iter: 400,
        ..DefaultSettings::default()
    };
    // Attempts: the problem as posed with tight tolerances; then with the unknowns scaled by
    // T_max (x = T / T_max) so the tolerances are relative; then Clarabel's defaults.
    let mut last = (SolverStatus::Unsolved, 0u32);
    for (scale, settings) in [
        (1.0, strict.clone()),
        (t_max_n.max(1e-300), strict),
        (t_max_n.max(1e-300), loose),
    ] {
        let mut dense = vec![vec![0.0; n]; m_eq + 2 * n];
        let mut b = vec![0.0; m_eq + 2 * n];
        for (k, &r) in rows.iter().enumerate() {
            for i in 0..n {
                dense[k][i] = g.a(r, i);
            }
            b[k] = w_n[r] / scale;
        }
        for i in 0..n {
            dense[m_eq + i][i] = 1.0; // x_i + s = t_max / scale
            b[m_eq + i] = t_max_n / scale;
            dense[m_eq + n + i][i] = -1.0; // −x_i + s = −t_min / scale
            b[m_eq + n + i] = -t_min_n / scale;
        }
        let a = CscMatrix::from(&dense);
        let p = CscMatrix::identity(n);
        let q = vec![0.0; n];
        let cones = [ZeroConeT(m_eq), NonnegativeConeT(2 * n)];
        let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings)
            .map_err(|_| TensionError::NonFinite)?;
        solver.solve();
        match solver.solution.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => {
                let x: Vec<f64> = solver
                    .solution
                    .x
                    .iter()
                    .map(|x| (x * scale).clamp(t_min_n, t_max_n))
                    .collect();
                // Polish: Clarabel's active set, solved exactly (interior-point answers sit
                // ~tolerance away from the bounds they touch). The first bound-detection
                // threshold whose KKT solution is optimal wins; else Clarabel's answer.
                let mut s = TensionSolver::new(n, TensionParams::default());
                for rel in [1e-5, 1e-7, 1e-9] {
                    let delta = rel * t_max_n.max(1.0);
                    let pattern: Vec<Bound> = x
                        .iter()
                        .map(|&t| {
                            if t <= t_min_n + delta {
                                Bound::Lower
                            } else if t >= t_max_n - delta {
                                Bound::Upper
                            } else {
                                Bound::Free
                            }
                        })
                        .collect();
                    if let Some(t) = s.polish(g, w_n, t_min_n, t_max_n, &pattern) {
                        return Ok(t);
                    }
                }
                return Ok(x);
            }
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
                let mut s = TensionSolver::new(n, TensionParams::default());
                s.lo = t_min_n;
                s.hi = t_max_n;
                return Err(s.closest_solution(g, w_n));
            }
            other => last = (other, solver.info.iterations),
        }
    }
    Err(TensionError::ReferenceFailed {
        status: match last.0 {
            SolverStatus::MaxIterations => "max_iterations",
            SolverStatus::MaxTime => "max_time",
            SolverStatus::NumericalError => "numerical_error",
            SolverStatus::InsufficientProgress => "insufficient_progress",
            SolverStatus::DualInfeasible | SolverStatus::AlmostDualInfeasible => "dual_infeasible",
            _ => "unsolved",
        },
        iterations: last.1,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    fn geom(s: &Scene, p: Vector3<f64>) -> Geometry {
        let mut g = Geometry::new(s.n_cables());
        g.update(s.cables.iter().map(|c| &c.anchor_m), &p).unwrap();
        g
    }

    #[test]
    fn spatial_center_matches_closed_form() {
        let s = Scene::default_scene();
        let g = geom(&s, s.ee_position_m);
        let mut ts = TensionSolver::new(8, TensionParams::default());
        let t = ts.solve(&g, &s.wrench_n(), 60.0, 350.0).unwrap().to_vec();
        let upper = 60.0 + 30.0 * 9.81 * 3f64.sqrt() / 4.0;
        for i in 0..4 {
            assert!((t[i] - upper).abs() < 1e-9 * upper, "{t:?}");
            assert!((t[i + 4] - 60.0).abs() < 1e-9 * 60.0, "{t:?}");
        }
        let r = clarabel_reference(&g, &s.wrench_n(), 60.0, 350.0).unwrap();
        for i in 0..8 {
            assert!((r[i] - t[i]).abs() < 1e-9 * t[i], "{r:?} vs {t:?}");
        }
    }

    #[test]
    fn planar_center_all_at_tmin() {
        let s = Scene::planar_paper();
        let g = geom(&s, s.ee_position_m);
        let mut ts = TensionSolver::new(4, TensionParams::default());
        let t = ts.solve(&g, &s.wrench_n(), 20.0, 250.0).unwrap().to_vec();
        assert!(t.iter().all(|x| (x - 20.0).abs() < 1e-12), "{t:?}");
        assert_eq!(ts.info().rank, 2);
    }

    #[test]
    fn infeasible_reports_component() {
        let s = Scene::default_scene();
        let g = geom(&s, s.ee_position_m);
        let mut ts = TensionSolver::new(8, TensionParams::default());
        // 20 t of payload cannot be carried with t_max = 350 N.
        let w = Vector3::new(0.0, 0.0, -20000.0 * 9.81);
        let e = ts.solve(&g, &w, 60.0, 350.0).unwrap_err();
        match e {
            TensionError::Infeasible {
                worst_component, ..
            } => assert_eq!(worst_component, 2),
            _ => panic!("{e}"),
        }
        assert!(e.to_string().contains("f_z"), "{e}");
        let e2 = clarabel_reference(&g, &w, 60.0, 350.0).unwrap_err();
        assert!(matches!(e2, TensionError::Infeasible { .. }));
        assert!(matches!(
            ts.solve(&g, &s.wrench_n(), 400.0, 350.0),
            Err(TensionError::InvalidBounds { .. })
        ));
    }
}
