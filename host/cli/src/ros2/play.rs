//! `kiss-odom ros2 --play`: publishes a recording's clouds on a ROS 2 topic at their recorded
//! pace, so the node (or any ROS 2 tool) can be fed without a robot.
//!
//! Frames come from the same readers as `kiss-odom run` ([`kiss_odom_io::open()`]), KITTI
//! correction included, and go out as `sensor_msgs/PointCloud2` with x, y, z and (when the
//! recording has per-point times) `t`, all FLOAT64: every value reaches the node exactly as
//! `run` reads it. The header stamp is the frame's time; frame `k` is sent `(t_k - t_0) / rate`
//! seconds after the first (frames without a time are `period` apart). With `lockstep` a
//! cloud also waits for the odometry of the one before (its stamp on the node's odometry
//! topic, at most `wait` seconds): a node on any machine then gets every cloud, none dropped,
//! and the pace is the node's.
//!
//! With the recording's IMU samples ([`PlayOptions::imu`]: a bag's or MCAP file's
//! `sensor_msgs/Imu` topic, a folder's `imu.csv`) the player also publishes them as
//! `sensor_msgs/Imu`, interleaved by time with the clouds: right before a cloud go the samples
//! the readers hand on with its frame (those up to its sweep's end, see
//! [`kiss_odom_io::imu::attach`]) and the first sample after that end, as a live IMU's would
//! have arrived before the cloud. The node then has every sample up to the cloud's end when the
//! cloud comes and never waits for more. Samples go out in those bursts, not at their own pace.

use super::dds::{self, Writer};
use super::msg::{Header, Odometry, PointCloud2, Time, ODOMETRY_TYPE, POINTCLOUD2_TYPE};
use super::msg::{Imu, IMU_TYPE};
use anyhow::{bail, Result};
use kiss_odom_io::{self as io, Format, ImuInput, Item, OpenOptions};
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// What to play and how.
#[derive(Clone, Debug)]
pub struct PlayOptions {
    /// Recording.
    pub(crate) path: PathBuf,
    /// Its format.
    pub(crate) format: Format,
    /// Topic inside a bag or MCAP (default: its only cloud topic).
    pub(crate) source_topic: Option<String>,
    /// ROS 2 topic to publish on.
    pub points_topic: String,
    /// `frame_id` of the published clouds.
    pub frame_id: String,
    /// Speed factor (2 = twice as fast).
    pub(crate) rate: f64,
    /// Time between frames that carry no time (s).
    pub(crate) period: f64,
    /// How long to wait for a subscriber before the first cloud (s), and with `lockstep` for
    /// each cloud's odometry.
    pub(crate) wait: f64,
    /// The node's odometry topic: publish a cloud only once the odometry of the one before has
    /// come on it (or `wait` passed).
    pub lockstep: Option<String>,
    /// DDS domain.
    pub domain: u16,
    /// Where the IMU samples come from and the ROS 2 topic to publish them on (`None`: no
    /// IMU). With [`ImuInput::Auto`] a recording without an IMU topic publishes none.
    pub imu: Option<(ImuInput, String)>,
}

/// Plays the recording; returns the number of clouds published.
pub fn run(
    opts: &PlayOptions,
    stop: &AtomicBool,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<u64> {
    Player::new(opts, err)?.play(stop, out, err)
}

/// A player set up: the recording opened, the DDS writers (and with `lockstep` the odometry
/// reader) created, so that discovery is under way; [`Player::play`] publishes. Between the
/// two, a caller that sees the subscriber's side of the match (the node's
/// [`super::watch::Watch`]) can wait for it: a player only sees its own side.
pub struct Player<'a> {
    opts: &'a PlayOptions,
    dataset: io::Dataset,
    clouds: Writer<PointCloud2>,
    imu: Option<Writer<Imu>>,
    acks: Option<dds::Reader<Odometry>>,
    /// Declared last: dropped after its writers and reader.
    _dp: dds::DomainParticipant,
}

