//! Hard cases of the taut-cable model: extreme elements, hostile inputs, clustered and
//! degenerate modes, tension-distribution corner cases; each checked against the dense
//! reference (`cablevib_testkit::hard_cases`).
//! Area binary of the core crate (see tests/README.md).

mod element;
mod inputs;
mod modes;
mod tension;
mod tiny_lengths;
