//! Parameters of the real-time solver.

/// Parameters of the active-set solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TensionParams {
    /// Largest number of active-set changes in a cold solve.
    pub max_iterations: usize,
    /// Bound violation tolerated, relative to max(1, T_max).
    pub feasibility_tol: f64,
}

impl Default for TensionParams {
    fn default() -> Self {
        TensionParams {
            max_iterations: 200,
            feasibility_tol: 1e-11,
        }
    }
}
