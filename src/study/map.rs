//! The first natural frequencies (f1 .. fK), the end-effector mode and the softest static
//! stiffness over a workspace grid, at one orientation or over a sweep of orientations.
//!
//! Grid points are lo, lo + step, …, hi on each axis; the heat-map plane's two axes make a
//! panel, and the third (slice) axis gives one panel per value. Every point takes the
//! scene's orientation q₀ (the scene file's, or a caller's override). With a [`Tilt`] (rigid
//! end-effectors only) the panels are orientations instead: the slice axis takes one value
//! and panel k has q_k = R(a, θ_k) · q₀, q₀ turned by θ_k about the world axis a.

use super::points::{evaluate_points_with, status_histogram, PointResult, Workers};
use super::{estimator_params, Param, ParamError, StudyError};
use crate::estimator::Tmin;
use crate::kinematics::{rotated_about, Pose};
use crate::scene::Scene;
use crate::stats::StatusHistogram;
use nalgebra::Vector3;

/// Most values on one grid axis.
pub const MAX_AXIS_VALUES: usize = 100_000;
/// Most grid points of one map (one `PointResult` each, ~0.5 kB).
pub const MAX_GRID_POINTS: usize = 5_000_000;
/// Floating-point noise of a grid value is snapped to a lattice of 1/this m (1 nm), so that
/// 0.25 + 7 × 0.1 prints as 0.95 ([`grid_axis`]).
const GRID_LATTICE_PER_M: f64 = 1e9;
/// A grid value's floating-point noise, relative to the size of its terms: a snap to the
/// lattice (or to 0) larger than this is a value the user gave, kept as it is.
const GRID_NOISE: f64 = 1e-12;
/// A plane axis given no range spans the central 80 % of the frame: this is half of it.
const DEFAULT_HALF_SPAN_SHARE: f64 = 0.4;

/// A closed interval `[lo, hi]`, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
}

/// The plane of a heat map; the third axis is swept as slices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plane {
    /// x horizontal, y vertical; slices along z.
    Xy,
    /// x horizontal, z vertical; slices along y.
    Xz,
    /// y horizontal, z vertical; slices along x.
    Yz,
}

impl Plane {
    /// (horizontal, vertical, slice) axis indices.
    pub fn axes(self) -> (usize, usize, usize) {
        match self {
            Plane::Xy => (0, 1, 2),
            Plane::Xz => (0, 2, 1),
            Plane::Yz => (1, 2, 0),
        }
    }
}

/// Which value a map shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapValue {
    /// The first natural frequency of the whole model, Hz (`Estimate::f1_hz`).
    F1,
    /// The end-effector mode (lowest mode with end-effector participation ≥ threshold), Hz.
    EeMode,
    /// The k-th natural frequency, Hz (1-based; needs k ≤ the map's mode count).
    Mode(usize),
    /// The smallest principal value of the static end-effector stiffness, N/m.
    StiffnessMin,
}

/// Most tilt angles of one map (one panel each).
pub const MAX_TILTS: usize = 360;

/// A sweep of the orientation: the scene's orientation turned about a fixed world axis by
/// each angle of a range (rigid end-effectors only).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tilt {
    /// The rotation axis in the world frame (any non-zero length).
    pub axis: Vector3<f64>,
    /// The angles, degrees: lo, lo + step, …, hi.
    pub range_deg: Interval,
    /// The angle step, degrees (> 0).
    pub step_deg: f64,
}

/// What to map.
#[derive(Debug, Clone)]
pub struct MapConfig {
    /// Range of x, y, z, m; `None`: the central 80 % of the frame for a plane axis, the
    /// scene's position for the slice axis.
    pub ranges_m: [Option<Interval>; 3],
    /// Grid step, m (all axes).
    pub step_m: f64,
    /// The heat-map plane.
    pub plane: Plane,
    /// Worker threads, one estimator each (0: one per core).
    pub threads: usize,
    /// Compute the end-effector mode too.
    pub ee_mode: bool,
    /// Modes kept per point (1 ..= `points::MAX_MODES`).
    pub modes: usize,
    /// Show a progress bar on stderr (a terminal only).
    pub progress: bool,
    /// Sweep the orientation instead of the slice axis: one panel per tilt angle, the slice
    /// axis at a single value.
    pub tilt: Option<Tilt>,
    /// Evaluate one shard of the grid only (see [`Shard`]); `None`: the whole grid.
    pub shard: Option<Shard>,
}

/// Most shards a grid is split into.
pub const MAX_SHARDS: usize = 1_000_000;

