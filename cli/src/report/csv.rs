//! The one CSV writer of the commands, and the number formats of their columns.
//!
//! Every CSV a command writes is plain RFC 4180 (written by the `csv` crate): one header row
//! of column names, then data rows; no comment lines, so that `pandas.read_csv(PATH)` and
//! MATLAB `readtable(PATH)` read it with no options. A value the estimator did not give is
//! `NaN` (both read it as a missing number). Units are in the column names (`_m`, `_n`,
//! `_hz`, `_n_m` for N/m); cables are numbered from 1 (`tension1_n` is cable 1).
//!
//! What used to be a `#` comment line — command, scene, model, T_min, T_max, the command
//! line, and each column's unit and meaning — is in a JSON sidecar next to the file,
//! `PATH.json` (`map.csv` → `map.csv.json`), written by [`write_csv`].

use super::{with_ext, write_file, ReportError};
use crate::output_file::{OutputFile, ScratchFile};
use crate::scene::Scene;
use crate::study::points::{ee_mode_hz, PointResult};
use serde_json::{json, Map, Value};
use std::path::Path;

/// One column: its name (with the unit as a suffix), unit and meaning, for the sidecar.
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    /// Header name, e.g. `f1_hz`.
    pub name: String,
    /// Unit (`"Hz"`, `"N"`, `"m"`, `"N/m"`, `"1"` for a ratio, `""` for text).
    pub unit: &'static str,
    /// What the column holds.
    pub description: String,
}

impl Column {
    /// A column.
    pub fn new(
        name: impl Into<String>,
        unit: &'static str,
        description: impl Into<String>,
    ) -> Self {
        Column {
            name: name.into(),
            unit,
            description: description.into(),
        }
    }
}

/// A CSV document being written, with the metadata of its sidecar.
#[derive(Debug)]
pub struct Csv {
    columns: Vec<Column>,
    writer: csv::Writer<Vec<u8>>,
    rows: usize,
    meta: Map<String, Value>,
}

impl Csv {
    /// A document with the header row of `columns`; `meta` goes to the sidecar.
    pub fn new(columns: Vec<Column>, meta: Map<String, Value>) -> Csv {
        let mut writer = csv::Writer::from_writer(Vec::new());
        // Writing into a Vec<u8> cannot fail.
        let _ = writer.write_record(columns.iter().map(|c| c.name.as_str()));
        Csv {
            columns,
            writer,
            rows: 0,
            meta,
        }
    }
    /// Append one row: one field per column.
    pub fn row<I, S>(&mut self, fields: I)
    where
        I: IntoIterator<Item = S>,
        S: AsRef<[u8]>,
    {
        let _ = self.writer.write_record(fields);
        self.rows += 1;
    }
    /// The column names.
    pub fn names(&self) -> Vec<&str> {
        self.columns.iter().map(|c| c.name.as_str()).collect()
    }
    /// Data rows written so far.
    pub fn rows(&self) -> usize {
        self.rows
    }
    /// The CSV text and the sidecar JSON (with `command_line` and the row count).
    pub fn into_parts(mut self, command_line: &str) -> (String, String) {
        let _ = self.writer.flush();
        let text =
            String::from_utf8(self.writer.into_inner().unwrap_or_default()).unwrap_or_default();
        let side = sidecar_text(&self.columns, self.meta, self.rows, command_line);
        (text, side)
    }
}

/// The sidecar JSON of a CSV of `rows` data rows with `columns`, `meta` and `command_line`.
fn sidecar_text(
    columns: &[Column],
    meta: Map<String, Value>,
    rows: usize,
    command_line: &str,
) -> String {
    let mut m = Map::new();
    m.insert(
        "format".into(),
        json!("csv: one header row, no comment lines; NaN where no value"),
    );
    m.insert("command_line".into(), json!(command_line));
    m.extend(meta);
    m.insert("rows".into(), json!(rows));
    let cols: Vec<Value> = columns
        .iter()
        .map(|c| json!({"name": c.name, "unit": c.unit, "description": c.description}))
        .collect();
    m.insert("columns".into(), Value::Array(cols));
    serde_json::to_string_pretty(&Value::Object(m)).unwrap_or_default() + "\n"
}

/// A CSV written row by row to its file (the same bytes as [`Csv`] and [`write_csv`], in
/// bounded memory), with the rows of later *sections* spilled to scratch files beside it
/// until [`CsvFile::finish`] appends them in order: a document whose order (e.g. curve-major)
/// is not the order its rows are computed in. The file is an [`OutputFile`]: it replaces
/// its target only when finished, and an error, a panic or a signal leaves the target as it
/// was and no temporary or scratch file.
#[derive(Debug)]
pub struct CsvFile {
    path: std::path::PathBuf,
    columns: Vec<Column>,
    meta: Map<String, Value>,
    /// Section 0, the file itself.
    first: csv::Writer<OutputFile>,
    /// The spill files of sections 1, 2, ...
    spills: Vec<(ScratchFile, csv::Writer<std::io::BufWriter<std::fs::File>>)>,
    rows: usize,
}

