//! Tests of `imu_msg`: messages written byte by byte from the message definitions.

use super::*;

const GYRO: [f64; 3] = [0.25, -1.5, 3.0e-3];
const ACCEL: [f64; 3] = [0.1, -0.2, 9.80665];

/// The 37 f64 after `frame_id`: orientation 1..4, covariances 90+k, rates and accelerations.
fn block_values() -> Vec<f64> {
    let mut v: Vec<f64> = vec![1.0, 2.0, 3.0, 4.0];
    v.extend((0..9).map(|k| 90.0 + f64::from(k)));
    v.extend(GYRO);
    v.extend((0..9).map(|k| 190.0 + f64::from(k)));
    v.extend(ACCEL);
    v.extend((0..9).map(|k| 290.0 + f64::from(k)));
    v
}

/// ROS 1: seq 7, stamp (sec, nsec), frame id, the block, little-endian and packed.
fn ros1(sec: u32, nsec: u32, frame_id: &str) -> Vec<u8> {
    let mut b = Vec::new();
    for v in [7u32, sec, nsec, frame_id.len() as u32] {
        b.extend(v.to_le_bytes());
    }
    b.extend(frame_id.as_bytes());
    for v in block_values() {
        b.extend(v.to_le_bytes());
    }
    b
}

/// CDR in either byte order: encapsulation, stamp, frame id with its NUL, padding to 8.
fn cdr(sec: i32, nsec: u32, frame_id: &str, be: bool) -> Vec<u8> {
    let w = |v: u32| if be { v.to_be_bytes() } else { v.to_le_bytes() };
    let mut b = vec![0, u8::from(!be), 0, 0];
    b.extend(w(sec as u32));
    b.extend(w(nsec));
    b.extend(w(frame_id.len() as u32 + 1));
    b.extend(frame_id.as_bytes());
    b.push(0);
    while (b.len() - 4) % 8 != 0 {
        b.push(0xee);
    }
    for v in block_values() {
        b.extend(if be { v.to_be_bytes() } else { v.to_le_bytes() });
    }
    b
}

fn expected(sec: u64, nsec: u64) -> ImuSample {
    ImuSample {
        time_ns: sec * 1_000_000_000 + nsec,
        gyro: GYRO,
        accel: ACCEL,
    }
}

#[test]
fn a_ros1_message_gives_its_stamp_rates_and_accelerations() {
    for frame_id in ["", "imu", "imu_link_with_a_long_name"] {
        let msg = ros1(1_700_000_000, 123_456_789, frame_id);
        assert_eq!(msg.len(), 16 + frame_id.len() + 296);
        let s = parse_ros1(&msg).unwrap();
        assert_eq!(
            s,
            expected(1_700_000_000, 123_456_789),
            "frame id {frame_id:?}"
        );
    }
}

#[test]
fn a_cdr_message_in_either_byte_order_gives_the_same_sample() {
    // Frame ids whose end needs 0 to 7 bytes of padding before the f64.
    for frame_id in ["", "i", "im", "imu", "imu_", "imu_l", "imu_li", "imu_lin"] {
        for be in [false, true] {
            let msg = cdr(1_700_000_000, 5, frame_id, be);
            let s = parse_cdr(&msg).unwrap_or_else(|e| panic!("{frame_id:?} be {be}: {e}"));
            assert_eq!(s, expected(1_700_000_000, 5), "{frame_id:?} be {be}");
        }
    }
}

#[test]
fn every_truncation_is_an_error_not_a_panic() {
    let messages = [
        (ros1(1, 2, "imu"), false),
        (cdr(1, 2, "imu", false), true),
        (cdr(1, 2, "imu_link", true), true),
    ];
    for (msg, is_cdr) in messages {
        let parse = if is_cdr { parse_cdr } else { parse_ros1 };
        for n in 0..msg.len() {
            let e = parse(&msg[..n]).unwrap_err();
            assert!(matches!(e, ImuError::Truncated(_)), "{n} bytes: {e}");
        }
        assert!(parse(&msg).is_ok());
    }
    // A frame id longer than the message.
    let mut msg = ros1(1, 2, "imu");
    msg[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = parse_ros1(&msg).unwrap_err();
    assert_eq!(e, ImuError::Truncated("header.frame_id"));
    println!("{e}");
}

#[test]
fn other_messages_and_impossible_stamps_are_refused() {
    let mut long = ros1(1, 2, "imu");
    long.push(0);
    assert_eq!(parse_ros1(&long), Err(ImuError::Trailing(1)));
    // CDR may pad to 4 bytes, no more.
    let mut padded = cdr(1, 2, "imu", false);
    padded.extend([0; 3]);
    assert!(parse_cdr(&padded).is_ok());
    padded.extend([0; 5]);
    assert_eq!(parse_cdr(&padded), Err(ImuError::Trailing(8)));
    let mut xcdr2 = cdr(1, 2, "imu", false);
    xcdr2[1] = 7;
    assert_eq!(parse_cdr(&xcdr2), Err(ImuError::Encapsulation([0, 7])));
    assert_eq!(parse_cdr(&cdr(-1, 2, "imu", false)), Err(ImuError::Stamp));
    assert_eq!(
        parse_ros1(&ros1(1, 1_000_000_000, "imu")),
        Err(ImuError::Stamp)
    );
}
