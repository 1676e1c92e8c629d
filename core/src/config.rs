//! Parameters (the paper's Table I) and storage capacities.
//!
//! Where this crate follows the reference `kiss-icp` 1.3.0 rather than the paper's text:
//! - the Geman-McClure scale is `kernel_scale * sigma` with `kernel_scale = 1` (the paper writes
//!   `kappa = sigma / 3`, Eq. (10)); set `kernel_scale = 1/3` for the paper's value;
//! - the adaptive threshold starts with `initial_threshold^2` as one sample of Eq. (6);
//! - ICP stops on `|dx| < convergence_criterion` *or* after `max_iterations` (the paper has no
//!   cap; the reference's default cap is 500);
//! - deskewing moves every point to the end of the sweep, so poses are end-of-sweep poses.

use crate::error::ConfigError;
use crate::registration::PLANE_KERNEL_SCALE;
use crate::scalar::Real;

/// How registration treats directions the scene does not constrain.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Degeneracy {
    /// As kiss-icp 1.3.0: ICP moves the pose along every direction (bit-identical to it).
    #[default]
    Reference,
    /// The reference, except on frames whose registration the reference leaves degenerate
    /// (observability below `Robust::plane_gate`): those are registered again with
    /// point-to-plane terms wherever the map around a registration point is planar (GenZ-ICP's,
    /// see `registration::planes`), so sparse structure moves the pose along walls and ground;
    /// for tunnels, corridors, long walls, open ground.
    Robust,
}

/// Pipeline parameters. [`Config::new`] gives the reference defaults for a maximum range.
///
/// The fields from `max_range` to `deskew` are the paper's Table I (with the reference's
/// iteration cap), `kernel_scale` and `max_correspondence_factor` the reference's kernel and
/// correspondence rules; what follows goes beyond the paper: flagging and handling degenerate
/// frames (`degeneracy_ratio`, `degeneracy`, `robust`) and a bound on a frame's work
/// (`work_budget`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config<T> {
    /// `r_max`: points farther than this are dropped and voxels farther than this from the
    /// current pose are pruned from the local map.
    pub max_range: T,
    /// Points closer than this are dropped (the sensor's blind zone, the vehicle itself).
    pub min_range: T,
    /// `v`: local map voxel size; the paper's default is `0.01 r_max`.
    pub voxel_size: T,
    /// `alpha`: the map-merge cloud uses voxels of `alpha v` (paper: 0.5).
    pub alpha: T,
    /// `beta`: the registration cloud uses voxels of `beta v` (paper: 1.5).
    pub beta: T,
    /// Put the merge and registration clouds in the reference's order (the bucket order of
    /// kiss-icp's hash table, rebuilt in `downsample::reference_order`), which its poses need
    /// bit for bit. `false` keeps them in the order the scan gave their first points: the same
    /// points, without the sort, and neighbours stay near each other in the map's memory.
    pub reference_order: bool,
    /// `N_max`: points per map voxel (paper: 20, at most 255 here).
    pub max_points_per_voxel: u32,
    /// `tau_0`: the threshold's seed sample (paper: 2 m).
    pub initial_threshold: T,
    /// `delta_min`: model deviations at or below this do not update the threshold (0.1 m).
    pub min_motion_threshold: T,
    /// `gamma`: ICP stops when the norm of the correction twist is below this (1e-4).
    pub convergence_criterion: T,
    /// ICP iteration cap (reference default 500); reaching it is reported in the status.
    pub max_iterations: u32,
    /// Deskew scans that carry per-point timestamps (Eq. (4)).
    pub deskew: bool,
    /// Deskew a whole scan ([`crate::Odometry::register_frame`]) a second time with the motion
    /// its first registration found, and register it again from there: the constant-velocity
    /// model deskews with the last sweep's motion, which is wrong where the motion changes
    /// from one sweep to the next. Only where that registration measured every direction (its
    /// observability not below `degeneracy_ratio`) and its motion moves a point at `r_max` by
    /// more than `min_motion_threshold` from where the model put it; a scan pushed in pieces
    /// ([`crate::Odometry::begin_frame`]) is deskewed once, its points not being kept. The
    /// reference (`false`) deskews once.
    pub redeskew: bool,
    /// Geman-McClure scale as a multiple of `sigma` (reference: 1, paper: 1/3).
    pub kernel_scale: T,
    /// Correspondences farther than `max_correspondence_factor * sigma` are rejected (3).
    pub max_correspondence_factor: T,
    /// A frame is flagged degenerate when the weakest direction of the point-to-plane
    /// information (from map voxel normals) carries less than this fraction of the strongest.
    pub degeneracy_ratio: T,
    /// What ICP does along directions the scene does not constrain: move as the reference
    /// does ([`Degeneracy::Reference`], the default) or register the frames the reference finds
    /// degenerate again with point-to-plane terms ([`Degeneracy::Robust`], tuned by
    /// [`Config::robust`]).
    pub degeneracy: Degeneracy,
    /// Robust mode's parameters; the other modes ignore them.
    pub robust: Robust<T>,
    /// A registration cloud of more points than this (a dense sensor's) is made again from the
    /// merge cloud with voxels of `beta v` scaled by its points over this number (GenZ-ICP's
    /// adaptive voxel, from LOCUS 2.0), so ICP's work per iteration stops growing with the
    /// scene's detail; 0 (the reference's) keeps every `beta v` voxel. Only after a
    /// registration that measured every direction (so never on the first two frames, nor
    /// after a frame flagged [`crate::Flag::Degenerate`]): a weakly constrained scene's sparse
    /// structure is what measures its weak directions. The first registration against the map
    /// (the second frame, from a prediction standing still: the one that iterates longest)
    /// registers the thinned cloud first, then every voxel from where that ended if it measured
    /// every direction (not with a `work_budget`, which bounds one registration). The points
    /// counted are those the source buffer held (`Capacities::source_points`).
    pub desired_source_points: usize,
    /// Work units ICP may spend on one frame (see [`crate::FrameReport::work`]); `None` (the
    /// reference's behaviour) leaves it to `gamma` and `max_iterations`. When a frame would
    /// exceed it, ICP keeps its last complete iterate and the frame is flagged
    /// [`crate::Flag::Budget`]. Together with the capacities this bounds a frame's work; see
    /// `Capacities` for the formula.
    pub work_budget: Option<u64>,
}

