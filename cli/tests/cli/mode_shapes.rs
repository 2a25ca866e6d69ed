//! Mode shapes of the structured solver (`ModalSolver::mode_shapes`) against an
//! independent reference: the dense K and M assembled node by node (`modal::assemble`,
//! `assemble_rigid`) and a dense symmetric eigensolver on L⁻¹KL⁻ᵀ (M = LLᵀ) written here,
//! sharing nothing with the shapes' chain closed forms and bordered null space. Continuous
//! cables, which have no dense assembly, are checked against the FEM shapes as N grows.
use cablevib::modal::{ModalParams, ModalSolver, Mode, ModeShapes, ShapeParams, MAX_MULTIPLICITY};
use cablevib::scene::{ElementKind, Scene};
use cablevib_cli::cli::modes::PoseModel;
use nalgebra::{DMatrix, DVector, Matrix6};

/// Modes checked per case (clusters cut by the limit are completed).
const K_MODES: usize = 40;
/// Safety factor on the dense solver's accuracy: a backward-stable dense solve perturbs
/// L⁻¹KL⁻ᵀ by a few ε·λ_max, which moves its eigenvalues by that much and its invariant
/// subspaces by that over the gap (Davis-Kahan).
const DENSE_ULPS: f64 = 10.0;
/// The subspace tolerance: clusters closer than DENSE_ULPS·ε·λ_max/SUBSPACE_TOL are
/// compared as one group, so the dense reference itself is accurate to SUBSPACE_TOL.
const SUBSPACE_TOL: f64 = 1e-7;

fn pose(name: &str, element: ElementKind, n: usize) -> PoseModel {
    // A scene file is found from the repository root; a built-in name as it is.
    let path = match name.ends_with(".toml") {
        true => format!("{}/../{name}", env!("CARGO_MANIFEST_DIR")),
        false => name.to_string(),
    };
    let s = Scene::load(&path).unwrap().with_model(element, n);
    PoseModel::new(&s).unwrap()
}

/// Dense generalized eigen-decomposition: ascending λ and M-orthonormal columns.
fn dense_eig(k: &DMatrix<f64>, m: &DMatrix<f64>) -> (Vec<f64>, DMatrix<f64>) {
    let l = m.clone().cholesky().unwrap().l();
    let a = l.solve_lower_triangular(k).unwrap();
    let c = l.solve_lower_triangular(&a.transpose()).unwrap();
    let c = (&c + c.transpose()) * 0.5;
    let n = c.nrows();
    let e = c.symmetric_eigen();
    let mut idx: Vec<usize> = (0..e.eigenvalues.len()).collect();
    idx.sort_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j]));
    let y = DMatrix::from_fn(n, idx.len(), |r, j| e.eigenvectors[(r, idx[j])]);
    let u = l.transpose().solve_upper_triangular(&y).unwrap();
    (idx.iter().map(|&i| e.eigenvalues[i]).collect(), u)
}

/// A shape in the dense DOF order: end-effector, then each cable's interior nodes.
fn dense_vector(s: &ModeShapes, mode: usize) -> DVector<f64> {
    let m = &s.modes[mode];
    let mut v: Vec<f64> = m.ee.iter().take(s.dim).copied().collect();
    for nodes in &m.cables {
        for u in &nodes[1..nodes.len() - 1] {
            v.extend_from_slice(u.as_slice());
        }
    }
    DVector::from_vec(v)
}

/// Largest M-norm of the part of Φ's columns outside span(U) (U M-orthonormal): the sine
/// of the largest principal angle between the subspaces (to first order).
fn subspace_error(phi: &DMatrix<f64>, u: &DMatrix<f64>, m: &DMatrix<f64>) -> f64 {
    let r = phi - u * (u.transpose() * m * phi);
    (0..r.ncols())
        .map(|c| {
            let x = r.column(c);
            (x.transpose() * m * x)[(0, 0)].max(0.0).sqrt()
        })
        .fold(0.0, f64::max)
}

