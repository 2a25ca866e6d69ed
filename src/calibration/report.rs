//! [`Report`]: what a calibration found, as the command line prints it (its JSON form prints this
//! structure) and the Python package returns it.

use serde::Serialize;

/// One fitted parameter.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterResult {
    /// Name, e.g. `ea_factor.3`.
    pub name: String,
    /// SI unit (`"1"` for a ratio).
    pub unit: String,
    /// The estimate (for an undetermined parameter: where the fit left it, about its
    /// nominal value; not a measurement).
    pub value: f64,
    /// Standard error (None when undetermined).
    pub std_error: Option<f64>,
    /// Whether the data determine it (its data-only standard error is below half its
    /// scale: min(|nominal|, range), or the range for a nominal of 0).
    pub determined: bool,
    /// Its standard error from the data alone (∞ → None when the data cannot see it).
    pub data_std_error: Option<f64>,
    /// Nominal value (the start, and the prior's centre).
    pub nominal: f64,
    /// Lower bound.
    pub lower: f64,
    /// Upper bound.
    pub upper: f64,
    /// Whether the estimate sits on a bound (its standard error then assumes it free).
    pub at_bound: bool,
    /// The prior's standard deviation, when one was given.
    pub prior_sigma: Option<f64>,
    /// How its sensitivities were computed: `analytic` (mode shapes), `difference`
    /// (central differences of the model) or `linear` (damping).
    pub sensitivity: String,
}

/// One measured mode before and after the fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModeResidual {
    /// Line in the data file.
    pub line: usize,
    /// Pose index (0-based, in order of first appearance in the data).
    pub pose: usize,
    /// Position of the pose, m.
    pub position_m: [f64; 3],
    /// The pairing rule (`ee2`, `mode 7`) and how it was set (`given` or `by frequency`).
    pub pairing: String,
    /// `identify`'s pairing hint (model mode order), when the data had one.
    pub model_mode_hint: Option<usize>,
    /// Measured frequency, Hz.
    pub measured_hz: f64,
    /// Its standard deviation, Hz.
    pub sigma_hz: f64,
    /// The paired model mode's frequency before the fit, Hz.
    pub model_before_hz: f64,
    /// After the fit, Hz.
    pub model_after_hz: f64,
    /// (model − measured)/σ before.
    pub normalised_before: f64,
    /// (model − measured)/σ after.
    pub normalised_after: f64,
    /// The paired model mode's order at the pose after the fit (1-based, first of its
    /// cluster) and its multiplicity.
    pub model_mode_after: usize,
    /// Multiplicity of the paired model mode's cluster.
    pub multiplicity: u32,
    /// Its end-effector participation after the fit.
    pub participation_after: f64,
}

/// One measured damping ratio before and after the fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DampingResidual {
    /// Line in the data file.
    pub line: usize,
    /// Measured ζ.
    pub measured: f64,
    /// Its σ.
    pub sigma: f64,
    /// Model ζ before (the scene's damping at the measured frequency).
    pub model_before: f64,
    /// Model ζ after.
    pub model_after: f64,
}

/// One measured tension before and after the fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TensionResidual {
    /// Line in the tensions file.
    pub line: usize,
    /// Cable (1-based).
    pub cable: usize,
    /// Measured tension, N.
    pub measured_n: f64,
    /// Its σ, N.
    pub sigma_n: f64,
    /// Model tension before, N.
    pub model_before_n: f64,
    /// After, N.
    pub model_after_n: f64,
}

/// A data row not in the fit, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LeftOutRow {
    /// Line in the data file.
    pub line: usize,
    /// Why (status not ok, ambiguous pairing, no such model mode).
    pub reason: String,
}

/// The report of one calibration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// Scene name.
    pub scene: String,
    /// The model (`fem × 10`, …).
    pub model: String,
    /// The modes file.
    pub data: String,
    /// The tensions file, when given.
    pub tension_data: Option<String>,
    /// Distinct measured poses.
    pub poses: usize,
    /// Measured frequencies in the fit.
    pub frequencies: usize,
    /// Measured damping ratios in the fit.
    pub damping_ratios: usize,
    /// Measured tensions in the fit.
    pub tensions: usize,
    /// Where the frequencies' σ came from: counts of `sigma_hz`, `frequency_std_hz`, the
    /// relative default ([`crate::calibration::SigmaDefaults`]).
    pub sigma_sources: [usize; 3],
    /// The parameters.
    pub parameters: Vec<ParameterResult>,
    /// Correlation matrix in the parameters' order (None where undetermined).
    pub correlation: Vec<Vec<Option<f64>>>,
    /// Singular values of the scaled data Jacobian (rows / σ, columns × range), descending.
    pub singular_values: Vec<f64>,
    /// Names of the undetermined parameters.
    pub undetermined: Vec<String>,
    /// χ² at the nominal parameters.
    pub chi2_before: f64,
    /// χ² after the fit (data rows only).
    pub chi2: f64,
    /// Degrees of freedom: data rows − determined parameters.
    pub dof: usize,
    /// χ²/dof after the fit.
    pub chi2_per_dof: f64,
    /// χ²/dof at the nominal parameters.
    pub chi2_per_dof_before: f64,
    /// P(χ² larger) for noise of the stated size.
    pub p_value: f64,
    /// True when the misfit is within the stated noise (p ≥ the threshold).
    pub fits: bool,
    /// The verdict in words.
    pub verdict: String,
    /// RMS of (model − measured)/σ of the frequencies after the fit.
    pub rms_normalised_after: f64,
    /// The same before.
    pub rms_normalised_before: f64,
    /// Measured modes.
    pub residuals: Vec<ModeResidual>,
    /// Measured damping ratios (when a damping parameter was fitted).
    pub damping_residuals: Vec<DampingResidual>,
    /// Measured tensions.
    pub tension_residuals: Vec<TensionResidual>,
    /// Rows left out of the fit (status, pairing), with the reason.
    pub left_out: Vec<LeftOutRow>,
    /// Columns of the data files not used.
    pub unused_columns: Vec<String>,
    /// Notes on the data (defaults used, columns ignored, orientation assumed).
    pub notes: Vec<String>,
    /// Accepted steps of the iteration (over all pairing rounds).
    pub iterations: u32,
    /// Model evaluations (each one at every pose).
    pub evaluations: u32,
    /// Rounds of fit and re-pairing by frequency.
    pub pairing_rounds: u32,
    /// Starts of the iteration (more than one when the first answer failed the χ² test).
    pub starts: u32,
    /// Whether the iteration met its tolerance.
    pub converged: bool,
    /// Wall time, s.
    pub seconds: f64,
}
