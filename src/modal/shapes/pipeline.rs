//! The one mode-shape pipeline over a model's bordered system (`bordered`), with the
//! repairs of a cluster that is not one clean eigenvalue, the same for every model (the
//! module docs):
//!
//! 1. two modes given apart by at most `MERGE_REL` (1e-9) whose bordered system has no
//!    clean null space of its own multiplicity at either λ are one cluster (the count's
//!    bisection can split an exact double by its rounding);
//! 2. a cluster given as one that is not one eigenvalue (modes 1e-10 apart given together)
//!    is split by the count from its λ to 1e-8 above (`count::split_cluster`), each part's
//!    shapes taken;
//! 3. a cluster still not separated from a given neighbour is a near-cluster (`near`):
//!    below the null space's resolution taken with its neighbours as one cluster at their
//!    mean λ under the count's certificate, else resolved with them member by member; the
//!    neighbours' shapes given already are replaced.

use super::bordered::{push_cluster, solve, Bordered, MERGE_REL};
use super::count::split_cluster;
use super::near;
use super::{ModeShapes, ShapeError, ShapeParams, MAX_MULTIPLICITY};

/// The mass-normalised mode shapes of `sys` at the eigenvalues `modes` = (λ in rad²/s²,
/// multiplicity), appended to `out`: for each, `multiplicity` shapes, M-orthonormal,
/// ordered by descending end-effector participation, with the repairs of the module docs.
pub(in crate::modal) fn mode_shapes<B: Bordered>(
    sys: &mut B,
    modes: &[(f64, u32)],
    params: &ShapeParams,
    out: &mut ModeShapes,
) -> Result<(), ShapeError> {
    for &(lambda, m) in modes {
        if !(lambda.is_finite() && lambda > 0.0) || m == 0 || m > MAX_MULTIPLICITY {
            return Err(ShapeError::BadMode {
                lambda,
                multiplicity: m,
            });
        }
    }
    // The index in `out.modes` where each given mode's shapes start.
    let mut starts = vec![0; modes.len()];
    let mut next_mode = 0;
    while next_mode < modes.len() {
        let first_mode = next_mode;
        starts[next_mode] = out.modes.len();
        let (mut lambda, mut m) = modes[next_mode];
        next_mode += 1;
        let mut got = solve(sys, lambda, m, params);
        // 1. Two modes given apart that are one.
        while let Err(ShapeError::NotAnEigenvalue { .. }) = got {
            match modes.get(next_mode) {
                Some(&(ln, mn))
                    if (ln - lambda).abs() <= MERGE_REL * lambda && m + mn <= MAX_MULTIPLICITY =>
                {
                    lambda = (lambda * m as f64 + ln * mn as f64) / (m + mn) as f64;
                    m += mn;
                    starts[next_mode] = out.modes.len();
                    next_mode += 1;
                    got = solve(sys, lambda, m, params);
                }
                _ => break,
            }
        }
        let e = match got {
            Ok((at, null)) => {
                push_cluster(sys, &at, &null, lambda, m, out);
                continue;
            }
            Err(e @ ShapeError::NotAnEigenvalue { .. }) => e,
            Err(e) => return Err(e),
        };
        // 2. One cluster given that is several eigenvalues: split by the count.
        if m > 1 {
            let mut count = |x: f64| sys.count(x);
            if let Some(parts) = split_cluster(&mut count, lambda, m, params) {
                let solved: Result<Vec<_>, _> = parts
                    .iter()
                    .map(|&(l, k)| solve(sys, l, k, params).map(|s| (s, l, k)))
                    .collect();
                if let Ok(solved) = solved {
                    for ((at, null), l, k) in solved {
                        push_cluster(sys, &at, &null, l, k, out);
                    }
                    continue;
                }
            }
        }
        // 3. Not separated from a given neighbour: a near-cluster (`near`), the
        // neighbours' shapes given already replaced.
        if let Some((group, at, null, mean, total)) =
            near::merged(sys, modes, (first_mode, next_mode), params)
        {
            out.modes.truncate(starts[group.start]);
            starts[group.clone()].fill(out.modes.len());
            push_cluster(sys, &at, &null, mean, total, out);
            next_mode = group.end;
            continue;
        }
        let (group, shapes) =
            near::near_cluster(sys, modes, &starts, (first_mode, next_mode), params).ok_or(e)?;
        out.modes.truncate(starts[group.start]);
        // Each given mode's shapes start at its member's first.
        let mut at = out.modes.len();
        for j in group.clone() {
            starts[j] = shapes[at - out.modes.len()].cluster_start;
            at += modes[j].1 as usize;
        }
        out.modes.extend(shapes);
        next_mode = group.end;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    //! The pipeline's repairs on a toy model whose eigen-decomposition is known exactly:
    //! no chains, K = Q diag(λ_k) Qᵀ and M = I at the "end-effector" (dim 6), so the bordered
    //! matrix is K − λI, its eigenvectors Q's columns, its count #{λ_k < λ}.
    use super::*;
    use crate::modal::shapes::bordered::Nodes;
    use crate::modal::shapes::ModeShape;
    use nalgebra::Matrix6;
    use nalgebra::{DMatrix, DVector};

    struct Toy {
        k: Matrix6<f64>,
        lambdas: [f64; 6],
        q: Matrix6<f64>,
    }

    impl Toy {
        fn new(lambdas: [f64; 6]) -> Toy {
            // A fixed orthogonal Q (QR of a fixed full matrix), so no eigenvector is a
            // coordinate axis.
            let a = Matrix6::from_fn(|r, c| {
                ((r * 7 + c * 3) % 11) as f64 + (r == c) as u8 as f64 * 5.0
            });
            let q = a.qr().q();
            let k = q * Matrix6::from_diagonal(&lambdas.into()) * q.transpose();
            Toy { k, lambdas, q }
        }
    }

    impl Bordered for Toy {
        type At = ();
        type Vector = ();
        fn dim(&self) -> usize {
            6
        }
        fn ee_mass(&self) -> Matrix6<f64> {
            Matrix6::identity()
        }
        fn at(&mut self, _: f64) {}
        fn matrix(&self, _: &(), lambda: f64) -> DMatrix<f64> {
            let a = self.k - Matrix6::identity() * lambda;
            DMatrix::from_fn(6, 6, |r, c| a[(r, c)])
        }
        fn vector(&self, _: &(), _: &DVector<f64>) {}
        fn cable_mass(&self, _: &(), _: &(), _: &(), _: &(), _: bool) -> Option<f64> {
            Some(0.0)
        }
        fn nodes(&self, _: &(), _: &()) -> Nodes {
            (Vec::new(), Vec::new())
        }
        fn count(&mut self, lambda: f64) -> u32 {
            self.lambdas.iter().filter(|&&l| l < lambda).count() as u32
        }
    }

    /// |cos| of the angle between shape `s`'s end-effector part and eigenvector k.
    fn alignment(toy: &Toy, s: &ModeShape, k: usize) -> f64 {
        (s.ee.dot(&toy.q.column(k)) / s.ee.norm()).abs()
    }

    fn run(toy: &mut Toy, modes: &[(f64, u32)]) -> Result<ModeShapes, ShapeError> {
        let mut out = ModeShapes {
            dim: 6,
            ..ModeShapes::default()
        };
        mode_shapes(toy, modes, &ShapeParams::default(), &mut out).map(|_| out)
    }

    #[test]
    fn a_cluster_given_as_one_that_is_several_is_split_by_the_count() {
        // Three eigenvalues 1e-9 apart given as one double: σ₂/σ₃ = 1/2 at λ = 1, not a
        // clean double; the count splits it into 1 and 1 + 1e-9, each clean.
        let mut toy = Toy::new([1.0, 1.0 + 1e-9, 1.0 + 2e-9, 2.0, 3.0, 4.0]);
        let out = run(&mut toy, &[(1.0, 2)]).unwrap();
        assert_eq!(out.modes.len(), 2);
        for (k, s) in out.modes.iter().enumerate() {
            assert_eq!(s.multiplicity, 1);
            // λ from the count's bisection to ~4ε; the shape within the separation σ₁/σ₂
            // (≤ 1e-6 here) of the exact eigenvector.
            assert!((s.lambda - toy.lambdas[k]).abs() <= 1e-14, "{}", s.lambda);
            assert!(1.0 - alignment(&toy, s, k) <= 1e-6, "{k}");
            // Mass-normalised: φᵀMφ = 1 (M = I).
            assert!((s.ee.norm() - 1.0).abs() <= 1e-12);
        }
    }

    #[test]
    fn a_near_cluster_is_resolved_with_its_neighbour() {
        // Two modes 2e-6 apart, each given 1e-8 off: alone, σ₁/σ₂ ≈ 5e-3 > the 1e-3
        // tolerance at either λ; together (σ₂/σ₃ ≈ 2e-6) separated, and each member's own
        // smallest singular vector is its eigenvector to ~1e-8/2e-6.
        let mut toy = Toy::new([1.0, 1.0 + 2e-6, 2.0, 3.0, 4.0, 5.0]);
        let given = [(1.0 + 1e-8, 1), (1.0 + 2e-6 - 1e-8, 1), (2.0, 1)];
        let out = run(&mut toy, &given).unwrap();
        assert_eq!(out.modes.len(), 3);
        for (k, s) in out.modes.iter().enumerate() {
            assert_eq!(s.lambda, given[k].0, "each member keeps its λ");
            assert!(1.0 - alignment(&toy, s, k) <= 1e-4, "{k}");
            assert!((s.ee.norm() - 1.0).abs() <= 1e-12);
        }
        // M-orthogonal after the symmetric orthonormalisation.
        assert!(out.modes[0].ee.dot(&out.modes[1].ee).abs() <= 1e-12);
        // Without the repair the first mode alone is refused.
        let alone = run(&mut toy, &given[..1]);
        assert!(matches!(alone, Err(ShapeError::NotAnEigenvalue { .. })));
    }

    #[test]
    fn a_near_cluster_below_the_resolution_is_one_cluster_at_its_mean() {
        // Three eigenvalues 2e-8 apart (above the 1e-9 of a plain merge), each given 5e-11
        // off (inside the count's 1e-10 window, as rounding leaves a source's λ): alone
        // σ₁/σ₂ ≈ 2.5e-3 > the 1e-3 tolerance; the count certifies exactly three in the
        // group's span, and at the mean the triple's null space is separated (σ₃/σ₄ ≈
        // 2e-8). Expected: one cluster of 3 at the mean spanning the three eigenvectors,
        // the neighbour at 2 on its own.
        let exact = [1.0, 1.0 + 2e-8, 1.0 + 4e-8, 2.0, 3.0, 4.0];
        let mut toy = Toy::new(exact);
        let given = [
            (1.0 + 5e-11, 1),
            (1.0 + 2e-8 - 5e-11, 1),
            (1.0 + 4e-8 + 5e-11, 1),
            (2.0, 1),
        ];
        let alone = solve(&mut toy, given[0].0, 1, &ShapeParams::default());
        assert!(matches!(alone, Err(ShapeError::NotAnEigenvalue { .. })));
        let out = run(&mut toy, &given).unwrap();
        assert_eq!(out.modes.len(), 4);
        let mean = given[..3].iter().map(|g| g.0).sum::<f64>() / 3.0;
        for s in &out.modes[..3] {
            assert_eq!((s.multiplicity, s.cluster_start), (3, 0));
            assert_eq!(s.lambda, mean);
            // Within the triple's eigenspace (Q's first three columns) to the separation
            // σ₃/σ₄ ≈ 2e-8 (squared in the projection).
            let p: f64 = (0..3).map(|k| alignment(&toy, s, k).powi(2)).sum();
            assert!((p - 1.0).abs() <= 1e-9, "{p}");
            assert!((s.ee.norm() - 1.0).abs() <= 1e-12);
        }
        assert_eq!(out.modes[3].multiplicity, 1);
        assert!(1.0 - alignment(&toy, &out.modes[3], 3) <= 1e-12);
        // A group whose span holds more modes than given (the middle one left out) is
        // not merged: the count finds three there, the group has two.
        let short = [given[0], given[2], given[3]];
        let got = run(&mut toy, &short);
        assert!(
            got.as_ref()
                .map_or(true, |o| o.modes.iter().all(|s| s.multiplicity == 1)),
            "{got:?}"
        );
    }

    #[test]
    fn modes_given_apart_that_are_one_are_merged() {
        // An exact double given as two modes 1e-12 apart (a count's rounding): neither
        // alone has a clean 1-dimensional null space; merged, the double's.
        let mut toy = Toy::new([1.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        let out = run(&mut toy, &[(1.0, 1), (1.0 + 1e-12, 1)]).unwrap();
        assert_eq!(out.modes.len(), 2);
        assert!(out.modes.iter().all(|s| s.multiplicity == 2));
        // The pair spans the double's eigenspace: projections onto Q's first two columns.
        for s in &out.modes {
            let p = alignment(&toy, s, 0).powi(2) + alignment(&toy, s, 1).powi(2);
            assert!((p - 1.0).abs() <= 1e-9, "{p}");
        }
    }
}
