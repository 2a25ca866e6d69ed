//! The recurrence against an independent dense condensation of the same chain: the whole
//! interior's K − λM assembled (nalgebra), S = Z_ee − Z_ei Z_ii⁻¹ Z_ie by LU, S' = −uᵀMu
//! with u the forced shape (end displacement e_k, interior −Z_ii⁻¹ Z_ie e_k), the count from
//! the interior's symmetric eigenvalues.

use super::*;
use crate::cable::Segment;
use nalgebra::{DMatrix, SymmetricEigen};

/// A non-uniform, curved test profile (not a catenary: the recurrence does not care):
/// chords turning by ~40° along the cable, tension growing 3× from anchor to end.
pub(crate) fn test_chain(n_el: usize, ea_n: f64, mu: f64) -> SagChain {
    let mut c = SagChain::new(n_el);
    let l0 = 7.0;
    c.set_profile(
        ea_n,
        mu,
        l0,
        n_el,
        |s| {
            let t = s / l0;
            [6.5 * t + 0.2 * (3.0 * t).sin(), 2.0 * t * t - 0.8 * t]
        },
        |s| 200.0 + 400.0 * s / l0,
    )
    .unwrap();
    c
}

/// The dense K and M of one direction set of a chain: `dof` DOF per node (2 in plane, 1
/// out), nodes 1..=N (the anchor, node 0, fixed; the end node N last), element stiffness
/// blocks `k(j)` (dof × dof) on [1 −1; −1 1], element mass m as (m/6)[2I I; I 2I].
fn dense_chain(
    n_el: usize,
    dof: usize,
    k: impl Fn(usize) -> DMatrix<f64>,
    m: f64,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let nd = dof * n_el;
    let mut kk = DMatrix::<f64>::zeros(nd, nd);
    let mut mm = DMatrix::<f64>::zeros(nd, nd);
    let eye = DMatrix::<f64>::identity(dof, dof);
    for j in 0..n_el {
        let ke = k(j);
        for (a, na) in [(0usize, j), (1, j + 1)] {
            for (b, nb) in [(0usize, j), (1, j + 1)] {
                if na == 0 || nb == 0 {
                    continue;
                }
                let sg = if a == b { 1.0 } else { -1.0 };
                let mc = if a == b { m / 3.0 } else { m / 6.0 };
                let (ra, rb) = (dof * (na - 1), dof * (nb - 1));
                for r in 0..dof {
                    for c in 0..dof {
                        kk[(ra + r, rb + c)] += sg * ke[(r, c)];
                        mm[(ra + r, rb + c)] += mc * eye[(r, c)];
                    }
                }
            }
        }
    }
    (kk, mm)
}

/// Dense (S, S', count) of one direction set ([`dense_chain`]) at λ.
fn dense_condense(
    n_el: usize,
    dof: usize,
    k: impl Fn(usize) -> DMatrix<f64>,
    m: f64,
    lambda: f64,
) -> (DMatrix<f64>, DMatrix<f64>, usize) {
    let (kk, mm) = dense_chain(n_el, dof, k, m);
    let nd = dof * n_el;
    let eye = DMatrix::<f64>::identity(dof, dof);
    let z = &kk - &mm * lambda;
    let ni = nd - dof;
    let zii = z.view((0, 0), (ni, ni)).into_owned();
    let zie = z.view((0, ni), (ni, dof)).into_owned();
    let zee = z.view((ni, ni), (dof, dof)).into_owned();
    let x = if ni > 0 {
        zii.clone().lu().solve(&zie).unwrap()
    } else {
        DMatrix::zeros(0, dof)
    };
    let s = &zee - zie.transpose() * &x;
    // Forced shapes u_k = [−X e_k; e_k]; S' = −Uᵀ M U.
    let mut u = DMatrix::<f64>::zeros(nd, dof);
    u.view_mut((0, 0), (ni, dof)).copy_from(&(-&x));
    u.view_mut((ni, 0), (dof, dof)).copy_from(&eye);
    let ds = -(u.transpose() * &mm * &u);
    let neg = if ni > 0 {
        SymmetricEigen::new(zii)
            .eigenvalues
            .iter()
            .filter(|&&v| v < 0.0)
            .count()
    } else {
        0
    };
    (s, ds, neg)
}

