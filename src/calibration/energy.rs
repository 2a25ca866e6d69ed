//! Analytic eigenvalue sensitivities from the structured mode shapes.
//!
//! For K φ = λ M φ with φ mass-normalised (φᵀMφ = 1), a parameter p moves a simple
//! eigenvalue by dλ/dp = φᵀ(∂K/∂p − λ ∂M/∂p)φ. The structured shapes give φ at every node
//! of every cable ([`crate::modal::ModeShapes`]), so each term is a sum of element energies
//! of the taut FEM (and massless) cables, K_e = EA/l e eᵀ + T/l (I − e eᵀ) on [1 −1; −1 1],
//! M_e = (μl/6)[2I I; I 2I]:
//!
//! - U_a,i = Σ_e (EA/l)(e·Δu)², the axial strain energy of cable i (×2), and U_h,i the
//!   same of its hidden cable (nodes y_j of the axial chain from the drum, y_0 = 0, to the
//!   junction's displacement along the cable: the uniform chain's interior equations
//!   β y_{j−1} + 2α y_j + β y_{j+1} = 0, α = k − λm/3, β = −k − λm/6, give the shape);
//! - U_t,i = Σ_e (T/l)|Δu − (e·Δu)e|², proportional to the tension;
//! - T_i = Σ_e (m_e/3)(|u_j|² + u_j·u_{j+1} + |u_{j+1}|²) (and T_h,i of the hidden cable), the
//!   kinetic norms; the end-effector's φ_tᵀφ_t (translation) and θ (rotation).
//!
//! Then, with f_i the EA factor of cable i, L_b,i its axial length behind the exit point
//! (hidden length plus wrapped arc), F_i the dynamic axial force of its first element on the
//! anchor node (e·[k_a(u_1 − u_0) + λ m_e(u_0/3 + u_1/6)]), γ the weight
//! per length, m the end-effector mass and T_i the tensions:
//!
//! - ∂λ/∂f_i = (U_a,i + U_h,i)/f_i (EA of the free and the hidden cable ∝ f_i);
//! - ∂λ/∂L_h,i = −(U_h,i + λ T_h,i)/L_b,i (the hidden elements' k ∝ 1/L_b, m ∝ L_b); at
//!   L_b = 0 its limit −F_i²/EA_h (a series compliance L/EA_h under the force F_i), which is
//!   also the exact value for the massless series spring;
//! - ∂λ/∂γ = −λ Σ_i (T_i + T_h,i)/γ (the cable mass ∝ γ; the taut tensions do not move);
//! - ∂λ/∂m = −λ φ_tᵀφ_t + Σ_i (dT_i/dm)(U_t,i/T_i + φ_eeᵀ ∂K_ee/∂T_i φ_ee), with dT/dm of the
//!   tension distribution's active set ([`tension_mass_derivative`]) and K_ee the rigid
//!   body's rotational geometric stiffness and the pulleys' term, both linear in T;
//! - ∂λ/∂I_kk = −λ (e_kᵀ Rᵀ θ)² (the body-frame inertia's diagonal).
//!
//! Σ_i (U_a,i + U_t,i + U_h,i) + φ_eeᵀ K_ee φ_ee = λ (the Rayleigh quotient), a check the
//! tests make. A cluster of m equal eigenvalues has no derivative of each member; the mean
//! of the members' diagonal terms is the derivative of the cluster's mean eigenvalue
//! (trace/m, independent of the basis), which is what a measured frequency of an unresolved
//! cluster sees.

use super::params::{Applied, ParamKind};
use crate::estimator::PoseModel;
use crate::modal::ModeShape;
use crate::tension::Bound;
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Vector3, Vector6};

/// The energies of one mode shape, per cable and at the end-effector.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ShapeEnergies {
    /// λ of the shape, rad²/s².
    pub lambda: f64,
    /// U_a,i: axial (free cable), N/m × (1/√kg)² = rad²/s².
    pub axial: Vec<f64>,
    /// U_t,i: transverse (∝ tension).
    pub transverse: Vec<f64>,
    /// U_h,i: the hidden cable's axial energy (0 without one, or when merged into `axial`
    /// as the massless series spring).
    pub hidden: Vec<f64>,
    /// T_i: kinetic norm of the free cable (dimensionless share of φᵀMφ = 1).
    pub kinetic: Vec<f64>,
    /// T_h,i: of the hidden cable.
    pub hidden_kinetic: Vec<f64>,
    /// F_i: the dynamic axial force of the first element on the anchor node (stiffness and
    /// consistent-mass terms), per unit modal amplitude, N/√kg.
    pub first_force: Vec<f64>,
    /// φ_ee: translation (1/√kg), then rotation (rad/(m·√kg), rigid body).
    pub ee: Vector6<f64>,
    /// φ_eeᵀ K_ee φ_ee: the rigid body's rotational geometric stiffness and the pulleys'.
    pub ee_stiffness: f64,
}

