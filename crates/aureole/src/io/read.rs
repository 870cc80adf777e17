//! Reading HDR and display images by their content: OpenEXR (through `exr`),
//! Radiance RGBE, PFM (ours), PNG, JPEG and TIFF (through `image`).

use std::io::Cursor;
use std::path::Path;

use exr::prelude::{self as x, ReadChannels, ReadLayers};

use crate::error::{Error, Result};
use crate::image::{Image, Layout, Primaries};

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
}

/// The formats we read, for messages.
pub const READ_FORMATS: &str = "OpenEXR, Radiance .hdr, PFM, PNG, JPEG or TIFF";

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Exr,
    Pfm,
    Other,
}

fn sniff(head: &[u8]) -> Option<Kind> {
    if head.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        Some(Kind::Exr)
    } else if head.starts_with(b"PF") || head.starts_with(b"Pf") {
        Some(Kind::Pfm)
    } else if head.starts_with(b"#?")
        || head.starts_with(b"\x89PNG")
        || head.starts_with(&[0xff, 0xd8, 0xff])
        || head.starts_with(b"II*\0")
        || head.starts_with(b"MM\0*")
    {
        Some(Kind::Other)
    } else {
        None
    }
}

/// Bounds on what a decoder may allocate, checked against the dimensions a
/// file declares before any pixel is decoded (a header is untrusted input).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// The most bytes the decoded image and the decoder's own buffers may take.
    pub max_bytes: u64,
}

impl Limits {
    /// No bound but the address space.
    pub const NONE: Limits = Limits {
        max_bytes: u64::MAX,
    };
}

/// Reads the image at `path`, recognising the format by its content.
pub fn read_image(path: &Path) -> Result<Loaded> {
    read_image_limited(path, Limits::NONE)
}

/// As [`read_image`], refusing a file whose decoding would need more than
/// `limits` allows.
pub fn read_image_limited(path: &Path, limits: Limits) -> Result<Loaded> {
    let metadata = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    // Every format we read stores at least a byte per pixel's worth of
    // data for its planes, so a file larger than the bound cannot fit.
    if metadata.len() > limits.max_bytes {
        return Err(Error::Decode {
            path: path.to_path_buf(),
            message: format!(
                "the file ({}) is larger than the memory limit ({})",
                crate::memory::format_bytes(metadata.len()),
                crate::memory::format_bytes(limits.max_bytes)
            ),
        });
    }
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    decode_image(&bytes, limits).map_err(|message| Error::Decode {
        path: path.to_path_buf(),
        message,
    })
}

/// Decodes an image file held in memory, recognising the format by its
/// content. The error is one line saying what is wrong.
pub fn decode_image(bytes: &[u8], limits: Limits) -> std::result::Result<Loaded, String> {
    let head = &bytes[..bytes.len().min(16)];
    match sniff(head) {
        Some(Kind::Exr) => decode_exr(bytes, limits),
        Some(Kind::Pfm) => {
            let pfm = super::pfm::decode_limited(bytes, limits.max_bytes)?;
            let layout = if pfm.channels.len() == 1 {
                Layout::Luminance
            } else {
                Layout::Rgb
            };
            Ok(Loaded {
                image: Image {
                    width: pfm.width,
                    height: pfm.height,
                    layout,
                    planes: pfm.channels,
                    alpha: None,
                    white_luminance: None,
                    primaries: None,
                },
                format: "PFM",
                display_referred: false,
                notes: Vec::new(),
            })
        }
        Some(Kind::Other) => decode_with_image_crate(bytes, limits),
        None if bytes.is_empty() => Err(format!("the file is empty; expected {READ_FORMATS}")),
        None => Err(format!(
            "not an image this tool reads (first bytes {:02x?}); expected {READ_FORMATS}",
            &head[..head.len().min(8)]
        )),
    }
}

