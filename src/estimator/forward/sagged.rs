//! The forward model of one pose when the scene's cables sag (`[effects] sag = true`):
//! the tension distribution ([`SagTensionSolver`]: the least Σ T² with each cable on its
//! elastic catenary and the end-effector in equilibrium with the cables' end forces),
//! then each cable's chain about its sagged profile (`fem`: N straight elements between
//! nodes on the catenary; `continuous`: the exact N → ∞ limit), then the structured
//! solver's first root ([`SagModalSolver`]) and its end-effector mode. Nothing here
//! allocates after [`SagModel::new`].

use super::{CableSide, EndEffector, ForwardParams, TensionReport};
use crate::elastic_catenary::Catenary;
use crate::estimator::EstimatorError;
use crate::kinematics::{Geometry, Pose};
use crate::modal::sagged::SagChains;
use crate::modal::sagged::{
    assemble_sagged, SagCableFrame, SagDenseCable, SagEndEffector, SagLoadError,
};
use crate::modal::{ModalError, Root, SagModalSolver};
use crate::scene::{ElementKind, Scene};
use crate::tension::{SagCable, SagTensionSolver, TensionInfo};
use nalgebra::{DMatrix, Matrix3, Matrix6, Vector3};

/// Every buffer of the sagged forward model, sized once.
#[derive(Debug, Clone)]
pub(in crate::estimator) struct SagModel {
    /// The sagged tension distribution (keeps its catenaries as warm start).
    pub(super) tension: SagTensionSolver,
    /// The structured solver on the sagged chains.
    pub(super) modal: SagModalSolver,
    /// Each cable's EA (N) and weight per unstretched length (N/m).
    materials: Vec<SagCable>,
    /// Each cable's mass per unstretched length, kg/m.
    mu_kg_m: Vec<f64>,
    /// Each cable's attachment frame of the last load.
    frames: Vec<SagCableFrame>,
    /// `modal`'s evaluation counter when it was last loaded.
    loaded_at: u32,
}

impl SagModel {
    /// Buffers for the cables of `scene` (allocates: set-up only).
    pub(super) fn new(scene: &Scene, params: &ForwardParams) -> SagModel {
        let n = scene.n_cables();
        let modal = match scene.model.element {
            ElementKind::Continuous => {
                SagModalSolver::new_continuous(params.modal, n, params.sag_continuous)
            }
            _ => SagModalSolver::new(params.modal, n, scene.model.elements_per_cable.max(1)),
        };
        let frame = SagCableFrame {
            h: Vector3::x(),
            arm_m: Vector3::zeros(),
            end_force_n: Vector3::zeros(),
        };
        SagModel {
            tension: SagTensionSolver::new(n, params.sag_tension),
            modal,
            materials: SagCable::of_scene(scene),
            mu_kg_m: scene
                .cables
                .iter()
                .map(|c| c.mass_per_length_kg_m)
                .collect(),
            frames: vec![frame; n],
            loaded_at: 0,
        }
    }

    /// Set each cable's chain on its catenary and load the end-effector.
    fn load(&mut self, scene: &Scene, pose: &Pose, g: &Geometry) -> Result<(), EstimatorError> {
        let n = scene.n_cables();
        for i in 0..n {
            let cat = self.tension.catenaries_of()[i];
            let [h, up, _] = self.tension.basis(i);
            self.frames[i] = SagCableFrame {
                h,
                arm_m: g.arm_m[i],
                end_force_n: -(h * cat.h_n + up * cat.v_end_n()),
            };
            set_chain(&mut self.modal, i, scene, &cat, self.mu_kg_m[i])?;
            if let Some(hidden) = super::axial_behind_exit(&scene.cables[i], g, i) {
                support_chain(&mut self.modal, i, scene, &cat, &hidden)?;
            }
            let exit = g.pulley_exit(i).map(|e| exit_motion(e, &cat, &h, &up));
            self.modal
                .set_exit_motion(i, exit)
                .map_err(EstimatorError::SagModel)?;
        }
        let up = self.tension.basis(0)[1];
        let body = EndEffector::of_body(scene, pose);
        let ee = if body.rigid {
            SagEndEffector::Rigid {
                mass_kg: body.mass_kg,
                inertia_kg_m2: body.inertia_kg_m2,
            }
        } else {
            SagEndEffector::Point {
                mass_kg: scene.ee_mass_kg,
            }
        };
        self.modal
            .load(&self.frames[..n], &up, &ee)
            .map_err(EstimatorError::SagModel)
    }

    /// Each cable's unit horizontal h of the last load and the unit vertical up (world
    /// frame): the frames [`SagModalSolver::mode_shapes`] needs.
    pub(super) fn shape_frames(&self) -> (Vec<Vector3<f64>>, Vector3<f64>) {
        let up = self.tension.basis(0)[1];
        (self.frames.iter().map(|f| f.h).collect(), up)
    }

