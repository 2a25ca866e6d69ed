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
//! - **leak**: the state is carried to the next basis by the mass overlap O (rows the next
//!   basis's modes, columns the held), so the part of held mode j's shape outside the next
//!   basis, ℓ_j = 1 − Σ_i O_ij² / n_j, is dropped at the update. Updated at every sample it
//!   would leave over the interval a little at a time; held, it rings on until the update
//!   drops it at once: e_leak = Σ_j (A_j + B_j) ℓ_j × (1 − dt/T). n_j = φ_jᵀ M₁ φ_j is the
//!   held shape's own squared norm under the next pose's mass
//!   ([`crate::modal::ModeShapes::mass_norms_of`]): the cables' element masses change with
//!   their lengths, which moves Σ_i O_ij² by about 4e-4 a sample of the interval on the
//!   paper robot's circle for a shape wholly inside the next basis; against n_j that is
//!   not counted. Where a mode crosses the cut (the circle's 33.75 Hz end-effector pair, the
//!   top of the K = 39 kept, at t ≈ 0.465 s, while a cable cluster rises through it),
//!   ℓ_j reaches 0.2-0.97 over two consecutive updates; elsewhere it is < 1e-3.
//!
//! **The interval.** An interval whose e_free + e_forced + e_stat + e_leak exceeds its
//! budget ([`BUDGET_SHARE`] of the tolerance times the pilot's peak deviation) is shortened
//! and its end solved again. Both the first guess and the shortened interval are planned
//! ([`longest_within`]): the longest interval whose error predicted from the held modes'
//! amplitudes now (A_j, B_j, the load's rate change ahead, F'' f ahead) and each mode's
//! drift of frequency a sample, δ_j (Δω_j = δ_j U), is within [`PLAN_SHARE`] of the budget.
//! The first guess takes δ_j over the last interval (the new mode followed back to the held
//! pose by its shape, [`followed_back`]) and F'' of the last three update poses, at most
//! [`MAX_GROWTH`] × the last interval; a shortened one the drift and F'' the rejected
//! interval measured. (Scaling the last interval by budget/error instead, the amplitudes
//! of the last interval and its error's growth ∝ U taken for this one's, 1 471 bases were
//! solved for 943 updates on the paper robot's circle and 281 for 199 on suspended-8's
//! sagged S-curve; planned, 942 for 934 and 219 for 206 at the same share.) At rest Δω = 0
//! and F'' = 0: the interval doubles to its cap.
//!
//! The budget share is measured against updates at every sample (the same K): on the
//! circle, without e_leak, the share 3/16 left 1.29e-3 of the peak and 1/4 8.3e-4 (what the
//! held basis dropped at the crossing depended on where the updates fell); with it, 1/8,
//! 3/16, 1/4 and 3/8 leave 3.2e-4, 3.8e-4, 6.5e-4 and 1.47e-3 (the last over the tolerance at
//! the crossings, each of its intervals spending its budget); the S-curve 1.2e-4, 1.2e-4,
//! 1.9e-4 and 2.7e-4 (its prediction is conservative there: at 3 samples about 1.7 × the
//! whole run's measured error). 3/16 keeps the circle at less than half the tolerance.

use nalgebra::{Matrix6, Vector6};

/// First interval, samples.
pub const FIRST_INTERVAL: usize = 16;
/// Longest interval, s.
pub const MAX_INTERVAL_S: f64 = 1.0;
/// Longest memory counted for a ringing (module docs), s.
pub const MAX_MEMORY_S: f64 = 0.3;
/// The share of the tolerance one interval may spend (module docs: measured against
/// updates at every sample, the paper robot's whole circle / its first second /
/// suspended-8's sagged S-curve: 1/8 3.2e-4 / – / 1.2e-4 of the peak, 3/16 3.8e-4 / 3.3e-4
/// / 1.2e-4, 1/4 6.5e-4 / 5.1e-4 / 1.9e-4, 3/8 1.47e-3 on the circle, from the held
/// modes' mass leaving the kept basis over the intervals where a mode crosses the cut).
pub const BUDGET_SHARE: f64 = 0.1875;

/// The share of the budget an interval is planned for ([`longest_within`]): the rest is
/// the margin for the drift's change from the last interval to this one.
pub const PLAN_SHARE: f64 = 0.9;

/// The most an interval grows from the last one's (× this).
pub const MAX_GROWTH: usize = 2;

