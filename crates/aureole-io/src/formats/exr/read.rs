//! Reading a whole file's largest level: its chunks decompressed in
//! parallel on the run's thread pool, by our own codecs (libdeflate for
//! ZIP, PIZ, B44, PXR24, RLE; DWA through `exr`), straight into each
//! channel's samples at the channel's own resolution, a subsampled chroma
//! channel's too, which the `exr` crate does not read. The channels a
//! caller spreads come as f32, converted as they are placed; the others
//! as the file stores them.

use std::borrow::Cow;
use std::io::Cursor;

use exr::block::chunk::TileCoordinates;
use exr::compression::Compression as X;
use exr::io::PeekRead;
use exr::math::Vec2;
use exr::meta::attribute::{SampleType, Text};
use exr::meta::header::Header;
use exr::meta::{BlockDescription, MetaData, Requirements};
use exr::prelude::{f16, FlatSamples};
use half::slice::{HalfBitsSliceExt, HalfFloatSliceExt};
use libdeflater::Decompressor;
use rayon::prelude::*;

use super::layout::{samples_between, BlockLayout};
use super::{b44, piz, pxr24, rle, zip};
use crate::spares::Spares;

/// A file's headers and where its chunks are.
pub(crate) struct File {
    pub headers: Vec<Header>,
    /// Each part's chunk offsets, from the start of the file.
    offsets: Vec<Vec<u64>>,
}

impl File {
    /// The headers and offset tables of `bytes`, checked as `exr` checks
    /// them, but for subsampled channels (which it refuses), checked as
    /// OpenEXR does: only in scanline parts, dividing the data window's
    /// position and size.
    pub fn parse(bytes: &[u8]) -> Result<File, String> {
        let error = |e: exr::error::Error| e.to_string();
        let mut read = PeekRead::new(Cursor::new(bytes));
        exr::meta::magic_number::validate_exr(&mut read).map_err(error)?;
        let requirements = Requirements::read(&mut read).map_err(error)?;
        requirements.validate().map_err(error)?;
        // Strict, as `exr` reads headers for its own validated reads.
        let headers = Header::read_all(&mut read, &requirements, true).map_err(|e| {
            let e = e.to_string();
            if e.contains("window") {
                format!("the header's data window or display window is out of range ({e})")
            } else {
                format!("a header is damaged ({e})")
            }
        })?;
        let offsets = MetaData::read_offset_tables(&mut read, &headers).map_err(error)?;
        for (i, header) in headers.iter().enumerate() {
            let window = header.data_window();
            for channel in header
                .channels
                .list
                .iter()
                .filter(|c| c.sampling != Vec2(1, 1))
            {
                let (sx, sy) = (channel.sampling.0, channel.sampling.1);
                if header.blocks != BlockDescription::ScanLines || header.deep {
                    return Err(format!(
                        "part {i}: channel {} is subsampled ({sx}x{sy}) in a tiled or deep part, which OpenEXR allows only in scanline parts",
                        channel.name
                    ));
                }
                let divides = |n: i64, s: usize| s > 0 && n.rem_euclid(s as i64) == 0;
                if !(divides(window.position.0.into(), sx)
                    && divides(window.position.1.into(), sy)
                    && divides(window.size.0 as i64, sx)
                    && divides(window.size.1 as i64, sy))
                {
                    return Err(format!(
                        "part {i}: channel {}'s sampling {sx}x{sy} does not divide the data window's position and size",
                        channel.name
                    ));
                }
            }
        }
        // Everything else as `exr` checks it, the sampling set aside.
        let mut unsampled: Vec<Header> = headers.to_vec();
        for header in &mut unsampled {
            for channel in header.channels.list.iter_mut() {
                channel.sampling = Vec2(1, 1);
            }
        }
        MetaData::validate(&unsampled, false).map_err(error)?;
        Ok(File {
            headers: headers.to_vec(),
            offsets: offsets.into_vec(),
        })
    }
}

