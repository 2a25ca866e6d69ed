//! Writing the files a command produces: never over one of its inputs, and whole or not at
//! all.
//!
//! - [`refuse_inputs`]: before anything is written, an output that is one of the command's
//!   inputs (the same file: device and inode, whatever the names, so a hard link, a symbolic
//!   link or `./` do not hide it), or two outputs that are one file, is refused with a
//!   one-line error naming both.
//! - [`OutputFile`]: a file is written under a temporary name beside its target,
//!   `NAME.PID.part` in the same directory (so the final rename stays on one file system),
//!   and renamed over the target only by [`OutputFile::commit`], after its data reached the
//!   disk (`fsync`). An error (the file dropped uncommitted), a panic, or SIGINT, SIGTERM,
//!   SIGHUP or SIGPIPE with their default action (`cleanup`) removes the temporary file
//!   and leaves a target that existed before untouched. SIGKILL (or a power cut) leaves the
//!   temporary `NAME.PID.part` beside an untouched target.
//! - [`write_whole`]: a whole file from bytes in memory, the same way.
//! - [`ScratchFile`]: a temporary file beside a target that is never renamed (a writer's
//!   spill space), removed the same way.
//! - [`crate::outln!`]: standard output, written with an error instead of a panic when it
//!   cannot be ([`StdoutError`]).
//!
//! A target that is a symbolic link is written through it (the link is kept, the file it
//! points to replaced). A target that exists and is a character device or a FIFO
//! (`/dev/stdout`, `/dev/null`, a pipe) is written in place, since it cannot be replaced; a
//! directory, block device or socket is refused. A replaced file keeps its permission bits;
//! other hard links to it keep the old contents (the name gets a new file).

mod cleanup;
mod stdout;

use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::{FileTypeExt, MetadataExt, OpenOptionsExt, PermissionsExt};
use std::path::{Component, Path, PathBuf};

pub use cleanup::SLOTS as MAX_SIGNAL_CLEANED_FILES;
pub use stdout::{flush_stdout, stdout_bytes, stdout_write, StdoutError};

/// Buffer of an [`OutputFile`], bytes.
const BUFFER_BYTES: usize = 64 * 1024;
/// Longest file name kept in a temporary name, bytes (a name is at most 255 bytes, and the
/// temporary one adds `.PID-K.part`).
const TEMP_NAME_BYTES: usize = 200;
/// Symbolic links followed to find a target's file.
const MAX_LINKS: usize = 40;

/// Why an output was not written.
#[derive(Debug, thiserror::Error)]
pub enum OutputFileError {
    /// The output is one of the command's inputs.
    #[error(
        "{output}: is the input {input} (the same file); an output is never written over an \
         input: choose another output path"
    )]
    IsInput {
        /// The output, as given.
        output: String,
        /// The input, as given.
        input: String,
    },
    /// Two outputs of one command are the same file.
    #[error("{second}: is also the output {first}; each output needs a path of its own")]
    SameOutput {
        /// The first output, as given.
        first: String,
        /// The second output, as given.
        second: String,
    },
    /// The target is a directory, block device or socket.
    #[error("{file}: is a {kind}; an output must be a regular file, a character device or a FIFO")]
    NotWritable {
        /// The target.
        file: String,
        /// What it is.
        kind: &'static str,
    },
    /// The target exists and the output must not replace anything.
    #[error("{file}: exists; it is never overwritten (choose a new path)")]
    Exists {
        /// The target.
        file: String,
    },
    /// The OS refused an operation.
    #[error("{file}: cannot {what}: {cause}")]
    Io {
        /// The target, as given.
        file: String,
        /// What failed, e.g. `write`.
        what: &'static str,
        /// The cause, in the message (not a `source()`, which the command line would print
        /// again).
        cause: io::Error,
    },
}

/// A file's identity: device and inode (symbolic links followed); `None` when it cannot be
/// read (then it is no file the command reads or replaces).
fn identity(path: &Path) -> Option<(u64, u64)> {
    std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
}