/// A decoder's message in the user's words: most of the ways a file can be
/// cut short surface as one of these.
fn explain(format: &str, message: String) -> String {
    // Some decoders' messages span lines; ours are one line each.
    let message = message.split_whitespace().collect::<Vec<_>>().join(" ");
    let lower = message.to_lowercase();
    let truncated = [
        "missing bytes",
        "fill whole buffer",
        "unexpected end",
        "unexpected eof",
        "eof in header",
    ]
    .iter()
    .any(|m| lower.contains(m));
    if truncated {
        format!("cannot read {format}: the file ends early (truncated?): {message}")
    } else {
        format!("cannot read {format}: {message}")
    }
}

fn decode_exr(bytes: &[u8], limits: Limits) -> std::result::Result<Loaded, String> {
    let meta = x::MetaData::read_from_buffered(Cursor::new(bytes), false)
        .map_err(|e| explain("OpenEXR", e.to_string()))?;
    // Every layer is decoded, then ours are copied out as f32 planes.
    let (mut pixels, mut needed) = (0u64, 0u64);
    for header in &meta.headers {
        let layer = header.layer_size.0 as u64 * header.layer_size.1 as u64;
        let stored: u64 = header
            .channels
            .list
            .iter()
            .map(|c| c.sample_type.bytes_per_sample() as u64)
            .sum();
        pixels = pixels.saturating_add(layer);
        needed = needed.saturating_add(layer.saturating_mul(stored + 4 * 4));
    }
    if needed > limits.max_bytes {
        return Err(format!(
            "OpenEXR declares {pixels} pixels ({}x{} in its first part), which need {} to decode but the memory limit is {}",
            meta.headers.first().map_or(0, |h| h.layer_size.0),
            meta.headers.first().map_or(0, |h| h.layer_size.1),
            crate::memory::format_bytes(needed),
            crate::memory::format_bytes(limits.max_bytes)
        ));
    }
    let image = x::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| explain("OpenEXR", e.to_string()))?;

    let mut notes = Vec::new();
    // The default view of a multi-view file is the channels without a view
    // prefix (`Y`, not `right.Y`); in a multi-part file, the first part that
    // has colour channels.
    let has = |layer: &x::Layer<x::AnyChannels<x::FlatSamples>>, name: &str| {
        layer
            .channel_data
            .list
            .iter()
            .any(|c| c.name.to_string() == name)
    };
    let chosen = image
        .layer_data
        .iter()
        .position(|l| (has(l, "R") && has(l, "G") && has(l, "B")) || has(l, "Y"))
        .ok_or_else(|| {
            let names: Vec<String> = image
                .layer_data
                .iter()
                .flat_map(|l| l.channel_data.list.iter().map(|c| c.name.to_string()))
                .collect();
            format!(
                "no R, G, B or Y channel in any layer (channels: {})",
                names.join(", ")
            )
        })?;
    for (i, layer) in image.layer_data.iter().enumerate() {
        if i != chosen {
            let name = layer
                .attributes
                .layer_name
                .as_ref()
                .map_or_else(|| format!("#{i}"), |n| n.to_string());
            notes.push(format!("ignored EXR layer {name}"));
        }
    }
    let layer = &image.layer_data[chosen];
    let (width, height) = (layer.size.0, layer.size.1);
    let plane = |name: &str| {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)
            .map(|c| c.sample_data.values_as_f32().collect::<Vec<f32>>())
    };
    let rgb = has(layer, "R") && has(layer, "G") && has(layer, "B");
    let (layout, used): (Layout, &[&str]) = if rgb {
        (Layout::Rgb, &["R", "G", "B", "A"])
    } else {
        (Layout::Luminance, &["Y", "A"])
    };
    let planes: Vec<Vec<f32>> = used
        .iter()
        .filter(|n| **n != "A")
        .filter_map(|n| plane(n))
        .collect();
    let ignored: Vec<String> = layer
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .filter(|n| !used.contains(&n.as_str()))
        .collect();
    if !ignored.is_empty() {
        notes.push(format!("ignored EXR channels {}", ignored.join(", ")));
    }
    let white_luminance = layer
        .attributes
        .white_luminance
        .filter(|w| w.is_finite() && *w > 0.0);
    let primaries = image.attributes.chromaticities.map(|c| Primaries {
        red: [c.red.0, c.red.1],
        green: [c.green.0, c.green.1],
        blue: [c.blue.0, c.blue.1],
        white: [c.white.0, c.white.1],
    });
    if primaries.is_some_and(|p| p.luminance_weights().is_none()) {
        notes.push("the chromaticities attribute is degenerate: luminance uses Rec.709".into());
    }
    Ok(Loaded {
        image: Image {
            width,
            height,
            layout,
            planes,
            alpha: plane("A"),
            white_luminance,
            primaries,
        },
        format: "OpenEXR",
        display_referred: false,
        notes,
    })
}

