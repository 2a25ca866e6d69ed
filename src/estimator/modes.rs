//! The first K natural frequencies at the pose of the last successful cycle, by the
//! structured engine ([`crate::modal::ModalSolver::modes`]). Offline use: it spends tens of
//! evaluations of D(λ) per mode and leaves the cycle's warm state alone (the eigen solver
//! keeps its loaded problem; only its evaluation counter moves).

use super::{Estimator, EstimatorError, Status};
use crate::modal::quasi_static::{ConvectiveLoad, QuasiStaticLoad};
use crate::modal::{self, DenseModes, Mode, ShapeParams};
use nalgebra::{DMatrix, Matrix6, Vector6};

impl EeModalBasis {
    /// The basis of the structured engine's mode shapes (taut or sagging FEM cables) and
    /// the load of the influence field `field` on them (the end-effector's alone when
    /// None); `convective`: a sagging robot's second-derivative fields and their load.
    pub(super) fn structured(
        dim: usize,
        shapes: modal::ModeShapes,
        field: Option<(QuasiStaticLoad, modal::ModeShapes)>,
        convective: Option<(ConvectiveLoad, modal::ModeShapes)>,
        flexibility: Matrix6<f64>,
        ee_mass: Matrix6<f64>,
    ) -> Result<EeModalBasis, BasisError> {
        let (load, field) = match field {
            Some((load, field)) => (load, Some(field)),
            None => (QuasiStaticLoad::end_effector_only(&shapes, &ee_mass), None),
        };
        let (convective_load, convective_flexibility, second_field) = match convective {
            Some((c, second)) => (
                c.participation.clone(),
                c.load_flexibility(&flexibility),
                Some(second),
            ),
            None => (Vec::new(), Matrix6::zeros(), None),
        };
        EeModalBasis {
            dim,
            lambda: shapes.modes.iter().map(|m| m.lambda).collect(),
            phi_ee: shapes.modes.iter().map(|m| m.ee).collect(),
            flexibility,
            ee_mass,
            structured: true,
            shapes: Some(shapes),
            field,
            second_field,
            convective_load,
            convective_flexibility,
            load_ee: Vec::new(),
            load_flexibility: Matrix6::zeros(),
            quasi_static_mass_kg: Matrix6::zeros(),
        }
        .with_load(&load)
    }

    /// The load shapes, load flexibility and quasi-static mass of `load`
    /// ([`QuasiStaticLoad`]).
    fn with_load(mut self, load: &QuasiStaticLoad) -> Result<EeModalBasis, BasisError> {
        let singular = BasisError::QuasiStatic("the end-effector's mass matrix is singular");
        self.load_ee = load.load_shapes(&self.ee_mass).ok_or(singular.clone())?;
        self.load_flexibility = load
            .load_flexibility(&self.flexibility, &self.ee_mass)
            .ok_or(singular)?;
        self.quasi_static_mass_kg = load.mass_kg;
        Ok(self)
    }
}

impl Estimator {
    /// The first `k` natural frequencies (ascending) of the pose of the last successful
    /// [`Estimator::update`] into `out`; returns how many were written (min(k, out.len(),
    /// the model's number of modes)). When the last cycle was not ok, its error; before
    /// any cycle, `Modal(NotLoaded)`. A mode whose λ is not finite and > 0 or whose
    /// participation is not finite is [`EstimatorError::Unverified`] (the cycle's own rule,
    /// [`super::check_answer`]), never a number.
    ///
    /// ```
    /// use cablevib::prelude::*;
    ///
    /// let scene = Scene::load("spatial-paper")?;
    /// let mut est = Estimator::new(&scene)?;
    /// let f1 = est.update(&Pose::in_scene(&scene, scene.ee_position_m), Tmin::Scene).f1_hz;
    /// let mut modes = [Mode::default(); 10];
    /// let n = est.modes(10, &mut modes)?;
    /// assert_eq!(n, 10);
    /// // The first of them is the cycle's f1; they ascend, by clusters: at this symmetric
    /// // pose 3 modes share f1 and the next 5 another frequency (the paper's modes 4-8).
    /// assert!((modes[0].frequency_hz - f1).abs() <= 1e-9 * f1);
    /// assert!(modes.windows(2).all(|w| w[0].frequency_hz <= w[1].frequency_hz));
    /// assert_eq!((modes[0].multiplicity, modes[3].multiplicity), (3, 5));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn modes(&mut self, k: usize, out: &mut [Mode]) -> Result<usize, EstimatorError> {
        match self.estimate.status {
            Status::Ok => {
                let n = self.cycle.modes(k, out)?;
                for m in &out[..n] {
                    if !(m.lambda.is_finite() && m.lambda > 0.0) {
                        let (what, value) = ("an eigenvalue (rad²/s²)", m.lambda);
                        return Err(EstimatorError::Unverified { what, value });
                    }
                    if !m.ee_participation.is_finite() {
                        let (what, value) = ("an end-effector participation", m.ee_participation);
                        return Err(EstimatorError::Unverified { what, value });
                    }
                }
                Ok(n)
            }
            _ => Err(self
                .estimate
                .error
                .unwrap_or(EstimatorError::Modal(crate::modal::ModalError::NotLoaded))),
        }
    }
}

