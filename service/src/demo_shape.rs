//! The demo's shaping (`DemoConfig::shape`: ZV, ZVD or EI): its replay shapes its poses
//! online with the live end-effector mode.
//!
//! Each pose of the circle goes through an [`OnlineShaper`] (ring buffer, no allocation per
//! sample) designed at the end-effector mode frequency of the latest ok estimate that has one
//! (`ee_mode_hz`), with the damping ratio the scene's damping gives at that frequency
//! ([`Damping::modal_ratio`]; 0 without `[damping]`). Until the first such estimate arrives,
//! the poses pass unshaped (the shaper has no design yet); the summary says how many did.
//! The published pose is the shaper's output. The replay example's shaping uses the same type.

use nalgebra::Vector3;

use super::ServiceError;
use crate::scene::{Damping, Scene};
use crate::trajectory::shaping::{Impulses, OnlineShaper, ShaperKind, DEFAULT_MIN_FREQUENCY_HZ};

/// The replay's shaper and what it did.
#[derive(Debug, Clone)]
pub struct DemoShape {
    shaper: OnlineShaper,
    damping: Damping,
    /// Poses published before the shaper had a design (unshaped).
    unshaped: u64,
    /// Poses published shaped.
    shaped: u64,
    /// Σ of the design frequency over the shaped poses, Hz.
    sum_design_hz: f64,
    /// Largest distance between a published (shaped) pose and the unshaped one, m.
    max_deviation_m: f64,
}

impl DemoShape {
    /// A shaper of `kind` for poses at `rate_hz` on `scene` (its damping).
    pub fn new(kind: ShaperKind, rate_hz: f64, scene: &Scene) -> Result<Self, ServiceError> {
        let shaper =
            OnlineShaper::new(kind, 1.0 / rate_hz, DEFAULT_MIN_FREQUENCY_HZ).map_err(|reason| {
                ServiceError::Shape {
                    kind: kind.as_str(),
                    reason,
                }
            })?;
        Ok(DemoShape {
            shaper,
            damping: scene.damping,
            unshaped: 0,
            shaped: 0,
            sum_design_hz: 0.0,
            max_deviation_m: 0.0,
        })
    }

    /// The pose to publish for the trajectory's position `x` (m), given the end-effector mode
    /// frequency of the latest ok estimate (Hz; not finite or ≤ 0: none yet, or this cycle's
    /// estimate had none, and the shaper keeps its last design). No allocation.
    pub fn push(&mut self, x: Vector3<f64>, ee_mode_hz: f64) -> Vector3<f64> {
        let zeta = if ee_mode_hz.is_finite() && ee_mode_hz > 0.0 {
            self.damping
                .modal_ratio(2.0 * std::f64::consts::PI * ee_mode_hz)
        } else {
            f64::NAN
        };
        let y = self.shaper.push(x, ee_mode_hz, zeta);
        match self.shaper.design() {
            None => self.unshaped += 1,
            Some((f, _)) => {
                self.shaped += 1;
                self.sum_design_hz += f;
            }
        }
        self.max_deviation_m = self.max_deviation_m.max((y - x).norm());
        y
    }

    /// The summary line: the shaper, the mean design frequency, the delay it adds there, the
    /// poses published unshaped before the first estimate with an end-effector mode, and the
    /// largest distance between the shaped and the unshaped path.
    pub fn summary_line(&self) -> String {
        let kind = self.shaper.kind();
        if self.shaped == 0 {
            return format!(
                "  shaping: {} online on the end-effector mode: no estimate with an end-effector \
                 mode arrived; all {} poses published unshaped",
                kind.as_str(),
                self.unshaped
            );
        }
        let mean_hz = self.sum_design_hz / self.shaped as f64;
        let zeta = self
            .damping
            .modal_ratio(2.0 * std::f64::consts::PI * mean_hz);
        let delay_ms =
            Impulses::design(kind, mean_hz, zeta).map_or(f64::NAN, |i| i.duration_s() * 1e3);
        format!(
            "  shaping: {} online on the end-effector mode (ζ {:.4}): mean design frequency \
             {:.4} Hz, adds {:.2} ms; {} poses published unshaped before the first estimate with \
             an end-effector mode, {} shaped; shaped path's peak deviation from the unshaped \
             {:.4} mm",
            kind.as_str(),
            zeta,
            mean_hz,
            delay_ms,
            self.unshaped,
            self.shaped,
            self.max_deviation_m * 1e3
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Before an end-effector mode arrives the published pose is the trajectory's, bit for
    /// bit; after, it is what an independent `OnlineShaper` fed the same samples returns
    /// (ZV at 30 Hz, ζ 0 on the undamped paper scene).
    #[test]
    fn poses_pass_unshaped_until_the_first_mode_then_are_the_shapers_output() {
        let scene = Scene::load("spatial-paper").unwrap();
        let mut demo = DemoShape::new(ShaperKind::Zv, 1000.0, &scene).unwrap();
        let mut reference =
            OnlineShaper::new(ShaperKind::Zv, 1e-3, DEFAULT_MIN_FREQUENCY_HZ).unwrap();
        let path = |k: usize| Vector3::new(0.1 * (k as f64 * 0.01).sin(), 0.002 * k as f64, 1.0);
        for k in 0..200 {
            let f = if k < 50 { f64::NAN } else { 30.0 };
            let y = demo.push(path(k), f);
            let r = reference.push(path(k), f, if k < 50 { f64::NAN } else { 0.0 });
            if k < 50 {
                assert_eq!(y, path(k), "sample {k}");
            }
            assert_eq!(y, r, "sample {k}");
        }
        assert_eq!((demo.unshaped, demo.shaped), (50, 150));
        assert!((demo.sum_design_hz / 150.0 - 30.0).abs() < 1e-12);
        assert!(demo.max_deviation_m > 0.0);
        let line = demo.summary_line();
        assert!(line.contains("adds 16.67 ms"), "{line}");
    }
}
