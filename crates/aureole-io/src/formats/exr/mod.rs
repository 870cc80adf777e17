//! OpenEXR through the `exr` crate: scanline or tiled, half, float or
//! uint, single or multi-part, every compression it reads.
//!
//! A compositor expects a result to drop back into its script, so the
//! whole file is kept ([`Kept`]): the colour layer we spread is taken out,
//! and a result written as EXR puts it back in its place, under its own
//! channel names and sample types, with every other layer, part, window and
//! attribute as it was.
use std::path::Path;

use aureole::image::{Image, Layout, Primaries};
use aureole::memory::format_bytes;
use exr::image::{FlatImage, Layers};
use exr::meta::attribute::{LevelMode, SampleType};
use exr::meta::header::Header;
use exr::meta::BlockDescription;
use exr::prelude::{self as x};

use super::{Decoded, LinearPlanes, Note, Samples, HALF_MAX};
use crate::compression::Compression;
use crate::formats::{explain, Choice, Shape};
use crate::limits::Limits;
use crate::spares::Spares;

mod b44;
mod choose;
mod chroma;
mod dwa;
mod encode;
mod layout;
mod piz;
mod predictor;
mod pxr24;
mod read;
mod rle;
mod write;
mod zip;

use choose::{
    by_prefix, choose, is_vector, other_layers, other_views, parts_of_headers, Candidate,
};
pub(crate) use encode::encode;
use encode::GlareAt;

/// What an EXR file held besides the planes aureole spreads.
#[derive(Debug, Clone)]
pub(crate) struct Kept {
    /// The whole file, less the samples of the channels we took.
    image: FlatImage,
    /// The part we took them from.
    part: usize,
    /// The chosen layer's channel-name prefix (`ViewLayer.Combined.`), or
    /// empty.
    prefix: String,
    /// The channels we took, colour then alpha, as the file names them.
    taken: Vec<Taken>,
    /// They were luminance and chroma (`Y`, `RY`, `BY`): the result is RGB.
    chroma: bool,
    /// Where the glare layers go beside it.
    glare_at: GlareAt,
    /// The same layer in the file's other views, each with its image,
    /// which the front ends replace by the camera's result.
    views: Vec<KeptView>,
}

/// The spread layer of another view of a multi-view file.
#[derive(Debug, Clone)]
struct KeptView {
    name: String,
    part: usize,
    prefix: String,
    taken: Vec<Taken>,
    chroma: bool,
    image: Image,
    /// Where this view's glare layers go, and what they hold (none until
    /// a front end adds them).
    glare_at: GlareAt,
    glare: Vec<aureole::GlareLayer>,
}

/// A channel taken out of the file, to be put back under its own name.
#[derive(Debug, Clone)]
struct Taken {
    name: String,
    kind: SampleType,
    /// OpenEXR's `pLinear`: how lossy compressions quantise it.
    linear: bool,
}

impl Kept {
    /// Where the file's display window lies in the chosen part's pixels
    /// (its data window): the frame's optical axis, and its overscan.
    pub(crate) fn display_window(&self) -> Option<aureole::DisplayWindow> {
        let layer = self.image.layer_data.get(self.part)?;
        let display = self.image.attributes.display_window;
        let origin = layer.attributes.layer_position;
        Some(aureole::DisplayWindow {
            x: i64::from(display.position.0) - i64::from(origin.0),
            y: i64::from(display.position.1) - i64::from(origin.1),
            width: display.size.0,
            height: display.size.1,
        })
    }

    /// The other views' images, to be replaced by results, each with the
    /// glare layers to write beside it.
    pub(crate) fn views_mut(
        &mut self,
    ) -> impl Iterator<Item = (&mut Image, &mut Vec<aureole::GlareLayer>)> {
        self.views.iter_mut().map(|v| (&mut v.image, &mut v.glare))
    }

