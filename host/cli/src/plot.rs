//! Plots a run leaves next to its poses and metrics: `trajectory.png`, a top view (x against
//! y, same metres per pixel on both axes) of the estimate and, when known, the ground truth;
//! and `diagnostics.png` (`diagnostics_png`), the error, latency and iterations per frame.
//!
//! Text needs a TrueType font, which `plotters` (built with `ab_glyph`) does not ship: one is
//! loaded from the usual system places the first time a plot is drawn. Without one the plot is
//! still drawn, just without title, labels and legend.

mod diagnostics;
mod style;
mod trajectory;

pub(crate) use diagnostics::{diagnostics_png, FramePoint};
pub use style::ESTIMATE_COLOR;
pub(crate) use trajectory::trajectory_png;
