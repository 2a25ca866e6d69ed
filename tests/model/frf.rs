//! The end-effector receptance (modal::frf) against independent references: a dense complex
//! LU solve of the assembled (1 + iη)K − ω²M and (1 + iωβ)K − (ω² − iωα)M at each frequency
//! (fem and catenary, N = 10 and 40, point mass and rigid body); the continuous cable as the
//! fem's N → ∞ limit (1/N²); modal damping against the dense modal superposition of all modes.

use cablevib::estimator::PoseModel;
use cablevib::modal::{dense_receptance, lambda_to_hz, ModalParams, ModalSolver};
use cablevib::scene::{Damping, ElementKind, Scene};
use nalgebra::{DMatrix, Matrix6, SymmetricEigen};
use num_complex::Complex64;

fn pose(mut s: Scene, kind: ElementKind, n: usize) -> (PoseModel, ModalSolver) {
    s.model.element = kind;
    s.model.elements_per_cable = n;
    let p = PoseModel::new(&s).expect("pose");
    let mut solver = ModalSolver::new(ModalParams::default());
    p.load(&mut solver);
    (p, solver)
}

fn rel(a: &Matrix6<Complex64>, b: &Matrix6<Complex64>, dim: usize) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for i in 0..dim {
        for j in 0..dim {
            num += (a[(i, j)] - b[(i, j)]).norm_sqr();
            den += b[(i, j)].norm_sqr();
        }
    }
    (num / den).sqrt()
}

const DAMPINGS: [Damping; 2] = [
    Damping::LossFactor { eta: 0.02 },
    Damping::Rayleigh {
        alpha_per_s: 0.5,
        beta_s: 2e-4,
    },
];

/// Worst relative (Frobenius) difference structured vs dense over `freqs`, and at the
/// model's lowest natural frequencies (on resonance).
fn compare(p: &PoseModel, solver: &mut ModalSolver, freqs: &[f64]) -> (f64, f64) {
    let (k, m) = p.dense().expect("dense");
    let dim = p.dim();
    let mut modes = vec![cablevib::modal::Mode::default(); 4];
    let nm = solver.modes(4, &mut modes).unwrap();
    let (mut away, mut on) = (0.0f64, 0.0f64);
    for d in &DAMPINGS {
        for &f in freqs {
            let w = 2.0 * std::f64::consts::PI * f;
            let h = solver.receptance(d, w).unwrap();
            let r = dense_receptance(&k, &m, dim, d, w).unwrap();
            away = away.max(rel(&h, &r, dim));
        }
        for md in &modes[..nm] {
            let w = md.lambda.sqrt();
            let h = solver.receptance(d, w).unwrap();
            let r = dense_receptance(&k, &m, dim, d, w).unwrap();
            on = on.max(rel(&h, &r, dim));
        }
    }
    (away, on)
}

/// The frequencies of the dense comparisons, Hz.
fn compared_frequencies() -> Vec<f64> {
    (0..12).map(|i| 0.5 + 7.3 * i as f64).collect()
}

/// Loss factor and Rayleigh on the paper's spatial robot with `n` elements per cable (fem
/// and catenary) against the dense complex solve: [`damped_receptance_matches_the_dense_complex_solve`].
fn damped_spatial_matches_the_dense_complex_solve(n: usize) {
    for kind in [ElementKind::Fem, ElementKind::Catenary] {
        let (p, mut s) = pose(Scene::default_scene(), kind, n);
        let (away, on) = compare(&p, &mut s, &compared_frequencies());
        eprintln!("spatial {kind:?} N {n}: away {away:.2e}, on resonance {on:.2e}");
        assert!(away < 1e-9, "{kind:?} {n}: {away}");
        assert!(on < 1e-7, "{kind:?} {n}: {on}");
    }
}

