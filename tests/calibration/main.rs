//! Calibration: the analytic eigenvalue sensitivities against central differences of the
//! model, the recovery of known parameters from data of an independent dense FEM (coverage
//! of the reported standard errors over seeded trials), honesty (unseen parameters named
//! undetermined, a model that lacks an effect judged not to fit).
//! Area binary of the core crate (see tests/README.md).

mod honesty;
mod recovery;
mod sensitivities;