    /// Each cable's catenary of the last tension solve.
    pub(super) fn catenaries(&self) -> &[Catenary] {
        self.tension.catenaries_of()
    }

    /// The sagged equilibrium at geometry `g` with the bounds (N) of a cycle, solved by a
    /// copy of this model's tension solver (warm from its last solve; the cycle's own state
    /// is left alone): every cable's nodes in world coordinates, m, at
    /// s_j = j L0/N on its catenary (j = 0 ..= N, N this model's chain's elements; node 0
    /// the anchor), the node lists of [`SagModalSolver::mode_shapes`]. Allocates (offline:
    /// the path's influence field, `estimator::path_field`).
    pub(super) fn equilibrium_nodes(
        &self,
        scene: &Scene,
        g: &Geometry,
        t_min_n: &[f64],
        t_max_n: &[f64],
    ) -> Result<Vec<Vec<Vector3<f64>>>, EstimatorError> {
        let mut scratch = self.tension.clone();
        scratch.solve(
            g,
            &self.materials,
            &scene.gravity_m_s2,
            &scene.wrench6_n(),
            t_min_n,
            t_max_n,
        )?;
        Ok((0..scene.n_cables())
            .map(|i| {
                let cat = scratch.catenaries_of()[i];
                let [h, up, _] = scratch.basis(i);
                let n = self.modal.chain(i).n_el().max(1);
                (0..=n)
                    .map(|j| {
                        let [x, z] = cat.point_at_m(cat.l0_m * j as f64 / n as f64);
                        g.exit_m[i] + h * x + up * z
                    })
                    .collect()
            })
            .collect())
    }
}

impl CableSide for SagModel {
    type Problem = SagChains;

    fn solver(&self) -> &SagModalSolver {
        &self.modal
    }

    fn solver_mut(&mut self) -> &mut SagModalSolver {
        &mut self.modal
    }

    fn loaded_at(&self) -> u32 {
        self.loaded_at
    }

    fn reset_tensions(&mut self) {
        self.tension.reset_warm_start();
    }

    /// The tensions' warm start, a first-root search the cycle's budget cut, and the
    /// end-effector tracking.
    fn reset(&mut self) {
        self.tension.reset_warm_start();
        self.modal.forget_pending();
        self.modal.reset_tracking();
    }

    /// The SQP iterations of the sagged tension solve (the rest default).
    fn tension_info(&self) -> TensionInfo {
        TensionInfo {
            iterations: self.tension.info().iterations,
            ..TensionInfo::default()
        }
    }

