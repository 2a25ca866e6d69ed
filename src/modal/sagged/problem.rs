//! The loaded problem of one pose ([`SagChains`]: the sagged chains, how each attaches to
//! the end-effector, its mass) and the evaluation of D(λ), D'(λ) and the blocked count.

use super::poles::SagPoles;
use super::{SagCableFrame, SagEndEffector, SagLoadError};
use crate::cable::sagged::{SagBatch, SagChain, SagChainEval, SagContinuous, SagContinuousParams};
use crate::kinematics::attach_map;
use crate::modal::engine::{quad, DynEval, SYM3};
use nalgebra::{Matrix3, Matrix6, SymmetricEigen, Vector3, Vector6};
use num_complex::Complex64;

/// The mode count reported for continuous cables (infinitely many modes): large enough
/// for any request, small enough that sums of counts do not overflow.
pub(super) const CONTINUOUS_MODES: usize = u32::MAX as usize / 2;
/// Poles memoized per chain beyond the FEM chain's own 3(N − 1): a hidden cable's lowest
/// ones and the junction's (higher ones are searched each time they are asked for).
const POLES_PER_SUPPORT: usize = 16;
/// Poles memoized per chain at most, whatever the mesh: the tracker asks for the poles
/// near the end-effector's mode, whose number below it is the cable's physics, not its
/// mesh (higher ones are searched each time they are asked for). Why a cap: 3(N − 1) slots
/// of 24 bytes per chain are 576 MB at 10⁶ elements on 8 cables, allocated before any
/// memory budget is checked.
const POLES_PER_CHAIN_MAX: usize = 256;
/// |h| must be 1 and h ⟂ up to this (relative): the basis is the caller's, rounding only.
const BASIS_TOL: f64 = 1e-9;

/// How one cable's end stiffness enters D: the four world-frame matrices that multiply
/// a, b, c of S_in = [a b; b c] and s_out: h hᵀ, h upᵀ + up hᵀ, up upᵀ, n nᵀ (3 × 3 as six
/// entries, [`SYM3`] order), and for a rigid body the same through the attachment map,
/// Gᵀ P G (6 × 6).
#[derive(Debug, Clone, Copy)]
pub(super) struct CableProj {
    p3: [[f64; 6]; 4],
    p6: [Matrix6<f64>; 4],
}