/// Robust mode's parameters ([`Degeneracy::Robust`]): when a frame is registered again with
/// point-to-plane terms, and the motion prior that holds what no term constrains. The defaults
/// ([`Robust::new`]) gate at 0.015 with no prior; the measurements behind them, and robust
/// mode's tunnel setting, are in BENCHMARKS.md ("Degenerate scenes").
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Robust<T> {
    /// The gate: a frame whose reference registration leaves an observability (see
    /// [`crate::FrameReport::observability`]) below this is registered again from the
    /// prediction with point-to-plane terms where the map is planar, and flagged
    /// [`crate::Flag::Planes`]; every other frame keeps the reference's pose, bit for bit. 1 or
    /// more: every frame with plane terms, without the reference registration first
    /// (observability is at most 1).
    pub plane_gate: T,
    /// The hold prior: in a registration with plane terms, from the third frame, the position
    /// is pulled to the constant-velocity prediction with this weight per correspondence, so
    /// what no correspondence constrains stays at the prediction (see `stages::MotionPrior`).
    /// 0: none.
    pub prediction_prior: T,
    /// The vehicle prior: the same, for no motion along the sensor's `y` axis (a car-like
    /// vehicle with the sensor's `x` axis forward does not slide sideways). In a corridor, a
    /// turn's motion across it then fixes the motion along it. 0: none.
    pub lateral_prior: T,
    /// The Geman-McClure scale of a registration with plane terms, over `sigma` (default
    /// [`crate::stages::PLANE_KERNEL_SCALE`], the paper's 1/3).
    pub kernel_scale: T,
    /// A registration with plane terms also stops when its iterate comes back within `gamma`
    /// of one of its last [`crate::stages::CYCLE_LEN`] iterates: the step changes of the plane
    /// terms can hold it in a loop that `|dx| < gamma` never ends. `false`: the reference's
    /// stopping rule.
    pub cycle_stop: bool,
}

