//! Each field of an Ouster lidar packet's header and column headers corrupted alone: the
//! refusal names that field (its variant, and its text), not another one.

use kiss_odom_sensors::ouster::{self, wire::field};
use kiss_odom_sensors::{Decode, PacketError};
mod common;
#[path = "common/ouster.rs"]
mod ouster_packets;

use common::{feed, with, Log};
use ouster_packets::{ouster_packet, small_ouster};

#[test]
fn each_corrupted_header_field_is_refused_by_its_own_name() {
    use PacketError::*;
    // The decoder of the packets' metadata, fresh or after the frame's first packet.
    let refusal = |after: bool, bytes: &[u8]| {
        let mut dec = ouster::Decoder::new(&small_ouster()).unwrap();
        let mut log = Log::default();
        if after {
            feed(&mut dec, &ouster_packet(7, 0, 1234), &mut log).unwrap();
        }
        dec.push(bytes, &mut log)
    };
    let good = ouster_packet(7, 1, 1234);
    let set = |at: usize, v: u8| with(&good, at, v);
    // Column `c`'s measurement id (columns 20 bytes apart after the 32-byte header).
    let id = |c: usize, m: u16| {
        let mut b = good.clone();
        let at = field::HEADER_LEN + 20 * c + field::COLUMN_MEASUREMENT_ID.start;
        b[at..at + 2].copy_from_slice(&m.to_le_bytes());
        b
    };
    let older = ouster_packet(6, 1, 1234);
    let (fresh, after) = (false, true);
    let beyond = |id| MeasurementId { id, columns: 64 };
    // (field, packet, after a good one, refusal, what its text names)
    #[rustfmt::skip]
    let rows = vec![
        ("length", good[..100].to_vec(), fresh, Truncated, "shorter"),
        ("packet type", set(field::PACKET_TYPE.start, 3), fresh, PacketType, "data packet"),
        ("init id", set(field::INIT_ID.start, 78), fresh, MetadataMismatch, "initialisation id"),
        ("serial", set(field::SERIAL.start + 1, 9), fresh, MetadataMismatch, "serial"),
        ("measurement id", id(0, 64), fresh, beyond(64), "measurement id 64"),
        ("measurement id", id(15, 1000), after, beyond(1000), "64 columns_per_frame"),
        ("frame id", older, after, Late, "frame id"),
    ];
    for (name, bytes, after, want, names) in &rows {
        let row = format!("{name} (after a good packet: {after})");
        assert_eq!(refusal(*after, bytes), Err(*want), "{row}");
        let text = want.to_string();
        assert!(
            text.contains(names),
            "{row}: \"{text}\" does not name {names}"
        );
    }
}
