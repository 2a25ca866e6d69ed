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
/// Distances to a bound (relative to max(1 N, the problem's scale: the upper bounds kept
/// and the load)) under which Clarabel's answer is
/// taken to sit on that bound, loosest first: an interior-point answer stays about its
/// tolerance away from the bounds it touches.
const BOUND_DETECTION_REL: [f64; 3] = [1e-5, 1e-7, 1e-9];
/// Floor of the unknowns' scale and of the load in the equilibrium check (0 would divide
/// by zero).
const SCALE_FLOOR: f64 = 1e-300;
/// An upper bound at least this many times the problem's force scale (the largest of 1 N,
/// the lower bounds and the wrench's components) is left out of the QP. Such a bound
/// (CASPR writes force_max = 9999999999 N for "unbounded") is not reached unless the
/// tensions are a million times the load, and kept in the QP it sets the scale of every
/// tolerance: at 1e10 N, a 1e-9 relative test accepts a 10 N error. Leaving it out is
/// exact when the answer respects it (the relaxed problem's optimum is then the full
/// one's); the check of the answer verifies that, and the full problem is solved if not.
pub const UNBOUNDED_T_MAX_RATIO: f64 = 1e6;
/// Equilibrium check of every answer: ‖A T − w‖∞ at most this fraction of the load (the
/// polished answers are exact to ~1e-14; Clarabel's unpolished default-tolerance answer,
/// feasibility 1e-8, passes with room).
pub const EQUILIBRIUM_CHECK_REL: f64 = 1e-7;
/// Bound check of every answer: T_i within its bounds to this fraction of the force scale
/// (the answers are clamped to the bounds, so any excess is a defect).
const BOUND_CHECK_REL: f64 = 1e-9;

/// Reference solution with Clarabel (interior point), built fresh per call: tolerances 1e-13,
/// then with the unknowns scaled by the largest upper bound kept (see
/// [`UNBOUNDED_T_MAX_RATIO`]), then Clarabel's defaults, until it solves or
/// certifies infeasibility; the solution is polished by solving the KKT system of the
/// active set Clarabel found (kept only if optimal). Allocates; for tests, `analyze` and
/// cross-checks, not the real-time path. Infeasibility is reported with the same
/// closest-solution analysis as [`TensionSolver`]; an answer that does not balance the
/// wrench or leaves a bound is an error, never returned ([`clarabel_reference_bounds`]).
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
///
/// Upper bounds at least [`UNBOUNDED_T_MAX_RATIO`] times the problem's force scale are left
/// out of the QP (see there). Every answer is checked before it is returned: A T = w to
/// [`EQUILIBRIUM_CHECK_REL`] of the load and every T_i within its own bounds; an answer that
/// fails is never returned ([`TensionError::ReferenceRejected`]).
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
    let force_scale = force_scale_n(w_n, t_min_n);
    let relaxed: Vec<bool> = t_max_n
        .iter()
        .map(|&h| h < UNBOUNDED_T_MAX_RATIO * force_scale)
        .collect();
    let all = vec![true; n];
    // The relaxed problem first when it drops a bound; the full one if its answer fails.
    let uppers: Vec<&[bool]> = if relaxed.iter().all(|&b| b) {
        vec![&all]
    } else {
        vec![&relaxed, &all]
    };
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
    let mut last = Err(TensionError::ReferenceFailed {
        status: status_name(SolverStatus::Unsolved),
        iterations: 0,
    });
    for upper in uppers {
        // The scale of the unknowns and of the tolerances: the bounds kept and the load.
        let scale = (0..n)
            .filter(|&i| upper[i])
            .map(|i| t_max_n[i])
            .fold(force_scale, f64::max)
            .max(SCALE_FLOOR);
        // Attempts: the problem as posed with tight tolerances; then with the unknowns
        // scaled (x = T / scale) so the tolerances are relative; then Clarabel's defaults.
        for (unknowns, settings) in [
            (1.0, strict.clone()),
            (scale, strict.clone()),
            (scale, loose.clone()),
        ] {
            let problem = Problem {
                g,
                w_n,
                rows: &rows,
                t_min_n,
                t_max_n,
                upper,
                unknowns,
                scale,
            };
            let mut solver = problem.solver(settings)?;
            solver.solve();
            match solver.solution.status {
                SolverStatus::Solved | SolverStatus::AlmostSolved => {
                    let t = problem.polish(&solver.solution.x);
                    match check(g, w_n, &t, t_min_n, t_max_n, force_scale) {
                        Ok(()) => return Ok(t),
                        Err(e) => last = Err(e),
                    }
                }
                SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
                    // The relaxed problem's feasible set contains the full one's.
                    return Err(TensionSolver::closest_for(n, g, w_n, t_min_n, t_max_n));
                }
                other => {
                    if !matches!(last, Err(TensionError::ReferenceRejected { .. })) {
                        last = Err(TensionError::ReferenceFailed {
                            status: status_name(other),
                            iterations: solver.info.iterations,
                        });
                    }
                }
            }
        }
    }
    last
}

