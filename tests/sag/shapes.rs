//! The sagged mode shapes of the structured engine
//! ([`cablevib::modal::SagModalSolver::mode_shapes`]: each chain's interior
//! solutions by forward substitution, the bordered system's null space, the consistent
//! mass's quadratic form) against the dense eigenvectors of the independently assembled
//! sagged K and M ([`cablevib::modal::sagged::assemble_sagged`]: world-frame element
//! matrices, sharing only the element data; a Cholesky reduction and a symmetric
//! eigensolver written here), at N = 10 and 40, point mass and rigid body, light and heavy
//! sag; and the estimator's modal basis on `suspended_8` with sag against the same dense
//! solve.
//!
//! Checked per mode: the mass normalisation uᵀMu = 1 with the dense M (1e-9: the element
//! sums and the assembly differ only in rounding, ~N·ε, and the cluster's Gram inverse
//! square root); the residual ‖(K − λM)u‖/(‖K‖·‖u‖) (1e-10: the forward substitution's
//! rounding, which grows at most linearly along a chain below its cut-off, and λ's own
//! ~1e-12); the eigenspace against the dense eigenvectors: the part of each dense vector
//! of the cluster outside the structured span, M-norm, ≤ 64·ε·λ_max/gap + 1e-9 (the dense
//! solver's eigenvector error is ε·‖K‖/gap in the M-norm, λ_max its scale; 64 the same
//! unknown constant as in `fem_dense.rs`; gap the relative distance to the nearest other
//! eigenvalue); the end-effector participation against the dense vector's (1e-8).
//! Measured worst values are printed (`--nocapture`).

use cablevib::cable::sagged::SagSupport;
use cablevib::cable::Segment;
use cablevib::estimator::{Estimator, Tmin};
use cablevib::kinematics::Pose;
use cablevib::modal::sagged::{SagCableFrame, SagEndEffector};
use cablevib::modal::SagModalSolver;
use cablevib::modal::{ModalParams, ModeShapes, ShapeParams};
use cablevib::scene::{ElementKind, Scene};
use cablevib_testkit::dense_fem::dense_eig;
use cablevib_testkit::sag_cases::{sagged_fem, shipped};
use cablevib_testkit::sag_robot::*;
use nalgebra::{DMatrix, DVector, Matrix6, Vector3};

/// Mass normalisation (module docs).
const MASS_TOL: f64 = 1e-9;
/// Relative residual of K u = λ M u (module docs).
const RESIDUAL_TOL: f64 = 1e-10;
/// Factor on the dense eigenvector bound ε·λ_max/gap (module docs).
const DENSE_FACTOR: f64 = 64.0;
/// Floor of the subspace comparison.
const SUBSPACE_FLOOR: f64 = 1e-9;
/// Participation against the dense vector's.
const PART_TOL: f64 = 1e-8;

/// A cable's hidden cable in the dense DOF order: its element count N_h and the world
/// direction d of its junction's motion.
type Hidden = Option<(usize, Vector3<f64>)>;

