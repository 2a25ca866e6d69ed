//! Mode shapes of sagging cables ([`SagModalSolver::mode_shapes`]): the bordered system of
//! the module docs with the sagged FEM chains ([`crate::cable::sagged`]) in place of the
//! uniform scalar ones.
//!
//! **One chain at λ.** Cable i's element j has the in-plane stiffness K_j (2 × 2 in
//! (h, up)), the out-of-plane one k_j, and the consistent mass (m/6)[2I I; I 2I]; in the
//! cable's frame (h, up, n) they form the 3 × 3 K_j = diag(K_j^in, k_j). Its interior
//! equations at λ, with the anchor held (u₀ = 0),
//!
//! ```text
//!     −(K_{j−1} + λm/6) u_{j−1} + (K_{j−1} + K_j − 2λm/3) u_j − (K_j + λm/6) u_{j+1} = 0
//! ```
//!
//! for j = 1 … N − 1, are solved forward from u₁ (K_j + λm/6 is positive definite, so
//! u_{j+1} always exists): the three columns Y (u₁ = e_h, e_up, e_n; re-orthonormalised at
//! each element, `sag_chain_shape`) span every interior solution, u_j = Y_j a with a free
//! amplitude a ∈ ℝ³. The end value is Y_N a and the force the chain puts on its end node per unit
//! amplitude F = (K_{N−1} − λm/3) Y_N − (K_{N−1} + λm/6) Y_{N−1}; F Y_N⁻¹ is the chain's
//! condensed stiffness S(λ) = diag(S_in, s_out) (the one D(λ) sums).
//!
//! **Bordered system.** With E_i = [h_i up n_i] and G_i the attachment map (I for a point
//! mass), the unknowns (φ, a_1 … a_n) (dim + 3n of them) satisfy
//!
//! ```text
//!     (K_ee − λ M_ee) φ + Σ_i G_iᵀ E_i F_i a_i = 0
//!     σ_i (E_iᵀ G_i φ − Y_N,i a_i)            = 0     for every cable i
//! ```
//!
//! (σ_i the size of the last element's stiffness plus λm/2). Its null space at an eigenvalue
//! λ of multiplicity m is the eigenspace, including modes with the end-effector still
//! (Y_N,i singular: λ is a blocked eigenvalue of cable i) where D(λ) has a pole. It is taken
//! by the taut shapes' equilibrated SVD with the same separation test
//! ([`ShapeParams::null_tol`]).
//!
//! **Hidden cable** ([`SagChain::set_support`]). Node 0 is the junction at the pulley: it
//! moves along the anchor tangent d (in (h, up)) and is held there by the hidden cable's
//! N_h axial elements (k_h, m_h) from the fixed drum. A fourth solution joins the three:
//! the hidden cable from the drum, t_0 = 0, t_1 = 1, β_h t_{j−1} + 2α_h t_j + β_h t_{j+1} = 0
//! (α_h = k_h − λm_h/3, β_h = −k_h − λm_h/6 < 0), puts the junction at z_0 = d t_{N_h}; with
//! z_1 = 0 the same interior equations give z_2 … z_N (t to largest entry 1; z the fourth
//! column of the re-orthonormalised state). Every solution of the chain and its hidden cable is u_j = Y_j a + z_j c
//! (hidden nodes c t_j): the amplitude c is one more unknown, and the junction's own
//! equation along d one more row,
//!
//! ```text
//!     σ_J (dᵀ(K_0 − λm/3) u_0 + dᵀ(−K_0 − λm/6) u_1 + α_h c t_{N_h} + β_h c t_{N_h−1}) = 0
//! ```
//!
//! (the free cable's first element and the hidden cable's last). The end force and end
//! value gain F_z c and z_N c. The columns c and rows of the junctions come after every
//! a_i and end row, so a robot without hidden cables has the same bordered matrix. The
//! shapes draw node 0 as the junction's motion d c t_{N_h} (world frame) and not the hidden
//! cable's nodes (as the taut hidden-cable shapes); those enter the normalisation:
//! (m_h/6) c_a c_b Σ (2t_j² + 2t_j t_{j+1} + 2t_{j+1}²) over the hidden elements.
//!
//! **Normalisation.** The nodes u_j = Y_j a (interior) and E_iᵀ G_i φ (end) of each null
//! vector give the consistent mass's quadratic form exactly (Σ over the elements of
//! (m/6)(2u_j·v_j + u_j·v_{j+1} + u_{j+1}·v_j + 2u_{j+1}·v_{j+1}), plus φᵀM_eeφ: the dense
//! M's, with the hidden cables' term above); a cluster is M-orthonormalised and rotated as
//! the taut shapes are. Two modes given apart by at most `MERGE_REL` (1e-9 relative) whose bordered
//! system at either λ has no clean null space of its own multiplicity are taken as one
//! cluster (the count's bisection can split an exact double by its rounding).
//!
//! **Near-clusters.** A cluster still not separated (its σ_m/σ_{m+1} above the tolerance:
//! a near-double 2e-6 … 5e-6 apart on the symmetric paper robot with sag) is grown by its
//! nearest given neighbours within `NEAR_MAX_REL` (1e-3 relative) until, at each member's
//! λ, the member's own m smallest singular vectors are separated from all but the
//! cluster's other M − m (σ_m/σ_{M+1} ≤ the tolerance, M the cluster's total). Those
//! vectors (each a chain solution at its own λ) are M-orthonormalised together by the
//! symmetric orthonormalisation (the least change to each; refused when the normalised
//! Gram matrix has an eigenvalue below 0.5, i.e. two members gave nearly one vector), each
//! member keeping its λ; shapes already given for a member are replaced. Isolated clusters
//! never take this path.
//!
//! **Accuracy.** The forward solution is exact in exact arithmetic. Above a chain's
//! transverse cut-off the transverse solution grows like sinh(jφ) along it, and solved
//! alone every column turns towards it, the axial one lost in their rounding; the state of
//! the solutions at two neighbouring nodes is therefore re-orthonormalised after each step
//! (`sag_chain_shape`: the same span, kept well conditioned; the amplitudes a are those of
//! the end's basis). The dense eigenvectors are the check (`tests/sag/shapes.rs`, with and
//! without hidden cables; cli/tests/cli/hidden_sag.rs, the frequency response of the large
//! robots above their cut-off against the dense modal sum). Offline: allocates.

