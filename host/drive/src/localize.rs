//! Localization in a prior map on a host: the map file read whole, the core's
//! [`Localizer`] run after each frame the driver answers,
//! on the odometry's registration cloud and its motion over the frame.
//!
//! The host localizes in `f64` whatever the odometry's scalar (the board runs the core's
//! localizer in its own). The prior map is read in place, as a board reads it from flash.

use crate::settings::Settings;
use crate::{Driver, Outcome, Step};
use anyhow::{anyhow, Context, Result};
use kiss_odom_core::localize::{Localizer, Located, PriorCapacities, Settings as LocalizeSettings};
use kiss_odom_core::prior_map::TileMap;
use kiss_odom_core::{Config, Sequential};
use nalgebra::Isometry3;
use std::path::Path;
use std::sync::Mutex;

/// The map files this process read, each kept once for its lifetime: a localizer reads its map
/// in place, and another on the same bytes (a Python object made again) shares them.
static MAPS: Mutex<Vec<&'static [u8]>> = Mutex::new(Vec::new());

/// `bytes`, kept for the process's lifetime (one copy per distinct content).
fn keep(bytes: Vec<u8>) -> &'static [u8] {
    let mut maps = MAPS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(m) = maps.iter().find(|m| ***m == bytes[..]) {
        return m;
    }
    let m: &'static [u8] = Box::leak(bytes.into_boxed_slice());
    maps.push(m);
    m
}

/// The core's localizer over a map file the process keeps for its lifetime.
pub struct MapLocalizer {
    loc: Localizer<'static, f64, Box<[u64]>>,
    /// The frame's registration cloud, its memory kept from frame to frame.
    source: Vec<[f64; 3]>,
    /// Damaged tiles found so far (each load that met one counts it).
    pub damaged_tiles: u32,
    /// Whether the damaged tiles were warned about.
    damaged_said: bool,
}

impl MapLocalizer {
    /// Opens the map at `path` for an odometry configured with `config` (`f64`), in the map
    /// frame named `frame`, starting at `initial`; `source_points` is the odometry's
    /// registration cloud capacity. Errors name the file and the reason.
    pub fn open(
        path: &Path,
        frame: &str,
        config: &Config<f64>,
        source_points: usize,
        initial: Isometry3<f64>,
    ) -> Result<Self> {
        let bytes = std::fs::read(path)
            .with_context(|| format!("{}: cannot read the map", path.display()))?;
        let bytes = keep(bytes);
        let file = TileMap::open(bytes).map_err(|e| anyhow!("{}: {e}", path.display()))?;
        let h = *file.header();
        let settings = LocalizeSettings::for_config(config);
        let caps = PriorCapacities {
            source_points: source_points.max(1),
        };
        let words = vec![0u64; Localizer::<f64, Box<[u64]>>::words(&caps)];
        let loc = Localizer::new(
            file,
            frame,
            config,
            settings,
            caps,
            words.into_boxed_slice(),
            initial,
        )
        .map_err(|e| {
            anyhow!(
                "{}: {e} (map: voxel {} m, frame {:?}, tiles of {} m; run: voxel {} m, \
                 frame {frame:?})",
                path.display(),
                h.voxel_size,
                h.frame_name(),
                h.tile_size,
                config.voxel_size
            )
        })?;
        Ok(Self {
            loc,
            source: Vec::new(),
            damaged_tiles: 0,
            damaged_said: false,
        })
    }

    /// The localizer in the map at `path` for `driver`'s odometry, built with `settings` (in
    /// `output.map_frame`), starting at `initial` (the sensor's pose in the map frame): what
    /// `run --map`, the ROS 2 node and Python open.
    pub fn for_driver(
        path: &Path,
        settings: &Settings,
        driver: &Driver,
        initial: Isometry3<f64>,
    ) -> Result<Self> {
        let config = settings.core_config::<f64>()?;
        let source = driver.build().capacities.source_points;
        Self::open(path, &settings.output.map_frame, &config, source, initial)
    }

    /// Starts again from `pose` (map frame), degraded until confirmed.
    pub fn reseed(&mut self, pose: Isometry3<f64>) {
        self.loc.reseed(pose);
    }

    /// Localizes the frame `outcome` answered: a registered frame by its registration cloud,
    /// any other by the odometry's motion alone.
    pub fn locate(&mut self, driver: &Driver, outcome: &Outcome) -> Located<f64> {
        match outcome.step {
            Step::Registered(_) => driver.source_cloud_into(&mut self.source),
            _ => self.source.clear(),
        }
        let located = self.loc.locate(
            &Sequential,
            &self.source,
            &driver.last_delta(),
            outcome.sigma,
        );
        if let Some(l) = located.loaded {
            self.damaged_tiles += l.damaged;
        }
        located
    }

    /// The sensor's pose in the map frame: the last frame's, or the start's before the first
    /// frame and after [`Self::reseed`].
    pub fn pose(&self) -> &Isometry3<f64> {
        self.loc.pose()
    }

    /// A warning, once, when a damaged tile was skipped.
    pub fn damaged_warning(&mut self) -> Option<String> {
        if self.damaged_tiles == 0 || self.damaged_said {
            return None;
        }
        self.damaged_said = true;
        Some(format!(
            "the map has a damaged tile (checksum): skipped, its area localizes on the rest \
             of the map ({} so far)",
            self.damaged_tiles
        ))
    }

    /// Bytes of the localizer's state.
    pub fn state_bytes(&self) -> usize {
        self.loc.state_bytes()
    }

    /// Bytes of the localizer's state on a board (f32) registering `source_points` points:
    /// whatever the map and the tiles held, which stay in flash.
    pub fn board_bytes(source_points: usize) -> usize {
        let caps = PriorCapacities {
            source_points: source_points.max(1),
        };
        8 * Localizer::<f32, Box<[u64]>>::words(&caps)
            + std::mem::size_of::<Localizer<'static, f32, Box<[u64]>>>()
    }

    /// The map file.
    pub fn file(&self) -> &TileMap<'static> {
        self.loc.file()
    }
}
