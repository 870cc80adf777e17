//! Writing an EXR result: the spread layer's planes put back into the
//! file they came from (every view, part, layer and attribute kept), the
//! glare layers beside them, or a new file of the planes alone.

use std::path::Path;

use exr::image::{FlatImage, Layers};
use exr::meta::attribute::SampleType;
use exr::prelude::{self as x};
use half::slice::HalfFloatSliceExt;
use rayon::prelude::*;

use super::choose::{split_view, Part};
use super::{dwa, write, Kept, LinearPlanes, Note, Samples, Taken, HALF_MAX};
use crate::atomic::write_atomic;
use crate::compression::Compression;
use crate::error::{Error, Result};
use crate::spares::Spares;

/// Where glare layers go beside a spread layer: `{parent}{name}.R`, or in
/// a single-part multi-view file, for a view other than the default,
/// `{parent}{name}.{view}.R` (OpenEXR's multi-view convention puts the view
/// last before the channel, so that each view's glare is a layer of that
/// view).
#[derive(Debug, Clone, Default)]
pub(super) struct GlareAt {
    pub(super) parent: String,
    pub(super) view: Option<String>,
}

impl GlareAt {
    /// The place beside the layer of `prefix` in `part`.
    pub(super) fn of(part: &Part, prefix: &str) -> GlareAt {
        let named = part.views.get(1..).unwrap_or_default();
        let (base, view) = split_view(prefix, named);
        GlareAt {
            parent: parent(&base).to_string(),
            view: view.map(str::to_string),
        }
    }

    fn name(&self, glare: &str, channel: &str) -> String {
        match &self.view {
            Some(view) => format!("{}{glare}.{view}.{channel}", self.parent),
            None => format!("{}{glare}.{channel}", self.parent),
        }
    }
}

/// Samples to store, in a buffer `spares` lends: half (clamped to its
/// range, counted) or float; on every core, half through F16C where the
/// CPU has it. A buffer the allocator refuses is said in words.
pub(super) fn samples(
    plane: &[f32],
    half: bool,
    clamp: bool,
    spares: &Spares,
    clamped: &mut usize,
) -> std::result::Result<x::FlatSamples, String> {
    const CHUNK: usize = 1 << 16;
    if !half {
        let mut out = spares.floats(plane.len()).map_err(|e| e.to_string())?;
        out.par_chunks_mut(CHUNK)
            .zip(plane.par_chunks(CHUNK))
            .for_each(|(o, p)| o.copy_from_slice(p));
        return Ok(x::FlatSamples::F32(out));
    }
    let mut out = spares.halves(plane.len()).map_err(|e| e.to_string())?;
    *clamped += out
        .par_chunks_mut(CHUNK)
        .zip(plane.par_chunks(CHUNK))
        .map(|(o, p)| {
            o.convert_from_f32_slice(p);
            if !clamp {
                return 0;
            }
            let mut beyond = 0;
            for (o, &v) in o.iter_mut().zip(p) {
                if v.is_finite() && v.abs() > HALF_MAX {
                    *o = x::f16::from_f32(v.clamp(-HALF_MAX, HALF_MAX));
                    beyond += 1;
                }
            }
            beyond
        })
        .sum::<usize>();
    Ok(x::FlatSamples::F16(out))
}

/// A result to put back where its channels were taken from.
pub(super) struct Layer<'a> {
    pub(super) part: usize,
    pub(super) prefix: &'a str,
    pub(super) taken: &'a [Taken],
    pub(super) chroma: bool,
    pub(super) size: (usize, usize),
    pub(super) colour: &'a [&'a [f32]],
    pub(super) alpha: Option<&'a [f32]>,
}

/// Puts `result` into its part of `image` under the channel names and
/// sample types it was read with (unless `samples` says otherwise, or the
/// colour changed form from luminance/chroma to RGB).
pub(super) fn put_back(
    image: &mut FlatImage,
    result: &Layer,
    samples: Option<Samples>,
    spares: &Spares,
    clamped: &mut usize,
) -> std::result::Result<(), String> {
    let colours = result.colour.len();
    let layer = &mut image.layer_data[result.part];
    if (layer.size.0, layer.size.1) != result.size {
        return Err(format!(
            "the result is {}x{} but the layer read was {}x{}",
            result.size.0, result.size.1, layer.size.0, layer.size.1
        ));
    }
    let taken = result.taken;
    let like = |name: &str| Taken {
        name: format!("{}{name}", result.prefix),
        kind: taken.first().map_or(SampleType::F32, |t| t.kind),
        linear: false,
    };
    let colour_ids: Vec<Taken> = if result.chroma || taken.len() < colours {
        let names: &[&str] = if colours == 3 {
            &["R", "G", "B"]
        } else {
            &["Y"]
        };
        names.iter().map(|n| like(n)).collect()
    } else {
        taken[..colours].to_vec()
    };
    let alpha_id = taken
        .get(if result.chroma { 3 } else { colours })
        .cloned()
        .unwrap_or_else(|| like("A"));
    let channel = |id: &Taken, plane: &[f32], clamp: bool, clamped: &mut usize| {
        let half = is_half(id.kind, samples);
        Ok::<_, String>(x::AnyChannel {
            name: id.name.as_str().into(),
            sample_data: self::samples(plane, half, clamp, spares, clamped)?,
            quantize_linearly: id.linear,
            sampling: x::Vec2(1, 1),
        })
    };
    let mut list = std::mem::take(&mut layer.channel_data.list);
    for (id, plane) in colour_ids.iter().zip(result.colour) {
        list.push(channel(id, plane, true, clamped)?);
    }
    if let Some(alpha) = result.alpha {
        list.push(channel(&alpha_id, alpha, false, clamped)?);
    }
    layer.channel_data = x::AnyChannels::sort(list);
    // A preview shows the picture before the camera: no longer true.
    layer.attributes.preview = None;
    Ok(())
}