    /// What a kernel file records of what it was built for.
    pub(crate) fn recorded_kernel(&self) -> crate::formats::KernelRecord {
        use exr::meta::attribute::AttributeValue as V;
        // A custom attribute may be read as the file's or as its part's.
        let part = self.image.layer_data.get(self.part);
        let value = |name: &str| {
            let key = x::Text::from(name);
            self.image
                .attributes
                .other
                .get(&key)
                .or_else(|| part.and_then(|l| l.attributes.other.get(&key)))
                .cloned()
        };
        crate::formats::KernelRecord {
            image_width: match value(crate::formats::IMAGE_WIDTH_ATTRIBUTE) {
                Some(V::I32(n)) => usize::try_from(n).ok(),
                _ => None,
            },
            threshold: match value(crate::formats::THRESHOLD_ATTRIBUTE) {
                Some(V::F64(t)) if t.is_finite() && t >= 0.0 => Some(t),
                _ => None,
            },
            shares: match value(crate::formats::LIGHT_ATTRIBUTE) {
                Some(V::F64(least)) => Some(least),
                _ => None,
            },
        }
    }

    /// Parts, views, layers and channels, a line each, for a person.
    pub(crate) fn describe(&self) -> Vec<String> {
        let mut lines = vec![window_line(&self.image.attributes)];
        for (i, layer) in self.image.layer_data.iter().enumerate() {
            let kind = match layer.encoding.blocks {
                x::Blocks::ScanLines => "scanlines",
                x::Blocks::Tiles(_) => "tiles",
            };
            let chosen = if i == self.part {
                format!(", spreading {}", layer_name(&self.prefix))
            } else {
                String::new()
            };
            let mut channels: Vec<(String, String)> = layer
                .channel_data
                .list
                .iter()
                .map(|c| {
                    (
                        c.name.to_string(),
                        type_name(sample_type(&c.sample_data)).into(),
                    )
                })
                .collect();
            // The channels taken out to spread (the chosen layer's, the other
            // views') are listed where they were.
            let views = self.views.iter().map(|v| (v.part, &v.taken));
            for (_, taken) in std::iter::once((self.part, &self.taken))
                .chain(views)
                .filter(|(part, _)| *part == i)
            {
                channels.extend(
                    taken
                        .iter()
                        .map(|t| (t.name.clone(), type_name(t.kind).into())),
                );
            }
            let part = Described {
                index: i,
                attributes: &layer.attributes,
                size: layer.size,
                kind,
                compression: layer.encoding.compression,
                chosen: &chosen,
            };
            lines.extend(part.lines(channels));
        }
        lines
    }
}

/// The display window's line of a file's description.
fn window_line(attributes: &x::ImageAttributes) -> String {
    let display = attributes.display_window;
    format!(
        "display window ({}, {})–({}, {}), pixel aspect {}",
        display.position.0,
        display.position.1,
        display.position.0 + display.size.0 as i32 - 1,
        display.position.1 + display.size.1 as i32 - 1,
        attributes.pixel_aspect
    )
}

/// A part as `info` describes it, from its header or its decoded layer.
struct Described<'a> {
    index: usize,
    attributes: &'a x::LayerAttributes,
    size: x::Vec2<usize>,
    /// `scanlines`, `tiles` or `deep`.
    kind: &'a str,
    compression: x::Compression,
    /// What is said of it last (the layer spread).
    chosen: &'a str,
}

impl Described<'_> {
    /// Its line, then a line per layer: `channels` are (name, sample type
    /// and sampling in words).
    fn lines(&self, channels: Vec<(String, String)>) -> Vec<String> {
        let own = self.attributes;
        let name = own
            .layer_name
            .as_ref()
            .map(|n| format!(" {:?}", n.to_string()))
            .unwrap_or_default();
        let view = own
            .view_name
            .as_ref()
            .map(|v| format!(", view {v}"))
            .unwrap_or_default();
        let views = own
            .multi_view_names
            .as_ref()
            .map(|v| {
                let names: Vec<String> = v.iter().map(ToString::to_string).collect();
                format!(", views {}", names.join(", "))
            })
            .unwrap_or_default();
        let at = own.layer_position;
        let compression = Compression::from_exr(self.compression)
            .map_or_else(|| format!("{:?}", self.compression), |c| c.to_string());
        let mut lines = vec![format!(
            "part {}{name}: {}, data window ({}, {})–({}, {}), {compression}{view}{views}{}",
            self.index,
            self.kind,
            at.0,
            at.1,
            at.0 + self.size.0 as i32 - 1,
            at.1 + self.size.1 as i32 - 1,
            self.chosen
        )];
        for (prefix, mut list) in by_prefix(channels.iter().map(|(n, t)| (n.as_str(), t))) {
            list.sort_by_key(|c| c.0);
            let short: Vec<&str> = list.iter().map(|(n, _)| *n).collect();
            let what = if is_vector(&short) { " (vectors)" } else { "" };
            let list: Vec<String> = list.iter().map(|(c, t)| format!("{c} {t}")).collect();
            lines.push(format!(
                "  layer {}{what}: {}",
                layer_name(&prefix),
                list.join(", ")
            ));
        }
        lines
    }
}

