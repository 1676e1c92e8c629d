//! The node's IMU samples between the receiver and the worker: a bounded queue in time order
//! from which each registered cloud takes the samples up to its sweep's end
//! ([`kiss_odom_io::imu::attach::handed_on`], the rule every recording's frames follow). Samples
//! after that end stay for the next cloud; a cloud dropped by the latest-only mailbox, or
//! skipped, takes none, so the next registered cloud gets them, as the gyroscope prior
//! integrates from the last registered sweep's end.
//!
//! The queue holds at most `CAPACITY` samples; a sample arriving when it is full pushes out
//! the oldest, which is counted as dropped (an IMU streaming while no cloud comes).

use kiss_odom_io::imu::attach::handed_on;
use kiss_odom_io::imu::ImuSample;
use kiss_odom_io::ros::imu_msg::ImuError;
use std::collections::VecDeque;
use std::sync::{Condvar, Mutex};
use std::time::{Duration, Instant};

/// Samples the queue holds: 4 s at 1 kHz, 20 s at 200 Hz.
pub(crate) const CAPACITY: usize = 4096;

/// The counts the exit summary prints.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ImuCounts {
    /// Messages the receiver took from DDS.
    pub received: u64,
    /// Messages that were not a `sensor_msgs/Imu` (skipped with a warning).
    pub malformed: u64,
    /// Samples pushed out of the full queue before a cloud took them.
    pub dropped: u64,
}

/// Samples in time order, at most `capacity`.
#[derive(Debug)]
pub(crate) struct ImuQueue {
    samples: VecDeque<ImuSample>,
    capacity: usize,
    counts: ImuCounts,
}

impl ImuQueue {
    /// An empty queue of at most `capacity` (at least 1) samples.
    pub fn new(capacity: usize) -> Self {
        Self {
            samples: VecDeque::new(),
            capacity: capacity.max(1),
            counts: ImuCounts::default(),
        }
    }

    /// Adds a received sample in time order (one older than the newest is put in its place);
    /// when full, the oldest goes and is counted.
    pub(crate) fn push(&mut self, s: ImuSample) {
        self.counts.received += 1;
        if self.samples.len() == self.capacity {
            self.samples.pop_front();
            self.counts.dropped += 1;
        }
        let at = self.samples.partition_point(|q| q.time_ns <= s.time_ns);
        self.samples.insert(at, s);
    }

    /// Counts a message that could not be read.
    pub fn malformed(&mut self) {
        self.counts.received += 1;
        self.counts.malformed += 1;
    }

    /// The samples up to `end` (s; all if `None`, a cloud whose end is unknown), in time order;
    /// later ones stay.
    pub(crate) fn take_until(&mut self, end: Option<f64>) -> Vec<ImuSample> {
        let n = match end {
            Some(end) => handed_on(self.samples.make_contiguous(), end),
            None => self.samples.len(),
        };
        self.samples.drain(..n).collect()
    }

    /// Whether a sample at or after `end` (s) has come, so none up to it is still on its way
    /// (the IMU's messages come in time order).
    pub(crate) fn covers(&self, end: f64) -> bool {
        self.samples.back().is_some_and(|s| s.seconds() >= end)
    }

    /// The counters.
    pub(crate) fn counts(&self) -> ImuCounts {
        self.counts
    }
}

/// Warnings of malformed messages kept until the worker prints them; more are only counted.
const KEPT_ERRORS: usize = 100;

/// The queue shared by the receiver and the worker, and the warnings of malformed messages
/// (the receiver has no error stream; the worker prints them).
pub(crate) struct ImuInbox {
    queue: Mutex<(ImuQueue, Vec<String>)>,
    arrived: Condvar,
}

impl ImuInbox {
    /// An empty inbox of [`CAPACITY`] samples.
    pub fn new() -> Self {
        Self::with_capacity(CAPACITY)
    }

