//! The std side of kiss-odom: file formats, the `kiss-odom` command, metrics, plots, the LiDAR
//! simulator and the cross-check against the reference. The odometry itself is
//! `kiss-odom-core`; this crate is glue and file formats around it.
//!
//! Frames reach the core one way, through [`drive::Driver`]: readers ([`io`]) yield frames,
//! the driver registers them and answers each with an outcome, and the commands ([`run`],
//! [`mod@bench`], [`crosscheck`]) decide what to write, time or compare. [`args`] holds the
//! options the commands share, [`output`] how every file is written.

pub mod args;
pub mod bench;
pub mod cli;
pub mod convert;
pub mod crosscheck;
pub mod drive;
pub mod exec;
pub mod interrupt;
pub mod io;
pub mod live;
pub mod memory;
pub mod metrics;
pub mod output;
pub mod plot;
pub mod pose;
pub mod replay;
#[cfg(feature = "ros2")]
pub mod ros2;
pub mod run;
pub mod settings;
pub mod simulate;
pub mod stats;
pub mod viz;
