//! The least-squares machinery: a bounded Levenberg-Marquardt iteration on weighted
//! residuals, and the statistics of its answer.
//!
//! **Iteration.** Minimise ½‖r(x)‖² (r: residuals already divided by their σ, and the
//! prior's rows (x − x_nominal)/σ_prior) over lower ≤ x ≤ upper. Each step solves
//! (JᵀJ + μ diag(JᵀJ)) δ = −Jᵀr on the parameters not held at a bound (a parameter at a
//! bound whose gradient pushes it out stays there) and clips x + δ into the bounds; a step
//! that lowers the cost is taken and μ shrinks by max(1/3, 1 − (2ρ − 1)³) (ρ: actual over
//! predicted decrease), else μ grows tenfold (Nielsen's rule). It stops when the cost falls
//! by less than `cost_rel_tol` of itself, when a step moves no parameter by more than
//! `step_rel_tol` of its range, or after `max_iterations`.
//!
//! **Statistics.** The data rows' Jacobian J, with columns scaled by each parameter's
//! range R_k (upper − lower), has singular values σ_j and right singular vectors V: moving
//! parameter k by its whole range changes the misfit by R_k ‖J e_k‖, and the data alone give
//! it the standard error s_k = R_k (Σ_j V_kj²/σ_j²)^½. A parameter whose s_k is at least
//! `undetermined_fraction` of its range is **undetermined**: the data cannot place it within
//! its bounds (an unseen parameter has a zero column, σ = 0, s = ∞). The standard errors of
//! the others are the diagonal of (J_DᵀJ_D + P_D)⁻¹ over the determined ones (P: the prior's
//! precision), their correlations its normalised entries. χ² = Σ r² over the data rows with
//! dof = rows − determined parameters; the fit is consistent with the stated noise when the
//! probability of a larger χ² (the regularised upper incomplete gamma Q(dof/2, χ²/2)) is at
//! least `p_min`.

use nalgebra::{DMatrix, DVector};

/// Bounds and tolerances of the fit (finite everywhere).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitParams {
    /// Largest number of accepted steps (default 100).
    pub max_iterations: u32,
    /// Stop when a step lowers the cost by less than this fraction (default 1e-10).
    pub cost_rel_tol: f64,
    /// Stop when a step moves every parameter by less than this fraction of its range
    /// (default 1e-10).
    pub step_rel_tol: f64,
    /// Relative step of the central differences for parameters without an analytic
    /// sensitivity, as a fraction of the parameter's range (default 1e-5).
    pub difference_step: f64,
    /// A parameter is undetermined when its data-only standard error is at least this
    /// fraction of its scale, min(|nominal|, range) or the range for a nominal of 0
    /// (default 0.5).
    pub undetermined_fraction: f64,
    /// The fit is consistent with the stated noise when P(χ² larger) ≥ this (default 0.01).
    pub p_min: f64,
    /// Largest number of rounds of fit and re-pairing by frequency (default 3).
    pub max_pairing_rounds: u32,
    /// Largest change of a parameter in one step, as a fraction of its scale (default 0.2).
    pub max_step: f64,
    /// When a fit fails the χ² test, the most further starts tried (default 6): several
    /// stiffness distributions can give nearly the same sorted frequencies, so the answer
    /// from the nominal values can be a local minimum.
    pub restarts: u32,
    /// The further starts are drawn uniformly within ± this fraction of each parameter's
    /// scale about the nominal value (default 0.5).
    pub restart_spread: f64,
}

impl Default for FitParams {
    fn default() -> Self {
        FitParams {
            max_iterations: 100,
            cost_rel_tol: 1e-10,
            step_rel_tol: 1e-10,
            difference_step: 1e-5,
            undetermined_fraction: 0.5,
            p_min: 0.01,
            max_pairing_rounds: 3,
            max_step: 0.2,
            restarts: 6,
            restart_spread: 0.5,
        }
    }
}

/// What one iteration needs of the problem.
pub trait LeastSquares {
    /// The weighted residuals at `x` and, when `jacobian`, their Jacobian (rows × params).
    fn residuals(
        &mut self,
        x: &[f64],
        jacobian: bool,
    ) -> Result<(DVector<f64>, Option<DMatrix<f64>>), String>;
}

/// How the iteration ended.
#[derive(Debug, Clone, PartialEq)]
pub struct FitInfo {
    /// Accepted steps.
    pub iterations: u32,
    /// Residual evaluations (each one model evaluation at every pose).
    pub evaluations: u32,
    /// Whether a tolerance was met (else the iteration bound).
    pub converged: bool,
}

