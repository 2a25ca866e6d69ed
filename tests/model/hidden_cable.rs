//! The cable hidden between the winch and the pulley (`hidden_length`): an axial spring,
//! with its mass, in series with the free cable.
//!
//! References, built here from the scene's numbers only (not from the crate's chains):
//! - an independent dense FEM: the free cables as N straight FEM elements (3 DOF per node),
//!   each hidden cable as N axial elements from the drum (fixed) to the junction at the
//!   pulley (one axial DOF: the pulley holds it transversely). Frequencies against the
//!   structured engine to 1e-9 relative, certified on that matrix pair by the inertia of
//!   K − σM in 40-digit arithmetic at σ = λ(1 ± 1e-9) (tests/py/inertia_certificate.py,
//!   mpmath in a venv under target/): the dense f64 eigen-solve alone is only as accurate
//!   as ε·λ_max/λ (~5e-9 at N = 40);
//! - the closed-form series spring EA/(L_free + L_hidden) for the axial mode of one vertical
//!   massless cable;
//! - the static stiffness against the dense FEM's static condensation (1e-9) and a central
//!   finite difference of the cables' force law with the series spring (1e-6).
use cablevib::cable::{CableModel, HiddenAxial};
use cablevib::estimator::{Estimator, PoseModel, Tmin};
use cablevib::kinematics::Pose;
use cablevib::modal::{
    condense_static, dense_modes, dense_relative_accuracy, ModalParams, ModalSolver, Mode,
};
use cablevib::scene::{ElementKind, Scene, DEFAULT_SCENE_TOML};
use cablevib_testkit::dense_fem::{dense_with_hidden, FreeCable};
use cablevib_testkit::ee_hz;
use nalgebra::{DMatrix, Matrix3, Vector3};

/// The paper's spatial robot with 2.5 m of hidden cable behind every anchor (cable 3's
/// hidden cable twice as stiff and half as heavy: the material keys are read).
pub(crate) fn paper_with_hidden(element: &str, n: usize, hidden_m: f64) -> Scene {
    let text = DEFAULT_SCENE_TOML.replacen(
        "area = 50.265e-6",
        &format!("area = 50.265e-6\nhidden_length = {hidden_m:?}"),
        1,
    );
    let mut s = Scene::from_toml_str(&text, "hidden.toml").unwrap();
    if let Some(h) = s.cables[3].hidden.as_mut() {
        h.youngs_modulus_pa *= 2.0;
        h.mass_per_length_kg_m *= 0.5;
    }
    s.with_model(ElementKind::parse(element).unwrap(), n)
}

/// The independent dense FEM of a scene at a pose with given tensions: (K, M), DOF 0..3 the
/// end-effector. `n` FEM elements per free cable and per hidden cable.
fn dense_fem(scene: &Scene, p: &Vector3<f64>, t: &[f64], n: usize) -> (DMatrix<f64>, DMatrix<f64>) {
    dense_ref(scene, p, t, n, false)
}

/// As [`dense_fem`]; `catenary`: each free element's block is the paper's catenary element
/// (`catenary_block`, the element alone) and the junction moves along its stiffest
/// eigenvector (signed along the cable), the eigenvector found here by a dense solve.
/// Otherwise the FEM element (EA/l) e eᵀ + (T/l)(I − e eᵀ), the junction along e.
pub(crate) fn dense_ref(
    scene: &Scene,
    p: &Vector3<f64>,
    t: &[f64],
    n: usize,
    catenary: bool,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let frame = cablevib::cable::up_frame(&scene.gravity_m_s2);
    dense_with_hidden(scene, n, |ci, c| {
        let d = p - c.anchor_m;
        let len = d.norm();
        let e = d / len;
        let l = len / n as f64;
        let eet = e * e.transpose();
        let (kc, dir) = if catenary {
            let gamma = c.mass_per_length_kg_m * scene.gravity_m_s2.norm();
            let kc =
                cablevib::cable::catenary_block(&(e * l), t[ci], c.ea_n(), gamma, &frame).unwrap();
            let eig = kc.symmetric_eigen();
            let r = eig.eigenvalues.imax();
            let v: Vector3<f64> = eig.eigenvectors.column(r).into_owned();
            (kc, if v.dot(&e) < 0.0 { -v } else { v })
        } else {
            (
                eet * (c.ea_n() / l) + (Matrix3::identity() - eet) * (t[ci] / l),
                e,
            )
        };
        FreeCable {
            blocks: vec![kc; n],
            element_mass_kg: c.mass_per_length_kg_m * l,
            junction_dir: dir,
        }
    })
}

