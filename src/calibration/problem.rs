//! The weighted residuals of a calibration and their Jacobian: measured frequencies against
//! the paired model modes, measured damping ratios against the damping model, measured
//! tensions against the model's, and the priors' rows.
//!
//! Rows: (f_model − f)/σ_f with ∂f/∂p = (∂λ/∂p)/(8π² f); (ζ_model(ω) − ζ)/σ_ζ at the
//! measured ω = 2πf (ζ = modal_ratio, or α/(2ω) + βω/2: linear in the parameters);
//! (T_model − T)/σ_T; then (x_k − nominal_k)/σ_prior,k. A Jacobian column the model has no
//! analytic form for is filled by central differences of the whole model.

use super::data::Measurements;
use super::evaluate::{Evaluator, PoseOut, PoseTask};
use super::fit::LeastSquares;
use super::params::{Applied, FitSpec, ParamKind};
use crate::modal::lambda_to_hz;
use crate::scene::Scene;
use nalgebra::{DMatrix, DVector};
use std::sync::atomic::AtomicUsize;

/// Where each data row of the residual vector comes from.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Layout {
    /// Frequency rows: (row in the data, task, rule index in the task).
    pub modes: Vec<(usize, usize, usize)>,
    /// Damping rows: row in the data (its ζ and σ there).
    pub damping: Vec<usize>,
    /// Tension rows: (row in the tensions, task, index of the cable in the task).
    pub tensions: Vec<(usize, usize, usize)>,
}

impl Layout {
    /// Number of data rows.
    pub fn data_rows(&self) -> usize {
        self.modes.len() + self.damping.len() + self.tensions.len()
    }
}

/// The calibration as a least-squares problem.
pub struct Problem<'a> {
    /// The nominal scene (element resolved).
    pub base: &'a Scene,
    /// The parameters.
    pub spec: &'a FitSpec,
    /// The data.
    pub data: &'a Measurements,
    /// The poses and their rules.
    pub tasks: Vec<PoseTask>,
    /// The rows.
    pub layout: Layout,
    /// Whether the analytic sensitivities apply.
    pub analytic: bool,
    /// Central-difference step as a fraction of each parameter's range.
    pub difference_step: f64,
    /// Model evaluations so far (each at every pose).
    pub evaluations: u32,
    hints: Vec<AtomicUsize>,
}

