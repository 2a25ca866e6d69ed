//! Sagging cables: the elastic catenary's statics, the sagged tension solve, the sagged FEM
//! against the dense solve and physics, the continuous (N → ∞) model, the real-time sagged
//! estimator, its allocations and cost, and the comparison with the independent Python
//! reference (tests/py/sag_reference.py).
//! Area binary of the core crate (see tests/README.md).

// Allocation counts (the real-time path allocates nothing) need the counting allocator.
cablevib_testkit::count_allocations!();

mod continuous;
mod dense_basis;
mod ee_mode;
mod ee_mode_continuous;
mod fem_alloc;
mod fem_dense;
mod fem_physics;
mod frf;
mod frf_modal;
mod many_modes;
mod pulleys;
mod realtime;
mod shapes;
mod simulate;
mod speed;
mod statics;
mod tension;
mod vs_reference;
