//! Kernel pictures for people: log-scaled, like the paper's "filter
//! profile" images, so that faint rays and the bright core both show.

use std::path::Path;

use image::{ImageBuffer, ImageFormat, Rgb};

use super::atomic::write_atomic;
use crate::error::{Error, Result};
use crate::kernel::Kernel;

/// Decades of weight the picture spans, from its brightest spread pixel down.
pub const PICTURE_DECADES: f64 = 6.0;

/// Writes an 8-bit PNG where grey level ∝ log₁₀ K over
/// [`PICTURE_DECADES`] decades below the brightest pixel outside the centre
/// (the unspread centre is far brighter and shows white). A coloured kernel
/// gives a colour picture, all channels on one scale.
pub fn write_log_png(path: &Path, kernel: &Kernel) -> Result<()> {
    let (width, height) = (kernel.width(), kernel.height());
    let (cx, cy) = kernel.centre();
    let centre = cy * width + cx;
    let peak = kernel
        .channels()
        .iter()
        .flat_map(|plane| {
            plane
                .iter()
                .enumerate()
                .filter(move |&(i, _)| i != centre || plane.len() == 1)
                .map(|(_, &v)| v)
        })
        .fold(0f32, f32::max);
    let top = if peak > 0.0 { f64::from(peak) } else { 1.0 };
    let level = |v: f32| {
        let t = 1.0 + (f64::from(v).max(1e-300) / top).log10() / PICTURE_DECADES;
        (t.clamp(0.0, 1.0) * 255.0).round() as u8
    };
    let planes = kernel.channels();
    let picture = ImageBuffer::from_fn(width as u32, height as u32, |x, y| {
        let i = y as usize * width + x as usize;
        let at = |c: usize| level(planes[c.min(planes.len() - 1)][i]);
        Rgb([at(0), at(1), at(2)])
    });
    write_atomic(path, |out| {
        picture
            .write_to(out, ImageFormat::Png)
            .map_err(|e| Error::Encode {
                path: path.to_path_buf(),
                format: "PNG",
                message: e.to_string(),
            })
    })
}
