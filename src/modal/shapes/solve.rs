//! [`ModalSolver::mode_shapes`]: the bordered system at each eigenvalue, its null space, the
//! M-orthonormalisation within a cluster and the node displacements (see the module docs).

use super::chain_shape::ChainShape;
use super::{ModeShape, ModeShapes, ShapeError, ShapeParams, MAX_MULTIPLICITY};
use crate::cable::{CableModel, ChainKind};
use crate::eig3::eig3_jacobi;
use crate::kinematics::attach_map;
use crate::modal::{lambda_to_hz, ModalSolver};
use nalgebra::{DMatrix, DVector, Matrix3x6, SymmetricEigen, Vector3, Vector6};

/// A near-cluster (module docs) grows across gaps between given modes up to this,
/// relative: its members' frequencies are then given at their mean, within half of it.
pub(super) const NEAR_MERGE_REL: f64 = 1e-6;
/// The count's window around a near-cluster's span, relative (above the eigenvalue
/// sources' ≲ 1e-12, below [`NEAR_MERGE_REL`]).
const NEAR_SPAN_MARGIN: f64 = 1e-10;
/// A projector eigenvalue above this is in its range (they are 0 or 1 to rounding).
const PROJ_RANGE_MIN: f64 = 0.5;
/// Sweeps of Ruiz equilibration (each halves the logarithm of every row's and column's
/// imbalance: 30 sweeps bring a 1e30 spread to within a factor 1 + 1e-7).
const RUIZ_SWEEPS: usize = 30;

/// One chain copy: a direction of one chain of one cable.
#[derive(Debug, Clone)]
pub(super) struct ChainCopy {
    /// The chain's index in [`Layout::kinds`].
    pub(super) chain: usize,
    /// Unit direction of the copy (world frame).
    dir: Vector3<f64>,
    /// End direction on the end-effector's coordinates, G_iᵀ dir.
    pub(super) b: Vector6<f64>,
}

/// How the models' chains attach, independent of λ.
#[derive(Debug, Clone)]
pub(super) struct Layout {
    /// Each active chain's kind.
    pub(super) kinds: Vec<ChainKind>,
    /// Every chain copy.
    pub(super) copies: Vec<ChainCopy>,
    /// Per cable: its copies' indices, its attachment map and whether it is continuous.
    cable_copies: Vec<Vec<usize>>,
    attach: Vec<Matrix3x6<f64>>,
    pub(super) fractions: Vec<Vec<f64>>,
    /// Per cable: its discrete hidden cable's element mass, kg (0 without one).
    pub(super) hidden_mass_kg: Vec<f64>,
}

impl Layout {
    fn new(
        models: &[CableModel],
        arms_m: Option<&[nalgebra::Vector3<f64>]>,
        samples: usize,
    ) -> Layout {
        let mut l = Layout {
            kinds: Vec::new(),
            copies: Vec::new(),
            cable_copies: Vec::new(),
            attach: Vec::new(),
            fractions: Vec::new(),
            hidden_mass_kg: Vec::new(),
        };
        for (i, m) in models.iter().enumerate() {
            let g = match arms_m {
                Some(arms) => attach_map(&arms[i]),
                None => attach_map(&Vector3::zeros()),
            };
            let mut mine = Vec::new();
            let mut continuous = false;
            let mut hidden_kg = 0.0;
            for c in &m.chains[..m.n_chains] {
                if matches!(c.kind, ChainKind::Discrete { k, m, .. } if k == 0.0 && m == 0.0) {
                    continue; // no stiffness, no mass: loads nothing (as `load` skips it)
                }
                continuous |= matches!(c.kind, ChainKind::Continuous { .. })
                    || matches!(c.kind, ChainKind::Supported { free, .. } if free.n_el == 0);
                if let ChainKind::Supported { hidden, .. } = c.kind {
                    if hidden.n_el > 0 {
                        hidden_kg = hidden.m;
                    }
                }
                let e = eig3_jacobi(&c.proj);
                for r in 0..3 {
                    if e.values[r] > PROJ_RANGE_MIN {
                        let dir = e.vectors[r];
                        mine.push(l.copies.len());
                        l.copies.push(ChainCopy {
                            chain: l.kinds.len(),
                            dir,
                            b: g.transpose() * dir,
                        });
                    }
                }
                l.kinds.push(c.kind);
            }
            let n = if continuous {
                samples - 1
            } else {
                m.n_el.max(1)
            };
            l.fractions
                .push((0..=n).map(|j| j as f64 / n as f64).collect());
            l.cable_copies.push(mine);
            l.attach.push(g);
            l.hidden_mass_kg.push(hidden_kg);
        }
        l
    }
}

