//! Localization in a prior map: the odometry's registered scan, registered again to a map of
//! the site read tile by tile from a [`TileMap`], gives the pose in the map frame.
//!
//! Each frame, after [`crate::Odometry`] registered the scan:
//!
//! 1. predict: the last map-frame pose moved by the odometry's motion over the frame (its
//!    registration against the local map, which holds what the prior map lacks: parked cars,
//!    new shelves);
//! 2. hold the tiles within reach of the prediction (`tiles`);
//! 3. register the odometry's registration cloud `P^*` to the prior map from the prediction
//!    (the paper's robust ICP, Eq. (9)-(12), its gate `max(3 sigma_t, gate_floor)`);
//! 4. measure it: the share of `P^*` off level ground within `inlier_distance` of a map point
//!    (level ground fits whatever the horizontal error), and the registration's conditioning
//!    (the observability ratio);
//! 5. judge it ([`State`]): a good share and conditioning moves the pose to the registration;
//!    a fair share moves it too (in a long aisle the map measures the pose across it, not
//!    along), degraded; else the pose is the prediction, degraded, until `lost_after_m` metres
//!    or `lost_after_frames` frames have passed without a fix (a good share at a quarter of the
//!    conditioning counts; below it, as in an open field, the share fits whatever the pose and
//!    vouches for nothing): lost. A pose not yet confirmed
//!    by a good registration (the start, a reseed, the search's answer) is lost after
//!    `confirm_frames` frames in a row whose share is not good.
//!    Lost runs the bounded search (`search`) around the dead-reckoned pose, a few starts per
//!    frame, while a fair fit from the prediction still moves the pose (and a good one ends
//!    the search); its answer is confirmed by `confirm_frames` good frames before the state says
//!    localized again. [`Localizer::reseed`] takes a pose from the user instead.
//!
//! Storage: ICP's work, in words sized by [`Localizer::words`], and the held tiles' keys. The
//! prior map is never copied: its tiles are read in place, from flash on a board, so the state
//! does not grow with the map or the reach.

mod fit;
mod search;
mod settings;
mod tiles;

pub use search::{STARTS as SEARCH_STARTS, STEP_DEG as SEARCH_STEP_DEG, STEP_M as SEARCH_STEP_M};
pub use settings::{LocalizeError, PriorCapacities, Settings};
pub use tiles::{tiles_touched, Loaded, MAX_TILES_HELD};

use crate::config::Config;
use crate::geometry::Pose;
use crate::lie::renormalize;
use crate::prior_map::TileMap;
use crate::registration::{work_words, Executor};
use crate::scalar::Real;
use crate::storage::Storage;
use search::Search;
use tiles::Held;

/// How sure the localization is of the frame's pose.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum State {
    /// Registered to the map with a good share of inliers and conditioning, confirmed.
    Localized,
    /// A pose to use with care: a fair registration, an unconfirmed one, or the odometry
    /// carrying the last fix forward for a short way.
    Degraded,
    /// No fix for too long: the pose is the odometry's guess while the search runs.
    Lost,
}

impl State {
    /// The name `frames.csv` uses.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Localized => "localized",
            Self::Degraded => "degraded",
            Self::Lost => "lost",
        }
    }
}

/// One frame's localization.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Located<T: Real> {
    /// The sensor's pose in the map frame.
    pub pose: Pose<T>,
    /// How sure it is.
    pub state: State,
    /// Share of `P^*` within `inlier_distance` of the map at the registered pose, counting
    /// only the points off level ground (level ground fits whatever the horizontal error).
    pub inlier_share: T,
    /// The registration's observability ratio (`None` if nothing was measured).
    pub observability: Option<T>,
    /// How far the registration moved the prediction (m).
    pub correction: T,
    /// What the tiles' load did this frame, if one was needed.
    pub loaded: Option<Loaded>,
    /// Search starts registered this frame.
    pub searched: u32,
    /// The search found the pose this frame.
    pub recovered: bool,
    /// Tiles of the prior map held (damaged ones included).
    pub held_tiles: u32,
    /// Points of the prior map within reach (in the held tiles, read in place).
    pub held_points: u32,
}

