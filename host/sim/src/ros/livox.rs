//! A Livox sensor's frames as the Livox ROS driver's `CustomMsg` (`simulate --messages
//! livox`): each frame in `parts` messages of consecutive points (the driver publishes at a
//! configurable rate, `publish_freq`; one message a frame is its default, 10 Hz), each with its
//! first point's time as `timebase` and header stamp, every point's time after it as
//! `offset_time`, received when its last point was taken. Times are the nanoseconds `imu.csv`
//! writes ([`Stamp::of`]), so a reader gets the folder's times to the nanosecond.

use super::drivers::{self, CustomPoint};
use super::messages::{Encoding, Stamp};
use crate::sensor::Frame;
use anyhow::{bail, Result};

/// The messages of `frame` split in `parts` (fewer if it has fewer points), each with the time
/// it is received (ns); `lines` lasers fire in turn (the point's `line`).
pub fn custom_messages(
    enc: Encoding,
    frame: &Frame,
    parts: usize,
    lines: u8,
) -> Result<Vec<(u64, Vec<u8>)>> {
    let n = frame.points.len();
    let parts = parts.clamp(1, n.max(1));
    let mut out = Vec::with_capacity(parts);
    for part in 0..parts {
        let range = part * n / parts..(part + 1) * n / parts;
        let Some(&first) = frame.stamps.get(range.start) else {
            continue;
        };
        let ns = |t: f64| match Stamp::of(t) {
            Some(s) => Ok(s.nanos()),
            None => bail!("a point at {t} s cannot be a ROS stamp; use --start-time"),
        };
        let timebase = ns(first)?;
        let mut points: Vec<CustomPoint> = Vec::with_capacity(range.len());
        let mut last = timebase;
        for i in range {
            let t = ns(frame.stamps[i])?;
            last = last.max(t);
            let Ok(offset) = u32::try_from(t.saturating_sub(timebase)) else {
                bail!("a CustomMsg spans more than 4.29 s: split it in more parts");
            };
            let [x, y, z, intensity] = frame.points[i];
            let reflectivity = (intensity.clamp(0.0, 1.0) * 255.0).round() as u8;
            let line = (i % usize::from(lines.max(1))) as u8;
            points.push((offset, [x, y, z], reflectivity, 0, line));
        }
        out.push((last, drivers::custom_msg(enc, timebase, &points)));
    }
    Ok(out)
}
