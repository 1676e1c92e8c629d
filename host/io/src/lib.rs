//! Recorded LiDAR data in, trajectories out: every dataset layout, container and sensor
//! capture kiss-odom reads, the pose files it writes, and the metrics that score them.
//!
//! Every input is a [`FrameSource`]: a stream of scans read one at a time, so a long recording
//! never has to fit in memory and no frame costs more than the scan capacity
//! ([`OpenOptions::scan_points`]) whatever its file says. [`open()`] picks the reader and
//! [`Selection`] keeps the frames of a [`FrameRange`]. The readers
//! come in four families:
//!
//! - [`folders`]: a folder of frame files (`.bin`, `.ply`, `.pcd`), generic or KITTI layout;
//! - [`ros`]: ROS 1 bags and ROS 2 MCAP files carrying `sensor_msgs/PointCloud2`;
//! - [`capture`]: pcap/pcapng captures of sensor packets, decoded by `kiss-odom-sensors`;
//! - [`layouts`]: the public datasets' own layouts (MulRan, NCLT, Newer College, HeLiPR,
//!   Boreas, nuScenes, Apollo, KITTI raw), read as kiss-icp's dataloaders read them.
//!
//! [`poses`] reads and writes trajectories (KITTI, TUM), [`metrics`] scores them against ground
//! truth as kiss-icp does, [`imu`] holds the IMU samples sensor captures carry beside their
//! frames and their `imu.csv`, [`pose`] holds the pose helpers they share, and [`mod@write`] is how
//! every file is written: whole or not at all. Nothing here depends on the command line.

pub mod capture;
pub mod dataset;
pub mod folders;
pub mod imu;
pub mod layouts;
pub mod metrics;
pub mod open;
pub mod pose;
pub mod poses;
pub mod ros;
pub mod select;
pub mod write;

pub use dataset::{
    Dataset, DatasetInfo, Format, Frame, FrameSource, ImuInput, Item, OpenOptions, SensorKind,
    SensorOptions, SweepInfo, Trailer,
};
pub use open::open;
pub use select::{FrameRange, Selection};
