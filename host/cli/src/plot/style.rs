//! What every plot shares: its colours, the system font text needs, and the title.

use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use std::sync::OnceLock;

/// Colour of the estimated trajectory.
pub const ESTIMATE_COLOR: RGBColor = RGBColor(31, 119, 180);
/// Colour of the ground truth.
pub const GROUND_TRUTH_COLOR: RGBColor = RGBColor(255, 127, 14);
/// Colour of the start marker.
pub const START_COLOR: RGBColor = RGBColor(44, 160, 44);

/// Where TrueType fonts usually are (Debian/Ubuntu, Fedora, Arch, Alpine, macOS, Windows).
const FONT_CANDIDATES: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation-sans/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
    "/usr/share/fonts/noto/NotoSans-Regular.ttf",
    "/usr/share/fonts/truetype/noto/NotoSans-Regular.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf",
    "/Library/Fonts/Arial.ttf",
    "C:\\Windows\\Fonts\\arial.ttf",
];

/// Registers the first usable system font as `sans-serif` (once per process); `true` if text
/// can be drawn.
pub fn font_available() -> bool {
    static READY: OnceLock<bool> = OnceLock::new();
    *READY.get_or_init(|| {
        FONT_CANDIDATES.iter().any(|path| {
            let Ok(bytes) = std::fs::read(path) else {
                return false;
            };
            // plotters keeps fonts for the life of the process: leak the one we register.
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            register_font("sans-serif", FontStyle::Normal, bytes).is_ok()
        })
    })
}

/// Fills `root` white and, when `text`, draws `title` on top: the area left for the chart.
pub fn titled<'a>(
    root: &DrawingArea<BitMapBackend<'a>, Shift>,
    title: &str,
    text: bool,
) -> Result<DrawingArea<BitMapBackend<'a>, Shift>> {
    root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
    if !text {
        return Ok(root.clone());
    }
    // The top margin keeps the title's ascenders inside the image.
    root.margin(10, 0, 0, 0)
        .titled(title, ("sans-serif", 28))
        .map_err(|e| anyhow!("{e}"))
}

/// PNG checks the plot tests share.
#[cfg(test)]
pub mod png_pixels {
    use plotters::style::RGBColor;
    use std::path::Path;

    /// Width, height and RGB pixels of a PNG, after checking its signature and IHDR by hand.
    pub fn decode(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
        let bytes = std::fs::read(path).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
        assert_eq!(&bytes[12..16], b"IHDR");
        let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
        let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb);
        let pixels = buf[..info.buffer_size()]
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        (w, h, pixels)
    }

    pub fn count(pixels: &[[u8; 3]], c: RGBColor) -> usize {
        pixels.iter().filter(|p| **p == [c.0, c.1, c.2]).count()
    }
}
