//! The cablevib command line: [`report`] writes the studies' CSV files, SVG plots and
//! Markdown, [`cli`] parses the commands and runs them (the `cablevib` binary is
//! `src/main.rs`). It builds on the core (`cablevib`: scene → estimator and the studies) and
//! the service (`cablevib-service`).
#![warn(missing_docs)]
// Standard output through `cablevib::outln!` (an error, not a panic, when it cannot be
// written).
#![warn(clippy::print_stdout)]
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

// The core's modules and the service, under the paths the files name (`crate::scene::...`).
use cablevib::{
    calibration, caspr, estimator, identify, input_file, kinematics, modal, output_file, scene,
    study, trajectory,
};
use cablevib_service as service;

// Layer 7
pub mod report;
// Layer 8
pub mod cli;
