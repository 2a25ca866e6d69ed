//! `SagTensionSolver`'s construction, fixed-point solve and accessors (the method is
//! documented in the module docs).

use super::newton::{fold_candidate, newton_step_bounded, NewtonCable};
use super::{SagCable, SagTensionError, SagTensionInfo, SagTensionParams, SagTensionSolver};
use crate::kinematics::{up_frame, Geometry};
use crate::sag::{CableChord, Catenary, SagError};
use crate::tension::Bound;
use crate::tension::TensionSolver;
use nalgebra::Vector3;

/// Below this horizontal part (relative to the chord length) a chord counts as vertical
/// and takes the fixed horizontal h of `up_frame`: its catenary has H ≈ 0 there, so the
/// choice of h does not change the force.
const VERTICAL_REL: f64 = 1e-14;

/// A pass whose end directions moved less than this (rad) while barely contracting has
/// stalled and is accepted: 1e-10 rad moves a cable's end force by 1e-10 of its tension
/// (the stall is ~1e-11 rad where it was measured, at poses where the QP's active set
/// changes; the reported residual says what it left).
const STALL_MAX_RAD: f64 = 1e-10;
/// A pass that shrinks the directions' change by less than this factor has stalled.
const STALL_CONTRACTION: f64 = 0.5;
/// Newton's steps stop for the rest of a solve after a pass that shrank the directions'
/// change by less than this factor (near the answer they shrink it quadratically).
const NEWTON_CONTRACTION: f64 = 1.0;

/// The QP's tensions equal the current ones when they differ by at most this fraction of
/// the largest (a few ulps of it).
const FIXED_POINT_TENSION_REL: f64 = 1e-14;

