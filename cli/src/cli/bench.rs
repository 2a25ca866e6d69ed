//! `cablevib bench`: the real-time estimator along the paper's circle (radius 0.75 m, or
//! `--radius-m` for a larger robot), per-cycle latency, allocations, and the dense
//! reference on a few poses for comparison.

use super::args::{resolve_scene, SceneArgs};
use super::{json_f64, AllocCounter, CliError};
use crate::estimator::{reference_analysis, Estimator, EstimatorParams, Tmin};
use crate::modal::lambda_to_hz;
use crate::scene::Scene;
use crate::service::stats::{percentile, StatusHistogram};
use crate::trajectory::{circle_pose_with_radius, CIRCLE_RADIUS_M};
use cablevib::outln;
use clap::Args;
use std::time::Instant;

/// `cablevib bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Scene and overrides.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Cycles to time.
    #[arg(long, default_value_t = 20_000)]
    pub cycles: usize,
    /// Period of one revolution of the circle, s (poses are spaced 1 ms apart). With a large
    /// radius, lengthen it: a pose step above 5 mm per cycle starts every cycle cold (e.g.
    /// `--radius-m 30 --period-s 400`, 0.47 m/s).
    #[arg(long, default_value_t = 4.0)]
    pub period_s: f64,
    /// Radius of the circle around the scene's position, m (the paper's 0.75 m by default;
    /// a 300 m robot needs metres to move its cables measurably).
    #[arg(long, default_value_t = CIRCLE_RADIUS_M)]
    pub radius_m: f64,
    /// Poses on which the dense reference is timed and compared (0 to skip).
    #[arg(long, default_value_t = 8)]
    pub dense_samples: usize,
    /// Skip the end-effector mode (f1 only).
    #[arg(long)]
    pub no_ee_mode: bool,
    /// One JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// The timed cycles along the circle.
struct CircleRun {
    /// Per-cycle compute time, ns, ascending.
    ns: Vec<u64>,
    /// D(λ) evaluations per cycle, ascending.
    evals: Vec<u64>,
    statuses: StatusHistogram,
    /// (smallest valid f1 in Hz, its cycle), and the largest.
    f1_min: (f64, usize),
    f1_max: (f64, usize),
    allocs: u64,
    /// Age of the end-effector answer at each ok cycle that had one, cycles, ascending.
    ee_age: Vec<u64>,
    /// Ok cycles without an end-effector answer (none known yet, or none found).
    ee_unknown: usize,
}

/// Time `a.cycles` cycles of `est` (after one cold cycle) along the circle.
fn run_circle(
    est: &mut Estimator,
    s: &Scene,
    a: &BenchArgs,
    allocations: AllocCounter,
) -> CircleRun {
    // Warm-up cycle (cold start), then timed cycles.
    est.update(
        &circle_pose_with_radius(s, 0, a.period_s, a.radius_m),
        Tmin::Scene,
    );
    let mut ns = Vec::with_capacity(a.cycles);
    let mut evals = Vec::with_capacity(a.cycles);
    let mut statuses = StatusHistogram::default();
    let mut f1_min = (f64::INFINITY, 0usize);
    let mut f1_max = (f64::NEG_INFINITY, 0usize);
    let mut ee_age = Vec::with_capacity(a.cycles);
    let mut ee_unknown = 0;
    let alloc0 = allocations();
    for k in 1..=a.cycles {
        let pose = circle_pose_with_radius(s, k, a.period_s, a.radius_m);
        let t0 = Instant::now();
        let e = est.update(&pose, Tmin::Scene);
        let dt = t0.elapsed().as_nanos() as u64;
        ns.push(dt);
        evals.push(e.eigen_evaluations);
        statuses.record(e.status);
        if e.is_ok() {
            if e.f1_hz < f1_min.0 {
                f1_min = (e.f1_hz, k);
            }
            if e.f1_hz > f1_max.0 {
                f1_max = (e.f1_hz, k);
            }
            match e.ee_mode {
                Some(m) => ee_age.push(u64::from(m.age_cycles)),
                None => ee_unknown += 1,
            }
        }
    }
    let allocs = allocations() - alloc0;
    ns.sort_unstable();
    evals.sort_unstable();
    ee_age.sort_unstable();
    CircleRun {
        ns,
        evals: evals.iter().map(|&x| x as u64).collect(),
        statuses,
        f1_min,
        f1_max,
        allocs,
        ee_age,
        ee_unknown,
    }
}

/// The dense reference against a cold real-time estimator on a sample of the poses.
struct DenseCheck {
    /// Dense solve times, ns, ascending.
    ns: Vec<u64>,
    max_rel_err_f1: f64,
    max_rel_err_ee: f64,
}

