//! Robosense RS-LiDAR-16, RS-LiDAR-32, RS-Bpearl, RS-Helios (5515 and 16P), RS-Ruby and
//! RS-Airy: MSOP packets to timed points, sweeps cut by azimuth.
//!
//! A Robosense unit sends its points in MSOP packets (port 6699) and its device information,
//! with every laser's vertical and horizontal angle, in DIFOP packets (port 7788, once a
//! second). The angles are the unit's own: the decoder takes them from a DIFOP packet pushed
//! to it, or from a [`Calibration`] the host read from the `angle.csv` Robosense ships; until
//! then every MSOP packet is refused with [`crate::PacketError::NoCalibration`].
//!
//! A return's azimuth is its block's azimuth plus the rotation to the next firing's block in
//! proportion to its firing time in the block (the manuals' time stamp appendix; rs_driver's
//! block iterators), kept exact rather than truncated to 0.01 degree as rs_driver does; its
//! range is measured from the lens centre, which turns with the rotor (rs_driver's geometry).
//! The RS-16, RS-32 and Bpearl send the same packet layout, so the model is the caller's to
//! say. The MEMS RS-M1 and the solid-state E1R send points with their own directions
//! ([`solid`]). The RS-Airy fills a firing's 96 lasers in two blocks (four in dual return)
//! and says its return mode in each packet; its 48- and 192-channel modes are refused
//! ([`crate::PacketError::Header`]). The RS-Ruby's dual-return packets hold one and a half
//! firings, their blocks paired as AAB or ABB. Not decoded: the E1R's dual-return packets.

mod calibration;
mod decoder;
mod model;
pub mod solid;
pub mod wire;

pub use calibration::{Calibration, Config, Laser, MAX_ANGLE_DEG};
pub use decoder::{Decoder, GAP_NS};
pub use model::{
    AiryInstall, Difop as DifopLayout, Layout, Model, Stamp, AIRY_96, AIRY_CHANNEL_MODE,
    AIRY_DATA_TYPE, AIRY_INSTALL, AIRY_RETURN_MODE, MAX_LASERS,
};
