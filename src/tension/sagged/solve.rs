//! `SagTensionSolver`'s construction, SQP solve and accessors (the method is documented in
//! the module docs).

use super::kkt::{kkt_step, multiplier_of, KktCable};
use super::{SagCable, SagTensionError, SagTensionInfo, SagTensionParams, SagTensionSolver};
use crate::elastic_catenary::{CableChord, Catenary, SagError};
use crate::kinematics::{up_frame, Geometry};
use crate::tension::TensionSolver;
use nalgebra::{Vector3, Vector6};

/// Below this horizontal part (relative to the chord length) a chord counts as vertical
/// and takes the fixed horizontal h of `up_frame`: its catenary has H ≈ 0 there, so the
/// choice of h does not change the force.
const VERTICAL_REL: f64 = 1e-14;

/// Bounds of the Hessian's diagonal D_i = 1 − λ·b_i′: positive, so that every subproblem is
/// strictly convex (a clamped D_i only slows the convergence, the answer is the KKT point
/// whatever D). 1 is exact for a weightless cable; a very slack cable (heavy cables on the
/// paper's robot at T_min, `tests/sag/tension.rs`) needs more than 20.
const D_MIN: f64 = 0.05;
const D_MAX: f64 = 1e4;
/// The secant of b_i is taken over a tension change above this fraction of the tension
/// (below it, rounding in b_i dominates the difference).
const SECANT_MIN_REL: f64 = 1e-7;
/// Step halvings of the line search.
const MAX_HALVINGS: u32 = 12;
/// Armijo's fraction of the merit's predicted decrease.
const ARMIJO: f64 = 1e-4;
/// Steps below this fraction of the largest tension are taken in full (the region of the
/// Newton–KKT step's fast local convergence, where an ℓ1 merit can reject good steps).
const FULL_STEP_REL: f64 = 1e-6;
/// A free cable out of its bounds, or a bound multiplier of the wrong sign, by less than
/// this fraction of the largest tension is accepted in the Newton–KKT step (rounding).
const KKT_TOL_REL: f64 = 1e-9;

impl SagTensionSolver {
    /// Allocate for `n_cables` cables.
    pub fn new(n_cables: usize, params: SagTensionParams) -> SagTensionSolver {
        let blank = Catenary {
            l0_m: 0.0,
            ea_n: 1.0,
            w_n_m: 0.0,
            h_n: 0.0,
            v_anchor_n: 0.0,
        };
        let chord = CableChord {
            span_m: 0.0,
            rise_m: 0.0,
            ea_n: 1.0,
            w_n_m: 0.0,
        };
        SagTensionSolver {
            params,
            qp: TensionSolver::new(n_cables, params.tension),
            tangent_geom: Geometry::new(n_cables),
            lin_geom: Geometry::new(n_cables),
            chords: vec![chord; n_cables],
            cats: vec![blank; n_cables],
            tracks: vec![None; n_cables],
            h: vec![Vector3::zeros(); n_cables],
            n_out: vec![Vector3::zeros(); n_cables],
            up: Vector3::z(),
            t_end: vec![0.0; n_cables],
            dtan: vec![Vector3::zeros(); n_cables],
            kkt: vec![KktCable::blank(); n_cables],
            t_new: vec![0.0; n_cables],
            t_base: vec![0.0; n_cables],
            b_prev: vec![Vector6::zeros(); n_cables],
            db: vec![Vector6::zeros(); n_cables],
            lambda: Vector6::zeros(),
            have_warm: false,
            info: SagTensionInfo::default(),
        }
    }