impl Layout {
    /// Each cable's element mass between its node list's nodes, kg (its first chain's: all
    /// chains of a cable share the element mass; 0 without chains).
    pub(super) fn element_mass_kg(&self) -> Vec<f64> {
        self.cable_copies
            .iter()
            .zip(&self.fractions)
            .map(
                |(copies, fr)| match copies.first().map(|&q| self.kinds[self.copies[q].chain]) {
                    Some(ChainKind::Discrete { m, .. }) => m,
                    Some(ChainKind::Continuous { m_total, .. }) => {
                        m_total / (fr.len().saturating_sub(1)).max(1) as f64
                    }
                    // A supported chain's free cable: its element mass, or its whole mass
                    // over the sample intervals (continuous).
                    Some(ChainKind::Supported { free, .. }) if free.n_el > 0 => free.m,
                    Some(ChainKind::Supported { free, .. }) => {
                        free.m / (fr.len().saturating_sub(1)).max(1) as f64
                    }
                    _ => 0.0,
                },
            )
            .collect()
    }
}

/// The clusters `modes` (ascending λ) in runs whose neighbours are within the reach of a
/// near-cluster ([`ModalSolver::mode_shapes`] merges a near-cluster only with modes given in
/// the same call): what a caller that asks for shapes a few clusters at a time keeps
/// together.
pub fn near_runs(modes: &[(f64, u32)]) -> Vec<std::ops::Range<usize>> {
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

/// The null space of one cluster before normalisation: columns (φ, C_1 … C_n).
pub(super) struct NullSpace {
    pub(super) vectors: DMatrix<f64>,
    pub(super) residual: f64,
}

impl ModalSolver {
    /// The mass-normalised mode shapes at the eigenvalues `modes` = (λ in rad²/s²,
    /// multiplicity), e.g. from [`Self::eigen_clusters`] or the dense reference: for each,
    /// `multiplicity` shapes, M-orthonormal, ordered by descending end-effector participation.
    ///
    /// The solver must be loaded ([`Self::load`] or [`Self::load_rigid`]) with the same
    /// `models`; `arms_m` are the attachment arms (world frame, m) of a rigid end-effector
    /// (ignored for a point mass). Continuous cables are sampled at
    /// [`ShapeParams::continuous_samples`] points. Allocates; never on the real-time path.
    pub fn mode_shapes(
        &mut self,
        models: &[CableModel],
        arms_m: &[Vector3<f64>],
        modes: &[(f64, u32)],
        params: &ShapeParams,
    ) -> Result<ModeShapes, ShapeError> {
        let layout = self.layout(models, arms_m, params)?;
        let dim = self.problem.dim;
        let mut shapes = vec![ChainShape::default(); layout.kinds.len()];
        let mut out = ModeShapes {
            dim,
            fractions: layout.fractions.clone(),
            modes: Vec::new(),
            element_mass_kg: layout.element_mass_kg(),
            hidden_element_mass_kg: layout.hidden_mass_kg.clone(),
        };
        for &(lambda, m) in modes {
            if !(lambda.is_finite() && lambda > 0.0) || m == 0 || m > MAX_MULTIPLICITY {
                return Err(ShapeError::BadMode {
                    lambda,
                    multiplicity: m,
                });
            }
        }
        // Where each given mode's shapes start in `out.modes`.
        let mut starts = vec![0; modes.len()];
        let mut i = 0;
        while i < modes.len() {
            starts[i] = out.modes.len();
            let (lambda, m) = modes[i];
            let first = self.cluster_shapes(&layout, &mut shapes, (lambda, m), params, &mut out);
            let Err(e @ ShapeError::NotAnEigenvalue { .. }) = first else {
                first?;
                i += 1;
                continue;
            };
            // Not one clean cluster (e.g. modes 1e-10 apart given as one): resolve it by
            // the count and take each part's shapes.
            if let Some(parts) = self.split_cluster(lambda, m, params) {
                let split = parts.into_iter().try_for_each(|part| {
                    self.cluster_shapes(&layout, &mut shapes, part, params, &mut out)
                });
                match split {
                    Ok(()) => {
                        i += 1;
                        continue;
                    }
                    Err(ShapeError::NotAnEigenvalue { .. }) => out.modes.truncate(starts[i]),
                    Err(e) => return Err(e),
                }
            }
            // Not separated from a given neighbour either (a near-cluster): taken with its
            // nearest neighbours as one cluster (module docs).
            let (lo, hi) = self
                .near_cluster(&layout, &mut shapes, modes, &starts, i, params, &mut out)
                .ok_or(e)?;
            debug_assert!(lo <= i && i < hi);
            let first = starts[lo];
            starts[lo..hi].fill(first);
            i = hi;
        }
        Ok(out)
    }

    /// The given modes around `modes[i]` (whose own null space is not separated) grown by
    /// their nearest given neighbours within [`NEAR_MERGE_REL`] until the group, taken as one
    /// cluster at its multiplicity-weighted mean λ with the multiplicity the count
    /// certifies in its span, has a separated null space; its shapes replace those of the
    /// group's members already in `out` (from `starts`). The group's range, or `None`.
    #[allow(clippy::too_many_arguments)]
    fn near_cluster(
        &mut self,
        layout: &Layout,
        shapes: &mut [ChainShape],
        modes: &[(f64, u32)],
        starts: &[usize],
        i: usize,
        params: &ShapeParams,
        out: &mut ModeShapes,
    ) -> Option<(usize, usize)> {
        let (mut lo, mut hi) = (i, i + 1);
        loop {
            let gap = |a: f64, b: f64| (b - a) / b;
            let below = (lo > 0)
                .then(|| gap(modes[lo - 1].0, modes[lo].0))
                .filter(|&g| g <= NEAR_MERGE_REL);
            let above = modes
                .get(hi)
                .map(|&(l, _)| gap(modes[hi - 1].0, l))
                .filter(|&g| g <= NEAR_MERGE_REL);
            match (below, above) {
                (Some(b), Some(a)) if b <= a => lo -= 1,
                (Some(_), None) => lo -= 1,
                (_, Some(_)) => hi += 1,
                (None, None) => return None,
            }
            let group = &modes[lo..hi];
            let total: u32 = group.iter().map(|x| x.1).sum();
            if total > MAX_MULTIPLICITY {
                return None;
            }
            // The count certificate: exactly `total` eigenvalues in the group's span.
            let (first, last) = (group[0].0, group[group.len() - 1].0);
            let below_span = self.count_below(first * (1.0 - NEAR_SPAN_MARGIN));
            let in_span = self
                .count_below(last * (1.0 + NEAR_SPAN_MARGIN))
                .saturating_sub(below_span);
            if in_span != total {
                continue;
            }
            let mean = group.iter().map(|&(l, m)| l * m as f64).sum::<f64>() / total as f64;
            out.modes.truncate(starts[lo]);
            if self
                .cluster_shapes(layout, shapes, (mean, total), params, out)
                .is_ok()
            {
                return Some((lo, hi));
            }
        }
    }

    /// The chains' layout of `models` (the checks of [`Self::mode_shapes`]: parameters,
    /// a rigid body's arms, hidden cables both discrete or both continuous, the models the
    /// solver was loaded with).
    pub(super) fn layout(
        &self,
        models: &[CableModel],
        arms_m: &[Vector3<f64>],
        params: &ShapeParams,
    ) -> Result<Layout, ShapeError> {
        params.check()?;
        let dim = self.problem.dim;
        if dim == 6 && arms_m.len() < models.len() {
            return Err(ShapeError::MissingArms {
                given: arms_m.len(),
                cables: models.len(),
            });
        }
        if models.iter().any(|m| {
            m.chains[..m.n_chains].iter().any(|c| {
                matches!(c.kind, ChainKind::Supported { free, hidden }
                    if (free.n_el == 0) != (hidden.n_el == 0))
            })
        }) {
            return Err(ShapeError::HiddenCable);
        }
        let arms = (dim == 6).then_some(arms_m);
        let layout = Layout::new(models, arms, params.continuous_samples);
        if layout.kinds.len() != self.problem.n_chains {
            return Err(ShapeError::NotLoaded {
                loaded: self.problem.n_chains,
                given: layout.kinds.len(),
            });
        }
        Ok(layout)
    }

    /// The shapes of one cluster (λ, m), appended to `out`.
    fn cluster_shapes(
        &self,
        layout: &Layout,
        shapes: &mut [ChainShape],
        (lambda, m): (f64, u32),
        params: &ShapeParams,
        out: &mut ModeShapes,
    ) -> Result<(), ShapeError> {
        for (sh, kind) in shapes.iter_mut().zip(&layout.kinds) {
            sh.fill(kind, lambda);
        }
        let null = self.null_space(layout, shapes, lambda, m, params)?;
        let v = self.normalise(layout, shapes, &null.vectors);
        let start = out.modes.len();
        for (col, part) in v {
            let (cables, hidden) = nodes(layout, shapes, &col, out.dim);
            out.modes.push(ModeShape {
                lambda,
                frequency_hz: lambda_to_hz(lambda),
                ee: ee_of(&col, out.dim),
                cables,
                hidden,
                ee_participation: part,
                cluster_start: start,
                multiplicity: m,
                null_residual: null.residual,
            });
        }
        Ok(())
    }

    /// The bordered matrix at λ (see the module docs) and its m-dimensional null space.
    fn null_space(
        &self,
        layout: &Layout,
        shapes: &[ChainShape],
        lambda: f64,
        m: u32,
        params: &ShapeParams,
    ) -> Result<NullSpace, ShapeError> {
        let p = &self.problem;
        let d = p.dim;
        let n = d + layout.copies.len();
        let m = m as usize;
        let mut a = DMatrix::<f64>::zeros(n, n);
        for r in 0..d {
            for c in 0..d {
                a[(r, c)] = p.k6[(r, c)] - lambda * p.m6[(r, c)];
            }
        }
        for (q, cp) in layout.copies.iter().enumerate() {
            let sh = &shapes[cp.chain];
            for r in 0..d {
                a[(r, d + q)] = sh.f * cp.b[r];
                a[(d + q, r)] = sh.scale * cp.b[r];
            }
            a[(d + q, d + q)] = -sh.scale * sh.g;
        }
        null_of(a, m, lambda, params)
    }

    /// M-orthonormalise the null vectors (columns) and rotate them to diagonalise the
    /// end-effector's mass; returns the columns with their participations, descending.
    fn normalise(
        &self,
        layout: &Layout,
        shapes: &[ChainShape],
        v: &DMatrix<f64>,
    ) -> Vec<(DVector<f64>, f64)> {
        let m = v.ncols();
        let d = self.problem.dim;
        let m6 = &self.problem.m6;
        let ends: Vec<Vec<f64>> = (0..m)
            .map(|a| {
                layout
                    .copies
                    .iter()
                    .map(|cp| (0..d).map(|r| cp.b[r] * v[(r, a)]).sum())
                    .collect()
            })
            .collect();
        let mut gram = DMatrix::<f64>::zeros(m, m);
        let mut ee = DMatrix::<f64>::zeros(m, m);
        for a in 0..m {
            for b in 0..=a {
                let mut own = 0.0;
                for r in 0..d {
                    for c in 0..d {
                        own += v[(r, a)] * m6[(r, c)] * v[(c, b)];
                    }
                }
                let mut cab = 0.0;
                for (q, cp) in layout.copies.iter().enumerate() {
                    let sh = &shapes[cp.chain];
                    let (ca, cb) = (v[(d + q, a)], v[(d + q, b)]);
                    let (ea, eb) = (ends[a][q], ends[b][q]);
                    cab += ca * cb * sh.m_ii + (ca * eb + ea * cb) * sh.m_ie + ea * eb * sh.m_ee;
                }
                gram[(a, b)] = own + cab;
                gram[(b, a)] = own + cab;
                ee[(a, b)] = own;
                ee[(b, a)] = own;
            }
        }
        orthonormalise(v, gram, &ee)
    }
}

/// M-orthonormalise the null vectors `v` (columns) from their mass Gram matrix `gram`
/// (vᵀMv) and rotate them to diagonalise the end-effector's mass `ee` (φᵀM_eeφ);
/// returns the columns with their participations, descending.
pub(super) fn orthonormalise(
    v: &DMatrix<f64>,
    gram: DMatrix<f64>,
    ee: &DMatrix<f64>,
) -> Vec<(DVector<f64>, f64)> {
    let m = v.ncols();
    // Symmetric orthonormalisation T1 = Q Λ^{-1/2}, then the end-effector's mass in
    // that basis diagonalised (descending).
    let g = SymmetricEigen::new(gram);
    let mut t1 = g.eigenvectors.clone();
    for (c, &l) in g.eigenvalues.iter().enumerate() {
        let s = 1.0 / l.max(f64::MIN_POSITIVE).sqrt();
        t1.column_mut(c).scale_mut(s);
    }
    let e = SymmetricEigen::new(t1.transpose() * ee * &t1);
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&i, &j| e.eigenvalues[j].total_cmp(&e.eigenvalues[i]));
    let t = &t1 * &e.eigenvectors;
    order
        .iter()
        .map(|&c| {
            let mut col = v * t.column(c);
            // Sign: the largest entry positive (a convention; shapes are ± anyway).
            let imax = col.iamax();
            if col[imax] < 0.0 {
                col.neg_mut();
            }
            (col, e.eigenvalues[c].clamp(0.0, 1.0))
        })
        .collect()
}

