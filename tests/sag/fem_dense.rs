//! The structured sagged solver (D(λ) from the chains' block recurrences, the
//! Wittrick–Williams count, Newton per branch) against the dense reference (the whole
//! robot's K and M assembled in world coordinates from each element's world chord, a
//! dense generalized symmetric eigen-solve): the two share only the element data.
//!
//! Tolerance. A backward-stable dense solve has absolute eigenvalue error ~ε·λ_max
//! (`cablevib::modal::dense_relative_accuracy`); the structured solver is far more
//! accurate on low modes. So each eigenvalue must agree to DENSE_FACTOR·ε·λ_max/λ
//! relative (the dense bound; its constant is not known a priori: the reduction
//! L⁻¹KL⁻ᵀ and the assembly's sums add to it) plus the structured Newton tolerance 1e-12.
//! Measured worst: 4.2 (single cable) and 7.4 (robots) × ε·λ_max/λ; the symmetric robot's
//! 69 is a mode near λ_max where both errors are ~1e-14 (the structured Newton's own).
//!
//! Also the γ → 0 limit: without weight the sagged FEM is today's chord FEM (CableModel,
//! closed-form uniform chains) fed with EA' = EA(1 + T/EA), μ' = μ/(1 + T/EA).

use cablevib::cable::{up_frame, CableModel};
use cablevib::kinematics::rigid_geometric_stiffness;
use cablevib::modal::sagged::{HangingCable, SagEndEffector};
use cablevib::modal::SagModalSolver;
use cablevib::modal::{dense_modes_ee, ModalParams, ModalSolver, Mode};
use cablevib::scene::ElementKind;
use cablevib_testkit::sag_robot::*;
use nalgebra::{Matrix3, Vector3};

/// Factor on the dense solver's bound ε·λ_max/λ: ~9× the measured worst (module docs).
const DENSE_FACTOR: f64 = 64.0;
/// The structured solver's own Newton tolerance (relative).
const STRUCTURED_TOL: f64 = 1e-12;

/// (dense λ ascending, λ_max, dense participations).
fn dense_of(s: &SagModalSolver, cables: &[HangingCable]) -> (Vec<f64>, f64, Vec<f64>) {
    let (k, m) = dense_matrices(s, cables);
    let (m6, _) = s.ee_matrices();
    let d = dense_modes_ee(&k, &m, &m6, s.dim(), true).unwrap();
    (d.lambda, d.lambda_max, d.ee_participation)
}

/// Compare every structured mode (up to `k`) with the dense ones; the count at the
/// geometric means of well-separated neighbours; the first root. Returns the worst
/// error in units of the dense bound.
fn compare(cables: &[HangingCable], n_el: usize, ee: &SagEndEffector, k: usize) -> f64 {
    let mut s = solver_for(cables, n_el, ee);
    let (dl, lmax, dp) = dense_of(&s, cables);
    assert_eq!(dl.len(), s.total_modes());
    let mut modes = vec![Mode::default(); k];
    let n = s.modes(k, &mut modes).unwrap();
    assert_eq!(n, k.min(dl.len()));
    let mut worst = 0.0f64;
    for (i, m) in modes[..n].iter().enumerate() {
        let bound = DENSE_FACTOR * f64::EPSILON * lmax / dl[i] + STRUCTURED_TOL;
        let err = (m.lambda - dl[i]).abs() / dl[i];
        assert!(
            err <= bound,
            "N {n_el} mode {i}: {} vs dense {} (err {err:.2e}, bound {bound:.2e})",
            m.lambda,
            dl[i]
        );
        worst = worst.max(err / (f64::EPSILON * lmax / dl[i]));
        // Participation of simple, well-separated modes (a cluster's dense basis is arbitrary).
        let sep = |j: usize| (dl[j] - dl[i]).abs() > 1e-6 * dl[i];
        if m.multiplicity == 1 && (i == 0 || sep(i - 1)) && (i + 1 >= dl.len() || sep(i + 1)) {
            // Both participations are ratios of mode-shape norms, ~1e-8 conditioned by the
            // separation 1e-6 at worst.
            assert!(
                (m.ee_participation - dp[i]).abs() < 1e-6,
                "participation mode {i}: {} vs {}",
                m.ee_participation,
                dp[i]
            );
        }
    }
    // Count: exact at any λ not within the dense error of an eigenvalue.
    for i in 0..dl.len().min(3 * k) - 1 {
        if dl[i + 1] > dl[i] * (1.0 + 1e-6) {
            let x = (dl[i] * dl[i + 1]).sqrt();
            assert_eq!(s.count_below(x) as usize, i + 1, "N {n_el} count at {x}");
        }
    }
    let r = s.first_root_cold().unwrap();
    let bound = DENSE_FACTOR * f64::EPSILON * lmax / dl[0] + STRUCTURED_TOL;
    assert!(
        (r.lambda - dl[0]).abs() / dl[0] <= bound,
        "first root {} vs {}",
        r.lambda,
        dl[0]
    );
    worst
}