/// Localization in a prior map over storage it owns or borrows (see [`crate::storage`]).
pub struct Localizer<'m, T: Real, S: Storage> {
    file: TileMap<'m>,
    settings: Settings<T>,
    config: Config<T>,
    caps: PriorCapacities,
    storage: S,
    held: Held<'m>,
    pose: Pose<T>,
    state: State,
    /// Good frames in a row.
    confirmed: u32,
    /// Travel and frames since the last fix.
    since_fix: (T, u32),
    /// A good registration since the start, the last reseed or the search's answer.
    fixed: bool,
    /// Frames in a row whose inlier share was below the good one.
    misfits: u32,
    search: Option<Search<T>>,
}

impl<'m, T: Real, S: Storage> Localizer<'m, T, S> {
    /// Words of storage for `caps`.
    pub const fn words(caps: &PriorCapacities) -> usize {
        work_words::<T>(caps.source_points, false)
    }

    /// A localizer in `file` (whose frame must be named `frame`) for an odometry configured
    /// with `config`, starting at `initial` (map frame), degraded until confirmed.
    pub fn new(
        file: TileMap<'m>,
        frame: &str,
        config: &Config<T>,
        settings: Settings<T>,
        caps: PriorCapacities,
        mut storage: S,
        initial: Pose<T>,
    ) -> Result<Self, LocalizeError> {
        let h = file.header();
        let v = config.voxel_size.wide();
        if (h.voxel_size - v).abs() > 1e-9 * v {
            return Err(LocalizeError::VoxelSize);
        }
        if h.frame_name() != frame {
            return Err(LocalizeError::Frame);
        }
        let s = settings;
        let share = |x: T| x >= T::zero() && x <= T::one();
        let positive = |x: T| x > T::zero() && x.is_finite();
        let valid = share(s.good_share)
            && share(s.fair_share)
            && share(s.search_margin)
            && positive(s.reach)
            && positive(s.inlier_distance)
            && positive(s.gate_floor)
            && positive(s.lost_after_m);
        if !valid {
            return Err(LocalizeError::Settings);
        }
        let held_reach = s.reach.wide() + 0.5 * h.tile_size;
        if tiles_touched(held_reach, h.tile_size) > MAX_TILES_HELD {
            return Err(LocalizeError::TileSize);
        }
        if caps.source_points == 0 || storage.as_mut().len() < Self::words(&caps) {
            return Err(LocalizeError::Storage);
        }
        Ok(Self {
            file,
            settings,
            config: *config,
            caps,
            storage,
            held: Held::new(),
            pose: initial,
            state: State::Degraded,
            confirmed: 0,
            since_fix: (T::zero(), 0),
            fixed: false,
            misfits: 0,
            search: None,
        })
    }

    /// The pose in the map frame after the last frame.
    pub fn pose(&self) -> &Pose<T> {
        &self.pose
    }

    /// The state after the last frame.
    pub fn state(&self) -> State {
        self.state
    }

