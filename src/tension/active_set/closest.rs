//! When the wrench is outside the feasible set: the closest achievable tensions, reported
//! with the infeasibility error.

use super::*;

impl TensionSolver {
    /// [`Self::closest_solution`] of a fresh solver for `n` cables and per-cable bounds
    /// t_min_n[i] ≤ T_i ≤ t_max_n[i] (N): the infeasibility report of
    /// [`super::clarabel_reference`].
    pub(in crate::tension) fn closest_for(
        n: usize,
        g: &Geometry,
        w_n: &[f64; 6],
        t_min_n: &[f64],
        t_max_n: &[f64],
    ) -> TensionError {
        let mut s = TensionSolver::new(n, TensionParams::default());
        s.lo[..n].copy_from_slice(t_min_n);
        s.hi[..n].copy_from_slice(t_max_n);
        s.closest_solution(g, w_n)
    }

    /// The closest achievable wrench: min ½‖A T − w‖² + ½ρ‖T‖² over the box, by a bounded
    /// number of projected-gradient (FISTA) steps. Leaves the tensions in `self.t`.
    pub(super) fn closest_solution(&mut self, g: &Geometry, w_n: &[f64; 6]) -> TensionError {
        let n = self.n;
        let (lo, hi) = (self.lo, self.hi);
        let (lo_min, hi_max) = (self.lo_min(), self.hi_max());
        // Lipschitz constant of the gradient: ‖A‖² ≤ trace(AᵀA) = Σ (1 + ‖r_i × s_i‖²).
        let rho = CLOSEST_REGULARISATION;
        let lip = (0..n)
            .map(|i| 1.0 + g.arm_m[i].cross(&g.unit[i]).norm_squared())
            .sum::<f64>()
            + rho;
        let wf = Vector3::new(w_n[0], w_n[1], w_n[2]);
        let wm = Vector3::new(w_n[3], w_n[4], w_n[5]);
        let mut x = [0.0; MAX_CABLES];
        for (i, v) in x.iter_mut().enumerate().take(n) {
            *v = 0.5 * (lo[i] + hi[i]);
        }
        let mut yv = x;
        let mut tk = 1.0f64;
        for _ in 0..CLOSEST_STEPS {
            let r = g.wrench_of(&yv[..n]) - wf;
            let rm = g.moment_of(&yv[..n]) - wm;
            let mut xn = [0.0; MAX_CABLES];
            for i in 0..n {
                let grad = g.unit[i].dot(&r) + g.arm_m[i].cross(&g.unit[i]).dot(&rm) + rho * yv[i];
                xn[i] = (yv[i] - grad / lip).clamp(lo[i], hi[i]);
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
        let mut up = 0u32;
        let mut dn = 0u32;
        for (i, &xi) in x.iter().enumerate().take(n) {
            let eps = CLOSEST_AT_BOUND_REL * (hi[i] - lo[i]).max(1.0);
            if xi >= hi[i] - eps {
                up |= 1 << i;
                self.bound[i] = Bound::Upper;
            } else if xi <= lo[i] + eps {
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
            t_min_n: lo_min,
            t_max_n: hi_max,
            per_cable_bounds: self.bounds_differ(),
        }
    }
}
