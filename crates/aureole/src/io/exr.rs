//! OpenEXR output through the `exr` crate: float32, one `Y` channel for an
//! achromatic plane or `R`, `G`, `B`.

use exr::prelude::*;

use super::atomic::write_atomic;
use crate::error::{Error, Result};

/// Writes one plane as `Y` or three as `R`, `G`, `B`, float32, ZIP
/// compressed (lossless).
pub fn write(
    path: &std::path::Path,
    width: usize,
    height: usize,
    channels: &[Vec<f32>],
) -> Result<()> {
    let names: &[&str] = match channels.len() {
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
    let list = names
        .iter()
        .zip(channels)
        .map(|(name, plane)| AnyChannel::new(*name, FlatSamples::F32(plane.clone())))
        .collect();
    let layer = Layer::new(
        (width, height),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    let image = Image::from_layer(layer);
    write_atomic(path, |out| {
        image.write().to_buffered(out).map_err(|e| Error::Encode {
            path: path.to_path_buf(),
            format: "EXR",
            message: e.to_string(),
        })
    })
}
