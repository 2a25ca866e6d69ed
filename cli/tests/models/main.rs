//! Models checked through the `cablevib` binary and the analysis: CASPR import (synthetic
//! and real models), real robots, structured modes, hard sagged cases and the sagged
//! reference.
//! Area binary of the command-line crate (see tests/README.md at the repository root).

// Allocation counts (the real-time path allocates nothing) need the counting allocator.
cablevib_testkit::count_allocations!();

mod caspr_import;
mod caspr_real;
mod hard_cases_sag;
mod modes_structured;
mod real_robots;
mod sag_reference;
