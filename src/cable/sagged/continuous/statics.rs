//! S(0) and dS/dλ at λ = 0 of the continuous sagged cable's discrete model in closed form:
//! its sub-segments are springs in series.
//!
//! At λ = 0 the force p = K u′ is constant along the cable, so with the compliance
//! integrated from the anchor, F(s) = ∫₀ˢ K⁻¹ ds (symmetric 2 × 2 in plane; a scalar out of
//! plane), the end displacement is F(L) p and S(0) = F(L)⁻¹. The static shape for a unit end
//! displacement is U(s) = F(s) F(L)⁻¹, and the first-order term of S(λ) is the consistent
//! mass of that shape (Rayleigh):
//!
//! ```text
//!   dS/dλ(0) = −∫ μ Uᵀ U ds = −S(0) M S(0),   M = ∫ μ F(s)² ds.
//! ```
//!
//! On sub-segment k, F is linear from F_a to F_b = F_a + ℓ_k C̃_k (C̃_k its compliance,
//! diagonal in its principal frame), so its part of M is
//! μℓ_k [(F_a² + F_b²)/3 + (F_a F_b + F_b F_a)/6]. F and M are kept in the current
//! sub-segment's frame and turned into the next one's (a similarity: F² turns like F), then
//! into (h, up) at the end. No blocked eigenvalue lies below 0. This is the same model as `propagate::eval` at λ = 0
//! (one Riccati step per node there, a sum here); they agree to rounding (tested).

use super::kernel::rotate;
use super::Segment;
use crate::cable::sagged::SagChainEval;

/// Symmetric 2 × 2 as [a, b, c] = [[a, b], [b, c]].
type Sym = [f64; 3];

/// (A B + B A)/2 of symmetric A, B.
#[inline(always)]
fn sym_product(a: Sym, b: Sym) -> Sym {
    [
        a[0] * b[0] + a[1] * b[1],
        0.5 * (a[0] * b[1] + a[1] * b[2] + a[1] * b[0] + a[2] * b[1]),
        a[1] * b[1] + a[2] * b[2],
    ]
}

/// S(0) and dS/dλ(0) of the chain `segs` (each sub-segment's frame relative to the
/// previous one, the first's relative to (h, up); `final_rot` the last frame's axis in
/// (h, up)); None when a sub-segment's stiffness is not positive (a mesh capped on a very
/// slack cable can leave c_a < 0: the recursion's pivots, and its count at λ = 0, then say
/// what the model does, so the caller uses it). F and M are accumulated in each
/// sub-segment's own frame, turned from one to the next as the recursion turns S: where
/// the cable is nearly straight F is nearly diagonal there, and det F (axial compliance
/// ~1e5 times below the transverse one) keeps its digits.
pub(super) fn static_eval(segs: &[Segment], final_rot: [f64; 2]) -> Option<SagChainEval> {
    if !segs
        .iter()
        .all(|g| g.k.iter().all(|&k| k > 0.0 && k.is_finite()))
    {
        return None;
    }
    let mut f: Sym = [0.0; 3];
    let mut m: Sym = [0.0; 3];
    let (mut fo, mut mo) = (0.0, 0.0);
    for g in segs {
        let a = rotate(f, g.rot[0], g.rot[1]);
        m = rotate(m, g.rot[0], g.rot[1]);
        f = [a[0] + 1.0 / g.k[0], a[1], a[2] + 1.0 / g.k[1]];
        let (aa, bb, ab) = (sym_product(a, a), sym_product(f, f), sym_product(a, f));
        for i in 0..3 {
            m[i] += g.mul * ((aa[i] + bb[i]) / 3.0 + ab[i] / 3.0);
        }
        let fa = fo;
        fo += 1.0 / g.k[2];
        mo += g.mul * (fa * fa + fa * fo + fo * fo) / 3.0;
    }
    let det = f[0] * f[2] - f[1] * f[1];
    let s_in = [f[2] / det, -f[1] / det, f[0] / det];
    // −S M S, symmetric.
    let sm = [
        s_in[0] * m[0] + s_in[1] * m[1],
        s_in[0] * m[1] + s_in[1] * m[2],
        s_in[1] * m[0] + s_in[2] * m[1],
        s_in[1] * m[1] + s_in[2] * m[2],
    ];
    let ds_in = [
        -(sm[0] * s_in[0] + sm[1] * s_in[1]),
        -(sm[0] * s_in[1] + sm[1] * s_in[2]),
        -(sm[2] * s_in[1] + sm[3] * s_in[2]),
    ];
    // Last sub-segment's frame → (h, up): rotate by −θ.
    let (c, sn) = (final_rot[0], -final_rot[1]);
    Some(SagChainEval {
        s_in: rotate(s_in, c, sn),
        ds_in: rotate(ds_in, c, sn),
        s_out: 1.0 / fo,
        ds_out: -mo / (fo * fo),
        below: 0,
    })
}

