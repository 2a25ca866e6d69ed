//! Signals with known modes for the measured-frequency tracker's tests: a single-degree-of-
//! freedom oscillator under white-noise force, whose natural frequency may move, integrated
//! by classical Runge-Kutta; Gaussian noise from [`crate::Rng`]. Never allocates.

use crate::Rng;

/// A standard normal number (the core's Box-Muller on two uniform draws).
pub fn gaussian(rng: &mut Rng) -> f64 {
    let u1 = rng.next();
    let u2 = rng.next();
    cablevib::rng::box_muller(u1, u2)
}

/// ẍ + 2ζω ẋ + ω² x = F, F held over each step (unit mass).
#[derive(Debug, Clone, Copy)]
pub struct Oscillator {
    /// Displacement, m.
    pub x: f64,
    /// Velocity, m/s.
    pub v: f64,
    /// Damping ratio ζ.
    pub zeta: f64,
}

impl Oscillator {
    /// At rest with damping ratio `zeta`.
    pub fn new(zeta: f64) -> Oscillator {
        Oscillator {
            x: 0.0,
            v: 0.0,
            zeta,
        }
    }

    /// One step of `dt_s` at natural frequency `f_hz` under force `force` (per unit mass);
    /// returns the acceleration at the step's end, m/s². RK4: the frequency error is
    /// O((ωΔt)⁴) ≈ 1e-6 relative at ωΔt = 0.2.
    pub fn step(&mut self, f_hz: f64, force: f64, dt_s: f64) -> f64 {
        let w = 2.0 * core::f64::consts::PI * f_hz;
        let (c, k) = (2.0 * self.zeta * w, w * w);
        let acc = |x: f64, v: f64| force - c * v - k * x;
        let (x, v) = (self.x, self.v);
        let (k1x, k1v) = (v, acc(x, v));
        let (k2x, k2v) = (
            v + 0.5 * dt_s * k1v,
            acc(x + 0.5 * dt_s * k1x, v + 0.5 * dt_s * k1v),
        );
        let (k3x, k3v) = (
            v + 0.5 * dt_s * k2v,
            acc(x + 0.5 * dt_s * k2x, v + 0.5 * dt_s * k2v),
        );
        let (k4x, k4v) = (v + dt_s * k3v, acc(x + dt_s * k3x, v + dt_s * k3v));
        self.x += dt_s / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        self.v += dt_s / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        acc(self.x, self.v)
    }
}
