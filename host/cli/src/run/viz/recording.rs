//! `--rerun FILE.rrd` or `--rerun ADDR`: every frame of a run logged for the Rerun
//! viewer, on two time lines, `frame` (the frame index) and `time` (the frame's time in
//! seconds, when known). The entity paths (the book's "Viewing a run"):
//!
//! - `world/sensor`: the pose after the frame (`Transform3D`, sensor to world);
//! - `world/sensor/scan`: the input scan as read, every `output.rerun_scan_stride`th point;
//! - `world/source`: the registration (source) cloud, deskewed, in the world frame;
//! - `world/map`: the local map, every `output.rerun_map_every` frames and after the last;
//! - `world/trajectory`, `world/ground_truth`: the paths so far, as often as the map;
//! - `metrics/<name>`: one scalar series each (latency, iterations, sigma, ...);
//! - `flags/<flag>`: 0 or 1 per registered frame, one series per status flag;
//! - `events`: a `TextLog` line for each flagged, empty or skipped frame.
//!
//! Rerun stores positions as `f32`: logged poses agree with `poses_kitti.txt` to about 1e-7
//! relative.

use super::options::ViewArgs;
use crate::run::observe::{Observer, Seen};
use crate::run::record::FrameRow;
use anyhow::{Context, Result};
use kiss_odom_core::Flag;
use kiss_odom_drive::settings::Output;
use kiss_odom_drive::{Driver, Step};
use nalgebra::{Isometry3, Point3};
use rerun as rr;

/// Colours: the source cloud, the map, the scan, the estimate and the ground truth.
const SOURCE: rr::Color = rr::Color(rr::datatypes::Rgba32::from_rgb(214, 39, 40));
const MAP: rr::Color = rr::Color(rr::datatypes::Rgba32::from_rgb(120, 120, 120));
const SCAN: rr::Color = rr::Color(rr::datatypes::Rgba32::from_rgb(31, 119, 180));
const ESTIMATE: rr::Color = rr::Color(rr::datatypes::Rgba32::from_rgb(31, 119, 180));
const GROUND_TRUTH: rr::Color = rr::Color(rr::datatypes::Rgba32::from_rgb(255, 127, 14));

/// The recording stream and what is logged every N frames.
pub struct Recorder {
    rec: rr::RecordingStream,
    scan_stride: usize,
    map_every: u64,
    /// Frames seen, and whether the map and paths were logged at the latest.
    frames: u64,
    logged_map: bool,
    trajectory: Vec<[f32; 3]>,
    ground_truth: Vec<[f32; 3]>,
}

/// A viewer address as given (`HOST:PORT` or a full `rerun+http://` URL) as Rerun's URL.
fn proxy_url(addr: &str) -> String {
    if addr.contains("://") {
        addr.into()
    } else {
        format!("rerun+http://{addr}/proxy")
    }
}

fn f32s(p: Point3<f64>) -> [f32; 3] {
    [p.x as f32, p.y as f32, p.z as f32]
}

impl Recorder {
    /// A recording to the file or viewer `args` name, as much of it as `output` asks.
    pub fn new(args: &ViewArgs, output: &Output) -> Result<Self> {
        let builder = rr::RecordingStreamBuilder::new("kiss-odom");
        let rec = match (args.rerun_file(), args.rerun_address()) {
            (Some(path), _) => builder.save(path).context("cannot record the run")?,
            (None, Some(addr)) => builder
                .connect_grpc_opts(proxy_url(&addr))
                .with_context(|| format!("{addr}: cannot connect to a Rerun viewer"))?,
            (None, None) => anyhow::bail!("no Rerun file or viewer given"),
        };
        rec.log_static("world", &rr::ViewCoordinates::RIGHT_HAND_Z_UP())?;
        Ok(Self {
            rec,
            scan_stride: output.rerun_scan_stride.max(1) as usize,
            map_every: u64::from(output.rerun_map_every.max(1)),
            frames: 0,
            logged_map: false,
            trajectory: Vec::new(),
            ground_truth: Vec::new(),
        })
    }

    /// The local map and the paths so far, at the current time.
    fn log_map(&mut self, driver: &Driver) -> Result<()> {
        let map = driver.map_points();
        let points = map.iter().map(|&p| f32s(p.into()));
        let rec = &self.rec;
        rec.log(
            "world/map",
            &rr::Points3D::new(points)
                .with_colors([MAP])
                .with_radii([0.05]),
        )?;
        rec.log(
            "world/trajectory",
            &rr::LineStrips3D::new([self.trajectory.clone()]).with_colors([ESTIMATE]),
        )?;
        if !self.ground_truth.is_empty() {
            rec.log(
                "world/ground_truth",
                &rr::LineStrips3D::new([self.ground_truth.clone()]).with_colors([GROUND_TRUTH]),
            )?;
        }
        self.logged_map = true;
        Ok(())
    }

