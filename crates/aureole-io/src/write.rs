//! Writing images by the extension of their path: linear formats as they
//! are, pictures through the display path. Every file appears whole or not
//! at all.

use std::path::Path;

use aureole::image::{Image, Layout};

use crate::compression::Compression;
use crate::display::{render, Depth, DisplayOptions, Picture};
use crate::error::{Error, Result};
use crate::formats::{
    by_extension, extension, holding, image_outputs, picture_outputs, Encoder, Format, Kind,
    LinearPlanes, Note, Original, Samples,
};

/// How to store a linear image.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LinearOptions {
    /// EXR only: half or float samples; `None`: as the EXR read had them,
    /// else float.
    pub samples: Option<Samples>,
    /// EXR only: the compression; `None`: the EXR read's, else ZIP,
    /// lossless and what compositors expect.
    pub compression: Option<Compression>,
}

/// How to write an image to whatever format its path names.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WriteOptions {
    /// For linear formats.
    pub linear: LinearOptions,
    /// For pictures: exposure and tone curve.
    pub display: DisplayOptions,
    /// For pictures: the sample depth, by default the format's own.
    pub depth: Option<Depth>,
}

/// What writing made.
#[derive(Debug, Clone, PartialEq)]
pub enum Written {
    /// A linear file, with what the format could not keep.
    Linear(Vec<Note>),
    /// A picture, showing this luminance (cd/m²) as white.
    Picture {
        /// The luminance shown as white, cd/m².
        white: f64,
        /// The exposure value (EV100) that shows it as white.
        ev100: f64,
    },
}

/// The format `path` names for an image, or an error listing those we write.
pub fn output_format(path: &Path) -> Result<&'static Format> {
    by_extension(path).ok_or_else(|| Error::OutputFormat {
        path: path.to_path_buf(),
        extension: extension(path),
        allowed: image_outputs(),
    })
}

/// Refuses an `output` that is `input` itself, by any path or link to it.
pub fn refuse_overwrite(output: &Path, input: &Path) -> Result<()> {
    if crate::atomic::same_file(input, output) {
        return Err(Error::OverwritesInput {
            path: output.to_path_buf(),
        });
    }
    Ok(())
}

/// Writes `image` (file units, `scale` cd/m² per unit) to `path`: linear
/// formats keep its values, pictures go through exposure, tone curve and
/// sRGB.
pub fn write_image(
    path: &Path,
    image: &Image,
    scale: f64,
    options: &WriteOptions,
) -> Result<Written> {
    write_image_into(path, image, scale, options, Original::default())
}

/// As [`write_image`], into the file `image` was read from: an EXR result
/// keeps `original`'s other layers and parts, windows, attributes,
/// channel names and sample types.
pub fn write_image_into(
    path: &Path,
    image: &Image,
    scale: f64,
    options: &WriteOptions,
    original: Original,
) -> Result<Written> {
    let format = output_format(path)?;
    match format.kind() {
        Kind::Linear => {
            write_linear_into(path, image, options.linear, original).map(Written::Linear)
        }
        Kind::Picture => {
            let picture = render(image, scale, &options.display);
            let depth = options.depth.unwrap_or(format.depths[0]);
            write_picture(path, &picture, depth)?;
            Ok(Written::Picture {
                white: picture.white,
                ev100: picture.ev100(),
            })
        }
    }
}

/// Refuses, before any work, a path whose extension names no linear
/// format ([`write_linear`] writes those alone).
pub fn check_linear_output(path: &Path) -> Result<()> {
    match by_extension(path).map(|f| &f.encode) {
        Some(Encoder::Linear(_)) => Ok(()),
        _ => Err(linear_refused(path)),
    }
}

fn linear_refused(path: &Path) -> Error {
    Error::OutputFormat {
        path: path.to_path_buf(),
        extension: extension(path),
        allowed: crate::formats::linear_outputs(),
    }
}

/// Writes `image` as `.exr`, `.hdr` or `.pfm` by the extension of `path`.
/// Returns what the format could not keep.
pub fn write_linear(path: &Path, image: &Image, options: LinearOptions) -> Result<Vec<Note>> {
    write_linear_into(path, image, options, Original::default())
}

/// As [`write_linear`], into the file `image` was read from (see
/// [`write_image_into`]).
pub fn write_linear_into(
    path: &Path,
    image: &Image,
    options: LinearOptions,
    original: Original,
) -> Result<Vec<Note>> {
    let Some(Encoder::Linear(encode)) = by_extension(path).map(|f| &f.encode) else {
        return Err(linear_refused(path));
    };
    let colour = match image.layout {
        Layout::Luminance => vec![image.planes[0].as_slice()],
        Layout::Rgb => image.planes.iter().take(3).map(Vec::as_slice).collect(),
    };
    encode(
        path,
        LinearPlanes {
            width: image.width,
            height: image.height,
            colour,
            alpha: image.alpha.as_deref(),
            white_luminance: image.white_luminance,
            primaries: image.primaries,
            samples: options.samples,
            compression: options.compression,
            original,
            kernel: Default::default(),
        },
    )
}

/// `picture` as an 8-bit PNG in memory, compressed for speed (a preview
/// sent to a browser); the error says why it could not be encoded.
pub fn preview_png(picture: &Picture) -> std::result::Result<Vec<u8>, String> {
    crate::formats::picture::preview_png((picture.width, picture.height), &picture.eight_bit())
}

/// Writes `picture` as PNG, JPEG or TIFF by the extension of `path`.
pub fn write_picture(path: &Path, picture: &Picture, depth: Depth) -> Result<()> {
    let picture_format = |f: &'static Format| match f.encode {
        Encoder::Picture(encoding) => Some((f, encoding)),
        Encoder::Linear(_) => None,
    };
    let Some((format, encoding)) = by_extension(path).and_then(picture_format) else {
        return Err(Error::OutputFormat {
            path: path.to_path_buf(),
            extension: extension(path),
            allowed: picture_outputs(),
        });
    };
    if !format.depths.contains(&depth) {
        return Err(Error::Encode {
            path: path.to_path_buf(),
            format: format.name,
            message: format!(
                "{} holds {} bits per sample; use {} for {}",
                format.name,
                format.depths[0].bits(),
                holding(depth),
                depth.bits()
            ),
        });
    }
    crate::formats::picture::encode(path, picture, depth, encoding, format.name)
}
