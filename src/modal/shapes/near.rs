//! The near-cluster repairs of the mode-shape pipeline (`pipeline`, the `shapes` module
//! docs): a given mode whose bordered system has no clean null space of its multiplicity,
//! not one eigenvalue merged with a neighbour nor a cluster the count splits, is taken
//! with its nearest given neighbours, the same for every model:
//!
//! 1. **below the null space's resolution** ([`merged`]): grown across gaps of at most
//!    [`NEAR_MERGE_REL`] (relative) until the count certifies that the group's span holds
//!    exactly its summed multiplicity M (one count [`NEAR_SPAN_MARGIN`] below its lowest
//!    member, one as far above its highest) and the bordered system at the group's
//!    multiplicity-weighted mean λ has a separated M-dimensional null space: its shapes are
//!    the cluster's, at the mean (each member's frequency within half of
//!    [`NEAR_MERGE_REL`]). The chains' rounding can keep each member's σ_m near 1e-12 and
//!    its neighbours' near 1e-9 (the paper robot's end-effector triplet 4e-9 apart at
//!    N = 10⁵): no member's own null vectors are its eigenvector there.
//! 2. **resolved member by member** ([`near_cluster`], [`resolve_near`]): grown by the
//!    nearest neighbours within [`NEAR_MAX_REL`] until, at each member's λ, the member's
//!    own m smallest singular vectors are separated from all but the cluster's other M − m
//!    (σ_m/σ_{M+1} ≤ the tolerance). Those vectors (each a chain solution at its own λ)
//!    are M-orthonormalised together by the symmetric orthonormalisation (the least change
//!    to each; refused when the normalised Gram matrix has an eigenvalue below
//!    [`NEAR_GRAM_MIN`], i.e. two members gave nearly one vector), each member keeping its
//!    λ. It needs the mass form of two chain solutions at different λ, which a model gives
//!    where it is exact ([`Bordered::cable_mass`]): a near-double 2e-6 … 5e-6 apart on the
//!    symmetric paper robot with sag.
//!
//! The first is tried first: where it applies the members are one eigenvalue to the
//! model's resolution. Isolated clusters never take either path.

use super::bordered::{ee_of, null_within, orthonormalise, Bordered, NullSpace, MERGE_REL};
use super::{ModeShape, ShapeParams, MAX_MULTIPLICITY};
use crate::modal::lambda_to_hz;
use nalgebra::{DMatrix, DVector, SymmetricEigen, Vector3, Vector6};
use std::ops::Range;

/// A near-cluster below the null space's resolution grows across gaps between given modes
/// up to this, relative: its members' frequencies are then given at their mean, within
/// half of it.
pub(super) const NEAR_MERGE_REL: f64 = 1e-6;

/// The count's window around such a near-cluster's span, relative (above the eigenvalue
/// sources' ≲ 1e-12, below [`NEAR_MERGE_REL`]).
const NEAR_SPAN_MARGIN: f64 = 1e-10;

/// Largest relative distance of a neighbour taken into a near-cluster resolved member by
/// member: modes farther apart are separated by the bordered system's singular values at
/// every pose met (the near-doubles of the symmetric paper robot with sag are ~5e-6 apart).
const NEAR_MAX_REL: f64 = 1e-3;

/// Smallest eigenvalue of a near-cluster's normalised mass Gram matrix: below it, two
/// members' shapes are close to one vector (not two modes) and the cluster is refused.
const NEAR_GRAM_MIN: f64 = 0.5;

/// The clusters `modes` (ascending λ) in runs whose neighbours are within the reach of a
/// near-cluster below the null space's resolution (the pipeline merges one only with modes
/// given in the same call): what a caller that asks for shapes a few clusters at a time
/// keeps together.
pub fn near_runs(modes: &[(f64, u32)]) -> Vec<Range<usize>> {
    let mut runs = Vec::new();
    let mut start = 0;
    for i in 1..=modes.len() {
        if i == modes.len() || (modes[i].0 - modes[i - 1].0) > NEAR_MERGE_REL * modes[i].0 {
            runs.push(start..i);
            start = i;
        }
    }
    runs
}

