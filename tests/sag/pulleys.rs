//! Sagging cables on swivel pulleys (docs/pulleys.md): the pulleys' own stiffness term
//! (the exit point moves with the pose) in the sagged D(λ).
//!
//! - **Static stiffness** against central finite differences of the sagged static
//!   equilibrium with the pulley geometry, written here from the elastic catenary alone
//!   (its closed-form end point and flexibility; no chain, no modal code): at a pose q each
//!   cable's exit point A(q) and wrap arc come from the chord geometry (as the sagged
//!   tension distribution places them); the free cable keeps its unstretched length and
//!   hangs from the junction J = A(q) + τ_a ξ (τ_a its anchor tangent at the reference pose:
//!   the cable slides over the pulley), where ξ balances the cable behind the exit point,
//!   T_a(q) − T_a = k_b (ξ + R φ(q) − R φ) (k_b = EA/(wrap arc + hidden length): the
//!   wrapped arc stretches by its own change too). The wrench the cables put on the
//!   end-effector, W(q), gives K = −∂W/∂q; "pinned" keeps A and the wrap arc at the
//!   reference pose's (the model without the term).
//! - **Dense reference**: the structured modes with the term against a dense eigen-solve
//!   of the assembled sagged K, M with the term at the end-effector's DOFs.
use cablevib::elastic_catenary::Catenary;
use cablevib::estimator::{Estimator, EstimatorParams, Tmin};
use cablevib::kinematics::{rotation_of, Geometry, Pose};
use cablevib::modal::{dense_modes_ee, dense_relative_accuracy, Mode};
use cablevib::scene::{ElementKind, Scene};
use cablevib_testkit::ee_hz;
use nalgebra::{Matrix3, Matrix6, Rotation3, Vector3, Vector6};

/// The scene at `rel` (from the repository root) with sag on and the element model given.
fn sag_scene(rel: &str, element: ElementKind, n: usize) -> Scene {
    let path = format!("{}/{rel}", env!("CARGO_MANIFEST_DIR"));
    let mut s = Scene::from_path(std::path::Path::new(&path))
        .unwrap()
        .with_model(element, n);
    s.set_sag(true).unwrap();
    s
}

const SCENES: [&str; 2] = [
    "scenes/spatial_paper_pulleys.toml",
    "scenes/caroca_with_rotating_pulleys.toml",
];

/// A pose off the scene's default one (no symmetry).
fn pose_of(s: &Scene) -> Pose {
    Pose {
        position_m: s.ee_position_m + Vector3::new(0.05, -0.03, 0.02),
        orientation_wxyz: s.ee_orientation_wxyz,
    }
}

/// The geometry at position `p` and rotation `rot` (point mass: identity).
fn geometry(s: &Scene, p: &Vector3<f64>, rot: &Matrix3<f64>) -> Geometry {
    let mut g = Geometry::for_scene(s);
    if s.rigid {
        g.update_rigid(
            s.cables.iter().map(|c| &c.anchor_m),
            s.cables.iter().map(|c| &c.attachment_m),
            p,
            rot,
        )
        .unwrap();
    } else {
        g.update(s.cables.iter().map(|c| &c.anchor_m), p).unwrap();
    }
    g
}

/// The catenary of `c0`'s material and unstretched length through the chord (span, rise),
/// by Newton on the end force with the closed-form flexibility, from `c0`'s end force.
fn hang(c0: &Catenary, span: f64, rise: f64) -> Catenary {
    let mut c = *c0;
    for _ in 0..50 {
        let [x, z] = c.end_point_m();
        let (rx, rz) = (span - x, rise - z);
        if rx.hypot(rz) <= 1e-15 * span.hypot(rise) {
            return c;
        }
        let [a, b, d] = c.flexibility_m_n();
        let det = a * d - b * b;
        let dh = (d * rx - b * rz) / det;
        let dv = (a * rz - b * rx) / det;
        let ve = c.v_end_n() + dv;
        c.h_n += dh;
        c.v_anchor_n = ve - c.w_n_m * c.l0_m;
    }
    let [x, z] = c.end_point_m();
    assert!(
        (span - x).hypot(rise - z) <= 1e-13 * span.hypot(rise),
        "{c:?}"
    );
    c
}

/// The reference pose's per-cable state the statics keep.
struct Reference {
    cats: Vec<Catenary>,
    /// Anchor tangents τ_a (world).
    tau: Vec<Vector3<f64>>,
    /// Wrap arcs, m.
    wrap: Vec<f64>,
    /// Exit points, m.
    exit: Vec<Vector3<f64>>,
    /// Stiffness of the cable behind each exit point, N/m (infinite: none).
    k_behind: Vec<f64>,
    p0: Vector3<f64>,
    rot0: Matrix3<f64>,
    up: Vector3<f64>,
}

