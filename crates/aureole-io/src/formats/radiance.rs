//! Radiance RGBE (`.hdr`) through the `image` crate: three channels sharing
//! an exponent, no negatives and no alpha. The header's `EXPOSURE` and
//! `COLORCORR` (what the pixels were multiplied by after rendering) are
//! undone on reading and written back into a result, and `PRIMARIES` gives
//! the luminance weights, like an EXR's chromaticities.

use std::io::Cursor;
use std::path::Path;

use aureole::image::Primaries;
use image::{codecs::hdr::HdrEncoder, Rgb};

use super::{Decoded, LinearPlanes, Note};
use crate::atomic::write_atomic;
use crate::error::{Error, Result};
use crate::limits::Limits;

const NAME: &str = "Radiance RGBE";

/// What a Radiance header said about its pixels.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Header {
    /// `EXPOSURE`: every pixel was multiplied by it.
    exposure: f32,
    /// `COLORCORR`: each channel was multiplied by its factor.
    correction: [f32; 3],
    /// `PRIMARIES` as written, passed through.
    primaries: Option<String>,
    /// The `VIEW` lines' options, in order (a later option overrides).
    pub(crate) view: Option<String>,
}

/// Radiance's own primaries, which a picture without a `PRIMARIES` line
/// is in (`color.h`'s `STDPRIMS`): its luminance is 0.265 R + 0.670 G +
/// 0.065 B, as `evalglare` and `pvalue -b` weigh it.
pub const STANDARD_PRIMARIES: Primaries = Primaries {
    red: [0.640, 0.330],
    green: [0.290, 0.600],
    blue: [0.150, 0.060],
    white: [1.0 / 3.0, 1.0 / 3.0],
};

/// Decodes a Radiance file: the pixels through the `image` crate, then the
/// header's exposure and colour correction undone.
pub(crate) fn decode(bytes: &[u8], limits: Limits) -> std::result::Result<Decoded, String> {
    let mut decoded = super::picture::decode(bytes, limits)?;
    let Ok(decoder) = image::codecs::hdr::HdrDecoder::new(Cursor::new(bytes)) else {
        return Ok(decoded);
    };
    let meta = decoder.metadata();
    let positive = |v: f32| v.is_finite() && v > 0.0;
    let exposure = meta.exposure.filter(|e| positive(*e)).unwrap_or(1.0);
    // A factor of 0 or less would make every pixel infinite or negative:
    // the writer meant none, and the user hears so.
    if let Some(bad) = meta.exposure.filter(|e| !positive(*e)) {
        decoded.notes.push(format!(
            "the header's EXPOSURE={bad} is not a factor above 0: ignored, pixels read as stored"
        ));
    }
    if let Some((r, g, b)) = meta
        .color_correction
        .filter(|(r, g, b)| [r, g, b].iter().any(|v| !positive(**v)))
    {
        decoded.notes.push(format!(
            "the header's COLORCORR={r} {g} {b} holds a factor that is not above 0: ignored, pixels read as stored"
        ));
    }
    let correction = meta
        .color_correction
        .map(|(r, g, b)| [r, g, b])
        .filter(|c| c.iter().all(|v| positive(*v)))
        .unwrap_or([1.0; 3]);
    let primaries_text = meta
        .custom_attributes
        .iter()
        .find(|(k, _)| k == "PRIMARIES")
        .map(|(_, v)| v.trim().to_string());
    let primaries = primaries_text.as_deref().and_then(parse_primaries);
    if exposure != 1.0 || correction != [1.0; 3] {
        for (c, plane) in decoded.image.planes.iter_mut().enumerate() {
            let gain = 1.0 / (exposure * correction[c.min(2)]);
            plane.iter_mut().for_each(|v| *v *= gain);
        }
        decoded.notes.push(format!(
            "the header's EXPOSURE={exposure}{} is undone (pixels divided by it), and written back into a .hdr result",
            if correction != [1.0; 3] {
                format!(" and COLORCORR={} {} {}", correction[0], correction[1], correction[2])
            } else {
                String::new()
            }
        ));
    }
    if let Some(p) = primaries {
        if p.luminance_weights().is_some() {
            decoded.image.primaries = Some(p);
        } else {
            decoded
                .notes
                .push("the header's PRIMARIES are degenerate: luminance uses Rec.709".into());
        }
    }
    let views: Vec<&str> = meta
        .custom_attributes
        .iter()
        .filter(|(k, _)| k == "VIEW")
        .map(|(_, v)| v.trim())
        .collect();
    decoded.original.radiance = Some(Header {
        exposure,
        correction,
        primaries: primaries_text,
        view: (!views.is_empty()).then(|| views.join(" ")),
    });
    Ok(decoded)
}