/// One channel of a part, at its own resolution.
#[derive(Debug, Clone)]
pub(crate) struct Channel {
    pub name: Text,
    /// How the file stores it.
    pub kind: SampleType,
    pub linear: bool,
    pub sampling: (usize, usize),
    /// Its samples in x and y.
    pub size: (usize, usize),
    pub samples: FlatSamples,
}

/// A chunk's data with the block it holds.
struct Block<'a> {
    data: &'a [u8],
    layout: BlockLayout,
    /// Its first column and line within the part's data window.
    column: usize,
    line: usize,
}

/// Lines of one part that chunks fill together: one chunk of scanlines,
/// or a row of tiles.
struct Band<'a> {
    part: usize,
    line: usize,
    lines: usize,
    blocks: Vec<Block<'a>>,
}

/// A band's lines of one channel, as they will be stored.
enum Rows<'a> {
    F16(&'a mut [f16]),
    F32(&'a mut [f32]),
    U32(&'a mut [u32]),
}

/// Little-endian i32s from `bytes` at `at`, moving it on.
fn i32_at(bytes: &[u8], at: &mut usize) -> Result<i32, String> {
    let b = bytes
        .get(*at..*at + 4)
        .ok_or("a chunk runs past the end of the file")?;
    *at += 4;
    Ok(i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// The chunk at `offset` of part `part`: its data and, if it is of the
/// largest level, its block's place.
fn chunk<'a>(
    bytes: &'a [u8],
    offset: u64,
    part: usize,
    headers: &[Header],
) -> Result<Option<Block<'a>>, String> {
    let header = &headers[part];
    let mut at = usize::try_from(offset).map_err(|_| "a chunk offset is beyond the file")?;
    if headers.len() > 1 {
        let named = i32_at(bytes, &mut at)?;
        if usize::try_from(named).ok() != Some(part) {
            return Err(format!("a chunk of part {part} is marked as part {named}"));
        }
    }
    let tile = match header.blocks {
        BlockDescription::ScanLines => {
            let y = i64::from(i32_at(bytes, &mut at)?);
            let top = i64::from(header.own_attributes.layer_position.1);
            let lines = header.compression.scan_lines_per_block() as i64;
            if y < top || (y - top) % lines != 0 {
                return Err(format!(
                    "a chunk of part {part} starts at line {y}, not at one of its blocks"
                ));
            }
            TileCoordinates {
                tile_index: Vec2(0, ((y - top) / lines) as usize),
                level_index: Vec2(0, 0),
            }
        }
        BlockDescription::Tiles(_) => {
            let mut next = || -> Result<usize, String> {
                usize::try_from(i32_at(bytes, &mut at)?)
                    .map_err(|_| "a tile's coordinates are negative".to_string())
            };
            let (x, y, level_x, level_y) = (next()?, next()?, next()?, next()?);
            if (level_x, level_y) != (0, 0) {
                return Ok(None);
            }
            TileCoordinates {
                tile_index: Vec2(x, y),
                level_index: Vec2(0, 0),
            }
        }
    };
    let size = usize::try_from(i32_at(bytes, &mut at)?)
        .map_err(|_| "a chunk's size is negative".to_string())?;
    let data = bytes
        .get(at..at.saturating_add(size))
        .ok_or("a chunk runs past the end of the file")?;
    let bounds = header
        .get_absolute_block_pixel_coordinates(tile)
        .map_err(|e| e.to_string())?;
    bounds
        .validate(Some(header.layer_size))
        .map_err(|e| e.to_string())?;
    let (column, line) = (bounds.position.0 as usize, bounds.position.1 as usize);
    Ok(Some(Block {
        data,
        layout: BlockLayout::new(header, (column, line), (bounds.size.0, bounds.size.1)),
        column,
        line,
    }))
}

/// Every part's channels, the largest level; the channels `as_float`
/// names (part, channel name) as f32.
pub(crate) fn read(
    bytes: &[u8],
    file: &File,
    as_float: &[(usize, &str)],
    spares: &Spares,
) -> Result<Vec<Vec<Channel>>, String> {
    let headers = &file.headers;
    let mut blocks: Vec<Vec<Block>> = headers.iter().map(|_| Vec::new()).collect();
    for (part, offsets) in file.offsets.iter().enumerate() {
        for &offset in offsets {
            if let Some(block) = chunk(bytes, offset, part, headers)? {
                blocks[part].push(block);
            }
        }
    }
    let bands = bands(headers, blocks)?;
    let mut parts: Vec<Vec<Channel>> = headers
        .iter()
        .enumerate()
        .map(|(p, header)| channels(p, header, as_float, spares))
        .collect::<Result<_, String>>()?;
    // Each band gets its lines of every channel of its part.
    let mut rows: Vec<Vec<Rows>> = bands.iter().map(|_| Vec::new()).collect();
    for (p, channels) in parts.iter_mut().enumerate() {
        let top = i64::from(headers[p].own_attributes.layer_position.1);
        for channel in channels.iter_mut() {
            let width = channel.size.0;
            let mut rest = Rows::of(&mut channel.samples);
            let mut row = 0;
            for (b, band) in bands.iter().enumerate().filter(|(_, b)| b.part == p) {
                let first = top + band.line as i64;
                let start = samples_between(channel.sampling.1, top, first - 1);
                let count =
                    samples_between(channel.sampling.1, first, first + band.lines as i64 - 1);
                // Bands follow one another without a gap (`bands`).
                debug_assert_eq!(start, row);
                let (mine, after) = rest.split_at(count * width);
                rows[b].push(mine);
                rest = after;
                row = start + count;
            }
        }
    }
    let widths: Vec<Vec<usize>> = headers.iter().map(widths).collect();
    bands.into_par_iter().zip(rows).try_for_each_init(
        Decompressor::new,
        |decompressor, (band, mut rows)| {
            let header = &headers[band.part];
            for block in band.blocks {
                let samples = decompress(block.data, &block.layout, header, decompressor)?;
                place(
                    &samples,
                    &block.layout,
                    block.column,
                    &mut rows,
                    &widths[band.part],
                );
            }
            Ok::<(), String>(())
        },
    )?;
    Ok(parts)
}

/// Each channel's samples in a line of `header`'s data window.
fn widths(header: &Header) -> Vec<usize> {
    let left = i64::from(header.own_attributes.layer_position.0);
    let right = left + header.layer_size.0 as i64 - 1;
    header
        .channels
        .list
        .iter()
        .map(|c| samples_between(c.sampling.0, left, right))
        .collect()
}

/// The channels of part `p`, their samples zeroed, ready to be filled.
fn channels(
    p: usize,
    header: &Header,
    as_float: &[(usize, &str)],
    spares: &Spares,
) -> Result<Vec<Channel>, String> {
    let origin = header.own_attributes.layer_position;
    let (left, top) = (i64::from(origin.0), i64::from(origin.1));
    let (right, bottom) = (
        left + header.layer_size.0 as i64 - 1,
        top + header.layer_size.1 as i64 - 1,
    );
    header
        .channels
        .list
        .iter()
        .map(|c| {
            let size = (
                samples_between(c.sampling.0, left, right),
                samples_between(c.sampling.1, top, bottom),
            );
            let n = size.0 * size.1;
            let float = as_float
                .iter()
                .any(|&(part, name)| part == p && c.name.eq(name));
            let samples = match (float, c.sample_type) {
                (true, _) | (false, SampleType::F32) => spares.floats(n).map(FlatSamples::F32),
                (false, SampleType::F16) => spares.halves(n).map(FlatSamples::F16),
                (false, SampleType::U32) => aureole::image::zeros(n).map(FlatSamples::U32),
            }
            .map_err(|e| e.to_string())?;
            Ok(Channel {
                name: c.name.clone(),
                kind: c.sample_type,
                linear: c.quantize_linearly,
                sampling: (c.sampling.0.max(1), c.sampling.1.max(1)),
                size,
                samples,
            })
        })
        .collect()
}

/// The blocks of every part grouped into bands of lines, in order;
/// refuses blocks that overlap or leave lines or columns unfilled.
fn bands<'a>(headers: &[Header], blocks: Vec<Vec<Block<'a>>>) -> Result<Vec<Band<'a>>, String> {
    let mut bands = Vec::new();
    for (part, mut blocks) in blocks.into_iter().enumerate() {
        let (width, height) = (headers[part].layer_size.0, headers[part].layer_size.1);
        blocks.sort_by_key(|b| (b.line, b.column));
        let mut next_line = 0;
        let mut blocks = blocks.into_iter().peekable();
        while let Some(first) = blocks.next() {
            let (line, lines) = (first.line, first.layout.height);
            if line != next_line {
                return Err(incomplete(part, next_line, line));
            }
            let mut next_column = first.column + first.layout.width;
            if first.column != 0 {
                return Err(incomplete(part, line, line));
            }
            let mut row = vec![first];
            while let Some(block) = blocks.next_if(|b| b.line == line) {
                if block.column != next_column || block.layout.height != lines {
                    return Err(incomplete(part, line, line));
                }
                next_column += block.layout.width;
                row.push(block);
            }
            if next_column != width {
                return Err(incomplete(part, line, line));
            }
            bands.push(Band {
                part,
                line,
                lines,
                blocks: row,
            });
            next_line = line + lines;
        }
        if next_line != height {
            return Err(incomplete(part, next_line, height));
        }
    }
    Ok(bands)
}

