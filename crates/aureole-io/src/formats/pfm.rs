//! Portable Float Map: `PF` (RGB) or `Pf` (one channel), a text header
//! `W H` and a scale whose sign gives the byte order (negative: little
//! endian), then float32 rows from the bottom of the image to the top.

use std::io::Write;
use std::path::Path;

use aureole::image::{Image, Layout};
use aureole::memory::format_bytes;
use rayon::prelude::*;

use super::{Decoded, LinearPlanes, Note};
use crate::atomic::write_atomic;
use crate::error::{Error, Result};
use crate::limits::Limits;

/// A decoded PFM: planes top row first, like every image in the library.
#[derive(Debug, Clone, PartialEq)]
pub struct Pfm {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// One plane (`Pf`) or three (`PF`: R, G, B).
    pub planes: Vec<Vec<f32>>,
}

/// Writes one plane as `Pf` or three as `PF`, little endian, atomically.
pub(crate) fn encode(path: &Path, image: LinearPlanes) -> Result<Vec<Note>> {
    let (width, height, planes) = (image.width, image.height, &image.colour);
    let magic = match planes.len() {
        1 => "Pf",
        3 => "PF",
        n => {
            return Err(Error::Encode {
                path: path.to_path_buf(),
                format: "PFM",
                message: format!("PFM holds 1 or 3 channels, not {n}"),
            })
        }
    };
    write_atomic(path, |out| {
        let io = |e| Error::io(path, e);
        write!(out, "{magic}\n{width} {height}\n-1.0\n").map_err(io)?;
        // Blocks of rows turned into bytes in parallel, written in order.
        const ROWS: usize = 64;
        let row_bytes = width * planes.len() * 4;
        let mut block = vec![0u8; ROWS * row_bytes];
        let rows: Vec<usize> = (0..height).rev().collect();
        for part in rows.chunks(ROWS) {
            let bytes = &mut block[..part.len() * row_bytes];
            bytes
                .par_chunks_mut(row_bytes)
                .zip(part)
                .for_each(|(out, &y)| {
                    for (x, pixel) in out.chunks_exact_mut(planes.len() * 4).enumerate() {
                        for (value, plane) in pixel.chunks_exact_mut(4).zip(planes) {
                            value.copy_from_slice(&plane[y * width + x].to_le_bytes());
                        }
                    }
                });
            out.write_all(bytes).map_err(io)?;
        }
        Ok(())
    })?;
    Ok(if image.alpha.is_some() {
        vec![Note::AlphaDropped { format: "PFM" }]
    } else {
        Vec::new()
    })
}

/// Decodes a PFM file for the format table.
pub(crate) fn decode_file(bytes: &[u8], limits: Limits) -> std::result::Result<Decoded, String> {
    let pfm = decode_limited(bytes, limits.max_bytes)?;
    let layout = if pfm.planes.len() == 1 {
        Layout::Luminance
    } else {
        Layout::Rgb
    };
    Ok(Decoded {
        image: Image {
            width: pfm.width,
            height: pfm.height,
            layout,
            planes: pfm.planes,
            alpha: None,
            white_luminance: None,
            primaries: None,
        },
        display_referred: false,
        notes: Vec::new(),
        compression: None,
        original: Default::default(),
    })
}

/// A PFM header: what follows the magic, and where the samples start.
pub(crate) struct Header {
    pub channels: usize,
    pub width: usize,
    pub height: usize,
    scale: f32,
    /// The offset of the whitespace byte that ends the header.
    at: usize,
}

/// Parses the header at the start of `bytes`.
pub(crate) fn header(bytes: &[u8]) -> std::result::Result<Header, String> {
    let mut at = 0;
    let mut token = |what: &str| -> std::result::Result<String, String> {
        while at < bytes.len() && bytes[at].is_ascii_whitespace() {
            at += 1;
        }
        let start = at;
        while at < bytes.len() && !bytes[at].is_ascii_whitespace() && at - start < 64 {
            at += 1;
        }
        if start == at {
            return Err(format!("PFM header ends before its {what}"));
        }
        Ok(String::from_utf8_lossy(&bytes[start..at]).into_owned())
    };
    let channels = match token("magic")?.as_str() {
        "PF" => 3,
        "Pf" => 1,
        other => {
            return Err(format!(
                "not a PFM file: magic {other:?}, expected \"PF\" or \"Pf\""
            ))
        }
    };
    let dimension = |text: String, what: &str| {
        text.parse::<usize>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| format!("PFM {what} {text:?} is not a whole number above 0"))
    };
    let width = dimension(token("width")?, "width")?;
    let height = dimension(token("height")?, "height")?;
    let scale_text = token("scale")?;
    let scale: f32 = scale_text
        .parse()
        .ok()
        .filter(|s: &f32| s.is_finite() && *s != 0.0)
        .ok_or_else(|| format!("PFM scale {scale_text:?} is not a non-zero number"))?;
    Ok(Header {
        channels,
        width,
        height,
        scale,
        at,
    })
}

