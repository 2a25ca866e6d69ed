//! The Newton–KKT step of the SQP on an active set (the step of
//! [`super::SagTensionSolver`] when the active set is settled).
//!
//! At tensions T the equilibrium map F(T) = Σ_i f_i(T_i) − w, f_i(T_i) = T_i a_i(T_i), is
//! linearised with the columns b_i = df_i/dT_i = a_i + T_i a_i′ (a_i the column (t_i, r_i × t_i)
//! of cable i's end tangent, a_i′ its derivative with the cable's own tension). The
//! subproblem of the SQP is
//!
//! ```text
//!   minimise Σ_i (T_i Δ_i + ½ D_i Δ_i²)   subject to   F(T) + Σ_i b_i Δ_i = 0,   lo ≤ T + Δ ≤ hi
//! ```
//!
//! with D_i > 0 the diagonal Hessian of the Lagrangian ½‖T‖² − λᵀF(T) (exactly diagonal:
//! each f_i depends on T_i alone), D_i = 1 − λ·b_i′. On a given active set (cables on a
//! bound keep Δ_i = bound − T_i), the free cables' Δ_i = (b_i·λ − T_i)/D_i, and λ solves the
//! 6 × 6 system (Σ_F b_i b_iᵀ/D_i) λ = −F(T) − Σ_B b_i Δ_i + Σ_F b_i T_i/D_i. The active
//! set is corrected until the step is the subproblem's KKT point: free cables inside their
//! bounds and the bound multipliers ν_i = T_i + D_i Δ_i − b_i·λ of the right sign (≥ 0 at
//! T_min, ≤ 0 at T_max). Rows of the columns that are zero for every cable (the moment rows of a point
//! mass) are left out (λ = 0 there).

use crate::tension::Bound;
use nalgebra::{Matrix6, Vector6};

/// A row whose entries are all below this fraction of the largest entry is a zero row.
const ZERO_ROW_REL: f64 = 1e-14;

/// One cable's data for the step.
#[derive(Debug, Clone, Copy)]
pub(super) struct KktCable {
    /// b_i = df_i/dT_i: (t_i + T_i t_i′, r_i × (t_i + T_i t_i′)).
    pub(super) b: Vector6<f64>,
    /// T_i, N.
    pub(super) t_n: f64,
    /// D_i > 0, the Hessian's diagonal entry.
    pub(super) d: f64,
    /// Which bound the cable is on (Free: Δ_i from λ).
    pub(super) bound: Bound,
}

impl KktCable {
    /// A free cable with D = 1 and zero columns (buffer fill).
    pub(super) fn blank() -> KktCable {
        KktCable {
            b: Vector6::zeros(),
            t_n: 0.0,
            d: 1.0,
            bound: Bound::Free,
        }
    }
}

/// The subproblem's answer by a primal-dual active-set loop started from the cables' bounds
/// (the D = I subproblem's active set): the step on the current set ([`step_on_set`]); a
/// free cable out of its bounds by more than `tol_n` is put on that bound (the farthest
/// first), else a bound cable whose multiplier has the wrong sign by more than `tol_n` is
/// freed (the worst first); at most 2n + 2 sets. New tensions into `out` (N) and λ, or None
/// (a singular system, or no set within the budget). `residual` is F(T) (N, N·m).
pub(super) fn kkt_step(
    cables: &mut [KktCable],
    residual: &Vector6<f64>,
    lo: &[f64],
    hi: &[f64],
    tol_n: f64,
    out: &mut [f64],
) -> Option<Vector6<f64>> {
    let n = cables.len();
    for _ in 0..2 * n + 2 {
        let lambda = step_on_set(cables, residual, lo, hi, out)?;
        // Primal: the free cable farthest out of its bounds.
        let mut worst: Option<(usize, f64)> = None;
        for (i, c) in cables.iter().enumerate() {
            if c.bound == Bound::Free {
                let v = (lo[i] - out[i]).max(out[i] - hi[i]);
                if v > tol_n && worst.is_none_or(|(_, w)| v > w) {
                    worst = Some((i, v));
                }
            }
        }
        if let Some((i, _)) = worst {
            cables[i].bound = if out[i] < lo[i] {
                Bound::Lower
            } else {
                Bound::Upper
            };
            continue;
        }
        // Dual: the bound multiplier of the most wrong sign.
        for (i, c) in cables.iter().enumerate() {
            let nu = c.t_n + c.d * (out[i] - c.t_n) - c.b.dot(&lambda);
            let v = match c.bound {
                Bound::Free => continue,
                Bound::Lower => -nu,
                Bound::Upper => nu,
            };
            if v > tol_n && worst.is_none_or(|(_, w)| v > w) {
                worst = Some((i, v));
            }
        }
        if let Some((i, _)) = worst {
            cables[i].bound = Bound::Free;
            continue;
        }
        for (i, o) in out.iter_mut().enumerate() {
            *o = o.clamp(lo[i], hi[i]);
        }
        return Some(lambda);
    }
    None
}

