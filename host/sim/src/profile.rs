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
}
