//! Errors of the modal solvers.

/// Errors of the modal solvers.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ModalError {
    /// The static stiffness on the end-effector is not positive definite (slack cables, a
    /// mechanism): there is a zero or negative frequency.
    #[error(
        "static end-effector stiffness is not positive definite (smallest eigenvalue {0:.3e} N/m)"
    )]
    NotPositiveDefinite(f64),
    /// The bounded iteration ran out before the tolerance was met.
    #[error("eigen iteration did not converge in {evaluations} evaluations (bracket [{lo:.6e}, {hi:.6e}] rad²/s²)")]
    NoConvergence {
        /// Evaluations of D(λ) done.
        evaluations: u32,
        /// Lower end of the last bracket, rad²/s².
        lo: f64,
        /// Upper end of the last bracket, rad²/s².
        hi: f64,
    },
    /// No mode with enough end-effector participation within the scan bound (pole
    /// intervals scanned by the taut tracker, modes swept on sagged cables).
    #[error("no end-effector mode found within {0} pole intervals or modes")]
    NoEeMode(u32),
    /// The dense mass matrix is not positive definite (bad input).
    #[error("mass matrix is not positive definite")]
    MassNotDefinite,
    /// A dense symmetric eigen-solve failed (a non-finite entry, or its bounded iteration
    /// ran out).
    #[error("dense eigen-solve: {0}")]
    DenseEigen(#[from] super::sym_eigen::SymEigenError),
    /// The model cannot be assembled densely (continuous cables).
    #[error(
        "the continuous model has no finite assembly; use fem or catenary for the dense reference"
    )]
    NotAssemblable,
    /// The Wittrick-Williams certificate disagrees with the root found.
    #[error("eigenvalue count check failed at λ = {0:.6e} rad²/s²")]
    CountMismatch(f64),
    /// Nothing is loaded: no cycle has succeeded yet.
    #[error("no pose loaded: no successful cycle yet")]
    NotLoaded,
    /// The dense reference would need more memory than its budget.
    #[error("dense reference refused: {dof} DOF need about {bytes} bytes, over the budget of {budget} bytes (use the structured solver)")]
    DenseTooLarge {
        /// Degrees of freedom of the assembled model.
        dof: usize,
        /// Estimated memory of the dense solve, bytes.
        bytes: u64,
        /// The budget, bytes.
        budget: u64,
    },
}
