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
//! u_{j+1} always exists): the three columns Y (u₁ = e_h, e_up, e_n, then each column scaled
//! to largest entry 1) span every interior solution, u_j = Y_j a with a free amplitude
//! a ∈ ℝ³. The end value is Y_N a and the force the chain puts on its end node per unit
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
//! **Normalisation.** The nodes u_j = Y_j a (interior) and E_iᵀ G_i φ (end) of each null
//! vector give the consistent mass's quadratic form exactly (Σ over the elements of
//! (m/6)(2u_j·v_j + u_j·v_{j+1} + u_{j+1}·v_j + 2u_{j+1}·v_{j+1}), plus φᵀM_eeφ: the dense
//! M's); a cluster is M-orthonormalised and rotated as the taut shapes are.
//!
//! **Accuracy.** The forward solution is exact in exact arithmetic; in floating point its
//! rounding grows with the solution's own growth along the chain, which is at most linear
//! below the chains' cut-off (the first modes of a robot lie far below it; above it the
//! solution grows like sinh(jφ) and is still the dominant, accurately computed one). The
//! dense eigenvectors are the check (`tests/sag/shapes.rs`). Offline: allocates.

use super::count::clusters_by_count;
use super::solve::{null_of, orthonormalise};
use super::{ModeShape, ModeShapes, ShapeError, ShapeParams, MAX_MULTIPLICITY};
use crate::cable::sagged::SagChain;
use crate::kinematics::attach_map;
use crate::modal::lambda_to_hz;
use crate::modal::sagged::SagModalSolver;
use nalgebra::{DMatrix, DVector, Matrix3, Matrix3x6, Matrix6, Vector3, Vector6};

/// One cable's interior solutions at one λ, in the cable's frame (h, up, n).
#[derive(Debug, Clone, Default)]
struct SagChainShape {
    /// Y_j for j = 0 ..= N (Y_0 = 0): the three solutions as columns.
    y: Vec<Matrix3<f64>>,
    /// Element mass μ l0, kg.
    mass_kg: f64,
    /// End force per unit amplitude, F (N/m per unit amplitude).
    force: Matrix3<f64>,
    /// Row scale of the end constraint, N/m.
    scale: f64,
}

/// Element j's stiffness in the cable frame, diag(K_in, k_out), N/m.
fn element_k(chain: &SagChain, j: usize) -> Matrix3<f64> {
    let e = chain.element(j);
    let [a, b, c] = e.k_in;
    Matrix3::new(a, b, 0.0, b, c, 0.0, 0.0, 0.0, e.k_out)
}

impl SagChainShape {
    /// The interior solutions of `chain` at λ (see the module docs).
    fn fill(chain: &SagChain, lambda: f64) -> SagChainShape {
        let n = chain.n_el().max(1);
        let m = chain.element_mass_kg();
        let id = Matrix3::identity();
        let mut y = vec![Matrix3::zeros(); n + 1];
        y[1] = id;
        for j in 1..n {
            let (kp, kn) = (element_k(chain, j - 1), element_k(chain, j));
            let rhs = (kp + kn - id * (2.0 * lambda * m / 3.0)) * y[j]
                - (kp + id * (lambda * m / 6.0)) * y[j - 1];
            let lhs = kn + id * (lambda * m / 6.0);
            // Positive definite (K_j ⪰ 0 with T > 0, and λm ≥ 0): the solve exists.
            y[j + 1] = lhs.lu().solve(&rhs).unwrap_or_else(Matrix3::zeros);
        }
        // Each column to largest entry 1 (its growth along the chain is arbitrary).
        for c in 0..3 {
            let mx = y.iter().fold(0.0f64, |a, yj| a.max(yj.column(c).amax()));
            if mx > 0.0 {
                for yj in y.iter_mut() {
                    yj.column_mut(c).scale_mut(1.0 / mx);
                }
            }
        }
        let kl = element_k(chain, n - 1);
        let force =
            (kl - id * (lambda * m / 3.0)) * y[n] - (kl + id * (lambda * m / 6.0)) * y[n - 1];
        let scale = (kl.amax() + 0.5 * lambda * m).max(f64::MIN_POSITIVE);
        SagChainShape {
            y,
            mass_kg: m,
            force,
            scale,
        }
    }
}

/// How one loaded cable attaches: its frame E = [h up n] and attachment map (3 × dim).
struct Attach {
    frame: Matrix3<f64>,
    map: Matrix3x6<f64>,
}

