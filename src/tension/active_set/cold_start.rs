//! The cold solve: from the minimum-norm solution of the equalities, add the most violated
//! bound until none is violated (Goldfarb-Idnani dual active set with H = I).

use super::*;

impl TensionSolver {
    /// Cold solve (Goldfarb-Idnani dual active set): from the minimum-norm solution of the
    /// equalities, add the most violated bound until none is violated beyond `tol` (N).
    pub(super) fn cold_solve(&mut self, tol: f64) -> Result<(), TensionError> {
        let mut x = self.cold_start()?;
        let mut scratch = StepScratch {
            np: [0.0; MAX_CABLES],
            z: [0.0; MAX_CABLES],
            rr: [0.0; MAX_CABLES + M],
        };
        let mut iters = 0u32;
        loop {
            let p = self.most_violated(&x, tol);
            if p == usize::MAX {
                break;
            }
            self.add_constraint(p, &mut x, &mut scratch, &mut iters)?;
        }
        self.info.iterations = iters;
        self.record_active_set(&x);
        Ok(())
    }

    /// Start of the cold solve: the equality rows active, x = Aᵀ (A Aᵀ)⁻¹ w (the
    /// minimum-norm solution of the equalities) and their multipliers in `u`.
    fn cold_start(&mut self) -> Result<[f64; MAX_CABLES], TensionError> {
        let n = self.n;
        let k = self.n_rows;
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
        Ok(x)
    }

    /// The most violated inactive bound at `x` (beyond `tol`, N), or `usize::MAX` when none is.
    fn most_violated(&self, x: &[f64; MAX_CABLES], tol: f64) -> usize {
        let n = self.n;
        let k = self.n_rows;
        let mut p = usize::MAX;
        let mut worst = -tol;
        for i in 0..n {
            let lo_v = x[i] - self.lo[i];
            let hi_v = self.hi[i] - x[i];
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
        p
    }

    /// Make constraint `p` active: full steps along its normal, partial steps that drop the
    /// active bound whose multiplier reaches zero first, until `p` is added. Counts every
    /// step in `iters` against [`TensionParams::max_iterations`].
    fn add_constraint(
        &mut self,
        p: usize,
        x: &mut [f64; MAX_CABLES],
        scratch: &mut StepScratch,
        iters: &mut u32,
    ) -> Result<(), TensionError> {
        let n = self.n;
        let k = self.n_rows;
        let StepScratch { np, z, rr } = scratch;
        self.normal(p, np);
        let bp = self.rhs_of(p);
        let mut up = 0.0;
        loop {
            *iters += 1;
            if *iters as usize > self.params.max_iterations {
                self.info.iterations = *iters;
                return Err(TensionError::NotConverged { iterations: *iters });
            }
            self.directions(np, z, rr);
            // Partial step: largest step keeping inequality multipliers ≥ 0.
            let mut t1 = f64::INFINITY;
            let mut kdrop = usize::MAX;
            for j in k..self.n_active {
                if rr[j] > STEP_MULTIPLIER_MIN {
                    let s = self.u[j] / rr[j];
                    if s < t1 {
                        t1 = s;
                        kdrop = j;
                    }
                }
            }
            let zz = dot(z, z, n);
            let sp = dot(np, x, n) - bp;
            let t2 = if zz > STEP_DIRECTION_MIN_SQ {
                -sp / zz
            } else {
                f64::INFINITY
            };
            if !t1.is_finite() && !t2.is_finite() {
                self.info.iterations = *iters;
                return Err(TensionError::Infeasible {
                    worst_component: 0,
                    residual_n: [0.0; 6],
                    at_upper_mask: 0,
                    at_lower_mask: 0,
                    t_min_n: self.lo_min(),
                    t_max_n: self.hi_max(),
                    per_cable_bounds: self.bounds_differ(),
                });
            }
            let t = t1.min(t2);
            if t2.is_finite() {
                axpy(x, t, z, n);
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
                    return Err(TensionError::NotConverged { iterations: *iters });
                }
                return Ok(());
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

    /// The answer of the cold solve: tensions `x` and the bound pattern of its active set.
    fn record_active_set(&mut self, x: &[f64; MAX_CABLES]) {
        let n = self.n;
        let k = self.n_rows;
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
    }
}

/// Scratch vectors of one cold-solve step (allocated once per cold solve).
struct StepScratch {
    /// Normal n_p of the constraint being added.
    np: [f64; MAX_CABLES],
    /// Primal step direction z = (I − QQᵀ) n_p.
    z: [f64; MAX_CABLES],
    /// Dual step direction r = R⁻¹ Qᵀ n_p.
    rr: [f64; MAX_CABLES + M],
}
