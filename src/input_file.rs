//! Bounded reading of the text files a user hands the program (scenes, trajectory CSVs).
//!
//! [`read_text`] reads a whole file into a `String` only when it is a regular file of at
//! most a named number of bytes and valid UTF-8. A device (`/dev/zero`, `/dev/urandom`)
//! would otherwise be read until memory runs out, a FIFO would block forever, and a
//! directory would give an obscure OS error; each is refused with a one-line message that
//! names the file and what it is.
//!
//! What a message quotes from those files is kept short: [`message_number`] (a number in at
//! most 6 significant digits) and [`message_excerpt`] (a line cut and escaped).

use std::fs::{File, FileType, Metadata, OpenOptions};
use std::io::Read;
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::Path;

/// Largest scene file read, bytes (16 MiB): a scene with the most cables the IPC layout
/// allows is a few kB, so only a wrong file reaches this.
pub const MAX_SCENE_BYTES: u64 = 16 * 1024 * 1024;

/// Largest trajectory CSV read, bytes (256 MiB): an hour of 1 kHz `t,x,y,z` rows at about
/// 60 bytes a row (≈ 216 MB) fits; the parsed samples take about half as much again.
pub const MAX_TRAJECTORY_BYTES: u64 = 256 * 1024 * 1024;

/// Why an input file was not read.
#[derive(Debug, thiserror::Error)]
pub enum InputFileError {
    /// The OS refused to stat, open or read the file.
    #[error("{file}: cannot read {what}: {cause}")]
    Io {
        /// The file.
        file: String,
        /// What the file was meant to be, e.g. `scene file`.
        what: &'static str,
        /// The cause, in the message (not a `source()`: the command line prints the chain of
        /// sources, which would repeat it).
        cause: std::io::Error,
    },
    /// A directory, FIFO, socket or device.
    #[error("{file}: is a {kind}, not a regular file; a {what} must be a regular file")]
    NotRegular {
        /// The file.
        file: String,
        /// What the file was meant to be.
        what: &'static str,
        /// What it is, e.g. `FIFO (named pipe)`.
        kind: &'static str,
    },
    /// Larger than the limit for its kind of input.
    #[error("{file}: {what} is {size_bytes} bytes, over the limit of {limit_bytes} bytes")]
    TooLarge {
        /// The file.
        file: String,
        /// What the file was meant to be.
        what: &'static str,
        /// Its size, bytes (the size read when the file grew while being read).
        size_bytes: u64,
        /// The limit, bytes.
        limit_bytes: u64,
    },
    /// Not UTF-8 text.
    #[error("{file}: {what} is not UTF-8 text (invalid byte at offset {offset})")]
    NotUtf8 {
        /// The file.
        file: String,
        /// What the file was meant to be.
        what: &'static str,
        /// Byte offset of the first invalid sequence.
        offset: usize,
    },
}

/// Reads the regular file `path` as UTF-8 text of at most `limit_bytes` bytes; `what`
/// (e.g. `scene file`) says in errors what the file was meant to be.
pub fn read_text(
    path: &Path,
    what: &'static str,
    limit_bytes: u64,
) -> Result<String, InputFileError> {
    let file = path.display().to_string();
    let io = |cause| InputFileError::Io {
        file: file.clone(),
        what,
        cause,
    };
    let mut f = open_checked(path, what, limit_bytes)?;
    let bytes = read_at_most(&mut f, limit_bytes).map_err(io)?;
    if bytes.len() as u64 > limit_bytes {
        // The file grew after the size check (or its size is not known, as in /proc).
        return Err(InputFileError::TooLarge {
            file,
            what,
            size_bytes: bytes.len() as u64,
            limit_bytes,
        });
    }
    String::from_utf8(bytes).map_err(|e| InputFileError::NotUtf8 {
        file,
        what,
        offset: e.utf8_error().valid_up_to(),
    })
}

/// Opens `path` for reading when it is a regular file of at most `limit_bytes` bytes (the
/// checks of [`read_text`], for a reader that streams the file: it must still stop at
/// `limit_bytes`, since the file can grow after the check).
pub fn open_checked(
    path: &Path,
    what: &'static str,
    limit_bytes: u64,
) -> Result<File, InputFileError> {
    let file = path.display().to_string();
    let io = |cause| InputFileError::Io {
        file: file.clone(),
        what,
        cause,
    };
    // Checked twice. `std::fs::metadata` (follows symlinks) refuses a FIFO or device before
    // anything is opened: opening a FIFO blocks until a writer appears and opening some
    // devices has side effects. The path can still be swapped between that check and the
    // open, so the open is non-blocking (O_NONBLOCK: no effect on regular files) and the
    // opened handle is checked again; that second check is the one that cannot race.
    check_kind_and_size(
        &std::fs::metadata(path).map_err(io)?,
        &file,
        what,
        limit_bytes,
    )?;
    let f = OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(io)?;
    check_kind_and_size(&f.metadata().map_err(io)?, &file, what, limit_bytes)?;
    Ok(f)
}

