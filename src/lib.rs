//! # cablevib
//!
//! Vibration-aware estimation for cable-driven parallel robots (CDPRs): every control
//! cycle, the cable tensions, the end-effector stiffness and the first natural frequency of
//! a cable model, computed without heap allocation, blocking or unbounded loops.
//!
//! ## The model (Nguyen et al., "A novel modified analytical method and finite element
//! method for vibration analysis of cable-driven parallel robots", with the corrections
//! written down in `docs/model.md`)
//!
//! - **Kinematics** ([`kinematics`]): cable i runs from anchor a_i to the end-effector at
//!   p; s_i = (p − a_i)/L_i. The structure matrix A = [s_1 … s_n] (3 × n).
//! - **Tension distribution** ([`tension`]): minimise ½‖T‖² subject to A T = w,
//!   T_min ≤ T_i ≤ T_max (N), w = m g when the cables carry the weight.
//! - **Cable elements** ([`cable`]): N equal elements per cable, 3 DOF per node, consistent
//!   mass (μl/6)[2I I; I 2I]. FEM: K_c = EA/l e eᵀ + T/l (I − e eᵀ). Catenary: K_c = −F⁻¹
//!   with the flexibility F of paper Eq. 28 in the cancellation-free form of `docs/model.md`
//!   (section 5).
//! - **Modes** ([`modal`]): K u = λ M u, f = √λ / 2π (Hz). Dense reference: Cholesky
//!   reduction and a symmetric eigensolver (accuracy ε·λ_max/λ).
//!
//! ## Why the real-time path is fast and exact
//!
//! All elements of a cable are identical, so in the eigenbasis of K_c a cable's interior
//! nodes decouple into uniform scalar chains (spring k, element mass m). Condensing a chain
//! onto its end gives its dynamic stiffness in closed form (Chebyshev polynomials):
//!
//! ```text
//!   α = k − λm/3,  β = −k − λm/6,  c = −α/β,
//!   s_N(λ) = α + β U_{N−2}(c) / U_{N−1}(c)        (sin((N−1)θ)/sin(Nθ) for c = cos θ)
//! ```
//!
//! and for the continuous string or bar (N → ∞) s(λ) = (S/L) φ cot φ, φ = L√(λμ/S).
//! The end-effector's dynamic stiffness is D(λ) = Σ_chains s_c(λ) P_c − λ m_ee I (3 × 3).
//! The Wittrick–Williams count J(λ) = Σ_chains (blocked chain eigenvalues below λ) +
//! (negative eigenvalues of D(λ)) is the exact number of natural frequencies below λ.
//! Below the lowest blocked eigenvalue every eigenvalue of D decreases from the static
//! stiffness D(0) ≻ 0 to −∞, so f1 is the unique root of μ_min(D(λ)): a safeguarded Newton
//! iteration, warm-started from the last cycle and certified by the count, finds it to
//! ~1e-12 relative in a few evaluations, independent of N.
//!
//! A mode's *end-effector participation* is m_ee‖v‖² / vᵀ(−D′(λ))v for the null vector v
//! of D(λ): the share of the mode's kinetic-energy norm carried by the end-effector mass.
//! The *end-effector mode* is the lowest mode whose participation reaches the scene's
//! threshold (default 0.5); see [`modal::ModalSolver::ee_mode_tracked`].
//!
//! ## Layers
//!
//! This crate is the core: it builds the estimator and the offline studies with nothing of
//! iceoryx2, clap or the renderers. The workspace adds three crates on top of it:
//! `cablevib-ipc` (ipc-schema/: the wire messages, re-exporting [`status`]),
//! `cablevib-service` (service/: the iceoryx2 service) and `cablevib-cli` (cli/: reports,
//! the command line and the `cablevib` binary); the Python bindings (python/) use the core
//! alone. Each layer uses only the layers below it (`tests/layers/` checks every `crate::`
//! path and every crate's dependencies), so the code reads bottom-up; the modules are
//! declared below in layer order. The table of layers, what each module owns and a pose's
//! path through one cycle are in `docs/architecture.md`.
//!
//! ## Example
//!
//! The README's example (also `examples/estimate.rs`): f1 and the tensions along a line
//! through the paper's spatial robot.
//!
//! ```
#![doc = include_str!("../examples/estimate.rs")]
//! ```
#![warn(missing_docs)]
// Numerical kernels index several arrays with one loop variable; iterator chains would
// hide the maths. `!(x > 0.0)` is used on purpose: it is also true for NaN.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
// Layer 0
pub mod alloc_count;
pub mod eig3;
pub mod identify;
pub mod input_file;
pub mod memory_budget;
pub mod output_file;
pub mod rng;
mod simd;
pub mod status;
// Layer 1
pub mod measured;
pub mod scene;
pub mod stats;
// Layer 2
pub mod caspr;
pub mod elastic_catenary;
pub mod kinematics;
// Layer 3
pub mod cable;
pub mod tension;
pub mod trajectory;
// Layer 4
pub mod modal;
// Layer 5
pub mod estimator;
// Layer 6
pub mod calibration;
pub mod study;
// Layer 7: the names most programs need
pub mod prelude;
#[cfg(test)]
mod readme_tests {
    /// The README's Rust example is `examples/estimate.rs` (below its `//!` header), which
    /// the crate docs above run as a doctest: so the README's code compiles and runs.
    #[test]
    fn readme_example_is_the_doctested_example() {
        let root = env!("CARGO_MANIFEST_DIR");
        let readme = std::fs::read_to_string(format!("{root}/README.md")).expect("README.md");
        let example = std::fs::read_to_string(format!("{root}/examples/estimate.rs"))
            .expect("examples/estimate.rs");
        let blocks: Vec<&str> = readme
            .split("```rust\n")
            .skip(1)
            .map(|b| b.split("```").next().unwrap_or(""))
            .collect();
        assert_eq!(blocks.len(), 1, "one Rust block in README.md");
        let body: String = example
            .lines()
            .skip_while(|l| l.starts_with("//!"))
            .skip_while(|l| l.is_empty())
            .map(|l| format!("{l}\n"))
            .collect();
        assert_eq!(
            blocks[0], body,
            "README.md's example differs from examples/estimate.rs"
        );
    }
}
