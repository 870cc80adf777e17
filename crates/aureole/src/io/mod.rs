//! Files: HDR and display images in and out, kernels out as PFM, EXR and
//! PNG pictures; every write atomic.

pub mod atomic;
pub mod exr;
pub mod pfm;
pub mod picture;
pub mod read;
pub mod write;

use std::path::Path;

use crate::error::{Error, Result};
use crate::kernel::Kernel;

/// The kernel formats, by extension.
pub const KERNEL_EXTENSIONS: &str = ".pfm (float32), .exr (float32), .png (log-scaled picture)";

/// The image formats we write, by extension: linear, then for display.
pub const IMAGE_EXTENSIONS: &str = ".exr, .hdr, .pfm (linear) or .png, .jpg, .tif (for display)";

/// Whether `path` names a display format (tone mapped, sRGB) rather than a
/// linear one.
pub fn is_display_format(path: &Path) -> bool {
    matches!(
        extension(path).as_str(),
        "png" | "jpg" | "jpeg" | "tif" | "tiff"
    )
}

/// Writes `kernel` to `path` in the format its extension names: `.pfm`,
/// `.exr` or `.png`. The file appears whole or not at all.
pub fn write_kernel(path: &Path, kernel: &Kernel) -> Result<()> {
    match extension(path).as_str() {
        "pfm" => pfm::write(path, kernel.width(), kernel.height(), kernel.channels()),
        "exr" => exr::write(path, kernel.width(), kernel.height(), kernel.channels()),
        "png" => picture::write_log_png(path, kernel),
        other => Err(Error::OutputFormat {
            path: path.to_path_buf(),
            extension: other.to_string(),
            allowed: KERNEL_EXTENSIONS,
        }),
    }
}

/// The lower-case extension of `path`, empty if none.
pub fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default()
}
