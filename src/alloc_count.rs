//! A counting global allocator: proves (tests, soak) and reports (`cablevib bench`,
//! `cablevib serve`) that the per-cycle path makes no heap allocation; and a constant-time
//! block pool for the one thread that cannot avoid small allocations (the service loop:
//! iceoryx2 0.10 allocates a small shared state per loan and per received request).
//!
//! [`CountingAlloc`] counts each allocation (`alloc`, `alloc_zeroed` and `realloc`;
//! `dealloc` is not counted) twice:
//!
//! - globally, over every thread of the process ([`allocations`], [`allocated_bytes`]):
//!   what a binary reports per cycle;
//! - per thread ([`thread_allocations`], [`thread_allocated_bytes`]): what a test measures,
//!   so that what other threads allocate meanwhile (the test harness's runner and output
//!   capture, a logger) is not charged to the code under test. Take the calling thread's
//!   count before and after the measured code and compare.
//!
//! and says where each came from: the system allocator ([`system_allocations`],
//! [`thread_system_allocations`]) or the pool ([`pool_allocations`],
//! [`thread_pool_allocations`]); the totals above count both.
//!
//! **The pool.** [`POOL_BLOCKS`] blocks of [`POOL_BLOCK_BYTES`] bytes (alignment 16) in a
//! static array, used only by the one thread that holds [`claim_pool`]'s guard: its
//! allocations of at most that size and alignment come from the pool, in constant time (pop
//! the thread's free list; when it is empty, take at once every block other threads freed;
//! else the next never-used block; when all are in use, the system allocator, counted as
//! such). A pool block freed by the holder goes back on its list (constant time); freed by
//! another thread, on a lock-free shared list that only the holder takes from (one producer
//! side per freeing thread, one consumer: no ABA). Every other allocation, and every
//! allocation of every other thread, goes to the system allocator unchanged.
//!
//! The per-thread counters and the pool's per-thread state are const-initialised `Cell`s
//! without destructors: updating and reading them never allocates, so counting cannot
//! recurse into the allocator.
//!
//! Nothing counts, and the pool is never used, until a binary (or an integration test,
//! which is its own binary) installs it as its global allocator:
//!
//! ```ignore
//! #[global_allocator]
//! static A: cablevib::alloc_count::CountingAlloc = cablevib::alloc_count::CountingAlloc;
//! ```
//!
//! Without that every count stays 0.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::{Cell, UnsafeCell};
use std::marker::PhantomData;
use std::ptr::null_mut;
use std::sync::atomic::{AtomicBool, AtomicPtr, AtomicU64, AtomicUsize, Ordering};

/// The system allocator with allocation counters and the pool; install it with
/// `#[global_allocator]` (see the module docs).
#[derive(Debug, Default, Clone, Copy)]
pub struct CountingAlloc;

/// Size of one pool block, bytes: iceoryx2 0.10's per-loan shared state (an `Rc` or `Arc`
/// of a port handle and three words) and its per-request one fit.
pub const POOL_BLOCK_BYTES: usize = 128;
/// Alignment of a pool block, bytes.
pub const POOL_BLOCK_ALIGN: usize = 16;
/// Blocks in the pool (128 KiB): far more than the loans and requests a service holds at
/// once (bounded by its ports' configuration).
pub const POOL_BLOCKS: usize = 1024;

static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);
static ALLOCATED_BYTES: AtomicU64 = AtomicU64::new(0);
static POOL_ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

thread_local! {
    // Const-initialised, no destructor: never allocates, always accessible.
    static THREAD_ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
    static THREAD_ALLOCATED_BYTES: Cell<u64> = const { Cell::new(0) };
    static THREAD_POOL_ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
    /// Whether this thread holds the pool.
    static POOL_HOLDER: Cell<bool> = const { Cell::new(false) };
    /// The holder's free list (blocks linked through their first word).
    static LOCAL_FREE: Cell<*mut u8> = const { Cell::new(null_mut()) };
}

#[repr(C, align(16))]
struct Block([u8; POOL_BLOCK_BYTES]);

/// The pool's storage; a block is handed to one owner at a time by the lists below.
struct Arena(UnsafeCell<[Block; POOL_BLOCKS]>);

