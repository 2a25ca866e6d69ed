//! Hard cases of the cable element and the cable model, each with its expected limit, on
//! both the dense reference and the real-time path: exactly and nearly vertical cables,
//! the catenary element as the weight per length γ goes to 0 (element and whole robot, at
//! every mesh size), a cable near slack, and EA/T from 1e2 to 1e9.
//!
//! Every test prints what it measured (`cargo test --release --test hard_cases element -- --nocapture`);
//! docs/hard-cases.md lists the cases, the expected behaviour and these tests. The shared
//! checks and their tolerance (real-time against the dense reference) are in
//! testkit/src/hard_cases.rs.

use cablevib::cable::{catenary_block, fem_block, up_frame};
use cablevib::estimator::Status;
use cablevib::scene::{ElementKind, Scene};
use cablevib_testkit::ee_hz;
use cablevib_testkit::hard_cases::*;
use cablevib_testkit::rel;
use nalgebra::{Matrix3, Vector3};

/// The largest value of T/(2EA) over the cables at one estimate.
fn max_t_over_2ea(s: &Scene, t: &[f64]) -> f64 {
    s.cables
        .iter()
        .zip(t)
        .map(|(c, &t)| t / (2.0 * c.ea_n()))
        .fold(0.0, f64::max)
}

/// Catenary against FEM, per frequency: the catenary element's transverse stiffness is
/// T/(l(1 + T/EA)) (chord = unstressed length, docs/model.md section 5.3) instead of T/l, i.e. f lower by up
/// to T/(2EA); with weight, the tension varies by γl along an element (±γl/(4T) in f) and
/// sag softens the axial spring by ≈ (γl/T)²·EA/(12T) (Irvine, per element; half in f).
fn catenary_vs_fem_bound(s: &Scene, t: &[f64], lengths: &[f64]) -> f64 {
    let g = s.gravity_m_s2.norm();
    let n = s.model.elements_per_cable as f64;
    let mut b = 0.0f64;
    for ((c, &t), &len) in s.cables.iter().zip(t).zip(lengths) {
        let ea = c.ea_n();
        let gl = c.mass_per_length_kg_m * g * len / n;
        b = b.max(t / (2.0 * ea) + gl / (4.0 * t) + (gl / t).powi(2) * ea / (24.0 * t));
    }
    b
}

/// Straight taut cable limit of the catenary element (docs/model.md section 5.3):
/// K = EA/L0 e eᵀ + T/(L0 (1 + T/EA)) (I − e eᵀ).
fn straight_limit(e: &Vector3<f64>, l0: f64, t: f64, ea: f64) -> (f64, f64) {
    let _ = e;
    (ea / l0, t / (l0 * (1.0 + t / ea)))
}

/// Relative errors of a 3 × 3 element block against axial stiffness `ka` along `e` and
/// transverse `kt`: (axial, transverse, coupling / √(ka kt)).
fn block_errors(k: &Matrix3<f64>, e: &Vector3<f64>, ka: f64, kt: f64) -> (f64, f64, f64) {
    let p = Matrix3::identity() - e * e.transpose();
    let ax = ((e.transpose() * k * e)[(0, 0)] - ka).abs() / ka;
    let tr = (p * k * p - p * kt).norm() / (kt * 2f64.sqrt());
    let cp = (p * k * e).norm() / (ka * kt).sqrt();
    (ax, tr, cp)
}

// ---------------------------------------------------------------------------------------
// Vertical cables
// ---------------------------------------------------------------------------------------

