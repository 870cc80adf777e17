//! Applying the camera to an image (MODEL.md §7–8): the light of pixels
//! brighter than the threshold is spread by the kernel, the rest stays:
//! O = I·[Y ≤ T] + K ⊛ (I·[Y > T]). A [`Plan`] builds the kernel and its
//! spectrum once for an image size and applies them to any number of images.

use rayon::prelude::*;

use crate::config::Config;
use crate::convolve::double::DoubleConvolver;
use crate::convolve::plan::{Convolver, Input};
use crate::error::{Error, Result};
use crate::image::{Image, Layout, REC709_LUMINANCE};
use crate::kernel::{Extent, Kernel};

/// How the light is split and what is written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ApplyOptions {
    /// Threshold T in cd/m²: pixels whose luminance is at or below it keep
    /// their light in place.
    pub threshold: f64,
    /// Soft knee, relative to T: between T and T·(1 + knee) the spread
    /// fraction rises smoothly from 0 to 1. 0 is the paper's hard threshold.
    pub knee: f64,
    /// cd/m² per file unit: what the threshold is compared with.
    pub scale: f64,
    /// Write only the light the camera adds (output − input), for
    /// compositing additively over the original.
    pub glare_only: bool,
    /// How the bright pixels are spread.
    pub method: Method,
}

/// How the light of the bright pixels is spread. Both give the same result
/// up to f32 round-off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// Whichever the cost estimate says is faster for this image.
    #[default]
    Auto,
    /// The FFT convolution of the bright planes: its cost does not depend
    /// on how many pixels are bright.
    Fft,
    /// The kernel added, weighted, at every bright pixel: cheaper for a few
    /// bright pixels or a small kernel, and exact in f32.
    Splat,
}

impl Default for ApplyOptions {
    fn default() -> Self {
        ApplyOptions {
            threshold: 0.0,
            knee: 0.0,
            scale: 1.0,
            glare_only: false,
            method: Method::Auto,
        }
    }
}

/// The result of applying a plan.
#[derive(Debug, Clone)]
pub struct Applied {
    /// The camera's image (or only its glare), in the input's units.
    pub image: Image,
    /// Σ luminance of the input, file units.
    pub energy_in: f64,
    /// Σ luminance of the camera's image, file units: the input's less what
    /// was spread beyond the frame.
    pub energy_out: f64,
    /// How many pixels were above the threshold and spread.
    pub spread_pixels: usize,
    /// How they were spread ([`Method::Fft`] or [`Method::Splat`]).
    pub method: Method,
    /// Whether the FFT ran in f64 because the scene's range is beyond f32.
    pub double: bool,
}

/// The kernel of an optical chain for one image size, with its spectrum.
pub struct Plan {
    width: usize,
    height: usize,
    kernel: Kernel,
    /// K at the centre, per kernel channel: applied exactly, pixel by pixel.
    centres: Vec<f32>,
    /// Convolves with the rest of K, the light that moves. Leaving the
    /// (1 − ε) peak out of the FFT keeps its f32 round-off ~1/ε times smaller.
    convolver: Convolver,
    /// The same in f64, built the first time a scene's range needs it.
    double: std::sync::OnceLock<DoubleConvolver>,
}

impl Plan {
    /// Builds the kernel for `width`×`height` images, by default large
    /// enough that light from any pixel reaches every other ((2W − 1)×(2H − 1)),
    /// or at most `max_extent`, and transforms it.
    pub fn new(
        config: &Config,
        width: usize,
        height: usize,
        max_extent: Option<(usize, usize)>,
    ) -> Result<Plan> {
        let extent = Extent::for_image_within(width, height, max_extent)?;
        Ok(Plan::from_kernel(config.kernel(&extent)?, width, height))
    }

    /// A plan for `width`×`height` images with a kernel built before (e.g.
    /// by `aureole psf`, read back from a file): kernels are cacheable.
    pub fn from_kernel(kernel: Kernel, width: usize, height: usize) -> Plan {
        let centres = kernel.centre_weights();
        let convolver = Convolver::without_centre(&kernel, width, height);
        Plan {
            width,
            height,
            kernel,
            centres,
            convolver,
            double: std::sync::OnceLock::new(),
        }
    }

    /// The image size the plan is for, width × height.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The kernel in use.
    pub fn kernel(&self) -> &Kernel {
        &self.kernel
    }