/// The sagged problem of one pose, as `load` leaves it (read-only on the hot path), and
/// its evaluation counter: the problem of [`SagModalSolver`](crate::modal::SagModalSolver),
/// which sets it up (`load`, `load_catenaries`, …) and solves it.
#[derive(Debug, Clone)]
pub struct SagChains {
    pub(in crate::modal) chains: Vec<SagChain>,
    /// The continuous chains (empty unless the solver was built for them) and their
    /// cached static evaluations; used instead of `chains` when `continuous`.
    pub(in crate::modal) cont: Vec<SagContinuous>,
    pub(in crate::modal) cont_static: Vec<SagChainEval>,
    pub(in crate::modal) continuous: bool,
    /// The FEM chains packed for the lockstep evaluation, when they all have one element
    /// count (`batched`); else they are evaluated one by one.
    batch: SagBatch,
    batched: bool,
    /// Each loaded FEM chain's S(0), S'(0) (set by [`Self::pack`]).
    static_fem: Vec<SagChainEval>,
    proj: Vec<CableProj>,
    /// Cables loaded.
    pub(in crate::modal) n: usize,
    /// 3 (point mass) or 6 (rigid body).
    pub(in crate::modal) dim: usize,
    /// End-effector mass, kg.
    ee_mass_kg: f64,
    /// diag(m I, I_world), kg and kg·m².
    pub(in crate::modal) m6: Matrix6<f64>,
    /// M6^{1/2} (the cluster participations' congruence).
    pub(in crate::modal) m6_sqrt: Matrix6<f64>,
    /// The tensions' rotational geometric stiffness (rigid body), N·m/rad, plus the
    /// swivel pulleys' own term ([`Self::add_exit_term`]; N/m in the translational block).
    pub(in crate::modal) k6: Matrix6<f64>,
    /// Each cable's map from the end's displacement to its chain's base translation,
    /// (I − τ_a sᵀ) ∂A/∂B (None: the base stays put; [`super::SagModalSolver::set_exit_motion`]).
    pub(in crate::modal) exit_map: Vec<Option<Matrix3<f64>>>,
    /// Each loaded cable's attachment arm, m (rigid body: the term's map G).
    arm: Vec<Vector3<f64>>,
    /// Whether `k6` holds a pulley term (a point mass's D then adds its translational block).
    pub(in crate::modal) has_exit: bool,
    /// Evaluations of D(λ) since the problem was built (a wrapping counter).
    pub(in crate::modal) evaluations: u32,
    /// A pose is loaded (the chains set since have not been loaded yet: false).
    pub(in crate::modal) loaded: bool,
    /// The chains' poles, found by their own counts and followed between loads
    /// (`poles`); shown to the searches while `follow` is set.
    pub(in crate::modal) poles: SagPoles,
    pub(in crate::modal) follow: bool,
    /// Each chain's blocked count and S' ([a, b, c] in plane, out of plane) at the last
    /// counted evaluation (the chains' shares of a mode and the chains' poles next to it).
    pub(in crate::modal) last_below: Vec<u32>,
    pub(in crate::modal) last_ds: Vec<[f64; 4]>,
    pub(in crate::modal) last_lambda: f64,
    /// The value of the evaluation counter where the cycle's budget ends (None:
    /// unlimited): no pole search goes past it.
    pub(in crate::modal) pole_budget_end: Option<u32>,
}

impl SagChains {
    /// Cable `i` has a continuous chain (the solver was built for them and i is in range).
    pub(super) fn check_continuous_index(&self, i: usize) -> Result<(), SagLoadError> {
        if !self.continuous || i >= self.cont.len() {
            return Err(SagLoadError::CableCount {
                given: i + 1,
                capacity: self.cont.len(),
            });
        }
        Ok(())
    }

    /// Room for `n_cables` chains of up to `n_el_max` elements each (the only allocation).
    pub(in crate::modal) fn new(
        n_cables: usize,
        n_el_max: usize,
        continuous: Option<SagContinuousParams>,
    ) -> SagChains {
        let zero = CableProj {
            p3: [[0.0; 6]; 4],
            p6: [Matrix6::zeros(); 4],
        };
        let n_cont = if continuous.is_some() { n_cables } else { 0 };
        let cont_params = continuous.unwrap_or_default();
        SagChains {
            chains: (0..n_cables).map(|_| SagChain::new(n_el_max)).collect(),
            cont: (0..n_cont)
                .map(|_| SagContinuous::new(cont_params))
                .collect(),
            cont_static: vec![SagChainEval::default(); n_cont],
            continuous: continuous.is_some(),
            batch: SagBatch::new(if continuous.is_some() { 0 } else { n_cables }, n_el_max),
            batched: false,
            static_fem: vec![SagChainEval::default(); n_cables],
            proj: vec![zero; n_cables],
            n: 0,
            dim: 3,
            ee_mass_kg: 0.0,
            m6: Matrix6::zeros(),
            m6_sqrt: Matrix6::zeros(),
            k6: Matrix6::zeros(),
            exit_map: vec![None; n_cables],
            arm: vec![Vector3::zeros(); n_cables],
            has_exit: false,
            evaluations: 0,
            loaded: false,
            poles: SagPoles::new(
                n_cables,
                (3 * n_el_max + POLES_PER_SUPPORT).min(POLES_PER_CHAIN_MAX),
            ),
            follow: false,
            last_below: vec![0; n_cables],
            last_ds: vec![[0.0; 4]; n_cables],
            last_lambda: f64::NAN,
            pole_budget_end: None,
        }
    }