/// Element level: exactly vertical elements (node I above and below node J) and nearly
/// vertical ones (horizontal/vertical force ratio 1e-12 .. 1e-3): finite, positive
/// definite, no horizontal-vertical coupling when exactly vertical, continuous in the
/// ratio (‖K(r) − K(0)‖ ≤ 4r‖K‖: a rotation by r), and within T/EA + γl/(2T) of the FEM
/// block in the transverse direction, the axial stiffness EA/l exact.
#[test]
fn vertical_element_exact_and_nearly_vertical() {
    let frame = up_frame(&Vector3::new(0.0, 0.0, -9.81));
    let (t, ea) = (100.0, 1.0e6);
    let mut worst = (0.0f64, 0.0f64);
    for dir in [1.0, -1.0] {
        for gamma in [0.25, 1e-3, 0.0] {
            for l in [2.0, 0.2, 0.02] {
                let e0 = Vector3::new(0.0, 0.0, dir);
                let k0 = catenary_block(&(e0 * l), t, ea, gamma, &frame).unwrap();
                assert!(k0.iter().all(|x| x.is_finite()), "{k0}");
                assert!(k0.cholesky().is_some(), "not SPD: {k0}");
                for (r, c) in [(0, 2), (1, 2), (0, 1)] {
                    assert!(
                        k0[(r, c)].abs() <= 1e-14 * k0.norm(),
                        "vertical element coupling K[{r},{c}] = {}",
                        k0[(r, c)]
                    );
                }
                assert!(rel(k0[(2, 2)], ea / l) <= 4.0 * EPS, "axial {}", k0[(2, 2)]);
                let kf = fem_block(&e0, l, ea, t, true);
                let dt = rel(k0[(0, 0)], kf[(0, 0)]).max(rel(k0[(1, 1)], kf[(1, 1)]));
                let bound = t / ea + gamma * l / (2.0 * t) + (gamma * l / t).powi(2);
                assert!(
                    dt <= bound,
                    "dir {dir} γ {gamma} l {l}: transverse vs FEM {dt:.2e} > {bound:.2e}"
                );
                worst.0 = worst.0.max(dt / bound);
                for ratio in [1e-12, 1e-9, 1e-6, 1e-3] {
                    let e = Vector3::new(ratio, 0.0, dir).normalize();
                    let k = catenary_block(&(e * l), t, ea, gamma, &frame).unwrap();
                    assert!(k.iter().all(|x| x.is_finite()) && k.cholesky().is_some());
                    let jump = (k - k0).norm() / k0.norm();
                    assert!(
                        jump <= 4.0 * ratio + 1e-14,
                        "dir {dir} γ {gamma} l {l} ratio {ratio:e}: ‖ΔK‖/‖K‖ = {jump:.2e}"
                    );
                    worst.1 = worst.1.max(jump / ratio);
                }
            }
        }
    }
    eprintln!(
        "vertical element: transverse vs FEM at {:.2} of its bound; ‖ΔK‖/‖K‖ ≤ {:.2}·ratio",
        worst.0, worst.1
    );
}

/// System level: a robot with an exactly vertical cable above and one below the
/// end-effector, then moved sideways so that their horizontal/vertical ratio is 1e-12 ..
/// 1e-3: the real-time path equals the dense reference, f1 and the end-effector mode are
/// continuous (|Δf|/f ≤ 2·ratio + tolerances), and the catenary model is within
/// [`catenary_vs_fem_bound`] (T/(2EA) plus the weight terms) of the FEM model.
#[test]
fn vertical_cables_anchor_above_and_below() {
    let n = 10;
    let fem = vertical_scene("fem", n);
    let cat = vertical_scene("catenary", n);
    let mut base: Option<[(f64, f64, f64); 2]> = None;
    let mut worst_cf = 0.0f64;
    for ratio in [0.0, 1e-12, 1e-9, 1e-6, 1e-3] {
        let p = Vector3::new(ratio, 0.0, 1.0); // vertical cables are 1 m long
        let mut now = [(0.0, 0.0, 0.0); 2];
        for (k, s) in [&fem, &cat].into_iter().enumerate() {
            let label = format!("{} ratio {ratio:e}", s.model.element.as_str());
            let e = realtime(s, p, s.t_min_n);
            assert_sane(&label, &e, s, s.t_min_n);
            let r = dense(s, p, s.t_min_n);
            let (_, tol) = assert_matches_dense(&label, s, &e, &r);
            now[k] = (e.f1_hz, ee_hz(&e), tol);
        }
        // Catenary within T/(2EA) (+ weight terms) of FEM.
        let e = realtime(&fem, p, fem.t_min_n);
        let g = geometry(&fem, &p);
        let bound = catenary_vs_fem_bound(&cat, e.tensions(), &g.length_m);
        let t2ea = max_t_over_2ea(&fem, e.tensions());
        for (what, a, b) in [("f1", now[1].0, now[0].0), ("ee", now[1].1, now[0].1)] {
            let d = rel(a, b);
            assert!(
                d <= bound + now[0].2 + now[1].2,
                "ratio {ratio:e} {what}: catenary {a} vs FEM {b}: {d:.2e} > bound {bound:.2e}"
            );
            worst_cf = worst_cf.max(d / t2ea);
        }
        match base {
            None => base = Some(now),
            Some(b0) => {
                for k in 0..2 {
                    for (what, a, b) in [("f1", now[k].0, b0[k].0), ("ee", now[k].1, b0[k].1)] {
                        let d = rel(a, b);
                        let lim = 2.0 * ratio + now[k].2 + b0[k].2;
                        assert!(
                            d <= lim,
                            "ratio {ratio:e} element {k} {what}: {a} vs vertical {b}: jump {d:.2e} > {lim:.2e}"
                        );
                    }
                }
            }
        }
    }
    eprintln!("vertical cables: catenary vs FEM up to {worst_cf:.2} × T/(2EA)");
}

