//! Measured data: the modes CSV (one row per measured mode, `identify`'s output accepted as
//! it is) and the tensions CSV, parsed and checked row by row.
//!
//! **Modes.** Columns by name, in any order, after optional `#` comment lines: `x_m, y_m,
//! z_m, frequency_hz` (required); `qw, qx, qy, qz` (all four or none; a rigid platform's
//! orientation, else the scene's), `t_min_n` (the lower tension bound the robot held, else
//! the scene's), `sigma_hz` (the frequency's standard deviation; else `frequency_std_hz`,
//! else `sigma_rel` × frequency), `damping_ratio` and its `damping_ratio_std` (else
//! `damping_sigma_rel` × ζ, at least 1e-4), `mode` (`ee` or `eeK`: the K-th end-effector
//! mode at the pose in ascending frequency, `ee` = `ee1`; or the 1-based order of the mode
//! at the pose; empty: paired by frequency), `model_mode` (a pairing hint, reported, never
//! taken as the pairing) and `status` (rows whose status is not `ok` are left out and
//! listed, except `identify`'s [`PAIRING_STATUSES`]: those say how the row paired with the
//! nominal model, a hint like `model_mode`, and the row is kept and counted). Every other
//! column is listed once as not used.
//!
//! **Tensions.** `x_m, y_m, z_m, cable, tension_n` (cable 1-based), optional `sigma_n` (else
//! `tension_sigma_rel` × tension), `qw..qz`, `t_min_n`.
//!
//! A missing column, a field that is not a finite number where one is needed, a frequency
//! or σ that is not positive, a row with the wrong number of fields, two rows that are the
//! same measurement, and more than [`MAX_ROWS`] rows are errors naming the file and the
//! line. Nothing is dropped without being listed.

use super::CalibrationError;
use crate::input_file::read_text;
use nalgebra::Vector3;
use std::path::Path;

/// Largest data file read, bytes (32 MiB: ~200 000 rows of `identify`'s 19 columns).
pub const MAX_DATA_BYTES: u64 = 32 * 1024 * 1024;
/// Largest number of data rows per file: a fit over more is not what this is for.
pub const MAX_ROWS: usize = 100_000;
/// Smallest σ of a damping ratio derived from `damping_sigma_rel`.
pub const MIN_DAMPING_SIGMA: f64 = 1e-4;

/// How a measured mode is to be paired with a model mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ModeLabel {
    /// No `mode` given: by frequency among the model's end-effector modes.
    Unlabelled,
    /// The model's mode of this 1-based order at the pose.
    Order(usize),
    /// The model's K-th end-effector mode (participation ≥ the scene's threshold), 1-based.
    Ee(usize),
}

impl std::fmt::Display for ModeLabel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ModeLabel::Unlabelled => write!(f, "-"),
            ModeLabel::Order(k) => write!(f, "{k}"),
            ModeLabel::Ee(k) => write!(f, "ee{k}"),
        }
    }
}

/// Where a row's σ came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SigmaSource {
    /// The `sigma_hz` (or `sigma_n`) column.
    Column,
    /// `identify`'s `frequency_std_hz` column.
    IdentifyStd,
    /// The relative default (`SigmaDefaults::frequency_rel`).
    Relative,
}

/// The pose of a measurement: reference-point position (m), orientation (None: the
/// scene's) and the lower tension bound (None: the scene's), N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasuredPose {
    /// Position, m.
    pub position_m: Vector3<f64>,
    /// Unit quaternion [w, x, y, z], when given.
    pub orientation_wxyz: Option<[f64; 4]>,
    /// T_min the robot held (every cable), N, when given.
    pub t_min_n: Option<f64>,
}

impl MeasuredPose {
    fn key(&self) -> [u64; 8] {
        let q = self.orientation_wxyz.unwrap_or([f64::NAN; 4]);
        let p = self.position_m;
        [
            p.x.to_bits(),
            p.y.to_bits(),
            p.z.to_bits(),
            q[0].to_bits(),
            q[1].to_bits(),
            q[2].to_bits(),
            q[3].to_bits(),
            self.t_min_n.unwrap_or(f64::NAN).to_bits(),
        ]
    }
}

