//! The lowest eigenvalues and their multiplicities by bisection on the Wittrick-Williams
//! count ([`Solver::eigen_clusters`](crate::modal::Solver::eigen_clusters); offline: the
//! shapes' input when no other eigenvalue source is at hand), and a cluster that is not
//! one eigenvalue split by the count.

use super::{ShapeError, ShapeParams};

/// A cluster that is not one eigenvalue is resolved by the count from [`SPLIT_BELOW`]
/// below the λ given (its lowest member, to the eigenvalue source's accuracy ≲ 1e-12) ...
const SPLIT_BELOW: f64 = 1e-12;
/// ... to this relative distance above it (wider than any cluster probe, ≲ 1e-10).
const SPLIT_WINDOW: f64 = 1e-8;
/// The first upper bound tried, rad²/s²; it grows by [`GROWTH`] until enough eigenvalues
/// are below it ...
const START_HI: f64 = 1.0;
/// ... by this factor ...
const GROWTH: f64 = 4.0;
/// ... at most this many times (4⁶⁰⁰ covers any finite λ).
const GROWTH_STEPS: usize = 600;

/// The eigenvalues (λ, multiplicity) by the count from `lambda` (its cluster's lowest
/// member) to [`SPLIT_WINDOW`] above it, ascending, until they hold `m` modes; `None` when
/// the window holds fewer.
pub(super) fn split_cluster(
    count: &mut impl FnMut(f64) -> u32,
    lambda: f64,
    m: u32,
    params: &ShapeParams,
) -> Option<Vec<(f64, u32)>> {
    let (lo, hi) = (lambda * (1.0 - SPLIT_BELOW), lambda * (1.0 + SPLIT_WINDOW));
    let found0 = count(lo) as usize;
    if (count(hi) as usize) < found0 + m as usize {
        return None;
    }
    clusters_between(count, lo, hi, found0, found0 + m as usize, params).ok()
}

/// The lowest eigenvalues of the problem whose count of eigenvalues strictly below λ is
/// `count(λ)`, as clusters (λ in rad²/s², multiplicity), ascending, until at least `k`
/// modes are covered: each cluster's λ is the bisection limit of the count to a relative
/// width of 4ε, modes within [`ShapeParams::cluster_rel`] (relative) of it form its
/// cluster.
pub(in crate::modal) fn clusters_by_count(
    mut count: impl FnMut(f64) -> u32,
    k: usize,
    params: &ShapeParams,
) -> Result<Vec<(f64, u32)>, ShapeError> {
    params.check()?;
    if k == 0 {
        return Ok(Vec::new());
    }
    let mut hi = START_HI;
    let mut steps = 0;
    while (count(hi) as usize) < k {
        hi *= GROWTH;
        steps += 1;
        if steps > GROWTH_STEPS || !hi.is_finite() {
            return Err(ShapeError::BadParams("no finite bound holds k eigenvalues"));
        }
    }
    clusters_between(&mut count, 0.0, hi, 0, k, params)
}

/// The eigenvalues in (lo, hi] above the `found` ones at or below lo, as clusters (λ,
/// multiplicity) ascending, until `until` modes are covered: each λ the bisection limit of
/// the count, the modes within [`ShapeParams::cluster_rel`] (relative) of it its cluster.
fn clusters_between(
    count: &mut impl FnMut(f64) -> u32,
    mut lo: f64,
    hi: f64,
    mut found: usize,
    until: usize,
    params: &ShapeParams,
) -> Result<Vec<(f64, u32)>, ShapeError> {
    let mut out = Vec::new();
    while found < until {
        let lambda = bisect_next(count, lo, hi, found, params)?;
        let above = lambda * (1.0 + params.cluster_rel);
        let m = (count(above) as usize).saturating_sub(found).max(1);
        out.push((lambda, m as u32));
        found += m;
        lo = above;
    }
    Ok(out)
}

/// The smallest λ in (lo, hi] with more than `found` modes at or below it, by bisection on
/// `count`.
fn bisect_next(
    count: &mut impl FnMut(f64) -> u32,
    mut lo: f64,
    mut hi: f64,
    found: usize,
    params: &ShapeParams,
) -> Result<f64, ShapeError> {
    for _ in 0..params.max_bisections {
        if hi - lo <= 4.0 * f64::EPSILON * hi {
            return Ok(0.5 * (lo + hi));
        }
        let mid = 0.5 * (lo + hi);
        if (count(mid) as usize) > found {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Err(crate::modal::ModalError::NoConvergence {
        evaluations: params.max_bisections,
        lo,
        hi,
    }
    .into())
}
