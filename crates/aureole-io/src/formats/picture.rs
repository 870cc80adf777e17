//! Pictures through the `image` crate: PNG, JPEG and TIFF in (display
//! images, sRGB-decoded; float TIFF as it is) and out (8 or 16-bit sRGB);
//! Radiance RGBE is decoded here too.

use std::io::Cursor;
use std::path::Path;

use aureole::image::{Image, Layout};
use aureole::memory::format_bytes;
use image::{ImageBuffer, ImageFormat, Rgb};
use rayon::prelude::*;

use super::Decoded;
use crate::atomic::write_atomic;
use crate::display::{srgb_to_linear, Depth, Picture};
use crate::error::{Error, Result};
use crate::formats::explain;
use crate::limits::Limits;

/// Decodes what the `image` crate reads: Radiance RGBE, and PNG, JPEG and
/// TIFF. 8/16-bit files are display images, decoded from sRGB to linear;
/// float TIFF and Radiance are linear as they are.
pub(crate) fn decode(bytes: &[u8], limits: Limits) -> std::result::Result<Decoded, String> {
    use image::DynamicImage as D;
    let mut reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| explain("image", e.to_string()))?;
    let format = super::by_content(bytes).map_or("image", |f| f.name);
    // The decoder checks the declared size before it allocates; the crate's
    // 512 MiB default would refuse float images of 8K, so ours replaces it.
    // Beyond the decoded image come its RGBA f32 copy and our planes.
    let mut bounds = image::Limits::default();
    bounds.max_alloc = Some(limits.max_bytes / 3);
    reader.limits(bounds);
    let decoded = reader.decode().map_err(|e| match e {
        image::ImageError::Limits(_) => format!(
            "cannot read {format}: decoding it would exceed the memory limit of {}",
            format_bytes(limits.max_bytes)
        ),
        e => explain(format, e.to_string()),
    })?;
    let rgba_bytes = decoded.width() as u64 * decoded.height() as u64 * 32;
    if rgba_bytes > limits.max_bytes {
        return Err(format!(
            "{format} of {}x{} needs {} to decode but the memory limit is {}",
            decoded.width(),
            decoded.height(),
            format_bytes(rgba_bytes),
            format_bytes(limits.max_bytes)
        ));
    }
    let (width, height) = (decoded.width() as usize, decoded.height() as usize);
    let float = matches!(decoded, D::ImageRgb32F(_) | D::ImageRgba32F(_));
    let grey = matches!(
        decoded,
        D::ImageLuma8(_) | D::ImageLumaA8(_) | D::ImageLuma16(_) | D::ImageLumaA16(_)
    );
    let has_alpha = decoded.color().has_alpha();
    // Radiance (and float RGB TIFF) arrive as RGB f32: taken apart as they
    // are, without an RGBA copy; the rest through RGBA f32.
    let (pixels, stride) = match decoded {
        D::ImageRgb32F(rgb) => (rgb.into_raw(), 3),
        other => (other.into_rgba32f().into_raw(), 4),
    };
    let decode = |v: f32| if float { v } else { srgb_to_linear(v) };
    let channel = |c: usize| -> Vec<f32> {
        pixels
            .par_chunks_exact(stride)
            .map(|p| decode(p[c]))
            .collect()
    };
    let (layout, planes) = if grey {
        (Layout::Luminance, vec![channel(0)])
    } else {
        (Layout::Rgb, vec![channel(0), channel(1), channel(2)])
    };
    let alpha = has_alpha.then(|| pixels.par_chunks_exact(stride).map(|p| p[3]).collect());
    Ok(Decoded {
        image: Image {
            width,
            height,
            layout,
            planes,
            alpha,
            white_luminance: None,
            primaries: None,
        },
        display_referred: !float,
        notes: Vec::new(),
        compression: None,
        original: Default::default(),
    })
}

/// Encodes `picture` in `format` at `depth`, atomically; `name` is the
/// format in words.
pub(crate) fn encode(
    path: &Path,
    picture: &Picture,
    depth: Depth,
    format: ImageFormat,
    name: &'static str,
) -> Result<()> {
    let size = (picture.width, picture.height);
    match depth {
        Depth::Sixteen => {
            let samples: Vec<u16> = picture
                .rgb
                .iter()
                .map(|v| (v.clamp(0.0, 1.0) * 65535.0).round() as u16)
                .collect();
            encode_samples(path, size, samples, format, name)
        }
        Depth::Eight => encode_samples(path, size, picture.eight_bit(), format, name),
    }
}

/// Encodes RGB samples (row-major, top row first) in `format`, atomically;
/// `name` is the format in words.
pub(crate) fn encode_samples<T>(
    path: &Path,
    (width, height): (usize, usize),
    samples: Vec<T>,
    format: ImageFormat,
    name: &'static str,
) -> Result<()>
where
    T: image::Primitive,
    Rgb<T>: image::Pixel<Subpixel = T> + image::PixelWithColorType,
    [T]: image::EncodableLayout,
{
    let encode_error = |message: String| Error::Encode {
        path: path.to_path_buf(),
        format: name,
        message,
    };
    let picture = ImageBuffer::<Rgb<T>, _>::from_raw(width as u32, height as u32, samples)
        .ok_or_else(|| encode_error("picture buffer has the wrong size".into()))?;
    write_atomic(path, |out| {
        picture
            .write_to(out, format)
            .map_err(|e| encode_error(e.to_string()))
    })
}

/// 8-bit RGB codes (row-major, top row first) as a PNG in memory, quickly
/// compressed: a preview sent to a browser, not a file to keep.
pub(crate) fn preview_png(
    (width, height): (usize, usize),
    codes: &[u8],
) -> std::result::Result<Vec<u8>, String> {
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    use image::ImageEncoder;
    let mut out = Vec::new();
    let (w, h) = (u32::try_from(width), u32::try_from(height));
    let (Ok(w), Ok(h)) = (w, h) else {
        return Err(format!("a {width}x{height} picture is too large for PNG"));
    };
    PngEncoder::new_with_quality(&mut out, CompressionType::Fast, FilterType::Sub)
        .write_image(codes, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| e.to_string())?;
    Ok(out)
}
