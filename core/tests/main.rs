//! The core's integration tests in one binary: the public API, the work budget, whole-pipeline
//! runs on a generated street, the proptest properties and robust mode's gate.

mod api;
mod budget;
mod common;
mod pipeline;
mod properties;
mod robust_gate;