// SAFETY: blocks are only accessed through pointers handed out by the allocator, one owner
// at a time (the pool's lists never hold a block that is in use).
unsafe impl Sync for Arena {}

static ARENA: Arena = Arena(UnsafeCell::new(
    [const { Block([0; POOL_BLOCK_BYTES]) }; POOL_BLOCKS],
));
/// Blocks handed out at least once (the next never-used block's index).
static NEXT_UNUSED: AtomicUsize = AtomicUsize::new(0);
/// Blocks freed by threads other than the holder (a Treiber stack: pushed by any thread,
/// taken whole by the holder).
static REMOTE_FREE: AtomicPtr<u8> = AtomicPtr::new(null_mut());
/// Some thread holds the pool.
static POOL_CLAIMED: AtomicBool = AtomicBool::new(false);

fn arena_start() -> usize {
    ARENA.0.get() as usize
}

/// Whether `p` is a pool block.
fn in_pool(p: *mut u8) -> bool {
    let a = p as usize;
    a >= arena_start() && a < arena_start() + POOL_BLOCKS * POOL_BLOCK_BYTES
}

fn is_holder() -> bool {
    POOL_HOLDER.try_with(|c| c.get()).unwrap_or(false)
}

/// The link stored in a free block.
///
/// # Safety
/// `b` is a free pool block.
unsafe fn next_of(b: *mut u8) -> *mut u8 {
    // SAFETY: a free block's first word is its list link (blocks are 16-aligned).
    unsafe { b.cast::<*mut u8>().read() }
}

/// # Safety
/// `b` is a pool block no one else uses.
unsafe fn set_next(b: *mut u8, next: *mut u8) {
    // SAFETY: as for `next_of`.
    unsafe { b.cast::<*mut u8>().write(next) }
}

/// A block for the holder, in constant time; None when every block is in use.
fn pool_pop() -> Option<*mut u8> {
    let mut head = LOCAL_FREE.try_with(|c| c.get()).ok()?;
    if head.is_null() {
        head = REMOTE_FREE.swap(null_mut(), Ordering::Acquire);
    }
    if !head.is_null() {
        // SAFETY: `head` is a free block of the holder's list (or just taken from the
        // shared one, which only the holder takes from).
        let next = unsafe { next_of(head) };
        let _ = LOCAL_FREE.try_with(|c| c.set(next));
        return Some(head);
    }
    // Only the holder takes never-used blocks: a plain load and store suffice.
    let i = NEXT_UNUSED.load(Ordering::Relaxed);
    if i < POOL_BLOCKS {
        NEXT_UNUSED.store(i + 1, Ordering::Relaxed);
        return Some((arena_start() + i * POOL_BLOCK_BYTES) as *mut u8);
    }
    None
}

/// Return block `b` to the pool: the holder's list, or the shared one.
///
/// # Safety
/// `b` is a pool block being freed.
unsafe fn pool_push(b: *mut u8) {
    if is_holder() {
        if let Ok(head) = LOCAL_FREE.try_with(|c| c.get()) {
            // SAFETY: `b` is being freed: no one else uses it.
            unsafe { set_next(b, head) };
            let _ = LOCAL_FREE.try_with(|c| c.set(b));
            return;
        }
    }
    let mut head = REMOTE_FREE.load(Ordering::Relaxed);
    loop {
        // SAFETY: as above.
        unsafe { set_next(b, head) };
        match REMOTE_FREE.compare_exchange_weak(head, b, Ordering::Release, Ordering::Relaxed) {
            Ok(_) => return,
            Err(h) => head = h,
        }
    }
}

/// Whether an allocation of `layout` may come from the pool on this thread.
fn pool_fits(layout: &Layout) -> bool {
    layout.size() <= POOL_BLOCK_BYTES && layout.align() <= POOL_BLOCK_ALIGN && is_holder()
}

/// The calling thread's hold on the pool (see the module docs); released when dropped.
/// Not `Send`: the pool belongs to the thread that claimed it.
#[derive(Debug)]
pub struct PoolGuard {
    _not_send: PhantomData<*const ()>,
}