#[test]
fn single_cable_equals_dense() {
    let cables = &robot(3, 0.8, 1.0e5, true)[1..2];
    let mut worst = 0.0f64;
    for n_el in [1usize, 2, 3, 8, 30] {
        worst = worst.max(compare(cables, n_el, &point(), 40));
    }
    eprintln!("single cable: worst error {worst:.1} × ε·λmax/λ");
}

#[test]
fn robots_equal_dense() {
    let mut worst = 0.0f64;
    for (n, heavy) in [(4usize, false), (8, false), (8, true)] {
        let cables = robot(n, 0.6, 2.0e5, heavy);
        for ee in [point(), rigid()] {
            for n_el in [2usize, 6, 20] {
                worst = worst.max(compare(&cables, n_el, &ee, 30));
            }
        }
    }
    eprintln!("robots: worst error {worst:.1} × ε·λmax/λ");
}

/// The chord FEM of a weightless catenary: EA' = EA(1 + T/EA), μ' = μ/(1 + T/EA) on the
/// stretched chord L = L0(1 + T/EA), direction (H h + V up)/T.
fn chord_model(c: &HangingCable, n_el: usize) -> (CableModel, Vector3<f64>, f64) {
    let cat = &c.catenary;
    let t = cat.h_n.hypot(cat.v_anchor_n);
    let st = 1.0 + t / cat.ea_n;
    let e = (c.h * cat.h_n + up() * cat.v_anchor_n) / t;
    let m = CableModel::build(
        ElementKind::Fem,
        n_el,
        &e,
        cat.l0_m * st,
        t,
        cat.ea_n * st,
        c.mu_kg_m / st,
        0.0,
        &up_frame(&(-up() * G)),
        true,
    )
    .unwrap();
    (m, e, t)
}

/// Weightless cables: the robot's cables with w = 0 (μ kept for the mass).
fn weightless(n: usize) -> Vec<HangingCable> {
    robot(n, 0.6, 2.0e5, false)
        .into_iter()
        .map(|mut c| {
            c.catenary.w_n_m = 0.0;
            c
        })
        .collect()
}

/// 1 + T/EA of a weightless catenary.
fn st_of(cat: &cablevib::elastic_catenary::Catenary) -> f64 {
    1.0 + cat.h_n.hypot(cat.v_anchor_n) / cat.ea_n
}

#[test]
fn weightless_chain_equals_chord_fem() {
    // S(λ) of each cable against the chord model's closed-form chains: S_in = s_a c cᵀ +
    // s_t (I − c cᵀ), s_out = s_t. Both are exact to rounding: |ΔS| ≲ ε·N·k_axial (the
    // closed form's own accuracy, see cable::chain's tests), so 1e-11·N relative to EA/l0.
    let mut worst = 0.0f64;
    for c in weightless(4) {
        for n_el in [1usize, 3, 10, 40] {
            let mut ch = cablevib::cable::sagged::SagChain::new(n_el);
            ch.set_fem(&c.catenary, c.mu_kg_m, n_el).unwrap();
            let (model, _, t) = chord_model(&c, n_el);
            let cat = &c.catenary;
            let (co, si) = (cat.h_n / t, cat.v_anchor_n / t);
            let k_ax = cat.ea_n * n_el as f64 / cat.l0_m;
            let k_t = t * n_el as f64 / (cat.l0_m * st_of(cat));
            let m_tot = c.mu_kg_m * cat.l0_m;
            let cut = 12.0 * k_ax * n_el as f64 / m_tot;
            for i in 1..200 {
                let lambda = cut * 1.2 * (i as f64 / 200.0).powi(4);
                let a = model.chains[0].eval(lambda);
                let b = model.chains[1].eval(lambda);
                let e = ch.eval(lambda);
                let want = [
                    a.s * co * co + b.s * si * si,
                    (a.s - b.s) * co * si,
                    a.s * si * si + b.s * co * co,
                    b.s,
                ];
                let dwant = [
                    a.ds * co * co + b.ds * si * si,
                    (a.ds - b.ds) * co * si,
                    a.ds * si * si + b.ds * co * co,
                    b.ds,
                ];
                let got = [e.s_in[0], e.s_in[1], e.s_in[2], e.s_out];
                let dgot = [e.ds_in[0], e.ds_in[1], e.ds_in[2], e.ds_out];
                for q in 0..4 {
                    // Near a blocked eigenvalue λ_p, S ≈ r/(λ − λ_p) and a relative rounding
                    // δ of λ_p moves S by ~δ S²/k, k the pole's chain spring (the transverse
                    // T/l0' is the smaller): the scale k_axial + |S| + S²/k_t.
                    let w = want[q].abs();
                    let es = (got[q] - want[q]).abs() / (k_ax + w + w * w / k_t);
                    let ed = (dgot[q] - dwant[q]).abs() / (m_tot + dwant[q].abs());
                    assert!(
                        es < 1e-11 * n_el as f64,
                        "S N {n_el} λ {lambda} q {q}: {} vs {}",
                        got[q],
                        want[q]
                    );
                    // S' of the closed form: relative ε·N²·(pole factor) (cable::chain's tests).
                    assert!(
                        ed < 1e-8 * (n_el * n_el) as f64,
                        "S' N {n_el} λ {lambda} q {q}: {} vs {}",
                        dgot[q],
                        dwant[q]
                    );
                    worst = worst.max(es);
                }
                assert_eq!(e.below, a.below + 2 * b.below, "N {n_el} λ {lambda}");
            }
        }
    }
    eprintln!("weightless chain vs chord FEM: S {worst:.2e}");
}

