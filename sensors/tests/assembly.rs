//! Sweep assembly on synthetic packet streams: where sweeps end, what each point's time is,
//! and how lost, late, repeated, foreign and malformed packets are counted.

use kiss_odom_sensors::ouster::{self, SensorInfo};
use kiss_odom_sensors::velodyne::{self, Model};
use kiss_odom_sensors::{
    Chunk, Decode, PacketError, PointMeta, Pushed, SweepEnd, SweepSink, SweepStart, SweepStats,
};
#[path = "common/ouster.rs"]
mod ouster_packets;

use ouster_packets::{ouster_packet, small_ouster};

/// Collects everything a decoder hands on.
#[derive(Default)]
struct Log {
    starts: Vec<SweepStart>,
    ends: Vec<SweepStats>,
    /// (sweep, time, meta) of every point.
    points: Vec<(usize, f64, PointMeta)>,
}

impl SweepSink for Log {
    fn begin_sweep(&mut self, s: &SweepStart) {
        assert_eq!(self.starts.len(), self.ends.len(), "begin inside a sweep");
        self.starts.push(*s);
    }
    fn points(&mut self, c: Chunk<'_>) {
        assert!(c.xyz.len() == c.times.len() && c.times.len() == c.meta.len());
        assert!(!c.xyz.is_empty() && c.xyz.len() <= kiss_odom_sensors::CHUNK);
        let sweep = self.starts.len() - 1;
        for (t, m) in c.times.iter().zip(c.meta) {
            self.points.push((sweep, *t, *m));
        }
    }
    fn end_sweep(&mut self, s: &SweepStats) {
        self.ends.push(*s);
    }
}

/// Pushes `bytes` as a caller must: again when the decoder says a new sweep begins with them.
/// Returns what the last push answered.
fn feed(push: &mut dyn FnMut(&[u8]) -> Result<Pushed, PacketError>, bytes: &[u8]) -> Pushed {
    let first = push(bytes).unwrap();
    if first != Pushed::Again {
        return first;
    }
    let second = push(bytes).unwrap();
    assert_ne!(second, Pushed::Again, "two Again in a row");
    second
}

fn vfeed(dec: &mut velodyne::Decoder, bytes: &[u8], log: &mut Log) -> Pushed {
    feed(&mut |b| dec.push(b, log), bytes)
}

fn ofeed(dec: &mut ouster::Decoder, bytes: &[u8], log: &mut Log) -> Pushed {
    feed(&mut |b| dec.push(b, log), bytes)
}

/// Pushes `bytes`, again when the decoder asks; refusals are returned.
fn push_again(
    dec: &mut ouster::Decoder,
    bytes: &[u8],
    log: &mut Log,
) -> Result<Pushed, PacketError> {
    match dec.push(bytes, log)? {
        Pushed::Again => dec.push(bytes, log),
        done => Ok(done),
    }
}

/// VLP-16 at 10 Hz: 1327.104 us a packet, 0.398 degrees (40 units) a block.
const VLP16_PACKET_US: u32 = 1327;
const BLOCK_UNITS: u32 = 40;

/// A VLP-16 strongest-return packet: block k at azimuth `az0 + 40 k`, every channel at 10 m.
fn vlp16(ts_us: u32, az0: u32) -> [u8; 1206] {
    let mut b = [0u8; 1206];
    for k in 0..12 {
        let at = k * 100;
        b[at..at + 2].copy_from_slice(&[0xFF, 0xEE]);
        let az = ((az0 + BLOCK_UNITS * k as u32) % 36000) as u16;
        b[at + 2..at + 4].copy_from_slice(&az.to_le_bytes());
        for c in 0..32 {
            b[at + 4 + 3 * c..at + 6 + 3 * c].copy_from_slice(&5000u16.to_le_bytes());
        }
    }
    b[1200..1204].copy_from_slice(&ts_us.to_le_bytes());
    b[1204] = 0x37;
    b[1205] = 0x22;
    b
}

/// Packet `i` of a steady 10 Hz VLP-16 stream starting at azimuth 100.00 degrees.
fn nth(i: u32) -> [u8; 1206] {
    vlp16(
        1_000_000 + i * VLP16_PACKET_US,
        10_000 + i * 12 * BLOCK_UNITS,
    )
}

