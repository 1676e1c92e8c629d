//! A ray-cast spinning LiDAR with exact ground truth: scenes, motion, sensors and their packets.
//!
//! It sits upstream of everything else: it writes sequences in the generic layout that
//! `kiss-odom run` reads, for tests, fuzzing, benchmarks, the deskew study and degenerate-scene
//! stress tests. A seeded scene ([`city`], built from [`shapes`] and indexed by [`scene`]) is
//! swept by a multi-beam sensor ([`sensor`]) riding a smooth parametric trajectory
//! ([`trajectory`]) of a [`Profile`]: a [`Simulation`], with an [`imu`] riding along.
//! [`packets`] fires a real sensor's beams at its own timing and packs its UDP packets,
//! [`capture`] writes them as a pcap, [`ros`] the frames, packets and IMU samples as a ROS bag,
//! MCAP file or sqlite3 bag, [`writer`] the generic layout, [`layouts`] the public datasets'
//! own layouts, both replacing only a data set `simulate` wrote ([`replace`]), and
//! [`sequence`] a whole sequence; a [`revisit`] drives the same scene again, changed, along
//! another path, for localization in a prior map. Every random draw is
//! keyed by indices ([`rng`]), so the bytes depend on the seed and parameters only, never on
//! the thread count.

pub mod capture;
pub mod city;
pub mod imu;
pub mod layouts;
pub mod packets;
pub mod profile;
pub mod replace;
pub mod revisit;
pub mod rng;
pub mod ros;
pub mod scene;
pub mod sensor;
pub mod sequence;
pub mod shapes;
pub mod simulation;
pub mod trajectory;
pub mod writer;

pub use imu::ImuSpec;
pub use layouts::Layout;
pub use packets::{PacketSensor, PacketSim};
pub use profile::Profile;
pub use revisit::Revisit;
pub use scene::{Scene, Surface};
pub use sensor::{Frame, Lidar};
pub use sequence::{write, Format, Messages, Request, Written};
pub use simulation::{SimParams, Simulation, MAX_FRAMES};
pub use trajectory::{PoseM, Trajectory};
