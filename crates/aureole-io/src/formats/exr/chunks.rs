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

use super::zip;

/// Chunks compressed together before they are written, per thread: a
/// bound on the compressed chunks held at once (a few MB at 4K).
const CHUNKS_PER_THREAD: usize = 16;

/// Writes `image` to `out`: headers, offset tables and every chunk.
pub(crate) fn write(image: &FlatImage, out: impl Write + Seek) -> exr::error::UnitResult {
    let headers = image.write().infer_meta_data();
    let layers = image.layer_data.create_writer(&headers);
    exr::block::write(out, headers, true, |meta, writer| {
        let order: Vec<(usize, BlockIndex)> =
            exr::block::enumerate_ordered_header_block_indices(&meta.headers).collect();
        let batch = CHUNKS_PER_THREAD * rayon::current_num_threads();
        for blocks in order.chunks(batch) {
            let chunks = blocks
                .par_iter()
                .map_init(zip::compressor, |compressor, &(index, block)| {
                    let data = layers.extract_uncompressed_block(&meta.headers, block);
                    let chunk = compress(
                        UncompressedBlock { index: block, data },
                        &meta.headers,
                        compressor,
                    )?;
                    Ok((index, chunk))
                })
                .collect::<exr::error::Result<Vec<(usize, Chunk)>>>()?;
            for (index, chunk) in chunks {
                writer.write_chunk(index, chunk)?;
            }
        }
        Ok(())
    })
}

/// One block as a chunk: ZIP and ZIPS through libdeflate, the rest as
/// `exr` compresses them. Samples are stored little-endian: on a
/// big-endian machine `exr` converts them and compresses them too.
fn compress(
    block: UncompressedBlock,
    headers: &[Header],
    compressor: &mut libdeflater::Compressor,
) -> exr::error::Result<Chunk> {
    let Some(header) = headers.get(block.index.layer) else {
        return block.compress_to_chunk(headers);
    };
    let zipped = matches!(header.compression, X::ZIP1 | X::ZIP16);
    if !zipped || cfg!(target_endian = "big") || header.deep {
        return block.compress_to_chunk(headers);
    }
    let index = block.index;
    let compressed_pixels_le = zip::compress(block.data, compressor);
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
    Ok(Chunk {
        layer_index: index.layer,
        compressed_block,
    })
}