/// Groups of consecutive clusters (first mode, modes) whose gaps to each other are below
/// `gap_min`; a group whose upper gap (to `next`, the first eigenvalue past the clusters)
/// is below `gap_min` is incomplete and dropped.
fn groups(clusters: &[(f64, u32)], next: f64, gap_min: f64) -> Vec<(usize, usize)> {
    let mut out: Vec<(usize, usize)> = Vec::new();
    let mut start = 0;
    for (i, &(l, m)) in clusters.iter().enumerate() {
        let merge = i > 0 && l - clusters[i - 1].0 < gap_min;
        match out.last_mut() {
            Some(g) if merge => g.1 += m as usize,
            _ => out.push((start, m as usize)),
        }
        start += m as usize;
    }
    if next - clusters.last().unwrap().0 < gap_min {
        out.pop();
    }
    out
}

/// The participation of dense modes `cols` (M-normalised columns of `u`).
fn dense_participation(
    u: &DMatrix<f64>,
    cols: std::ops::Range<usize>,
    ee: &Matrix6<f64>,
    d: usize,
) -> f64 {
    cols.map(|j| {
        let x = u.column(j);
        let mut a = 0.0;
        for r in 0..d {
            for q in 0..d {
                a += x[r] * ee[(r, q)] * x[q];
            }
        }
        a
    })
    .sum()
}

/// The eigenvalues as clusters (λ, multiplicity) from the two structured sources: the
/// shapes' own count bisection, and the spectrum engine (`ModalSolver::modes`).
fn structured_clusters(pm: &PoseModel, spectrum: bool) -> Vec<(f64, u32)> {
    let mut solver = ModalSolver::new(ModalParams::default());
    pm.load(&mut solver);
    if !spectrum {
        return solver
            .eigen_clusters(K_MODES, &ShapeParams::default())
            .unwrap();
    }
    let mut modes = vec![Mode::default(); K_MODES + MAX_MULTIPLICITY as usize];
    let n = solver.modes(modes.len(), &mut modes).unwrap();
    let mut out = Vec::new();
    for (i, md) in modes[..n].iter().enumerate() {
        let complete = md.cluster_start + md.multiplicity as usize <= n;
        if md.cluster_start == i && complete {
            out.push((md.lambda, md.multiplicity));
        }
        if md.cluster_start == i && i >= K_MODES {
            break;
        }
    }
    out
}

fn check_against_dense(label: &str, pm: &PoseModel) {
    let (k, m) = pm.dense().unwrap();
    let (lambda, u) = dense_eig(&k, &m);
    for spectrum in [false, true] {
        let source = if spectrum { "spectrum" } else { "count" };
        let counted = structured_clusters(pm, spectrum);
        check_shapes(
            &format!("{label} ({source})"),
            pm,
            (&k, &m),
            (&lambda, &u),
            &counted,
        );
    }
}

