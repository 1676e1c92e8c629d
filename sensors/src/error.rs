//! Error enums: small, `Copy`, each variant saying what the caller should do.

/// Why a packet was not decoded. The packet is skipped and counted in the sweep's
/// [`crate::SweepStats`] (`bad_packets`, `out_of_order` or `other_sensor`); the decoder state is
/// unchanged, so the caller can log the error and go on with the next packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PacketError {
    /// Shorter than the format's fixed length: the capture cut it (snap length, a file cut in
    /// the middle). Skip it.
    Truncated,
    /// Longer than the format's fixed length: a packet of another kind (Velodyne position
    /// packet, Ouster IMU packet) or another Ouster profile/beam count than the metadata
    /// says. Skip it; if every packet says so, check the port and the metadata.
    Length,
    /// The packet does not start with the format's start bytes (Hesai `EE FF`): another kind
    /// of packet on the port, or corrupted. Skip it.
    StartBytes,
    /// A Hesai packet of another protocol version than the model's (XT32 6.1, QT128 3.2,
    /// Pandar128 and OT128 1.4: another Hesai model on the port; skip it; if every packet says
    /// so, give the right model), or a Livox packet whose version byte is not its protocol's
    /// (SDK 1: 5, SDK 2: 0; if every packet says so, give the other model).
    Version,
    /// A Livox SDK 2 or Hesai QT128 packet whose CRC does not match its bytes: corrupted on the
    /// way. Skip it.
    Checksum,
    /// A Velodyne data block does not start with its `0xFFEE` flag: corrupted. Skip it.
    BlockFlag,
    /// A Velodyne or Hesai azimuth at or above 360.00 degrees: corrupted. Skip it.
    Azimuth,
    /// A Velodyne timestamp at or above one hour (it counts microseconds past the hour), or a
    /// Hesai date that does not exist: corrupted. Skip it.
    Timestamp,
    /// The Velodyne factory byte names a model this crate does not decode (or none, as old
    /// HDL-32E firmware): give the model in [`crate::velodyne::Config::model`]. Hesai: the
    /// header's laser or block count or distance unit is not the protocol's model's.
    UnknownModel,
    /// The Velodyne return-mode byte is not strongest (0x37), last (0x38) or dual (0x39); the
    /// Hesai one is none of the six modes, or disagrees with the header's return count.
    UnknownReturnMode,
    /// The Hesai return-mode byte is triple return (0x3D, the XT32M's first, last and
    /// strongest in three blocks): not decoded. Set the sensor to a single or dual return mode.
    TripleReturn,
    /// The packet comes from another sensor than the sweep's (another model or return mode,
    /// or an Ouster column whose measurement id is beyond the frame): two sensors on one
    /// port. Filter by source address, or give each sensor its own port.
    OtherSensor,
    /// An Ouster packet whose type is not lidar data, or a Livox packet of a data type that
    /// is not points (IMU) or not decoded: skip it.
    PacketType,
    /// The Ouster packet's initialisation id or serial number differs from the metadata's:
    /// the metadata JSON belongs to another sensor. Give the JSON saved with this recording.
    MetadataMismatch,
    /// An Ouster column the packet marks valid lies outside the metadata's `column_window`:
    /// the sensor sends columns the metadata says it does not. Give the metadata saved with
    /// this recording.
    ColumnWindow,
    /// The Ouster packet's column timestamps are spaced for another `lidar_mode` than the
    /// metadata's (`columns_per_frame` columns a turn at its rate): its encoder angles would
    /// be wrong. Give the metadata saved with this recording.
    ColumnRate,
    /// The packets come from a model whose angles only its unit's calibration file gives
    /// (Velodyne HDL-64E, VLS-128, VLP-32A/B; Robosense without its DIFOP packet's angles) and
    /// none was given: give the file (or the DIFOP port). Nothing is decoded until then.
    NoCalibration,
    /// The packet is older than the sweep being assembled (a late or repeated packet): it is
    /// dropped and counted in `out_of_order`. Nothing to do.
    Late,
}