/// A structured shape in the dense DOF order: the end-effector's `dim`, then each cable's
/// interior nodes (world frame), then on a hidden cable (`hidden[c]`, none when `hidden`
/// is empty) its interior axial nodes and the junction's displacement along d (node 0's
/// component along d; node 0 is checked to move along d only). The shapes do not draw the
/// hidden cable's interior nodes: they are filled here from the junction's value by the
/// dense model's own rows of those nodes, (K − λM)_hh u_h = −(K − λM)_h,rest u_rest (the
/// hidden cable's drum-fixed solution; its rows' residual is then zero by construction,
/// every other row is checked).
fn dense_order(
    shapes: &ModeShapes,
    i: usize,
    hidden: &[Hidden],
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
) -> DVector<f64> {
    let s = &shapes.modes[i];
    let mut out = Vec::new();
    let mut filled = Vec::new();
    out.extend((0..shapes.dim).map(|r| s.ee[r]));
    for (c, cable) in s.cables.iter().enumerate() {
        for node in &cable[1..cable.len() - 1] {
            out.extend(node.iter().copied());
        }
        if let Some((nh, d)) = hidden.get(c).copied().flatten() {
            let w = cable[0].dot(&d);
            let off = (cable[0] - d * w).norm();
            let scale = cable.iter().fold(0.0f64, |a, x| a.max(x.amax()));
            assert!(
                off <= 1e-12 * scale,
                "cable {c}: node 0 leaves d by {off:.2e}"
            );
            filled.extend(out.len()..out.len() + nh - 1);
            out.extend(std::iter::repeat_n(0.0, nh - 1));
            out.push(w);
        }
    }
    let mut u = DVector::from_vec(out);
    if !filled.is_empty() {
        let z = k - m * s.lambda;
        let rest: Vec<usize> = (0..u.len()).filter(|r| !filled.contains(r)).collect();
        let zhh = z.select_rows(&filled).select_columns(&filled);
        let zhr = z.select_rows(&filled).select_columns(&rest);
        let ur = u.select_rows(&rest);
        let uh = zhh.lu().solve(&(-(zhr * ur))).expect("hidden rows regular");
        for (q, &r) in filled.iter().enumerate() {
            u[r] = uh[q];
        }
    }
    u
}

/// Worst values of one comparison.
#[derive(Default, Debug)]
struct Worst {
    mass: f64,
    residual: f64,
    subspace: f64,
    part: f64,
}

/// Compare the structured shapes of the lowest `k` modes with the dense eigenvectors.
fn compare(
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    shapes: &ModeShapes,
    m_ee: &Matrix6<f64>,
    hidden: &[Hidden],
    what: &str,
) -> Worst {
    let (dl, dv) = dense_eig(k, m);
    let lmax = dl.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    let knorm = k.norm();
    let dim = shapes.dim;
    let mut w = Worst::default();
    let mut i = 0;
    while i < shapes.modes.len() {
        let mult = shapes.modes[i].multiplicity as usize;
        let lambda = shapes.modes[i].lambda;
        let us: Vec<DVector<f64>> = (i..i + mult)
            .map(|j| dense_order(shapes, j, hidden, k, m))
            .collect();
        for (q, u) in us.iter().enumerate() {
            assert_eq!(u.len(), k.nrows(), "{what}: DOF");
            let mass = (u.transpose() * m * u)[(0, 0)];
            let res = (k * u - m * u * lambda).norm() / (knorm * u.norm());
            assert!(
                (mass - 1.0).abs() < MASS_TOL,
                "{what} mode {}: uᵀMu = {mass}",
                i + q
            );
            assert!(
                res < RESIDUAL_TOL,
                "{what} mode {}: residual {res:.2e}",
                i + q
            );
            w.mass = w.mass.max((mass - 1.0).abs());
            w.residual = w.residual.max(res);
        }
        // The dense cluster: modes i .. i + mult; its gap to the neighbours.
        assert!(
            (dl[i] - lambda).abs() < (DENSE_FACTOR * f64::EPSILON * lmax / lambda + 1e-12) * lambda,
            "{what}: λ {lambda} vs dense {}",
            dl[i]
        );
        let mut gap = f64::INFINITY;
        if i > 0 {
            gap = gap.min((lambda - dl[i - 1]) / lambda);
        }
        if i + mult < dl.len() {
            gap = gap.min((dl[i + mult] - lambda) / lambda);
        }
        let tol = DENSE_FACTOR * f64::EPSILON * lmax / lambda / gap + SUBSPACE_FLOOR;
        for q in 0..mult {
            let d = dv.column(i + q).into_owned();
            // M-orthogonal projection onto the structured span (the us are M-orthonormal).
            let mut r = d.clone();
            for u in &us {
                let c = (u.transpose() * m * &d)[(0, 0)];
                r -= u * c;
            }
            let out = (r.transpose() * m * &r)[(0, 0)].max(0.0).sqrt();
            assert!(
                out < tol,
                "{what} mode {}: dense vector {out:.2e} outside the structured span (tol {tol:.2e})",
                i + q
            );
            w.subspace = w.subspace.max(out);
        }
        if mult == 1 {
            let d = dv.column(i);
            let mut p = 0.0;
            for r in 0..dim {
                for c in 0..dim {
                    p += d[r] * m_ee[(r, c)] * d[c];
                }
            }
            let e = (p - shapes.modes[i].ee_participation).abs();
            assert!(e < PART_TOL, "{what} mode {i}: participation {e:.2e}");
            w.part = w.part.max(e);
        }
        i += mult;
    }
    w
}