impl CsvFile {
    /// Starts `path` (creating its parent directories) with the header row of `columns`,
    /// and `sections − 1` scratch files beside it; `meta` goes to the sidecar.
    pub fn create(
        path: &Path,
        columns: Vec<Column>,
        meta: Map<String, Value>,
        sections: usize,
    ) -> Result<CsvFile, ReportError> {
        super::create_parent(path)?;
        let mut first = csv::Writer::from_writer(OutputFile::create(path)?);
        let mut spills = Vec::new();
        for _ in 1..sections.max(1) {
            let scratch = ScratchFile::create_beside(path)?;
            let f = scratch.file().try_clone().map_err(super::io_err(path))?;
            spills.push((
                scratch,
                csv::Writer::from_writer(std::io::BufWriter::new(f)),
            ));
        }
        first
            .write_record(columns.iter().map(|c| c.name.as_str()))
            .map_err(|e| csv_err(path, e))?;
        Ok(CsvFile {
            path: path.to_path_buf(),
            columns,
            meta,
            first,
            spills,
            rows: 0,
        })
    }

    /// Appends one row (one field per column) to section `k`.
    pub fn row<I, S>(&mut self, k: usize, fields: I) -> Result<(), ReportError>
    where
        I: IntoIterator<Item = S>,
        S: AsRef<[u8]>,
    {
        let w = match k {
            0 => {
                self.first
                    .write_record(fields)
                    .map_err(|e| csv_err(&self.path, e))?;
                self.rows += 1;
                return Ok(());
            }
            _ => match self.spills.get_mut(k - 1) {
                Some((_, w)) => w,
                None => return Ok(()),
            },
        };
        w.write_record(fields).map_err(|e| csv_err(&self.path, e))?;
        self.rows += 1;
        Ok(())
    }

    /// Appends the sections to the file in order, puts it in place (the scratch files
    /// removed) and writes the sidecar (with `command_line` and the row count).
    pub fn finish(self, command_line: &str) -> Result<(), ReportError> {
        let CsvFile {
            path,
            columns,
            meta,
            first,
            spills,
            rows,
        } = self;
        let mut out = first
            .into_inner()
            .map_err(|e| super::io_err(&path)(e.into_error()))?;
        for (scratch, w) in spills {
            let mut f = w
                .into_inner()
                .map_err(|e| super::io_err(&path)(e.into_error()))?
                .into_inner()
                .map_err(|e| super::io_err(&path)(e.into_error()))?;
            std::io::Seek::rewind(&mut f).map_err(super::io_err(&path))?;
            std::io::copy(&mut f, &mut out).map_err(super::io_err(&path))?;
            drop(scratch);
        }
        out.commit()?;
        let side = sidecar_text(&columns, meta, rows, command_line);
        write_file(&sidecar_path(&path), &side)
    }
}

/// A `csv` crate error as an I/O error of `path`.
fn csv_err(path: &Path, e: csv::Error) -> ReportError {
    ReportError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(e.to_string()),
    }
}

/// Write `csv` to `path` and its metadata to `path.json` (see the module doc).
pub fn write_csv(path: &Path, csv: Csv, command_line: &str) -> Result<(), ReportError> {
    let (text, side) = csv.into_parts(command_line);
    write_file(path, &text)?;
    write_file(&sidecar_path(path), &side)
}

/// The sidecar of a CSV: `PATH.json`.
pub fn sidecar_path(csv_path: &Path) -> std::path::PathBuf {
    with_ext(csv_path, "json")
}

/// The command line of this process, for a sidecar: the program as `cablevib`, the
/// arguments shell-quoted where needed.
pub fn process_command_line() -> String {
    let mut parts = vec!["cablevib".to_string()];
    parts.extend(std::env::args().skip(1).map(|a| shell_quote(&a)));
    parts.join(" ")
}

/// `a` as one shell word: unchanged when it is plain, else in single quotes.
fn shell_quote(a: &str) -> String {
    let plain = !a.is_empty()
        && a.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.,:=/+@%".contains(c));
    if plain {
        a.to_string()
    } else {
        format!("'{}'", a.replace('\'', r"'\''"))
    }
}

/// The sidecar fields of a command on scene `s`: command, scene, model, T_min, T_max.
pub fn scene_meta(command: &str, s: &Scene) -> Map<String, Value> {
    let mut m = Map::new();
    m.insert("command".into(), json!(command));
    m.insert("scene".into(), json!(s.name));
    m.insert(
        "model".into(),
        json!({
            "element": s.model.element.as_str(),
            "elements_per_cable": s.model.elements_per_cable,
        }),
    );
    m.insert("t_min_n".into(), json!(s.t_min_n));
    if s.has_per_cable_bounds() {
        let lo: Vec<f64> = (0..s.n_cables()).map(|i| s.cable_t_min_n(i)).collect();
        let hi: Vec<f64> = (0..s.n_cables()).map(|i| s.cable_t_max_n(i)).collect();
        m.insert("cable_t_min_n".into(), json!(lo));
        m.insert("cable_t_max_n".into(), json!(hi));
    }
    m.insert("t_max_n".into(), json!(s.t_max_n));
    m.insert("cables".into(), json!(s.n_cables()));
    m.insert(
        "cable_numbering".into(),
        json!("from 1: tension1_n is cable 1 of the scene"),
    );
    m
}