/// One measured mode.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeRow {
    /// Line in the file, 1-based.
    pub line: usize,
    /// Where it was measured.
    pub pose: MeasuredPose,
    /// Natural frequency, Hz.
    pub frequency_hz: f64,
    /// Its standard deviation, Hz.
    pub sigma_hz: f64,
    /// Where σ came from.
    pub sigma_source: SigmaSource,
    /// Damping ratio ζ and its σ, when measured.
    pub damping: Option<(f64, f64)>,
    /// How to pair it.
    pub label: ModeLabel,
    /// `identify`'s `model_mode` hint (1-based order), shown in reports only.
    pub model_mode_hint: Option<usize>,
}

/// One measured cable tension.
#[derive(Debug, Clone, PartialEq)]
pub struct TensionRow {
    /// Line in the file, 1-based.
    pub line: usize,
    /// Where it was measured.
    pub pose: MeasuredPose,
    /// Cable index, 0-based (the file's `cable` is 1-based).
    pub cable: usize,
    /// Tension, N.
    pub tension_n: f64,
    /// Its standard deviation, N.
    pub sigma_n: f64,
}

/// `identify`'s statuses of a row it could not pair with the nominal model (`unpaired`: no
/// model mode near it; `ambiguous`: two about as near). They are about the model the
/// calibration corrects (identify pairs at the uncalibrated model, which can be 20 % off),
/// not about the measurement: such rows are kept, paired by the calibration itself and
/// counted in [`Measurements::pairing_hint_lines`].
pub const PAIRING_STATUSES: [&str; 2] = ["unpaired", "ambiguous"];

/// A row left out of the fit, with the reason.
#[derive(Debug, Clone, PartialEq)]
pub struct LeftOut {
    /// Line in the file, 1-based.
    pub line: usize,
    /// Why, e.g. `status unstable`.
    pub reason: String,
}

/// Measured data for a calibration.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Measurements {
    /// Name of the modes file (in messages).
    pub origin: String,
    /// The measured modes used.
    pub modes: Vec<ModeRow>,
    /// Rows of the modes file left out (status not ok).
    pub left_out: Vec<LeftOut>,
    /// Lines of rows kept whose status was one of [`PAIRING_STATUSES`].
    pub pairing_hint_lines: Vec<usize>,
    /// Columns of the modes file not used.
    pub unused_columns: Vec<String>,
    /// Name of the tensions file, when given.
    pub tension_origin: Option<String>,
    /// The measured tensions.
    pub tensions: Vec<TensionRow>,
    /// Columns of the tensions file not used.
    pub tension_unused_columns: Vec<String>,
}

/// Defaults of the σ a row does not give (finite, > 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SigmaDefaults {
    /// σ of a frequency relative to it (default 0.005).
    pub frequency_rel: f64,
    /// σ of a damping ratio relative to it (default 0.2: damping is known far less well).
    pub damping_rel: f64,
    /// σ of a tension relative to it (default 0.02).
    pub tension_rel: f64,
}

impl Default for SigmaDefaults {
    fn default() -> Self {
        SigmaDefaults {
            frequency_rel: 0.005,
            damping_rel: 0.2,
            tension_rel: 0.02,
        }
    }
}

impl SigmaDefaults {
    /// Each default finite and > 0, else an error naming it.
    pub fn check(&self) -> Result<(), CalibrationError> {
        for (name, v) in [
            ("sigma_rel", self.frequency_rel),
            ("damping_sigma_rel", self.damping_rel),
            ("tension_sigma_rel", self.tension_rel),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(CalibrationError::Problem(format!(
                    "{name} {v}: must be finite and > 0"
                )));
            }
        }
        Ok(())
    }
}

/// A CSV table: header names and the data rows with their line numbers.
struct Table<'a> {
    origin: &'a str,
    names: Vec<&'a str>,
    rows: Vec<(usize, Vec<&'a str>)>,
}

