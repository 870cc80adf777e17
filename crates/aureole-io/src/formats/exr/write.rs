//! Writing a whole file's chunks: compressed in parallel on the run's own
//! thread pool (the `exr` crate's writer builds a pool of its own for
//! every file), ZIP and ZIPS by libdeflate ([`super::zip`]), every other
//! compression by `exr`, and handed in order to `exr`'s chunk writer,
//! which writes the headers and the offset tables.

use std::cell::RefCell;
use std::io::{Seek, SeekFrom, Write};

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

thread_local! {
    /// Each thread's compressor and buffers: chunks are compressed on the
    /// threads of rayon's pool, which live as long as the process, so a
    /// frame sequence compresses every frame in the same memory.
    static ZIPPER: RefCell<zip::Zipper> = RefCell::new(zip::Zipper::new());
}

/// Samples that a lossy compression could not hold, lowered ([`dwa`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Lowered {
    pub count: usize,
    /// The largest magnitude any of them was written with.
    pub ceiling: f32,
}

/// Writes `image` to `out`: headers, offset tables and every chunk.
/// Returns the samples lowered so that DWA does not make them infinite.
pub(crate) fn write(image: &FlatImage, mut out: impl Write + Seek) -> exr::error::Result<Lowered> {
    let headers = image.write().infer_meta_data();
    // `exr` keeps an image's own attributes in a HashMap, which it writes
    // in an order that changes from run to run; the headers are written
    // again afterwards with each one's attributes sorted by name, as
    // OpenEXR writes them, so that a file's bytes depend on its content
    // alone. Their length is the same, so the offsets that follow hold.
    let mut written = Vec::new();
    Header::write_all(&headers, &mut written, headers.len() > 1)?;
    let sorted = sorted_attributes(&written, headers.len());
    let layers = image.layer_data.create_writer(&headers);
    let mut lowered = Lowered {
        count: 0,
        ceiling: crate::formats::HALF_MAX,
    };
    exr::block::write(&mut out, headers, true, |meta, writer| {
        let order: Vec<(usize, BlockIndex)> =
            exr::block::enumerate_ordered_header_block_indices(&meta.headers).collect();
        let batch = CHUNKS_PER_THREAD * rayon::current_num_threads();
        for blocks in order.chunks(batch) {
            let chunks = blocks
                .par_iter()
                .map(|&(index, block)| {
                    let data = layers.extract_uncompressed_block(&meta.headers, block);
                    let (chunk, lowered) =
                        compress(UncompressedBlock { index: block, data }, &meta.headers)?;
                    Ok((index, chunk, lowered))
                })
                .collect::<exr::error::Result<Vec<(usize, Chunk, Lowered)>>>()?;
            for (index, chunk, block) in chunks {
                lowered.count += block.count;
                lowered.ceiling = lowered.ceiling.min(block.ceiling);
                writer.write_chunk(index, chunk)?;
            }
        }
        Ok(())
    })?;
    if let Some(sorted) = sorted {
        out.seek(SeekFrom::Start(HEADERS_AT))?;
        out.write_all(&sorted)?;
        out.flush()?;
    }
    Ok(lowered)
}

/// Where the headers start: after the magic number and the version field.
const HEADERS_AT: u64 = 8;

/// `count` headers as `Header::write_all` wrote them, each one's
/// attributes (name, type name, size, value) sorted by name; `None` if the
/// bytes are not such headers.
fn sorted_attributes(headers: &[u8], count: usize) -> Option<Vec<u8>> {
    let until_nul = |from: usize| -> Option<usize> {
        Some(from + headers.get(from..)?.iter().position(|&b| b == 0)?)
    };
    let mut sorted = Vec::with_capacity(headers.len());
    let mut at = 0;
    for _ in 0..count {
        let mut attributes: Vec<(&[u8], &[u8])> = Vec::new();
        while *headers.get(at)? != 0 {
            let name_end = until_nul(at)?;
            let size_at = until_nul(name_end + 1)? + 1;
            let size = i32::from_le_bytes(headers.get(size_at..size_at + 4)?.try_into().ok()?);
            let end = size_at + 4 + usize::try_from(size).ok()?;
            attributes.push((headers.get(at..name_end)?, headers.get(at..end)?));
            at = end;
        }
        at += 1;
        attributes.sort_by(|a, b| a.0.cmp(b.0));
        for (_, attribute) in attributes {
            sorted.extend_from_slice(attribute);
        }
        sorted.push(0);
    }
    sorted.extend_from_slice(headers.get(at..)?);
    (sorted.len() == headers.len()).then_some(sorted)
}

/// One block as a chunk: ZIP and ZIPS through libdeflate, DWA within the
/// half range ([`dwa`]), the rest as `exr` compresses them. Samples are
/// stored little-endian: on a big-endian machine `exr` converts them and
/// compresses them too.
fn compress(block: UncompressedBlock, headers: &[Header]) -> exr::error::Result<(Chunk, Lowered)> {
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
    let compressed_pixels_le = ZIPPER.with_borrow_mut(|zipper| zipper.compress(block.data));
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

#[cfg(test)]
mod tests {
    use exr::image::{AnyChannel, AnyChannels, Encoding, Image, Layer};
    use exr::meta::attribute::{AttributeValue, Text};
    use exr::meta::header::{ImageAttributes, LayerAttributes};
    use exr::prelude::FlatSamples;

    use super::*;

    /// A small image with a renderer's worth of custom attributes, built
    /// anew, so that its attribute maps hash afresh.
    fn image() -> FlatImage {
        let channel = AnyChannel::new("R", FlatSamples::F32(vec![0.5; 4]));
        let mut layer = Layer::new(
            (2, 2),
            LayerAttributes::named("ViewLayer"),
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(vec![channel].into()),
        );
        for (i, name) in ["Scene", "Frame", "Camera", "Date", "cycles.samples", "Time"]
            .into_iter()
            .enumerate()
        {
            layer
                .attributes
                .other
                .insert(Text::from(name), AttributeValue::I32(i as i32));
        }
        let mut image = Image::from_layers(
            ImageAttributes::new(exr::prelude::IntegerBounds::from_dimensions(layer.size)),
            vec![layer],
        );
        for name in ["zeta", "alpha", "mu", "beta"] {
            image
                .attributes
                .other
                .insert(Text::from(name), AttributeValue::F32(1.0));
        }
        image
    }

    fn bytes(image: &FlatImage) -> Vec<u8> {
        let mut out = std::io::Cursor::new(Vec::new());
        write(image, &mut out).unwrap();
        out.into_inner()
    }

    #[test]
    fn attributes_are_written_sorted_whatever_the_map_order() {
        let first = bytes(&image());
        for _ in 0..8 {
            assert_eq!(bytes(&image()), first);
        }
        let at = |name: &str| {
            first
                .windows(name.len() + 1)
                .position(|w| w[..name.len()] == *name.as_bytes() && w[name.len()] == 0)
                .unwrap()
        };
        let names = [
            "Camera", "Date", "Frame", "Scene", "Time", "alpha", "beta", "channels",
        ];
        assert!(names.windows(2).all(|pair| at(pair[0]) < at(pair[1])));
        // The file still reads, every attribute in it.
        let read = exr::prelude::read_all_flat_layers_from_file;
        let path = std::env::temp_dir().join(format!("aureole-sorted-{}.exr", std::process::id()));
        std::fs::write(&path, &first).unwrap();
        let image = read(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        let kept = image.attributes.other.len() + image.layer_data[0].attributes.other.len();
        assert_eq!(kept, 10);
    }
}