/// Whether the QP's tensions `qp_n` on the current tangents give back the current tensions
/// `t_n` (those the tangents were solved at), to [`FIXED_POINT_TENSION_REL`]: then the
/// largest first-order change of direction another pass would make, max |dt_i/dT_i|·|ΔT_i|
/// (rad, `dtan` the tangents' turn per newton), else None.
fn fixed_point_reached(qp_n: &[f64], t_n: &[f64], dtan: &[Vector3<f64>]) -> Option<f64> {
    let scale = t_n.iter().fold(0.0f64, |m, t| m.max(t.abs()));
    let mut moved = 0.0f64;
    for ((q, t), d) in qp_n.iter().zip(t_n).zip(dtan) {
        let dt = (q - t).abs();
        if !(dt <= FIXED_POINT_TENSION_REL * scale) {
            return None;
        }
        moved = moved.max(d.norm() * dt);
    }
    Some(moved)
}

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
            chords: vec![chord; n_cables],
            cats: vec![blank; n_cables],
            tracks: vec![None; n_cables],
            h: vec![Vector3::zeros(); n_cables],
            n_out: vec![Vector3::zeros(); n_cables],
            up: Vector3::z(),
            t_end: vec![0.0; n_cables],
            dtan: vec![Vector3::zeros(); n_cables],
            newton_in: vec![
                NewtonCable::new(
                    &Vector3::x(),
                    &Vector3::zeros(),
                    &Vector3::zeros(),
                    0.0,
                    Bound::Free
                );
                n_cables
            ],
            newton_out: vec![0.0; n_cables],
            t_before: vec![0.0; n_cables],
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
        let r = self.fixed_point(w, t_min_n, t_max_n);
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
        }
    }

    /// The passes of the module docs.
    fn fixed_point(&mut self, w: &[f64; 6], lo: &[f64], hi: &[f64]) -> Result<(), SagTensionError> {
        let mut change = f64::INFINITY;
        let warm = self.have_warm;
        if warm {
            // Start from the last end tensions on the new chords, and Newton's step from
            // them on the last active set (the first QP pass then starts near the answer).
            change = self.catenaries()?;
            if self.params.newton {
                self.accelerate(w, lo, hi, false)?;
            }
        }
        let mut iterations = 0;
        let mut converged = false;
        let mut newton = self.params.newton;
        while iterations < self.params.max_iterations {
            iterations += 1;
            let before = change;
            let t = self.qp.solve_wrench_bounds(&self.tangent_geom, w, lo, hi);
            let t = match t {
                Ok(t) => t,
                Err(e) => {
                    self.t_end.copy_from_slice(self.qp.tensions_n());
                    return Err(e.into());
                }
            };
            // The catenaries are those of the current tensions (after the warm start or a
            // pass): when the QP on their tangents gives these tensions back, they are the
            // fixed point, and no further catenary sweep is needed to see it.
            if warm || iterations > 1 {
                if let Some(moved) = fixed_point_reached(t, &self.t_end, &self.dtan) {
                    if moved < self.params.direction_tol_rad {
                        change = moved;
                        converged = true;
                        break;
                    }
                }
            }
            self.t_end.copy_from_slice(t);
            change = self.catenaries()?;
            // Converged below the tolerance; or stalled near it: where the QP's active set
            // is about to change, the fixed point contracts by barely anything per pass (or
            // hops by ~1e-11 rad between two active sets), so more passes gain nothing.
            if change < self.params.direction_tol_rad
                || (change < STALL_MAX_RAD && change > STALL_CONTRACTION * before)
            {
                converged = true;
                break;
            }
            // Newton's steps continue while the passes contract; otherwise (its active set
            // or linearisation is wrong, e.g. far from the answer on a cold start where a
            // cable is about to leave its bound) the plain passes take over. A warm solve
            // keeps the steps, and after a pass that did not contract tries the free cable
            // nearest a fold on its bound (its free fixed point may have vanished).
            let contracted = change <= NEWTON_CONTRACTION * before;
            newton &= warm || contracted;
            if newton {
                self.accelerate(w, lo, hi, !contracted)?;
            }
        }
        self.info = SagTensionInfo {
            iterations,
            direction_change_rad: change,
            ..self.info
        };
        self.residual(w);
        if !converged {
            return Err(SagTensionError::NoConvergence {
                iterations,
                direction_change_rad: change,
            });
        }
        Ok(())
    }

    /// Replace the QP's tensions by Newton's step (`newton.rs`) from them, on the QP's
    /// active set corrected by the step's bounds (and, with `fold`, with the free cable
    /// nearest a fold put on its nearer bound first), with the catenaries at the new
    /// tensions; the QP's tensions and catenaries stay (the plain pass) when the step is
    /// not defined or a catenary does not exist.
    fn accelerate(
        &mut self,
        w: &[f64; 6],
        lo: &[f64],
        hi: &[f64],
        fold: bool,
    ) -> Result<(), SagTensionError> {
        let n = self.t_end.len();
        let bounds = self.qp.bounds();
        for i in 0..n {
            let g = &self.tangent_geom;
            self.newton_in[i] = NewtonCable::new(
                &g.unit[i],
                &self.dtan[i],
                &g.arm_m[i],
                self.t_end[i],
                bounds[i],
            );
        }
        if fold {
            if let Some(i) = fold_candidate(&self.newton_in[..n]) {
                let c = &mut self.newton_in[i];
                let lower = c.t_n - lo[i] <= hi[i] - c.t_n;
                c.bound = if lower { Bound::Lower } else { Bound::Upper };
                c.t_n = if lower { lo[i] } else { hi[i] };
            }
        }
        if !newton_step_bounded(&mut self.newton_in[..n], w, lo, hi, &mut self.newton_out) {
            return Ok(());
        }
        self.t_before.copy_from_slice(&self.t_end);
        self.t_end.copy_from_slice(&self.newton_out[..n]);
        if self.catenaries().is_err() {
            self.t_end.copy_from_slice(&self.t_before);
            self.catenaries()?;
        }
        Ok(())
    }

    /// Each cable's catenary for its current T_e and its world end tangent; returns the
    /// largest change of direction, rad.
    fn catenaries(&mut self) -> Result<f64, SagTensionError> {
        let mut change: f64 = 0.0;
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
            let old = self.tangent_geom.unit[i];
            change = change.max(old.cross(&t).norm().atan2(old.dot(&t)));
            self.tangent_geom.unit[i] = t;
            self.cats[i] = cat;
            self.tracks[i] = Some(track);
        }
        Ok(change)
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