fn dense_check(s: &Scene, a: &BenchArgs, p: EstimatorParams) -> Result<DenseCheck, CliError> {
    let mut dense_ns = Vec::new();
    let mut max_rel_err_f1 = 0.0f64;
    let mut max_rel_err_ee = 0.0f64;
    let mut rt_on_samples = Vec::new();
    if s.model.element.is_discrete() {
        for j in 0..a.dense_samples {
            let k = 1 + j * (a.cycles / a.dense_samples.max(1)).max(1);
            let pose = circle_pose_with_radius(s, k, a.period_s, a.radius_m);
            let t0 = Instant::now();
            let r = reference_analysis(s, &pose.position_m, Tmin::Scene, true);
            let dt = t0.elapsed().as_nanos() as u64;
            let Ok(r) = r else { continue };
            dense_ns.push(dt);
            let mut cold =
                Estimator::with_params(s, p).map_err(|e| CliError::Analysis(e.to_string()))?;
            let t1 = Instant::now();
            let e = *cold.update(&pose, Tmin::Scene);
            rt_on_samples.push(t1.elapsed().as_nanos() as u64);
            if e.is_ok() {
                max_rel_err_f1 =
                    max_rel_err_f1.max((e.f1_hz - lambda_to_hz(r.modes.lambda[0])).abs() / e.f1_hz);
                if let Some((_, l)) = r.modes.first_ee_mode(p.modal.ee_participation_min) {
                    if let Some(m) = e.ee_mode {
                        max_rel_err_ee = max_rel_err_ee
                            .max((m.frequency_hz - lambda_to_hz(l)).abs() / m.frequency_hz);
                    }
                }
            }
        }
    }
    dense_ns.sort_unstable();
    Ok(DenseCheck {
        ns: dense_ns,
        max_rel_err_f1,
        max_rel_err_ee,
    })
}

/// `cablevib bench`.
pub fn run(a: &BenchArgs, allocations: AllocCounter) -> Result<(), CliError> {
    let s = resolve_scene(&a.scene)?;
    if a.cycles == 0
        || !(a.period_s.is_finite() && a.period_s > 0.0)
        || !(a.radius_m.is_finite() && a.radius_m >= 0.0)
    {
        return Err(CliError::Usage(
            "--cycles must be > 0, --period-s finite and > 0, --radius-m finite and >= 0".into(),
        ));
    }
    // The real-time preset, as the service runs.
    let p = EstimatorParams {
        ee_mode: !a.no_ee_mode,
        ..EstimatorParams::realtime().for_scene(&s)
    };
    let mut est = Estimator::with_params(&s, p).map_err(|e| CliError::Analysis(e.to_string()))?;
    let c = run_circle(&mut est, &s, a, allocations);
    // Dense reference on a sample of poses, timed in the same run.
    let d = dense_check(&s, a, p)?;
    if a.json {
        print_json(&s, a, p, &c, &d)?;
    } else {
        print_text(&s, a, p, &c, &d, &est)?;
    }
    Ok(())
}

/// Median dense time over the real-time p50 (NaN when the p50 is 0).
fn dense_ratio(c: &CircleRun, d: &DenseCheck) -> f64 {
    let p50 = percentile(&c.ns, 0.5);
    if p50 > 0 {
        percentile(&d.ns, 0.5) as f64 / p50 as f64
    } else {
        f64::NAN
    }
}

fn print_json(
    s: &Scene,
    a: &BenchArgs,
    p: EstimatorParams,
    c: &CircleRun,
    d: &DenseCheck,
) -> Result<(), CliError> {
    let q = |x: f64| percentile(&c.ns, x);
    let names: Vec<(String, usize)> = c
        .statuses
        .nonzero()
        .map(|(code, n)| (cablevib_ipc::status_str(code).to_string(), n as usize))
        .collect();
    // null when no ok cycle had an end-effector answer.
    let ee_age = |x: f64| (!c.ee_age.is_empty()).then(|| percentile(&c.ee_age, x));
    let o = serde_json::json!({
        "scene": s.name,
        "element": s.model.element.as_str(),
        "elements_per_cable": s.model.elements_per_cable,
        "ee_mode": p.ee_mode,
        "cycles": a.cycles,
        "radius_m": a.radius_m,
        "p50_ns": q(0.5), "p90_ns": q(0.9), "p99_ns": q(0.99), "p999_ns": q(0.999), "max_ns": q(1.0),
        "eigen_evaluations_p50": percentile(&c.evals, 0.5),
        "eigen_evaluations_p99": percentile(&c.evals, 0.99),
        "eigen_evaluations_max": c.evals.last().copied().unwrap_or(0) as usize,
        "ee_mode_age_p50": ee_age(0.5),
        "ee_mode_age_p99": ee_age(0.99),
        "ee_mode_age_max": ee_age(1.0),
        "ee_mode_unknown_cycles": c.ee_unknown,
        "cycle_evaluations_budget": p.modal.cycle_evaluations,
        "allocations_per_cycle": c.allocs as f64 / a.cycles as f64,
        "allocations_total": c.allocs,
        "dense_samples": d.ns.len(),
        "dense_median_ns": percentile(&d.ns, 0.5),
        "dense_to_realtime_p50_ratio": json_f64(dense_ratio(c, d)),
        "max_rel_err_f1": d.max_rel_err_f1,
        "max_rel_err_ee_mode": d.max_rel_err_ee,
        "f1_min_hz": json_f64(c.f1_min.0), "f1_max_hz": json_f64(c.f1_max.0),
        "statuses": names.iter().map(|(n, c)| serde_json::json!({"status": n, "count": c})).collect::<Vec<_>>(),
    });
    outln!("{o}")?;
    Ok(())
}

