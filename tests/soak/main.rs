//! Soak of the real-time estimator: a random walk through and out of the
//! workspace (mean-reverting ±1 cm steps, kicks and one-cycle glitches anywhere in the frame
//! plus 15 %), random T_min changes and injected bad samples (NaN, ±Inf, non-unit
//! quaternions, negative / NaN / too large T_min, a pose at an anchor).
//!
//! Checked every cycle: no panic; an estimate marked ok has finite, positive f1 and
//! end-effector mode, finite stiffness and tensions within [T_min, T_max]; a non-ok estimate
//! has NaN frequencies (nothing stale). Every 101 cycles a cold estimator answers the same
//! input and must agree (status, and f1 / end-effector mode to 1e-9), so warm starts never
//! pass off a stale or wrong value. Zero heap allocations in the measured loop (the counting
//! allocator of `cablevib::alloc_count` (the binary's `count_allocations!`), read on the soak thread around the
//! loop, so the test harness's other threads are not charged) and no
//! resident-memory growth. Prints the count of each status and the latency percentiles.
//!
//! Its own test binary: it measures the whole process's resident memory, which tests running
//! beside it in one binary would grow. `cargo test --release --test soak` runs the short soak
//! (2 × 20 000 cycles); `cargo test --release --test soak -- --ignored --nocapture` runs the long one
//! (10⁶ cycles of the paper's spatial robot, FEM N = 40, plus 2·10⁵ with the catenary
//! element); its figures are recorded in docs/hard-cases.md.

// The allocation counts need the counting allocator.
cablevib_testkit::count_allocations!();

use cablevib::alloc_count::{thread_allocated_bytes, thread_allocations};
use cablevib::estimator::Tmin;
use cablevib::estimator::{Estimator, Status};
use cablevib::kinematics::Pose;
use cablevib::scene::{ElementKind, Scene};
use cablevib::stats::percentile;
use cablevib_testkit::Rng;
use cablevib_testkit::{ee_hz, ee_p};
use nalgebra::Vector3;
use std::time::Instant;

/// Resident set size, kB (Linux; 0 elsewhere).
fn rss_kb() -> u64 {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| {
            s.split_whitespace()
                .nth(1)
                .and_then(|x| x.parse::<u64>().ok())
        })
        .map(|pages| pages * 4)
        .unwrap_or(0)
}

// ---------------------------------------------------------------------------------------
// The walk
// ---------------------------------------------------------------------------------------

const N_STATUS: usize = 16;

#[derive(Debug)]
struct Report {
    cycles: usize,
    status: [u64; N_STATUS],
    injected: u64,
    cold_checks: u64,
    allocations: u64,
    allocated_bytes: u64,
    rss_before_kb: u64,
    rss_after_kb: u64,
    latency_ns: [u64; 6],    // p50, p90, p99, p99.9, p99.99, max
    latency_ok_ns: [u64; 3], // p50, p99, max over ok cycles
    wall_s: f64,
    failures: Vec<String>,
    /// The first solver failures (NotConverged, RankDeficient) on finite input: what to look at.
    solver_failures: Vec<String>,
    /// Slowest cycle: (ns, status, position, t_min).
    slowest: (u64, Status, Vector3<f64>, f64),
}

