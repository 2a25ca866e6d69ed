//! Tension distribution: the QP of paper Eqs. 9-11 with C = I, c = 0,
//!
//! ```text
//!     minimise ½‖T‖²   subject to   A T = w,   T_min,i ≤ T_i ≤ T_max,i,
//! ```
//!
//! The bounds are per cable ([`TensionSolver::solve_wrench_bounds`],
//! [`clarabel_reference_bounds`]); [`TensionSolver::solve_wrench`] is the common case of one
//! T_min and one T_max for every cable.
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
//! real-time solver), `reference` (the Clarabel reference) and `sagged` (the same QP
//! with sagging cables: each chord direction replaced by its catenary's end tangent,
//! [`SagTensionSolver`]).

mod active_set;
mod error;
mod info;
mod params;
mod reference;
mod sagged;

pub use active_set::TensionSolver;
pub use error::TensionError;
pub use info::{Bound, TensionInfo};
pub use params::TensionParams;
pub use reference::{
    clarabel_reference, clarabel_reference_bounds, clarabel_reference_wrench,
    EQUILIBRIUM_CHECK_REL, UNBOUNDED_T_MAX_RATIO,
};
pub use sagged::{SagCable, SagTensionError, SagTensionInfo, SagTensionParams, SagTensionSolver};

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

    /// Per-cable lower bounds: every tension at or above its own cable's bound, equal to the
    /// Clarabel reference with the same bounds to 1e-9 relative, at poses where the raised
    /// bounds are active; equal per-cable values give the uniform solve bit for bit.
    #[test]
    fn per_cable_lower_bounds_match_the_reference() {
        let s = Scene::default_scene();
        let n = s.n_cables();
        let lo: Vec<f64> = (0..n)
            .map(|i| if i % 2 == 1 { 100.0 } else { 10.0 })
            .collect();
        let hi = vec![s.t_max_n; n];
        let w6 = s.wrench6_n();
        let mut ts = TensionSolver::new(n, TensionParams::default());
        let mut active_raised = 0;
        for p in [
            s.ee_position_m,
            Vector3::new(0.3, 0.2, 1.0),
            Vector3::new(-0.5, 0.4, 1.4),
            Vector3::new(0.6, -0.6, 0.8),
        ] {
            let g = geom(&s, p);
            let t = ts.solve_wrench_bounds(&g, &w6, &lo, &hi).unwrap().to_vec();
            let r = clarabel_reference_bounds(&g, &w6, &lo, &hi).unwrap();
            for i in 0..n {
                assert!(t[i] >= lo[i], "{p:?}: cable {i} {} < {}", t[i], lo[i]);
                assert!(
                    (t[i] - r[i]).abs() <= 1e-9 * r[i],
                    "{p:?}: cable {i}: {} vs Clarabel {}",
                    t[i],
                    r[i]
                );
                active_raised += (lo[i] == 100.0 && t[i] == 100.0) as usize;
            }
            assert_eq!(ts.lower_bounds_n(), &lo[..]);
            let mut uniform = TensionSolver::new(n, TensionParams::default());
            let u = uniform
                .solve_wrench(&g, &w6, 60.0, s.t_max_n)
                .unwrap()
                .to_vec();
            let mut same = TensionSolver::new(n, TensionParams::default());
            let v = same
                .solve_wrench_bounds(&g, &w6, &vec![60.0; n], &hi)
                .unwrap()
                .to_vec();
            let bits = |x: &[f64]| x.iter().map(|t| t.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(&u),
                bits(&v),
                "{p:?}: uniform slices are the uniform solve"
            );
        }
        assert!(active_raised > 0, "the raised bounds were never active");
        let g = geom(&s, s.ee_position_m);
        assert!(matches!(
            ts.solve_wrench_bounds(&g, &w6, &lo[..n - 1], &hi),
            Err(TensionError::InvalidBounds { .. })
        ));
        let mut bad = lo.clone();
        bad[3] = 400.0;
        assert!(matches!(
            ts.solve_wrench_bounds(&g, &w6, &bad, &hi),
            Err(TensionError::InvalidBounds { t_min_n, .. }) if t_min_n == 400.0
        ));
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
