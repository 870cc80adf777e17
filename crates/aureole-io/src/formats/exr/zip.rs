//! OpenEXR's ZIP and ZIPS chunks: the [`predictor`](super::predictor)'s
//! bytes through zlib, by libdeflate both ways (the `exr` crate compresses
//! with miniz_oxide at level 4: more than twice the CPU time for the same
//! size, docs/performance.md's codec table).

use libdeflater::{CompressionLvl, Compressor, DecompressionError, Decompressor};

use super::predictor::{predict_into, unpredict};

/// libdeflate's level for every ZIP chunk we write. Measured on a 4K half
/// RGB frame of the night street after the camera, one thread: level 1
/// compresses in 0.29 CPU-s to 15.18 MB, level 2 in 0.35 to 15.00, level 4
/// (what OpenEXR 3.x writes) in 0.41 to 14.81, level 6 in 0.57 to 14.49.
/// Level 1 keeps files within 2.5 % of OpenEXR's in 70 % of level 4's
/// time; float kernels barely compress at any level (91 %).
pub(crate) const LEVEL: i32 = 1;

/// A compressor at [`LEVEL`] and its buffers, one per thread, kept from
/// chunk to chunk and from frame to frame.
pub(crate) struct Zipper {
    compressor: Compressor,
    split: Vec<u8>,
    predicted: Vec<u8>,
    compressed: Vec<u8>,
}

impl Zipper {
    pub(crate) fn new() -> Zipper {
        Zipper {
            // LEVEL is in libdeflate's range (0–12), so `new` cannot fail;
            // the default level is a fallback that never runs.
            compressor: Compressor::new(CompressionLvl::new(LEVEL).unwrap_or_default()),
            split: Vec::new(),
            predicted: Vec::new(),
            compressed: Vec::new(),
        }
    }

    /// The bytes of a chunk's samples (little-endian, as the file stores
    /// them uncompressed) as a ZIP chunk's data; the samples themselves
    /// where compressing would not make them smaller, as OpenEXR does.
    pub(crate) fn compress(&mut self, raw: Vec<u8>) -> Vec<u8> {
        predict_into(&raw, &mut self.split, &mut self.predicted);
        let bound = self.compressor.zlib_compress_bound(self.predicted.len());
        if self.compressed.len() < bound {
            self.compressed.resize(bound, 0);
        }
        match self
            .compressor
            .zlib_compress(&self.predicted, &mut self.compressed)
        {
            Ok(n) if n < raw.len() => self.compressed[..n].to_vec(),
            _ => raw,
        }
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
        // One zipper for chunks of every length, as a thread keeps it.
        let mut zipper = Zipper::new();
        let mut decompressor = Decompressor::new();
        for length in [4097usize, 1, 2, 3, 17, 4096, 4097] {
            let raw: Vec<u8> = (0..length).map(|i| (i * 7 % 13) as u8).collect();
            let data = zipper.compress(raw.clone());
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
        assert_eq!(Zipper::new().compress(raw.clone()), raw);
    }
}
