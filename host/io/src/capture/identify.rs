//! Which sensor family a datagram comes from, by its bytes alone: how `live` without
//! `--sensor` (and a recording read on a given `input.port`) finds its decoder from the first
//! packet, and how a recording's other ports are searched for a second sensor's packets. Each
//! family's packets are recognised as its decoder checks them first: a Velodyne data packet's
//! length and first block flag, a Hesai header ([`hesai::identify`]), a Livox packet's version
//! byte with the length its data type (SDK 1) or its length field (SDK 2) gives, a Robosense
//! packet of a layout one model alone writes ([`robosense::wire::model_of`],
//! [`robosense::solid::Model::of`]).

use kiss_odom_sensors::{hesai, livox, robosense, velodyne};

/// A family of sensors whose packets name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// A Velodyne data packet (the model is in its product byte).
    Velodyne,
    /// A Hesai point cloud packet of this model.
    Hesai(hesai::Model),
    /// A Livox data packet: SDK 1 (taken for a Horizon, Tele-15 or Avia) or SDK 2 (Mid-360).
    Livox(livox::Model),
    /// A spinning Robosense MSOP packet of a layout only this model writes (RS-Ruby, RS-Airy).
    Robosense(robosense::Model),
    /// A Robosense RS-M1 or E1R MSOP packet.
    RobosenseSolid(robosense::solid::Model),
}

impl Family {
    /// The family's sensors, as the reports name them.
    pub fn name(self) -> &'static str {
        match self {
            Self::Velodyne => "Velodyne",
            Self::Hesai(m) => m.name(),
            Self::Livox(livox::Model::Mid360) => "Livox Mid-360/HAP",
            Self::Livox(_) => "Livox SDK 1 sensor (Mid-40/70, Horizon, Tele-15, Avia)",
            Self::Robosense(m) => m.name(),
            Self::RobosenseSolid(m) => m.name(),
        }
    }
}

/// The family whose packets begin like `bytes`, if any. Ouster packets need the sensor's
/// metadata to be read at all, and the spinning Robosense models that send alike (RS-16,
/// RS-32 and Bpearl; Helios and Helios-16P) `--sensor`: none of those is named here.
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
    if let Some(model) = robosense::solid::Model::of(bytes) {
        return Some(Family::RobosenseSolid(model));
    }
    robosense::wire::model_of(bytes).map(Family::Robosense)
}

/// A spinning Robosense MSOP packet's frame, for tests: `model`'s id and every block's flag.
#[cfg(test)]
pub(super) fn robosense_frame(model: robosense::Model) -> Vec<u8> {
    let l = model.layout();
    let mut b = vec![0u8; robosense::wire::LEN];
    b[..l.id.len()].copy_from_slice(l.id);
    for k in 0..l.blocks {
        let at = l.header + k * l.block_len();
        b[at..at + l.block_id.len()].copy_from_slice(l.block_id);
    }
    b
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

    #[test]
    fn robosense_packets_are_named_where_one_model_alone_writes_them() {
        use robosense::{solid, Model};
        let named: Vec<_> = Model::ALL
            .iter()
            .map(|&m| (m.name(), family_of(&robosense_frame(m))))
            .collect();
        println!("{named:?}");
        for (m, family) in Model::ALL.iter().zip(&named) {
            let alone = robosense::wire::model_of(&robosense_frame(*m)).is_some();
            let want = alone.then_some(Family::Robosense(*m));
            assert_eq!(family.1, want, "{}", m.name());
        }
        // The models that send alike are not named, the Ruby and the Airy are.
        assert_eq!(named.iter().filter(|(_, f)| f.is_some()).count(), 2);
        let mut airy = robosense_frame(Model::Airy);
        assert_eq!(family_of(&airy).map(Family::name), Some("RS-Airy"));
        airy.pop();
        assert_eq!(family_of(&airy), None);
        for m in [solid::Model::M1, solid::Model::E1r] {
            let mut b = vec![0u8; m.packet_len()];
            b[..4].copy_from_slice(&[0x55, 0xAA, 0x5A, 0xA5]);
            assert_eq!(family_of(&b), Some(Family::RobosenseSolid(m)));
            b[3] = 0;
            assert_eq!(family_of(&b), None);
        }
    }
}