// ---------------------------------------------------------------------------------------
// gamma = 0 and gamma → 0
// ---------------------------------------------------------------------------------------

/// Element level: the catenary element against the analytic straight limit of docs/model.md (section 5.3),
/// for γ = 0 and γ = 1e-15 .. 1e-3 N/m, elements of a 2 m cable refined from N = 1 to
/// 10 000, EA/T = 1e2 .. 1e9, five orientations (vertical both ways, horizontal, sloped up
/// and down). Expected: the axial, transverse and coupling parts within
///   rounding  4ε(1 + EA/T)  (forming K = −F⁻¹ in global axes mixes ε·EA/l into the
///                            transverse part; it does not depend on N), plus
///   weight    axial (γl/T)²·EA/T, transverse γl/T + (γl/T)²·EA/T, coupling (γl/T)·√(EA/T)
///             (tension varying by γl along the element; the chord turned by ≈ γl/(2T)
///             from the end tangents, which mixes the axial spring into the others),
/// so refining the mesh (l → 0) never loses accuracy. The literal Eq. 28 would lose it
/// like ε·EA/(γ l) (docs/model.md section 5.1).
#[test]
fn gamma_to_zero_element_is_the_straight_limit_at_every_n() {
    let frame = up_frame(&Vector3::new(0.0, 0.0, -9.81));
    let (t, big_l) = (100.0, 2.0);
    let dirs = [
        Vector3::new(0.0, 0.0, 1.0),
        Vector3::new(0.0, 0.0, -1.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.3, -0.5, 0.8).normalize(),
        Vector3::new(0.6, 0.0, -0.8),
    ];
    let mut worst = [0.0f64; 3];
    for ea_t in [1e2, 1e4, 1e6, 1e9] {
        let ea = ea_t * t;
        let round = 4.0 * EPS * (1.0 + ea_t) + 1e-14;
        for e in &dirs {
            for gamma in [0.0, 1e-15, 1e-12, 1e-9, 1e-6, 1e-3] {
                for n in [1usize, 10, 100, 1000, 10_000] {
                    let l0 = big_l / n as f64;
                    let k = catenary_block(&(e * l0), t, ea, gamma, &frame).unwrap();
                    let (ka, kt) = straight_limit(e, l0, t, ea);
                    let (ax, tr, cp) = block_errors(&k, e, ka, kt);
                    let w = gamma * l0 / t;
                    let sag = w * w * ea_t; // (γl/T)²·EA/T: sag couples the axial spring in
                    let lim = [round + sag, round + w + sag, round + w * ea_t.sqrt()];
                    for (i, (got, name)) in [(ax, "axial"), (tr, "transverse"), (cp, "coupling")]
                        .into_iter()
                        .enumerate()
                    {
                        assert!(
                            got <= lim[i],
                            "EA/T {ea_t:e} e {:?} γ {gamma:e} N {n}: {name} error {got:.2e} > {:.2e}",
                            e.as_slice(),
                            lim[i]
                        );
                        if gamma == 0.0 {
                            worst[i] = worst[i].max(got / (EPS * (1.0 + ea_t)));
                        }
                    }
                }
            }
        }
    }
    eprintln!(
        "γ = 0: axial / transverse / coupling error ≤ {:.2} / {:.2} / {:.2} × ε(1 + EA/T), flat in N",
        worst[0], worst[1], worst[2]
    );
}

