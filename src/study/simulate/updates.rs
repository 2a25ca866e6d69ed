//! When the modal basis is replaced along the path: the error a held basis makes over an
//! interval, predicted before the interval is run, and the next interval from it.
//!
//! Over an interval of T = U·dt from update pose p₀ to p₁ the response uses p₀'s modes
//! (their dynamic parts) and a static flexibility interpolated linearly from F(p₀) to
//! F(p₁) (the quasi-static part: [`crate::modal::response::ModalResponse::displacement_with`]).
//! Both bases are solved before the interval is run, so its error is predicted from them:
//!
//! - **dynamic**: held mode j is followed to the next basis by its shape: its frequency
//!   there is the Rayleigh quotient of its shape under the next pose's modes,
//!   ω_j(p₁)² = Σ_i O_ij² λ_i(p₁) / Σ_i O_ij² with the whole shapes' mass overlap O
//!   ([`followed`]; a crossing or a rotation inside a near-degenerate cluster is followed,
//!   not taken for a jump of frequency). Held at ω_j(p₀) while the robot's drifts to
//!   ω_j(p₁), the mode's *free* vibration (its amplitude A_j now, less the forced part of
//!   the load's ramp, [`crate::modal::response::ModalResponse::ringing_amplitudes`], plus
//!   what the change of the load's rate over the interval can start, |φ_j||ψ_j||Δḟ|/ω_j³)
//!   falls out of phase by |Δω_j|·T/2, and that phase error stays in the motion as long as
//!   it rings: the next intervals' add to it. With the ringing's memory τ_j = 1/(ζ_jω_j)
//!   (at most the rest of the path and [`MAX_MEMORY_S`]), the phase errors of the τ_j/T intervals it spans add
//!   up to A_j|Δω_j|τ_j/2 against an amplitude decayed by e^{−t/τ_j}, at most
//!   A_j|Δω_j|τ_j/(2e): e_free = Σ_j A_j |Δω_j| max(T, τ_j/e)/2. The forced part B_j
//!   follows the frequency in amplitude only: e_forced = Σ_j B_j · 2|Δω_j|/ω_j. Against
//!   the reference the policy is held to, the basis updated at every sample (which holds
//!   each mode for one sample too), an interval of U samples holds U − 1 samples more:
//!   both are counted × (1 − dt/T), none for U = 1.
//!   (Counting each interval's phase error alone, and the interval's whole load impulse
//!   as ringing, the paper's circle was updated every 4 samples along its whole 10 s and
//!   still missed 1e-3 in its first second, where the modes ring from the start at
//!   speed.)
//! - **static**: linear interpolation of F misses F''T²/8, F'' the second divided
//!   difference of the last three update poses' flexibilities: e_stat = max over the
//!   interval of |(F'' f)| T²/8.
//!
//! An interval whose e_free + e_forced + e_stat exceeds its budget ([`BUDGET_SHARE`] of the
//! tolerance times the pilot's peak deviation) is shortened and its end solved again; the
//! next interval grows by the budget's margin (the errors grow at least linearly with T),
//! at most doubling. At rest Δω = 0 and F'' = 0: the interval grows to its cap.

use nalgebra::{Matrix6, Vector6};

/// First interval, samples.
pub const FIRST_INTERVAL: usize = 16;
/// Longest interval, s.
pub const MAX_INTERVAL_S: f64 = 1.0;
/// Longest memory counted for a ringing (module docs), s.
pub const MAX_MEMORY_S: f64 = 0.3;
/// The share of the tolerance one interval may spend (module docs: measured on the paper
/// robot's circle, 1/4 left 1.4e-3 of the peak against updates at every sample, 1/8
/// 5.3e-4, 1/16 2.1e-4).
pub const BUDGET_SHARE: f64 = 0.125;

/// The largest relative residual ρ of a mode of a Rayleigh–Ritz update, per unit of the
/// tolerance ([`crate::modal::ritz`]: its frequency is then within ρ/2 of an exact one and
/// its shape within ρ/g of the exact modes within a relative gap g). At the default 1e-3,
/// ρ ≤ 1e-5: the frequency error 5e-6 of ω is 1/400 of what an interval of the paper
/// robot's circle holds its modes off by (2e-3 of ω drifts at 11 Hz/s over ~10 ms), and the
/// shape's angle 1e-5/g is 1e-4 at a separated cut (g ≥ 0.1 in λ) and within a
/// near-degenerate pair split by 3 %.
pub const RITZ_RESIDUAL_PER_TOLERANCE: f64 = 0.01;

/// Guard modes above K kept in the Rayleigh–Ritz start block: K, 8 ..= 48 (each sweep
/// shrinks mode j's error by λ_j/λ_{K+guard+1}; measured on the paper robot's circle, K = 39:
/// with 9, 24 and 40 guards 414, 716 and 918 of its 943 updates met the residual bound,
/// the rest fell back to the structured shapes).
pub fn ritz_guard(modes: usize) -> usize {
    modes.clamp(8, 48)
}

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

/// A held mode's share of the dynamic error (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HeldMode {
    /// The end-effector amplitude of its free vibration now, m.
    pub free_m: f64,
    /// The end-effector amplitude of its forced part now, m.
    pub forced_m: f64,
    /// |φ||ψ|/ω³: the free amplitude a change of the load's rate of 1 N/s starts, m·s/N.
    pub start_m_s_per_n: f64,
    /// Its angular frequency at the held pose, rad/s.
    pub omega_rad_s: f64,
    /// How long its free vibration rings, 1/(ζω), at most the rest of the path and
    /// [`MAX_MEMORY_S`], s.
    pub memory_s: f64,
}

