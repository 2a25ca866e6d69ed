//! The time response and input shaping against independent references: a dense Newmark
//! (average acceleration) integration of the whole assembled FEM at a frozen pose, and a
//! fine-step Runge-Kutta integration of a single mode whose frequency drifts.

use cablevib::estimator::{Estimator, Tmin};
use cablevib::kinematics::Pose;
use cablevib::modal::response::ModalResponse;
use cablevib::scene::{Damping, ElementKind, Scene};
use cablevib::study::simulate::SampledPath;
use cablevib::trajectory::moves::{Move, Profile};
use cablevib::trajectory::shaping::{OnlineShaper, ShaperKind};
use cablevib_testkit::exact_response::assert_update_policy_within_tolerance;
use nalgebra::{DMatrix, DVector, Vector3, Vector6};

/// Rayleigh mass-proportional damping α = 1.2 /s: ζ ≈ 1 % at the paper robot's ~10 Hz first
/// mode, smaller above (every mode underdamped); C = αM is explicit for the dense solve.
const ALPHA: f64 = 1.2;

/// The paper's spatial robot, fem × 10 (219 DOF), its default pose and a 0.5 m S-curve
/// along x in 0.5 s, then 0.5 s at rest, sampled at 1 ms.
fn setup() -> (Estimator, DMatrix<f64>, DMatrix<f64>, SampledPath, f64) {
    let mut s = Scene::default_scene().with_model(ElementKind::Fem, 10);
    s.damping = Damping::Rayleigh {
        alpha_per_s: ALPHA,
        beta_s: 0.0,
    };
    let mut est = Estimator::new(&s).unwrap();
    let pose = Pose::in_scene(&s, s.ee_position_m);
    assert!(est.update(&pose, Tmin::Scene).is_ok());
    let (k, m) = est.dense_matrices().unwrap();
    let mv = Move::new(
        s.ee_position_m,
        Vector3::new(0.5, 0.0, 0.0),
        0.5,
        Profile::SCurve,
    )
    .unwrap();
    let dt = 1e-3;
    let samples = mv.sampled(dt, 0.5).unwrap();
    let path = SampledPath {
        dt_s: dt,
        positions_m: samples.position_m,
        at_rest_ends: true,
    };
    let mass = s.ee_mass_kg;
    (est, k, m, path, mass)
}

/// −m·a at the samples (central differences, at rest beyond the ends), x only.
fn forces(path: &SampledPath, mass: f64) -> Vec<f64> {
    let p = &path.positions_m;
    let n = p.len();
    (0..n)
        .map(|k| {
            let prev = p[k.saturating_sub(1)];
            let next = p[(k + 1).min(n - 1)];
            -mass * (next.x - 2.0 * p[k].x + prev.x) / (path.dt_s * path.dt_s)
        })
        .collect()
}