#[cfg(test)]
mod tests {
    use crate::cable::sagged::{SagChainEval, SagContinuous, SagContinuousParams};
    use crate::elastic_catenary::Catenary;

    fn close(a: f64, b: f64, scale: f64) -> bool {
        (a - b).abs() <= 1e-12 * scale
    }

    fn check(x: &SagChainEval, y: &SagChainEval, what: &str) {
        let s = x.s_in.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let d = x.ds_in.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..3 {
            assert!(
                close(x.s_in[i], y.s_in[i], s),
                "{what}: S_in {:?} vs {:?}",
                x.s_in,
                y.s_in
            );
            assert!(
                close(x.ds_in[i], y.ds_in[i], d),
                "{what}: dS_in {:?} vs {:?}",
                x.ds_in,
                y.ds_in
            );
        }
        assert!(close(x.s_out, y.s_out, x.s_out.abs()), "{what}: s_out");
        assert!(close(x.ds_out, y.ds_out, x.ds_out.abs()), "{what}: ds_out");
        assert_eq!(x.below, y.below, "{what}: count");
    }

    /// The closed form (springs in series, the static shape's consistent mass) against the
    /// Riccati recursion of `propagate` at λ = 0 on the same sub-segments, an independent
    /// formulation of the same discrete model: to 1e-12 of each block's largest entry (the
    /// recursion condenses one node at a time; a few ulps per node over up to 256
    /// sub-segments). Taut, sagging, slack (low point inside), rising and falling, vertical
    /// and weightless cables, at the real-time and the offline mesh; a very slack cable whose
    /// capped mesh has sub-segments of negative axial compliance (blocked eigenvalues below
    /// 0) keeps the recursion (the closed form declines it).
    #[test]
    fn closed_form_equals_the_recursion_at_zero() {
        let cats = [
            (10.0, 2.5, 150.0, 40.0),
            (10.0, 2.5, 150.0, -80.0),
            (10.0, 2.5, 20.0, -12.3),
            (200.0, 90.0, 1e4, -9e3),
            (30.0, 50.0, 5.0, -700.0),
            (5.0, 2.0, 0.0, 3.0),
            (5.0, 0.0, 100.0, 20.0),
            (180.0, 88.0, 2.0e5, 6.0e4),
        ];
        let mut declined = 0;
        for params in [
            SagContinuousParams::realtime(),
            SagContinuousParams::default(),
        ] {
            for (l0_m, w_n_m, h_n, v_anchor_n) in cats {
                let cat = Catenary {
                    l0_m,
                    ea_n: 3e6,
                    w_n_m,
                    h_n,
                    v_anchor_n,
                };
                let mut c = SagContinuous::new(params);
                c.set(&cat, 0.25).unwrap();
                let what = format!("{cat:?} {params:?}");
                let recursion = c.eval(0.0);
                let closed = super::static_eval(c.segments(), c.final_rot);
                assert_eq!(closed.is_none(), recursion.below > 0, "{what}");
                check(&c.static_eval(), &recursion, &what);
                if let Some(e) = closed {
                    check(&e, &recursion, &what);
                } else {
                    declined += 1;
                }
            }
        }
        assert!(
            declined > 0,
            "no mesh with a negative compliance: the fallback is untested"
        );
    }
}