impl<'a> Problem<'a> {
    /// The problem of `tasks` and `layout`.
    pub fn new(
        base: &'a Scene,
        spec: &'a FitSpec,
        data: &'a Measurements,
        tasks: Vec<PoseTask>,
        layout: Layout,
        analytic: bool,
        difference_step: f64,
    ) -> Problem<'a> {
        let hints = tasks.iter().map(|_| AtomicUsize::new(0)).collect();
        Problem {
            base,
            spec,
            data,
            tasks,
            layout,
            analytic,
            difference_step,
            evaluations: 0,
            hints,
        }
    }

    /// The model at every pose for `x` (with the analytic derivatives when `jacobian`).
    pub fn eval(&mut self, x: &[f64], jacobian: bool) -> Result<(Applied, Vec<PoseOut>), String> {
        self.evaluations += 1;
        let ev = Evaluator {
            base: self.base,
            spec: self.spec,
            tasks: &self.tasks,
            analytic: self.analytic,
            hints: &self.hints,
        };
        ev.eval(x, jacobian).map_err(|(k, e)| {
            let p = self.tasks[k].pose.position_m;
            format!("pose ({}, {}, {}) m: {e}", p.x, p.y, p.z)
        })
    }

    /// Residuals (data rows, then prior rows) and, when `jacobian`, the Jacobian with NaN in
    /// the columns the model gave no analytic value for.
    pub fn assemble(
        &self,
        x: &[f64],
        applied: &Applied,
        outs: &[PoseOut],
        jacobian: bool,
    ) -> Result<(DVector<f64>, Option<DMatrix<f64>>), String> {
        let np = self.spec.params.len();
        let prior: Vec<(usize, f64)> = self
            .spec
            .params
            .iter()
            .enumerate()
            .filter_map(|(k, p)| p.prior_sigma.map(|s| (k, s)))
            .collect();
        let rows = self.layout.data_rows() + prior.len();
        let mut r = DVector::zeros(rows);
        let mut j = jacobian.then(|| DMatrix::zeros(rows, np));
        let mut at = 0;
        for &(row, task, rule) in &self.layout.modes {
            let m = &self.data.modes[row];
            let p = outs[task].picked[rule].as_ref().ok_or_else(|| {
                format!(
                    "line {}: the model has no {} any more",
                    m.line, self.tasks[task].rules[rule]
                )
            })?;
            let f = lambda_to_hz(p.lambda);
            r[at] = (f - m.frequency_hz) / m.sigma_hz;
            if let Some(j) = j.as_mut() {
                let scale = 1.0 / (8.0 * std::f64::consts::PI.powi(2) * f) / m.sigma_hz;
                for (k, par) in self.spec.params.iter().enumerate() {
                    j[(at, k)] = if par.kind.is_damping() {
                        0.0
                    } else {
                        p.dlambda.get(k).map_or(f64::NAN, |d| d * scale)
                    };
                }
            }
            at += 1;
        }
        for &row in &self.layout.damping {
            let m = &self.data.modes[row];
            let (zeta, sigma) = m.damping.expect("damping rows have a ratio");
            let w = 2.0 * std::f64::consts::PI * m.frequency_hz;
            r[at] = (applied.scene.damping.modal_ratio(w) - zeta) / sigma;
            if let Some(j) = j.as_mut() {
                for (k, par) in self.spec.params.iter().enumerate() {
                    j[(at, k)] = match par.kind {
                        ParamKind::ModalRatio => 1.0,
                        ParamKind::RayleighAlpha => 0.5 / w,
                        ParamKind::RayleighBeta => 0.5 * w,
                        _ => 0.0,
                    } / sigma;
                }
            }
            at += 1;
        }
        for &(row, task, c) in &self.layout.tensions {
            let t = &self.data.tensions[row];
            r[at] = (outs[task].tensions_n[c] - t.tension_n) / t.sigma_n;
            if let Some(j) = j.as_mut() {
                for k in 0..np {
                    j[(at, k)] = outs[task]
                        .dtension
                        .get(c)
                        .map_or(f64::NAN, |d| d[k] / t.sigma_n);
                }
            }
            at += 1;
        }
        for &(k, s) in &prior {
            r[at] = (x[k] - self.spec.params[k].nominal) / s;
            if let Some(j) = j.as_mut() {
                j[(at, k)] = 1.0 / s;
            }
            at += 1;
        }
        Ok((r, j))
    }

    /// The residuals alone at `x`.
    fn residuals_only(&mut self, x: &[f64]) -> Result<DVector<f64>, String> {
        let (applied, outs) = self.eval(x, false)?;
        Ok(self.assemble(x, &applied, &outs, false)?.0)
    }

    /// Fills every Jacobian column holding a NaN by a central difference of the model
    /// (one-sided at a bound).
    fn fill_differences(&mut self, x: &[f64], j: &mut DMatrix<f64>) -> Result<(), String> {
        for k in 0..j.ncols() {
            if !j.column(k).iter().any(|v| v.is_nan()) {
                continue;
            }
            let p = &self.spec.params[k];
            let h = self.difference_step * (p.upper - p.lower);
            let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
            xp[k] = (x[k] + h).min(p.upper);
            xm[k] = (x[k] - h).max(p.lower);
            let rp = self.residuals_only(&xp)?;
            let rm = self.residuals_only(&xm)?;
            let col = (rp - rm) / (xp[k] - xm[k]);
            j.set_column(k, &col);
        }
        Ok(())
    }
}

impl LeastSquares for Problem<'_> {
    fn residuals(
        &mut self,
        x: &[f64],
        jacobian: bool,
    ) -> Result<(DVector<f64>, Option<DMatrix<f64>>), String> {
        let (applied, outs) = self.eval(x, jacobian)?;
        let (r, mut j) = self.assemble(x, &applied, &outs, jacobian)?;
        if let Some(j) = j.as_mut() {
            self.fill_differences(x, j)?;
        }
        Ok((r, j))
    }
}
