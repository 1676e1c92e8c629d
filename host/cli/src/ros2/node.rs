//! `kiss-odom ros2`: PointCloud2 in, odometry, `/tf` and optionally the local map out.
//!
//! Two threads. The receiver takes every cloud the DDS reader delivers and puts it in a
//! one-cloud mailbox; a cloud still waiting there when a newer one arrives is replaced and
//! counted as dropped (latest-only: a slow frame never queues work, and a dropped cloud is never
//! registered). The worker takes the mailbox's cloud, decodes it with the readers' PointCloud2
//! code, registers it through `engine` and publishes. A cloud that cannot be decoded
//! (no x/y/z, a point step its fields do not fit), has no point, or has no usable point is
//! skipped with a warning and counted; it does not touch the odometry either. So the poses
//! published are those `kiss-odom run` gives on the sequence of registered clouds.
//!
//! With the gyroscope prior on and an IMU topic ([`NodeOptions::imu_topic`]), the receiver also
//! takes the `sensor_msgs/Imu` messages (before the clouds on each wake-up), decodes them with
//! the readers' decoder and queues the samples ([`super::imu`]); the worker gives each cloud it
//! registers the samples up to its sweep's end, waiting for them at most `[imu] max_gap`.
//!
//! Published per registered cloud, stamped with the cloud's stamp:
//! - `nav_msgs/Odometry`: pose of the base in `lidar_odom_frame`; twist = the last motion
//!   (previous registered cloud to this one, expressed in the base frame at the previous
//!   cloud) over the time between their stamps (`scan_period` when the stamps do not increase): linear = translation / dt,
//!   angular = rotation vector / dt; covariance: see `covariances`.
//! - `/tf`: `lidar_odom_frame -> base` (or its inverse with `invert_odom_tf`).
//! - the local map in `lidar_odom_frame`, at most every `local_map_period` seconds.
//! - with a prior map (`map_file`): the cloud localized in it (the core's localizer, as `run
//!   --map`), the base's pose in the map frame on `map_pose_topic` and `map -> lidar_odom_frame`
//!   on `/tf` (not with `invert_odom_tf`, whose odometry frame is the base's child).
//!
//! With a base-to-LiDAR extrinsic `E`, the base pose is `E L E^-1` for the LiDAR pose `L`
//! (the odometry frame is the base frame at the first cloud), as kiss-icp's wrapper does.

use super::dds::{self, Writer};
use super::engine::{self, Registered};
use super::imu::{ImuCounts, ImuInbox};
use super::msg::{
    Covariance, Header, Odometry, PointCloud2, Pose, PoseWithCovariance, RawCloud, TfMessage, Time,
    TransformStamped, Twist, TwistWithCovariance, Vector3, ODOMETRY_TYPE, POINTCLOUD2_TYPE,
    TFMESSAGE_TYPE,
};
use super::params::NodeParams;
use super::watch::Watch;
use crate::stats::percentile;
use anyhow::{anyhow, Context, Result};
use kiss_odom_drive::localize::MapLocalizer;
use kiss_odom_drive::settings::Settings;
use kiss_odom_drive::Driver;
use kiss_odom_io::poses::{format_kitti, parse_xyz_rpy};
use kiss_odom_io::ros::imu_msg;
use kiss_odom_io::ros::message::parse_cdr;
use kiss_odom_io::ros::pointcloud2::{decode, frame_of};
use nalgebra::Isometry3;
use rustdds::mio1::{Events, Interest, Poll, Token};
use rustdds::StatusEvented;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

/// How often blocked threads look at the stop flag.
const TICK: Duration = Duration::from_millis(100);