    /// At geometry `g` (the chords at `pose`): the sagged tension distribution for the
    /// per-cable bounds (N, on the end-effector-end tension), shown to `on_tensions` (also
    /// when it failed), the chains on the catenaries, and the first root (Newton from the
    /// predicted λ `warm`, rad²/s², cold when None). No rank check (`min_rank` unused):
    /// the sagged tension distribution has none.
    fn first_root(
        &mut self,
        scene: &Scene,
        pose: &Pose,
        g: &Geometry,
        t_min_n: &[f64],
        t_max_n: &[f64],
        _min_rank: u32,
        warm: Option<f64>,
        on_tensions: impl FnOnce(TensionReport<'_>),
    ) -> Result<Root, EstimatorError> {
        let w = scene.wrench6_n();
        let res = self
            .tension
            .solve(
                g,
                &self.materials,
                &scene.gravity_m_s2,
                &w,
                t_min_n,
                t_max_n,
            )
            .map(|_| ());
        on_tensions(TensionReport {
            iterations: self.tension.info().iterations,
            warm: false,
            tensions_n: self.tension.tensions_n(),
        });
        res?;
        self.load(scene, pose, g)?;
        self.loaded_at = self.modal.evaluations();
        self.modal
            .begin_cycle(self.modal.params().cycle_evaluations);
        Ok(self.modal.first_root(warm)?)
    }

    /// The static end-effector stiffness of the loaded pose (3 × 3 or 6 × 6 block), N/m;
    /// NaN when D(0) fails.
    fn static_stiffness(&self, _scene: &Scene, _g: &Geometry) -> Matrix6<f64> {
        self.modal
            .static_stiffness()
            .unwrap_or(Matrix6::repeat(f64::NAN))
    }

    /// The dense reference's K (N/m) and M (kg) of the loaded pose (FEM chains only).
    fn dense_matrices(
        &self,
        _scene: &Scene,
        g: &Geometry,
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), ModalError> {
        if self.modal.is_continuous() {
            return Err(ModalError::NotAssemblable);
        }
        let n = self.frames.len();
        let (m6, k6) = self.modal.ee_matrices();
        let up = self.tension.basis(0)[1];
        let mut cables = Vec::with_capacity(n);
        for i in 0..n {
            cables.push(SagDenseCable {
                chain: self.modal.chain(i),
                h: self.frames[i].h,
                arm_m: g.arm_m[i],
            });
        }
        assemble_sagged(&cables, &up, &m6, &k6, self.modal.dim())
    }

    /// The end-effector mode (λ in rad²/s², participation) within what is left of this
    /// cycle's budget, tracked from the last cycle ([`SagModalSolver::ee_mode_tracked`];
    /// `r1` this cycle's first root): Ok(None) while the work goes on over the cycles
    /// (`warm` false restarts it). Continuous cables too: their mesh rule
    /// ([`SagContinuousParams`]) holds its tolerance up to `max_halfwaves` per cable and its
    /// error grows as λ above (the real-time rule's answers are within ~4e-4 in λ of the
    /// extrapolated FEM on the bench circles, tests/sag/ee_mode_continuous.rs).
    fn ee_mode(&mut self, r1: &Root, warm: bool) -> Result<Option<(f64, f64)>, ModalError> {
        Ok(self
            .modal
            .ee_mode_tracked(r1, warm)?
            .map(|m| (m.lambda, m.ee_participation)))
    }
}

/// Cable `i`'s chain for the scene's element on catenary `cat`.
fn set_chain(
    modal: &mut SagModalSolver,
    i: usize,
    scene: &Scene,
    cat: &Catenary,
    mu_kg_m: f64,
) -> Result<(), EstimatorError> {
    if modal.is_continuous() {
        return modal
            .set_continuous(i, cat, mu_kg_m)
            .map(|_| ())
            .map_err(EstimatorError::SagModel);
    }
    let n_el = scene.model.elements_per_cable.clamp(1, MAX_ELEMENTS);
    modal
        .chain_mut(i)
        .set_fem(cat, mu_kg_m, n_el)
        .map_err(|e| EstimatorError::SagModel(SagLoadError::Chain(i, e)))
}

/// The base translation of a chain whose exit point moves (cable on swivel pulley `e`,
/// catenary `cat` in the plane (h, up)), per displacement of its end:
/// X = (I − τ_a sᵀ) ∂A/∂B ([`SagModalSolver::set_exit_motion`]). The statics place the exit
/// point A by the chord (the straight line from the pulley to the attachment point, the
/// sagged tension distribution's simplification), so ∂A/∂B is the chord geometry's; the
/// cable leaves A along its catenary tangent τ_a = (H h + V_a up)/T_a, and slides over the
/// pulley by the wrap arc's change s·δA.
fn exit_motion(
    e: &crate::kinematics::PulleyExit,
    cat: &Catenary,
    h: &Vector3<f64>,
    up: &Vector3<f64>,
) -> Matrix3<f64> {
    let ta = cat.h_n.hypot(cat.v_anchor_n);
    let tau = (h * cat.h_n + up * cat.v_anchor_n) / ta;
    (Matrix3::identity() - tau * e.unit.transpose()) * e.exit_jacobian()
}

/// Largest element count per cable (the scene's limit).
const MAX_ELEMENTS: usize = crate::scene::MAX_ELEMENTS_PER_CABLE;

/// Put cable `i`'s chain (set on `cat`) on the cable behind its exit point: the junction
/// moves along the catenary's tangent at the anchor, (H, V_a)/T_a in (h, up); the hidden
/// cable runs straight from the pulley to the drum, for a FEM chain as the free cable's
/// number of equal consistent-mass axial elements, for a continuous cable as the exact
/// axial bar (one spring when it is massless), as the taut models have it.
fn support_chain(
    modal: &mut SagModalSolver,
    i: usize,
    scene: &Scene,
    cat: &Catenary,
    hidden: &crate::cable::HiddenAxial,
) -> Result<(), EstimatorError> {
    let n_el = scene.model.elements_per_cable.clamp(1, MAX_ELEMENTS);
    // Continuous cables: the exact axial bar (n_el 0); massless: one spring.
    let nh = match (hidden.mu_kg_m > 0.0, modal.is_continuous()) {
        (true, true) => 0,
        (true, false) => n_el,
        (false, _) => 1,
    };
    let segment = crate::cable::Segment {
        k: hidden.ea_n * nh.max(1) as f64 / hidden.length_m,
        m: hidden.mu_kg_m * hidden.length_m / nh.max(1) as f64,
        n_el: nh,
    };
    let ta = cat.h_n.hypot(cat.v_anchor_n);
    let support = crate::cable::sagged::SagSupport {
        hidden: segment,
        direction: [cat.h_n / ta, cat.v_anchor_n / ta],
    };
    if modal.is_continuous() {
        return modal
            .support_continuous(i, Some(support))
            .map_err(EstimatorError::SagModel);
    }
    modal
        .chain_mut(i)
        .set_support(Some(support))
        .map_err(|e| EstimatorError::SagModel(SagLoadError::Chain(i, e)))
}