fn velodyne_decoder(cut: Option<f64>) -> velodyne::Decoder {
    velodyne::Decoder::new(velodyne::Config {
        cut_angle_deg: cut,
        ..Default::default()
    })
    .unwrap()
}

#[test]
fn velodyne_sweeps_end_at_the_cut_and_points_take_the_firing_table_times() {
    let mut dec = velodyne_decoder(Some(0.0));
    let mut log = Log::default();
    // 36000 / 480 = 75 packets a turn; 200 packets pass the cut twice.
    let mut ended = 0;
    for i in 0..200 {
        ended += usize::from(vfeed(&mut dec, &nth(i), &mut log) == Pushed::Ended);
    }
    assert_eq!(ended, 2);
    dec.finish(&mut log);
    assert_eq!(dec.model(), Some(Model::Vlp16));
    let ends: Vec<_> = log.ends.iter().map(|s| s.end).collect();
    assert_eq!(
        ends,
        [SweepEnd::Complete, SweepEnd::Complete, SweepEnd::Finished]
    );
    // The first sweep runs from 100 degrees past the cut: packet 54 is the first whose last
    // block is past 360 (10000 + 480 k + 440 >= 36000), and it ends the sweep it belongs to.
    assert_eq!(log.ends[0].packets, 55);
    assert_eq!(log.ends[1].packets, 75);
    for s in &log.ends {
        assert_eq!(s.points, s.packets * 384);
        assert_eq!((s.lost_packets, s.out_of_order, s.bad_packets), (0, 0, 0));
    }
    // Sweep 1 starts at packet 55; its packet 3, block 5, channel 17 (second firing sequence,
    // laser 1) fired 3 packets + 5 x 110.592 + 55.296 + 2.304 us after the sweep start.
    let start = log.starts[1];
    assert_eq!(
        start.start_ns,
        u64::from(1_000_000 + 55 * VLP16_PACKET_US) * 1000
    );
    let t = log
        .points
        .iter()
        .filter(|p| p.0 == 1)
        .nth(3 * 384 + 5 * 32 + 17)
        .unwrap()
        .1;
    let want = (3 * VLP16_PACKET_US) as f64 * 1e-6 + (5.0 * 110.592 + 55.296 + 2.304) * 1e-6;
    assert!((t - want).abs() < 1e-12, "{t} vs {want}");
    // Times never go back within a sweep here, and start at 0.
    for w in log.points.windows(2).filter(|w| w[0].0 == w[1].0) {
        assert!(w[1].1 >= w[0].1);
    }
    assert_eq!(log.points.iter().find(|p| p.0 == 1).unwrap().1, 0.0);
}

#[test]
fn velodyne_losses_late_packets_and_jumps_are_counted_not_patched() {
    let mut dec = velodyne_decoder(None);
    let mut log = Log::default();
    for i in 0..10 {
        if (4..7).contains(&i) {
            continue; // three packets lost
        }
        vfeed(&mut dec, &nth(i), &mut log);
    }
    // A repeated and an older packet: dropped.
    assert_eq!(dec.push(&nth(9), &mut log), Err(PacketError::Late));
    assert_eq!(dec.push(&nth(2), &mut log), Err(PacketError::Late));
    // On time, but the azimuth jumped by 90 degrees.
    dec.push(
        &vlp16(1_000_000 + 10 * VLP16_PACKET_US, 19_000 + 4800),
        &mut log,
    )
    .unwrap();
    dec.finish(&mut log);
    let s = log.ends[0];
    assert_eq!((s.lost_packets, s.out_of_order, s.azimuth_jumps), (3, 2, 1));
    assert_eq!(s.packets, 8);
    assert_eq!(s.last_error, Some(PacketError::Late));
}