/// The m-dimensional null space of the bordered matrix `a` at λ (see the module docs):
/// equilibrated, then the right singular vectors of its m smallest singular values,
/// refused unless σ_m/σ_{m+1} ≤ [`ShapeParams::null_tol`].
pub(super) fn null_of(
    a: DMatrix<f64>,
    m: usize,
    lambda: f64,
    params: &ShapeParams,
) -> Result<NullSpace, ShapeError> {
    null_within(a, m, m, lambda, params)
}

/// As [`null_of`], but the m smallest singular vectors need only be separated from those
/// beyond the `within` smallest (`within ≥ m`): σ_m/σ_{within+1} ≤
/// [`ShapeParams::null_tol`] (a near-cluster's member: its vectors may mix with the
/// cluster's other `within − m` directions, resolved by the caller).
pub(super) fn null_within(
    mut a: DMatrix<f64>,
    m: usize,
    within: usize,
    lambda: f64,
    params: &ShapeParams,
) -> Result<NullSpace, ShapeError> {
    let n = a.ncols();
    let bad = |sigma_m, sigma_next| ShapeError::NotAnEigenvalue {
        lambda,
        multiplicity: m as u32,
        sigma_m,
        sigma_next,
    };
    if m > n || within < m {
        return Err(bad(f64::NAN, f64::NAN));
    }
    let col_scale = equilibrate(&mut a);
    let svd =
        nalgebra::linalg::SVD::try_new(a, false, true, f64::EPSILON, params.svd_max_iterations)
            .ok_or(ShapeError::Svd(lambda))?;
    let vt = svd.v_t.ok_or(ShapeError::Svd(lambda))?;
    let s = &svd.singular_values;
    let smax = s.max();
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&i, &j| s[i].total_cmp(&s[j]));
    let sigma_m = s[idx[m - 1]] / smax;
    let sigma_next = if within < n {
        s[idx[within]] / smax
    } else {
        f64::INFINITY
    };
    // The null space is the m-dimensional one only if σ_m is clearly below σ_{m+1}.
    let separation = sigma_m / sigma_next;
    if !(separation <= params.null_tol) {
        return Err(bad(sigma_m, sigma_next));
    }
    let mut vectors = DMatrix::zeros(n, m);
    for (c, &i) in idx[..m].iter().enumerate() {
        let v = vt.row(i).transpose().component_mul(&col_scale);
        vectors.set_column(c, &(&v / v.norm()));
    }
    Ok(NullSpace {
        vectors,
        residual: separation,
    })
}

