//! The names most programs need, in one import: `use cablevib::prelude::*;`.
//!
//! | name | what |
//! |---|---|
//! | [`Scene`] | a robot: `Scene::load("spatial-paper")` or a scene `.toml` |
//! | [`Estimator`], [`EstimatorParams`], [`Pose`], [`Tmin`] | the per-cycle estimator: `Estimator::new(&scene)?.update(&pose, Tmin::Scene)` |
//! | [`Estimate`], [`EeMode`], [`Stiffness`], [`Status`] | what one cycle returns |
//! | [`Mode`] | one natural frequency of a pose: [`Estimator::modes`] |
//! | [`frf()`], [`FrfConfig`], [`DampingChoice`], [`Damping`] | the receptance at the end-effector over a band |
//! | [`simulate()`], [`SampledPath`], [`SimulateConfig`] | the end-effector's vibration along a path |
//! | [`Vector3`] | nalgebra's 3-vector (positions in m) |
//!
//! ```
//! use cablevib::prelude::*;
//!
//! let scene = Scene::load("planar-paper")?;
//! let mut est = Estimator::new(&scene)?;
//! let e = est.update(&Pose::in_scene(&scene, scene.ee_position_m), Tmin::Scene);
//! assert!(e.is_ok() && e.f1_hz > 0.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub use crate::estimator::{EeMode, Estimate, Estimator, EstimatorParams, Status, Stiffness, Tmin};
pub use crate::kinematics::Pose;
pub use crate::modal::Mode;
pub use crate::scene::{Damping, ElementKind, Scene};
pub use crate::study::frf::{frf, DampingChoice, FrfConfig, FrfResult};
pub use crate::study::simulate::{simulate, SampledPath, SimulateConfig, SimulateResult};
pub use nalgebra::Vector3;