impl<'a> Table<'a> {
    fn parse(text: &'a str, origin: &'a str) -> Result<Table<'a>, CalibrationError> {
        let file = |m: String| CalibrationError::File {
            file: origin.to_string(),
            message: m,
        };
        let mut names: Option<Vec<&str>> = None;
        let mut rows = Vec::new();
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        for (i, line) in text.split('\n').enumerate() {
            let number = i + 1;
            let line = line.strip_suffix('\r').unwrap_or(line);
            if line.trim().is_empty() || line.trim_start().starts_with('#') {
                continue;
            }
            if line.contains('"') {
                return Err(CalibrationError::Row {
                    file: origin.to_string(),
                    line: number,
                    message: "quoted fields are not read: plain comma-separated values only".into(),
                });
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            match &names {
                None => {
                    for (k, n) in fields.iter().enumerate() {
                        if n.is_empty() {
                            return Err(file(format!("header column {} has no name", k + 1)));
                        }
                        if fields[..k].contains(n) {
                            return Err(file(format!("header names column `{n}` twice")));
                        }
                    }
                    names = Some(fields);
                }
                Some(h) => {
                    if fields.len() != h.len() {
                        return Err(CalibrationError::Row {
                            file: origin.to_string(),
                            line: number,
                            message: format!("{} fields, the header has {}", fields.len(), h.len()),
                        });
                    }
                    if rows.len() == MAX_ROWS {
                        return Err(file(format!("more than {MAX_ROWS} data rows")));
                    }
                    rows.push((number, fields));
                }
            }
        }
        let names = names.ok_or_else(|| file("no header line (and no data)".into()))?;
        Ok(Table {
            origin,
            names,
            rows,
        })
    }

    fn column(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| *n == name)
    }

    fn required(&self, name: &str) -> Result<usize, CalibrationError> {
        self.column(name).ok_or_else(|| CalibrationError::File {
            file: self.origin.to_string(),
            message: format!(
                "no `{name}` column (header: {})",
                crate::input_file::message_excerpt(&self.names.join(","))
            ),
        })
    }

    fn row_err(&self, line: usize, message: String) -> CalibrationError {
        CalibrationError::Row {
            file: self.origin.to_string(),
            line,
            message,
        }
    }

    /// The number in column `c` of a row: None when empty, an error when not a finite number.
    fn number(&self, line: usize, f: &[&str], c: usize) -> Result<Option<f64>, CalibrationError> {
        let s = f[c];
        if s.is_empty() {
            return Ok(None);
        }
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            _ => Err(self.row_err(
                line,
                format!(
                    "{} = `{}` is not a finite number",
                    self.names[c],
                    crate::input_file::message_excerpt(s)
                ),
            )),
        }
    }

    fn needed(&self, line: usize, f: &[&str], c: usize) -> Result<f64, CalibrationError> {
        self.number(line, f, c)?
            .ok_or_else(|| self.row_err(line, format!("{} is empty", self.names[c])))
    }

    /// The pose columns' indices.
    fn pose_columns(&self) -> Result<PoseColumns, CalibrationError> {
        let xyz = [
            self.required("x_m")?,
            self.required("y_m")?,
            self.required("z_m")?,
        ];
        let q: Vec<Option<usize>> = ["qw", "qx", "qy", "qz"]
            .iter()
            .map(|n| self.column(n))
            .collect();
        let quaternion = match q.iter().filter(|c| c.is_some()).count() {
            0 => None,
            4 => Some([q[0].unwrap(), q[1].unwrap(), q[2].unwrap(), q[3].unwrap()]),
            _ => {
                return Err(CalibrationError::File {
                    file: self.origin.to_string(),
                    message: "give all four quaternion columns qw, qx, qy, qz or none".into(),
                })
            }
        };
        Ok(PoseColumns {
            xyz,
            quaternion,
            t_min: self.column("t_min_n"),
        })
    }

    fn pose(
        &self,
        line: usize,
        f: &[&str],
        c: &PoseColumns,
    ) -> Result<MeasuredPose, CalibrationError> {
        let mut p = [0.0; 3];
        for (k, &col) in c.xyz.iter().enumerate() {
            p[k] = self.number(line, f, col)?.ok_or_else(|| {
                self.row_err(
                    line,
                    format!(
                        "{} is empty: every measurement needs the pose it was taken at",
                        self.names[col]
                    ),
                )
            })?;
        }
        let orientation_wxyz = match c.quaternion {
            None => None,
            Some(cols) => {
                let v: Vec<Option<f64>> = cols
                    .iter()
                    .map(|&k| self.number(line, f, k))
                    .collect::<Result<_, _>>()?;
                match v.iter().filter(|x| x.is_some()).count() {
                    0 => None,
                    4 => {
                        let q = [v[0].unwrap(), v[1].unwrap(), v[2].unwrap(), v[3].unwrap()];
                        Some(
                            crate::kinematics::unit_quaternion(q)
                                .map_err(|e| self.row_err(line, format!("orientation: {e}")))?,
                        )
                    }
                    _ => {
                        return Err(
                            self.row_err(line, "give all four of qw, qx, qy, qz or none".into())
                        )
                    }
                }
            }
        };
        let t_min_n = match c.t_min {
            None => None,
            Some(k) => match self.number(line, f, k)? {
                Some(t) if t > 0.0 => Some(t),
                Some(t) => return Err(self.row_err(line, format!("t_min_n = {t} must be > 0"))),
                None => None,
            },
        };
        Ok(MeasuredPose {
            position_m: Vector3::new(p[0], p[1], p[2]),
            orientation_wxyz,
            t_min_n,
        })
    }

    fn unused(&self, used: &[&str]) -> Vec<String> {
        self.names
            .iter()
            .filter(|n| !used.contains(n))
            .map(|n| n.to_string())
            .collect()
    }
}

