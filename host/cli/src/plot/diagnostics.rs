//! `diagnostics.png`: what went wrong where, beside `trajectory.png`. Stacked panels: the
//! position error against distance travelled (when there is ground truth), then the core's
//! latency and ICP iterations per frame; frames the core flagged degenerate, stopped at the
//! iteration cap or by the work budget, or registered with robust mode's plane terms are marked
//! in every panel.

use super::style::{font_available, titled, ESTIMATE_COLOR};
use anyhow::{anyhow, bail, Context, Result};
use kiss_odom_core::{Flag, Status};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Image size in pixels.
pub const WIDTH: u32 = 1000;
/// Image height in pixels.
pub const HEIGHT: u32 = 1000;

/// The flags marked, each with its colour.
pub const MARKED: [(Flag, RGBColor); 4] = [
    (Flag::Degenerate, RGBColor(214, 39, 40)),
    (Flag::IterationCap, RGBColor(148, 103, 189)),
    (Flag::Budget, RGBColor(255, 127, 14)),
    (Flag::Planes, RGBColor(140, 86, 75)),
];

/// One frame of the diagnostics.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FramePoint {
    /// Frame index.
    pub index: usize,
    /// Core latency (ms), if the frame reached the core.
    pub latency_ms: Option<f64>,
    /// ICP iterations, if registered.
    pub iterations: Option<u32>,
    /// The core's flags.
    pub status: Status,
    /// Distance travelled along the ground truth up to this frame (m) and the position error
    /// there (m), when the frame has ground truth.
    pub error: Option<(f64, f64)>,
}

/// Writes the diagnostics of `frames` to `path` (see the module doc), titled `title`.
///
/// Fails with no frame, a non-finite value, or when the file cannot be written; never because
/// no font is installed (the panels are then drawn without text).
pub fn diagnostics_png(path: &Path, frames: &[FramePoint], title: &str) -> Result<()> {
    render(path, frames, title, font_available())
        .with_context(|| format!("cannot plot {}", path.display()))
}

/// What drawing on a bitmap can fail with.
type DrawResult =
    Result<(), DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>>;

/// A series of (x, y) and the frames' flags at each point.
type Series = Vec<(f64, f64, Status)>;

