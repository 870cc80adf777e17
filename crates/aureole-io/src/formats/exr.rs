//! OpenEXR through the `exr` crate: scanline or tiled, half or float, every
//! compression it reads; written as float32 (or half) planes named `Y` or
//! `R`, `G`, `B` (and `A`), in scanlines, with any compression it writes
//! ([`Compression`]).

use std::io::Cursor;
use std::path::Path;

use aureole::image::{Image, Layout, Primaries};
use aureole::memory::format_bytes;
use exr::prelude::{self as x, ReadChannels, ReadLayers};

use super::{Decoded, LinearPlanes, Note, HALF_MAX};
use crate::atomic::write_atomic;
use crate::compression::Compression;
use crate::error::{Error, Result};
use crate::limits::Limits;
use crate::read::explain;

/// Decodes an OpenEXR file: the first part with colour channels, its
/// `R`, `G`, `B` (or `Y`) and `A`, and the attributes we keep.
pub(crate) fn decode(bytes: &[u8], limits: Limits) -> std::result::Result<Decoded, String> {
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
            format_bytes(needed),
            format_bytes(limits.max_bytes)
        ));
    }
    let mut image = x::read()
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
    let layer = image.layer_data.swap_remove(chosen);
    let (width, height) = (layer.size.0, layer.size.1);
    let rgb = has(&layer, "R") && has(&layer, "G") && has(&layer, "B");
    let (layout, used): (Layout, &[&str]) = if rgb {
        (Layout::Rgb, &["R", "G", "B", "A"])
    } else {
        (Layout::Luminance, &["Y", "A"])
    };
    let ignored: Vec<String> = layer
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .filter(|n| !used.contains(&n.as_str()))
        .collect();
    let compression = Compression::from_exr(layer.encoding.compression);
    let white_luminance = layer
        .attributes
        .white_luminance
        .filter(|w| w.is_finite() && *w > 0.0);
    // Float samples are moved out, not copied: a 4K frame is 100 MB.
    let mut channels: Vec<(String, x::FlatSamples)> = layer
        .channel_data
        .list
        .into_iter()
        .map(|c| (c.name.to_string(), c.sample_data))
        .collect();
    let mut plane = |name: &str| {
        let at = channels.iter().position(|(n, _)| n == name)?;
        Some(match channels.swap_remove(at).1 {
            x::FlatSamples::F32(values) => values,
            other => other.values_as_f32().collect(),
        })
    };
    let planes: Vec<Vec<f32>> = used
        .iter()
        .filter(|n| **n != "A")
        .filter_map(|n| plane(n))
        .collect();
    let alpha = plane("A");
    if !ignored.is_empty() {
        notes.push(format!("ignored EXR channels {}", ignored.join(", ")));
    }
    let primaries = image.attributes.chromaticities.map(|c| Primaries {
        red: [c.red.0, c.red.1],
        green: [c.green.0, c.green.1],
        blue: [c.blue.0, c.blue.1],
        white: [c.white.0, c.white.1],
    });
    if primaries.is_some_and(|p| p.luminance_weights().is_none()) {
        notes.push("the chromaticities attribute is degenerate: luminance uses Rec.709".into());
    }
    Ok(Decoded {
        image: Image {
            width,
            height,
            layout,
            planes,
            alpha,
            white_luminance,
            primaries,
        },
        display_referred: false,
        notes,
        compression,
    })
}

/// Writes the planes to `path` atomically; with `half`, samples beyond the
/// half range are clamped to it (and counted).
pub(crate) fn encode(path: &Path, planes: &LinearPlanes) -> Result<Vec<Note>> {
    use exr::prelude::{
        f16, AnyChannel, AnyChannels, Encoding, FlatSamples, Layer, LayerAttributes, Vec2,
        WritableImage,
    };
    let names: &[&str] = match planes.colour.len() {
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
    let mut notes = Vec::new();
    let mut clamped = 0;
    let mut samples = |plane: &[f32], colour: bool| {
        if planes.half {
            FlatSamples::F16(
                plane
                    .iter()
                    .map(|&v| {
                        if colour && v.abs() > HALF_MAX {
                            clamped += 1;
                            f16::from_f32(v.clamp(-HALF_MAX, HALF_MAX))
                        } else {
                            f16::from_f32(v)
                        }
                    })
                    .collect(),
            )
        } else {
            FlatSamples::F32(plane.to_vec())
        }
    };
    let mut list: Vec<AnyChannel<FlatSamples>> = names
        .iter()
        .zip(&planes.colour)
        .map(|(name, plane)| AnyChannel::new(*name, samples(plane, true)))
        .collect();
    if let Some(alpha) = planes.alpha {
        list.push(AnyChannel::new("A", samples(alpha, false)));
    }
    if clamped > 0 {
        notes.push(Note::ClampedToHalf { count: clamped });
    }
    let attributes = LayerAttributes {
        white_luminance: planes.white_luminance,
        ..LayerAttributes::default()
    };
    let layer = Layer::new(
        (planes.width, planes.height),
        attributes,
        Encoding {
            compression: planes.compression.to_exr(),
            ..Encoding::SMALL_LOSSLESS
        },
        AnyChannels::sort(list.into_iter().collect()),
    );
    let mut exr_image = exr::prelude::Image::from_layer(layer);
    exr_image.attributes.chromaticities =
        planes
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
    })?;
    Ok(notes)
}