    /// An empty inbox of `capacity` samples.
    pub(crate) fn with_capacity(capacity: usize) -> Self {
        Self {
            queue: Mutex::new((ImuQueue::new(capacity), Vec::new())),
            arrived: Condvar::new(),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, (ImuQueue, Vec<String>)> {
        self.queue.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Adds a decoded message's sample, or counts a malformed one and keeps its warning.
    pub(crate) fn put(&self, sample: Result<ImuSample, ImuError>) {
        let mut guard = self.lock();
        let (q, errors) = &mut *guard;
        match sample {
            Ok(s) => q.push(s),
            Err(e) => {
                q.malformed();
                if errors.len() < KEPT_ERRORS {
                    let k = q.counts.received;
                    errors.push(format!("IMU message {k}: skipped: {e}"));
                }
            }
        }
        self.arrived.notify_all();
    }

    /// The warnings of malformed messages since the last call.
    pub(crate) fn take_errors(&self) -> Vec<String> {
        std::mem::take(&mut self.lock().1)
    }

    /// The samples of a cloud whose sweep ends at `end`. When none at or after `end` has come
    /// yet, waits for one at most `wait` (the IMU topic runs behind the cloud topic), then
    /// takes what is there (the prior says `gap` if they stop more than `max_gap` short of
    /// the end). Waits only once the IMU has delivered a sample, so a node whose IMU topic is
    /// silent registers at once.
    pub(crate) fn take_for(&self, end: Option<f64>, wait: Duration) -> Vec<ImuSample> {
        let mut q = self.lock();
        if let Some(end) = end {
            let deadline = Instant::now() + wait;
            while q.0.counts.received > q.0.counts.malformed && !q.0.covers(end) {
                let left = deadline.saturating_duration_since(Instant::now());
                if left.is_zero() {
                    break;
                }
                q = self
                    .arrived
                    .wait_timeout(q, left)
                    .unwrap_or_else(|e| e.into_inner())
                    .0;
            }
        }
        q.0.take_until(end)
    }

    /// The counters.
    pub(crate) fn counts(&self) -> ImuCounts {
        self.lock().0.counts()
    }
}

impl Default for ImuInbox {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at_ms(ms: u64) -> ImuSample {
        ImuSample {
            time_ns: ms * 1_000_000,
            ..ImuSample::default()
        }
    }

    fn ms(v: &[ImuSample]) -> Vec<u64> {
        v.iter().map(|s| s.time_ns / 1_000_000).collect()
    }

    #[test]
    fn a_cloud_takes_the_samples_up_to_its_end_and_later_ones_stay_for_the_next() {
        let mut q = ImuQueue::new(16);
        // Eighths of a second: times and ends exact in binary.
        for t in [125, 250, 375, 500, 625] {
            q.push(at_ms(t));
        }
        // The sample at the end is the cloud's, as for every recording's frames.
        assert_eq!(ms(&q.take_until(Some(0.375))), [125, 250, 375]);
        assert!(q.covers(0.5) && q.covers(0.625) && !q.covers(0.626));
        // A dropped cloud took nothing: the next registered one takes its samples too.
        q.push(at_ms(750));
        assert_eq!(ms(&q.take_until(Some(0.75))), [500, 625, 750]);
        assert!(q.take_until(Some(0.875)).is_empty());
        // A sample arriving out of order is put in its place.
        q.push(at_ms(1125));
        q.push(at_ms(1000));
        assert_eq!(ms(&q.take_until(None)), [1000, 1125]);
        assert_eq!(
            q.counts(),
            ImuCounts {
                received: 8,
                malformed: 0,
                dropped: 0
            }
        );
    }

    #[test]
    fn a_full_queue_drops_the_oldest_and_counts_it() {
        let mut q = ImuQueue::new(3);
        for t in 1..=5 {
            q.push(at_ms(t));
        }
        q.malformed();
        assert_eq!(
            q.counts(),
            ImuCounts {
                received: 6,
                malformed: 1,
                dropped: 2
            }
        );
        assert_eq!(ms(&q.take_until(Some(1.0))), [3, 4, 5]);
    }

    #[test]
    fn the_worker_waits_a_bounded_time_for_the_samples_up_to_the_end() {
        let inbox = ImuInbox::with_capacity(8);
        // Nothing received yet: no wait at all (a wait would last the two minutes).
        let start = Instant::now();
        assert!(inbox
            .take_for(Some(0.01), Duration::from_secs(120))
            .is_empty());
        assert!(start.elapsed() < Duration::from_secs(60));
        // Samples stop short of the end: the wait is bounded, then what is there goes.
        inbox.put(Ok(at_ms(5)));
        let start = Instant::now();
        assert_eq!(
            ms(&inbox.take_for(Some(0.02), Duration::from_millis(30))),
            [5]
        );
        assert!(start.elapsed() >= Duration::from_millis(30));
        // A sample after the end arriving meanwhile ends the wait (of up to two minutes); it
        // stays. The pause makes it arrive during the wait most of the time; arriving before,
        // it ends the wait as well.
        inbox.put(Ok(at_ms(15)));
        std::thread::scope(|s| {
            s.spawn(|| {
                std::thread::sleep(Duration::from_millis(20));
                inbox.put(Ok(at_ms(25)));
            });
            let start = Instant::now();
            assert_eq!(
                ms(&inbox.take_for(Some(0.02), Duration::from_secs(120))),
                [15]
            );
            assert!(start.elapsed() < Duration::from_secs(60));
        });
        inbox.put(Err(ImuError::Truncated("header.stamp")));
        assert_eq!(
            inbox.take_errors(),
            ["IMU message 4: skipped: message ends inside header.stamp"]
        );
        assert!(inbox.take_errors().is_empty());
        assert_eq!(ms(&inbox.take_for(None, Duration::ZERO)), [25]);
        assert_eq!(
            inbox.counts(),
            ImuCounts {
                received: 4,
                malformed: 1,
                dropped: 0
            }
        );
    }
}