/// `path` made absolute and lexically normal (`.` dropped, `..` applied), for comparing
/// outputs that do not exist yet.
fn normal(path: &Path) -> PathBuf {
    let abs = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir().unwrap_or_default().join(path)
    };
    let mut out = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            c => out.push(c),
        }
    }
    out
}

/// Refuses, before anything is written, an output that is one of `inputs` (by identity)
/// and two outputs that are one file (by identity, or by name when they do not exist yet).
/// Inputs that do not exist are skipped (reading them fails on its own).
pub fn refuse_inputs<P: AsRef<Path>, Q: AsRef<Path>>(
    outputs: &[P],
    inputs: &[Q],
) -> Result<(), OutputFileError> {
    let ins: Vec<(&Path, (u64, u64))> = inputs
        .iter()
        .filter_map(|p| identity(p.as_ref()).map(|id| (p.as_ref(), id)))
        .collect();
    // (the output as named, its file identity when it exists, its normalised path)
    type Seen<'a> = (&'a Path, Option<(u64, u64)>, PathBuf);
    let mut seen: Vec<Seen<'_>> = Vec::new();
    for out in outputs {
        let out = out.as_ref();
        let id = identity(out);
        if let Some(id) = id {
            if let Some((input, _)) = ins.iter().find(|(_, i)| *i == id) {
                return Err(OutputFileError::IsInput {
                    output: out.display().to_string(),
                    input: input.display().to_string(),
                });
            }
        }
        let name = normal(out);
        if let Some((first, _, _)) = seen
            .iter()
            .find(|(_, i, n)| (id.is_some() && *i == id) || *n == name)
        {
            return Err(OutputFileError::SameOutput {
                first: first.display().to_string(),
                second: out.display().to_string(),
            });
        }
        seen.push((out, id, name));
    }
    Ok(())
}

/// The file a target names: symbolic links followed (a dangling one to the file it would
/// create).
fn resolve(target: &Path) -> io::Result<PathBuf> {
    let mut p = target.to_path_buf();
    for _ in 0..MAX_LINKS {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let link = std::fs::read_link(&p)?;
                p = match p.parent() {
                    Some(dir) if link.is_relative() => dir.join(link),
                    _ => link,
                };
            }
            _ => return Ok(p),
        }
    }
    Err(io::Error::other("too many levels of symbolic links"))
}

/// A temporary file's path, removed on drop unless kept.
#[derive(Debug)]
struct TempPath {
    path: PathBuf,
    registration: Option<cleanup::Registration>,
}

impl TempPath {
    /// Creates a new, empty temporary file beside `file` (never an existing one), with
    /// permission bits `mode`.
    fn create_beside(file: &Path, mode: u32) -> io::Result<(TempPath, File)> {
        let dir = match file.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let dir = if dir.is_absolute() {
            dir
        } else {
            std::env::current_dir()?.join(dir)
        };
        let name = file.file_name().map_or(&[][..], |n| n.as_bytes());
        let name = String::from_utf8_lossy(&name[..name.len().min(TEMP_NAME_BYTES)]).into_owned();
        let pid = std::process::id();
        let mut k = 0u32;
        loop {
            let tail = if k == 0 {
                format!(".{pid}.part")
            } else {
                format!(".{pid}-{k}.part")
            };
            let path = dir.join(format!("{name}{tail}"));
            match OpenOptions::new()
                .read(true)
                .write(true)
                .create_new(true)
                .mode(mode)
                .open(&path)
            {
                Ok(f) => {
                    let registration = cleanup::register(&path);
                    return Ok((TempPath { path, registration }, f));
                }
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists && k < 1000 => k += 1,
                Err(e) => return Err(e),
            }
        }
    }

    /// Renames the file to `target` (replacing it when `replace`), after which nothing is
    /// removed.
    fn rename_to(mut self, target: &Path, replace: bool) -> io::Result<()> {
        if replace {
            std::fs::rename(&self.path, target)?;
        } else {
            rename_no_replace(&self.path, target)?;
        }
        self.registration = None;
        self.path = PathBuf::new();
        Ok(())
    }
}

