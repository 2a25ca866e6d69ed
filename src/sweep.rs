//! Offline sweeps over the real-time estimator: what accuracy costs (`accuracy`),
//! frequency maps over a workspace grid (`map`), frequencies along a trajectory
//! (`trajectory`) and against the minimum tension (`sweep-tmin`).
//!
//! Every sweep drives [`Estimator::update`] (the per-cycle path, exact to ~1e-12 against
//! the faithful model) and writes a CSV with one row per evaluated point — including the
//! points where the estimator has no valid answer, which keep their status code and NaN
//! frequencies — and an SVG figure ([`crate::svg`]). Long sweeps split their points over
//! `--threads` worker threads (one estimator each, `std::thread::scope`) and print a
//! throttled percentage on stderr.
//!
//! The accuracy study also runs the dense reference ([`reference_analysis`]) for the
//! paper's convergence figures (mode 3 against the number of elements, Figs. 5 and 10).

use crate::cli::{resolve_scene, CliError, SceneArgs};
use crate::estimator::{reference_analysis, Estimate, Estimator, EstimatorParams, Status};
use crate::kinematics::Pose;
use crate::modal::lambda_to_hz;
use crate::scene::{ElementKind, Scene};
use crate::service::stats::percentile;
use crate::svg::{Axis, HLine, HeatMap, HeatPanel, LinePlot, Mark, Series, PALETTE};
use crate::trajectory::{circle_pose, Circle, Samples, TrajectoryError};
use clap::{Args, ValueEnum};
use nalgebra::Vector3;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Errors of the sweep commands.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// Scene loading or overrides.
    #[error(transparent)]
    Cli(#[from] CliError),
    /// Bad option value.
    #[error("{0}")]
    Usage(String),
    /// The estimator could not be built (the scene's default pose is unsolvable).
    #[error("{0}")]
    Build(String),
    /// A trajectory could not be made or read.
    #[error(transparent)]
    Trajectory(#[from] TrajectoryError),
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> SweepError + '_ {
    move |source| SweepError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Write `text` to `path`, creating parent directories.
pub fn write_file(path: &Path, text: &str) -> Result<(), SweepError> {
    if let Some(d) = path.parent() {
        if !d.as_os_str().is_empty() {
            std::fs::create_dir_all(d).map_err(io_err(d))?;
        }
    }
    std::fs::write(path, text).map_err(io_err(path))
}

/// `PREFIX` + `ext` (`map` → `map.csv`), keeping any dots already in the prefix.
pub fn with_ext(prefix: &Path, ext: &str) -> PathBuf {
    let mut s = prefix.as_os_str().to_os_string();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}

/// A closed interval `MIN,MAX` (m), or a single value `V` (MIN = MAX = V).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
}

/// Parse `MIN,MAX` or `V`.
pub fn parse_interval(s: &str) -> Result<Interval, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("`{x}`: {e}")))
        .collect::<Result<_, _>>()?;
    let (lo, hi) = match v.as_slice() {
        [a] => (*a, *a),
        [a, b] => (*a, *b),
        _ => return Err(format!("expected MIN,MAX or a single value, got `{s}`")),
    };
    if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
        return Err(format!("expected finite MIN <= MAX, got `{s}`"));
    }
    Ok(Interval { lo, hi })
}

/// Grid values lo, lo + step, …, hi (the last value snaps to hi when within 1e-9 step).
pub fn grid_axis(iv: Interval, step: f64) -> Result<Vec<f64>, SweepError> {
    if !(step.is_finite() && step > 0.0) {
        return Err(SweepError::Usage(format!("--step {step}: must be > 0")));
    }
    let n = ((iv.hi - iv.lo) / step + 1e-9).floor() as usize + 1;
    if n > 100_000 {
        return Err(SweepError::Usage(format!(
            "{n} grid values on [{}, {}] at step {step}: too many",
            iv.lo, iv.hi
        )));
    }
    Ok((0..n)
        .map(|i| {
            // Snap to a 1e-9 m lattice so 0.25 + 7 × 0.1 prints as 0.95.
            let v = ((iv.lo + i as f64 * step) * 1e9).round() / 1e9;
            if (v - iv.hi).abs() < 1e-9 * step {
                iv.hi
            } else if v.abs() < 1e-12 * step {
                0.0
            } else {
                v
            }
        })
        .collect())
}

fn estimator_params(s: &Scene, ee_mode: bool) -> EstimatorParams {
    let mut p = EstimatorParams::default();
    p.modal.ee_participation_min = s.model.ee_participation_min;
    p.ee_mode = ee_mode;
    p
}

fn build(s: &Scene, p: EstimatorParams) -> Result<Estimator, SweepError> {
    Estimator::with_params(s, p).map_err(|e| SweepError::Build(e.to_string()))
}

/// One evaluated point of a sweep.
#[derive(Debug, Clone, Copy)]
pub struct PointResult {
    /// End-effector position, m.
    pub position_m: Vector3<f64>,
    /// T_min used, N.
    pub t_min_n: f64,
    /// What the real-time estimator returned (status, f1, end-effector mode, tensions).
    pub estimate: Estimate,
}

/// Throttled progress line on stderr.
struct Progress<'a> {
    label: Option<&'a str>,
    total: usize,
    last: Instant,
    last_pct: usize,
}

impl<'a> Progress<'a> {
    fn new(label: Option<&'a str>, total: usize) -> Self {
        Progress {
            label,
            total,
            last: Instant::now(),
            last_pct: usize::MAX,
        }
    }
    fn show(&mut self, done: usize, force: bool) {
        let Some(l) = self.label else { return };
        let pct = (done * 100).checked_div(self.total).unwrap_or(100);
        if pct != self.last_pct && (force || self.last.elapsed() >= Duration::from_millis(250)) {
            eprint!("\r{l}: {pct:>3}% ({done}/{} points)", self.total);
            let _ = std::io::stderr().flush();
            self.last = Instant::now();
            self.last_pct = pct;
        }
    }
    fn finish(&mut self) {
        if self.label.is_some() {
            self.show(self.total, true);
            eprintln!();
        }
    }
}

/// Evaluate `points` (positions, m) at `t_min_n` on `threads` threads, one estimator per
/// thread. Work is handed out in runs of `chunk` consecutive points (so a thread's
/// estimator may warm-start along a run); the result keeps the order of `points`. With
/// `progress = Some(label)` a percentage is printed on stderr (at most 4 times a second).
pub fn evaluate_points(
    scene: &Scene,
    points: &[Vector3<f64>],
    t_min_n: f64,
    params: EstimatorParams,
    threads: usize,
    chunk: usize,
    progress: Option<&str>,
) -> Result<Vec<PointResult>, SweepError> {
    let jobs: Vec<(usize, usize)> = (0..points.len())
        .step_by(chunk.max(1))
        .map(|a| (a, (a + chunk.max(1)).min(points.len())))
        .collect();
    let rows = evaluate_jobs(
        scene,
        &jobs,
        threads,
        progress,
        points.len(),
        |k| {
            let (a, b) = jobs[k];
            (a..b).map(|i| (points[i], t_min_n)).collect()
        },
        params,
    )?;
    Ok(rows)
}

/// Shared worker pool: job k yields its (position, T_min) list; results are concatenated
/// in job order.
fn evaluate_jobs<F>(
    scene: &Scene,
    jobs: &[(usize, usize)],
    threads: usize,
    progress: Option<&str>,
    total: usize,
    job_points: F,
    params: EstimatorParams,
) -> Result<Vec<PointResult>, SweepError>
where
    F: Fn(usize) -> Vec<(Vector3<f64>, f64)> + Sync,
{
    let threads = threads.clamp(1, 64).min(jobs.len().max(1));
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let mut prog = Progress::new(progress, total);
    let mut per_job: Vec<Option<Vec<PointResult>>> = vec![None; jobs.len()];
    let results = std::thread::scope(|sc| {
        let handles: Vec<_> = (0..threads)
            .map(|_| {
                sc.spawn(|| -> Result<Vec<(usize, Vec<PointResult>)>, SweepError> {
                    let mut est = build(scene, params)?;
                    let mut local = Vec::new();
                    loop {
                        let k = next.fetch_add(1, Ordering::Relaxed);
                        if k >= jobs.len() {
                            break;
                        }
                        let pts = job_points(k);
                        let mut out = Vec::with_capacity(pts.len());
                        for (p, t) in pts {
                            let e = *est.update(&Pose::at(p), t);
                            out.push(PointResult {
                                position_m: p,
                                t_min_n: t,
                                estimate: e,
                            });
                        }
                        done.fetch_add(out.len(), Ordering::Relaxed);
                        local.push((k, out));
                    }
                    Ok(local)
                })
            })
            .collect();
        while !handles.iter().all(|h| h.is_finished()) {
            prog.show(done.load(Ordering::Relaxed), false);
            std::thread::sleep(Duration::from_millis(20));
        }
        handles
            .into_iter()
            .map(|h| h.join().expect("sweep worker panicked"))
            .collect::<Vec<_>>()
    });
    prog.finish();
    for r in results {
        for (k, v) in r? {
            per_job[k] = Some(v);
        }
    }
    Ok(per_job.into_iter().flatten().flatten().collect())
}