    /// The end-effector's mass matrix and its square root; clears the geometric stiffness.
    pub(super) fn set_end_effector(&mut self, ee: &SagEndEffector) -> Result<(), SagLoadError> {
        let (mass, inertia) = match *ee {
            SagEndEffector::Point { mass_kg } => (mass_kg, None),
            SagEndEffector::Rigid {
                mass_kg,
                inertia_kg_m2,
            } => (mass_kg, Some(inertia_kg_m2)),
        };
        if !(mass > 0.0 && mass.is_finite()) {
            return Err(SagLoadError::BadMass);
        }
        self.ee_mass_kg = mass;
        self.m6 = Matrix6::zeros();
        self.m6_sqrt = Matrix6::zeros();
        self.k6 = Matrix6::zeros();
        self.has_exit = false;
        for i in 0..3 {
            self.m6[(i, i)] = mass;
            self.m6_sqrt[(i, i)] = mass.sqrt();
        }
        self.dim = 3;
        if let Some(j) = inertia {
            let e = SymmetricEigen::new(j);
            if !(j.iter().all(|x| x.is_finite()) && e.eigenvalues.min() > 0.0) {
                return Err(SagLoadError::BadMass);
            }
            let root = e.eigenvectors
                * Matrix3::from_diagonal(&e.eigenvalues.map(f64::sqrt))
                * e.eigenvectors.transpose();
            self.m6.fixed_view_mut::<3, 3>(3, 3).copy_from(&j);
            self.m6_sqrt.fixed_view_mut::<3, 3>(3, 3).copy_from(&root);
            self.dim = 6;
        }
        Ok(())
    }

    /// Cable i's projectors from its frame (chain i must be set), and its share of the
    /// rigid body's geometric stiffness: (f·r) I − sym(f rᵀ) for the end force f at arm r.
    pub(super) fn set_cable(
        &mut self,
        i: usize,
        frame: &SagCableFrame,
        up: &Vector3<f64>,
    ) -> Result<(), SagLoadError> {
        let h = frame.h;
        let finite = h.iter().chain(up.iter()).all(|x| x.is_finite());
        if !(finite
            && (h.norm_squared() - 1.0).abs() <= BASIS_TOL
            && (up.norm_squared() - 1.0).abs() <= BASIS_TOL
            && h.dot(up).abs() <= BASIS_TOL)
        {
            return Err(SagLoadError::BadFrame(i));
        }
        let n = h.cross(up);
        let mats = [
            h * h.transpose(),
            h * up.transpose() + up * h.transpose(),
            up * up.transpose(),
            n * n.transpose(),
        ];
        self.arm[i] = frame.arm_m;
        let pr = &mut self.proj[i];
        for (q, m) in mats.iter().enumerate() {
            for (j, &(r, c)) in SYM3.iter().enumerate() {
                pr.p3[q][j] = m[(r, c)];
            }
        }
        if self.dim == 6 {
            let (r, f) = (frame.arm_m, frame.end_force_n);
            if !(r.iter().chain(f.iter()).all(|x| x.is_finite())) {
                return Err(SagLoadError::BadFrame(i));
            }
            let g = attach_map(&r);
            for (q, m) in mats.iter().enumerate() {
                pr.p6[q] = g.transpose() * m * g;
            }
            let fr = f * r.transpose();
            let kg = Matrix3::identity() * f.dot(&r) - (fr + fr.transpose()) * 0.5;
            let mut rot = self.k6.fixed_view_mut::<3, 3>(3, 3);
            rot += kg;
        }
        Ok(())
    }

