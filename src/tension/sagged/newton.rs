//! Newton's step on the fixed point's optimality system, the active set held (the
//! accelerator of [`super::SagTensionSolver`]'s passes).
//!
//! A fixed point T = QP(A(T)) with free cables F and cables B on a bound satisfies, with
//! the QP's multipliers μ (one per wrench row) and a_i(T_i) cable i's column of A (world end
//! tangent t_i and r_i × t_i), both of which depend on its own tension only:
//!
//! ```text
//!   r₁,i = T_i − a_i(T_i)·μ = 0   (i ∈ F: stationarity of ½‖T‖² − μᵀ(A T − w))
//!   r₂   = Σ_i a_i(T_i) T_i − w = 0   (equilibrium, every cable)
//! ```
//!
//! With a_i′ = dφ_i/dT_i (−s h_i + c up, r_i × …) the derivative of the column (φ_i the
//! end tangent's angle above the horizontal, c, s its cosine and sine), d_i = 1 − a_i′·μ and
//! b_i = a_i + a_i′ T_i, Newton's step is ΔT_i = (a_i·Δμ − r₁,i)/d_i (i ∈ F, ΔT = 0 on B)
//! and, from the equilibrium row, the 6 × 6 system
//!
//! ```text
//!   (Σ_F b_i a_iᵀ / d_i) Δμ = −r₂ + Σ_F b_i r₁,i / d_i.
//! ```
//!
//! Rows of A that are zero for every cable (the moment rows of a point mass, the
//! out-of-plane rows of a planar robot) are left out (Δμ = 0 there). The start μ is the
//! least-squares multiplier of T_F on the current columns. Near the solution the step
//! converges quadratically where the plain passes contract linearly (by a factor of 0.3 to
//! 0.6 per pass on sagging robots) or not at all: with a very slack cable d_i turns
//! negative (its tangent turns so fast with its tension that the plain passes move away
//! from the fixed point), and Newton's step still reaches it. It is only proposed: the
//! caller takes it when every |d_i| is safely above zero, and the next QP pass decides the
//! active set and convergence as before.
//!
//! **Active set of the step.** Because a_i turns with T_i, the fixed point need not be
//! unique, and it can vanish: as the pose moves, a free cable's fixed point can meet a
//! second one and disappear (a fold, where d_i → 0), and only the solution with that cable
//! on its bound is left. Newton's step with the cable held free then hops around the
//! vanished root and the passes never settle. So (`newton_step_bounded`) a free cable the
//! step would take out of its bounds is put on that bound and the step recomputed; and
//! after a pass that did not contract, the free cable nearest a fold (smallest |d_i|, when
//! below `FOLD_DIAGONAL`, `fold_candidate`) is put on its nearer bound before the step.
//! Either guess is only a start: the QP pass after it frees the cable again if its bound
//! was wrong.

use crate::tension::Bound;
use nalgebra::{Matrix6, Vector3, Vector6};

/// A row of A whose entries are all below this fraction of the largest entry is a zero row.
const ZERO_ROW_REL: f64 = 1e-14;
/// |d_i| = |1 − a_i′·μ| below this: the step is not defined (the cable's turn with its
/// tension cancels its stationarity row). d_i < 0 is allowed: there the plain passes are
/// unstable (they move away from the fixed point by the factor 1/|d_i| − … per pass) and
/// only Newton's step reaches it.
const MIN_DIAGONAL: f64 = 1e-3;
/// A free cable counts as near a fold when |d_i| is below this (d_i → 0 at the fold; a
/// cable whose tangent barely turns with its tension has d_i ≈ 1).
const FOLD_DIAGONAL: f64 = 0.5;

/// One cable's data for the step: its column, the column's derivative with its tension,
/// its tension and whether it is free.
#[derive(Debug, Clone, Copy)]
pub(super) struct NewtonCable {
    /// a_i: (t_i, r_i × t_i).
    pub(super) a: Vector6<f64>,
    /// da_i/dT_i, 1/N.
    pub(super) da: Vector6<f64>,
    /// T_i, N.
    pub(super) t_n: f64,
    /// Which bound the QP put it on.
    pub(super) bound: Bound,
}

impl NewtonCable {
    /// Cable data from its end tangent `t`, the tangent's turn `dt_dt` (1/N), its arm and
    /// tension.
    pub(super) fn new(
        t: &Vector3<f64>,
        dt_dt: &Vector3<f64>,
        arm_m: &Vector3<f64>,
        t_n: f64,
        bound: Bound,
    ) -> NewtonCable {
        let m = arm_m.cross(t);
        let dm = arm_m.cross(dt_dt);
        NewtonCable {
            a: Vector6::new(t.x, t.y, t.z, m.x, m.y, m.z),
            da: Vector6::new(dt_dt.x, dt_dt.y, dt_dt.z, dm.x, dm.y, dm.z),
            t_n,
            bound,
        }
    }
}

