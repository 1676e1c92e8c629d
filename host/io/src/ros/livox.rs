//! Livox's own point messages, `livox_ros_driver/CustomMsg` and `livox_ros_driver2/CustomMsg`
//! (what the Livox drivers publish for LIO pipelines, with `xfer_format` 1), as frames.
//!
//! A message holds a header, `timebase` (ns, the sensor-clock time of its first point),
//! `point_num`, and its points, each `offset_time` (ns after `timebase`), x, y, z (m, float32),
//! `reflectivity`, `tag` and `line`. Each point's time is `timebase + offset_time` on the
//! sensor's clock, the clock of the IMU the driver publishes beside it (`--imu`): a frame's
//! stamps are seconds after its first message's `timebase`, and it ends (`Frame::end`) at its
//! latest point. The
//! drivers publish at a configurable rate (`publish_freq`, 10 Hz by default): each message is
//! a frame, or with `input.frame_period` the messages whose first points fall in one period are
//! merged into one frame (periods counted from the first message, a message placed in the
//! period its first point is nearest the start of, within half the messages' spacing). A
//! message whose `point_num` disagrees with its points, or that does not parse, is a skipped
//! frame (merged: left out of its frame with a warning).

use super::kinds::Kind;
use super::pointcloud2::{stamp_of_nanos, Stamp};
use super::recording::{MessageStream, Recording};
use super::serial::Reader;
use crate::dataset::{Frame, FrameSource, Item, OpenOptions};
use anyhow::{bail, Result};

/// One point of a `CustomMsg`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CustomPoint {
    /// Time after the message's `timebase`, ns.
    pub offset_time: u32,
    /// x, y, z in metres, sensor frame.
    pub xyz: [f32; 3],
    /// Reflectivity, 0 to 255.
    pub reflectivity: u8,
    /// Livox's tag (return number, noise flags).
    pub tag: u8,
    /// The laser that fired it.
    pub line: u8,
}

/// A `CustomMsg`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CustomMsg {
    /// `header.stamp`.
    pub stamp: Stamp,
    /// Sensor-clock time of the first point, ns.
    pub timebase: u64,
    /// The points the message says it holds.
    pub point_num: u32,
    /// The sensor's id.
    pub lidar_id: u8,
    /// The points.
    pub points: Vec<CustomPoint>,
}

/// Bytes of a ROS 1 point: offset_time, x, y, z (4 each), reflectivity, tag, line.
const POINT_BYTES: usize = 19;

/// Parses a `CustomMsg` (ROS 1 serialized if `ros1`, else CDR). A `point_num` other than the
/// number of points is an error: which of the two is right cannot be told.
pub fn parse(ros1: bool, body: &[u8]) -> Result<CustomMsg, String> {
    let mut r = Reader::of(ros1, body)?;
    let (stamp, _) = r.header()?;
    let timebase = r.u64("timebase")?;
    let point_num = r.u32("point_num")?;
    let lidar_id = r.u8("lidar_id")?;
    r.take(3, "rsvd")?;
    let n = r.count("points", POINT_BYTES)?;
    if n != point_num as usize {
        return Err(format!(
            "point_num is {point_num} but the message holds {n} points"
        ));
    }
    let mut points = Vec::with_capacity(n);
    for _ in 0..n {
        let offset_time = r.u32("points.offset_time")?;
        let xyz = [r.f32("points.x")?, r.f32("points.y")?, r.f32("points.z")?];
        points.push(CustomPoint {
            offset_time,
            xyz,
            reflectivity: r.u8("points.reflectivity")?,
            tag: r.u8("points.tag")?,
            line: r.u8("points.line")?,
        });
    }
    r.finish()?;
    Ok(CustomMsg {
        stamp,
        timebase,
        point_num,
        lidar_id,
        points,
    })
}

/// Opens the `CustomMsg` messages on `topic` of `rec` as frames.
pub fn open(
    rec: Box<dyn Recording>,
    topic: &str,
    opts: &OpenOptions,
    warnings: &mut Vec<String>,
) -> Result<Box<dyn FrameSource>> {
    let (file, ros1) = (rec.label().to_string(), rec.ros1());
    let period_ns = match opts.sensor.frame_period_s {
        Some(p) if p.is_finite() && p > 0.0 => Some((p * 1e9).round() as u64),
        Some(p) => bail!("input.frame_period = {p}: give a positive number of seconds"),
        None => None,
    };
    let total = rec.count(topic);
    let mut stream = rec.stream(&[topic.to_string()])?;
    warnings.extend(stream.take_warnings());
    Ok(Box::new(LivoxFrames {
        stream,
        file,
        topic: topic.to_string(),
        ros1,
        total: total.filter(|_| period_ns.is_none()),
        period_ns,
        max_points: opts.scan_points,
        message: 0,
        index: 0,
        ahead: None,
        first: None,
        spacing: 0,
        last_timebase: None,
        pending: None,
        done: false,
    }))
}

/// A message read: its index, receive time, and the message with the period it belongs to
/// (0 without `input.frame_period`), or why it was left out.
type Read = (usize, u64, Result<(CustomMsg, u64), String>);