impl SagModalSolver {
    /// The lowest clusters of the loaded pose, (λ in rad²/s², multiplicity), ascending,
    /// until at least `k` modes are covered (a cluster cut by `k` completed): bisection on
    /// the Wittrick–Williams count ([`Self::count_below`]) to a relative width of 4ε, modes
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
        clusters_by_count(|x| self.count_below(x), k.max(1), params)
    }

    /// The mass-normalised mode shapes of the loaded pose (FEM chains) at the eigenvalues
    /// `modes` = (λ in rad²/s², multiplicity), e.g. from [`Self::lowest_clusters`]: for
    /// each, `multiplicity` shapes, M-orthonormal, ordered by descending end-effector
    /// participation (see the module docs). `h` is each cable's unit horizontal (world
    /// frame), `up` the unit vertical, `arms_m` the attachment arms of a rigid end-effector
    /// (ignored for a point mass): the frames the pose was loaded with. A cable's nodes are
    /// at the fractions j/N of its unstretched length ([`ModeShapes::fractions`]).
    /// Continuous cables: [`ShapeError::SagContinuous`]. Allocates; never on the real-time
    /// path.
    pub fn mode_shapes(
        &self,
        h: &[Vector3<f64>],
        up: &Vector3<f64>,
        arms_m: &[Vector3<f64>],
        modes: &[(f64, u32)],
        params: &ShapeParams,
    ) -> Result<ModeShapes, ShapeError> {
        params.check()?;
        if self.is_continuous() {
            return Err(ShapeError::SagContinuous);
        }
        // The recovery below starts every chain at a fixed anchor (y_0 = 0); a chain on a
        // hidden cable starts at a moving junction, so its shapes would be wrong.
        if (0..self.loaded_cables()).any(|i| self.chain(i).support().is_some()) {
            return Err(ShapeError::SagHidden);
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
        let mut out = ModeShapes {
            dim,
            fractions,
            modes: Vec::new(),
            element_mass_kg: (0..n_cables)
                .map(|i| self.chain(i).element_mass_kg())
                .collect(),
        };
        let (m6, k6) = self.ee_matrices();
        for &(lambda, m) in modes {
            if !(lambda.is_finite() && lambda > 0.0) || m == 0 || m > MAX_MULTIPLICITY {
                return Err(ShapeError::BadMode {
                    lambda,
                    multiplicity: m,
                });
            }
            let shapes: Vec<SagChainShape> = (0..n_cables)
                .map(|i| SagChainShape::fill(self.chain(i), lambda))
                .collect();
            let a = bordered(&attach, &shapes, &m6, &k6, dim, lambda);
            let null = null_of(a, m as usize, lambda, params)?;
            let v = &null.vectors;
            let nodes: Vec<Vec<Vec<Vector3<f64>>>> = (0..v.ncols())
                .map(|c| local_nodes(&attach, &shapes, &v.column(c).into_owned(), dim))
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
                        .map(|(i, sh)| element_mass_form(sh.mass_kg, &nodes[a][i], &nodes[b][i]))
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
                let cables = local_nodes(&attach, &shapes, &col, dim)
                    .into_iter()
                    .zip(&attach)
                    .map(|(u, at)| u.into_iter().map(|x| at.frame * x).collect())
                    .collect();
                out.modes.push(ModeShape {
                    lambda,
                    frequency_hz: lambda_to_hz(lambda),
                    ee: phi,
                    cables,
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

/// The bordered matrix at λ (module docs).
fn bordered(
    attach: &[Attach],
    shapes: &[SagChainShape],
    m6: &Matrix6<f64>,
    k6: &Matrix6<f64>,
    dim: usize,
    lambda: f64,
) -> DMatrix<f64> {
    let n = dim + 3 * shapes.len();
    let mut a = DMatrix::<f64>::zeros(n, n);
    for r in 0..dim {
        for c in 0..dim {
            a[(r, c)] = k6[(r, c)] - lambda * m6[(r, c)];
        }
    }
    for (i, (sh, at)) in shapes.iter().zip(attach).enumerate() {
        let col = dim + 3 * i;
        // G_iᵀ E_i F_i (dim × 3) and σ E_iᵀ G_i (3 × dim).
        let gef = at.map.transpose() * at.frame * sh.force;
        let eg = at.frame.transpose() * at.map;
        let yn = sh.y[sh.y.len() - 1];
        for r in 0..dim {
            for q in 0..3 {
                a[(r, col + q)] = gef[(r, q)];
                a[(col + q, r)] = sh.scale * eg[(q, r)];
            }
        }
        for r in 0..3 {
            for q in 0..3 {
                a[(col + r, col + q)] = -sh.scale * yn[(r, q)];
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

/// Each cable's nodes (cable frame) of a bordered vector: Y_j a inside, E_iᵀ G_i φ at the
/// end, 0 at the anchor.
fn local_nodes(
    attach: &[Attach],
    shapes: &[SagChainShape],
    col: &DVector<f64>,
    dim: usize,
) -> Vec<Vec<Vector3<f64>>> {
    let mut phi = Vector6::zeros();
    for r in 0..dim {
        phi[r] = col[r];
    }
    shapes
        .iter()
        .zip(attach)
        .enumerate()
        .map(|(i, (sh, at))| {
            let amp = Vector3::new(col[dim + 3 * i], col[dim + 3 * i + 1], col[dim + 3 * i + 2]);
            let last = sh.y.len() - 1;
            let mut u: Vec<Vector3<f64>> = sh.y.iter().map(|yj| yj * amp).collect();
            u[last] = at.frame.transpose() * (at.map * phi);
            u
        })
        .collect()
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
