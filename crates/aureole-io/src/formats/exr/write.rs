//! Writing a whole file's chunks: compressed in parallel on the run's own
//! thread pool (the `exr` crate's writer builds a pool of its own for
//! every file), ZIP and ZIPS by libdeflate ([`super::zip`]), every other
//! compression by `exr`, and handed in order to `exr`'s chunk writer,
//! which writes the headers and the offset tables.

use std::io::{Seek, Write};

use exr::block::chunk::TileCoordinates;
use exr::block::chunk::{Chunk, CompressedBlock, CompressedScanLineBlock, CompressedTileBlock};
use exr::block::writer::ChunksWriter;
use exr::block::{BlockIndex, UncompressedBlock};
use exr::compression::Compression as X;
use exr::image::write::layers::{LayersWriter, WritableLayers};
use exr::image::write::WritableImage;
use exr::image::FlatImage;
use exr::meta::header::Header;
use exr::meta::BlockDescription;
use rayon::prelude::*;

use super::{dwa, zip};

/// Chunks compressed together before they are written, per thread: a
/// bound on the compressed chunks held at once (a few MB at 4K).
const CHUNKS_PER_THREAD: usize = 16;

/// Samples that a lossy compression could not hold, lowered ([`dwa`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Lowered {
    pub count: usize,
    /// The largest magnitude any of them was written with.
    pub ceiling: f32,
}

/// Writes `image` to `out`: headers, offset tables and every chunk.
/// Returns the samples lowered so that DWA does not make them infinite.
pub(crate) fn write(image: &FlatImage, out: impl Write + Seek) -> exr::error::Result<Lowered> {
    let headers = image.write().infer_meta_data();
    let layers = image.layer_data.create_writer(&headers);
    let mut lowered = Lowered {
        count: 0,
        ceiling: crate::formats::HALF_MAX,
    };
    exr::block::write(out, headers, true, |meta, writer| {
        let order: Vec<(usize, BlockIndex)> =
            exr::block::enumerate_ordered_header_block_indices(&meta.headers).collect();
        let batch = CHUNKS_PER_THREAD * rayon::current_num_threads();
        for blocks in order.chunks(batch) {
            let chunks = blocks
                .par_iter()
                .map_init(
                    || (zip::compressor(), Vec::new()),
                    |(compressor, scratch), &(index, block)| {
                        let data = layers.extract_uncompressed_block(&meta.headers, block);
                        let (chunk, lowered) = compress(
                            UncompressedBlock { index: block, data },
                            &meta.headers,
                            compressor,
                            scratch,
                        )?;
                        Ok((index, chunk, lowered))
                    },
                )
                .collect::<exr::error::Result<Vec<(usize, Chunk, Lowered)>>>()?;
            for (index, chunk, block) in chunks {
                lowered.count += block.count;
                lowered.ceiling = lowered.ceiling.min(block.ceiling);
                writer.write_chunk(index, chunk)?;
            }
        }
        Ok(())
    })?;
    Ok(lowered)
}

/// One block as a chunk: ZIP and ZIPS through libdeflate, DWA within the
/// half range ([`dwa`]), the rest as `exr` compresses them. Samples are
/// stored little-endian: on a big-endian machine `exr` converts them and
/// compresses them too.
fn compress(
    block: UncompressedBlock,
    headers: &[Header],
    compressor: &mut libdeflater::Compressor,
    scratch: &mut Vec<u8>,
) -> exr::error::Result<(Chunk, Lowered)> {
    let none = Lowered {
        count: 0,
        ceiling: crate::formats::HALF_MAX,
    };
    let Some(header) = headers.get(block.index.layer) else {
        return Ok((block.compress_to_chunk(headers)?, none));
    };
    if dwa::is_dwa(header.compression) {
        let (chunk, count, ceiling) = dwa::compress(block, headers)?;
        return Ok((chunk, Lowered { count, ceiling }));
    }
    let zipped = matches!(header.compression, X::ZIP1 | X::ZIP16);
    if !zipped || cfg!(target_endian = "big") || header.deep {
        return Ok((block.compress_to_chunk(headers)?, none));
    }
    let index = block.index;
    let compressed_pixels_le = zip::compress(block.data, compressor, scratch);
    let compressed_block = match header.blocks {
        BlockDescription::ScanLines => CompressedBlock::ScanLine(CompressedScanLineBlock {
            compressed_pixels_le,
            y_coordinate: i32::try_from(index.pixel_position.y())
                .map_err(|_| exr::error::Error::Invalid("pixel index".into()))?
                + header.own_attributes.layer_position.y(),
        }),
        BlockDescription::Tiles(_) => CompressedBlock::Tile(CompressedTileBlock {
            compressed_pixels_le,
            coordinates: TileCoordinates {
                tile_index: index.pixel_position / header.max_block_pixel_size(),
                level_index: index.level,
            },
        }),
    };
    let chunk = Chunk {
        layer_index: index.layer,
        compressed_block,
    };
    Ok((chunk, none))
}