#[test]
fn recurrence_equals_dense_condensation() {
    let mut worst = [0.0f64; 2];
    for n_el in [1usize, 2, 3, 7, 20] {
        let c = test_chain(n_el, 2.0e5, 0.3);
        let k_in = |j: usize| {
            let k = c.element(j).k_in;
            DMatrix::from_row_slice(2, 2, &[k[0], k[1], k[1], k[2]])
        };
        let k_out = |j: usize| DMatrix::from_element(1, 1, c.element(j).k_out);
        // λ up to above the transverse cut-off and into the axial band.
        let lam_t = 12.0 * c.element(0).k_out.max(c.element(n_el - 1).k_out) / c.element_mass_kg();
        for i in 0..60 {
            let lambda = lam_t * 40.0 * (i as f64 / 60.0).powi(3) + 0.37 * i as f64;
            let e = c.eval(lambda);
            let (si, dsi, ni) = dense_condense(n_el, 2, k_in, c.element_mass_kg(), lambda);
            let (so, dso, no) = dense_condense(n_el, 1, k_out, c.element_mass_kg(), lambda);
            assert_eq!(e.below as usize, ni + no, "N {n_el} λ {lambda}");
            let rec = [e.s_in[0], e.s_in[1], e.s_in[2], e.s_out];
            let den = [si[(0, 0)], si[(0, 1)], si[(1, 1)], so[(0, 0)]];
            let drec = [e.ds_in[0], e.ds_in[1], e.ds_in[2], e.ds_out];
            let dden = [dsi[(0, 0)], dsi[(0, 1)], dsi[(1, 1)], dso[(0, 0)]];
            // Scales: S against the largest element spring (the LU's own error is
            // ~ε·cond·k_max, cond of the interior ≲ 1e6 here), S' against the chain mass
            // plus |S'| (near a blocked eigenvalue both grow like 1/(λ − λ_j)²).
            let k_scale = 2.0e5 / c.element_length_m();
            let mass = c.element_mass_kg() * n_el as f64;
            for q in 0..4 {
                let es = (rec[q] - den[q]).abs() / (k_scale + den[q].abs());
                let ed = (drec[q] - dden[q]).abs() / (mass + dden[q].abs());
                assert!(
                    es < 1e-9,
                    "S N {n_el} λ {lambda} q {q}: {} vs {}",
                    rec[q],
                    den[q]
                );
                assert!(
                    ed < 1e-7,
                    "S' N {n_el} λ {lambda} q {q}: {} vs {}",
                    drec[q],
                    dden[q]
                );
                worst[0] = worst[0].max(es);
                worst[1] = worst[1].max(ed);
            }
        }
    }
    eprintln!(
        "sagged recurrence vs dense: S {:.2e}, S' {:.2e}",
        worst[0], worst[1]
    );
}

/// The eigenvalues of K u = λ M u (dense: Cholesky of M, symmetric eigen-solver),
/// ascending.
fn dense_generalized(k: &DMatrix<f64>, m: &DMatrix<f64>) -> Vec<f64> {
    let l = m.clone().cholesky().unwrap().l();
    let a = l.solve_lower_triangular(k).unwrap();
    let c = l.solve_lower_triangular(&a.transpose()).unwrap();
    let mut v: Vec<f64> = SymmetricEigen::new((&c + c.transpose()) * 0.5)
        .eigenvalues
        .iter()
        .copied()
        .collect();
    v.sort_by(f64::total_cmp);
    v
}

