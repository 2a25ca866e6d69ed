//! Modal identification against systems whose modes are known: multi-DOF systems with
//! closed-form modes simulated by exact discrete-time integration written here, the paper's
//! robot under white-noise forcing (its modes from the dense reference), closely spaced
//! modes, and hostile records. Area binary of the core crate (see tests/README.md).

mod closed_form;
mod input_output;
mod robot;
