//! The PandarQT128 (protocol 3.2) and Pandar128/OT128 (protocol 1.4) packets the Hesai tests
//! decode: layouts from the header flags, CRCs sealed, and a calibration of 128 channels.

use kiss_odom_sensors::hesai::{self, wire128, Calibration, Model};

/// What [`packet`] builds: [`Spec::qt`] a QT128C2X's packet, [`Spec::p128`] a Pandar128E3X's
/// or OT128's.
pub struct Spec {
    pub version: (u8, u8),
    pub flags: u8,
    pub azimuth: u16,
    pub us: u32,
    pub mode: u8,
    pub mode_flag: u8,
    pub operational_state: u8,
    pub azimuth_states: u16,
    pub sequence: u32,
}

impl Spec {
    pub fn qt(azimuth: u16, us: u32) -> Self {
        Self {
            version: wire128::VERSION_QT,
            // Sequence, safety, signature, confidence: the QT128C2X's 1127 bytes.
            flags: 0x1D,
            azimuth,
            us,
            mode: 0x37,
            mode_flag: 1,
            operational_state: 0,
            azimuth_states: 0,
            sequence: 0,
        }
    }
    pub fn p128(azimuth: u16, us: u32) -> Self {
        Self {
            version: wire128::VERSION_128,
            // Sequence, IMU, safety: 861 bytes.
            flags: 0x07,
            operational_state: 2,
            azimuth_states: 0b01 << 12,
            ..Self::qt(azimuth, us)
        }
    }
}

/// Where the tail begins for the flags of `s` (the layout `wire128`'s module doc gives).
pub fn tail_at(s: &Spec) -> usize {
    let unit = unit_len(s);
    let safety = if s.flags & 4 != 0 { 17 } else { 0 };
    12 + 2 * (2 + 128 * unit) + 4 + safety
}

/// Bytes of a channel unit for the version and flags of `s`.
pub fn unit_len(s: &Spec) -> usize {
    let extra = if s.version == wire128::VERSION_128 {
        (s.flags >> 4 & 7).count_ones() as usize
    } else {
        usize::from(s.flags & 0x10 != 0)
    };
    3 + extra
}

/// The azimuth step from firing to firing at the packets' 600 rpm, 0.01 degree: the QT128's
/// 111.11 us firings 0.4 degree apart, protocol 1.4's standard 55.556 us (high resolution
/// 27.778 us) firings 0.2 (0.1) degree apart.
pub fn step(s: &Spec) -> u32 {
    match (s.version, s.operational_state) {
        (wire128::VERSION_QT, _) => 40,
        (_, 0) => 10,
        _ => 20,
    }
}

/// A packet whose channel `c` of block `k` returns `(200 + c + 1000 k) * 4 mm` on even
/// channels and `(200 + c) * 4 mm` on odd ones (a dual pair's blocks agree on odd channels),
/// except that channel 9 returns nothing.
pub fn packet(s: &Spec) -> Vec<u8> {
    let returns: u8 = if matches!(s.mode, 0x39 | 0x3B | 0x3C) {
        2
    } else {
        1
    };
    let mut b = vec![0u8; wire128::packet_len(s.version, s.flags)];
    b[0..4].copy_from_slice(&[0xEE, 0xFF, s.version.0, s.version.1]);
    b[6..12].copy_from_slice(&[128, 2, 1, 4, returns, s.flags]);
    let unit = unit_len(s);
    for k in 0..2 {
        let firing = k / usize::from(returns);
        let at = 12 + (2 + 128 * unit) * k;
        let az = (u32::from(s.azimuth) + step(s) * firing as u32) % 36000;
        b[at..at + 2].copy_from_slice(&(az as u16).to_le_bytes());
        for c in 0..128 {
            let ch = at + 2 + unit * c;
            let d = match c {
                9 => 0,
                c if c % 2 == 0 => 200 + c as u16 + 1000 * k as u16,
                c => 200 + c as u16,
            };
            b[ch..ch + 2].copy_from_slice(&d.to_le_bytes());
            b[ch + 2] = c as u8;
        }
    }
    let t = tail_at(s);
    b[t + 5] = s.mode_flag;
    b[t + 9..t + 11].copy_from_slice(&s.azimuth_states.to_le_bytes());
    b[t + 11] = s.operational_state;
    b[t + 12] = s.mode;
    b[t + 13..t + 15].copy_from_slice(&600u16.to_le_bytes());
    b[t + 15..t + 21].copy_from_slice(&[124, 10, 30, 7, 36, 29]);
    b[t + 21..t + 25].copy_from_slice(&s.us.to_le_bytes());
    if s.flags & 1 != 0 {
        b[t + 26..t + 30].copy_from_slice(&s.sequence.to_le_bytes());
    }
    seal(&mut b)
}

/// `b` with its body and tail CRCs computed.
pub fn seal(b: &mut [u8]) -> Vec<u8> {
    for (covered, at) in wire128::crc_ranges((b[2], b[3]), b[11]) {
        let crc = wire128::crc32_mpeg2(&b[covered]);
        b[at..at + 4].copy_from_slice(&crc.to_le_bytes());
    }
    b.to_vec()
}

/// A calibration of channel `c` at elevation `40 - 0.625 c` and azimuth offset `0.01 c - 0.5`.
pub fn calibration() -> Calibration {
    let mut c = Calibration::nominal();
    c.channels = 128;
    for i in 0..128 {
        c.elevation_deg[i] = 40.0 - 0.625 * i as f64;
        c.azimuth_deg[i] = 0.01 * i as f64 - 0.5;
    }
    c
}

/// A decoder of `model` with [`calibration`].
pub fn decoder(model: Model) -> hesai::Decoder {
    hesai::Decoder::new(hesai::Config {
        model,
        calibration: Some(calibration()),
        ..hesai::Config::default()
    })
    .unwrap()
}
