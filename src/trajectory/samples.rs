//! Sampled trajectories: poses at listed times, read from a CSV file.
//!
//! ## Trajectory CSV files (one rule set, [`Samples::parse_csv`])
//!
//! - Each data row is `t,x,y,z` (time in s, position in m) or `t,x,y,z,qw,qx,qy,qz` (and
//!   the end-effector orientation as a unit quaternion w, x, y, z): 4 or 8 finite numbers.
//!   Every data row has as many fields as the first one.
//! - A quaternion follows the command line's rule ([`unit_quaternion`]): |‖q‖ − 1| at most
//!   [`QUATERNION_INPUT_TOL`](crate::kinematics::QUATERNION_INPUT_TOL) (= 1e-3, so 4 printed digits pass), then divided by its norm;
//!   otherwise the row is refused, naming its line. Without quaternion columns the poses
//!   take the scene's orientation. A point-mass end-effector has no orientation: the
//!   columns are then checked and have no effect (the command line says so once).
//! - Times increase strictly from row to row.
//! - Lines end with LF, CR LF or CR alone (each counts as one line in messages); a UTF-8
//!   byte-order mark at the start of the file is not part of the first line.
//! - Blank lines are skipped; `#` starts a comment that runs to the end of its line.
//! - One header line (a row whose fields are not all numbers) is allowed before the first
//!   data row.
//! - At least one data row.
//!
//! Between samples the position is interpolated linearly and the orientation by slerp (the
//! shorter arc). Errors name the file and the line, quoting at most 80 characters of it
//! with control characters escaped, and numbers in at most 6 significant digits.

use std::path::Path;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::TrajectoryError;
use crate::input_file::{
    message_excerpt, message_number, open_checked, InputFileError, MAX_TRAJECTORY_BYTES,
};
use crate::kinematics::{unit_quaternion, Pose};
use crate::scene::Scene;

/// Fields of a row without orientation: t, x, y, z.
const FIELDS_POSITION: usize = 4;
/// Fields of a row with orientation: t, x, y, z, qw, qx, qy, qz.
const FIELDS_POSE: usize = 8;

/// Poses at listed times.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Samples {
    /// Times, s, strictly increasing.
    pub t_s: Vec<f64>,
    /// Positions, m.
    pub position_m: Vec<Vector3<f64>>,
    /// Orientations, unit quaternions [w, x, y, z], one per time; empty when the file has no
    /// quaternion columns (the poses then take the scene's orientation).
    pub orientation_wxyz: Vec<[f64; 4]>,
    /// Angle along the circle, degrees (empty unless sampled from a [`crate::trajectory::Circle`]).
    pub angle_deg: Vec<f64>,
}

impl Samples {
    /// Reads a trajectory CSV file (rules in the module docs; a regular file of at most
    /// [`MAX_TRAJECTORY_BYTES`]). The samples take memory in proportion to the file;
    /// [`visit_csv`] reads a file row by row in bounded memory.
    pub fn read_csv(path: &Path) -> Result<Samples, TrajectoryError> {
        let mut s = Samples::default();
        visit_csv(path, |r| {
            s.push(&r);
            Ok::<(), TrajectoryError>(())
        })?;
        Ok(s)
    }

    /// Parses trajectory CSV text (rules in the module docs); `origin` names the source in
    /// errors.
    pub fn parse_csv(text: &str, origin: &str) -> Result<Samples, TrajectoryError> {
        let mut s = Samples::default();
        let mut p = RowParser::new(origin);
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        for (i, line) in lines(text).enumerate() {
            if let Some(r) = p.line(i + 1, line)? {
                s.push(&r);
            }
        }
        p.finish()?;
        Ok(s)
    }

    /// Appends one row.
    fn push(&mut self, r: &Row) {
        self.t_s.push(r.t_s);
        self.position_m.push(r.position_m);
        if let Some(q) = r.orientation_wxyz {
            self.orientation_wxyz.push(q);
        }
    }

    /// The position at time `t_s` (s from the first sample), m, linear between samples;
    /// the first position before the start, `None` after the last sample.
    pub fn position_at(&self, t_s: f64) -> Option<Vector3<f64>> {
        let (j, w) = self.segment(t_s)?;
        if w == 0.0 {
            return Some(self.position_m[j]);
        }
        Some(self.position_m[j] * (1.0 - w) + self.position_m[j + 1] * w)
    }

