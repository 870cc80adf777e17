//! OpenEXR through the `exr` crate: scanline or tiled, half, float or
//! uint, single or multi-part, every compression it reads.
//!
//! A compositor expects a result to drop back into its script, so the
//! whole file is kept ([`Kept`]): the colour layer we spread is taken out,
//! and a result written as EXR puts it back in its place, under its own
//! channel names and sample types, with every other layer, part, window and
//! attribute as it was.
use std::collections::BTreeMap;
use std::path::Path;

use aureole::image::{Image, Layout, Primaries};
use aureole::memory::format_bytes;
use exr::image::{FlatImage, Layers};
use exr::meta::attribute::{LevelMode, SampleType};
use exr::meta::header::Header;
use exr::meta::BlockDescription;
use exr::prelude::{self as x};
use half::slice::HalfFloatSliceExt;
use rayon::prelude::*;

use super::{Decoded, LinearPlanes, Note, Samples, HALF_MAX};
use crate::atomic::write_atomic;
use crate::compression::Compression;
use crate::error::{Error, Result};
use crate::formats::{explain, Choice, Shape};
use crate::limits::Limits;
use crate::spares::Spares;

mod b44;
mod chroma;
mod dwa;
mod layout;
mod piz;
mod predictor;
mod pxr24;
mod read;
mod rle;
mod write;
mod zip;

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

/// Where glare layers go beside a spread layer: `{parent}{name}.R`, or in
/// a single-part multi-view file, for a view other than the default,
/// `{parent}{name}.{view}.R` (OpenEXR's multi-view convention puts the view
/// last before the channel, so that each view's glare is a layer of that
/// view).
#[derive(Debug, Clone, Default)]
struct GlareAt {
    parent: String,
    view: Option<String>,
}

