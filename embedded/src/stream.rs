//! The `packets` profile: a Velodyne VLP-16 recording's UDP payloads (with `mid360`, a Livox
//! Mid-360's; with `hesai`, the Hesai model `KISS_EMBED_HESAI` names; with `velodyne` or
//! `robosense`, the HDL-64E, VLS-128 or Robosense model `KISS_EMBED_MODEL` names), embedded in the
//! image, streamed packet by packet through `kiss-odom-sensors` into the core, as a sensor on the network would deliver them. A sweep is never held whole:
//! each chunk the decoder emits goes straight into the odometry's `FrameInput`.
//!
//! The span rule: the core needs a sweep's (first, last) capture time when the sweep begins,
//! before its last packet. We take the previous sweep's span (times are relative to each
//! sweep's first packet, so a steady rotation repeats it); the first sweep takes the nominal
//! 0.1 s (it is not deskewed anyway: there is no motion estimate yet).
//!
//! Each sweep's cost (decoding and odometry) is measured between two `kiss_frame_mark` calls,
//! so `run.sh` reports it as that frame's `cost`; `input` lines give the packets of each sweep.

use crate::frames::PACKET_LEN as LEN;
use crate::profile::{kiss_frame_mark, Codec, Scalar, EXIT_CONFIG_ERROR, EXIT_FRAME_ERROR};
use kiss_odom_core::{Odometry, Storage};
use kiss_odom_sensors::{Chunk, Decode, Pushed, SweepSink, SweepStart, SweepStats, CHUNK};

#[repr(C, align(8))]
struct Aligned<B: ?Sized>(B);

/// The UDP payloads, `LEN` bytes each, in capture order (`build.rs`).
static PACKETS: &Aligned<[u8]> =
    &Aligned(*include_bytes!(concat!(env!("OUT_DIR"), "/packets.bin")));

/// Span of the first sweep, seconds after its first packet.
const NOMINAL_SPAN: (f64, f64) = (0.0, 0.1);

/// Forwards the decoder's chunks to the odometry and notes what the sweep was.
struct Feed<F: FnMut(&[[Scalar; 3]], &[f64])> {
    push: F,
    xyz: [[Scalar; 3]; CHUNK],
    points: usize,
    span: (f64, f64),
    stats: Option<SweepStats>,
}

impl<F: FnMut(&[[Scalar; 3]], &[f64])> Feed<F> {
    fn new(push: F) -> Self {
        Self {
            push,
            xyz: [[0.0; 3]; CHUNK],
            points: 0,
            span: (f64::INFINITY, f64::NEG_INFINITY),
            stats: None,
        }
    }
}

impl<F: FnMut(&[[Scalar; 3]], &[f64])> SweepSink for Feed<F> {
    fn begin_sweep(&mut self, _: &SweepStart) {}
    fn points(&mut self, c: Chunk<'_>) {
        let n = c.xyz.len().min(CHUNK);
        for (dst, src) in self.xyz.iter_mut().zip(c.xyz) {
            *dst = src.map(|v| v as Scalar);
        }
        for &t in c.times {
            self.span = (self.span.0.min(t), self.span.1.max(t));
        }
        self.points += n;
        (self.push)(&self.xyz[..n], &c.times[..n.min(c.times.len())]);
    }
    fn end_sweep(&mut self, stats: &SweepStats) {
        self.stats = Some(*stats);
    }
}

/// The VLP-16 decoder: the simulator's sweeps start at azimuth 0.
#[cfg(not(any(
    feature = "mid360",
    feature = "hesai",
    feature = "velodyne",
    feature = "robosense"
)))]
fn decoder() -> Option<kiss_odom_sensors::velodyne::Decoder> {
    use kiss_odom_sensors::velodyne;
    let config = velodyne::Config {
        model: Some(velodyne::Model::Vlp16),
        calibration: None,
        cut_angle_deg: Some(0.0),
    };
    velodyne::Decoder::new(config).ok()
}