impl Estimator {
    /// The dense reference of exactly the models of the last successful cycle (same
    /// tensions, same end-effector): assembled K and M and every eigenvalue, with
    /// participations when `vectors`. Allocates O(DOF²); refused beyond
    /// [`crate::modal::DENSE_MEMORY_BUDGET_BYTES`]. Offline use.
    pub fn dense_modes(&self, vectors: bool) -> Result<DenseModes, EstimatorError> {
        let (k, m) = self.dense_matrices()?;
        let (ee, dim) = self.cycle.ee_mass();
        Ok(modal::dense_modes_ee(&k, &m, &ee, dim, vectors)?)
    }

    /// The degrees of freedom of the last successful cycle's model: the size of
    /// [`Self::dense_matrices`]' K and M (the end-effector's 3 or 6, 3 per interior node,
    /// one axial DOF per node of a cable behind a pulley), the count every solver reports;
    /// None for continuous cables or before an ok cycle.
    pub fn model_dof(&self) -> Option<usize> {
        (self.estimate.status == Status::Ok)
            .then(|| self.cycle.assembled_dof())
            .flatten()
    }

    /// The assembled K (N/m) and M (kg) of the last successful cycle's models (DOF order of
    /// [`modal::assemble`]: the end-effector's 3 or 6 first, then each cable's interior
    /// nodes from the anchor).
    pub fn dense_matrices(&self) -> Result<(DMatrix<f64>, DMatrix<f64>), EstimatorError> {
        if self.estimate.status != Status::Ok {
            return Err(self
                .estimate
                .error
                .unwrap_or(EstimatorError::Modal(modal::ModalError::NotLoaded)));
        }
        Ok(self.cycle.dense_matrices(&self.scene)?)
    }
}

/// Why a field's products with the shapes failed.
pub(super) const NODES_DIFFER: &str = "the influence field's nodes are not the shapes'";

/// Bytes of one node's displacement in a mode shape (a `Vector3<f64>`).
pub const SHAPE_BYTES_PER_NODE: u64 = 24;

/// Modes beyond the K asked for that a mode-shape computation holds at its peak: a cluster
/// cut by K is completed, and the recovery's working arrays (each chain's node function)
/// take about as much again; measured within 10 % on the paper robot at N = 10⁵
/// (the shapes of 1, 12, 48 modes: 89, 333, 934 MB against 134, 346, 1037 MB estimated).
const SHAPE_EXTRA_MODES: u64 = 6;

/// The nodes of one mode shape of `scene`'s model: each cable's N + 1 nodes (`fem`,
/// `catenary`, sagging FEM), 2 (`massless`) or `continuous_samples` (`continuous`), and the
/// end-effector's 2.
pub fn shape_nodes(scene: &crate::scene::Scene, continuous_samples: usize) -> u64 {
    use crate::scene::ElementKind;
    let per_cable = match scene.model.element {
        ElementKind::Continuous => continuous_samples as u64,
        ElementKind::Massless => 2,
        _ => scene.model.elements_per_cable as u64 + 1,
    };
    per_cable * scene.n_cables() as u64 + 2
}

/// The memory a computation holding the shapes of `modes` modes of `scene` needs at its
/// peak, bytes: (`SHAPE_EXTRA_MODES` + `modes`) × [`shape_nodes`] × `bytes_per_node_mode`
/// ([`SHAPE_BYTES_PER_NODE`] for one set of shapes; more when a caller holds two sets or
/// their CSV text). Saturating.
pub fn shapes_memory_bytes(
    scene: &crate::scene::Scene,
    modes: usize,
    continuous_samples: usize,
    bytes_per_node_mode: u64,
) -> u64 {
    (modes as u64)
        .saturating_add(SHAPE_EXTRA_MODES)
        .saturating_mul(shape_nodes(scene, continuous_samples))
        .saturating_mul(bytes_per_node_mode)
}