/// N = 10 here, 40 in [`slow`].
#[test]
fn sagged_shapes_equal_dense_eigenvectors() {
    sagged_shapes_equal_dense_eigenvectors_at(&[10]);
}

fn sagged_shapes_equal_dense_eigenvectors_at(sizes: &[usize]) {
    let mut worst = Worst::default();
    for heavy in [false, true] {
        let cables = robot(8, 0.6, 2.0e5, heavy);
        for ee in [point(), rigid()] {
            for &n_el in sizes {
                let mut s = solver_for(&cables, n_el, &ee);
                let clusters = s.eigen_clusters(12, &ShapeParams::default()).unwrap();
                let h: Vec<_> = cables.iter().map(|c| c.h).collect();
                let arms: Vec<_> = cables.iter().map(|c| c.arm_m).collect();
                let shapes = s
                    .mode_shapes(&h, &up(), &arms, &clusters, &ShapeParams::default())
                    .unwrap();
                assert!(shapes.modes.len() >= 12);
                let (k, m) = dense_matrices(&s, &cables);
                let what = format!(
                    "heavy {heavy} {} N {n_el}",
                    if matches!(ee, SagEndEffector::Point { .. }) {
                        "point"
                    } else {
                        "rigid"
                    }
                );
                let w = compare(&k, &m, &shapes, &s.ee_matrices().0, &[], &what);
                worst.mass = worst.mass.max(w.mass);
                worst.residual = worst.residual.max(w.residual);
                worst.subspace = worst.subspace.max(w.subspace);
                worst.part = worst.part.max(w.part);
            }
        }
    }
    eprintln!("sagged shapes vs dense: {worst:?}");
}

/// Hidden cable behind every anchor (m): the paper robot's winches on the floor.
const HIDDEN_M: f64 = 2.5;

/// The sagged shapes on hidden cables ([`SagChain::set_support`]: the junction at the
/// pulley moving along the catenary's tangent at the anchor, held by N consistent-mass
/// axial elements of 2.5 m of the same cable) against the dense eigenvectors of
/// [`assemble_sagged`] with the hidden cables' nodes explicit (module docs' checks and
/// tolerances, with the whole vector: the junction and the hidden nodes included in uᵀMu),
/// N = 1, 2 (one element from the junction to the end, or one interior node), 10 and 40, point
/// mass and rigid body, light and heavy sag. N = 40 in [`slow`].
#[test]
fn sagged_shapes_on_hidden_cables_equal_dense_eigenvectors() {
    sagged_shapes_on_hidden_cables_at(&[1, 2, 10]);
}