/// The step on the cables' current active set: new tensions into `out` (N, unclamped) and
/// λ; None when the system is singular.
fn step_on_set(
    cables: &[KktCable],
    residual: &Vector6<f64>,
    lo: &[f64],
    hi: &[f64],
    out: &mut [f64],
) -> Option<Vector6<f64>> {
    let rows = nonzero_rows(cables);
    let mut m = Matrix6::<f64>::zeros();
    let mut rhs = -residual;
    for (i, c) in cables.iter().enumerate() {
        match c.bound {
            Bound::Free => {
                m += c.b * c.b.transpose() / c.d;
                rhs += c.b * (c.t_n / c.d);
            }
            Bound::Lower => rhs -= c.b * (lo[i] - c.t_n),
            Bound::Upper => rhs -= c.b * (hi[i] - c.t_n),
        }
    }
    let lambda = solve_on_rows(m, rhs, &rows)?;
    for (i, (c, o)) in cables.iter().zip(out.iter_mut()).enumerate() {
        *o = match c.bound {
            Bound::Free => c.t_n + (c.b.dot(&lambda) - c.t_n) / c.d,
            Bound::Lower => lo[i],
            Bound::Upper => hi[i],
        };
    }
    Some(lambda)
}

/// The multipliers of the subproblem with D = I at its answer `t_new` (N): the least-squares
/// λ of t_new,F = B_Fᵀ λ over the free cables; None when singular.
pub(super) fn multiplier_of(cables: &[KktCable], t_new: &[f64]) -> Option<Vector6<f64>> {
    let rows = nonzero_rows(cables);
    let mut g = Matrix6::<f64>::zeros();
    let mut rhs = Vector6::zeros();
    for (c, t) in cables.iter().zip(t_new) {
        if c.bound == Bound::Free {
            g += c.b * c.b.transpose();
            rhs += c.b * *t;
        }
    }
    solve_on_rows(g, rhs, &rows)
}

/// Which of the six rows carry an entry of some cable's column.
fn nonzero_rows(cables: &[KktCable]) -> [bool; 6] {
    let scale = cables.iter().map(|c| c.b.amax()).fold(0.0, f64::max);
    let mut rows = [false; 6];
    for (r, keep) in rows.iter_mut().enumerate() {
        *keep = cables.iter().any(|c| c.b[r].abs() > ZERO_ROW_REL * scale);
    }
    rows
}

/// Solve m x = rhs on the kept rows and columns (x = 0 on the others) by full-pivot LU.
fn solve_on_rows(
    mut m: Matrix6<f64>,
    mut rhs: Vector6<f64>,
    rows: &[bool; 6],
) -> Option<Vector6<f64>> {
    for (r, &keep) in rows.iter().enumerate() {
        if !keep {
            m.row_mut(r).fill(0.0);
            m.column_mut(r).fill(0.0);
            m[(r, r)] = 1.0;
            rhs[r] = 0.0;
        }
    }
    let x = m.full_piv_lu().solve(&rhs)?;
    x.iter().all(|v| v.is_finite()).then_some(x)
}
