//! The reference solver: Clarabel's interior-point method with tight tolerances, built
//! fresh per call, its answer polished by the active-set solver's KKT solve.

use super::active_set::{bounds_are_valid, invalid_bounds};
use super::{Bound, TensionError, TensionParams, TensionSolver};
use crate::kinematics::Geometry;
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, ZeroConeT,
};
use nalgebra::Vector3;

/// A row of A whose entries are all at or below this is identically zero (a planar
/// robot's out-of-plane row, a point mass's moment rows) and is left out of the problem.
const ZERO_ROW_ENTRY: f64 = 1e-14;
/// A wrench component above this (N or N·m) on a left-out zero row cannot be produced:
/// infeasible, reported with the closest solution.
const ZERO_ROW_WRENCH: f64 = 1e-9;
/// Clarabel's gap and feasibility tolerances in the strict attempts (near double
/// precision: the polish then only snaps the active bounds).
const STRICT_TOL: f64 = 1e-13;
/// Clarabel's KKT-ratio tolerance in the strict attempts.
const STRICT_KTRATIO: f64 = 1e-10;
/// Iteration limit of the strict attempts.
const STRICT_MAX_ITER: u32 = 200;
/// Iteration limit of the last attempt with Clarabel's default tolerances.
const LOOSE_MAX_ITER: u32 = 400;
/// Distances to a bound (relative to max(1, T_max)) under which Clarabel's answer is
/// taken to sit on that bound, loosest first: an interior-point answer stays about its
/// tolerance away from the bounds it touches.
const BOUND_DETECTION_REL: [f64; 3] = [1e-5, 1e-7, 1e-9];
/// Floor of T_max as the unknowns' scale (T_max = 0 would divide by zero).
const SCALE_FLOOR: f64 = 1e-300;

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
    if !bounds_are_valid(t_min_n, t_max_n) {
        return Err(TensionError::InvalidBounds { t_min_n, t_max_n });
    }
    let n = g.n();
    clarabel_reference_bounds(g, w_n, &vec![t_min_n; n], &vec![t_max_n; n])
}

/// [`clarabel_reference_wrench`] with per-cable bounds `t_min_n[i] ≤ T_i ≤ t_max_n[i]` (N, one
/// value per cable): the reference of [`TensionSolver::solve_wrench_bounds`].
pub fn clarabel_reference_bounds(
    g: &Geometry,
    w_n: &[f64; 6],
    t_min_n: &[f64],
    t_max_n: &[f64],
) -> Result<Vec<f64>, TensionError> {
    let n = g.n();
    if let Some(e) = invalid_bounds(n, t_min_n, t_max_n) {
        return Err(e);
    }
    let t_max_scale = t_max_n.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !w_n.iter().all(|x| x.is_finite()) {
        return Err(TensionError::NonFinite);
    }
    // Equality rows that are not identically zero (a planar robot's normal row is; so are
    // a point mass's moment rows).
    let rows: Vec<usize> = (0..6)
        .filter(|&r| (0..n).any(|i| g.a(r, i).abs() > ZERO_ROW_ENTRY))
        .collect();
    for r in 0..6 {
        if !rows.contains(&r) && w_n[r].abs() > ZERO_ROW_WRENCH {
            return Err(TensionSolver::closest_for(n, g, w_n, t_min_n, t_max_n));
        }
    }
    let strict = DefaultSettings {
        verbose: false,
        tol_gap_abs: STRICT_TOL,
        tol_gap_rel: STRICT_TOL,
        tol_feas: STRICT_TOL,
        tol_ktratio: STRICT_KTRATIO,
        max_iter: STRICT_MAX_ITER,
        ..DefaultSettings::default()
    };
    let loose = DefaultSettings {
        verbose: false,
        max_iter: LOOSE_MAX_ITER,
        ..DefaultSettings::default()
    };
    // Attempts: the problem as posed with tight tolerances; then with the unknowns scaled by
    // T_max (x = T / T_max) so the tolerances are relative; then Clarabel's defaults.
    let mut last = (SolverStatus::Unsolved, 0u32);
    for (scale, settings) in [
        (1.0, strict.clone()),
        (t_max_scale.max(SCALE_FLOOR), strict),
        (t_max_scale.max(SCALE_FLOOR), loose),
    ] {
        let problem = Problem {
            g,
            w_n,
            rows: &rows,
            t_min_n,
            t_max_n,
            scale,
        };
        let mut solver = problem.solver(settings)?;
        solver.solve();
        match solver.solution.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => {
                return Ok(problem.polish(&solver.solution.x));
            }
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
                return Err(TensionSolver::closest_for(n, g, w_n, t_min_n, t_max_n));
            }
            other => last = (other, solver.info.iterations),
        }
    }
    Err(TensionError::ReferenceFailed {
        status: status_name(last.0),
        iterations: last.1,
    })
}