fn sagged_shapes_on_hidden_cables_at(sizes: &[usize]) {
    let mut worst = Worst::default();
    for heavy in [false, true] {
        let cables = robot(8, 0.6, 2.0e5, heavy);
        for ee in [point(), rigid()] {
            for &n_el in sizes {
                let mut s = SagModalSolver::new(ModalParams::default(), cables.len(), n_el);
                s.load_catenaries(&cables, n_el, &up(), &ee).unwrap();
                let mut hidden = Vec::new();
                let mut frames = Vec::new();
                for (i, c) in cables.iter().enumerate() {
                    let cat = &c.catenary;
                    let ta = cat.h_n.hypot(cat.v_anchor_n);
                    let direction = [cat.h_n / ta, cat.v_anchor_n / ta];
                    let support = SagSupport {
                        hidden: Segment {
                            k: cat.ea_n * n_el as f64 / HIDDEN_M,
                            m: c.mu_kg_m * HIDDEN_M / n_el as f64,
                            n_el,
                        },
                        direction,
                    };
                    s.chain_mut(i).set_support(Some(support)).unwrap();
                    hidden.push(Some((n_el, c.h * direction[0] + up() * direction[1])));
                    frames.push(SagCableFrame {
                        h: c.h,
                        arm_m: c.arm_m,
                        end_force_n: -(c.h * cat.h_n + up() * cat.v_end_n()),
                    });
                }
                s.load(&frames, &up(), &ee).unwrap();
                let want = 12.min(s.total_modes());
                let clusters = s.eigen_clusters(want, &ShapeParams::default()).unwrap();
                let h: Vec<_> = cables.iter().map(|c| c.h).collect();
                let arms: Vec<_> = cables.iter().map(|c| c.arm_m).collect();
                let shapes = s
                    .mode_shapes(&h, &up(), &arms, &clusters, &ShapeParams::default())
                    .unwrap();
                assert!(shapes.modes.len() >= want);
                let (k, m) = dense_matrices(&s, &cables);
                let hidden_dofs = cables.len() * n_el;
                let dim = s.dim();
                assert_eq!(k.nrows(), dim + cables.len() * 3 * (n_el - 1) + hidden_dofs);
                let what = format!(
                    "hidden, heavy {heavy} {} N {n_el}",
                    if dim == 3 { "point" } else { "rigid" }
                );
                let w = compare(&k, &m, &shapes, &s.ee_matrices().0, &hidden, &what);
                // The junctions move (relative to each shape's largest node): the hidden
                // cables take part in these modes.
                let moved = shapes
                    .modes
                    .iter()
                    .map(|md| {
                        let nodes = md.cables.iter().flatten();
                        let big = nodes.clone().fold(0.0f64, |a, x| a.max(x.norm()));
                        md.cables.iter().map(|c| c[0].norm()).fold(0.0, f64::max) / big
                    })
                    .fold(0.0, f64::max);
                eprintln!("{what}: junction motion up to {moved:.1e} of the largest node");
                assert!(moved > 1e-6, "{what}: junctions still ({moved:.1e})");
                worst.mass = worst.mass.max(w.mass);
                worst.residual = worst.residual.max(w.residual);
                worst.subspace = worst.subspace.max(w.subspace);
                worst.part = worst.part.max(w.part);
            }
        }
    }
    eprintln!("sagged shapes on hidden cables vs dense: {worst:?}");
}

/// The estimator's sagged shapes on a scene with `hidden_length` (the paper robot,
/// `scenes/spatial_paper.toml` with 2.5 m under [cable], sag on, fem × 10 and 40, at its
/// centre and off it): structured (not the dense fallback) and equal to the estimator's
/// own dense model with the hidden nodes explicit, by the module docs' checks on the whole
/// vector; the junction's direction d = h (H/T_a) + up (V_a/T_a) from the catenaries. N = 40
/// in [`slow`].
#[test]
fn estimator_shapes_with_sag_and_hidden_length_equal_dense() {
    estimator_shapes_with_sag_and_hidden_length_at(&[10]);
}

