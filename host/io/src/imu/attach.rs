//! Hands IMU samples on with the frames of any source: each frame takes the samples up to its
//! sweep's end ([`Frame::sweep_end`], the instant the gyroscope prior integrates to) that no
//! earlier frame took, and the last frame takes the rest, so every sample is in exactly one
//! frame. A folder's `imu.csv`, a bag's or MCAP file's `sensor_msgs/Imu` topic and `--imu FILE`
//! all go through [`WithImu`]; a sensor capture's IMU packets arrive with its sweeps instead.

use crate::dataset::{Frame, FrameSource, Item, Trailer};
use crate::imu::ImuSample;
use anyhow::Result;

/// How many of `samples` (in time order) a frame whose sweep ends at `end` (s,
/// [`Frame::sweep_end`]) takes: those up to and including `end`. The rule of every source,
/// and of the ROS 2 node's IMU queue.
pub fn handed_on(samples: &[ImuSample], end: f64) -> usize {
    samples.partition_point(|s| s.seconds() <= end)
}

/// Samples in time order and the first not yet handed on.
#[derive(Clone, Debug, Default)]
struct Queue {
    samples: Vec<ImuSample>,
    next: usize,
}

impl Queue {
    /// The samples after the last handed on, up to `end` (s; all if `None`).
    fn until(&mut self, end: Option<f64>) -> Vec<ImuSample> {
        let rest = &self.samples[self.next..];
        let n = match end {
            Some(end) => handed_on(rest, end),
            None => rest.len(),
        };
        self.next += n;
        rest[..n].to_vec()
    }

    /// Starts again after `t` (s; from the first sample if `None`).
    fn restart_after(&mut self, t: Option<f64>) {
        self.next = match t {
            Some(t) => self.samples.partition_point(|s| s.seconds() <= t),
            None => 0,
        };
    }
}

/// A source whose frames carry the given IMU samples (replacing any they had).
pub struct WithImu {
    inner: Box<dyn FrameSource>,
    queue: Queue,
    /// The item after the one handed on last, read to tell whether that one was the last.
    ahead: Option<Result<Option<Item>>>,
    /// Frame times by identity, to know after a seek where the frame before ended.
    times: Option<Vec<f64>>,
    /// Set by a seek the times cannot place: the next frame takes only its own sweep's samples.
    placed: bool,
}

impl WithImu {
    /// `inner`'s frames with `samples` (in time order).
    pub fn new(inner: Box<dyn FrameSource>, samples: Vec<ImuSample>) -> Self {
        Self {
            inner,
            queue: Queue { samples, next: 0 },
            ahead: None,
            times: None,
            placed: true,
        }
    }

    /// Frame times by identity (`times.txt`): after a seek to frame `k`, it takes the samples
    /// since frame `k - 1`'s time. Without them it takes those since its own first point.
    pub fn with_times(mut self, times: Option<Vec<f64>>) -> Self {
        self.times = times;
        self
    }

    fn read(&mut self) -> Result<Option<Item>> {
        self.ahead.take().unwrap_or_else(|| self.inner.next_item())
    }

    /// Gives `frame` its samples; `last` when no item follows it.
    fn attach(&mut self, frame: &mut Frame, last: bool) {
        if !self.placed {
            self.placed = true;
            let start = frame
                .sweep
                .as_ref()
                .map(|s| s.start_s)
                .or_else(|| frame.stamps.as_deref()?.iter().copied().reduce(f64::min));
            // Just before the first point, so that a sample at it is the frame's.
            self.queue.restart_after(start.map(|t| t - 1e-9));
        }
        let end = if last { None } else { frame.sweep_end() };
        frame.imu = self.queue.until(end);
    }
}

impl FrameSource for WithImu {
    fn len_hint(&self) -> Option<usize> {
        self.inner.len_hint()
    }

    fn next_item(&mut self) -> Result<Option<Item>> {
        let mut item = self.read()?;
        if let Some(Item::Frame(frame)) = &mut item {
            let ahead = self.inner.next_item();
            let last = matches!(ahead, Ok(None));
            self.ahead = Some(ahead);
            self.attach(frame, last);
        }
        Ok(item)
    }

    fn seek(&mut self, index: usize) -> bool {
        if !self.inner.seek(index) {
            return false;
        }
        self.ahead = None;
        let before = match index.checked_sub(1) {
            None => Some(None),
            Some(k) => self.times.as_ref().and_then(|t| t.get(k)).map(|&t| Some(t)),
        };
        match before {
            Some(t) => self.queue.restart_after(t),
            None => self.placed = false,
        }
        true
    }

    fn trailer(&mut self) -> Trailer {
        self.inner.trailer()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frames ending at 0.1, 0.2, ... (their latest point time), frame 2 unreadable.
    struct Frames {
        next: usize,
        n: usize,
    }

    impl FrameSource for Frames {
        fn len_hint(&self) -> Option<usize> {
            Some(self.n)
        }
        fn next_item(&mut self) -> Result<Option<Item>> {
            let index = self.next;
            if index == self.n {
                return Ok(None);
            }
            self.next += 1;
            let end = 0.1 * (index + 1) as f64;
            if index == 2 {
                return Ok(Some(Item::Skipped {
                    index,
                    name: "f2".into(),
                    time: Some(end),
                    reason: "bad".into(),
                }));
            }
            Ok(Some(Item::Frame(Frame {
                index,
                points: vec![[1.0, 0.0, 0.0]; 2],
                stamps: Some(vec![end - 0.05, end]),
                ..Frame::default()
            })))
        }
        fn seek(&mut self, index: usize) -> bool {
            self.next = index;
            true
        }
    }

    /// A sample every 25 ms from 5 ms to 0.605 s: sample k at (25 k + 5) ms.
    fn samples() -> Vec<ImuSample> {
        (0..=24)
            .map(|k| ImuSample {
                time_ns: k * 25_000_000 + 5_000_000,
                ..ImuSample::default()
            })
            .collect()
    }

    fn counts(source: &mut dyn FrameSource) -> Vec<(usize, Vec<u64>)> {
        let mut out = Vec::new();
        while let Some(item) = source.next_item().unwrap() {
            if let Item::Frame(f) = item {
                let k = f.imu.iter().map(|s| s.time_ns / 25_000_000).collect();
                out.push((f.index, k));
            }
        }
        out
    }

    #[test]
    fn each_frame_takes_the_samples_up_to_its_end_and_the_last_takes_the_rest() {
        let mut source = WithImu::new(Box::new(Frames { next: 0, n: 5 }), samples());
        let got = counts(&mut source);
        // Frame 2 is skipped: frame 3 takes its samples too.
        let want: Vec<(usize, Vec<u64>)> = vec![
            (0, (0..=3).collect()),
            (1, (4..=7).collect()),
            (3, (8..=15).collect()),
            (4, (16..=24).collect()),
        ];
        assert_eq!(got, want);
    }

    #[test]
    fn after_a_seek_a_frame_takes_the_samples_since_the_frame_before_or_its_own_start() {
        let times = Some((1..=5).map(|k| 0.1 * k as f64).collect());
        let mut timed =
            WithImu::new(Box::new(Frames { next: 0, n: 5 }), samples()).with_times(times);
        assert!(timed.seek(3));
        assert_eq!(counts(&mut timed)[0], (3, (12..=15).collect()));
        let mut untimed = WithImu::new(Box::new(Frames { next: 0, n: 5 }), samples());
        assert!(untimed.seek(3));
        // Its first point is at 0.35 s.
        assert_eq!(counts(&mut untimed)[0], (3, (14..=15).collect()));
    }
}
