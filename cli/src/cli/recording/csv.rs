//! A CSV recording: a header row naming the columns, then one row per sample. `t` (or `t_s`)
//! is the time in s; `x_m, y_m, z_m` (and `qw, qx, qy, qz`), when present, are the
//! end-effector's pose; every other column is a vibration channel (all of them, or those
//! named by `--channels`). Lines starting with `#` are comments. Read line by line: memory
//! is one line of at most [`MAX_LINE_BYTES`].

use super::{CliError, Item, Layout, ReadOptions};
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// Longest line read, bytes.
pub const MAX_LINE_BYTES: u64 = 64 * 1024;
const POSE: [&str; 7] = ["x_m", "y_m", "z_m", "qw", "qx", "qy", "qz"];

/// Read the CSV recording `path` (module docs).
pub fn read(
    path: &Path,
    opts: &ReadOptions,
    sink: &mut dyn FnMut(Item<'_>) -> Result<(), CliError>,
) -> Result<(), CliError> {
    let shown = path.display().to_string();
    let f = crate::input_file::open_checked(path, "recording", u64::MAX)
        .map_err(|e| CliError::Usage(e.to_string()))?;
    if opts.topic.is_some() || opts.pose_topic.is_some() || opts.input_topic.is_some() {
        return Err(CliError::Usage(format!(
            "{shown}: a CSV recording has no topics (--topic, --pose-topic and --input-topic are for MCAP files)"
        )));
    }
    let mut r = BufReader::new(f);
    let mut line = String::new();
    let mut lineno = 0usize;
    let mut next = |line: &mut String, lineno: &mut usize| -> Result<bool, CliError> {
        loop {
            line.clear();
            let n = (&mut r)
                .take(MAX_LINE_BYTES + 1)
                .read_line(line)
                .map_err(|e| CliError::Usage(format!("{shown}: line {}: {e}", *lineno + 1)))?;
            if n == 0 {
                return Ok(false);
            }
            *lineno += 1;
            if n as u64 > MAX_LINE_BYTES {
                return Err(CliError::Usage(format!(
                    "{shown}: line {lineno}: longer than {MAX_LINE_BYTES} bytes"
                )));
            }
            let t = line.trim();
            if !t.is_empty() && !t.starts_with('#') {
                return Ok(true);
            }
        }
    };
    if !next(&mut line, &mut lineno)? {
        return Err(CliError::Usage(format!("{shown}: no header row")));
    }
    let names: Vec<String> = line
        .trim()
        .split(',')
        .map(|s| s.trim().trim_matches('"').to_string())
        .collect();
    let t_col = names
        .iter()
        .position(|n| n == "t" || n == "t_s")
        .ok_or_else(|| {
            CliError::Usage(format!(
                "{shown}: no time column `t` (s) in the header ({})",
                names.join(",")
            ))
        })?;
    let pose_cols: Vec<Option<usize>> = POSE
        .iter()
        .map(|p| names.iter().position(|n| n == p))
        .collect();
    let has_pos = pose_cols[..3].iter().all(|c| c.is_some());
    let has_quat = pose_cols[3..].iter().all(|c| c.is_some());
    let wanted: Vec<String> = if opts.channels.is_empty() {
        (0..names.len())
            .filter(|&i| i != t_col && !POSE.contains(&names[i].as_str()))
            .map(|i| names[i].clone())
            .collect()
    } else {
        opts.channels.clone()
    };
    let wanted = opts
        .with_inputs(wanted)
        .map_err(|e| CliError::Usage(format!("{shown}: {e}")))?;
    let chans: Vec<usize> = {
        wanted
            .iter()
            .map(|c| {
                names.iter().position(|n| n == c).ok_or_else(|| {
                    let opt = if opts.inputs.contains(c) {
                        "--input"
                    } else {
                        "--channels"
                    };
                    CliError::Usage(format!(
                        "{shown}: {opt} `{c}`: no such column (the header has {})",
                        names.join(",")
                    ))
                })
            })
            .collect::<Result<_, _>>()?
    };
    if chans.len() <= opts.inputs.len() {
        return Err(CliError::Usage(format!(
            "{shown}: no response channel (columns other than t, the pose and the --input ones)"
        )));
    }
    sink(Item::Layout(&Layout {
        channels: chans.iter().map(|&i| names[i].clone()).collect(),
        source: format!("CSV {shown}"),
        inputs: opts.inputs.len(),
        separate_inputs: false,
    }))?;
    let mut fields: Vec<f64> = vec![f64::NAN; names.len()];
    let mut values = vec![0.0; chans.len()];
    while next(&mut line, &mut lineno)? {
        let mut k = 0;
        for (i, s) in line.trim().split(',').enumerate() {
            if i >= names.len() {
                k = i + 1;
                break;
            }
            let s = s.trim();
            fields[i] = s.parse::<f64>().map_err(|_| {
                CliError::Usage(format!(
                    "{shown}: line {lineno}: column {} `{}` is not a number",
                    names[i],
                    crate::input_file::message_excerpt(s)
                ))
            })?;
            k = i + 1;
        }
        if k != names.len() {
            return Err(CliError::Usage(format!(
                "{shown}: line {lineno}: {k} fields, the header has {}",
                names.len()
            )));
        }
        let t = fields[t_col];
        for (v, &c) in values.iter_mut().zip(&chans) {
            *v = fields[c];
        }
        sink(Item::Sample {
            t_s: t,
            values: &values,
        })?;
        if has_pos {
            let g = |j: usize| fields[pose_cols[j].expect("present")];
            sink(Item::Pose {
                t_s: t,
                position_m: [g(0), g(1), g(2)],
                orientation_wxyz: has_quat.then(|| [g(3), g(4), g(5), g(6)]),
            })?;
        }
    }
    Ok(())
}