/// A channel-name prefix as a layer's name for a person.
fn layer_name(prefix: &str) -> String {
    if prefix.is_empty() {
        "(unprefixed)".to_string()
    } else {
        prefix.trim_end_matches('.').to_string()
    }
}

fn sample_type(samples: &x::FlatSamples) -> SampleType {
    match samples {
        x::FlatSamples::F16(_) => SampleType::F16,
        x::FlatSamples::F32(_) => SampleType::F32,
        x::FlatSamples::U32(_) => SampleType::U32,
    }
}

fn type_name(t: SampleType) -> &'static str {
    match t {
        SampleType::F16 => "half",
        SampleType::F32 => "float",
        SampleType::U32 => "uint",
    }
}

/// Refuses what the `exr` crate would refuse with a less helpful word, or
/// what would not fit in memory, from the headers alone.
fn check_headers(headers: &[Header], limits: Limits) -> std::result::Result<bool, String> {
    let (mut pixels, mut needed) = (0u64, 0u64);
    let mut levels = false;
    for (i, header) in headers.iter().enumerate() {
        if header.deep {
            return Err(format!(
                "part {i} holds deep data (several samples per pixel), which aureole does not spread; flatten it first (for example oiiotool in.exr --flatten -o flat.exr)"
            ));
        }
        let subsampled: Vec<String> = header
            .channels
            .list
            .iter()
            .filter(|c| c.sampling != x::Vec2(1, 1))
            .map(|c| format!("{} ({}x{})", c.name, c.sampling.0, c.sampling.1))
            .collect();
        if !subsampled.is_empty() && header.blocks != BlockDescription::ScanLines {
            return Err(format!(
                "part {i} is tiled with subsampled channels {}, which OpenEXR allows only in scanline files",
                subsampled.join(", ")
            ));
        }
        if let BlockDescription::Tiles(tiles) = header.blocks {
            levels |= tiles.level_mode != LevelMode::Singular;
        }
        let layer = header.layer_size.0 as u64 * header.layer_size.1 as u64;
        let stored: u64 = header
            .channels
            .list
            .iter()
            .map(|c| c.sample_type.bytes_per_sample() as u64)
            .sum();
        pixels = pixels.saturating_add(layer);
        // The decoded samples, and our f32 planes beside them.
        needed = needed.saturating_add(layer.saturating_mul(stored + 4 * 4));
    }
    if needed > limits.max_bytes {
        return Err(format!(
            "OpenEXR declares {pixels} pixels ({}x{} in its first part), which need {} to decode but the memory limit is {}",
            headers.first().map_or(0, |h| h.layer_size.0),
            headers.first().map_or(0, |h| h.layer_size.1),
            format_bytes(needed),
            format_bytes(limits.max_bytes)
        ));
    }
    Ok(levels)
}

/// The size and planes of the layer `choice` names (or the beauty), from
/// the headers alone.
/// `None` when the headers cannot be read (decoding says why).
pub(crate) fn probe(
    path: &Path,
    limits: Limits,
    choice: &Choice,
) -> std::result::Result<Option<Shape>, String> {
    let Ok(meta) = x::MetaData::read_from_file(path, false) else {
        return Ok(None);
    };
    check_headers(&meta.headers, limits)?;
    let chosen = choose(&parts_of_headers(&meta.headers), choice)?;
    let size = meta.headers[chosen.part].layer_size;
    Ok(Some(Shape {
        width: size.0,
        height: size.1,
        planes: if chosen.colour.len() == 1 { 1 } else { 3 },
        alpha: chosen.alpha.is_some(),
    }))
}