/// Ruiz equilibration: scale rows and columns of `a` in place until every row and column
/// has largest entry ≈ 1 (the chains' rows range from T/l to EA/l, and the end-effector's
/// from λ·m to the sum of both: unbalanced, the SVD's backward error ε‖A‖ would swamp the
/// small rows). Returns the column scales c: the null vectors of the original matrix are
/// c ∘ (those of the scaled one).
fn equilibrate(a: &mut DMatrix<f64>) -> DVector<f64> {
    let n = a.ncols();
    let mut cs = DVector::from_element(n, 1.0);
    for _ in 0..RUIZ_SWEEPS {
        for r in 0..a.nrows() {
            let mx = a.row(r).amax();
            if mx > 0.0 {
                a.row_mut(r).scale_mut(1.0 / mx.sqrt());
            }
        }
        for c in 0..n {
            let mx = a.column(c).amax();
            if mx > 0.0 {
                let f = 1.0 / mx.sqrt();
                a.column_mut(c).scale_mut(f);
                cs[c] *= f;
            }
        }
    }
    cs
}

/// The end-effector part of a null vector.
fn ee_of(col: &DVector<f64>, dim: usize) -> Vector6<f64> {
    let mut ee = Vector6::zeros();
    for r in 0..dim {
        ee[r] = col[r];
    }
    ee
}

