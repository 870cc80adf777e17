//! Reading images by their content, whatever their name says: the format
//! table ([`crate::formats`]) recognises the file and decodes it.

use std::io::Read;
use std::path::Path;

use aureole::image::Image;
use aureole::memory::format_bytes;

use crate::compression::Compression;
use crate::error::{Error, Result};
use crate::formats::{by_content, readable, Original};
pub use crate::formats::{Choice, Shape};
use crate::limits::Limits;
use crate::spares::Spares;

/// A decoded file and what the user should know about how it was read.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The pixels, linear, in the file's units.
    pub image: Image,
    /// The file's format, in words.
    pub format: &'static str,
    /// Whether it was an 8/16-bit display image (sRGB-decoded, so its
    /// luminance is only relative).
    pub display_referred: bool,
    /// Remarks for the user (ignored channels and layers, …), one line each.
    pub notes: Vec<String>,
    /// The file's compression, for an EXR (a result is written with the
    /// same unless told otherwise).
    pub compression: Option<Compression>,
    /// The rest of the file (an EXR's other layers, parts, windows and
    /// attributes), for writing the result back into it.
    pub original: Original,
}

/// The shape of the image at `path` (the layer `choice` names), from its
/// header alone, so that what a run needs can be checked before the file
/// is decoded: refused when decoding it would need more than `limits`;
/// `None` when the header does not say (reading the file then says why).
pub fn probe(path: &Path, limits: Limits, choice: &Choice) -> Result<Option<Shape>> {
    let Some(head) = head_of_file(path) else {
        return Ok(None);
    };
    let Some(format) = by_content(&head) else {
        return Ok(None);
    };
    let shape = match format.name {
        "OpenEXR" => {
            crate::formats::exr::probe(path, limits, choice).map_err(|message| Error::Decode {
                path: path.to_path_buf(),
                message,
            })?
        }
        // A PFM shorter than it declares is refused by its decoder, which
        // says so.
        "PFM" => crate::formats::pfm::header(&head)
            .ok()
            .filter(|h| {
                let declared =
                    (h.width as u64 * h.height as u64).saturating_mul(h.channels as u64 * 4);
                std::fs::metadata(path).is_ok_and(|m| m.len() >= declared)
            })
            .map(|header| Shape {
                width: header.width,
                height: header.height,
                planes: header.channels,
                alpha: false,
            }),
        _ => image::ImageReader::open(path)
            .ok()
            .and_then(|r| r.with_guessed_format().ok())
            .and_then(|r| r.into_dimensions().ok())
            .map(|(width, height)| Shape {
                width: width as usize,
                height: height as usize,
                planes: 3,
                alpha: false,
            }),
    };
    if let Some(shape) = shape {
        // The decoded planes, and the decoder's own copy at least as large.
        let planes = (shape.planes + usize::from(shape.alpha)) as u64;
        let needed = (shape.width as u64)
            .saturating_mul(shape.height as u64)
            .saturating_mul(planes * 4 * 2);
        if needed > limits.max_bytes {
            return Err(Error::Decode {
                path: path.to_path_buf(),
                message: format!(
                    "{} declares {}x{} pixels, which need {} to decode but the memory limit is {}",
                    format.name,
                    shape.width,
                    shape.height,
                    format_bytes(needed),
                    format_bytes(limits.max_bytes)
                ),
            });
        }
    }
    Ok(shape)
}

/// An OpenEXR file's parts, views, layers and channels, a line each, from
/// its headers alone: what can be said of a file that cannot be spread
/// (deep data, no single colour layer). `None` for another format or
/// headers that cannot be read.
pub fn exr_structure(path: &Path) -> Option<Vec<String>> {
    match by_content(&head_of_file(path)?) {
        Some(format) if format.name == "OpenEXR" => crate::formats::exr::structure(path),
        _ => None,
    }
}

/// The first 256 bytes of the regular file at `path`, where it is one and
/// can be read. A pipe's bytes are read once, by the reader: a look ahead
/// would take them from it.
fn head_of_file(path: &Path) -> Option<Vec<u8>> {
    if !std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
        return None;
    }
    let mut head = Vec::with_capacity(256);
    std::fs::File::open(path)
        .and_then(|f| f.take(256).read_to_end(&mut head))
        .ok()?;
    Some(head)
}