/// An answer of the iteration: x, r(x), J(x) and how it ended.
pub type Answer = (Vec<f64>, DVector<f64>, DMatrix<f64>, FitInfo);

/// Minimises ½‖r‖² of `p` from `x0` within the bounds; returns x, r(x), J(x) and the info.
pub fn levenberg_marquardt(
    p: &mut impl LeastSquares,
    x0: &[f64],
    (lower, upper, scale): (&[f64], &[f64], &[f64]),
    params: &FitParams,
) -> Result<Answer, String> {
    let n = x0.len();
    let range: Vec<f64> = (0..n).map(|k| upper[k] - lower[k]).collect();
    let mut x: Vec<f64> = (0..n).map(|k| x0[k].clamp(lower[k], upper[k])).collect();
    let (mut r, j) = p.residuals(&x, true)?;
    let mut j = j.ok_or("no Jacobian")?;
    let mut info = FitInfo {
        iterations: 0,
        evaluations: 1,
        converged: false,
    };
    let mut cost = 0.5 * r.norm_squared();
    let mut mu = 1e-3;
    while info.iterations < params.max_iterations {
        let g = j.transpose() * &r;
        let h = j.transpose() * &j;
        let free: Vec<usize> = (0..n)
            .filter(|&k| !((x[k] <= lower[k] && g[k] > 0.0) || (x[k] >= upper[k] && g[k] < 0.0)))
            .collect();
        if free.is_empty() || free.iter().all(|&k| g[k] == 0.0) {
            info.converged = true;
            break;
        }
        let dmax = free.iter().map(|&k| h[(k, k)]).fold(0.0f64, f64::max);
        let floor = (1e-12 * dmax).max(f64::MIN_POSITIVE);
        let mut accepted = None;
        for _ in 0..40 {
            let m = free.len();
            let a = DMatrix::from_fn(m, m, |i, l| {
                let (ki, kl) = (free[i], free[l]);
                h[(ki, kl)]
                    + if i == l {
                        mu * h[(ki, ki)].max(floor)
                    } else {
                        0.0
                    }
            });
            let b = DVector::from_fn(m, |i, _| -g[free[i]]);
            let Some(chol) = a.cholesky() else {
                mu *= 10.0;
                continue;
            };
            let mut d = chol.solve(&b);
            // A step is at most `max_step` of each parameter's scale (a box trust region):
            // far from the answer the Gauss-Newton step along a weak direction is huge.
            let over = free
                .iter()
                .enumerate()
                .map(|(i, &k)| d[i].abs() / (params.max_step * scale[k]))
                .fold(0.0f64, f64::max);
            if over > 1.0 {
                d /= over;
            }
            let mut xn = x.clone();
            for (i, &k) in free.iter().enumerate() {
                xn[k] = (x[k] + d[i]).clamp(lower[k], upper[k]);
            }
            let small = (0..n).all(|k| (xn[k] - x[k]).abs() <= params.step_rel_tol * range[k]);
            if small {
                info.converged = true;
                break;
            }
            info.evaluations += 1;
            match p.residuals(&xn, true) {
                Ok((rn, Some(jn))) => {
                    let cn = 0.5 * rn.norm_squared();
                    if cn < cost {
                        let step = DVector::from_fn(n, |k, _| xn[k] - x[k]);
                        let predicted = -(g.dot(&step) + 0.5 * step.dot(&(&h * &step)));
                        let rho = if predicted > 0.0 {
                            (cost - cn) / predicted
                        } else {
                            0.0
                        };
                        mu *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
                        accepted = Some((xn, rn, jn, cn));
                        break;
                    }
                    mu *= 10.0;
                }
                _ => mu *= 10.0,
            }
        }
        let Some((xn, rn, jn, cn)) = accepted else {
            info.converged = info.converged || mu > 1e30;
            break;
        };
        info.iterations += 1;
        let fell = cost - cn;
        x = xn;
        r = rn;
        j = jn;
        cost = cn;
        if fell <= params.cost_rel_tol * cost.max(f64::MIN_POSITIVE) {
            info.converged = true;
            break;
        }
    }
    Ok((x, r, j, info))
}