    /// The accumulator of D(λ), D'(λ) and the blocked count before any cable is added.
    #[inline]
    fn start(&self, lambda: f64) -> Acc {
        if self.dim == 3 {
            let m = self.ee_mass_kg;
            let mut d = [-lambda * m, -lambda * m, -lambda * m, 0.0, 0.0, 0.0];
            if self.has_exit {
                for (j, &(r, c)) in SYM3.iter().enumerate() {
                    d[j] += self.k6[(r, c)];
                }
            }
            Acc::Point {
                d,
                dd: [-m, -m, -m, 0.0, 0.0, 0.0],
                below: 0,
            }
        } else {
            Acc::Rigid {
                d: self.k6 - self.m6 * lambda,
                dd: -self.m6,
                below: 0,
            }
        }
    }

    /// vᵀ D_i v for chain i's share D_i = Σ_q s_q P_q of D with `s` = [a, b, c, s_out] (its
    /// S or S' in the cable's basis), over the leading `dim` block.
    pub(super) fn chain_quad(&self, i: usize, s: &[f64; 4], v: &Vector6<f64>) -> f64 {
        let mut w = 0.0;
        for (q, &sq) in s.iter().enumerate() {
            let pq = if self.dim == 6 {
                quad(&self.proj[i].p6[q], v, 6)
            } else {
                let (p, x, y, z) = (&self.proj[i].p3[q], v[0], v[1], v[2]);
                x * x * p[0]
                    + y * y * p[1]
                    + z * z * p[2]
                    + 2.0 * (x * y * p[3] + x * z * p[4] + y * z * p[5])
            };
            w += sq * pq;
        }
        w
    }

    /// Add cable i's end stiffness `e` to the accumulator.
    #[inline]
    fn add(&self, acc: &mut Acc, i: usize, e: &SagChainEval) {
        let s = [e.s_in[0], e.s_in[1], e.s_in[2], e.s_out];
        let ds = [e.ds_in[0], e.ds_in[1], e.ds_in[2], e.ds_out];
        match acc {
            Acc::Point { d, dd, below } => {
                let p = &self.proj[i].p3;
                for j in 0..6 {
                    d[j] += s[0] * p[0][j] + s[1] * p[1][j] + s[2] * p[2][j] + s[3] * p[3][j];
                    dd[j] += ds[0] * p[0][j] + ds[1] * p[1][j] + ds[2] * p[2][j] + ds[3] * p[3][j];
                }
                *below += e.below;
            }
            Acc::Rigid { d, dd, below } => {
                // Entry by entry, q = 0..4 in order: the sums of `d += P_q s_q` bit for
                // bit, in one pass over D and D' instead of eight.
                let p = &self.proj[i].p6;
                let (p0, p1) = (p[0].as_slice(), p[1].as_slice());
                let (p2, p3) = (p[2].as_slice(), p[3].as_slice());
                let (d, dd) = (d.as_mut_slice(), dd.as_mut_slice());
                for e in 0..36 {
                    d[e] = d[e] + p0[e] * s[0] + p1[e] * s[1] + p2[e] * s[2] + p3[e] * s[3];
                    dd[e] = dd[e] + p0[e] * ds[0] + p1[e] * ds[1] + p2[e] * ds[2] + p3[e] * ds[3];
                }
                *below += e.below;
            }
        }
    }

    /// D, D' and the blocked count from the chains' evaluations `ev(i)`, each passed to
    /// `sink` as it is added.
    #[inline]
    fn assemble(
        &self,
        lambda: f64,
        ev: impl Fn(usize) -> SagChainEval,
        mut sink: impl FnMut(usize, &SagChainEval),
    ) -> DynEval {
        let mut acc = self.start(lambda);
        for i in 0..self.n {
            let e = ev(i);
            sink(i, &e);
            self.add(&mut acc, i, &e);
        }
        acc.finish()
    }