fn estimator_shapes_with_sag_and_hidden_length_at(sizes: &[usize]) {
    let text = with_hidden(&std::fs::read_to_string("scenes/spatial_paper.toml").unwrap());
    for &n_el in sizes {
        for offset in [[0.0, 0.0], [0.3, 0.2]] {
            let mut scene = Scene::from_toml_str(&text, "spatial_hidden.toml").unwrap();
            assert!(scene.has_hidden_cable());
            scene.set_sag(true).unwrap();
            scene.model.element = ElementKind::Fem;
            scene.model.elements_per_cable = n_el;
            let mut est = Estimator::new(&scene).unwrap();
            let p = scene.ee_position_m + Vector3::new(offset[0], offset[1], 0.0);
            let e = *est.update(&Pose::at(p), Tmin::Scene);
            assert!(e.status.is_ok(), "{:?}", e.error);
            let basis = est.ee_modal_basis(12).unwrap();
            assert!(basis.structured, "N {n_el}: the basis is structured");
            let shapes = basis.shapes.clone().unwrap();
            let cats = est.sag_catenaries().unwrap().to_vec();
            let hidden = junction_directions(&scene, &cats, &p, n_el);
            let (k, m) = est.dense_matrices().unwrap();
            let m_ee = est.sag_modal().unwrap().ee_matrices().0;
            let what = format!("spatial paper hidden N {n_el} at {offset:?}");
            let w = compare(&k, &m, &shapes, &m_ee, &hidden, &what);
            eprintln!("{what}: {w:?}");
        }
    }
}

/// Bad input: continuous cables, cable counts that do not match, a λ that is not an
/// eigenvalue: errors, no panic.
#[test]
fn sagged_shapes_refuse_bad_input() {
    let cables = robot(4, 0.6, 2.0e5, false);
    let mut s = SagModalSolver::new(ModalParams::default(), cables.len(), 10);
    let h: Vec<_> = cables.iter().map(|c| c.h).collect();
    let p = ShapeParams::default();
    assert!(
        s.mode_shapes(&h, &up(), &[], &[(1.0, 1)], &p).is_err(),
        "not loaded"
    );
    s.load_catenaries(&cables, 10, &up(), &point()).unwrap();
    assert!(s.mode_shapes(&h[..3], &up(), &[], &[(1.0, 1)], &p).is_err());
    let c = s.eigen_clusters(1, &p).unwrap();
    assert!(s.mode_shapes(&h, &up(), &[], &c, &p).is_ok());
    let off = c[0].0 * 1.3;
    assert!(s.mode_shapes(&h, &up(), &[], &[(off, 1)], &p).is_err());
    assert!(s.mode_shapes(&h, &up(), &[], &[(f64::NAN, 1)], &p).is_err());
}

/// The estimator's basis on `suspended_8` with sag (FEM, N = 10 and 40) comes from the
/// structured engine and equals the dense model's: λ to the dense bound 64·ε·λ_max/λ (as in
/// `fem_dense.rs`) + 1e-12, and the end-effector block Σ φ φᵀ of each group of modes
/// within 1e-6 of each other (basis-independent), times the end-effector's mass, to the
/// dense eigenvector bound 64·ε·λ_max/(λ·gap) + 1e-9 (module docs). N = 40 in [`slow`].
#[test]
fn estimator_basis_with_sag_is_structured_and_equals_dense() {
    estimator_basis_with_sag_at(&[(10, [0.0, 0.0]), (10, [0.2, 0.1])]);
}

