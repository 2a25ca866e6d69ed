//! Tension distribution: the QP of paper Eqs. 9-11 with C = I, c = 0,
//!
//! ```text
//!     minimise ½‖T‖²   subject to   A T = w,   T_min ≤ T_i ≤ T_max,
//! ```
//!
//! with A the structure matrix of [`crate::kinematics`] (3 × n force rows; 6 × n with the
//! moment rows of a rigid end-effector), w the wrench (N, N·m) and T the tensions (N).
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
//!
//! Files: `params`, `info` and `error` (the types a caller sees), `active_set` (the
//! real-time solver) and `reference` (the Clarabel reference).

mod active_set;
mod error;
mod info;
mod params;
mod reference;

pub use active_set::TensionSolver;
pub use error::TensionError;
pub use info::{Bound, TensionInfo};
pub use params::TensionParams;
pub use reference::{clarabel_reference, clarabel_reference_wrench};

/// Largest number of equality rows: force (3) and moment (3).
const M: usize = 6;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::Geometry;
    use crate::scene::Scene;
    use nalgebra::Vector3;

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
