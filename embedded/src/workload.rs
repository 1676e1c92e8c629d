//! The workload: register the embedded frames with `kiss-odom-core` and print, for each frame,
//! the pose (bit-exact) and the report, then the memory figures.
//!
//! The bare-metal builds and the host twin run this same code with the same features, so their
//! `frame` and `pose` lines must agree character for character; `cost` and the summary lines
//! carry the per-target measurements.

use crate::frames;
#[cfg(not(any(feature = "packets", feature = "net")))]
use crate::frames::FrameInfo;
#[cfg(not(any(feature = "packets", feature = "net")))]
use crate::profile::{kiss_frame_mark, EXIT_FRAME_ERROR};
use crate::profile::{
    Codec, Scalar, ARENA_WORDS, CAPS, CAPS_NAME, CODEC_NAME, EXIT_CONFIG_ERROR, SCALAR_NAME,
};
#[cfg(not(any(feature = "packets", feature = "net")))]
use kiss_odom_core::FrameReport;
use kiss_odom_core::{Config, Degeneracy, Odometry, Robust, Words};

#[cfg(not(any(feature = "packets", feature = "net")))]
/// Points per push in the `tiny` profile: one VLP-16 data packet (12 blocks of 32 returns).
const PACKET_POINTS: usize = 384;

#[repr(C, align(8))]
#[cfg(not(any(feature = "packets", feature = "net")))]
struct Aligned<B: ?Sized>(B);

#[cfg(not(any(feature = "packets", feature = "net")))]
static BYTES: &Aligned<[u8]> = &Aligned(*include_bytes!(concat!(env!("OUT_DIR"), "/frames.bin")));

#[cfg(not(any(feature = "packets", feature = "net")))]
static STAMPS: &Aligned<[u8]> = &Aligned(*include_bytes!(concat!(env!("OUT_DIR"), "/stamps.bin")));

/// The points of one embedded frame.
#[cfg(not(any(feature = "packets", feature = "net")))]
pub fn points(f: &FrameInfo) -> &'static [[Scalar; 3]] {
    let all: &'static [[Scalar; 3]] = bytemuck::cast_slice(&BYTES.0);
    &all[f.start..f.start + f.len]
}

/// The per-point capture times of one embedded frame (`tiny` only).
#[cfg(not(any(feature = "packets", feature = "net")))]
pub fn stamps(f: &FrameInfo) -> &'static [f64] {
    let all: &'static [f64] = bytemuck::cast_slice(&STAMPS.0);
    all.get(f.start..f.start + f.len).unwrap_or(&[])
}

/// The odometry configuration: the reference defaults for `MAX_RANGE` with `VOXEL_SIZE`
/// (1 m in both profiles; `Config::new(50.0)` alone would give 0.5 m voxels); under the
/// `robust` feature, robust mode with plane terms on every frame and the motion prior
/// (`plane_gate` 1, `lateral_prior` 1, `prediction_prior` 0.01: its tunnel setting, the most
/// work a frame of robust mode's plane registration takes) on those voxels; under `accurate`,
/// the `accurate` preset's registration on voxels half as large (as `Config::accurate` halves
/// the reference's).
pub fn config() -> Config<Scalar> {
    let base = if cfg!(any(feature = "tiny", feature = "packets", feature = "net")) {
        // Config::tiny() itself at its 50 m and 2 m; `far` widens both.
        Config {
            max_range: frames::MAX_RANGE as Scalar,
            voxel_size: frames::VOXEL_SIZE as Scalar,
            ..Config::tiny()
        }
    } else {
        Config {
            voxel_size: frames::VOXEL_SIZE as Scalar,
            ..Config::new(frames::MAX_RANGE as Scalar)
        }
    };
    let base = Config {
        work_budget: frames::BUDGET,
        ..base
    };
    if cfg!(feature = "robust") {
        Config {
            degeneracy: Degeneracy::Robust,
            robust: Robust::tunnel(),
            ..base
        }
    } else if cfg!(feature = "accurate") {
        Config {
            voxel_size: base.voxel_size / 2.0,
            degeneracy: Degeneracy::Robust,
            robust: Robust::accurate(),
            ..base
        }
    } else {
        base
    }
}