/// Loss factor and Rayleigh are exact: structured = dense to 1e-9 relative away from the
/// resonances (measured ~1e-12), and to 1e-7 on them (the dense solve's conditioning
/// there grows as 1/η). N = 10 here; N = 40 (939 DOF, 64 dense complex LUs) in
/// [`slow::damped_receptance_at_40_elements_matches_the_dense_complex_solve`].
#[test]
fn damped_receptance_matches_the_dense_complex_solve() {
    let freqs = compared_frequencies();
    damped_spatial_matches_the_dense_complex_solve(10);
    // Rigid body (6 × 6, translations first).
    let (p, mut s) = pose(Scene::box_6dof(), ElementKind::Fem, 10);
    assert_eq!(p.dim(), 6);
    let (away, on) = compare(&p, &mut s, &freqs);
    eprintln!("box_6dof fem N 10: away {away:.2e}, on resonance {on:.2e}");
    assert!(away < 1e-9 && on < 1e-7, "{away} {on}");
}

/// The continuous cable's receptance is the fem's N → ∞ limit: the difference falls as 1/N²
/// (ratio 4 ± 5 % per doubling) at a damped frequency between the first modes.
#[test]
fn continuous_receptance_is_the_fem_limit() {
    let d = Damping::LossFactor { eta: 0.02 };
    let (pc, mut sc) = pose(Scene::default_scene(), ElementKind::Continuous, 1);
    let w = 2.0 * std::f64::consts::PI * 15.0;
    let hc = sc.receptance(&d, w).unwrap();
    let err = |n| {
        let (_, mut s) = pose(Scene::default_scene(), ElementKind::Fem, n);
        rel(&s.receptance(&d, w).unwrap(), &hc, pc.dim())
    };
    let e: Vec<f64> = [100, 200, 400].iter().map(|&n| err(n)).collect();
    eprintln!("continuous vs fem N 100/200/400: {e:?}");
    assert!(e[0] < 1e-3);
    for i in 0..2 {
        assert!((4.0 * e[i + 1] / e[i] - 1.0).abs() < 0.05, "{e:?}");
    }
}

/// Modal damping with every mode in the basis is the dense modal superposition
/// Σ φφᵀ/(λ_r − ω² + 2iζω_rω) over all modes of the assembled K, M (generalised symmetric
/// eigenproblem), to 2e-6 relative (measured 6e-7: the accuracy of the structured
/// end-effector shapes, null vectors of D at the roots, on the planar robot's clusters); with the modes below 4× the band and the static
/// correction, within the bound 2ζω/ω_r + ω²/λ_r of the first left-out mode.
#[test]
fn modal_damping_matches_the_dense_modal_superposition() {
    let zeta = 0.01;
    let (p, mut s) = pose(Scene::planar_paper(), ElementKind::Fem, 10);
    let (k, m) = p.dense().expect("dense");
    let dim = p.dim();
    let n = k.nrows();
    let l = m.clone().cholesky().unwrap().l();
    let c = l.solve_lower_triangular(&k).unwrap();
    let c = l.solve_lower_triangular(&c.transpose()).unwrap();
    let eig = SymmetricEigen::new((&c + c.transpose()) * 0.5);
    let phi: DMatrix<f64> = l
        .transpose()
        .solve_upper_triangular(&eig.eigenvectors)
        .unwrap();
    let dense = |w: f64| {
        let mut h = Matrix6::from_element(Complex64::new(0.0, 0.0));
        for r in 0..n {
            let lr = eig.eigenvalues[r];
            let den = Complex64::new(lr - w * w, 2.0 * zeta * lr.sqrt() * w);
            for i in 0..dim {
                for j in 0..dim {
                    h[(i, j)] += phi[(i, r)] * phi[(j, r)] / den;
                }
            }
        }
        h
    };
    let all = s.modal_basis(&p.models, &p.geometry.arm_m, 1e9, n).unwrap();
    assert_eq!(all.lambda.len(), n);
    let band_hz = 30.0;
    let cut = s
        .modal_basis(&p.models, &p.geometry.arm_m, 4.0 * band_hz, n)
        .unwrap();
    let first_out = lambda_to_hz(
        eig.eigenvalues
            .iter()
            .copied()
            .filter(|&x| lambda_to_hz(x) > 4.0 * band_hz)
            .fold(f64::INFINITY, f64::min),
    );
    let (mut e_all, mut e_cut, mut bound) = (0.0f64, 0.0f64, 0.0f64);
    for i in 1..=60 {
        let f = band_hz * i as f64 / 60.0;
        let w = 2.0 * std::f64::consts::PI * f;
        let r = dense(w);
        e_all = e_all.max(rel(&all.receptance(zeta, w), &r, dim));
        e_cut = e_cut.max(rel(&cut.receptance(zeta, w), &r, dim));
        bound = bound.max(2.0 * zeta * f / first_out + (f / first_out).powi(2));
    }
    eprintln!(
        "modal damping: all {} modes {e_all:.2e}; {} modes + static correction {e_cut:.2e} (bound {bound:.2e})",
        all.lambda.len(),
        cut.lambda.len()
    );
    assert!(e_all < 2e-6, "{e_all}");
    assert!(e_cut < bound, "{e_cut} vs {bound}");
}

