//! The files each command reads and writes, known from its options before it runs: [`run`]
//! refuses an output that is one of the inputs (the same file, by device and inode) before
//! anything is computed or written ([`crate::output_file::refuse_inputs`]). The match below
//! names every command, so a new one must say what it reads and writes.
//!
//! `accuracy` names its files after the scene's `name`, so it checks them itself once the
//! scene is loaded (still before any work).
//!
//! [`run`]: super::run

use super::figure::target;
use super::{output_paths, CliError, Command};
use crate::report::csv::sidecar_path;
use std::path::{Path, PathBuf};

/// What a command reads and writes.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Files {
    /// Files read (scenes, trajectories, model files); a name that is no file is skipped.
    pub inputs: Vec<PathBuf>,
    /// Files written.
    pub outputs: Vec<PathBuf>,
}

impl Files {
    fn new(inputs: impl IntoIterator<Item = PathBuf>) -> Files {
        Files {
            inputs: inputs.into_iter().collect(),
            outputs: Vec::new(),
        }
    }
    /// A CSV and its sidecar.
    fn csv(&mut self, path: &Path) {
        self.outputs.push(path.to_path_buf());
        self.outputs.push(sidecar_path(path));
    }
    fn out(&mut self, path: impl Into<PathBuf>) {
        self.outputs.push(path.into());
    }
}

/// The files of `command` (see the module doc).
pub fn files(command: &Command) -> Result<Files, CliError> {
    Ok(match command {
        Command::Analyze(a) => {
            let mut f = Files::new([a.scene.input_path()]);
            if let Some(prefix) = &a.export_matrices {
                f.outputs.extend(super::analyze::matrix_paths(prefix));
            }
            if let Some(p) = &a.shapes {
                f.csv(p);
            }
            f
        }
        Command::Bench(a) => Files::new([a.scene.input_path()]),
        Command::Serve(a) => Files::new([PathBuf::from(a.scene_name())]),
        Command::Demo(a) => {
            let mut f = Files::new([PathBuf::from(&a.scene)]);
            if let Some(p) = &a.hold_csv {
                f.out(p);
                f.outputs.extend(super::serve::hold_figure_paths(p));
            }
            if let Some(p) = &a.monitor.record {
                f.out(p);
            }
            f
        }
        Command::BenchIpc(a) => Files::new([PathBuf::from(&a.scene)]),
        Command::Monitor(a) => {
            let mut f = Files::new(a.scene.iter().map(PathBuf::from));
            if let Some(p) = &a.record {
                f.out(p);
            }
            f
        }
        Command::Replay(a) => Files::new([a.file.clone()]),
        // Its outputs are checked in `accuracy::run` (module doc).
        Command::Accuracy(a) => Files::new([a.scene.input_path()]),
        Command::Map(a) => {
            let mut f = Files::new([a.scene.input_path()]);
            let (csv, fig, fmt) = output_paths(&a.out, &a.svg, a.format)?;
            f.csv(&csv);
            if a.shard.is_none() {
                for v in &a.show {
                    let part = crate::report::map::value_names(*v).2;
                    f.out(super::map::shown_path(&fig, &part, fmt));
                }
                f.out(fig);
            }
            f
        }
        Command::Trajectory(a) => {
            let mut f = Files::new([a.scene.input_path()]);
            f.inputs.extend(a.csv.clone());
            let (csv, fig, _) = output_paths(&a.out, &a.svg, a.format)?;
            f.csv(&csv);
            f.out(fig);
            f
        }
        Command::SweepTmin(a) => {
            let mut f = Files::new([a.scene.input_path()]);
            let (csv, fig, _) = output_paths(&a.out, &a.svg, a.format)?;
            f.csv(&csv);
            f.out(fig);
            f
        }
        Command::SagCompare(a) => {
            let mut f = Files::new([a.scene.input_path()]);
            let (csv, fig, _) = output_paths(&a.out, &a.svg, a.format)?;
            f.csv(&csv);
            f.out(fig);
            f
        }
        Command::Completions(_) | Command::Man(_) => Files::default(),
        Command::Import(a) => match &a.format {
            super::import::ImportFormat::Caspr(c) => {
                let mut f = Files::new([c.bodies.clone(), c.cables.clone()]);
                f.out(&c.output);
                f
            }
        },
        Command::Modes(a) => {
            let mut f = Files::new([a.scene.input_path()]);
            if let Some(p) = &a.csv {
                f.csv(p);
            }
            if let Some(p) = &a.svg {
                f.out(target(p, a.format)?.0);
            }
            f
        }
        Command::Frf(a) => {
            let mut f = Files::new([a.scene.input_path()]);
            if let Some(p) = &a.csv {
                f.csv(p);
            }
            if let Some(p) = &a.svg {
                f.out(target(p, a.format)?.0);
            }
            f
        }
        Command::Simulate(a) => {
            let mut f = Files::new([a.scene.input_path()]);
            f.inputs.extend(a.path.csv.clone());
            let (csv, fig, _) = a.output_paths()?;
            f.csv(&csv);
            f.out(fig);
            f
        }
        Command::Identify(a) => {
            let mut f = Files::new([a.recording.clone()]);
            f.inputs.extend(a.scene.iter().map(PathBuf::from));
            if let Some(p) = &a.csv {
                f.csv(p);
            }
            if let Some(p) = &a.svg {
                f.out(target(p, a.format)?.0);
            }
            f
        }
        Command::Calibrate(a) => {
            let mut f = Files::new([a.data.clone(), a.scene.input_path()]);
            f.inputs.extend(a.tensions.clone());
            f.outputs.extend(a.output.clone());
            if let Some(p) = &a.svg {
                f.out(target(p, a.format)?.0);
            }
            f
        }
        Command::Shape(a) => {
            let mut f = Files::new([PathBuf::from(&a.scene)]);
            f.inputs.extend(a.trajectory.clone());
            f.inputs.extend(a.path.csv.clone());
            if let Some(p) = &a.output {
                f.csv(p);
            }
            if let Some(p) = &a.sensitivity {
                f.out(target(p, a.format)?.0);
            }
            f
        }
    })
}

/// [`crate::output_file::refuse_inputs`] as a command-line error.
pub fn refuse_inputs(outputs: &[PathBuf], inputs: &[PathBuf]) -> Result<(), CliError> {
    Ok(crate::output_file::refuse_inputs(outputs, inputs)?)
}
