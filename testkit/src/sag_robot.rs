//! Hand-made sagged robots for the sagged-FEM tests: each cable's catenary is given by its
//! own (L0, EA, w, H, V_a) and its plane by its horizontal unit h, so the tests need no
//! statics solver (the vibration problem only needs each cable's profile and frame; the
//! end points need not meet for the dense/structured comparison); the structured solver
//! loaded with one ([`solver_for`]) and the dense matrices of its chains ([`dense_matrices`]).
use cablevib::elastic_catenary::Catenary;
use cablevib::modal::sagged::{assemble_sagged, HangingCable, SagDenseCable, SagEndEffector};
use cablevib::modal::{ModalParams, SagModalSolver};
use nalgebra::{DMatrix, Matrix3, Vector3};

/// Gravity's magnitude, m/s².
pub const G: f64 = 9.81;

/// Up (the tests' gravity is −z).
pub fn up() -> Vector3<f64> {
    Vector3::z()
}

/// A robot of `n` cables around the end-effector: horizontal directions spread over the
/// circle, alternately cables from above (V < 0) and from below with the low point inside
/// the span (V_a < 0 < V_e); `mu` the mass per length, `ea` the
/// axial rigidity. `heavy` raises the weight and lowers H (sag/span ~ 1/6 on the lower
/// cables, Irvine's λ² ~ 10² ... 10³).
pub fn robot(n: usize, mu: f64, ea: f64, heavy: bool) -> Vec<HangingCable> {
    (0..n)
        .map(|i| {
            let phi = 2.0 * std::f64::consts::PI * (i as f64 + 0.3) / n as f64;
            let h = Vector3::new(phi.cos(), phi.sin(), 0.0);
            let l0 = 3.0 + 0.37 * i as f64;
            let w = mu * G;
            let h_n = if heavy {
                15.0 + 4.0 * i as f64
            } else {
                120.0 + 25.0 * i as f64
            };
            // Even: from an anchor above (V < 0 all along, descending to the end-effector);
            // odd: from below with the low point inside (V_a < 0 < V_e).
            let v_a = if i % 2 == 0 {
                -(0.6 * h_n + w * l0)
            } else {
                -0.35 * w * l0
            };
            // Attachment on the body's side toward the anchor, at its top for the cables
            // from above: (f·r) > 0, a stabilising rotational geometric stiffness.
            let z = if i % 2 == 0 { 0.2 } else { -0.2 };
            HangingCable {
                catenary: Catenary {
                    l0_m: l0,
                    ea_n: ea,
                    w_n_m: w,
                    h_n,
                    v_anchor_n: v_a,
                },
                mu_kg_m: mu,
                h,
                arm_m: Vector3::new(-0.15 * (phi + 0.4).cos(), -0.12 * (phi + 0.4).sin(), z),
            }
        })
        .collect()
}

/// A point-mass end-effector of 5 kg.
pub fn point() -> SagEndEffector {
    SagEndEffector::Point { mass_kg: 5.0 }
}

/// A rigid end-effector of 5 kg with a full (non-diagonal) inertia.
pub fn rigid() -> SagEndEffector {
    SagEndEffector::Rigid {
        mass_kg: 5.0,
        inertia_kg_m2: Matrix3::new(0.20, 0.01, -0.02, 0.01, 0.25, 0.015, -0.02, 0.015, 0.30),
    }
}

/// Pose k: every cable's H and V_a moved by a few per cent (a smooth path).
pub fn pose(base: &[HangingCable], k: usize, out: &mut [HangingCable]) {
    let t = k as f64 * 1e-3;
    for (i, (o, b)) in out.iter_mut().zip(base).enumerate() {
        *o = *b;
        let f = 1.0 + 0.05 * (t + i as f64).sin();
        o.catenary.h_n *= f;
        o.catenary.v_anchor_n *= f;
    }
}

/// The structured sagged solver loaded with `cables` (`n_el` FEM elements each, up = +z)
/// and the end-effector `ee`.
pub fn solver_for(cables: &[HangingCable], n_el: usize, ee: &SagEndEffector) -> SagModalSolver {
    let mut s = SagModalSolver::new(ModalParams::default(), cables.len(), n_el);
    s.load_catenaries(cables, n_el, &up(), ee).unwrap();
    s
}

/// The dense sagged K (N/m) and M (kg) of the chains loaded in `s` ([`assemble_sagged`]:
/// world-frame element matrices from the same element data, not D(λ)), with the
/// end-effector's mass matrix and geometric stiffness.
pub fn dense_matrices(s: &SagModalSolver, cables: &[HangingCable]) -> (DMatrix<f64>, DMatrix<f64>) {
    let dc: Vec<SagDenseCable> = cables
        .iter()
        .enumerate()
        .map(|(i, c)| SagDenseCable {
            chain: s.chain(i),
            h: c.h,
            arm_m: c.arm_m,
        })
        .collect();
    let (m6, k6) = s.ee_matrices();
    assemble_sagged(&dc, &up(), &m6, &k6, s.dim()).unwrap()
}