use super::count::clusters_by_count;
use super::sag_chain_shape::SagChainShape;
use super::solve::{null_of, null_within, orthonormalise};
use super::{ModeShape, ModeShapes, ShapeError, ShapeParams, MAX_MULTIPLICITY};
use crate::kinematics::attach_map;
use crate::modal::lambda_to_hz;
use crate::modal::sagged::SagModalSolver;
use nalgebra::{
    DMatrix, DVector, Matrix3, Matrix3x6, Matrix6, SymmetricEigen, Vector3, Vector4, Vector6,
};

/// Largest relative distance of two modes given apart that are taken as one cluster when
/// neither alone is a clean null space of the bordered system (the count's bisection
/// resolves λ to ~ε·λ_max/λ; modes this close are one eigenvalue to the f64 model's
/// accuracy).
const MERGE_REL: f64 = 1e-9;

/// Largest relative distance of a neighbour taken into a near-cluster (module docs): modes
/// farther apart are separated by the bordered system's singular values at every pose met
/// (the near-doubles of the symmetric paper robot with sag are ~5e-6 apart).
const NEAR_MAX_REL: f64 = 1e-3;

/// Smallest eigenvalue of a near-cluster's normalised mass Gram matrix: below it, two
/// members' shapes are close to one vector (not two modes) and the cluster is refused.
const NEAR_GRAM_MIN: f64 = 0.5;