impl Drop for TempPath {
    fn drop(&mut self) {
        if !self.path.as_os_str().is_empty() {
            let _ = std::fs::remove_file(&self.path);
        }
        // Then the slot is freed (field drop order: after this body).
    }
}

/// Renames `from` to `to` unless `to` exists (then `AlreadyExists`).
fn rename_no_replace(from: &Path, to: &Path) -> io::Result<()> {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        use std::ffi::CString;
        let c = |p: &Path| CString::new(p.as_os_str().as_bytes()).map_err(io::Error::other);
        let (f, t) = (c(from)?, c(to)?);
        // SAFETY: two valid NUL-terminated paths relative to the working directory.
        let r = unsafe {
            libc::renameat2(
                libc::AT_FDCWD,
                f.as_ptr(),
                libc::AT_FDCWD,
                t.as_ptr(),
                libc::RENAME_NOREPLACE,
            )
        };
        if r == 0 {
            return Ok(());
        }
        let e = io::Error::last_os_error();
        // A file system without the flag: the link below, which fails the same way.
        if !matches!(e.raw_os_error(), Some(libc::EINVAL) | Some(libc::ENOSYS)) {
            return Err(e);
        }
    }
    std::fs::hard_link(from, to)?;
    std::fs::remove_file(from)
}

/// What an existing target is, for a refusal (`None`: it can be written).
fn unwritable_kind(t: std::fs::FileType) -> Option<&'static str> {
    if t.is_dir() {
        Some("directory")
    } else if t.is_block_device() {
        Some("block device")
    } else if t.is_socket() {
        Some("socket")
    } else {
        None
    }
}

/// An output file being written (see the module doc): [`Write`] and [`Seek`] into it, then
/// [`OutputFile::commit`]. Dropped uncommitted, it leaves no trace.
#[derive(Debug)]
pub struct OutputFile {
    /// The target as given (messages).
    shown: PathBuf,
    /// The file the target names (symbolic links followed).
    target: PathBuf,
    /// The temporary file, `None` for a target written in place (device, FIFO).
    temp: Option<TempPath>,
    writer: BufWriter<File>,
    replace: bool,
}

impl OutputFile {
    /// Starts writing `target`, which [`OutputFile::commit`] replaces when it exists.
    pub fn create(target: &Path) -> Result<OutputFile, OutputFileError> {
        OutputFile::open(target, true)
    }

    /// Starts writing `target`, which must not exist now nor when committed
    /// ([`OutputFileError::Exists`]).
    pub fn create_new(target: &Path) -> Result<OutputFile, OutputFileError> {
        OutputFile::open(target, false)
    }

    fn open(target: &Path, replace: bool) -> Result<OutputFile, OutputFileError> {
        let shown = target.to_path_buf();
        let io = |what, cause| OutputFileError::Io {
            file: shown.display().to_string(),
            what,
            cause,
        };
        let file = resolve(target).map_err(|e| io("resolve the path", e))?;
        let existing = match std::fs::metadata(&file) {
            Ok(m) => Some(m),
            Err(e) if e.kind() == io::ErrorKind::NotFound => None,
            Err(e) => return Err(io("read the target's metadata", e)),
        };
        if let Some(m) = &existing {
            if let Some(kind) = unwritable_kind(m.file_type()) {
                return Err(OutputFileError::NotWritable {
                    file: shown.display().to_string(),
                    kind,
                });
            }
            if !replace {
                return Err(OutputFileError::Exists {
                    file: shown.display().to_string(),
                });
            }
            if !m.file_type().is_file() {
                // A character device or a FIFO: written in place.
                let f = OpenOptions::new()
                    .write(true)
                    .truncate(true)
                    .open(&file)
                    .map_err(|e| io("open", e))?;
                return Ok(OutputFile {
                    shown,
                    target: file,
                    temp: None,
                    writer: BufWriter::with_capacity(BUFFER_BYTES, f),
                    replace,
                });
            }
        }
        // A replaced file keeps its permission bits; a new one gets 0o666 less the umask.
        let mode = existing
            .as_ref()
            .map_or(0o666, |m| m.permissions().mode() & 0o7777);
        let (temp, f) = TempPath::create_beside(&file, mode)
            .map_err(|e| io("create a temporary file beside it", e))?;
        if existing.is_some() {
            // create_new applied the umask to `mode`; the replaced file's bits exactly.
            let _ = f.set_permissions(std::fs::Permissions::from_mode(mode));
        }
        Ok(OutputFile {
            shown,
            target: file,
            temp: Some(temp),
            writer: BufWriter::with_capacity(BUFFER_BYTES, f),
            replace,
        })
    }