    /// Applies the camera to `image` (which must have the plan's size);
    /// `progress` hears the fraction done, 0 to 1.
    pub fn apply(
        &self,
        image: &Image,
        options: &ApplyOptions,
        progress: &mut dyn FnMut(f64),
    ) -> Result<Applied> {
        self.apply_recycling(image, options, Vec::new(), progress)
    }

    /// [`Plan::apply`], writing into `recycled`, the planes of a result
    /// that is no longer needed (e.g. the previous frame's): in a frame
    /// sequence this saves mapping fresh memory for every frame.
    pub fn apply_recycling(
        &self,
        image: &Image,
        options: &ApplyOptions,
        recycled: Vec<Vec<f32>>,
        progress: &mut dyn FnMut(f64),
    ) -> Result<Applied> {
        if (image.width, image.height) != (self.width, self.height) {
            return Err(Error::SizeMismatch {
                expected: (self.width, self.height),
                found: (image.width, image.height),
            });
        }
        let threshold = options.threshold / options.scale;
        let knee = options.knee;
        let luminance = Luminance::of(image);
        let pixels = image.width * image.height;
        // Counted row by row without a plane of fractions (with every pixel
        // fully spread, threshold 0, none is needed), with what splatting
        // the bright pixels would cost.
        let (w, h) = (image.width, image.height);
        let (kw, kh) = (self.kernel.width(), self.kernel.height());
        let (cx, cy) = self.kernel.centre();
        let counts = (0..h)
            .into_par_iter()
            .map(|y| {
                let mut row = Counts::default();
                for x in 0..w {
                    let y_lum = f64::from(luminance.at(y * w + x));
                    let f = spread_fraction(y_lum, threshold, knee);
                    if f > 0.0 {
                        let b = y_lum * f64::from(f);
                        row.squares += b * b;
                        row.spread += 1;
                        row.full += usize::from(f == 1.0);
                        row.splat_area += covered(x, kw, cx, w);
                    }
                }
                row.splat_area *= covered(y, kh, cy, h);
                row
            })
            .collect::<Vec<Counts>>()
            .into_iter()
            // In row order: the same sums with any number of threads.
            .fold(Counts::default(), Counts::add);
        let spread_pixels = counts.spread;
        let energy_in = image.total_luminance();

        let method = match options.method {
            Method::Auto if self.splat_cost(image, counts.splat_area) < self.fft_cost(image) => {
                Method::Splat
            }
            Method::Auto => Method::Fft,
            chosen => chosen,
        };
        let mut output = image.clone_without_planes();
        let double = spread_pixels > 0
            && method == Method::Fft
            && self.beyond_f32(image, &luminance, counts.squares);
        if spread_pixels > 0 && method == Method::Splat {
            output.planes = self.splat(image, &luminance, threshold, knee, recycled);
        } else if double {
            output.planes = self.spread_double(image, &luminance, threshold, knee);
        } else if spread_pixels == 0 {
            output.planes = copies(&image.planes, recycled);
        } else if counts.full == pixels {
            // Every plane is its own bright part and nothing stays.
            let planes: Vec<&[f32]> = image.planes.iter().map(Vec::as_slice).collect();
            output.planes = self.spread(&planes, None, image.layout, recycled, progress);
        } else {
            let fractions: Vec<f32> = (0..pixels)
                .into_par_iter()
                .map(|i| spread_fraction(f64::from(luminance.at(i)), threshold, knee))
                .collect();
            let planes: Vec<&[f32]> = image.planes.iter().map(Vec::as_slice).collect();
            output.planes =
                self.spread(&planes, Some(&fractions), image.layout, recycled, progress);
        }
        progress(1.0);
        let energy_out = output.total_luminance();
        if options.glare_only {
            for (out, input) in output.planes.iter_mut().zip(&image.planes) {
                out.par_iter_mut().zip(input).for_each(|(o, i)| *o -= i);
            }
        }
        Ok(Applied {
            image: output,
            energy_in,
            energy_out,
            spread_pixels,
            method,
            double,
        })
    }