/// What the node needs besides its parameters.
#[derive(Clone, Debug)]
pub struct NodeOptions {
    /// Odometry settings.
    pub settings: Settings,
    /// Frames, topics, covariance.
    pub params: NodeParams,
    /// DDS domain.
    pub domain: u16,
    /// Also write each published pose as a KITTI line to this file.
    pub poses: Option<PathBuf>,
    /// The worker takes a cloud at most once per this period (zero: as soon as one waits).
    /// Clouds arriving meanwhile are latest-only, as during a slow registration: a way to
    /// bound the node's share of the computer, and to make drops certain in tests.
    pub min_period: Duration,
    /// The `sensor_msgs/Imu` topic whose samples feed the gyroscope prior (`None`: no
    /// subscription). Only read with the prior on (`settings.imu.enabled`).
    pub imu_topic: Option<String>,
    /// Kept up to date with what the node's readers and writers have matched and the IMU
    /// messages it took, for a caller in the same process ([`Watch`]).
    pub watch: Arc<Watch>,
}

/// Counters printed at exit.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Summary {
    /// Clouds the receiver took from DDS.
    pub received: u64,
    /// Clouds registered and published.
    pub registered: u64,
    /// Clouds replaced in the mailbox by a newer one (latest-only).
    pub dropped: u64,
    /// Clouds that could not be decoded.
    pub malformed: u64,
    /// Clouds with no point, or no usable point.
    pub empty: u64,
    /// Warnings printed (every skip, non-finite points, oddities).
    pub warnings: u64,
    /// End-to-end latency (arrival to publication) of registered clouds, ms.
    pub(crate) latency_ms: Vec<f64>,
    /// Time in the core's frame call, ms.
    pub(crate) core_ms: Vec<f64>,
    /// IMU messages, when the node subscribes to an IMU topic.
    pub imu: Option<ImuCounts>,
}

impl Summary {
    /// The closing line.
    pub fn line(&self) -> String {
        let stats = |v: &[f64]| {
            let mut s = v.to_vec();
            s.sort_by(f64::total_cmp);
            format!(
                "p50 {:.1} p99 {:.1} max {:.1}",
                percentile(&s, 50.0),
                percentile(&s, 99.0),
                s.last().copied().unwrap_or(0.0)
            )
        };
        let imu = self.imu.map_or(String::new(), |c| {
            format!(
                ", imu received {} (malformed {}), dropped {} (queue full)",
                c.received, c.malformed, c.dropped
            )
        });
        format!(
            "summary: received {}, registered {}, dropped {} (latest-only), skipped {} \
             (malformed {}, empty {}), warnings {}, latency ms {}, core ms {}{imu}",
            self.received,
            self.registered,
            self.dropped,
            self.malformed + self.empty,
            self.malformed,
            self.empty,
            self.warnings,
            stats(&self.latency_ms),
            stats(&self.core_ms),
        )
    }
}

/// The one-cloud mailbox between the receiver and the worker.
#[derive(Default)]
struct Mailbox {
    state: Mutex<Slot>,
    ready: Condvar,
}

#[derive(Default)]
struct Slot {
    cloud: Option<(RawCloud, Instant)>,
    received: u64,
    dropped: u64,
}

impl Mailbox {
    fn put(&self, cloud: RawCloud) {
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        s.received += 1;
        if s.cloud.replace((cloud, Instant::now())).is_some() {
            s.dropped += 1;
        }
        self.ready.notify_one();
    }

    /// The waiting cloud, if one arrives within [`TICK`].
    fn take(&self) -> Option<(RawCloud, Instant)> {
        let s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let (mut s, _) = self
            .ready
            .wait_timeout_while(s, TICK, |s| s.cloud.is_none())
            .unwrap_or_else(|e| e.into_inner());
        s.cloud.take()
    }

    fn counts(&self) -> (u64, u64) {
        let s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        (s.received, s.dropped)
    }
}