/// The shapes at `counted` against the dense (K, M) and its eigen-decomposition.
fn check_shapes(
    label: &str,
    pm: &PoseModel,
    (k, m): (&DMatrix<f64>, &DMatrix<f64>),
    (lambda, u): (&[f64], &DMatrix<f64>),
    counted: &[(f64, u32)],
) {
    let lmax = lambda.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    let mut solver = ModalSolver::new(ModalParams::default());
    pm.load(&mut solver);
    let p = ShapeParams::default();
    // Shapes at the structured eigenvalues (4ε relative from the count, 1e-14 from the
    // spectrum engine; the dense ones carry ε·λ_max absolute, too coarse for the robots'
    // cable modes 1e-5 apart). A given cluster that is not one eigenvalue is split by the
    // count (`mode_shapes` does it), so the clusters are read back from the shapes.
    let shapes = solver
        .mode_shapes(&pm.models, &pm.geometry.arm_m, counted, &p)
        .unwrap();
    let counted: Vec<(f64, u32)> = shapes
        .modes
        .iter()
        .enumerate()
        .filter(|(i, md)| md.cluster_start == *i)
        .map(|(_, md)| (md.lambda, md.multiplicity))
        .collect();
    // The eigenvalues, each repeated by its multiplicity, are the dense ones (to the dense
    // accuracy, plus the structured source's): checks the multiplicities too.
    let expanded: Vec<f64> = counted
        .iter()
        .flat_map(|&(l, n)| std::iter::repeat_n(l, n as usize))
        .collect();
    let nk = expanded.len();
    assert_eq!(shapes.modes.len(), nk);
    for (i, &l) in expanded.iter().enumerate() {
        let tol = DENSE_ULPS * f64::EPSILON * lmax + 1e-12 * l;
        assert!(
            (l - lambda[i]).abs() <= tol,
            "{label}: mode {i}: count λ {l} vs dense {}",
            lambda[i]
        );
    }
    let phi = DMatrix::from_columns(
        &(0..nk)
            .map(|i| dense_vector(&shapes, i))
            .collect::<Vec<_>>(),
    );
    assert_eq!(phi.nrows(), k.nrows(), "{label}: DOF");
    // M-orthonormal to 1e-9 within a cluster (by construction; the consistent-mass moments
    // are the dense M's quadratic form, exact to ≈ Nε). Across clusters orthogonality is
    // the shapes' accuracy: λ from the count is within ~1e-15 relative, which tilts a shape
    // towards a neighbour at relative gap g by ~1e-15/g (catenary chains of identical cables
    // split by ε·EA/T ≈ 1e-9, so g can be that small): 1e-9 or 1e-15/g, whichever is larger.
    let gram = phi.transpose() * m * &phi;
    let mut orth = 0.0f64;
    for a in 0..nk {
        for b in 0..nk {
            let (la, lb) = (shapes.modes[a].lambda, shapes.modes[b].lambda);
            let same = shapes.modes[a].cluster_start == shapes.modes[b].cluster_start;
            let tol = if same {
                1e-9
            } else {
                1e-9f64.max(1e-15 * la / (la - lb).abs())
            };
            let e = (gram[(a, b)] - if a == b { 1.0 } else { 0.0 }).abs();
            assert!(
                e <= tol,
                "{label}: (ΦᵀMΦ − I)[{a},{b}] = {e:.2e} > {tol:.1e}"
            );
            orth = orth.max(e / tol * 1e-9);
        }
    }
    // Residual ‖Kφ − λMφ‖ / (‖K‖_F ‖φ‖): an exact eigenvector at λ with relative error 4ε
    // gives ~ε; a shape error δ adds ≤ δ. 1e-10 leaves room for rounding over ~1000 DOF
    // and is far below any wrong shape (which has a residual ~ the relative gap, ≥ 1e-7).
    let knorm = k.norm();
    let mut worst_res = 0.0f64;
    for (i, sm) in shapes.modes.iter().enumerate() {
        let x = phi.column(i);
        let r = (k * x - m * x * sm.lambda).norm() / (knorm * x.norm());
        worst_res = worst_res.max(r);
    }
    assert!(worst_res < 1e-10, "{label}: residual {worst_res:.2e}");
    // Subspaces and participations against dense, per group of clusters whose gap to the
    // rest exceeds DENSE_ULPS·ε·λ_max/SUBSPACE_TOL (so the dense vectors are accurate to
    // SUBSPACE_TOL there). Participation: the trace of the group's projector against the
    // end-effector mass moves to first order in the subspace error: same tolerance.
    let gap_min = DENSE_ULPS * f64::EPSILON * lmax / SUBSPACE_TOL;
    let gr = groups(&counted, lambda[nk], gap_min);
    let ee = pm.ee_mass();
    let (mut worst_sub, mut worst_part) = (0.0f64, 0.0f64);
    for &(s, n) in &gr {
        let e = subspace_error(
            &phi.columns(s, n).into_owned(),
            &u.columns(s, n).into_owned(),
            m,
        );
        assert!(
            e <= SUBSPACE_TOL,
            "{label}: modes {s}..{}: subspace error {e:.2e}",
            s + n
        );
        let pd = dense_participation(u, s..s + n, &ee, shapes.dim);
        let ps: f64 = shapes.modes[s..s + n]
            .iter()
            .map(|x| x.ee_participation)
            .sum();
        assert!(
            (pd - ps).abs() <= SUBSPACE_TOL,
            "{label}: modes {s}..{}: participation {ps} vs dense {pd}",
            s + n
        );
        worst_sub = worst_sub.max(e);
        worst_part = worst_part.max((pd - ps).abs());
    }
    // Within a cluster the shapes are ordered by descending participation.
    for w in shapes.modes.windows(2) {
        if w[0].cluster_start == w[1].cluster_start {
            assert!(w[0].ee_participation >= w[1].ee_participation, "{label}");
        }
    }
    let covered: usize = gr.iter().map(|g| g.1).sum();
    eprintln!(
        "{label}: {} DOF, λ_max {lmax:.2e}; {nk} modes in {} clusters (largest {}); ΦᵀMΦ−I {orth:.1e} (scaled to a 1e-9 tolerance), residual {worst_res:.1e}; vs dense in {} groups ({covered} modes, largest {}): subspace {worst_sub:.1e}, participation {worst_part:.1e}",
        k.nrows(),
        counted.len(),
        counted.iter().map(|c| c.1).max().unwrap(),
        gr.len(),
        gr.iter().map(|g| g.1).max().unwrap_or(0)
    );
}