    /// Whether f32 FFT round-off would show in the dark pixels: its
    /// expected size ([`f32_round_off`]) must stay below [`DARK_TOLERANCE`]
    /// of the dark level, the 1st percentile of the positive luminances
    /// (sampled); `squares` is ‖B‖₂².
    fn beyond_f32(&self, image: &Image, luminance: &Luminance, squares: f64) -> bool {
        let pixels = image.width * image.height;
        let stride = (pixels / 65536).max(1);
        let mut sample: Vec<f32> = (0..pixels)
            .step_by(stride)
            .map(|i| luminance.at(i))
            .filter(|&y| y > 0.0)
            .collect();
        if sample.is_empty() {
            return false;
        }
        let at = sample.len() / 100;
        let (_, dark, _) = sample.select_nth_unstable_by(at, f32::total_cmp);
        let moved = 1.0 - self.centres.iter().copied().fold(1.0f32, f32::min);
        let noise = f32_round_off(
            squares.sqrt(),
            f64::from(moved),
            self.convolver.padded_size(),
        );
        noise > DARK_TOLERANCE * f64::from(*dark)
    }

    /// [`Plan::spread`] in f64 for every bright pixel: O = I − B + c·B + K′ ⊛ B
    /// per plane (K′ the kernel less its centre weight c).
    fn spread_double(
        &self,
        image: &Image,
        luminance: &Luminance,
        threshold: f64,
        knee: f64,
    ) -> Vec<Vec<f32>> {
        let double = self
            .double
            .get_or_init(|| DoubleConvolver::without_centre(&self.kernel, self.width, self.height));
        let fractions: Vec<f64> = (0..image.width * image.height)
            .into_par_iter()
            .map(|i| f64::from(spread_fraction(f64::from(luminance.at(i)), threshold, knee)))
            .collect();
        let kernels = self.centres.len();
        image
            .planes
            .iter()
            .enumerate()
            .map(|(c, plane)| {
                let bright: Vec<f64> = plane
                    .par_iter()
                    .zip(&fractions)
                    .map(|(&v, f)| f64::from(v) * f)
                    .collect();
                let mut out: Vec<f64> = plane
                    .par_iter()
                    .zip(&bright)
                    .map(|(&v, b)| f64::from(v) - b)
                    .collect();
                for (k, weight) in terms(image.layout, kernels, c) {
                    let spread = double.convolve(&bright, k);
                    let (weight, centre) = (f64::from(weight), f64::from(self.centres[k]));
                    out.par_iter_mut()
                        .zip(&spread)
                        .zip(&bright)
                        .for_each(|((o, s), b)| *o += weight * (s + centre * b));
                }
                out.into_iter().map(|v| v as f32).collect()
            })
            .collect()
    }

    /// How many convolutions an image of `layout` takes.
    fn convolutions(&self, layout: Layout) -> usize {
        match layout {
            Layout::Rgb => 3,
            Layout::Luminance => self.convolver.channels(),
        }
    }

    /// Nanoseconds the FFT route takes for `image`, estimated from the
    /// transforms' n·log₂n count plus the passes over the planes around them
    /// (fitted to runs at 4K with full-frame and 401×401 kernels on two
    /// cores: `cargo run --release --example crossover`).
    fn fft_cost(&self, image: &Image) -> f64 {
        let (px, py) = self.convolver.padded_size();
        let n_log = |n: usize| n as f64 * (n as f64).log2();
        let h = image.height as f64;
        let columns = (px / 2 + 1) as f64;
        let per_plane = 2.0 * h * n_log(px) + 2.0 * columns * n_log(py);
        let pixels = (image.width * image.height) as f64;
        (0.04 * per_plane + 5.0 * pixels) * self.convolutions(image.layout) as f64
    }

    /// Nanoseconds splatting takes: every bright pixel adds the part of the
    /// kernel that falls inside the frame (`area` output pixels in all) to
    /// every output plane, after a pass over the planes (fitted likewise).
    fn splat_cost(&self, image: &Image, area: usize) -> f64 {
        let pixels = (image.width * image.height) as f64;
        // Kernel rows that stay in cache between bright pixels add faster.
        let per_add = if self.kernel.width() * self.kernel.height() <= 1 << 20 {
            0.055
        } else {
            0.19
        };
        (per_add * area as f64 + 2.0 * pixels) * self.convolutions(image.layout) as f64
    }

