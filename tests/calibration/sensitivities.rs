//! The analytic dλ/dp (mode shapes and element energies, `calibration::energy`) against
//! central differences of the structured model's eigenvalues, and the energies' sum against λ
//! (the Rayleigh quotient of the shapes).

use cablevib::calibration::data::MeasuredPose;
use cablevib::calibration::evaluate::{Evaluator, PoseTask, Rule};
use cablevib::calibration::{FitSpec, ParamKind};
use cablevib::estimator::{PoseModel, Tmin};
use cablevib::modal::{ModalParams, ModalSolver, Mode, ShapeParams};
use cablevib::scene::{ElementKind, Scene};
use nalgebra::Vector3;
use std::sync::atomic::AtomicUsize;

fn pose(x: f64, y: f64, z: f64) -> MeasuredPose {
    MeasuredPose {
        position_m: Vector3::new(x, y, z),
        orientation_wxyz: None,
        t_min_n: None,
    }
}

/// The picked eigenvalues (rad²/s²) of every rule at every pose, and their analytic
/// derivatives, at parameter values `x`.
fn eval(
    s: &Scene,
    spec: &FitSpec,
    tasks: &[PoseTask],
    x: &[f64],
    jac: bool,
) -> Vec<(f64, Vec<f64>)> {
    let hints: Vec<AtomicUsize> = tasks.iter().map(|_| AtomicUsize::new(0)).collect();
    let ev = Evaluator {
        base: s,
        spec,
        tasks,
        analytic: true,
        hints: &hints,
    };
    let (_, outs) = ev.eval(x, jac).expect("model at every pose");
    outs.iter()
        .flat_map(|o| {
            o.picked.iter().map(|p| {
                let p = p.as_ref().expect("rule resolves");
                (p.lambda, p.dlambda.clone())
            })
        })
        .collect()
}

/// The derivative of the picked eigenvalues with respect to parameter `k` at `x` by
/// central differences with Richardson extrapolation, (4 D(h/2) − D(h))/3 with D(h) =
/// (λ(x + h) − λ(x − h))/2h: error O(h⁴). At a lower bound (a hidden length of 0) the
/// second-order forward difference F(h) = (−3λ(x) + 4λ(x + h) − λ(x + 2h))/2h, extrapolated
/// the same way, (4 F(h/2) − F(h))/3: error O(h³).
fn difference(
    s: &Scene,
    spec: &FitSpec,
    tasks: &[PoseTask],
    x: &[f64],
    k: usize,
    h: f64,
) -> Vec<f64> {
    let at = |d: f64| {
        let mut y = x.to_vec();
        y[k] += d;
        eval(s, spec, tasks, &y, false)
            .into_iter()
            .map(|v| v.0)
            .collect::<Vec<f64>>()
    };
    let one_sided = x[k] - h < spec.params[k].lower;
    let level = |h: f64| -> Vec<f64> {
        if one_sided {
            let (f0, f1, f2) = (at(0.0), at(h), at(2.0 * h));
            (0..f0.len())
                .map(|i| (-3.0 * f0[i] + 4.0 * f1[i] - f2[i]) / (2.0 * h))
                .collect()
        } else {
            let (p, m) = (at(h), at(-h));
            (0..p.len()).map(|i| (p[i] - m[i]) / (2.0 * h)).collect()
        }
    };
    let (d1, d2) = (level(h), level(h / 2.0));
    (0..d1.len()).map(|i| (4.0 * d2[i] - d1[i]) / 3.0).collect()
}

/// Checks every parameter's analytic derivative against the extrapolated difference with
/// h = 1e-6 of the value's scale: the poses include end-effector modes next to avoided
/// crossings with string modes, where λ(p) bends within 1e-3 relative of p (a difference
/// over h = 1e-3 jumps to the other branch), so h is small and extrapolated (truncation
/// below 1e-9 relative there; rounding ~1e-16 λ / 1e-6 ≈ 1e-10 of the derivative).
/// Agreement to 1e-6 of the largest derivative of that parameter over the modes; a wrong or
/// missing term (a tension change, a hidden cable's mass, the consistent mass's share of the
/// anchor force) was off by 1e-5 or more.
fn check(s: &Scene, names: &[&str], x: &[f64], tasks: &[PoseTask]) {
    let spec = FitSpec::new(s, names).unwrap();
    assert_eq!(spec.params.len(), x.len());
    let base = eval(s, &spec, tasks, x, true);
    for (k, p) in spec.params.iter().enumerate() {
        let scale = match p.kind {
            ParamKind::HiddenLength(_) | ParamKind::EeCom(_) => 1.0,
            _ => x[k].abs(),
        };
        let fd = difference(s, &spec, tasks, x, k, 1e-6 * scale);
        let big = fd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (i, (_, d)) in base.iter().enumerate() {
            let err = (d[k] - fd[i]).abs();
            assert!(
                err <= 1e-6 * big,
                "{} ({}), mode {i}: analytic {:.9e}, difference {:.9e}",
                p.name,
                s.name,
                d[k],
                fd[i]
            );
        }
        println!(
            "{:<18} max |dλ/dp| {big:.4e}: analytic = difference within 1e-6",
            p.name
        );
    }
}

fn tasks(poses: &[MeasuredPose], rules: &[Rule]) -> Vec<PoseTask> {
    poses
        .iter()
        .map(|p| PoseTask::new(*p, rules.to_vec()))
        .collect()
}