struct PoseColumns {
    xyz: [usize; 3],
    quaternion: Option<[usize; 4]>,
    t_min: Option<usize>,
}

/// The pose columns every file may have (used when present).
const POSE_NAMES: [&str; 8] = ["x_m", "y_m", "z_m", "qw", "qx", "qy", "qz", "t_min_n"];

fn parse_label(s: &str) -> Option<ModeLabel> {
    if s.is_empty() {
        return Some(ModeLabel::Unlabelled);
    }
    if s == "ee" {
        return Some(ModeLabel::Ee(1));
    }
    if let Some(k) = s.strip_prefix("ee") {
        return k
            .parse::<usize>()
            .ok()
            .filter(|&k| k >= 1)
            .map(ModeLabel::Ee);
    }
    s.parse::<usize>()
        .ok()
        .filter(|&k| k >= 1)
        .map(ModeLabel::Order)
}

/// The text of the data file `path` (a regular file of at most [`MAX_DATA_BYTES`]; `what`
/// names it in messages) and its name.
fn read(path: &Path, what: &'static str) -> Result<(String, String), CalibrationError> {
    let origin = path.display().to_string();
    let text = read_text(path, what, MAX_DATA_BYTES).map_err(|e| CalibrationError::File {
        file: origin.clone(),
        message: strip_file(&e.to_string(), &origin),
    })?;
    Ok((text, origin))
}

/// Reads the modes CSV at `path`.
pub fn read_modes(path: &Path, sigma: &SigmaDefaults) -> Result<Measurements, CalibrationError> {
    let (text, origin) = read(path, "measured-modes CSV")?;
    parse_modes(&text, &origin, sigma)
}

/// Reads the tensions CSV at `path` into `m` (cable numbers checked against `n_cables`).
pub fn read_tensions(
    path: &Path,
    n_cables: usize,
    sigma: &SigmaDefaults,
    m: &mut Measurements,
) -> Result<(), CalibrationError> {
    let (text, origin) = read(path, "measured-tensions CSV")?;
    parse_tensions(&text, &origin, n_cables, sigma, m)
}