    /// O = I − B + Σ over bright pixels of B·K, row by row (each output row
    /// adds the bright pixels in a fixed order: the same bits with any
    /// number of threads).
    fn splat(
        &self,
        image: &Image,
        luminance: &Luminance,
        threshold: f64,
        knee: f64,
        recycled: Vec<Vec<f32>>,
    ) -> Vec<Vec<f32>> {
        let (w, h) = (image.width, image.height);
        let (kw, kh) = (self.kernel.width(), self.kernel.height());
        let (cx, cy) = self.kernel.centre();
        let kernels = self.kernel.channels();
        // Bright pixels: position and spread fraction, in row-major order.
        let rows: Vec<Vec<(usize, usize, f32)>> = (0..h)
            .into_par_iter()
            .map(|y| {
                (0..w)
                    .filter_map(|x| {
                        let f =
                            spread_fraction(f64::from(luminance.at(y * w + x)), threshold, knee);
                        (f > 0.0).then_some((x, y, f))
                    })
                    .collect()
            })
            .collect();
        let bright: Vec<(usize, usize, f32)> = rows.iter().flatten().copied().collect();
        let terms: Vec<Vec<(usize, f32)>> = (0..image.planes.len())
            .map(|c| terms(image.layout, kernels.len(), c))
            .collect();
        let mut outputs = copies(&image.planes, recycled);
        for ((out, plane), terms) in outputs.iter_mut().zip(&image.planes).zip(&terms) {
            out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
                // The light that leaves: the bright part of this row.
                for &(x, by, f) in &rows[y] {
                    row[x] -= plane[by * w + x] * f;
                }
                for &(x, by, f) in &bright {
                    // Kernel row j lands on output row by + j − cy.
                    let Some(j) = (y + cy).checked_sub(by).filter(|&j| j < kh) else {
                        continue;
                    };
                    let value = plane[by * w + x] * f;
                    let first = x.saturating_sub(cx);
                    let last = (x + kw - cx).min(w);
                    if first >= last {
                        continue;
                    }
                    for &(k, weight) in terms {
                        let start = first + cx - x;
                        let kernel = &kernels[k][j * kw + start..j * kw + start + (last - first)];
                        let v = value * weight;
                        for (o, &kv) in row[first..last].iter_mut().zip(kernel) {
                            *o += v * kv;
                        }
                    }
                }
            });
        }
        outputs
    }

    /// The bright planes through the kernel, its centre weight applied
    /// exactly. A coloured kernel spreads a luminance image as
    /// Y = Σ w_c K_c ⊛ Y.
    fn spread(
        &self,
        planes: &[&[f32]],
        fractions: Option<&[f32]>,
        layout: Layout,
        recycled: Vec<Vec<f32>>,
        progress: &mut dyn FnMut(f64),
    ) -> Vec<Vec<f32>> {
        let kernels = self.convolver.channels();
        match (layout, kernels) {
            (_, 1) | (Layout::Rgb, _) => {
                let inputs: Vec<Input> = planes
                    .iter()
                    .enumerate()
                    .map(|(c, plane)| {
                        let channel = c.min(kernels - 1);
                        Input {
                            plane,
                            fractions,
                            channel,
                            centre: self.centres[channel],
                        }
                    })
                    .collect();
                self.convolver.convolve_all(&inputs, recycled, progress)
            }
            (Layout::Luminance, _) => {
                // Three kernels over one plane: its bright part goes through
                // each, and what stays is added once.
                let plane = planes[0];
                let bright: Option<Vec<f32>> = fractions.map(|fractions| {
                    plane
                        .par_iter()
                        .zip(fractions)
                        .map(|(v, f)| v * f)
                        .collect()
                });
                let source = bright.as_deref().unwrap_or(plane);
                let inputs: Vec<Input> = (0..kernels)
                    .map(|channel| Input {
                        plane: source,
                        fractions: None,
                        channel,
                        centre: self.centres[channel],
                    })
                    .collect();
                let mut parts = self.convolver.convolve_all(&inputs, recycled, progress);
                let mut sum = parts.remove(0);
                sum.par_iter_mut().for_each(|s| *s *= REC709_LUMINANCE[0]);
                for (part, weight) in parts.iter().zip(&REC709_LUMINANCE[1..]) {
                    sum.par_iter_mut()
                        .zip(part)
                        .for_each(|(s, p)| *s += weight * p);
                }
                if let Some(bright) = &bright {
                    sum.par_iter_mut()
                        .zip(plane)
                        .zip(bright)
                        .for_each(|((s, v), b)| *s += v - b);
                }
                vec![sum]
            }
        }
    }
}

/// The share of the dark level the round-off may reach before f64 is used:
/// a tenth of the 1 % that a user could see.
const DARK_TOLERANCE: f64 = 1e-3;

