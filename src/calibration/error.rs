//! [`CalibrationError`]: every refusal of a calibration, one line each, naming the row of the
//! data file or the parameter at fault.

/// Why a calibration was refused or could not finish.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CalibrationError {
    /// A parameter name, bound, nominal value or prior that cannot be used: the message
    /// names the parameter.
    #[error("parameter `{name}`: {message}")]
    Parameter {
        /// The parameter as the user wrote it (or its expanded name).
        name: String,
        /// What is wrong.
        message: String,
    },
    /// A data file that cannot be used as a whole (missing column, too large, unreadable).
    #[error("{file}: {message}")]
    File {
        /// The file (or `<measurements>` for data handed over in memory).
        file: String,
        /// What is wrong.
        message: String,
    },
    /// One row of a data file (1-based line number in the file).
    #[error("{file}: line {line}: {message}")]
    Row {
        /// The file.
        file: String,
        /// Line number, 1-based.
        line: usize,
        /// What is wrong with it.
        message: String,
    },
    /// The problem as a whole cannot be fitted (more parameters than measurements, no
    /// usable row left).
    #[error("{0}")]
    Problem(String),
    /// The model failed at the nominal parameters or could not be evaluated.
    #[error("{0}")]
    Model(String),
}

impl CalibrationError {
    /// A [`CalibrationError::Parameter`].
    pub(crate) fn param(name: &str, message: impl Into<String>) -> Self {
        CalibrationError::Parameter {
            name: name.to_string(),
            message: message.into(),
        }
    }
}