impl<T: Real> Robust<T> {
    /// The gate at 0.015, no prior.
    pub fn new() -> Self {
        Self {
            plane_gate: T::of(0.015),
            prediction_prior: T::zero(),
            lateral_prior: T::zero(),
            kernel_scale: T::of(PLANE_KERNEL_SCALE),
            cycle_stop: false,
        }
    }

    /// Robust mode's tunnel setting for a car-like vehicle: plane terms on every frame, the
    /// vehicle prior 1 and the hold prior 0.01 (use it with `r_max / 200` voxels).
    pub fn tunnel() -> Self {
        Self {
            plane_gate: T::one(),
            prediction_prior: T::of(0.01),
            lateral_prior: T::one(),
            ..Self::new()
        }
    }

    /// The `accurate` preset's: plane terms on every frame and the cycle stop, no motion prior
    /// (see [`Config::accurate`]).
    pub fn accurate() -> Self {
        Self {
            plane_gate: T::one(),
            cycle_stop: true,
            ..Self::new()
        }
    }

    fn validate(&self) -> bool {
        let nonneg = |x: T| x.is_finite() && x >= T::zero();
        let pos = self.kernel_scale.is_finite() && self.kernel_scale > T::zero();
        pos && nonneg(self.plane_gate)
            && nonneg(self.prediction_prior)
            && nonneg(self.lateral_prior)
    }
}

impl<T: Real> Default for Robust<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real> Config<T> {
    /// The reference defaults for a sensor with range `max_range` (voxel size `r_max / 100`).
    pub fn new(max_range: T) -> Self {
        Self {
            max_range,
            min_range: T::zero(),
            voxel_size: max_range / T::of(100.0),
            alpha: T::of(0.5),
            beta: T::of(1.5),
            reference_order: true,
            max_points_per_voxel: 20,
            initial_threshold: T::of(2.0),
            min_motion_threshold: T::of(0.1),
            convergence_criterion: T::of(1e-4),
            max_iterations: 500,
            deskew: true,
            redeskew: false,
            kernel_scale: T::one(),
            max_correspondence_factor: T::of(3.0),
            degeneracy_ratio: T::of(0.02),
            degeneracy: Degeneracy::Reference,
            robust: Robust::new(),
            desired_source_points: 0,
            work_budget: None,
        }
    }

    /// Robust mode ([`Degeneracy::Robust`]) with the reference's other defaults: on a scene
    /// that is not degenerate its poses are the reference's. Its point-to-plane terms read
    /// planes from the map's voxels, so the voxel size must resolve the structure that
    /// constrains the free directions: `r_max / 100` does over open ground; in a tunnel whose
    /// features stand 0.2-0.8 m proud of its walls it does not, and its tunnel setting is
    /// `plane_gate` 1 with `r_max / 200` voxels, for a car-like vehicle with the motion prior
    /// (`lateral_prior` 1, `prediction_prior` 0.01; over open ground `lateral_prior` 1):
    /// BENCHMARKS.md section 12.
    pub fn robust(max_range: T) -> Self {
        Self {
            degeneracy: Degeneracy::Robust,
            ..Self::new(max_range)
        }
    }