/// One attempt's problem: rows `rows` of A T = w, the bounds, unknowns x = T / `scale`.
struct Problem<'a> {
    g: &'a Geometry,
    w_n: &'a [f64; 6],
    rows: &'a [usize],
    /// Per-cable lower bounds, N.
    t_min_n: &'a [f64],
    /// Per-cable upper bounds, N.
    t_max_n: &'a [f64],
    scale: f64,
}

impl Problem<'_> {
    /// Clarabel's solver for min ½‖x‖² s.t. A x = w / scale, x ≤ t_max / scale,
    /// −x ≤ −t_min / scale.
    fn solver(&self, settings: DefaultSettings<f64>) -> Result<DefaultSolver<f64>, TensionError> {
        let (g, w_n, rows, scale) = (self.g, self.w_n, self.rows, self.scale);
        let (t_min_n, t_max_n) = (self.t_min_n, self.t_max_n);
        let n = g.n();
        let m_eq = rows.len();
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
            b[m_eq + i] = t_max_n[i] / scale;
            dense[m_eq + n + i][i] = -1.0; // −x_i + s = −t_min / scale
            b[m_eq + n + i] = -t_min_n[i] / scale;
        }
        let a = CscMatrix::from(&dense);
        let p = CscMatrix::identity(n);
        let q = vec![0.0; n];
        let cones = [ZeroConeT(m_eq), NonnegativeConeT(2 * n)];
        DefaultSolver::new(&p, &q, &a, &b, &cones, settings).map_err(|_| TensionError::NonFinite)
    }

    /// Clarabel's solution `x` in N, polished: Clarabel's active set, solved exactly
    /// (interior-point answers sit ~tolerance away from the bounds they touch). The first
    /// bound-detection threshold whose KKT solution is optimal wins; else Clarabel's answer.
    fn polish(&self, x: &[f64]) -> Vec<f64> {
        let (g, w_n, scale) = (self.g, self.w_n, self.scale);
        let (t_min_n, t_max_n) = (self.t_min_n, self.t_max_n);
        let n = g.n();
        let x: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, x)| (x * scale).clamp(t_min_n[i], t_max_n[i]))
            .collect();
        let t_max_scale = t_max_n.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mut s = TensionSolver::new(n, TensionParams::default());
        for rel in BOUND_DETECTION_REL {
            let delta = rel * t_max_scale.max(1.0);
            let pattern: Vec<Bound> = x
                .iter()
                .enumerate()
                .map(|(i, &t)| {
                    if t <= t_min_n[i] + delta {
                        Bound::Lower
                    } else if t >= t_max_n[i] - delta {
                        Bound::Upper
                    } else {
                        Bound::Free
                    }
                })
                .collect();
            if let Some(t) = s.polish(g, w_n, t_min_n, t_max_n, &pattern) {
                return t;
            }
        }
        x
    }
}

/// Clarabel's status as a name for [`TensionError::ReferenceFailed`].
fn status_name(status: SolverStatus) -> &'static str {
    match status {
        SolverStatus::MaxIterations => "max_iterations",
        SolverStatus::MaxTime => "max_time",
        SolverStatus::NumericalError => "numerical_error",
        SolverStatus::InsufficientProgress => "insufficient_progress",
        SolverStatus::DualInfeasible | SolverStatus::AlmostDualInfeasible => "dual_infeasible",
        _ => "unsolved",
    }
}