fn estimator_basis_with_sag_at(cases: &[(usize, [f64; 2])]) {
    for &(n_el, offset) in cases {
        let scene = sagged_fem(shipped("suspended_8.toml"), n_el);
        let mut est = Estimator::new(&scene).unwrap();
        let pose = Pose {
            position_m: scene.ee_position_m + nalgebra::Vector3::new(offset[0], offset[1], 0.0),
            orientation_wxyz: scene.ee_orientation_wxyz,
        };
        let e = *est.update(&pose, Tmin::Scene);
        assert!(e.status.is_ok(), "{:?}", e.error);
        let basis = est.ee_modal_basis(8).unwrap();
        assert!(basis.structured, "N {n_el}: the basis is structured");
        let (k, m) = est.dense_matrices().unwrap();
        let (dl, dv) = dense_eig(&k, &m);
        let lmax = dl.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        let dim = basis.dim;
        let mut i = 0;
        let mut worst = 0.0f64;
        while i < basis.lambda.len() {
            let l = basis.lambda[i];
            let bound = DENSE_FACTOR * f64::EPSILON * lmax / l + 1e-12;
            assert!(
                (l - dl[i]).abs() < bound * l,
                "N {n_el} mode {i}: {l} vs {} (bound {bound:.1e})",
                dl[i]
            );
            let mut j = i + 1;
            // Modes within 1e-6 of each other form one group: the dense solver's vectors of
            // near-equal modes are only defined as a subspace.
            while j < basis.lambda.len() && basis.lambda[j] < l * (1.0 + 1e-6) {
                j += 1;
            }
            let mut a = Matrix6::<f64>::zeros();
            let mut b = Matrix6::<f64>::zeros();
            for q in i..j {
                a += basis.phi_ee[q] * basis.phi_ee[q].transpose();
                let mut d = nalgebra::Vector6::zeros();
                for r in 0..dim {
                    d[r] = dv[(r, q)];
                }
                b += d * d.transpose();
            }
            // Relative to the block of a mode carried by the end-effector alone (‖φφᵀ‖ ~ 1/m):
            // the error is ε·λ_max/gap in the M-norm, not relative to a small mode's block.
            let err = (a - b).norm() * basis.ee_mass[(0, 0)];
            let mut gap = f64::INFINITY;
            if i > 0 {
                gap = gap.min((l - dl[i - 1]) / l);
            }
            if j < dl.len() {
                gap = gap.min((dl[j] - l) / l);
            }
            let tol = DENSE_FACTOR * f64::EPSILON * lmax / l / gap + SUBSPACE_FLOOR;
            assert!(
                err < tol,
                "N {n_el} cluster at mode {i}: {err:.2e} (tol {tol:.1e})"
            );
            worst = worst.max(err);
            i = j;
        }
        eprintln!("suspended-8 sag N {n_el}: end-effector blocks within {worst:.2e}");
    }
}

/// The paper robot with sag (`scenes/spatial_paper.toml`, fem × 40), with and without
/// 2.5 m of hidden cable, over the modes `frf --modal-ratio` takes for its default band
/// (the estimator's basis of 16 … 128 modes: the sizes it doubles through until past
/// 4 × 50 Hz; with hidden cables 16, 32 and 256, past the double at 120 Hz that was refused
/// while the sagged count was noisy next to the axial poles): near-doubles 2e-6 … 5e-6 apart
/// (22.36 Hz with hidden cables, 79.6 Hz without) whose bordered systems are not
/// separated at the null tolerance alone are resolved as near-clusters, not refused; every
/// shape equals the dense eigenvectors by the module docs' checks (the subspace test with
/// the gap to the nearest other eigenvalue, so the near-cluster's members are compared as
/// the subspace their bound allows). Here the 32 modes with hidden cables (the near-double at
/// 22.36 Hz); the other five bases (a dense solve of 939 DOF and more each) in [`slow`].
#[test]
fn paper_robot_sag_shapes_over_the_default_frf_band_equal_dense() {
    paper_robot_sag_shapes_at(&[("hidden", 32)]);
}