/// A regular file of at most `limit_bytes` bytes.
fn check_kind_and_size(
    meta: &Metadata,
    file: &str,
    what: &'static str,
    limit_bytes: u64,
) -> Result<(), InputFileError> {
    if let Some(kind) = irregular_kind(meta.file_type()) {
        return Err(InputFileError::NotRegular {
            file: file.to_string(),
            what,
            kind,
        });
    }
    if meta.len() > limit_bytes {
        return Err(InputFileError::TooLarge {
            file: file.to_string(),
            what,
            size_bytes: meta.len(),
            limit_bytes,
        });
    }
    Ok(())
}

/// What a file that is not a regular file is, for the message (`None` for a regular file).
fn irregular_kind(t: FileType) -> Option<&'static str> {
    if t.is_file() {
        None
    } else if t.is_dir() {
        Some("directory")
    } else if t.is_fifo() {
        Some("FIFO (named pipe)")
    } else if t.is_char_device() {
        Some("character device")
    } else if t.is_block_device() {
        Some("block device")
    } else if t.is_socket() {
        Some("socket")
    } else {
        Some("special file")
    }
}

/// At most `limit_bytes + 1` bytes of `f` (one more than allowed tells a file over the
/// limit from one exactly at it).
fn read_at_most(f: &mut File, limit_bytes: u64) -> std::io::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    f.take(limit_bytes.saturating_add(1))
        .read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// A number from the user for a message: up to 6 significant digits, plain between 1e-3
/// and 1e6, else in scientific notation (`1e308`, not 309 digits); NaN and ±inf as such.
pub fn message_number(x: f64) -> String {
    if !x.is_finite() || x == 0.0 {
        return format!("{x}");
    }
    let plain = format!("{x}");
    if plain.len() <= 10 {
        return plain;
    }
    if (1e-3..1e6).contains(&x.abs()) {
        let s = format!("{x:.6}");
        return s.trim_end_matches('0').trim_end_matches('.').to_string();
    }
    let s = format!("{x:.5e}");
    match s.split_once('e') {
        Some((m, e)) => format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.')),
        None => s,
    }
}

/// A number for a message with `decimals` fixed decimals (`-12.3457` for 4), as
/// `format!("{x:.decimals$}")` writes it, except from 1e6 in magnitude on: there
/// [`message_number`]'s compact form (`1e307`, not 308 digits and the decimals).
pub fn message_fixed(x: f64, decimals: usize) -> String {
    if x.is_finite() && x.abs() >= 1e6 {
        message_number(x)
    } else {
        format!("{x:.decimals$}")
    }
}

/// Longest excerpt of a user's line quoted in a message, characters.
pub const MESSAGE_EXCERPT_CHARS: usize = 80;