    /// The `accurate` preset: lower error than the reference's on ordinary scenes, tunnels and open
    /// ground, not in a bare corridor (BENCHMARKS.md, "The accurate preset"), at 1.1-2.6 times the
    /// default's time on urban and KITTI scans. Every frame is registered with point-to-plane terms
    /// where the map is planar (GenZ-ICP's weighting, see `registration::planes`) and
    /// point-to-point terms elsewhere, on a map of `r_max / 200` voxels; a registration that goes
    /// round a loop stops there ([`Robust::cycle_stop`]), a whole scan whose motion was not the
    /// model's is deskewed again with its own ([`Config::redeskew`]), and a dense scan's
    /// registration cloud is thinned toward 3,000 points where the scene measures every direction
    /// ([`Config::desired_source_points`]). Both clouds keep the scan's order
    /// ([`Config::reference_order`] `false`). Its poses are not the reference's.
    pub fn accurate(max_range: T) -> Self {
        // GenZ-ICP's `desired_num_voxelized_points` in its `outdoor` and `kitti` presets. A
        // 64-beam sweep keeps 3,700-4,600 points at `beta v` on generated streets and
        // 6,000-12,500 on KITTI's (BENCHMARKS.md, "The accurate preset").
        const DESIRED_SOURCE_POINTS: usize = 3_000;
        Self {
            voxel_size: max_range / T::of(200.0),
            degeneracy: Degeneracy::Robust,
            robust: Robust::accurate(),
            desired_source_points: DESIRED_SOURCE_POINTS,
            redeskew: true,
            reference_order: false,
            ..Self::new(max_range)
        }
    }

    /// The parameters [`Capacities::TINY`] was sized for: a 16-beam sensor's sparse rings with
    /// `r_max` 50 m, voxels of 2 m and at most 10 points each (the reference's defaults would be
    /// 0.5 m voxels and 20 points, several times the memory, and no better on such data).
    pub fn tiny() -> Self {
        Self {
            voxel_size: T::of(2.0),
            max_points_per_voxel: 10,
            ..Self::new(T::of(50.0))
        }
    }

    /// Largest accepted `max_range` (m). The adaptive threshold squares distances of order
    /// `r_max` (Eq. (6)-(7)); beyond about 1e154 m that overflows f64 and sigma would stay
    /// infinite for good. No range sensor reaches a thousand kilometres, so this is the limit.
    pub const MAX_RANGE_LIMIT: f64 = 1.0e6;

    /// Checks that every parameter is finite and in its domain (`max_range` at most
    /// [`Self::MAX_RANGE_LIMIT`]).
    pub fn validate(&self) -> Result<(), ConfigError> {
        let pos = |x: T| x.is_finite() && x > T::zero();
        let in_range = pos(self.max_range) && self.max_range <= T::of(Self::MAX_RANGE_LIMIT);
        if !(in_range && self.min_range.is_finite() && self.min_range >= T::zero()) {
            return Err(ConfigError::Range);
        }
        if self.min_range >= self.max_range {
            return Err(ConfigError::Range);
        }
        if !pos(self.voxel_size) || !pos(self.alpha) || !pos(self.beta) {
            return Err(ConfigError::VoxelSize);
        }
        if self.max_points_per_voxel == 0 || self.max_points_per_voxel > 255 {
            return Err(ConfigError::PointsPerVoxel);
        }
        let nonneg = |x: T| x.is_finite() && x >= T::zero();
        if !pos(self.initial_threshold)
            || !nonneg(self.min_motion_threshold)
            || !pos(self.kernel_scale)
            || !pos(self.max_correspondence_factor)
            || !nonneg(self.degeneracy_ratio)
            || !self.robust.validate()
        {
            return Err(ConfigError::Threshold);
        }
        if !nonneg(self.convergence_criterion) || self.max_iterations == 0 {
            return Err(ConfigError::Iterations);
        }
        Ok(())
    }
}

