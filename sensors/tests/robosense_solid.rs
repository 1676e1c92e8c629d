//! The RS-M1 and E1R decoder on synthetic packets: each return at its own direction (the M1's
//! pitch and yaw, the E1R's vector), times from the packet and block offsets, frames cut where
//! the sequence starts again, and bad input (truncated, another packet kind, late, a return
//! mode changed midway, a time past what a `u64` of microseconds holds, the E1R's dual
//! return) refused and counted.

mod common;

use common::{feed, with, Log};
use kiss_odom_sensors::robosense::solid::{self, Decoder, Model};
use kiss_odom_sensors::{Decode, PacketError, SweepEnd};

/// A `model` packet's bytes with only its header: id, sequence number `seq`, return `mode`, a
/// time `us` microseconds past 2024-01-01.
fn header(model: Model, seq: u16, us: u64, mode: u8) -> Vec<u8> {
    let mut b = vec![0u8; model.packet_len()];
    b[..4].copy_from_slice(&solid::ID);
    b[4..6].copy_from_slice(&seq.to_be_bytes());
    b[8] = mode;
    let t = 1_704_067_200_000_000 + us;
    b[10..16].copy_from_slice(&(t / 1_000_000).to_be_bytes()[2..]);
    b[16..20].copy_from_slice(&((t % 1_000_000) as u32).to_be_bytes());
    b
}

/// Packet `seq` at `us` microseconds past 2024-01-01: block `k`, channel `c` at distance
/// 10 m + c, pitch `k - 12` degrees, yaw `2 c` degrees, `k` us after the packet time.
fn packet(seq: u16, us: u64, mode: u8) -> Vec<u8> {
    let mut b = header(Model::M1, seq, us, mode);
    for k in 0..Model::M1.blocks() {
        let at = 32 + k * 47;
        b[at] = k as u8;
        for c in 0..5 {
            let ch = at + 2 + 9 * c;
            let d = ((10.0 + c as f64) / solid::DISTANCE_RES_M) as u16;
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
    let mut dec = Decoder::new(Model::M1);
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
    let mut dec = Decoder::new(Model::M1);
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
    let mut dec = Decoder::new(Model::M1);
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

/// An E1R packet at `us` past 2024-01-01: block `k` one return at 20 m + k cm along the
/// direction (cos a, sin a, 0.1) scaled to 32768ths, a = k degrees, 3 k us after the packet.
fn e1r_packet(seq: u16, us: u64, mode: u8) -> Vec<u8> {
    let mut b = header(Model::E1r, seq, us, mode);
    for k in 0..Model::E1r.blocks() {
        let at = 32 + k * 12;
        b[at..at + 2].copy_from_slice(&(3 * k as u16).to_be_bytes());
        let d = ((20.0 + 0.01 * k as f64) / solid::DISTANCE_RES_M).round() as u16;
        b[at + 2..at + 4].copy_from_slice(&d.to_be_bytes());
        let a = (k as f64).to_radians();
        for (i, v) in [a.cos(), a.sin(), 0.1].iter().enumerate() {
            let x = (v * 32768.0).round().min(32767.0) as i16;
            b[at + 4 + 2 * i..at + 6 + 2 * i].copy_from_slice(&x.to_be_bytes());
        }
        b[at + 10] = 50;
    }
    b
}

#[test]
fn each_e1r_return_lies_along_its_vector_and_dual_return_is_refused() {
    let mut dec = Decoder::new(Model::E1r);
    let mut log = Log::default();
    feed(&mut dec, &e1r_packet(1, 0, 0x04), &mut log).unwrap();
    dec.finish(&mut log);
    assert_eq!(log.points.len(), 96);
    let mut worst = 0f64;
    for (k, (_, p, t, m)) in log.points.iter().enumerate() {
        let a = (k as f64).to_radians();
        let d = ((20.0 + 0.01 * k as f64) / 0.005).round() * 0.005;
        let v = [a.cos(), a.sin(), 0.1].map(|v| (v * 32768.0f64).round().min(32767.0) / 32768.0);
        let q = v.map(|v| v * d);
        worst = worst.max((0..3).map(|j| (p[j] - q[j]).abs()).fold(0.0, f64::max));
        assert!((t - 3.0 * k as f64 * 1e-6).abs() < 1e-12);
        assert_eq!((m.ring, m.intensity), (0, 50));
    }
    println!("E1R: worst |dxyz| {worst:.1e} m (tolerance 1e-9 m)");
    assert!(worst < 1e-9);
    // Its dual-return packets say no return order; an M1's packet is another length.
    let mut dec = Decoder::new(Model::E1r);
    let mut log = Log::default();
    let dual = feed(&mut dec, &e1r_packet(1, 0, 0x00), &mut log);
    assert_eq!(dual, Err(PacketError::DualNotDecoded));
    assert_eq!(
        feed(&mut dec, &packet(1, 0, 0x04), &mut log),
        Err(PacketError::Length)
    );
    assert_eq!(Model::of(&e1r_packet(1, 0, 4)), Some(Model::E1r));
    assert_eq!(Model::of(&packet(1, 0, 4)), Some(Model::M1));
}
