//! The `cablevib` command-line tool. See `cablevib --help`.
use clap::Parser;

/// Counts heap allocations so `cablevib bench` and `serve` can report allocations per cycle.
#[global_allocator]
static GLOBAL: cablevib::alloc_count::CountingAlloc = cablevib::alloc_count::CountingAlloc;

/// The calling thread's allocations from the system allocator (the cycle runs on it; the
/// service's pool hits are counted apart).
fn allocations() -> u64 {
    cablevib::alloc_count::thread_system_allocations()
}

/// Restores the default action of SIGPIPE (terminate quietly), which the Rust runtime sets to
/// "ignore" before `main`: a reader that closes the pipe early (`cablevib ... | head`) then
/// ends the process the way it ends `cat` or `grep` (status 141 in a shell), instead of
/// `println!` panicking on EPIPE. Done once here, so every print of every command (and
/// clap's help) is covered. iceoryx2 does not rely on SIGPIPE being ignored: its socket-pair
/// sends pass MSG_NOSIGNAL and its events use datagram sockets, which never raise it.
fn default_sigpipe() {
    // SAFETY: called first in main, before any thread exists; SIG_DFL is a valid disposition.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Keeps freed heap memory in the process instead of handing it back to the kernel after
/// every large free (glibc's allocator). By default glibc maps each block above a moving
/// threshold (from 128 KiB) separately and trims the heap's free top past twice that, so
/// a loop that allocates and frees blocks of a few hundred KiB (`simulate`'s basis
/// updates: the assembled K and M, n × q blocks) pays page faults and zeroing in the kernel
/// for the same memory again at every turn: 0.4-0.6 s of system time of ~2.5 s on the
/// paper robot's circle. Blocks below 32 MiB (glibc's largest mmap threshold) then come
/// from the heap, and up to 64 MiB of free heap top is kept. The peak memory is the same
/// (only its return after the peak is kept back); blocks of 32 MiB and more are still
/// mapped apart and returned when freed.
fn keep_freed_heap() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: called first in main, before any thread exists or anything is allocated by
    // us; mallopt only changes the allocator's thresholds.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 64 << 20);
    }
}

fn main() {
    default_sigpipe();
    keep_freed_heap();
    let cli = match cablevib_cli::cli::Cli::try_parse() {
        Ok(cli) => cli,
        // Help and version go to standard output, usage errors to standard error; a failed
        // write of either is a one-line error, not a silent exit.
        Err(e) => match e.print() {
            Ok(()) => std::process::exit(e.exit_code()),
            Err(io) => fail(&cablevib::output_file::StdoutError(io).into()),
        },
    };
    if let Err(e) = run(cli) {
        fail(&e);
    }
}

/// The one-line error and exit status 1.
fn fail(e: &anyhow::Error) -> ! {
    eprintln!("cablevib: {e:#}");
    std::process::exit(1);
}

/// The command, then standard output flushed (every command writes whole lines, so this
/// only reports what a line-less write left).
fn run(cli: cablevib_cli::cli::Cli) -> anyhow::Result<()> {
    cablevib_cli::cli::run(cli, allocations)?;
    cablevib::output_file::flush_stdout()?;
    Ok(())
}