    /// The map file.
    pub fn file(&self) -> &TileMap<'m> {
        &self.file
    }

    /// Bytes of the state: ICP's work and the bookkeeping (the held tiles' keys among it).
    pub fn state_bytes(&self) -> usize {
        8 * Self::words(&self.caps) + core::mem::size_of::<Self>()
    }

    /// Starts again from `pose` (map frame), degraded until confirmed: a pose from the user.
    pub fn reseed(&mut self, pose: Pose<T>) {
        self.pose = pose;
        self.state = State::Degraded;
        self.confirmed = 0;
        self.since_fix = (T::zero(), 0);
        self.fixed = false;
        self.misfits = 0;
        self.search = None;
    }

    /// Localizes the frame the odometry just registered: `source` is its `P^*`
    /// ([`crate::Odometry::source`]), `motion` its motion over the frame
    /// ([`crate::Odometry::last_delta`]) and `sigma` its `sigma_t`.
    pub fn locate<E: Executor>(
        &mut self,
        exec: &E,
        source: &[[T; 3]],
        motion: &Pose<T>,
        sigma: T,
    ) -> Located<T> {
        let source = &source[..source.len().min(self.caps.source_points)];
        let mut predicted = self.pose * motion;
        renormalize(&mut predicted);
        let t = predicted.translation.vector;
        let reach = self.settings.reach.wide();
        let loaded = self.held.around(&self.file, t.x.wide(), t.y.wide(), reach);
        let mut out = Located {
            pose: predicted,
            state: State::Degraded,
            inlier_share: T::zero(),
            observability: None,
            correction: T::zero(),
            loaded,
            searched: 0,
            recovered: false,
            held_tiles: self.held.len() as u32,
            held_points: self.held.points() as u32,
        };
        let step = motion.translation.vector.norm();
        let gate = (T::of(3.0) * sigma).max(self.settings.gate_floor);
        let (pose, share, obs) = self.register(exec, source, &predicted, gate);
        out.inlier_share = share;
        out.observability = obs;
        out.correction = (pose.translation.vector - t).norm();
        let s = &self.settings;
        let good = share >= s.good_share && obs.is_some_and(|o| o >= s.min_observability);
        if self.state == State::Lost && !good {
            // Lost: the map's fair fit still moves the pose, and the search runs on.
            if share >= s.fair_share {
                out.pose = pose;
            }
            self.search_step(exec, source, &predicted, &mut out);
        } else {
            self.search = None;
            self.judge(pose, share, obs, step, &mut out);
        }
        self.pose = out.pose;
        self.state = out.state;
        out
    }

    /// Step 5 for a tracked frame.
    fn judge(&mut self, pose: Pose<T>, share: T, obs: Option<T>, step: T, out: &mut Located<T>) {
        let s = &self.settings;
        let conditioned = obs.is_some_and(|o| o >= s.min_observability);
        if share >= s.good_share && conditioned {
            out.pose = pose;
            self.since_fix = (T::zero(), 0);
            self.fixed = true;
            self.misfits = 0;
            self.confirmed = self.confirmed.saturating_add(1);
            out.state = if self.confirmed >= s.confirm_frames {
                State::Localized
            } else {
                State::Degraded
            };
            return;
        }
        self.confirmed = 0;
        // A fair fit moves the pose where the map measures it (in a long aisle, across it).
        if share >= s.fair_share {
            out.pose = pose;
        }
        // A good fit the map conditions fairly keeps the pose from drifting away: no
        // confirmation, but no time lost either. Below a quarter of the conditioning (an open
        // field's ground and far poles) the share fits metres off as well as on the pose.
        let weak = s.min_observability * T::of(0.25);
        if share >= s.good_share && obs.is_some_and(|o| o >= weak) {
            self.since_fix = (T::zero(), 0);
        } else {
            self.since_fix = (self.since_fix.0 + step, self.since_fix.1.saturating_add(1));
        }
        self.misfits = if share >= s.good_share {
            0
        } else {
            self.misfits.saturating_add(1)
        };
        // Without a fix, the pose drifts as the odometry does; a pose never confirmed (the
        // start, a reseed, the search's answer) that the map does not fit is no pose at all.
        let lost = self.since_fix.0 > s.lost_after_m
            || self.since_fix.1 > s.lost_after_frames
            || (!self.fixed && self.misfits >= s.confirm_frames);
        out.state = if lost { State::Lost } else { State::Degraded };
        if lost {
            self.search = Some(Search::new());
        }
    }

    /// One frame of the search around the dead-reckoned `at`.
    fn search_step<E: Executor>(
        &mut self,
        exec: &E,
        source: &[[T; 3]],
        at: &Pose<T>,
        out: &mut Located<T>,
    ) {
        out.state = State::Lost;
        let mut search = self.search.unwrap_or_else(Search::new);
        let gate = self.settings.gate_floor;
        for _ in 0..self.settings.search_per_frame {
            if search.done() {
                break;
            }
            let from = search::start(search.next, at);
            let (pose, share, obs) = self.register(exec, source, &from, gate);
            if obs.is_some_and(|o| o >= self.settings.min_observability) {
                search.note(pose * at.inverse(), share);
            }
            search.next += 1;
            out.searched += 1;
        }
        if search.done() {
            let s = &self.settings;
            if let Some(correction) = search.verdict(s.good_share, s.search_margin) {
                out.pose = correction * at;
                renormalize(&mut out.pose);
                out.correction = (out.pose.translation.vector - at.translation.vector).norm();
                out.state = State::Degraded;
                out.recovered = true;
                self.confirmed = 0;
                self.since_fix = (T::zero(), 0);
                self.fixed = false;
                self.misfits = 0;
                self.search = None;
                return;
            }
            search = Search::new();
        }
        self.search = Some(search);
    }
}

#[cfg(test)]
mod tests;