/// Make the calling thread the pool's user: its small allocations come from the pool from
/// now on, until the guard is dropped. None when another thread holds it (there is one
/// holder at a time). Without [`CountingAlloc`] installed the pool is never used.
pub fn claim_pool() -> Option<PoolGuard> {
    if POOL_CLAIMED
        .compare_exchange(false, true, Ordering::Acquire, Ordering::Relaxed)
        .is_err()
    {
        return None;
    }
    POOL_HOLDER.try_with(|c| c.set(true)).ok()?;
    Some(PoolGuard {
        _not_send: PhantomData,
    })
}

impl Drop for PoolGuard {
    fn drop(&mut self) {
        let _ = POOL_HOLDER.try_with(|c| c.set(false));
        // Hand the holder's free blocks to the shared list, for the next holder.
        let mut b = LOCAL_FREE
            .try_with(|c| c.replace(null_mut()))
            .unwrap_or(null_mut());
        while !b.is_null() {
            // SAFETY: `b` is on the holder's free list.
            let next = unsafe { next_of(b) };
            // SAFETY: a free block; pushed on the shared list (no longer the holder).
            unsafe { pool_push(b) };
            b = next;
        }
        POOL_CLAIMED.store(false, Ordering::Release);
    }
}

/// Count one allocation of `bytes` bytes on the global and the calling thread's counters
/// (`pool`: it came from the pool).
fn count(bytes: usize, pool: bool) {
    ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
    ALLOCATED_BYTES.fetch_add(bytes as u64, Ordering::Relaxed);
    let _ = THREAD_ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
    let _ = THREAD_ALLOCATED_BYTES.try_with(|c| c.set(c.get() + bytes as u64));
    if pool {
        POOL_ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        let _ = THREAD_POOL_ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
    }
}

/// Heap allocations (`alloc`, `alloc_zeroed`, `realloc`) made by every thread of the
/// process since it started, from the system allocator and from the pool.
pub fn allocations() -> u64 {
    ALLOCATIONS.load(Ordering::Relaxed)
}

/// Bytes requested by those allocations (the new size for a `realloc`).
pub fn allocated_bytes() -> u64 {
    ALLOCATED_BYTES.load(Ordering::Relaxed)
}

/// Of [`allocations`], the ones served by the pool.
pub fn pool_allocations() -> u64 {
    POOL_ALLOCATIONS.load(Ordering::Relaxed)
}

/// Of [`allocations`], the ones served by the system allocator.
pub fn system_allocations() -> u64 {
    allocations().wrapping_sub(pool_allocations())
}

/// Heap allocations made by the calling thread since it started (system and pool).
pub fn thread_allocations() -> u64 {
    THREAD_ALLOCATIONS.try_with(|c| c.get()).unwrap_or(0)
}

/// Bytes requested by the calling thread's allocations (the new size for a `realloc`).
pub fn thread_allocated_bytes() -> u64 {
    THREAD_ALLOCATED_BYTES.try_with(|c| c.get()).unwrap_or(0)
}

/// Of [`thread_allocations`], the ones served by the pool.
pub fn thread_pool_allocations() -> u64 {
    THREAD_POOL_ALLOCATIONS.try_with(|c| c.get()).unwrap_or(0)
}

/// Of [`thread_allocations`], the ones served by the system allocator.
pub fn thread_system_allocations() -> u64 {
    thread_allocations().wrapping_sub(thread_pool_allocations())
}