/// Writes the planes to `path` atomically: into the file they were read
/// from when it is given, else as a new file. With half samples, values
/// beyond the half range are clamped to it (and counted).
pub(crate) fn encode(path: &Path, mut planes: LinearPlanes) -> Result<Vec<Note>> {
    let encode_error = |message: String| Error::Encode {
        path: path.to_path_buf(),
        format: "EXR",
        message,
    };
    let colours = planes.colour.len();
    if colours != 1 && colours != 3 {
        return Err(encode_error(format!(
            "expected 1 or 3 channels, not {colours}"
        )));
    }
    let mut notes = Vec::new();
    let mut clamped = 0;
    let glare = std::mem::take(&mut planes.original.glare);
    let spares = std::mem::take(&mut planes.original.spares);
    let image = match planes.original.exr.take() {
        Some(kept) => {
            let Kept {
                mut image,
                part,
                prefix,
                taken,
                chroma,
                glare_at,
                views,
            } = *kept;
            let result = Layer {
                part,
                prefix: &prefix,
                taken: &taken,
                chroma,
                size: (planes.width, planes.height),
                colour: &planes.colour,
                alpha: planes.alpha,
            };
            put_back(&mut image, &result, planes.samples, &spares, &mut clamped)
                .map_err(encode_error)?;
            // The glare in the spread layer's sample type.
            let kind = taken.first().map_or(SampleType::F32, |t| t.kind);
            let half = is_half(kind, planes.samples);
            add_glare(
                &mut image.layer_data[part],
                &glare_at,
                &glare,
                half,
                &spares,
                &mut clamped,
            )
            .map_err(encode_error)?;
            for view in &views {
                add_glare(
                    &mut image.layer_data[view.part],
                    &view.glare_at,
                    &view.glare,
                    half,
                    &spares,
                    &mut clamped,
                )
                .map_err(|e| encode_error(format!("view {}: {e}", view.name)))?;
                let colour: Vec<&[f32]> = view.image.planes.iter().map(Vec::as_slice).collect();
                let result = Layer {
                    part: view.part,
                    prefix: &view.prefix,
                    taken: &view.taken,
                    chroma: view.chroma,
                    size: (view.image.width, view.image.height),
                    colour: &colour,
                    alpha: view.image.alpha.as_deref(),
                };
                put_back(&mut image, &result, planes.samples, &spares, &mut clamped)
                    .map_err(|e| encode_error(format!("view {}: {e}", view.name)))?;
            }
            if let Some(compression) = planes.compression {
                for layer in image.layer_data.iter_mut() {
                    layer.encoding.compression = compression.to_exr();
                }
            }
            image
        }
        None => {
            let mut image = new_image(&planes, &spares, &mut clamped).map_err(encode_error)?;
            let half = planes.samples == Some(Samples::Half);
            add_glare(
                &mut image.layer_data[0],
                &GlareAt::default(),
                &glare,
                half,
                &spares,
                &mut clamped,
            )
            .map_err(encode_error)?;
            image
        }
    };
    if clamped > 0 {
        notes.push(Note::ClampedToHalf { count: clamped });
    }
    let mut lowered = None;
    write_atomic(path, |out| {
        lowered = Some(write::write(&image, out).map_err(|e| encode_error(e.to_string()))?);
        Ok(())
    })?;
    if let Some(lowered) = lowered.filter(|l| l.count > 0) {
        let dwa = image
            .layer_data
            .iter()
            .map(|l| l.encoding.compression)
            .find(|&c| dwa::is_dwa(c))
            .and_then(Compression::from_exr)
            .unwrap_or(Compression::Dwaa);
        notes.push(Note::ClampedForCompression {
            count: lowered.count,
            compression: dwa,
            ceiling: lowered.ceiling as u32,
        });
    }
    give_back(image, &spares);
    Ok(notes)
}

