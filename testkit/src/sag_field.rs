//! The path's influence field of a sagging robot, written in the tests: every cable node's
//! motion with the end-effector when the unstretched lengths follow each pose's sagged
//! tension distribution (the reference of the crate's `estimator::path_field`).
//!
//! At the pose and at p ± δ e_d, p ± 2δ e_d (δ = [`DELTA_M`]) a fresh estimator solves the
//! sagged tension distribution from scratch (cold) and reports each cable's unstretched
//! length L0 (the program's definition of the lengths along a path); from the chord and L0
//! alone each cable's elastic catenary is solved here with Irvine's closed form (Cable
//! Structures, ch. 2: x(s) = H s/EA + (H/w)[asinh(V(s)/H) − asinh(V_a/H)],
//! z(s) = (V_a s + w s²/2)/EA + [T(s) − T_a]/w, Newton on (H, V_a)), the nodes placed at
//! s_j = j L0/N and differentiated by the fourth-order central difference. No catenary,
//! tension-plane or difference code of the crate is used. Point-mass robots without
//! pulleys (what the crate's field covers).

use cablevib::estimator::{Estimator, Tmin};
use cablevib::kinematics::Pose;
use cablevib::scene::Scene;
use nalgebra::{DMatrix, Matrix2, Vector2, Vector3};

/// The difference step, m: truncation O((δ/L)⁴) ≈ 1e-13 for cables of 2 .. 10 m, the cold
/// tension solves' convergence (1e-11 of the largest tension) ~1e-9 of the field.
pub const DELTA_M: f64 = 1e-3;

/// Every cable's nodes (N + 1 from the anchor), world, m.
pub type Nodes = Vec<Vec<Vector3<f64>>>;

/// Each cable's (H, V_a) solved here and the crate's, N.
pub type Catenaries = Vec<(Vector2<f64>, Vector2<f64>)>;

/// Irvine's (x, z) at unstretched arclength `s` from the anchor (module docs), m.
pub fn irvine_point(h: f64, va: f64, w: f64, ea: f64, s: f64) -> Vector2<f64> {
    let v = va + w * s;
    let x = h * s / ea + (h / w) * ((v / h).asinh() - (va / h).asinh());
    let z = (va * s + 0.5 * w * s * s) / ea + (h.hypot(v) - h.hypot(va)) / w;
    Vector2::new(x, z)
}

/// Irvine's elastic catenary from the anchor (0, 0) to (X, Z) for unstretched length `l0`,
/// weight `w` (N/m) and `ea` (N): (H, V_a) by Newton on the two closed-form end equations
/// (Jacobian by central differences) from `start`; its residual asserted (1e-12 of the
/// chord).
pub fn irvine_solve(x: f64, z: f64, l0: f64, w: f64, ea: f64, start: Vector2<f64>) -> Vector2<f64> {
    let end = |p: Vector2<f64>| irvine_point(p[0], p[1], w, ea, l0) - Vector2::new(x, z);
    let mut p = start;
    for _ in 0..60 {
        let r = end(p);
        if r.norm() <= 1e-14 * (x.abs() + z.abs()) {
            break;
        }
        let mut j = Matrix2::zeros();
        for c in 0..2 {
            let h = 1e-7 * p[c].abs().max(1.0);
            let (mut a, mut b) = (p, p);
            a[c] += h;
            b[c] -= h;
            j.set_column(c, &((end(a) - end(b)) / (2.0 * h)));
        }
        p -= j.lu().solve(&r).expect("Irvine Jacobian regular");
    }
    let r = end(p).norm();
    assert!(
        r <= 1e-12 * (x.abs() + z.abs()),
        "Irvine's Newton: residual {r:e} m"
    );
    p
}

/// The nodes of every cable of `scene` (`n` elements each) at `p`, from a cold estimator's
/// L0 and the catenaries solved here; also each cable's (H, V_a) here and the crate's.
pub fn reference_nodes(scene: &Scene, p: Vector3<f64>, n: usize) -> (Nodes, Catenaries) {
    let mut est = Estimator::new(scene).unwrap();
    let e = *est.update(&Pose::in_scene(scene, p), Tmin::Scene);
    assert!(e.is_ok(), "{p:?}: {:?}", e.error);
    let cats = est.sag_catenaries().unwrap().to_vec();
    let up = -scene.gravity_m_s2.normalize();
    let mut nodes = Vec::new();
    let mut hv = Vec::new();
    for (c, cat) in scene.cables.iter().zip(&cats) {
        let chord = p - c.anchor_m;
        let rise = chord.dot(&up);
        let horizontal = chord - up * rise;
        let span = horizontal.norm();
        let hdir = horizontal / span;
        let w = c.mass_per_length_kg_m * scene.gravity_m_s2.norm();
        let (l0, ea) = (cat.l0_m, c.ea_n());
        // Newton from 5 % off the crate's answer (the elastic catenary through a chord with
        // a given L0 is unique, so the root does not depend on the start).
        let start = Vector2::new(cat.h_n, cat.v_anchor_n) * 1.05;
        let sol = irvine_solve(span, rise, l0, w, ea, start);
        hv.push((sol, Vector2::new(cat.h_n, cat.v_anchor_n)));
        nodes.push(
            (0..=n)
                .map(|j| {
                    let q = irvine_point(sol[0], sol[1], w, ea, l0 * j as f64 / n as f64);
                    c.anchor_m + hdir * q[0] + up * q[1]
                })
                .collect(),
        );
    }
    (nodes, hv)
}