/// An input-file error's message without its leading `file: ` (the error adds it again).
fn strip_file(message: &str, file: &str) -> String {
    message
        .strip_prefix(&format!("{file}: "))
        .unwrap_or(message)
        .to_string()
}

/// Parses the modes CSV `text` (`origin` names it in messages).
pub fn parse_modes(
    text: &str,
    origin: &str,
    sigma: &SigmaDefaults,
) -> Result<Measurements, CalibrationError> {
    sigma.check()?;
    let t = Table::parse(text, origin)?;
    let pc = t.pose_columns()?;
    let f_col = t.required("frequency_hz")?;
    let sigma_col = t.column("sigma_hz");
    let std_col = t.column("frequency_std_hz");
    let zeta_col = t.column("damping_ratio");
    let zeta_std_col = t.column("damping_ratio_std");
    let mode_col = t.column("mode");
    let hint_col = t.column("model_mode");
    let status_col = t.column("status");
    let mut used: Vec<&str> = POSE_NAMES.to_vec();
    used.extend([
        "frequency_hz",
        "mode",
        "model_mode",
        "status",
        "damping_ratio",
    ]);
    used.push(if sigma_col.is_some() {
        "sigma_hz"
    } else {
        "frequency_std_hz"
    });
    if zeta_col.is_some() {
        used.push("damping_ratio_std");
    }
    let mut m = Measurements {
        origin: origin.to_string(),
        unused_columns: t.unused(&used),
        ..Measurements::default()
    };
    for (line, f) in &t.rows {
        let line = *line;
        if let Some(c) = status_col {
            if PAIRING_STATUSES.contains(&f[c]) {
                m.pairing_hint_lines.push(line);
            } else if f[c] != "ok" {
                let reason = if f[c].is_empty() {
                    "status is empty".to_string()
                } else {
                    format!("status {}", crate::input_file::message_excerpt(f[c]))
                };
                m.left_out.push(LeftOut { line, reason });
                continue;
            }
        }
        let pose = t.pose(line, f, &pc)?;
        let frequency_hz = t.needed(line, f, f_col)?;
        if !(frequency_hz > 0.0) {
            return Err(t.row_err(line, format!("frequency_hz = {frequency_hz} must be > 0")));
        }
        let given = |c: Option<usize>| -> Result<Option<f64>, CalibrationError> {
            match c {
                Some(c) => t.number(line, f, c),
                None => Ok(None),
            }
        };
        let (sigma_hz, sigma_source) = if let Some(s) = given(sigma_col)? {
            (s, SigmaSource::Column)
        } else if let Some(s) = given(if sigma_col.is_none() { std_col } else { None })? {
            (s, SigmaSource::IdentifyStd)
        } else {
            (sigma.frequency_rel * frequency_hz, SigmaSource::Relative)
        };
        if !(sigma_hz > 0.0) {
            return Err(t.row_err(
                line,
                format!("σ of the frequency {sigma_hz} Hz must be > 0"),
            ));
        }
        let damping = match given(zeta_col)? {
            None => None,
            Some(z) if (0.0..1.0).contains(&z) => {
                let s = match given(zeta_std_col)? {
                    Some(s) if s > 0.0 => s,
                    Some(s) => {
                        return Err(t.row_err(line, format!("damping_ratio_std = {s} must be > 0")))
                    }
                    None => (sigma.damping_rel * z).max(MIN_DAMPING_SIGMA),
                };
                Some((z, s))
            }
            Some(z) => {
                return Err(t.row_err(line, format!("damping_ratio = {z} must be in [0, 1)")))
            }
        };
        let label = match mode_col {
            None => ModeLabel::Unlabelled,
            Some(c) => parse_label(f[c]).ok_or_else(|| {
                t.row_err(
                    line,
                    format!(
                        "mode = `{}`: give ee, eeK or a mode order 1, 2, ... (or leave it empty)",
                        crate::input_file::message_excerpt(f[c])
                    ),
                )
            })?,
        };
        let model_mode_hint = match hint_col {
            Some(c) => t.number(line, f, c)?.map(|v| v as usize),
            None => None,
        };
        m.modes.push(ModeRow {
            line,
            pose,
            frequency_hz,
            sigma_hz,
            sigma_source,
            damping,
            label,
            model_mode_hint,
        });
    }
    check_mode_duplicates(&m.modes, origin)?;
    Ok(m)
}

