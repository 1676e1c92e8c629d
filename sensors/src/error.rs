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
    /// A Livox SDK 2 header whose length field disagrees with the length its `dot_num` points
    /// take: corrupted (the CRC does not cover the header). Skip it.
    LengthField {
        /// The header's length field.
        stated: u16,
        /// The length of its points and header.
        expected: u16,
    },
    /// A Livox packet whose data type and point count (SDK 2: `dot_num`; SDK 1: the data type's)
    /// take another length than the packet has, where the packet's length is one its format
    /// allows (SDK 2: its length field agrees with it; SDK 1: another data type's): the data
    /// type or `dot_num` is corrupted. Skip it.
    PointsLength {
        /// The data type byte.
        data_type: u8,
        /// The points that data type and `dot_num` announce.
        points: u16,
        /// The packet's length (SDK 2: its length field and datagram).
        len: u16,
    },
    /// A Hesai header whose flags announce another optional part (the UDP sequence number,
    /// the functional safety part, the signature, a channel's extra bytes) than the packet
    /// holds: its length is one another flags byte announces. Corrupted; skip it.
    HeaderFlags {
        /// The header's flags byte.
        flags: u8,
        /// The length those flags announce.
        announced: u16,
        /// The packet's length.
        len: u16,
    },
    /// A Livox SDK 2 IMU packet whose `dot_num` is not 1 (an IMU packet holds one sample):
    /// corrupted. Skip it.
    ImuPoints {
        /// The header's `dot_num`.
        dot_num: u16,
    },
    /// A Livox SDK 2 point packet whose `time_interval` is 0: its points' times (and the
    /// packet's period, by which losses are counted) are unknown. Skip it.
    PointInterval,
    /// A data block does not start with its flag (bytes `FF EE`; a Velodyne bank's `FF DD`,
    /// `FF CC`, `FF BB`; the RS-Ruby's `FE`) nor with another model's: corrupted. Skip it.
    BlockFlag,
    /// A Velodyne, Hesai or Robosense azimuth at or above 360.00 degrees: corrupted. Skip it.
    Azimuth,
    /// A PandarAT128 block azimuth outside every mirror frame of the unit's angle correction:
    /// corrupted, or the correction of another unit. Skip it; if every packet says so, give
    /// the `.dat` of this unit.
    MirrorFrame,
    /// A Velodyne timestamp at or above one hour (it counts microseconds past the hour):
    /// corrupted. Skip it.
    Timestamp,
    /// A UTC date or time of day that does not exist (Hesai, Robosense, Livox GPS time: month
    /// 13, February 30, hour 24, microseconds beyond the second): corrupted. Skip it.
    DateTime,
    /// A Livox timestamp type the protocol does not define (SDK 1: above 4; SDK 2: above 2):
    /// the time cannot be read. Skip it.
    TimeType {
        /// The packet's timestamp type byte.
        kind: u8,
    },
    /// The packet's time is further after the packet before it than the packets between can
    /// explain (by their sequence numbers, or 16 packet periods without them): a stray
    /// packet's time. It is dropped and counted in `out_of_order`; a timeline this far ahead
    /// is taken once [`crate::RESYNC_PACKETS`] packets agree on it (a pause, a clock step).
    Ahead,
    /// The Velodyne factory byte names a model this crate does not decode (or none, as old
    /// HDL-32E firmware): give the model in [`crate::velodyne::Config::model`].
    UnknownModel,
    /// A Hesai header whose laser count, block count or distance unit is not the model's, or
    /// an RS-Airy header of another channel mode than 96 (another model on the port, or
    /// corrupted). Skip it; if every packet says so, give
    /// the right model.
    Header,
    /// The Velodyne return-mode byte is not strongest (0x37), last (0x38) or dual (0x39); the
    /// Hesai or RS-M1 one is none of the model's modes. Also after the first packet fixed the
    /// mode: a byte no mode has is corrupted, not another sensor's. Skip it.
    UnknownReturnMode,
    /// A Hesai header's return count is not 1 or 2, or contradicts the return-mode byte (a
    /// count of 1 with a dual mode, or one above the model's most with the mode): corrupted.
    /// Skip it.
    ReturnCount {
        /// The header's return count.
        count: u8,
        /// The return-mode byte.
        mode: u8,
    },
    /// A Hesai dual-return packet whose pair of blocks (one firing) has two azimuths: the
    /// data is not dual-return data, or corrupted. Skip it.
    DualPair {
        /// Azimuth of the pair's first block, 0.01 degree.
        first: u16,
        /// Azimuth of its second block.
        second: u16,
    },
    /// A Hesai packet whose block azimuths advance from firing to firing by another step than
    /// its motor speed and the model's firing time give (none: the rotor does not turn, or
    /// dual-return data under a single-return mode byte; a multiple: another protocol's or
    /// operational state's packets). Skip it.
    FiringStep {
        /// The step seen, 0.01 degree.
        step: u16,
        /// The step the motor speed and firing time give.
        expected: u16,
    },
    /// A Pandar128 or OT128 packet whose operational state and block azimuth state are not a
    /// state the model's firing-time file lists (OT128: high resolution 0 with azimuth states
    /// 0-3, standard 2 with 0-1; Pandar128: energy saving 3 too; 1 is shutdown): its
    /// channels' firing times are unknown. Skip it.
    FiringState {
        /// The operational state byte.
        operational: u8,
        /// The block's azimuth state.
        azimuth: u8,
    },
    /// The Hesai return-mode byte is triple return (0x3D, the XT32M's first, last and
    /// strongest in three blocks): not decoded. Set the sensor to a single or dual return mode.
    TripleReturn,
    /// Dual-return packets of a model whose pairs are not decoded (the E1R's, whose blocks
    /// say no return order): set the sensor to a single return mode.
    DualNotDecoded,
    /// The packet comes from another sensor than the sweep's (another model or return mode,
    /// another model's block flags): two sensors on one port. Filter by source address, or
    /// give each sensor its own port.
    OtherSensor,
    /// An Ouster packet whose type is not lidar data, or a Livox packet of a data type that
    /// is not points (IMU) or not decoded: skip it.
    PacketType,
    /// The Ouster packet's initialisation id or serial number differs from the metadata's:
    /// the metadata JSON belongs to another sensor. Give the JSON saved with this recording.
    MetadataMismatch,
    /// An Ouster column whose measurement id is not below the metadata's `columns_per_frame`:
    /// the metadata is of another `lidar_mode` (or the column header is corrupted). Give the
    /// metadata saved with this recording.
    MeasurementId {
        /// The column's measurement id.
        id: u16,
        /// The metadata's `columns_per_frame`.
        columns: u16,
    },
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
        let text = match *self {
            Self::Truncated => "packet shorter than the format's length (truncated)",
            Self::Length => {
                "packet longer than the format's length (another packet kind or profile)"
            }
            Self::StartBytes => "not the format's start bytes (Hesai: EE FF)",
            Self::Version => "a protocol version not the model's (another Hesai or Livox model?)",
            Self::Checksum => "CRC does not match the packet's bytes (corrupted)",
            Self::LengthField { stated, expected } => {
                return write!(
                    f,
                    "header length field {stated} where its points take {expected} bytes"
                )
            }
            Self::PointsLength {
                data_type,
                points,
                len,
            } => {
                return write!(
                    f,
                    "data type {data_type} with {points} points takes another length than the \
                     packet's {len} bytes (a data type or dot_num not the packet's)"
                )
            }
            Self::HeaderFlags {
                flags,
                announced,
                len,
            } => {
                return write!(
                    f,
                    "header flags {flags:#04X} announce a {announced}-byte packet, not the \
                     packet's {len} bytes"
                )
            }
            Self::ImuPoints { dot_num } => {
                return write!(f, "an IMU packet whose dot_num is {dot_num}, not 1")
            }
            Self::PointInterval => "time_interval 0: its points' times are unknown",
            Self::BlockFlag => {
                "a data block without its block flag (FF EE, a Velodyne bank's FF DD/CC/BB, the \
                 RS-Ruby's FE)"
            }
            Self::Azimuth => "an azimuth of 360 degrees or more",
            Self::MirrorFrame => "an azimuth outside every mirror frame of the angle correction",
            Self::Timestamp => "a timestamp of one hour or more (microseconds past the hour)",
            Self::DateTime => {
                "a date or time of day that does not exist (month 13, hour 24, microseconds \
                 beyond the second...)"
            }
            Self::TimeType { kind } => {
                return write!(
                    f,
                    "timestamp type {kind}, which the protocol does not define"
                )
            }
            Self::Ahead => {
                "a time further after the packet before it than the packets between explain (a \
                 stray packet's time, or the first packets after a pause)"
            }
            Self::UnknownModel => "unknown model (Velodyne product byte)",
            Self::Header => "a header's laser count, block count or distance unit not the model's",
            Self::UnknownReturnMode => "a return-mode byte the model does not define",
            Self::ReturnCount { count, mode } => {
                return write!(
                    f,
                    "header return count {count} against return-mode byte {mode:#04X}"
                )
            }
            Self::DualPair { first, second } => {
                return write!(
                    f,
                    "a dual-return mode byte, but a firing's two blocks at azimuths {first} and \
                     {second} (0.01 degree)"
                )
            }
            Self::FiringStep { step, expected } => {
                return write!(
                    f,
                    "block azimuths {step} apart (0.01 degree) from firing to firing where the \
                     motor speed, firing time and return mode give {expected}"
                )
            }
            Self::FiringState {
                operational,
                azimuth,
            } => {
                return write!(
                    f,
                    "operational state {operational} with azimuth state {azimuth}, which the \
                     model's firing times do not list"
                )
            }
            Self::TripleReturn => {
                "triple return (0x3D) is not decoded: set the sensor to a single or dual return \
                 mode"
            }
            Self::DualNotDecoded => {
                "dual-return packets of this model are not decoded: set it to a single return \
                 mode"
            }
            Self::OtherSensor => "packet of another sensor than the sweep's",
            Self::PacketType => "not a point data packet (IMU, status, or a data type not decoded)",
            Self::MetadataMismatch => "initialisation id or serial differs from the metadata",
            Self::MeasurementId { id, columns } => {
                return write!(
                    f,
                    "column measurement id {id} beyond the metadata's {columns} columns_per_frame \
                     (metadata of another lidar_mode)"
                )
            }
            Self::ColumnWindow => {
                "a valid column outside the metadata's column_window (metadata of another \
                 configuration)"
            }
            Self::ColumnRate => {
                "column timestamps spaced for another lidar_mode than the metadata's \
                 columns_per_frame"
            }
            Self::NoCalibration => "a model that needs its calibration file, and none was given",
            Self::Late => "a time or frame id not after the packet before it (late or repeated)",
        };
        f.write_str(text)
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