// The loop index is the cycle number (also used for the latency slot), and `!(x <= tol)`
// is meant to catch NaN.
#[allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
fn soak(scene: &Scene, cycles: usize, seed: u64) -> Report {
    let mut est = Estimator::new(scene).expect("estimator");
    let mut cold = Estimator::new(scene).expect("estimator");
    let (lo, hi) = scene.frame_bounds_m();
    let extent = hi - lo;
    // The walk box: the frame plus 15 % on each side (so it leaves the workspace).
    let wlo = lo - extent * 0.15;
    let whi = hi + extent * 0.15;
    let t_max = scene.t_max_n;
    let mut rng = Rng(seed);
    let home = scene.ee_position_m;
    let mut p = home;
    let mut t_min = scene.t_min_n;
    // Latency buffers allocated and touched before the measurement (no page faults or
    // growth inside it).
    let mut latency: Vec<u64> = vec![1; cycles];
    let mut latency_ok: Vec<u64> = vec![1; cycles];
    let mut n_ok = 0usize;
    let mut status = [0u64; N_STATUS];
    let mut injected = 0u64;
    let mut cold_checks = 0u64;
    // Failures are recorded as (cycle, code) into a fixed array; text is built afterwards.
    type Fail = (usize, u8, f64, Vector3<f64>, f64, f64, f64);
    let mut fails: [Fail; 32] = [(0, 0, 0.0, Vector3::zeros(), 0.0, 0.0, 0.0); 32];
    let mut n_fails = 0usize;
    // (cycle, code, value, position, t_min, warm value, cold value)
    let mut fail = |k: usize, code: u8, x: f64, p: Vector3<f64>, tm: f64, w: f64, c: f64| {
        if n_fails < fails.len() {
            fails[n_fails] = (k, code, x, p, tm, w, c);
        }
        n_fails += 1;
    };
    let mut solver_fail: [(
        usize,
        Vector3<f64>,
        f64,
        Option<cablevib::estimator::EstimatorError>,
    ); 8] = [(0, Vector3::zeros(), 0.0, None); 8];
    let mut n_solver_fail = 0usize;
    let mut slowest = (0u64, Status::Ok, Vector3::zeros(), 0.0);
    // Warm up once outside the measurement (the first cold start).
    est.update(&Pose::at(p), Tmin::Uniform(t_min));

    let rss_before = rss_kb();
    let allocations_before = thread_allocations();
    let bytes_before = thread_allocated_bytes();
    let wall = Instant::now();
    for k in 0..cycles {
        // Random walk: ±1 cm steps pulled back to the default pose (stationary spread
        // ≈ 0.3 m, relaxation 5000 cycles), rare kicks anywhere in the walk box (sustained excursions that leave the
        // workspace and wander back), and one-cycle glitches anywhere in the box.
        if rng.chance(1e-4) {
            for i in 0..3 {
                p[i] = rng.range(wlo[i], whi[i]);
            }
        } else {
            for i in 0..3 {
                if extent[i] > 0.0 {
                    p[i] += rng.range(-1e-2, 1e-2) + 2e-4 * (home[i] - p[i]);
                }
                if p[i] < wlo[i] {
                    p[i] = 2.0 * wlo[i] - p[i];
                }
                if p[i] > whi[i] {
                    p[i] = 2.0 * whi[i] - p[i];
                }
            }
        }
        let mut q = p;
        if rng.chance(5e-3) {
            for i in 0..3 {
                q[i] = rng.range(wlo[i], whi[i]);
            }
        }
        // T_min set-point changes (the previous one stays in force when refused).
        if rng.chance(2e-3) {
            t_min = rng.range(0.05, 1.0) * scene.t_min_n * 2.0;
        }
        let mut pose = Pose::at(q);
        let mut tm = t_min;
        let mut bad = true;
        match rng.next_u64() % 100 {
            0 => pose.position_m[k % 3] = f64::NAN,
            1 => {
                pose.position_m[k % 3] = if k % 2 == 0 {
                    f64::INFINITY
                } else {
                    f64::NEG_INFINITY
                }
            }
            2 => pose.orientation_wxyz = [rng.range(0.0, 2.0), 0.3, -0.2, 0.1],
            3 => pose.orientation_wxyz[k % 4] = f64::NAN,
            4 => tm = -rng.range(1e-6, 100.0),
            5 => {
                tm = if k % 2 == 0 {
                    f64::NAN
                } else {
                    t_max * rng.range(1.0001, 3.0)
                }
            }
            6 => pose.position_m = scene.cables[k % scene.n_cables()].anchor_m,
            _ => bad = false,
        }
        injected += bad as u64;
        let t0 = Instant::now();
        let e = est.update(&pose, Tmin::Uniform(tm));
        let dt = t0.elapsed().as_nanos().min(u64::MAX as u128) as u64;
        latency[k] = dt;
        status[(e.status.as_u32() as usize).min(N_STATUS - 1)] += 1;
        if dt > slowest.0 {
            slowest = (dt, e.status, pose.position_m, tm);
        }
        if matches!(e.status, Status::NotConverged | Status::RankDeficient) {
            if n_solver_fail < solver_fail.len() {
                solver_fail[n_solver_fail] = (k, pose.position_m, tm, e.error);
            }
            n_solver_fail += 1;
        }
        if e.status == Status::Ok {
            latency_ok[n_ok] = dt;
            n_ok += 1;
            if !(e.f1_hz.is_finite() && e.f1_hz > 0.0) {
                fail(k, 1, e.f1_hz, pose.position_m, tm, f64::NAN, f64::NAN);
            }
            // The end-effector mode is unknown (NaN, age u32::MAX) when no mode reaches the
            // participation threshold (an avoided crossing splits it); a number is a mode at
            // or above f1 that reaches it.
            let ee_ok = if ee_hz(e).is_nan() {
                e.ee_mode.is_none()
            } else {
                ee_hz(e).is_finite()
                    && ee_hz(e) >= e.f1_hz * (1.0 - 1e-9)
                    && ee_p(e) >= scene.model.ee_participation_min
            };
            if !ee_ok {
                fail(k, 2, ee_hz(e), pose.position_m, tm, f64::NAN, f64::NAN);
            }
            if !e
                .stiffness
                .translational_n_m()
                .iter()
                .all(|x| x.is_finite())
            {
                fail(k, 3, f64::NAN, pose.position_m, tm, f64::NAN, f64::NAN);
            }
            let tol = 1e-9 * t_max;
            for &t in e.tensions() {
                if !(t.is_finite() && t >= tm - tol && t <= t_max + tol) {
                    fail(k, 4, t, pose.position_m, tm, f64::NAN, f64::NAN);
                }
            }
            if bad {
                fail(k, 5, 0.0, pose.position_m, tm, f64::NAN, f64::NAN); // an injected bad sample answered ok
            }
        } else if !(e.f1_hz.is_nan() && ee_hz(e).is_nan()) {
            fail(k, 6, e.f1_hz, pose.position_m, tm, f64::NAN, f64::NAN);
        }
        // Cold cross-check (not timed).
        if k % 101 == 0 {
            let e = *e;
            cold.reset();
            let c = cold.update(&pose, Tmin::Uniform(tm));
            cold_checks += 1;
            if c.status != e.status {
                fail(
                    k,
                    7,
                    c.status.as_u32() as f64,
                    pose.position_m,
                    tm,
                    f64::NAN,
                    f64::NAN,
                );
            } else if e.status == Status::Ok {
                let d1 = (c.f1_hz - e.f1_hz).abs() / c.f1_hz;
                // Both unknown (NaN) agree too.
                let de = if ee_hz(c).is_nan() && ee_hz(&e).is_nan() {
                    0.0
                } else {
                    (ee_hz(c) - ee_hz(&e)).abs() / ee_hz(c)
                };
                if !(d1 <= 1e-9) {
                    fail(k, 8, d1, pose.position_m, tm, e.f1_hz, c.f1_hz);
                }
                if !(de <= 1e-9) {
                    fail(k, 9, de, pose.position_m, tm, ee_hz(&e), ee_hz(c));
                }
            }
        }
    }
    let wall_s = wall.elapsed().as_secs_f64();
    let allocations = thread_allocations() - allocations_before;
    let allocated_bytes = thread_allocated_bytes() - bytes_before;
    let rss_after = rss_kb();

    let what = |c: u8| match c {
        1 => "ok estimate with non-finite or non-positive f1",
        2 => "ok estimate with bad end-effector mode",
        3 => "ok estimate with non-finite stiffness",
        4 => "ok estimate with a tension outside [T_min, T_max]",
        5 => "injected bad sample answered ok",
        6 => "non-ok estimate carrying a frequency",
        7 => "cold estimator gives another status (its code)",
        8 => "warm f1 differs from cold (relative)",
        9 => "warm end-effector mode differs from cold (relative)",
        _ => "?",
    };
    let failures = fails[..n_fails.min(fails.len())]
        .iter()
        .map(|&(k, c, x, p, tm, w, cv)| {
            format!(
                "cycle {k}: {} ({x:e}) at [{:.6}, {:.6}, {:.6}] m, t_min {tm} N; warm {w}, cold {cv}",
                what(c),
                p.x,
                p.y,
                p.z
            )
        })
        .chain((n_fails > fails.len()).then(|| format!("... {} failures in all", n_fails)))
        .collect();
    let solver_failures = solver_fail[..n_solver_fail.min(solver_fail.len())]
        .iter()
        .map(|(k, p, tm, e)| {
            format!(
                "cycle {k}: position [{:.6}, {:.6}, {:.6}] m, t_min {tm} N: {}",
                p.x,
                p.y,
                p.z,
                e.map(|e| e.to_string()).unwrap_or_default()
            )
        })
        .collect();
    latency_ok.truncate(n_ok);
    latency.sort_unstable();
    latency_ok.sort_unstable();
    Report {
        cycles,
        status,
        injected,
        cold_checks,
        allocations,
        allocated_bytes,
        rss_before_kb: rss_before,
        rss_after_kb: rss_after,
        latency_ns: [
            percentile(&latency, 0.5),
            percentile(&latency, 0.9),
            percentile(&latency, 0.99),
            percentile(&latency, 0.999),
            percentile(&latency, 0.9999),
            latency.last().copied().unwrap_or(0),
        ],
        latency_ok_ns: [
            percentile(&latency_ok, 0.5),
            percentile(&latency_ok, 0.99),
            latency_ok.last().copied().unwrap_or(0),
        ],
        wall_s,
        failures,
        solver_failures,
        slowest,
    }
}

