//! The error of the command-line tools.

use crate::report::ReportError;
use crate::scene::SceneError;
use crate::study::StudyError;

/// Errors of the command-line tools.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// Bad scene.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Bad option value.
    #[error("{0}")]
    Usage(String),
    /// The analysis failed (infeasible tensions, ...).
    #[error("{0}")]
    Analysis(String),
    /// Output failed.
    #[error("output: {0}")]
    Io(#[from] std::io::Error),
    /// A service command failed.
    #[error(transparent)]
    Service(#[from] crate::service::ServiceError),
    /// A study failed or was given bad values.
    #[error(transparent)]
    Study(#[from] StudyError),
    /// Standard output could not be written.
    #[error(transparent)]
    Stdout(#[from] crate::output_file::StdoutError),
    /// An output was refused (it is an input) or not written whole.
    #[error(transparent)]
    Output(#[from] crate::output_file::OutputFileError),
    /// Writing a result file failed.
    #[error(transparent)]
    Report(#[from] ReportError),
}
