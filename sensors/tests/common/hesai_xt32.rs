//! The PandarXT-32 (protocol 6.1) packets the Hesai tests decode: a packet of any azimuth,
//! time, return mode and sequence number, and the decoder of the nominal XT32.

use kiss_odom_sensors::hesai::{self, wire::field};

/// What [`packet`] builds.
pub struct Spec {
    /// Azimuth of the first firing and the step from firing to firing, 0.01 degree.
    pub azimuth: u16,
    pub step: u16,
    /// Microseconds within the second.
    pub us: u32,
    pub mode: u8,
    pub sequence: Option<u32>,
}

impl Spec {
    pub fn new(azimuth: u16, us: u32) -> Self {
        Self {
            azimuth,
            step: 18,
            us,
            mode: 0x37,
            sequence: None,
        }
    }
}

/// A packet whose every channel `c` of firing `f` returns `(100 + c + f) * 4 mm`, except that
/// channel 5 returns nothing.
pub fn packet(s: &Spec) -> Vec<u8> {
    let returns: u8 = if matches!(s.mode, 0x39 | 0x3B | 0x3C) {
        2
    } else {
        1
    };
    let len = if s.sequence.is_some() {
        field::LEN_WITH_SEQUENCE
    } else {
        field::LEN
    };
    let mut b = vec![0u8; len];
    b[0..6].copy_from_slice(&[0xEE, 0xFF, 6, 1, 0, 0]);
    b[6..12].copy_from_slice(&[32, 8, 0, 4, returns, u8::from(s.sequence.is_some())]);
    for k in 0..8 {
        let firing = k / usize::from(returns);
        let at = 12 + 130 * k;
        let az = (u32::from(s.azimuth) + u32::from(s.step) * firing as u32) % 36000;
        b[at..at + 2].copy_from_slice(&(az as u16).to_le_bytes());
        for c in 0..32 {
            let ch = at + 2 + 4 * c;
            let mut d = if c == 5 {
                0
            } else {
                100 + c as u16 + firing as u16
            };
            // In dual mode the second block of a pair differs on even channels only.
            if returns == 2 && k % 2 == 1 && c % 2 == 0 && d != 0 {
                d += 1000;
            }
            b[ch..ch + 2].copy_from_slice(&d.to_le_bytes());
            b[ch + 2] = c as u8;
        }
    }
    b[field::RETURN_MODE] = s.mode;
    b[field::MOTOR_SPEED].copy_from_slice(&600u16.to_le_bytes());
    b[field::DATE_TIME].copy_from_slice(&[124, 9, 17, 15, 47, 12]);
    b[field::MICROSECONDS].copy_from_slice(&s.us.to_le_bytes());
    b[field::MICROSECONDS.end] = 0x42;
    if let Some(q) = s.sequence {
        b[field::UDP_SEQUENCE].copy_from_slice(&q.to_le_bytes());
    }
    b
}

/// A decoder of the XT32 with its nominal angles.
pub fn decoder() -> hesai::Decoder {
    hesai::Decoder::new(hesai::Config::default()).unwrap()
}