/// The file's parts, views, layers and channels, a line each, from its
/// headers alone (deep parts included); `None` when they cannot be read.
pub(crate) fn structure(path: &Path) -> Option<Vec<String>> {
    let meta = x::MetaData::read_from_file(path, false).ok()?;
    let mut lines = vec![window_line(&meta.headers.first()?.shared_attributes)];
    for (i, header) in meta.headers.iter().enumerate() {
        let kind = match (header.deep, header.blocks) {
            (true, _) => "deep",
            (false, BlockDescription::ScanLines) => "scanlines",
            (false, BlockDescription::Tiles(_)) => "tiles",
        };
        let channels = header.channels.list.iter().map(|c| {
            let sampling = if c.sampling == x::Vec2(1, 1) {
                String::new()
            } else {
                format!(" (sampled {}x{})", c.sampling.0, c.sampling.1)
            };
            (
                c.name.to_string(),
                format!("{}{sampling}", type_name(c.sample_type)),
            )
        });
        let part = Described {
            index: i,
            attributes: &header.own_attributes,
            size: header.layer_size,
            kind,
            compression: header.compression,
            chosen: "",
        };
        lines.extend(part.lines(channels.collect()));
    }
    Some(lines)
}

/// Decodes an OpenEXR file: the colour layer chosen by `choice` (or the
/// beauty), and the same layer in the file's other views, with everything
/// else kept for writing back.
pub(crate) fn decode(
    bytes: &[u8],
    limits: Limits,
    choice: &Choice,
    spares: &Spares,
) -> std::result::Result<Decoded, String> {
    let file = read::File::parse(bytes).map_err(|e| explain("OpenEXR", e))?;
    let levels = check_headers(&file.headers, limits)?;
    let parts = parts_of_headers(&file.headers);
    let chosen = choose(&parts, choice)?;
    let (view, views) = other_views(&parts, &chosen);
    // The channels we spread come as f32, converted as they are placed.
    let wanted: Vec<(usize, &str)> = std::iter::once(&chosen)
        .chain(views.iter().map(|(_, c)| c))
        .flat_map(|c| {
            c.colour
                .iter()
                .chain(&c.alpha)
                .map(move |name| (c.part, name.as_str()))
        })
        .collect();
    let mut channels =
        read::read(bytes, &file, &wanted, spares).map_err(|e| explain("OpenEXR", e))?;

    let mut notes = layer_notes(&parts, &chosen, view, &views, levels);
    let attributes = &file.headers[0].shared_attributes;
    let primaries = attributes.chromaticities.map(|c| Primaries {
        red: [c.red.0, c.red.1],
        green: [c.green.0, c.green.1],
        blue: [c.blue.0, c.blue.1],
        white: [c.white.0, c.white.1],
    });
    if primaries.is_some_and(|p| p.luminance_weights().is_none()) && !chosen.chroma {
        notes.push("the chromaticities attribute is degenerate: luminance uses Rec.709".into());
    }
    let (image, taken) = extract(&chosen, &file.headers, &mut channels, primaries, &mut notes)?;
    let mut kept_views = Vec::new();
    for (name, candidate) in views {
        let glare_at = GlareAt::of(&parts[candidate.part], &candidate.prefix);
        let (image, taken) = extract(
            &candidate,
            &file.headers,
            &mut channels,
            primaries,
            &mut Vec::new(),
        )?;
        kept_views.push(KeptView {
            name,
            part: candidate.part,
            prefix: candidate.prefix,
            taken,
            chroma: candidate.chroma,
            image,
            glare_at,
            glare: Vec::new(),
        });
    }
    let subsampled: Vec<String> = channels
        .iter()
        .flatten()
        .filter(|c| c.sampling != (1, 1))
        .map(|c| c.name.to_string())
        .collect();
    if !subsampled.is_empty() {
        notes.push(format!(
            "channels {} are subsampled: an EXR output holds them at full resolution",
            subsampled.join(", ")
        ));
    }
    let compression = Compression::from_exr(file.headers[chosen.part].compression);
    let kept = kept_image(&file.headers, channels);
    Ok(Decoded {
        image,
        display_referred: false,
        notes,
        compression,
        // The spares are the reader's to attach, for every format.
        original: super::Original {
            exr: Some(Box::new(Kept {
                image: kept,
                part: chosen.part,
                glare_at: GlareAt::of(&parts[chosen.part], &chosen.prefix),
                prefix: chosen.prefix,
                taken,
                chroma: chosen.chroma,
                views: kept_views,
            })),
            ..Default::default()
        },
    })
}