fn print_text(
    s: &Scene,
    a: &BenchArgs,
    p: EstimatorParams,
    c: &CircleRun,
    d: &DenseCheck,
    est: &Estimator,
) -> Result<(), CliError> {
    let q = |x: f64| percentile(&c.ns, x);
    let allocs = c.allocs;
    let per_cycle_allocs = allocs as f64 / a.cycles as f64;
    let names: Vec<(String, usize)> = c
        .statuses
        .nonzero()
        .map(|(code, n)| (cablevib_ipc::status_str(code).to_string(), n as usize))
        .collect();
    outln!(
        "scene {}  model {} × {}  {} cycles along the r = {} m circle ({} s per revolution, 1 ms spacing){}",
        s.name,
        s.model.element.as_str(),
        s.model.elements_per_cable,
        a.cycles,
        a.radius_m,
        a.period_s,
        if p.ee_mode { "" } else { ", f1 only" }
    )?;
    outln!(
        "  per-cycle compute: p50 {} ns  p90 {} ns  p99 {} ns  p99.9 {} ns  max {} ns",
        q(0.5),
        q(0.9),
        q(0.99),
        q(0.999),
        q(1.0)
    )?;
    let ev = &c.evals;
    outln!(
        "  D(λ) evaluations per cycle: p50 {}  p90 {}  p99 {}  max {} (budget {})",
        percentile(ev, 0.5),
        percentile(ev, 0.9),
        percentile(ev, 0.99),
        percentile(ev, 1.0),
        p.modal.cycle_evaluations
    )?;
    if p.ee_mode {
        let ea = &c.ee_age;
        if ea.is_empty() {
            outln!("  end-effector answer: none in {} ok cycles", c.ee_unknown)?;
        } else {
            outln!(
                "  end-effector answer's age, cycles: p50 {}  p99 {}  max {} ({} ok cycles without one)",
                percentile(ea, 0.5),
                percentile(ea, 0.99),
                percentile(ea, 1.0),
                c.ee_unknown
            )?;
        }
    }
    outln!(
        "  heap allocations: {allocs} in {} cycles ({per_cycle_allocs} per cycle)",
        a.cycles
    )?;
    outln!("  statuses: {names:?}")?;
    let rc = est.rescan_counts();
    outln!(
        "  end-effector mode bookkeeping: full scans cold {} uncertified {} none {}; lost {} dropped {}; partner searches {} neighbour searches {}; scans continued over cycles {}, cycles over budget {}",
        rc.cold_scans,
        rc.uncertified_scans,
        rc.no_mode_scans,
        rc.lost,
        rc.dropped,
        rc.partner_searches,
        rc.neighbour_searches,
        rc.continued_scans,
        rc.starved_cycles
    )?;
    let (f1_min, f1_max) = (c.f1_min, c.f1_max);
    if f1_min.0.is_finite() {
        outln!(
            "  f1 along the circle: min {:.6} Hz (cycle {}), max {:.6} Hz (cycle {})",
            f1_min.0,
            f1_min.1,
            f1_max.0,
            f1_max.1
        )?;
    }
    if !d.ns.is_empty() {
        outln!(
            "  dense reference on {} poses: median {:.3} ms  → {:.0}× the real-time p50; max |Δf1|/f1 {:.2e}, max |Δf_ee|/f_ee {:.2e}",
            d.ns.len(),
            percentile(&d.ns, 0.5) as f64 / 1e6,
            dense_ratio(c, d),
            d.max_rel_err_f1,
            d.max_rel_err_ee
        )?;
    }
    Ok(())
}