fn render(path: &Path, frames: &[FramePoint], title: &str, text: bool) -> Result<()> {
    if frames.is_empty() {
        bail!("no frames");
    }
    let x = |f: &FramePoint| f.index as f64;
    let error: Series = frames
        .iter()
        .filter_map(|f| f.error.map(|(d, e)| (d, e, f.status)))
        .collect();
    let latency: Series = frames
        .iter()
        .filter_map(|f| f.latency_ms.map(|l| (x(f), l, f.status)))
        .collect();
    let iterations: Series = frames
        .iter()
        .filter_map(|f| f.iterations.map(|i| (x(f), f64::from(i), f.status)))
        .collect();
    for (name, s) in [("error", &error), ("latency", &latency)] {
        if let Some(p) = s.iter().find(|p| !(p.0.is_finite() && p.1.is_finite())) {
            bail!("{name} at {} is not finite", p.0);
        }
    }

    let err = |e: &dyn std::fmt::Display| anyhow!("{e}");
    let root = BitMapBackend::new(path, (WIDTH, HEIGHT)).into_drawing_area();
    let area = titled(&root, title, text)?;
    let mut panels: Vec<(Series, &str, &str)> = Vec::new();
    if !error.is_empty() {
        panels.push((error, "distance travelled [m]", "position error [m]"));
    }
    panels.push((latency, "frame", "core latency [ms]"));
    panels.push((iterations, "frame", "ICP iterations"));
    let areas = area.split_evenly((panels.len(), 1));
    for (k, ((series, x_desc, y_desc), a)) in panels.iter().zip(&areas).enumerate() {
        panel(a, series, x_desc, y_desc, text && k == 0, text).map_err(|e| err(&e))?;
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// One panel: the series as a line, flagged frames as filled markers; the legend of the
/// markers when `legend`.
fn panel(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    series: &Series,
    x_desc: &str,
    y_desc: &str,
    legend: bool,
    text: bool,
) -> DrawResult {
    let (mut x0, mut x1, mut y1) = (f64::MAX, f64::MIN, 0.0_f64);
    for &(x, y, _) in series {
        (x0, x1, y1) = (x0.min(x), x1.max(x), y1.max(y));
    }
    if series.is_empty() {
        (x0, x1) = (0.0, 1.0);
    }
    if x1 - x0 < 1e-9 {
        x1 = x0 + 1.0;
    }
    let y1 = if y1 > 0.0 { y1 * 1.1 } else { 1.0 };
    let (x_lab, y_lab) = if text { (40, 70) } else { (0, 0) };
    let mut chart = ChartBuilder::on(area)
        .margin(15)
        .x_label_area_size(x_lab)
        .y_label_area_size(y_lab)
        .build_cartesian_2d(x0..x1, 0.0..y1)?;
    let mut mesh = chart.configure_mesh();
    if text {
        mesh.x_desc(x_desc)
            .y_desc(y_desc)
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .light_line_style(RGBColor(235, 235, 235));
    } else {
        mesh.x_labels(0)
            .y_labels(0)
            .disable_x_mesh()
            .disable_y_mesh();
    }
    mesh.draw()?;
    chart.draw_series(LineSeries::new(
        series.iter().map(|&(x, y, _)| (x, y)),
        ESTIMATE_COLOR.stroke_width(2),
    ))?;
    for (flag, colour) in MARKED {
        let marked = series.iter().filter(|p| p.2.contains(flag));
        let drawn =
            chart.draw_series(marked.map(|&(x, y, _)| Circle::new((x, y), 6, colour.filled())))?;
        if legend {
            drawn
                .label(flag.name())
                .legend(move |(x, y)| Circle::new((x + 10, y), 5, colour.filled()));
        }
    }
    if legend {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 16))
            .draw()?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::style::png_pixels::{count, decode};

    fn frames(n: usize, with_error: bool) -> Vec<FramePoint> {
        (0..n)
            .map(|i| FramePoint {
                index: i,
                latency_ms: Some(20.0 + (i % 7) as f64),
                iterations: Some(3 + (i % 5) as u32),
                status: if i == 5 {
                    Status::OK.with(Flag::Degenerate)
                } else if i == 9 {
                    Status::OK.with(Flag::IterationCap)
                } else if i == 13 {
                    Status::OK.with(Flag::Budget)
                } else if i == 19 {
                    Status::OK.with(Flag::Planes)
                } else {
                    Status::OK
                },
                error: with_error.then_some((i as f64 * 1.5, 0.01 * i as f64)),
            })
            .collect()
    }

    #[test]
    fn panels_draw_the_series_and_mark_flagged_frames() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("d.png");
        diagnostics_png(&path, &frames(20, true), "sample").unwrap();
        let (w, h, pixels) = decode(&path);
        assert_eq!((w, h), (WIDTH, HEIGHT));
        // Three panels of a 2-px line each: well over a thousand pixels in all.
        let line = count(&pixels, ESTIMATE_COLOR);
        assert!(line > 1000, "series pixels: {line}");
        for (flag, colour) in MARKED {
            // A filled marker of radius 6 in each of three panels (and one in the legend).
            let n = count(&pixels, colour);
            assert!(n > 3 * 80, "{} marker pixels: {n}", flag.name());
        }
    }

    #[test]
    fn without_ground_truth_or_fonts_two_panels_still_show() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("d.png");
        render(&path, &frames(20, false), "t", false).unwrap();
        let (_, _, pixels) = decode(&path);
        assert!(count(&pixels, ESTIMATE_COLOR) > 500);
        // Two panels, one marker each.
        let n = count(&pixels, MARKED[0].1);
        assert!((2 * 80..4 * 130).contains(&n), "marker pixels: {n}");
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("d.png");
        assert!(diagnostics_png(&path, &[], "t").is_err());
        let mut f = frames(3, true);
        f[1].latency_ms = Some(f64::INFINITY);
        assert!(diagnostics_png(&path, &f, "t").is_err());
        let one = frames(1, true);
        diagnostics_png(&path, &one, "one frame").unwrap();
    }
}
