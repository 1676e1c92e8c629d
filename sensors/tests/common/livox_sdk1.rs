//! The Livox SDK 1 packets the tests decode: every data type, each firing at a known place.

use kiss_odom_sensors::livox::sdk1;

/// A packet of `data_type` at `t` ns whose firing `k` returns the point (1 + k, 2, -0.5) m
/// (the second return twice as far), reflectivity k and tag 16; firing 3 returns nothing.
pub fn packet(data_type: u8, t: u64) -> Vec<u8> {
    let (size, n) = sdk1::layout(data_type).unwrap();
    let mut b = vec![0u8; 18 + size * n];
    b[0..4].copy_from_slice(&[5, 1, 1, 0]);
    b[8] = 1;
    b[9] = data_type;
    b[10..18].copy_from_slice(&t.to_le_bytes());
    for k in 0..n {
        if k == 3 {
            continue;
        }
        let at = 18 + size * k;
        let p = &mut b[at..at + size];
        let mm = |v: f64| ((v * 1000.0).round() as i32).to_le_bytes();
        let xyz = [1.0 + k as f64, 2.0, -0.5];
        let cart = |p: &mut [u8], s: f64| {
            for (i, v) in xyz.iter().enumerate() {
                p[4 * i..4 * i + 4].copy_from_slice(&mm(v * s));
            }
            p[12] = k as u8;
        };
        let r = (xyz[0] * xyz[0] + xyz[1] * xyz[1] + xyz[2] * xyz[2]).sqrt();
        let zenith = ((xyz[2] / r).acos().to_degrees() * 100.0).round() as u16;
        let azimuth = (xyz[1].atan2(xyz[0]).to_degrees() * 100.0).round() as u16;
        let depth = |s: f64| ((r * s * 1000.0).round() as u32).to_le_bytes();
        match data_type {
            0 => cart(p, 1.0),
            2 => {
                cart(p, 1.0);
                p[13] = 16;
            }
            4 => {
                cart(p, 1.0);
                p[13] = 16;
                cart(&mut p[14..], 2.0);
                p[27] = 16;
            }
            1 | 3 => {
                p[0..4].copy_from_slice(&depth(1.0));
                p[4..6].copy_from_slice(&zenith.to_le_bytes());
                p[6..8].copy_from_slice(&azimuth.to_le_bytes());
                p[8] = k as u8;
                if data_type == 3 {
                    p[9] = 16;
                }
            }
            5 => {
                p[0..2].copy_from_slice(&zenith.to_le_bytes());
                p[2..4].copy_from_slice(&azimuth.to_le_bytes());
                p[4..8].copy_from_slice(&depth(1.0));
                p[8] = k as u8;
                p[9] = 16;
                p[10..14].copy_from_slice(&depth(2.0));
                p[14] = k as u8;
                p[15] = 16;
            }
            _ => {}
        }
    }
    b
}
