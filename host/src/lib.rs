//! The std side of kiss-odom: file formats, the `kiss-odom` command, metrics, plots, the LiDAR
//! simulator and the cross-check against the reference. The odometry itself is
//! `kiss-odom-core`; this crate is glue and file formats around it.

pub mod bench;
pub mod cli;
pub mod crosscheck;
pub mod exec;
pub mod io;
pub mod metrics;
pub mod plot;
#[cfg(feature = "ros2")]
pub mod ros2;
pub mod run;
pub mod settings;
pub mod simulate;
