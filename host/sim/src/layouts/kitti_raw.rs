//! KITTI raw: drive `2011_10_03_drive_0027_sync`, which kiss-icp's loader reads as odometry
//! sequence 00. Scans are `velodyne_points/data/NNNNNNNNNN.bin` (float32 x y z intensity)
//! tilted down by the loader's vertical-angle correction, which the loader then undoes; the
//! ground truth is one OXTS packet a scan whose pose, by pykitti's Mercator projection, is
//! `O_0 T_vi^-1 L T_vi` (`T_vi` the IMU-to-Velodyne calibration written beside it), so that
//! the loader's `T_vi inv(O_0) O T_vi^-1` is `L`.

use super::{euler, inverse, matrix, num, put, rigid, translation, Source};
use anyhow::Result;
use nalgebra::{Matrix4, Rotation3};
use std::path::Path;

/// The date folder written.
pub const DATE: &str = "2011_10_03";

/// The drive folder written (odometry sequence 00).
pub const DRIVE: &str = "2011_10_03_drive_0027_sync";

/// pykitti's earth radius (m).
const EARTH_RADIUS: f64 = 6378137.0;

/// The loader's vertical-angle correction (rad).
const VERTICAL_ANGLE_OFFSET: f64 = (0.205 * core::f64::consts::PI) / 180.0;

/// The first packet: latitude, longitude (deg), altitude (m), roll, pitch, yaw (rad).
const FIRST: [f64; 6] = [
    49.011212804408,
    8.4228850417969,
    112.83492279053,
    0.022447,
    1.4e-5,
    -1.2219096732051,
];

/// The IMU-to-Velodyne calibration: a rigid transform close to KITTI's.
pub fn t_velo_imu() -> Matrix4<f64> {
    let r = Rotation3::from_euler_angles(0.0148, 0.0020, -0.00078);
    rigid(r.matrix(), [-0.8086759, 0.3195559, -0.7997231])
}

/// A point tilted down by the correction's angle about `normalize(p x z)`, which the
/// correction turns back up.
fn uncorrect(p: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = p;
    let n = (x * x + y * y).sqrt();
    if n == 0.0 {
        return p;
    }
    let a = [y / n, -x / n, 0.0];
    let (s, c) = VERTICAL_ANGLE_OFFSET.sin_cos();
    // a is perpendicular to p: p cos - (a x p) sin.
    let axp = [
        a[1] * z - a[2] * y,
        a[2] * x - a[0] * z,
        a[0] * y - a[1] * x,
    ];
    [x * c - axp[0] * s, y * c - axp[1] * s, z * c - axp[2] * s]
}

/// pykitti's Mercator position of latitude and longitude (deg) at `scale`.
fn mercator(lat: f64, lon: f64, scale: f64) -> (f64, f64) {
    let pi = core::f64::consts::PI;
    let tx = scale * lon * pi * EARTH_RADIUS / 180.0;
    let ty = scale * EARTH_RADIUS * ((90.0 + lat) * pi / 360.0).tan().ln();
    (tx, ty)
}

/// `YYYY-MM-DD HH:MM:SS.fffffffff` of `t` seconds after 2011-10-03 12:55:34.
fn clock(t: f64) -> String {
    let ns = ((12.0 * 3600.0 + 55.0 * 60.0 + 34.0 + t) * 1e9).round() as u64;
    let s = ns / 1_000_000_000;
    format!(
        "2011-10-03 {:02}:{:02}:{:02}.{:09}",
        s / 3600,
        s / 60 % 60,
        s % 60,
        ns % 1_000_000_000
    )
}

fn calibrations(dir: &Path) -> Result<()> {
    let d = dir.join(DATE);
    let t = t_velo_imu();
    let rows = |m: &Matrix4<f64>| -> (String, String) {
        let r = (0..9)
            .map(|i| num(m[(i / 3, i % 3)]))
            .collect::<Vec<_>>()
            .join(" ");
        (r, translation(m).map(num).join(" "))
    };
    let (r, tr) = rows(&t);
    let imu = format!("calib_time: 25-May-2012 12:47:16\nR: {r}\nT: {tr}\n");
    put(&d.join("calib_imu_to_velo.txt"), imu.as_bytes())?;
    let velo = "calib_time: 15-Mar-2012 11:37:16\nR: 7.533745e-03 -9.999714e-01 -6.166020e-04 \
        1.480249e-02 7.280733e-04 -9.998902e-01 9.998621e-01 7.523790e-03 1.480755e-02\n\
        T: -4.069766e-03 -7.631618e-02 -2.717806e-01\ndelta_f: 0 0\ndelta_c: 0 0\n";
    put(&d.join("calib_velo_to_cam.txt"), velo.as_bytes())?;
    let mut cam = String::from("calib_time: 09-Jan-2012 13:57:47\ncorner_dist: 9.950000e-02\n");
    for (i, bx) in [0.0, -387.5744, 44.85728, -337.2877].iter().enumerate() {
        cam.push_str(&format!("R_rect_0{i}: 1 0 0 0 1 0 0 0 1\n"));
        cam.push_str(&format!(
            "P_rect_0{i}: 721.5377 0 609.5593 {bx} 0 721.5377 172.854 0 0 0 1 0\n"
        ));
    }
    put(&d.join("calib_cam_to_cam.txt"), cam.as_bytes())
}

/// Writes the sequence into `dir`.
pub fn write(dir: &Path, source: &mut Source) -> Result<bool> {
    let drive = dir.join(DATE).join(DRIVE);
    let complete = source.each_frame(|frame| {
        let values = frame.points.iter().flat_map(|p| {
            let q = uncorrect([p[0], p[1], p[2]].map(f64::from));
            [q[0] as f32, q[1] as f32, q[2] as f32, p[3]]
        });
        let path = drive.join(format!("velodyne_points/data/{:010}.bin", frame.index));
        put(&path, &super::f32_bytes(values))
    })?;
    if !complete {
        return Ok(false);
    }
    calibrations(dir)?;
    let [lat0, lon0, alt0, roll0, pitch0, yaw0] = FIRST;
    let scale = (lat0 * core::f64::consts::PI / 180.0).cos();
    let (tx0, ty0) = mercator(lat0, lon0, scale);
    let first = rigid(
        Rotation3::from_euler_angles(roll0, pitch0, yaw0).matrix(),
        [tx0, ty0, alt0],
    );
    let calib = t_velo_imu();
    let calib_inv = inverse(&calib)?;
    let mut times = String::new();
    for k in 0..source.frames {
        let o = first * calib_inv * matrix(&source.truth(k)) * calib;
        let [tx, ty, alt] = translation(&o);
        let pi = core::f64::consts::PI;
        let lon = tx * 180.0 / (scale * pi * EARTH_RADIUS);
        let lat = (ty / (scale * EARTH_RADIUS)).exp().atan() * 360.0 / pi - 90.0;
        let (roll, pitch, yaw) = euler(&o);
        let mut packet: Vec<String> = [lat, lon, alt, roll, pitch, yaw].map(num).to_vec();
        packet.extend(std::iter::repeat_n("0".to_string(), 19));
        packet.extend(["4", "10", "4", "4", "4"].map(String::from));
        let text = packet.join(" ") + "\n";
        put(
            &drive.join(format!("oxts/data/{k:010}.txt")),
            text.as_bytes(),
        )?;
        times.push_str(&clock(source.end_time(k)));
        times.push('\n');
    }
    put(
        &drive.join("velodyne_points/timestamps.txt"),
        times.as_bytes(),
    )?;
    put(&drive.join("oxts/timestamps.txt"), times.as_bytes())?;
    Ok(true)
}
