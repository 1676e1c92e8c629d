//! The RS-M1 decoder on synthetic packets: each return at its own pitch and yaw, times from
//! the packet and block offsets, frames cut where the sequence starts again, and bad input
//! (truncated, another packet kind, late, a return mode changed midway, a time past what a
//! `u64` of microseconds holds) refused and counted.

mod common;

use common::{feed, with, Log};
use kiss_odom_sensors::robosense::m1::{self, Decoder};
use kiss_odom_sensors::{Decode, PacketError, SweepEnd};

/// Packet `seq` at `us` microseconds past 2024-01-01: block `k`, channel `c` at distance
/// 10 m + c, pitch `k - 12` degrees, yaw `2 c` degrees, `k` us after the packet time.
fn packet(seq: u16, us: u64, mode: u8) -> Vec<u8> {
    let mut b = vec![0u8; m1::LEN];
    b[..4].copy_from_slice(&m1::ID);
    b[4..6].copy_from_slice(&seq.to_be_bytes());
    b[8] = mode;
    let t = 1_704_067_200_000_000 + us;
    b[10..16].copy_from_slice(&(t / 1_000_000).to_be_bytes()[2..]);
    b[16..20].copy_from_slice(&((t % 1_000_000) as u32).to_be_bytes());
    for k in 0..m1::BLOCKS {
        let at = 32 + k * 47;
        b[at] = k as u8;
        for c in 0..5 {
            let ch = at + 2 + 9 * c;
            let d = ((10.0 + c as f64) / m1::DISTANCE_RES_M) as u16;
            let pitch = (32768 + (k as i32 - 12) * 100) as u16;
            let yaw = (32768 + 200 * c as i32) as u16;
            b[ch..ch + 2].copy_from_slice(&d.to_be_bytes());
            b[ch + 2..ch + 4].copy_from_slice(&pitch.to_be_bytes());
            b[ch + 4..ch + 6].copy_from_slice(&yaw.to_be_bytes());
            b[ch + 6] = 80;
        }
    }
    b
}

#[test]
fn each_return_lies_at_its_own_pitch_and_yaw() {
    let mut dec = Decoder::new();
    let mut log = Log::default();
    feed(&mut dec, &packet(1, 0, 0x04), &mut log).unwrap();
    dec.finish(&mut log);
    assert_eq!(log.points.len(), 25 * 5);
    let mut worst = 0f64;
    for (i, (_, p, t, m)) in log.points.iter().enumerate() {
        let (k, c) = (i / 5, i % 5);
        let (pitch, yaw) = (
            ((k as f64) - 12.0).to_radians(),
            (2.0 * c as f64).to_radians(),
        );
        let d = 10.0 + c as f64;
        let q = [
            d * pitch.cos() * yaw.cos(),
            d * pitch.cos() * yaw.sin(),
            d * pitch.sin(),
        ];
        worst = worst.max((0..3).map(|j| (p[j] - q[j]).abs()).fold(0.0, f64::max));
        assert!((t - k as f64 * 1e-6).abs() < 1e-12);
        assert_eq!(usize::from(m.ring), c);
    }
    println!("RS-M1: worst |dxyz| {worst:.1e} m (tolerance 1e-9 m)");
    assert!(worst < 1e-9);
}

#[test]
fn a_frame_ends_where_the_sequence_starts_again() {
    let mut dec = Decoder::new();
    let mut log = Log::default();
    for (seq, us) in [(1, 0), (2, 160), (4, 480), (1, 100_000), (2, 100_160)] {
        feed(&mut dec, &packet(seq, us, 0x04), &mut log).unwrap();
    }
    dec.finish(&mut log);
    assert_eq!(log.ends.len(), 2);
    assert_eq!(log.ends[0].end, SweepEnd::NextFrame);
    assert_eq!((log.ends[0].packets, log.ends[0].lost_packets), (3, 1));
    assert_eq!(log.ends[1].packets, 2);
}

#[test]
fn bad_input_is_refused_with_its_reason() {
    let mut dec = Decoder::new();
    let mut log = Log::default();
    let p = packet(5, 1000, 0x04);
    feed(&mut dec, &p, &mut log).unwrap();
    assert_eq!(
        feed(&mut dec, &p[..1000], &mut log),
        Err(PacketError::Truncated)
    );
    // A 1248-byte packet of the spinning models.
    assert_eq!(
        feed(&mut dec, &vec![0u8; 1248], &mut log),
        Err(PacketError::Length)
    );
    assert_eq!(
        feed(&mut dec, &with(&p, 0, 0x56), &mut log),
        Err(PacketError::StartBytes)
    );
    // The same packet again, then one of the same frame from before.
    assert_eq!(feed(&mut dec, &p, &mut log), Err(PacketError::Late));
    // Dual return midway: another sensor's.
    assert_eq!(
        feed(&mut dec, &packet(6, 1160, 0x00), &mut log),
        Err(PacketError::OtherSensor)
    );
    assert_eq!(
        feed(&mut dec, &packet(6, 1160, 0x07), &mut log),
        Err(PacketError::UnknownReturnMode)
    );
    // 2^48 - 1 seconds: more microseconds than a u64 holds.
    let mut far = packet(7, 1320, 0x04);
    far[10..16].fill(0xFF);
    assert_eq!(feed(&mut dec, &far, &mut log), Err(PacketError::DateTime));
    dec.finish(&mut log);
    let s = log.ends.last().unwrap();
    assert_eq!(
        (s.packets, s.bad_packets, s.out_of_order, s.other_sensor),
        (1, 5, 1, 1)
    );
}