/// Decodes PFM bytes; the error says what is wrong.
pub fn decode(bytes: &[u8]) -> std::result::Result<Pfm, String> {
    decode_limited(bytes, u64::MAX)
}

/// As [`decode`], refusing images whose planes would take more than
/// `max_bytes`.
pub fn decode_limited(bytes: &[u8], max_bytes: u64) -> std::result::Result<Pfm, String> {
    let Header {
        channels,
        width,
        height,
        scale,
        at,
    } = header(bytes)?;
    let data = bytes.get(at + 1..).unwrap_or(&[]);
    let needed = width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(channels * 4))
        .ok_or_else(|| format!("PFM size {width}x{height} is too large"))?;
    if data.len() < needed {
        return Err(format!(
            "PFM declares {width}x{height}x{channels} floats ({needed} bytes) but holds {} bytes",
            data.len()
        ));
    }
    if needed as u64 > max_bytes {
        return Err(format!(
            "PFM of {width}x{height} needs {} but the memory limit is {}",
            format_bytes(needed as u64),
            format_bytes(max_bytes)
        ));
    }
    let little = scale < 0.0;
    let read = |raw: &[u8]| {
        let raw = [raw[0], raw[1], raw[2], raw[3]];
        if little {
            f32::from_le_bytes(raw)
        } else {
            f32::from_be_bytes(raw)
        }
    };
    // Row by row in parallel, each plane's row gathered from its source
    // row (rows run from the bottom of the image in the file).
    let row_bytes = width * channels * 4;
    let planes = (0..channels)
        .map(|c| {
            let mut plane =
                aureole::image::zeros::<f32>(width * height).map_err(|e| e.to_string())?;
            plane
                .par_chunks_mut(width)
                .enumerate()
                .for_each(|(y, row)| {
                    let from = (height - 1 - y) * row_bytes;
                    let source = &data[from..from + row_bytes];
                    for (value, raw) in row.iter_mut().zip(source.chunks_exact(4 * channels)) {
                        *value = read(&raw[4 * c..4 * c + 4]);
                    }
                });
            Ok(plane)
        })
        .collect::<std::result::Result<Vec<_>, String>>()?;
    Ok(Pfm {
        width,
        height,
        planes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_one_and_three_channels() {
        let dir = tempfile::tempdir().unwrap();
        for count in [1, 3] {
            let planes: Vec<Vec<f32>> = (0..count)
                .map(|c| (0..12).map(|i| i as f32 * 0.5 - c as f32).collect())
                .collect();
            let path = dir.path().join(format!("k{count}.pfm"));
            let borrowed = LinearPlanes {
                width: 4,
                height: 3,
                colour: planes.iter().map(Vec::as_slice).collect(),
                alpha: None,
                white_luminance: None,
                primaries: None,
                samples: None,
                compression: None,
                original: Default::default(),
                kernel: Default::default(),
            };
            encode(&path, borrowed).unwrap();
            let back = decode(&std::fs::read(&path).unwrap()).unwrap();
            assert_eq!((back.width, back.height), (4, 3));
            assert_eq!(back.planes, planes);
        }
    }

    #[test]
    fn rows_are_stored_bottom_to_top() {
        // The first stored float is the bottom-left pixel.
        let bytes = [
            b"Pf\n1 2\n-1.0\n".as_slice(),
            &1f32.to_le_bytes(),
            &2f32.to_le_bytes(),
        ]
        .concat();
        let pfm = decode(&bytes).unwrap();
        assert_eq!(pfm.planes[0], vec![2.0, 1.0]);
        let big = [b"Pf\n1 1\n1.0\n".as_slice(), &3f32.to_be_bytes()].concat();
        assert_eq!(decode(&big).unwrap().planes[0], vec![3.0]);
    }

    #[test]
    fn refuses_bad_headers_and_short_data() {
        for (bytes, expected) in [
            (b"P6\n1 1\n255\n".to_vec(), "magic"),
            (b"Pf\n0 1\n-1.0\n".to_vec(), "width"),
            (b"Pf\n2 2\n-1.0\n\0\0\0\0".to_vec(), "holds 4 bytes"),
            (b"Pf\n2".to_vec(), "before its height"),
            (b"Pf\n1 1\nzero\n".to_vec(), "scale"),
        ] {
            let e = decode(&bytes).unwrap_err();
            assert!(e.contains(expected), "{e}");
        }
    }
}