    /// The orientation at time `t_s` (s from the first sample), by slerp between samples
    /// (the shorter arc); the first before the start, `None` after the last sample or when
    /// the samples have no orientation.
    pub fn orientation_at(&self, t_s: f64) -> Option<[f64; 4]> {
        if self.orientation_wxyz.is_empty() {
            return None;
        }
        let (j, w) = self.segment(t_s)?;
        let q = |k: usize| {
            let [w, x, y, z] = self.orientation_wxyz[k];
            UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z))
        };
        if w == 0.0 {
            return Some(self.orientation_wxyz[j]);
        }
        let r = q(j).slerp(&q(j + 1), w).into_inner();
        Some([r.w, r.i, r.j, r.k])
    }

    /// Sample j and the weight w ∈ [0, 1) toward sample j + 1 at time `t_s` from the first
    /// sample (w = 0 before the start and at or after the last sample's time); `None` after
    /// the last sample.
    fn segment(&self, t_s: f64) -> Option<(usize, f64)> {
        let ts = &self.t_s;
        let t = ts[0] + t_s;
        if t > *ts.last()? {
            return None;
        }
        let j = ts.partition_point(|&x| x <= t);
        if j == 0 {
            return Some((0, 0.0));
        }
        if j >= ts.len() {
            return Some((ts.len() - 1, 0.0));
        }
        let (ta, tb) = (ts[j - 1], ts[j]);
        Some((j - 1, (t - ta) / (tb - ta)))
    }

    /// Every sample as a pose: its own orientation, or the scene's when the samples have
    /// none or the end-effector is a point mass.
    pub fn poses(&self, s: &Scene) -> Vec<Pose> {
        self.position_m
            .iter()
            .enumerate()
            .map(|(k, &p)| match self.orientation_wxyz.get(k) {
                // A point mass has no orientation: the columns have no effect there.
                Some(&q) if s.rigid => Pose {
                    position_m: p,
                    orientation_wxyz: q,
                },
                _ => Pose::in_scene(s, p),
            })
            .collect()
    }

    /// Time from the first to the last sample, s.
    pub fn duration_s(&self) -> f64 {
        self.t_s[self.t_s.len() - 1] - self.t_s[0]
    }
}

/// One data row of a trajectory CSV.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// Time, s.
    pub t_s: f64,
    /// Position, m.
    pub position_m: Vector3<f64>,
    /// Orientation, unit quaternion [w, x, y, z] (normalised), when the file has the columns.
    pub orientation_wxyz: Option<[f64; 4]>,
}

impl Row {
    /// This row as a pose: its own orientation, or the scene's when the file has none or
    /// the end-effector is a point mass (which has no orientation).
    pub fn pose(&self, s: &Scene) -> Pose {
        match self.orientation_wxyz {
            Some(q) if s.rigid => Pose {
                position_m: self.position_m,
                orientation_wxyz: q,
            },
            _ => Pose::in_scene(s, self.position_m),
        }
    }
}

/// The rules of the module docs, one line at a time: the one parser of [`Samples::parse_csv`]
/// and [`visit_csv`].
#[derive(Debug)]
struct RowParser<'a> {
    origin: &'a str,
    header_seen: bool,
    fields_per_row: Option<usize>,
    last_t_s: Option<f64>,
    rows: usize,
}

impl<'a> RowParser<'a> {
    fn new(origin: &'a str) -> Self {
        RowParser {
            origin,
            header_seen: false,
            fields_per_row: None,
            last_t_s: None,
            rows: 0,
        }
    }

