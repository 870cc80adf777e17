//! Luminance/chroma files (`Y` at full resolution, `RY` = (R − Y)/Y and
//! `BY` = (B − Y)/Y at half resolution both ways) to RGB, as OpenEXR's
//! `RgbaInputFile` reconstructs them (`ImfRgbaYca`): the missing chroma
//! samples from a 27-tap filter, first along the lines that have chroma,
//! then down the columns; RGB from the file's luminance weights; then
//! pixels more saturated than their neighbours desaturated, which hides
//! the filter's ringing at sharp colour edges. Values pass through half
//! floats where OpenEXR's do, so a file gives the same samples as there.

use exr::prelude::f16;

/// Half of the filter's width.
const HALF_TAPS: i64 = 13;

/// The filter that fills a missing chroma sample from its even
/// neighbours at −13, −11, …, +13 (`reconstructChromaHoriz`).
const TAPS: [f32; 14] = [
    0.002128, -0.007540, 0.019597, -0.043159, 0.087929, -0.186077, 0.627123, 0.627123, -0.186077,
    0.087929, -0.043159, 0.019597, -0.007540, 0.002128,
];

/// Rec.709's primaries and white, x and y: OpenEXR's default
/// chromaticities.
pub(crate) const REC709: [[f32; 2]; 4] =
    [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06], [0.3127, 0.3290]];

fn half(v: f32) -> f32 {
    f16::from_f32(v).to_f32()
}

/// A filtered sum as OpenEXR computes it: in float, in order, stored as
/// a half.
fn filtered(samples: impl Iterator<Item = f32>) -> f32 {
    let mut taps = samples.zip(TAPS).map(|(v, tap)| v * tap);
    let first = taps.next().unwrap_or(0.0);
    half(taps.fold(first, |sum, term| sum + term))
}

/// The file's luminance weights as OpenEXR computes them in float
/// (`computeYw`: the Y row of `RGBtoXYZ`, over its sum). `primaries`: red,
/// green, blue and white, x and y.
pub(crate) fn weights(primaries: [[f32; 2]; 4]) -> [f32; 3] {
    let [[rx, ry], [gx, gy], [bx, by], [wx, wy]] = primaries;
    let y = 1.0f32;
    let x = wx * y / wy;
    let z = (1.0 - wx - wy) * y / wy;
    let d = rx * (by - gy) + bx * (gy - ry) + gx * (ry - by);
    let sr = (x * (by - gy) - gx * (y * (by - 1.0) + by * (x + z))
        + bx * (y * (gy - 1.0) + gy * (x + z)))
        / d;
    let sg = (x * (ry - by) + rx * (y * (by - 1.0) + by * (x + z))
        - bx * (y * (ry - 1.0) + ry * (x + z)))
        / d;
    let sb = (x * (gy - ry) - rx * (y * (gy - 1.0) + gy * (x + z))
        + gx * (y * (ry - 1.0) + ry * (x + z)))
        / d;
    let row = [sr * ry, sg * gy, sb * by];
    let sum = row[0] + row[1] + row[2];
    row.map(|v| v / sum)
}

/// A line of the file as OpenEXR's reader holds it: Y, and chroma at
/// every pixel (missing ones filtered along the line).
#[derive(Clone)]
struct Yca {
    y: Vec<f32>,
    ry: Vec<f32>,
    by: Vec<f32>,
}

/// The planes of a luminance/chroma file and where its data window starts.
pub(crate) struct Planes<'a> {
    pub y: &'a [f32],
    /// Half resolution both ways: the samples of the even columns of the
    /// even lines.
    pub ry: &'a [f32],
    pub by: &'a [f32],
    pub width: usize,
    pub height: usize,
    /// The data window's first column and line, in file coordinates
    /// (OpenEXR requires them even for chroma at 2×2).
    pub origin: (i64, i64),
}