#[test]
fn spatial_paper_fem_and_catenary_match_dense() {
    for n in [10, 40] {
        for el in [ElementKind::Fem, ElementKind::Catenary] {
            let pm = pose("spatial-paper", el, n);
            check_against_dense(&format!("spatial-paper {} N={n}", el.as_str()), &pm);
        }
    }
}

#[test]
fn planar_paper_fem_and_catenary_match_dense() {
    for n in [10, 40] {
        for el in [ElementKind::Fem, ElementKind::Catenary] {
            let pm = pose("planar-paper", el, n);
            check_against_dense(&format!("planar-paper {} N={n}", el.as_str()), &pm);
        }
    }
}

#[test]
fn rigid_box_matches_dense() {
    let pm = pose("scenes/box_6dof.toml", ElementKind::Fem, 10);
    assert_eq!(pm.dim(), 6);
    check_against_dense("box-6dof fem N=10", &pm);
}

/// All sampled node displacements of modes `range` (end-effector, then every cable node), as
/// columns.
fn sampled(s: &ModeShapes, range: std::ops::Range<usize>) -> DMatrix<f64> {
    let cols: Vec<DVector<f64>> = range
        .map(|i| {
            let m = &s.modes[i];
            let mut v: Vec<f64> = m.ee.iter().take(s.dim).copied().collect();
            for nodes in &m.cables {
                for u in nodes {
                    v.extend_from_slice(u.as_slice());
                }
            }
            DVector::from_vec(v)
        })
        .collect();
    DMatrix::from_columns(&cols)
}

/// ‖V₁V₁ᵀ − V₂V₂ᵀ‖_F / ‖V₁V₁ᵀ‖_F through the small Gram matrices (basis-independent
/// within a cluster).
fn projector_distance(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    let (aa, bb, ab) = (a.transpose() * a, b.transpose() * b, a.transpose() * b);
    let d2 = aa.norm_squared() + bb.norm_squared() - 2.0 * ab.norm_squared();
    d2.max(0.0).sqrt() / aa.norm()
}

