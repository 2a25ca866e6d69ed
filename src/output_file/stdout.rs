//! Standard output as a fallible output: [`crate::outln!`] writes one line and returns
//! `Result<(), StdoutError>` where `println!` panics (a full disk, `> /dev/full`, a closed
//! terminal), so that a command ends with a one-line error and a non-zero exit instead.
//! A closed pipe (`| head`) is left to SIGPIPE, which ends the process quietly as it ends
//! `cat`.

use std::io::{self, Write};

/// Standard output could not be written.
#[derive(Debug, thiserror::Error)]
#[error("cannot write to standard output: {0}")]
pub struct StdoutError(pub io::Error);

/// Writes `args` to standard output (see [`crate::outln!`]).
pub fn stdout_write(args: std::fmt::Arguments) -> Result<(), StdoutError> {
    io::stdout().lock().write_fmt(args).map_err(StdoutError)
}

/// Writes `bytes` to standard output.
pub fn stdout_bytes(bytes: &[u8]) -> Result<(), StdoutError> {
    io::stdout().lock().write_all(bytes).map_err(StdoutError)
}

/// Flushes standard output (what is left of a line without its newline).
pub fn flush_stdout() -> Result<(), StdoutError> {
    io::stdout().lock().flush().map_err(StdoutError)
}

/// `println!` that returns `Result<(), StdoutError>` instead of panicking when standard
/// output cannot be written: `outln!("{x}")?`.
#[macro_export]
macro_rules! outln {
    () => {
        $crate::output_file::stdout_write(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::output_file::stdout_write(format_args!("{}\n", format_args!($($arg)*)))
    };
}
