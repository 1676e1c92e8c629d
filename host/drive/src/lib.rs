//! kiss-odom on a host: the configuration, the worker threads and the one way frames go
//! through the core.
//!
//! [`Settings`] holds every parameter of a run, read from TOML (what `run` writes) or
//! kiss-icp's YAML, and gives the core its `Config` and `Capacities`. A [`Driver`] owns the
//! odometry in the scalar and map storage the settings choose, with a [`Pool`] of worker
//! threads for the correspondence search, and answers every frame with an [`Outcome`]. The
//! `kiss-odom` commands, its ROS 2 node and the Python bindings all run the core through here.

pub mod capacity;
pub mod driver;
mod engine;
pub mod error;
pub mod growth;
pub mod imu_check;
pub mod localize;
pub mod map_build;
pub mod outcome;
pub mod pool;
pub mod prior;
pub mod settings;
pub mod widen;

pub use capacity::CapacityWarnings;
pub use driver::{Build, Driver, OnEmpty, Preloaded};
pub use error::one_line;
pub use growth::StateMemory;
pub use outcome::{FrameMeta, ImuUse, MapInUse, Outcome, Step, SweepMotions};
pub use pool::Pool;
pub use prior::PriorWarnings;
pub use settings::{Imu, Scalar, Settings, Storage};