    /// The same file with no user-space buffer: every write goes straight to the file (what
    /// a reader of a file killed mid-way sees is all that was written).
    pub fn unbuffered(self) -> Result<OutputFile, OutputFileError> {
        let OutputFile {
            shown,
            target,
            temp,
            writer,
            replace,
        } = self;
        let file = writer.into_inner().map_err(|e| OutputFileError::Io {
            file: shown.display().to_string(),
            what: "write",
            cause: e.into_error(),
        })?;
        Ok(OutputFile {
            shown,
            target,
            temp,
            writer: BufWriter::with_capacity(0, file),
            replace,
        })
    }

    /// The target, as given.
    pub fn path(&self) -> &Path {
        &self.shown
    }

    /// The temporary file being written (`None` for a target written in place).
    pub fn temp_path(&self) -> Option<&Path> {
        self.temp.as_ref().map(|t| t.path.as_path())
    }

    /// Flushes, syncs the data to the disk and renames the file over its target.
    pub fn commit(self) -> Result<(), OutputFileError> {
        let OutputFile {
            shown,
            target,
            temp,
            writer,
            replace,
        } = self;
        let io = |what, cause| OutputFileError::Io {
            file: shown.display().to_string(),
            what,
            cause,
        };
        let file = writer
            .into_inner()
            .map_err(|e| io("write", e.into_error()))?;
        let Some(temp) = temp else {
            return Ok(());
        };
        file.sync_all().map_err(|e| io("write", e))?;
        drop(file);
        temp.rename_to(&target, replace).map_err(|e| {
            if e.kind() == io::ErrorKind::AlreadyExists {
                OutputFileError::Exists {
                    file: shown.display().to_string(),
                }
            } else {
                io("rename the finished file into place", e)
            }
        })
    }
}

impl Write for OutputFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.writer.write(buf)
    }
    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.writer.write_all(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.writer.flush()
    }
}

impl Seek for OutputFile {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        self.writer.seek(pos)
    }
}

/// Writes `bytes` to `target` whole or not at all ([`OutputFile`]).
pub fn write_whole(target: &Path, bytes: &[u8]) -> Result<(), OutputFileError> {
    let mut f = OutputFile::create(target)?;
    f.write_all(bytes).map_err(|cause| OutputFileError::Io {
        file: target.display().to_string(),
        what: "write",
        cause,
    })?;
    f.commit()
}

/// A temporary file beside a target, never renamed: removed when dropped, on a panic, or
/// on a signal as an [`OutputFile`]'s.
#[derive(Debug)]
pub struct ScratchFile {
    file: File,
    temp: TempPath,
}

impl ScratchFile {
    /// A new, empty scratch file beside `target` (read and write).
    pub fn create_beside(target: &Path) -> Result<ScratchFile, OutputFileError> {
        let file = resolve(target).unwrap_or_else(|_| target.to_path_buf());
        let (temp, file) =
            TempPath::create_beside(&file, 0o600).map_err(|cause| OutputFileError::Io {
                file: target.display().to_string(),
                what: "create a scratch file beside it",
                cause,
            })?;
        Ok(ScratchFile { file, temp })
    }

    /// The open file.
    pub fn file(&self) -> &File {
        &self.file
    }

    /// The scratch file's path.
    pub fn path(&self) -> &Path {
        &self.temp.path
    }
}

#[cfg(test)]
mod tests;