/// The blocked count (both ends held) steps exactly at the blocked eigenvalues of the
/// dense held-held chain (in plane and out of plane together), next to each one: for every
/// dense eigenvalue λ_j separated from its neighbours, count(λ_j(1 − δ)) = j and
/// count(λ_j(1 + δ)) = j + 1, with δ = 1e-11 or the dense solve's own bound 8·ε·λ_max/λ_j
/// where larger (and below a third of the gap to the neighbours). Stiff heavy cables
/// (EA/T up to 1e6, the axial band far above the transverse cut-off) are where the
/// recurrence's second form alone lost the count: next to an axial pole its pivots carry
/// ~1e-9 relative noise and the count flipped back and forth over 1e-8 of λ.
#[test]
fn blocked_count_steps_at_the_dense_blocked_eigenvalues() {
    let mut checked = 0;
    for (n_el, ea) in [(20usize, 2.0e8), (40, 2.0e8), (40, 2.0e6), (80, 5.0e8)] {
        let c = test_chain(n_el, ea, 9.0);
        let m = c.element_mass_kg();
        let k_in = |j: usize| {
            let k = c.element(j).k_in;
            DMatrix::from_row_slice(2, 2, &[k[0], k[1], k[1], k[2]])
        };
        let k_out = |j: usize| DMatrix::from_element(1, 1, c.element(j).k_out);
        let mut lam = Vec::new();
        for (dof, (kk, mm)) in [
            (2, dense_chain(n_el, 2, k_in, m)),
            (1, dense_chain(n_el, 1, k_out, m)),
        ] {
            let ni = kk.nrows() - dof;
            let kk = kk.view((0, 0), (ni, ni)).into_owned();
            let mm = mm.view((0, 0), (ni, ni)).into_owned();
            lam.extend(dense_generalized(&kk, &mm));
        }
        lam.sort_by(f64::total_cmp);
        let top = lam[lam.len() - 1];
        for (j, &l) in lam.iter().enumerate() {
            let gap_lo = if j > 0 { l - lam[j - 1] } else { l };
            let gap_hi = lam.get(j + 1).map_or(f64::INFINITY, |&h| h - l);
            let delta = (8.0 * f64::EPSILON * top / l).max(1e-11);
            if delta * l > gap_lo.min(gap_hi) / 3.0 {
                continue;
            }
            let below = c.eval(l * (1.0 - delta)).below as usize;
            let above = c.eval(l * (1.0 + delta)).below as usize;
            assert_eq!(below, j, "N {n_el} EA {ea:e}: count below λ_{j} = {l:e}");
            assert_eq!(
                above,
                j + 1,
                "N {n_el} EA {ea:e}: count above λ_{j} = {l:e}"
            );
            checked += 1;
        }
    }
    eprintln!("blocked count checked next to {checked} dense eigenvalues");
    assert!(checked > 300, "{checked}");
}

#[test]
fn static_stiffness_is_springs_in_series_out_of_plane() {
    // Out of plane at λ = 0 the chain is springs N_j/l_j in series: 1/s = Σ l_j/N_j.
    let c = test_chain(50, 1.0e6, 0.2);
    let flex: f64 = c.elements().map(|e| 1.0 / e.k_out).sum();
    let s0 = c.static_eval().s_out;
    assert!((s0 * flex - 1.0).abs() < 1e-13, "{s0} vs {}", 1.0 / flex);
}

#[test]
fn bad_inputs_are_errors() {
    let mut c = SagChain::new(4);
    let p = |s: f64| [s, 0.0];
    assert!(matches!(
        c.set_profile(1e5, 0.1, 2.0, 5, p, |_| 10.0),
        Err(SagChainError::ElementCount { .. })
    ));
    assert!(matches!(
        c.set_profile(f64::NAN, 0.1, 2.0, 4, p, |_| 10.0),
        Err(SagChainError::BadInput { .. })
    ));
    assert!(matches!(
        c.set_profile(1e5, 0.1, 2.0, 4, p, |s| 1.0 - s),
        Err(SagChainError::BadElement { element: 2, .. })
    ));
    assert_eq!(c.n_el(), 0);
    assert_eq!(c.eval(3.0), SagChainEval::default());
}

/// Chains of one element count with different materials and profiles (the batch's lanes
/// must not mix), 11 of them: one full block of [`SAG_LANES`] and a partial one.
fn varied_chains(n_el: usize) -> Vec<SagChain> {
    (0..11)
        .map(|i| {
            let f = 1.0 + 0.37 * i as f64;
            let mut c = SagChain::new(n_el);
            let l0 = 5.0 + i as f64;
            c.set_profile(
                2.0e5 * f,
                0.3 / f,
                l0,
                n_el,
                |s| {
                    let t = s / l0;
                    [
                        6.0 * t * f + 0.2 * (3.0 * t).sin(),
                        2.0 * t * t - 0.8 * t * f,
                    ]
                },
                |s| 100.0 * f + 300.0 * s / l0,
            )
            .unwrap();
            c
        })
        .collect()
}

fn assert_same_bits(a: &SagChainEval, b: &SagChainEval, derivative: bool, what: &str) {
    let bits = |e: &SagChainEval| [e.s_in[0], e.s_in[1], e.s_in[2], e.s_out].map(f64::to_bits);
    let dbits = |e: &SagChainEval| [e.ds_in[0], e.ds_in[1], e.ds_in[2], e.ds_out].map(f64::to_bits);
    assert_eq!(bits(a), bits(b), "S {what}: {a:?} vs {b:?}");
    assert_eq!(a.below, b.below, "count {what}");
    if derivative {
        assert_eq!(dbits(a), dbits(b), "S' {what}: {a:?} vs {b:?}");
    } else {
        assert!(
            a.ds_in.iter().chain([&a.ds_out]).all(|&x| x == 0.0),
            "{what}"
        );
    }
}