/// Every cable's node displacements of a null vector: C_k w inside, G_i φ at the end; and
/// each hidden cable's (C_k times the supported chain's hidden nodes, empty without one).
pub(super) fn nodes(
    layout: &Layout,
    shapes: &[ChainShape],
    col: &DVector<f64>,
    dim: usize,
) -> (Vec<Vec<Vector3<f64>>>, Vec<Vec<f64>>) {
    let phi = ee_of(col, dim);
    let hidden = layout
        .cable_copies
        .iter()
        .map(|copies| {
            copies
                .iter()
                .find(|&&q| !shapes[layout.copies[q].chain].hidden_w.is_empty())
                .map(|&q| {
                    let amp = col[dim + q];
                    let sh = &shapes[layout.copies[q].chain];
                    sh.hidden_w.iter().map(|w| amp * w).collect()
                })
                .unwrap_or_default()
        })
        .collect();
    let cables = layout
        .cable_copies
        .iter()
        .enumerate()
        .map(|(i, copies)| {
            let fr = &layout.fractions[i];
            let last = fr.len() - 1;
            let mut u = vec![Vector3::zeros(); fr.len()];
            for &q in copies {
                let cp = &layout.copies[q];
                let sh = &shapes[cp.chain];
                let amp = col[dim + q];
                // Node 0 moves only on a hidden cable (the junction at its pulley).
                for (j, uj) in u.iter_mut().enumerate().take(last) {
                    let w = if sh.w.is_empty() {
                        sh.at(fr[j])
                    } else {
                        sh.w[j]
                    };
                    *uj += cp.dir * (amp * w);
                }
            }
            u[last] = layout.attach[i] * phi;
            u
        })
        .collect();
    (cables, hidden)
}