/// The structured engine's first `count` modes of a pose model.
pub(crate) fn structured_modes(pm: &PoseModel, count: usize) -> Vec<Mode> {
    let mut solver = ModalSolver::new(ModalParams::default());
    pm.load(&mut solver);
    let mut out = vec![Mode::default(); count];
    let got = solver.modes(count, &mut out).unwrap();
    out.truncate(got);
    out
}

/// FEM and the paper's catenary element (the junction along its axial eigenvector), each
/// with its hidden cables as explicit axial elements. N = 10 here; N = 40 in
/// [`slow::hidden_cable_frequencies_at_40_elements_equal_an_independent_dense_fem`].
#[test]
fn hidden_cable_frequencies_equal_an_independent_dense_fem() {
    hidden_cable_frequencies_equal_the_dense_fem(10);
}

/// The dense FEM at N = 40 (over 1000 DOF: a dense eigen-solve and a 40-digit inertia count
/// per pose, tens of seconds), run by `.ci/run` (tests/README.md, "Slow reference sweeps").
mod slow {
    #[test]
    #[ignore = "slow reference sweep: cargo test --release --tests -- --ignored slow::"]
    fn hidden_cable_frequencies_at_40_elements_equal_an_independent_dense_fem() {
        super::hidden_cable_frequencies_equal_the_dense_fem(40);
    }
}

/// [`hidden_cable_frequencies_equal_an_independent_dense_fem`] with `n` elements per cable.
fn hidden_cable_frequencies_equal_the_dense_fem(n: usize) {
    for element in ["fem", "catenary"] {
        let scene = paper_with_hidden(element, n, 2.5);
        for p in [Vector3::new(0.0, 0.0, 1.0), Vector3::new(0.3, 0.2, 1.0)] {
            let pm = PoseModel::at(&scene, &Pose::at(p), Tmin::Scene).unwrap();
            let (k, m) = dense_ref(&scene, &p, &pm.tensions_n, n, element == "catenary");
            let dense = dense_modes(&k, &m, scene.ee_mass_kg, false).unwrap();
            // The crate's own dense assembly of the loaded models is the same matrix pair.
            let (k2, m2) = pm.dense().unwrap();
            assert_eq!(k2.shape(), k.shape());
            assert!((&k2 - &k).norm() <= 1e-12 * k.norm());
            assert!((&m2 - &m).norm() <= 1e-12 * m.norm());
            let count = 12;
            let modes = structured_modes(&pm, count);
            assert_eq!(modes.len(), count);
            let mut worst = 0.0f64;
            for (j, mode) in modes.iter().enumerate() {
                let ld = dense.lambda[j];
                let tol = 1e-9f64.max(8.0 * dense_relative_accuracy(ld, dense.lambda_max));
                let err = (mode.lambda - ld).abs() / ld;
                assert!(
                    err <= tol,
                    "{element} N {n} {p:?} mode {j}: {} vs dense {ld}: {err:.2e} > {tol:.2e}",
                    mode.lambda
                );
                worst = worst.max(err);
            }
            eprintln!(
                "{element} N {n} at {p:?}: worst relative λ error over {count} modes {worst:.1e}"
            );
            // The certificate: the j-th eigenvalue of (K, M) lies in λ_j(1 ± CERT_REL).
            let sigmas: Vec<(f64, f64)> = modes
                .iter()
                .flat_map(|md| [(md.lambda, -CERT_REL), (md.lambda, CERT_REL)])
                .collect();
            let counts = certified_counts(&k, &m, 3, &sigmas);
            for (j, pair) in counts.chunks(2).enumerate() {
                assert!(
                    pair[0] <= j as u64 && pair[1] > j as u64,
                    "N {n} {p:?} mode {j}: λ {} not certified to {CERT_REL:e}: {} below \
                     λ(1 − r), {} below λ(1 + r)",
                    modes[j].lambda,
                    pair[0],
                    pair[1]
                );
            }
            eprintln!("N {n} at {p:?}: {count} modes certified to {CERT_REL:e} (40 digits)");
        }
    }
}

/// The relative half-width of the certificate's interval around each structured λ.
const CERT_REL: f64 = 1e-9;