/// The lockstep batch does the scalar recurrence's IEEE operations in the same order on
/// every lane (no fusing, no reassociation in Rust): tolerance 0, bit for bit, with and
/// without the derivative, below and above every blocked eigenvalue (counts up to ~3N).
#[test]
fn batch_equals_scalar_recurrence_bit_for_bit() {
    for n_el in [1usize, 2, 7, 40] {
        let chains = varied_chains(n_el);
        let mut batch = SagBatch::new(chains.len(), 40);
        assert!(batch.pack(&chains));
        let lam_t = chains
            .iter()
            .map(|c| 12.0 * c.element(0).k_out.max(c.element(n_el - 1).k_out) / c.element_mass_kg())
            .fold(0.0, f64::max);
        for i in 0..80 {
            let lambda = lam_t * 40.0 * (i as f64 / 80.0).powi(3) + 0.37 * i as f64;
            for derivative in [true, false] {
                let mut seen = 0;
                batch.eval_with(lambda, derivative, |j, e| {
                    assert_eq!(j, seen);
                    seen += 1;
                    let what = format!("N {n_el} chain {j} λ {lambda}");
                    assert_same_bits(e, &chains[j].eval(lambda), derivative, &what);
                });
                assert_eq!(seen, chains.len());
            }
        }
    }
}

