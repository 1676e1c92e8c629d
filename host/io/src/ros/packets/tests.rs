//! Tests of `packets`.

use super::*;
use crate::ros::test_messages as msg;

/// `n` packets of `len` bytes, each filled with its number, stamped 1 ms apart.
fn some(n: usize, len: usize) -> Vec<(u64, Vec<u8>)> {
    (0..n)
        .map(|k| {
            (
                1_700_000_000_000_000_000 + k as u64 * 1_000_000,
                vec![k as u8 + 1; len],
            )
        })
        .collect()
}

fn check(got: &[Packet<'_>], want: &[(u64, Vec<u8>)]) {
    assert_eq!(got.len(), want.len());
    for (g, (t, data)) in got.iter().zip(want) {
        assert_eq!(g.stamp_ns, Some(*t));
        assert_eq!(g.data, &data[..]);
    }
}

#[test]
fn each_drivers_message_gives_its_packets_and_stamps_in_both_generations() {
    for ros1 in [true, false] {
        let v = some(3, VELODYNE_PACKET);
        let body = msg::velodyne_scan(ros1, 5, &v);
        check(&packets(Kind::VelodyneScan, ros1, &body).unwrap(), &v);
        // Hesai packets are shorter than nebula's 1,500-byte array; both layouts read.
        let h = some(4, 1080);
        for body in [
            msg::pandar_scan(ros1, 5, &h),
            msg::pandar_scan_sized(ros1, 5, &h),
        ] {
            check(&packets(Kind::PandarScan, ros1, &body).unwrap(), &h);
        }
        let o = some(1, 12_544);
        let body = msg::ouster_packet(ros1, &o[0].1);
        let got = packets(Kind::OusterPacket, ros1, &body).unwrap();
        assert_eq!(
            (got.len(), got[0].data, got[0].stamp_ns),
            (1, &o[0].1[..], None)
        );
    }
    let n = some(5, 1_362);
    check(
        &packets(Kind::NebulaPackets, false, &msg::nebula_packets(5, &n)).unwrap(),
        &n,
    );
}

#[test]
fn damaged_messages_are_errors_naming_the_field_never_a_panic() {
    let h = some(2, 1080);
    let mut body = msg::pandar_scan(false, 5, &h);
    // The first packet's size (after the header, count, stamp and 1,500 bytes) says 1,501.
    let at = body.len() - 2 * 1512 + 8 + 1500;
    body[at..at + 4].copy_from_slice(&1501u32.to_le_bytes());
    let e = packets(Kind::PandarScan, false, &body).unwrap_err();
    assert!(e.contains("packets.size 1501"), "{e}");
    for (kind, body) in [
        (
            Kind::VelodyneScan,
            msg::velodyne_scan(false, 5, &some(2, 1206)),
        ),
        (Kind::PandarScan, msg::pandar_scan(false, 5, &h)),
        (Kind::NebulaPackets, msg::nebula_packets(5, &some(2, 100))),
        (Kind::OusterPacket, msg::ouster_packet(false, &[1; 48])),
        (Kind::RobosenseScan, msg::robosense_scan(5, &some(2, 1248))),
        (
            Kind::RobosenseInfo,
            msg::robosense_info("RS", (5, &[3; 1248])),
        ),
    ] {
        for cut in 0..body.len() {
            assert!(
                packets(kind, false, &body[..cut]).is_err(),
                "{kind:?} cut at {cut}"
            );
        }
        let mut long = body.clone();
        long.extend([0; 8]);
        let e = packets(kind, false, &long).unwrap_err();
        assert!(e.contains("after the end"), "{kind:?}: {e}");
    }
    // A count the message cannot hold is refused before anything is allocated for it.
    let mut o = msg::Out::new(true);
    o.header(5);
    o.u32(u32::MAX);
    let e = packets(Kind::VelodyneScan, true, &o.bytes).unwrap_err();
    assert!(e.contains("4294967295 packets cannot fit"), "{e}");
    assert!(packets(Kind::Cloud, true, &o.bytes).is_err());
}