/// A finite value in scientific notation with 8 decimals, else `NaN`.
pub fn num(x: f64) -> String {
    num_p(x, 8)
}

/// A finite value in scientific notation with `digits` decimals, else `NaN`.
pub fn num_p(x: f64, digits: usize) -> String {
    if x.is_finite() {
        format!("{x:.digits$e}")
    } else {
        "NaN".into()
    }
}

/// Columns of [`PointResult`] rows for a scene with `n` cables and `k` modes:
/// position, the orientation (`qw`, `qx`, `qy`, `qz`, when `orientation`: rigid
/// end-effectors), T_min, status, f1, the end-effector mode, participations, tensions, then
/// f2 .. fK and the smallest stiffness.
pub fn point_columns(n: usize, k: usize, orientation: bool) -> Vec<Column> {
    let mut c = vec![
        Column::new("x_m", "m", "end-effector position x"),
        Column::new("y_m", "m", "end-effector position y"),
        Column::new("z_m", "m", "end-effector position z"),
    ];
    if orientation {
        for q in ["qw", "qx", "qy", "qz"] {
            c.push(Column::new(
                q,
                "1",
                format!("end-effector orientation, unit quaternion w, x, y, z: {q}"),
            ));
        }
    }
    c.extend([
        Column::new("t_min_n", "N", "lower tension bound of every cable"),
        Column::new("status", "", "estimator status (ok, tension_infeasible, ...); numbers are NaN unless ok"),
        Column::new("f1_hz", "Hz", "first natural frequency (mode 1)"),
        Column::new("ee_mode_hz", "Hz", "end-effector mode: lowest mode with end-effector participation at or above the scene's threshold"),
        Column::new("f1_ee_participation", "1", "end-effector participation of mode 1"),
        Column::new("ee_mode_participation", "1", "end-effector participation of the end-effector mode"),
    ]);
    for i in 1..=n {
        c.push(Column::new(
            format!("tension{i}_n"),
            "N",
            format!("tension of cable {i}"),
        ));
    }
    for j in 2..=k {
        c.push(Column::new(
            format!("f{j}_hz"),
            "Hz",
            format!("natural frequency of mode {j}"),
        ));
    }
    c.push(Column::new(
        "stiffness_min_n_m",
        "N/m",
        "smallest principal value of the static end-effector stiffness (translational block)",
    ));
    c
}

/// The fields of one [`PointResult`] row (see [`point_columns`], with the same
/// `orientation`).
pub fn point_fields(r: &PointResult, orientation: bool) -> Vec<String> {
    let e = &r.estimate;
    let mut s = vec![
        r.position_m.x.to_string(),
        r.position_m.y.to_string(),
        r.position_m.z.to_string(),
    ];
    if orientation {
        s.extend(r.orientation_wxyz.iter().map(|q| q.to_string()));
    }
    s.extend([
        r.t_min_n.to_string(),
        e.status.as_str().to_string(),
        num(e.f1_hz),
        num(ee_mode_hz(e)),
        num_p(e.f1_ee_participation, 4),
        num_p(e.ee_mode.map_or(f64::NAN, |m| m.participation), 4),
    ]);
    s.extend(e.tensions().iter().map(|t| num_p(*t, 6)));
    s.extend((2..=r.n_modes).map(|j| num(r.mode_hz(j))));
    s.push(num_p(r.stiffness_min_n_m, 6));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_with_commas_are_quoted_and_the_sidecar_names_every_column() {
        let cols = vec![Column::new("a_m", "m", "a"), Column::new("label", "", "b")];
        let mut c = Csv::new(cols, Map::new());
        c.row(["1", "plain"]);
        c.row(["NaN", "x, \"y\""]);
        let (text, side) = c.into_parts("cablevib test");
        assert_eq!(text, "a_m,label\n1,plain\nNaN,\"x, \"\"y\"\"\"\n");
        let v: Value = serde_json::from_str(&side).unwrap();
        assert_eq!(v["rows"], 2);
        assert_eq!(v["command_line"], "cablevib test");
        assert_eq!(v["columns"][1]["name"], "label");
        assert_eq!(
            sidecar_path(Path::new("d/map.csv")),
            Path::new("d/map.csv.json")
        );
    }

    #[test]
    fn shell_words_are_quoted_only_when_needed() {
        assert_eq!(shell_quote("--x=-1,1"), "--x=-1,1");
        assert_eq!(shell_quote("paper Table 4"), "'paper Table 4'");
        assert_eq!(shell_quote("it's"), r"'it'\''s'");
        assert_eq!(shell_quote(""), "''");
    }
}