/// The paper's spatial robot (fem × 10), two cables with hidden parts, at poses off its
/// symmetry: the end-effector modes and two string modes.
#[test]
fn point_mass_fem_sensitivities_match_differences() {
    let s = Scene::default_scene().with_model(ElementKind::Fem, 10);
    let names = [
        "ea_factor",
        "hidden_length.1",
        "hidden_length.2",
        "weight_per_length",
        "ee_mass",
    ];
    let mut x = vec![0.9, 1.1, 0.7, 1.2, 1.0, 0.8, 0.95, 1.05];
    x.extend([0.0, 1.5, 0.251, 32.0]);
    let t = tasks(
        &[pose(0.21, -0.13, 1.1), pose(-0.3, 0.25, 1.4)],
        &[
            Rule::Ee(1),
            Rule::Ee(2),
            Rule::Ee(3),
            Rule::Order(1),
            Rule::Order(4),
        ],
    );
    check(&s, &names, &x, &t);
}

/// The 6-DOF box robot: inertia, mass (with the rotational geometric stiffness's tension
/// term) and EA factors.
#[test]
fn rigid_body_sensitivities_match_differences() {
    let s = Scene::box_6dof();
    let names = [
        "ea_factor.1",
        "ea_factor.6",
        "ea_factor_all",
        "ee_mass",
        "ee_inertia",
        "hidden_length.3",
    ];
    let x = [0.8, 1.1, 0.9, 26.0, 0.5, 0.55, 0.7, 0.8];
    let mut p = pose(0.2, -0.1, 1.3);
    p.orientation_wxyz = Some([0.9950041652780258, 0.0, 0.09983341664682815, 0.0]);
    let t = tasks(&[p], &[Rule::Ee(1), Rule::Ee(2), Rule::Ee(4), Rule::Ee(6)]);
    check(&s, &names, &x, &t);
}

/// Swivel pulleys (the pulleys' stiffness term moves with the tensions) and the massless
/// element (the hidden cable as a series spring).
#[test]
fn pulley_and_massless_sensitivities_match_differences() {
    let dir = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/spatial_paper_pulleys.toml"
    );
    let s = Scene::load(dir).unwrap();
    let names = [
        "ea_factor.2",
        "hidden_length.2",
        "hidden_length.5",
        "ee_mass",
        "weight_per_length",
    ];
    let w = s.weight_per_length_n_m(0);
    let x = [1.2, 0.8, 0.0, 31.0, w];
    let t = tasks(
        &[pose(0.15, 0.2, 1.2)],
        &[Rule::Ee(1), Rule::Ee(2), Rule::Ee(3), Rule::Order(2)],
    );
    check(&s, &names, &x, &t);
    let m = Scene::default_scene().with_model(ElementKind::Massless, 1);
    let names = [
        "ea_factor.3",
        "hidden_length.3",
        "hidden_length.4",
        "ee_mass",
    ];
    let t = tasks(
        &[pose(-0.2, 0.1, 1.0)],
        &[Rule::Order(1), Rule::Order(2), Rule::Order(3)],
    );
    check(&m, &names, &[0.7, 1.0, 0.0, 28.0], &t);
}

/// Σ (axial + transverse + hidden energies) + φ_eeᵀK_eeφ_ee = λ for every shape: the shapes'
/// node displacements and the element formulas agree (1e-9 relative).
#[test]
fn energies_sum_to_lambda() {
    let mut s = Scene::default_scene().with_model(ElementKind::Fem, 12);
    s.cables[1].hidden = Some(cablevib::scene::HiddenCable {
        length_m: 1.2,
        youngs_modulus_pa: s.cables[1].youngs_modulus_pa,
        area_m2: s.cables[1].area_m2,
        mass_per_length_kg_m: s.cables[1].mass_per_length_kg_m,
    });
    for (scene, p) in [
        (
            s,
            cablevib::kinematics::Pose::at(Vector3::new(0.2, -0.1, 1.2)),
        ),
        (
            Scene::box_6dof(),
            cablevib::kinematics::Pose {
                position_m: Vector3::new(0.1, 0.2, 1.3),
                orientation_wxyz: [1.0, 0.0, 0.0, 0.0],
            },
        ),
    ] {
        let pm = PoseModel::at(&scene, &p, Tmin::Scene).unwrap();
        let mut solver = ModalSolver::new(ModalParams::default());
        pm.load(&mut solver);
        let mut modes = vec![Mode::default(); 40];
        let n = solver.modes(40, &mut modes).unwrap();
        let clusters: Vec<(f64, u32)> = modes[..n]
            .iter()
            .enumerate()
            .filter(|(i, m)| m.cluster_start == *i)
            .map(|(_, m)| (m.lambda, m.multiplicity))
            .collect();
        let shapes = solver
            .mode_shapes(
                &pm.models,
                &pm.geometry.arm_m,
                &clusters,
                &ShapeParams::default(),
            )
            .unwrap();
        for sh in &shapes.modes {
            let e = cablevib::calibration::energy::energies(&pm, sh).unwrap();
            assert!(
                e.rayleigh_defect().abs() <= 1e-9 * sh.lambda,
                "{}: λ {} defect {}",
                scene.name,
                sh.lambda,
                e.rayleigh_defect()
            );
        }
    }
}