/// With 2.5 m of cable hidden behind each anchor (the supported chain at a complex λ), and
/// with it behind swivel pulleys (the wrap arc in series too): structured = the dense complex
/// solve of the FEM assembled with the hidden cable's own nodes, to the same bounds as
/// without. N = 10 here; N = 40 in
/// [`slow::damped_receptance_with_a_hidden_cable_at_40_elements_matches_the_dense_complex_solve`].
#[test]
fn damped_receptance_with_a_hidden_cable_matches_the_dense_complex_solve() {
    hidden_cable_matches_the_dense_complex_solve(10);
}

/// [`damped_receptance_with_a_hidden_cable_matches_the_dense_complex_solve`] with `n`
/// elements per cable.
fn hidden_cable_matches_the_dense_complex_solve(n: usize) {
    let hide = |mut s: Scene| {
        for c in &mut s.cables {
            c.hidden = Some(cablevib::scene::HiddenCable {
                length_m: 2.5,
                youngs_modulus_pa: c.youngs_modulus_pa,
                area_m2: c.area_m2,
                mass_per_length_kg_m: c.mass_per_length_kg_m,
            });
        }
        s
    };
    let pulleys = Scene::from_path(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/spatial_paper_pulleys.toml"
    )))
    .expect("pulley scene");
    for (name, scene) in [
        ("spatial", hide(Scene::default_scene())),
        ("spatial with pulleys", hide(pulleys)),
    ] {
        let (p, mut s) = pose(scene, ElementKind::Fem, n);
        let (away, on) = compare(&p, &mut s, &compared_frequencies());
        eprintln!("{name} hidden N {n}: away {away:.2e}, on resonance {on:.2e}");
        assert!(away < 1e-9, "{name} {n}: {away}");
        assert!(on < 1e-7, "{name} {n}: {on}");
    }
}

/// The dense sweeps at N = 40 (939 DOF and more: a dense complex LU takes seconds), run by
/// `.ci/run` (tests/README.md, "Slow reference sweeps").
mod slow {
    #[test]
    #[ignore = "slow reference sweep: cargo test --release --tests -- --ignored slow::"]
    fn damped_receptance_at_40_elements_matches_the_dense_complex_solve() {
        super::damped_spatial_matches_the_dense_complex_solve(40);
    }

    #[test]
    #[ignore = "slow reference sweep: cargo test --release --tests -- --ignored slow::"]
    fn damped_receptance_with_a_hidden_cable_at_40_elements_matches_the_dense_complex_solve() {
        super::hidden_cable_matches_the_dense_complex_solve(40);
    }
}