/// The Mid-360 decoder: frames of the Livox ROS driver's 0.1 s.
#[cfg(feature = "mid360")]
fn decoder() -> Option<kiss_odom_sensors::livox::Decoder> {
    use kiss_odom_sensors::livox;
    let config = livox::Config {
        model: livox::Model::Mid360,
        ..livox::Config::default()
    };
    livox::Decoder::new(config).ok()
}

/// A Hesai decoder with the generated unit's angles (`build.rs`), its sweeps cut as `run`
/// cuts them without options.
#[cfg(all(feature = "hesai", not(hesai_at128)))]
fn decoder() -> Option<kiss_odom_sensors::hesai::Decoder> {
    use crate::frames::{AZIMUTH_DEG, ELEVATION_DEG, HESAI_MODEL};
    use kiss_odom_sensors::hesai;
    let mut calibration = hesai::Calibration::nominal();
    calibration.channels = ELEVATION_DEG.len();
    calibration.elevation_deg[..ELEVATION_DEG.len()].copy_from_slice(&ELEVATION_DEG);
    calibration.azimuth_deg[..AZIMUTH_DEG.len()].copy_from_slice(&AZIMUTH_DEG);
    let config = hesai::Config {
        model: HESAI_MODEL,
        calibration: (!ELEVATION_DEG.is_empty()).then_some(calibration),
        cut_angle_deg: None,
    };
    hesai::Decoder::new(config).ok()
}

/// The AT128 decoder with the generated unit's mirror-frame correction.
#[cfg(all(feature = "hesai", hesai_at128))]
fn decoder() -> Option<kiss_odom_sensors::hesai::Decoder<kiss_odom_sensors::hesai::MirrorAngles>> {
    kiss_odom_sensors::hesai::Decoder::at128(&crate::frames::CORRECTION).ok()
}

/// A Velodyne HDL-64E or VLS-128 decoder with the generated unit's calibration
/// (`build.rs`); the simulator's sweeps start at azimuth 0.
#[cfg(feature = "velodyne")]
fn decoder() -> Option<kiss_odom_sensors::velodyne::Decoder> {
    use crate::frames::{DISTANCE_RESOLUTION_M, LASERS, VELODYNE_MODEL};
    use kiss_odom_sensors::velodyne::{Calibration, Config, Decoder, Laser};
    let mut lasers = kiss_odom_sensors::heapless::Vec::new();
    for [v, a, dz, dx] in LASERS {
        let laser = Laser {
            vertical_deg: v,
            azimuth_offset_deg: a,
            vertical_offset_m: dz,
            horizontal_offset_m: dx,
            ..Laser::default()
        };
        lasers.push(laser).ok()?;
    }
    let config = Config {
        model: Some(VELODYNE_MODEL),
        calibration: Some(Calibration {
            lasers,
            distance_resolution_m: DISTANCE_RESOLUTION_M,
        }),
        cut_angle_deg: Some(0.0),
    };
    Decoder::new(config).ok()
}

/// The RS-M1 or E1R decoder: its points carry their directions, its frames are cut by
/// sequence number.
#[cfg(all(feature = "robosense", robosense_solid))]
fn decoder() -> Option<kiss_odom_sensors::robosense::solid::Decoder> {
    Some(kiss_odom_sensors::robosense::solid::Decoder::new(
        crate::frames::SOLID_MODEL,
    ))
}

/// A Robosense decoder with the angles of the recording's DIFOP packet (`build.rs`); the
/// simulator's sweeps start at azimuth 0.
#[cfg(all(feature = "robosense", not(robosense_solid)))]
fn decoder() -> Option<kiss_odom_sensors::robosense::Decoder> {
    use crate::frames::{DIFOP, ROBOSENSE_MODEL};
    use kiss_odom_sensors::robosense::{wire::Difop, Calibration, Config, Decoder};
    let difop = Difop::new_checked(&DIFOP).ok()?;
    let config = Config {
        model: ROBOSENSE_MODEL,
        calibration: Some(Calibration::from_difop(ROBOSENSE_MODEL, &difop).ok()?),
        cut_angle_deg: Some(0.0),
    };
    Decoder::new(config).ok()
}