/// System level: the spatial robot with γ = μ|g| scaled to 0 and 1e-15 .. 1e-3 N/m (gravity
/// scaled, so the carried weight vanishes too and every cable sits near t_min): the
/// catenary model must be the straight-cable model, i.e. within T/(2EA) of the FEM model
/// and never above it (f_cat/f_fem ∈ [1 − T/(2EA) − tol, 1 + tol]), at N = 10 on the dense
/// reference and the real-time path, and at N = 10 .. 5120 on the real-time path (no loss
/// of accuracy as the mesh is refined).
#[test]
fn gamma_to_zero_system_is_the_straight_cable_model() {
    let base = Scene::default_scene();
    let mu = base.cables[0].mass_per_length_kg_m;
    let p = Vector3::new(0.3, 0.2, 1.0);
    let mut worst = 0.0f64;
    for gamma in [0.0, 1e-15, 1e-12, 1e-9, 1e-6, 1e-3] {
        let mut s = base.clone();
        s.gravity_m_s2 = Vector3::new(0.0, 0.0, -gamma / mu);
        for n in [10usize, 40, 160, 640, 5120] {
            let fem = s.with_model(ElementKind::Fem, n);
            let cat = s.with_model(ElementKind::Catenary, n);
            let ef = realtime(&fem, p, s.t_min_n);
            let ec = realtime(&cat, p, s.t_min_n);
            let label = format!("γ {gamma:e} N {n}");
            assert_sane(&label, &ef, &fem, s.t_min_n);
            assert_sane(&label, &ec, &cat, s.t_min_n);
            let (mut tf, mut tc) = (1e-9, 1e-9);
            if n == 10 {
                let rf = dense(&fem, p, s.t_min_n);
                let rc = dense(&cat, p, s.t_min_n);
                tf = assert_matches_dense(&format!("{label} fem"), &fem, &ef, &rf).1;
                tc = assert_matches_dense(&format!("{label} catenary"), &cat, &ec, &rc).1;
            }
            let t2ea = max_t_over_2ea(&s, ef.tensions());
            let g = geometry(&s, &p);
            let weight = catenary_vs_fem_bound(&cat, ef.tensions(), &g.length_m) - t2ea;
            for (what, c, f) in [("f1", ec.f1_hz, ef.f1_hz), ("ee", ee_hz(&ec), ee_hz(&ef))] {
                let d = (f - c) / f;
                assert!(
                    d >= -(tf + tc + weight) && d <= t2ea + weight + tf + tc,
                    "{label} {what}: catenary {c} vs FEM {f}: (f_fem − f_cat)/f_fem = {d:.3e}, T/(2EA) = {t2ea:.3e}"
                );
                worst = worst.max(d.abs() / t2ea);
            }
        }
    }
    eprintln!("γ → 0: |f_fem − f_cat|/f_fem ≤ {worst:.3} × T/(2EA) at every N");
}

// ---------------------------------------------------------------------------------------
// Near slack, EA/T
// ---------------------------------------------------------------------------------------

