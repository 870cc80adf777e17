//! HDR images in memory: linear planes in the file's own units, with the
//! scale that turns them into luminance (cd/m²).

use rayon::prelude::*;

/// Rec.709 luminance weights: Y = 0.2126 R + 0.7152 G + 0.0722 B.
pub const REC709_LUMINANCE: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// The CIE xy chromaticities of an image's red, green and blue primaries and
/// its white point (the EXR `chromaticities` attribute).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Primaries {
    /// Red primary, (x, y).
    pub red: [f32; 2],
    /// Green primary, (x, y).
    pub green: [f32; 2],
    /// Blue primary, (x, y).
    pub blue: [f32; 2],
    /// White point, (x, y).
    pub white: [f32; 2],
}

impl Primaries {
    /// The Y row of the RGB → XYZ matrix, normalised so that RGB (1, 1, 1)
    /// is white of Y = 1; `None` for degenerate primaries (not finite, a
    /// chromaticity with y = 0, or three primaries on one line).
    ///
    /// Primaries outside the spectrum locus are valid: ACES AP0's blue has
    /// y < 0, which gives it a negative weight (Y = 0.344 R + 0.728 G −
    /// 0.072 B), as SMPTE ST 2065-1 states.
    pub fn luminance_weights(&self) -> Option<[f32; 3]> {
        let points = [self.red, self.green, self.blue, self.white];
        let usable = points
            .iter()
            .all(|[x, y]| x.is_finite() && y.is_finite() && y.abs() > 1e-6);
        let [[rx, ry], [gx, gy], [bx, by]] =
            [self.red, self.green, self.blue].map(|p| p.map(f64::from));
        let twice_area = (gx - rx) * (by - ry) - (bx - rx) * (gy - ry);
        if !usable || twice_area.abs() < 1e-6 {
            return None;
        }
        // Columns: XYZ of each primary at Y = 1; solve M·s = XYZ(white).
        let xyz = |[x, y]: [f32; 2]| {
            let (x, y) = (f64::from(x), f64::from(y));
            [x / y, 1.0, (1.0 - x - y) / y]
        };
        let (r, g, b, w) = (
            xyz(self.red),
            xyz(self.green),
            xyz(self.blue),
            xyz(self.white),
        );
        let det = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
            a[0] * (b[1] * c[2] - b[2] * c[1]) - b[0] * (a[1] * c[2] - a[2] * c[1])
                + c[0] * (a[1] * b[2] - a[2] * b[1])
        };
        let d = det(r, g, b);
        let weights = [det(w, g, b) / d, det(r, w, b) / d, det(r, g, w) / d];
        weights
            .iter()
            .all(|v| v.is_finite())
            .then(|| weights.map(|v| v as f32))
    }
}

/// Which colour channels an image holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// One plane of luminance, `Y`.
    Luminance,
    /// Three planes of linear Rec.709 `R`, `G`, `B`.
    Rgb,
}

/// A linear image. Planes are row-major, top row first.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Luminance-only or RGB.
    pub layout: Layout,
    /// One plane (Y) or three (R, G, B), in the file's units.
    pub planes: Vec<Vec<f32>>,
    /// Alpha, carried through untouched (never used to un-premultiply).
    pub alpha: Option<Vec<f32>>,
    /// The EXR `whiteLuminance` attribute: cd/m² of the value 1.
    pub white_luminance: Option<f32>,
    /// The EXR `chromaticities` attribute; Rec.709 when absent.
    pub primaries: Option<Primaries>,
}

/// What a frame is made of, from its pixels or a file's header alone:
/// enough to know what a run on it needs before it is decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shape {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Colour planes: 1 (luminance) or 3 (RGB).
    pub planes: usize,
    /// Whether it has alpha.
    pub alpha: bool,
}

impl Shape {
    /// The shape of `image`.
    pub fn of(image: &Image) -> Shape {
        Shape {
            width: image.width,
            height: image.height,
            planes: image.planes.len(),
            alpha: image.alpha.is_some(),
        }
    }
}

/// Samples that a luminance image must not hold (NaN or infinite, or
/// negative): how many and where the first one is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BadSamples {
    /// How many samples (over all colour planes) there are.
    pub count: usize,
    /// Column and row (from the top) of the first.
    pub first: (usize, usize),
}