/// The samples of a written image, kept for the next frame's.
pub(super) fn give_back(image: FlatImage, spares: &Spares) {
    for layer in image.layer_data {
        for channel in layer.channel_data.list {
            match channel.sample_data {
                x::FlatSamples::F16(values) => spares.give_halves(values),
                x::FlatSamples::F32(values) => spares.give_floats(values),
                x::FlatSamples::U32(_) => {}
            }
        }
    }
}

/// Whether a channel read as `kind` is written as half floats: as read,
/// unless `samples` says.
pub(super) fn is_half(kind: SampleType, samples: Option<Samples>) -> bool {
    match samples {
        Some(Samples::Half) => true,
        Some(Samples::Float) => false,
        None => kind == SampleType::F16,
    }
}

/// The prefix of the layer that holds a channel prefix's layer
/// (`ViewLayer.` of `ViewLayer.Combined.`), where glare layers go beside it.
pub(super) fn parent(prefix: &str) -> &str {
    let trimmed = prefix.strip_suffix('.').unwrap_or(prefix);
    trimmed.rfind('.').map_or("", |at| &prefix[..=at])
}

/// Adds each glare layer's planes to `layer` as `{parent}{name}.R/G/B` (or
/// `.Y`; [`GlareAt`] for a view), in the beauty's sample type, replacing
/// channels of those names.
pub(super) fn add_glare(
    layer: &mut x::Layer<x::AnyChannels<x::FlatSamples>>,
    at: &GlareAt,
    glare: &[aureole::GlareLayer],
    half: bool,
    spares: &Spares,
    clamped: &mut usize,
) -> std::result::Result<(), String> {
    if glare.is_empty() {
        return Ok(());
    }
    let mut added = Vec::new();
    for one in glare {
        let names: &[&str] = if one.image.planes.len() == 3 {
            &["R", "G", "B"]
        } else {
            &["Y"]
        };
        for (short, plane) in names.iter().zip(&one.image.planes) {
            let name = at.name(&one.name, short);
            added.push(x::AnyChannel::new(
                name.as_str(),
                samples(plane, half, true, spares, clamped)?,
            ));
        }
    }
    let mut list = std::mem::take(&mut layer.channel_data.list);
    list.retain(|c| !added.iter().any(|a| a.name == c.name));
    list.extend(added);
    layer.channel_data = x::AnyChannels::sort(list);
    Ok(())
}

/// A single-part file of the planes: `Y` or `R`, `G`, `B`, and `A`.
pub(super) fn new_image(
    planes: &LinearPlanes,
    spares: &Spares,
    clamped: &mut usize,
) -> std::result::Result<FlatImage, String> {
    let names: &[&str] = if planes.colour.len() == 1 {
        &["Y"]
    } else {
        &["R", "G", "B"]
    };
    let half = planes.samples == Some(Samples::Half);
    let mut list: Vec<x::AnyChannel<x::FlatSamples>> = names
        .iter()
        .zip(&planes.colour)
        .map(|(name, plane)| {
            Ok(x::AnyChannel::new(
                *name,
                samples(plane, half, true, spares, clamped)?,
            ))
        })
        .collect::<std::result::Result<_, String>>()?;
    if let Some(alpha) = planes.alpha {
        list.push(x::AnyChannel::new(
            "A",
            samples(alpha, half, false, spares, clamped)?,
        ));
    }
    let attributes = x::LayerAttributes {
        white_luminance: planes.white_luminance,
        ..x::LayerAttributes::default()
    };
    let layer = x::Layer::new(
        (planes.width, planes.height),
        attributes,
        x::Encoding {
            compression: planes.compression.unwrap_or(Compression::Zip).to_exr(),
            ..x::Encoding::SMALL_LOSSLESS
        },
        x::AnyChannels::sort(list.into_iter().collect()),
    );
    let mut image = x::Image::from_layer(layer);
    image.attributes.chromaticities =
        planes
            .primaries
            .map(|p| exr::meta::attribute::Chromaticities {
                red: x::Vec2(p.red[0], p.red[1]),
                green: x::Vec2(p.green[0], p.green[1]),
                blue: x::Vec2(p.blue[0], p.blue[1]),
                white: x::Vec2(p.white[0], p.white[1]),
            });
    if let Some(width) = planes
        .kernel
        .image_width
        .and_then(|w| i32::try_from(w).ok())
    {
        image.attributes.other.insert(
            crate::formats::IMAGE_WIDTH_ATTRIBUTE.into(),
            exr::meta::attribute::AttributeValue::I32(width),
        );
    }
    if let Some(threshold) = planes.kernel.threshold {
        image.attributes.other.insert(
            crate::formats::THRESHOLD_ATTRIBUTE.into(),
            exr::meta::attribute::AttributeValue::F64(threshold),
        );
    }
    if let Some(least) = planes.kernel.shares {
        image.attributes.other.insert(
            crate::formats::LIGHT_ATTRIBUTE.into(),
            exr::meta::attribute::AttributeValue::F64(least),
        );
    }
    let mut layers = Layers::new();
    layers.push(image.layer_data);
    Ok(FlatImage {
        attributes: image.attributes,
        layer_data: layers,
    })
}