/// How one loaded cable attaches: its frame E = [h up n] and attachment map (3 × dim).
pub(super) struct Attach {
    pub(super) frame: Matrix3<f64>,
    pub(super) map: Matrix3x6<f64>,
}

impl SagModalSolver {
    /// The lowest clusters of the loaded pose, (λ in rad²/s², multiplicity), ascending,
    /// until at least `k` modes are covered (a cluster cut by `k` completed): bisection on
    /// the Wittrick–Williams count ([`Self::count_below`]) to a relative width of 4ε (at most
    /// every mode of the model: `k` is capped at [`Self::total_modes`]), modes
    /// within [`ShapeParams::cluster_rel`] of each other grouped (as
    /// [`crate::modal::ModalSolver::eigen_clusters`]). The count is exact at and next to
    /// the chains' poles, where modes with the end-effector still sit; the input of
    /// [`Self::mode_shapes`]. About 55 count evaluations per cluster.
    pub fn lowest_clusters(
        &mut self,
        k: usize,
        params: &ShapeParams,
    ) -> Result<Vec<(f64, u32)>, ShapeError> {
        if self.loaded_cables() == 0 {
            return Err(crate::modal::ModalError::NotLoaded.into());
        }
        let k = k.max(1).min(self.total_modes());
        clusters_by_count(|x| self.count_below(x), k, params)
    }