    /// Line `number` (from 1, without its end): a data row, or nothing (blank, comment,
    /// header).
    fn line(&mut self, number: usize, line: &str) -> Result<Option<Row>, TrajectoryError> {
        let row = |msg: String| TrajectoryError::Row {
            origin: self.origin.to_string(),
            line: number,
            msg,
        };
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            return Ok(None);
        }
        let quoted = || message_excerpt(line);
        let mut values = [0.0; FIELDS_POSE];
        let mut n = 0;
        let mut parse_error = None;
        for f in line.split(',').map(str::trim) {
            match f.parse::<f64>() {
                Ok(v) if n < FIELDS_POSE => values[n] = v,
                Ok(_) => {}
                Err(e) => {
                    parse_error = Some(e);
                    break;
                }
            }
            n += 1;
        }
        if let Some(e) = parse_error {
            if self.rows == 0 && !self.header_seen {
                self.header_seen = true;
                return Ok(None);
            }
            return Err(row(format!("`{}`: {e}", quoted())));
        }
        let width = *self.fields_per_row.get_or_insert(n);
        if !(n == FIELDS_POSITION || n == FIELDS_POSE) || !values[..n].iter().all(|v| v.is_finite())
        {
            return Err(row(format!(
                "expected 4 or 8 finite numbers t,x,y,z[,qw,qx,qy,qz] (s, m, unit quaternion), got `{}`",
                quoted()
            )));
        }
        if n != width {
            return Err(row(format!(
                "expected as many fields as the first data row ({width}), got {n} in `{}`",
                quoted()
            )));
        }
        if let Some(last) = self.last_t_s {
            if values[0] <= last {
                return Err(row(format!(
                    "time {} s does not increase (previous {} s)",
                    message_number(values[0]),
                    message_number(last)
                )));
            }
        }
        let orientation_wxyz = if width == FIELDS_POSE {
            Some(
                unit_quaternion([values[4], values[5], values[6], values[7]])
                    .map_err(|e| row(e.to_string()))?,
            )
        } else {
            None
        };
        self.last_t_s = Some(values[0]);
        self.rows += 1;
        Ok(Some(Row {
            t_s: values[0],
            position_m: Vector3::new(values[1], values[2], values[3]),
            orientation_wxyz,
        }))
    }

    /// The end of the input: an error when it had no data row.
    fn finish(&self) -> Result<(), TrajectoryError> {
        if self.rows == 0 {
            return Err(TrajectoryError::Empty {
                origin: self.origin.to_string(),
            });
        }
        Ok(())
    }
}

/// Longest line [`visit_csv`] reads, bytes (1 MiB; a data row is at most 8 numbers, ~200
/// bytes): a longer line is refused, so one line cannot take the memory of the file.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// What [`visit_csv`] read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CsvShape {
    /// Data rows.
    pub rows: usize,
    /// Whether the rows have quaternion columns.
    pub orientation: bool,
}

/// Reads the trajectory CSV file `path` row by row (the rules of the module docs; a regular
/// file of at most [`MAX_TRAJECTORY_BYTES`]), calling `f` on each data row in order; stops
/// at the first error, the file's or `f`'s. Memory: one line, at most [`MAX_LINE_BYTES`],
/// whatever the file's length.
pub fn visit_csv<E, F>(path: &Path, mut f: F) -> Result<CsvShape, E>
where
    E: From<TrajectoryError>,
    F: FnMut(Row) -> Result<(), E>,
{
    use std::io::{BufReader, Read};
    const WHAT: &str = "trajectory CSV";
    let file = path.display().to_string();
    let io = |cause| {
        TrajectoryError::Input(InputFileError::Io {
            file: file.clone(),
            what: WHAT,
            cause,
        })
    };
    let handle = open_checked(path, WHAT, MAX_TRAJECTORY_BYTES).map_err(TrajectoryError::from)?;
    let mut reader = BufReader::new(handle.take(MAX_TRAJECTORY_BYTES + 1));
    let mut p = RowParser::new(&file);
    let mut buf = Vec::new();
    let (mut offset, mut number, mut orientation, mut after_cr) = (0u64, 0usize, false, false);
    loop {
        let start = offset;
        let Some((read, dropped_lf)) = next_line(&mut reader, &mut buf, after_cr).map_err(io)?
        else {
            break;
        };
        // A CR LF pair is one line end: the LF after a CR is dropped from the next line.
        let start = start + dropped_lf as u64;
        offset += read as u64;
        if offset > MAX_TRAJECTORY_BYTES {
            // The file grew after the size check.
            return Err(TrajectoryError::Input(InputFileError::TooLarge {
                file,
                what: WHAT,
                size_bytes: offset,
                limit_bytes: MAX_TRAJECTORY_BYTES,
            })
            .into());
        }
        number += 1;
        after_cr = buf.last() == Some(&b'\r');
        if matches!(buf.last(), Some(b'\r' | b'\n')) {
            buf.pop();
        } else if buf.len() > MAX_LINE_BYTES {
            return Err(TrajectoryError::Row {
                origin: file.clone(),
                line: number,
                msg: format!(
                    "line longer than {MAX_LINE_BYTES} bytes: `{}`",
                    message_excerpt(&String::from_utf8_lossy(&buf[..200]))
                ),
            }
            .into());
        }
        let text = std::str::from_utf8(&buf).map_err(|e| {
            TrajectoryError::Input(InputFileError::NotUtf8 {
                file: file.clone(),
                what: WHAT,
                offset: (start as usize) + e.valid_up_to(),
            })
        })?;
        let text = if start == 0 {
            text.strip_prefix('\u{feff}').unwrap_or(text)
        } else {
            text
        };
        if let Some(r) = p.line(number, text)? {
            orientation = r.orientation_wxyz.is_some();
            f(r)?;
        }
    }
    p.finish()?;
    Ok(CsvShape {
        rows: p.rows,
        orientation,
    })
}

