//! Writing linear images: OpenEXR, Radiance .hdr and PFM.

use std::path::Path;

use image::{codecs::hdr::HdrEncoder, Rgb};

use super::atomic::write_atomic;
use super::exr::{write_planes, ExrPlanes};
use crate::error::{Error, Result};
use crate::image::{Image, Layout};

/// The largest finite half float.
pub const HALF_MAX: f32 = 65504.0;

/// A copy with every colour sample clamped to the half range, and how many
/// were clamped.
fn clamp_to_half(image: &Image) -> (Image, usize) {
    let mut copy = image.clone();
    let mut count = 0;
    for v in copy.planes.iter_mut().flatten() {
        if v.abs() > HALF_MAX {
            *v = v.clamp(-HALF_MAX, HALF_MAX);
            count += 1;
        }
    }
    (copy, count)
}

/// How to store a linear image.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LinearOptions {
    /// EXR only: half floats instead of float32.
    pub half: bool,
}

/// Writes `image` as `.exr`, `.hdr` or `.pfm` by the extension of `path`,
/// atomically. Returns remarks for the user (what the format could not keep).
pub fn write_linear(path: &Path, image: &Image, options: LinearOptions) -> Result<Vec<String>> {
    let mut notes = Vec::new();
    match super::extension(path).as_str() {
        "exr" => {
            let clamped;
            let image = if options.half {
                let (copy, count) = clamp_to_half(image);
                if count > 0 {
                    notes.push(format!(
                        "{count} samples beyond ±{HALF_MAX} (the largest half float) written as ±{HALF_MAX}; drop --half to keep them"
                    ));
                }
                clamped = copy;
                &clamped
            } else {
                image
            };
            let mut planes: Vec<(&'static str, &[f32])> = match image.layout {
                Layout::Luminance => vec![("Y", &image.planes[0])],
                Layout::Rgb => vec![
                    ("R", &image.planes[0]),
                    ("G", &image.planes[1]),
                    ("B", &image.planes[2]),
                ],
            };
            if let Some(alpha) = &image.alpha {
                planes.push(("A", alpha));
            }
            write_planes(
                path,
                &ExrPlanes {
                    width: image.width,
                    height: image.height,
                    planes,
                    half: options.half,
                    white_luminance: image.white_luminance,
                    primaries: image.primaries,
                },
            )?;
        }
        "pfm" => {
            if image.alpha.is_some() {
                notes.push("PFM has no alpha channel: alpha not written".to_string());
            }
            super::pfm::write(path, image.width, image.height, &image.planes)?;
        }
        "hdr" => {
            let negatives = image.planes.iter().flatten().filter(|v| **v < 0.0).count();
            if negatives > 0 {
                notes.push(format!(
                    "Radiance RGBE holds no negative values: {negatives} samples written as 0"
                ));
            }
            if image.alpha.is_some() {
                notes.push("Radiance .hdr has no alpha channel: alpha not written".to_string());
            }
            let plane = |c: usize| &image.planes[c.min(image.planes.len() - 1)];
            let pixels: Vec<Rgb<f32>> = (0..image.width * image.height)
                .map(|i| Rgb([0, 1, 2].map(|c| plane(c)[i].max(0.0))))
                .collect();
            write_atomic(path, |out| {
                HdrEncoder::new(out)
                    .encode(&pixels, image.width, image.height)
                    .map_err(|e| Error::Encode {
                        path: path.to_path_buf(),
                        format: "Radiance HDR",
                        message: e.to_string(),
                    })
            })?;
        }
        other => {
            return Err(Error::OutputFormat {
                path: path.to_path_buf(),
                extension: other.to_string(),
                allowed: super::IMAGE_EXTENSIONS,
            })
        }
    }
    Ok(notes)
}