    /// The frame's scalars, flag series and events.
    fn log_figures(&self, seen: &Seen<'_>) -> Result<()> {
        let (rec, o) = (&self.rec, seen.outcome);
        let scalar =
            |name: &str, v: f64| rec.log(format!("metrics/{name}"), &rr::Scalars::single(v));
        let event = |text: String| {
            rec.log(
                "events",
                &rr::TextLog::new(text).with_level(rr::TextLogLevel::WARN),
            )
        };
        scalar("sigma", o.sigma)?;
        match &o.step {
            Step::Registered(r) => {
                scalar("latency_ms", o.latency.as_secs_f64() * 1e3)?;
                scalar("iterations", f64::from(r.iterations))?;
                scalar("work", r.work as f64)?;
                scalar("model_error", r.model_error)?;
                scalar("map_voxels", f64::from(r.map_voxels))?;
                scalar("map_points", f64::from(r.map_points))?;
                let d = r.dropped;
                let dropped = [
                    d.non_finite,
                    d.truncated,
                    d.merge_full,
                    d.source_full,
                    d.map_voxels_full,
                    d.map_points_full,
                ];
                scalar("dropped", dropped.iter().map(|&n| f64::from(n)).sum())?;
                if let Some(obs) = r.observability {
                    scalar("observability", obs)?;
                }
                for flag in Flag::ALL {
                    let on = f64::from(u8::from(r.status.contains(flag)));
                    rec.log(format!("flags/{}", flag.name()), &rr::Scalars::single(on))?;
                }
                let names: Vec<&str> = r.status.flags().map(Flag::name).collect();
                if !names.is_empty() {
                    event(format!("frame {}: {}", o.meta.index, names.join(", ")))?;
                }
            }
            Step::Empty => event(format!("frame {}: no usable point", o.meta.index))?,
            Step::Skipped(why) => event(format!("frame {}: skipped: {why}", o.meta.index))?,
        }
        Ok(())
    }
}

/// A pose as Rerun's transform (column-major rotation).
fn transform(pose: &Isometry3<f64>) -> rr::Transform3D {
    let r = pose.rotation.to_rotation_matrix();
    let m: [f32; 9] = std::array::from_fn(|i| r.matrix().as_slice()[i] as f32);
    let t = pose.translation.vector;
    rr::Transform3D::from_translation_mat3x3([t.x as f32, t.y as f32, t.z as f32], m)
}

impl Observer for Recorder {
    fn frame(&mut self, seen: &Seen<'_>, _: &mut FrameRow) -> Result<()> {
        let (rec, o) = (&self.rec, seen.outcome);
        rec.set_time_sequence("frame", i64::try_from(o.meta.index).unwrap_or(i64::MAX));
        if let Some(t) = seen.time.filter(|t| t.is_finite()) {
            rec.set_duration_secs("time", t);
        }
        rec.log("world/sensor", &transform(&o.pose))?;
        if let Some(points) = seen.points {
            let thinned = points.iter().step_by(self.scan_stride);
            rec.log(
                "world/sensor/scan",
                &rr::Points3D::new(thinned.map(|&p| f32s(p.into())))
                    .with_colors([SCAN])
                    .with_radii([0.03]),
            )?;
        }
        if o.report().is_some() {
            let source = seen.driver.source_cloud();
            let world = source.iter().map(|&p| f32s(o.pose * Point3::from(p)));
            rec.log(
                "world/source",
                &rr::Points3D::new(world)
                    .with_colors([SOURCE])
                    .with_radii([0.05]),
            )?;
        }
        self.log_figures(seen)?;
        self.trajectory.push(f32s(o.pose.translation.vector.into()));
        if let Some(g) = seen.ground_truth {
            self.ground_truth.push(f32s(g.translation.vector.into()));
        }
        self.logged_map = false;
        if self.frames % self.map_every == 0 {
            self.log_map(seen.driver)?;
        }
        self.frames += 1;
        Ok(())
    }

    fn finish(&mut self, driver: &Driver) -> Result<Vec<String>> {
        if self.frames > 0 && !self.logged_map {
            self.log_map(driver)?;
        }
        self.rec
            .flush_blocking()
            .map_err(|e| anyhow::anyhow!("Rerun recording: {e}"))?;
        Ok(Vec::new())
    }
}
