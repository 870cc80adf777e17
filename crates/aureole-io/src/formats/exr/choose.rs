//! Which layer of an EXR file is spread: its parts, views and channel
//! names read as layers, the beauty found (or the one asked for by name),
//! and the same layer in the file's other views.

use std::collections::BTreeMap;

use exr::meta::header::Header;

use super::layer_name;
use crate::formats::Choice;

/// Channels grouped by layer: the prefix up to the last `.`, and the rest.
pub(super) fn by_prefix<'a, T>(
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
pub(super) struct Candidate {
    pub(super) part: usize,
    pub(super) part_name: Option<String>,
    pub(super) prefix: String,
    /// `R`, `G`, `B` (or `Y`, or `Y`, `RY`, `BY`) as the file names them.
    pub(super) colour: Vec<String>,
    pub(super) alpha: Option<String>,
    pub(super) chroma: bool,
    /// Its name says it holds data in colour channels (normals, positions,
    /// Cryptomatte IDs): chosen only by name, never as the beauty.
    pub(super) data: bool,
}

/// Layer names (the last part of the prefix) that renderers use for data
/// written into R, G, B: Arnold's and RenderMan's `N` and `P`, Nuke's
/// `Pref`, motion and UV passes, Cryptomatte's `CryptoObject00`.
pub(super) fn holds_data(prefix: &str) -> bool {
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
pub(super) fn is_vector(short: &[&str]) -> bool {
    find(short, "X").is_some() && find(short, "Y").is_some()
}

impl Candidate {
    pub(super) fn describe(&self) -> String {
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
pub(super) fn find<'a>(names: &[&'a str], wanted: &str) -> Option<&'a str> {
    if let Some(exact) = names.iter().find(|n| **n == wanted) {
        return Some(exact);
    }
    let mut loose = names.iter().filter(|n| n.eq_ignore_ascii_case(wanted));
    match (loose.next(), loose.next()) {
        (Some(one), None) => Some(one),
        _ => None,
    }
}

/// A part's name and channel names: what choosing a layer looks at, from a
/// decoded file or from its headers alone.
pub(super) struct Part {
    pub(super) name: Option<String>,
    pub(super) channels: Vec<String>,
    /// The `view` it belongs to, in a multi-part stereo file.
    pub(super) view: Option<String>,
    /// The `multiView` attribute: the views of a single-part stereo file,
    /// the default (unprefixed) view first.
    pub(super) views: Vec<String>,
}

pub(super) fn parts_of_headers(headers: &[Header]) -> Vec<Part> {
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

pub(super) fn candidates(parts: &[Part]) -> Vec<Candidate> {
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
pub(super) fn lone_channels(parts: &[Part]) -> Vec<Candidate> {
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
pub(super) fn choose(parts: &[Part], choice: &Choice) -> std::result::Result<Candidate, String> {
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
pub(super) fn vectors_named(parts: &[Part], wanted: &str) -> Option<String> {
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

pub(super) fn no_colour(parts: &[Part]) -> String {
    let names: Vec<&str> = parts
        .iter()
        .flat_map(|p| p.channels.iter().map(String::as_str))
        .collect();
    format!(
        "no colour layer: a layer needs R, G, B or Y (channels: {})",
        names.join(", ")
    )
}

/// A layer's prefix in a single-part multi-view file split into the
/// layer's own (`beauty.`) and the view it names, where its last component
/// is one of `named`, the views but the default (whose layers carry no
/// view's name): `beauty.left.` is (`beauty.`, `left`), `left.` is (``,
/// `left`), `beauty.` is (`beauty.`, none).
pub(super) fn split_view<'a>(prefix: &'a str, named: &[String]) -> (String, Option<&'a str>) {
    let trimmed = prefix.trim_end_matches('.');
    match trimmed.rsplit_once('.') {
        Some((base, last)) if named.iter().any(|v| v == last) => (format!("{base}."), Some(last)),
        None if named.iter().any(|v| v == trimmed) => (String::new(), Some(trimmed)),
        _ => (prefix.to_string(), None),
    }
}

/// The same layer in each other view of a stereo or multi-view file, as
/// OpenEXR's multi-view convention names them: in a multi-part file, the
/// part of another `view` holding the layer under the same prefix (the one
/// whose name differs only by the view's, where several do); in a
/// single-part file with a `multiView` list, the layer whose prefix has the
/// view's name as its last component (`left.R`, `beauty.left.R`), the
/// default view's being unprefixed.
/// Returns the chosen layer's view and the others'.
pub(super) fn other_views(
    parts: &[Part],
    chosen: &Candidate,
) -> (Option<String>, Vec<(String, Candidate)>) {
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
        let (base, view) = split_view(&chosen.prefix, named);
        let view = view.unwrap_or(default);
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
pub(super) fn other_layers(parts: &[Part], chosen: &[&Candidate]) -> String {
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