/// The next line of `reader` into `buf` with its end (LF or CR; at most
/// [`MAX_LINE_BYTES`] + 1 bytes: a longer line is returned cut, without an end), skipping
/// one LF first when `after_cr` (the second byte of a CR LF). Returns the bytes consumed and
/// whether an LF was skipped, or `None` at the end of the input.
fn next_line(
    reader: &mut impl std::io::BufRead,
    buf: &mut Vec<u8>,
    mut after_cr: bool,
) -> std::io::Result<Option<(usize, bool)>> {
    buf.clear();
    let (mut consumed, mut dropped_lf) = (0, false);
    loop {
        let chunk = reader.fill_buf()?;
        if chunk.is_empty() {
            return Ok((!buf.is_empty()).then_some((consumed, dropped_lf)));
        }
        if after_cr {
            after_cr = false;
            if chunk[0] == b'\n' {
                reader.consume(1);
                consumed += 1;
                dropped_lf = true;
                continue;
            }
        }
        let room = MAX_LINE_BYTES + 1 - buf.len();
        let end = chunk
            .iter()
            .take(room)
            .position(|&b| b == b'\n' || b == b'\r');
        let take = end.map_or(chunk.len().min(room), |e| e + 1);
        buf.extend_from_slice(&chunk[..take]);
        reader.consume(take);
        consumed += take;
        if end.is_some() || buf.len() > MAX_LINE_BYTES {
            return Ok(Some((consumed, dropped_lf)));
        }
    }
}

