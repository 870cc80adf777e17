//! DWAA and DWAB keep R, G, B, Y, RY and BY (OpenEXR's default rules, by
//! channel-name suffix) as half floats through a lossy DCT: float samples
//! beyond ±65504 come back infinite, and so do samples just below it that
//! the DCT's error carries over. A block that holds samples near the top
//! of the half range has them clamped to it, is compressed, decoded again,
//! and has its largest samples lowered until none comes back infinite; the
//! count goes into a note.

use exr::block::chunk::{Chunk, CompressedBlock};
use exr::block::UncompressedBlock;
use exr::compression::Compression as X;
use exr::meta::attribute::{IntegerBounds, SampleType};
use exr::meta::header::Header;
use exr::prelude::f16;

use super::layout::BlockLayout;
use crate::formats::HALF_MAX;

/// The channel-name suffixes the lossy DCT takes.
const LOSSY: [&str; 6] = ["R", "G", "B", "Y", "RY", "BY"];

/// Samples above this are checked after compressing: the DCT's error,
/// about 1 % (measured on lamps at 2·10⁴–6.5·10⁴ over dark skies), never
/// reaches the top of the half range from here.
const CHECKED_ABOVE: f32 = 32768.0;

/// Each retry lowers the block's largest samples by this factor.
const STEP: f32 = 0.97;

/// Whether `compression` stores some channels as lossy halves.
pub(crate) fn is_dwa(compression: X) -> bool {
    matches!(compression, X::DWAA(_) | X::DWAB(_))
}

fn is_lossy(name: &str) -> bool {
    LOSSY.contains(&name.rsplit('.').next().unwrap_or_default())
}

/// Where a block's samples of lossy channels lie in its bytes: (offset,
/// sample type) of each.
fn lossy_samples(layout: &BlockLayout, header: &Header) -> Vec<(usize, SampleType)> {
    let lossy: Vec<bool> = header
        .channels
        .list
        .iter()
        .map(|c| is_lossy(&c.name.to_string()))
        .collect();
    let mut samples = Vec::new();
    let mut at = 0;
    for y in layout.lines() {
        for (c, channel) in layout.channels.iter().enumerate() {
            if !channel.on_line(y) {
                continue;
            }
            let size = channel.bytes();
            if lossy[c] && channel.kind != SampleType::U32 {
                samples.extend((0..channel.nx).map(|i| (at + i * size, channel.kind)));
            }
            at += channel.nx * size;
        }
    }
    samples
}

fn sample(bytes: &[u8], (at, kind): (usize, SampleType)) -> f32 {
    match kind {
        SampleType::F16 => f16::from_bits(u16::from_le_bytes([bytes[at], bytes[at + 1]])).to_f32(),
        _ => f32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]),
    }
}

fn set(bytes: &mut [u8], (at, kind): (usize, SampleType), v: f32) {
    match kind {
        SampleType::F16 => bytes[at..at + 2].copy_from_slice(&f16::from_f32(v).to_le_bytes()),
        _ => bytes[at..at + 4].copy_from_slice(&v.to_le_bytes()),
    }
}

/// A DWA block as a chunk whose lossy samples all come back finite; and
/// how many samples were lowered for it, and to what at most.
pub(crate) fn compress(
    block: UncompressedBlock,
    headers: &[Header],
) -> exr::error::Result<(Chunk, usize, f32)> {
    let Some(header) = headers.get(block.index.layer) else {
        return Ok((block.compress_to_chunk(headers)?, 0, HALF_MAX));
    };
    let size = (block.index.pixel_size.0, block.index.pixel_size.1);
    let position = (block.index.pixel_position.0, block.index.pixel_position.1);
    let layout = BlockLayout::new(header, position, size);
    let samples = lossy_samples(&layout, header);
    let near_top = |data: &[u8]| {
        samples
            .iter()
            .any(|&s| sample(data, s).abs() > CHECKED_ABOVE && sample(data, s).is_finite())
    };
    // Samples are little-endian here only on a little-endian machine.
    if cfg!(target_endian = "big")
        || layout.byte_size() != block.data.len()
        || !near_top(&block.data)
    {
        return Ok((block.compress_to_chunk(headers)?, 0, HALF_MAX));
    }
    let index = block.index;
    let mut data = block.data;
    let finite: Vec<bool> = samples
        .iter()
        .map(|&s| sample(&data, s).is_finite())
        .collect();
    let mut changed = vec![false; samples.len()];
    let mut lower = |data: &mut [u8], ceiling: f32| {
        for (i, &s) in samples.iter().enumerate() {
            let v = sample(data, s);
            if finite[i] && v.abs() > ceiling {
                set(data, s, v.clamp(-ceiling, ceiling));
                changed[i] = true;
            }
        }
    };
    let mut ceiling = HALF_MAX;
    lower(&mut data, ceiling);
    let rectangle = IntegerBounds::new(
        exr::math::Vec2(position.0 as i32, position.1 as i32),
        exr::math::Vec2(size.0, size.1),
    );
    loop {
        let chunk = UncompressedBlock {
            index,
            data: data.clone(),
        }
        .compress_to_chunk(headers)?;
        let compressed = match &chunk.compressed_block {
            CompressedBlock::ScanLine(b) => &b.compressed_pixels_le,
            CompressedBlock::Tile(b) => &b.compressed_pixels_le,
            _ => &data,
        };
        let back = if compressed.len() == data.len() {
            compressed.clone()
        } else {
            exr::compression::dwa::decompress(
                &header.channels,
                compressed.clone(),
                rectangle,
                data.len(),
                false,
            )?
        };
        let overflows = samples
            .iter()
            .zip(&finite)
            .any(|(&s, &was)| was && !sample(&back, s).is_finite());
        if !overflows || ceiling < 1.0 {
            let lowered = changed.iter().filter(|&&c| c).count();
            return Ok((chunk, lowered, ceiling));
        }
        ceiling *= STEP;
        lower(&mut data, ceiling);
    }
}
