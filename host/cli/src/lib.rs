//! The `kiss-odom` command: one module per command, and what they share (options, signals,
//! plots, the Rerun and point-cloud observers). The odometry is `kiss-odom-core`, run through
//! `kiss-odom-drive`; recordings are read and poses written by `kiss-odom-io`; `simulate`
//! drives `kiss-odom-sim`. This crate is glue: argument parsing, the run loop and its outputs.
//!
//! [`run`] feeds a recording's frames to the driver and writes what each command writes;
//! `live` is `run` on a socket, watching each pose as it comes; `listen` collects the poses a
//! receiver that runs the odometry itself sends. With the `dev` feature, `dev` is the
//! developer's tool: `bench` and `crosscheck` time and compare the same frames against the
//! reference kiss-icp. Only what the workspace's tests and the
//! binary reach is public: [`cli::main_with`], the outputs' names, the ROS 2 node's parts,
//! `eval`, the memory and signal helpers.

pub(crate) mod args;
#[cfg(feature = "dev")]
pub(crate) mod bench;
pub mod cli;
pub(crate) mod convert;
#[cfg(feature = "dev")]
pub(crate) mod crosscheck;
#[cfg(feature = "dev")]
pub mod dev;
pub mod eval;
pub mod interrupt;
pub(crate) mod listen;
pub(crate) mod live;
pub(crate) mod map;
pub mod memory;
pub mod plot;
#[cfg(feature = "dev")]
pub(crate) mod reference;
pub(crate) mod replay;
#[cfg(feature = "ros2")]
pub mod ros2;
pub mod run;
pub(crate) mod simulate;
pub(crate) mod size;
pub(crate) mod stats;