/// Shard `index` (1-based) of `count`: a contiguous, balanced slice of a map's grid, for a
/// batch scheduler's array job.
///
/// The unit is a grid row (the points along the horizontal axis, which one estimator
/// evaluates warm-started from the row's first point): with R rows in the grid's order,
/// shard i holds rows ⌊(i − 1)·R/N⌋ .. ⌊i·R/N⌋ (shards differ by at most one row; a shard
/// may be empty when N > R). Every row starts from the same cold estimator, so a shard's
/// points are the unsharded map's points bit for bit, and the shards' CSVs, in order and
/// with the header kept only from the first, are the unsharded CSV byte for byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, 1 ..= `count`.
    pub index: usize,
    /// How many shards, 1 ..= [`MAX_SHARDS`].
    pub count: usize,
}

impl Shard {
    /// Parse `I/N` (1 ≤ I ≤ N ≤ [`MAX_SHARDS`]).
    pub fn parse(text: &str) -> Result<Shard, String> {
        let t = text.trim();
        let bad = || format!("`{t}`: expected I/N with 1 <= I <= N (e.g. 2/8)");
        let (i, n) = t.split_once('/').ok_or_else(bad)?;
        let (Ok(index), Ok(count)) = (i.trim().parse::<usize>(), n.trim().parse::<usize>()) else {
            return Err(bad());
        };
        if count == 0 || count > MAX_SHARDS {
            return Err(format!("`{t}`: N must be within 1..={MAX_SHARDS}"));
        }
        if index == 0 || index > count {
            return Err(format!("`{t}`: I must be within 1..={count}"));
        }
        Ok(Shard { index, count })
    }

    /// The rows `[a, b)` of this shard among `rows`.
    pub fn rows(&self, rows: usize) -> std::ops::Range<usize> {
        // u128: rows × count cannot overflow.
        let at = |k: usize| ((k as u128 * rows as u128) / self.count as u128) as usize;
        at(self.index - 1)..at(self.index)
    }
}

/// Grid values lo, lo + step, …, hi (the last value snaps to hi when within 1e-9 step).
/// The rounding noise of lo + i·step (within 1e-12 of max(|lo|, i·step)) is snapped to the
/// 1 nm lattice or to 0; nothing else is rounded: lo itself, and every value off the
/// lattice by more (−1e-12 m, a grid of 0.1 nm steps), is kept to full precision.
pub fn grid_axis(iv: Interval, step: f64, param: Param) -> Result<Vec<f64>, StudyError> {
    if !(step.is_finite() && step > 0.0) {
        return Err(ParamError::invalid(param, format!("{step:?}"), "must be > 0").into());
    }
    // Counted in f64 first: a subnormal step gives an infinite count, which `as usize`
    // saturates and `+ 1` wrapped to an empty grid.
    let steps = ((iv.hi - iv.lo) / step + 1e-9).floor();
    if !(steps < MAX_AXIS_VALUES as f64) {
        let rule = format!(
            "{:?} grid values on [{:?}, {:?}]: too many (at most {MAX_AXIS_VALUES})",
            steps + 1.0,
            iv.lo,
            iv.hi
        );
        return Err(ParamError::invalid(param, format!("{step:?}"), rule).into());
    }
    let n = steps as usize + 1;
    Ok((0..n)
        .map(|i| {
            let exact = iv.lo + i as f64 * step;
            let noise = GRID_NOISE * iv.lo.abs().max(i as f64 * step);
            let snapped = (exact * GRID_LATTICE_PER_M).round() / GRID_LATTICE_PER_M;
            let v = if (snapped - exact).abs() <= noise {
                snapped
            } else {
                exact
            };
            if (v - iv.hi).abs() < 1e-9 * step {
                iv.hi
            } else if v.abs() <= noise {
                0.0
            } else {
                v
            }
        })
        .collect())
}

/// A computed map: grid axes and one result per grid point.
#[derive(Debug, Clone)]
pub struct MapResult {
    /// Grid values of x, y, z, m.
    pub axes: [Vec<f64>; 3],
    /// The heat-map plane.
    pub plane: Plane,
    /// The tilt angles, degrees, when the map sweeps the orientation (one panel each, the
    /// slice axis at one value); empty otherwise.
    pub tilts_deg: Vec<f64>,
    /// The tilt axis (world frame, unit) when `tilts_deg` is not empty.
    pub tilt_axis: Vector3<f64>,
    /// Results ordered panel-major (slice or tilt angle), then vertical, then horizontal.
    pub points: Vec<PointResult>,
    /// Worker threads the map ran on.
    pub threads: usize,
    /// The shard evaluated (`points` then holds its rows only), `None` for the whole grid.
    pub shard: Option<Shard>,
    /// Grid points of the whole grid (all shards).
    pub grid_points: usize,
    /// Modes kept per point (the CSV's f1_hz .. fK_hz columns, also for an empty shard).
    pub modes: usize,
}