fn paper_robot_sag_shapes_at(cases: &[(&str, usize)]) {
    let text = std::fs::read_to_string("scenes/spatial_paper.toml").unwrap();
    let hidden_text = with_hidden(&text);
    for &(name, k) in cases {
        let text = if name == "hidden" {
            &hidden_text
        } else {
            &text
        };
        let mut scene = Scene::from_toml_str(text, "spatial.toml").unwrap();
        scene.set_sag(true).unwrap();
        let mut est = Estimator::new(&scene).unwrap();
        let p = scene.ee_position_m;
        let e = *est.update(&Pose::at(p), Tmin::Scene);
        assert!(e.status.is_ok(), "{:?}", e.error);
        let basis = est
            .ee_modal_basis(k)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(basis.structured, "{name}: the basis is structured");
        let shapes = basis.shapes.clone().unwrap();
        let cats = est.sag_catenaries().unwrap().to_vec();
        let n_el = scene.model.elements_per_cable;
        let hidden: Vec<Hidden> = if name == "hidden" {
            junction_directions(&scene, &cats, &p, n_el)
        } else {
            Vec::new()
        };
        let (km, mm) = est.dense_matrices().unwrap();
        let m_ee = est.sag_modal().unwrap().ee_matrices().0;
        let what = format!(
            "spatial paper sag {name}, k {k}, {} modes",
            shapes.modes.len()
        );
        let w = compare(&km, &mm, &shapes, &m_ee, &hidden, &what);
        eprintln!("{what}: {w:?}");
    }
}

/// A scene file's text with `hidden_length = HIDDEN_M` under its `[cable]` table.
fn with_hidden(text: &str) -> String {
    text.replacen(
        "[cable]",
        &format!("[cable]\nhidden_length = {HIDDEN_M:?}"),
        1,
    )
}

/// Each cable's hidden cable of `n_el` elements, its junction moving along the catenary's
/// anchor tangent d = h (H/T_a) + up (V_a/T_a), with h the unit horizontal from the anchor
/// towards the attachment point `p` (m).
fn junction_directions(
    scene: &Scene,
    cats: &[cablevib::elastic_catenary::Catenary],
    p: &Vector3<f64>,
    n_el: usize,
) -> Vec<Hidden> {
    let up = -scene.gravity_m_s2 / scene.gravity_m_s2.norm();
    scene
        .cables
        .iter()
        .zip(cats)
        .map(|(c, cat)| {
            let d = p - c.anchor_m;
            let h = (d - up * d.dot(&up)).normalize();
            let ta = cat.h_n.hypot(cat.v_anchor_n);
            Some((n_el, h * (cat.h_n / ta) + up * (cat.v_anchor_n / ta)))
        })
        .collect()
}

/// The dense comparisons at N = 40 (a dense eigen-solve with vectors of about 1000 DOF each),
/// run by `.ci/run` (tests/README.md, "Slow reference sweeps").
mod slow {
    #[test]
    #[ignore = "slow reference sweep: cargo test --release --tests -- --ignored slow::"]
    fn sagged_shapes_at_40_elements_equal_dense_eigenvectors() {
        super::sagged_shapes_equal_dense_eigenvectors_at(&[40]);
    }

    #[test]
    #[ignore = "slow reference sweep: cargo test --release --tests -- --ignored slow::"]
    fn sagged_shapes_on_hidden_cables_at_40_elements_equal_dense_eigenvectors() {
        super::sagged_shapes_on_hidden_cables_at(&[40]);
    }

    #[test]
    #[ignore = "slow reference sweep: cargo test --release --tests -- --ignored slow::"]
    fn estimator_shapes_with_sag_and_hidden_length_at_40_elements_equal_dense() {
        super::estimator_shapes_with_sag_and_hidden_length_at(&[40]);
    }

    #[test]
    #[ignore = "slow reference sweep: cargo test --release --tests -- --ignored slow::"]
    fn estimator_basis_with_sag_at_40_elements_equals_dense() {
        super::estimator_basis_with_sag_at(&[(40, [0.2, 0.1])]);
    }

    #[test]
    #[ignore = "slow reference sweep: cargo test --release --tests -- --ignored slow::"]
    fn paper_robot_sag_shapes_over_the_default_frf_band_equal_dense() {
        super::paper_robot_sag_shapes_at(&[
            ("plain", 16),
            ("plain", 32),
            ("plain", 64),
            ("plain", 128),
            ("hidden", 16),
            ("hidden", 256),
        ]);
    }
}