/// e_free + e_forced of the module docs, m: `held` the held modes, `omega1` each one's
/// angular frequency at the next update pose (rad/s, [`followed`]), `rate_change` the
/// largest change of the load's rate over the interval (N/s), `t_s` the interval, `dt_s`
/// the sample period (against updates at every sample: × (1 − dt/T)).
pub fn dynamic_error(
    held: &[HeldMode],
    omega1: &[f64],
    rate_change: f64,
    t_s: f64,
    dt_s: f64,
) -> f64 {
    if t_s <= dt_s {
        return 0.0;
    }
    let mut e = 0.0;
    for (m, &w1) in held.iter().zip(omega1) {
        let dw = (w1 - m.omega_rad_s).abs();
        let ringing = m.free_m + m.start_m_s_per_n * rate_change;
        let span = t_s.max(m.memory_s / std::f64::consts::E);
        e += ringing * dw * span * 0.5 + m.forced_m * 2.0 * dw / m.omega_rad_s;
    }
    e * (1.0 - dt_s / t_s)
}

/// The share of a held shape's mass that must lie in the next basis for its frequency to
/// be followed there ([`followed`]); below it, the next basis's mode of the same index.
pub const FOLLOW_MIN: f64 = 0.5;

/// Each held mode's angular frequency at the next update pose, into `omega1` (rad/s, one
/// per held mode, `omega0` the held ones): with the mass `overlap` of the next basis (rows,
/// `lambda1` its λ, rad²/s²) with the held one (columns), the Rayleigh quotient of the held
/// shape under the next pose's modes, √(Σ_i O_ij² λ1_i / Σ_i O_ij²) (module docs); by index
/// without an overlap, or when less than [`FOLLOW_MIN`] of the shape's mass is in the next
/// basis (the held frequency past the next basis's last mode).
pub fn followed(lambda1: &[f64], overlap: Option<&[f64]>, omega0: &[f64], omega1: &mut [f64]) {
    let held = omega0.len();
    for (j, w1) in omega1.iter_mut().enumerate().take(held) {
        let by_index = lambda1.get(j).map_or(omega0[j], |l| l.sqrt());
        *w1 = match overlap {
            Some(o) if o.len() == lambda1.len() * held => {
                let (mut num, mut den) = (0.0, 0.0);
                for (i, l) in lambda1.iter().enumerate() {
                    let x = o[i * held + j] * o[i * held + j];
                    num += x * l;
                    den += x;
                }
                if den >= FOLLOW_MIN {
                    (num / den).sqrt()
                } else {
                    by_index
                }
            }
            _ => by_index,
        };
    }
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
/// within 1 ..= `max`: ×min(2, 0.9·budget/error).
pub fn next_interval(u: usize, error: f64, budget: f64, max: usize) -> usize {
    let factor = if error > 0.0 {
        (0.9 * budget / error).min(2.0)
    } else {
        2.0
    };
    ((u as f64 * factor).floor() as usize).clamp(1, max.max(1))
}

/// The shortened interval after one of `u` samples predicted `error` over `budget`:
/// ×max(1/4, 0.9·budget/error), at least 1 and below `u` when `u` > 1.
pub fn shortened(u: usize, error: f64, budget: f64) -> usize {
    let factor = (0.9 * budget / error).max(0.25);
    ((u as f64 * factor).floor() as usize).clamp(1, u.saturating_sub(1).max(1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_grow_at_rest_and_shrink_with_error() {
        assert_eq!(next_interval(10, 0.0, 1.0, 1000), 20);
        assert_eq!(next_interval(10, 0.0, 1.0, 15), 15);
        assert_eq!(next_interval(10, 4.0, 1.0, 1000), 2);
        assert_eq!(shortened(10, 100.0, 1.0), 2);
        assert_eq!(shortened(1, 100.0, 1.0), 1);
        let mode = HeldMode {
            free_m: 1.0,
            forced_m: 0.5,
            start_m_s_per_n: 0.0,
            omega_rad_s: 10.0,
            memory_s: 0.0,
        };
        // A frozen basis at rest: no drift, no error.
        assert_eq!(dynamic_error(&[mode], &[10.0], 0.0, 0.1, 0.0), 0.0);
        // One sample held is what updating at every sample does: no error against it.
        assert_eq!(dynamic_error(&[mode], &[11.0], 0.0, 0.1, 0.1), 0.0);
        // A drift of 1 rad/s over 0.1 s: the free part's phase error A·Δω·T/2 and the
        // forced part's amplitude B·2Δω/ω.
        let e = dynamic_error(&[mode], &[11.0], 0.0, 0.1, 0.0);
        assert!((e - (0.05 + 0.1)).abs() < 1e-12, "{e}");
        // A ringing that outlasts the interval carries its phase error on: τ/e.
        let long = HeldMode {
            memory_s: 1.0,
            forced_m: 0.0,
            ..mode
        };
        let e = dynamic_error(&[long], &[11.0], 0.0, 0.1, 0.0);
        assert!((e - 0.5 / std::f64::consts::E).abs() < 1e-12, "{e}");
        // Followed through a crossing by the shape: held mode 0 is the next basis's mode 1.
        let mut w1 = [0.0; 2];
        followed(
            &[4.0, 9.0],
            Some(&[0.0, 1.0, 1.0, 0.0]),
            &[2.5, 2.6],
            &mut w1,
        );
        assert_eq!(w1, [3.0, 2.0]);
        // A quadratic F(s) = s² I: F'' = 2 I whatever the spacing.
        let f = |s: f64| Matrix6::identity() * s * s;
        let d2 = second_difference(&f(-3.0), &f(0.0), &f(5.0), 3, 5);
        assert!((d2 - Matrix6::identity() * 2.0).norm() < 1e-12);
    }
}
