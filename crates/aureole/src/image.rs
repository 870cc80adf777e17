//! HDR images in memory: linear planes in the file's own units, with the
//! scale that turns them into luminance (cd/m²).

/// Rec.709 luminance weights: Y = 0.2126 R + 0.7152 G + 0.0722 B.
pub const REC709_LUMINANCE: [f32; 3] = [0.2126, 0.7152, 0.0722];

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
}

/// Pixels that are NaN or infinite: how many and where the first one is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NonFinite {
    /// How many samples (over all colour planes) are not finite.
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
        }
    }

    /// The luminance of pixel `i` in file units.
    pub fn luminance_at(&self, i: usize) -> f32 {
        match self.layout {
            Layout::Luminance => self.planes[0][i],
            Layout::Rgb => {
                REC709_LUMINANCE[0] * self.planes[0][i]
                    + REC709_LUMINANCE[1] * self.planes[1][i]
                    + REC709_LUMINANCE[2] * self.planes[2][i]
            }
        }
    }

    /// Σ luminance over the image, in file units, summed in f64.
    pub fn total_luminance(&self) -> f64 {
        (0..self.width * self.height)
            .map(|i| f64::from(self.luminance_at(i)))
            .sum()
    }

    /// The NaN and infinite samples of the colour planes, if any.
    pub fn non_finite(&self) -> Option<NonFinite> {
        let mut count = 0;
        let mut first = usize::MAX;
        for plane in &self.planes {
            for (i, v) in plane.iter().enumerate() {
                if !v.is_finite() {
                    count += 1;
                    first = first.min(i);
                }
            }
        }
        (count > 0).then(|| NonFinite {
            count,
            first: (first % self.width, first / self.width),
        })
    }

    /// Replaces NaN and infinite samples by 0; returns how many there were.
    pub fn sanitize(&mut self) -> usize {
        let mut count = 0;
        for v in self.planes.iter_mut().flatten() {
            if !v.is_finite() {
                *v = 0.0;
                count += 1;
            }
        }
        count
    }
}