/// A cable near slack (T → 0 inside the bounds). The planar robot at its centre carries no
/// wrench, so every cable sits at t_min and its first mode (out of plane, transverse
/// chains only, stiffness ∝ T) scales exactly as √t_min: f1/√t_min must stay constant to
/// 1e-9 from t_min = 20 N down to 1e-9 N (FEM and continuous models). The spatial robot's
/// first mode (a string mode of the lower cables at t_min) tends to 1.4497·√t_min. Both on
/// the dense eigensolver (t_min ≥ 1e-3 N, at the real-time path's tensions: the dense
/// reference's Clarabel QP fails here, see `clarabel_reference_handles_wide_tension_ranges`)
/// and the real-time path; every model (FEM,
/// catenary, continuous, massless) must give an ok, finite answer. t_min = 0 leaves a cable
/// with no stiffness: a status, not a number.
#[test]
fn cable_near_slack() {
    let planar = Scene::planar_paper();
    let spatial = Scene::default_scene();
    let mut failures = Vec::new();
    for (s, limit_tol) in [(&planar, 1e-9), (&spatial, 2e-6)] {
        for el in [
            ElementKind::Fem,
            ElementKind::Continuous,
            ElementKind::Catenary,
            ElementKind::Massless,
        ] {
            let sc = s.with_model(el, 10);
            let thr = sc.model.ee_participation_min;
            let mut first: Option<f64> = None;
            for t_min in [20.0, 1.0, 1e-1, 1e-3, 1e-6, 1e-9] {
                let label = format!("{} {} t_min {t_min:e}", s.name, el.as_str());
                let e = realtime(&sc, sc.ee_position_m, t_min);
                if e.status != Status::Ok {
                    failures.push(format!(
                        "{label}: {:?} ({}), tensions {:?}",
                        e.status,
                        e.error.map(|x| x.to_string()).unwrap_or_default(),
                        e.tensions()
                    ));
                    continue;
                }
                assert_sane(&label, &e, &sc, t_min);
                if (el.is_discrete() || el == ElementKind::Massless) && t_min >= 1e-3 {
                    let m = dense_with(&sc, sc.ee_position_m, e.tensions());
                    let extra = catenary_conditioning(&sc, e.tensions());
                    assert_matches_modes(&label, &e, &m, thr, extra);
                }
                let c = e.f1_hz / t_min.sqrt();
                if matches!(el, ElementKind::Fem | ElementKind::Continuous) {
                    // Planar: exact √t_min law. Spatial: the limit is approached as
                    // t_min/(upper cable tension) → 0; compare the small-t_min values.
                    let check = s.name == "planar-paper" || t_min <= 1e-3;
                    if check {
                        match first {
                            None => first = Some(c),
                            Some(c0) => assert!(
                                rel(c, c0) <= limit_tol,
                                "{label}: f1/√t_min = {c} vs {c0}: {:.2e}",
                                rel(c, c0)
                            ),
                        }
                    }
                }
            }
            eprintln!(
                "{} {}: f1/√t_min → {:?}",
                s.name,
                el.as_str(),
                first.map(|c| format!("{c:.7}"))
            );
            let e = realtime(&sc, sc.ee_position_m, 0.0);
            assert_no_numbers(&format!("{} {} t_min 0", s.name, el.as_str()), &e);
        }
    }
    assert!(
        failures.is_empty(),
        "a cable near slack (t_min > 0) must give an ok estimate:\n{}",
        failures.join("\n")
    );
}

/// EA/T from 1e2 to 1e9 (Young's modulus scaled at t_min = 60 N, spatial robot off
/// centre): real-time equals dense within the dense solver's accuracy (which degrades as
/// λ_max/λ₁ ∝ EA/T) plus, for the catenary model, [`catenary_conditioning`]; the f1 (a
/// string mode) converges to its inextensible limit.
#[test]
fn ea_over_t_from_1e2_to_1e9() {
    let base = Scene::default_scene();
    let p = Vector3::new(0.3, 0.2, 1.0);
    for el in [ElementKind::Fem, ElementKind::Catenary] {
        let mut prev: Option<f64> = None;
        for ea_t in [1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9] {
            let mut s = base.with_model(el, 10);
            for c in s.cables.iter_mut() {
                c.youngs_modulus_pa = ea_t * s.t_min_n / c.area_m2;
            }
            let label = format!("{} EA/T {ea_t:e}", el.as_str());
            let e = realtime(&s, p, s.t_min_n);
            assert_sane(&label, &e, &s, s.t_min_n);
            let r = dense(&s, p, s.t_min_n);
            let (err, tol) = assert_matches_dense(&label, &s, &e, &r);
            eprintln!(
                "{label}: f1 {:.9} Hz, ee {:.6} Hz, rel {err:.1e} (tol {tol:.1e})",
                e.f1_hz,
                ee_hz(&e)
            );
            if ea_t >= 1e6 {
                if let Some(f) = prev {
                    assert!(rel(e.f1_hz, f) < 1e-5, "{label}: f1 {} vs {f}", e.f1_hz);
                }
                prev = Some(e.f1_hz);
            }
        }
    }
}
