//! Sensor captures: [`pcap`] reads pcap/pcapng files into UDP datagrams (with [`reassembly`]
//! of IP fragments), [`sweeps`] decodes the datagrams into sweeps with `kiss-odom-sensors`
//! (Ouster with [`ouster_meta`], Velodyne with an optional [`velodyne_calib`], Hesai with an
//! optional [`hesai_calib`]), and [`frames`]
//! hands the sweeps on as a frame source.

pub mod frames;
pub mod hesai_at128;
pub mod hesai_calib;
pub mod ouster_meta;
pub mod pcap;
pub mod reassembly;
pub mod robosense_calib;
pub mod sweeps;
pub mod velodyne_calib;