// SAFETY: the system allocator upholds the `GlobalAlloc` contract for what is forwarded to
// it. A pool block is 16-aligned and POOL_BLOCK_BYTES long, handed out only for layouts that
// fit, and owned by one allocation at a time (a block is on at most one free list, and on
// none while in use). Counting and the pool touch only atomics, the static arena and
// const-initialised thread-local `Cell`s, which neither allocate nor unwind.
unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if pool_fits(&layout) {
            if let Some(b) = pool_pop() {
                count(layout.size(), true);
                return b;
            }
        }
        count(layout.size(), false);
        // SAFETY: the caller's guarantees on `layout` are passed on unchanged.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if pool_fits(&layout) {
            if let Some(b) = pool_pop() {
                count(layout.size(), true);
                // SAFETY: `b` is a block of at least `layout.size()` bytes, ours now.
                unsafe { b.write_bytes(0, layout.size()) };
                return b;
            }
        }
        count(layout.size(), false);
        // SAFETY: as for `alloc`.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if in_pool(ptr) {
            if new_size <= POOL_BLOCK_BYTES {
                // The block already holds it.
                count(new_size, true);
                return ptr;
            }
            // SAFETY: `layout.align()` is a valid alignment and the caller guarantees that
            // `new_size`, rounded up to it, does not overflow.
            let new_layout = unsafe { Layout::from_size_align_unchecked(new_size, layout.align()) };
            // SAFETY: a non-zero size (larger than a block).
            let new = unsafe { self.alloc(new_layout) };
            if !new.is_null() {
                // SAFETY: both are valid for `layout.size()` bytes and do not overlap;
                // `ptr` is a pool block freed once.
                unsafe {
                    std::ptr::copy_nonoverlapping(ptr, new, layout.size());
                    pool_push(ptr);
                }
            }
            return new;
        }
        count(new_size, false);
        // SAFETY: `ptr` was allocated by this allocator from `System` (not a pool block),
        // with `layout`.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        if in_pool(ptr) {
            // SAFETY: a pool block being freed.
            unsafe { pool_push(ptr) };
            return;
        }
        // SAFETY: `ptr` was allocated by this allocator from `System` with `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pool_serves_its_holder_reuses_blocks_and_falls_back_when_full() {
        let a = CountingAlloc;
        let small = Layout::from_size_align(48, 8).unwrap();
        let large = Layout::from_size_align(POOL_BLOCK_BYTES + 1, 8).unwrap();
        // Not the holder: the system allocator.
        // SAFETY: valid non-zero layouts; every pointer is freed once with its layout.
        unsafe {
            let p = a.alloc(small);
            assert!(!in_pool(p));
            a.dealloc(p, small);
        }
        let guard = claim_pool().expect("no other holder in this test binary");
        assert!(claim_pool().is_none(), "one holder at a time");
        let (pool0, all0) = (thread_pool_allocations(), thread_allocations());
        // SAFETY: as above.
        unsafe {
            let p = a.alloc(small);
            assert!(in_pool(p) && (p as usize).is_multiple_of(POOL_BLOCK_ALIGN));
            let q = a.alloc(large);
            assert!(!in_pool(q), "larger than a block: the system allocator");
            a.dealloc(q, large);
            a.dealloc(p, small);
            // Freed by the holder: the same block again (its own free list).
            let r = a.alloc_zeroed(small);
            assert_eq!(r, p);
            assert!(std::slice::from_raw_parts(r, 48).iter().all(|&b| b == 0));
            // Freed by another thread: the shared list, taken back by the holder.
            let addr = r as usize;
            std::thread::spawn(move || CountingAlloc.dealloc(addr as *mut u8, small))
                .join()
                .unwrap();
            assert_eq!(a.alloc(small), r);
            // Growing past a block moves to the system allocator and frees the block.
            let g = a.realloc(r, small, 4 * POOL_BLOCK_BYTES);
            assert!(!in_pool(g));
            a.dealloc(g, Layout::from_size_align(4 * POOL_BLOCK_BYTES, 8).unwrap());
            // Every block in use: the system allocator takes over.
            let mut held = Vec::with_capacity(POOL_BLOCKS + 1);
            for _ in 0..=POOL_BLOCKS {
                held.push(a.alloc(small));
            }
            assert!(held[..POOL_BLOCKS].iter().all(|&p| in_pool(p)));
            assert!(!in_pool(held[POOL_BLOCKS]));
            for p in held {
                a.dealloc(p, small);
            }
        }
        // Counted only when installed as the global allocator (not here): the calls above
        // go around it, so the pool counters moved by the pool hits alone.
        assert!(thread_pool_allocations() - pool0 >= POOL_BLOCKS as u64);
        assert!(thread_allocations() - all0 >= thread_pool_allocations() - pool0);
        drop(guard);
        assert!(claim_pool().is_some(), "released");
    }
}
