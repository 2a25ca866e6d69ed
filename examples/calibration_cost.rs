//! What a calibration costs, and how the cost grows with poses and parameters:
//! `cargo run --release --example calibration_cost` (docs/calibration.md quotes its output).
//!
//! The 6-DOF box robot (`scenes/box_6dof.toml`, fem × 10, with a light rope): its six end-effector modes
//! measured at each pose (a rigid platform has six), with the cables' tensions; the "truth"
//! is the same model at other parameter values (this measures time, not accuracy: the
//! recovery against an independent dense FEM is `tests/calibration`). Each case is timed
//! `REPEATS` times; the median wall time is printed, with the iterations and model
//! evaluations of the fit. The machine may be shared: read ratios within one run.

use cablevib::calibration::data::{parse_modes, parse_tensions, MeasuredPose};
use cablevib::calibration::evaluate::{Evaluator, PoseTask, Rule};
use cablevib::calibration::{calibrate, CalibrationParams, FitSpec, SigmaDefaults};
use cablevib::kinematics::rotated_about;
use cablevib::modal::lambda_to_hz;
use cablevib::scene::Scene;
use nalgebra::Vector3;
use std::sync::atomic::AtomicUsize;
use std::time::Instant;

const REPEATS: usize = 3;

/// The parameters of the full case, in order: 16 of them (8 + 1 + 3 + 4).
const NAMES: [&str; 7] = [
    "ea_factor",
    "ee_mass",
    "ee_inertia",
    "hidden_length.1",
    "hidden_length.2",
    "hidden_length.3",
    "hidden_length.4",
];

/// CPU time of the process so far (every thread), s.
fn cpu_seconds() -> f64 {
    // SAFETY: getrusage writes the struct it is given; RUSAGE_SELF is valid.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) };
    let t = |v: libc::timeval| v.tv_sec as f64 + 1e-6 * v.tv_usec as f64;
    t(u.ru_utime) + t(u.ru_stime)
}

/// A fixed pseudo-random sequence in [0, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `count` poses of the box robot about its default pose (±0.3 m, ±0.05 rad) where the
/// model with the parameters `spec` at `truth` holds the platform.
fn poses(
    s: &Scene,
    spec: &FitSpec,
    truth: &[f64],
    count: usize,
    rng: &mut Lcg,
) -> Vec<MeasuredPose> {
    let mut out = Vec::new();
    while out.len() < count {
        let p = s.ee_position_m
            + Vector3::new(
                0.6 * rng.next() - 0.3,
                0.6 * rng.next() - 0.3,
                0.6 * rng.next() - 0.3,
            );
        let axis = Vector3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5);
        let pose = MeasuredPose {
            position_m: p,
            orientation_wxyz: Some(rotated_about(
                &s.ee_orientation_wxyz,
                &axis,
                0.1 * rng.next() - 0.05,
            )),
            t_min_n: None,
        };
        if model(s, spec, truth, &[pose]).is_some() {
            out.push(pose);
        }
    }
    out
}

/// The model at `poses`: its six end-effector modes and its tensions at each.
fn model(
    s: &Scene,
    spec: &FitSpec,
    x: &[f64],
    poses: &[MeasuredPose],
) -> Option<Vec<cablevib::calibration::evaluate::PoseOut>> {
    let tasks: Vec<PoseTask> = poses
        .iter()
        .map(|p| PoseTask {
            cables: (0..s.n_cables()).collect(),
            ..PoseTask::new(*p, (1..=6).map(Rule::Ee).collect())
        })
        .collect();
    let hints: Vec<AtomicUsize> = tasks.iter().map(|_| AtomicUsize::new(0)).collect();
    let ev = Evaluator {
        base: s,
        spec,
        tasks: &tasks,
        analytic: true,
        hints: &hints,
    };
    let (_, outs) = ev.eval(x, false).ok()?;
    outs.iter()
        .all(|o| o.picked.iter().all(Option::is_some))
        .then_some(outs)
}

