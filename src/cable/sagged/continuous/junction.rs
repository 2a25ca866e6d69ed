//! The anchor node on the hidden cable (`SagContinuous::set_support`): the junction step
//! that starts both forms of the condensation (`propagate`, `transfer`).

use super::kernel::{nonzero, rotate};

/// One direction's D, e, x = D − e and the λ-derivatives of D, e on a sub-segment.
#[derive(Clone, Copy)]
pub(super) struct De {
    pub(super) d: f64,
    pub(super) e: f64,
    pub(super) x: f64,
    pub(super) dd: f64,
    pub(super) de: f64,
}

/// The anchor node on the hidden cable (`SagContinuous::set_support`) at λ: the unit
/// direction of its motion in the first sub-segment's frame, the hidden cable's end
/// stiffness h, dh/dλ and its blocked count.
#[derive(Clone, Copy)]
pub(super) struct Junction {
    pub(super) dir: [f64; 2],
    pub(super) h: f64,
    pub(super) dh: f64,
    pub(super) below: u32,
}

/// S₁, dS₁/dλ (first sub-segment's frame) and the count so far with the anchor node on the
/// junction `j`, from the first sub-segment's axial `a` and transverse `t` D, e, x. In the
/// basis (d, p) of the junction's direction (D̂, Ê, X̂ the sub-segment's matrices turned
/// into it), node 0's one DOF has the pivot q₀ = D̂_dd + h and, with v = Ê e_d,
/// S₁ = D̂ − v vᵀ/q₀, written without cancellation at small λ (X̂ = D̂ − Ê → 0):
///
/// ```text
///   S₁[dd] = (D̂_dd h + X̂_dd (D̂_dd + Ê_dd))/q₀
///   S₁[dp] = (D̂_dp h + D̂_dp X̂_dd + Ê_dd X̂_dp)/q₀
///   S₁[pp] = D̂_pp − Ê_dp²/q₀
///   dS₁ = dD̂ − (dv vᵀ + v dvᵀ)/q₀ + v vᵀ dq₀/q₀²,   dq₀ = dD̂_dd + dh
/// ```
///
/// (at λ = 0, S₁[dd] = k h/(k + h): the series spring). The count adds the hidden cable's
/// and [q₀ < 0] (Wittrick–Williams).
#[inline]
pub(super) fn junction_start(a: De, t: De, j: &Junction) -> ([f64; 3], [f64; 3], u32) {
    let [c, s] = j.dir;
    let dm = rotate([a.d, 0.0, t.d], c, s);
    let em = rotate([a.e, 0.0, t.e], c, s);
    let xm = rotate([a.x, 0.0, t.x], c, s);
    let ddm = rotate([a.dd, 0.0, t.dd], c, s);
    let dem = rotate([a.de, 0.0, t.de], c, s);
    let q = nonzero(dm[0] + j.h, dm[0].abs() + j.h.abs());
    let below = j.below + (q < 0.0) as u32;
    let r = 1.0 / q;
    let dq = ddm[0] + j.dh;
    let (v0, v1) = (em[0], em[1]);
    let sm = [
        (dm[0] * j.h + xm[0] * (dm[0] + em[0])) * r,
        (dm[1] * j.h + dm[1] * xm[0] + em[0] * xm[1]) * r,
        dm[2] - v1 * v1 * r,
    ];
    let r2 = dq * r * r;
    let dsm = [
        ddm[0] - 2.0 * dem[0] * v0 * r + v0 * v0 * r2,
        ddm[1] - (dem[1] * v0 + v1 * dem[0]) * r + v0 * v1 * r2,
        ddm[2] - 2.0 * dem[1] * v1 * r + v1 * v1 * r2,
    ];
    (rotate(sm, c, -s), rotate(dsm, c, -s), below)
}
