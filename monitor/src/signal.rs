//! SIGINT/SIGTERM set a flag the monitor's loop polls, so that the MCAP file is closed
//! cleanly (summary and footer written) on Ctrl-C or `kill`.

use std::sync::atomic::{AtomicBool, Ordering};

static STOP: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_: libc::c_int) {
    STOP.store(true, Ordering::Release);
}

/// Installs the handler for SIGINT and SIGTERM (once per process) and returns the flag it sets.
pub fn stop_on_signals() -> &'static AtomicBool {
    // SAFETY: the handler only stores to an atomic (async-signal-safe); sigaction is given a
    // zeroed, valid struct with an empty mask.
    unsafe {
        let mut sa: libc::sigaction = core::mem::zeroed();
        sa.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as usize;
        libc::sigemptyset(&mut sa.sa_mask);
        for sig in [libc::SIGINT, libc::SIGTERM] {
            libc::sigaction(sig, &sa, core::ptr::null_mut());
        }
    }
    &STOP
}

/// Whether SIGINT or SIGTERM arrived since [`stop_on_signals`] installed the handler.
pub fn received() -> bool {
    STOP.load(Ordering::Acquire)
}