/// The cables' wrench on the end-effector (force, moment about the centroid) at the
/// displacement `q` (translation, small rotation) from the reference; `pinned`: exit
/// points and wrap arcs held at the reference's.
fn wrench(s: &Scene, r: &Reference, q: &Vector6<f64>, pinned: bool) -> Vector6<f64> {
    let th = Vector3::new(q[3], q[4], q[5]);
    let rot = Rotation3::new(th).into_inner() * r.rot0;
    let p = r.p0 + Vector3::new(q[0], q[1], q[2]);
    let g = geometry(s, &p, &rot);
    let mut w = Vector6::zeros();
    for i in 0..s.n_cables() {
        let b = p + g.arm_m[i];
        let (a, wrap) = if pinned {
            (r.exit[i], r.wrap[i])
        } else {
            (g.exit_m[i], g.wrap_arc_m(i))
        };
        let c0 = &r.cats[i];
        let ta0 = c0.tension_anchor_n();
        // The end force at junction offset ξ, and the junction's imbalance.
        let at = |xi: f64| {
            let chord = b - (a + r.tau[i] * xi);
            let rise = chord.dot(&r.up);
            let horiz = chord - r.up * rise;
            let span = horiz.norm();
            let h = horiz / span;
            let c = hang(c0, span, rise);
            let f = -(h * c.h_n + r.up * c.v_end_n());
            let imbalance = if r.k_behind[i].is_finite() {
                c.tension_anchor_n() - ta0 - r.k_behind[i] * (xi + wrap - r.wrap[i])
            } else {
                0.0
            };
            (f, imbalance)
        };
        // ξ by the secant method (the imbalance is smooth and nearly linear in ξ).
        let (mut x0, mut x1) = (0.0, 1e-9);
        let (mut r0, mut r1) = (at(x0).1, at(x1).1);
        for _ in 0..60 {
            if r1 == 0.0 || r1 == r0 {
                break;
            }
            let x2 = x1 - r1 * (x1 - x0) / (r1 - r0);
            (x0, r0) = (x1, r1);
            x1 = x2;
            r1 = at(x1).1;
            if (x1 - x0).abs() <= 1e-17 {
                break;
            }
        }
        let f = at(x1).0;
        let m = g.arm_m[i].cross(&f);
        w += Vector6::new(f.x, f.y, f.z, m.x, m.y, m.z);
    }
    w
}

/// K = −∂W/∂q by central differences (step h in m and rad), the leading dim × dim block.
fn k_fd(s: &Scene, r: &Reference, dim: usize, pinned: bool, h: f64) -> Matrix6<f64> {
    let mut k = Matrix6::zeros();
    for j in 0..dim {
        let d = Vector6::ith(j, h);
        let col = (wrench(s, r, &d, pinned) - wrench(s, r, &-d, pinned)) / (2.0 * h);
        for i in 0..dim {
            k[(i, j)] = -col[i];
        }
    }
    k
}

/// The estimator at `s`'s pose and the reference state of its sagged statics.
fn reference(s: &Scene) -> (Estimator, Reference) {
    let mut params = EstimatorParams::default();
    params.sag.continuous.rel_tol = 1e-12;
    let mut est = Estimator::with_params(s, params).unwrap();
    let pose = pose_of(s);
    let e = *est.update(&pose, Tmin::Scene);
    assert!(e.is_ok(), "{:?}", e.status);
    let rot0 = if s.rigid {
        rotation_of(&pose.orientation_wxyz)
    } else {
        Matrix3::identity()
    };
    let g = geometry(s, &pose.position_m, &rot0);
    let up = -s.gravity_m_s2.normalize();
    let cats = est.sag_catenaries().unwrap().to_vec();
    let mut tau = Vec::new();
    let mut k_behind = Vec::new();
    for (i, c) in s.cables.iter().enumerate() {
        let chord = g.unit[i] * g.length_m[i];
        let horiz = chord - up * chord.dot(&up);
        let h = horiz.normalize();
        let cat = &cats[i];
        tau.push((h * cat.h_n + up * cat.v_anchor_n) / cat.tension_anchor_n());
        let (len, ea) = match c.hidden {
            Some(hd) => (hd.length_m + g.wrap_arc_m(i), hd.ea_n()),
            None => (g.wrap_arc_m(i), c.ea_n()),
        };
        k_behind.push(if len > 0.0 { ea / len } else { f64::INFINITY });
    }
    let r = Reference {
        cats,
        tau,
        wrap: (0..s.n_cables()).map(|i| g.wrap_arc_m(i)).collect(),
        exit: g.exit_m.clone(),
        k_behind,
        p0: pose.position_m,
        rot0,
        up,
    };
    (est, r)
}