/// Reads the image at `path`, recognising the format by its content, and
/// refusing a file whose decoding would need more than `limits` allows.
pub fn read_image(path: &Path, limits: Limits) -> Result<Loaded> {
    read_image_with(path, limits, &Choice::default())
}

/// As [`read_image`], reading the layer and part `choice` names.
pub fn read_image_with(path: &Path, limits: Limits, choice: &Choice) -> Result<Loaded> {
    read_image_reusing(path, limits, choice, &Spares::default())
}

/// As [`read_image_with`], into buffers `spares` lends (earlier frames'),
/// which the image's [`Loaded::original`] carries to the writer.
pub fn read_image_reusing(
    path: &Path,
    limits: Limits,
    choice: &Choice,
    spares: &Spares,
) -> Result<Loaded> {
    let metadata = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    let refuse = |message: String| Error::Decode {
        path: path.to_path_buf(),
        message,
    };
    // A device (/dev/zero, a disk) never ends, or is no image: refused
    // before a byte is read.
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let kind = metadata.file_type();
        if kind.is_char_device() || kind.is_block_device() {
            return Err(refuse(
                "is a device, not an image file; read a file, or a pipe (a named pipe, /dev/stdin)"
                    .into(),
            ));
        }
    }
    // Every format we read stores at least a byte per pixel's worth of
    // data for its planes, so a file larger than the bound cannot fit.
    if metadata.len() > limits.max_bytes {
        return Err(refuse(format!(
            "the file ({}) is larger than the memory limit ({})",
            format_bytes(metadata.len()),
            format_bytes(limits.max_bytes)
        )));
    }
    let mut bytes = spares
        .bytes(usize::try_from(metadata.len()).unwrap_or(0))
        .map_err(|error| Error::Content {
            path: path.to_path_buf(),
            error,
        })?;
    // A pipe says no length: it is read up to the bound, and refused
    // beyond it.
    std::fs::File::open(path)
        .and_then(|file| {
            file.take(limits.max_bytes.saturating_add(1))
                .read_to_end(&mut bytes)
        })
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > limits.max_bytes {
        spares.give_bytes(bytes);
        return Err(refuse(format!(
            "holds more than the memory limit ({}) allows to read",
            format_bytes(limits.max_bytes)
        )));
    }
    let loaded = decode(&bytes, limits, choice, spares);
    spares.give_bytes(bytes);
    loaded.map_err(refuse)
}

/// Decodes an image file held in memory, recognising the format by its
/// content. The error is one line saying what is wrong.
pub fn decode_image(bytes: &[u8], limits: Limits) -> std::result::Result<Loaded, String> {
    decode_image_with(bytes, limits, &Choice::default())
}

/// As [`decode_image`], decoding the layer and part `choice` names.
pub fn decode_image_with(
    bytes: &[u8],
    limits: Limits,
    choice: &Choice,
) -> std::result::Result<Loaded, String> {
    decode(bytes, limits, choice, &Spares::default())
}

fn decode(
    bytes: &[u8],
    limits: Limits,
    choice: &Choice,
    spares: &Spares,
) -> std::result::Result<Loaded, String> {
    let head = &bytes[..bytes.len().min(16)];
    match by_content(head) {
        Some(format) if choice.is_some() && format.name != "OpenEXR" => Err(format!(
            "a {} file has one layer: a layer or part can be chosen in an OpenEXR file only",
            format.name
        )),
        Some(format) => {
            let mut decoded = (format.decode)(bytes, limits, choice, spares)?;
            decoded.original.spares = spares.clone();
            Ok(Loaded {
                image: decoded.image,
                format: format.name,
                display_referred: decoded.display_referred,
                notes: decoded.notes,
                compression: decoded.compression,
                original: decoded.original,
            })
        }
        None if bytes.is_empty() => Err(format!("the file is empty; expected {}", readable())),
        None => Err(format!(
            "not an image this tool reads (first bytes {:02x?}); expected {}",
            &head[..head.len().min(8)],
            readable()
        )),
    }
}