/// Print the figures and return what is wrong (checked after every soak has run).
fn report(label: &str, r: &Report) -> Vec<String> {
    eprintln!(
        "soak {label}: {} cycles in {:.2} s ({} injected bad samples, {} cold cross-checks)",
        r.cycles, r.wall_s, r.injected, r.cold_checks
    );
    for (code, &n) in r.status.iter().enumerate() {
        if n > 0 {
            let name = cablevib::status::StatusCode::from_u32(code as u32)
                .map(|s| s.as_str())
                .unwrap_or("?");
            eprintln!(
                "  status {name:<20} {n:>9} ({:.2} %)",
                100.0 * n as f64 / r.cycles as f64
            );
        }
    }
    let us = |ns: u64| ns as f64 / 1e3;
    eprintln!(
        "  latency all cycles µs: p50 {:.1}  p90 {:.1}  p99 {:.1}  p99.9 {:.1}  p99.99 {:.1}  max {:.1}",
        us(r.latency_ns[0]),
        us(r.latency_ns[1]),
        us(r.latency_ns[2]),
        us(r.latency_ns[3]),
        us(r.latency_ns[4]),
        us(r.latency_ns[5])
    );
    eprintln!(
        "  latency ok cycles µs:  p50 {:.1}  p99 {:.1}  max {:.1}",
        us(r.latency_ok_ns[0]),
        us(r.latency_ok_ns[1]),
        us(r.latency_ok_ns[2])
    );
    let (ns, st, p, tm) = r.slowest;
    eprintln!(
        "  slowest cycle {:.1} µs: {st:?} at [{:.4}, {:.4}, {:.4}] m, t_min {tm} N",
        us(ns),
        p.x,
        p.y,
        p.z
    );
    for f in &r.solver_failures {
        eprintln!("  solver failure: {f}");
    }
    eprintln!(
        "  heap allocations in the loop: {} ({} bytes); RSS {} kB -> {} kB",
        r.allocations, r.allocated_bytes, r.rss_before_kb, r.rss_after_kb
    );
    let mut problems = Vec::new();
    if !r.failures.is_empty() {
        problems.push(format!(
            "soak {label}: {} failures:\n{}",
            r.failures.len(),
            r.failures.join("\n")
        ));
    }
    if r.allocations != 0 {
        problems.push(format!(
            "soak {label}: {} heap allocations in the loop",
            r.allocations
        ));
    }
    // No growth: no allocation means no heap growth, and the latency buffers were touched
    // before the loop; allow 256 kB of stack / allocator noise in the resident set.
    if r.rss_after_kb > r.rss_before_kb + 256 {
        problems.push(format!(
            "soak {label}: resident memory grew {} -> {} kB",
            r.rss_before_kb, r.rss_after_kb
        ));
    }
    let ok = r.status[Status::Ok.as_u32() as usize];
    if (ok as f64) < 0.2 * r.cycles as f64 || r.injected == 0 {
        problems.push(format!(
            "soak {label}: only {ok} ok cycles / {} injected: the walk does not exercise the estimator",
            r.injected
        ));
    }
    problems
}

#[test]
fn soak_short() {
    let s = Scene::default_scene();
    let mut problems = report("short spatial fem N=40", &soak(&s, 20_000, 0x50A6_0001));
    let c = s.with_model(ElementKind::Catenary, 10);
    problems.extend(report(
        "short spatial catenary N=10",
        &soak(&c, 20_000, 0x50A6_0002),
    ));
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
#[ignore = "long soak (10^6 cycles): cargo test --release --test soak -- --ignored --nocapture"]
fn soak_long_1m_cycles() {
    let s = Scene::default_scene();
    let mut problems = report("long spatial fem N=40", &soak(&s, 1_000_000, 0x50A6_1000));
    let c = s.with_model(ElementKind::Catenary, 40);
    problems.extend(report(
        "long spatial catenary N=40",
        &soak(&c, 200_000, 0x50A6_1001),
    ));
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
