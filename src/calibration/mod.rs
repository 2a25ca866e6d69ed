//! Calibration: fit a scene's stiffness, mass and damping parameters to measured natural
//! frequencies (and damping ratios, and cable tensions) at many poses.
//!
//! **The problem.** Measured modes i at poses P(i) with frequencies f_i ± σ_i; parameters
//! x (EA factors per cable, hidden lengths, the cables' weight per length, the
//! end-effector's mass, inertia and centre of mass, the pulleys' radius, damping:
//! [`params`]). Minimise
//!
//! ```text
//!     χ²(x) = Σ_i ((f_i(x) − f_i)/σ_i)² + Σ_d ((ζ_d(x) − ζ_d)/σ_d)² + Σ_t ((T_t(x) − T_t)/σ_t)²
//!             [+ Σ_k ((x_k − x_k,nominal)/σ_prior,k)²]
//! ```
//!
//! within bounds, by Levenberg-Marquardt ([`fit`]). f_i(x) is the model mode paired with
//! measured mode i ([`pairing`]): the structured engine's modes at each pose, as `cablevib
//! modes` computes them ([`evaluate`]).
//!
//! **Sensitivities.** ∂f/∂p = (∂λ/∂p)/(8π²f) with ∂λ/∂p = φᵀ(∂K/∂p − λ ∂M/∂p)φ, φ the
//! mass-normalised mode shape of the structured engine ([`energy`]): exact for the taut
//! `fem` and `massless` models, for every parameter that changes the cables' or the
//! end-effector's matrices (EA, hidden length, weight per length, mass with the tensions it
//! moves, inertia). We use this form rather than the condensed one, dλ/dp =
//! −vᵀ(∂D/∂p)v / vᵀ(∂D/∂λ)v on D(λ)'s null vector v: the two are equal, but ∂D/∂p needs the
//! derivative of every chain recurrence with respect to each element's data (the solver's
//! internals), while φ comes from the shapes' public entry point and ∂K/∂p, ∂M/∂p are the
//! element matrices' own closed forms. Parameters that move the geometry of every element
//! (the centre of mass, the pulley radius), and every parameter of the `catenary` and
//! `continuous` models, take central differences of the whole model instead; the report
//! names the method of each parameter.
//!
//! **Identifiability.** What the data can determine is read from the singular values of the
//! data Jacobian scaled by each parameter's range: a parameter whose data-only standard
//! error is a sizeable fraction of its range is named undetermined and given no standard
//! error ([`fit::statistics`]). χ²/dof against the stated noise gives the verdict.
//!
//! Layout: `params` (names, bounds, the scene of a parameter vector), `data` (the CSV
//! files), `evaluate` (the model at the poses), `energy` (the analytic sensitivities),
//! `pairing`, `problem` (residuals and Jacobian), `fit` (the iteration and its
//! statistics), `report`, `run` (the calibration from start to report). Offline: allocates.

pub mod data;
pub mod energy;
mod error;
pub mod evaluate;
pub mod fit;
pub mod pairing;
pub mod params;
mod problem;
pub mod report;
mod run;

pub use data::{Measurements, ModeLabel, SigmaDefaults};
pub use error::{CalibrationError, CalibrationOption};
pub use fit::FitParams;
pub use pairing::PairingParams;
pub use params::{apply, Applied, FitSpec, ParamKind, Parameter, PARAMETER_NAMES};
pub use report::Report;
pub use run::{calibrate, Calibration, CalibrationParams};
