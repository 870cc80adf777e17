//! OpenEXR output through the `exr` crate: float32 (or half) planes named
//! `Y` or `R`, `G`, `B` (and `A`), ZIP compressed (lossless).

use exr::prelude::*;

use super::atomic::write_atomic;
use crate::error::{Error, Result};

/// Named planes of one image, with what its header should carry.
pub struct ExrPlanes<'a> {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// (channel name, row-major plane) pairs.
    pub planes: Vec<(&'static str, &'a [f32])>,
    /// Store half floats instead of float32.
    pub half: bool,
    /// The `whiteLuminance` attribute to keep, cd/m² of the value 1.
    pub white_luminance: Option<f32>,
    /// The `chromaticities` attribute to keep.
    pub primaries: Option<crate::image::Primaries>,
}

/// Writes the planes to `path` atomically.
pub fn write_planes(path: &std::path::Path, image: &ExrPlanes<'_>) -> Result<()> {
    let list = image
        .planes
        .iter()
        .map(|(name, plane)| {
            let samples = if image.half {
                FlatSamples::F16(plane.iter().map(|&v| f16::from_f32(v)).collect())
            } else {
                FlatSamples::F32(plane.to_vec())
            };
            AnyChannel::new(*name, samples)
        })
        .collect();
    let attributes = LayerAttributes {
        white_luminance: image.white_luminance,
        ..LayerAttributes::default()
    };
    let layer = Layer::new(
        (image.width, image.height),
        attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    let mut exr_image = Image::from_layer(layer);
    exr_image.attributes.chromaticities =
        image
            .primaries
            .map(|p| exr::meta::attribute::Chromaticities {
                red: Vec2(p.red[0], p.red[1]),
                green: Vec2(p.green[0], p.green[1]),
                blue: Vec2(p.blue[0], p.blue[1]),
                white: Vec2(p.white[0], p.white[1]),
            });
    write_atomic(path, |out| {
        exr_image
            .write()
            .to_buffered(out)
            .map_err(|e| Error::Encode {
                path: path.to_path_buf(),
                format: "EXR",
                message: e.to_string(),
            })
    })
}

/// Writes one plane as `Y` or three as `R`, `G`, `B`, float32.
pub fn write(
    path: &std::path::Path,
    width: usize,
    height: usize,
    channels: &[Vec<f32>],
) -> Result<()> {
    let names: &[&'static str] = match channels.len() {
        1 => &["Y"],
        3 => &["R", "G", "B"],
        n => {
            return Err(Error::Encode {
                path: path.to_path_buf(),
                format: "EXR",
                message: format!("expected 1 or 3 channels, not {n}"),
            })
        }
    };
    write_planes(
        path,
        &ExrPlanes {
            width,
            height,
            planes: names
                .iter()
                .zip(channels)
                .map(|(n, p)| (*n, p.as_slice()))
                .collect(),
            half: false,
            white_luminance: None,
            primaries: None,
        },
    )
}