/// The largest relative residual ρ of a mode of a Rayleigh–Ritz update, per unit of the
/// tolerance ([`crate::modal::ritz`]: its frequency is then within ρ/2 of an exact one and
/// its shape within ρ/g of the exact modes within a relative gap g). At the default 1e-3,
/// ρ ≤ 1e-5: the frequency error 5e-6 of ω is 1/400 of what an interval of the paper
/// robot's circle holds its modes off by (2e-3 of ω drifts at 11 Hz/s over ~10 ms), and the
/// shape's angle 1e-5/g is 1e-4 at a separated cut (g ≥ 0.1 in λ) and within a
/// near-degenerate pair split by 3 %.
pub const RITZ_RESIDUAL_PER_TOLERANCE: f64 = 0.01;

/// Guard modes above K kept in the Rayleigh–Ritz start block: K/3, 8 ..= 48 (each sweep
/// shrinks mode j's error by λ_j/λ_{K+guard+1}, and a check costs O(n q² + q³) with
/// q = K + guard). Measured on the paper robot's circle (K = 39, 863 bases, first checks
/// predicted by [`crate::modal::ritz::RitzSchedule`], at most 16 sweeps; CPU of the whole
/// run, medians of three runs for 11, 13 and 15, one run for the others): 8, 11, 13, 15, 18
/// and 26 guards took 1.21, 1.09, 1.05, 1.04, 1.23 and 1.22 s, 13-15 the least (more
/// sweeps, each cheaper, and cheaper checks); 8 left 26 updates to the
/// structured shapes, 13 one. (With K or 2K/3 guards a first check at the
/// fifth sweep had been the best fixed choice; the 25 updates 18-19 guards then left to the
/// structured shapes were those whose iteration needed more than the 8 sweeps the
/// iteration then allowed, whatever its own bound said.)
pub fn ritz_guard(modes: usize) -> usize {
    (modes / 3).clamp(8, 48)
}

/// The predicted error of one interval, m.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct IntervalError {
    /// Phase error of the held modes, m.
    pub dynamic_m: f64,
    /// Interpolation error of the static flexibility, m.
    pub static_m: f64,
    /// What the held modes' mass leaving the kept basis drops at once, m.
    pub leak_m: f64,
}