    /// Solve at the cable chords `g` (kinematics at the pose) with each cable's material,
    /// gravity (m/s², sets "up" and nothing else: the weights are in `cables`), the wrench
    /// `w` the cables carry (force N, moment N·m, as [`TensionSolver::solve_wrench_bounds`])
    /// and per-cable bounds on the end tension (N). Returns the end tensions. No allocation.
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &mut self,
        g: &Geometry,
        cables: &[SagCable],
        gravity_m_s2: &Vector3<f64>,
        w: &[f64; 6],
        t_min_n: &[f64],
        t_max_n: &[f64],
    ) -> Result<&[f64], SagTensionError> {
        let n = self.t_end.len();
        if g.n() != n || cables.len() != n {
            return Err(SagTensionError::Invalid {
                what: "geometry or cable count differs from the solver's",
            });
        }
        if !gravity_m_s2.iter().all(|x| x.is_finite()) {
            return Err(SagTensionError::Invalid {
                what: "non-finite gravity",
            });
        }
        if !self.have_warm {
            // Cold: nothing from an earlier solve; the passes of this one warm-start the next.
            self.tracks.iter_mut().for_each(|t| *t = None);
        }
        self.set_chords(g, cables, gravity_m_s2);
        let r = self.sqp(w, t_min_n, t_max_n);
        if r.is_err() {
            self.have_warm = false;
        }
        r?;
        self.have_warm = true;
        Ok(&self.t_end)
    }

    /// Plane bases, chords and the QP geometry's arms and lengths.
    fn set_chords(&mut self, g: &Geometry, cables: &[SagCable], gravity: &Vector3<f64>) {
        let frame = up_frame(gravity);
        self.up = frame.column(2).into_owned();
        for i in 0..self.t_end.len() {
            let l = g.unit[i] * g.length_m[i];
            let rise = l.dot(&self.up);
            let horiz = l - self.up * rise;
            let span = horiz.norm();
            let h = if span > VERTICAL_REL * g.length_m[i] {
                horiz / span
            } else {
                frame.column(0).into_owned()
            };
            self.h[i] = h;
            self.n_out[i] = h.cross(&self.up);
            self.chords[i] = CableChord {
                span_m: span,
                rise_m: rise,
                ea_n: cables[i].ea_n,
                w_n_m: cables[i].w_n_m,
            };
            self.tangent_geom.arm_m[i] = g.arm_m[i];
            self.tangent_geom.length_m[i] = g.length_m[i];
            self.tangent_geom.unit[i] = g.unit[i];
            self.lin_geom.arm_m[i] = g.arm_m[i];
            self.lin_geom.length_m[i] = g.length_m[i];
        }
    }

    /// The SQP of the module docs.
    fn sqp(&mut self, w: &[f64; 6], lo: &[f64], hi: &[f64]) -> Result<(), SagTensionError> {
        let n = self.t_end.len();
        let warm = self.have_warm;
        if warm {
            for ((t, l), h) in self.t_end.iter_mut().zip(lo).zip(hi) {
                *t = t.clamp(*l, *h);
            }
        } else {
            // Cold: the chord QP (tangent_geom holds the chords after set_chords).
            match self.qp.solve_wrench_bounds(&self.tangent_geom, w, lo, hi) {
                Ok(t) => self.t_end.copy_from_slice(t),
                Err(e) => {
                    self.t_end.copy_from_slice(self.qp.tensions_n());
                    return Err(e.into());
                }
            }
            self.db.iter_mut().for_each(|d| *d = Vector6::zeros());
            self.lambda = Vector6::zeros();
        }
        self.info = SagTensionInfo::default();
        self.catenaries()?;
        self.info.sweeps = 1;
        let mut rho: f64 = 0.0;
        let mut iterations = 0;
        let mut converged = false;
        let mut step = f64::INFINITY;
        while iterations < self.params.max_iterations {
            iterations += 1;
            let scale = self.t_end.iter().fold(0.0f64, |m, t| m.max(t.abs()));
            let res = self.residual6(w);
            // The linearised equilibrium B T′ = B T − F(T) and the D = I subproblem.
            let mut rhs = -res;
            for i in 0..n {
                let v = self.tangent_geom.unit[i] + self.dtan[i] * self.t_end[i];
                self.lin_geom.unit[i] = v;
                let m = self.lin_geom.arm_m[i].cross(&v);
                let b = Vector6::new(v.x, v.y, v.z, m.x, m.y, m.z);
                rhs += b * self.t_end[i];
                self.kkt[i] = KktCable {
                    b,
                    t_n: self.t_end[i],
                    d: (1.0 - self.lambda.dot(&self.db[i])).clamp(D_MIN, D_MAX),
                    bound: crate::tension::Bound::Free,
                };
            }
            let rhs6 = [rhs[0], rhs[1], rhs[2], rhs[3], rhs[4], rhs[5]];
            match self.qp.solve_wrench_bounds(&self.lin_geom, &rhs6, lo, hi) {
                Ok(t) => self.t_new.copy_from_slice(t),
                Err(e) => {
                    self.t_end.copy_from_slice(self.qp.tensions_n());
                    return Err(e.into());
                }
            }
            for (c, b) in self.kkt.iter_mut().zip(self.qp.bounds()) {
                c.bound = *b;
            }
            // The Newton–KKT step on that active set with the exact Hessian's diagonal.
            let tol = KKT_TOL_REL * scale;
            match kkt_step(&mut self.kkt, &res, lo, hi, tol, &mut self.t_base) {
                Some(l) => {
                    self.t_new.copy_from_slice(&self.t_base);
                    self.lambda = l;
                }
                None => {
                    if let Some(l) = multiplier_of(&self.kkt, &self.t_new) {
                        self.lambda = l;
                    }
                }
            }
            step = self
                .t_new
                .iter()
                .zip(&self.t_end)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            if step <= self.params.step_tol_rel * scale {
                converged = true;
                break;
            }
            self.line_search(w, &res, &mut rho, step <= FULL_STEP_REL * scale)?;
        }
        self.info.iterations = iterations;
        self.info.step_n = step;
        self.residual(w);
        if !converged {
            return Err(SagTensionError::NoConvergence {
                iterations,
                step_n: step,
            });
        }
        Ok(())
    }

    /// Move from the current tensions toward `t_new` by backtracking on the ℓ1 merit
    /// ½‖T‖² + ρ‖F(T)‖₁ (`res` = F at the current tensions; ρ raised to twice the largest
    /// multiplier), the full step when `full`; then the secant of each b_i.
    fn line_search(
        &mut self,
        w: &[f64; 6],
        res: &Vector6<f64>,
        rho: &mut f64,
        full: bool,
    ) -> Result<(), SagTensionError> {
        let n = self.t_end.len();
        *rho = rho.max(2.0 * self.lambda.amax());
        let res1 = res.lp_norm(1);
        let phi0 = 0.5 * self.t_end.iter().map(|t| t * t).sum::<f64>() + *rho * res1;
        let slope = self
            .t_end
            .iter()
            .zip(&self.t_new)
            .map(|(t, u)| t * (u - t))
            .sum::<f64>()
            - *rho * res1;
        self.t_base.copy_from_slice(&self.t_end);
        for i in 0..n {
            self.b_prev[i] = self.kkt[i].b;
        }
        let mut alpha = 1.0;
        let mut halvings = 0;
        loop {
            for i in 0..n {
                self.t_end[i] = if alpha == 1.0 {
                    self.t_new[i]
                } else {
                    self.t_base[i] + alpha * (self.t_new[i] - self.t_base[i])
                };
            }
            self.info.sweeps += 1;
            let last = halvings == MAX_HALVINGS;
            match self.catenaries() {
                Ok(()) => {
                    let phi = 0.5 * self.t_end.iter().map(|t| t * t).sum::<f64>()
                        + *rho * self.residual6(w).lp_norm(1);
                    let tol = 1e-14 * phi0.abs();
                    if full || last || phi <= phi0 + ARMIJO * alpha * slope + tol {
                        break;
                    }
                }
                Err(e) if last => return Err(e),
                Err(_) => {}
            }
            alpha *= 0.5;
            halvings += 1;
        }
        for i in 0..n {
            let dt = self.t_end[i] - self.t_base[i];
            if dt.abs() > SECANT_MIN_REL * self.t_end[i].abs() {
                let v = self.tangent_geom.unit[i] + self.dtan[i] * self.t_end[i];
                let m = self.lin_geom.arm_m[i].cross(&v);
                let b = Vector6::new(v.x, v.y, v.z, m.x, m.y, m.z);
                self.db[i] = (b - self.b_prev[i]) / dt;
            }
        }
        Ok(())
    }

    /// F(T) = Σ T_e,i a_i − w at the current tensions and tangents (N, N·m).
    fn residual6(&self, w: &[f64; 6]) -> Vector6<f64> {
        let g = &self.tangent_geom;
        let f = g.wrench_of(&self.t_end);
        let m = g.moment_of(&self.t_end);
        Vector6::new(
            f.x - w[0],
            f.y - w[1],
            f.z - w[2],
            m.x - w[3],
            m.y - w[4],
            m.z - w[5],
        )
    }

    /// Each cable's catenary for its current T_e, its world end tangent and the tangent's
    /// turn with the tension.
    fn catenaries(&mut self) -> Result<(), SagTensionError> {
        for i in 0..self.t_end.len() {
            let warm = self.tracks[i].as_ref().filter(|w| w.catenary.l0_m > 0.0);
            let chord = &self.chords[i];
            let (cat, info, track) =
                match chord.solve_end_tension_tracked(self.t_end[i], warm, &self.params.sag) {
                    Ok(ok) => ok,
                    Err(e @ SagError::TooSlack { .. }) => {
                        return Err(SagTensionError::Slack {
                            cable: i,
                            reason: e,
                        })
                    }
                    Err(e) if !(self.t_end[i] > 0.0) => {
                        return Err(SagTensionError::Slack {
                            cable: i,
                            reason: e,
                        })
                    }
                    Err(e) => {
                        return Err(SagTensionError::Catenary {
                            cable: i,
                            source: e,
                        })
                    }
                };
            if !(cat.tension_min_n() > 0.0) {
                let reason = SagError::TooSlack {
                    t_end_n: self.t_end[i],
                    t_end_min_n: f64::NAN,
                };
                return Err(SagTensionError::Slack { cable: i, reason });
            }
            let [c, s] = cat.tangent_at(cat.l0_m);
            let t = self.h[i] * c + self.up * s;
            let dphi = if info.dphi_dt_end_rad_n.is_finite() {
                info.dphi_dt_end_rad_n
            } else {
                0.0
            };
            self.dtan[i] = (self.up * c - self.h[i] * s) * dphi;
            self.tangent_geom.unit[i] = t;
            self.cats[i] = cat;
            self.tracks[i] = Some(track);
        }
        Ok(())
    }

    /// Equilibrium residual of the reported state (tensions and tangents).
    fn residual(&mut self, w: &[f64; 6]) {
        let g = &self.tangent_geom;
        let f = g.wrench_of(&self.t_end) - Vector3::new(w[0], w[1], w[2]);
        let m = g.moment_of(&self.t_end) - Vector3::new(w[3], w[4], w[5]);
        self.info.residual_force_n = f.amax();
        self.info.residual_moment_n_m = m.amax();
    }

    /// Forget the warm start (the next solve starts from the chords).
    pub fn reset_warm_start(&mut self) {
        self.have_warm = false;
        self.qp.reset_warm_start();
        self.cats.iter_mut().for_each(|c| c.l0_m = 0.0);
        self.tracks.iter_mut().for_each(|t| *t = None);
    }

    /// End-effector-end tensions T_e,i of the last solve (the QP's closest solution after
    /// `Infeasible`), N.
    pub fn tensions_n(&self) -> &[f64] {
        &self.t_end
    }

    /// Each cable's catenary of the last successful solve.
    pub fn catenaries_of(&self) -> &[Catenary] {
        &self.cats
    }

    /// Anchor-end tension of cable i, N.
    pub fn tension_anchor_n(&self, i: usize) -> f64 {
        self.cats[i].tension_anchor_n()
    }

    /// Smallest tension along cable i, N.
    pub fn tension_min_n(&self, i: usize) -> f64 {
        self.cats[i].tension_min_n()
    }

    /// Cable i's plane basis (h_i, up, n_i), world unit vectors.
    pub fn basis(&self, i: usize) -> [Vector3<f64>; 3] {
        [self.h[i], self.up, self.n_out[i]]
    }

    /// World unit end tangents t_i (the cable pulls the end-effector with −T_e,i t_i).
    pub fn end_tangents(&self) -> &[Vector3<f64>] {
        &self.tangent_geom.unit
    }

    /// What the last solve did.
    pub fn info(&self) -> SagTensionInfo {
        self.info
    }
}
