//! The core's integration tests in one binary: the public API, the work budget, whole-pipeline
//! runs on a generated street, the proptest properties, robust mode's gate and the second
//! deskew pass.

mod api;
mod budget;
mod common;
mod pipeline;
mod properties;
mod redeskew;
mod rehome;
mod robust_gate;