impl MapResult {
    /// Number of panels: tilt angles when tilting, else slices.
    pub fn panel_count(&self) -> usize {
        if self.tilts_deg.is_empty() {
            self.axes[self.plane.axes().2].len()
        } else {
            self.tilts_deg.len()
        }
    }
    /// Grid point with the largest valid `value`, and the value.
    pub fn max(&self, v: MapValue) -> Option<(Vector3<f64>, f64)> {
        max_of(&self.points, v)
    }
    /// Grid point with the smallest valid `value`, and the value.
    pub fn min(&self, v: MapValue) -> Option<(Vector3<f64>, f64)> {
        self.points
            .iter()
            .filter_map(|p| pick(p, v).map(|f| (p.position_m, f)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }
    /// How many points have each status.
    pub fn status_counts(&self) -> StatusHistogram {
        status_histogram(&self.points)
    }
}

/// Point of `points` with the largest valid `value`, and the value.
pub fn max_of(points: &[PointResult], v: MapValue) -> Option<(Vector3<f64>, f64)> {
    points
        .iter()
        .filter_map(|p| pick(p, v).map(|f| (p.position_m, f)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// The value `v` of a point, when its estimate is ok and the value finite.
pub fn pick(p: &PointResult, v: MapValue) -> Option<f64> {
    let e = &p.estimate;
    let f = match v {
        MapValue::F1 => e.f1_hz,
        MapValue::EeMode => super::points::ee_mode_hz(e),
        MapValue::Mode(k) => p.mode_hz(k),
        MapValue::StiffnessMin => p.stiffness_min_n_m,
    };
    (e.is_ok() && f.is_finite()).then_some(f)
}

/// The grid axes of a map of scene `s`.
fn grid(s: &Scene, cfg: &MapConfig) -> Result<[Vec<f64>; 3], StudyError> {
    let (lo, hi) = s.frame_bounds_m();
    let (_, _, sl) = cfg.plane.axes();
    let mut axes: [Vec<f64>; 3] = Default::default();
    for k in 0..3 {
        let iv = match cfg.ranges_m[k] {
            Some(iv) => iv,
            None if k == sl => Interval {
                lo: s.ee_position_m[k],
                hi: s.ee_position_m[k],
            },
            None => {
                let (c, r) = (
                    (lo[k] + hi[k]) / 2.0,
                    DEFAULT_HALF_SPAN_SHARE * (hi[k] - lo[k]),
                );
                Interval {
                    lo: c - r,
                    hi: c + r,
                }
            }
        };
        axes[k] = grid_axis(iv, cfg.step_m, Param::StepM)?;
    }
    Ok(axes)
}

/// The orientations of a map's panels.
struct PanelOrientations {
    /// Unit quaternions [w, x, y, z]: the scene's turned by each tilt angle, or the scene's
    /// alone.
    quaternions: Vec<[f64; 4]>,
    /// The tilt angles, degrees (empty without a tilt).
    angles_deg: Vec<f64>,
    /// The unit tilt axis (zero without a tilt).
    axis: Vector3<f64>,
}

/// The orientations of a map's panels (`slices`: values on the slice axis).
fn orientations(
    s: &Scene,
    cfg: &MapConfig,
    slices: usize,
) -> Result<PanelOrientations, StudyError> {
    let Some(t) = cfg.tilt else {
        return Ok(PanelOrientations {
            quaternions: vec![s.ee_orientation_wxyz],
            angles_deg: Vec::new(),
            axis: Vector3::zeros(),
        });
    };
    if !s.rigid {
        let reason = format!(
            "scene `{}` has a point-mass end-effector, where orientation has no effect",
            s.name
        );
        return Err(ParamError::not_applicable(Param::TiltDeg, reason).into());
    }
    let Some(axis) = crate::scene::unit_direction(&t.axis) else {
        let value = format!("{:?}", t.axis.as_slice());
        let rule = "must be finite and non-zero";
        return Err(ParamError::invalid(Param::TiltAxis, value, rule).into());
    };
    if slices != 1 {
        let reason = "the panels are the tilt angles, so the slice axis takes a single value";
        return Err(ParamError::not_applicable(Param::TiltDeg, reason).into());
    }
    if !(t.step_deg.is_finite() && t.step_deg > 0.0) {
        let value = format!("{:?}", t.step_deg);
        return Err(ParamError::invalid(Param::TiltStepDeg, value, "must be > 0").into());
    }
    let angles = grid_axis(t.range_deg, t.step_deg, Param::TiltStepDeg)?;
    if angles.len() > MAX_TILTS {
        let rule = format!("{} tilt angles: at most {MAX_TILTS}", angles.len());
        return Err(ParamError::invalid(Param::TiltStepDeg, t.step_deg, rule).into());
    }
    let quaternions = angles
        .iter()
        .map(|a| rotated_about(&s.ee_orientation_wxyz, &axis, a.to_radians()))
        .collect();
    Ok(PanelOrientations {
        quaternions,
        angles_deg: angles,
        axis,
    })
}

/// Evaluate the map of scene `s` at its T_min.
pub fn compute(s: &Scene, cfg: &MapConfig) -> Result<MapResult, StudyError> {
    let axes = grid(s, cfg)?;
    let (h, v, sl) = cfg.plane.axes();
    let PanelOrientations {
        quaternions: qs,
        angles_deg: tilts_deg,
        axis: tilt_axis,
    } = orientations(s, cfg, axes[sl].len())?;
    let n = axes[h].len() * axes[v].len() * axes[sl].len() * qs.len();
    if n > MAX_GRID_POINTS {
        let rule = format!("{n} grid points: too many (at most {MAX_GRID_POINTS})");
        let step = format!("{:?}", cfg.step_m);
        return Err(ParamError::invalid(Param::StepM, step, rule).into());
    }
    let mut points = Vec::with_capacity(n);
    for q in &qs {
        for &ws in &axes[sl] {
            for &wv in &axes[v] {
                for &wh in &axes[h] {
                    let mut p = Vector3::zeros();
                    p[h] = wh;
                    p[v] = wv;
                    p[sl] = ws;
                    points.push(Pose {
                        position_m: p,
                        orientation_wxyz: *q,
                    });
                }
            }
        }
    }
    let row = axes[h].len();
    let grid_points = points.len();
    if let Some(sh) = cfg.shard {
        let r = sh.rows(grid_points / row);
        points = points[r.start * row..r.end * row].to_vec();
    }
    let w = Workers {
        params: estimator_params(s, cfg.ee_mode),
        threads: cfg.threads,
        progress: cfg.progress.then_some("map"),
        n_modes: cfg.modes,
    };
    let res = evaluate_points_with(s, &points, Tmin::Scene, row, &w)?;
    Ok(MapResult {
        axes,
        plane: cfg.plane,
        tilts_deg,
        tilt_axis,
        points: res,
        threads: w.thread_count(),
        shard: cfg.shard,
        grid_points,
        modes: cfg.modes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_axes() {
        let g = grid_axis(Interval { lo: -1.0, hi: 1.0 }, 0.1, Param::StepM).unwrap();
        assert_eq!(g.len(), 21);
        assert_eq!(g[20], 1.0);
        assert_eq!(g[10], 0.0);
        let g = grid_axis(Interval { lo: 0.25, hi: 1.25 }, 0.1, Param::StepM).unwrap();
        assert_eq!(g.len(), 11);
        assert_eq!(g[7], 0.95);
        let g = grid_axis(Interval { lo: -0.3, hi: 0.3 }, 0.1, Param::StepM).unwrap();
        assert_eq!(g, [-0.3, -0.2, -0.1, 0.0, 0.1, 0.2, 0.3]);
        // A value the user gave is not noise: kept to full precision (it was 0 and 0, 0).
        let g = grid_axis(
            Interval {
                lo: -1e-12,
                hi: -1e-12,
            },
            0.1,
            Param::StepM,
        )
        .unwrap();
        assert_eq!(g, [-1e-12]);
        let g = grid_axis(Interval { lo: 0.0, hi: 3e-10 }, 1e-10, Param::StepM).unwrap();
        assert_eq!(g, [0.0, 1e-10, 2e-10, 3e-10]);
    }

    #[test]
    fn shards_cover_the_rows_once_and_balanced() {
        for rows in [0, 1, 5, 7, 21, 100] {
            for count in 1..=9 {
                let mut next = 0;
                for index in 1..=count {
                    let r = Shard { index, count }.rows(rows);
                    assert_eq!(r.start, next, "rows {rows}, shard {index}/{count}");
                    assert!(r.len() == rows / count || r.len() == rows / count + 1);
                    next = r.end;
                }
                assert_eq!(next, rows);
            }
        }
    }

    #[test]
    fn shard_specs() {
        assert_eq!(Shard::parse("2/3"), Ok(Shard { index: 2, count: 3 }));
        for bad in [
            "0/3", "4/3", "1/0", "a/b", "1/", "/2", "3", "", "1/2/3", "-1/2",
        ] {
            let e = Shard::parse(bad).unwrap_err();
            assert!(!e.contains('\n'), "{e}");
        }
    }
}