/// Chains on a hidden cable ([`SagChain::set_support`]) in the lockstep batch, beside
/// fixed-anchor chains: the junction step runs per lane by the scalar path's function and
/// the rest in lockstep, so tolerance 0 (bit for bit) on S, S' and the count against
/// [`SagChain::eval`], with and without S'. Hidden cables of 0 (continuous bar), 1, 3 and
/// 40 elements; λ on a sweep from 0 to far above the blocked eigenvalues (transverse,
/// axial, the junction's and the hidden segments'), then at both sides of a count step in
/// each sweep interval where a chain's count steps (bisected to adjacent doubles: a pivot
/// there is nearly singular) and exactly on the hidden segments' poles.
#[test]
fn batch_with_hidden_cables_equals_scalar_bit_for_bit() {
    for n_el in [1usize, 2, 7, 40] {
        let mut chains = varied_chains(n_el);
        for (i, c) in chains.iter_mut().enumerate() {
            if i % 4 == 3 {
                continue; // a fixed anchor beside the supported lanes
            }
            let [dc, ds] = c.element(0).chord;
            let nh = [0usize, 1, 3, 40][i % 4];
            let per = if nh == 0 { 1.0 } else { nh as f64 };
            let sup = SagSupport {
                hidden: Segment {
                    k: 2.0e5 * (1.0 + 0.3 * i as f64) / 2.5 * per,
                    m: 0.3 * 2.5 / per,
                    n_el: nh,
                },
                direction: [dc, ds],
            };
            c.set_support(Some(sup)).unwrap();
        }
        let mut batch = SagBatch::new(chains.len(), 40);
        assert!(batch.pack(&chains));
        // Above the stiffest element's or hidden element's k/m, times 100.
        let lam_hi = chains
            .iter()
            .map(|c| {
                let e = c.element(0);
                let h = c
                    .support()
                    .map_or(0.0, |s| s.hidden.k / s.hidden.m.max(1e-300));
                100.0 * (e.k_axial_n_m / e.mass_kg).max(h)
            })
            .fold(0.0, f64::max);
        let check = |lambda: f64| {
            for derivative in [true, false] {
                let mut seen = 0;
                batch.eval_with(lambda, derivative, |j, e| {
                    seen += 1;
                    let what = format!("N {n_el} chain {j} λ {lambda:e}");
                    assert_same_bits(e, &chains[j].eval(lambda), derivative, &what);
                });
                assert_eq!(seen, chains.len());
            }
        };
        let sweep: Vec<f64> = std::iter::once(0.0)
            .chain((0..=600).map(|i| lam_hi * 1e-9f64.powf(1.0 - i as f64 / 600.0)))
            .collect();
        let mut near_poles = 0;
        for w in sweep.windows(2) {
            check(w[0]);
            for c in &chains {
                let (mut lo, mut hi) = (w[0], w[1]);
                let below = |l: f64| c.eval(l).below;
                if below(lo) == below(hi) {
                    continue;
                }
                while next_up(lo) < hi {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    if below(mid) == below(lo) {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                check(lo);
                check(hi);
                near_poles += 1;
            }
        }
        for c in &chains {
            if let Some(sup) = c.support() {
                for j in 1..4 {
                    let p = sup.hidden.pole(j);
                    if p.is_finite() {
                        check(p);
                    }
                }
            }
        }
        assert!(near_poles > 50, "N {n_el}: {near_poles} count steps");
    }
}

/// The next double above a positive finite x.
fn next_up(x: f64) -> f64 {
    f64::from_bits(x.to_bits() + 1)
}

/// An exactly singular pivot (λ exactly on a blocked eigenvalue) takes the nudge in the
/// batch as in the scalar recurrence: a straight cable of 2 unit elements, element mass 3
/// kg, axial force 2 N, at λ = 2 (λm/3 = 2 exactly): both pivots are exactly singular.
#[test]
fn batch_nudges_singular_pivots_like_the_scalar_recurrence() {
    let mut c = SagChain::new(2);
    c.set_profile(10.0, 3.0, 2.0, 2, |s| [s, 0.0], |_| 2.0)
        .unwrap();
    let chains = [c.clone(), c];
    let mut batch = SagBatch::new(2, 2);
    assert!(batch.pack(&chains));
    batch.eval_with(2.0, true, |j, e| {
        let s = chains[j].eval(2.0);
        assert!(s.s_out.is_finite() && s.s_in.iter().all(|x| x.is_finite()));
        assert_same_bits(e, &s, true, "singular");
    });
}

#[test]
fn batch_refuses_mixed_element_counts() {
    let chains = [test_chain(3, 1e5, 0.1), test_chain(4, 1e5, 0.1)];
    let mut batch = SagBatch::new(2, 4);
    assert!(!batch.pack(&chains));
    assert_eq!(batch.n_chains(), 0);
    assert!(
        !batch.pack(&[test_chain(5, 1e5, 0.1)]),
        "above the capacity"
    );
    assert!(batch.pack(&chains[..1]));
    assert_eq!(batch.n_chains(), 1);
}

/// The end stiffness S at a complex λ (the damped frequency response) against the dense
/// complex condensation Z_ee − Z_eiZ_ii⁻¹Z_ie of the chain's K − λM (nalgebra complex LU), in
/// plane and out of plane, to 1e-9 of the largest element spring (as the real test).
#[test]
fn complex_lambda_matches_dense_condensation() {
    use num_complex::Complex64;
    let dense =
        |n_el: usize, dof: usize, k: &dyn Fn(usize) -> DMatrix<f64>, m: f64, l: Complex64| {
            let (kk, mm) = dense_chain(n_el, dof, k, m);
            let nd = dof * n_el;
            let z = kk.map(|v| Complex64::new(v, 0.0)) - mm.map(|v| Complex64::new(v, 0.0) * l);
            let ni = nd - dof;
            let zii = z.view((0, 0), (ni, ni)).into_owned();
            let zie = z.view((0, ni), (ni, dof)).into_owned();
            let zee = z.view((ni, ni), (dof, dof)).into_owned();
            if ni == 0 {
                return zee;
            }
            let x = zii.lu().solve(&zie).unwrap();
            &zee - zie.transpose() * &x
        };
    for n_el in [1usize, 3, 20] {
        let c = test_chain(n_el, 2.0e5, 0.3);
        let k_in = |j: usize| {
            let k = c.element(j).k_in;
            DMatrix::from_row_slice(2, 2, &[k[0], k[1], k[1], k[2]])
        };
        let k_out = |j: usize| DMatrix::from_element(1, 1, c.element(j).k_out);
        let lam_t = 12.0 * c.element(0).k_out / c.element_mass_kg();
        let k_scale = 2.0e5 / c.element_length_m();
        for l in [
            Complex64::new(0.3 * lam_t, 0.01 * lam_t),
            Complex64::new(4.0 * lam_t, -0.2 * lam_t),
        ] {
            let (s_in, s_out) = c.eval_at(l);
            let si = dense(n_el, 2, &k_in, c.element_mass_kg(), l);
            let so = dense(n_el, 1, &k_out, c.element_mass_kg(), l);
            let pairs = [
                (s_in[0], si[(0, 0)]),
                (s_in[1], si[(0, 1)]),
                (s_in[2], si[(1, 1)]),
                (s_out, so[(0, 0)]),
            ];
            for (q, (a, b)) in pairs.iter().enumerate() {
                let e = (a - b).norm() / (k_scale + b.norm());
                assert!(e < 1e-9, "N {n_el} λ {l} q {q}: {a} vs {b}");
            }
        }
    }
}