fn fnum(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.8e}")
    } else {
        "NaN".into()
    }
}

fn fnum_p(x: f64, digits: usize) -> String {
    if x.is_finite() {
        format!("{x:.digits$e}")
    } else {
        "NaN".into()
    }
}

/// CSV header of [`PointResult`] rows for a scene with `n` cables.
fn point_csv_header(n: usize) -> String {
    let mut h = String::from(
        "x_m,y_m,z_m,t_min_n,status,f1_hz,ee_mode_hz,f1_ee_participation,ee_mode_participation",
    );
    for i in 0..n {
        let _ = write!(h, ",tension{}_n", i + 1);
    }
    h
}

fn point_csv_row(r: &PointResult) -> String {
    let e = &r.estimate;
    let mut s = format!(
        "{},{},{},{},{},{},{},{},{}",
        r.position_m.x,
        r.position_m.y,
        r.position_m.z,
        r.t_min_n,
        e.status.as_str(),
        fnum(e.f1_hz),
        fnum(e.ee_mode_hz),
        fnum_p(e.f1_ee_participation, 4),
        fnum_p(e.ee_mode_participation, 4)
    );
    for t in e.tensions() {
        let _ = write!(s, ",{}", fnum_p(*t, 6));
    }
    s
}

fn status_counts(rows: &[PointResult]) -> Vec<(Status, usize)> {
    let mut v: Vec<(Status, usize)> = Vec::new();
    for r in rows {
        match v.iter_mut().find(|(s, _)| *s == r.estimate.status) {
            Some(x) => x.1 += 1,
            None => v.push((r.estimate.status, 1)),
        }
    }
    v.sort_by_key(|(s, _)| s.as_u32());
    v
}

fn counts_text(c: &[(Status, usize)]) -> String {
    c.iter()
        .map(|(s, n)| format!("{} {}", s.as_str(), n))
        .collect::<Vec<_>>()
        .join(", ")
}

// ---------------------------------------------------------------------------------------
// map
// ---------------------------------------------------------------------------------------

/// The plane of a heat map; the third axis is swept as slices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
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
    fn axes(self) -> (usize, usize, usize) {
        match self {
            Plane::Xy => (0, 1, 2),
            Plane::Xz => (0, 2, 1),
            Plane::Yz => (1, 2, 0),
        }
    }
}

/// Which frequency a heat map shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MapValue {
    /// The first natural frequency of the whole model.
    F1,
    /// The end-effector mode (lowest mode with end-effector participation ≥ threshold).
    EeMode,
}

/// `cablevib map`: first natural frequency over a workspace grid.
#[derive(Debug, Args, Clone)]
pub struct MapArgs {
    /// Scene and overrides (`--t-min` sets the map's T_min; `--position` the coordinate
    /// of an axis given no range).
    #[command(flatten)]
    pub scene: SceneArgs,
    /// x range MIN,MAX or a single value, m (default: the central 80 % of the frame
    /// for a plane axis, the scene's position for the slice axis).
    #[arg(long, value_parser = parse_interval, allow_hyphen_values = true)]
    pub x: Option<Interval>,
    /// y range MIN,MAX or a single value, m.
    #[arg(long, value_parser = parse_interval, allow_hyphen_values = true)]
    pub y: Option<Interval>,
    /// z range MIN,MAX or a single value, m.
    #[arg(long, value_parser = parse_interval, allow_hyphen_values = true)]
    pub z: Option<Interval>,
    /// Grid step, m (all axes).
    #[arg(long, default_value_t = 0.1)]
    pub step: f64,
    /// Plane of the heat map; a range on the third axis gives one panel per slice.
    #[arg(long, value_enum, default_value = "xy")]
    pub plane: Plane,
    /// Frequency shown in the heat map (the CSV has both).
    #[arg(long, value_enum, default_value = "f1")]
    pub value: MapValue,
    /// Output prefix: writes PREFIX.csv and PREFIX.svg.
    #[arg(long, default_value = "map")]
    pub out: PathBuf,
    /// Write the figure here instead of PREFIX.svg.
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Worker threads (one estimator each).
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Skip the end-effector mode (f1 only; faster).
    #[arg(long)]
    pub no_ee_mode: bool,
    /// Heat-map panels per row (3-D grids).
    #[arg(long, default_value_t = 4)]
    pub columns: usize,
    /// No progress on stderr.
    #[arg(long)]
    pub quiet: bool,
}

/// A computed map: grid axes and one result per grid point.
#[derive(Debug, Clone)]
pub struct MapResult {
    /// Grid values of x, y, z, m.
    pub axes: [Vec<f64>; 3],
    /// The heat-map plane.
    pub plane: Plane,
    /// Results ordered slice-major, then vertical, then horizontal.
    pub points: Vec<PointResult>,
}