impl<'a> Player<'a> {
    /// Checks `opts`, opens the recording and creates the participant, writers and reader.
    pub fn new(opts: &'a PlayOptions, err: &mut dyn Write) -> Result<Self> {
        if !(opts.rate.is_finite() && opts.rate > 0.0) {
            bail!("--rate must be positive");
        }
        if !(opts.period.is_finite() && opts.period > 0.0) {
            bail!("--period must be positive");
        }
        let open = |imu: ImuInput| {
            io::open(
                &opts.path,
                opts.format,
                &OpenOptions {
                    topic: opts.source_topic.clone(),
                    imu,
                    ..OpenOptions::default()
                },
            )
        };
        let dataset = match &opts.imu {
            None => open(ImuInput::Builtin)?,
            // A recording with several IMU topics and none named: play its clouds alone.
            Some((ImuInput::Auto, _)) => open(ImuInput::Auto).or_else(|e| {
                writeln!(err, "warning: {e:#}; publishing no IMU samples")?;
                open(ImuInput::Builtin)
            })?,
            Some((input, _)) => open(input.clone())?,
        };
        let dp = dds::participant(opts.domain)?;
        let clouds = dds::writer(
            &dp,
            &opts.points_topic,
            POINTCLOUD2_TYPE,
            &dds::sensor_qos(),
        )?;
        let imu = opts
            .imu
            .as_ref()
            .map(|(_, topic)| dds::writer(&dp, topic, IMU_TYPE, &dds::imu_qos()))
            .transpose()?;
        let acks = opts
            .lockstep
            .as_ref()
            .map(|topic| dds::reader(&dp, topic, ODOMETRY_TYPE, &dds::reliable_qos(10)))
            .transpose()?;
        Ok(Self {
            opts,
            dataset,
            clouds,
            imu,
            acks,
            _dp: dp,
        })
    }