#[test]
fn velodyne_other_sensors_and_bad_packets_are_refused_and_counted() {
    let mut dec = velodyne_decoder(None);
    let mut log = Log::default();
    vfeed(&mut dec, &nth(0), &mut log);
    let mut other = nth(1);
    other[1205] = 0x28; // a VLP-32C on the same port
    assert_eq!(dec.push(&other, &mut log), Err(PacketError::OtherSensor));
    let mut dual = nth(1);
    dual[1204] = 0x39; // the same model in another return mode
    assert_eq!(dec.push(&dual, &mut log), Err(PacketError::OtherSensor));
    let mut az = nth(1);
    az[302..304].copy_from_slice(&36001u16.to_le_bytes());
    assert_eq!(dec.push(&az, &mut log), Err(PacketError::Azimuth));
    assert_eq!(
        dec.push(&nth(1)[..600], &mut log),
        Err(PacketError::Truncated)
    );
    let mut flag = nth(1);
    flag[500] = 0;
    assert_eq!(dec.push(&flag, &mut log), Err(PacketError::BlockFlag));
    vfeed(&mut dec, &nth(1), &mut log);
    dec.finish(&mut log);
    let s = log.ends[0];
    assert_eq!((s.packets, s.other_sensor, s.bad_packets), (2, 2, 3));

    // Before any packet decoded: an unknown product byte, an unknown return mode.
    let mut fresh = velodyne_decoder(None);
    let mut unknown = nth(0);
    unknown[1205] = 0x99;
    assert_eq!(
        fresh.push(&unknown, &mut log),
        Err(PacketError::UnknownModel)
    );
    let mut mode = nth(0);
    mode[1204] = 0x10;
    assert_eq!(
        fresh.push(&mode, &mut log),
        Err(PacketError::UnknownReturnMode)
    );
    // Those go to the next sweep's statistics.
    vfeed(&mut fresh, &nth(0), &mut log);
    fresh.finish(&mut log);
    assert_eq!(log.ends.last().unwrap().bad_packets, 2);
}

#[test]
fn velodyne_a_silence_ends_the_sweep() {
    let mut dec = velodyne_decoder(None);
    let mut log = Log::default();
    vfeed(&mut dec, &nth(0), &mut log);
    vfeed(&mut dec, &nth(1), &mut log);
    // 0.4 s later (the sensor stopped, or the capture has a hole).
    let late = vlp16(1_000_000 + 400_000, 0);
    // The open sweep ends first, alone; the packet then begins the next.
    assert_eq!(dec.push(&late, &mut log), Ok(Pushed::Again));
    assert_eq!((log.starts.len(), log.ends.len()), (1, 1));
    assert_eq!(dec.push(&late, &mut log), Ok(Pushed::Decoded));
    dec.finish(&mut log);
    let ends: Vec<_> = log.ends.iter().map(|s| s.end).collect();
    assert_eq!(ends, [SweepEnd::Gap, SweepEnd::Finished]);
}

#[test]
fn velodyne_configuration_is_checked() {
    assert!(velodyne::Decoder::new(velodyne::Config {
        cut_angle_deg: Some(360.0),
        ..Default::default()
    })
    .is_err());
    let mut calib = velodyne::Calibration::nominal(Model::Vlp16);
    assert!(velodyne::Decoder::new(velodyne::Config {
        model: Some(Model::Vlp32c),
        calibration: Some(calib.clone()),
        ..Default::default()
    })
    .is_err());
    calib.lasers[3].vertical_deg = f64::NAN;
    assert!(velodyne::Decoder::new(velodyne::Config {
        calibration: Some(calib),
        ..Default::default()
    })
    .is_err());
}

#[test]
fn ouster_sweeps_follow_frame_ids_and_times_follow_the_columns() {
    let info = small_ouster();
    let mut dec = ouster::Decoder::new(&info).unwrap();
    let mut log = Log::default();
    for fid in [7u16, 8] {
        for k in 0..4 {
            ofeed(&mut dec, &ouster_packet(fid, k, 1234), &mut log);
        }
    }
    dec.finish(&mut log);
    assert_eq!(log.ends.len(), 2);
    for (s, fid) in log.ends.iter().zip([7, 8]) {
        assert_eq!(
            s.end,
            SweepEnd::Complete,
            "the last column closes the sweep"
        );
        assert_eq!((s.frame_id, s.packets, s.points), (Some(fid), 4, 128));
        assert_eq!((s.lost_packets, s.out_of_order), (0, 0));
    }
    assert_eq!(log.starts[1].start_ns, 5_000_000_000 + 8 * 100_000_000);
    // Column 37 of a frame was captured 3.7 ms after column 0.
    let (_, t, m) = log
        .points
        .iter()
        .find(|p| p.0 == 1 && p.2.column == 37)
        .unwrap();
    assert!((t - 0.0037).abs() < 1e-12 && m.ring == 0);
    assert_eq!(info.destaggered_column(0, 62), Some(2));
}

