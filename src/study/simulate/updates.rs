//! When the modal basis is replaced along the path: the error a held basis makes over an
//! interval, predicted before the interval is run, and the next interval from it.
//!
//! Over an interval of T = U·dt from update pose p₀ to p₁ the response uses p₀'s modes
//! (their dynamic parts) and a static flexibility interpolated linearly from F(p₀) to
//! F(p₁) (the quasi-static part: [`crate::modal::response::ModalResponse::displacement_with`]).
//! Both bases are solved before the interval is run, so its error is predicted from them:
//!
//! - **dynamic**: mode j rings with the end-effector amplitude A_j (its dynamic amplitude
//!   now, plus what the interval's load can add, |φ_j||ψ_j|∫|f|dt/ω_j, ψ_j the mode's load
//!   shape, φ_j where the cables carry no mass); held at ω_j(p₀) while
//!   the robot's drifts towards ω_j(p₁), it falls out of phase by |Δω_j|·T/2 over the
//!   interval: e_dyn = Σ_j A_j |Δω_j| T/2 (modes matched by index: a crossing shows as a
//!   large Δω and shortens the interval, the safe side);
//! - **static**: linear interpolation of F misses F''T²/8, F'' the second divided
//!   difference of the last three update poses' flexibilities: e_stat = max over the
//!   interval of |(F'' f)| T²/8.
//!
//! An interval whose e_dyn + e_stat exceeds its budget (a quarter of the tolerance times
//! the pilot's peak deviation) is shortened and its end solved again; the next interval
//! grows by the square root of the budget's margin (both errors go as T²), at most
//! doubling. At rest Δω = 0 and F'' = 0: the interval grows to its cap.

use nalgebra::{Matrix6, Vector6};

/// First interval, samples.
pub const FIRST_INTERVAL: usize = 16;
/// Longest interval, s.
pub const MAX_INTERVAL_S: f64 = 1.0;
/// The share of the tolerance one interval may spend.
pub const BUDGET_SHARE: f64 = 0.25;

/// The predicted error of one interval, m.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct IntervalError {
    /// Phase error of the held modes, m.
    pub dynamic_m: f64,
    /// Interpolation error of the static flexibility, m.
    pub static_m: f64,
}

impl IntervalError {
    /// Both, m.
    pub fn total_m(&self) -> f64 {
        self.dynamic_m + self.static_m
    }
}

/// e_dyn of the module docs: `amplitude[j]` the end-effector dynamic amplitude of held mode
/// j now (m), `phi_norm2[j]` its |φ_j||ψ_j| (1/kg; ψ_j its load shape), `lambda0`, `lambda1` the held and the next
/// basis's λ (rad²/s², matched by index), `load_impulse` ∫|f|dt over the interval (N·s),
/// `t_s` the interval.
pub fn dynamic_error(
    amplitude: &[f64],
    phi_norm2: &[f64],
    lambda0: &[f64],
    lambda1: &[f64],
    load_impulse: f64,
    t_s: f64,
) -> f64 {
    let n = amplitude.len().min(lambda0.len()).min(lambda1.len());
    let mut e = 0.0;
    for j in 0..n {
        let w0 = lambda0[j].sqrt();
        let a = amplitude[j] + phi_norm2[j] * load_impulse / w0;
        e += a * (lambda1[j].sqrt() - w0).abs() * 0.5 * t_s;
    }
    e
}

/// F'' per sample² from three flexibilities at samples −`back`, 0 and +`ahead` (the second
/// divided difference); zero without a previous pose (`back` = 0).
pub fn second_difference(
    previous: &Matrix6<f64>,
    now: &Matrix6<f64>,
    next: &Matrix6<f64>,
    back: usize,
    ahead: usize,
) -> Matrix6<f64> {
    if back == 0 || ahead == 0 {
        return Matrix6::zeros();
    }
    let (b, a) = (back as f64, ahead as f64);
    ((next - now) / a - (now - previous) / b) * (2.0 / (a + b))
}

/// e_stat of the module docs over loads `f` of an interval of `ahead` samples: the largest
/// |translation of F'' f| · ahead²/8.
pub fn static_error(
    d2: &Matrix6<f64>,
    loads: impl Iterator<Item = Vector6<f64>>,
    ahead: usize,
) -> f64 {
    let worst = loads.fold(0.0f64, |m, f| m.max((d2 * f).fixed_rows::<3>(0).norm()));
    worst * (ahead * ahead) as f64 / 8.0
}

/// The next interval from one of `u` samples that predicted `error` against `budget` (m),
/// within 1 ..= `max`: ×min(2, 0.9·√(budget/error)).
pub fn next_interval(u: usize, error: f64, budget: f64, max: usize) -> usize {
    let factor = if error > 0.0 {
        (0.9 * (budget / error).sqrt()).min(2.0)
    } else {
        2.0
    };
    ((u as f64 * factor).floor() as usize).clamp(1, max.max(1))
}

/// The shortened interval after one of `u` samples predicted `error` over `budget`:
/// ×max(1/4, 0.9·√(budget/error)), at least 1 and below `u` when `u` > 1.
pub fn shortened(u: usize, error: f64, budget: f64) -> usize {
    let factor = (0.9 * (budget / error).sqrt()).max(0.25);
    ((u as f64 * factor).floor() as usize).clamp(1, u.saturating_sub(1).max(1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_grow_at_rest_and_shrink_with_error() {
        assert_eq!(next_interval(10, 0.0, 1.0, 1000), 20);
        assert_eq!(next_interval(10, 0.0, 1.0, 15), 15);
        assert_eq!(next_interval(10, 4.0, 1.0, 1000), 4);
        assert_eq!(shortened(10, 100.0, 1.0), 2);
        assert_eq!(shortened(1, 100.0, 1.0), 1);
        // A frozen basis at rest: no drift, no error.
        let e = dynamic_error(&[1.0], &[1.0], &[100.0], &[100.0], 5.0, 0.1);
        assert_eq!(e, 0.0);
        // A quadratic F(s) = s² I: F'' = 2 I whatever the spacing.
        let f = |s: f64| Matrix6::identity() * s * s;
        let d2 = second_difference(&f(-3.0), &f(0.0), &f(5.0), 3, 5);
        assert!((d2 - Matrix6::identity() * 2.0).norm() < 1e-12);
    }
}
