//! cablevib (crate docs written with the model; see README).
#![warn(missing_docs)]
pub mod cable;
pub mod cli;
pub mod estimator;
pub mod kinematics;
pub mod modal;
pub mod scene;
pub mod service;
pub mod tension;
