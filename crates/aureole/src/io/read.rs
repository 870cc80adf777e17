//! Reading HDR and display images by their content: OpenEXR (through `exr`),
//! Radiance RGBE, PFM (ours), PNG, JPEG and TIFF (through `image`).

use std::io::Read;
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

/// Reads the image at `path`, recognising the format by its content.
pub fn read_image(path: &Path) -> Result<Loaded> {
    let mut head = [0u8; 16];
    let got = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .map_err(|e| Error::io(path, e))?;
    let decode_error = |message: String| Error::Decode {
        path: path.to_path_buf(),
        message,
    };
    match sniff(&head[..got]) {
        Some(Kind::Exr) => read_exr(path),
        Some(Kind::Pfm) => {
            let pfm = super::pfm::read(path)?;
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
        Some(Kind::Other) => read_with_image_crate(path),
        None if got == 0 => Err(decode_error(format!(
            "the file is empty; expected {READ_FORMATS}"
        ))),
        None => Err(decode_error(format!(
            "not an image this tool reads (first bytes {:02x?}); expected {READ_FORMATS}",
            &head[..got.min(8)]
        ))),
    }
}

fn read_exr(path: &Path) -> Result<Loaded> {
    let decode_error = |message: String| Error::Decode {
        path: path.to_path_buf(),
        message,
    };
    let image = x::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(|e| decode_error(format!("cannot read OpenEXR: {e}")))?;

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
            decode_error(format!(
                "no R, G, B or Y channel in any layer (channels: {})",
                names.join(", ")
            ))
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

fn read_with_image_crate(path: &Path) -> Result<Loaded> {
    use image::DynamicImage as D;
    let decode_error = |message: String| Error::Decode {
        path: path.to_path_buf(),
        message,
    };
    let mut reader = image::ImageReader::open(path)
        .map_err(|e| Error::io(path, e))?
        .with_guessed_format()
        .map_err(|e| Error::io(path, e))?;
    let format = match reader.format() {
        Some(image::ImageFormat::Hdr) => "Radiance HDR",
        Some(image::ImageFormat::Png) => "PNG",
        Some(image::ImageFormat::Jpeg) => "JPEG",
        Some(image::ImageFormat::Tiff) => "TIFF",
        _ => "image",
    };
    // Float images of 8K and more exceed the crate's 512 MiB default.
    reader.no_limits();
    let decoded = reader
        .decode()
        .map_err(|e| decode_error(format!("cannot read {format}: {e}")))?;
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