/// Two rows at one pose that are the same measurement (same frequency, or the same mode
/// label) are refused, naming both lines.
fn check_mode_duplicates(rows: &[ModeRow], origin: &str) -> Result<(), CalibrationError> {
    let mut seen: std::collections::HashMap<([u64; 8], u64), usize> = Default::default();
    let mut labels: std::collections::HashMap<([u64; 8], ModeLabel), usize> = Default::default();
    for r in rows {
        let k = r.pose.key();
        if let Some(first) = seen.insert((k, r.frequency_hz.to_bits()), r.line) {
            return Err(CalibrationError::Row {
                file: origin.to_string(),
                line: r.line,
                message: format!(
                    "duplicate of line {first} (same pose and frequency {} Hz)",
                    r.frequency_hz
                ),
            });
        }
        if r.label != ModeLabel::Unlabelled {
            if let Some(first) = labels.insert((k, r.label), r.line) {
                return Err(CalibrationError::Row {
                    file: origin.to_string(),
                    line: r.line,
                    message: format!("line {first} already gives mode {} at this pose", r.label),
                });
            }
        }
    }
    Ok(())
}

/// Parses the tensions CSV `text` into `m`.
pub fn parse_tensions(
    text: &str,
    origin: &str,
    n_cables: usize,
    sigma: &SigmaDefaults,
    m: &mut Measurements,
) -> Result<(), CalibrationError> {
    sigma.check()?;
    let t = Table::parse(text, origin)?;
    let pc = t.pose_columns()?;
    let cable_col = t.required("cable")?;
    let t_col = t.required("tension_n")?;
    let s_col = t.column("sigma_n");
    let mut used: Vec<&str> = POSE_NAMES.to_vec();
    used.extend(["cable", "tension_n", "sigma_n"]);
    let mut rows = Vec::with_capacity(t.rows.len());
    let mut seen: std::collections::HashMap<([u64; 8], usize), usize> = Default::default();
    for (line, f) in &t.rows {
        let line = *line;
        let pose = t.pose(line, f, &pc)?;
        let cable = match f[cable_col].parse::<usize>() {
            Ok(c) if (1..=n_cables).contains(&c) => c - 1,
            _ => {
                return Err(t.row_err(
                    line,
                    format!(
                        "cable = `{}` is not a cable number of the scene (1..={n_cables})",
                        crate::input_file::message_excerpt(f[cable_col])
                    ),
                ))
            }
        };
        let tension_n = t.needed(line, f, t_col)?;
        if !(tension_n > 0.0) {
            return Err(t.row_err(line, format!("tension_n = {tension_n} must be > 0")));
        }
        let sigma_n = match s_col {
            Some(c) => t.number(line, f, c)?,
            None => None,
        }
        .unwrap_or(sigma.tension_rel * tension_n);
        if !(sigma_n > 0.0) {
            return Err(t.row_err(line, format!("sigma_n = {sigma_n} must be > 0")));
        }
        if let Some(first) = seen.insert((pose.key(), cable), line) {
            return Err(t.row_err(
                line,
                format!(
                    "line {first} already gives cable {}'s tension at this pose",
                    cable + 1
                ),
            ));
        }
        rows.push(TensionRow {
            line,
            pose,
            cable,
            tension_n,
            sigma_n,
        });
    }
    m.tension_origin = Some(origin.to_string());
    m.tensions = rows;
    m.tension_unused_columns = t.unused(&used);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const IDENTIFY: &str = "# identify provenance\n\
window,t_start_s,t_end_s,x_m,y_m,z_m,qw,qx,qy,qz,identified_mode,frequency_hz,frequency_std_hz,damping_ratio,damping_ratio_std,model_frequency_hz,model_mode,model_ee_participation,status\n\
0,0,10,0.1,0,1.2,,,,,1,30.5,0.05,0.01,0.002,31.0,25,0.97,ok\n\
0,0,10,0.1,0,1.2,,,,,2,33.0,,0.012,,33.1,26,0.95,ok\n\
1,10,20,0.2,0,1.2,,,,,1,29.0,0.05,,,,,,unstable\n\
1,10,20,0.2,0,1.2,,,,,2,31.0,0.05,,,30.0,3,0.9,ambiguous\n\
1,10,20,0.2,0,1.2,,,,,3,34.0,0.05,,,,,,unpaired\n";

    #[test]
    fn identify_output_is_read_as_it_is() {
        let m = parse_modes(IDENTIFY, "id.csv", &SigmaDefaults::default()).unwrap();
        // identify's pairing statuses are hints about the nominal model: kept, counted.
        assert_eq!(m.modes.len(), 4);
        assert_eq!(m.pairing_hint_lines, [6, 7]);
        assert_eq!(m.modes[0].sigma_source, SigmaSource::IdentifyStd);
        assert_eq!(m.modes[0].sigma_hz, 0.05);
        assert_eq!(m.modes[1].sigma_source, SigmaSource::Relative);
        assert_eq!(m.modes[1].damping, Some((0.012, 0.012 * 0.2)));
        assert_eq!(m.modes[0].model_mode_hint, Some(25));
        assert_eq!(m.modes[0].label, ModeLabel::Unlabelled);
        assert_eq!(m.left_out.len(), 1);
        assert_eq!(m.left_out[0].line, 5);
        assert_eq!(m.left_out[0].reason, "status unstable");
        assert_eq!(
            m.unused_columns,
            [
                "window",
                "t_start_s",
                "t_end_s",
                "identified_mode",
                "model_frequency_hz",
                "model_ee_participation"
            ]
        );
    }

    #[test]
    fn bad_rows_are_one_line_errors_naming_the_line() {
        let sd = SigmaDefaults::default();
        for (text, needle) in [
            (
                "x_m,y_m,z_m,frequency_hz\n0,0,1,NaN\n",
                "line 2: frequency_hz = `NaN` is not a finite number",
            ),
            (
                "x_m,y_m,z_m,frequency_hz\n0,0,1,30\n0,0,1,30\n",
                "line 3: duplicate of line 2",
            ),
            (
                "x_m,y_m,z_m,frequency_hz,mode\n0,0,1,30,ee\n0,0,1,31,ee1\n",
                "line 3: line 2 already gives mode ee1",
            ),
            ("x_m,y_m,frequency_hz\n0,0,30\n", "no `z_m` column"),
            (
                "x_m,y_m,z_m,frequency_hz\n0,0,1\n",
                "line 2: 3 fields, the header has 4",
            ),
            (
                "x_m,y_m,z_m,frequency_hz\n0,,1,30\n",
                "line 2: y_m is empty",
            ),
            (
                "x_m,y_m,z_m,frequency_hz,mode\n0,0,1,30,first\n",
                "line 2: mode = `first`",
            ),
            (
                "x_m,y_m,z_m,frequency_hz\n0,0,1,-3\n",
                "line 2: frequency_hz = -3 must be > 0",
            ),
        ] {
            let e = parse_modes(text, "d.csv", &sd).unwrap_err().to_string();
            assert!(e.contains(needle) && e.starts_with("d.csv"), "{e}");
            assert!(!e.contains('\n'), "{e}");
        }
        let mut m = Measurements::default();
        let e = parse_tensions(
            "x_m,y_m,z_m,cable,tension_n\n0,0,1,9,100\n",
            "t.csv",
            8,
            &sd,
            &mut m,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("line 2: cable = `9`"), "{e}");
    }
}