impl MapResult {
    /// Grid point with the largest valid `value`, and the value.
    pub fn max(&self, v: MapValue) -> Option<(Vector3<f64>, f64)> {
        self.points
            .iter()
            .filter_map(|p| pick(&p.estimate, v).map(|f| (p.position_m, f)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
    }
    /// Grid point with the smallest valid `value`, and the value.
    pub fn min(&self, v: MapValue) -> Option<(Vector3<f64>, f64)> {
        self.points
            .iter()
            .filter_map(|p| pick(&p.estimate, v).map(|f| (p.position_m, f)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }
    /// How many points have each status.
    pub fn status_counts(&self) -> Vec<(Status, usize)> {
        status_counts(&self.points)
    }
}

fn pick(e: &Estimate, v: MapValue) -> Option<f64> {
    let f = match v {
        MapValue::F1 => e.f1_hz,
        MapValue::EeMode => e.ee_mode_hz,
    };
    (e.is_ok() && f.is_finite()).then_some(f)
}

/// Compute a map (no files).
pub fn compute_map(a: &MapArgs) -> Result<(Scene, MapResult), SweepError> {
    let s = resolve_scene(&a.scene)?;
    let (lo, hi) = s.frame_bounds_m();
    let (h, v, sl) = a.plane.axes();
    let given = [a.x, a.y, a.z];
    let mut axes: [Vec<f64>; 3] = Default::default();
    for k in 0..3 {
        let iv = match given[k] {
            Some(iv) => iv,
            None if k == sl => Interval {
                lo: s.ee_position_m[k],
                hi: s.ee_position_m[k],
            },
            None => {
                let (c, r) = ((lo[k] + hi[k]) / 2.0, 0.4 * (hi[k] - lo[k]));
                Interval {
                    lo: c - r,
                    hi: c + r,
                }
            }
        };
        axes[k] = grid_axis(iv, a.step)?;
    }
    let n = axes[0].len() * axes[1].len() * axes[2].len();
    if n > 5_000_000 {
        return Err(SweepError::Usage(format!("{n} grid points: too many")));
    }
    let mut points = Vec::with_capacity(n);
    for &ws in &axes[sl] {
        for &wv in &axes[v] {
            for &wh in &axes[h] {
                let mut p = Vector3::zeros();
                p[h] = wh;
                p[v] = wv;
                p[sl] = ws;
                points.push(p);
            }
        }
    }
    let params = estimator_params(&s, !a.no_ee_mode);
    let label = (!a.quiet).then_some("map");
    let res = evaluate_points(
        &s,
        &points,
        s.t_min_n,
        params,
        a.threads,
        axes[h].len(),
        label,
    )?;
    Ok((
        s,
        MapResult {
            axes,
            plane: a.plane,
            points: res,
        },
    ))
}

/// `cablevib map`: writes PREFIX.csv (every grid point, with its status) and PREFIX.svg.
pub fn map(a: &MapArgs) -> Result<(), SweepError> {
    let t0 = Instant::now();
    let (s, m) = compute_map(a)?;
    let secs = t0.elapsed().as_secs_f64();
    let mut csv = format!(
        "# cablevib map: scene {}, model {} x {}, T_min {} N, T_max {} N\n{}\n",
        s.name,
        s.model.element.as_str(),
        s.model.elements_per_cable,
        s.t_min_n,
        s.t_max_n,
        point_csv_header(s.n_cables())
    );
    for r in &m.points {
        csv.push_str(&point_csv_row(r));
        csv.push('\n');
    }
    let csv_path = with_ext(&a.out, "csv");
    write_file(&csv_path, &csv)?;
    let svg_path = a.svg.clone().unwrap_or_else(|| with_ext(&a.out, "svg"));
    write_file(&svg_path, &map_svg(&s, &m, a.value))?;
    let counts = m.status_counts();
    println!(
        "map: scene {}  T_min {} N  {} points in {:.2} s ({} threads)  statuses: {}",
        s.name,
        s.t_min_n,
        m.points.len(),
        secs,
        a.threads,
        counts_text(&counts)
    );
    let name = match a.value {
        MapValue::F1 => "f1",
        MapValue::EeMode => "end-effector mode",
    };
    if let (Some((pmin, fmin)), Some((pmax, fmax))) = (m.min(a.value), m.max(a.value)) {
        println!(
            "  {name}: min {fmin:.4} Hz at ({:.3}, {:.3}, {:.3}) m, max {fmax:.4} Hz at ({:.3}, {:.3}, {:.3}) m",
            pmin.x, pmin.y, pmin.z, pmax.x, pmax.y, pmax.z
        );
    }
    println!("  wrote {} and {}", csv_path.display(), svg_path.display());
    Ok(())
}

const AXIS_NAMES: [&str; 3] = ["x", "y", "z"];

/// The heat-map figure of a map.
pub fn map_svg(s: &Scene, m: &MapResult, v: MapValue) -> String {
    let (h, vv, sl) = m.plane.axes();
    let (nh, nv) = (m.axes[h].len(), m.axes[vv].len());
    let per = nh * nv;
    let gmax = m.max(v);
    let mut maps = Vec::new();
    for (k, &ws) in m.axes[sl].iter().enumerate() {
        let slice = &m.points[k * per..(k + 1) * per];
        let values: Vec<Option<f64>> = slice.iter().map(|p| pick(&p.estimate, v)).collect();
        let mut markers = Vec::new();
        let smax = slice
            .iter()
            .filter_map(|p| pick(&p.estimate, v).map(|f| (p.position_m, f)))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        if let (Some((p, f)), Some((_, g))) = (smax, gmax) {
            let text = if f == g {
                format!("max {f:.3} Hz")
            } else {
                format!("{f:.3}")
            };
            if m.axes[sl].len() == 1 || f == g {
                markers.push((p[h], p[vv], text));
            }
        }
        let bad = values.iter().filter(|x| x.is_none()).count();
        maps.push(HeatMap {
            caption: format!(
                "{} = {} m{}",
                AXIS_NAMES[sl],
                crate::svg::fmt_num(ws),
                if bad > 0 {
                    format!(" ({bad} without value)")
                } else {
                    String::new()
                }
            ),
            x: m.axes[h].clone(),
            y: m.axes[vv].clone(),
            values,
            markers,
        });
    }
    let counts = m.status_counts();
    let vname = match v {
        MapValue::F1 => "first natural frequency",
        MapValue::EeMode => "end-effector mode",
    };
    let mut sub = format!(
        "{} × {} elements/cable, T_min {} N, T_max {} N, step {} m",
        s.model.element.as_str(),
        s.model.elements_per_cable,
        s.t_min_n,
        s.t_max_n,
        crate::svg::fmt_num(if nh > 1 {
            m.axes[h][1] - m.axes[h][0]
        } else {
            0.0
        })
    );
    if let Some((_, f)) = gmax {
        let _ = write!(sub, "; max {f:.3} Hz");
    }
    if let Some((_, f)) = m.min(v) {
        let _ = write!(sub, ", min {f:.3} Hz");
    }
    let _ = write!(sub, "; {}", counts_text(&counts));
    let single_slice = m.axes[sl].len() == 1;
    HeatPanel {
        title: format!(
            "{}: {vname}{}",
            s.name,
            if single_slice {
                format!(
                    " ({} = {} m)",
                    AXIS_NAMES[sl],
                    crate::svg::fmt_num(m.axes[sl][0])
                )
            } else {
                String::new()
            }
        ),
        subtitle: sub,
        x_label: format!("{} (m)", AXIS_NAMES[h]),
        y_label: format!("{} (m)", AXIS_NAMES[vv]),
        value_label: "f (Hz)".into(),
        invalid_label: "no valid estimate".into(),
        maps,
        columns: a_columns(m.axes[sl].len()),
        range: None,
    }
    .to_svg()
}

fn a_columns(n: usize) -> usize {
    match n {
        0..=3 => n.max(1),
        4 => 2,
        5..=9 => 3,
        _ => 4,
    }
}

// ---------------------------------------------------------------------------------------
// trajectory
// ---------------------------------------------------------------------------------------

/// `cablevib trajectory`: f1 and the end-effector mode along a trajectory.
#[derive(Debug, Args, Clone)]
pub struct TrajectoryArgs {
    /// Scene and overrides.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Trajectory CSV with columns t,x,y,z (s, m; `#` comments and a header line are
    /// skipped). Default: the paper's circle around the scene's position.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Comma-separated T_min values, N, one curve each (default: the scene's T_min).
    #[arg(long = "t-mins", value_delimiter = ',', num_args = 1..)]
    pub t_mins: Vec<f64>,
    /// Circle radius, m (default trajectory only).
    #[arg(long, default_value_t = 0.75)]
    pub radius_m: f64,
    /// Period of one revolution of the circle, s (poses 1 ms apart).
    #[arg(long, default_value_t = 4.0)]
    pub period_s: f64,
    /// Output prefix: writes PREFIX.csv and PREFIX.svg.
    #[arg(long, default_value = "trajectory")]
    pub out: PathBuf,
    /// Write the figure here instead of PREFIX.svg.
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Worker threads (T_min curves are spread over them).
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Skip the end-effector mode (f1 only).
    #[arg(long)]
    pub no_ee_mode: bool,
    /// No progress on stderr.
    #[arg(long)]
    pub quiet: bool,
}

/// Evaluate a trajectory for each T_min (one run per T_min, consecutive poses so the
/// estimator warm-starts); results are T_min-major.
pub fn compute_trajectory(
    s: &Scene,
    tr: &Samples,
    t_mins: &[f64],
    ee_mode: bool,
    threads: usize,
    progress: Option<&str>,
) -> Result<Vec<PointResult>, SweepError> {
    let n = tr.position_m.len();
    let jobs: Vec<(usize, usize)> = (0..t_mins.len()).map(|k| (k * n, (k + 1) * n)).collect();
    evaluate_jobs(
        s,
        &jobs,
        threads,
        progress,
        n * t_mins.len(),
        |k| tr.position_m.iter().map(|p| (*p, t_mins[k])).collect(),
        estimator_params(s, ee_mode),
    )
}

/// `cablevib trajectory`: writes PREFIX.csv and PREFIX.svg.
pub fn trajectory(a: &TrajectoryArgs) -> Result<(), SweepError> {
    let s = resolve_scene(&a.scene)?;
    let t_mins = if a.t_mins.is_empty() {
        vec![s.t_min_n]
    } else {
        a.t_mins.clone()
    };
    if let Some(t) = t_mins
        .iter()
        .find(|t| !(t.is_finite() && **t >= 0.0 && **t <= s.t_max_n))
    {
        return Err(SweepError::Usage(format!(
            "--t-mins {t}: must be within [0, t_max = {} N]",
            s.t_max_n
        )));
    }
    let tr = match &a.csv {
        Some(p) => Samples::read_csv(p)?,
        None => {
            if !(a.period_s.is_finite()
                && a.period_s > 0.0
                && a.period_s <= 3600.0
                && a.radius_m.is_finite()
                && a.radius_m >= 0.0)
            {
                return Err(SweepError::Usage(
                    "--period-s must be in (0, 3600] and --radius-m finite and >= 0".into(),
                ));
            }
            Circle::new(&s, a.radius_m, a.period_s)?.sampled(&s)
        }
    };
    let label = (!a.quiet).then_some("trajectory");
    let res = compute_trajectory(&s, &tr, &t_mins, !a.no_ee_mode, a.threads, label)?;
    let n = tr.position_m.len();
    let circle = !tr.angle_deg.is_empty();
    let mut csv = format!(
        "# cablevib trajectory: scene {}, model {} x {}, T_max {} N\nt_s,angle_deg,{}\n",
        s.name,
        s.model.element.as_str(),
        s.model.elements_per_cable,
        s.t_max_n,
        point_csv_header(s.n_cables())
    );
    for (k, r) in res.iter().enumerate() {
        let i = k % n;
        let ang = if circle {
            format!("{}", tr.angle_deg[i])
        } else {
            "NaN".into()
        };
        let _ = writeln!(csv, "{},{ang},{}", tr.t_s[i], point_csv_row(r));
    }
    let csv_path = with_ext(&a.out, "csv");
    write_file(&csv_path, &csv)?;
    let xlab = if circle {
        "angle along the circle (deg)"
    } else {
        "t (s)"
    };
    let mut plot = LinePlot::new(
        &format!(
            "{}: first natural frequency along the {}",
            s.name,
            if circle {
                format!("circle (r = {} m)", a.radius_m)
            } else {
                "trajectory".into()
            }
        ),
        if circle {
            Axis::linear(xlab).with_range(0.0, 360.0)
        } else {
            Axis::linear(xlab)
        },
        Axis::linear("f (Hz)"),
    );
    let mut sub = format!(
        "{} × {} elements/cable, T_max {} N",
        s.model.element.as_str(),
        s.model.elements_per_cable,
        s.t_max_n
    );
    println!(
        "trajectory: scene {}  {} poses × {} T_min values",
        s.name,
        n,
        t_mins.len()
    );
    for (k, &tm) in t_mins.iter().enumerate() {
        let rows = &res[k * n..(k + 1) * n];
        let xs: Vec<f64> = if circle {
            tr.angle_deg.clone()
        } else {
            tr.t_s.clone()
        };
        let f1: Vec<(f64, f64)> = rows
            .iter()
            .zip(&xs)
            .map(|(r, &x)| {
                (
                    x,
                    if r.estimate.is_ok() {
                        r.estimate.f1_hz
                    } else {
                        f64::NAN
                    },
                )
            })
            .collect();
        let ee: Vec<(f64, f64)> = rows
            .iter()
            .zip(&xs)
            .map(|(r, &x)| {
                (
                    x,
                    if r.estimate.is_ok() {
                        r.estimate.ee_mode_hz
                    } else {
                        f64::NAN
                    },
                )
            })
            .collect();
        let color = PALETTE[k % PALETTE.len()];
        plot.series
            .push(Series::new(&format!("f1, T_min = {tm} N"), f1.clone(), Mark::Line).color(color));
        let differs = f1
            .iter()
            .zip(&ee)
            .any(|(a, b)| b.1.is_finite() && (a.1 - b.1).abs() > 1e-9 * b.1.abs());
        if !a.no_ee_mode && differs {
            plot.series.push(
                Series::new(
                    &format!("end-effector mode, T_min = {tm} N"),
                    ee,
                    Mark::Dashed,
                )
                .color(color),
            );
        }
        let ok: Vec<f64> = f1.iter().map(|p| p.1).filter(|f| f.is_finite()).collect();
        let counts = status_counts(rows);
        let (lo, hi) = (
            ok.iter().copied().fold(f64::INFINITY, f64::min),
            ok.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        );
        if lo.is_finite() {
            println!(
                "  T_min {tm} N: f1 min {lo:.4} Hz  max {hi:.4} Hz  statuses: {}",
                counts_text(&counts)
            );
            let _ = write!(sub, "; T_min {tm} N: f1 {lo:.3}–{hi:.3} Hz");
        } else {
            println!(
                "  T_min {tm} N: no valid estimate  statuses: {}",
                counts_text(&counts)
            );
            let _ = write!(sub, "; T_min {tm} N: no valid estimate");
        }
        if counts.iter().any(|(st, _)| *st != Status::Ok) {
            let _ = write!(sub, " ({})", counts_text(&counts));
        }
    }
    plot.subtitle = sub;
    let svg_path = a.svg.clone().unwrap_or_else(|| with_ext(&a.out, "svg"));
    write_file(&svg_path, &plot.to_svg())?;
    println!("  wrote {} and {}", csv_path.display(), svg_path.display());
    Ok(())
}

// ---------------------------------------------------------------------------------------
// sweep-tmin
// ---------------------------------------------------------------------------------------

/// `cablevib sweep-tmin`: f1 against T_min at one pose, with the fitted a·√T_min.
#[derive(Debug, Args, Clone)]
pub struct SweepTminArgs {
    /// Scene and overrides (`--position` sets the pose).
    #[command(flatten)]
    pub scene: SceneArgs,
    /// First T_min, N (default: the scene's T_min).
    #[arg(long)]
    pub from: Option<f64>,
    /// Last T_min, N (default: twice the first, at most T_max).
    #[arg(long)]
    pub to: Option<f64>,
    /// Number of T_min values (evenly spaced, both ends included).
    #[arg(long, default_value_t = 25)]
    pub steps: usize,
    /// Output prefix: writes PREFIX.csv and PREFIX.svg.
    #[arg(long, default_value = "sweep-tmin")]
    pub out: PathBuf,
    /// Write the figure here instead of PREFIX.svg.
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Skip the end-effector mode (f1 only).
    #[arg(long)]
    pub no_ee_mode: bool,
    /// Points to overlay for comparison, T_MIN:HZ pairs separated by commas
    /// (e.g. a paper's printed values).
    #[arg(long, value_parser = parse_pairs)]
    pub compare: Option<Pairs>,
    /// Legend text of the --compare points.
    #[arg(long, default_value = "compared")]
    pub compare_label: String,
}

/// A list of (x, y) pairs from the command line.
#[derive(Debug, Clone, PartialEq)]
pub struct Pairs(pub Vec<(f64, f64)>);

/// Parse `A:B,C:D,...` into pairs of finite numbers.
pub fn parse_pairs(s: &str) -> Result<Pairs, String> {
    s.split(',')
        .map(|p| {
            let (a, b) = p
                .split_once(':')
                .ok_or_else(|| format!("`{p}`: expected T_MIN:HZ"))?;
            let a: f64 = a.trim().parse().map_err(|e| format!("`{a}`: {e}"))?;
            let b: f64 = b.trim().parse().map_err(|e| format!("`{b}`: {e}"))?;
            if a.is_finite() && b.is_finite() {
                Ok((a, b))
            } else {
                Err(format!("`{p}`: not finite"))
            }
        })
        .collect::<Result<Vec<_>, _>>()
        .map(Pairs)
}

/// Least-squares coefficient a of f = a·√T through the origin: a = Σ f√T / Σ T, over the
/// finite pairs.
pub fn sqrt_fit(t_min_n: &[f64], f_hz: &[f64]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (&t, &f) in t_min_n.iter().zip(f_hz) {
        if t.is_finite() && f.is_finite() && t >= 0.0 {
            num += f * t.sqrt();
            den += t;
        }
    }
    if den > 0.0 {
        num / den
    } else {
        f64::NAN
    }
}

/// f1 against T_min.
#[derive(Debug, Clone)]
pub struct TminSweep {
    /// One result per T_min.
    pub points: Vec<PointResult>,
    /// Fitted a in f1 = a·√T_min, Hz/√N.
    pub a: f64,
    /// Largest |f1 − a√T|/f1 over the valid points.
    pub max_rel_residual: f64,
}

/// Compute f1 against T_min (no files).
pub fn compute_sweep_tmin(
    s: &Scene,
    from: f64,
    to: f64,
    steps: usize,
    ee_mode: bool,
) -> Result<TminSweep, SweepError> {
    if !(from.is_finite() && to.is_finite() && from >= 0.0 && from <= to && to <= s.t_max_n)
        || steps == 0
        || steps > 100_000
    {
        return Err(SweepError::Usage(format!(
            "need 0 <= --from ({from}) <= --to ({to}) <= t_max ({}) and 1 <= --steps <= 100000",
            s.t_max_n
        )));
    }
    let ts: Vec<f64> = (0..steps)
        .map(|i| {
            if steps == 1 {
                from
            } else {
                from + (to - from) * i as f64 / (steps - 1) as f64
            }
        })
        .collect();
    let mut est = build(s, estimator_params(s, ee_mode))?;
    let pose = Pose::at(s.ee_position_m);
    let points: Vec<PointResult> = ts
        .iter()
        .map(|&t| PointResult {
            position_m: s.ee_position_m,
            t_min_n: t,
            estimate: *est.update(&pose, t),
        })
        .collect();
    let f: Vec<f64> = points
        .iter()
        .map(|p| {
            if p.estimate.is_ok() {
                p.estimate.f1_hz
            } else {
                f64::NAN
            }
        })
        .collect();
    let a = sqrt_fit(&ts, &f);
    let max_rel_residual = ts
        .iter()
        .zip(&f)
        .filter(|(_, f)| f.is_finite() && **f > 0.0)
        .map(|(t, f)| (f - a * t.sqrt()).abs() / f)
        .fold(0.0, f64::max);
    Ok(TminSweep {
        points,
        a,
        max_rel_residual,
    })
}

/// `cablevib sweep-tmin`: writes PREFIX.csv and PREFIX.svg.
pub fn sweep_tmin(a: &SweepTminArgs) -> Result<(), SweepError> {
    let s = resolve_scene(&a.scene)?;
    let from = a.from.unwrap_or(s.t_min_n);
    let to = a.to.unwrap_or((2.0 * from).min(s.t_max_n));
    let r = compute_sweep_tmin(&s, from, to, a.steps, !a.no_ee_mode)?;
    let mut csv = format!(
        "# cablevib sweep-tmin: scene {}, model {} x {}, position ({}, {}, {}) m; fit f1 = {:.6} sqrt(T_min)\nt_min_n,status,f1_hz,ee_mode_hz,fit_hz\n",
        s.name,
        s.model.element.as_str(),
        s.model.elements_per_cable,
        s.ee_position_m.x,
        s.ee_position_m.y,
        s.ee_position_m.z,
        r.a
    );
    for p in &r.points {
        let _ = writeln!(
            csv,
            "{},{},{},{},{}",
            p.t_min_n,
            p.estimate.status.as_str(),
            fnum(p.estimate.f1_hz),
            fnum(p.estimate.ee_mode_hz),
            fnum(r.a * p.t_min_n.sqrt())
        );
    }
    let csv_path = with_ext(&a.out, "csv");
    write_file(&csv_path, &csv)?;
    let pts = |f: &dyn Fn(&Estimate) -> f64| -> Vec<(f64, f64)> {
        r.points
            .iter()
            .map(|p| {
                (
                    p.t_min_n,
                    if p.estimate.is_ok() {
                        f(&p.estimate)
                    } else {
                        f64::NAN
                    },
                )
            })
            .collect()
    };
    let f1 = pts(&|e| e.f1_hz);
    let ee = pts(&|e| e.ee_mode_hz);
    let fine: Vec<(f64, f64)> = (0..=200)
        .map(|i| {
            let t = from + (to - from) * i as f64 / 200.0;
            (t, r.a * t.sqrt())
        })
        .collect();
    let mut plot = LinePlot::new(
        &format!("{}: first natural frequency against T_min", s.name),
        Axis::linear("T_min (N)"),
        Axis::linear("f (Hz)"),
    );
    plot.subtitle = format!(
        "{} × {} elements/cable at ({}, {}, {}) m; fit f1 = {:.5}·√T_min (max deviation {:.1e})",
        s.model.element.as_str(),
        s.model.elements_per_cable,
        s.ee_position_m.x,
        s.ee_position_m.y,
        s.ee_position_m.z,
        r.a,
        r.max_rel_residual
    );
    plot.series
        .push(Series::new(&format!("fit {:.5}·√T_min", r.a), fine, Mark::Line).color(PALETTE[1]));
    plot.series
        .push(Series::new("f1 (estimator)", f1.clone(), Mark::Points).color(PALETTE[0]));
    let differs = f1
        .iter()
        .zip(&ee)
        .any(|(a, b)| b.1.is_finite() && (a.1 - b.1).abs() > 1e-9 * b.1.abs());
    if !a.no_ee_mode && differs {
        plot.series
            .push(Series::new("end-effector mode", ee, Mark::LinePoints).color(PALETTE[2]));
    }
    if let Some(c) = &a.compare {
        plot.series
            .push(Series::new(&a.compare_label, c.0.clone(), Mark::Points).color(PALETTE[6]));
        for &(t, f) in &c.0 {
            let ours = r
                .points
                .iter()
                .find(|p| (p.t_min_n - t).abs() < 1e-9 && p.estimate.is_ok())
                .map(|p| p.estimate.f1_hz);
            if let Some(o) = ours {
                println!(
                    "  T_min {t} N: {} {f} Hz, estimator {o:.6} Hz, ratio {:.6}",
                    a.compare_label,
                    f / o
                );
            }
        }
    }
    let svg_path = a.svg.clone().unwrap_or_else(|| with_ext(&a.out, "svg"));
    write_file(&svg_path, &plot.to_svg())?;
    let counts = status_counts(&r.points);
    println!(
        "sweep-tmin: scene {}  T_min {from}..{to} N ({} values)  fit f1 = {:.6}·sqrt(T_min) Hz, max relative deviation {:.2e}  statuses: {}",
        s.name,
        a.steps,
        r.a,
        r.max_rel_residual,
        counts_text(&counts)
    );
    println!("  wrote {} and {}", csv_path.display(), svg_path.display());
    Ok(())
}

// ---------------------------------------------------------------------------------------
// accuracy
// ---------------------------------------------------------------------------------------

/// `cablevib accuracy`: f1 error and per-cycle cost of every model the scene can use.
#[derive(Debug, Args, Clone)]
pub struct AccuracyArgs {
    /// Scene and overrides (pose and T_min of the accuracy study; the model options
    /// are ignored: every model is run).
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output directory: writes OUT/accuracy.md (this scene's section), OUT/img/*.svg
    /// and OUT/data/*.csv.
    #[arg(long, default_value = "docs")]
    pub out_dir: PathBuf,
    /// Largest number of elements per cable (FEM and catenary).
    #[arg(long, default_value_t = 80)]
    pub max_elements: usize,
    /// Every N from 1 to --max-elements instead of 1,2,3,4,5,6,8,10,12,16,20,25,32,40,50,64,80.
    #[arg(long)]
    pub all_n: bool,
    /// Timed cycles per model along the circle (f1 only and with the end-effector mode).
    #[arg(long, default_value_t = 2000)]
    pub cycles: usize,
    /// Timing rounds over all models; each model reports its fastest round's median.
    #[arg(long, default_value_t = 5)]
    pub rounds: usize,
    /// Period of one revolution of the timing circle, s (poses 1 ms apart).
    #[arg(long, default_value_t = 4.0)]
    pub period_s: f64,
    /// Largest N of the dense mode-3 convergence study (paper Figs. 5 and 10); 0 skips it.
    #[arg(long, default_value_t = 40)]
    pub dense_max: usize,
}

/// The element counts of the study.
pub fn element_counts(max: usize, all: bool) -> Vec<usize> {
    const LIST: [usize; 17] = [1, 2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 25, 32, 40, 50, 64, 80];
    let mut v: Vec<usize> = if all {
        (1..=max).collect()
    } else {
        LIST.iter().copied().filter(|&n| n <= max).collect()
    };
    for extra in [max / 2, max] {
        if extra >= 1 && !v.contains(&extra) {
            v.push(extra);
        }
    }
    v.sort_unstable();
    v
}

/// One model of the accuracy study.
#[derive(Debug, Clone)]
pub struct AccuracyRow {
    /// Element kind.
    pub element: ElementKind,
    /// Elements per cable (FEM, catenary), else `None`.
    pub n: Option<usize>,
    /// Transverse geometric stiffness T/l on.
    pub geometric_stiffness: bool,
    /// Status at the study pose.
    pub status: Status,
    /// Why, when not ok.
    pub reason: String,
    /// f1 at the study pose, Hz.
    pub f1_hz: f64,
    /// End-effector mode at the study pose, Hz.
    pub ee_mode_hz: f64,
    /// (f1 − f1_ref)/f1_ref.
    pub err_ref: f64,
    /// (f1 − f1_continuous)/f1_continuous.
    pub err_continuous: f64,
    /// (f_ee − f_ee,ref)/f_ee,ref.
    pub ee_err_ref: f64,
    /// Per-cycle time along the circle, f1 only: median and p99, ns.
    pub f1_ns: (u64, u64),
    /// Per-cycle time with the end-effector mode: median and p99, ns.
    pub ee_ns: (u64, u64),
    /// Median D(λ) evaluations per cycle (with the end-effector mode).
    pub evaluations: u64,
}

impl AccuracyRow {
    /// A short model name ("fem N=10", "massless, no geometric stiffness", ...).
    pub fn label(&self) -> String {
        match (self.element, self.n) {
            (ElementKind::Massless, _) if !self.geometric_stiffness => {
                "massless springs, axial only".into()
            }
            (ElementKind::Massless, _) => "massless springs + T/l".into(),
            (ElementKind::Continuous, _) => "continuous (N → ∞)".into(),
            (k, Some(n)) => format!("{} N={n}", k.as_str()),
            (k, None) => k.as_str().into(),
        }
    }
}

/// The whole accuracy study of one scene and pose.
#[derive(Debug, Clone)]
pub struct AccuracyReport {
    /// Rows: massless ×2, continuous, FEM per N, catenary per N.
    pub rows: Vec<AccuracyRow>,
    /// Reference f1: catenary Richardson-extrapolated from N = max/2 and max, Hz.
    pub f1_ref_hz: f64,
    /// Reference end-effector mode, the same way, Hz.
    pub ee_ref_hz: f64,
    /// The continuous limit of the straight-cable FEM, Hz.
    pub f1_continuous_hz: f64,
    /// Observed convergence order of the catenary f1 from N = max/4, max/2, max.
    pub catenary_order: f64,
    /// Largest N.
    pub max_elements: usize,
}

fn timing(
    s: &Scene,
    ee_mode: bool,
    cycles: usize,
    period_s: f64,
) -> Result<((u64, u64), u64), SweepError> {
    if cycles == 0 {
        return Ok(((0, 0), 0));
    }
    let mut est = build(s, estimator_params(s, ee_mode))?;
    est.update(&circle_pose(s, 0, period_s), s.t_min_n);
    let mut ns = Vec::with_capacity(cycles);
    let mut ev = Vec::with_capacity(cycles);
    let mut ok = 0usize;
    for k in 1..=cycles {
        let pose = circle_pose(s, k, period_s);
        let t0 = Instant::now();
        let e = est.update(&pose, s.t_min_n);
        ns.push(t0.elapsed().as_nanos() as u64);
        ev.push(e.eigen_evaluations as u64);
        ok += e.is_ok() as usize;
    }
    if ok == 0 {
        return Ok(((0, 0), 0));
    }
    ns.sort_unstable();
    ev.sort_unstable();
    Ok((
        (percentile(&ns, 0.5), percentile(&ns, 0.99)),
        percentile(&ev, 0.5),
    ))
}

fn at_pose(s: &Scene) -> Result<Estimate, SweepError> {
    let mut est = build(s, estimator_params(s, true))?;
    let e = *est.update(&Pose::at(s.ee_position_m), s.t_min_n);
    if e.is_ok() {
        return Ok(e);
    }
    // The end-effector mode may be what failed; f1 alone may still be valid.
    let mut est = build(s, estimator_params(s, false))?;
    let e1 = *est.update(&Pose::at(s.ee_position_m), s.t_min_n);
    Ok(if e1.is_ok() { e1 } else { e })
}

/// Run the study (no files): f1 and the end-effector mode at the scene's pose and T_min
/// for every model, errors against the reference, and per-cycle timings along the circle.
///
/// Timings: `rounds` rounds, each timing every model for `cycles` cycles in turn; a
/// model reports the round with the smallest median (its p99 from the same round), so
/// that a burst of unrelated load on the machine does not land on one model only.
pub fn compute_accuracy(
    base: &Scene,
    ns: &[usize],
    cycles: usize,
    period_s: f64,
    rounds: usize,
) -> Result<AccuracyReport, SweepError> {
    let max = ns.iter().copied().max().unwrap_or(1);
    let mut models: Vec<Scene> = Vec::new();
    let mut ml = base.with_model(ElementKind::Massless, 1);
    ml.model.geometric_stiffness = false;
    models.push(ml);
    models.push(base.with_model(ElementKind::Massless, 1));
    models.push(base.with_model(ElementKind::Continuous, 1));
    for &n in ns {
        models.push(base.with_model(ElementKind::Fem, n));
    }
    for &n in ns {
        models.push(base.with_model(ElementKind::Catenary, n));
    }
    // Best round per model: ((p50, p99) f1 only, (p50, p99) with EE mode, evaluations).
    type Best = ((u64, u64), (u64, u64), u64);
    let mut best: Vec<Option<Best>> = vec![None; models.len()];
    for _ in 0..rounds.max(1) {
        for (k, s) in models.iter().enumerate() {
            let (f1, _) = timing(s, false, cycles, period_s)?;
            let (ee, ev) = timing(s, true, cycles, period_s)?;
            let b = best[k].get_or_insert((f1, ee, ev));
            if f1.0 > 0 && f1.0 < b.0 .0 {
                b.0 = f1;
            }
            if ee.0 > 0 && ee.0 < b.1 .0 {
                b.1 = ee;
                b.2 = ev;
            }
        }
    }
    let mut rows = Vec::new();
    for (s, b) in models.iter().zip(best) {
        let e = at_pose(s)?;
        let (f1_ns, ee_ns, evals) = b.unwrap_or_default();
        rows.push(AccuracyRow {
            element: s.model.element,
            n: s.model
                .element
                .is_discrete()
                .then_some(s.model.elements_per_cable),
            geometric_stiffness: s.model.geometric_stiffness,
            status: e.status,
            reason: e.error.map(|x| x.to_string()).unwrap_or_default(),
            f1_hz: if e.is_ok() { e.f1_hz } else { f64::NAN },
            ee_mode_hz: if e.is_ok() { e.ee_mode_hz } else { f64::NAN },
            err_ref: f64::NAN,
            err_continuous: f64::NAN,
            ee_err_ref: f64::NAN,
            f1_ns,
            ee_ns,
            evaluations: evals,
        });
    }
    let cat = |n: usize, ee: bool| {
        rows.iter()
            .find(|r| r.element == ElementKind::Catenary && r.n == Some(n))
            .map(|r| if ee { r.ee_mode_hz } else { r.f1_hz })
            .unwrap_or(f64::NAN)
    };
    let rich = |ee: bool| {
        let (a, b) = (cat(max / 2, ee), cat(max, ee));
        if max >= 2 {
            b + (b - a) / 3.0
        } else {
            b
        }
    };
    let f1_ref_hz = rich(false);
    let ee_ref_hz = rich(true);
    let catenary_order = if max >= 4 {
        let (a, b, c) = (cat(max / 4, false), cat(max / 2, false), cat(max, false));
        ((a - b) / (b - c)).abs().log2()
    } else {
        f64::NAN
    };
    let f1_continuous_hz = rows
        .iter()
        .find(|r| r.element == ElementKind::Continuous)
        .map(|r| r.f1_hz)
        .unwrap_or(f64::NAN);
    for r in &mut rows {
        r.err_ref = (r.f1_hz - f1_ref_hz) / f1_ref_hz;
        r.err_continuous = (r.f1_hz - f1_continuous_hz) / f1_continuous_hz;
        r.ee_err_ref = (r.ee_mode_hz - ee_ref_hz) / ee_ref_hz;
    }
    Ok(AccuracyReport {
        rows,
        f1_ref_hz,
        ee_ref_hz,
        f1_continuous_hz,
        catenary_order,
        max_elements: max,
    })
}

/// Mode 3 (index 2 of the dense spectrum) against N, paper Figs. 5 and 10.
#[derive(Debug, Clone)]
pub struct Mode3Row {
    /// Element kind.
    pub element: ElementKind,
    /// Elements per cable.
    pub n: usize,
    /// Frequencies of modes 1-3 (NaN when the model has fewer modes), Hz.
    pub modes_hz: [f64; 3],
    /// Degrees of freedom.
    pub dof: usize,
    /// Wall time of the dense reference, s.
    pub seconds: f64,
}

/// The dense convergence study: modes 1-3 for FEM and catenary, N in `ns`.
pub fn compute_mode3(s: &Scene, ns: &[usize]) -> Result<Vec<Mode3Row>, SweepError> {
    let mut out = Vec::new();
    for el in [ElementKind::Fem, ElementKind::Catenary] {
        for &n in ns {
            let m = s.with_model(el, n);
            let t0 = Instant::now();
            let r = reference_analysis(&m, &m.ee_position_m, m.t_min_n, false).map_err(|e| {
                SweepError::Build(format!("dense reference, {} N={n}: {e}", el.as_str()))
            })?;
            let seconds = t0.elapsed().as_secs_f64();
            let mut modes_hz = [f64::NAN; 3];
            for (k, l) in r.modes.lambda.iter().take(3).enumerate() {
                modes_hz[k] = lambda_to_hz(*l);
            }
            out.push(Mode3Row {
                element: el,
                n,
                modes_hz,
                dof: r.dof,
                seconds,
            });
        }
    }
    Ok(out)
}

fn sci(x: f64) -> String {
    if x.is_finite() {
        format!("{x:+.2e}")
    } else {
        "—".into()
    }
}

fn us(ns: u64) -> String {
    if ns == 0 {
        "—".into()
    } else {
        format!("{:.1}", ns as f64 / 1e3)
    }
}

fn hz(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.6}")
    } else {
        "—".into()
    }
}

fn cpu_name() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|x| x.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

fn file_stem(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The figures of the study: error vs N, error vs per-cycle time, and mode 3 vs N.
pub fn accuracy_svgs(
    s: &Scene,
    r: &AccuracyReport,
    mode3: &[Mode3Row],
) -> (String, String, Option<String>) {
    let family = |el: ElementKind| -> Vec<&AccuracyRow> {
        r.rows.iter().filter(|x| x.element == el).collect()
    };
    let fem = family(ElementKind::Fem);
    let cat = family(ElementKind::Catenary);
    let pt = |v: &[&AccuracyRow], f: &dyn Fn(&AccuracyRow) -> f64| -> Vec<(f64, f64)> {
        v.iter()
            .map(|x| (x.n.unwrap_or(0) as f64, f(x).abs()))
            .collect()
    };
    let mut p = LinePlot::new(
        &format!("{}: f1 error against elements per cable", s.name),
        Axis::log("elements per cable N"),
        Axis::log("|f1 − f1,ref| / f1,ref"),
    );
    p.subtitle = format!(
        "pose ({}, {}, {}) m, T_min {} N; reference f1,ref = {:.9} Hz (catenary N = {}, Richardson)",
        s.ee_position_m.x,
        s.ee_position_m.y,
        s.ee_position_m.z,
        s.t_min_n,
        r.f1_ref_hz,
        r.max_elements
    );
    p.series.push(
        Series::new(
            "FEM vs reference",
            pt(&fem, &|x| x.err_ref),
            Mark::LinePoints,
        )
        .color(PALETTE[0]),
    );
    p.series.push(
        Series::new(
            "catenary vs reference",
            pt(&cat, &|x| x.err_ref),
            Mark::LinePoints,
        )
        .color(PALETTE[1]),
    );
    p.series.push(
        Series::new(
            "FEM vs its continuous limit",
            pt(&fem, &|x| x.err_continuous),
            Mark::Dashed,
        )
        .color(PALETTE[2]),
    );
    for row in &r.rows {
        if row.n.is_none() && row.err_ref.is_finite() {
            let color = match row.element {
                ElementKind::Continuous => PALETTE[3],
                _ if row.geometric_stiffness => PALETTE[4],
                _ => PALETTE[6],
            };
            p.hlines.push(HLine {
                name: format!("{}: {:.1e}", row.label(), row.err_ref.abs()),
                y: row.err_ref.abs(),
                color: color.into(),
            });
        }
    }
    let err_n = p.to_svg();

    let mut q = LinePlot::new(
        &format!("{}: what accuracy costs", s.name),
        Axis::log("median per-cycle time of the real-time path, f1 only (µs)"),
        Axis::log("|f1 − f1,ref| / f1,ref"),
    );
    q.subtitle = format!(
        "{} cycles along the r = 0.75 m circle per model; error at ({}, {}, {}) m, T_min {} N",
        "timed", s.ee_position_m.x, s.ee_position_m.y, s.ee_position_m.z, s.t_min_n
    );
    let lab_ns = [1usize, 4, 10, 40, r.max_elements];
    let scatter = |v: &[&AccuracyRow]| -> (Vec<(f64, f64)>, Vec<Option<String>>) {
        v.iter()
            .filter(|x| x.f1_ns.0 > 0)
            .map(|x| {
                (
                    (x.f1_ns.0 as f64 / 1e3, x.err_ref.abs()),
                    x.n.filter(|n| lab_ns.contains(n)).map(|n| format!("N={n}")),
                )
            })
            .unzip()
    };
    let (a, la) = scatter(&fem);
    q.series.push(
        Series::new("FEM", a, Mark::Points)
            .color(PALETTE[0])
            .labels(la),
    );
    let (b, lb) = scatter(&cat);
    q.series.push(
        Series::new("catenary", b, Mark::Points)
            .color(PALETTE[1])
            .labels(lb),
    );
    for row in r.rows.iter().filter(|x| x.n.is_none()) {
        if row.f1_ns.0 > 0 && row.err_ref.is_finite() {
            let color = match row.element {
                ElementKind::Continuous => PALETTE[3],
                _ if row.geometric_stiffness => PALETTE[4],
                _ => PALETTE[6],
            };
            q.series.push(
                Series::new(
                    &row.label(),
                    vec![(row.f1_ns.0 as f64 / 1e3, row.err_ref.abs())],
                    Mark::Points,
                )
                .color(color),
            );
        }
    }
    let cost = q.to_svg();

    let m3 = if mode3.is_empty() {
        None
    } else {
        let mut m = LinePlot::new(
            &format!(
                "{}: convergence of mode 3 with the number of elements",
                s.name
            ),
            Axis::linear("elements per cable N"),
            Axis::linear("frequency of mode 3 (Hz)"),
        );
        m.subtitle = format!(
            "dense reference (all modes), pose ({}, {}, {}) m, T_min {} N",
            s.ee_position_m.x, s.ee_position_m.y, s.ee_position_m.z, s.t_min_n
        );
        for (k, el) in [ElementKind::Fem, ElementKind::Catenary].iter().enumerate() {
            let pts: Vec<(f64, f64)> = mode3
                .iter()
                .filter(|x| x.element == *el)
                .map(|x| (x.n as f64, x.modes_hz[2]))
                .collect();
            m.series.push(
                Series::new(&format!("{} element", el.as_str()), pts, Mark::LinePoints)
                    .color(PALETTE[k]),
            );
        }
        Some(m.to_svg())
    };
    (err_n, cost, m3)
}

/// The Markdown section of one scene (between its markers in accuracy.md).
pub fn accuracy_markdown(
    s: &Scene,
    r: &AccuracyReport,
    mode3: &[Mode3Row],
    command: &str,
    cycles: usize,
    rounds: usize,
    img: &[String],
) -> String {
    let mut o = String::new();
    let _ = writeln!(o, "## {}\n", s.name);
    let _ = writeln!(o, "Generated by\n\n```sh\n{command}\n```\n");
    let _ = writeln!(
        o,
        "Pose ({}, {}, {}) m, T_min {} N, T_max {} N. Reference f1,ref = **{:.9} Hz**: the catenary \
         element at N = {} and N = {} extrapolated by Richardson (f(N) + (f(N) − f(N/2))/3; the \
         observed order of the catenary f1 from N = {}, {}, {} is {:.2}). The continuous limit of \
         the straight-cable FEM is {:.9} Hz ({} from the reference). End-effector mode reference: \
         {:.9} Hz.\n",
        s.ee_position_m.x,
        s.ee_position_m.y,
        s.ee_position_m.z,
        s.t_min_n,
        s.t_max_n,
        r.f1_ref_hz,
        r.max_elements / 2,
        r.max_elements,
        r.max_elements / 4,
        r.max_elements / 2,
        r.max_elements,
        r.catenary_order,
        r.f1_continuous_hz,
        sci((r.f1_continuous_hz - r.f1_ref_hz) / r.f1_ref_hz),
        r.ee_ref_hz
    );
    let _ = writeln!(
        o,
        "Times: per-cycle `Estimator::update` (tensions, cable models, f1, optionally the \
         end-effector mode) over {cycles} consecutive poses of the r = 0.75 m circle, 1 ms apart, \
         one thread, {} ({} logical CPUs, shared with other work); {rounds} rounds over all \
         models, each model showing its fastest round (median and that round's p99). \
         Errors are signed, (f − f_ref)/f_ref.\n",
        cpu_name(),
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    );
    for i in img.iter().take(2) {
        let _ = writeln!(o, "![]({i})\n");
    }
    let _ = writeln!(
        o,
        "| model | f1 (Hz) | error vs ref | error vs continuous | end-effector mode (Hz) | its error vs ref | f1 only p50 / p99 (µs) | with EE mode p50 / p99 (µs) | D(λ) evals |"
    );
    let _ = writeln!(o, "|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for row in &r.rows {
        if row.status != Status::Ok {
            let _ = writeln!(
                o,
                "| {} | {} | — | — | — | — | — | — | — |",
                row.label(),
                row.status.as_str(),
            );
            continue;
        }
        let _ = writeln!(
            o,
            "| {} | {} | {} | {} | {} | {} | {} / {} | {} / {} | {} |",
            row.label(),
            hz(row.f1_hz),
            sci(row.err_ref),
            sci(row.err_continuous),
            hz(row.ee_mode_hz),
            sci(row.ee_err_ref),
            us(row.f1_ns.0),
            us(row.f1_ns.1),
            us(row.ee_ns.0),
            us(row.ee_ns.1),
            row.evaluations
        );
    }
    let notes: Vec<String> = r
        .rows
        .iter()
        .filter(|x| x.status != Status::Ok)
        .map(|x| format!("- {}: `{}` — {}", x.label(), x.status.as_str(), x.reason))
        .collect();
    if !notes.is_empty() {
        let _ = writeln!(o, "\n{}", notes.join("\n"));
    }
    if !mode3.is_empty() {
        let _ = writeln!(
            o,
            "\n### Mode 3 against N (paper Fig. {})\n",
            if s.n_cables() == 4 { "5" } else { "10" }
        );
        if let Some(i) = img.get(2) {
            let _ = writeln!(o, "![]({i})\n");
        }
        let _ = writeln!(
            o,
            "Dense reference (`reference_analysis`: assembled K and M, every mode), one thread.\n"
        );
        let _ = writeln!(
            o,
            "| N | DOF | FEM modes 1-3 (Hz) | catenary modes 1-3 (Hz) | dense time FEM (ms) |"
        );
        let _ = writeln!(o, "|---:|---:|---|---|---:|");
        let fem: Vec<&Mode3Row> = mode3
            .iter()
            .filter(|x| x.element == ElementKind::Fem)
            .collect();
        for f in fem {
            let c = mode3
                .iter()
                .find(|x| x.element == ElementKind::Catenary && x.n == f.n);
            let modes = |m: &[f64; 3]| {
                m.iter()
                    .map(|x| {
                        if x.is_finite() {
                            format!("{x:.4}")
                        } else {
                            "—".into()
                        }
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let _ = writeln!(
                o,
                "| {} | {} | {} | {} | {:.1} |",
                f.n,
                f.dof,
                modes(&f.modes_hz),
                c.map(|c| modes(&c.modes_hz)).unwrap_or_default(),
                f.seconds * 1e3
            );
        }
    }
    o
}

/// Replace (or append) the section between `<!-- accuracy:NAME:begin -->` and
/// `<!-- accuracy:NAME:end -->` in `doc`.
pub fn splice_section(doc: &str, name: &str, body: &str) -> String {
    let begin = format!("<!-- accuracy:{name}:begin -->");
    let end = format!("<!-- accuracy:{name}:end -->");
    let block = format!("{begin}\n{body}{end}\n");
    if let (Some(a), Some(b)) = (doc.find(&begin), doc.find(&end)) {
        if a < b {
            let after = &doc[b + end.len()..];
            let after = after.strip_prefix('\n').unwrap_or(after);
            return format!("{}{block}{after}", &doc[..a]);
        }
    }
    let mut d = doc.to_string();
    if !d.is_empty() && !d.ends_with("\n\n") {
        d.push_str(if d.ends_with('\n') { "\n" } else { "\n\n" });
    }
    d.push_str(&block);
    d
}

fn command_line(a: &AccuracyArgs) -> String {
    let mut c = format!("cablevib accuracy {}", a.scene.scene);
    if let Some(p) = a.scene.position {
        let _ = write!(c, " --position {},{},{}", p.x, p.y, p.z);
    }
    if let Some(t) = a.scene.t_min {
        let _ = write!(c, " --t-min {t}");
    }
    let _ = write!(
        c,
        " --out-dir {} --max-elements {} --cycles {}",
        a.out_dir.display(),
        a.max_elements,
        a.cycles
    );
    if a.all_n {
        c.push_str(" --all-n");
    }
    if a.period_s != 4.0 {
        let _ = write!(c, " --period-s {}", a.period_s);
    }
    if a.rounds != 5 {
        let _ = write!(c, " --rounds {}", a.rounds);
    }
    if a.dense_max != 40 {
        let _ = write!(c, " --dense-max {}", a.dense_max);
    }
    c
}

/// `cablevib accuracy`: writes OUT/data/accuracy-SCENE.csv, OUT/data/mode3-SCENE.csv,
/// OUT/img/accuracy-SCENE-{error-vs-n,cost,mode3}.svg and this scene's section of
/// OUT/accuracy.md.
pub fn accuracy(a: &AccuracyArgs) -> Result<(), SweepError> {
    let s = resolve_scene(&a.scene)?;
    if a.max_elements == 0 || a.max_elements > 2000 {
        return Err(SweepError::Usage(
            "--max-elements must be in 1..=2000".into(),
        ));
    }
    if !(a.period_s.is_finite() && a.period_s > 0.0) {
        return Err(SweepError::Usage("--period-s must be > 0".into()));
    }
    let ns = element_counts(a.max_elements, a.all_n);
    let t0 = Instant::now();
    eprintln!(
        "accuracy: {} models × {} cycles × 2 × {} rounds on {}",
        3 + 2 * ns.len(),
        a.cycles,
        a.rounds.max(1),
        s.name
    );
    let r = compute_accuracy(&s, &ns, a.cycles, a.period_s, a.rounds)?;
    let dense_ns: Vec<usize> = element_counts(a.dense_max.max(1), false)
        .into_iter()
        .filter(|&n| a.dense_max > 0 && n <= a.dense_max)
        .collect();
    eprintln!(
        "accuracy: real-time study done in {:.1} s; dense mode-3 study for N = {:?}",
        t0.elapsed().as_secs_f64(),
        dense_ns
    );
    let mode3 = compute_mode3(&s, &dense_ns)?;
    let stem = file_stem(&s.name);
    let data = a.out_dir.join("data");
    let imgd = a.out_dir.join("img");
    // CSVs.
    let mut csv = String::from(
        "model,element,n,geometric_stiffness,status,f1_hz,err_ref,err_continuous,ee_mode_hz,ee_err_ref,f1_p50_ns,f1_p99_ns,ee_p50_ns,ee_p99_ns,evaluations_p50\n",
    );
    for x in &r.rows {
        let _ = writeln!(
            csv,
            "\"{}\",{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            x.label(),
            x.element.as_str(),
            x.n.map(|n| n.to_string()).unwrap_or_default(),
            x.geometric_stiffness,
            x.status.as_str(),
            fnum(x.f1_hz),
            fnum(x.err_ref),
            fnum(x.err_continuous),
            fnum(x.ee_mode_hz),
            fnum(x.ee_err_ref),
            x.f1_ns.0,
            x.f1_ns.1,
            x.ee_ns.0,
            x.ee_ns.1,
            x.evaluations
        );
    }
    write_file(&data.join(format!("accuracy-{stem}.csv")), &csv)?;
    if !mode3.is_empty() {
        let mut m = String::from("element,n,dof,mode1_hz,mode2_hz,mode3_hz,dense_seconds\n");
        for x in &mode3 {
            let _ = writeln!(
                m,
                "{},{},{},{},{},{},{}",
                x.element.as_str(),
                x.n,
                x.dof,
                fnum(x.modes_hz[0]),
                fnum(x.modes_hz[1]),
                fnum(x.modes_hz[2]),
                x.seconds
            );
        }
        write_file(&data.join(format!("mode3-{stem}.csv")), &m)?;
    }
    // Figures.
    let (e_n, cost, m3) = accuracy_svgs(&s, &r, &mode3);
    let mut imgs = vec![
        format!("accuracy-{stem}-error-vs-n.svg"),
        format!("accuracy-{stem}-cost.svg"),
    ];
    write_file(&imgd.join(&imgs[0]), &e_n)?;
    write_file(&imgd.join(&imgs[1]), &cost)?;
    if let Some(m3) = m3 {
        imgs.push(format!("accuracy-{stem}-mode3.svg"));
        write_file(&imgd.join(&imgs[2]), &m3)?;
    }
    // Markdown section.
    let rel: Vec<String> = imgs.iter().map(|i| format!("img/{i}")).collect();
    let body = accuracy_markdown(
        &s,
        &r,
        &mode3,
        &command_line(a),
        a.cycles,
        a.rounds.max(1),
        &rel,
    );
    let md = a.out_dir.join("accuracy.md");
    let old = match std::fs::read_to_string(&md) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            "# What accuracy costs in time\n\nSections below are written by `cablevib accuracy`.\n"
                .to_string()
        }
        Err(e) => return Err(io_err(&md)(e)),
    };
    write_file(&md, &splice_section(&old, &s.name, &body))?;
    println!(
        "accuracy: {}  f1,ref {:.9} Hz  continuous {:.9} Hz  ({:.1} s)",
        s.name,
        r.f1_ref_hz,
        r.f1_continuous_hz,
        t0.elapsed().as_secs_f64()
    );
    for x in &r.rows {
        println!(
            "  {:<34} {:<10} f1 {:>14}  err {:>10}  p50 {:>7} µs  (+EE {:>7} µs)",
            x.label(),
            x.status.as_str(),
            hz(x.f1_hz),
            sci(x.err_ref),
            us(x.f1_ns.0),
            us(x.ee_ns.0)
        );
    }
    println!("  wrote {}", md.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_and_axes() {
        assert_eq!(
            parse_interval("-1,1").unwrap(),
            Interval { lo: -1.0, hi: 1.0 }
        );
        assert_eq!(
            parse_interval("0.5").unwrap(),
            Interval { lo: 0.5, hi: 0.5 }
        );
        assert!(parse_interval("1,-1").is_err());
        assert!(parse_interval("a").is_err());
        let g = grid_axis(Interval { lo: -1.0, hi: 1.0 }, 0.1).unwrap();
        assert_eq!(g.len(), 21);
        assert_eq!(g[20], 1.0);
        assert_eq!(g[10], 0.0);
        let g = grid_axis(Interval { lo: 0.25, hi: 1.25 }, 0.1).unwrap();
        assert_eq!(g.len(), 11);
    }

    #[test]
    fn splice_replaces_only_its_section() {
        let d = splice_section("# T\n", "a", "A1\n");
        let d = splice_section(&d, "b", "B1\n");
        let d = splice_section(&d, "a", "A2\n");
        assert!(d.contains("A2") && !d.contains("A1") && d.contains("B1"));
        assert!(d.find("A2").unwrap() < d.find("B1").unwrap());
    }

    #[test]
    fn counts() {
        assert_eq!(
            element_counts(80, false),
            vec![1, 2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 25, 32, 40, 50, 64, 80]
        );
        assert_eq!(element_counts(6, false), vec![1, 2, 3, 4, 5, 6]);
        assert_eq!(element_counts(7, false), vec![1, 2, 3, 4, 5, 6, 7]);
    }
}
