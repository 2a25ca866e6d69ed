//! A sagged chain whose anchor node is not fixed but held by the cable hidden between the
//! pulley and the winch drum ([`crate::scene::HiddenCable`]): the pulley holds the junction
//! (node 0) across the cable, so it moves only along the cable's tangent at the pulley, d
//! (unit, in (h, up)); along d it is held by the hidden cable, a straight axial
//! [`Segment`] whose drum end is fixed, with end stiffness h(λ).
//!
//! **The junction step.** Node 0's one DOF u_d is condensed onto node 1 before the chain's
//! recurrence (module docs) runs from node 1 on. Element 1's stiffness k (2 × 2) in the
//! basis (d, p), p = d rotated by +90°, is [[α, β], [β, γ]]; its diagonal block is
//! A = k − (λm/3) I, its coupling block B = −k − (λm/6) I. The junction's pivot is
//! q₀ = α − λm/3 + h, and node 1's stiffness S₁ = A − (B d)(B d)ᵀ/q₀ is, entry by entry,
//!
//! ```text
//!     S₁[dd] = (h (α − λm/3) + Δ)/q₀,     Δ = (2α − λm/6)(−λm/2)
//!     S₁[pd] = β (h − λm/2)/q₀
//!     S₁[pp] = γ − λm/3 − β²/q₀
//! ```
//!
//! (Δ = (α − λm/3)² − (α + λm/6)², the element's two-port determinant along d, as in
//! `cable::supported`): at λ = 0, S₁[dd] = h α/(α + h), the series spring, with no
//! cancellation. Rotated back to (h, up), S₁ starts the recurrence. The count adds the
//! hidden segment's blocked count and [q₀ < 0] (the junction's pivot, Wittrick–Williams).
//! The out-of-plane chain is unchanged (the pulley holds node 0 out of the plane).

use super::SagChainError;
use crate::cable::{ChainScalar, Segment};

/// The cable behind a sagged cable's anchor (its pulley): the hidden segment and the
/// direction the junction moves along.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SagSupport {
    /// The hidden cable (drum end fixed, the other end at the junction).
    pub hidden: Segment,
    /// Unit direction of the junction's motion (cos, sin) in (h, up): the cable's tangent
    /// at the anchor, pointing along the cable.
    pub direction: [f64; 2],
}

impl SagSupport {
    /// A unit direction (to 1e-9) and a hidden segment with finite k > 0 and m ≥ 0; the
    /// check of both chains' `set_support`.
    pub(super) fn check(support: Option<&SagSupport>) -> Result<(), SagChainError> {
        if let Some(s) = support {
            let [c, sn] = s.direction;
            let h = s.hidden;
            let unit = (c * c + sn * sn - 1.0).abs() <= 1e-9;
            if !(unit && h.k > 0.0 && h.k.is_finite() && h.m >= 0.0 && h.m.is_finite()) {
                return Err(SagChainError::BadInput {
                    name: "hidden cable",
                    value: h.k,
                });
            }
        }
        Ok(())
    }
}

