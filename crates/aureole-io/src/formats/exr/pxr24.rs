//! OpenEXR's PXR24 chunks (`ImfPxr24Compressor`): each channel's line as
//! differences to the sample before, split into byte planes (high byte
//! first), through zlib. Float samples keep their top 24 bits (lossy);
//! half and uint samples are exact.

use exr::meta::attribute::SampleType;
use libdeflater::Decompressor;

use super::layout::BlockLayout;

/// Bytes a sample takes in the byte planes.
fn plane_bytes(kind: SampleType) -> usize {
    match kind {
        SampleType::F16 => 2,
        SampleType::F32 => 3,
        SampleType::U32 => 4,
    }
}

/// A compressed PXR24 chunk back to its samples (little-endian, line by
/// line).
pub(crate) fn decompress(
    data: &[u8],
    layout: &BlockLayout,
    decompressor: &mut Decompressor,
) -> Result<Vec<u8>, String> {
    let planes: usize = layout
        .channels
        .iter()
        .map(|c| c.nx * c.ny * plane_bytes(c.kind))
        .sum();
    let mut bytes = vec![0; planes];
    let n = decompressor
        .zlib_decompress(data, &mut bytes)
        .map_err(|_| "a PXR24 chunk's data is damaged or too long for its lines".to_string())?;
    if n != planes {
        return Err(format!(
            "a PXR24 chunk holds {n} bytes where its lines need {planes}"
        ));
    }
    let mut out = Vec::with_capacity(layout.byte_size());
    let mut at = 0;
    for y in layout.lines() {
        for channel in layout.channels.iter().filter(|c| c.on_line(y)) {
            let n = channel.nx;
            let width = plane_bytes(channel.kind);
            let line = &bytes[at..at + n * width];
            at += n * width;
            let byte = |plane: usize, j: usize| u32::from(line[plane * n + j]);
            let mut pixel = 0u32;
            for j in 0..n {
                match channel.kind {
                    SampleType::F16 => {
                        pixel = pixel.wrapping_add(byte(0, j) << 8 | byte(1, j));
                        out.extend_from_slice(&(pixel as u16).to_le_bytes());
                    }
                    SampleType::F32 => {
                        pixel = pixel
                            .wrapping_add(byte(0, j) << 24 | byte(1, j) << 16 | byte(2, j) << 8);
                        out.extend_from_slice(&pixel.to_le_bytes());
                    }
                    SampleType::U32 => {
                        pixel = pixel.wrapping_add(
                            byte(0, j) << 24 | byte(1, j) << 16 | byte(2, j) << 8 | byte(3, j),
                        );
                        out.extend_from_slice(&pixel.to_le_bytes());
                    }
                }
            }
        }
    }
    Ok(out)
}