/// Continuous cables (closed-form sin(φx) shapes, no dense assembly) against the FEM shapes
/// with N elements sampled at the same points (the FEM shapes are checked against dense
/// above): the consistent-mass FEM converges as 1/N², so doubling N divides the distance by
/// about 4 (accepted 3 ..= 5), and it is small at N = 80.
#[test]
fn continuous_shapes_are_the_limit_of_fem() {
    // The distance comes from a difference of squared norms: resolution ≈ √ε.
    const RESOLUTION: f64 = 1e-6;
    let shapes_of = |el: ElementKind, n: usize, samples: usize| {
        let pm = pose("planar-paper", el, n);
        let p = ShapeParams {
            continuous_samples: samples,
            ..ShapeParams::default()
        };
        let mut solver = ModalSolver::new(ModalParams::default());
        pm.load(&mut solver);
        let cl = solver.eigen_clusters(10, &p).unwrap();
        let s = solver
            .mode_shapes(&pm.models, &pm.geometry.arm_m, &cl, &p)
            .unwrap();
        (cl, s)
    };
    let mut last: Option<Vec<f64>> = None;
    for n in [20usize, 40, 80] {
        let (cc, sc) = shapes_of(ElementKind::Continuous, 1, n + 1);
        let (cf, sf) = shapes_of(ElementKind::Fem, n, 2);
        let mut errs = Vec::new();
        let mut start = 0;
        for (a, b) in cc.iter().zip(&cf) {
            assert_eq!(a.1, b.1, "N={n}: multiplicities");
            let r = start..start + a.1 as usize;
            errs.push(projector_distance(
                &sampled(&sc, r.clone()),
                &sampled(&sf, r),
            ));
            start += a.1 as usize;
        }
        let shown: Vec<String> = errs.iter().map(|e| format!("{e:.2e}")).collect();
        eprintln!("continuous vs fem N={n}: projector distances per cluster {shown:?}");
        if let Some(prev) = &last {
            for (c, (p, e)) in prev.iter().zip(&errs).enumerate() {
                if *p < RESOLUTION {
                    continue; // at the Gram difference's resolution: nothing to converge
                }
                let ratio = p / e;
                assert!(
                    (3.0..=5.0).contains(&ratio),
                    "cluster {c}: N={n}: ratio {ratio:.2} ({p:.2e} → {e:.2e})"
                );
            }
        }
        last = Some(errs);
    }
    let worst = last.unwrap().into_iter().fold(0.0, f64::max);
    assert!(worst < 1e-2, "N=80: {worst:.2e}");
}

/// The CSV holds every node of every mode with the documented columns, the anchors at rest
/// and each cable's last node moving with the end-effector (G_i φ); the SVG has one panel per
/// mode asked for.
#[test]
fn csv_and_svg_of_the_rigid_box() {
    use cablevib_cli::report::shapes_csv::{shapes_csv, SHAPES_HEADER};
    use cablevib_cli::report::svg::modes::modes_svg;
    let pm = pose("scenes/box_6dof.toml", ElementKind::Fem, 6);
    let mut solver = ModalSolver::new(ModalParams::default());
    pm.load(&mut solver);
    let p = ShapeParams::default();
    let cl = solver.eigen_clusters(5, &p).unwrap();
    let s = solver
        .mode_shapes(&pm.models, &pm.geometry.arm_m, &cl, &p)
        .unwrap();
    let (text, sidecar) = shapes_csv(&pm.scene, &pm.geometry, &s, None).into_parts("test");
    let sidecar: serde_json::Value = serde_json::from_str(&sidecar).expect("sidecar JSON");
    assert_eq!(sidecar["modes"], s.modes.len());
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(SHAPES_HEADER));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect())
        .collect();
    let n_cables = pm.scene.n_cables();
    // Per mode: centroid translation and rotation rows, then 7 nodes per cable.
    assert_eq!(rows.len(), s.modes.len() * (2 + 7 * n_cables));
    for r in &rows {
        assert_eq!(r.len(), 10);
        let (mode, cable, node) = (r[0] as usize - 1, r[2] as usize, r[3] as usize);
        let m = &s.modes[mode];
        assert!((r[1] - m.frequency_hz).abs() <= 1e-8 * m.frequency_hz);
        if cable == 0 {
            continue;
        }
        let i = cable - 1;
        let u = nalgebra::Vector3::new(r[7], r[8], r[9]);
        if node == 0 {
            let a = pm.scene.cables[i].anchor_m;
            assert_eq!(u.norm(), 0.0);
            assert!((nalgebra::Vector3::new(r[4], r[5], r[6]) - a).norm() < 1e-8);
        }
        if node == 6 {
            let g = cablevib::kinematics::attach_map(&pm.geometry.arm_m[i]);
            let want = g * m.ee;
            assert!(
                (u - want).norm() <= 1e-8 * want.norm().max(1e-12),
                "{u} vs {want}"
            );
        }
    }
    let svg = modes_svg(&pm.scene, &pm.geometry, &s, 4);
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert_eq!(svg.matches("mode ").count(), 4, "one titled panel per mode");
}
