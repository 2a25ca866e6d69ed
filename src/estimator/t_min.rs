//! [`Tmin`]: which lower tension bounds (N) a cycle or an analysis uses.
//!
//! A scene gives each cable its own lower bound (`[[cables]] t_min`, else `[tension] t_min`);
//! those are the default everywhere. A caller that wants other bounds says so by name —
//! one value for every cable (a uniform set-point) or one per cable — so the
//! scene-wide `[tension] t_min` cannot be passed by mistake where a cable has its own.

use crate::scene::{Scene, MAX_CABLES};

/// The lower tension bounds of one cycle or analysis.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Tmin<'a> {
    /// The scene's own bounds: cable i's `t_min`, else the scene's `[tension] t_min`.
    #[default]
    Scene,
    /// One value (N) for every cable, overriding the scene's (a uniform set-point).
    Uniform(f64),
    /// One value (N) per cable of the scene, in the scene's cable order. A slice of another
    /// length is refused by the estimator as `TminOutOfRange`.
    PerCable(&'a [f64]),
}

impl Tmin<'_> {
    /// A caller's T_min override: `Uniform` when given, the scene's bounds otherwise.
    pub fn from_override(t_min_n: Option<f64>) -> Tmin<'static> {
        t_min_n.map_or(Tmin::Scene, Tmin::Uniform)
    }

    /// Write the bounds (N) for `scene`'s cables into `out[..n]` (n = the scene's cable
    /// count, ≤ `out.len()`); a `PerCable` slice of the wrong length writes NaN, which every
    /// bound check refuses. No allocation.
    pub fn fill(&self, scene: &Scene, out: &mut [f64]) {
        let n = scene.n_cables();
        match *self {
            Tmin::Scene => {
                for (i, v) in out[..n].iter_mut().enumerate() {
                    *v = scene.cable_t_min_n(i);
                }
            }
            Tmin::Uniform(t) => out[..n].fill(t),
            Tmin::PerCable(t) if t.len() == n => out[..n].copy_from_slice(t),
            Tmin::PerCable(_) => out[..n].fill(f64::NAN),
        }
    }

    /// The bounds (N) for `scene`'s cables, one per cable (entries past them NaN).
    pub fn per_cable(&self, scene: &Scene) -> [f64; MAX_CABLES] {
        let mut t = [f64::NAN; MAX_CABLES];
        self.fill(scene, &mut t);
        t
    }

    /// The smallest of the bounds (N) over `scene`'s cables: the value a study's `t_min_n`
    /// column carries (every cable's when they are equal).
    pub fn lowest_n(&self, scene: &Scene) -> f64 {
        let t = self.per_cable(scene);
        t[..scene.n_cables()]
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }
}
