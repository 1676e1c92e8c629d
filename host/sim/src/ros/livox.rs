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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_splits_into_messages_of_its_points_in_turn_each_timed_from_its_first() {
        let frame = Frame {
            index: 0,
            points: (0..10).map(|i| [i as f32, 0.0, 0.0, 0.5]).collect(),
            stamps: (0..10).map(|i| 2.0 + i as f64 * 1e-3).collect(),
            surfaces: Vec::new(),
            end_time: 2.009,
        };
        let parts = custom_messages(Encoding::Ros1, &frame, 3, 4).unwrap();
        // 3, 3 and 4 points; received at their last point's time.
        let received: Vec<u64> = parts.iter().map(|(ns, _)| *ns).collect();
        assert_eq!(received, [2_002_000_000, 2_005_000_000, 2_009_000_000]);
        // The second message: header (4 + 8 + 4 + 11), timebase, point_num 3, id, rsvd,
        // count, then 19 bytes a point: offset_time 0, 1 ms, 2 ms after 2.003 s.
        let body = &parts[1].1;
        let at = 27;
        assert_eq!(body[at..at + 8], 2_003_000_000u64.to_le_bytes());
        assert_eq!(body[at + 8..at + 12], 3u32.to_le_bytes());
        let point = |k: usize| at + 20 + 19 * k;
        assert_eq!(body[point(2)..point(2) + 4], 2_000_000u32.to_le_bytes());
        // x of the first point (3.0), reflectivity 128 (0.5 of 255), line 3 % 4.
        assert_eq!(body[point(0) + 4..point(0) + 8], 3.0f32.to_le_bytes());
        assert_eq!(body[point(0) + 16..point(0) + 19], [128, 0, 3]);
        assert_eq!(body.len(), point(3));
    }
}