/// Newton's new tensions for `cables` and wrench `w` into `out` (N); false when the step is
/// not defined (a singular system, a small d_i or a non-finite value): the caller keeps the
/// plain pass.
pub(super) fn newton_step(cables: &[NewtonCable], w: &[f64; 6], out: &mut [f64]) -> bool {
    let rows = nonzero_rows(cables);
    let Some(mu) = least_squares_multiplier(cables, &rows) else {
        return false;
    };
    let mut m = Matrix6::<f64>::zeros();
    let mut rhs = -Vector6::from_column_slice(w);
    for c in cables {
        rhs += c.a * c.t_n;
    }
    rhs = -rhs;
    for c in cables.iter().filter(|c| c.bound == Bound::Free) {
        let d = 1.0 - c.da.dot(&mu);
        if !(d.abs() >= MIN_DIAGONAL) {
            return false;
        }
        let b = c.a + c.da * c.t_n;
        let r1 = c.t_n - c.a.dot(&mu);
        m += b * c.a.transpose() / d;
        rhs += b * (r1 / d);
    }
    let Some(dmu) = solve_on_rows(m, rhs, &rows) else {
        return false;
    };
    for (c, o) in cables.iter().zip(out.iter_mut()) {
        *o = match c.bound {
            Bound::Free => {
                let d = 1.0 - c.da.dot(&mu);
                c.t_n + (c.a.dot(&dmu) - (c.t_n - c.a.dot(&mu))) / d
            }
            _ => c.t_n,
        };
    }
    out.iter().all(|t| t.is_finite())
}

/// Newton's step with its active set corrected: while the step takes free cables out of
/// their bounds (`lo`, `hi`, N), the cable that goes farthest out (N) is put on that
/// bound (its tension set to it) and the step is recomputed, at most once per
/// cable. Where a cable's tangent turns with its tension, the fixed points on either side of
/// a bound can both exist or neither; this step lands on the bound instead of leaving the
/// passes to hop between the two active sets. False as [`newton_step`] or when no active
/// set within the flips keeps every free cable inside its bounds.
pub(super) fn newton_step_bounded(
    cables: &mut [NewtonCable],
    w: &[f64; 6],
    lo: &[f64],
    hi: &[f64],
    out: &mut [f64],
) -> bool {
    for _ in 0..=cables.len() {
        if !newton_step(cables, w, out) {
            return false;
        }
        let worst = (0..cables.len())
            .filter(|&i| cables[i].bound == Bound::Free)
            .map(|i| (i, (lo[i] - out[i]).max(out[i] - hi[i])))
            .filter(|&(_, v)| v >= 0.0)
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((i, _)) = worst else {
            return true;
        };
        let below = out[i] <= lo[i];
        cables[i].bound = if below { Bound::Lower } else { Bound::Upper };
        cables[i].t_n = if below { lo[i] } else { hi[i] };
    }
    false
}

/// The free cable nearest a fold of the fixed point: the smallest |d_i| = |1 − a_i′·μ| at
/// the least-squares multiplier μ of the free tensions, when it is below [`FOLD_DIAGONAL`].
/// None without such a cable or a multiplier.
pub(super) fn fold_candidate(cables: &[NewtonCable]) -> Option<usize> {
    let rows = nonzero_rows(cables);
    let mu = least_squares_multiplier(cables, &rows)?;
    (0..cables.len())
        .filter(|&i| cables[i].bound == Bound::Free)
        .map(|i| (i, (1.0 - cables[i].da.dot(&mu)).abs()))
        .filter(|&(_, d)| d < FOLD_DIAGONAL)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// Which of the six rows carry an entry of some cable's column.
fn nonzero_rows(cables: &[NewtonCable]) -> [bool; 6] {
    let scale = cables.iter().map(|c| c.a.amax()).fold(0.0, f64::max);
    let mut rows = [false; 6];
    for (r, keep) in rows.iter_mut().enumerate() {
        *keep = cables.iter().any(|c| c.a[r].abs() > ZERO_ROW_REL * scale);
    }
    rows
}

/// μ minimising ‖T_F − A_Fᵀ μ‖ on the kept rows: (A_F A_Fᵀ) μ = A_F T_F.
fn least_squares_multiplier(cables: &[NewtonCable], rows: &[bool; 6]) -> Option<Vector6<f64>> {
    let mut g = Matrix6::<f64>::zeros();
    let mut rhs = Vector6::zeros();
    for c in cables.iter().filter(|c| c.bound == Bound::Free) {
        g += c.a * c.a.transpose();
        rhs += c.a * c.t_n;
    }
    solve_on_rows(g, rhs, rows)
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
