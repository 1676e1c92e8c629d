//! The scenes and motions a simulated sequence can have.

use serde::Serialize;

/// Scene and motion of a simulated sequence.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Profile {
    /// City streets and side streets (buildings, parked cars, poles, trees, kerb clutter),
    /// driven from a standing start at 5-15 m/s with car-like turns.
    Urban,
    /// An endless featureless tunnel along x, driven at 3-8 m/s: degenerate along its axis.
    Corridor,
    /// The urban scene at 20-30 m/s (after a 3 s launch) with turns near 1 rad/s: strong
    /// motion distortion.
    Fast,
    /// A lone ground plane, driven like urban: degenerate in x, y and yaw.
    Plane,
    /// The corridor with sparse structure on its walls (pillars, door frames, cabinets every
    /// 10-40 m): observable along the axis, but weakly, as a real tunnel is.
    Tunnel,
    /// The lone ground plane with sparse objects (poles, trees, boulders 20-60 m apart along
    /// the route): observable in x, y and yaw, but weakly, as an open field is.
    Field,
    /// Long suburban streets at 55-65 km/h with gentle turns, houses in rows out to 100 m on
    /// both sides, yards, hedges, trees and lamp posts: a 16-beam sensor's map fills its whole
    /// `r_max` disc (use with `--sensor vlp16`).
    Suburban,
    /// The urban scene walked with a hand-held sensor at 1-1.8 m/s from a standing start: the
    /// walker looks around (yaw swings up to about 150 deg/s), the hand pitches and rolls by
    /// 5-15 degrees and bobs with each step.
    Handheld,
    /// The urban scene flown at 3-10 m/s, 5-11 m up with climbs and descents up to 2.5 m/s,
    /// banking into turns, with fast yaw swings (up to about 200 deg/s).
    Drone,
    /// A warehouse-like corridor network: aisles 3-4 m wide between long rows of racks (3-6 m
    /// tall, with gaps) under an 8 m ceiling, cross aisles every 20-40 m, driven at 1.5-3 m/s
    /// with right-angle turns.
    Warehouse,
    /// A road through dense woodland out past 100 m (crowns and shrubs as foliage volumes),
    /// hillsides rising beside it to plateaus, and overpasses on piers with sloping ramps,
    /// driven at 30-43 km/h on `suburban`'s roads: a map fills its `r_max` ball in depth,
    /// many times what streets give.
    Forest,
}

impl Profile {
    /// Whether the sensor swings about its path (a hand or a multirotor, not a car).
    pub const fn swings(self) -> bool {
        matches!(self, Self::Handheld | Self::Drone)
    }
}
