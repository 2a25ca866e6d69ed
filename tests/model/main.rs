//! The taut-cable model: the real-time estimator against the dense reference, the paper's
//! tables, sum rules, the end-effector mode and its budget, rigid-body effects, the inverse
//! T_min query, tiny T_min, and property tests over random scenes and poses.
//! Area binary of the core crate (see tests/README.md).

// Allocation counts (the real-time path allocates nothing) need the counting allocator.
cablevib_testkit::count_allocations!();

mod budget_continuation;
mod cable_inertia;
mod ee_budget;
mod effects_rigid;
mod frf;
mod hidden_cable;
mod hidden_models;
mod inverse_query;
mod paper_tables;
mod proptest_model;
mod pulleys;
mod realtime_exact;
mod realtime_vs_dense;
mod ritz_update;
mod sag_path_field;
mod scene_fuzz;
mod sum_rules;
mod tiny_t_min;
mod vibration;
mod vibration_exact;
