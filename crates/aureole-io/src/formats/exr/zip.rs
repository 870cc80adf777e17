//! OpenEXR's ZIP and ZIPS chunks: the [`predictor`](super::predictor)'s
//! bytes through zlib, by libdeflate both ways (the `exr` crate compresses
//! with miniz_oxide at level 4: more than twice the CPU time for the same
//! size, docs/performance.md's codec table).

use libdeflater::{CompressionLvl, Compressor, DecompressionError, Decompressor};

use super::predictor::{predict, unpredict};

/// libdeflate's level for every ZIP chunk we write. Measured on a 4K half
/// RGB frame of the night street after the camera, one thread: level 1
/// compresses in 0.29 CPU-s to 15.18 MB, level 2 in 0.35 to 15.00, level 4
/// (what OpenEXR 3.x writes) in 0.41 to 14.81, level 6 in 0.57 to 14.49.
/// Level 1 keeps files within 2.5 % of OpenEXR's in 70 % of level 4's
/// time; float kernels barely compress at any level (91 %).
pub(crate) const LEVEL: i32 = 1;

/// A compressor at [`LEVEL`], one per thread.
pub(crate) fn compressor() -> Compressor {
    // LEVEL is in libdeflate's range (0–12), so `new` cannot fail; the
    // default level is a fallback that never runs.
    Compressor::new(CompressionLvl::new(LEVEL).unwrap_or_default())
}

/// The bytes of a chunk's samples (little-endian, as the file stores them
/// uncompressed) as a ZIP chunk's data; the samples themselves where
/// compressing would not make them smaller, as OpenEXR does. `scratch`
/// is the thread's buffer, kept between chunks.
pub(crate) fn compress(
    raw: Vec<u8>,
    compressor: &mut Compressor,
    scratch: &mut Vec<u8>,
) -> Vec<u8> {
    let predicted = predict(&raw);
    let bound = compressor.zlib_compress_bound(predicted.len());
    if scratch.len() < bound {
        scratch.resize(bound, 0);
    }
    match compressor.zlib_compress(&predicted, scratch) {
        Ok(n) if n < raw.len() => scratch[..n].to_vec(),
        _ => raw,
    }
}

/// A compressed ZIP chunk back to its `expected` bytes of samples.
pub(crate) fn decompress(
    data: &[u8],
    expected: usize,
    decompressor: &mut Decompressor,
) -> Result<Vec<u8>, String> {
    let mut predicted = vec![0; expected];
    let n = decompressor
        .zlib_decompress(data, &mut predicted)
        .map_err(|e| match e {
            DecompressionError::BadData => "a ZIP chunk's data is damaged".to_string(),
            DecompressionError::InsufficientSpace => {
                format!("a ZIP chunk holds more than the {expected} bytes of its lines")
            }
        })?;
    if n != expected {
        return Err(format!(
            "a ZIP chunk holds {n} bytes where its lines need {expected}"
        ));
    }
    Ok(unpredict(&mut predicted))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_come_back_as_they_were() {
        let mut compressor = compressor();
        let mut decompressor = Decompressor::new();
        for length in [1usize, 2, 3, 17, 4096, 4097] {
            let raw: Vec<u8> = (0..length).map(|i| (i * 7 % 13) as u8).collect();
            let data = compress(raw.clone(), &mut compressor, &mut Vec::new());
            assert!(data.len() < length || data == raw, "{length}");
            if data.len() < length {
                assert_eq!(decompress(&data, length, &mut decompressor).unwrap(), raw);
                assert!(decompress(&data, length + 1, &mut decompressor).is_err());
            }
        }
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
        assert_eq!(
            compress(raw.clone(), &mut compressor(), &mut Vec::new()),
            raw
        );
    }
}
