//! OpenEXR's B44 and B44A chunks (`ImfB44Compressor`): each half channel
//! in blocks of 4×4 samples, 14 bytes each (a first sample and 15 six-bit
//! differences at one shift), or 3 bytes for a block of one value (B44A);
//! `pLinear` channels (chroma) are stored as exp(x/8). Float and uint
//! channels are stored as they are.

use std::sync::OnceLock;

use exr::meta::attribute::SampleType;
use exr::prelude::f16;

use super::layout::BlockLayout;

/// A `pLinear` sample's bits back from the scale B44 stores it on, which
/// is exp(x/8): 8·ln(x) (OpenEXR's `logTable`, which it names
/// `convertToLinear`; 0 for negative, infinite and NaN bits).
fn from_exp(bits: u16) -> u16 {
    static TABLE: OnceLock<Vec<u16>> = OnceLock::new();
    let table = TABLE.get_or_init(|| {
        (0..=u16::MAX)
            .map(|b| {
                let h = f16::from_bits(b);
                if !h.is_finite() || h < f16::ZERO {
                    0
                } else {
                    f16::from_f32((8.0 * f64::from(h).ln()) as f32).to_bits()
                }
            })
            .collect()
    });
    table[usize::from(bits)]
}

/// OpenEXR's ordered bits back to a half's bits.
fn unordered(s: u16) -> u16 {
    if s & 0x8000 != 0 {
        s & 0x7fff
    } else {
        !s
    }
}

/// A 14-byte block: s[0], then each column's differences, at `shift`.
fn unpack14(b: &[u8]) -> [u16; 16] {
    let b: Vec<u16> = b.iter().map(|&v| u16::from(v)).collect();
    let mut s = [0u16; 16];
    s[0] = (b[0] << 8) | b[1];
    let shift = b[2] >> 2;
    let bias = 0x20u16.wrapping_shl(u32::from(shift));
    let d = |v: u16| (v & 0x3f).wrapping_shl(u32::from(shift)).wrapping_sub(bias);
    s[4] = s[0].wrapping_add(d((b[2] << 4) | (b[3] >> 4)));
    s[8] = s[4].wrapping_add(d((b[3] << 2) | (b[4] >> 6)));
    s[12] = s[8].wrapping_add(d(b[4]));
    s[1] = s[0].wrapping_add(d(b[5] >> 2));
    s[5] = s[4].wrapping_add(d((b[5] << 4) | (b[6] >> 4)));
    s[9] = s[8].wrapping_add(d((b[6] << 2) | (b[7] >> 6)));
    s[13] = s[12].wrapping_add(d(b[7]));
    s[2] = s[1].wrapping_add(d(b[8] >> 2));
    s[6] = s[5].wrapping_add(d((b[8] << 4) | (b[9] >> 4)));
    s[10] = s[9].wrapping_add(d((b[9] << 2) | (b[10] >> 6)));
    s[14] = s[13].wrapping_add(d(b[10]));
    s[3] = s[2].wrapping_add(d(b[11] >> 2));
    s[7] = s[6].wrapping_add(d((b[11] << 4) | (b[12] >> 4)));
    s[11] = s[10].wrapping_add(d((b[12] << 2) | (b[13] >> 6)));
    s[15] = s[14].wrapping_add(d(b[13]));
    s.map(unordered)
}

/// A compressed B44 or B44A chunk back to its samples (little-endian, line
/// by line).
pub(crate) fn decompress(data: &[u8], layout: &BlockLayout) -> Result<Vec<u8>, String> {
    let short = || "a B44 chunk ends before its blocks do".to_string();
    let mut rest = data;
    // Each channel's samples, row by row: half ones as values, others as
    // the bytes stored.
    let mut planes: Vec<Vec<u8>> = Vec::with_capacity(layout.channels.len());
    for channel in &layout.channels {
        let (nx, ny) = (channel.nx, channel.ny);
        if channel.kind != SampleType::F16 {
            let n = nx * ny * channel.bytes();
            let (stored, after) = (rest.get(..n).ok_or_else(short)?, &rest[n..]);
            planes.push(stored.to_vec());
            rest = after;
            continue;
        }
        let mut plane = vec![0u16; nx * ny];
        for y in (0..ny).step_by(4) {
            for x in (0..nx).step_by(4) {
                let flat = rest.get(2).ok_or_else(short)? >= &(13 << 2);
                let size = if flat { 3 } else { 14 };
                let block = rest.get(..size).ok_or_else(short)?;
                let mut s = if flat {
                    [unordered((u16::from(block[0]) << 8) | u16::from(block[1])); 16]
                } else {
                    unpack14(block)
                };
                rest = &rest[size..];
                if channel.linear {
                    s = s.map(from_exp);
                }
                for (i, row) in (y..ny.min(y + 4)).enumerate() {
                    for (j, column) in (x..nx.min(x + 4)).enumerate() {
                        plane[row * nx + column] = s[i * 4 + j];
                    }
                }
            }
        }
        planes.push(plane.iter().flat_map(|v| v.to_le_bytes()).collect());
    }
    if !rest.is_empty() {
        return Err("a B44 chunk holds more than its blocks".to_string());
    }
    let mut out = Vec::with_capacity(layout.byte_size());
    let mut rows = vec![0usize; planes.len()];
    for y in layout.lines() {
        for (c, channel) in layout.channels.iter().enumerate() {
            if !channel.on_line(y) {
                continue;
            }
            let n = channel.nx * channel.bytes();
            out.extend_from_slice(&planes[c][rows[c] * n..(rows[c] + 1) * n]);
            rows[c] += 1;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plinear_samples_come_back_from_their_exponential() {
        // 8·ln(1) = 0; 8·ln(e) = 8; 8·ln(0) = −∞; negatives and NaN: 0.
        assert_eq!(from_exp(f16::ONE.to_bits()), 0);
        let e = f16::from_f32(std::f32::consts::E);
        assert!((f16::from_bits(from_exp(e.to_bits())).to_f32() - 8.0).abs() < 0.01);
        assert_eq!(from_exp(0), f16::NEG_INFINITY.to_bits());
        assert_eq!(from_exp(f16::from_f32(-2.0).to_bits()), 0);
        assert_eq!(from_exp(f16::NAN.to_bits()), 0);
    }

    #[test]
    fn a_flat_block_fills_its_samples() {
        // 1.0 is 0x3c00: ordered, positive values have the top bit set.
        let ordered = 0x3c00u16 | 0x8000;
        let layout = BlockLayout {
            channels: vec![super::super::layout::ChannelBlock {
                kind: SampleType::F16,
                sampling: (1, 1),
                nx: 3,
                ny: 2,
                linear: false,
            }],
            y0: 0,
            x0: 0,
            height: 2,
            width: 3,
        };
        let data = [(ordered >> 8) as u8, ordered as u8, 13 << 2];
        let out = decompress(&data, &layout).unwrap();
        assert_eq!(out, [0x00, 0x3c].repeat(6));
        assert!(decompress(&data[..2], &layout).is_err());
    }
}