/// The sRGB decoding curve: display code value (0…1) to linear light.
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

fn decode_with_image_crate(bytes: &[u8], limits: Limits) -> std::result::Result<Loaded, String> {
    use image::DynamicImage as D;
    let mut reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| explain("image", e.to_string()))?;
    let format = match reader.format() {
        Some(image::ImageFormat::Hdr) => "Radiance HDR",
        Some(image::ImageFormat::Png) => "PNG",
        Some(image::ImageFormat::Jpeg) => "JPEG",
        Some(image::ImageFormat::Tiff) => "TIFF",
        _ => "image",
    };
    // The decoder checks the declared size before it allocates; the crate's
    // 512 MiB default would refuse float images of 8K, so ours replaces it.
    // Beyond the decoded image come its RGBA f32 copy and our planes.
    let mut bounds = image::Limits::default();
    bounds.max_alloc = Some(limits.max_bytes / 3);
    reader.limits(bounds);
    let decoded = reader.decode().map_err(|e| match e {
        image::ImageError::Limits(_) => format!(
            "cannot read {format}: decoding it would exceed the memory limit of {}",
            crate::memory::format_bytes(limits.max_bytes)
        ),
        e => explain(format, e.to_string()),
    })?;
    let rgba_bytes = decoded.width() as u64 * decoded.height() as u64 * 32;
    if rgba_bytes > limits.max_bytes {
        return Err(format!(
            "{format} of {}x{} needs {} to decode but the memory limit is {}",
            decoded.width(),
            decoded.height(),
            crate::memory::format_bytes(rgba_bytes),
            crate::memory::format_bytes(limits.max_bytes)
        ));
    }
    let (width, height) = (decoded.width() as usize, decoded.height() as usize);
    let float = matches!(decoded, D::ImageRgb32F(_) | D::ImageRgba32F(_));
    let grey = matches!(
        decoded,
        D::ImageLuma8(_) | D::ImageLumaA8(_) | D::ImageLuma16(_) | D::ImageLumaA16(_)
    );
    let has_alpha = decoded.color().has_alpha();
    let rgba = decoded.into_rgba32f();
    let pixels = rgba.as_raw();
    let decode = |v: f32| if float { v } else { srgb_to_linear(v) };
    let channel = |c: usize| -> Vec<f32> { pixels.chunks_exact(4).map(|p| decode(p[c])).collect() };
    let (layout, planes) = if grey {
        (Layout::Luminance, vec![channel(0)])
    } else {
        (Layout::Rgb, vec![channel(0), channel(1), channel(2)])
    };
    let alpha = has_alpha.then(|| pixels.chunks_exact(4).map(|p| p[3]).collect());
    Ok(Loaded {
        image: Image {
            width,
            height,
            layout,
            planes,
            alpha,
            white_luminance: None,
            primaries: None,
        },
        format,
        display_referred: !float,
        notes: Vec::new(),
    })
}