impl GlareAt {
    /// The place beside the layer of `prefix` in `part`.
    fn of(part: &Part, prefix: &str) -> GlareAt {
        let named = part.views.get(1..).unwrap_or_default();
        let trimmed = prefix.trim_end_matches('.');
        let (base, view) = match trimmed.rsplit_once('.') {
            Some((base, last)) if named.iter().any(|v| v == last) => {
                (format!("{base}."), Some(last))
            }
            None if named.iter().any(|v| v == trimmed) => (String::new(), Some(trimmed)),
            _ => (prefix.to_string(), None),
        };
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

/// A channel taken out of the file, to be put back under its own name.
#[derive(Debug, Clone)]
struct Taken {
    name: String,
    kind: SampleType,
    /// OpenEXR's `pLinear`: how lossy compressions quantise it.
    linear: bool,
}

impl Kept {
    /// The other views' names and images, to be replaced by results.
    pub(crate) fn views_mut(&mut self) -> impl Iterator<Item = (&str, &mut Image)> {
        self.views
            .iter_mut()
            .map(|v| (v.name.as_str(), &mut v.image))
    }

    /// Glare layers to write beside view `view`'s result.
    pub(crate) fn add_view_glare(&mut self, view: &str, layers: Vec<aureole::GlareLayer>) {
        if let Some(kept) = self.views.iter_mut().find(|v| v.name == view) {
            kept.glare = layers;
        }
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

/// Channels grouped by layer: the prefix up to the last `.`, and the rest.
fn by_prefix<'a, T>(
    names: impl Iterator<Item = (&'a str, T)>,
) -> BTreeMap<String, Vec<(&'a str, T)>> {
    let mut groups: BTreeMap<String, Vec<(&str, T)>> = BTreeMap::new();
    for (name, t) in names {
        let split = name.rfind('.').map_or(0, |i| i + 1);
        groups
            .entry(name[..split].to_string())
            .or_default()
            .push((&name[split..], t));
    }
    groups
}

/// A layer that holds colour: where, and which of its channels.
#[derive(Clone)]
struct Candidate {
    part: usize,
    part_name: Option<String>,
    prefix: String,
    /// `R`, `G`, `B` (or `Y`, or `Y`, `RY`, `BY`) as the file names them.
    colour: Vec<String>,
    alpha: Option<String>,
    chroma: bool,
    /// Its name says it holds data in colour channels (normals, positions,
    /// Cryptomatte IDs): chosen only by name, never as the beauty.
    data: bool,
}

/// Layer names (the last part of the prefix) that renderers use for data
/// written into R, G, B: Arnold's and RenderMan's `N` and `P`, Nuke's
/// `Pref`, motion and UV passes, Cryptomatte's `CryptoObject00`.
fn holds_data(prefix: &str) -> bool {
    const DATA: [&str; 14] = [
        "n",
        "p",
        "pref",
        "normal",
        "normals",
        "position",
        "vector",
        "vectors",
        "motion",
        "motionvector",
        "uv",
        "depth",
        "z",
        "id",
    ];
    let last = prefix
        .trim_end_matches('.')
        .rsplit('.')
        .next()
        .unwrap_or("");
    let last = last.to_ascii_lowercase();
    DATA.contains(&last.as_str()) || last.starts_with("crypto")
}

/// A layer of vectors (`N.X`, `N.Y`, `N.Z`; Blender's `Normal`, `Vector`,
/// `Position`): its `Y` is a component, not luminance. `X` tells them
/// apart; `Z` alone does not, as a luminance image's depth is `Y` and `Z`.
fn is_vector(short: &[&str]) -> bool {
    find(short, "X").is_some() && find(short, "Y").is_some()
}

impl Candidate {
    fn describe(&self) -> String {
        let channels: Vec<&str> = self
            .colour
            .iter()
            .chain(&self.alpha)
            .map(|c| c.strip_prefix(self.prefix.as_str()).unwrap_or(c))
            .collect();
        let part = match &self.part_name {
            Some(name) => format!("part {} {name:?}: ", self.part),
            None => String::new(),
        };
        format!(
            "{} ({part}{})",
            layer_name(&self.prefix),
            channels.join(", ")
        )
    }

    fn is_beauty(&self) -> bool {
        self.prefix.is_empty()
    }

    fn is_combined(&self) -> bool {
        self.prefix
            .trim_end_matches('.')
            .rsplit('.')
            .next()
            .is_some_and(|last| last.eq_ignore_ascii_case("combined"))
    }
}

/// The channel among `names` called `wanted`: exactly, else in another
/// case when only one matches.
fn find<'a>(names: &[&'a str], wanted: &str) -> Option<&'a str> {
    if let Some(exact) = names.iter().find(|n| **n == wanted) {
        return Some(exact);
    }
    let mut loose = names.iter().filter(|n| n.eq_ignore_ascii_case(wanted));
    match (loose.next(), loose.next()) {
        (Some(one), None) => Some(one),
        _ => None,
    }
}

/// Every colour layer of every part, in file order.
/// A part's name and channel names: what choosing a layer looks at, from a
/// decoded file or from its headers alone.
struct Part {
    name: Option<String>,
    channels: Vec<String>,
    /// The `view` it belongs to, in a multi-part stereo file.
    view: Option<String>,
    /// The `multiView` attribute: the views of a single-part stereo file,
    /// the default (unprefixed) view first.
    views: Vec<String>,
}

fn parts_of_headers(headers: &[Header]) -> Vec<Part> {
    let parts = headers.iter().map(|header| Part {
        name: header
            .own_attributes
            .layer_name
            .as_ref()
            .map(|n| n.to_string()),
        channels: header
            .channels
            .list
            .iter()
            .map(|c| c.name.to_string())
            .collect(),
        view: header
            .own_attributes
            .view_name
            .as_ref()
            .map(|v| v.to_string()),
        views: header
            .own_attributes
            .multi_view_names
            .iter()
            .flatten()
            .map(|v| v.to_string())
            .collect(),
    });
    parts.collect()
}

fn candidates(parts: &[Part]) -> Vec<Candidate> {
    let mut found = Vec::new();
    for (index, part) in parts.iter().enumerate() {
        for (prefix, channels) in by_prefix(part.channels.iter().map(|n| (n.as_str(), ()))) {
            let short: Vec<&str> = channels.iter().map(|(n, _)| *n).collect();
            let full = |c: &str| format!("{prefix}{c}");
            let rgb = ["R", "G", "B"].map(|c| find(&short, c));
            let (colour, chroma) = if let [Some(r), Some(g), Some(b)] = rgb {
                (vec![full(r), full(g), full(b)], false)
            } else if is_vector(&short) {
                continue;
            } else if let Some(y) = find(&short, "Y") {
                match (find(&short, "RY"), find(&short, "BY")) {
                    (Some(ry), Some(by)) => (vec![full(y), full(ry), full(by)], true),
                    _ => (vec![full(y)], false),
                }
            } else {
                continue;
            };
            found.push(Candidate {
                part: index,
                part_name: part.name.clone(),
                prefix: prefix.clone(),
                colour,
                alpha: find(&short, "A").map(full),
                chroma,
                data: holds_data(&prefix),
            });
        }
    }
    found
}

/// Parts of one colour channel (a grey picture stored as `G`): read as
/// luminance, as a compositor shows them, when no part holds colour.
fn lone_channels(parts: &[Part]) -> Vec<Candidate> {
    let mut found = Vec::new();
    for (index, part) in parts.iter().enumerate() {
        if let [name] = part.channels.as_slice() {
            let name = name.clone();
            let split = name.rfind('.').map_or(0, |i| i + 1);
            if find(&["R", "G", "B"], &name[split..]).is_none() {
                continue;
            }
            found.push(Candidate {
                part: index,
                part_name: part.name.clone(),
                prefix: name[..split].to_string(),
                colour: vec![name],
                alpha: None,
                chroma: false,
                data: false,
            });
        }
    }
    found
}

/// The layer to spread: the one asked for, else the beauty as compositors
/// find it (unprefixed channels, else the only colour layer, else
/// Blender's `Combined`).
fn choose(parts: &[Part], choice: &Choice) -> std::result::Result<Candidate, String> {
    let mut all = candidates(parts);
    if all.is_empty() {
        all = lone_channels(parts);
    }
    if let Some(wanted) = &choice.part {
        let named = |p: &Part| p.name.as_deref() == Some(wanted.as_str());
        let index = match wanted.trim().parse::<usize>() {
            Ok(i) if i < parts.len() => i,
            _ => parts.iter().position(named).ok_or_else(|| {
                let names: Vec<String> = parts
                    .iter()
                    .enumerate()
                    .map(|(i, p)| match &p.name {
                        Some(n) => format!("{i} ({n})"),
                        None => i.to_string(),
                    })
                    .collect();
                format!(
                    "there is no part {wanted:?}: the file's parts are {}",
                    names.join(", ")
                )
            })?,
        };
        all.retain(|c| c.part == index);
    }
    let listing = |all: &[Candidate]| {
        all.iter()
            .map(Candidate::describe)
            .collect::<Vec<_>>()
            .join("; ")
    };
    if let Some(wanted) = &choice.layer {
        let wanted = wanted.trim().trim_end_matches('.');
        let matches = |c: &Candidate, exact: bool| {
            let name = c.prefix.trim_end_matches('.');
            if exact {
                name == wanted
            } else {
                name.eq_ignore_ascii_case(wanted)
            }
        };
        let at = all
            .iter()
            .position(|c| matches(c, true))
            .or_else(|| all.iter().position(|c| matches(c, false)));
        return match at {
            Some(at) => Ok(all.swap_remove(at)),
            None => Err(match vectors_named(parts, wanted) {
                Some(channels) => format!(
                    "layer {wanted:?} holds vectors ({channels}), not light; the layers that can be chosen are {}",
                    listing(&all)
                ),
                None if all.is_empty() => no_colour(parts),
                None => format!(
                    "there is no colour layer {wanted:?}; the layers that can be chosen are {}",
                    listing(&all)
                ),
            }),
        };
    }
    let data: Vec<Candidate> = all.iter().filter(|c| c.data).cloned().collect();
    all.retain(|c| !c.data);
    let at = all
        .iter()
        .position(Candidate::is_beauty)
        .or_else(|| (all.len() == 1).then_some(0))
        .or_else(|| all.iter().position(Candidate::is_combined));
    match at {
        Some(at) => Ok(all.swap_remove(at)),
        None if all.is_empty() && data.is_empty() => Err(no_colour(parts)),
        None if all.is_empty() => Err(format!(
            "no colour layer: the layers with colour channels hold data ({}); choose one by name (--layer) if it is light",
            listing(&data)
        )),
        None => Err(format!(
            "several colour layers and none is the beauty (unprefixed R, G, B or Blender's Combined): {}; choose one by name (--layer)",
            listing(&all)
        )),
    }
}

/// The channels of a vector layer called `wanted`, if there is one.
fn vectors_named(parts: &[Part], wanted: &str) -> Option<String> {
    parts.iter().find_map(|part| {
        by_prefix(part.channels.iter().map(|n| (n.as_str(), ())))
            .into_iter()
            .find(|(prefix, channels)| {
                let short: Vec<&str> = channels.iter().map(|(n, _)| *n).collect();
                prefix.trim_end_matches('.').eq_ignore_ascii_case(wanted) && is_vector(&short)
            })
            .map(|(_, channels)| {
                let names: Vec<&str> = channels.iter().map(|(n, _)| *n).collect();
                names.join(", ")
            })
    })
}

fn no_colour(parts: &[Part]) -> String {
    let names: Vec<&str> = parts
        .iter()
        .flat_map(|p| p.channels.iter().map(String::as_str))
        .collect();
    format!(
        "no colour layer: a layer needs R, G, B or Y (channels: {})",
        names.join(", ")
    )
}

/// The same layer in each other view of a stereo or multi-view file, as
/// OpenEXR's multi-view convention names them: in a multi-part file, the
/// part of another `view` holding the layer under the same prefix (the one
/// whose name differs only by the view's, where several do); in a
/// single-part file with a `multiView` list, the layer whose prefix has the
/// view's name as its last component (`left.R`, `beauty.left.R`), the
/// default view's being unprefixed.
/// Returns the chosen layer's view and the others'.
fn other_views(parts: &[Part], chosen: &Candidate) -> (Option<String>, Vec<(String, Candidate)>) {
    let all = candidates(parts);
    let alike = |c: &Candidate, prefix: &str| {
        c.prefix == prefix && c.colour.len() == chosen.colour.len() && c.chroma == chosen.chroma
    };
    let part = &parts[chosen.part];
    let mut found: Vec<(String, Candidate)> = Vec::new();
    if let Some(view) = &part.view {
        for other_view in parts.iter().filter_map(|p| p.view.as_ref()) {
            if other_view == view || found.iter().any(|(v, _)| v == other_view) {
                continue;
            }
            let renamed = part
                .name
                .as_ref()
                .map(|n| n.replace(view.as_str(), other_view));
            let matching: Vec<&Candidate> = all
                .iter()
                .filter(|c| alike(c, &chosen.prefix))
                .filter(|c| parts[c.part].view.as_ref() == Some(other_view))
                .collect();
            let best = matching
                .iter()
                .find(|c| c.part_name.is_some() && c.part_name == renamed)
                .or(matching.first());
            if let Some(best) = best {
                found.push((other_view.clone(), (*best).clone()));
            }
        }
        (Some(view.clone()), found)
    } else if let Some((default, named)) = part.views.split_first() {
        let trimmed = chosen.prefix.trim_end_matches('.');
        let (base, view) = match trimmed.rsplit_once('.') {
            Some((base, last)) if named.iter().any(|v| v == last) => (format!("{base}."), last),
            None if named.iter().any(|v| v == trimmed) => (String::new(), trimmed),
            _ => (chosen.prefix.clone(), default.as_str()),
        };
        for other in part.views.iter().filter(|v| v.as_str() != view) {
            let prefix = if other == default {
                base.clone()
            } else {
                format!("{base}{other}.")
            };
            if let Some(c) = all
                .iter()
                .find(|c| c.part == chosen.part && alike(c, &prefix))
            {
                found.push((other.clone(), c.clone()));
            }
        }
        (Some(view.to_string()), found)
    } else {
        (None, found)
    }
}

/// The layers and parts besides `chosen`, for a note: a few names.
fn other_layers(parts: &[Part], chosen: &[&Candidate]) -> String {
    let mut names = Vec::new();
    for (index, part) in parts.iter().enumerate() {
        let groups = by_prefix(part.channels.iter().map(|n| (n.as_str(), ())));
        for prefix in groups.keys() {
            if chosen
                .iter()
                .any(|c| index == c.part && *prefix == c.prefix)
            {
                continue;
            }
            let name = layer_name(prefix);
            names.push(match &part.name {
                Some(part_name) if parts.len() > 1 => format!("{part_name}: {name}"),
                _ => name,
            });
        }
    }
    const SHOWN: usize = 6;
    if names.len() > SHOWN {
        let more = names.len() - SHOWN;
        names.truncate(SHOWN);
        names.push(format!("{more} more"));
    }
    names.join(", ")
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

    let mut notes = Vec::new();
    let mut spread: Vec<&Candidate> = vec![&chosen];
    spread.extend(views.iter().map(|(_, c)| c));
    let others = other_layers(&parts, &spread);
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

/// Samples to store, in a buffer `spares` lends: half (clamped to its
/// range, counted) or float; on every core, half through F16C where the
/// CPU has it.
fn samples(
    plane: &[f32],
    half: bool,
    clamp: bool,
    spares: &Spares,
    clamped: &mut usize,
) -> x::FlatSamples {
    const CHUNK: usize = 1 << 16;
    if !half {
        let mut out = spares.floats(plane.len());
        out.par_chunks_mut(CHUNK)
            .zip(plane.par_chunks(CHUNK))
            .for_each(|(o, p)| o.copy_from_slice(p));
        return x::FlatSamples::F32(out);
    }
    let mut out = spares.halves(plane.len());
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
    x::FlatSamples::F16(out)
}

/// A result to put back where its channels were taken from.
struct Layer<'a> {
    part: usize,
    prefix: &'a str,
    taken: &'a [Taken],
    chroma: bool,
    size: (usize, usize),
    colour: &'a [&'a [f32]],
    alpha: Option<&'a [f32]>,
}