#[test]
fn weightless_robot_equals_chord_fem() {
    // The robots' first 30 modes: both solvers are exact to rounding (Newton to 1e-12/1e-14
    // on D of the same model, evaluated by independent formulas), so 1e-10 relative.
    let mut worst = 0.0f64;
    for ee in [point(), rigid()] {
        for n_el in [2usize, 10, 40] {
            let cables = weightless(8);
            let mut s = solver_for(&cables, n_el, &ee);
            let mut models = Vec::new();
            let (mut units, mut arms, mut tens) = (Vec::new(), Vec::new(), Vec::new());
            for c in &cables {
                let (m, e, t) = chord_model(c, n_el);
                models.push(m);
                units.push(e);
                arms.push(c.arm_m);
                tens.push(t);
            }
            let mut r = ModalSolver::new(ModalParams::default());
            match ee {
                SagEndEffector::Point { mass_kg } => r.load(&models, mass_kg),
                SagEndEffector::Rigid {
                    mass_kg,
                    inertia_kg_m2,
                } => {
                    let kg: Matrix3<f64> = rigid_geometric_stiffness(&units, &arms, &tens);
                    r.load_rigid(&models, mass_kg, &inertia_kg_m2, &arms, &kg)
                }
            }
            let k = 30;
            let (mut a, mut b) = (vec![Mode::default(); k], vec![Mode::default(); k]);
            let n = s.modes(k, &mut a).unwrap();
            assert_eq!(n, r.modes(k, &mut b).unwrap());
            for i in 0..n {
                let err = (a[i].lambda - b[i].lambda).abs() / b[i].lambda;
                assert!(
                    err < 1e-10,
                    "N {n_el} mode {i}: {} vs chord {}",
                    a[i].lambda,
                    b[i].lambda
                );
                assert_eq!(a[i].multiplicity, b[i].multiplicity, "mode {i}");
                worst = worst.max(err);
            }
            let f = s.first_root_cold().unwrap().lambda;
            let g = r.first_root(None).unwrap().lambda;
            assert!((f - g).abs() < 1e-10 * g, "{f} vs {g}");
            let (d1, d2) = (s.static_stiffness().unwrap(), r.eval(0.0).d);
            assert!(
                (d1 - d2).abs().max() < 1e-10 * d2.abs().max(),
                "{d1} vs {d2}"
            );
        }
    }
    eprintln!("weightless robot vs chord FEM: λ {worst:.2e}");
}

#[test]
fn symmetric_robot_clusters_equal_dense() {
    // Four identical cables at right angles: blocked modes of multiplicity 4, of which the
    // end-effector absorbs at most 3 directions, so modes sit exactly on the chains' poles
    // (end-effector still) and degenerate end-effector modes appear.
    let one = robot(2, 0.6, 2.0e5, true)[1];
    let cables: Vec<HangingCable> = (0..4)
        .map(|i| {
            let phi = std::f64::consts::FRAC_PI_2 * i as f64;
            HangingCable {
                h: Vector3::new(phi.cos(), phi.sin(), 0.0),
                ..one
            }
        })
        .collect();
    let mut worst = 0.0f64;
    for n_el in [3usize, 10] {
        worst = worst.max(compare(&cables, n_el, &point(), 40));
        let mut s = solver_for(&cables, n_el, &point());
        let mut modes = vec![Mode::default(); 40];
        let n = s.modes(40, &mut modes).unwrap();
        let max_mult = modes[..n].iter().map(|m| m.multiplicity).max().unwrap();
        assert!(max_mult >= 2, "no cluster found");
        // A cluster's participations sum to the dense cluster's sum.
        let (dl, _, dp) = dense_of(&s, &cables);
        let mut i = 0;
        while i < n {
            let m = (modes[i].multiplicity as usize).clamp(1, n - i);
            let sum_s: f64 = modes[i..i + m].iter().map(|m| m.ee_participation).sum();
            let sum_d: f64 = dp[i..i + m].iter().sum();
            assert!(
                (sum_s - sum_d).abs() < 1e-6,
                "cluster at {}: {sum_s} vs {sum_d} (λ {})",
                i,
                dl[i]
            );
            i += m;
        }
    }
    eprintln!("symmetric robot: worst error {worst:.1} × ε·λmax/λ");
}
