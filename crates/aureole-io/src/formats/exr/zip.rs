//! OpenEXR's ZIP and ZIPS chunks: the samples' bytes split into even and
//! odd halves, each byte replaced by its difference to the one before
//! (+128), then zlib. Compressed by libdeflate: the `exr` crate compresses
//! with miniz_oxide at level 4, more than twice the CPU time for the same
//! size (measured in README.md's codec table).

use libdeflater::{CompressionLvl, Compressor};

/// libdeflate's level for every ZIP chunk we write. Measured on a 4K half
/// RGB frame of the night street (bench/codec.py): level 1 compresses
/// in 0.29 CPU-s to 15.18 MB, level 2 in 0.35 to 15.00, level 4 (what
/// OpenEXR 3.x writes) in 0.41 to 14.81, level 6 in 0.57 to 14.49. Level 1
/// keeps files within 2.5 % of OpenEXR's at 70 % of level 4's time; float
/// kernels barely compress at any level (91 %).
pub(crate) const LEVEL: i32 = 1;

/// A compressor at [`LEVEL`], one per thread.
pub(crate) fn compressor() -> Compressor {
    // LEVEL is in libdeflate's range (0–12), so `new` cannot fail; the
    // default level is a fallback that never runs.
    Compressor::new(CompressionLvl::new(LEVEL).unwrap_or_default())
}

/// The bytes of a chunk's samples (little-endian, as the file stores them
/// uncompressed) as a ZIP chunk's data; the samples themselves where
/// compressing would not make them smaller, as OpenEXR does.
pub(crate) fn compress(raw: Vec<u8>, compressor: &mut Compressor) -> Vec<u8> {
    let predicted = predict(&raw);
    let mut compressed = vec![0; compressor.zlib_compress_bound(predicted.len())];
    match compressor.zlib_compress(&predicted, &mut compressed) {
        Ok(n) if n < raw.len() => {
            compressed.truncate(n);
            compressed
        }
        _ => raw,
    }
}

/// The even bytes, then the odd ones, each as its difference to the one
/// before plus 128 (OpenEXR's `ImfZip`).
fn predict(raw: &[u8]) -> Vec<u8> {
    let mut split: Vec<u8> = Vec::with_capacity(raw.len());
    split.extend(raw.iter().step_by(2));
    split.extend(raw.iter().skip(1).step_by(2));
    let mut out = Vec::with_capacity(raw.len());
    out.extend(split.first());
    out.extend(
        split
            .windows(2)
            .map(|pair| pair[1].wrapping_sub(pair[0]).wrapping_add(128)),
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_inflate_back_to_the_predicted_bytes() {
        let mut compressor = compressor();
        let mut decompressor = libdeflater::Decompressor::new();
        for length in [1usize, 2, 3, 17, 4096, 4097] {
            let raw: Vec<u8> = (0..length).map(|i| (i * 7 % 13) as u8).collect();
            let data = compress(raw.clone(), &mut compressor);
            assert!(data.len() < length || data == raw, "{length}");
            if data.len() < length {
                let mut inflated = vec![0; length];
                decompressor.zlib_decompress(&data, &mut inflated).unwrap();
                assert_eq!(inflated, predict(&raw), "{length}");
            }
        }
    }

    #[test]
    fn the_predictor_is_openexrs() {
        // Bytes 1 2 3 4 5: even 1 3 5, odd 2 4; differences from 1.
        assert_eq!(predict(&[1, 2, 3, 4, 5]), vec![1, 130, 130, 125, 130]);
    }

    #[test]
    fn incompressible_chunks_are_stored_as_they_are() {
        let mut state = 1u32;
        let raw: Vec<u8> = (0..64)
            .map(|_| {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (state >> 24) as u8
            })
            .collect();
        assert_eq!(compress(raw.clone(), &mut compressor()), raw);
    }
}
