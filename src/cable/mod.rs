//! Cable element models and their decomposition into scalar chains.
//!
//! Each cable is split into N equal elements from its anchor (node I of the first
//! element) to the end-effector (node J of the last one), 3 translational DOF per node.
//! Every element of a cable has the same chord, tension T (N) and length l = L/N (m), so
//! every element has the same 3 × 3 stiffness block K_c (N/m) and the element matrices
//!
//! ```text
//!     K_e = [ K_c  −K_c ; −K_c  K_c ],      M_e = (μ l / 6) [ 2I  I ; I  2I ]   (Eq. 16)
//! ```
//!
//! - FEM element (Eqs. 16-18): K_c = EA/l · e eᵀ + T/l · (I − e eᵀ) (the sum of K_L and K_G).
//! - Catenary element (Eqs. 19-32) in the cancellation-free form of docs/model.md:
//!   the flexibility F (m/N) in a local frame whose z axis points up (against gravity),
//!   K_c = −F⁻¹ (F is negative definite in the paper's sign convention), rotated to the
//!   global frame. Uses the chord as unstressed length L0 and the QP tension T0 (Step 3).
//!
//! With K_c = Σ_r k_r v_r v_rᵀ (eigen-decomposition), the cable's interior nodes decouple
//! into scalar *chains*: uniform spring-mass chains with spring k_r (N/m) and consistent
//! element mass m_e = μ l (kg), fixed at the anchor and attached to the end-effector along
//! v_r. The FEM element has one axial chain (k = EA/l, direction e) and a transverse chain
//! of multiplicity 2 (k = T/l, projector I − e eᵀ). See [`Chain`].
//!
//! Files: `element` (the FEM and catenary element blocks), `chain` (one uniform chain's
//! dynamic stiffness: closed form for N elements, and the continuous limit) and `batch`
//! (many chains at one λ in fixed 8-lane blocks, with an AVX2 build chosen at run time).
//! `sagged`: a sagging cable's FEM chain on its elastic catenary (non-uniform elements,
//! 2 × 2 in-plane blocks), condensed onto its end by a block recurrence.

use crate::scene::ElementKind;
use nalgebra::{Matrix3, Vector3};

mod batch;
mod chain;
mod element;
pub mod sagged;
mod scalar;

pub use crate::kinematics::up_frame;
pub use batch::{eval_continuous_batch, eval_discrete_batch, BATCH_MAX_ELEMENTS};
pub use chain::supported::{
    eval_supported, supported_end_mass, supported_from_parts, supported_n_poles, supported_pole,
    supported_pole_near, supported_static, Segment,
};
pub use chain::{
    chain_recurrence, end_mass_q, eval_discrete_recurrence, Chain, ChainEval, ChainKind,
};
pub use element::{catenary_block, catenary_flexibility, catenary_modes, fem_block};
pub use scalar::ChainScalar;

/// Errors of the element models.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum CableError {
    /// Tension not positive and finite.
    #[error("cable tension {0} N must be finite and > 0")]
    BadTension(f64),
    /// The element cannot hang: a vertical element whose tension is below its own weight
    /// (the catenary's low point would need a slack segment).
    #[error("catenary element cannot carry its own weight (tension {tension_n:?} N, element weight {weight_n:?} N)")]
    TooSlack {
        /// Tension, N.
        tension_n: f64,
        /// Element weight γ L0, N.
        weight_n: f64,
    },
    /// The flexibility matrix is singular or not definite (numerically broken input).
    #[error("catenary flexibility matrix is not definite")]
    NotDefinite,
    /// The `auto` model must be resolved (estimator::resolve_auto) before use.
    #[error("the auto model is not resolved")]
    Unresolved,
    /// The model and the hidden cable do not match (the auto model, or a chain that is not
    /// the element's own).
    #[error("a hidden cable (hidden_length) needs a resolved element model (fem, continuous, massless or catenary)")]
    HiddenNotModelled,
    /// The hidden cable's data are not positive and finite.
    #[error("hidden cable: length {length_m:?} m, EA {ea_n:?} N, mass per length {mu_kg_m:?} kg/m (length and EA must be finite and > 0, mass ≥ 0)")]
    BadHidden {
        /// Axial length behind the exit point, m.
        length_m: f64,
        /// EA, N.
        ea_n: f64,
        /// μ, kg/m.
        mu_kg_m: f64,
    },
}

/// The cable behind a cable's exit point (the pulley), as the element models take it: its
/// axial length (the hidden cable, plus the wrap on the pulley), EA and mass per length.
/// Only its axial stretch and axial inertia act on the free cable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HiddenAxial {
    /// Axial length behind the exit point, m.
    pub length_m: f64,
    /// Axial rigidity EA, N.
    pub ea_n: f64,
    /// Mass per length μ, kg/m.
    pub mu_kg_m: f64,
}