/// The given modes `lo..hi` grown by their nearest given neighbour within `max_rel`
/// (relative to the upper of the two): the new range, or `None` when no neighbour is that
/// near or the group's multiplicity would pass [`MAX_MULTIPLICITY`].
fn grow(modes: &[(f64, u32)], (lo, hi): (usize, usize), max_rel: f64) -> Option<(usize, usize)> {
    let gap = |a: f64, b: f64| (b - a) / b;
    let below = (lo > 0)
        .then(|| gap(modes[lo - 1].0, modes[lo].0))
        .filter(|&g| g <= max_rel);
    let above = modes
        .get(hi)
        .map(|&(l, _)| gap(modes[hi - 1].0, l))
        .filter(|&g| g <= max_rel);
    let grown = match (below, above) {
        (Some(b), Some(a)) if b <= a => (lo - 1, hi),
        (Some(_), None) => (lo - 1, hi),
        (_, Some(_)) => (lo, hi + 1),
        (None, None) => return None,
    };
    let total: u32 = modes[grown.0..grown.1].iter().map(|x| x.1).sum();
    (total <= MAX_MULTIPLICITY).then_some(grown)
}

/// A near-cluster below the null space's resolution around the given modes `range`
/// (module docs, 1): the group's range, the chains' solutions and null space at its mean
/// λ, the mean and the certified multiplicity; `None` when no group within
/// [`NEAR_MERGE_REL`] passes the count and the null space's test.
#[allow(clippy::type_complexity)]
pub(super) fn merged<B: Bordered>(
    sys: &mut B,
    modes: &[(f64, u32)],
    mut range: (usize, usize),
    params: &ShapeParams,
) -> Option<(Range<usize>, B::At, NullSpace, f64, u32)> {
    loop {
        range = grow(modes, range, NEAR_MERGE_REL)?;
        let group = &modes[range.0..range.1];
        let total: u32 = group.iter().map(|x| x.1).sum();
        // The count certificate: exactly `total` eigenvalues in the group's span.
        let (first, last) = (group[0].0, group[group.len() - 1].0);
        let below_span = sys.count(first * (1.0 - NEAR_SPAN_MARGIN));
        let in_span = sys
            .count(last * (1.0 + NEAR_SPAN_MARGIN))
            .saturating_sub(below_span);
        if in_span != total {
            continue;
        }
        let mean = group.iter().map(|&(l, m)| l * m as f64).sum::<f64>() / total as f64;
        let at = sys.at(mean);
        let a = sys.matrix(&at, mean);
        if let Ok(null) = null_within(a, total as usize, total as usize, mean, params) {
            return Some((range.0..range.1, at, null, mean, total));
        }
    }
}

/// The given modes `range` grown by their nearest neighbours within [`NEAR_MAX_REL`] until
/// [`resolve_near`] resolves them (module docs, 2), the first shape at `starts[lo]`: the
/// group's range and shapes, or `None` when no neighbour is left to take.
pub(super) fn near_cluster<B: Bordered>(
    sys: &mut B,
    modes: &[(f64, u32)],
    starts: &[usize],
    mut range: (usize, usize),
    params: &ShapeParams,
) -> Option<(Range<usize>, Vec<ModeShape>)> {
    loop {
        range = grow(modes, range, NEAR_MAX_REL)?;
        let (lo, hi) = range;
        if let Some(shapes) = resolve_near(sys, &modes[lo..hi], starts[lo], params) {
            return Some((lo..hi, shapes));
        }
    }
}

/// One null vector of a near-cluster's member (at the member's λ).
struct NearVector<V> {
    member: usize,
    phi: Vector6<f64>,
    parts: V,
}

