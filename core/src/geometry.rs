//! The two geometric types every stage shares.

/// Rigid transform used for every pose: a unit quaternion and a translation.
pub type Pose<T> = nalgebra::Isometry3<T>;
/// A 3D point.
pub type Point<T> = nalgebra::Point3<T>;