/// The in-plane recurrence's start at node 1 with the anchor node on the support: S₁, S₁′
/// (as [a, b, c] in (h, up)) and the count so far (module docs), from the chain's first
/// element (k0: [a, b, c] in (h, up), N/m; the element mass m, kg; the singular-pivot nudge,
/// N/m) and the hidden segment's end stiffness, its derivative and its count at λ. The one
/// computation of the scalar recurrence and the lockstep batch's supported lanes (`batch`).
#[inline]
pub(super) fn junction_start<T: ChainScalar>(
    (k0, m, nudge): ([f64; 3], f64, f64),
    support: &SagSupport,
    lambda: T,
    (h, dh, h_below): (T, T, u32),
) -> ([T; 3], [T; 3], u32) {
    let re = T::re;
    let [dc, ds] = support.direction;
    let k = k0;
    // k in (d, p), p = (−ds, dc).
    let alpha = dc * dc * k[0] + 2.0 * dc * ds * k[1] + ds * ds * k[2];
    let beta = -ds * dc * k[0] + (dc * dc - ds * ds) * k[1] + ds * dc * k[2];
    let gamma = ds * ds * k[0] - 2.0 * dc * ds * k[1] + dc * dc * k[2];
    let al = re(alpha) - lambda * m / 3.0;
    let (a2, b2) = (re(2.0 * alpha) - lambda * m / 6.0, lambda * (-0.5 * m));
    let delta = a2 * b2;
    let ddelta = b2 * (-m / 6.0) - a2 * (0.5 * m);
    let mut q = al + h;
    if q.is_zero() {
        q = re(nudge.max(f64::EPSILON * support.hidden.k));
    }
    let dq = dh - re(m / 3.0);
    let below = h_below + q.is_negative() as u32;
    let qi = q.recip();
    let q2 = qi * qi;
    let num = h * al + delta;
    let dnum = dh * al + h * (-m / 3.0) + ddelta;
    let sdd = num * qi;
    let dsdd = (dnum * q - num * dq) * q2;
    let g = h - lambda * m / 2.0;
    let spd = g * qi * beta;
    let dspd = ((dh - re(m / 2.0)) * q - g * dq) * q2 * beta;
    let spp = re(gamma) - lambda * m / 3.0 - qi * (beta * beta);
    let dspp = re(-m / 3.0) + dq * q2 * (beta * beta);
    let rot = |xdd: T, xpd: T, xpp: T| -> [T; 3] {
        [
            xdd * (dc * dc) - xpd * (2.0 * dc * ds) + xpp * (ds * ds),
            xdd * (dc * ds) + xpd * (dc * dc - ds * ds) - xpp * (ds * dc),
            xdd * (ds * ds) + xpd * (2.0 * ds * dc) + xpp * (dc * dc),
        ]
    };
    (rot(sdd, spd, spp), rot(dsdd, dspd, dspp), below)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cable::sagged::tests::test_chain;
    use crate::cable::sagged::SagChain;
    use nalgebra::{DMatrix, SymmetricEigen};
    use num_complex::Complex64;

    /// The in-plane K and M of a supported chain, dense: DOFs the hidden cable's nodes
    /// 1 ..= nh (nh the junction, moving along d), the free interior nodes (2 each), the end
    /// node (2) last.
    fn dense(c: &SagChain, sup: &SagSupport) -> (DMatrix<f64>, DMatrix<f64>) {
        let (n, nh) = (c.n_el(), sup.hidden.n_el);
        let nd = nh + 2 * n;
        let mut k = DMatrix::<f64>::zeros(nd, nd);
        let mut m = DMatrix::<f64>::zeros(nd, nd);
        for e in 0..nh {
            for (a, na) in [e, e + 1].into_iter().enumerate() {
                for (b, nb) in [e, e + 1].into_iter().enumerate() {
                    if na == 0 || nb == 0 {
                        continue;
                    }
                    let same = a == b;
                    k[(na - 1, nb - 1)] += if same { sup.hidden.k } else { -sup.hidden.k };
                    m[(na - 1, nb - 1)] += sup.hidden.m / if same { 3.0 } else { 6.0 };
                }
            }
        }
        // Free node j → (first row, 2 × w map).
        let d = DMatrix::from_row_slice(2, 1, &sup.direction);
        let eye = DMatrix::<f64>::identity(2, 2);
        let place = |j: usize| -> (usize, DMatrix<f64>) {
            if j == 0 {
                (nh - 1, d.clone())
            } else {
                (nh + 2 * (j - 1), eye.clone())
            }
        };
        let me = c.element_mass_kg();
        for j in 0..n {
            let kj = c.element(j).k_in;
            let ke = DMatrix::from_row_slice(2, 2, &[kj[0], kj[1], kj[1], kj[2]]);
            for (a, na) in [j, j + 1].into_iter().enumerate() {
                for (b, nb) in [j, j + 1].into_iter().enumerate() {
                    let ((ra, ga), (rb, gb)) = (place(na), place(nb));
                    let sg = if a == b { 1.0 } else { -1.0 };
                    let mc = if a == b { me / 3.0 } else { me / 6.0 };
                    let kk = ga.transpose() * &ke * &gb * sg;
                    let mm = ga.transpose() * &gb * mc;
                    for r in 0..kk.nrows() {
                        for q in 0..kk.ncols() {
                            k[(ra + r, rb + q)] += kk[(r, q)];
                            m[(ra + r, rb + q)] += mm[(r, q)];
                        }
                    }
                }
            }
        }
        (k, m)
    }

    /// S_in, S_in' and the count of a chain on a hidden cable against the dense
    /// condensation of the same chain (independent of the junction step's closed form):
    /// S to 1e-9 of the largest spring, S' to 1e-7 of the masses, the count exactly; the
    /// out-of-plane part is the fixed-anchor chain's.
    #[test]
    fn supported_chain_equals_dense_condensation() {
        for (n_el, nh, theta) in [(1usize, 1usize, 0.3f64), (3, 2, -0.2), (12, 12, 0.45)] {
            let mut c = test_chain(n_el, 2.0e5, 0.3);
            let fixed = c.eval(123.0);
            let sup = SagSupport {
                hidden: Segment {
                    k: 3.0e5 * nh as f64 / 4.0,
                    m: 0.3 * 4.0 / nh as f64,
                    n_el: nh,
                },
                direction: [theta.cos(), theta.sin()],
            };
            c.set_support(Some(sup)).unwrap();
            let (k, m) = dense(&c, &sup);
            let nd = k.nrows();
            let ni = nd - 2;
            let k_scale = 2.0e5 / c.element_length_m() + sup.hidden.k;
            let mass = c.element_mass_kg() * n_el as f64 + sup.hidden.m * nh as f64;
            for i in 0..50 {
                let lambda = 1e7 * (i as f64 / 50.0).powi(3) + 0.5 * i as f64;
                let e = c.eval(lambda);
                let z = &k - &m * lambda;
                let zii = z.view((0, 0), (ni, ni)).into_owned();
                let zie = z.view((0, ni), (ni, 2)).into_owned();
                let x = zii.clone().lu().solve(&zie).unwrap();
                let s = z.view((ni, ni), (2, 2)).into_owned() - zie.transpose() * &x;
                let mut u = DMatrix::<f64>::zeros(nd, 2);
                u.view_mut((0, 0), (ni, 2)).copy_from(&(-&x));
                u.view_mut((ni, 0), (2, 2))
                    .copy_from(&DMatrix::identity(2, 2));
                let ds = -(u.transpose() * &m * &u);
                let neg = SymmetricEigen::new(zii)
                    .eigenvalues
                    .iter()
                    .filter(|&&v| v < 0.0)
                    .count();
                let out = c.eval(lambda);
                let mut plain = test_chain(n_el, 2.0e5, 0.3);
                plain.set_support(None).unwrap();
                let po = plain.eval(lambda);
                assert_eq!(out.s_out, po.s_out);
                assert_eq!(
                    e.below as usize,
                    neg + (po.below as usize - plain_in_count(&plain, lambda)),
                    "N {n_el} λ {lambda}"
                );
                let rec = [e.s_in[0], e.s_in[1], e.s_in[2]];
                let den = [s[(0, 0)], s[(0, 1)], s[(1, 1)]];
                let drec = [e.ds_in[0], e.ds_in[1], e.ds_in[2]];
                let dden = [ds[(0, 0)], ds[(0, 1)], ds[(1, 1)]];
                for q in 0..3 {
                    assert!(
                        (rec[q] - den[q]).abs() <= 1e-9 * (k_scale + den[q].abs()),
                        "S N {n_el} λ {lambda} q {q}: {} vs {}",
                        rec[q],
                        den[q]
                    );
                    assert!(
                        (drec[q] - dden[q]).abs() <= 1e-7 * (mass + dden[q].abs()),
                        "S' N {n_el} λ {lambda} q {q}: {} vs {}",
                        drec[q],
                        dden[q]
                    );
                }
            }
            assert!(fixed.s_in != c.eval(123.0).s_in);
        }
    }

    /// At a complex λ (the damped frequency response): S_in against the dense complex
    /// condensation of the same chain, to 1e-9 of the largest spring.
    #[test]
    fn supported_chain_at_complex_lambda_equals_dense_condensation() {
        for (n_el, nh) in [(1usize, 1usize), (12, 12)] {
            let mut c = test_chain(n_el, 2.0e5, 0.3);
            let sup = SagSupport {
                hidden: Segment {
                    k: 3.0e5 * nh as f64 / 4.0,
                    m: 0.3 * 4.0 / nh as f64,
                    n_el: nh,
                },
                direction: [0.4f64.cos(), 0.4f64.sin()],
            };
            c.set_support(Some(sup)).unwrap();
            let (k, m) = dense(&c, &sup);
            let nd = k.nrows();
            let ni = nd - 2;
            let k_scale = 2.0e5 / c.element_length_m() + sup.hidden.k;
            for lambda in [
                Complex64::new(3.0e3, 60.0),
                Complex64::new(4.0e5, -2.0e4),
                Complex64::new(2.0e6, 1.0e5),
            ] {
                let z =
                    k.map(|x| Complex64::new(x, 0.0)) - m.map(|x| Complex64::new(x, 0.0)) * lambda;
                let zii = z.view((0, 0), (ni, ni)).into_owned();
                let zie = z.view((0, ni), (ni, 2)).into_owned();
                let x = zii.lu().solve(&zie).unwrap();
                let sd = z.view((ni, ni), (2, 2)).into_owned() - zie.transpose() * &x;
                let (s_in, _) = c.eval_at(lambda);
                let den = [sd[(0, 0)], sd[(0, 1)], sd[(1, 1)]];
                for q in 0..3 {
                    assert!(
                        (s_in[q] - den[q]).norm() <= 1e-9 * (k_scale + den[q].norm()),
                        "N {n_el} λ {lambda} q {q}: {} vs {}",
                        s_in[q],
                        den[q]
                    );
                }
            }
        }
    }

    /// The fixed-anchor chain's in-plane count at λ (its total minus the out-of-plane
    /// chain's, which the support leaves alone).
    fn plain_in_count(plain: &SagChain, lambda: f64) -> usize {
        let (_, _, below_in) = plain.eval_in_plane(lambda);
        below_in as usize
    }
}
