//! The temporary files of unfinished outputs, removed when a signal ends the process.
//!
//! A file being written lives under a temporary name beside its target
//! ([`super::OutputFile`]); dropping it unfinished removes it, but a signal whose action is
//! the default (SIGINT from Ctrl-C, SIGTERM, SIGHUP, SIGPIPE) ends the process without
//! running destructors. So every temporary name is also kept here, in a fixed table that a
//! signal handler can read without allocating or locking, and the handler unlinks them
//! (`unlink` is async-signal-safe) before the signal takes its default action again.
//!
//! The handler is installed, once, on the first temporary file, and only for the signals
//! whose action is still the default: a command that handles a signal itself (the monitor
//! closes its recording on SIGINT, the service stops on it) keeps its handler and removes or
//! finishes its files on its own path. SIGKILL cannot be caught: it leaves the temporary
//! file (the target is untouched).
//!
//! Each slot has a state: free, being filled, armed (the handler may unlink it) or taken
//! (the handler is unlinking it). The owner arms a slot only after its bytes are written and
//! frees it only from armed, so the handler never reads a path that is being changed. A
//! path longer than a slot, or a table full ([`SLOTS`] files at once), is not registered:
//! that file is still removed on an error or a panic, only not on a signal.

use std::cell::UnsafeCell;
use std::os::unix::ffi::OsStrExt;
use std::path::Path;
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Once;

/// Temporary files that can be registered at once.
pub const SLOTS: usize = 64;
/// Longest path registered, bytes (with its terminating NUL).
const PATH_BYTES: usize = 4096;

const FREE: u8 = 0;
const FILLING: u8 = 1;
const ARMED: u8 = 2;
const TAKEN: u8 = 3;

/// The signals whose default action ends the process and whose handler removes the files.
const SIGNALS: [libc::c_int; 4] = [libc::SIGHUP, libc::SIGINT, libc::SIGPIPE, libc::SIGTERM];

struct Slot {
    state: AtomicU8,
    path: UnsafeCell<[u8; PATH_BYTES]>,
}

// SAFETY: `path` is written only by the owner that moved `state` from FREE to FILLING, and
// read only by the handler that moved it from ARMED to TAKEN; the two never overlap.
unsafe impl Sync for Slot {}

#[allow(clippy::declare_interior_mutable_const)]
const EMPTY: Slot = Slot {
    state: AtomicU8::new(FREE),
    path: UnsafeCell::new([0; PATH_BYTES]),
};

static TABLE: [Slot; SLOTS] = [EMPTY; SLOTS];
static INSTALL: Once = Once::new();

/// A registered temporary file: its slot in the table.
#[derive(Debug)]
pub(super) struct Registration(usize);

/// Registers the absolute path `path` for removal on a signal (`None` when it does not fit
/// or the table is full), installing the handler the first time.
pub(super) fn register(path: &Path) -> Option<Registration> {
    INSTALL.call_once(install);
    let bytes = path.as_os_str().as_bytes();
    if bytes.len() >= PATH_BYTES || bytes.contains(&0) {
        return None;
    }
    for (k, slot) in TABLE.iter().enumerate() {
        if slot
            .state
            .compare_exchange(FREE, FILLING, Ordering::Acquire, Ordering::Relaxed)
            .is_ok()
        {
            // SAFETY: this thread owns the slot (FILLING) until it stores ARMED.
            let buf = unsafe { &mut *slot.path.get() };
            buf[..bytes.len()].copy_from_slice(bytes);
            buf[bytes.len()] = 0;
            slot.state.store(ARMED, Ordering::Release);
            return Some(Registration(k));
        }
    }
    None
}

impl Drop for Registration {
    /// Frees the slot (left alone when the handler has taken it: the process is ending).
    fn drop(&mut self) {
        let _ =
            TABLE[self.0]
                .state
                .compare_exchange(ARMED, FREE, Ordering::AcqRel, Ordering::Relaxed);
    }
}

/// Installs [`on_signal`] for each of [`SIGNALS`] whose action is the default.
fn install() {
    for sig in SIGNALS {
        // SAFETY: sigaction with a null new action only reads the current one into `old`;
        // the new action is a zeroed struct with a valid handler and an empty mask.
        unsafe {
            let mut old: libc::sigaction = core::mem::zeroed();
            if libc::sigaction(sig, core::ptr::null(), &mut old) != 0
                || old.sa_sigaction != libc::SIG_DFL
            {
                continue;
            }
            let mut sa: libc::sigaction = core::mem::zeroed();
            sa.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as usize;
            libc::sigemptyset(&mut sa.sa_mask);
            // Back to the default action on entry: the signal raised again below ends the
            // process as it would have without this handler.
            sa.sa_flags = libc::SA_RESETHAND;
            libc::sigaction(sig, &sa, core::ptr::null_mut());
        }
    }
}

/// Unlinks every armed temporary file, then raises `sig` again (its action is the default
/// again; it is delivered when the handler returns).
extern "C" fn on_signal(sig: libc::c_int) {
    for slot in &TABLE {
        if slot
            .state
            .compare_exchange(ARMED, TAKEN, Ordering::Acquire, Ordering::Relaxed)
            .is_ok()
        {
            // SAFETY: the slot holds a NUL-terminated path (armed), which no one changes
            // while it is TAKEN; unlink and raise are async-signal-safe.
            unsafe {
                libc::unlink(slot.path.get() as *const libc::c_char);
            }
        }
    }
    // SAFETY: raise is async-signal-safe.
    unsafe {
        libc::raise(sig);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slots_are_reused_and_long_paths_are_not_registered() {
        let a = register(Path::new("/tmp/cablevib-cleanup-test-a")).expect("a slot");
        let k = a.0;
        assert_eq!(TABLE[k].state.load(Ordering::Acquire), ARMED);
        drop(a);
        assert_eq!(TABLE[k].state.load(Ordering::Acquire), FREE);
        let long = format!("/{}", "x".repeat(PATH_BYTES));
        assert!(register(Path::new(&long)).is_none());
    }
}
