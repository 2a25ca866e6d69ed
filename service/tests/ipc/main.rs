//! The iceoryx2 service in process: hostile clients, counters under a flood, message fuzzing,
//! zero allocations while serving.
//! Area binary of the service crate (see tests/README.md at the repository root).

// Allocation counts (the real-time path allocates nothing) need the counting allocator.
cablevib_testkit::count_allocations!();

/// One serving test at a time: the service thread claims the process's one allocation pool
/// (`alloc_count::claim_pool`), and a second server running beside it in this binary gets
/// none, so its per-loan allocations go to the system allocator. The tests that count those
/// allocations or bound the resident memory would then fail depending on which test thread
/// started first.
pub(crate) fn one_server_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static SERVING: std::sync::Mutex<()> = std::sync::Mutex::new(());
    SERVING.lock().unwrap_or_else(|e| e.into_inner())
}

mod hostile_client;
mod hostile_vibration;
mod ipc_counters;
mod message_fuzz;
mod serve_allocations;
