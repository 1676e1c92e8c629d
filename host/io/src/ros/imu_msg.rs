//! `sensor_msgs/Imu` as the two ROS generations serialize it, read into an [`ImuSample`]: the
//! header's stamp (its time, on the clock of the clouds' stamps), `angular_velocity` (rad/s)
//! and `linear_acceleration` (m/s^2). ROS 1 (bags) is little-endian and packed; CDR (ROS 2's
//! MCAP files) has a 4-byte encapsulation header, either byte order, and aligns every value to
//! its size. After `header.frame_id` both carry the same block of 37 f64; every range is
//! checked against the message's length before a byte of it is read.

use crate::imu::ImuSample;
use core::ops::Range;

/// Connection type of the messages in a ROS 1 bag.
pub const ROS1_TYPE: &str = "sensor_msgs/Imu";

/// MD5 of the ROS 1 `sensor_msgs/Imu` definition.
pub const ROS1_MD5: &str = "6a62c6daae103f4ff57a132d6f95cec2";

/// Schema name of the messages in a ROS 2 MCAP file.
pub const ROS2_SCHEMA: &str = "sensor_msgs/msg/Imu";

/// The ROS 1 header: `seq`, `stamp.sec`, `stamp.nsec` (u32 each), `frame_id`'s length.
mod ros1 {
    use core::ops::Range;
    pub const SEQ: Range<usize> = 0..4;
    pub const SEC: Range<usize> = 4..8;
    pub const NSEC: Range<usize> = 8..12;
    pub const FRAME_ID_LEN: Range<usize> = 12..16;
}

/// The CDR header: the encapsulation, then (offsets from its end) `stamp.sec` (i32),
/// `stamp.nanosec` (u32) and `frame_id`'s length, which counts its terminating NUL.
mod cdr {
    use core::ops::Range;
    pub const ENCAPSULATION: Range<usize> = 0..4;
    pub const SEC: Range<usize> = 0..4;
    pub const NSEC: Range<usize> = 4..8;
    pub const FRAME_ID_LEN: Range<usize> = 8..12;
}

/// The block after `frame_id` (offsets from its start): orientation (4 f64, not read) and its
/// covariance (9), then the two vectors this reader keeps, each followed by its covariance.
mod block {
    use core::ops::Range;
    pub const ANGULAR_VELOCITY: Range<usize> = 104..128;
    pub const LINEAR_ACCELERATION: Range<usize> = 200..224;
    pub const LEN: usize = 296;
}

/// Why a message is not a `sensor_msgs/Imu`; the caller counts it, warns and leaves it out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImuError {
    /// The message ends inside the named field (cut short, or another type's).
    Truncated(&'static str),
    /// The CDR encapsulation is not plain CDR (these two bytes).
    Encapsulation([u8; 2]),
    /// Bytes after the message's end (another type's).
    Trailing(usize),
    /// A stamp before 1970 or nanoseconds of a second or more.
    Stamp,
}

impl core::fmt::Display for ImuError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Truncated(field) => write!(f, "message ends inside {field}"),
            Self::Encapsulation([a, b]) => write!(f, "encapsulation {a:02x}{b:02x} is not CDR"),
            Self::Trailing(n) => write!(f, "{n} bytes after the end of the message"),
            Self::Stamp => write!(f, "stamp before 1970 or nanoseconds beyond a second"),
        }
    }
}

/// Bytes `range` of `buf`, or which field they would have been.
fn get<'a>(buf: &'a [u8], range: Range<usize>, what: &'static str) -> Result<&'a [u8], ImuError> {
    buf.get(range).ok_or(ImuError::Truncated(what))
}

fn word(buf: &[u8], range: Range<usize>, what: &'static str, be: bool) -> Result<u32, ImuError> {
    let b: [u8; 4] = get(buf, range, what)?
        .try_into()
        .map_err(|_| ImuError::Truncated(what))?;
    Ok(if be {
        u32::from_be_bytes(b)
    } else {
        u32::from_le_bytes(b)
    })
}

/// Three f64 at `range` of `buf`.
fn vector(buf: &[u8], range: Range<usize>, be: bool) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (v, c) in out.iter_mut().zip(buf[range].chunks_exact(8)) {
        let b = [c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]];
        *v = if be {
            f64::from_be_bytes(b)
        } else {
            f64::from_le_bytes(b)
        };
    }
    out
}

/// The sample of the block that starts at `at` in `buf`, which must end within `slack` bytes
/// of it.
fn sample(
    buf: &[u8],
    at: usize,
    slack: usize,
    (sec, nsec): (i64, u32),
    be: bool,
) -> Result<ImuSample, ImuError> {
    const WHAT: &str = "the orientation, rates and accelerations";
    let end = at
        .checked_add(block::LEN)
        .ok_or(ImuError::Truncated(WHAT))?;
    let body = get(buf, at..end, WHAT)?;
    let extra = buf.len() - end;
    if extra > slack {
        return Err(ImuError::Trailing(extra));
    }
    if sec < 0 || nsec >= 1_000_000_000 {
        return Err(ImuError::Stamp);
    }
    Ok(ImuSample {
        time_ns: sec as u64 * 1_000_000_000 + u64::from(nsec),
        gyro: vector(body, block::ANGULAR_VELOCITY, be),
        accel: vector(body, block::LINEAR_ACCELERATION, be),
    })
}

/// Reads a ROS 1 serialized `sensor_msgs/Imu`.
pub fn parse_ros1(msg: &[u8]) -> Result<ImuSample, ImuError> {
    get(msg, ros1::SEQ, "header.seq")?;
    let sec = word(msg, ros1::SEC, "header.stamp", false)?;
    let nsec = word(msg, ros1::NSEC, "header.stamp", false)?;
    let len = word(msg, ros1::FRAME_ID_LEN, "header.frame_id", false)? as usize;
    let at = ros1::FRAME_ID_LEN
        .end
        .checked_add(len)
        .filter(|&at| at <= msg.len())
        .ok_or(ImuError::Truncated("header.frame_id"))?;
    sample(msg, at, 0, (i64::from(sec), nsec), false)
}

/// Reads a CDR serialized `sensor_msgs/msg/Imu` (with its encapsulation header).
pub fn parse_cdr(msg: &[u8]) -> Result<ImuSample, ImuError> {
    let head = get(msg, cdr::ENCAPSULATION, "the encapsulation header")?;
    let be = match [head[0], head[1]] {
        [0, 0] => true,
        [0, 1] => false,
        other => return Err(ImuError::Encapsulation(other)),
    };
    let body = &msg[cdr::ENCAPSULATION.end..];
    let sec = word(body, cdr::SEC, "header.stamp", be)? as i32;
    let nsec = word(body, cdr::NSEC, "header.stamp", be)?;
    let len = word(body, cdr::FRAME_ID_LEN, "header.frame_id", be)? as usize;
    // f64 are aligned to 8 bytes from the encapsulation header's end.
    let at = cdr::FRAME_ID_LEN
        .end
        .checked_add(len)
        .filter(|&at| at <= body.len())
        .ok_or(ImuError::Truncated("header.frame_id"))?
        .next_multiple_of(8);
    // Serializers may pad the message to a multiple of 4 bytes.
    sample(body, at, 3, (i64::from(sec), nsec), be)
}

#[cfg(test)]
mod tests;