#[test]
fn ouster_lost_late_and_foreign_packets_are_counted() {
    let info = small_ouster();
    let mut dec = ouster::Decoder::new(&info).unwrap();
    let mut log = Log::default();
    ofeed(&mut dec, &ouster_packet(7, 0, 1234), &mut log);
    ofeed(&mut dec, &ouster_packet(7, 2, 1234), &mut log); // packet 1 lost
                                                           // Another sensor's packet (serial differs): the metadata is not its.
    assert_eq!(
        dec.push(&ouster_packet(7, 1, 999), &mut log),
        Err(PacketError::MetadataMismatch)
    );
    // Frame 8 begins before frame 7's last packet: 7 ends with 2 packets lost.
    ofeed(&mut dec, &ouster_packet(8, 0, 1234), &mut log);
    // Frame 7's last packet arrives late.
    assert_eq!(
        dec.push(&ouster_packet(7, 3, 1234), &mut log),
        Err(PacketError::Late)
    );
    // Frames 9 and 10 never arrive.
    for k in 1..4 {
        ofeed(&mut dec, &ouster_packet(8, k, 1234), &mut log);
    }
    ofeed(&mut dec, &ouster_packet(11, 3, 1234), &mut log);
    dec.finish(&mut log);
    let [a, b, c] = [log.ends[0], log.ends[1], log.ends[2]];
    assert_eq!(
        (a.end, a.lost_packets, a.other_sensor),
        (SweepEnd::NextFrame, 2, 1)
    );
    assert_eq!(
        (b.end, b.lost_packets, b.out_of_order),
        (SweepEnd::Complete, 0, 1)
    );
    // 2 frames of 4 packets skipped, plus the 3 packets of frame 11 before the one received.
    assert_eq!((c.frame_id, c.lost_packets), (Some(11), 8 + 3));
    // A measurement id beyond the frame: metadata of another mode.
    let mut wide = ouster_packet(12, 0, 1234);
    wide[32 + 8..32 + 10].copy_from_slice(&64u16.to_le_bytes());
    assert_eq!(
        dec.push(&wide, &mut log),
        Err(PacketError::MeasurementId {
            id: 64,
            columns: 64
        })
    );
    assert_eq!(
        dec.push(&ouster_packet(12, 0, 1234)[..100], &mut log),
        Err(PacketError::Truncated)
    );
}

#[test]
fn ouster_metadata_that_cannot_decode_is_refused() {
    let mut info = small_ouster();
    info.columns_per_frame = 0;
    assert!(ouster::Decoder::new(&info).is_err());
    let mut info = small_ouster();
    info.beam_azimuth_deg.pop();
    assert!(ouster::Decoder::new(&info).is_err());
    let mut info = small_ouster();
    info.lidar_to_sensor[3] = f64::INFINITY;
    assert!(ouster::Decoder::new(&info).is_err());
}