    /// The mass-normalised mode shapes of the loaded pose (FEM chains) at the eigenvalues
    /// `modes` = (λ in rad²/s², multiplicity), e.g. from [`Self::lowest_clusters`]: for
    /// each, `multiplicity` shapes, M-orthonormal, ordered by descending end-effector
    /// participation (see the module docs). `h` is each cable's unit horizontal (world
    /// frame), `up` the unit vertical, `arms_m` the attachment arms of a rigid end-effector
    /// (ignored for a point mass): the frames the pose was loaded with. A cable's nodes are
    /// at the fractions j/N of its unstretched length ([`ModeShapes::fractions`]); on a
    /// hidden cable node 0 is the junction's motion and the hidden cable's mass is in the
    /// normalisation (module docs). Continuous cables: [`ShapeError::SagContinuous`].
    /// Allocates; never on the real-time path.
    pub fn mode_shapes(
        &self,
        h: &[Vector3<f64>],
        up: &Vector3<f64>,
        arms_m: &[Vector3<f64>],
        modes: &[(f64, u32)],
        params: &ShapeParams,
    ) -> Result<ModeShapes, ShapeError> {
        let (attach, mut out, hcol) = self.frame(h, up, arms_m, params)?;
        let dim = self.dim();
        let n_cables = self.loaded_cables();
        let (m6, k6) = self.ee_matrices();
        for &(lambda, m) in modes {
            if !(lambda.is_finite() && lambda > 0.0) || m == 0 || m > MAX_MULTIPLICITY {
                return Err(ShapeError::BadMode {
                    lambda,
                    multiplicity: m,
                });
            }
        }
        let solve = |lambda: f64, m: u32| {
            let shapes: Vec<SagChainShape> = (0..n_cables)
                .map(|i| SagChainShape::fill(self.chain(i), lambda))
                .collect();
            let a = bordered(&attach, &shapes, &hcol, &m6, &k6, dim, lambda);
            null_of(a, m as usize, lambda, params).map(|null| (shapes, null))
        };
        // The index in `out.modes` where each given mode's shapes start.
        let mut starts = vec![0; modes.len()];
        let mut next_mode = 0;
        while next_mode < modes.len() {
            let first_mode = next_mode;
            starts[next_mode] = out.modes.len();
            let (mut lambda, mut m) = modes[next_mode];
            next_mode += 1;
            let mut got = solve(lambda, m);
            // Two modes given apart that are one (the count splits an exact double by its
            // rounding, ~1e-12 relative on the symmetric paper robot with hidden cables): the
            // bordered system has their null vectors at either λ; taken as one cluster.
            while let Err(ShapeError::NotAnEigenvalue { .. }) = got {
                match modes.get(next_mode) {
                    Some(&(ln, mn))
                        if (ln - lambda).abs() <= MERGE_REL * lambda
                            && m + mn <= MAX_MULTIPLICITY =>
                    {
                        lambda = (lambda * m as f64 + ln * mn as f64) / (m + mn) as f64;
                        m += mn;
                        starts[next_mode] = out.modes.len();
                        next_mode += 1;
                        got = solve(lambda, m);
                    }
                    _ => break,
                }
            }
            let (shapes, null) = match got {
                Err(e @ ShapeError::NotAnEigenvalue { .. }) => {
                    // Not separated from a neighbour: resolved with it as a near-cluster
                    // (module docs), the neighbour's shapes given already replaced.
                    let (lo, hi) = self
                        .near_cluster(&attach, &hcol, modes, (first_mode, next_mode), params)
                        .ok_or(e)?;
                    out.modes.truncate(starts[lo]);
                    let group = self
                        .resolve_near(&attach, &hcol, &modes[lo..hi], starts[lo], params)
                        .ok_or(e)?;
                    out.modes.extend(group);
                    next_mode = hi;
                    continue;
                }
                got => got?,
            };
            let v = &null.vectors;
            let nodes: Vec<LocalNodes> = (0..v.ncols())
                .map(|c| local_nodes(&attach, &shapes, &hcol, &v.column(c).into_owned(), dim))
                .collect();
            let cols = v.ncols();
            let mut gram = DMatrix::<f64>::zeros(cols, cols);
            let mut ee = DMatrix::<f64>::zeros(cols, cols);
            for a in 0..cols {
                for b in 0..=a {
                    let own = quad(&m6, v, a, b, dim);
                    let cab: f64 = shapes
                        .iter()
                        .enumerate()
                        .map(|(i, sh)| {
                            let ((na, ha), (nb, hb)) = (&nodes[a], &nodes[b]);
                            element_mass_form(sh.mass_kg, &na[i], &nb[i])
                                + sh.hidden_mass_form(sh, ha[i], hb[i])
                        })
                        .sum();
                    gram[(a, b)] = own + cab;
                    gram[(b, a)] = own + cab;
                    ee[(a, b)] = own;
                    ee[(b, a)] = own;
                }
            }
            let start = out.modes.len();
            for (col, part) in orthonormalise(v, gram, &ee) {
                let mut phi = Vector6::zeros();
                for r in 0..dim {
                    phi[r] = col[r];
                }
                let (local, amps) = local_nodes(&attach, &shapes, &hcol, &col, dim);
                let cables = local
                    .into_iter()
                    .zip(&attach)
                    .map(|(u, at)| u.into_iter().map(|x| at.frame * x).collect())
                    .collect();
                let hidden = shapes
                    .iter()
                    .zip(amps)
                    .map(|(sh, c)| sh.hidden_nodes(c))
                    .collect();
                out.modes.push(ModeShape {
                    lambda,
                    frequency_hz: lambda_to_hz(lambda),
                    ee: phi,
                    cables,
                    hidden,
                    ee_participation: part,
                    cluster_start: start,
                    multiplicity: m,
                    null_residual: null.residual,
                });
            }
        }
        Ok(out)
    }
}