/// Σ_k c_k (nodes at p + s_k e − p) / (scale) over the stencil (s_k, c_k).
fn stencil(
    scene: &Scene,
    p: Vector3<f64>,
    n: usize,
    e: Vector3<f64>,
    st: &[(f64, f64)],
    scale: f64,
) -> Nodes {
    let mut out: Option<Nodes> = None;
    for &(s, c) in st {
        let (nodes, _) = reference_nodes(scene, p + e * s, n);
        let f = c / scale;
        match &mut out {
            None => {
                out = Some(
                    nodes
                        .iter()
                        .map(|a| a.iter().map(|x| (x - p) * f).collect())
                        .collect(),
                )
            }
            Some(o) => {
                for (a, b) in o.iter_mut().zip(&nodes) {
                    for (y, x) in a.iter_mut().zip(b) {
                        *y += (x - p) * f;
                    }
                }
            }
        }
    }
    out.unwrap()
}

/// The path's field at `p`: per translation d, every node's ∂x/∂p_d (fourth-order central
/// difference of [`reference_nodes`]).
pub fn reference_field(scene: &Scene, p: Vector3<f64>, n: usize) -> [Nodes; 3] {
    let d = DELTA_M;
    let st = [(-2.0 * d, 1.0), (-d, -8.0), (d, 8.0), (2.0 * d, -1.0)];
    [Vector3::x(), Vector3::y(), Vector3::z()].map(|e| stencil(scene, p, n, e, &st, 12.0 * d))
}

/// The second derivative of every node along the unit `dir` at `p`, ∂²x/∂p²[dir, dir]
/// (fourth-order central second difference [−x(−2h) + 16x(−h) − 30x(0) + 16x(h) −
/// x(2h)]/(12h²) with h = [`CURVATURE_STEP_M`]).
pub fn reference_curvature(scene: &Scene, p: Vector3<f64>, n: usize, dir: Vector3<f64>) -> Nodes {
    let h = CURVATURE_STEP_M;
    let st = [
        (-2.0 * h, -1.0),
        (-h, 16.0),
        (0.0, -30.0),
        (h, 16.0),
        (2.0 * h, -1.0),
    ];
    stencil(scene, p, n, dir, &st, 12.0 * h * h)
}

/// The second difference's step, m: truncation O((h/L)⁴) ≈ 1e-11 for cables of 2 .. 10 m;
/// the cold solves' convergence (node positions to ~1e-12 m) over h² leaves ~1e-7 of a
/// field of order 1/L.
pub const CURVATURE_STEP_M: f64 = 5e-3;

/// Fields (node lists per cable, N + 1 nodes from the anchor) as the dense model's
/// `rows` × cols matrix: the end-effector's rows `ee[d]`, then each cable's interior nodes
/// (`Estimator::dense_matrices`' DOF order of a point mass without pulleys).
pub fn dense_columns(cols: &[&Nodes], rows: usize, ee: &[Vector3<f64>]) -> DMatrix<f64> {
    let mut r = DMatrix::zeros(rows, cols.len());
    for (d, col) in cols.iter().enumerate() {
        for a in 0..3 {
            r[(a, d)] = ee[d][a];
        }
        let mut row = 3;
        for cable in col.iter() {
            for x in &cable[1..cable.len() - 1] {
                for a in 0..3 {
                    r[(row + a, d)] = x[a];
                }
                row += 3;
            }
        }
        assert_eq!(row, rows, "the dense model's DOF are the field's");
    }
    r
}

/// The reference field at `p` as the dense model's `rows` × 3 matrix ([`dense_columns`]).
pub fn dense_reference_field(
    scene: &Scene,
    p: Vector3<f64>,
    n: usize,
    rows: usize,
) -> DMatrix<f64> {
    let f = reference_field(scene, p, n);
    let ee = [Vector3::x(), Vector3::y(), Vector3::z()];
    dense_columns(&[&f[0], &f[1], &f[2]], rows, &ee)
}