    /// Pack the loaded FEM chains for the lockstep evaluation (no allocation); chains of
    /// different element counts stay on the one-by-one path.
    /// Also caches each chain's static evaluation.
    pub(super) fn pack(&mut self) {
        self.poles.clear();
        self.batched = !self.continuous && self.batch.pack(&self.chains[..self.n]);
        if self.continuous {
            return;
        }
        let cache = &mut self.static_fem;
        if self.batched {
            self.batch.eval_with(0.0, true, |i, e| cache[i] = *e);
        } else {
            for (c, chain) in cache.iter_mut().zip(&self.chains[..self.n]) {
                *c = chain.eval(0.0);
            }
        }
    }

    /// D(λ), D'(λ) and Σ_cables blocked count (every chain's recurrence; not counted: the
    /// counted evaluation is [`Condensed::eval`](crate::modal::Condensed::eval)); without
    /// `derivative` D' is not computed (it holds −M only): for evaluations that only count.
    pub(super) fn evaluate_with(&self, lambda: f64, derivative: bool) -> DynEval {
        self.evaluate_into(lambda, derivative, |_, _| {})
    }

    /// [`Self::evaluate_with`], each chain's evaluation passed to `sink` (chain, S_i).
    pub(super) fn evaluate_into(
        &self,
        lambda: f64,
        derivative: bool,
        mut sink: impl FnMut(usize, &SagChainEval),
    ) -> DynEval {
        if self.continuous {
            self.assemble(lambda, |i| self.cont[i].eval(lambda), sink)
        } else if self.batched {
            let mut acc = self.start(lambda);
            self.batch.eval_with(lambda, derivative, |i, e| {
                sink(i, e);
                self.add(&mut acc, i, e)
            });
            acc.finish()
        } else {
            self.assemble(lambda, |i| self.chains[i].eval(lambda), sink)
        }
    }

    /// D(λ), D'(λ) and the blocked count by the chains' one-by-one recurrence
    /// ([`SagChain::eval`]), the reference of the lockstep evaluation (counted as an
    /// evaluation too).
    pub fn eval_reference(&mut self, lambda: f64) -> DynEval {
        self.evaluations = self.evaluations.wrapping_add(1);
        if self.continuous {
            return self.evaluate_with(lambda, true);
        }
        self.assemble(lambda, |i| self.chains[i].eval(lambda), |_, _| {})
    }

    /// D(λ) at a complex λ (the damped frequency response, `frf`), the FEM chains only:
    /// the same assembly as [`Self::eval`] with each chain's in-plane and out-of-plane
    /// recurrences at complex λ ([`SagChain::eval_at`]). None for continuous cables (their
    /// Magnus propagator is real). Point mass: the leading 3 × 3 block.
    pub(in crate::modal) fn d_complex(&self, lambda: Complex64) -> Option<Matrix6<Complex64>> {
        if self.continuous {
            return None;
        }
        let re = |x: f64| Complex64::new(x, 0.0);
        let mut d = if self.dim == 3 {
            let mut d = Matrix6::from_element(re(0.0));
            for r in 0..3 {
                d[(r, r)] = -lambda * self.ee_mass_kg;
            }
            if self.has_exit {
                for r in 0..3 {
                    for c in 0..3 {
                        d[(r, c)] += re(self.k6[(r, c)]);
                    }
                }
            }
            d
        } else {
            self.k6.map(re) - self.m6.map(re) * lambda
        };
        for (i, chain) in self.chains[..self.n].iter().enumerate() {
            let (s_in, s_out) = chain.eval_at(lambda);
            let s = [s_in[0], s_in[1], s_in[2], s_out];
            let pr = &self.proj[i];
            for (q, &sq) in s.iter().enumerate() {
                if self.dim == 6 {
                    d += pr.p6[q].map(|x| re(x) * sq);
                } else {
                    for (j, &(r, c)) in SYM3.iter().enumerate() {
                        let v = re(pr.p3[q][j]) * sq;
                        d[(r, c)] += v;
                        if r != c {
                            d[(c, r)] += v;
                        }
                    }
                }
            }
        }
        Some(d)
    }

