//! Recordings of measured vibration, streamed: a CSV file ([`csv`](mod@csv)) or an MCAP file
//! ([`mcap`](mod@mcap): ROS 2 bags in CDR, and JSON channels). A reader hands its samples to
//! a sink one by one, in file order, so a recording of any length is read in the memory of
//! one line or one MCAP chunk; the readers' errors are one line naming the file and where.

pub mod csv;
pub mod mcap;
pub mod ros2;

use super::CliError;
use std::path::Path;

/// One item of a recording.
#[derive(Debug, Clone, Copy)]
pub enum Item<'a> {
    /// The channels, once, before the first sample.
    Layout(&'a Layout),
    /// A vibration sample: one value per channel.
    Sample {
        /// Time, s.
        t_s: f64,
        /// The channels' values.
        values: &'a [f64],
    },
    /// A measured input sample from a topic of its own ([`ReadOptions::input_topic`]): one
    /// value per input, on its own clock.
    Input {
        /// Time, s.
        t_s: f64,
        /// The inputs' values.
        values: &'a [f64],
    },
    /// A pose of the end-effector.
    Pose {
        /// Time, s.
        t_s: f64,
        /// Position, m.
        position_m: [f64; 3],
        /// Orientation w, x, y, z, if the recording has one.
        orientation_wxyz: Option<[f64; 4]>,
    },
}

/// What to read from a recording.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// Channels to identify from (CSV column names, or MCAP field names); empty: all.
    pub channels: Vec<String>,
    /// MCAP: the topic of the vibration samples (`None`: the only IMU / wrench topic).
    pub topic: Option<String>,
    /// MCAP: the topic of the poses (`None`: the only `PoseStamped` topic, if any).
    pub pose_topic: Option<String>,
    /// Measured inputs (force or hammer channels: CSV column names, or MCAP field names of
    /// the vibration topic's messages): left out of the default channels and handed after
    /// them in each sample.
    pub inputs: Vec<String>,
    /// MCAP: the topic of the measured inputs when they are not fields of the vibration
    /// topic (a `WrenchStamped` stream beside an IMU's): its samples come as [`Item::Input`],
    /// and [`Item::Sample`] holds the responses only.
    pub input_topic: Option<String>,
}

impl ReadOptions {
    /// The channels of a sample: `all` (the wanted outputs, or the reader's default) less
    /// the inputs, then the inputs; an input also named in `--channels` is refused.
    pub fn with_inputs(&self, all: Vec<String>) -> Result<Vec<String>, String> {
        if let Some(c) = self.channels.iter().find(|c| self.inputs.contains(c)) {
            return Err(format!(
                "`{c}` is named both by --channels and by --input: a channel is a response or a measured input"
            ));
        }
        if let Some((i, c)) = self
            .inputs
            .iter()
            .enumerate()
            .find(|(i, c)| self.inputs[..*i].contains(c))
        {
            return Err(format!("--input `{c}` is named twice (input {})", i + 1));
        }
        let mut out: Vec<String> = all
            .into_iter()
            .filter(|c| !self.inputs.contains(c))
            .collect();
        out.extend(self.inputs.iter().cloned());
        Ok(out)
    }
}

/// What a reader found before the first sample.
#[derive(Debug, Clone)]
pub struct Layout {
    /// Names of the vibration channels, in the order of [`Item::Sample`]'s values.
    pub channels: Vec<String>,
    /// Where they come from (file kind, topic, schema), for the output.
    pub source: String,
    /// How many of the channels, the last ones, are measured inputs ([`ReadOptions::inputs`]).
    pub inputs: usize,
    /// The inputs come on a topic of their own ([`Item::Input`]), not in [`Item::Sample`].
    pub separate_inputs: bool,
}

/// Read `path` (CSV or MCAP, by its first bytes): `sink` gets the [`Item::Layout`], then
/// every item in file order.
pub fn read(
    path: &Path,
    opts: &ReadOptions,
    sink: &mut dyn FnMut(Item<'_>) -> Result<(), CliError>,
) -> Result<(), CliError> {
    let mut magic = [0u8; 8];
    let n = {
        use std::io::Read;
        let mut f = crate::input_file::open_checked(path, "recording", u64::MAX)
            .map_err(|e| CliError::Usage(e.to_string()))?;
        f.read(&mut magic).unwrap_or(0)
    };
    if n >= 5 && magic[..5] == [0x89, b'M', b'C', b'A', b'P'] {
        mcap::read(path, opts, sink)
    } else {
        csv::read(path, opts, sink)
    }
}
