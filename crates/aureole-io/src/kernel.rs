//! Kernel files: planes out and in (PFM, EXR), and pictures for people,
//! log-scaled like the paper's "filter profile" images so that faint rays
//! and the bright core both show.

use std::path::Path;

use aureole::Kernel;

use crate::display::Picture;
use crate::error::{Error, Result};
use crate::formats::{by_extension, extension, kernel_outputs, Encoder, KernelStorage};
use crate::formats::{picture, LinearPlanes};
use crate::limits::Limits;
use crate::read::read_image;

/// Decades of weight the picture spans, from its brightest spread pixel down.
pub const PICTURE_DECADES: f64 = 6.0;

pub use crate::formats::{
    KernelRecord, IMAGE_WIDTH_ATTRIBUTE, LIGHT_ATTRIBUTE, THRESHOLD_ATTRIBUTE,
};

/// Writes `kernel` to `path` in the format its extension names: its planes
/// as float32 (`.pfm`: `Pf` or `PF`; `.exr`: `Y` or `R`, `G`, `B`,
/// uncompressed), or a log-scaled picture (`.png`). The file appears whole
/// or not at all.
pub fn write_kernel(path: &Path, kernel: &Kernel) -> Result<()> {
    write_kernel_for(path, kernel, KernelRecord::default())
}

/// [`write_kernel`], recording in an EXR what the kernel was built for: the
/// width of its images ([`IMAGE_WIDTH_ATTRIBUTE`]), so that applying it to
/// another width can be refused, its camera's threshold
/// ([`THRESHOLD_ATTRIBUTE`]), and that its planes hold the shares of light
/// that fall within them ([`LIGHT_ATTRIBUTE`]). PFM has no room for them:
/// a PFM kernel is read as holding all its light.
pub fn write_kernel_for(path: &Path, kernel: &Kernel, record: KernelRecord) -> Result<()> {
    let least = (0..kernel.planes().len())
        .map(|c| kernel.sum(c))
        .fold(f64::INFINITY, f64::min);
    let record = KernelRecord {
        shares: Some(least),
        ..record
    };
    let refuse = || Error::OutputFormat {
        path: path.to_path_buf(),
        extension: extension(path),
        allowed: kernel_outputs(),
    };
    let format = by_extension(path).ok_or_else(refuse)?;
    match (format.kernels, &format.encode) {
        (KernelStorage::Planes, Encoder::Linear(encode)) => {
            let planes = LinearPlanes {
                width: kernel.width(),
                height: kernel.height(),
                colour: kernel.planes().iter().map(Vec::as_slice).collect(),
                alpha: None,
                white_luminance: None,
                primaries: None,
                samples: Some(crate::formats::Samples::Float),
                // A float kernel's mantissas are noise to deflate: ZIP keeps
                // 91 % of a 4K lens kernel and takes seconds both ways,
                // so kernels are stored as they are.
                compression: Some(crate::compression::Compression::None),
                original: Default::default(),
                kernel: record,
            };
            encode(path, planes).map(drop)
        }
        (KernelStorage::LogPicture, Encoder::Picture(encoding)) => picture::encode_samples(
            path,
            (kernel.width(), kernel.height()),
            log_picture(kernel),
            *encoding,
            format.name,
        ),
        _ => Err(refuse()),
    }
}

/// Reads a kernel written by [`write_kernel`] (or any image of 1 or 3
/// planes of non-negative weights, centre in its middle) and normalises
/// each plane to ΣK = 1, unless the file records that its planes hold
/// shares of their light ([`LIGHT_ATTRIBUTE`]), which are kept.
pub fn read_kernel(path: &Path, limits: Limits) -> Result<Kernel> {
    read_kernel_file(path, limits).map(|(kernel, _)| kernel)
}

/// [`read_kernel`], with what the file records of what the kernel was
/// built for ([`write_kernel_for`]).
pub fn read_kernel_file(path: &Path, limits: Limits) -> Result<(Kernel, KernelRecord)> {
    let loaded = read_image(path, limits)?;
    let record = loaded.original.recorded_kernel();
    let image = loaded.image;
    let kernel = if record.shares.is_some() {
        Kernel::from_shares(image.width, image.height, image.planes)
    } else {
        Kernel::from_planes(image.width, image.height, image.planes)
    }
    .map_err(|error| Error::Content {
        path: path.to_path_buf(),
        error,
    })?;
    Ok((kernel, record))
}

/// 8-bit RGB levels where grey ∝ log₁₀ K over [`PICTURE_DECADES`] decades
/// below the brightest pixel outside the centre (the unspread centre is far
/// brighter and shows white). A coloured kernel gives a colour picture, all
/// channels on one scale.
pub fn log_picture(kernel: &Kernel) -> Vec<u8> {
    let (width, height) = (kernel.width(), kernel.height());
    let (cx, cy) = kernel.centre();
    let centre = cy * width + cx;
    let planes = kernel.planes();
    let peak = planes
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
    let channel = |c: usize| &planes[c.min(planes.len() - 1)];
    let (r, g, b) = (channel(0), channel(1), channel(2));
    let mut levels = Vec::with_capacity(width * height * 3);
    for ((&r, &g), &b) in r.iter().zip(g).zip(b) {
        levels.extend([level(r), level(g), level(b)]);
    }
    levels
}

/// The central `width`×`height` of the kernel's [`log_picture`], black
/// where the kernel does not reach.
pub fn log_picture_window(kernel: &Kernel, width: usize, height: usize) -> Picture {
    let levels = log_picture(kernel);
    let (kw, kh) = (kernel.width(), kernel.height());
    let (cx, cy) = kernel.centre();
    let mut rgb = vec![0.0; width * height * 3];
    for y in 0..height {
        let ky = (cy + y).checked_sub(height / 2).filter(|&v| v < kh);
        for x in 0..width {
            let kx = (cx + x).checked_sub(width / 2).filter(|&v| v < kw);
            if let (Some(kx), Some(ky)) = (kx, ky) {
                for c in 0..3 {
                    rgb[(y * width + x) * 3 + c] =
                        f32::from(levels[(ky * kw + kx) * 3 + c]) / 255.0;
                }
            }
        }
    }
    Picture {
        width,
        height,
        rgb,
        white: 0.0,
    }
}
