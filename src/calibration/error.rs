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
    /// No parameter named to fit ([`CalibrationOption::Fit`]).
    #[error("{}", nothing_to_fit(&CalibrationOption::name))]
    NothingToFit,
    /// A bound, nominal value or prior for a parameter that is not fitted.
    #[error("{}", not_fitted(.0, &CalibrationOption::name))]
    NotFitted(String),
    /// A scene with sag on: only the chord model is calibrated.
    #[error("{}", sagged(&CalibrationOption::name))]
    Sagged,
}

/// What a calibration's caller sets, named in the refusals that ask for it: the library
/// by its own names ([`CalibrationOption::name`]), a front end by its flags
/// ([`CalibrationError::render`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CalibrationOption {
    /// The parameters to fit (`FitSpec::new`'s names).
    Fit,
    /// The chord model: the scene with sag off.
    SagOff,
}

impl CalibrationOption {
    /// The option in the library's terms.
    pub fn name(self) -> &'static str {
        match self {
            CalibrationOption::Fit => "fit",
            CalibrationOption::SagOff => "sag = false",
        }
    }
}

/// [`CalibrationError::NothingToFit`]'s message.
fn nothing_to_fit(name: &dyn Fn(CalibrationOption) -> &'static str) -> String {
    format!(
        "no parameter to fit: give {} NAME[,NAME...]",
        name(CalibrationOption::Fit)
    )
}

/// [`CalibrationError::NotFitted`]'s message.
fn not_fitted(param: &str, name: &dyn Fn(CalibrationOption) -> &'static str) -> String {
    format!(
        "parameter `{param}`: is not among the fitted parameters (add it to {})",
        name(CalibrationOption::Fit)
    )
}

/// [`CalibrationError::Sagged`]'s message.
fn sagged(name: &dyn Fn(CalibrationOption) -> &'static str) -> String {
    format!(
        "scenes with [effects] sag = true are not calibrated yet: calibrate the chord model ({}) or switch sag off",
        name(CalibrationOption::SagOff)
    )
}

impl CalibrationError {
    /// The message with each option called `name(option)` (the command line passes its
    /// flags); equal to the `Display` text with [`CalibrationOption::name`].
    pub fn render(&self, name: &dyn Fn(CalibrationOption) -> &'static str) -> String {
        match self {
            CalibrationError::NothingToFit => nothing_to_fit(name),
            CalibrationError::NotFitted(param) => not_fitted(param, name),
            CalibrationError::Sagged => sagged(name),
            other => other.to_string(),
        }
    }

    /// A [`CalibrationError::Parameter`].
    pub(crate) fn param(name: &str, message: impl Into<String>) -> Self {
        CalibrationError::Parameter {
            name: name.to_string(),
            message: message.into(),
        }
    }
}