/// Number of eigenvalues of the f64 matrix pair (K, M) below λ(1 + rel) for each (λ, rel),
/// from the inertia of K − σM in 40-digit arithmetic (Sylvester; tests/py/
/// inertia_certificate.py, mpmath 1.3.0 in a venv under target/). The elimination order:
/// every DOF but the end-effector's `dim` first, in their order (chain by chain: little
/// fill), the end-effector last.
fn certified_counts(
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    dim: usize,
    sigmas: &[(f64, f64)],
) -> Vec<u64> {
    let triplets = |a: &DMatrix<f64>| {
        let mut out = Vec::new();
        for j in 0..a.ncols() {
            for i in 0..=j {
                let v = a[(i, j)];
                if v != 0.0 {
                    out.push(serde_json::json!([i, j, format!("{v:?}")]));
                }
            }
        }
        out
    };
    let n = k.nrows();
    let order: Vec<usize> = (dim..n).chain(0..dim).collect();
    let input = serde_json::json!({
        "n": n,
        "order": order,
        "k": triplets(k),
        "m": triplets(m),
        "sigmas": sigmas.iter().map(|&(l, r)| [format!("{l:?}"), format!("{r:e}")]).collect::<Vec<_>>(),
    });
    let python = cablevib_testkit::pinned_venv::pinned_venv_python(
        "py-mpmath-1.3.0",
        &[("mpmath", "mpmath", "1.3.0")],
    );
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/py/inertia_certificate.py"
    );
    let mut child = std::process::Command::new(python)
        .arg(script)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("python");
    use std::io::Write;
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.to_string().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "inertia_certificate.py failed");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    v["negatives"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect()
}

#[test]
fn without_hidden_length_the_models_are_todays_bit_for_bit() {
    let with_zero = paper_with_hidden("fem", 10, 0.0);
    let plain = Scene::default_scene().with_model(ElementKind::Fem, 10);
    assert!(!with_zero.has_hidden_cable());
    let a = PoseModel::new(&with_zero).unwrap();
    let b = PoseModel::new(&plain).unwrap();
    assert_eq!(a.models, b.models);
    let mut ea = Estimator::new(&with_zero).unwrap();
    let mut eb = Estimator::new(&plain).unwrap();
    let pose = Pose::at(Vector3::new(0.3, 0.2, 1.0));
    let (x, y) = (
        *ea.update(&pose, Tmin::Scene),
        *eb.update(&pose, Tmin::Scene),
    );
    assert_eq!(x.f1_hz.to_bits(), y.f1_hz.to_bits());
    assert_eq!(ee_hz(&x).to_bits(), ee_hz(&y).to_bits());
}

/// One vertical massless cable of free length L under a point mass, with a massless hidden
/// cable of length L_h behind its anchor: the vertical mode is λ = EA/((L + L_h) m) exactly
/// (springs in series); the FEM element with a massless hidden cable and a nearly massless
/// free cable tends to it.
#[test]
fn massless_hidden_cable_is_the_series_spring() {
    let (ea, len, lh, t, mass) = (1.0e6, 1.8, 2.5, 400.0, 12.0);
    let e = Vector3::new(0.0, 0.0, -1.0); // anchor above, cable down to the mass
    let frame = Matrix3::identity();
    let hidden = HiddenAxial {
        length_m: lh,
        ea_n: ea,
        mu_kg_m: 0.0,
    };
    let exact = ea / ((len + lh) * mass);
    for (kind, mu, tol) in [
        (ElementKind::Massless, 0.0, 1e-13),
        (ElementKind::Fem, 1e-9, 1e-9),
        (ElementKind::Continuous, 1e-9, 1e-9),
    ] {
        let mut model = CableModel::build(kind, 10, &e, len, t, ea, mu, 0.0, &frame, true).unwrap();
        model.support_on_hidden(kind, &e, &hidden).unwrap();
        // The static stiffness along the cable: the series spring.
        let k_axial = (e.transpose() * model.static_stiffness * e)[(0, 0)];
        let k_series = ea / (len + lh);
        assert!(
            (k_axial - k_series).abs() <= 1e-13 * k_series,
            "{kind:?}: {k_axial} vs {k_series}"
        );
        let mut solver = ModalSolver::new(ModalParams::default());
        solver.load(&[model], mass);
        let mut out = [Mode::default(); 3];
        let got = solver.modes(3, &mut out).unwrap();
        // Two transverse modes T/(L m), then the axial one.
        let axial = out[..got]
            .iter()
            .map(|m| m.lambda)
            .min_by(|a, b| (a - exact).abs().total_cmp(&(b - exact).abs()))
            .unwrap();
        assert!(
            (axial - exact).abs() <= tol * exact,
            "{kind:?}: {axial} vs {exact}"
        );
    }
}