impl Image {
    /// An image of `layout` filled with `value`.
    pub fn filled(width: usize, height: usize, layout: Layout, value: f32) -> Image {
        let planes = match layout {
            Layout::Luminance => 1,
            Layout::Rgb => 3,
        };
        Image {
            width,
            height,
            layout,
            planes: vec![vec![value; width * height]; planes],
            alpha: None,
            white_luminance: None,
            primaries: None,
        }
    }

    /// The same image with no colour planes: size, layout, alpha and
    /// attributes, for a result to fill in.
    pub fn clone_without_planes(&self) -> Image {
        Image {
            width: self.width,
            height: self.height,
            layout: self.layout,
            planes: Vec::new(),
            alpha: self.alpha.clone(),
            white_luminance: self.white_luminance,
            primaries: self.primaries,
        }
    }

    /// The image resampled to `width`×`height` by area: each new pixel is
    /// the mean of the old pixels it covers, weighted by the part of each it
    /// covers, so that luminance stays luminance and the light of the
    /// whole (sum × pixel area) is kept. For previews, which are smaller.
    pub fn resampled(&self, width: usize, height: usize) -> Image {
        let (width, height) = (width.max(1), height.max(1));
        let columns = area_weights(self.width, width);
        let rows = area_weights(self.height, height);
        let resample = |plane: &Vec<f32>| -> Vec<f32> {
            // Along rows first, in f64 so that wide spans stay exact.
            let narrow: Vec<f64> = (0..self.height)
                .into_par_iter()
                .flat_map_iter(|y| {
                    let row = &plane[y * self.width..(y + 1) * self.width];
                    columns
                        .iter()
                        .map(move |w| w.iter().map(|&(x, f)| f * f64::from(row[x])).sum::<f64>())
                })
                .collect();
            (0..height)
                .into_par_iter()
                .flat_map_iter(|y| {
                    let (rows, narrow) = (&rows, &narrow);
                    (0..width).map(move |x| {
                        rows[y]
                            .iter()
                            .map(|&(r, f)| f * narrow[r * width + x])
                            .sum::<f64>() as f32
                    })
                })
                .collect()
        };
        Image {
            width,
            height,
            layout: self.layout,
            planes: self.planes.iter().map(resample).collect(),
            alpha: self.alpha.as_ref().map(resample),
            white_luminance: self.white_luminance,
            primaries: self.primaries,
        }
    }

    /// Y = w·RGB for this image's primaries (Rec.709 unless the file
    /// says otherwise).
    pub fn luminance_weights(&self) -> [f32; 3] {
        self.primaries
            .and_then(|p| p.luminance_weights())
            .unwrap_or(REC709_LUMINANCE)
    }

    /// The luminance of every pixel, in file units.
    pub fn luminance(&self) -> Vec<f32> {
        match PixelLuminance::of(self) {
            PixelLuminance::Plane(y) => y.to_vec(),
            rgb => (0..self.width * self.height)
                .into_par_iter()
                .map(|i| rgb.at(i))
                .collect(),
        }
    }

    /// Σ luminance over the image, in file units, summed in f64 row by row
    /// (rows in parallel, added in order: the same bits every run).
    pub fn total_luminance(&self) -> f64 {
        let weights: Vec<f64> = match self.layout {
            Layout::Luminance => vec![1.0],
            Layout::Rgb => self
                .luminance_weights()
                .iter()
                .map(|&w| f64::from(w))
                .collect(),
        };
        let width = self.width.max(1);
        let rows: Vec<f64> = (0..self.height)
            .into_par_iter()
            .map(|y| {
                self.planes
                    .iter()
                    .zip(&weights)
                    .map(|(plane, w)| w * sum_f64(&plane[y * width..(y + 1) * width]))
                    .sum::<f64>()
            })
            .collect();
        rows.iter().sum()
    }

    /// The NaN and infinite samples of the colour planes, if any.
    pub fn non_finite(&self) -> Option<BadSamples> {
        self.find(|v| !v.is_finite())
    }

    /// The negative samples of the colour planes, if any: luminance cannot
    /// be negative, but resampling filters and denoisers leave some.
    pub fn negatives(&self) -> Option<BadSamples> {
        self.find(|v| v < 0.0)
    }

