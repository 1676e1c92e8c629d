//! The messages sensor drivers record (`io::ros::packets::packets`: VelodyneScan, PandarScan,
//! NebulaPackets, Ouster's PacketMsg, RobosenseScan and RobosenseInfoPacket;
//! `io::ros::livox::parse`: Livox's CustomMsg), ROS 1 or CDR. The first byte picks the
//! serialization (bit 0) and the message (bits 1 to 3). What
//! parses holds no more packets or points than its bytes can: every packet at least a stamp
//! and a length (12 bytes), every point 19 bytes, and as many points as `point_num` says.
#![no_main]

use kiss_odom_io::ros::kinds::Kind;
use kiss_odom_io::ros::{livox, packets};
use libfuzzer_sys::fuzz_target;

const KINDS: [Kind; 6] = [
    Kind::VelodyneScan,
    Kind::PandarScan,
    Kind::NebulaPackets,
    Kind::OusterPacket,
    Kind::RobosenseScan,
    Kind::RobosenseInfo,
];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, body)) = data.split_first() else {
        return;
    };
    let ros1 = pick & 1 == 0;
    match KINDS.get(usize::from(pick >> 1) % (KINDS.len() + 1)) {
        Some(&kind) => {
            if let Ok(list) = packets::packets(kind, ros1, body) {
                assert!(list.len() <= body.len().max(12) / 12 + 1);
                let bytes: usize = list.iter().map(|p| p.data.len()).sum();
                assert!(bytes <= body.len());
            }
        }
        None => {
            if let Ok(msg) = livox::parse(ros1, body) {
                assert_eq!(msg.points.len(), msg.point_num as usize);
                assert!(msg.points.len() * 19 <= body.len());
            }
        }
    }
});
