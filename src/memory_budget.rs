//! The one memory budget of the offline work: every computation whose memory grows with a
//! user's input (the dense reference's n × n matrices, the mode shapes of N elements per
//! cable held for K modes, the CSV text of those shapes) estimates its bytes before it
//! allocates and is refused past [`MEMORY_BUDGET_BYTES`] with one line saying what, how much
//! and what to change. One rule, one number, for the command line and the Python package
//! alike; the estimate's formula sits with the code that allocates.
//!
//! The budget is fixed (no option raises it): at 2 GiB a dense solve already takes minutes
//! and a mode-shape table is 10⁸ node displacements, more than any figure or CSV reader
//! takes; the structured solver's eigenvalues and the end-effector's response need none of
//! it (O(1) memory in the element count).

/// Memory one offline computation may use, bytes (2 GiB).
pub const MEMORY_BUDGET_BYTES: u64 = 2 << 30;

/// A computation refused before it allocated: its estimate is over [`MEMORY_BUDGET_BYTES`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{what} would need about {} of memory, over the budget of {} ({remedy})", gib(*bytes), gib(*budget))]
pub struct OverBudget {
    /// What was refused, e.g. `mode shapes of 12 modes × 8000008 nodes`.
    pub what: String,
    /// The estimate, bytes.
    pub bytes: u64,
    /// The budget, bytes.
    pub budget: u64,
    /// What to change (fewer elements or modes, the structured solver, ...).
    pub remedy: &'static str,
}

/// `bytes` as GiB with three significant digits (`4.47 GiB`), or MiB below 1 GiB.
fn gib(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= (1u64 << 30) as f64 {
        format!("{:.3} GiB", b / (1u64 << 30) as f64)
    } else {
        format!("{:.1} MiB", b / (1u64 << 20) as f64)
    }
}

/// Refuse `what` when its estimated `bytes` exceed [`MEMORY_BUDGET_BYTES`]; `remedy` says
/// what to change. Call it before allocating.
pub fn check(
    what: impl FnOnce() -> String,
    bytes: u64,
    remedy: &'static str,
) -> Result<(), OverBudget> {
    if bytes > MEMORY_BUDGET_BYTES {
        return Err(OverBudget {
            what: what(),
            bytes,
            budget: MEMORY_BUDGET_BYTES,
            remedy,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn over_the_budget_is_one_line_naming_both_sizes() {
        assert!(check(|| "x".into(), MEMORY_BUDGET_BYTES, "r").is_ok());
        let e = check(|| "mode shapes".into(), 5 << 30, "use fewer modes").unwrap_err();
        let msg = e.to_string();
        assert_eq!(
            msg,
            "mode shapes would need about 5.000 GiB of memory, over the budget of 2.000 GiB (use fewer modes)"
        );
        assert_eq!(gib(3 << 20), "3.0 MiB");
    }
}
