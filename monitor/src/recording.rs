//! Reading a `cablevib monitor` recording back, message by message, in bounded memory.
//!
//! The file must be a regular file (a FIFO, a device such as `/dev/zero` or a directory is
//! refused with one line, as every input of cablevib is: `cablevib::input_file`) and a
//! complete MCAP file: MCAP magic at its start, a footer record and the magic at its end (a
//! monitor killed before it closed the file leaves neither; the Python `mcap` reader reads such
//! a file up to its last whole chunk). It is then read chunk by chunk (`mcap::io::MessageReader`
//! over a buffered file): each chunk's CRC is checked before any of its messages is yielded,
//! and a chunk whose compressed or decompressed size, or a record whose length, is above
//! [`MAX_CHUNK_BYTES`] is refused with one line, so memory is bounded by about twice that
//! whatever the file's length or what its headers claim.

use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

use cablevib::input_file::open_checked;
use mcap::sans_io::LinearReaderOptions;

use crate::encode::{PoseRecord, TminRecord, SCHEMA_ESTIMATE, SCHEMA_POSE, SCHEMA_T_MIN};
use crate::MonitorError;

/// The largest MCAP chunk (compressed or decompressed) or record read, bytes (64 MiB): the
/// monitor writes chunks of 256 KiB, `ros2 bag` of about 1 MiB.
pub const MAX_CHUNK_BYTES: usize = 64 * 1024 * 1024;

/// Bytes of an MCAP file's end: footer record (opcode, length, 20 bytes) and magic.
const FOOTER_AND_MAGIC: u64 = 1 + 8 + 20 + 8;
/// The footer record's opcode.
const OP_FOOTER: u8 = 0x02;

/// One cablevib message of a recording.
#[derive(Debug, Clone)]
pub enum Recorded {
    /// A pose.
    Pose(PoseRecord),
    /// A T_min set-point.
    Tmin(TminRecord),
    /// An estimate: its JSON text (parse what you need).
    Estimate(Vec<u8>),
}

/// The cablevib messages of a recording, in file order (other channels are skipped).
pub struct RecordingReader {
    shown: String,
    messages: mcap::io::MessageReader<BufReader<std::fs::File>>,
}

/// Opens recording `path`: a regular, complete MCAP file (one-line errors otherwise).
pub fn read_recording(path: &Path) -> Result<RecordingReader, MonitorError> {
    let shown = path.display().to_string();
    let bad = |what: String| MonitorError::Recording(format!("{shown}: {what}"));
    let mut f = open_checked(path, "recording", u64::MAX)
        .map_err(|e| MonitorError::Recording(e.to_string()))?;
    let io = |e: std::io::Error| bad(format!("cannot read: {e}"));
    let len = f.metadata().map_err(io)?.len();
    let mut start = [0u8; 8];
    let n = read_up_to(&mut f, &mut start).map_err(io)?;
    if n < 8 || start[..] != mcap::MAGIC[..] {
        return Err(bad("not an MCAP file (no MCAP magic at its start)".into()));
    }
    // The footer and the magic close a complete file: their absence means it was cut short.
    let complete = len >= 8 + FOOTER_AND_MAGIC && {
        let mut end = [0u8; FOOTER_AND_MAGIC as usize];
        f.seek(SeekFrom::End(-(FOOTER_AND_MAGIC as i64)))
            .map_err(io)?;
        read_up_to(&mut f, &mut end).map_err(io)? == end.len()
            && end[0] == OP_FOOTER
            && end[1..9] == 20u64.to_le_bytes()
            && end[29..] == mcap::MAGIC[..]
    };
    if !complete {
        return Err(bad(
            "not a complete MCAP file (no footer and end magic: a recording cut short, e.g. \
             by a killed monitor)"
                .into(),
        ));
    }
    f.seek(SeekFrom::Start(0)).map_err(io)?;
    let options = LinearReaderOptions::default()
        .with_prevalidate_chunk_crcs(true)
        .with_record_length_limit(MAX_CHUNK_BYTES);
    Ok(RecordingReader {
        shown,
        messages: mcap::io::MessageReader::new_with_options(
            BufReader::with_capacity(256 * 1024, f),
            options,
        ),
    })
}

fn read_up_to(f: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match f.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

impl RecordingReader {
    fn bad(&self, what: String) -> MonitorError {
        MonitorError::Recording(format!("{}: {what}", self.shown))
    }
}

impl Iterator for RecordingReader {
    type Item = Result<Recorded, MonitorError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let m = match self.messages.next()? {
                Ok(m) => m,
                Err(mcap::McapError::ChunkTooLarge(n)) => {
                    return Some(Err(self.bad(format!(
                        "an MCAP chunk of {n} bytes, over the limit of {MAX_CHUNK_BYTES} bytes"
                    ))))
                }
                Err(mcap::McapError::RecordTooLarge { opcode, len }) => {
                    return Some(Err(self.bad(format!(
                        "an MCAP record (opcode {opcode:#04x}) of {len} bytes, over the limit \
                         of {MAX_CHUNK_BYTES} bytes"
                    ))))
                }
                Err(e) => {
                    return Some(Err(self.bad(format!(
                        "unreadable MCAP content ({})",
                        e.to_string().replace('\n', " ")
                    ))))
                }
            };
            let Some(schema) = m.channel.schema.as_ref() else {
                continue;
            };
            let topic = &m.channel.topic;
            let parsed = match schema.name.as_str() {
                SCHEMA_POSE => serde_json::from_slice(&m.data)
                    .map(Recorded::Pose)
                    .map_err(|e| format!("a pose on {topic} does not fit {SCHEMA_POSE} ({e})")),
                SCHEMA_T_MIN => serde_json::from_slice(&m.data)
                    .map(Recorded::Tmin)
                    .map_err(|e| {
                        format!("a set-point on {topic} does not fit {SCHEMA_T_MIN} ({e})")
                    }),
                SCHEMA_ESTIMATE => Ok(Recorded::Estimate(m.data.into_owned())),
                _ => continue,
            };
            return Some(parsed.map_err(|e| self.bad(e)));
        }
    }
}