/// The lines of `text`, each ended by LF, CR LF or CR alone (Python's universal newlines),
/// without their ends.
fn lines(text: &str) -> impl Iterator<Item = &str> {
    text.split('\n')
        .flat_map(|l| l.strip_suffix('\r').unwrap_or(l).split('\r'))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_interpolates_and_ends() {
        let t = Samples::parse_csv(
            "t,x,y,z\n0,0,0,1\n# comment\n1.0, 1, 0, 1 # x\n2,1,2,1\n",
            "x",
        )
        .unwrap();
        assert_eq!(t.duration_s(), 2.0);
        assert_eq!(t.position_at(0.5), Some(Vector3::new(0.5, 0.0, 1.0)));
        assert_eq!(t.position_at(1.5), Some(Vector3::new(1.0, 1.0, 1.0)));
        assert_eq!(t.position_at(2.0), Some(Vector3::new(1.0, 2.0, 1.0)));
        assert_eq!(t.position_at(2.5), None);
    }

    #[test]
    fn csv_rules_are_enforced() {
        let bad = [
            ("0,0,0,1\n0,1,1,1\n", "does not increase"),
            ("0,0,0\n", "4 or 8 finite numbers"),
            ("0,0,0,1,5\n", "4 or 8 finite numbers"),
            ("0,0,0,nan\n", "4 or 8 finite numbers"),
            (
                "0,0,0,1\n1,0,0,1,1,0,0,0\n",
                "as many fields as the first data row (4)",
            ),
            ("0,0,0,1,1,0,0,0\n1,0,0,1,2,0,0,0\n", "f.csv:2: orientation"),
            ("0,0,0,1,1,0,0,0\n1,0,0,1,2,0,0,0\n", "norm 2"),
            ("0,0,0,1\nfoo\n", "`foo`"),
            ("t,x,y,z\nt,x,y,z\n0,0,0,1\n", "`t,x,y,z`"),
            ("", "no data rows"),
            ("# only a comment\n", "no data rows"),
        ];
        for (text, why) in bad {
            let e = Samples::parse_csv(text, "f.csv").unwrap_err().to_string();
            assert!(e.contains(why) && e.starts_with("f.csv"), "{text:?}: {e}");
        }
    }

    #[test]
    fn a_byte_order_mark_is_not_a_header() {
        // 5 rows in, 5 out: the t = 0 row after the mark is data, not a header.
        let rows = "0,0,0,1\n1,0,0,1\n2,0,0,1\n3,0,0,1\n4,0,0,1\n";
        let t = Samples::parse_csv(&format!("\u{feff}{rows}"), "b.csv").unwrap();
        assert_eq!(t.t_s, [0.0, 1.0, 2.0, 3.0, 4.0]);
        // With a header after the mark the header is skipped as usual.
        let h = Samples::parse_csv(&format!("\u{feff}t,x,y,z\n{rows}"), "b.csv").unwrap();
        assert_eq!(h.t_s.len(), 5);
    }

    #[test]
    fn cr_only_and_crlf_line_ends_are_read_with_their_line_numbers() {
        let lf = Samples::parse_csv("t,x,y,z\n0,0,0,1\n1,1,0,1\n", "f.csv").unwrap();
        for text in [
            "t,x,y,z\r0,0,0,1\r1,1,0,1\r",
            "t,x,y,z\r\n0,0,0,1\r\n1,1,0,1\r\n",
            "t,x,y,z\r0,0,0,1\n1,1,0,1",
        ] {
            assert_eq!(Samples::parse_csv(text, "f.csv").unwrap(), lf, "{text:?}");
        }
        // Line numbers count each line end once.
        for text in ["0,0,0,1\r0,1,1,1\r", "0,0,0,1\r\n0,1,1,1\r\n"] {
            let e = Samples::parse_csv(text, "f.csv").unwrap_err().to_string();
            assert!(e.starts_with("f.csv:2:"), "{text:?}: {e}");
        }
    }

    #[test]
    fn errors_quote_a_short_escaped_excerpt_and_compact_numbers() {
        let long = format!("0,0,0,1\n{}\0junk\n", "9".repeat(5_000_000));
        let e = Samples::parse_csv(&long, "f.csv").unwrap_err().to_string();
        assert!(
            e.len() < 200 && e.contains("… (5000005 bytes)"),
            "{}",
            &e[..200.min(e.len())]
        );
        let nul = Samples::parse_csv("0,0,0,1\n1,\0,0,1\n", "f.csv")
            .unwrap_err()
            .to_string();
        assert!(
            nul.contains("`1,\\0,0,1`") && !nul.contains('\0'),
            "{nul:?}"
        );
        let back = Samples::parse_csv("1e308,0,0,1\n-1e308,0,0,1\n", "f.csv")
            .unwrap_err()
            .to_string();
        assert!(
            back.contains("time -1e308 s does not increase (previous 1e308 s)"),
            "{back}"
        );
    }

    /// `Samples::read_csv` of `path` in a thread, failing the test if it blocks.
    fn read_within_timeout(path: &Path) -> Result<Samples, TrajectoryError> {
        let p = path.to_path_buf();
        crate::input_file::test_files::within_timeout(move || Samples::read_csv(&p))
    }

    #[test]
    fn csv_from_devices_fifos_and_directories_is_refused_without_blocking() {
        use crate::input_file::test_files::{non_regular, temp_dir};
        let dir = temp_dir("csv-kinds");
        for (p, kind) in non_regular(&dir, "t.csv") {
            let msg = read_within_timeout(&p).unwrap_err().to_string();
            let name = p.display().to_string();
            assert!(
                msg.starts_with(&format!("{name}: is a {kind}")) && msg.contains("trajectory CSV"),
                "{msg}"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn csv_over_the_limit_is_refused_and_a_small_file_read() {
        use crate::input_file::test_files::{sparse, temp_dir};
        use crate::input_file::MAX_TRAJECTORY_BYTES;
        let dir = temp_dir("csv-size");
        let big = sparse(&dir, "big.csv", MAX_TRAJECTORY_BYTES + 1);
        let msg = read_within_timeout(&big).unwrap_err().to_string();
        let expected = format!(
            "{}: trajectory CSV is {} bytes, over the limit of {MAX_TRAJECTORY_BYTES} bytes",
            big.display(),
            MAX_TRAJECTORY_BYTES + 1
        );
        assert_eq!(msg, expected);
        let small = dir.join("small.csv");
        std::fs::write(&small, "t,x,y,z\n0,0,0,1\n1,1,0,1\n").unwrap();
        let s = read_within_timeout(&small).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(s.duration_s(), 1.0);
    }

    /// The file reader (`visit_csv`, line by line) and the text parser read the same rows
    /// with the same line numbers, across its buffer's edges (a CR LF pair split between two
    /// reads included); a line over `MAX_LINE_BYTES` is refused without being held whole, and
    /// a byte that is not UTF-8 is named by its offset in the file.
    #[test]
    fn the_file_reader_streams_what_the_text_parser_reads() {
        use crate::input_file::test_files::temp_dir;
        let dir = temp_dir("csv-stream");
        let f = dir.join("t.csv");
        let mut body = String::from("\u{feff}# c\r\nt,x,y,z,qw,qx,qy,qz\r\n");
        for i in 0..20_000 {
            let end = ["\n", "\r", "\r\n"][i % 3];
            body += &format!("{i}.5, 0.{i}, 1, 2, 1, 0, 0, 0 # {i}{end}\n");
        }
        for text in [body.as_str(), "0,0,0,1\r1,0,0,1\r\n\r2,0,0,1", "0,1,2,3"] {
            std::fs::write(&f, text).unwrap();
            let streamed = Samples::read_csv(&f).unwrap();
            assert_eq!(streamed, Samples::parse_csv(text, "x").unwrap());
            let shape = visit_csv(&f, |_| Ok::<(), TrajectoryError>(())).unwrap();
            assert_eq!(shape.rows, streamed.t_s.len());
        }
        for (text, want) in [
            (
                "0,0,0,1\r\n\r\n0,1,1,1\n",
                "t.csv:3: time 0 s does not increase",
            ),
            ("0,0,0,1\r\r1,\0,0,1", "t.csv:3: `1,\\0,0,1`"),
            ("# only\r", "no data rows"),
        ] {
            std::fs::write(&f, text).unwrap();
            let e = Samples::read_csv(&f).unwrap_err().to_string();
            assert!(e.contains(want), "{text:?}: {e}");
        }
        let long = format!("0,0,0,1\n{}\n", "9".repeat(3 * MAX_LINE_BYTES));
        std::fs::write(&f, long).unwrap();
        let e = Samples::read_csv(&f).unwrap_err().to_string();
        assert!(
            e.contains(":2: line longer than 1048576 bytes") && e.len() < 300,
            "{}",
            &e[..300.min(e.len())]
        );
        std::fs::write(&f, b"0,0,0,1\n1,0,0,\xff\n").unwrap();
        let e = Samples::read_csv(&f).unwrap_err().to_string();
        assert!(
            e.contains("not UTF-8 text (invalid byte at offset 14)"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn quaternion_columns_are_normalised_and_interpolated_on_the_shortest_arc() {
        let t = Samples::parse_csv(
            "t,x,y,z,qw,qx,qy,qz\n0,0,0,1,1,0,0,0\n1,0,0,1,0.7071,0,0,0.7071\n",
            "q.csv",
        )
        .unwrap();
        assert_eq!(t.orientation_wxyz.len(), 2);
        let q = t.orientation_wxyz[1];
        let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        // Normalised by the reader: 1 within a few roundings.
        assert!((n - 1.0).abs() < 4.0 * f64::EPSILON, "{n}");
        // Half-way between the identity and a quarter turn about z: an eighth turn
        // (closed form cos(π/8), sin(π/8)); slerp's rounding only.
        let h = t.orientation_at(0.5).unwrap();
        let c = std::f64::consts::FRAC_PI_8;
        let want = [c.cos(), 0.0, 0.0, c.sin()];
        for (a, b) in h.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{h:?}");
        }
        // No quaternion columns: no orientations, so the scene's is used.
        let p = Samples::parse_csv("0,0,0,1\n", "p.csv").unwrap();
        assert!(p.orientation_wxyz.is_empty() && p.orientation_at(0.0).is_none());
    }
}
