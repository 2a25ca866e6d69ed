//! Real-time process settings: CPU pinning, SCHED_FIFO, locked memory. Each returns an error
//! text when the system refuses (no permission, no such CPU); the service logs it as a
//! warning and runs on without it.

/// SCHED_FIFO priority of the real-time mode (1 = lowest, 99 = highest). 80 leaves room above
/// for the kernel's own threaded interrupt handlers (50) and a controller that must preempt.
pub const FIFO_PRIORITY: i32 = 80;

/// Pins the calling thread to CPU `cpu`.
#[cfg(target_os = "linux")]
pub fn pin_to_cpu(cpu: usize) -> Result<(), String> {
    // SAFETY: cpu_set_t is plain data; CPU_ZERO/CPU_SET write inside it, and the call reads it.
    unsafe {
        let mut set: libc::cpu_set_t = core::mem::zeroed();
        if cpu >= 8 * core::mem::size_of::<libc::cpu_set_t>() {
            return Err(format!("CPU {cpu} is beyond the affinity mask"));
        }
        libc::CPU_ZERO(&mut set);
        libc::CPU_SET(cpu, &mut set);
        if libc::sched_setaffinity(0, core::mem::size_of::<libc::cpu_set_t>(), &set) != 0 {
            return Err(format!(
                "sched_setaffinity(CPU {cpu}): {}",
                std::io::Error::last_os_error()
            ));
        }
    }
    Ok(())
}

/// Switches the calling thread to SCHED_FIFO at [`FIFO_PRIORITY`].
#[cfg(target_os = "linux")]
pub fn set_fifo() -> Result<(), String> {
    let param = libc::sched_param {
        sched_priority: FIFO_PRIORITY,
    };
    // SAFETY: `param` is a valid sched_param for the duration of the call.
    if unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) } != 0 {
        return Err(format!(
            "sched_setscheduler(SCHED_FIFO, {FIFO_PRIORITY}): {}",
            std::io::Error::last_os_error()
        ));
    }
    Ok(())
}

/// Locks the process's current and future pages in RAM (no page faults on the cycle path).
#[cfg(target_os = "linux")]
pub fn lock_memory() -> Result<(), String> {
    // SAFETY: mlockall has no memory-safety preconditions.
    if unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) } != 0 {
        return Err(format!(
            "mlockall(MCL_CURRENT | MCL_FUTURE): {}",
            std::io::Error::last_os_error()
        ));
    }
    Ok(())
}

/// Not supported on this platform.
#[cfg(not(target_os = "linux"))]
pub fn pin_to_cpu(cpu: usize) -> Result<(), String> {
    Err(format!(
        "CPU pinning (CPU {cpu}) is implemented for Linux only"
    ))
}

/// Not supported on this platform.
#[cfg(not(target_os = "linux"))]
pub fn set_fifo() -> Result<(), String> {
    Err("SCHED_FIFO is implemented for Linux only".into())
}

/// Not supported on this platform.
#[cfg(not(target_os = "linux"))]
pub fn lock_memory() -> Result<(), String> {
    Err("mlockall is implemented for Linux only".into())
}
