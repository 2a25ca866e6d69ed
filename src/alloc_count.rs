//! A counting global allocator: proves (tests, soak) and reports (`cablevib bench`,
//! `cablevib serve`) that the per-cycle path makes no heap allocation.
//!
//! [`CountingAlloc`] forwards every call to the system allocator and counts each
//! allocation (`alloc`, `alloc_zeroed` and `realloc`; `dealloc` is not counted) twice:
//!
//! - globally, over every thread of the process ([`allocations`], [`allocated_bytes`]):
//!   what a binary reports per cycle;
//! - per thread ([`thread_allocations`], [`thread_allocated_bytes`]): what a test measures,
//!   so that what other threads allocate meanwhile (the test harness's runner and output
//!   capture, a logger) is not charged to the code under test. Take the calling thread's
//!   count before and after the measured code and compare.
//!
//! The per-thread counters are const-initialised `Cell`s without destructors: updating and
//! reading them never allocates, so counting cannot recurse into the allocator.
//!
//! Nothing counts until a binary (or an integration test, which is its own binary) installs
//! it as its global allocator:
//!
//! ```ignore
//! #[global_allocator]
//! static A: cablevib::alloc_count::CountingAlloc = cablevib::alloc_count::CountingAlloc;
//! ```
//!
//! Without that every count stays 0.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicU64, Ordering};

/// The system allocator with allocation counters; install it with `#[global_allocator]`
/// (see the module docs).
#[derive(Debug, Default, Clone, Copy)]
pub struct CountingAlloc;

static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);
static ALLOCATED_BYTES: AtomicU64 = AtomicU64::new(0);

thread_local! {
    // Const-initialised, no destructor: never allocates, always accessible.
    static THREAD_ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
    static THREAD_ALLOCATED_BYTES: Cell<u64> = const { Cell::new(0) };
}

/// Count one allocation of `bytes` bytes on the global and the calling thread's counters.
fn count(bytes: usize) {
    ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
    ALLOCATED_BYTES.fetch_add(bytes as u64, Ordering::Relaxed);
    let _ = THREAD_ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
    let _ = THREAD_ALLOCATED_BYTES.try_with(|c| c.set(c.get() + bytes as u64));
}

/// Heap allocations (`alloc`, `alloc_zeroed`, `realloc`) made by every thread of the
/// process since it started.
pub fn allocations() -> u64 {
    ALLOCATIONS.load(Ordering::Relaxed)
}

/// Bytes requested by those allocations (the new size for a `realloc`).
pub fn allocated_bytes() -> u64 {
    ALLOCATED_BYTES.load(Ordering::Relaxed)
}

/// Heap allocations made by the calling thread since it started.
pub fn thread_allocations() -> u64 {
    THREAD_ALLOCATIONS.try_with(|c| c.get()).unwrap_or(0)
}

/// Bytes requested by the calling thread's allocations (the new size for a `realloc`).
pub fn thread_allocated_bytes() -> u64 {
    THREAD_ALLOCATED_BYTES.try_with(|c| c.get()).unwrap_or(0)
}

// SAFETY: every call is forwarded unchanged to the system allocator, which upholds the
// `GlobalAlloc` contract; counting only touches atomics and const-initialised thread-local
// `Cell`s, which neither allocate nor unwind.
unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count(layout.size());
        // SAFETY: the caller's guarantees on `layout` are passed on unchanged.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count(layout.size());
        // SAFETY: as for `alloc`.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count(new_size);
        // SAFETY: `ptr` was allocated by this allocator, i.e. by `System`, with `layout`.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by this allocator, i.e. by `System`, with `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }
}