    fn find(&self, bad: impl Fn(f32) -> bool + Sync) -> Option<BadSamples> {
        const CHUNK: usize = 1 << 16;
        let in_plane = |plane: &Vec<f32>| {
            plane
                .par_chunks(CHUNK)
                .enumerate()
                .map(|(c, chunk)| {
                    let mut found = (0usize, usize::MAX);
                    for (i, &v) in chunk.iter().enumerate() {
                        if bad(v) {
                            found = (found.0 + 1, found.1.min(c * CHUNK + i));
                        }
                    }
                    found
                })
                .reduce(|| (0, usize::MAX), |a, b| (a.0 + b.0, a.1.min(b.1)))
        };
        let (count, first) = self
            .planes
            .par_iter()
            .map(in_plane)
            .reduce(|| (0, usize::MAX), |a, b| (a.0 + b.0, a.1.min(b.1)));
        (count > 0).then(|| BadSamples {
            count,
            first: (first % self.width, first / self.width),
        })
    }

    /// Replaces NaN, infinite and negative samples by 0; returns how many
    /// were replaced.
    pub fn sanitize(&mut self) -> usize {
        self.planes
            .par_iter_mut()
            .flat_map(|plane| plane.par_iter_mut())
            .filter(|v| !v.is_finite() || **v < 0.0)
            .map(|v| *v = 0.0)
            .count()
    }
}

