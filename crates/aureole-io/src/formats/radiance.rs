//! Radiance RGBE (`.hdr`) out, through the `image` crate: three channels
//! sharing an exponent, no negatives and no alpha. Files are decoded with
//! the pictures ([`super::picture::decode`]).

use std::path::Path;

use image::{codecs::hdr::HdrEncoder, Rgb};

use super::{LinearPlanes, Note};
use crate::atomic::write_atomic;
use crate::error::{Error, Result};

const NAME: &str = "Radiance RGBE";

/// Writes the planes as RGBE (a luminance plane in all three channels),
/// negatives as 0, atomically.
pub(crate) fn encode(path: &Path, planes: LinearPlanes) -> Result<Vec<Note>> {
    let mut notes = Vec::new();
    let colour = &planes.colour;
    let negatives = colour
        .iter()
        .flat_map(|p| p.iter())
        .filter(|v| **v < 0.0)
        .count();
    if negatives > 0 {
        notes.push(Note::NegativesZeroed {
            count: negatives,
            format: NAME,
        });
    }
    if planes.alpha.is_some() {
        notes.push(Note::AlphaDropped {
            format: "Radiance .hdr",
        });
    }
    let plane = |c: usize| colour[c.min(colour.len() - 1)];
    let pixels: Vec<Rgb<f32>> = (0..planes.width * planes.height)
        .map(|i| Rgb([0, 1, 2].map(|c| plane(c)[i].max(0.0))))
        .collect();
    write_atomic(path, |out| {
        HdrEncoder::new(out)
            .encode(&pixels, planes.width, planes.height)
            .map_err(|e| Error::Encode {
                path: path.to_path_buf(),
                format: "Radiance HDR",
                message: e.to_string(),
            })
    })?;
    Ok(notes)
}
