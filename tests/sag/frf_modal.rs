//! Modal damping with sag: the receptance by modal superposition of the sagged structured
//! shapes with the residual flexibility ([`cablevib::modal::ModalBasis::from_modes`] on the
//! estimator's basis, `Estimator::ee_modal_basis`) against a dense modal reference: every
//! eigenpair of the independently assembled sagged K and M (Cholesky reduction and a
//! symmetric eigensolver written here), H(ω) = Σ_all φ_r φ_rᵀ/(λ_r − ω² + 2iζω_rω), on
//! suspended-8 with sag (FEM, N = 10), ζ = 1 %.
//!
//! Tolerance: the basis takes the modes it leaves out (r > K) quasi-statically and
//! undamped, a relative error of about ω²/λ_r + 2ζω/ω_r for each, at most
//! ω²/λ_{K+1} + 2ζω/ω_{K+1} of their share; bounded here by 2·(ω²/λ_{K+1} +
//! 2ζω/ω_{K+1})·‖H‖ + 1e-8·‖H‖ (the dense eigenvectors' rounding), Frobenius, at frequencies
//! kept 2 % from every natural frequency.

use cablevib::estimator::{Estimator, Tmin};
use cablevib::kinematics::Pose;
use cablevib::modal::ModalBasis;
use cablevib::scene::{ElementKind, Scene};
use nalgebra::{DMatrix, Matrix6};
use num_complex::Complex64;

fn dense_eig(k: &DMatrix<f64>, m: &DMatrix<f64>) -> (Vec<f64>, DMatrix<f64>) {
    let l = m.clone().cholesky().expect("M positive definite").l();
    let a = l.solve_lower_triangular(k).unwrap();
    let c = l.solve_lower_triangular(&a.transpose()).unwrap();
    let c = (&c + c.transpose()) * 0.5;
    let e = nalgebra::SymmetricEigen::new(c);
    let u = l
        .transpose()
        .solve_upper_triangular(&e.eigenvectors)
        .unwrap();
    let mut idx: Vec<usize> = (0..e.eigenvalues.len()).collect();
    idx.sort_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j]));
    let lam = idx.iter().map(|&i| e.eigenvalues[i]).collect();
    let mut v = DMatrix::zeros(u.nrows(), idx.len());
    for (c, &i) in idx.iter().enumerate() {
        v.set_column(c, &u.column(i));
    }
    (lam, v)
}

#[test]
fn sagged_modal_damping_equals_dense_modal_superposition() {
    let mut scene = Scene::load("scenes/suspended_8.toml").unwrap();
    scene.model.sag = true;
    scene.model.element = ElementKind::Fem;
    scene.model.elements_per_cable = 10;
    let mut est = Estimator::new(&scene).unwrap();
    let pose = Pose::in_scene(
        &scene,
        scene.ee_position_m + nalgebra::Vector3::new(0.2, 0.1, 0.0),
    );
    let e = *est.update(&pose, Tmin::Scene);
    assert!(e.status.is_ok(), "{:?}", e.error);
    let zeta = 0.01;
    let k_modes = 40;
    let b = est.ee_modal_basis(k_modes).unwrap();
    assert!(b.structured);
    let dim = b.dim;
    let kk = b.lambda.len();
    let basis =
        ModalBasis::from_modes(b.lambda.clone(), b.phi_ee.clone(), &b.flexibility, dim).unwrap();
    let (k, m) = est.dense_matrices().unwrap();
    let (dl, dv) = dense_eig(&k, &m);
    let next = dl[kk];
    let mut worst = 0.0f64;
    let top_hz = 0.5 * dl[kk - 1].sqrt() / (2.0 * std::f64::consts::PI);
    for i in 1..=400 {
        let f = top_hz * i as f64 / 400.0;
        let w = 2.0 * std::f64::consts::PI * f;
        if dl.iter().any(|&l| ((w * w) / l - 1.0).abs() < 0.02) {
            continue;
        }
        let mut h = Matrix6::<Complex64>::from_element(Complex64::new(0.0, 0.0));
        for (r, &l) in dl.iter().enumerate() {
            let wr = l.sqrt();
            let den = Complex64::new(l - w * w, 2.0 * zeta * wr * w);
            for a in 0..dim {
                for c in 0..dim {
                    h[(a, c)] += Complex64::new(dv[(a, r)] * dv[(c, r)], 0.0) / den;
                }
            }
        }
        let got = basis.receptance(zeta, w);
        let (mut num, mut den) = (0.0f64, 0.0f64);
        for a in 0..dim {
            for c in 0..dim {
                num += (got[(a, c)] - h[(a, c)]).norm_sqr();
                den += h[(a, c)].norm_sqr();
            }
        }
        let err = (num / den).sqrt();
        let tol = 2.0 * (w * w / next + 2.0 * zeta * w / next.sqrt()) + 1e-8;
        assert!(err < tol, "{f:.3} Hz: {err:.2e} (tol {tol:.2e})");
        worst = worst.max(err / tol);
    }
    eprintln!("sagged modal damping vs dense: {kk} modes, worst error {worst:.2e} of the bound");
}

/// The frequency-response study with modal damping on a mesh whose every mode lies below the
/// basis's cut-off (suspended-8, FEM N = 6: 123 modes, all below 4 × 20 Hz): the basis then
/// holds every mode, and the response is the dense summation over every mode of the
/// assembled sagged (K, M) (the study's own dense check, `DenseCheckKind::Modal`), to the
/// structured shapes' accuracy: 1e-6 relative (Frobenius, every frequency of the band; the
/// residual flexibility of an empty remainder is rounding). It asked the sagged solver for
/// more modes than the model has ("no finite bound holds k eigenvalues") before.
#[test]
fn modal_damping_with_every_mode_in_the_basis_is_the_dense_summation() {
    use cablevib::study::frf::{frf, DampingChoice, DenseCheckKind, FrfConfig};
    let mut s = Scene::load("suspended-8").unwrap();
    s.model.element = ElementKind::Fem;
    s.model.elements_per_cable = 6;
    let cfg = FrfConfig {
        to_hz: 20.0,
        points: 40,
        damping: DampingChoice {
            modal_ratio: Some(0.02),
            ..DampingChoice::default()
        },
        dense: Some(DenseCheckKind::Modal { lu_points: 0 }),
        ..FrfConfig::default()
    };
    let r = frf(&s, &cfg).expect("modal damping with sag answers");
    let d = r.dense.expect("dense check");
    assert_eq!(d.dof, 123);
    eprintln!("suspended-8 N 6, every mode: {:.2e}", d.max_rel_diff);
    assert!(d.max_rel_diff <= 1e-6, "{:.2e}", d.max_rel_diff);
}