/// The statistics of a fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FitStats {
    /// Singular values of the range-scaled data Jacobian, descending.
    pub singular_values: Vec<f64>,
    /// Per parameter: whether the data determine it.
    pub determined: Vec<bool>,
    /// Per parameter: its data-only standard error (∞ when unseen).
    pub data_std: Vec<f64>,
    /// Per parameter: standard error (None when undetermined).
    pub std_error: Vec<Option<f64>>,
    /// Correlation matrix (None where a parameter is undetermined).
    pub correlation: Vec<Vec<Option<f64>>>,
}

/// The statistics of the data Jacobian `j` (weighted rows) with the prior precisions
/// `prior` (1/σ², 0 without a prior); `range` scales the singular values, `scale` is each
/// parameter's size against which its standard error is judged (min(|nominal|, range), or
/// the range for a nominal of 0).
pub fn statistics(
    j: &DMatrix<f64>,
    prior: &[f64],
    range: &[f64],
    scale: &[f64],
    params: &FitParams,
) -> FitStats {
    let n = range.len();
    let mut js = j.clone();
    for k in 0..n {
        js.column_mut(k).scale_mut(range[k]);
    }
    let (singular_values, data_std) = if js.nrows() == 0 {
        (vec![0.0; n], vec![f64::INFINITY; n])
    } else {
        let svd = js.clone().svd(false, true);
        let vt = svd.v_t.expect("v_t asked for");
        let mut sv: Vec<f64> = svd.singular_values.iter().copied().collect();
        let smax = sv.iter().copied().fold(0.0f64, f64::max);
        let mut var = vec![0.0; n];
        for (jx, &s) in sv.iter().enumerate() {
            let s = if s > 1e-14 * smax { s } else { 0.0 };
            for k in 0..n {
                let v = vt[(jx, k)];
                if v.abs() > 1e-12 {
                    var[k] += if s > 0.0 {
                        v * v / (s * s)
                    } else {
                        f64::INFINITY
                    };
                }
            }
        }
        // Fewer rows than parameters: the missing singular values are zero.
        for k in 0..n {
            let seen: f64 = (0..sv.len()).map(|jx| vt[(jx, k)] * vt[(jx, k)]).sum();
            if seen < 1.0 - 1e-9 {
                var[k] = f64::INFINITY;
            }
        }
        sv.sort_by(|a, b| b.total_cmp(a));
        sv.resize(n, 0.0);
        (
            sv,
            (0..n)
                .map(|k| range[k] * var[k].sqrt())
                .collect::<Vec<f64>>(),
        )
    };
    let determined: Vec<bool> = (0..n)
        .map(|k| data_std[k] < params.undetermined_fraction * scale[k])
        .collect();
    // The covariance of every parameter (data and prior), in range-scaled coordinates; its
    // pseudo-inverse drops only the directions nothing sees.
    let mut h = js.transpose() * &js;
    for k in 0..n {
        h[(k, k)] += prior[k] * range[k] * range[k];
    }
    let eps = 1e-14 * h.amax();
    let mut std_error = vec![None; n];
    let mut correlation = vec![vec![None; n]; n];
    if let Ok(cov) = h.pseudo_inverse(eps) {
        for k in (0..n).filter(|&k| determined[k]) {
            std_error[k] = Some(range[k] * cov[(k, k)].max(0.0).sqrt());
            for l in (0..n).filter(|&l| determined[l]) {
                let d = (cov[(k, k)] * cov[(l, l)]).sqrt();
                correlation[k][l] = Some(if d > 0.0 { cov[(k, l)] / d } else { 0.0 });
            }
        }
    }
    FitStats {
        singular_values,
        determined,
        data_std,
        std_error,
        correlation,
    }
}

/// ln Γ(x) for x > 0 (Lanczos, g = 7, 9 terms; relative error ~1e-15).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// The regularised upper incomplete gamma function Q(a, x) = Γ(a, x)/Γ(a): the series for
/// x < a + 1, Lentz's continued fraction above.
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if !(a > 0.0) || !(x >= 0.0) {
        return f64::NAN;
    }
    if x == 0.0 {
        return 1.0;
    }
    let lead = -x + a * x.ln() - ln_gamma(a);
    if x < a + 1.0 {
        let (mut ap, mut sum, mut del) = (a, 1.0 / a, 1.0 / a);
        for _ in 0..10_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        (1.0 - sum * lead.exp()).max(0.0)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (lead.exp() * h).clamp(0.0, 1.0)
    }
}

