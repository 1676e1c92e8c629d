//! Which sensor family a datagram comes from, by its bytes alone: how `live` without
//! `--sensor` (and a recording read on a given `input.port`) finds its decoder from the first
//! packet, and how a recording's other ports are searched for a second sensor's packets. Each
//! family's packets are recognised as its decoder checks them first: a Velodyne data packet's
//! length and first block flag, a Hesai header ([`hesai::identify`]), a Livox packet's version
//! byte with the length its data type (SDK 1) or its length field (SDK 2) gives.

use kiss_odom_sensors::{hesai, livox, velodyne};

/// A family of sensors whose packets name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// A Velodyne data packet (the model is in its product byte).
    Velodyne,
    /// A Hesai point cloud packet of this model.
    Hesai(hesai::Model),
    /// A Livox data packet: SDK 1 (taken for a Horizon, Tele-15 or Avia) or SDK 2 (Mid-360).
    Livox(livox::Model),
}

impl Family {
    /// The family's sensors, as the reports name them.
    pub fn name(self) -> &'static str {
        match self {
            Self::Velodyne => "Velodyne",
            Self::Hesai(m) => m.name(),
            Self::Livox(livox::Model::Mid360) => "Livox Mid-360/HAP",
            Self::Livox(_) => "Livox SDK 1 sensor (Mid-40/70, Horizon, Tele-15, Avia)",
        }
    }
}

/// The family whose packets begin like `bytes`, if any. Ouster packets need the sensor's
/// metadata to be read at all and Robosense ones `--sensor`: neither is named here.
pub fn family_of(bytes: &[u8]) -> Option<Family> {
    use livox::{sdk1, sdk2};
    let len = bytes.len();
    if len == velodyne::wire::field::LEN && bytes.get(..2) == Some(&[0xFF, 0xEE][..]) {
        return Some(Family::Velodyne);
    }
    if let Some(model) = hesai::identify(bytes) {
        return Some(Family::Hesai(model));
    }
    let byte = |i: usize| bytes.get(i).copied();
    if byte(sdk1::field::VERSION) == Some(sdk1::VERSION)
        && byte(sdk1::field::DATA_TYPE).and_then(sdk1::packet_len) == Some(len)
    {
        return Some(Family::Livox(livox::Model::Horizon));
    }
    let stated = match bytes.get(sdk2::field::LENGTH) {
        Some(&[lo, hi]) => usize::from(u16::from_le_bytes([lo, hi])),
        _ => 0,
    };
    let point_type = byte(sdk2::field::DATA_TYPE).filter(|t| *t != sdk2::IMU);
    if byte(sdk2::field::VERSION) == Some(sdk2::VERSION)
        && len >= sdk2::field::DATA
        && stated == len
        && point_type.and_then(sdk2::point_size).is_some()
    {
        return Some(Family::Livox(livox::Model::Mid360));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_familys_first_bytes_name_it() {
        let mut vlp = vec![0u8; 1206];
        vlp[..2].copy_from_slice(&[0xFF, 0xEE]);
        assert_eq!(family_of(&vlp), Some(Family::Velodyne));
        assert_eq!(family_of(&vlp[..1205]), None);
        let mut xt32 = vec![0u8; 1080];
        xt32[..8].copy_from_slice(&[0xEE, 0xFF, 6, 1, 0, 0, 32, 8]);
        assert_eq!(family_of(&xt32), Some(Family::Hesai(hesai::Model::Xt32)));
        let mut avia = vec![0u8; 18 + 14 * 96];
        avia[0] = 5;
        avia[9] = 2;
        assert_eq!(family_of(&avia), Some(Family::Livox(livox::Model::Horizon)));
        assert_eq!(family_of(&avia[..1000]), None);
        let mut mid = vec![0u8; 36 + 14 * 96];
        let n = mid.len() as u16;
        mid[1..3].copy_from_slice(&n.to_le_bytes());
        mid[10] = 1;
        assert_eq!(family_of(&mid), Some(Family::Livox(livox::Model::Mid360)));
        // An SDK 2 IMU packet is not a point stream's; a length field not the datagram's.
        mid[10] = 0;
        assert_eq!(family_of(&mid), None);
        mid[10] = 1;
        mid[1] ^= 1;
        assert_eq!(family_of(&mid), None);
        assert_eq!(family_of(&[]), None);
    }
}