/// Streams every embedded packet; the total instruction count where measured, or the exit
/// status of the first failing sweep.
pub fn run<S: Storage>(
    odom: &mut Odometry<Scalar, Codec, S>,
    insns: fn() -> Option<u64>,
    counter: &str,
) -> Result<Option<u64>, i32> {
    let Some(mut dec) = decoder() else {
        return Err(EXIT_CONFIG_ERROR);
    };
    // The decoder's own state, beside the odometry's (`Odometry::state_bytes`).
    out!(
        "decoder state_bytes={} packet_len={}",
        core::mem::size_of_val(&dec),
        LEN
    );
    let packets: &[u8] = &PACKETS.0;
    let n = packets.len() / LEN;
    let (mut next, mut sweep, mut span) = (0, 0, NOMINAL_SPAN);
    let mut total = Some(0u64);
    while next < n {
        let first = next;
        kiss_frame_mark();
        let t0 = insns();
        // `baseline`: the decoder alone (its points go nowhere), for the cost per packet.
        let (result, points, seen, stats) = if cfg!(feature = "baseline") {
            let mut feed = Feed::new(|_: &[[Scalar; 3]], _: &[f64]| {});
            let stats = decode_sweep(&mut dec, packets, &mut next, &mut feed);
            (None, feed.points, feed.span, stats)
        } else {
            let mut frame = odom.begin_frame(Some(span));
            let mut feed = Feed::new(|xyz: &[[Scalar; 3]], t: &[f64]| frame.push(xyz, Some(t)));
            let stats = decode_sweep(&mut dec, packets, &mut next, &mut feed);
            let (points, seen) = (feed.points, feed.span);
            (Some(frame.finish()), points, seen, stats)
        };
        let t1 = insns();
        kiss_frame_mark();
        if seen.1 > seen.0 {
            span = seen;
        }
        let cost = t0.zip(t1).map(|(a, b)| b - a);
        total = total.zip(cost).map(|(a, b)| a + b);
        out!(
            "input {} packets={} first_packet={} points={} lost={} bad={} end={:?}",
            sweep,
            next - first,
            first,
            points,
            stats.lost_packets,
            stats.bad_packets,
            stats.end
        );
        match result {
            Some(Ok(r)) => {
                out!("{}", crate::lines::FrameLine(sweep, points, &r));
                out!("{}", crate::lines::PoseLine(sweep, &r.pose));
            }
            Some(Err(e)) => {
                out!("error sweep {}: {}", sweep, e);
                return Err(EXIT_FRAME_ERROR);
            }
            None => {}
        }
        if let Some(c) = cost {
            out!("cost {} insns={} counter={}", sweep, c, counter);
        }
        sweep += 1;
    }
    Ok(total)
}

/// Pushes packets from `next` on until the decoder ends a sweep (or the packets run out);
/// `next` moves past the packets consumed. Returns the sweep's statistics.
fn decode_sweep<D: Decode, F: FnMut(&[[Scalar; 3]], &[f64])>(
    dec: &mut D,
    packets: &[u8],
    next: &mut usize,
    feed: &mut Feed<F>,
) -> SweepStats {
    while let Some(p) = packets.get(*next * LEN..(*next + 1) * LEN) {
        match dec.push(p, feed) {
            // The packet begins the next sweep (after a gap): it is pushed again then.
            Ok(Pushed::Again) => break,
            Ok(Pushed::Ended) => {
                *next += 1;
                break;
            }
            // Refusals are counted in the sweep's statistics by the decoder.
            Ok(Pushed::Decoded) | Err(_) => *next += 1,
        }
    }
    if feed.stats.is_none() {
        dec.finish(feed);
    }
    feed.stats.unwrap_or_default()
}
