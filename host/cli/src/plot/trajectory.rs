//! `trajectory.png`: a top view (x against y, same metres per pixel on both axes) of the
//! estimate and, when known, the ground truth.

use super::style::{font_available, titled, ESTIMATE_COLOR, GROUND_TRUTH_COLOR, START_COLOR};
use anyhow::{anyhow, bail, Context, Result};
use nalgebra::Isometry3;
use plotters::prelude::*;
use std::ops::Range;
use std::path::Path;

/// Image size in pixels.
const WIDTH: u32 = 1000;
const HEIGHT: u32 = 1000;
const MARGIN: u32 = 20;
const X_LABEL_AREA: u32 = 50;
const Y_LABEL_AREA: u32 = 80;

/// Writes a PNG top view of `estimate` (and `ground_truth` when given): x against y in metres
/// with equal scale on both axes, a marker at the start, a legend and `title`.
///
/// Fails on an empty or non-finite trajectory and when the file cannot be written; never
/// because no font is installed (the plot is then drawn without text).
pub fn trajectory_png(
    path: &Path,
    estimate: &[Isometry3<f64>],
    ground_truth: Option<&[Isometry3<f64>]>,
    title: &str,
) -> Result<()> {
    render(path, estimate, ground_truth, title, font_available())
        .with_context(|| format!("cannot plot {}", path.display()))
}

fn xy(poses: &[Isometry3<f64>], which: &str) -> Result<Vec<(f64, f64)>> {
    poses
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (x, y) = (p.translation.x, p.translation.y);
            if x.is_finite() && y.is_finite() {
                Ok((x, y))
            } else {
                bail!("{which} position at frame {i} is not finite")
            }
        })
        .collect()
}