/// Runs the node until `stop` is set; per-frame lines go to `out`, warnings to `err`.
pub fn run(
    opts: &NodeOptions,
    stop: &AtomicBool,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<Summary> {
    opts.params.validate()?;
    opts.settings.core_config::<f64>()?;
    opts.settings.capacities()?;
    let p = &opts.params;
    let dp = dds::participant(opts.domain)?;
    let mut reader = dds::cloud_reader(&dp, &p.points_topic)?;
    let imu_topic = opts
        .imu_topic
        .as_ref()
        .filter(|_| opts.settings.imu.enabled);
    let mut imu_reader = imu_topic.map(|t| dds::imu_reader(&dp, t)).transpose()?;
    let publish = Publishers {
        params: p.clone(),
        extrinsic: p.base_to_lidar.map(|_| p.extrinsic()).transpose()?,
        odom: dds::writer(&dp, &p.odom_topic, ODOMETRY_TYPE, &dds::reliable_qos(10))?,
        tf: p
            .publish_odom_tf
            .then(|| dds::writer(&dp, "/tf", TFMESSAGE_TYPE, &dds::reliable_qos(100)))
            .transpose()?,
        map: p
            .publish_local_map
            .then(|| {
                dds::writer(
                    &dp,
                    &p.local_map_topic,
                    POINTCLOUD2_TYPE,
                    &dds::reliable_qos(1),
                )
            })
            .transpose()?,
        map_pose: (!p.map_file.is_empty())
            .then(|| {
                dds::writer(
                    &dp,
                    &p.map_pose_topic,
                    ODOMETRY_TYPE,
                    &dds::reliable_qos(10),
                )
                .map(|w| (w, opts.settings.output.map_frame.clone()))
            })
            .transpose()?,
    };
    let mut poses = opts
        .poses
        .as_ref()
        .map(|path| std::fs::File::create(path).with_context(|| format!("{}", path.display())))
        .transpose()?;
    writeln!(
        out,
        "listening on {} (domain {}), publishing {}{}{}",
        p.points_topic,
        opts.domain,
        p.odom_topic,
        if p.publish_odom_tf { ", /tf" } else { "" },
        if p.publish_local_map {
            format!(", {}", p.local_map_topic)
        } else {
            String::new()
        }
    )?;
    if !p.map_file.is_empty() {
        writeln!(
            out,
            "localizing in {} (frame {}), publishing {}",
            p.map_file, opts.settings.output.map_frame, p.map_pose_topic
        )?;
    }
    if let Some(t) = imu_topic {
        writeln!(out, "gyroscope prior on, IMU samples from {t}")?;
    }

    let mailbox = Mailbox::default();
    let inbox = ImuInbox::new();
    let watch = &*opts.watch;
    let clouds = Topic(&mut reader, &p.points_topic);
    let imu = imu_reader
        .as_mut()
        .zip(imu_topic)
        .map(|(r, t)| (Topic(r, t), &inbox));
    let mut summary = std::thread::scope(|scope| -> Result<Summary> {
        let receiver = scope.spawn(|| receive(clouds, imu, &mailbox, watch, stop));
        let result = engine::driver(&opts.settings).and_then(|mut driver| {
            let mut map = open_map(p, &opts.settings, &driver)?;
            let cycle = Cycle {
                min_period: opts.min_period,
                stop,
                imu: imu_topic
                    .map(|_| (&inbox, Duration::from_secs_f64(opts.settings.imu.max_gap))),
                watch,
                map: map.as_mut(),
            };
            work(
                &mut driver,
                &mailbox,
                &publish,
                poses.as_mut(),
                cycle,
                out,
                err,
            )
        });
        // The worker may have failed; make sure the receiver ends either way.
        stop.store(true, Ordering::SeqCst);
        let received = receiver
            .join()
            .map_err(|_| anyhow!("the receiver thread panicked"))?;
        received?;
        result
    })?;
    let (received, dropped) = mailbox.counts();
    summary.received = received;
    summary.dropped = dropped;
    if imu_topic.is_some() {
        summary.warnings += warn_imu(&inbox, err);
        summary.imu = Some(inbox.counts());
    }
    writeln!(out, "{}", summary.line())?;
    Ok(summary)
}

/// The localizer `map_file` asks for, if any (a map that cannot be used stops the node).
fn open_map(p: &NodeParams, settings: &Settings, driver: &Driver) -> Result<Option<MapLocalizer>> {
    if p.map_file.is_empty() {
        return Ok(None);
    }
    let initial = parse_xyz_rpy(&p.initial_pose).context("initial_pose")?;
    MapLocalizer::for_driver(Path::new(&p.map_file), settings, driver, initial).map(Some)
}

/// A reader and the ROS 2 topic it reads.
struct Topic<'a>(&'a mut dds::CloudReader, &'a str);

/// Moves every cloud the reader delivers into the mailbox, and every IMU message into the
/// inbox (decoded; a malformed one is counted and its error kept for a warning), until `stop`.
/// IMU messages are drained first, so the samples that came before a cloud are there when
/// the worker takes it. The readers' matches go to `watch`.
fn receive(
    clouds: Topic,
    mut imu: Option<(Topic, &ImuInbox)>,
    mailbox: &Mailbox,
    watch: &Watch,
    stop: &AtomicBool,
) -> Result<()> {
    let Topic(reader, topic) = clouds;
    let mut poll = Poll::new()?;
    let registry = poll.registry();
    registry.register(reader, Token(0), Interest::READABLE)?;
    registry.register(reader.as_status_source_mio1(), Token(1), Interest::READABLE)?;
    if let Some((Topic(r, _), _)) = imu.as_mut() {
        registry.register(*r, Token(2), Interest::READABLE)?;
        registry.register(r.as_status_source_mio1(), Token(3), Interest::READABLE)?;
    }
    let mut events = Events::with_capacity(4);
    while !stop.load(Ordering::SeqCst) {
        poll.poll(&mut events, Some(TICK))?;
        // Drain on every wake-up and every tick: readiness is edge-triggered.
        watch.reader(topic, reader);
        if let Some((Topic(r, imu_topic), inbox)) = imu.as_mut() {
            watch.reader(imu_topic, r);
            while let Ok(Some(sample)) = r.take_next_sample() {
                inbox.put(imu_msg::parse_cdr(&sample.into_value().0));
                watch.took_imu_message();
            }
        }
        while let Ok(Some(sample)) = reader.take_next_sample() {
            mailbox.put(sample.into_value());
        }
    }
    Ok(())
}

/// Prints the warnings of the malformed IMU messages since the last call; returns how many.
fn warn_imu(inbox: &ImuInbox, err: &mut dyn Write) -> u64 {
    let errors = inbox.take_errors();
    for e in &errors {
        let _ = writeln!(err, "warning: {e}");
    }
    errors.len() as u64
}

/// How often the worker may take a cloud, the flag that ends it, with the prior on the IMU
/// samples and how long a cloud may wait for those up to its end, and with a prior map its
/// localizer.
struct Cycle<'a> {
    min_period: Duration,
    stop: &'a AtomicBool,
    imu: Option<(&'a ImuInbox, Duration)>,
    watch: &'a Watch,
    map: Option<&'a mut MapLocalizer>,
}

/// The worker loop: one registered or skipped cloud per mailbox delivery.
fn work(
    driver: &mut Driver,
    mailbox: &Mailbox,
    publish: &Publishers,
    mut poses: Option<&mut std::fs::File>,
    mut cycle: Cycle,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<Summary> {
    let mut localizer = cycle.map.take();
    let stop = cycle.stop;
    let mut next_take = Instant::now();
    let mut s = Summary::default();
    let mut previous: Option<f64> = None;
    let mut last_map: Option<Instant> = None;
    let mut n = 0u64;
    while !stop.load(Ordering::SeqCst) {
        publish.watch(cycle.watch);
        let wait = next_take.saturating_duration_since(Instant::now());
        if !wait.is_zero() {
            std::thread::sleep(wait.min(TICK));
            continue;
        }
        let Some((raw, arrived)) = mailbox.take() else {
            continue;
        };
        next_take = Instant::now() + cycle.min_period;
        n += 1;
        if let Some((inbox, _)) = cycle.imu {
            s.warnings += warn_imu(inbox, err);
        }
        let mut warn = |msg: String, s: &mut Summary| {
            s.warnings += 1;
            let _ = writeln!(err, "warning: cloud {n}: {msg}");
        };
        let cloud = match parse_cdr(&raw.0) {
            Ok(c) => c,
            Err(e) => {
                s.malformed += 1;
                warn(format!("skipped: {e}"), &mut s);
                continue;
            }
        };
        let stamp = Time {
            sec: cloud.stamp.sec as i32,
            nanosec: cloud.stamp.nsec,
        };
        let mut decoded = match decode(&cloud) {
            Ok(d) => d,
            Err(e) => {
                s.malformed += 1;
                warn(format!("stamp {}: skipped: {e}", cloud.stamp), &mut s);
                continue;
            }
        };
        for w in std::mem::take(&mut decoded.warnings) {
            warn(format!("stamp {}: {w}", cloud.stamp), &mut s);
        }
        let topic = publish.params.points_topic.clone();
        let mut frame = frame_of(n as usize, topic, cloud.stamp, decoded);
        let registered = if frame.points.is_empty() {
            None
        } else {
            if let Some((inbox, wait)) = cycle.imu {
                frame.imu = inbox.take_for(frame.sweep_end(), wait);
            }
            engine::register(driver, &frame, localizer.as_deref_mut())?
        };
        let Some(r) = registered else {
            s.empty += 1;
            let what = if frame.points.is_empty() {
                "empty cloud"
            } else {
                "no usable point (all non-finite or out of range)"
            };
            warn(format!("stamp {}: skipped: {what}", cloud.stamp), &mut s);
            continue;
        };
        if r.non_finite > 0 {
            warn(
                format!(
                    "stamp {}: {} non-finite points skipped",
                    cloud.stamp, r.non_finite
                ),
                &mut s,
            );
        }
        let t = stamp.seconds();
        let dt = match previous {
            Some(prev) if t - prev > 0.0 && (t - prev).is_finite() => t - prev,
            _ => publish.params.scan_period,
        };
        previous = Some(t);
        let frame_id = cloud.frame_id.clone();
        let base = publish.odometry(&r, dt, stamp, &frame_id)?;
        let in_map = publish.localized(&r, &base, dt, stamp, &frame_id)?;
        if let Some(w) = localizer
            .as_deref_mut()
            .and_then(MapLocalizer::damaged_warning)
        {
            warn(format!("stamp {}: {w}", cloud.stamp), &mut s);
        }
        let map_due =
            last_map.is_none_or(|m| m.elapsed().as_secs_f64() >= publish.params.local_map_period);
        if publish.map.is_some() && map_due {
            publish.local_map(driver, stamp)?;
            last_map = Some(Instant::now());
        }
        if let Some(f) = poses.as_deref_mut() {
            f.write_all(format_kitti(&[in_map.unwrap_or(base)]).as_bytes())?;
            f.flush()?;
        }
        let latency = arrived.elapsed().as_secs_f64() * 1e3;
        s.registered += 1;
        s.latency_ms.push(latency);
        s.core_ms.push(r.core_s * 1e3);
        writeln!(
            out,
            "frame {} stamp {} points {} latency {:.1} ms core {:.1} ms dropped {} status {}{}{}",
            s.registered - 1,
            cloud.stamp,
            r.input_points,
            latency,
            r.core_s * 1e3,
            mailbox.counts().1,
            r.status,
            if r.deskewed { " deskewed" } else { "" },
            r.located
                .map(|l| format!(" map {}", l.state.name()))
                .unwrap_or_default()
        )?;
    }
    Ok(s)
}

/// The writers and what they need to build messages.
struct Publishers {
    params: NodeParams,
    /// `None`: the base is the sensor, poses are published exactly as the core gives them.
    extrinsic: Option<Isometry3<f64>>,
    odom: Writer<Odometry>,
    tf: Option<Writer<TfMessage>>,
    map: Option<Writer<PointCloud2>>,
    /// With a prior map: the base's pose in the map frame, named `map_frame`.
    map_pose: Option<(Writer<Odometry>, String)>,
}

/// Pose and twist covariance (row-major 6x6, diagonal). The pose's diagonal is
/// `position_covariance` on x, y, z and `orientation_covariance` on the rotations, constant as
/// in kiss-icp's wrapper. The twist treats the same two values as the variance of one scan's
/// motion, so its diagonal is theirs divided by `dt^2`.
pub(crate) fn covariances(p: &NodeParams, dt: f64) -> (Covariance, Covariance) {
    let pose = Covariance::diagonal(p.position_covariance, p.orientation_covariance);
    let twist = Covariance::diagonal(
        p.position_covariance / (dt * dt),
        p.orientation_covariance / (dt * dt),
    );
    (pose, twist)
}

/// Linear and angular velocity of `delta` (a motion over `dt` seconds, in the moving frame).
pub fn twist_of(delta: &Isometry3<f64>, dt: f64) -> Twist {
    let v = delta.translation.vector / dt;
    let w = delta.rotation.scaled_axis() / dt;
    Twist {
        linear: Vector3 {
            x: v.x,
            y: v.y,
            z: v.z,
        },
        angular: Vector3 {
            x: w.x,
            y: w.y,
            z: w.z,
        },
    }
}

impl Publishers {
    /// Takes the writers' status events: the subscribers each has matched.
    fn watch(&self, watch: &Watch) {
        watch.writer(&self.params.odom_topic, &self.odom);
        if let Some(w) = &self.tf {
            watch.writer("/tf", w);
        }
        if let Some(w) = &self.map {
            watch.writer(&self.params.local_map_topic, w);
        }
        if let Some((w, _)) = &self.map_pose {
            watch.writer(&self.params.map_pose_topic, w);
        }
    }

    /// An odometry message: `child`'s `pose` in `header`'s frame, the twist of the base's last
    /// motion over `dt`, the covariances of the parameters.
    fn message(
        &self,
        header: Header,
        child: String,
        pose: &Isometry3<f64>,
        r: &Registered,
        dt: f64,
    ) -> Odometry {
        let delta = match &self.extrinsic {
            None => r.delta,
            Some(e) => e * r.delta * e.inverse(),
        };
        let (pose_cov, twist_cov) = covariances(&self.params, dt);
        Odometry {
            header,
            child_frame_id: child,
            pose: PoseWithCovariance {
                pose: Pose::of(pose),
                covariance: pose_cov,
            },
            twist: TwistWithCovariance {
                twist: twist_of(&delta, dt),
                covariance: twist_cov,
            },
        }
    }

    /// The moving frame's name for a cloud in `cloud_frame`.
    fn child_frame(&self, cloud_frame: &str) -> String {
        if self.params.base_frame.is_empty() {
            cloud_frame.to_string()
        } else {
            self.params.base_frame.clone()
        }
    }

    /// With a prior map, publishes the base's pose in the map frame (the localized sensor pose
    /// moved by the extrinsic) and, unless the odometry's transform is inverted, `map ->
    /// lidar_odom_frame` (that pose times the odometry's `base` inverse); returns it.
    fn localized(
        &self,
        r: &Registered,
        base: &Isometry3<f64>,
        dt: f64,
        stamp: Time,
        cloud_frame: &str,
    ) -> Result<Option<Isometry3<f64>>> {
        let (Some(l), Some((writer, map_frame))) = (&r.located, &self.map_pose) else {
            return Ok(None);
        };
        let p = &self.params;
        let in_map = match &self.extrinsic {
            None => l.pose,
            Some(e) => l.pose * e.inverse(),
        };
        let header = Header {
            stamp,
            frame_id: map_frame.clone(),
        };
        let child = self.child_frame(cloud_frame);
        let msg = self.message(header.clone(), child, &in_map, r, dt);
        writer
            .write(msg, None)
            .map_err(|e| anyhow!("publishing {}: {e:?}", p.map_pose_topic))?;
        if let (Some(tf), false) = (&self.tf, p.invert_odom_tf) {
            let t = TransformStamped {
                header,
                child_frame_id: p.lidar_odom_frame.clone(),
                transform: Pose::of(&(in_map * base.inverse())),
            };
            tf.write(
                TfMessage {
                    transforms: vec![t],
                },
                None,
            )
            .map_err(|e| anyhow!("publishing /tf: {e:?}"))?;
        }
        Ok(Some(in_map))
    }

    /// Publishes the odometry and the transform; returns the base pose.
    fn odometry(
        &self,
        r: &Registered,
        dt: f64,
        stamp: Time,
        cloud_frame: &str,
    ) -> Result<Isometry3<f64>> {
        let p = &self.params;
        let pose = match &self.extrinsic {
            None => r.pose,
            Some(e) => e * r.pose * e.inverse(),
        };
        let child = self.child_frame(cloud_frame);
        let header = Header {
            stamp,
            frame_id: p.lidar_odom_frame.clone(),
        };
        let msg = self.message(header.clone(), child.clone(), &pose, r, dt);
        self.odom
            .write(msg, None)
            .map_err(|e| anyhow!("publishing {}: {e:?}", p.odom_topic))?;
        if let Some(tf) = &self.tf {
            let t = if p.invert_odom_tf {
                TransformStamped {
                    header: Header {
                        stamp,
                        frame_id: child,
                    },
                    child_frame_id: p.lidar_odom_frame.clone(),
                    transform: Pose::of(&pose.inverse()),
                }
            } else {
                TransformStamped {
                    header,
                    child_frame_id: child,
                    transform: Pose::of(&pose),
                }
            };
            tf.write(
                TfMessage {
                    transforms: vec![t],
                },
                None,
            )
            .map_err(|e| anyhow!("publishing /tf: {e:?}"))?;
        }
        Ok(pose)
    }

    fn local_map(&self, driver: &Driver, stamp: Time) -> Result<()> {
        let Some(w) = &self.map else {
            return Ok(());
        };
        let mut points = driver.map_points();
        if let Some(e) = &self.extrinsic {
            for q in &mut points {
                let v = e * nalgebra::Point3::from(*q);
                *q = [v.x, v.y, v.z];
            }
        }
        let header = Header {
            stamp,
            frame_id: self.params.lidar_odom_frame.clone(),
        };
        w.write(PointCloud2::xyzt(header, &points, None), None)
            .map_err(|e| anyhow!("publishing {}: {e:?}", self.params.local_map_topic))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    #[test]
    fn twist_is_the_motion_over_the_interval_and_covariance_scales_with_it() {
        let delta = Isometry3::from_parts(
            Translation3::new(1.0, -0.5, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, 0.2),
        );
        let t = twist_of(&delta, 0.1);
        assert!((t.linear.x - 10.0).abs() < 1e-12 && (t.linear.y + 5.0).abs() < 1e-12);
        assert!((t.angular.z - 2.0).abs() < 1e-12, "{}", t.angular.z);
        assert!(t.angular.x.abs() < 1e-15 && t.angular.y.abs() < 1e-15);
        let p = NodeParams::default();
        let (pose, twist) = covariances(&p, 0.1);
        assert_eq!(pose.0[0], 0.1);
        assert_eq!(pose.0[35], 0.1);
        assert!((twist.0[0] - 10.0).abs() < 1e-12);
        assert_eq!(twist.0[1], 0.0);
    }

    #[test]
    fn mailbox_keeps_the_newest_cloud_and_counts_the_replaced_ones() {
        let m = Mailbox::default();
        assert!(m.take().is_none());
        for k in 0..3u8 {
            m.put(RawCloud(vec![k]));
        }
        assert_eq!(m.take().map(|(c, _)| c), Some(RawCloud(vec![2])));
        assert_eq!(m.counts(), (3, 2));
        m.put(RawCloud(vec![9]));
        assert_eq!(m.take().map(|(c, _)| c), Some(RawCloud(vec![9])));
        assert_eq!(m.counts(), (4, 2));
    }
}