    /// Add the swivel pulleys' own term to `k6` (after [`Self::pack`]: it reads the chains'
    /// static evaluations). A chain whose exit point moves, δA = ∂A/∂B δB, with the cable
    /// sliding over the pulley (the junction moves along the anchor tangent τ_a with the
    /// hidden cable stretched by the wrap arc's change s·δA), is the loaded chain with its
    /// base translated by (I − τ_a sᵀ) ∂A/∂B δB = X δB; the chain is translation-invariant
    /// statically, so its end force changes by −S(0)(δB − X δB): the term is −S(0) X, the
    /// chain's static stiffness S(0) in world coordinates. Its symmetric part is added
    /// (D must be symmetric; the chord-geometry statics leave a skew part, measured in
    /// docs/pulleys.md), through G = [I, −[r]×] on a rigid body. Massless, so the same at
    /// every λ, as the taut term. No allocation.
    pub(super) fn add_exit_term(&mut self) {
        for i in 0..self.n {
            let Some(x) = self.exit_map[i] else { continue };
            let e = if self.continuous {
                self.cont_static[i]
            } else {
                self.static_fem[i]
            };
            let s = [e.s_in[0], e.s_in[1], e.s_in[2], e.s_out];
            let p = &self.proj[i].p3;
            let mut k = Matrix3::zeros();
            for (j, &(r, c)) in SYM3.iter().enumerate() {
                let v = s[0] * p[0][j] + s[1] * p[1][j] + s[2] * p[2][j] + s[3] * p[3][j];
                k[(r, c)] = v;
                k[(c, r)] = v;
            }
            let t = -(k * x);
            let t = (t + t.transpose()) * 0.5;
            if self.dim == 6 {
                let g = attach_map(&self.arm[i]);
                self.k6 += g.transpose() * t * g;
            } else {
                let mut b = self.k6.fixed_view_mut::<3, 3>(0, 0);
                b += t;
            }
            self.has_exit = true;
        }
    }

    /// D(0) and D'(0) from the chains' cached static evaluations (no recurrence).
    pub(in crate::modal) fn static_eval(&self) -> DynEval {
        if self.continuous {
            self.assemble(0.0, |i| self.cont_static[i], |_, _| {})
        } else {
            self.assemble(0.0, |i| self.static_fem[i], |_, _| {})
        }
    }

    /// Number of natural frequencies: the end-effector's DOF plus every blocked one
    /// (unbounded for continuous cables: [`CONTINUOUS_MODES`]).
    pub(in crate::modal) fn total_modes(&self) -> usize {
        if self.continuous {
            return CONTINUOUS_MODES;
        }
        self.dim
            + self.chains[..self.n]
                .iter()
                .map(|c| c.blocked_modes())
                .sum::<usize>()
    }
}

/// D(λ), D'(λ) and the blocked count being summed over the cables (one on the stack per
/// evaluation: boxing the large variant would allocate on the real-time path).
#[allow(clippy::large_enum_variant)]
enum Acc {
    /// Point mass: the six distinct entries ([`SYM3`] order).
    Point {
        d: [f64; 6],
        dd: [f64; 6],
        below: u32,
    },
    /// Rigid body.
    Rigid {
        d: Matrix6<f64>,
        dd: Matrix6<f64>,
        below: u32,
    },
}

impl Acc {
    #[inline]
    fn finish(self) -> DynEval {
        match self {
            Acc::Point { d, dd, below } => {
                let (mut d6, mut dd6) = (Matrix6::zeros(), Matrix6::zeros());
                for (j, &(r, c)) in SYM3.iter().enumerate() {
                    d6[(r, c)] = d[j];
                    d6[(c, r)] = d[j];
                    dd6[(r, c)] = dd[j];
                    dd6[(c, r)] = dd[j];
                }
                DynEval {
                    d: d6,
                    dd: dd6,
                    below,
                    dim: 3,
                }
            }
            Acc::Rigid { d, dd, below } => DynEval {
                d,
                dd,
                below,
                dim: 6,
            },
        }
    }
}