impl SagModalSolver {
    /// The checks of [`Self::mode_shapes`] (parameters, FEM chains, discrete hidden cables,
    /// one horizontal per loaded cable, a rigid body's arms), each cable's frame and
    /// attachment, the shapes' node lists without modes, and the column of each hidden
    /// cable's amplitude in the bordered system.
    #[allow(clippy::type_complexity)]
    pub(super) fn frame(
        &self,
        h: &[Vector3<f64>],
        up: &Vector3<f64>,
        arms_m: &[Vector3<f64>],
        params: &ShapeParams,
    ) -> Result<(Vec<Attach>, ModeShapes, Vec<Option<usize>>), ShapeError> {
        params.check()?;
        if self.is_continuous() {
            return Err(ShapeError::SagContinuous);
        }
        // A FEM chain's hidden cable is discrete (the continuous bar goes with the
        // continuous chain, refused above).
        if (0..self.loaded_cables())
            .any(|i| self.chain(i).support().is_some_and(|s| s.hidden.n_el == 0))
        {
            return Err(ShapeError::HiddenCable);
        }
        let dim = self.dim();
        let n_cables = self.loaded_cables();
        if h.len() != n_cables || n_cables == 0 {
            return Err(ShapeError::NotLoaded {
                loaded: n_cables,
                given: h.len(),
            });
        }
        if dim == 6 && arms_m.len() < n_cables {
            return Err(ShapeError::MissingArms {
                given: arms_m.len(),
                cables: n_cables,
            });
        }
        let attach: Vec<Attach> = (0..n_cables)
            .map(|i| {
                let n = h[i].cross(up);
                let map = if dim == 6 {
                    attach_map(&arms_m[i])
                } else {
                    attach_map(&Vector3::zeros())
                };
                Attach {
                    frame: Matrix3::from_columns(&[h[i], *up, n]),
                    map,
                }
            })
            .collect();
        let fractions = (0..n_cables)
            .map(|i| {
                let n = self.chain(i).n_el().max(1);
                (0..=n).map(|j| j as f64 / n as f64).collect()
            })
            .collect();
        let out = ModeShapes {
            dim,
            fractions,
            modes: Vec::new(),
            element_mass_kg: (0..n_cables)
                .map(|i| self.chain(i).element_mass_kg())
                .collect(),
            hidden_element_mass_kg: (0..n_cables)
                .map(|i| self.chain(i).support().map_or(0.0, |s| s.hidden.m))
                .collect(),
        };
        // The columns of the hidden cables' amplitudes c_i, after every a_i.
        let mut next = dim + 3 * n_cables;
        let hcol: Vec<Option<usize>> = (0..n_cables)
            .map(|i| {
                self.chain(i).support().map(|_| {
                    next += 1;
                    next - 1
                })
            })
            .collect();
        Ok((attach, out, hcol))
    }
}

/// One null vector of a near-cluster's member (at the member's λ): its end-effector part,
/// each cable's nodes (cable frame) and hidden-cable amplitudes.
struct NearVector {
    member: usize,
    phi: Vector6<f64>,
    nodes: Vec<Vec<Vector3<f64>>>,
    hidden: Vec<f64>,
}

impl SagModalSolver {
    /// The given modes `lo..hi` (a cluster whose bordered system is not separated) grown by
    /// their nearest neighbours within [`NEAR_MAX_REL`] until [`Self::resolve_near`]
    /// resolves them: the range, or `None` when no neighbour is left to take.
    fn near_cluster(
        &self,
        attach: &[Attach],
        hcol: &[Option<usize>],
        modes: &[(f64, u32)],
        (mut lo, mut hi): (usize, usize),
        params: &ShapeParams,
    ) -> Option<(usize, usize)> {
        loop {
            let below = (lo > 0)
                .then(|| (modes[lo].0 - modes[lo - 1].0) / modes[lo].0)
                .filter(|&g| g <= NEAR_MAX_REL);
            let above = modes
                .get(hi)
                .map(|&(l, _)| (l - modes[hi - 1].0) / modes[hi - 1].0)
                .filter(|&g| g <= NEAR_MAX_REL);
            match (below, above) {
                (Some(b), Some(a)) if b <= a => lo -= 1,
                (Some(_), None) => lo -= 1,
                (_, Some(_)) => hi += 1,
                (None, None) => return None,
            }
            let total: u32 = modes[lo..hi].iter().map(|x| x.1).sum();
            if total > MAX_MULTIPLICITY {
                return None;
            }
            if self
                .resolve_near(attach, hcol, &modes[lo..hi], 0, params)
                .is_some()
            {
                return Some((lo, hi));
            }
        }
    }