/// Dense Newmark (average acceleration) of M ü + αM u̇ + K u = [f(t); 0], force linear
/// between the samples, `sub` steps per sample: the end-effector x at each sample.
fn newmark(k: &DMatrix<f64>, m: &DMatrix<f64>, f: &[f64], dt: f64, sub: usize) -> Vec<f64> {
    let n = k.nrows();
    let h = dt / sub as f64;
    let c = m * ALPHA;
    let keff = k + &c * (2.0 / h) + m * (4.0 / (h * h));
    let chol = keff.cholesky().unwrap();
    let mut u = DVector::zeros(n);
    let mut v = DVector::zeros(n);
    let mut a = DVector::zeros(n); // f(0) = 0: at rest
    let mut out = vec![0.0];
    for s in 1..f.len() {
        for j in 1..=sub {
            let w = j as f64 / sub as f64;
            let mut rhs = DVector::zeros(n);
            rhs[0] = f[s - 1] * (1.0 - w) + f[s] * w;
            rhs += m * (&u * (4.0 / (h * h)) + &v * (4.0 / h) + &a);
            rhs += &c * (&u * (2.0 / h) + &v);
            let un = chol.solve(&rhs);
            let vn = (&un - &u) * (2.0 / h) - &v;
            let an = (&un - &u) * (4.0 / (h * h)) - &v * (4.0 / h) - &a;
            u = un;
            v = vn;
            a = an;
        }
        out.push(u[0]);
    }
    out
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// The modal superposition of K modes with the static correction (the structured
/// engine's shapes at the frozen pose) against dense Newmark, dt → 0.
#[test]
fn modal_superposition_matches_dense_newmark_at_a_frozen_pose() {
    let (mut est, k, m, path, mass) = setup();
    let f = forces(&path, mass);
    // Newmark converges as dt²: three halvings, Richardson's extrapolation the reference.
    let runs: Vec<Vec<f64>> = [8usize, 16, 32]
        .iter()
        .map(|&sub| newmark(&k, &m, &f, path.dt_s, sub))
        .collect();
    let peak = runs[2].iter().fold(0.0f64, |p, x| p.max(x.abs()));
    let d1 = max_abs_diff(&runs[0], &runs[1]) / peak;
    let d2 = max_abs_diff(&runs[1], &runs[2]) / peak;
    println!(
        "Newmark: successive differences / peak {d1:.3e}, {d2:.3e} (ratio {:.2})",
        d1 / d2
    );
    assert!(
        (3.5..4.5).contains(&(d1 / d2)),
        "not second order: {d1:e} {d2:e}"
    );
    let reference: Vec<f64> = runs[1]
        .iter()
        .zip(&runs[2])
        .map(|(a, b)| b + (b - a) / 3.0)
        .collect();
    let ref_err = d2 / 3.0; // Richardson: the finest run's error, to leading order
    let damping = Damping::Rayleigh {
        alpha_per_s: ALPHA,
        beta_s: 0.0,
    };
    let mut last = f64::INFINITY;
    let mut errors = Vec::new();
    for kk in [6usize, 27, 36, 48, 64] {
        let b = est.ee_modal_basis(kk).unwrap();
        assert!(b.structured);
        let mut r = ModalResponse::new(3);
        r.set_basis(&b.lambda, &b.phi_ee, &damping, &b.flexibility, &b.ee_mass)
            .unwrap();
        let mut x = vec![0.0];
        for s in 1..f.len() {
            let f0 = Vector6::new(f[s - 1], 0.0, 0.0, 0.0, 0.0, 0.0);
            let f1 = Vector6::new(f[s], 0.0, 0.0, 0.0, 0.0, 0.0);
            r.step(&f0, &f1, path.dt_s);
            x.push(r.displacement(&f1)[0]);
        }
        let err = max_abs_diff(&x, &reference) / peak;
        println!(
            "K = {kk:>2} ({} modes): max |modal − Newmark| / peak = {err:.3e}",
            b.lambda.len()
        );
        errors.push((kk, err));
        assert!(err <= last * 1.01 + 1e-9, "error grew with K: {errors:?}");
        last = err;
    }
    // The reference's own error (Richardson estimate) is far below the bound.
    assert!(ref_err < 1e-5, "Newmark reference error {ref_err:e}");
    let (_, err48) = errors[3];
    assert!(err48 <= 1e-4, "K = 48: {err48:e} (> 1e-4 of the peak)");
}

/// RK4 of x'' + 2ζω(t)(x' − y') + ω(t)²(x − y) = 0 (a mode following a command y(t)),
/// `sub` steps per sample, y linear between samples: the deviation x − y after the end.
fn rk4_residual(y: &[f64], dt: f64, f_hz: impl Fn(f64) -> f64, zeta: f64, sub: usize) -> f64 {
    let h = dt / sub as f64;
    let (mut x, mut v) = (y[0], 0.0);
    let mut dev_hi = f64::NEG_INFINITY;
    let mut dev_lo = f64::INFINITY;
    let n = y.len();
    let end_cmd = y
        .iter()
        .rposition(|&q| (q - y[n - 1]).abs() > 1e-15)
        .unwrap_or(0)
        + 1;
    for s in 1..n {
        let yd = (y[s] - y[s - 1]) / dt;
        for j in 0..sub {
            let t0 = (s - 1) as f64 * dt + j as f64 * h;
            let yy = |t: f64| y[s - 1] + yd * (t - (s - 1) as f64 * dt);
            let acc = |t: f64, x: f64, v: f64| {
                let w = 2.0 * std::f64::consts::PI * f_hz(t);
                -2.0 * zeta * w * (v - yd) - w * w * (x - yy(t))
            };
            let k1 = (v, acc(t0, x, v));
            let k2 = (
                v + 0.5 * h * k1.1,
                acc(t0 + 0.5 * h, x + 0.5 * h * k1.0, v + 0.5 * h * k1.1),
            );
            let k3 = (
                v + 0.5 * h * k2.1,
                acc(t0 + 0.5 * h, x + 0.5 * h * k2.0, v + 0.5 * h * k2.1),
            );
            let k4 = (v + h * k3.1, acc(t0 + h, x + h * k3.0, v + h * k3.1));
            x += h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
            v += h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
        }
        if s >= end_cmd {
            dev_hi = dev_hi.max(x - y[n - 1]);
            dev_lo = dev_lo.min(x - y[n - 1]);
        }
    }
    dev_hi - dev_lo
}

/// A ZV shaper on a single mode: zero residual at its design frequency (to rounding, of
/// the fine-step integration), the closed-form residual cos(πr/2) at a frequency ratio r
/// (undamped); the time-varying shaper following a drifting frequency leaves far less
/// than one frozen at the start.
#[test]
fn zv_on_a_single_mode_against_fine_step_integration() {
    let dt = 1e-3;
    // A 0.1 s ramp of 1 m, then rest: unshaped residual, ZV at the design frequency, ZV
    // designed 20 % off.
    let n = 3000;
    let ramp: Vec<f64> = (0..n).map(|k| (k as f64 * dt / 0.1).min(1.0)).collect();
    let shape = |f_design: &dyn Fn(usize) -> f64, zeta: f64| -> Vec<f64> {
        let mut s = OnlineShaper::new(ShaperKind::Zv, dt, 0.5).unwrap();
        (0..n)
            .map(|k| s.push(Vector3::new(ramp[k], 0.0, 0.0), f_design(k), zeta).x)
            .collect()
    };
    let f0 = 4.0;
    let unshaped = rk4_residual(&ramp, dt, |_| f0, 0.0, 20);
    let at_design = rk4_residual(&shape(&|_| f0, 0.0), dt, |_| f0, 0.0, 20);
    println!("unshaped residual p-p {unshaped:.4e} m, ZV at design {at_design:.3e} m");
    assert!(unshaped > 0.1);
    // RK4 at h = 5e-5 s on a 4 Hz mode: truncation ~ (ωh)⁴ ~ 1e-8 relative.
    assert!(at_design < 1e-7 * unshaped, "ZV at design: {at_design:e}");
    // Off design by r = 1.2: residual fraction |cos(π·1.2/2)| of the unshaped.
    let off = rk4_residual(&shape(&|_| f0, 0.0), dt, |_| 1.2 * f0, 0.0, 20);
    let unshaped_off = rk4_residual(&ramp, dt, |_| 1.2 * f0, 0.0, 20);
    let want = (std::f64::consts::FRAC_PI_2 * 1.2).cos().abs();
    println!(
        "ZV off design r = 1.2: {:.4} of unshaped (closed form {want:.4})",
        off / unshaped_off
    );
    assert!(
        (off / unshaped_off - want).abs() < 2e-3,
        "{} vs {want}",
        off / unshaped_off
    );
    // A frequency drifting slowly (4 → 5 Hz over 3 s, ζ = 2 %): a staircase of ramps.
    let drift = |t: f64| 4.0 + t / 3.0;
    let stairs: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            (0..3)
                .map(|i| ((t - 0.9 * i as f64) / 0.1).clamp(0.0, 1.0))
                .sum::<f64>()
        })
        .collect();
    let zeta = 0.02;
    let run = |follow: bool| {
        let mut s = OnlineShaper::new(ShaperKind::Zv, dt, 0.5).unwrap();
        let y: Vec<f64> = (0..n)
            .map(|k| {
                let f = if follow {
                    drift(k as f64 * dt)
                } else {
                    drift(0.0)
                };
                s.push(Vector3::new(stairs[k], 0.0, 0.0), f, zeta).x
            })
            .collect();
        rk4_residual(&y, dt, drift, zeta, 20)
    };
    let unshaped = rk4_residual(&stairs, dt, drift, zeta, 20);
    let (following, frozen) = (run(true), run(false));
    println!("drifting mode: unshaped {unshaped:.3e}, ZV following {following:.3e}, ZV frozen at start {frozen:.3e}");
    assert!(following < 0.02 * unshaped, "{following:e} vs {unshaped:e}");
    assert!(
        following < 0.2 * frozen,
        "{following:e} vs frozen {frozen:e}"
    );
}

