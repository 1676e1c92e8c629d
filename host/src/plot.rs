//! Trajectory plots (being written).