/// Axis ranges covering `points` with the same metres per pixel on both axes for a plotting
/// area of `px_w` x `px_h` pixels; 5 % padding and at least 1 m of extent.
fn equal_scale_ranges(points: &[(f64, f64)], px_w: u32, px_h: u32) -> (Range<f64>, Range<f64>) {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in points {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if points.is_empty() {
        (x0, x1, y0, y1) = (0.0, 0.0, 0.0, 0.0);
    }
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let (px_w, px_h) = (f64::from(px_w.max(1)), f64::from(px_h.max(1)));
    // Metres per pixel that fits both extents.
    let scale = ((x1 - x0) / px_w)
        .max((y1 - y0) / px_h)
        .max(1.0 / px_w.min(px_h))
        * 1.05;
    let (hw, hh) = (0.5 * scale * px_w, 0.5 * scale * px_h);
    (cx - hw..cx + hw, cy - hh..cy + hh)
}

fn render(
    path: &Path,
    estimate: &[Isometry3<f64>],
    ground_truth: Option<&[Isometry3<f64>]>,
    title: &str,
    text: bool,
) -> Result<()> {
    if estimate.is_empty() {
        bail!("the estimate has no poses");
    }
    let est = xy(estimate, "estimate")?;
    let gt = match ground_truth {
        Some(g) => Some(xy(g, "ground truth")?),
        None => None,
    };
    let all: Vec<(f64, f64)> = est.iter().chain(gt.iter().flatten()).copied().collect();

    let draw_err = |e: &dyn std::fmt::Display| anyhow!("{e}");
    let root = BitMapBackend::new(path, (WIDTH, HEIGHT)).into_drawing_area();
    let area = titled(&root, title, text)?;
    let (x_lab, y_lab) = if text {
        (X_LABEL_AREA, Y_LABEL_AREA)
    } else {
        (0, 0)
    };
    let (w, h) = area.dim_in_pixel();
    let px_w = w.saturating_sub(2 * MARGIN + y_lab);
    let px_h = h.saturating_sub(2 * MARGIN + x_lab);
    let (xr, yr) = equal_scale_ranges(&all, px_w, px_h);

    let mut chart = ChartBuilder::on(&area)
        .margin(MARGIN)
        .x_label_area_size(x_lab)
        .y_label_area_size(y_lab)
        .build_cartesian_2d(xr, yr)
        .map_err(|e| draw_err(&e))?;
    if text {
        chart
            .configure_mesh()
            .x_desc("x [m]")
            .y_desc("y [m]")
            .label_style(("sans-serif", 16))
            .axis_desc_style(("sans-serif", 18))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(|e| draw_err(&e))?;
    } else {
        chart
            .configure_mesh()
            .x_labels(0)
            .y_labels(0)
            .disable_x_mesh()
            .disable_y_mesh()
            .draw()
            .map_err(|e| draw_err(&e))?;
    }

    if let Some(gt) = gt {
        let series = chart
            .draw_series(LineSeries::new(gt, GROUND_TRUTH_COLOR.stroke_width(2)))
            .map_err(|e| draw_err(&e))?;
        if text {
            series.label("ground truth").legend(|(x, y)| {
                PathElement::new([(x, y), (x + 20, y)], GROUND_TRUTH_COLOR.stroke_width(2))
            });
        }
    }
    let start = est[0];
    let series = chart
        .draw_series(LineSeries::new(est, ESTIMATE_COLOR.stroke_width(2)))
        .map_err(|e| draw_err(&e))?;
    if text {
        series.label("estimate").legend(|(x, y)| {
            PathElement::new([(x, y), (x + 20, y)], ESTIMATE_COLOR.stroke_width(2))
        });
    }
    let series = chart
        .draw_series(std::iter::once(Circle::new(start, 7, START_COLOR.filled())))
        .map_err(|e| draw_err(&e))?;
    if text {
        series
            .label("start")
            .legend(|(x, y)| Circle::new((x + 10, y), 5, START_COLOR.filled()));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 18))
            .draw()
            .map_err(|e| draw_err(&e))?;
    }
    root.present().map_err(|e| draw_err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::style::png_pixels::{count, decode};
    use nalgebra::{Translation3, UnitQuaternion};

    fn circle(n: usize, radius: f64) -> Vec<Isometry3<f64>> {
        (0..n)
            .map(|i| {
                let a = i as f64 / n as f64 * std::f64::consts::TAU;
                Isometry3::from_parts(
                    Translation3::new(radius * a.cos(), radius * a.sin(), 0.0),
                    UnitQuaternion::identity(),
                )
            })
            .collect()
    }

    #[test]
    fn png_is_written_with_estimate_and_ground_truth_colours() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("traj.png");
        let est = circle(200, 50.0);
        let gt = circle(200, 40.0);
        trajectory_png(&path, &est, Some(&gt), "circle").unwrap();
        let (w, h, pixels) = decode(&path);
        assert_eq!((w, h), (WIDTH, HEIGHT));
        assert_eq!(pixels.len(), (w * h) as usize);
        let (e, g) = (
            count(&pixels, ESTIMATE_COLOR),
            count(&pixels, GROUND_TRUTH_COLOR),
        );
        // A 2-px circle of radius ~400 px: thousands of pixels of each colour.
        assert!(e > 1000, "estimate pixels: {e}");
        assert!(g > 1000, "ground-truth pixels: {g}");
    }

    #[test]
    fn png_without_fonts_still_shows_the_estimate() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("traj.png");
        render(&path, &circle(100, 5.0), None, "no text", false).unwrap();
        let (_, _, pixels) = decode(&path);
        assert!(count(&pixels, ESTIMATE_COLOR) > 1000);
        assert_eq!(count(&pixels, GROUND_TRUTH_COLOR), 0);
    }

    #[test]
    fn single_pose_and_straight_line_plot_without_error() {
        let dir = tempfile::tempdir().unwrap();
        trajectory_png(&dir.path().join("a.png"), &circle(1, 0.0), None, "one").unwrap();
        let line: Vec<_> = (0..50)
            .map(|i| Isometry3::translation(i as f64, 0.0, 0.0))
            .collect();
        trajectory_png(&dir.path().join("b.png"), &line, Some(&line), "line").unwrap();
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.png");
        assert!(trajectory_png(&path, &[], None, "empty").is_err());
        let nan = [Isometry3::translation(f64::NAN, 0.0, 0.0)];
        assert!(trajectory_png(&path, &nan, None, "nan").is_err());
        let missing = dir.path().join("no/such/dir/x.png");
        assert!(trajectory_png(&missing, &circle(10, 1.0), None, "t").is_err());
    }

    #[test]
    fn ranges_have_equal_metres_per_pixel() {
        let pts = [(0.0, 0.0), (100.0, 10.0)];
        let (xr, yr) = equal_scale_ranges(&pts, 800, 400);
        let sx = (xr.end - xr.start) / 800.0;
        let sy = (yr.end - yr.start) / 400.0;
        assert!((sx - sy).abs() < 1e-12, "{sx} vs {sy}");
        assert!(xr.start < 0.0 && xr.end > 100.0 && yr.start < 0.0 && yr.end > 10.0);
    }
}