/// The paper robot (fem × 10, ζ = 2 %).
fn paper_scene() -> Scene {
    let mut scene = Scene::default_scene().with_model(ElementKind::Fem, 10);
    scene.damping = Damping::ModalRatio { zeta: 0.02 };
    scene
}

/// The paper robot ([`paper_scene`]) and its circle at 1 kHz for `duration_s`.
fn paper_circle(duration_s: f64) -> (Scene, SampledPath) {
    use cablevib::trajectory::{Trajectory, CIRCLE_PERIOD_S};
    let scene = paper_scene();
    let circle = Trajectory::circle(&scene, CIRCLE_PERIOD_S).unwrap();
    let path = SampledPath::from_trajectory(&circle, duration_s, 1e-3, false).unwrap();
    (scene, path)
}

/// The default basis-update policy against a run updating the modes at every sample, the
/// same K: within the default tolerance of that run's peak, on the paper robot's
/// off-centre S-curve (its frequencies change along it), with the number of updates it
/// made. The circle's first second (1 kHz: it starts at speed, so its modes ring) and the
/// whole 10 s circle are `slow::` (about 10 s and a minute of CPU).
#[test]
fn default_update_policy_is_within_the_tolerance_of_updating_every_sample() {
    let scene = paper_scene();
    let dt = 1e-3;
    let mv = Move::new(
        Vector3::new(0.3, 0.2, 1.0),
        Vector3::new(0.1, 0.2, -0.15),
        0.3,
        Profile::SCurve,
    )
    .unwrap();
    let s_curve = SampledPath {
        dt_s: dt,
        positions_m: mv.sampled(dt, 0.0).unwrap().position_m,
        at_rest_ends: true,
    };
    // measured 192 of 801, 4.5e-5 (before the planned intervals and the leak term: 203, 3.2e-5)
    assert_update_policy_within_tolerance("S-curve", &scene, &s_curve, 0.5, 0.5);
}