impl IntervalError {
    /// The three, m.
    pub fn total_m(&self) -> f64 {
        self.dynamic_m + self.static_m + self.leak_m
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
    let e: f64 = held
        .iter()
        .zip(omega1)
        .map(|(m, &w1)| m.error(w1 - m.omega_rad_s, rate_change, t_s))
        .sum();
    e * (1.0 - dt_s / t_s)
}

impl HeldMode {
    /// Its share of e_free + e_forced (module docs) before the factor (1 − dt/T), m: held
    /// over `t_s` while its frequency drifts by `dw` (rad/s), the load's rate changing by
    /// `rate_change` (N/s).
    fn error(&self, dw: f64, rate_change: f64, t_s: f64) -> f64 {
        let dw = dw.abs();
        let ringing = self.free_m + self.start_m_s_per_n * rate_change;
        let span = t_s.max(self.memory_s / std::f64::consts::E);
        ringing * dw * span * 0.5 + self.forced_m * 2.0 * dw / self.omega_rad_s
    }
}

/// The predicted error (module docs) of an interval of `u` samples of period `dt_s` whose
/// held modes drift by `drift` (rad/s a sample, one per held mode) while the load's rate
/// changes by `rate_change` (N/s), and whose static flexibility's F'' f reaches
/// `static_per_sample2` (m a sample²), m.
pub fn drifting_error(
    held: &[HeldMode],
    drift: &[f64],
    rate_change: f64,
    static_per_sample2: f64,
    u: usize,
    dt_s: f64,
) -> f64 {
    let stat = static_per_sample2 * (u * u) as f64 / 8.0;
    if u <= 1 {
        return stat;
    }
    let t_s = u as f64 * dt_s;
    let e: f64 = held
        .iter()
        .zip(drift)
        .map(|(m, &d)| m.error(d * u as f64, rate_change, t_s))
        .sum();
    e * (1.0 - 1.0 / u as f64) + stat
}

/// The longest interval, 1 ..= `rate_change.len()` samples, whose [`drifting_error`] is
/// within `target` (m): `rate_change[u − 1]` and `static_per_sample2[u − 1]` those of an
/// interval of u samples (both grow with u, so does the error: a bisection).
pub fn longest_within(
    held: &[HeldMode],
    drift: &[f64],
    rate_change: &[f64],
    static_per_sample2: &[f64],
    dt_s: f64,
    target: f64,
) -> usize {
    let e = |u: usize| {
        drifting_error(
            held,
            drift,
            rate_change[u - 1],
            static_per_sample2[u - 1],
            u,
            dt_s,
        )
    };
    let (mut lo, mut hi) = (1usize, rate_change.len().min(static_per_sample2.len()));
    if hi <= 1 || e(hi) <= target {
        return hi.max(1);
    }
    // e(lo) within (or lo = 1), e(hi) over.
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if e(mid) <= target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// e_leak of the module docs, m: held mode j's dynamic amplitude (free and forced) times
/// the share of its mass outside the next basis, 1 − Σ_i O_ij² / n_j (`overlap` row-major,
/// the next basis's modes as rows, one column per held mode; `norms` n_j = φ_jᵀ M₁ φ_j,
/// the held shape's own squared norm under the next pose's mass, which takes out the
/// change of M with the pose), × (1 − dt/T); 0 without an overlap.
pub fn leak_error(
    held: &[HeldMode],
    overlap: Option<&[f64]>,
    norms: Option<&[f64]>,
    t_s: f64,
    dt_s: f64,
) -> f64 {
    let (Some(o), Some(n)) = (overlap, norms) else {
        return 0.0;
    };
    let cols = held.len();
    if t_s <= dt_s || cols == 0 || n.len() < cols || o.len() % cols != 0 {
        return 0.0;
    }
    let rows = o.len() / cols;
    let e: f64 = held
        .iter()
        .enumerate()
        .map(|(j, m)| {
            let kept: f64 = (0..rows).map(|i| o[i * cols + j] * o[i * cols + j]).sum();
            let leak = if n[j] > 0.0 {
                (1.0 - kept / n[j]).max(0.0)
            } else {
                0.0
            };
            (m.free_m + m.forced_m) * leak
        })
        .sum();
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
    follow(lambda1, overlap, omega0, omega1, false);
}

/// The other way: each of the next basis's modes' angular frequency at the held pose, into
/// `omega0` (rad/s, `omega1` the next basis's): the Rayleigh quotient of its shape under the
/// held modes (`lambda0` their λ, `overlap` as in [`followed`]).
pub fn followed_back(lambda0: &[f64], overlap: Option<&[f64]>, omega1: &[f64], omega0: &mut [f64]) {
    follow(lambda0, overlap, omega1, omega0, true);
}

/// [`followed`] (`back` false: `lambda` the next basis's, the overlap's rows) and
/// [`followed_back`] (`back`: `lambda` the held basis's, the overlap's columns): each mode
/// of `omega_from` followed onto `lambda`'s modes.
fn follow(
    lambda: &[f64],
    overlap: Option<&[f64]>,
    omega_from: &[f64],
    omega_to: &mut [f64],
    back: bool,
) {
    let (n, m) = (lambda.len(), omega_from.len());
    let o = overlap.filter(|o| o.len() == n * m);
    // The overlap of `lambda`'s mode i with `omega_from`'s mode j.
    let at = |o: &[f64], i: usize, j: usize| if back { o[j * n + i] } else { o[i * m + j] };
    for (j, w) in omega_to.iter_mut().enumerate().take(omega_from.len()) {
        let by_index = lambda.get(j).map_or(omega_from[j], |l| l.sqrt());
        *w = match o {
            Some(o) => {
                let (mut num, mut den) = (0.0, 0.0);
                for (i, l) in lambda.iter().enumerate() {
                    let x = at(o, i, j) * at(o, i, j);
                    num += x * l;
                    den += x;
                }
                if den >= FOLLOW_MIN {
                    (num / den).sqrt()
                } else {
                    by_index
                }
            }
            None => by_index,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A held mode of 10 rad/s, free amplitude 1 m and forced 0.5 m, no memory.
    const MODE: HeldMode = HeldMode {
        free_m: 1.0,
        forced_m: 0.5,
        start_m_s_per_n: 0.0,
        omega_rad_s: 10.0,
        memory_s: 0.0,
    };

    #[test]
    fn intervals_grow_at_rest_and_shrink_with_error() {
        let mode = MODE;
        // At rest (no drift, no F'') the plan takes the longest interval offered; a drift
        // of 1 rad/s a sample at dt = 0.1 s leaves (0.05 u + 0.1) u (1 − 1/u) for u
        // samples: 2 samples within 0.21, 1 below it.
        let (zero, cap) = (vec![0.0; 20], 20);
        assert_eq!(
            longest_within(&[mode], &[0.0], &zero, &zero, 0.1, 1e-9),
            cap
        );
        assert_eq!(longest_within(&[mode], &[1.0], &zero, &zero, 0.1, 0.21), 2);
        assert_eq!(longest_within(&[mode], &[1.0], &zero, &zero, 0.1, 0.19), 1);
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
        let (mut w1, swap) = ([0.0; 2], [0.0, 1.0, 1.0, 0.0]);
        followed(&[4.0, 9.0], Some(&swap), &[2.5, 2.6], &mut w1);
        assert_eq!(w1, [3.0, 2.0]);
        // And back: the next basis's mode 1 is the held mode 0.
        followed_back(&[6.25, 6.76], Some(&swap), &[2.0, 3.0], &mut w1);
        assert_eq!(w1, [2.6, 2.5]);
        // A quadratic F(s) = s² I: F'' = 2 I whatever the spacing.
        let f = |s: f64| Matrix6::identity() * s * s;
        let d2 = second_difference(&f(-3.0), &f(0.0), &f(5.0), 3, 5);
        assert!((d2 - Matrix6::identity() * 2.0).norm() < 1e-12);
    }

    /// e_leak counts the share of a held shape's mass outside the next basis, measured
    /// against the shape's own norm under the next pose's mass: a shape whose cables got
    /// 2 % lighter (Σ O² = 0.98 = its norm) leaks nothing, one with half its mass outside
    /// leaks its dynamic amplitude's half, × (1 − dt/T).
    #[test]
    fn the_mass_leaving_the_kept_basis_is_counted_against_the_shapes_own_norm() {
        let mode = MODE;
        let held = [mode, mode];
        // Two next modes (rows) by two held (columns): held 0 wholly inside at norm 0.98,
        // held 1 with half of its norm 1.02 inside.
        let a = 0.98f64.sqrt();
        let b = (0.51f64 / 2.0).sqrt();
        let overlap = [a, b, 0.0, b];
        let norms = [0.98, 1.02];
        let e = leak_error(&held, Some(&overlap), Some(&norms), 0.004, 0.001);
        assert!((e - 1.5 * 0.5 * 0.75).abs() < 1e-12, "{e}");
        // Against a unit norm, held 0 would seem to leak 2 % of its mass.
        let unnormed = leak_error(&held, Some(&overlap), Some(&[1.0, 1.02]), 0.004, 0.001);
        assert!(
            (unnormed - e - 1.5 * 0.02 * 0.75).abs() < 1e-12,
            "{unnormed}"
        );
        // None against the basis updated at every sample, none without an overlap.
        assert_eq!(
            leak_error(&held, Some(&overlap), Some(&norms), 0.001, 0.001),
            0.0
        );
        assert_eq!(leak_error(&held, None, Some(&norms), 0.004, 0.001), 0.0);
    }

    /// The planned interval: the error of a drift a sample over u samples is the held
    /// error with ω₁ = ω₀ + drift·u plus F''f·u²/8, and the bisection finds the longest
    /// interval within the target that a scan over every length finds.
    #[test]
    fn the_planned_interval_is_the_longest_within_the_target() {
        let held = [
            HeldMode {
                free_m: 1e-6,
                forced_m: 2e-7,
                start_m_s_per_n: 1e-9,
                omega_rad_s: 60.0,
                memory_s: 0.2,
            },
            HeldMode {
                free_m: 3e-7,
                forced_m: 1e-7,
                start_m_s_per_n: 0.0,
                omega_rad_s: 200.0,
                memory_s: 0.01,
            },
        ];
        let drift = [0.02, 0.05];
        let dt = 1e-3;
        let rate_changes: Vec<f64> = (1..=300).map(|u| 3.0 * u as f64).collect();
        let statics: Vec<f64> = (1..=300)
            .map(|u| 1e-12 * (1.0 + (u as f64).sqrt()))
            .collect();
        for u in [2usize, 7, 40] {
            let omega1 = [60.0 + 0.02 * u as f64, 200.0 + 0.05 * u as f64];
            let direct = dynamic_error(&held, &omega1, rate_changes[u - 1], u as f64 * dt, dt)
                + statics[u - 1] * (u * u) as f64 / 8.0;
            let planned = drifting_error(&held, &drift, rate_changes[u - 1], statics[u - 1], u, dt);
            assert!(
                (planned - direct).abs() <= 1e-12 * direct,
                "{planned} vs {direct}"
            );
        }
        for target in [1e-12, 1e-10, 3e-10, 1e-9, 1e-8, 1.0] {
            let found = longest_within(&held, &drift, &rate_changes, &statics, dt, target);
            let scanned = (1..=300)
                .filter(|&u| {
                    drifting_error(&held, &drift, rate_changes[u - 1], statics[u - 1], u, dt)
                        <= target
                })
                .max()
                .unwrap_or(1);
            assert_eq!(found, scanned, "target {target:e}");
        }
    }
}