impl Planes<'_> {
    fn chroma_width(&self) -> usize {
        self.ry.len() / self.chroma_height().max(1)
    }

    fn chroma_height(&self) -> usize {
        super::layout::samples_between(2, self.origin.1, self.origin.1 + self.height as i64 - 1)
    }

    /// The window's line `line`, as the reader holds it
    /// (`readYCAScanLine`). A line without chroma takes its chroma from
    /// the even line before it (OpenEXR leaves its buffer's).
    fn yca(&self, line: usize) -> Yca {
        let w = self.width;
        let y = self.y[line * w..(line + 1) * w].to_vec();
        let absolute = self.origin.1 + line as i64;
        let even = absolute - absolute.rem_euclid(2);
        let chroma_row = ((even - self.origin.1).max(0) / 2) as usize;
        let chroma_row = chroma_row.min(self.chroma_height().saturating_sub(1));
        let cw = self.chroma_width();
        let along = |plane: &[f32]| -> Vec<f32> {
            let samples = &plane[chroma_row * cw..(chroma_row + 1) * cw];
            // Pixel x's chroma sample; the reader pads the line with the
            // first pixel's on the left and the one before the last on
            // the right (`padTmpBuf`; the last, for an odd width).
            let at = |x: i64| -> f32 {
                let x = if x < 0 {
                    0
                } else if x >= w as i64 {
                    w as i64 - 2 + (w as i64) % 2
                } else {
                    x
                };
                samples[((x.max(0) as usize) / 2).min(cw.saturating_sub(1))]
            };
            (0..w as i64)
                .map(|x| {
                    if (self.origin.0 + x).rem_euclid(2) == 0 {
                        at(x)
                    } else {
                        filtered((0..14).map(|k| at(x - HALF_TAPS + 2 * k)))
                    }
                })
                .collect()
        };
        Yca {
            y,
            ry: along(self.ry),
            by: along(self.by),
        }
    }
}

/// Every line of the window as the reader holds it, and which of them it
/// reads for a line beyond the window: the first above, the one before
/// the last below.
struct Lines(Vec<Yca>);

impl Lines {
    fn at(&self, line: i64) -> &Yca {
        let last = self.0.len() as i64 - 1;
        let line = if line < 0 {
            0
        } else if line > last {
            (last - 1).max(0)
        } else {
            line
        };
        &self.0[line as usize]
    }
}

/// A line of RGB pixels.
type Line = Vec<[f32; 3]>;

/// The RGB of a line from its Y and chroma (`YCAtoRGBA`), as halves.
fn rgb(yca: &Yca, weights: [f32; 3]) -> Line {
    let pixels = yca.y.iter().zip(&yca.ry).zip(&yca.by);
    pixels
        .map(|((&y, &ry), &by)| {
            if ry == 0.0 && by == 0.0 {
                return [half(y); 3];
            }
            let r = (ry + 1.0) * y;
            let b = (by + 1.0) * y;
            let g = (y - r * weights[0] - b * weights[2]) / weights[1];
            [half(r), half(g), half(b)]
        })
        .collect()
}

fn saturation([r, g, b]: [f32; 3]) -> f32 {
    let max = r.max(g.max(b));
    let min = r.min(g.min(b));
    if max > 0.0 {
        1.0 - min / max
    } else {
        0.0
    }
}

/// A pixel desaturated by `f` towards its largest component, keeping its
/// luminance (`desaturate`).
fn desaturate(rgb: [f32; 3], f: f32, weights: [f32; 3]) -> [f32; 3] {
    let max = rgb[0].max(rgb[1].max(rgb[2]));
    let out = rgb.map(|v| half((max - (max - v) * f).max(0.0)));
    let luminance = |c: [f32; 3]| c[0] * weights[0] + c[1] * weights[1] + c[2] * weights[2];
    let (before, after) = (luminance(rgb), luminance(out));
    if after > 0.0 {
        out.map(|v| half(v * (before / after)))
    } else {
        out
    }
}

/// A line from the lines above and below it (`fixSaturation`).
fn fix_saturation([above, line, below]: [&Line; 3], weights: [f32; 3]) -> Line {
    let n = line.len();
    let (mut a2, mut b2) = (saturation(above[0]), saturation(below[0]));
    let (mut a1, mut b1) = (a2, b2);
    let mut out = Vec::with_capacity(n);
    for (i, &pixel) in line.iter().enumerate() {
        let (a0, b0) = (a1, b1);
        a1 = a2;
        b1 = b2;
        if i + 1 < n {
            a2 = saturation(above[i + 1]);
            b2 = saturation(below[i + 1]);
        }
        let mean = (0.25 * (a0 + a2 + b0 + b2)).min(1.0);
        let saturated = saturation(pixel);
        let most = (1.0 - (1.0 - mean) * 0.25).min(1.0);
        out.push(if saturated > mean && saturated > most {
            desaturate(pixel, most / saturated, weights)
        } else {
            pixel
        });
    }
    out
}