/// What to change when mode shapes are over the memory budget.
pub const SHAPES_REMEDY: &str =
    "use fewer elements per cable or fewer modes; the frequencies alone (analyze) need no shapes";

/// Refuse holding the shapes of `modes` modes of `scene` when [`shapes_memory_bytes`] is
/// over the one memory budget ([`crate::memory_budget`]).
pub fn check_shapes_memory(
    scene: &crate::scene::Scene,
    modes: usize,
    continuous_samples: usize,
    bytes_per_node_mode: u64,
) -> Result<(), crate::memory_budget::OverBudget> {
    let nodes = shape_nodes(scene, continuous_samples);
    crate::memory_budget::check(
        || format!("the mode shapes of {modes} modes × {nodes} nodes"),
        shapes_memory_bytes(scene, modes, continuous_samples, bytes_per_node_mode),
        SHAPES_REMEDY,
    )
}

/// Why [`Estimator::ee_modal_basis`] has no basis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BasisError {
    /// The last cycle was not ok, or the eigen solve failed.
    #[error(transparent)]
    Estimator(#[from] EstimatorError),
    /// The mode shapes could not be recovered.
    #[error(transparent)]
    Shapes(#[from] modal::ShapeError),
    /// The shapes would need more memory than the budget (refused before allocating).
    #[error(transparent)]
    Memory(#[from] crate::memory_budget::OverBudget),
    /// The quasi-static load could not be formed.
    #[error("the quasi-static load of the cables: {0}")]
    QuasiStatic(&'static str),
}

/// The end-effector's view of the first modes of one pose: what a time response needs.
#[derive(Debug, Clone, PartialEq)]
pub struct EeModalBasis {
    /// 3 (point mass) or 6 (rigid body).
    pub dim: usize,
    /// λ = ω² of each mode, ascending, rad²/s².
    pub lambda: Vec<f64>,
    /// The end-effector part of each mass-normalised shape (translation 1/√kg, then
    /// rotation rad/(m·√kg); zeros beyond `dim`).
    pub phi_ee: Vec<Vector6<f64>>,
    /// The end-effector's static flexibility D(0)⁻¹ (its `dim` block; m/N, rad/(N·m)).
    pub flexibility: Matrix6<f64>,
    /// The end-effector's own mass matrix (kg, kg·m²).
    pub ee_mass: Matrix6<f64>,
    /// Whether the shapes came from the structured engine (taut or sagging FEM cables) or
    /// a dense solve (the dense model; sagging FEM chains where K is a large share of the
    /// DOF, `dense_sag_basis`).
    pub structured: bool,
    /// The whole shapes (every cable's nodes) when they came from the structured engine,
    /// a Rayleigh–Ritz update or the dense solve of sagging FEM chains: what carries a
    /// time response's state across poses
    /// ([`modal::ModeShapes::mass_overlap`]).
    pub shapes: Option<modal::ModeShapes>,
    /// The influence field the load was formed with, in the shapes' node lists (one entry
    /// of its `modes` per end-effector DOF: every node's displacement per unit
    /// end-effector displacement): the fixed-length static field on taut cables, the path's
    /// field on sagging ones (`modal::quasi_static`); None where the load is the
    /// end-effector's alone or the shapes are the dense model's.
    pub field: Option<modal::ModeShapes>,
    /// A sagging robot's second-derivative fields ∂²x/∂p_d∂p_e along its path (six entries
    /// of `modes`: xx, yy, zz, xy, xz, yz; 1/m) where `field` is the path's; None elsewhere
    /// (`estimator::path_field`).
    pub second_field: Option<modal::ModeShapes>,
    /// Each mode's convective load shape χ_k = (φ_kᵀ M C_i)_i (kg^½/m; module docs of
    /// [`modal::quasi_static`]): under the response's force −w of the path's velocity
    /// products w ([`super::convective_input`]), mode k's force is −χ_kᵀ w; empty without
    /// `second_field`.
    pub convective_load: Vec<Vector6<f64>>,
    /// The end-effector's static answer per unit of that force, F S (m·s²/m²; zeros without
    /// `second_field`).
    pub convective_flexibility: Matrix6<f64>,
    /// Each mode's load shape ψ_k = M_ee⁻¹ L_k (1/√kg; zeros beyond `dim`): under the
    /// end-effector load f = −M_ee a of a path's acceleration a, mode k's force is ψ_kᵀ f =
    /// −L_kᵀ a, the quasi-static inertia of the whole robot, the cables' included
    /// ([`modal::quasi_static`]); `phi_ee` where the cables carry no mass or take the
    /// end-effector's load alone (sagging cables over pulleys).
    pub load_ee: Vec<Vector6<f64>>,
    /// The end-effector's static answer to that load per unit f, F M_s M_ee⁻¹ (m/N;
    /// `flexibility` where the cables carry no mass or take the end-effector's load alone).
    pub load_flexibility: Matrix6<f64>,
    /// The robot's quasi-static mass M_qs = rᵀ M r (kg, kg·m²): the end-effector's and the
    /// share of the cables' the end-effector's motion carries (`ee_mass` where the cables
    /// take the end-effector's load alone).
    pub quasi_static_mass_kg: Matrix6<f64>,
}

impl Estimator {
    /// The end-effector's mass matrix, its DOF and its static flexibility D(0)⁻¹ (the `dim`
    /// block; NaN when singular) at the last cycle's pose.
    pub(super) fn ee_mass_flexibility(&self) -> (Matrix6<f64>, usize, Matrix6<f64>) {
        let (ee_mass, dim) = self.cycle.ee_mass();
        let s = self.estimate.stiffness.k6;
        let block = s.view((0, 0), (dim, dim)).into_owned();
        let mut flexibility = Matrix6::repeat(f64::NAN);
        if let Some(inv) = block.try_inverse() {
            flexibility = Matrix6::zeros();
            flexibility.view_mut((0, 0), (dim, dim)).copy_from(&inv);
        }
        (ee_mass, dim, flexibility)
    }

    /// The first `k` modes (a cluster cut by `k` completed) of the pose of the last
    /// successful [`Estimator::update`], end-effector parts of their mass-normalised shapes,
    /// and the static flexibility. Taut cables: the structured engine's eigenvalues
    /// ([`crate::modal::ModalSolver::modes`]) and shapes
    /// ([`crate::modal::ModalSolver::mode_shapes`]); sagging cables (FEM chains): the
    /// sagged engine's clusters and shapes
    /// ([`crate::modal::SagModalSolver::mode_shapes`]), or one dense solve of their model
    /// where K is a large share of its DOF ([`dense_sag_pays`](super::dense_sag_pays)); otherwise the dense model.
    /// Offline: allocates.
    pub fn ee_modal_basis(&mut self, k: usize) -> Result<EeModalBasis, BasisError> {
        if self.estimate.status != Status::Ok {
            return Err(BasisError::Estimator(
                self.estimate
                    .error
                    .unwrap_or(EstimatorError::Modal(modal::ModalError::NotLoaded)),
            ));
        }
        let (ee_mass, dim, flexibility) = self.ee_mass_flexibility();
        let k = k.max(1);
        // The whole shapes (structured engines) or the dense model's n × n matrices: each
        // refused past the one memory budget before it allocates.
        let samples = ShapeParams::default().continuous_samples;
        check_shapes_memory(&self.scene, k, samples, SHAPE_BYTES_PER_NODE)?;
        if let Some((solver, models, geometry)) = self.cycle.taut_shapes_input() {
            let mut modes = vec![Mode::default(); k + modal::MAX_MULTIPLICITY as usize];
            let n = solver
                .modes(modes.len(), &mut modes)
                .map_err(|e| BasisError::Estimator(e.into()))?;
            let mut clusters = Vec::new();
            let mut covered = 0usize;
            for (i, m) in modes[..n].iter().enumerate() {
                if covered >= k {
                    break;
                }
                if m.cluster_start == i {
                    clusters.push((m.lambda, m.multiplicity));
                    covered += m.multiplicity as usize;
                }
            }
            let params = ShapeParams::default();
            let shapes = solver
                .mode_shapes(models, &geometry.arm_m, &clusters, &params)
                .map_err(BasisError::Shapes)?;
            let field = solver
                .influence_field(models, &geometry.arm_m, &params)
                .map_err(BasisError::Shapes)?;
            let load = QuasiStaticLoad::from_shapes(&shapes, &field, &ee_mass)
                .ok_or(BasisError::QuasiStatic(NODES_DIFFER))?;
            let field = Some((load, field));
            return EeModalBasis::structured(dim, shapes, field, None, flexibility, ee_mass);
        }
        // Sagged FEM chains: one dense solve where it is cheaper than the structured
        // shapes (`dense_sag_basis`).
        let dense = self.sag_dense_shapes(k)?;
        if let Some((solver, h, up, geometry)) = self.cycle.sag_shapes_input() {
            if !solver.is_continuous() {
                let params = ShapeParams::default();
                let structured = dense.is_none();
                let shapes = match dense {
                    Some(shapes) => shapes,
                    None => {
                        let clusters = solver
                            .eigen_clusters(k, &params)
                            .map_err(BasisError::Shapes)?;
                        solver
                            .mode_shapes(&h, &up, &geometry.arm_m, &clusters, &params)
                            .map_err(BasisError::Shapes)?
                    }
                };
                let fixed = solver
                    .influence_field(&h, &up, &geometry.arm_m, &params)
                    .map_err(BasisError::Shapes)?;
                // The path's field (lengths re-solved along the path), not the fixed-length
                // one, and its convective load; the end-effector's load alone where it is
                // not covered (pulleys).
                let (field, convective) = match self.sag_path_fields(&fixed)? {
                    Some(p) => (
                        Some((
                            QuasiStaticLoad::from_path_field(&shapes, &p.first, &fixed, &ee_mass)
                                .ok_or(BasisError::QuasiStatic(NODES_DIFFER))?,
                            p.first,
                        )),
                        Some((
                            ConvectiveLoad::from_fields(&shapes, &p.second, &fixed, &ee_mass)
                                .ok_or(BasisError::QuasiStatic(NODES_DIFFER))?,
                            p.second,
                        )),
                    ),
                    None => (None, None),
                };
                let mut basis =
                    EeModalBasis::structured(dim, shapes, field, convective, flexibility, ee_mass)?;
                basis.structured = structured;
                return Ok(basis);
            }
        }
        let (kk, mm) = self.dense_matrices()?;
        let (lambda, phi_ee, vectors) = dense_ee_shapes(&kk, &mm, dim, k)?;
        let load = QuasiStaticLoad::from_dense(&kk, &mm, dim, &vectors).ok_or(
            BasisError::QuasiStatic("the cables' static stiffness is not positive definite"),
        )?;
        EeModalBasis {
            dim,
            lambda,
            phi_ee,
            flexibility,
            ee_mass,
            structured: false,
            shapes: None,
            field: None,
            second_field: None,
            convective_load: Vec::new(),
            convective_flexibility: Matrix6::zeros(),
            load_ee: Vec::new(),
            load_flexibility: Matrix6::zeros(),
            quasi_static_mass_kg: Matrix6::zeros(),
        }
        .with_load(&load)
    }
}

/// Every eigenvalue of K u = λ M u (dense; [`modal::standard_form`], [`modal::sym_eigen`]):
/// ascending, and the lowest mass-normalised eigenvectors on demand.
pub(super) struct DenseSolve {
    /// Every λ, ascending, rad²/s².
    pub(super) lambda: Vec<f64>,
    form: modal::standard_form::StandardForm,
    /// The standard form's reduction and eigenvalues (vectors on demand).
    eig: modal::sym_eigen::SymEigen,
}

impl DenseSolve {
    /// Solve the pencil (K, M) for its eigenvalues.
    pub(super) fn new(k: &DMatrix<f64>, m: &DMatrix<f64>) -> Result<DenseSolve, EstimatorError> {
        let mut form = modal::standard_form::StandardForm::new(k, m)?;
        let c = std::mem::replace(&mut form.c, DMatrix::zeros(0, 0));
        let eig = modal::sym_eigen::SymEigen::new(c).map_err(modal::ModalError::from)?;
        Ok(DenseSolve {
            lambda: eig.values().to_vec(),
            form,
            eig,
        })
    }

    /// The first `count` mass-normalised eigenvectors u (columns).
    pub(super) fn vectors(&self, count: usize) -> Result<DMatrix<f64>, EstimatorError> {
        let y = self
            .eig
            .lowest_vectors(count)
            .map_err(modal::ModalError::from)?;
        Ok(self.form.vectors(&y))
    }
}

/// The lowest `count` eigenpairs of K u = λ M u (dense), the first `dim` entries of each
/// mass-normalised u, and the u (columns).
#[allow(clippy::type_complexity)]
fn dense_ee_shapes(
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    dim: usize,
    count: usize,
) -> Result<(Vec<f64>, Vec<Vector6<f64>>, DMatrix<f64>), EstimatorError> {
    let solve = DenseSolve::new(k, m)?;
    let u = solve.vectors(count)?;
    let lambda = solve.lambda[..u.ncols()].to_vec();
    let phi = (0..u.ncols())
        .map(|c| {
            let mut p = Vector6::zeros();
            for r in 0..dim {
                p[r] = u[(r, c)];
            }
            p
        })
        .collect();
    Ok((lambda, phi, u))
}
