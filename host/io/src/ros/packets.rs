//! The packet messages vendors' ROS drivers record by default, read into the sensor's UDP
//! payloads, each with the stamp its driver gave it (the time it was received):
//!
//! - `velodyne_msgs/VelodyneScan` (ros-drivers' velodyne, nebula): a header, then packets of
//!   a stamp and a fixed `uint8[1206]`;
//! - `pandar_msgs/PandarScan` (nebula, Hesai's drivers): a header, then packets of a stamp,
//!   the data and its `size`; nebula's data is a fixed `uint8[1500]` (only the first `size`
//!   bytes are the packet), some drivers' a `uint8[]`: the layout the message's length fits;
//! - `nebula_msgs/NebulaPackets` (nebula, any sensor): a header, then packets of a stamp and
//!   a `uint8[]`;
//! - Ouster's `PacketMsg` (ouster-ros): one packet, a `uint8[] buf`, no stamp of its own;
//! - `robosense_msgs/RobosenseScan` (nebula): a header, then packets of a stamp and a fixed
//!   `uint8[1248]`; `RobosenseInfoPacket`: the model's name and one such packet (a DIFOP).
//!
//! Every length and count is checked against the message before it is used; what does not
//! parse is an error naming the field, for the caller to count.

use super::kinds::Kind;
use super::serial::Reader;

/// The bytes of a Velodyne data packet in a `VelodynePacket`.
pub const VELODYNE_PACKET: usize = 1206;

/// The bytes of nebula's `PandarPacket.data`.
pub const PANDAR_PACKET: usize = 1500;

/// The bytes of nebula's `RobosensePacket.data`.
pub const ROBOSENSE_PACKET: usize = 1248;

/// One packet of a message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Packet<'a> {
    /// When the driver received it, ns since the epoch, if the message says (and the stamp
    /// is a time: not before 1970, nanoseconds below a second).
    pub stamp_ns: Option<u64>,
    /// The UDP payload.
    pub data: &'a [u8],
}

/// The packets of a message of `kind` (ROS 1 serialized if `ros1`, else CDR), in order.
pub fn packets(kind: Kind, ros1: bool, body: &[u8]) -> Result<Vec<Packet<'_>>, String> {
    match kind {
        Kind::VelodyneScan => scan(ros1, body, Layout::Fixed(VELODYNE_PACKET, false)),
        Kind::NebulaPackets => scan(ros1, body, Layout::Sized(false)),
        Kind::PandarScan => scan(ros1, body, Layout::Fixed(PANDAR_PACKET, true))
            .or_else(|fixed| scan(ros1, body, Layout::Sized(true)).map_err(|_| fixed)),
        Kind::RobosenseScan => scan(ros1, body, Layout::Fixed(ROBOSENSE_PACKET, false)),
        Kind::RobosenseInfo => robosense_info(ros1, body).map(|(_, p)| vec![p]),
        Kind::OusterPacket => {
            let mut r = Reader::of(ros1, body)?;
            let data = r.bytes("buf")?;
            r.finish()?;
            Ok(vec![Packet {
                stamp_ns: None,
                data,
            }])
        }
        other => Err(format!("{other:?} messages carry no packets")),
    }
}

/// A `robosense_msgs/RobosenseInfoPacket`: the model's name and its DIFOP packet.
pub fn robosense_info(ros1: bool, body: &[u8]) -> Result<(String, Packet<'_>), String> {
    let mut r = Reader::of(ros1, body)?;
    let model = r.string("lidar_model")?;
    let stamp = r.time("packet.stamp")?;
    let data = r.take(ROBOSENSE_PACKET, "packet.data")?;
    r.finish()?;
    let stamp_ns = (stamp.sec >= 0 && stamp.nsec < 1_000_000_000)
        .then(|| stamp.sec as u64 * 1_000_000_000 + u64::from(stamp.nsec));
    Ok((model, Packet { stamp_ns, data }))
}

/// How a packet's data is laid out after its stamp.
#[derive(Clone, Copy, Debug)]
enum Layout {
    /// A fixed array of this many bytes; then, if true, a `uint32 size` of the bytes used.
    Fixed(usize, bool),
    /// A `uint8[]`; then, if true, a `uint32 size` of the bytes used.
    Sized(bool),
}

/// The packets of a message of a header and a sequence of (stamp, data) packets.
fn scan(ros1: bool, body: &[u8], layout: Layout) -> Result<Vec<Packet<'_>>, String> {
    let mut r = Reader::of(ros1, body)?;
    r.header()?;
    let least = match layout {
        Layout::Fixed(n, _) => 8 + n,
        Layout::Sized(_) => 8 + 4,
    };
    let n = r.count("packets", least)?;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let stamp = r.time("packets.stamp")?;
        let (data, sized) = match layout {
            Layout::Fixed(len, sized) => (r.take(len, "packets.data")?, sized),
            Layout::Sized(sized) => (r.bytes("packets.data")?, sized),
        };
        let data = if sized {
            let size = r.u32("packets.size")? as usize;
            data.get(..size).ok_or_else(|| {
                format!(
                    "packets.size {size} is more than the {} bytes of data",
                    data.len()
                )
            })?
        } else {
            data
        };
        let stamp_ns = (stamp.sec >= 0 && stamp.nsec < 1_000_000_000)
            .then(|| stamp.sec as u64 * 1_000_000_000 + u64::from(stamp.nsec));
        out.push(Packet { stamp_ns, data });
    }
    r.finish()?;
    Ok(out)
}

#[cfg(test)]
mod tests;