/// A cable model's hidden part, for the dense assembly: the segment (drum fixed, junction
/// at the free cable's anchor node) and the direction the junction moves along (the free
/// cable's, anchor → end-effector).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HiddenPart {
    /// The hidden segment (the same element count as the free cable; 0: a continuous bar).
    pub segment: Segment,
    /// Unit direction of the junction's motion.
    pub direction: Vector3<f64>,
}

/// The model of one cable at one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CableModel {
    /// Element stiffness block K_c, N/m (global frame). For continuous and massless models,
    /// the block of the whole cable (N = 1).
    pub kc: Matrix3<f64>,
    /// Element mass μ l, kg (0 for massless cables).
    pub element_mass_kg: f64,
    /// Number of elements (1 for continuous and massless models).
    pub n_el: usize,
    /// Up to 3 chains.
    pub chains: [Chain; 3],
    /// Number of valid chains.
    pub n_chains: usize,
    /// Static end stiffness of this cable on the end-effector, N/m.
    pub static_stiffness: Matrix3<f64>,
    /// The cable behind the exit point, when it has one ([`Self::support_on_hidden`]).
    pub hidden: Option<HiddenPart>,
}

impl CableModel {
    /// Build the model of a cable with unit vector `e` (anchor → end-effector), length
    /// `length_m`, tension `tension_n`, axial rigidity `ea_n`, mass per length `mu_kg_m`,
    /// weight per length `gamma_n_m` (sag), model `kind` with `n` elements. `frame` is
    /// [`up_frame`] of the scene's gravity. `geometric` = false drops T/l (FEM, massless).
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        kind: ElementKind,
        n: usize,
        e: &Vector3<f64>,
        length_m: f64,
        tension_n: f64,
        ea_n: f64,
        mu_kg_m: f64,
        gamma_n_m: f64,
        frame: &Matrix3<f64>,
        geometric: bool,
    ) -> Result<CableModel, CableError> {
        if !(tension_n.is_finite() && tension_n > 0.0) {
            return Err(CableError::BadTension(tension_n));
        }
        let eet = e * e.transpose();
        let perp = Matrix3::identity() - eet;
        let t_geo = if geometric { tension_n } else { 0.0 };
        let zero_chain = Chain::idle();
        let mut chains = [zero_chain; 3];
        let (kc, me, nel, nch) = match kind {
            ElementKind::Fem | ElementKind::Massless => {
                let (nel, me) = if kind == ElementKind::Fem {
                    (n.max(1), mu_kg_m * length_m / n.max(1) as f64)
                } else {
                    (1, 0.0)
                };
                let l = length_m / nel as f64;
                chains[0] = Chain {
                    kind: ChainKind::Discrete {
                        k: ea_n / l,
                        m: me,
                        n_el: nel,
                    },
                    mult: 1,
                    proj: eet,
                };
                chains[1] = Chain {
                    kind: ChainKind::Discrete {
                        k: t_geo / l,
                        m: me,
                        n_el: nel,
                    },
                    mult: 2,
                    proj: perp,
                };
                (fem_block(e, l, ea_n, tension_n, geometric), me, nel, 2)
            }
            ElementKind::Continuous => {
                let mt = mu_kg_m * length_m;
                chains[0] = Chain {
                    kind: ChainKind::Continuous {
                        k_total: ea_n / length_m,
                        m_total: mt,
                    },
                    mult: 1,
                    proj: eet,
                };
                chains[1] = Chain {
                    kind: ChainKind::Continuous {
                        k_total: t_geo / length_m,
                        m_total: mt,
                    },
                    mult: 2,
                    proj: perp,
                };
                (fem_block(e, length_m, ea_n, tension_n, geometric), mt, 1, 2)
            }
            ElementKind::Auto => return Err(CableError::Unresolved),
            ElementKind::Catenary => {
                let nel = n.max(1);
                let l = length_m / nel as f64;
                // Chord from node I (anchor side) to node J: along e.
                let (kr, vr) = catenary_modes(&(e * l), tension_n, ea_n, gamma_n_m, frame)?;
                let me = mu_kg_m * l;
                let mut kc = Matrix3::zeros();
                for r in 0..3 {
                    kc += vr[r] * vr[r].transpose() * kr[r];
                    chains[r] = Chain {
                        kind: ChainKind::Discrete {
                            k: kr[r],
                            m: me,
                            n_el: nel,
                        },
                        mult: 1,
                        proj: vr[r] * vr[r].transpose(),
                    };
                }
                (kc, me, nel, 3)
            }
        };
        let mut model = CableModel {
            kc,
            element_mass_kg: me,
            n_el: nel,
            chains,
            n_chains: nch,
            static_stiffness: Matrix3::zeros(),
            hidden: None,
        };
        model.static_stiffness = model.sum_static();
        Ok(model)
    }

    /// Σ_chains P_c s_c(0), N/m.
    fn sum_static(&self) -> Matrix3<f64> {
        let mut ks = Matrix3::zeros();
        for c in &self.chains[..self.n_chains] {
            ks += c.proj * c.eval(0.0).s;
        }
        ks
    }

    /// Put the anchor end of this model (built by [`Self::build`] with `kind`, unit vector
    /// `e`) on the cable behind its exit point: the axial chain becomes the free cable in
    /// series with `hidden` (the pulley holds the junction transversely, so the transverse
    /// chains are unchanged). FEM: the hidden cable as the free cable's number of equal
    /// consistent-mass axial elements (one spring when it is massless); continuous: the
    /// exact axial bar; massless: the series spring EA/L_free ⊕ EA_h/L_h; catenary: the
    /// chain along K_c's stiffest eigenvector (the element's axial one, tilted from the
    /// chord by the element's sag) is supported, the hidden cable as for `fem` (a straight
    /// cable's catenary element is the FEM element: its axial chain is EA/l with the
    /// consistent mass), the junction moving along that eigenvector. No allocation.
    pub fn support_on_hidden(
        &mut self,
        kind: ElementKind,
        e: &Vector3<f64>,
        hidden: &HiddenAxial,
    ) -> Result<(), CableError> {
        let HiddenAxial {
            length_m,
            ea_n,
            mu_kg_m,
        } = *hidden;
        let usable = length_m.is_finite()
            && length_m > 0.0
            && ea_n.is_finite()
            && ea_n > 0.0
            && mu_kg_m.is_finite()
            && mu_kg_m >= 0.0;
        if !usable {
            return Err(CableError::BadHidden {
                length_m,
                ea_n,
                mu_kg_m,
            });
        }
        let axial = &mut self.chains[0];
        let segment = match (kind, axial.kind) {
            (ElementKind::Massless, ChainKind::Discrete { k, .. }) => {
                let kh = ea_n / length_m;
                let ks = k * kh / (k + kh);
                axial.kind = ChainKind::Discrete {
                    k: ks,
                    m: 0.0,
                    n_el: 1,
                };
                self.kc += (e * e.transpose()) * (ks - k);
                Segment {
                    k: kh,
                    m: 0.0,
                    n_el: 1,
                }
            }
            (ElementKind::Fem, ChainKind::Discrete { k, m, n_el }) => {
                // A massless hidden cable is one spring (a massless discrete chain is
                // evaluated as a single element).
                let nh = if mu_kg_m > 0.0 { n_el } else { 1 };
                let hidden = Segment {
                    k: ea_n * nh as f64 / length_m,
                    m: mu_kg_m * length_m / nh as f64,
                    n_el: nh,
                };
                axial.kind = ChainKind::Supported {
                    free: Segment { k, m, n_el },
                    hidden,
                };
                hidden
            }
            (ElementKind::Continuous, ChainKind::Continuous { k_total, m_total }) => {
                let hidden = Segment {
                    k: ea_n / length_m,
                    m: mu_kg_m * length_m,
                    n_el: 0,
                };
                axial.kind = ChainKind::Supported {
                    free: Segment {
                        k: k_total,
                        m: m_total,
                        n_el: 0,
                    },
                    hidden,
                };
                hidden
            }
            (ElementKind::Catenary, _) => {
                // The catenary element's chains lie along the eigenvectors of K_c, which a
                // sagging element tilts from the chord: the junction moves along the
                // stiffest (axial) one, the other two stay held by the pulley.
                let r = (0..self.n_chains)
                    .max_by(|&a, &b| {
                        let (ka, kb) = (chain_k(&self.chains[a]), chain_k(&self.chains[b]));
                        ka.total_cmp(&kb)
                    })
                    .unwrap_or(0);
                let ChainKind::Discrete { k, m, n_el } = self.chains[r].kind else {
                    return Err(CableError::BadHidden {
                        length_m,
                        ea_n,
                        mu_kg_m,
                    });
                };
                // The chain's direction: the projector's column of largest norm, signed
                // along the cable (anchor → end-effector).
                let proj = self.chains[r].proj;
                let col = (0..3)
                    .max_by(|&a, &b| proj.column(a).norm().total_cmp(&proj.column(b).norm()))
                    .unwrap_or(0);
                let mut v: Vector3<f64> = proj.column(col).normalize();
                if v.dot(e) < 0.0 {
                    v = -v;
                }
                let nh = if mu_kg_m > 0.0 { n_el } else { 1 };
                let hidden = Segment {
                    k: ea_n * nh as f64 / length_m,
                    m: mu_kg_m * length_m / nh as f64,
                    n_el: nh,
                };
                self.chains[r].kind = ChainKind::Supported {
                    free: Segment { k, m, n_el },
                    hidden,
                };
                self.hidden = Some(HiddenPart {
                    segment: hidden,
                    direction: v,
                });
                self.static_stiffness = self.sum_static();
                return Ok(());
            }
            _ => return Err(CableError::HiddenNotModelled),
        };
        self.hidden = Some(HiddenPart {
            segment,
            direction: *e,
        });
        self.static_stiffness = self.sum_static();
        Ok(())
    }
}

/// A discrete chain's element spring, N/m (−∞ for other kinds).
fn chain_k(c: &Chain) -> f64 {
    match c.kind {
        ChainKind::Discrete { k, .. } => k,
        _ => f64::NEG_INFINITY,
    }
}