    /// The shapes of a near-cluster `group` (module docs), the first at index `start` of
    /// the output: at each member's λ the smallest singular vectors of its own
    /// multiplicity, taken only where the cluster's whole multiplicity M is separated
    /// (σ_M/σ_{M+1} ≤ [`ShapeParams::null_tol`]); then M-orthonormalised together
    /// (symmetric orthonormalisation, the least change to each), each member keeping its
    /// λ. `None` when a member's test fails or two members' vectors are close to one
    /// (normalised Gram eigenvalue below [`NEAR_GRAM_MIN`]).
    fn resolve_near(
        &self,
        attach: &[Attach],
        hcol: &[Option<usize>],
        group: &[(f64, u32)],
        start: usize,
        params: &ShapeParams,
    ) -> Option<Vec<ModeShape>> {
        let dim = self.dim();
        let n_cables = self.loaded_cables();
        let (m6, k6) = self.ee_matrices();
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
        let mut all_shapes = Vec::new();
        let mut raw = Vec::new();
        let mut separation = 0.0f64;
        for (p, &(lambda, m)) in members.iter().enumerate() {
            let shapes: Vec<SagChainShape> = (0..n_cables)
                .map(|i| SagChainShape::fill(self.chain(i), lambda))
                .collect();
            let a = bordered(attach, &shapes, hcol, &m6, &k6, dim, lambda);
            let null = null_within(a, m as usize, total as usize, lambda, params).ok()?;
            separation = separation.max(null.residual);
            for c in 0..m as usize {
                let col = null.vectors.column(c).into_owned();
                let mut phi = Vector6::zeros();
                for r in 0..dim {
                    phi[r] = col[r];
                }
                let (nodes, hidden) = local_nodes(attach, &shapes, hcol, &col, dim);
                raw.push(NearVector {
                    member: p,
                    phi,
                    nodes,
                    hidden,
                });
            }
            all_shapes.push(shapes);
        }
        let k = raw.len();
        let mut gram = DMatrix::<f64>::zeros(k, k);
        let mut ee = DMatrix::<f64>::zeros(k, k);
        for a in 0..k {
            for b in 0..=a {
                let (ra, rb) = (&raw[a], &raw[b]);
                let own = (ra.phi.transpose() * m6 * rb.phi)[(0, 0)];
                let cab: f64 = (0..n_cables)
                    .map(|i| {
                        let (sa, sb) = (&all_shapes[ra.member][i], &all_shapes[rb.member][i]);
                        element_mass_form(sa.mass_kg, &ra.nodes[i], &rb.nodes[i])
                            + sa.hidden_mass_form(sb, ra.hidden[i], rb.hidden[i])
                    })
                    .sum();
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
                let mut cables: Vec<Vec<Vector3<f64>>> = attach
                    .iter()
                    .zip(&raw[0].nodes)
                    .map(|(_, u)| vec![Vector3::zeros(); u.len()])
                    .collect();
                let mut hidden: Vec<Vec<f64>> = all_shapes[0]
                    .iter()
                    .map(|sh| vec![0.0; sh.hidden_nodes(0.0).len()])
                    .collect();
                for (r, w) in raw.iter().zip(c.iter()) {
                    phi += r.phi * *w;
                    for ((dst, sh), &amp) in
                        hidden.iter_mut().zip(&all_shapes[r.member]).zip(&r.hidden)
                    {
                        for (x, t) in dst.iter_mut().zip(sh.hidden_nodes(amp)) {
                            *x += t * *w;
                        }
                    }
                    for ((dst, src), at) in cables.iter_mut().zip(&r.nodes).zip(attach) {
                        for (x, y) in dst.iter_mut().zip(src) {
                            *x += at.frame * y * *w;
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
}

/// One null-space vector's shape: each cable's node displacements (m) and its hidden
/// part's amplitudes.
type LocalNodes = (Vec<Vec<Vector3<f64>>>, Vec<f64>);

/// The bordered matrix at λ (module docs); `hcol` the column of each hidden cable's
/// amplitude (its junction's row the same index).
fn bordered(
    attach: &[Attach],
    shapes: &[SagChainShape],
    hcol: &[Option<usize>],
    m6: &Matrix6<f64>,
    k6: &Matrix6<f64>,
    dim: usize,
    lambda: f64,
) -> DMatrix<f64> {
    let n = dim + 3 * shapes.len() + hcol.iter().flatten().count();
    let mut a = DMatrix::<f64>::zeros(n, n);
    for r in 0..dim {
        for c in 0..dim {
            a[(r, c)] = k6[(r, c)] - lambda * m6[(r, c)];
        }
    }
    for (i, (sh, at)) in shapes.iter().zip(attach).enumerate() {
        let col = dim + 3 * i;
        // G_iᵀ E_i F_i (dim × 4) and σ E_iᵀ G_i (3 × dim).
        let gef = at.map.transpose() * at.frame * sh.force;
        let eg = at.frame.transpose() * at.map;
        // The columns of the amplitudes: the three solutions', then the hidden cable's.
        let cols = [col, col + 1, col + 2, hcol[i].unwrap_or(usize::MAX)];
        for (q, &c) in cols.iter().enumerate().take(sh.ncol) {
            for r in 0..dim {
                a[(r, c)] = gef[(r, q)];
            }
            for r in 0..3 {
                a[(col + r, c)] = -sh.scale * sh.end[(r, q)];
            }
        }
        for r in 0..dim {
            for q in 0..3 {
                a[(col + q, r)] = sh.scale * eg[(q, r)];
            }
        }
        if let (Some(hs), Some(hc)) = (&sh.hidden, hcol[i]) {
            // The junction's row.
            for (q, &c) in cols.iter().enumerate() {
                a[(hc, c)] = hs.scale * hs.row[q];
            }
        }
    }
    a
}

/// φ_aᵀ M_ee φ_b of columns a, b of `v`.
fn quad(m6: &Matrix6<f64>, v: &DMatrix<f64>, a: usize, b: usize, dim: usize) -> f64 {
    let mut s = 0.0;
    for r in 0..dim {
        for c in 0..dim {
            s += v[(r, a)] * m6[(r, c)] * v[(c, b)];
        }
    }
    s
}

/// Each cable's nodes (cable frame) of a bordered vector, from the anchor or junction on
/// (E_iᵀ G_i φ at the end), and each hidden cable's amplitude (`SagChainShape::nodes`).
fn local_nodes(
    attach: &[Attach],
    shapes: &[SagChainShape],
    hcol: &[Option<usize>],
    col: &DVector<f64>,
    dim: usize,
) -> LocalNodes {
    let mut phi = Vector6::zeros();
    for r in 0..dim {
        phi[r] = col[r];
    }
    shapes
        .iter()
        .zip(attach)
        .enumerate()
        .map(|(i, (sh, at))| {
            let c = hcol[i].map_or(0.0, |r| col[r]);
            let a = Vector4::new(
                col[dim + 3 * i],
                col[dim + 3 * i + 1],
                col[dim + 3 * i + 2],
                c,
            );
            sh.nodes(&a, at.frame.transpose() * (at.map * phi))
        })
        .unzip()
}

/// The consistent mass's bilinear form of two node sets of one cable (element mass m, kg).
fn element_mass_form(m: f64, u: &[Vector3<f64>], v: &[Vector3<f64>]) -> f64 {
    let mut s = 0.0;
    for j in 0..u.len().saturating_sub(1) {
        s += 2.0 * u[j].dot(&v[j])
            + u[j].dot(&v[j + 1])
            + u[j + 1].dot(&v[j])
            + 2.0 * u[j + 1].dot(&v[j + 1]);
    }
    m / 6.0 * s
}
