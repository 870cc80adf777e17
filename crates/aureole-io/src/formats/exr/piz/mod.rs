//! OpenEXR's PIZ chunks (`ImfPizCompressor`): the values a block uses
//! mapped onto 0..n by a bitmap, each channel through a 2-D wavelet, then
//! Huffman coding; lossless. Decoding only.

mod huffman;
mod wavelet;

use super::layout::BlockLayout;

/// Bytes of the bitmap of the 2¹⁶ values.
const BITMAP_SIZE: usize = 1 << 13;

/// The values whose bits the bitmap sets (0 always), in order, and the
/// last index (`reverseLutFromBitmap`).
fn values_of(bitmap: &[u8]) -> (Vec<u16>, u16) {
    let mut values = vec![0u16; 1 << 16];
    let mut k = 0;
    for v in 0..=u16::MAX {
        let i = usize::from(v);
        if v == 0 || bitmap[i >> 3] & (1 << (i & 7)) != 0 {
            values[k] = v;
            k += 1;
        }
    }
    (values, (k - 1) as u16)
}

fn short() -> String {
    "a PIZ chunk ends before its data does".to_string()
}

/// A compressed PIZ chunk back to its samples (little-endian, line by
/// line).
pub(crate) fn decompress(data: &[u8], layout: &BlockLayout) -> Result<Vec<u8>, String> {
    // Each channel's values: nx × ny samples of one or two 16-bit halves.
    let sizes: Vec<usize> = layout
        .channels
        .iter()
        .map(|c| c.nx * c.ny * c.bytes() / 2)
        .collect();
    let total: usize = sizes.iter().sum();
    if data.is_empty() {
        return if total == 0 {
            Ok(Vec::new())
        } else {
            Err(short())
        };
    }
    let u16_at = |at: usize| -> Result<usize, String> {
        let b = data.get(at..at + 2).ok_or_else(short)?;
        Ok(usize::from(u16::from_le_bytes([b[0], b[1]])))
    };
    let (first, last) = (u16_at(0)?, u16_at(2)?);
    if first >= BITMAP_SIZE || last >= BITMAP_SIZE {
        return Err("a PIZ chunk's bitmap is damaged".to_string());
    }
    let mut bitmap = vec![0u8; BITMAP_SIZE];
    let mut at = 4;
    if first <= last {
        let stored = data.get(at..at + last - first + 1).ok_or_else(short)?;
        bitmap[first..=last].copy_from_slice(stored);
        at += stored.len();
    }
    let (values, max) = values_of(&bitmap);
    let length = data
        .get(at..at + 4)
        .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .ok_or_else(short)?;
    at += 4;
    let coded = usize::try_from(length)
        .ok()
        .and_then(|n| data.get(at..at + n))
        .ok_or_else(short)?;
    let mut decoded = huffman::decompress(coded, total)?;
    let mut start = 0;
    for (channel, &size) in layout.channels.iter().zip(&sizes) {
        let halves = channel.bytes() / 2;
        let plane = &mut decoded[start..start + size];
        for offset in 0..halves {
            wavelet::decode(
                &mut plane[offset..],
                channel.nx,
                halves,
                channel.ny,
                channel.nx * halves,
                max,
            );
        }
        start += size;
    }
    let mut out = vec![0u8; total * 2];
    let mut bytes = out.chunks_exact_mut(2);
    let mut starts: Vec<usize> = sizes
        .iter()
        .scan(0, |sum, &size| {
            let begin = *sum;
            *sum += size;
            Some(begin)
        })
        .collect();
    for y in layout.lines() {
        for (c, channel) in layout.channels.iter().enumerate() {
            if !channel.on_line(y) {
                continue;
            }
            let n = channel.nx * channel.bytes() / 2;
            for (v, o) in decoded[starts[c]..starts[c] + n].iter().zip(&mut bytes) {
                o.copy_from_slice(&values[usize::from(*v)].to_le_bytes());
            }
            starts[c] += n;
        }
    }
    Ok(out)
}
