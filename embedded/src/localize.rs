//! The `localize` profile: each frame of the `tiny` revisit, once the odometry registered it,
//! is localized in the prior map of the first drive, as `kiss-odom run --map` does on the host.
//! The map file is in flash (`.rodata`), read in place; the localizer's RAM is ICP's work and
//! the held tiles' keys, in a `static` of its own beside the odometry's arena.

use crate::frames;
use crate::profile::{kiss_frame_mark, Codec, Scalar, CAPS};
use kiss_odom_core::localize::{Localizer, PriorCapacities, Settings};
use kiss_odom_core::prior_map::TileMap;
use kiss_odom_core::{Config, Odometry, Pose, Real, Sequential, Storage, Words};
use nalgebra::{Quaternion, Translation3, UnitQuaternion};
use static_cell::ConstStaticCell;

#[repr(C, align(8))]
struct Aligned<B: ?Sized>(B);

/// The prior map file, as `kiss-odom map build` wrote it.
static MAP: &Aligned<[u8]> = &Aligned(*include_bytes!(concat!(env!("OUT_DIR"), "/map.komap")));

/// The odometry's registration cloud is what is localized.
const LOC_CAPS: PriorCapacities = PriorCapacities {
    source_points: CAPS.source_points,
};
const LOC_WORDS: usize = Localizer::<Scalar, &mut [u64]>::words(&LOC_CAPS);

static LOC_STATE: ConstStaticCell<Words<LOC_WORDS>> = ConstStaticCell::new(Words::new());

/// The localizer over the map in flash.
pub struct Prior {
    loc: Localizer<'static, Scalar, &'static mut Words<LOC_WORDS>>,
}

impl Prior {
    /// Opens the map and starts at the revisit's first pose; prints the `memory_localize`
    /// line (not compared with the host twin's: the struct holds pointers, 4 bytes here and 8
    /// there). `None` (the reason printed) if the map or the storage cannot be used.
    pub fn new(cfg: &Config<Scalar>) -> Option<Self> {
        let file = match TileMap::open(&MAP.0) {
            Ok(f) => f,
            Err(e) => {
                out!("error TileMap::open: {}", e);
                return None;
            }
        };
        let t = frames::START_T.map(Scalar::of);
        let q = frames::START_Q.map(Scalar::of);
        let start = Pose::from_parts(
            Translation3::new(t[0], t[1], t[2]),
            UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3])),
        );
        let storage = LOC_STATE.try_take()?;
        let settings = Settings::for_config(cfg);
        match Localizer::new(file, "map", cfg, settings, LOC_CAPS, storage, start) {
            Ok(loc) => {
                out!(
                    "memory_localize state_bytes={} map_bytes={} tiles={}",
                    loc.state_bytes(),
                    MAP.0.len(),
                    loc.file().len()
                );
                Some(Self { loc })
            }
            Err(e) => {
                out!("error Localizer::new: {}", e);
                None
            }
        }
    }

    /// Localizes frame `i`, which `odom` just registered: the `localize` line (state, inlier
    /// share, held tiles and the map-frame pose, compared with the host twin's) and, where
    /// measured, its cost.
    pub fn frame<S: Storage>(
        &mut self,
        odom: &Odometry<Scalar, Codec, S>,
        i: usize,
        insns: fn() -> Option<u64>,
        counter: &str,
    ) {
        kiss_frame_mark();
        let t0 = insns();
        let l = self
            .loc
            .locate(&Sequential, odom.source(), odom.last_delta(), odom.sigma());
        let t1 = insns();
        kiss_frame_mark();
        let m = l.pose.to_homogeneous();
        let p: [Scalar; 12] = core::array::from_fn(|k| m[(k / 4, k % 4)]);
        out!(
            "localize {} state={} share={:e} held_tiles={} held_points={} pose={:e} {:e} {:e} {:e} {:e} {:e} {:e} {:e} {:e} {:e} {:e} {:e}",
            i,
            l.state.name(),
            l.inlier_share,
            l.held_tiles,
            l.held_points,
            p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9], p[10], p[11]
        );
        if let Some(c) = t0.zip(t1).map(|(a, b)| b - a) {
            out!("cost_localize {} insns={} counter={}", i, c, counter);
        }
    }
}