/// The sagged structured D(0) with the pulleys' term against central differences of the
/// sagged statics with the pulley geometry (module docs), on the paper robot and CAROCA
/// with their pulleys:
///
/// - continuous cables (the chains' static stiffness is the elastic catenary's to the
///   mesh's accuracy, here `rel_tol` 1e-12): ‖D(0) − K_fd‖ ≤ 1e-6 ‖K‖. Measured 8.8e-7
///   (paper robot) and 6e-10 (CAROCA); the paper robot's floor is the continuous model's
///   own, the same 8.8e-7 between the model without the term and the pinned statics.
///   Without the term it is 7.9e-6 and 7.5e-6.
/// - fem × 10 and continuous alike, the term itself: the structured term (the end-effector
///   block less K_geo) against the symmetric part of K_fd − K_fd,pinned, ≤ 1e-3 of the term
///   (measured 5-6e-5: the central differences of catenary solves converged to 1e-15 of
///   the chord carry ~1e-9 N / h of noise, ~1e-4 of a term of ~15 N/m), and the statics'
///   skew part (the chord geometry's exit point with the catenary's tangent is not a
///   potential) below 1e-7 ‖K‖ (measured 3e-8, 3e-10): the symmetric part D holds is all
///   but that of the statics.
///
/// h = 1e-6 (m, rad): truncation ~h²·‖K‖/L² ~ 1e-12 ‖K‖ and rounding ~ε·|W|/h ~ 1e-10 ‖K‖
/// are far below both tolerances.
#[test]
fn sagged_static_stiffness_with_pulleys_equals_finite_differences() {
    for rel in SCENES {
        for element in [ElementKind::Continuous, ElementKind::Fem] {
            let s = sag_scene(rel, element, 10);
            let (est, r) = reference(&s);
            let dim = if s.rigid { 6 } else { 3 };
            let sm = est.sag_modal().unwrap();
            let d0 = sm.static_stiffness().unwrap();
            let d0 = d0.view((0, 0), (dim, dim)).into_owned();
            let h = 1e-6;
            let fd = k_fd(&s, &r, dim, false, h);
            let fd = fd.view((0, 0), (dim, dim)).into_owned();
            let pinned = k_fd(&s, &r, dim, true, h);
            let pinned = pinned.view((0, 0), (dim, dim)).into_owned();
            let k = fd.norm();
            let term_code = (sm.ee_matrices().1 - k_geo(&s, &r))
                .view((0, 0), (dim, dim))
                .into_owned();
            let term_fd = &fd - &pinned;
            let term_fd_sym = (&term_fd + term_fd.transpose()) * 0.5;
            let rel_term = (&term_code - &term_fd_sym).norm() / term_fd_sym.norm();
            let skew = (&fd - fd.transpose()).norm() * 0.5 / k;
            let rel_err = (&d0 - &fd).norm() / k;
            let rel_without = (&d0 - &term_code - &fd).norm() / k;
            eprintln!(
                "{rel} {element:?}: ‖D(0) − K_fd‖/‖K‖ {rel_err:.1e} (without the term \
                 {rel_without:.1e}); term {:.1e} of ‖K‖, against the FD's {rel_term:.1e}; \
                 skew {skew:.1e} of ‖K‖",
                term_fd.norm() / k
            );
            assert!(
                rel_term <= 1e-3,
                "{rel} {element:?}: {rel_term:e}\n{term_code}\n{term_fd}"
            );
            assert!(skew <= 1e-7, "{rel}: {skew:e}");
            assert!(term_fd.norm() > 1e-6 * k, "{rel}: the term is {term_fd}");
            if element == ElementKind::Continuous {
                assert!(rel_err <= 1e-6, "{rel}: {rel_err:e}\n{d0}\n{fd}");
            }
        }
    }
}

/// The rigid body's rotational geometric stiffness of the end forces at the reference pose
/// (Σ (f·r) I − sym(f rᵀ), N·m/rad), from the catenaries.
fn k_geo(s: &Scene, r: &Reference) -> Matrix6<f64> {
    let mut k = Matrix6::zeros();
    if !s.rigid {
        return k;
    }
    let g = geometry(s, &r.p0, &r.rot0);
    for i in 0..s.n_cables() {
        let chord = g.unit[i] * g.length_m[i];
        let hz = (chord - r.up * chord.dot(&r.up)).normalize();
        let f = -(hz * r.cats[i].h_n + r.up * r.cats[i].v_end_n());
        let a = g.arm_m[i];
        let fr = f * a.transpose();
        let kg = Matrix3::identity() * f.dot(&a) - (fr + fr.transpose()) * 0.5;
        let mut b = k.view_mut((3, 3), (3, 3));
        b += kg;
    }
    k
}