fn incomplete(part: usize, line: usize, until: usize) -> String {
    format!(
        "part {part}'s chunks do not fill its data window: line {line}{} is missing or written twice",
        if until > line {
            format!(" to {}", until - 1)
        } else {
            String::new()
        }
    )
}

/// A chunk's samples, little-endian, line by line.
fn decompress<'a>(
    data: &'a [u8],
    layout: &BlockLayout,
    header: &Header,
    decompressor: &mut Decompressor,
) -> Result<Cow<'a, [u8]>, String> {
    let expected = layout.byte_size();
    // Every compression stores a block as it is where compressing would
    // not make it smaller.
    if data.len() == expected {
        return Ok(Cow::Borrowed(data));
    }
    let samples = match header.compression {
        X::Uncompressed => Err(format!(
            "an uncompressed chunk holds {} bytes where its lines need {expected}",
            data.len()
        )),
        X::RLE => rle::decompress(data, expected),
        X::ZIP1 | X::ZIP16 => zip::decompress(data, expected, decompressor),
        X::PIZ => piz::decompress(data, layout),
        X::PXR24 => pxr24::decompress(data, layout, decompressor),
        X::B44 | X::B44A => b44::decompress(data, layout),
        X::DWAA(_) | X::DWAB(_) => dwa(data, layout, header),
        other => Err(format!("the {other} compression is not read")),
    }?;
    if samples.len() != expected {
        return Err(format!(
            "a chunk decompressed to {} bytes where its lines need {expected}",
            samples.len()
        ));
    }
    Ok(Cow::Owned(samples))
}