/// The problem's force scale, N: the largest of 1 N, the lower bounds and the wrench's
/// components (N and N·m).
fn force_scale_n(w_n: &[f64; 6], t_min_n: &[f64]) -> f64 {
    w_n.iter()
        .map(|x| x.abs())
        .chain(t_min_n.iter().copied())
        .fold(1.0, f64::max)
}

/// The check of an answer: equilibrium ‖A T − w‖∞ ≤ [`EQUILIBRIUM_CHECK_REL`] ×
/// max(‖w‖∞, max_r Σ_i |a_ri T_i|) (the load and the largest row of cable forces: rows in
/// N and N·m, each compared with its own kind), and t_min_i − tol ≤ T_i ≤ t_max_i + tol with
/// tol = [`BOUND_CHECK_REL`] × `force_scale_n`.
fn check(
    g: &Geometry,
    w_n: &[f64; 6],
    t: &[f64],
    t_min_n: &[f64],
    t_max_n: &[f64],
    force_scale_n: f64,
) -> Result<(), TensionError> {
    let n = g.n();
    let mut residual = 0.0_f64;
    let mut load = 0.0_f64;
    for (r, w) in w_n.iter().enumerate() {
        let f: f64 = (0..n).map(|i| g.a(r, i) * t[i]).sum();
        let size: f64 = (0..n).map(|i| (g.a(r, i) * t[i]).abs()).sum();
        residual = residual.max((f - w).abs());
        load = load.max(w.abs()).max(size);
    }
    let residual_rel = residual / load.max(SCALE_FLOOR);
    let tol = BOUND_CHECK_REL * force_scale_n;
    let bound_violation_n = (0..n)
        .map(|i| (t_min_n[i] - t[i]).max(t[i] - t_max_n[i]))
        .fold(0.0, f64::max);
    let finite = t.iter().all(|x| x.is_finite());
    if finite && residual_rel <= EQUILIBRIUM_CHECK_REL && bound_violation_n <= tol {
        Ok(())
    } else {
        Err(TensionError::ReferenceRejected {
            residual_rel: if finite { residual_rel } else { f64::NAN },
            tol_rel: EQUILIBRIUM_CHECK_REL,
            bound_violation_n,
        })
    }
}

/// One attempt's problem: rows `rows` of A T = w, the bounds (the upper ones where `upper`
/// is true), unknowns x = T / `unknowns`.
struct Problem<'a> {
    g: &'a Geometry,
    w_n: &'a [f64; 6],
    rows: &'a [usize],
    /// Per-cable lower bounds, N.
    t_min_n: &'a [f64],
    /// Per-cable upper bounds, N.
    t_max_n: &'a [f64],
    /// Which upper bounds are in the QP (the others are far above the load).
    upper: &'a [bool],
    /// Scale of the unknowns, N.
    unknowns: f64,
    /// Scale of the bound-detection tolerances, N: the bounds kept and the load.
    scale: f64,
}

