//! A sagging cable's vibration about its static (elastic catenary) profile, condensed onto
//! its end: the end dynamic stiffness S(λ) that the robot-level solver sums into D(λ).
//!
//! **Coordinates.** The cable hangs in the vertical plane through its anchor A and its end
//! P: h the horizontal unit from A toward P, up = −g/|g|, n = h × up out of the plane. The
//! profile (x(s), z(s)) in (h, up) and the tension T(s) come from
//! [`crate::elastic_catenary::Catenary`]; s ∈ [0, L0] is the unstretched arclength from the anchor.
//!
//! **The FEM chain** ([`SagChain`]). N equal elements of unstretched length l0 = L0/N,
//! nodes at s_j = j·l0 on the exact profile. Element j (from node j − 1 to node j) has the
//! chord c_j (unit, in plane) and chord length l_j between its nodes and the axial force
//! N_j = T(s at the element's middle). Its stiffness is the corotational truss tangent
//!
//! ```text
//!     K_e = (EA/l0) c cᵀ + (N_j/l_j)(I − c cᵀ)   on [1 −1; −1 1],
//!     M_e = (μ l0/6) [2I I; I 2I]                (consistent mass, m = μ l0 per element)
//! ```
//!
//! Since every chord lies in the cable's plane, K_e splits exactly into the in-plane 2 × 2
//! block k_j = (EA/l0) c cᵀ + (N_j/l_j)(I₂ − c cᵀ) in (h, up) and the out-of-plane scalar
//! spring N_j/l_j along n: two independent chains sharing the element mass m.
//!
//! **Condensation** ([`SagChain::eval`]). With A_j = k_j − (λm/3) I (element j's diagonal
//! block) and B_j = −k_j − (λm/6) I = −A_j − (λm/2) I (its coupling block), the end
//! stiffness S_j of the first j elements (anchor fixed, node j free) obeys
//!
//! ```text
//!     S_1 = A_1,
//!     Q_j = S_j + A_{j+1}                       (the block LDLᵀ pivot of interior node j)
//!     S_{j+1} = A_{j+1} − B_{j+1} Q_j⁻¹ B_{j+1}
//!             = S_j − λm I − E_j Q_j⁻¹ E_j,     E_j = S_j − (λm/2) I,
//! ```
//!
//! and S(λ) = S_N. The second form is the same Schur complement rewritten with
//! B = −(Q − E): at λ = 0 it is S − S(S + k)⁻¹S = S(S + k)⁻¹k (springs in series) with no
//! cancellation, where A − B Q⁻¹ B loses log₁₀ N digits. Next to a pole of a partial chain
//! (S_j large) it is the other way round: E Q⁻¹ E ≈ S_j cancels against S_j (measured: S
//! 76 % off next to a heavy stiff cable's axial pole, its blocked count flipping back and
//! forth over 1e-8 of λ), while B Q⁻¹ B is small. So each step takes the form whose terms
//! are smaller: the first when a norm of S_j (|a| + |c| + 2|b|) exceeds the element's
//! |k_a| + |k_c|, else the second; both are S_{j+1} = A − X Q⁻¹ X with (A, X) = (A_{j+1},
//! −B_{j+1}) or (S_j − λm I, E_j). The λ-derivative follows the recurrence forward: with
//! Y = Q⁻¹X,
//!
//! ```text
//!     S'_{j+1} = A' − (X'Y + Yᵀ X') + Yᵀ Q' Y,   Q' = S'_j − (m/3) I,
//!     (A', X') = (−(m/3) I, (m/6) I)  or  (S'_j − m I, S'_j − (m/2) I).
//! ```
//!
//! **Count** (Wittrick–Williams). The number of the chain's blocked (end held) eigenvalues
//! below λ is the number of negative eigenvalues of the pivots Q_1 … Q_{N−1} (Sylvester's
//! law of inertia on the block LDLᵀ of the interior's K − λM). A 2 × 2 pivot [a b; b c]
//! has one negative eigenvalue when ac − b² < 0, two when ac − b² > 0 and a < 0. A pivot
//! that is exactly singular (λ exactly on a blocked eigenvalue) is nudged by ε·(largest
//! element stiffness), as in the uniform chain's recurrence: the count then takes the
//! eigenvalue as not below λ, and S stays finite.
//!
//! **On a hidden cable** ([`SagSupport`], `supported`): the anchor node is the junction at
//! the pulley, moving along the cable's tangent there and held by the hidden cable's axial
//! segment; it is condensed onto node 1 in closed form, then the recurrence above runs
//! unchanged.
//!
//! **The continuous cable** ([`SagContinuous`]): the N → ∞ limit, by a 4th-order Magnus
//! chain of exact straight sub-segments (see its module docs).
//!
//! Cost: O(N) per evaluation, no allocation; the chain's element data are written into
//! buffers sized once by [`SagChain::new`].

mod batch;
mod chain;
mod continuous;
mod recurrence;
mod supported;

pub use batch::{SagBatch, SAG_LANES};
pub use chain::{SagChain, SagElement};
pub use continuous::*;
pub use supported::SagSupport;

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

/// Errors of the sagged chain's set-up (the evaluation itself cannot fail).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SagChainError {
    /// The element count is 0 or above the capacity given to [`SagChain::new`].
    #[error("{n_el} elements asked, the chain holds 1 ..= {capacity}")]
    ElementCount {
        /// Elements asked.
        n_el: usize,
        /// Capacity of the chain's buffers.
        capacity: usize,
    },
    /// A scalar input (EA, μ, L0) is not finite or out of range (EA, L0 > 0; μ ≥ 0).
    #[error("sagged chain input {name} = {value} is out of range")]
    BadInput {
        /// Which input.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// An element's axial force is not positive and finite (a slack point: no transverse
    /// stiffness), or its chord length is not.
    #[error("element {element}: axial force {axial_n} N, chord {chord_m} m (both must be finite and > 0)")]
    BadElement {
        /// Element index (0 at the anchor).
        element: usize,
        /// N_j, N.
        axial_n: f64,
        /// l_j, m.
        chord_m: f64,
    },
}

#[cfg(test)]
mod tests;
