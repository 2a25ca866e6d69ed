//! The iceoryx2 service in process: hostile clients, counters under a flood, message fuzzing,
//! zero allocations while serving.
//! Area binary of the service crate (see tests/README.md at the repository root).

// Allocation counts (the real-time path allocates nothing) need the counting allocator.
cablevib_testkit::count_allocations!();

mod hostile_client;
mod ipc_counters;
mod message_fuzz;
mod serve_allocations;