/// The shapes of a near-cluster `group` (module docs), the first at index `start` of the
/// output: at each member's λ the smallest singular vectors of its own multiplicity, taken
/// only where the cluster's whole multiplicity M is separated (σ_M/σ_{M+1} ≤
/// [`ShapeParams::null_tol`]); then M-orthonormalised together (symmetric
/// orthonormalisation, the least change to each), each member keeping its λ. `None` when a
/// member's test fails, the model has no mass form across two λ, or two members' vectors
/// are close to one (normalised Gram eigenvalue below [`NEAR_GRAM_MIN`]).
pub(super) fn resolve_near<B: Bordered>(
    sys: &mut B,
    group: &[(f64, u32)],
    start: usize,
    params: &ShapeParams,
) -> Option<Vec<ModeShape>> {
    let dim = sys.dim();
    let m6 = sys.ee_mass();
    // Members: the given modes, those within MERGE_REL as one.
    let mut members: Vec<(f64, u32)> = Vec::new();
    for &(l, m) in group {
        match members.last_mut() {
            Some(last) if (l - last.0).abs() <= MERGE_REL * last.0 => {
                last.0 = (last.0 * last.1 as f64 + l * m as f64) / (last.1 + m) as f64;
                last.1 += m;
            }
            _ => members.push((l, m)),
        }
    }
    let total: u32 = members.iter().map(|x| x.1).sum();
    let mut ats = Vec::new();
    let mut raw = Vec::new();
    let mut separation = 0.0f64;
    for (p, &(lambda, m)) in members.iter().enumerate() {
        let at = sys.at(lambda);
        let a = sys.matrix(&at, lambda);
        let null = null_within(a, m as usize, total as usize, lambda, params).ok()?;
        separation = separation.max(null.residual);
        for c in 0..m as usize {
            let col = null.vectors.column(c).into_owned();
            raw.push(NearVector {
                member: p,
                phi: ee_of(&col, dim),
                parts: sys.vector(&at, &col),
            });
        }
        ats.push(at);
    }
    let k = raw.len();
    let mut gram = DMatrix::<f64>::zeros(k, k);
    let mut ee = DMatrix::<f64>::zeros(k, k);
    for a in 0..k {
        for b in 0..=a {
            let (ra, rb) = (&raw[a], &raw[b]);
            let own = (ra.phi.transpose() * m6 * rb.phi)[(0, 0)];
            let cab = sys.cable_mass(
                &ats[ra.member],
                &ra.parts,
                &ats[rb.member],
                &rb.parts,
                ra.member == rb.member,
            )?;
            gram[(a, b)] = own + cab;
            gram[(b, a)] = own + cab;
            ee[(a, b)] = own;
            ee[(b, a)] = own;
        }
    }
    // Symmetric orthonormalisation of the unit-M-norm vectors: C = D G̃^{-1/2}.
    let d = DVector::from_iterator(k, (0..k).map(|a| 1.0 / gram[(a, a)].sqrt()));
    let dm = DMatrix::from_diagonal(&d);
    let g = SymmetricEigen::new(&dm * &gram * &dm);
    if !(g.eigenvalues.min() >= NEAR_GRAM_MIN) {
        return None;
    }
    let mut q = g.eigenvectors.clone();
    for (c, &l) in g.eigenvalues.iter().enumerate() {
        q.column_mut(c).scale_mut(1.0 / l.sqrt());
    }
    let coef = &dm * &q * g.eigenvectors.transpose();
    let nodes: Vec<_> = raw
        .iter()
        .map(|r| sys.nodes(&ats[r.member], &r.parts))
        .collect();
    let mut out = Vec::with_capacity(k);
    let mut col0 = 0;
    for &(lambda, m) in &members {
        let cp = coef.columns(col0, m as usize).into_owned();
        col0 += m as usize;
        let gp = cp.transpose() * &gram * &cp;
        let ep = cp.transpose() * &ee * &cp;
        let first = start + out.len();
        for (c, part) in orthonormalise(&cp, gp, &ep) {
            let mut phi = Vector6::zeros();
            let mut cables: Vec<Vec<Vector3<f64>>> = nodes[0]
                .0
                .iter()
                .map(|u| vec![Vector3::zeros(); u.len()])
                .collect();
            let mut hidden: Vec<Vec<f64>> = nodes[0].1.iter().map(|h| vec![0.0; h.len()]).collect();
            for ((r, (src, src_h)), w) in raw.iter().zip(&nodes).zip(c.iter()) {
                phi += r.phi * *w;
                for (dst, s) in cables.iter_mut().zip(src) {
                    for (x, y) in dst.iter_mut().zip(s) {
                        *x += y * *w;
                    }
                }
                for (dst, s) in hidden.iter_mut().zip(src_h) {
                    for (x, y) in dst.iter_mut().zip(s) {
                        *x += y * *w;
                    }
                }
            }
            out.push(ModeShape {
                lambda,
                frequency_hz: lambda_to_hz(lambda),
                ee: phi,
                cables,
                hidden,
                ee_participation: part,
                cluster_start: first,
                multiplicity: m,
                null_residual: separation,
            });
        }
    }
    Some(out)
}