/// A DWA chunk through `exr`'s decoder, which gives native-endian samples.
fn dwa(data: &[u8], layout: &BlockLayout, header: &Header) -> Result<Vec<u8>, String> {
    let rectangle = exr::meta::attribute::IntegerBounds::new(
        Vec2(layout.x0 as i32, layout.y0 as i32),
        Vec2(layout.width, layout.height),
    );
    let native = exr::compression::dwa::decompress(
        &header.channels,
        data.to_vec(),
        rectangle,
        layout.byte_size(),
        false,
    )
    .map_err(|e| format!("a DWA chunk: {e}"))?;
    if cfg!(target_endian = "big") {
        return Ok(swap_to_little_endian(native, layout));
    }
    Ok(native)
}

/// Native big-endian samples, line by line, as little-endian ones.
fn swap_to_little_endian(mut bytes: Vec<u8>, layout: &BlockLayout) -> Vec<u8> {
    let mut at = 0;
    for y in layout.lines() {
        for channel in layout.channels.iter().filter(|c| c.on_line(y)) {
            let size = channel.bytes();
            for sample in bytes[at..at + channel.nx * size].chunks_exact_mut(size) {
                sample.reverse();
            }
            at += channel.nx * size;
        }
    }
    bytes
}

impl<'a> Rows<'a> {
    fn of(samples: &'a mut FlatSamples) -> Rows<'a> {
        match samples {
            FlatSamples::F16(v) => Rows::F16(v),
            FlatSamples::F32(v) => Rows::F32(v),
            FlatSamples::U32(v) => Rows::U32(v),
        }
    }

    fn split_at(self, at: usize) -> (Rows<'a>, Rows<'a>) {
        match self {
            Rows::F16(v) => {
                let (a, b) = v.split_at_mut(at);
                (Rows::F16(a), Rows::F16(b))
            }
            Rows::F32(v) => {
                let (a, b) = v.split_at_mut(at);
                (Rows::F32(a), Rows::F32(b))
            }
            Rows::U32(v) => {
                let (a, b) = v.split_at_mut(at);
                (Rows::U32(a), Rows::U32(b))
            }
        }
    }

    /// Stores `bytes`, samples of type `kind`, from sample `at` on.
    fn store(&mut self, at: usize, bytes: &[u8], kind: SampleType, halves: &mut Vec<u16>) {
        match (self, kind) {
            (Rows::F32(rows), SampleType::F16) => {
                halves.clear();
                halves.extend(
                    bytes
                        .chunks_exact(2)
                        .map(|b| u16::from_le_bytes([b[0], b[1]])),
                );
                let out = &mut rows[at..at + halves.len()];
                halves.reinterpret_cast::<f16>().convert_to_f32_slice(out);
            }
            (Rows::F32(rows), SampleType::F32) => {
                for (o, b) in rows[at..].iter_mut().zip(bytes.chunks_exact(4)) {
                    *o = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                }
            }
            (Rows::F32(rows), SampleType::U32) => {
                for (o, b) in rows[at..].iter_mut().zip(bytes.chunks_exact(4)) {
                    *o = u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32;
                }
            }
            (Rows::F16(rows), _) => {
                for (o, b) in rows[at..].iter_mut().zip(bytes.chunks_exact(2)) {
                    *o = f16::from_bits(u16::from_le_bytes([b[0], b[1]]));
                }
            }
            (Rows::U32(rows), _) => {
                for (o, b) in rows[at..].iter_mut().zip(bytes.chunks_exact(4)) {
                    *o = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                }
            }
        }
    }
}

/// A block's samples into its band's rows of each channel, from column
/// `column` (`widths`: each channel's samples in a line of the part).
fn place(samples: &[u8], layout: &BlockLayout, column: usize, rows: &mut [Rows], widths: &[usize]) {
    let mut halves = Vec::new();
    let mut at = 0;
    let mut line_of = vec![0usize; layout.channels.len()];
    for y in layout.lines() {
        for (c, channel) in layout.channels.iter().enumerate() {
            if !channel.on_line(y) {
                continue;
            }
            let n = channel.nx * channel.bytes();
            // Subsampling is only allowed in scanline files, whose blocks
            // span the whole width: a column is a sample index there.
            let first = line_of[c] * widths[c] + column;
            rows[c].store(first, &samples[at..at + n], channel.kind, &mut halves);
            at += n;
            line_of[c] += 1;
        }
    }
}
