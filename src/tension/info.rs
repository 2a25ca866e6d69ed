//! What a solve reports besides the tensions: each cable's active bound and the solve's
//! statistics.

/// Which bound a cable sits on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Bound {
    /// Strictly between the bounds.
    #[default]
    Free,
    /// At T_min.
    Lower,
    /// At T_max.
    Upper,
}

/// What a solve did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TensionInfo {
    /// Active-set changes of the cold solve (0 when the warm start was accepted).
    pub iterations: u32,
    /// True when the previous active set was optimal again.
    pub warm_start_accepted: bool,
    /// Rank of the structure matrix (3 for a spatial robot, 2 for a planar one).
    pub rank: u32,
    /// ‖A T − w‖∞ of the answer, N.
    pub residual_n: f64,
}