impl Problem<'_> {
    /// Clarabel's solver for min ½‖x‖² s.t. A x = w / s, x ≤ t_max / s (the kept upper
    /// bounds), −x ≤ −t_min / s, with s = `unknowns`.
    fn solver(&self, settings: DefaultSettings<f64>) -> Result<DefaultSolver<f64>, TensionError> {
        let (g, w_n, rows, s) = (self.g, self.w_n, self.rows, self.unknowns);
        let (t_min_n, t_max_n) = (self.t_min_n, self.t_max_n);
        let n = g.n();
        let m_eq = rows.len();
        let uppers: Vec<usize> = (0..n).filter(|&i| self.upper[i]).collect();
        let m = m_eq + uppers.len() + n;
        let mut dense = vec![vec![0.0; n]; m];
        let mut b = vec![0.0; m];
        for (k, &r) in rows.iter().enumerate() {
            for i in 0..n {
                dense[k][i] = g.a(r, i);
            }
            b[k] = w_n[r] / s;
        }
        for (k, &i) in uppers.iter().enumerate() {
            dense[m_eq + k][i] = 1.0; // x_i + s = t_max / s
            b[m_eq + k] = t_max_n[i] / s;
        }
        let lower = m_eq + uppers.len();
        for i in 0..n {
            dense[lower + i][i] = -1.0; // −x_i + s = −t_min / s
            b[lower + i] = -t_min_n[i] / s;
        }
        let a = CscMatrix::from(&dense);
        let p = CscMatrix::identity(n);
        let q = vec![0.0; n];
        let cones = [ZeroConeT(m_eq), NonnegativeConeT(uppers.len() + n)];
        DefaultSolver::new(&p, &q, &a, &b, &cones, settings).map_err(|_| TensionError::NonFinite)
    }

    /// Clarabel's solution `x` in N, polished: Clarabel's active set, solved exactly
    /// (interior-point answers sit ~tolerance away from the bounds they touch). The first
    /// bound-detection threshold whose KKT solution is optimal wins; else Clarabel's answer.
    fn polish(&self, x: &[f64]) -> Vec<f64> {
        let (g, w_n) = (self.g, self.w_n);
        let (t_min_n, t_max_n) = (self.t_min_n, self.t_max_n);
        let n = g.n();
        let x: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, x)| (x * self.unknowns).clamp(t_min_n[i], t_max_n[i]))
            .collect();
        let mut s = TensionSolver::new(n, TensionParams::default());
        for rel in BOUND_DETECTION_REL {
            let delta = rel * self.scale.max(1.0);
            let pattern: Vec<Bound> = x
                .iter()
                .enumerate()
                .map(|(i, &t)| {
                    if t <= t_min_n[i] + delta {
                        Bound::Lower
                    } else if self.upper[i] && t >= t_max_n[i] - delta {
                        Bound::Upper
                    } else {
                        Bound::Free
                    }
                })
                .collect();
            if let Some(t) = s.polish(g, w_n, t_min_n, t_max_n, &pattern, self.scale) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    /// The check refuses an answer that does not balance the wrench (every cable at T_min
    /// where the load needs more: the answer once printed for CASPR's "unbounded" bounds)
    /// or leaves its bounds, and accepts the active-set solver's answer.
    #[test]
    fn check_refuses_unbalanced_or_out_of_bounds_answers() {
        let s = Scene::default_scene();
        let mut g = Geometry::new(s.n_cables());
        g.update(
            s.cables.iter().map(|c| &c.anchor_m),
            &Vector3::new(0.3, 0.2, 1.0),
        )
        .unwrap();
        let w = s.wrench_n();
        let w6 = s.wrench6_n();
        let n = s.n_cables();
        let (lo, hi) = (vec![60.0; n], vec![350.0; n]);
        let mut ts = TensionSolver::new(n, TensionParams::default());
        let good = ts.solve(&g, &w, 60.0, 350.0).unwrap().to_vec();
        let scale = force_scale_n(&w6, &lo);
        assert!(check(&g, &w6, &good, &lo, &hi, scale).is_ok());
        let e = check(&g, &w6, &lo, &lo, &hi, scale).unwrap_err();
        assert!(
            matches!(e, TensionError::ReferenceRejected { residual_rel, .. } if residual_rel > 1e-3),
            "{e}"
        );
        let mut out = good.clone();
        out[0] = 350.0 + 1e-3;
        assert!(check(&g, &w6, &out, &lo, &hi, scale).is_err());
        let mut nan = good;
        nan[1] = f64::NAN;
        assert!(check(&g, &w6, &nan, &lo, &hi, scale).is_err());
    }
}