/// `CustomMsg` messages as frames.
struct LivoxFrames {
    stream: Box<dyn MessageStream>,
    file: String,
    topic: String,
    ros1: bool,
    total: Option<usize>,
    /// Merge messages into frames of this period (ns); `None`: a frame per message.
    period_ns: Option<u64>,
    max_points: usize,
    /// The next message's place in the stream.
    message: usize,
    /// The next frame's identity.
    index: usize,
    /// A message read that begins the next frame.
    ahead: Option<Read>,
    /// The first message's timebase: where periods are counted from.
    first: Option<u64>,
    /// The latest spacing between two messages' timebases, ns.
    spacing: u64,
    last_timebase: Option<u64>,
    /// The error that ended the stream inside a merged frame, for the next call.
    pending: Option<anyhow::Error>,
    done: bool,
}

impl LivoxFrames {
    /// The next message, parsed; `None` at the end.
    fn read(&mut self) -> Result<Option<Read>> {
        if let Some(r) = self.ahead.take() {
            return Ok(Some(r));
        }
        let Some(m) = self.stream.next_message()? else {
            return Ok(None);
        };
        let parsed = match Kind::of_message(self.ros1, &m) {
            Ok(Kind::LivoxCustom) => parse(self.ros1, m.data),
            Ok(_) => Err(format!("{} is not a Livox CustomMsg", m.tp)),
            Err(what) => Err(format!("{what} is not a Livox CustomMsg")),
        };
        let (index, received) = (self.message, m.time_ns);
        self.message += 1;
        let placed = parsed.map(|msg| {
            let period = match self.period_ns {
                Some(p) => self.period_of(msg.timebase, p),
                None => 0,
            };
            (msg, period)
        });
        Ok(Some((index, received, placed)))
    }

    /// The period (counted from the first message) a message whose first point is at
    /// `timebase` belongs to.
    fn period_of(&mut self, timebase: u64, period: u64) -> u64 {
        let first = *self.first.get_or_insert(timebase);
        if let Some(last) = self.last_timebase {
            self.spacing = timebase.saturating_sub(last);
        }
        self.last_timebase = Some(timebase);
        (timebase.saturating_sub(first) + self.spacing / 2) / period
    }

    /// Where a message is, for names and reasons.
    fn name(&self, received: u64) -> String {
        format!("{}:{}@{}", self.file, self.topic, stamp_of_nanos(received))
    }

    /// Adds a message's points to `frame` (whose first point was at `base` ns), at most
    /// `max_points` in all; returns the latest point's time, ns.
    fn append(&self, frame: &mut Frame, base: u64, msg: &CustomMsg, beyond: &mut usize) -> u64 {
        let room = self.max_points.saturating_sub(frame.points.len());
        *beyond += msg.points.len().saturating_sub(room);
        let stamps = frame.stamps.get_or_insert_with(Vec::new);
        let intensity = frame.intensity.get_or_insert_with(Vec::new);
        let mut latest = msg.timebase;
        for p in msg.points.iter().take(room) {
            frame.points.push(p.xyz.map(f64::from));
            let ns = msg.timebase.saturating_add(u64::from(p.offset_time));
            latest = latest.max(ns);
            // Seconds after the frame's first point: exact to the nanosecond, where seconds
            // since 1970 would keep a quarter of a microsecond.
            stamps.push(ns.wrapping_sub(base) as i64 as f64 * 1e-9);
            intensity.push(f32::from(p.reflectivity));
        }
        latest
    }
}

impl FrameSource for LivoxFrames {
    fn len_hint(&self) -> Option<usize> {
        self.total
    }

    fn next_item(&mut self) -> Result<Option<Item>> {
        if let Some(e) = self.pending.take() {
            return Err(e);
        }
        if self.done {
            return Ok(None);
        }
        let first = match self.read() {
            Ok(Some(r)) => r,
            other => {
                self.done = true;
                return other.map(|_| None);
            }
        };
        let index = self.index;
        self.index += 1;
        let (k, received, placed) = first;
        let (msg, own) = match placed {
            Ok(placed) => placed,
            Err(reason) => {
                return Ok(Some(Item::Skipped {
                    index,
                    name: self.name(received),
                    time: Some(stamp_of_nanos(received).seconds()),
                    reason: format!("{}:{} message {k}: {reason}", self.file, self.topic),
                }))
            }
        };
        let mut frame = Frame {
            index,
            name: format!("{}:{}@{}", self.file, self.topic, msg.stamp),
            time: Some(msg.stamp.seconds()),
            ..Frame::default()
        };
        let (base, mut beyond) = (msg.timebase, 0);
        let mut latest = self.append(&mut frame, base, &msg, &mut beyond);
        while self.period_ns.is_some() {
            let next = match self.read() {
                Ok(Some(r)) => r,
                Ok(None) => break,
                Err(e) => {
                    // The frame so far is whole; the damage ends the stream after it.
                    self.done = true;
                    self.pending = Some(e);
                    break;
                }
            };
            match &next.2 {
                Ok((m, period)) if *period == own => {
                    latest = latest.max(self.append(&mut frame, base, m, &mut beyond));
                }
                Ok(_) => {
                    self.ahead = Some(next);
                    break;
                }
                Err(reason) => frame.warnings.push(format!(
                    "{}: message {} left out of the frame: {reason}",
                    self.name(next.1),
                    next.0
                )),
            }
        }
        // The sweep's end on the sensor's clock, which the IMU shares.
        frame.end = Some(latest as f64 * 1e-9);
        if beyond > 0 {
            frame.warnings.push(format!(
                "{}: {} points, only the first {} read (the core's scan capacity)",
                frame.name,
                frame.points.len() + beyond,
                self.max_points
            ));
        }
        Ok(Some(Item::Frame(frame)))
    }
}

#[cfg(test)]
mod tests;