/// Puts `result` into its part of `image` under the channel names and
/// sample types it was read with (unless `samples` says otherwise, or the
/// colour changed form from luminance/chroma to RGB).
fn put_back(
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
        x::AnyChannel {
            name: id.name.as_str().into(),
            sample_data: self::samples(plane, half, clamp, spares, clamped),
            quantize_linearly: id.linear,
            sampling: x::Vec2(1, 1),
        }
    };
    let mut list = std::mem::take(&mut layer.channel_data.list);
    for (id, plane) in colour_ids.iter().zip(result.colour) {
        list.push(channel(id, plane, true, clamped));
    }
    if let Some(alpha) = result.alpha {
        list.push(channel(&alpha_id, alpha, false, clamped));
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
            );
            for view in &views {
                add_glare(
                    &mut image.layer_data[view.part],
                    &view.glare_at,
                    &view.glare,
                    half,
                    &spares,
                    &mut clamped,
                );
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
            let mut image = new_image(&planes, &spares, &mut clamped);
            let half = planes.samples == Some(Samples::Half);
            add_glare(
                &mut image.layer_data[0],
                &GlareAt::default(),
                &glare,
                half,
                &spares,
                &mut clamped,
            );
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
fn give_back(image: FlatImage, spares: &Spares) {
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
fn is_half(kind: SampleType, samples: Option<Samples>) -> bool {
    match samples {
        Some(Samples::Half) => true,
        Some(Samples::Float) => false,
        None => kind == SampleType::F16,
    }
}

/// The prefix of the layer that holds a channel prefix's layer
/// (`ViewLayer.` of `ViewLayer.Combined.`), where glare layers go beside it.
fn parent(prefix: &str) -> &str {
    let trimmed = prefix.strip_suffix('.').unwrap_or(prefix);
    trimmed.rfind('.').map_or("", |at| &prefix[..=at])
}

/// Adds each glare layer's planes to `layer` as `{parent}{name}.R/G/B` (or
/// `.Y`; [`GlareAt`] for a view), in the beauty's sample type, replacing
/// channels of those names.
fn add_glare(
    layer: &mut x::Layer<x::AnyChannels<x::FlatSamples>>,
    at: &GlareAt,
    glare: &[aureole::GlareLayer],
    half: bool,
    spares: &Spares,
    clamped: &mut usize,
) {
    if glare.is_empty() {
        return;
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
                samples(plane, half, true, spares, clamped),
            ));
        }
    }
    let mut list = std::mem::take(&mut layer.channel_data.list);
    list.retain(|c| !added.iter().any(|a| a.name == c.name));
    list.extend(added);
    layer.channel_data = x::AnyChannels::sort(list);
}

/// A single-part file of the planes: `Y` or `R`, `G`, `B`, and `A`.
fn new_image(planes: &LinearPlanes, spares: &Spares, clamped: &mut usize) -> FlatImage {
    let names: &[&str] = if planes.colour.len() == 1 {
        &["Y"]
    } else {
        &["R", "G", "B"]
    };
    let half = planes.samples == Some(Samples::Half);
    let mut list: Vec<x::AnyChannel<x::FlatSamples>> = names
        .iter()
        .zip(&planes.colour)
        .map(|(name, plane)| x::AnyChannel::new(*name, samples(plane, half, true, spares, clamped)))
        .collect();
    if let Some(alpha) = planes.alpha {
        list.push(x::AnyChannel::new(
            "A",
            samples(alpha, half, false, spares, clamped),
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
    let mut layers = Layers::new();
    layers.push(image.layer_data);
    FlatImage {
        attributes: image.attributes,
        layer_data: layers,
    }
}