/// The sagged structured modes with pulleys (fem × 10, the scenes' model) against a dense
/// eigen-solve of the assembled sagged K, M (`assemble_sagged` on the same chains) whose
/// end-effector block holds the pulleys' term from the finite differences above (the
/// symmetric part of K_fd − K_fd,pinned: independent of the structured code's term), on the
/// paper robot and CAROCA with their pulleys, sag on: the first 12 modes and the
/// end-effector mode. Tolerance per mode: 4 × the dense solve's ε·λ_max/λ + 1e-10 (the
/// structured Newton) + 1e-3 × the term's own shift of that mode (the FD term is good to
/// ~6e-5 of itself, measured above). The test sees the term: some mode (the end-effector
/// mode on the paper robot: the strings' modes below it hardly move) shifts by more than
/// twice its tolerance when the term is left out of the dense K.
#[test]
fn sagged_modes_with_pulleys_equal_a_dense_solve_with_the_term() {
    use cablevib::modal::sagged::{assemble_sagged, SagDenseCable};
    let count = 12;
    for rel in SCENES {
        let s = sag_scene(rel, ElementKind::Fem, 10);
        let (mut est, r) = reference(&s);
        let dim = if s.rigid { 6 } else { 3 };
        let h = 1e-6;
        let term = k_fd(&s, &r, dim, false, h) - k_fd(&s, &r, dim, true, h);
        let term = (term + term.transpose()) * 0.5;
        let e = *est.estimate();
        let sm = est.sag_modal().unwrap();
        let (m6, k6_code) = sm.ee_matrices();
        let g = geometry(&s, &r.p0, &r.rot0);
        let cables: Vec<SagDenseCable> = (0..s.n_cables())
            .map(|i| {
                let chord = g.unit[i] * g.length_m[i];
                SagDenseCable {
                    chain: sm.chain(i),
                    h: (chord - r.up * chord.dot(&r.up)).normalize(),
                    arm_m: g.arm_m[i],
                }
            })
            .collect();
        let kg = k_geo(&s, &r);
        let with = kg + term;
        // The structured model's own end-effector block is K_geo plus its term.
        let code_term = k6_code - kg;
        assert!(
            (code_term - term).norm() <= 1e-3 * term.norm(),
            "{rel}: {code_term} vs {term}"
        );
        let dense = |k6: &Matrix6<f64>| {
            let (k, m) = assemble_sagged(&cables, &r.up, &m6, k6, dim).unwrap();
            dense_modes_ee(&k, &m, &m6, dim, true).unwrap()
        };
        let d_with = dense(&with);
        let d_without = dense(&kg);
        let mut out = vec![Mode::default(); count];
        let n = est.modes(count, &mut out).unwrap();
        assert_eq!(n, count);
        let tol = |j: usize| {
            let ld = d_with.lambda[j];
            let shift = (d_without.lambda[j] - ld).abs() / ld;
            4.0 * dense_relative_accuracy(ld, d_with.lambda_max) + 1e-10 + 1e-3 * shift
        };
        let mut seen: f64 = 0.0;
        let mut worst: f64 = 0.0;
        for (j, md) in out.iter().enumerate() {
            let ld = d_with.lambda[j];
            let err = (md.lambda - ld).abs() / ld;
            worst = worst.max(err / tol(j));
            seen = seen.max((d_without.lambda[j] - ld).abs() / ld / tol(j));
            assert!(
                err <= tol(j),
                "{rel} mode {}: {} vs {ld} ({err:.1e})",
                j + 1,
                md.lambda
            );
        }
        // The end-effector mode.
        let thr = s.model.ee_participation_min;
        let (je, le) = d_with.first_ee_mode(thr).unwrap();
        let (_, le0) = d_without.first_ee_mode(thr).unwrap();
        let lam_ee = (2.0 * std::f64::consts::PI * ee_hz(&e)).powi(2);
        let err_ee = (lam_ee - le).abs() / le;
        assert!(
            err_ee <= tol(je),
            "{rel} ee mode {}: {lam_ee} vs {le}",
            je + 1
        );
        worst = worst.max(err_ee / tol(je));
        seen = seen.max((le0 - le).abs() / le / tol(je));
        let hz = |l: f64| l.sqrt() / (2.0 * std::f64::consts::PI);
        eprintln!(
            "{rel}: worst error / tolerance {worst:.2}; the term moves a mode by {seen:.0} × \
             its tolerance; f1 {:.6} Hz (without the term {:.6}, {:+.2e}), ee mode {} {:.6} Hz \
             (without {:.6}, {:+.2e})",
            hz(d_with.lambda[0]),
            hz(d_without.lambda[0]),
            hz(d_with.lambda[0]) / hz(d_without.lambda[0]) - 1.0,
            je + 1,
            hz(le),
            hz(le0),
            hz(le) / hz(le0) - 1.0
        );
        assert!(seen > 2.0, "{rel}: {seen}");
    }
}