impl ShapeEnergies {
    /// λ minus the sum of the energies: zero to rounding when the shape and the element
    /// formulas agree.
    pub fn rayleigh_defect(&self) -> f64 {
        let u: f64 = (0..self.axial.len())
            .map(|i| self.axial[i] + self.transverse[i] + self.hidden[i])
            .sum();
        self.lambda - u - self.ee_stiffness
    }
}

/// Why the energies of a shape cannot be formed analytically.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EnergyError {
    /// A cable's node list does not match its element count.
    Layout,
    /// The hidden cable's shape is undefined: its own blocked resonance (the junction
    /// still) or a continuous bar.
    HiddenShape,
}

/// The energies of `shape` (a mode of `pm`, mass-normalised).
pub fn energies(pm: &PoseModel, shape: &ModeShape) -> Result<ShapeEnergies, EnergyError> {
    let n = pm.models.len();
    let lambda = shape.lambda;
    let mut e = ShapeEnergies {
        lambda,
        axial: vec![0.0; n],
        transverse: vec![0.0; n],
        hidden: vec![0.0; n],
        kinetic: vec![0.0; n],
        hidden_kinetic: vec![0.0; n],
        first_force: vec![0.0; n],
        ..ShapeEnergies::default()
    };
    for (i, model) in pm.models.iter().enumerate() {
        let u = &shape.cables[i];
        if u.len() != model.n_el + 1 {
            return Err(EnergyError::Layout);
        }
        let dir = pm.geometry.unit[i];
        let ka = dir.dot(&(model.kc * dir));
        let ktr = model.kc - dir * dir.transpose() * ka;
        let me = model.element_mass_kg;
        for j in 0..model.n_el {
            let du = u[j + 1] - u[j];
            let a = dir.dot(&du);
            e.axial[i] += ka * a * a;
            e.transverse[i] += du.dot(&(ktr * du));
            e.kinetic[i] +=
                me / 3.0 * (u[j].norm_squared() + u[j].dot(&u[j + 1]) + u[j + 1].norm_squared());
        }
        // The dynamic force of the first element on its anchor node, along the cable:
        // K_e and M_e's first row, e·[k_a(u_1 − u_0) + λ(m/3 u_0 + m/6 u_1)].
        e.first_force[i] =
            ka * dir.dot(&(u[1] - u[0])) + lambda * me * dir.dot(&(u[0] / 3.0 + u[1] / 6.0));
        if let Some(h) = &model.hidden {
            let seg = h.segment;
            if seg.n_el == 0 {
                return Err(EnergyError::HiddenShape);
            }
            if seg.m == 0.0 && seg.n_el == 1 && u[0] == Vector3::zeros() {
                // The massless series spring is merged into the axial chain (anchor still).
                continue;
            }
            let a = h.direction.dot(&u[0]);
            let (uh, th) = hidden_chain(seg.k, seg.m, seg.n_el, lambda, a)?;
            e.hidden[i] = uh;
            e.hidden_kinetic[i] = th;
        }
    }
    let phi = shape.ee;
    e.ee = phi;
    e.ee_stiffness = ee_quadratic(&ee_stiffness(pm, None), &phi);
    Ok(e)
}

/// The energy and kinetic norm of a uniform axial chain of `n` elements (spring k, element
/// mass m) held at node 0 whose node n moves by `a` at λ.
fn hidden_chain(k: f64, m: f64, n: usize, lambda: f64, a: f64) -> Result<(f64, f64), EnergyError> {
    let alpha = k - lambda * m / 3.0;
    let beta = -k - lambda * m / 6.0;
    let mut w = vec![0.0; n + 1];
    w[1] = 1.0;
    let mut peak = 1.0f64;
    for j in 1..n {
        w[j + 1] = -(2.0 * alpha * w[j] + beta * w[j - 1]) / beta;
        peak = peak.max(w[j + 1].abs());
        if peak > 1e150 {
            for v in w.iter_mut().take(j + 2) {
                *v /= peak;
            }
            peak = 1.0;
        }
    }
    let end = w[n];
    if !(end.abs() > 1e-9 * w.iter().fold(0.0f64, |s, v| s.max(v.abs()))) {
        return Err(EnergyError::HiddenShape);
    }
    let c = a / end;
    let (mut uh, mut th) = (0.0, 0.0);
    for j in 0..n {
        let (y0, y1) = (c * w[j], c * w[j + 1]);
        uh += k * (y1 - y0) * (y1 - y0);
        th += m / 3.0 * (y0 * y0 + y0 * y1 + y1 * y1);
    }
    Ok((uh, th))
}

fn ee_quadratic(k: &Matrix6<f64>, phi: &Vector6<f64>) -> f64 {
    phi.dot(&(k * phi))
}

/// K_ee of `pm` (rigid rotational geometric stiffness and the pulleys' term) at its
/// tensions, or its derivative with respect to cable `unit`'s tension (both are linear in T).
fn ee_stiffness(pm: &PoseModel, unit: Option<usize>) -> Matrix6<f64> {
    let n = pm.models.len();
    let t: Vec<f64> = match unit {
        None => pm.tensions_n.clone(),
        Some(c) => (0..n).map(|i| if i == c { 1.0 } else { 0.0 }).collect(),
    };
    let dim = pm.dim();
    let mut k = Matrix6::zeros();
    if pm.end_effector.rigid {
        let r =
            crate::kinematics::rigid_geometric_stiffness(&pm.geometry.unit, &pm.geometry.arm_m, &t);
        k.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
    }
    if pm.geometry.has_pulleys() {
        k += pm.geometry.pulley_stiffness(&t, dim);
    }
    k
}