/// The luminance of an image's pixels, computed where it is needed rather
/// than kept as a plane (a meter that samples every k-th pixel needs no
/// copy of the frame).
pub enum PixelLuminance<'a> {
    /// R, G, B planes and their luminance weights.
    Rgb([f32; 3], [&'a [f32]; 3]),
    /// A luminance plane.
    Plane(&'a [f32]),
}

impl<'a> PixelLuminance<'a> {
    /// The luminance of `image`'s pixels.
    pub fn of(image: &'a Image) -> PixelLuminance<'a> {
        match (image.layout, image.planes.as_slice()) {
            (Layout::Rgb, [r, g, b]) => PixelLuminance::Rgb(image.luminance_weights(), [r, g, b]),
            _ => PixelLuminance::Plane(&image.planes[0]),
        }
    }

    /// Y of pixel `i`, in file units: Y = w·RGB for the image's primaries.
    #[inline]
    pub fn at(&self, i: usize) -> f32 {
        match self {
            PixelLuminance::Rgb([wr, wg, wb], [r, g, b]) => wr * r[i] + wg * g[i] + wb * b[i],
            PixelLuminance::Plane(y) => y[i],
        }
    }
}

/// Σ values in f64, in eight interleaved partial sums (a fixed order, so
/// the same bits every run) that the CPU adds in parallel rather than one
/// addition waiting for the last.
pub(crate) fn sum_f64(values: &[f32]) -> f64 {
    let mut lanes = [0f64; 8];
    let chunks = values.chunks_exact(8);
    let rest: f64 = chunks.remainder().iter().map(|&v| f64::from(v)).sum();
    for chunk in chunks {
        for (lane, &v) in lanes.iter_mut().zip(chunk) {
            *lane += f64::from(v);
        }
    }
    lanes.iter().sum::<f64>() + rest
}

/// n zeros, written: calloc's untouched pages map the kernel's shared zero
/// page when first read, and a write after that read copies the page and
/// flushes every core's TLB (an interrupt to each, costly in a virtual
/// machine). A plane that is read whole (summed) before it is written
/// whole (scaled) is written first, on every core.
///
/// The memory is reserved first and its refusal returned
/// ([`crate::Error::Allocation`]): the estimate before a run is on the
/// safe side, but the machine's memory may have gone to other programs
/// since, and an abort would lose the run's words.
pub fn zeros<T: Copy + Default + Send + Sync>(n: usize) -> crate::Result<Vec<T>> {
    let mut v = Vec::new();
    grow_zeroed(&mut v, n)?;
    Ok(v)
}

/// `v` made `n` long, its new values zeros written on every core: a
/// buffer lent empty grows by hundreds of megabytes at 4K, and `resize`
/// would take each of its fresh pages' faults on one core. The memory is
/// reserved first ([`zeros`]).
pub(crate) fn grow_zeroed<T: Copy + Default + Send + Sync>(
    v: &mut Vec<T>,
    n: usize,
) -> crate::Result<()> {
    if v.len() >= n {
        v.truncate(n);
    } else {
        let more = n - v.len();
        v.try_reserve_exact(more)
            .map_err(|_| crate::Error::Allocation {
                bytes: (more as u64).saturating_mul(std::mem::size_of::<T>() as u64),
            })?;
        v.par_extend((0..more).into_par_iter().map(|_| T::default()));
    }
    Ok(())
}

/// For each of `to` cells spanning `from` old ones, the old cells it
/// covers and the fraction of the new cell each fills (summing to 1).
fn area_weights(from: usize, to: usize) -> Vec<Vec<(usize, f64)>> {
    let step = from as f64 / to as f64;
    (0..to)
        .map(|i| {
            let (start, end) = (i as f64 * step, (i + 1) as f64 * step);
            let first = start.floor() as usize;
            let last = (end.ceil() as usize).min(from);
            (first..last)
                .map(|k| {
                    let covered = (end.min(k as f64 + 1.0) - start.max(k as f64)).max(0.0);
                    (k, covered / step)
                })
                .filter(|&(_, f)| f > 0.0)
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plane_the_allocator_refuses_is_an_error_not_an_abort() {
        let refused = zeros::<f32>(1 << 60).unwrap_err();
        assert!(matches!(refused, crate::Error::Allocation { bytes } if bytes == 1 << 62));
        let line = refused.to_string();
        assert!(line.contains("could not allocate 4194304.0 TiB"), "{line}");
        assert_eq!(zeros::<f32>(5).unwrap(), vec![0.0; 5]);
    }

    #[test]
    fn rec709_primaries_give_the_rec709_weights() {
        let rec709 = Primaries {
            red: [0.64, 0.33],
            green: [0.30, 0.60],
            blue: [0.15, 0.06],
            white: [0.3127, 0.3290],
        };
        let w = rec709.luminance_weights().unwrap();
        for (a, b) in w.iter().zip(REC709_LUMINANCE) {
            assert!((a - b).abs() < 2e-4, "{w:?}");
        }
    }

    #[test]
    fn other_primaries_give_their_own_luminance() {
        // Tree.exr's primaries: Y = 0.24994 R + 0.66502 G + 0.08504 B.
        let tree = Primaries {
            red: [0.6295, 0.3410],
            green: [0.2867, 0.6108],
            blue: [0.1489, 0.0712],
            white: [0.3155, 0.3316],
        };
        let w = tree.luminance_weights().unwrap();
        for (a, b) in w.iter().zip([0.24994, 0.66502, 0.08504]) {
            assert!((a - b).abs() < 1e-4, "{w:?}");
        }
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        // Green halfway between red and blue: no basis of colour.
        let degenerate = Primaries {
            green: [0.3892, 0.2061],
            ..tree
        };
        assert!(degenerate.luminance_weights().is_none());
        let flat = Primaries {
            blue: [0.1489, 0.0],
            ..tree
        };
        assert!(flat.luminance_weights().is_none());
    }

    #[test]
    fn aces_primaries_give_the_rows_of_smpte_st_2065_1_and_s_2014_004() {
        let white = [0.32168, 0.33767];
        let ap0 = Primaries {
            red: [0.7347, 0.2653],
            green: [0.0, 1.0],
            blue: [0.0001, -0.0770],
            white,
        };
        let ap1 = Primaries {
            red: [0.713, 0.293],
            green: [0.165, 0.830],
            blue: [0.128, 0.044],
            white,
        };
        // The Y rows of the standards' normalised primary matrices.
        for (primaries, row) in [
            (ap0, [0.343_966_45, 0.728_166_1, -0.072_132_55]),
            (ap1, [0.272_228_72, 0.674_081_77, 0.053_689_52]),
        ] {
            let w = primaries.luminance_weights().unwrap();
            for (a, b) in w.iter().zip(row) {
                assert!((a - b).abs() < 2e-6, "{w:?} against {row:?}");
            }
        }
    }

    #[test]
    fn resampling_by_area_keeps_the_light() {
        let mut image = Image::filled(7, 5, Layout::Rgb, 0.0);
        for (i, v) in image.planes[1].iter_mut().enumerate() {
            *v = (i * 13 % 11) as f32;
        }
        let total = |im: &Image| -> f64 {
            im.planes[1].iter().map(|&v| f64::from(v)).sum::<f64>() / (im.width * im.height) as f64
        };
        for (w, h) in [(3, 2), (7, 5), (2, 5), (1, 1)] {
            let small = image.resampled(w, h);
            assert_eq!((small.width, small.height), (w, h));
            // The mean luminance, so sum × pixel area, is kept.
            assert!((total(&small) - total(&image)).abs() < 1e-5, "{w}x{h}");
        }
        assert_eq!(image.resampled(7, 5).planes, image.planes);
    }
}