/// A line from a user's file for a message: at most [`MESSAGE_EXCERPT_CHARS`] characters,
/// control characters (NUL, CR, ESC, …) escaped as `\0`, `\r`, `\u{1b}`, and `…` with the
/// line's length in bytes when it was cut. A message stays one short line whatever the
/// file holds.
pub fn message_excerpt(line: &str) -> String {
    let mut out = String::new();
    for (k, c) in line.chars().enumerate() {
        if k == MESSAGE_EXCERPT_CHARS {
            out.push_str(&format!("… ({} bytes)", line.len()));
            break;
        }
        if c == '\0' {
            out.push_str("\\0");
        } else if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// Hostile files for tests: a FIFO, a sparse file, and a guard against a read that blocks.
#[cfg(test)]
pub(crate) mod test_files {
    use std::path::{Path, PathBuf};
    use std::sync::mpsc;
    use std::time::Duration;

    /// How long a read may take before the test counts it as blocked.
    pub(crate) const READ_TIMEOUT: Duration = Duration::from_secs(5);

    /// A fresh, empty directory for one test.
    pub(crate) fn temp_dir(test: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("cablevib-{test}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("create test directory");
        d
    }

    /// A FIFO `name` in `dir` (nobody ever writes to it).
    pub(crate) fn fifo(dir: &Path, name: &str) -> PathBuf {
        let p = dir.join(name);
        let c = std::ffi::CString::new(p.to_str().expect("UTF-8 path")).expect("no NUL");
        // SAFETY: a valid NUL-terminated path; mkfifo only creates a file system entry.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
        p
    }

    /// The files that are not regular, each with its kind as the errors name it: a FIFO
    /// `fifo_name` made in `dir`, two character devices, and `dir` itself.
    pub(crate) fn non_regular(dir: &Path, fifo_name: &str) -> [(PathBuf, &'static str); 4] {
        [
            (fifo(dir, fifo_name), "FIFO (named pipe)"),
            (PathBuf::from("/dev/zero"), "character device"),
            (PathBuf::from("/dev/urandom"), "character device"),
            (dir.to_path_buf(), "directory"),
        ]
    }

    /// A sparse file `name` of `len` bytes in `dir` (no disk space used).
    pub(crate) fn sparse(dir: &Path, name: &str, len: u64) -> PathBuf {
        let p = dir.join(name);
        let f = std::fs::File::create(&p).expect("create sparse file");
        f.set_len(len).expect("set_len");
        p
    }

    /// `f()` in a thread; panics (fails the test) when it does not return within
    /// [`READ_TIMEOUT`], which a read of a FIFO without the kind check would not.
    pub(crate) fn within_timeout<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let _ = tx.send(f());
        });
        rx.recv_timeout(READ_TIMEOUT)
            .expect("the read blocked (no answer within the timeout)")
    }
}

#[cfg(test)]
mod tests {
    use super::test_files::*;
    use super::*;

    #[test]
    fn message_excerpts_are_short_and_escaped() {
        assert_eq!(message_excerpt("0,1,2,3"), "0,1,2,3");
        assert_eq!(
            message_excerpt("a\0b\rc\u{1b}d\te"),
            "a\\0b\\rc\\u{1b}d\\te"
        );
        let long = "x".repeat(5_000_000);
        let m = message_excerpt(&long);
        assert_eq!(
            m,
            format!("{}… (5000000 bytes)", "x".repeat(MESSAGE_EXCERPT_CHARS))
        );
    }

    #[test]
    fn message_numbers_are_compact() {
        assert_eq!(message_number(1e308), "1e308");
        assert_eq!(message_number(-1e308), "-1e308");
        assert_eq!(message_number(25.0), "25");
        assert_eq!(message_number(0.1 + 0.2), "0.3");
        assert_eq!(message_number(f64::NAN), "NaN");
    }

    /// `read_text` of a test file, failing the test if it blocks.
    fn read_with_timeout(path: &Path, limit: u64) -> Result<String, InputFileError> {
        let p = path.to_path_buf();
        within_timeout(move || read_text(&p, "test file", limit))
    }

    #[test]
    fn a_small_text_file_is_read() {
        let d = temp_dir("input-ok");
        let p = d.join("a.txt");
        std::fs::write(&p, "héllo\n").unwrap();
        assert_eq!(read_with_timeout(&p, 7).unwrap(), "héllo\n");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn devices_fifos_and_directories_are_refused() {
        let d = temp_dir("input-kinds");
        for (p, kind) in non_regular(&d, "fifo") {
            let e = read_with_timeout(&p, MAX_SCENE_BYTES).unwrap_err();
            assert!(matches!(e, InputFileError::NotRegular { .. }), "{e:?}");
            let msg = e.to_string();
            assert!(
                msg.starts_with(&p.display().to_string()) && msg.contains(kind),
                "{msg}"
            );
            assert!(!msg.contains('\n'), "{msg}");
        }
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_file_over_the_limit_is_refused_and_one_at_it_read() {
        let d = temp_dir("input-size");
        let p = sparse(&d, "big", MAX_SCENE_BYTES + 1);
        let msg = read_with_timeout(&p, MAX_SCENE_BYTES)
            .unwrap_err()
            .to_string();
        let size = (MAX_SCENE_BYTES + 1).to_string();
        let limit = MAX_SCENE_BYTES.to_string();
        assert!(
            msg.contains("big") && msg.contains(&size) && msg.contains(&limit),
            "{msg}"
        );
        std::fs::write(&p, "abcd").unwrap();
        assert_eq!(read_with_timeout(&p, 4).unwrap(), "abcd");
        assert!(matches!(
            read_with_timeout(&p, 3),
            Err(InputFileError::TooLarge { size_bytes: 4, .. })
        ));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_file_of_unknown_size_is_bounded_by_the_read() {
        // /proc files report size 0 whatever they hold.
        let e = read_with_timeout(Path::new("/proc/self/maps"), 8).unwrap_err();
        assert!(
            matches!(
                e,
                InputFileError::TooLarge {
                    size_bytes: 9,
                    limit_bytes: 8,
                    ..
                }
            ),
            "{e:?}"
        );
    }

    #[test]
    fn non_utf8_is_refused() {
        let d = temp_dir("input-utf8");
        let p = d.join("bin");
        std::fs::write(&p, b"ab\xffcd").unwrap();
        let msg = read_with_timeout(&p, 100).unwrap_err().to_string();
        assert!(
            msg.contains("not UTF-8") && msg.contains("offset 2"),
            "{msg}"
        );
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_missing_file_names_the_file() {
        let msg = read_with_timeout(Path::new("/no/such/file.toml"), 10)
            .unwrap_err()
            .to_string();
        assert!(
            msg.starts_with("/no/such/file.toml: cannot read test file"),
            "{msg}"
        );
    }
}
