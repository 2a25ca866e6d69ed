//! The error of the command-line tools, and the options by which it names the studies'
//! parameters.

use crate::caspr::{CasprError, ImportOption};
use crate::report::ReportError;
use crate::scene::SceneError;
use crate::service::{ServiceError, ServiceParam};
use crate::study::analysis::AnalyzeError;
use crate::study::{Param, StudyError};

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
    /// A service command failed (its parameters named by their options; the message is
    /// the whole line, no source below it).
    #[error("{}", .0.render(&service_flag))]
    Service(ServiceError),
    /// A study failed or was given bad values (its parameters named by their options).
    #[error("{}", .0.render(&flag))]
    Study(StudyError),
    /// The analysis of one pose failed or was given bad values.
    #[error("{}", .0.render(&flag))]
    Analyze(AnalyzeError),
    /// An import was refused (its options named by their flags).
    #[error("{}", .0.render(&import_flag))]
    Import(CasprError),
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

// Not `#[from]`: that would make the wrapped error the source as well, and `{:#}` would
// print the message twice.
impl From<StudyError> for CliError {
    fn from(e: StudyError) -> Self {
        CliError::Study(e)
    }
}

impl From<AnalyzeError> for CliError {
    fn from(e: AnalyzeError) -> Self {
        CliError::Analyze(e)
    }
}

impl From<CasprError> for CliError {
    fn from(e: CasprError) -> Self {
        CliError::Import(e)
    }
}

impl From<ServiceError> for CliError {
    fn from(e: ServiceError) -> Self {
        CliError::Service(e)
    }
}

/// The option that sets a study's parameter (`--modes` for [`Param::Modes`]).
pub fn flag(p: Param) -> &'static str {
    match p {
        Param::Modes => "--modes",
        Param::Solver => "--solver",
        Param::CompareDense => "--compare-dense",
        Param::StepM => "--step",
        Param::TiltDeg => "--tilt-deg",
        Param::TiltAxis => "--tilt-axis",
        Param::TiltStepDeg => "--tilt-step-deg",
        Param::TMinsN => "--t-mins",
        Param::PeriodS => "--period-s",
        Param::RadiusM => "--radius-m",
        Param::MaxElements => "--max-elements",
        Param::Points => "--points",
        Param::Axis => "--axis",
        Param::SpanM => "--span-m",
        Param::FromN => "--from",
        Param::ToN => "--to",
        Param::Steps => "--steps",
        Param::DurationS => "--duration",
        Param::DtS => "--dt",
        Param::MaxAccelerationMS2 => "--max-acceleration",
        Param::UpdateEvery => "--update-every",
        Param::SettleS => "--settle",
        Param::Tolerance => "--tolerance",
        Param::FromHz => "--from-hz",
        Param::ToHz => "--to-hz",
        Param::LossFactor => "--loss-factor",
        Param::Rayleigh => "--rayleigh",
        Param::RayleighAlpha => "--rayleigh alpha",
        Param::RayleighBeta => "--rayleigh beta",
        Param::ModalRatio => "--modal-ratio",
        Param::Undamped => "--undamped",
        Param::Dense => "--dense",
        Param::DenseModal => "--dense-modal",
        Param::DenseLuPoints => "--dense-lu-points",
    }
}

/// The option that sets a service command's parameter (`--rate-hz` for
/// [`ServiceParam::RateHz`]).
pub fn service_flag(p: ServiceParam) -> &'static str {
    match p {
        ServiceParam::Seconds => "--seconds",
        ServiceParam::RateHz => "--rate-hz",
        ServiceParam::RequiredHz => "--required-hz",
        ServiceParam::HoldF1Hz => "--hold-f1",
        ServiceParam::TMinSchedule => "--t-min-schedule",
        ServiceParam::HoldCsv => "--hold-csv",
        ServiceParam::Samples => "--samples",
        ServiceParam::Shape => "--shape",
        ServiceParam::Instance => "--instance",
    }
}

/// The flag of `cablevib import caspr` that sets an import option (`--t-min` for
/// [`ImportOption::TMin`]).
pub fn import_flag(o: ImportOption) -> &'static str {
    match o {
        ImportOption::CableSet => "--cable-set",
        ImportOption::WeightPerLength => "--weight-per-length",
        ImportOption::Area => "--area",
        ImportOption::YoungsModulus => "--youngs-modulus",
        ImportOption::TMin => "--t-min",
    }
}