mod slow {
    use super::*;

    /// The default update policy on the circle's first second at 1 kHz against updates at
    /// every sample (1 001 bases).
    #[test]
    #[ignore = "slow reference sweep: the circle's first second updated at every sample"]
    fn default_update_policy_on_the_circles_first_second() {
        let (scene, circle) = paper_circle(1.0);
        // measured 500 of 1001, 3.3e-4 (the circle's first second rings from its start at speed:
        // mostly short intervals)
        assert_update_policy_within_tolerance("circle 1 s", &scene, &circle, 0.5, 0.75);
    }

    /// The default update policy on the paper's whole 10 s circle at 1 kHz against updates
    /// at every sample (10 001 bases: about a minute of CPU). Before K ended at a separated
    /// cut (`study::simulate::pilot`), K = 38 split the end-effector pair at 33.75 Hz, which
    /// is degenerate on the symmetry axes the circle crosses every second; each update
    /// there dropped the share of the kept mode turned into its partner: 1.76e-3 of the
    /// peak.
    #[test]
    #[ignore = "slow reference sweep: the whole circle updated at every sample"]
    fn default_update_policy_on_the_whole_circle() {
        let (scene, circle) = paper_circle(10.0);
        // measured 779 of 10 001, 3.9e-4 (before the planned intervals and the leak term:
        // 943, 4.9e-4)
        assert_update_policy_within_tolerance("circle 10 s", &scene, &circle, 0.5, 0.2);
    }
}