/// The modes and tensions CSVs of the model `s` with the parameters `spec` at `truth`.
fn data(s: &Scene, spec: &FitSpec, truth: &[f64], poses: &[MeasuredPose]) -> (String, String) {
    let outs = model(s, spec, truth, poses).expect("the truth at every pose");
    let mut modes = String::from("x_m,y_m,z_m,qw,qx,qy,qz,frequency_hz,sigma_hz,mode\n");
    let mut tensions = String::from("x_m,y_m,z_m,qw,qx,qy,qz,cable,tension_n,sigma_n\n");
    for (p, o) in poses.iter().zip(&outs) {
        let q = p.orientation_wxyz.unwrap();
        let at = format!(
            "{:?},{:?},{:?},{:?},{:?},{:?},{:?}",
            p.position_m.x, p.position_m.y, p.position_m.z, q[0], q[1], q[2], q[3]
        );
        let mut seen = Vec::new();
        for (k, m) in o.picked.iter().enumerate() {
            let m = m.as_ref().expect("six end-effector modes");
            if seen.contains(&m.order) {
                continue; // one row per cluster
            }
            seen.push(m.order);
            let f = lambda_to_hz(m.lambda);
            modes.push_str(&format!("{at},{f:?},{:?},ee{}\n", 0.003 * f, k + 1));
        }
        for (c, t) in o.tensions_n.iter().enumerate() {
            tensions.push_str(&format!("{at},{},{t:?},{:?}\n", c + 1, 0.01 * t));
        }
    }
    (modes, tensions)
}

/// Median wall seconds, CPU seconds, iterations and evaluations of fitting `names` over
/// `n_poses` poses, with the numbers of modes and parameters.
fn case(s: &Scene, names: &[&str], n_poses: usize) -> (f64, f64, u32, u32, usize, usize) {
    let mut rng = Lcg(42);
    let spec = FitSpec::new(s, names).expect("parameters");
    let truth: Vec<f64> = spec
        .params
        .iter()
        .map(|p| {
            if p.nominal != 0.0 {
                p.nominal * (0.85 + 0.3 * rng.next())
            } else {
                0.5 + rng.next()
            }
        })
        .collect();
    let poses = poses(s, &spec, &truth, n_poses, &mut rng);
    let (m, t) = data(s, &spec, &truth, &poses);
    let sd = SigmaDefaults::default();
    let mut d = parse_modes(&m, "modes.csv", &sd).expect("modes");
    parse_tensions(&t, "tensions.csv", s.n_cables(), &sd, &mut d).expect("tensions");
    let mut runs: Vec<(f64, f64, u32, u32)> = (0..REPEATS)
        .map(|_| {
            let (t0, c0) = (Instant::now(), cpu_seconds());
            let c = calibrate(s, &d, &spec, &CalibrationParams::default()).expect("fit");
            assert!(c.report.fits, "{}", c.report.verdict);
            let (w, cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
            (w, cpu, c.report.iterations, c.report.evaluations)
        })
        .collect();
    runs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (secs, cpu, it, ev) = runs[REPEATS / 2];
    (secs, cpu, it, ev, d.modes.len(), spec.params.len())
}

fn main() {
    // A synthetic-fibre rope 100 times lighter than the scene's steel (the same EA): its
    // string modes start near 60 Hz, above the platform's six modes, which then stay clean
    // end-effector modes (with the steel rope they hybridise with the string modes).
    let mut s = Scene::box_6dof();
    for c in &mut s.cables {
        c.mass_per_length_kg_m /= 100.0;
    }
    println!(
        "box-6dof (fem × {}), six end-effector modes per pose, tensions of 8 cables; median of {REPEATS} (threads: {})",
        s.model.elements_per_cable,
        rayon::current_num_threads()
    );
    println!("\n| poses | modes | parameters | wall time (s) | CPU time (s) | iterations | model evaluations | CPU per evaluation (ms) |");
    println!("|---|---|---|---|---|---|---|---|");
    let row = |poses: usize, names: &[&str]| {
        let (secs, cpu, it, ev, modes, params) = case(&s, names, poses);
        println!(
            "| {poses} | {modes} | {params} | {secs:.3} | {cpu:.3} | {it} | {ev} | {:.1} |",
            1e3 * cpu / ev.max(1) as f64
        );
    };
    for poses in [5, 10, 20, 40, 80] {
        row(poses, &NAMES);
    }
    for names in [
        &["ee_mass"][..],
        &["ee_mass", "ee_inertia"],
        &["ea_factor"],
        &["ea_factor", "ee_mass", "ee_inertia"],
    ] {
        row(20, names);
    }
}