/// The estimator's static stiffness with hidden cables: against the independent dense FEM's
/// static condensation and a central difference of the force law F(p) = Σ T_i(p) e_i(p),
/// T_i(p) = T_i + EA/(L_i + L_h,i)·(|p − a_i| − L_i) (the series spring along each cable,
/// the tension's rotation across it).
#[test]
fn static_stiffness_is_the_series_spring() {
    let scene = paper_with_hidden("fem", 10, 2.5);
    let p = Vector3::new(0.3, 0.2, 1.0);
    let mut est = Estimator::new(&scene).unwrap();
    let e = *est.update(&Pose::at(p), Tmin::Scene);
    assert!(e.is_ok(), "{:?}", e.error);
    let kest = e.stiffness.translational_n_m();
    let t: Vec<f64> = e.tensions().to_vec();
    let (k, _) = dense_fem(&scene, &p, &t, 10);
    let kd = condense_static(&k, 3);
    let rel = (kest - Matrix3::from_fn(|r, c| kd[(r, c)])).norm() / kest.norm();
    assert!(rel <= 1e-9, "against the dense condensation: {rel:.2e}");
    let force = |q: &Vector3<f64>| -> Vector3<f64> {
        let mut f = Vector3::zeros();
        for (i, c) in scene.cables.iter().enumerate() {
            let l0 = (p - c.anchor_m).norm();
            let d = q - c.anchor_m;
            let h = c.hidden.unwrap();
            let flex = l0 / c.ea_n() + h.length_m / h.ea_n();
            let ti = t[i] + (d.norm() - l0) / flex;
            f += d / d.norm() * ti;
        }
        f
    };
    let h = 1e-6;
    let mut kfd = Matrix3::zeros();
    for j in 0..3 {
        let mut dp = Vector3::zeros();
        dp[j] = h;
        let col = (force(&(p + dp)) - force(&(p - dp))) / (2.0 * h);
        kfd.set_column(j, &col);
    }
    let rel = (kest - kfd).norm() / kest.norm();
    assert!(rel <= 1e-6, "against the finite difference: {rel:.2e}");
    // The hidden cable lowers the stiffness: without it, the same pose is stiffer.
    let mut plain =
        Estimator::new(&Scene::default_scene().with_model(ElementKind::Fem, 10)).unwrap();
    let e0 = *plain.update(&Pose::at(p), Tmin::Scene);
    assert!(
        e0.stiffness
            .translational_n_m()
            .symmetric_eigenvalues()
            .min()
            > kest.symmetric_eigenvalues().min()
    );
}

/// The continuous model with hidden cables is the FEM model's limit: f1 of FEM × 200
/// within its O(1/N²) error (~1e-4 here) of the continuous one, from above.
#[test]
fn continuous_hidden_cable_is_the_fem_limit() {
    let p = Pose::at(Vector3::new(0.3, 0.2, 1.0));
    let f1 = |element: &str, n: usize| {
        let mut est = Estimator::new(&paper_with_hidden(element, n, 2.5)).unwrap();
        let e = *est.update(&p, Tmin::Scene);
        assert!(e.is_ok(), "{element}: {:?}", e.error);
        (e.f1_hz, ee_hz(&e))
    };
    let (fc, eec) = f1("continuous", 1);
    let (ff, eef) = f1("fem", 200);
    assert!(
        ff >= fc && (ff - fc) / fc < 1e-4,
        "f1 fem {ff} continuous {fc}"
    );
    assert!(
        (eef - eec).abs() / eec < 1e-4,
        "ee fem {eef} continuous {eec}"
    );
}

