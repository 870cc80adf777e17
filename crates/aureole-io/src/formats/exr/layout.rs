//! Where a block's samples lie once it is decompressed: line by line from
//! its top, each line holding, channel after channel (in the header's
//! order), the samples that channel has on that line. A subsampled channel
//! (`RY`, `BY` at 2×2) has samples only on the lines and columns its
//! sampling divides, in the file's own coordinates (OpenEXR's
//! `numSamples` and `modp`).

use exr::meta::attribute::SampleType;
use exr::meta::header::Header;

/// One channel's share of a block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ChannelBlock {
    pub kind: SampleType,
    pub sampling: (usize, usize),
    /// Its samples in x and y within the block.
    pub nx: usize,
    pub ny: usize,
    /// OpenEXR's `pLinear`: B44 stores it on a log scale.
    pub linear: bool,
}

impl ChannelBlock {
    /// Bytes per sample.
    pub fn bytes(&self) -> usize {
        self.kind.bytes_per_sample()
    }

    /// Whether line `y` (file coordinates) holds samples of it.
    pub fn on_line(&self, y: i64) -> bool {
        y.rem_euclid(self.sampling.1 as i64) == 0
    }
}

/// The channels of a block and the lines it spans.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct BlockLayout {
    pub channels: Vec<ChannelBlock>,
    /// Its first line and column, in file coordinates.
    pub y0: i64,
    pub x0: i64,
    /// Its lines and columns.
    pub height: usize,
    pub width: usize,
}

/// The samples of a sampling `s` among the coordinates `a..=b`.
pub(crate) fn samples_between(s: usize, a: i64, b: i64) -> usize {
    let s = s.max(1) as i64;
    let (a1, b1) = (a.div_euclid(s), b.div_euclid(s));
    let count = b1 - a1 + if a1 * s < a { 0 } else { 1 };
    usize::try_from(count).unwrap_or(0)
}

impl BlockLayout {
    /// The block of `header` at `position` (within the data window) of
    /// `size` pixels.
    pub fn new(header: &Header, position: (usize, usize), size: (usize, usize)) -> BlockLayout {
        let origin = header.own_attributes.layer_position;
        let x0 = i64::from(origin.0) + position.0 as i64;
        let y0 = i64::from(origin.1) + position.1 as i64;
        let (x1, y1) = (x0 + size.0 as i64 - 1, y0 + size.1 as i64 - 1);
        let channels = header
            .channels
            .list
            .iter()
            .map(|c| ChannelBlock {
                kind: c.sample_type,
                sampling: (c.sampling.0.max(1), c.sampling.1.max(1)),
                nx: samples_between(c.sampling.0, x0, x1),
                ny: samples_between(c.sampling.1, y0, y1),
                linear: c.quantize_linearly,
            })
            .collect();
        BlockLayout {
            channels,
            y0,
            x0,
            height: size.1,
            width: size.0,
        }
    }

    /// The bytes of its samples.
    pub fn byte_size(&self) -> usize {
        self.channels.iter().map(|c| c.nx * c.ny * c.bytes()).sum()
    }

    /// Its lines, top first, in file coordinates.
    pub fn lines(&self) -> std::ops::Range<i64> {
        self.y0..self.y0 + self.height as i64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_are_counted_as_openexr_counts_them() {
        assert_eq!(samples_between(1, 0, 9), 10);
        assert_eq!(samples_between(2, 0, 9), 5);
        assert_eq!(samples_between(2, 1, 9), 4);
        assert_eq!(samples_between(2, 0, 0), 1);
        assert_eq!(samples_between(2, 1, 1), 0);
        assert_eq!(samples_between(2, -3, 2), 3);
        assert_eq!(samples_between(3, -3, -1), 1);
    }
}