#[test]
fn velodyne_a_clock_that_jumps_and_stays_is_taken_after_a_run_of_late_packets() {
    use kiss_odom_sensors::RESYNC_PACKETS;
    let mut dec = velodyne_decoder(None);
    let mut log = Log::default();
    for i in 0..10 {
        vfeed(&mut dec, &nth(i), &mut log);
    }
    // 40 minutes on: half an hour back on the hour-long clock, so older than the sweep.
    let jumped = |i: u32| {
        let mut p = nth(i);
        let t = u32::from_le_bytes(p[1200..1204].try_into().unwrap()) + 2_400_000_000;
        p[1200..1204].copy_from_slice(&(t % 3_600_000_000).to_le_bytes());
        p
    };
    for i in 10..10 + RESYNC_PACKETS - 1 {
        assert_eq!(dec.push(&jumped(i), &mut log), Err(PacketError::Late));
    }
    // The next one in the run ends the sweep, and its clock is the decoder's now.
    let i = 10 + RESYNC_PACKETS - 1;
    assert_eq!(vfeed(&mut dec, &jumped(i), &mut log), Pushed::Decoded);
    for i in i + 1..i + 20 {
        assert_eq!(vfeed(&mut dec, &jumped(i), &mut log), Pushed::Decoded);
    }
    dec.finish(&mut log);
    let [old, new] = [log.ends[0], log.ends[1]];
    assert_eq!(
        (old.end, old.packets, old.out_of_order),
        (SweepEnd::Resync, 10, 15)
    );
    assert_eq!((new.resyncs, new.packets, new.lost_packets), (1, 20, 0));
    // Late packets that do not agree among themselves (repeats of old ones) never do.
    let mut dec = velodyne_decoder(None);
    for i in 0..30 {
        vfeed(&mut dec, &nth(i), &mut log);
    }
    for _ in 0..3 * RESYNC_PACKETS {
        assert_eq!(dec.push(&nth(5), &mut log), Err(PacketError::Late));
    }
}

#[test]
fn velodyne_a_configured_model_overrides_the_product_byte_and_losses_follow_the_packets() {
    // VLP-16 packets whose product byte says HDL-32E (0x21), as some units write.
    let hdl = |i: u32| {
        let mut p = nth(i);
        p[1205] = 0x21;
        p
    };
    let mut log = Log::default();
    let mut by_byte = velodyne_decoder(None);
    for i in (0..40).filter(|i| *i != 20) {
        vfeed(&mut by_byte, &hdl(i), &mut log);
    }
    by_byte.finish(&mut log);
    assert_eq!(by_byte.model(), Some(Model::Hdl32e));
    // An HDL-32E sends a packet every 553 us; these come 1327 us apart: losses are counted
    // by the packets' spacing, so only the one missing packet is.
    assert_eq!(by_byte.shortest_step_us(), Some(VLP16_PACKET_US));
    assert!((by_byte.packet_us().unwrap() - 552.96).abs() < 1e-9);
    assert_eq!(log.ends.iter().map(|s| s.lost_packets).sum::<u32>(), 1);
    let mut given = velodyne::Decoder::new(velodyne::Config {
        model: Some(Model::Vlp16),
        ..Default::default()
    })
    .unwrap();
    let mut log = Log::default();
    for i in 0..3 {
        vfeed(&mut given, &hdl(i), &mut log);
    }
    assert_eq!(given.model(), Some(Model::Vlp16));
    // A packet with another product byte than the first is another sensor's.
    assert_eq!(given.push(&nth(3), &mut log), Err(PacketError::OtherSensor));
}

/// `small_ouster` with its real column spacing for the rate: 100 us a column of 64 is
/// 156.25 turns a second, so the check needs the rate said.
fn timed_ouster(hz: u16) -> SensorInfo {
    SensorInfo {
        frequency_hz: Some(hz),
        ..small_ouster()
    }
}

#[test]
fn ouster_packets_that_contradict_the_metadata_are_refused() {
    let mut log = Log::default();
    // Columns 100 us apart: 156 turns a second at 64 columns; 10 Hz is another mode.
    let mut dec = ouster::Decoder::new(&timed_ouster(10)).unwrap();
    assert_eq!(
        dec.push(&ouster_packet(7, 0, 1234), &mut log),
        Err(PacketError::ColumnRate)
    );
    let mut dec = ouster::Decoder::new(&timed_ouster(156)).unwrap();
    let mut log = Log::default();
    assert_eq!(
        ofeed(&mut dec, &ouster_packet(7, 0, 1234), &mut log),
        Pushed::Decoded
    );
    // A window of columns 0..=20: the packet of columns 16..31 carries valid ones beyond.
    let mut info = small_ouster();
    info.column_window = (0, 20);
    let mut dec = ouster::Decoder::new(&info).unwrap();
    let mut log = Log::default();
    ofeed(&mut dec, &ouster_packet(7, 0, 1234), &mut log);
    assert_eq!(
        dec.push(&ouster_packet(7, 1, 1234), &mut log),
        Err(PacketError::ColumnWindow)
    );
}