impl core::fmt::Display for PacketError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Truncated => "packet shorter than the format's length (truncated)",
            Self::Length => {
                "packet longer than the format's length (another packet kind or profile)"
            }
            Self::StartBytes => "not the format's start bytes (Hesai: EE FF)",
            Self::Version => "a protocol version not the model's (another Hesai or Livox model?)",
            Self::Checksum => "CRC does not match the packet's bytes (corrupted)",
            Self::BlockFlag => "a data block without its 0xFFEE flag",
            Self::Azimuth => "an azimuth of 360 degrees or more",
            Self::Timestamp => "a timestamp of one hour or more",
            Self::UnknownModel => "unknown model (Velodyne product byte, Hesai header)",
            Self::UnknownReturnMode => "unknown return-mode byte",
            Self::TripleReturn => {
                "triple return (0x3D) is not decoded: set the sensor to a single or dual return \
                 mode"
            }
            Self::OtherSensor => "packet of another sensor than the sweep's",
            Self::PacketType => "not a point data packet",
            Self::MetadataMismatch => "initialisation id or serial differs from the metadata",
            Self::ColumnWindow => {
                "a valid column outside the metadata's column_window (metadata of another \
                 configuration)"
            }
            Self::ColumnRate => {
                "column timestamps spaced for another lidar_mode than the metadata's \
                 columns_per_frame"
            }
            Self::NoCalibration => "a model that needs its calibration file, and none was given",
            Self::Late => "packet older than the sweep being assembled",
        })
    }
}

/// A configuration that cannot decode anything. Fix the configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// The calibration has another number of lasers than the model fires, or a non-finite
    /// number: give one entry per laser.
    Calibration,
    /// Ouster beam count (`pixels_per_column`) is zero, above [`crate::ouster::MAX_BEAMS`], or
    /// differs from the length of the angle tables.
    Beams,
    /// Ouster `columns_per_frame` is zero or above [`crate::ouster::MAX_COLUMNS`],
    /// `columns_per_packet` is zero or above [`crate::ouster::MAX_COLUMNS_PER_PACKET`], or the
    /// column window lies outside the frame.
    Columns,
    /// A transform or angle is not finite.
    NonFinite,
    /// Ouster `lidar_to_sensor_transform` is not rigid (an orthonormal rotation without
    /// reflection, last row 0 0 0 1) or moves the lidar more than [`crate::ouster::MAX_OFFSET_MM`].
    LidarToSensor,
    /// Ouster `beam_to_lidar_transform` (or `lidar_origin_to_beam_origin_mm`) is not rigid, or
    /// puts the beam origin more than [`crate::ouster::MAX_BEAM_ORIGIN_MM`] from the lidar's.
    BeamToLidar,
    /// An Ouster beam altitude beyond +-90 degrees.
    BeamAltitude,
    /// An Ouster beam azimuth offset beyond +-[`crate::ouster::MAX_BEAM_AZIMUTH_DEG`] degrees.
    BeamAzimuth,
    /// The cut angle is not below 360 degrees.
    CutAngle,
    /// The Livox frame period is zero or longer than [`crate::livox::GAP_NS`].
    FramePeriod,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Calibration => "calibration does not have one finite entry per laser",
            Self::Beams => "beam count zero, too large or not matching the angle tables",
            Self::Columns => "columns per frame or per packet zero or too large, or bad window",
            Self::NonFinite => "a transform or angle is not finite",
            Self::LidarToSensor => {
                "lidar_to_sensor_transform is not a rigid transform (orthonormal rotation, last \
                 row 0 0 0 1) within 500 mm"
            }
            Self::BeamToLidar => {
                "beam_to_lidar_transform / lidar_origin_to_beam_origin_mm is not a rigid \
                 transform within 200 mm"
            }
            Self::BeamAltitude => "beam_altitude_angles beyond +-90 degrees",
            Self::BeamAzimuth => "beam_azimuth_angles beyond +-45 degrees",
            Self::CutAngle => "cut angle not below 360 degrees",
            Self::FramePeriod => "frame period zero or longer than 0.3 s",
        })
    }
}