/// The numbers of docs/hidden-cable.md (printed with --nocapture): the paper robot at its
/// default pose, fem × 10, every cable with a hidden cable of its own material and length
/// L_h (ratio r = L_h / mean free length), and
/// each number's change against r = 0. The hidden cable only lowers them.
#[test]
fn paper_robot_with_hidden_cables_table() {
    let p = Scene::default_scene().ee_position_m;
    let mean_free: f64 = Scene::default_scene()
        .cables
        .iter()
        .map(|c| (p - c.anchor_m).norm())
        .sum::<f64>()
        / 8.0;
    let run = |lh: f64| {
        let mut s = Scene::default_scene().with_model(ElementKind::Fem, 10);
        for c in &mut s.cables {
            c.hidden = (lh > 0.0).then_some(cablevib::scene::HiddenCable {
                length_m: lh,
                youngs_modulus_pa: c.youngs_modulus_pa,
                area_m2: c.area_m2,
                mass_per_length_kg_m: c.mass_per_length_kg_m,
            });
        }
        let mut est = Estimator::new(&s).unwrap();
        let e = *est.update(&Pose::at(p), Tmin::Scene);
        assert!(e.is_ok(), "{:?}", e.error);
        (
            e.stiffness
                .translational_n_m()
                .symmetric_eigenvalues()
                .min(),
            e.f1_hz,
            ee_hz(&e),
        )
    };
    let base = run(0.0);
    eprintln!(
        "pose {p:?} m, mean free length {mean_free:.4} m; base k_min {:.1} N/m f1 {:.3} Hz ee {:.3} Hz",
        base.0, base.1, base.2
    );
    // The document's pose and first row are this run's (it once named a pose the numbers
    // were not computed at): the pose as written, k_min to 1 N/m, the frequencies to 1 mHz.
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/hidden-cable.md"))
        .unwrap()
        .replace('\n', " ");
    let pose = format!("at its default pose ({}, {}, {}) m", p.x, p.y, p.z);
    assert!(doc.contains(&pose), "docs/hidden-cable.md lacks {pose:?}");
    let row = format!(
        "| 0 (today) | 0 | {} | {:.3} | {:.3} |",
        group_thousands(base.0.round() as u64),
        base.1,
        base.2
    );
    assert!(doc.contains(&row), "docs/hidden-cable.md lacks {row:?}");
    let mut last = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
    for lh in [0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5] {
        let r = run(lh);
        assert!(r.0 <= last.0 && r.0 < base.0);
        last = r;
        eprintln!(
            "L_h {lh} m (ratio {:.3}): k_min {:.1} ({:+.2} %), f1 {:.3} ({:+.2} %), ee {:.3} ({:+.2} %)",
            lh / mean_free,
            r.0,
            100.0 * (r.0 / base.0 - 1.0),
            r.1,
            100.0 * (r.1 / base.1 - 1.0),
            r.2,
            100.0 * (r.2 / base.2 - 1.0)
        );
    }
}

/// `n` with a space between groups of three digits, as the documents print them.
fn group_thousands(n: u64) -> String {
    let d = n.to_string();
    let mut out = String::new();
    for (i, c) in d.chars().enumerate() {
        if i > 0 && (d.len() - i).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(c);
    }
    out
}

/// The real-time cycle's cost with and without hidden cables on the paper robot, measured
/// side by side (interleaved, 20 000 cycles each along a circle; printed with --nocapture,
/// no timed assert).
#[test]
fn realtime_cycle_cost_with_and_without_hidden_cables() {
    for (el, n) in [(ElementKind::Fem, 40), (ElementKind::Continuous, 1)] {
        let plain = Scene::default_scene().with_model(el, n);
        let mut hidden = plain.clone();
        for c in &mut hidden.cables {
            c.hidden = Some(cablevib::scene::HiddenCable {
                length_m: 2.5,
                youngs_modulus_pa: c.youngs_modulus_pa,
                area_m2: c.area_m2,
                mass_per_length_kg_m: c.mass_per_length_kg_m,
            });
        }
        let mut ests = [
            Estimator::realtime(&plain).unwrap(),
            Estimator::realtime(&hidden).unwrap(),
        ];
        let mut times = [Vec::new(), Vec::new()];
        let cycles = 20_000;
        for k in 0..cycles {
            let a = 2.0 * std::f64::consts::PI * k as f64 / 4000.0;
            let pose = Pose::at(Vector3::new(0.3 * a.cos(), 0.3 * a.sin(), 1.0));
            for (est, t) in ests.iter_mut().zip(times.iter_mut()) {
                let t0 = std::time::Instant::now();
                let e = *est.update(&pose, Tmin::Scene);
                t.push(t0.elapsed().as_secs_f64() * 1e6);
                assert!(e.f1_hz.is_finite());
            }
        }
        for (name, t) in ["without", "with 2.5 m hidden"]
            .iter()
            .zip(times.iter_mut())
        {
            t.sort_by(f64::total_cmp);
            eprintln!(
                "{el:?} × {n} {name}: p50 {:.2} µs, p99 {:.2} µs",
                t[cycles / 2],
                t[cycles * 99 / 100]
            );
        }
    }
}