/// The view options of the Radiance picture at `path` (its `VIEW=` lines,
/// in order), read from its header alone; `None` for another file or a
/// picture without one.
pub fn read_view(path: &Path) -> Option<String> {
    use std::io::{BufRead, Read};
    let file = std::fs::File::open(path).ok()?;
    // A header is a few lines; a file whose first 64 KiB hold no end of
    // header is not read further.
    let mut reader = std::io::BufReader::new(file.take(1 << 16));
    let mut line = String::new();
    reader.read_line(&mut line).ok()?;
    if !(line.starts_with("#?RADIANCE") || line.starts_with("#?RGBE")) {
        return None;
    }
    let mut views = Vec::new();
    loop {
        line.clear();
        if reader.read_line(&mut line).ok()? == 0 || line.trim().is_empty() {
            break;
        }
        if let Some(view) = line.strip_prefix("VIEW=") {
            views.push(view.trim().to_string());
        }
    }
    (!views.is_empty()).then(|| views.join(" "))
}

/// `PRIMARIES= rx ry gx gy bx by wx wy`; `None` when absent or all zero.
fn parse_primaries(text: &str) -> Option<Primaries> {
    let v: Vec<f32> = text
        .split_whitespace()
        .map(str::parse)
        .collect::<std::result::Result<_, _>>()
        .ok()?;
    let [rx, ry, gx, gy, bx, by, wx, wy] = v.as_slice() else {
        return None;
    };
    // Some writers put eight zeros for "not known".
    if v.iter().all(|x| *x == 0.0) {
        return None;
    }
    Some(Primaries {
        red: [*rx, *ry],
        green: [*gx, *gy],
        blue: [*bx, *by],
        white: [*wx, *wy],
    })
}

/// Writes the planes as RGBE (a luminance plane in all three channels),
/// negatives as 0, atomically; into a file read as Radiance, its exposure,
/// colour correction and primaries go back as they were.
pub(crate) fn encode(path: &Path, planes: LinearPlanes) -> Result<Vec<Note>> {
    let mut notes = Vec::new();
    let colour = &planes.colour;
    let negatives = colour
        .iter()
        .flat_map(|p| p.iter())
        .filter(|v| **v < 0.0)
        .count();
    if negatives > 0 {
        notes.push(Note::NegativesZeroed {
            count: negatives,
            format: NAME,
        });
    }
    if planes.alpha.is_some() {
        notes.push(Note::AlphaDropped {
            format: "Radiance .hdr",
        });
    }
    let header = planes.original.radiance.clone();
    let gain = |c: usize| {
        header
            .as_ref()
            .map_or(1.0, |h| h.exposure * h.correction[c])
    };
    let plane = |c: usize| colour[c.min(colour.len() - 1)];
    let pixels: Vec<Rgb<f32>> = (0..planes.width * planes.height)
        .map(|i| Rgb([0, 1, 2].map(|c| (plane(c)[i] * gain(c)).max(0.0))))
        .collect();
    let encode_error = |message: String| Error::Encode {
        path: path.to_path_buf(),
        format: "Radiance HDR",
        message,
    };
    let mut bytes = Vec::new();
    HdrEncoder::new(&mut bytes)
        .encode(&pixels, planes.width, planes.height)
        .map_err(|e| encode_error(e.to_string()))?;
    // The encoder writes a fixed header; ours go after its FORMAT line.
    if let Some(h) = &header {
        let mut lines = String::new();
        if h.exposure != 1.0 {
            lines += &format!("EXPOSURE={}\n", h.exposure);
        }
        if h.correction != [1.0; 3] {
            let [r, g, b] = h.correction;
            lines += &format!("COLORCORR={r} {g} {b}\n");
        }
        if let Some(p) = &h.primaries {
            lines += &format!("PRIMARIES={p}\n");
        }
        // The view stays true of the result: glare figures and Radiance's
        // tools read it.
        if let Some(v) = &h.view {
            lines += &format!("VIEW= {v}\n");
        }
        let format_line = b"FORMAT=32-bit_rle_rgbe\n";
        let at = bytes
            .windows(format_line.len())
            .position(|w| w == format_line)
            .map(|at| at + format_line.len())
            .ok_or_else(|| encode_error("the encoder wrote no FORMAT line".into()))?;
        bytes.splice(at..at, lines.into_bytes());
    }
    write_atomic(path, |out| {
        std::io::Write::write_all(out, &bytes).map_err(|e| Error::io(path, e))
    })?;
    Ok(notes)
}
