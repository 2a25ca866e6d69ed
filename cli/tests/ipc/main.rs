//! The service end to end through the `cablevib` binary: `serve`, `demo`, a Rust peer and
//! the Python controller example.
//! Area binary of the command-line crate (see tests/README.md at the repository root).

mod child;
mod demo_hold;
mod demo_shape;
mod ipc_service;
mod python_controller;