/// Runs every embedded frame; returns the exit status (0 on success).
/// `insns` reads the target's retired-instruction counter, if it has one.
pub fn run(state: &mut Words<ARENA_WORDS>, insns: fn() -> Option<u64>, counter: &str) -> i32 {
    let cfg = config();
    out!(
        "config scalar={} codec={} caps={} max_range={:e} voxel_size={:e} sequence={} first={} frames={} keep_every={} budget={}",
        SCALAR_NAME,
        CODEC_NAME,
        CAPS_NAME,
        cfg.max_range,
        cfg.voxel_size,
        frames::SEQUENCE,
        frames::FIRST,
        frames::FRAMES.len(),
        frames::KEEP_EVERY,
        frames::BUDGET.unwrap_or(0)
    );
    let mut odom = match Odometry::<Scalar, Codec, _>::new(cfg, CAPS, state) {
        Ok(o) => o,
        Err(e) => {
            out!("error Odometry::new: {}", e);
            return EXIT_CONFIG_ERROR;
        }
    };
    #[cfg(feature = "packets")]
    let total = crate::stream::run(&mut odom, insns, counter);
    #[cfg(feature = "net")]
    let total = crate::net::run(&mut odom, insns, counter);
    #[cfg(not(any(feature = "packets", feature = "net")))]
    let total = embedded_frames(&mut odom, insns, counter);
    let total = match total {
        Ok(t) => t,
        Err(code) => return code,
    };
    let hw = odom.high_water();
    out!(
        "memory arena_words={} arena_bytes={} state_bytes={}",
        ARENA_WORDS,
        ARENA_WORDS * 8,
        odom.state_bytes()
    );
    out!(
        "high_water merge_points={}/{} source_points={}/{} map_voxels={}/{} map_point_slots={}/{}",
        hw.merge_points,
        CAPS.merge_points,
        hw.source_points,
        CAPS.source_points,
        hw.map_voxels,
        CAPS.map_voxels,
        hw.map_point_slots,
        CAPS.map_points
    );
    if let Some(t) = total {
        out!("insns frames_total={} counter={}", t, counter);
    }
    0
}

/// Registers every embedded frame; the total instruction count where measured, or the exit
/// status of the first failing frame.
#[cfg(not(any(feature = "packets", feature = "net")))]
fn embedded_frames<S: kiss_odom_core::Storage>(
    odom: &mut Odometry<Scalar, Codec, S>,
    insns: fn() -> Option<u64>,
    counter: &str,
) -> Result<Option<u64>, i32> {
    let mut total: Option<u64> = Some(0);
    #[cfg(feature = "imu")]
    let mut imu = crate::imu::Imu::new();
    #[cfg(feature = "localize")]
    let Some(mut prior) = crate::localize::Prior::new(&config()) else {
        return Err(EXIT_CONFIG_ERROR);
    };
    for (i, f) in frames::FRAMES.iter().enumerate() {
        let pts = points(f);
        out!(
            "input {} raw={} cropped={} kept={}",
            i,
            f.raw,
            f.cropped,
            f.len
        );
        if cfg!(feature = "baseline") {
            core::hint::black_box(pts);
            total = None;
            continue;
        }
        kiss_frame_mark();
        let t0 = insns();
        #[cfg(feature = "imu")]
        imu.before(odom, i, f.t_max);
        let result = if cfg!(feature = "tiny") {
            // Packet by packet, as a sensor delivers them: the sweep is never held whole.
            let mut input = odom.begin_frame(Some((f.t_min, f.t_max)));
            for (p, t) in pts
                .chunks(PACKET_POINTS)
                .zip(stamps(f).chunks(PACKET_POINTS))
            {
                input.push(p, Some(t));
            }
            input.finish()
        } else {
            odom.register_frame(pts, None)
        };
        #[cfg(feature = "imu")]
        imu.after(odom);
        let t1 = insns();
        kiss_frame_mark();
        #[cfg(feature = "imu")]
        imu.print(i);
        let cost = t0.zip(t1).map(|(a, b)| b - a);
        total = total.zip(cost).map(|(a, b)| a + b);
        match result {
            Ok(r) => {
                emit_frame(i, f, &r, cost, counter);
                #[cfg(feature = "localize")]
                prior.frame(odom, i, insns, counter);
            }
            Err(e) => {
                out!("error frame {}: {}", i, e);
                return Err(EXIT_FRAME_ERROR);
            }
        }
    }
    Ok(total)
}

/// Prints one frame: the report line, the pose line (see `lines`) and, where measured, the
/// cost line.
#[cfg(not(any(feature = "defmt", feature = "packets", feature = "net")))]
fn emit_frame(i: usize, f: &FrameInfo, r: &FrameReport<Scalar>, cost: Option<u64>, counter: &str) {
    out!("{}", crate::lines::FrameLine(i, f.len, r));
    out!("{}", crate::lines::PoseLine(i, &r.pose));
    if let Some(c) = cost {
        out!("cost {} insns={} counter={}", i, c, counter);
    }
}

/// defmt flavour of [`emit_frame`]: the same fields, binary-encoded (decode with
/// `defmt-print -e ELF`).
#[cfg(all(feature = "defmt", not(any(feature = "packets", feature = "net"))))]
fn emit_frame(i: usize, f: &FrameInfo, r: &FrameReport<Scalar>, cost: Option<u64>, _counter: &str) {
    defmt::info!(
        "frame {=usize} status={} iterations={=u32} correspondences={=u32} points={=usize} merge={=u32} source={=u32} map_voxels={=u32} map_points={=u32} dropped={}",
        i,
        r.status,
        r.iterations,
        r.correspondences,
        f.len,
        r.merge_points,
        r.source_points,
        r.map_voxels,
        r.map_points,
        r.dropped
    );
    let m = r.pose.to_homogeneous();
    let pose: [Scalar; 12] = core::array::from_fn(|k| m[(k / 4, k % 4)]);
    defmt::info!("pose {=usize} {}", i, pose);
    if let Some(c) = cost {
        defmt::info!("cost {=usize} insns={=u64}", i, c);
    }
}