#[test]
fn ouster_a_restart_or_a_frame_id_far_ahead_is_resynchronised() {
    use kiss_odom_sensors::RESYNC_PACKETS;
    let info = small_ouster();
    // Frame 9's second packet says frame 1009: it opens a frame the rest never join.
    let mut dec = ouster::Decoder::new(&info).unwrap();
    let mut log = Log::default();
    for k in 0..4 {
        ofeed(&mut dec, &ouster_packet(8, k, 1234), &mut log);
    }
    ofeed(&mut dec, &ouster_packet(9, 0, 1234), &mut log);
    ofeed(&mut dec, &ouster_packet(1009, 1, 1234), &mut log);
    let mut refused = 0;
    for fid in 9..20u16 {
        for k in 0..4 {
            match push_again(&mut dec, &ouster_packet(fid, k, 1234), &mut log) {
                Err(PacketError::Late) => refused += 1,
                r => assert!(r.is_ok(), "{r:?}"),
            }
        }
    }
    dec.finish(&mut log);
    assert_eq!(refused, RESYNC_PACKETS - 1);
    let resync = log
        .ends
        .iter()
        .position(|s| s.end == SweepEnd::Resync)
        .unwrap();
    let far = log.ends[resync];
    // The frame far ahead: its one packet; the 1000 frame ids it skipped were never lost.
    assert_eq!(
        (far.frame_id, far.packets, far.lost_packets),
        (Some(1009), 1, 0)
    );
    assert_eq!(log.ends[resync + 1].resyncs, 1);
    assert!(log
        .ends
        .iter()
        .skip(resync + 2)
        .all(|s| s.lost_packets == 0));

    // A restart: frame ids from 0 again after frame 9.
    let mut dec = ouster::Decoder::new(&info).unwrap();
    let mut log = Log::default();
    for fid in 8..10u16 {
        for k in 0..4 {
            ofeed(&mut dec, &ouster_packet(fid, k, 1234), &mut log);
        }
    }
    let mut decoded = 0;
    for fid in 0..8u16 {
        for k in 0..4 {
            match push_again(&mut dec, &ouster_packet(fid, k, 1234), &mut log) {
                Ok(_) => decoded += 1,
                Err(e) => assert_eq!(e, PacketError::Late),
            }
        }
    }
    assert_eq!(decoded, 32 - (RESYNC_PACKETS - 1));
}

#[test]
fn ouster_transforms_and_angles_out_of_physics_are_refused() {
    use kiss_odom_sensors::ConfigError;
    let mut info = small_ouster();
    info.lidar_to_sensor[0] = 1.5;
    assert_eq!(info.validate(), Err(ConfigError::LidarToSensor));
    let mut info = small_ouster();
    info.lidar_to_sensor[14] = 1.0;
    assert_eq!(info.validate(), Err(ConfigError::LidarToSensor));
    let mut info = small_ouster();
    // A reflection is orthonormal but not a rotation.
    info.lidar_to_sensor[10] = -1.0;
    assert_eq!(info.validate(), Err(ConfigError::LidarToSensor));
    let mut info = small_ouster();
    info.beam_to_lidar[3] = 5000.0;
    assert_eq!(info.validate(), Err(ConfigError::BeamToLidar));
    let mut info = small_ouster();
    info.beam_altitude_deg[0] = 91.0;
    assert_eq!(info.validate(), Err(ConfigError::BeamAltitude));
    let mut info = small_ouster();
    info.beam_azimuth_deg[1] = -46.0;
    assert_eq!(info.validate(), Err(ConfigError::BeamAzimuth));
    // The OS sensors' own: a half turn about z, 36.18 mm up.
    let mut info = small_ouster();
    info.lidar_to_sensor = [
        -1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 36.18, 0.0, 0.0, 0.0, 1.0,
    ];
    assert_eq!(info.validate(), Ok(()));
}