/// The round-off an f32 FFT convolution leaves in a pixel, as an upper
/// estimate: per pixel about u·√(log₂ N)·‖B‖₂·m/√N for N padded samples,
/// bright part B (‖·‖₂ over the image) and moved mass m (the kernel less its
/// centre sums to m), u = 2⁻²⁴; times 4 to cover the largest pixel rather
/// than the typical one (checked against direct sums in tests/apply.rs).
pub fn f32_round_off(bright_l2: f64, moved: f64, padded: (usize, usize)) -> f64 {
    let n = (padded.0 * padded.1) as f64;
    4.0 * f64::from(f32::EPSILON) / 2.0 * n.log2().sqrt() * bright_l2 * moved / n.sqrt()
}

/// What the pass over the luminance finds.
#[derive(Debug, Clone, Copy, Default)]
struct Counts {
    /// Pixels with some light spread.
    spread: usize,
    /// Pixels with all their light spread.
    full: usize,
    /// Σ of the squared spread luminance: ‖B‖₂², for the round-off estimate.
    squares: f64,
    /// Σ over spread pixels of the output pixels their kernel reaches (the
    /// kernel's reach is a rectangle: row sums of its widths times its
    /// height on that row).
    splat_area: usize,
}

impl Counts {
    fn add(self, other: Counts) -> Counts {
        Counts {
            spread: self.spread + other.spread,
            full: self.full + other.full,
            squares: self.squares + other.squares,
            splat_area: self.splat_area + other.splat_area,
        }
    }
}

/// Output plane `c` of an image of `layout` as Σ weight · (kernel channel
/// k ⊛ plane c), over `kernels` channels: a coloured kernel spreads a
/// luminance plane as Y = Σ w_k K_k ⊛ Y, otherwise each plane goes through
/// its own channel (or the one channel).
fn terms(layout: Layout, kernels: usize, c: usize) -> Vec<(usize, f32)> {
    match (layout, kernels) {
        (Layout::Luminance, k) if k > 1 => REC709_LUMINANCE.iter().copied().enumerate().collect(),
        (_, k) => vec![(c.min(k - 1), 1.0)],
    }
}

/// How many of the `n` output positions p + i − c, for kernel indices i in
/// [0, k), fall inside [0, n): a kernel's reach from p along one axis.
fn covered(p: usize, k: usize, c: usize, n: usize) -> usize {
    (p + k - c).min(n).saturating_sub(p.saturating_sub(c))
}

/// `planes` copied into the planes of `recycled` (resized to match).
fn copies(planes: &[Vec<f32>], mut recycled: Vec<Vec<f32>>) -> Vec<Vec<f32>> {
    recycled.truncate(planes.len());
    recycled.resize_with(planes.len(), Vec::new);
    for (out, plane) in recycled.iter_mut().zip(planes) {
        out.clear();
        out.extend_from_slice(plane);
    }
    recycled
}

/// The fraction of a pixel's light that is spread, from its luminance `y`
/// (file units): 0 at or below the threshold, 1 above it, or a smoothstep
/// from T to T·(1 + knee).
pub fn spread_fraction(y: f64, threshold: f64, knee: f64) -> f32 {
    if y <= threshold {
        return 0.0;
    }
    let width = knee * threshold;
    if width <= 0.0 || y >= threshold + width {
        return 1.0;
    }
    let t = (y - threshold) / width;
    (t * t * (3.0 - 2.0 * t)) as f32
}

/// Per-pixel luminance of an image, computed where it is needed rather
/// than kept as a plane.
enum Luminance<'a> {
    Rgb([f32; 3], [&'a [f32]; 3]),
    Plane(&'a [f32]),
}

impl<'a> Luminance<'a> {
    fn of(image: &'a Image) -> Luminance<'a> {
        match (image.layout, image.planes.as_slice()) {
            (Layout::Rgb, [r, g, b]) => Luminance::Rgb(image.luminance_weights(), [r, g, b]),
            _ => Luminance::Plane(&image.planes[0]),
        }
    }

    /// The same value as [`Image::luminance`] gives for pixel `i`.
    fn at(&self, i: usize) -> f32 {
        match self {
            Luminance::Rgb([wr, wg, wb], [r, g, b]) => wr * r[i] + wg * g[i] + wb * b[i],
            Luminance::Plane(y) => y[i],
        }
    }
}