/// Fixed capacities of every buffer. Nothing grows at run time; each full buffer has a rule
/// (see [`crate::report::Dropped`]) and the frame report counts what it dropped.
///
/// [`Capacities::sized_for`] sizes them from the configuration (what hosts use by default);
/// the named sets below are fixed budgets. When the map fills, it evicts its farthest voxels
/// and its radius shrinks below `r_max` (see [`crate::FrameReport::map_radius`]).
///
/// Sizing rules (measured high-water marks are in BENCHMARKS.md):
/// - `scan_points`: points the sensor delivers per sweep (HDL-64E about 125k, OS1-128 262k).
///   Points past this index are ignored (truncation keeps the first `scan_points`).
/// - `merge_points`: occupied `alpha v` voxels of one scan. Roughly the scan's visible surface
///   area over `(alpha v)^2`; KITTI at `v = 1 m` uses about 20k.
/// - `source_points`: occupied `beta v` voxels, about a fifth of `merge_points`.
/// - `map_voxels`: occupied `v` voxels within `r_max` of the sensor: the surface area of the
///   scene inside the range sphere over `v^2`; about 16k on KITTI at 100 m and 1 m voxels.
/// - `map_points`: points in those voxels, at most `N_max` each; KITTI averages 5-8 per voxel.
/// - `plane_terms`: room for robust mode's point-to-plane terms ([`Degeneracy::Robust`] needs
///   it): per source point a cached plane (6 scalars), per 64 of them a second partial system
///   (29 scalars). `false` keeps the reference's storage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Capacities {
    /// Input points considered per scan.
    pub scan_points: usize,
    /// Points in the map-merge cloud (`alpha v` downsampling).
    pub merge_points: usize,
    /// Points in the registration cloud (`beta v` downsampling).
    pub source_points: usize,
    /// Voxels in the local map.
    pub map_voxels: usize,
    /// Points in the local map (all voxels together).
    pub map_points: usize,
    /// Room for point-to-plane terms, which robust mode needs (see the sizing rules).
    pub plane_terms: bool,
}

impl Capacities {
    /// Full scale, KITTI-like (HDL-64E or OS1-64/128 at `r_max` 100 m, 1 m voxels). Margins
    /// over the largest high-water marks of kitti-mini and generated 500-1000-frame urban and
    /// fast drives (BENCHMARKS.md): scan 2.1x (127,109, KITTI 05; an OS1-128 sweep fits),
    /// merge 2.4x (20,417, KITTI 01), source 2.6x (4,760, KITTI 01), map voxels 1.57x (18,318,
    /// urban-1000) and map point slots 1.48x (155,444, fast-500), the map sized so that with
    /// quantized points it stays under a third of the reference's.
    pub const FULL_SCALE: Self = Self {
        scan_points: 262_144,
        merge_points: 49_152,
        source_points: 12_288,
        map_voxels: 28_672,
        map_points: 229_376,
        plane_terms: false,
    };

    /// Full scale for robust mode ([`Config::robust`], `r_max` 100 m) down to 0.5 m voxels (its
    /// tunnel setting, `plane_gate` 1 and `r_max / 200`): an open field's ground then fills four
    /// times the voxels of [`Capacities::FULL_SCALE`]'s 1 m map.
    /// Margins over the largest high-water marks of generated 500-frame field runs and
    /// kitti-mini (BENCHMARKS.md section 12): merge 1.6x (39,917, KITTI 01), source 1.9x
    /// (12,588, KITTI 01), map voxels 1.5x (108,776, field-3), map point slots 1.8x (577,594,
    /// field-3).
    pub const ROBUST: Self = Self {
        scan_points: 262_144,
        merge_points: 65_536,
        source_points: 24_576,
        map_voxels: 163_840,
        map_points: 1_048_576,
        plane_terms: true,
    };

    /// Microcontroller scale (a few MiB): `r_max` about 50 m, 1 m voxels, f32 and quantised
    /// map points.
    pub const SMALL: Self = Self {
        scan_points: 131_072,
        merge_points: 12_288,
        source_points: 3_072,
        map_voxels: 8_192,
        map_points: 49_152,
        plane_terms: false,
    };

    /// A 16-beam sensor (VLP-16 class, about 29k points a sweep fed in pieces through
    /// `begin_frame`/`push`/`finish`) in under 512 KiB with f32 and quantised map points: use it
    /// with [`Config::tiny`] (`r_max` 50 m, 2 m voxels, `N_max` 10). 1.5x the high-water marks
    /// of a 600-sweep generated VLP-16 urban run (merge 2,785, source 578, voxels 2,657, point
    /// slots 18,272), no drop on three more such runs (BENCHMARKS.md). `scan_points` only
    /// bounds one sweep's kept points, stored nowhere.
    pub const TINY: Self = Self {
        scan_points: 32_768,
        merge_points: 4_224,
        source_points: 896,
        map_voxels: 4_032,
        map_points: 27_456,
        plane_terms: false,
    };