/// dT/dm (N/kg) of the tension distribution min ½‖T‖² s.t. A T = m g, T_min ≤ T ≤ T_max at
/// the tensions of `pm` with the active bounds `bounds`: the cables at a bound stay there,
/// the free ones move by the minimum-norm A_F⁺ g (A_F: the structure matrix's free columns;
/// the solution of the free set's KKT system). Zero when the cables do not carry the weight.
pub fn tension_mass_derivative(pm: &PoseModel, bounds: &[Bound]) -> Vec<f64> {
    let s = &pm.scene;
    let n = pm.models.len();
    let mut out = vec![0.0; n];
    if !s.weight_carried {
        return out;
    }
    let dim = pm.dim();
    let free: Vec<usize> = (0..n).filter(|&i| bounds[i] == Bound::Free).collect();
    if free.is_empty() {
        return out;
    }
    let a = DMatrix::from_fn(dim, free.len(), |r, c| pm.geometry.a(r, free[c]));
    let mut w = DVector::zeros(dim);
    for r in 0..3 {
        w[r] = s.gravity_m_s2[r];
    }
    let Ok(pinv) = a.pseudo_inverse(1e-12) else {
        return out;
    };
    let dt = pinv * w;
    for (c, &i) in free.iter().enumerate() {
        out[i] = dt[c];
    }
    out
}

/// One pose's model as the sensitivities need it.
pub struct PoseContext<'a> {
    /// The model at the pose.
    pub pm: &'a PoseModel,
    /// The parameters' scene.
    pub applied: &'a Applied,
    /// The end-effector's orientation at the pose (body → world).
    pub rotation: Matrix3<f64>,
    /// dT/dm, N/kg ([`tension_mass_derivative`]).
    pub dt_dm: &'a [f64],
}

/// dλ/dp of the shape with energies `e` for the parameter `kind` at value `value`, or None
/// when it has no analytic form here (the centre of mass, the pulley radius: geometry that
/// moves every element). A damping parameter does not move λ: Some(0).
pub fn sensitivity(
    ctx: &PoseContext<'_>,
    e: &ShapeEnergies,
    kind: ParamKind,
    value: f64,
) -> Option<f64> {
    let (pm, dt_dm) = (ctx.pm, ctx.dt_dm);
    let lambda = e.lambda;
    let s = &ctx.applied.scene;
    Some(match kind {
        ParamKind::EaFactor(i) => (e.axial[i] + e.hidden[i]) / value,
        ParamKind::EaFactorAll => {
            (0..e.axial.len())
                .map(|i| e.axial[i] + e.hidden[i])
                .sum::<f64>()
                / value
        }
        ParamKind::HiddenLength(i) => {
            let c = &s.cables[i];
            let behind = c.hidden.map_or(0.0, |h| h.length_m) + pm.geometry.wrap_arc_m(i);
            let merged = pm.models[i]
                .hidden
                .is_some_and(|h| h.segment.m == 0.0 && h.segment.n_el == 1);
            if behind > 0.0 && !merged {
                -(e.hidden[i] + lambda * e.hidden_kinetic[i]) / behind
            } else {
                let ea_h = c.hidden.map_or(c.ea_n(), |h| h.ea_n());
                -e.first_force[i] * e.first_force[i] / ea_h
            }
        }
        ParamKind::WeightPerLength => {
            let mut t = 0.0;
            for (i, c) in s.cables.iter().enumerate() {
                t += e.kinetic[i];
                let follows = c
                    .hidden
                    .is_none_or(|h| h.mass_per_length_kg_m == c.mass_per_length_kg_m);
                if follows {
                    t += e.hidden_kinetic[i];
                }
            }
            -lambda * t / value
        }
        ParamKind::EeMass => {
            let mut d = -lambda * e.ee.fixed_rows::<3>(0).norm_squared();
            for (i, &dt) in dt_dm.iter().enumerate() {
                if dt != 0.0 {
                    let t = pm.tensions_n[i];
                    let k = ee_stiffness(pm, Some(i));
                    d += dt * (e.transverse[i] / t + ee_quadratic(&k, &e.ee));
                }
            }
            d
        }
        ParamKind::EeInertia(k) => {
            // World inertia R I Rᵀ: ∂/∂I_kk = R e_k e_kᵀ Rᵀ.
            let b = ctx.rotation.transpose() * e.ee.fixed_rows::<3>(3);
            -lambda * b[k] * b[k]
        }
        ParamKind::ModalRatio | ParamKind::RayleighAlpha | ParamKind::RayleighBeta => 0.0,
        ParamKind::EeCom(_) | ParamKind::PulleyRadius => return None,
    })
}