    /// Waits for a subscriber (and with `lockstep` the odometry), then publishes the clouds
    /// (and IMU samples) until the recording ends or `stop` is set; returns the number of
    /// clouds published.
    pub fn play(
        mut self,
        stop: &AtomicBool,
        out: &mut dyn Write,
        err: &mut dyn Write,
    ) -> Result<u64> {
        let opts = self.opts;
        let dataset = &mut self.dataset;
        let w = &self.clouds;
        let imu_w = self
            .imu
            .as_ref()
            .zip(opts.imu.as_ref().map(|(_, topic)| topic.as_str()));
        let stopped = || stop.load(Ordering::SeqCst);
        let wait = crate::interrupt::seconds(opts.wait);
        if !dds::wait_for_reader(w, wait, &stopped) {
            writeln!(
                err,
                "warning: no subscriber on {} after {} s; publishing anyway",
                opts.points_topic, opts.wait
            )?;
        }
        if let (Some(r), Some(topic)) = (&self.acks, &opts.lockstep) {
            if !dds::wait_for_writer(r, wait, &stopped) {
                writeln!(
                    err,
                    "warning: no odometry on {topic} after {} s; --lockstep waits for each cloud anyway",
                    opts.wait
                )?;
            }
        }
        let mut acks = self.acks.as_mut().zip(opts.lockstep.as_ref());
        let mut first: Option<(f64, Instant)> = None;
        let mut sent = 0u64;
        let mut imu_sent = 0u64;
        let mut imu_checked = false;
        let mut next_time = 0.0;
        // One item ahead, for the first IMU sample after a cloud's end.
        let mut ahead = dataset.frames.next_item()?;
        // How many of the next frame's samples went out with the cloud before.
        let mut lead = 0;
        while !stopped() {
            let frame = match ahead.take() {
                None => break,
                Some(Item::Skipped { reason, .. }) => {
                    writeln!(err, "warning: {reason}")?;
                    ahead = dataset.frames.next_item()?;
                    continue;
                }
                Some(Item::Frame(f)) => f,
            };
            ahead = dataset.frames.next_item()?;
            for w in &frame.warnings {
                writeln!(err, "warning: {w}")?;
            }
            let time = frame
                .time
                .or_else(|| {
                    dataset
                        .info
                        .frame_times
                        .as_ref()
                        .and_then(|t| t.get(frame.index).copied())
                })
                .unwrap_or(next_time);
            next_time = time + opts.period;
            let (t0, start) = *first.get_or_insert((time, Instant::now()));
            // A tiny rate or a long gap is a long wait (past `Instant`'s range: until stopped).
            let due = start.checked_add(crate::interrupt::seconds((time - t0) / opts.rate));
            // Pacing: the cloud goes at its recorded time, the stop flag looked at meanwhile.
            while !stopped() {
                let left = due.map_or(Duration::MAX, |d| {
                    d.saturating_duration_since(Instant::now())
                });
                if left.is_zero() {
                    break;
                }
                std::thread::sleep(left.min(Duration::from_millis(50)));
            }
            if let Some((w, topic)) = imu_w {
                let next = match &ahead {
                    Some(Item::Frame(f)) => f.imu.first(),
                    _ => None,
                };
                let samples = frame.imu.iter().skip(lead).chain(next);
                lead = usize::from(next.is_some());
                if !imu_checked && !frame.imu.is_empty() {
                    imu_checked = true;
                    // Discovery found the cloud reader: an IMU reader, if any, is found by now.
                    let short = wait.min(Duration::from_secs(1));
                    if !dds::wait_for_reader(w, short, &stopped) {
                        writeln!(
                            err,
                            "warning: no subscriber on {topic}; publishing the IMU samples anyway"
                        )?;
                    }
                }
                for s in samples {
                    w.write(Imu::of(s, "imu"), None)
                        .map_err(|e| anyhow::anyhow!("publishing {topic}: {e:?}"))?;
                    imu_sent += 1;
                }
            }
            let stamp = Time::from_seconds(time);
            let header = Header {
                stamp,
                frame_id: opts.frame_id.clone(),
            };
            let msg = PointCloud2::xyzt(header, &frame.points, frame.stamps.as_deref());
            w.write(msg, None)
                .map_err(|e| anyhow::anyhow!("publishing {}: {e:?}", opts.points_topic))?;
            writeln!(
                out,
                "published {sent} {} stamp {time:.6} points {}",
                frame.name,
                frame.points.len()
            )?;
            sent += 1;
            if let Some((r, topic)) = &mut acks {
                if !answered(r, stamp, wait, &stopped) && !stopped() {
                    writeln!(
                        err,
                        "warning: no odometry for stamp {time:.6} on {topic} after {} s (skipped \
                         by the node?); publishing the next cloud",
                        opts.wait
                    )?;
                }
            }
        }
        // Best effort has no acknowledgement to wait for: give the event loop time to put the
        // last fragments on the wire before the participant goes.
        std::thread::sleep(Duration::from_millis(500));
        write!(out, "played {sent} clouds on {}", opts.points_topic)?;
        match imu_w {
            Some((_, topic)) => writeln!(out, ", {imu_sent} IMU samples on {topic}")?,
            None => writeln!(out)?,
        }
        Ok(sent)
    }
}

/// Waits until odometry stamped `stamp` comes on `r` (older messages are passed over), `stop`
/// says stop, or `wait` passes; returns whether it came.
fn answered(
    r: &mut dds::Reader<Odometry>,
    stamp: Time,
    wait: Duration,
    stop: &dyn Fn() -> bool,
) -> bool {
    let start = Instant::now();
    while start.elapsed() < wait && !stop() {
        while let Ok(Some(sample)) = r.take_next_sample() {
            if sample.into_value().header.stamp == stamp {
                return true;
            }
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    false
}