    /// [`Capacities::TINY`]'s sensor with the `accurate` preset's registration on voxels half as
    /// large ([`Config::tiny`] at 1 m voxels, plane terms). Halving the voxel edge at most
    /// quadruples the cells a surface covers, but a 16-beam sensor's rings leave most of the
    /// finer cells empty: the high-water marks of three 500-sweep generated VLP-16 urban runs
    /// (seeds 1-3) are 2.0-3.3x TINY's (merge 6,686, source 1,909, voxels 8,655, point slots
    /// 55,528, the largest of each); these are 1.5x those. About 1.5 MiB with f32 and
    /// quantised map points.
    pub const TINY_ACCURATE: Self = Self {
        scan_points: 32_768,
        merge_points: 10_048,
        source_points: 2_880,
        map_voxels: 12_992,
        map_points: 83_328,
        plane_terms: true,
    };

    /// Capacities sized from the configuration for a sensor of `scan_points` points a sweep,
    /// so that no buffer fills on a ground vehicle's data: what a host uses when none are named.
    ///
    /// The rule, from the geometry a sensor can see inside `r_max`: the ground it has swept is at
    /// most the disc of radius `r_max`, `D(c) = pi (r_max / c)^2` cells of size `c`, and what
    /// stands on it (facades, vegetation, which fills voxels in depth) is counted as twice that
    /// disc again. So `map_voxels = 3 D(v)`, 94,248 at 100 m and 1 m voxels (the margins over
    /// measured maps are in BENCHMARKS.md). `map_points` gives every voxel half of `N_max`
    /// (voxels average 5-8 of 20 on KITTI). A downsampled cloud never holds more points
    /// than its input, so `merge_points = scan_points` cannot drop; `source_points` is the
    /// smaller of that and `3 D(beta v)`. Each is capped ([`Self::SIZED_MAP_VOXELS`],
    /// [`Self::SIZED_MAP_POINTS`]) so that a tiny voxel cannot ask for gigabytes: a map sized
    /// at a cap can fill, and then evicts its farthest voxels as any full map does.
    pub fn sized_for<T: Real>(config: &Config<T>, scan_points: usize) -> Self {
        let disc = |cell: f64| {
            let r = config.max_range.wide() / cell;
            core::f64::consts::PI * r * r
        };
        // `as` saturates (NaN gives 0, which `validate` refuses).
        let count = |x: f64, cap: usize| (libm::ceil(x) as usize).clamp(1, cap);
        let v = config.voxel_size.wide();
        let map_voxels = count(3.0 * disc(v), Self::SIZED_MAP_VOXELS);
        let per_voxel = (config.max_points_per_voxel as usize).div_ceil(2).max(1);
        let source = count(3.0 * disc(config.beta.wide() * v), scan_points.max(1));
        Self {
            scan_points,
            merge_points: scan_points,
            source_points: source,
            map_voxels,
            map_points: map_voxels
                .saturating_mul(per_voxel)
                .min(Self::SIZED_MAP_POINTS),
            plane_terms: config.degeneracy == Degeneracy::Robust,
        }
    }

    /// The most map voxels [`Self::sized_for`] gives (4.2 M: a table of about 95 MB).
    pub const SIZED_MAP_VOXELS: usize = 1 << 22;
    /// The most map points [`Self::sized_for`] gives (8.4 M: 200 MB of f64 points).
    pub const SIZED_MAP_POINTS: usize = 1 << 23;

    /// Checks that every capacity is usable.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let ok = self.scan_points > 0
            && self.merge_points > 0
            && self.source_points > 0
            && self.map_voxels > 0
            && self.map_points > 0
            && self.merge_points < (1 << 30)
            && self.map_points / crate::local_map::BLOCK < (1 << 30)
            && self.scan_points <= u32::MAX as usize;
        if ok {
            Ok(())
        } else {
            Err(ConfigError::Capacity)
        }
    }
}

#[cfg(test)]
mod tests;