/// P(χ²_dof > chi2): the probability that noise of the stated size gives a larger misfit.
pub fn chi2_upper_tail(chi2: f64, dof: usize) -> f64 {
    gamma_q(dof as f64 / 2.0, chi2 / 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference values of the χ² upper tail Q(k/2, x/2), by mpmath's regularised incomplete
    /// gamma function at 30 digits (`mpmath.gammainc(k/2, x/2, inf, regularized=True)`),
    /// quoted to 15: the series branch (x < k/2 + 1) and the continued fraction, a tail of
    /// 1e-8; agreement to 1e-12 relative.
    #[test]
    fn chi2_tail_matches_reference_values() {
        for (x, k, sf) in [
            (1.0, 1, 0.317310507862914),
            (3.84145882069, 1, 0.050000000000123),
            (10.0, 10, 0.440493285065212),
            (124.342114, 100, 0.0499999962382862),
            (0.5, 4, 0.973500978839256),
            (200.0, 100, 1.17845007209794e-8),
        ] {
            let p = chi2_upper_tail(x, k);
            assert!((p - sf).abs() <= 1e-12 * sf, "χ²={x}, k={k}: {p} vs {sf}");
        }
    }

    struct Linear {
        a: DMatrix<f64>,
        b: DVector<f64>,
    }
    impl LeastSquares for Linear {
        fn residuals(
            &mut self,
            x: &[f64],
            _: bool,
        ) -> Result<(DVector<f64>, Option<DMatrix<f64>>), String> {
            let x = DVector::from_column_slice(x);
            Ok((&self.a * x - &self.b, Some(self.a.clone())))
        }
    }

    /// A linear problem: the unbounded answer is the normal equations' (checked by a QR
    /// solve); with a bound in the way the answer sits on it with the others re-fitted.
    #[test]
    fn levenberg_marquardt_solves_linear_problems_and_respects_bounds() {
        let a = DMatrix::from_row_slice(4, 2, &[1.0, 0.0, 1.0, 1.0, 1.0, 2.0, 1.0, 3.0]);
        let b = DVector::from_column_slice(&[1.0, 2.9, 5.1, 7.0]);
        // The normal equations' answer, solved by Cholesky.
        let want = (a.transpose() * &a)
            .cholesky()
            .unwrap()
            .solve(&(a.transpose() * &b));
        let mut p = Linear {
            a: a.clone(),
            b: b.clone(),
        };
        let bounds = (&[-10.0, -10.0][..], &[10.0, 10.0][..], &[20.0, 20.0][..]);
        let (x, _, _, info) =
            levenberg_marquardt(&mut p, &[0.0, 0.0], bounds, &FitParams::default()).unwrap();
        assert!(info.converged);
        assert!(
            (x[0] - want[0]).abs() < 1e-8 && (x[1] - want[1]).abs() < 1e-8,
            "{x:?} vs {want}"
        );
        // Slope bounded at 1.5: intercept re-fitted to mean(b − 1.5 t) = (16 − 9)/4.
        let bounds = (&[-10.0, -10.0][..], &[10.0, 1.5][..], &[20.0, 11.5][..]);
        let (x, _, _, _) =
            levenberg_marquardt(&mut p, &[0.0, 0.0], bounds, &FitParams::default()).unwrap();
        assert_eq!(x[1], 1.5);
        assert!((x[0] - 1.75).abs() < 1e-8, "{x:?}");
    }

    /// An unseen parameter (zero column) is undetermined; the others get the standard errors
    /// of the inverse normal matrix.
    #[test]
    fn an_unseen_parameter_is_undetermined() {
        let j =
            DMatrix::from_row_slice(3, 3, &[1.0, 0.0, 0.0, 0.0, 2.0, 0.0, 1.0, 1.0, 0.0]) * 10.0;
        let s = statistics(&j, &[0.0; 3], &[1.0; 3], &[1.0; 3], &FitParams::default());
        assert_eq!(s.determined, [true, true, false]);
        assert!(s.std_error[2].is_none());
        // (JᵀJ)⁻¹ of the seen two, by the 2 × 2 closed form.
        let h = [[200.0f64, 100.0], [100.0, 500.0]];
        let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
        let c = |i: usize, k: usize| {
            if i == k {
                h[1 - i][1 - k] / det
            } else {
                -h[i][k] / det
            }
        };
        assert!((s.std_error[0].unwrap() - c(0, 0).sqrt()).abs() < 1e-12);
        let r = c(0, 1) / (c(0, 0) * c(1, 1)).sqrt();
        assert!((s.correlation[0][1].unwrap() - r).abs() < 1e-12);
    }
}