/// RGB from Y, RY and BY all at full resolution, which OpenEXR's RGBA
/// reader does not take but the formulas of `YCAtoRGBA` decode.
pub(crate) fn full_resolution_to_rgb(
    y: Vec<f32>,
    mut ry: Vec<f32>,
    mut by: Vec<f32>,
    weights: [f32; 3],
) -> Vec<Vec<f32>> {
    let mut g = vec![0.0; y.len()];
    for i in 0..y.len().min(ry.len()).min(by.len()) {
        let r = (ry[i] + 1.0) * y[i];
        let b = (by[i] + 1.0) * y[i];
        g[i] = (y[i] - r * weights[0] - b * weights[2]) / weights[1];
        ry[i] = r;
        by[i] = b;
    }
    vec![ry, g, by]
}

/// R, G and B planes of the data window.
pub(crate) fn to_rgb(planes: &Planes, weights: [f32; 3]) -> [Vec<f32>; 3] {
    let (w, h) = (planes.width, planes.height);
    let mut out = [vec![0.0; w * h], vec![0.0; w * h], vec![0.0; w * h]];
    if w == 0 || h == 0 {
        return out;
    }
    let lines = Lines((0..h).map(|line| planes.yca(line)).collect());
    // The RGB of line `line` (within the window, or just beyond it): a
    // chroma line as it is, another with its chroma filtered down the
    // column from the chroma lines around it (`reconstructChromaVert`).
    let line_rgb = |line: i64| -> Line {
        let own = lines.at(line);
        if (planes.origin.1 + line).rem_euclid(2) == 0 {
            return rgb(own, weights);
        }
        let taps: Vec<&Yca> = (0..14)
            .map(|k| lines.at(line - HALF_TAPS + 2 * k))
            .collect();
        let column = |pick: fn(&Yca) -> &Vec<f32>| -> Vec<f32> {
            (0..w)
                .map(|i| filtered(taps.iter().map(|t| pick(t)[i])))
                .collect()
        };
        let yca = Yca {
            ry: column(|t| &t.ry),
            by: column(|t| &t.by),
            y: own.y.clone(),
        };
        rgb(&yca, weights)
    };
    let mut above = line_rgb(-1);
    let mut line = line_rgb(0);
    for row in 0..h {
        let below = line_rgb(row as i64 + 1);
        let fixed = fix_saturation([&above, &line, &below], weights);
        for (c, plane) in out.iter_mut().enumerate() {
            for (o, pixel) in plane[row * w..(row + 1) * w].iter_mut().zip(&fixed) {
                *o = pixel[c];
            }
        }
        above = std::mem::replace(&mut line, below);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rec709_weights_are_its_luminance_row() {
        let w = weights(REC709);
        for (found, expected) in w.iter().zip([0.2126, 0.7152, 0.0722]) {
            assert!((found - expected).abs() < 2e-4, "{w:?}");
        }
    }

    #[test]
    fn a_grey_file_stays_grey_and_a_flat_colour_stays_flat() {
        let (w, h) = (10, 8);
        let y = vec![2.0f32; w * h];
        let zeros = vec![0.0f32; (w / 2) * (h / 2)];
        let planes = Planes {
            y: &y,
            ry: &zeros,
            by: &zeros,
            width: w,
            height: h,
            origin: (0, 0),
        };
        let weights = weights(REC709);
        let [r, g, b] = to_rgb(&planes, weights);
        assert!(r.iter().chain(&g).chain(&b).all(|&v| v == 2.0));
        // RY = 0.5 everywhere: R = 1.5·Y on every pixel, filtered or not
        // (the taps sum to 1).
        let ry = vec![0.5f32; (w / 2) * (h / 2)];
        let planes = Planes { ry: &ry, ..planes };
        let [r, _, _] = to_rgb(&planes, weights);
        assert!(r.iter().all(|&v| (v - 3.0).abs() < 4e-3), "{r:?}");
    }
}