/// What the user should know of the layers read: every view spread, the
/// other layers going back unchanged, a lone channel read as luminance,
/// mip or rip levels.
fn layer_notes(
    parts: &[choose::Part],
    chosen: &Candidate,
    view: Option<String>,
    views: &[(String, Candidate)],
    levels: bool,
) -> Vec<String> {
    let mut notes = Vec::new();
    let mut spread: Vec<&Candidate> = vec![chosen];
    spread.extend(views.iter().map(|(_, c)| c));
    let others = other_layers(parts, &spread);
    if !views.is_empty() {
        let names: Vec<String> = views
            .iter()
            .map(|(view, c)| format!("{view}: {}", c.describe()))
            .collect();
        notes.push(format!(
            "a multi-view file: every view goes through the camera ({}{}; {}); a result in another format than EXR holds the first alone",
            view.map(|v| format!("{v}: ")).unwrap_or_default(),
            chosen.describe(),
            names.join("; ")
        ));
    }
    if !others.is_empty() {
        notes.push(format!(
            "spreading layer {}; the others ({others}) go back unchanged into an EXR output",
            chosen.describe()
        ));
    }
    if let [lone] = chosen.colour.as_slice() {
        if !lone.ends_with('Y') {
            notes.push(format!("the only channel, {lone}, is read as luminance"));
        }
    }
    if levels {
        notes.push(
            "the file has mip or rip levels: the largest is read, and an EXR output holds only it"
                .into(),
        );
    }
    notes
}

/// The candidate's channels taken out of `channels` as an image (RGB for
/// luminance/chroma), with what is needed to put them back.
fn extract(
    chosen: &Candidate,
    headers: &[Header],
    channels: &mut [Vec<read::Channel>],
    primaries: Option<Primaries>,
    notes: &mut Vec<String>,
) -> std::result::Result<(Image, Vec<Taken>), String> {
    let header = &headers[chosen.part];
    let (width, height) = (header.layer_size.0, header.layer_size.1);
    let origin = header.own_attributes.layer_position;
    let white_luminance = header
        .own_attributes
        .white_luminance
        .filter(|w| w.is_finite() && *w > 0.0);
    let part = &mut channels[chosen.part];
    let mut take = |name: &str| -> Option<(read::Channel, Taken)> {
        let at = part.iter().position(|c| c.name.eq(name))?;
        let channel = part.remove(at);
        let taken = Taken {
            name: name.to_string(),
            kind: channel.kind,
            linear: channel.linear,
        };
        Some((channel, taken))
    };
    let mut taken = Vec::new();
    let mut colour = Vec::new();
    for name in &chosen.colour {
        if let Some((channel, id)) = take(name) {
            colour.push(channel);
            taken.push(id);
        }
    }
    let alpha = chosen.alpha.as_deref().and_then(&mut take).map(|(c, id)| {
        taken.push(id);
        c
    });
    let layout = if colour.len() == 3 {
        Layout::Rgb
    } else {
        Layout::Luminance
    };
    let planes = if chosen.chroma {
        notes.push(
            "luminance/chroma channels (Y, RY, BY) decoded to RGB; an EXR output holds R, G, B"
                .into(),
        );
        let file = primaries.map_or(chroma::REC709, |p| [p.red, p.green, p.blue, p.white]);
        let weights = match chroma::weights(file) {
            w if w.iter().all(|v| v.is_finite()) => w,
            _ => {
                notes.push(
                    "the chromaticities attribute is degenerate: chroma decoded with Rec.709's"
                        .into(),
                );
                chroma::weights(chroma::REC709)
            }
        };
        let mut channels = colour.into_iter();
        let (Some(y), Some(ry), Some(by)) = (channels.next(), channels.next(), channels.next())
        else {
            return Err("a luminance/chroma layer lacks Y, RY or BY".into());
        };
        let y = full_resolution(y, (width, height));
        if ry.sampling == (2, 2) && by.sampling == (2, 2) {
            let planes = chroma::Planes {
                y: &y,
                ry: floats(&ry.samples),
                by: floats(&by.samples),
                width,
                height,
                origin: (i64::from(origin.0), i64::from(origin.1)),
            };
            chroma::to_rgb(&planes, weights).into()
        } else {
            let (ry, by) = (
                full_resolution(ry, (width, height)),
                full_resolution(by, (width, height)),
            );
            chroma::full_resolution_to_rgb(y, ry, by, weights)
        }
    } else {
        colour
            .into_iter()
            .map(|c| full_resolution(c, (width, height)))
            .collect()
    };
    let alpha = alpha.map(|a| full_resolution(a, (width, height)));
    let image = Image {
        width,
        height,
        layout,
        planes,
        alpha,
        white_luminance,
        primaries,
    };
    Ok((image, taken))
}

