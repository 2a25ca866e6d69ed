//! Sagged cables: the linearised dynamics of a cable about its elastic catenary
//! (`crate::sag::Catenary`), condensed onto its end-effector end.

mod continuous;
pub use continuous::*;

/// A sagged cable's end dynamic stiffness at λ = ω² (rad²/s²), seen from the end-effector,
/// in the cable's basis: (h, up) in plane, n out of plane. S(λ) = end force / end displacement
/// with the anchor fixed and the interior condensed (the analogue of `cable::ChainEval`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SagChainEval {
    /// In-plane S = [[a, b], [b, c]] as [a, b, c], N/m, basis (h, up).
    pub s_in: [f64; 3],
    /// dS_in/dλ as [a, b, c], kg.
    pub ds_in: [f64; 3],
    /// Out-of-plane s, N/m.
    pub s_out: f64,
    /// ds_out/dλ, kg.
    pub ds_out: f64,
    /// Blocked (end held) eigenvalues below λ, in-plane plus out-of-plane.
    pub below: u32,
}