/// The f32 samples of a channel read as float.
fn floats(samples: &x::FlatSamples) -> &[f32] {
    match samples {
        x::FlatSamples::F32(values) => values,
        _ => &[],
    }
}

/// A channel read as float, at full resolution: a subsampled one's
/// samples repeated over the pixels they stand for.
fn full_resolution(channel: read::Channel, (width, height): (usize, usize)) -> Vec<f32> {
    let values = match channel.samples {
        x::FlatSamples::F32(values) => values,
        other => other.values_as_f32().collect(),
    };
    if channel.sampling == (1, 1) {
        return values;
    }
    let (sx, sy) = channel.sampling;
    let columns = channel.size.0.max(1);
    let rows = channel.size.1.max(1);
    let mut full = Vec::with_capacity(width * height);
    for y in 0..height {
        let row = (y / sy).min(rows - 1);
        full.extend((0..width).map(|x| {
            values
                .get(row * columns + (x / sx).min(columns - 1))
                .copied()
                .unwrap_or(0.0)
        }));
    }
    full
}

/// Every part of the file as `exr` holds an image, less the channels
/// taken out; subsampled channels at full resolution, which is how `exr`
/// writes them.
fn kept_image(headers: &[Header], channels: Vec<Vec<read::Channel>>) -> FlatImage {
    let mut layers = Layers::new();
    for (header, channels) in headers.iter().zip(channels) {
        let size = (header.layer_size.0, header.layer_size.1);
        let list = channels
            .into_iter()
            .map(|c| {
                let (name, linear, sampling) = (c.name.clone(), c.linear, c.sampling);
                let kind = c.kind;
                let sample_data = if sampling == (1, 1) {
                    c.samples
                } else {
                    let full = full_resolution(c, size);
                    match kind {
                        SampleType::F16 => {
                            x::FlatSamples::F16(full.into_iter().map(x::f16::from_f32).collect())
                        }
                        SampleType::F32 => x::FlatSamples::F32(full),
                        SampleType::U32 => {
                            x::FlatSamples::U32(full.into_iter().map(|v| v as u32).collect())
                        }
                    }
                };
                x::AnyChannel {
                    name,
                    sample_data,
                    quantize_linearly: linear,
                    sampling: x::Vec2(1, 1),
                }
            })
            .collect();
        layers.push(x::Layer {
            channel_data: x::AnyChannels::sort(list),
            attributes: header.own_attributes.clone(),
            size: header.layer_size,
            encoding: x::Encoding {
                compression: header.compression,
                line_order: header.line_order,
                blocks: match header.blocks {
                    BlockDescription::ScanLines => x::Blocks::ScanLines,
                    BlockDescription::Tiles(tiles) => x::Blocks::Tiles(tiles.tile_size),
                },
            },
        });
    }
    FlatImage {
        attributes: headers[0].shared_attributes.clone(),
        layer_data: layers,
    }
}
