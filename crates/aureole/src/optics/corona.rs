//! Corona: star rays around bright lights (paper Eq. 7, docs/physics.md §4).
//!
//! f_c(r, φ) = C · l(r) · |cos(k (φ − φ₀) / 2)|^n(r), with
//! l(r) = exp(−σ r / l_m) and n(r) = −1 / ln(cos ω), ω = (r / w)^(s − 1);
//! n = 0 where ω ≥ π/2 (the isotropic core). Each ray m has its own length
//! l_m = l·(1 + j·ξ_m), and optionally its own width and intensity, drawn from
//! one seed.

use std::f64::consts::{FRAC_1_SQRT_2, FRAC_PI_2, TAU};

use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use serde::{Deserialize, Serialize};

use crate::schema::{length, Default, Kind, Parameter, EPSILON};

use super::shape::{self, Sample, SpreadShape, Supersampling, CHUNK_POINTS};
use super::whole::{self, Whole, Window};
use super::{Context, Model, Source};
use crate::check;
use crate::error::Result;
use crate::math;
use crate::units::Length;

/// The most rays a corona may have.
pub const MAX_RAYS: u32 = 1024;

/// Below this fraction of its start a ray carries no light worth resolving:
/// there its pixels are sampled once.
const FADED: f64 = 1e-9;

/// Where every ray has faded below this fraction of the brightest ray's
/// start, the kernel holds 0. The light beyond, e^(−x)(1 + x) of a ray's
/// with x = ln 10¹², is below 3·10⁻¹¹ of it, far under the f32 kernel's own
/// rounding (6·10⁻⁸), and computing it cost most of a corona's time.
const DARK: f64 = 1e-12;

/// −2 ln [`DARK`]: the lobe's exponent n (kδ/2)² beyond which it is dark.
/// A literal, since `dark_angle` runs at every point of a vector pass and
/// a logarithm is no `const fn`; a test holds it to DARK.
const DARK_LOBE: f64 = 55.262_042_231_857_1;

/// A jittered factor never goes below this fraction of its mean, so that a
/// ray's length, width and intensity stay positive.
const JITTER_FLOOR: f64 = 0.05;

/// Corona parameters, as in an `[[effect]]` table with `type = "corona"`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Corona {
    /// ε: fraction of the light that goes into the rays, 0…1.
    pub epsilon: f64,
    /// k: number of rays (a stop with n blades makes n rays for even n, 2n
    /// for odd n).
    pub rays: u32,
    /// l: mean ray length, the distance over which a ray fades by e^−σ.
    pub length: Length,
    /// σ: fade-out along the ray, > 0.
    #[serde(default = "one")]
    pub fadeout: f64,
    /// w: ray width parameter.
    #[serde(default = "three_px")]
    pub width: Length,
    /// s: spread. 0: constant width; < 0: rays converge; > 0: they diverge;
    /// 1: constant angular width (w has no effect).
    #[serde(default = "one")]
    pub spread: f64,
    /// Relative standard deviation of each ray's length (0.25 in the paper).
    #[serde(default = "quarter")]
    pub length_jitter: f64,
    /// Relative standard deviation of each ray's width.
    #[serde(default)]
    pub width_jitter: f64,
    /// Relative standard deviation of each ray's intensity.
    #[serde(default)]
    pub intensity_jitter: f64,
    /// φ₀: direction of the first ray, degrees counter-clockwise from the +x
    /// axis (to the right on the displayed image).
    #[serde(default)]
    pub rotation_deg: f64,
}

fn one() -> f64 {
    1.0
}
fn quarter() -> f64 {
    0.25
}
fn three_px() -> Length {
    Length::px(3.0)
}

/// The random factors of one ray: its length, width and intensity relative
/// to the corona's mean values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayFactors {
    /// l_m / l.
    pub length: f64,
    /// w_m / w.
    pub width: f64,
    /// Relative intensity of the ray.
    pub intensity: f64,
}

const RAYS: Parameter = Parameter {
    name: "rays",
    kind: Kind::Whole,
    low: Some((1.0, true)),
    high: Some((MAX_RAYS as f64, true)),
    default: Default::Required,
    unit: "",
    allowed: "a whole number of rays from 1 to 1024",
    about: "k: a stop of n blades gives n rays when n is even, 2n when odd",
};

const LENGTH: Parameter = length("length", Default::Required, "l: the mean ray length");

const FADEOUT: Parameter = Parameter {
    name: "fadeout",
    kind: Kind::Number,
    low: Some((0.0, false)),
    high: None,
    default: Default::Number(1.0),
    unit: "",
    allowed: "a number above 0 (without fade-out a ray carries infinite energy)",
    about: "σ: a ray fades by e^-σ over its length",
};

const WIDTH: Parameter = length("width", Default::Length("3px"), "w: a ray's width");

const SPREAD: Parameter = Parameter {
    name: "spread",
    kind: Kind::Number,
    low: Some((-10.0, true)),
    high: Some((10.0, true)),
    default: Default::Number(1.0),
    unit: "",
    allowed: "a number from -10 to 10",
    about: "s: 0 rays of constant width, < 0 converging, > 0 diverging",
};

const fn jitter(name: &'static str, default: f64, about: &'static str) -> Parameter {
    Parameter {
        name,
        kind: Kind::Number,
        low: Some((0.0, true)),
        high: Some((1.0, true)),
        default: Default::Number(default),
        unit: "",
        allowed: "a relative deviation from 0 to 1",
        about,
    }
}

const LENGTH_JITTER: Parameter = jitter(
    "length_jitter",
    0.25,
    "each ray's length varies by this, relative",
);
const WIDTH_JITTER: Parameter = jitter(
    "width_jitter",
    0.0,
    "each ray's width varies by this, relative",
);
const INTENSITY_JITTER: Parameter = jitter(
    "intensity_jitter",
    0.0,
    "each ray's brightness varies by this, relative",
);
const ROTATION: Parameter = crate::schema::angle(
    "rotation_deg",
    "the first ray's angle, counter-clockwise from +x",
);

impl Model for Corona {
    const KIND: &'static str = "corona";
    const PARAMETERS: &'static [Parameter] = &[
        EPSILON,
        RAYS,
        LENGTH,
        FADEOUT,
        WIDTH,
        SPREAD,
        LENGTH_JITTER,
        WIDTH_JITTER,
        INTENSITY_JITTER,
        ROTATION,
    ];

    fn scale_pixels(&mut self, factor: f64) {
        self.length = self.length.scaled_px(factor);
        self.width = self.width.scaled_px(factor);
    }

    /// Checks every parameter's range.
    fn validate(&self) -> Result<()> {
        const NAME: &str = "corona";
        EPSILON.check(NAME, self.epsilon)?;
        check::count(
            NAME,
            RAYS.name,
            self.rays,
            RAYS.admits(f64::from(self.rays)),
            RAYS.allowed,
        )?;
        FADEOUT.check(NAME, self.fadeout)?;
        SPREAD.check(NAME, self.spread)?;
        LENGTH_JITTER.check(NAME, self.length_jitter)?;
        WIDTH_JITTER.check(NAME, self.width_jitter)?;
        INTENSITY_JITTER.check(NAME, self.intensity_jitter)?;
        ROTATION.check(NAME, self.rotation_deg)
    }

    fn source(&self, context: &Context) -> Result<Source> {
        Ok(Source::Shape(
            self.epsilon,
            Box::new(self.shape(context.pitch_mm, context.seed, context.index_of_kind)?),
        ))
    }

    /// Beyond its dark radius the kernel holds exactly 0.
    fn reach_px(&self, context: &Context) -> Option<f64> {
        self.shape(context.pitch_mm, context.seed, context.index_of_kind)
            .ok()
            .map(|shape| shape.dark_radius)
    }
}

impl Corona {
    /// Each ray's random factors, ray 0 first (ray m points at
    /// φ₀ + 2πm/k). The same `seed` and `corona_index` (the number of coronas
    /// before this one in the chain) give the same factors on every machine.
    pub fn ray_factors(&self, seed: u64, corona_index: usize) -> Vec<RayFactors> {
        let mut rng = Pcg64::seed_from_u64(super::stream(seed, corona_index));
        let jittered = |jitter: f64, xi: f64| (1.0 + jitter * xi).max(JITTER_FLOOR);
        (0..self.rays)
            .map(|_| {
                // All three deviates are drawn for every ray, so that turning
                // one jitter on leaves the other factors as they were.
                let (xl, xw, xi) = (
                    standard_normal(&mut rng),
                    standard_normal(&mut rng),
                    standard_normal(&mut rng),
                );
                RayFactors {
                    length: jittered(self.length_jitter, xl),
                    width: jittered(self.width_jitter, xw),
                    intensity: jittered(self.intensity_jitter, xi),
                }
            })
            .collect()
    }

    fn shape(&self, pitch_mm: Option<f64>, seed: u64, corona_index: usize) -> Result<CoronaShape> {
        self.validate()?;
        let length = self.length.to_px(pitch_mm, "corona length")?;
        let width = self.width.to_px(pitch_mm, "corona width")?;
        let rotation = self.rotation_deg.to_radians().rem_euclid(TAU);
        let period = TAU / f64::from(self.rays);
        let rays = self
            .ray_factors(seed, corona_index)
            .into_iter()
            .enumerate()
            .map(|(m, f)| {
                let fade_per_px = self.fadeout / (length * f.length);
                let axis = rotation + m as f64 * period;
                Ray {
                    fade_per_px,
                    width: width * f.width,
                    intensity: f.intensity,
                    // Along the ray, l(r) changes by a factor e^(σ/l_m)
                    // per pixel.
                    along: ((6.5 * fade_per_px).ceil() as u32).clamp(1, 64),
                    // A diagonal ray counts as horizontal whichever way
                    // its cosine and sine round, so that mirror images
                    // are sampled alike.
                    horizontal: libm::fabs(libm::cos(axis)) >= libm::fabs(libm::sin(axis)) - 1e-12,
                }
            })
            .collect::<Vec<Ray>>();
        let slowest_fade = rays
            .iter()
            .map(|r| r.fade_per_px)
            .fold(f64::INFINITY, f64::min);
        let brightest = rays.iter().map(|r| r.intensity).fold(0.0, f64::max);
        // f ≤ brightest·e^(−σr/l) since the lobe is at most 1; √2/2 is the
        // pixel's half diagonal.
        let dark_radius = -libm::log(DARK) / slowest_fade + FRAC_1_SQRT_2;
        let mut shape = CoronaShape {
            slowest_fade,
            brightest,
            widest: rays.iter().map(|r| r.width).fold(0.0, f64::max),
            narrowest: rays.iter().map(|r| r.width).fold(f64::INFINITY, f64::min),
            k: f64::from(self.rays),
            rotation,
            spread: self.spread,
            unit_spread_exponent: 1.0 / math::neg_ln_cos(1.0),
            dark_radius,
            lobes_never_dark: false,
            faded_radius: (libm::log(brightest) - libm::log(FADED)) / slowest_fade,
            fades: side_by_side(&rays, |r| r.fade_per_px),
            widths: side_by_side(&rays, |r| r.width),
            intensities: side_by_side(&rays, |r| r.intensity),
            rays,
        };
        // The dark angle is least at infinite radius.
        shape.lobes_never_dark = shape.spread == 1.0
            && shape.dark_angle(shape.unit_spread_exponent, f64::INFINITY) >= 0.5 * TAU / shape.k;
        Ok(shape)
    }
}

/// One quantity of every ray, ray 0 again at the end.
fn side_by_side(rays: &[Ray], quantity: impl Fn(&Ray) -> f64) -> Vec<f64> {
    rays.iter().chain(rays.first()).map(quantity).collect()
}

/// A standard normal deviate by Box–Muller, with libm so that every
/// platform computes the same bits.
fn standard_normal(rng: &mut Pcg64) -> f64 {
    let unit = |bits: u64| (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    let u1 = 1.0 - unit(rng.next_u64()); // (0, 1]: the logarithm stays finite
    let u2 = unit(rng.next_u64());
    libm::sqrt(-2.0 * libm::log(u1)) * libm::cos(TAU * u2)
}

struct Ray {
    /// σ / l_m in px⁻¹.
    fade_per_px: f64,
    /// w_m in px.
    width: f64,
    intensity: f64,
    /// Samples along the ray that a pixel needs for its fade.
    along: u32,
    /// Whether the ray's axis is nearer the x axis than the y axis.
    horizontal: bool,
}

struct CoronaShape {
    /// The slowest fade of any ray, σ / max l_m, in px⁻¹.
    slowest_fade: f64,
    /// The largest ray intensity.
    brightest: f64,
    /// The widest and the narrowest ray, in px.
    widest: f64,
    narrowest: f64,
    k: f64,
    /// φ₀ in [0, 2π).
    rotation: f64,
    spread: f64,
    /// n for s = 1, the same at every radius and for every ray.
    unit_spread_exponent: f64,
    /// Beyond this distance (pixel centres, px) every sample of a pixel is
    /// below [`DARK`] of the brightest ray's start: the kernel holds 0.
    dark_radius: f64,
    /// Whether every direction may be lit at every radius: s = 1, where n
    /// stays too small for the lobes to fall below [`DARK`] between the rays.
    lobes_never_dark: bool,
    /// Where the brightest ray falls below [`FADED`] of its start.
    faded_radius: f64,
    rays: Vec<Ray>,
    /// The rays' σ / l_m, w_m and I_m side by side, ray 0 again at the end
    /// (the nearest ray to a direction just short of a full turn), for the
    /// vector passes of [`CoronaShape::chunk`].
    fades: Vec<f64>,
    widths: Vec<f64>,
    intensities: Vec<f64>,
}

/// What [`CoronaShape::chunk`] finds for a chunk of points.
struct Chunk {
    /// Distance from the centre, px.
    r: [f64; CHUNK_POINTS],
    /// Angle from the nearest ray's axis, in (−π/k, π/k].
    offset: [f64; CHUNK_POINTS],
    /// The nearest ray, an index of `fades`, `widths` and `intensities`.
    ray: [usize; CHUNK_POINTS],
    /// n of that ray there, and [`CoronaShape::spacing`] for it.
    n: [f64; CHUNK_POINTS],
    spacing: ([f64; CHUNK_POINTS], [f64; CHUNK_POINTS]),
    /// Whether `sample`'s dark test holds: the lobes leave the whole pixel
    /// below [`DARK`] of the brightest ray's start.
    dark: [bool; CHUNK_POINTS],
    /// f there.
    f: [f64; CHUNK_POINTS],
}

impl Chunk {
    fn new() -> Chunk {
        Chunk {
            r: [0.0; CHUNK_POINTS],
            offset: [0.0; CHUNK_POINTS],
            ray: [0; CHUNK_POINTS],
            n: [0.0; CHUNK_POINTS],
            spacing: ([0.0; CHUNK_POINTS], [0.0; CHUNK_POINTS]),
            dark: [false; CHUNK_POINTS],
            f: [0.0; CHUNK_POINTS],
        }
    }
}

/// 0, 1, 2, …: a row's offsets from its chunk's first point, read rather
/// than converted from the index, so that the loops take vectors.
const STEPS: [f64; CHUNK_POINTS] = {
    let mut steps = [0.0; CHUNK_POINTS];
    let mut i = 0;
    while i < CHUNK_POINTS {
        steps[i] = i as f64;
        i += 1;
    }
    steps
};

impl CoronaShape {
    /// The angle from a ray's axis beyond which a pixel centred at distance
    /// r (or more) from the centre is dark, for a least exponent n over its
    /// radii: there f < DARK·brightest, the bound `dark_radius` holds along
    /// the rays, here across them. |cos u| ≤ exp(−u²/2) for |u| ≤ π/2
    /// bounds the lobe by exp(−n (k δ/2)²/2), below DARK where
    /// n (k δ/2)² > −2 ln DARK, and f ≤ brightest × lobe. The pixel spans
    /// directions within asin(√2/2 / r) < 0.78/r of its centre's, found to
    /// 5·10⁻¹⁶ rad (3·10⁻⁵ rad to spare). Infinite where n = 0.
    fn dark_angle(&self, n: f64, r: f64) -> f64 {
        2.0 / self.k * (DARK_LOBE / n).sqrt() + 0.78 / r + 3e-5
    }

    /// The least exponent n of any ray at radii in [near, far]: ω = (r/w)^(s−1)
    /// and n = −1/ln cos ω falls as ω grows, so it is least at the widest ray
    /// (s < 1, at `near`) or the narrowest (s > 1, at `far`).
    fn least_exponent(&self, near: f64, far: f64) -> f64 {
        if self.spread > 1.0 {
            self.exponent(far, self.narrowest)
        } else {
            self.exponent(near.max(0.0), self.widest)
        }
    }

    /// The nearest ray to direction φ (relative to φ₀) and the angle from its
    /// axis, in (−π/k, π/k].
    fn nearest_ray(&self, phi: f64) -> (&Ray, f64) {
        let (index, offset) = self.axis(phi, self.rays.len());
        (self.ray(index), offset)
    }

    /// The nearest ray's index to direction φ (relative to φ₀), at most
    /// `last`, where ray k stands for ray 0, and the angle from its axis:
    /// without branches, so that [`CoronaShape::chunk`]'s pass over the
    /// points takes vectors.
    #[inline(always)]
    fn axis(&self, phi: f64, last: usize) -> (usize, f64) {
        let period = TAU / self.k;
        // φ ∈ [−π, π] and φ₀ ∈ [0, 2π): two turns at most bring u into
        // [0, 2π], without fmod's division.
        let mut u = phi - self.rotation;
        u = if u < 0.0 { u + TAU } else { u };
        u = if u < 0.0 { u + TAU } else { u };
        // u ≤ 2π: m ≤ k.
        let (m, whole) = math::nearest_and_whole(u / period);
        ((whole as usize).min(last), u - m * period)
    }

    /// Ray `index` of [`CoronaShape::axis`]: ray k is ray 0.
    fn ray(&self, index: usize) -> &Ray {
        self.rays.get(index).unwrap_or(&self.rays[0])
    }

    /// n(r) of docs/physics.md §4 for a ray of width `width`; 0 where ω ≥ π/2.
    #[inline(always)]
    fn exponent(&self, r: f64, width: f64) -> f64 {
        // The paper's cases s = 0 and s = 1 without a pow: millions of
        // samples near the rays need this.
        if self.spread == 1.0 {
            self.unit_spread_exponent
        } else if self.spread == 0.0 {
            exponent_of(width / r)
        } else {
            exponent_of(math::exp(math::ln(r / width) * (self.spread - 1.0)))
        }
    }

    /// The spans of `lit_spans` that the rays' angular lobes leave lit, or
    /// `None` where the lobes are too wide to bound.
    fn ray_spans(&self, y: f64) -> Option<Vec<(f64, f64)>> {
        // Every pixel of the row lies at r ≥ |y|. Where n grows with r
        // (s ≤ 1) the least exponent on the row is at |y| − √2/2, and the
        // bound of `sample`'s dark test then holds for every direction
        // farther than `reach` from a ray's axis.
        if self.spread > 1.0 || y.abs() < 2.0 {
            return None;
        }
        let n = self.least_exponent(y.abs() - FRAC_1_SQRT_2, y.abs());
        let reach = self.dark_angle(n, y.abs());
        let period = TAU / self.k;
        if reach >= 0.5 * period {
            return None;
        }
        // Directions on this row: (0, π) above the centre, (−π, 0) below;
        // x = y·cot φ runs monotonically over them.
        let (low, high) = if y > 0.0 {
            (0.0, std::f64::consts::PI)
        } else {
            (-std::f64::consts::PI, 0.0)
        };
        let x_at = |phi: f64| y * libm::cos(phi) / libm::sin(phi);
        let mut spans = Vec::new();
        for m in 0..self.rays.len() {
            let axis = (self.rotation + m as f64 * period).rem_euclid(TAU);
            for shift in [-TAU, 0.0] {
                let (a, b) = (axis + shift - reach, axis + shift + reach);
                if b <= low || a >= high {
                    continue;
                }
                let ends = [
                    if a <= low { None } else { Some(x_at(a)) },
                    if b >= high { None } else { Some(x_at(b)) },
                ];
                // Above the centre x falls as φ grows, below it rises.
                let (first, last) = if y > 0.0 {
                    (ends[1], ends[0])
                } else {
                    (ends[0], ends[1])
                };
                spans.push((
                    first.map_or(f64::NEG_INFINITY, |x| x - 1.0),
                    last.map_or(f64::INFINITY, |x| x + 1.0),
                ));
            }
        }
        Some(spans)
    }
}

impl SpreadShape for CoronaShape {
    fn whole(&self, _window: &Window) -> Whole {
        Whole::Plane(self.plane())
    }

    /// An even count of identical rays (no jitter drew them apart), one of
    /// them on a mirror axis of the frame (2φ₀ a whole number of periods
    /// 2π/k, to 10⁻⁹ of one): the rays are then their own mirror images
    /// across both axes.
    fn mirror_symmetric(&self) -> bool {
        let turns = 2.0 * self.rotation * self.k / TAU;
        let same = |a: &Ray, b: &Ray| {
            (a.fade_per_px, a.width, a.intensity) == (b.fade_per_px, b.width, b.intensity)
        };
        self.rays.len() % 2 == 0
            && (turns - libm::round(turns)).abs() < 1e-9
            && self
                .rays
                .first()
                .is_some_and(|first| self.rays.iter().all(|ray| same(ray, first)))
    }

    fn lit_spans(&self, y: f64) -> Option<Vec<(f64, f64)>> {
        if y.abs() > self.dark_radius {
            return Some(Vec::new());
        }
        // Pixel centres farther out than this are beyond `dark_radius`.
        let half = (self.dark_radius * self.dark_radius - y * y).sqrt();
        let Some(spans) = self.ray_spans(y) else {
            return Some(vec![(-half, half)]);
        };
        Some(
            spans
                .into_iter()
                .map(|(a, b)| (a.max(-half), b.min(half)))
                .filter(|(a, b)| a <= b)
                .collect(),
        )
    }

    fn density(&self, x: f64, y: f64) -> f64 {
        let r = (x * x + y * y).sqrt();
        let (ray, offset) = self.nearest_ray(math::atan2(y, x));
        self.value(ray, r, offset)
    }

    fn grid(&self, x: f64, y: f64) -> Supersampling {
        let r = (x * x + y * y).sqrt();
        if r < 2.0 {
            // Every ray meets here, within a pixel or two.
            return Supersampling::square(8);
        }
        let (ray, offset) = self.nearest_ray(math::atan2(y, x));
        self.grid_at(r, ray, offset)
    }

    fn sample(&self, x: f64, y: f64) -> Sample {
        let mut one = [Sample::Dark];
        self.sample_row(x, y, &mut one);
        one[0]
    }

    /// f in passes over the points, as [`CoronaShape::sample_row`]'s.
    fn density_at(&self, xs: &[f64], ys: &[f64], out: &mut [f64]) {
        let mut chunk = Chunk::new();
        shape::in_chunks(xs, ys, out, |xs, ys, out| {
            self.chunk(xs, ys, &mut chunk, false);
            out.copy_from_slice(&chunk.f[..out.len()]);
        });
    }

    /// The test, the grid and f from one pass over each chunk of the row
    /// ([`CoronaShape::chunk`]), then a pixel's answer from them.
    fn sample_row(&self, x0: f64, y: f64, out: &mut [Sample]) {
        let mut chunk = Chunk::new();
        let ys = [y; CHUNK_POINTS];
        for (c, samples) in out.chunks_mut(CHUNK_POINTS).enumerate() {
            let first = x0 + (c * CHUNK_POINTS) as f64;
            let mut xs = [0.0; CHUNK_POINTS];
            for (x, step) in xs.iter_mut().zip(&STEPS) {
                *x = first + step;
            }
            let n = samples.len();
            self.chunk(&xs[..n], &ys[..n], &mut chunk, !self.lobes_never_dark);
            for (i, sample) in samples.iter_mut().enumerate() {
                let r = chunk.r[i];
                *sample = if r > self.dark_radius {
                    Sample::Dark
                } else if r < 2.0 {
                    // Every ray meets here, within a pixel or two.
                    Sample::Grid(Supersampling::square(8))
                } else if chunk.dark[i] {
                    Sample::Dark
                } else {
                    let ray = self.ray(chunk.ray[i]);
                    let grid = self.grid_with(
                        r,
                        ray,
                        chunk.offset[i],
                        (chunk.spacing.0[i], chunk.spacing.1[i]),
                    );
                    if grid.x > 1 || grid.y > 1 {
                        Sample::Grid(grid)
                    } else {
                        Sample::One(chunk.f[i])
                    }
                }
            }
        }
    }
}

impl CoronaShape {
    /// Distance, nearest ray, n, the dark test (where `dark_test`) and f
    /// for the points (`xs`[i], `ys`[i]), at most [`CHUNK_POINTS`] of
    /// them: each a pass over the points without branches, in the CPU's
    /// widest vectors, with the same bits as [`SpreadShape::density`]'s
    /// and [`CoronaShape::nearest_ray`]'s scalar steps.
    fn chunk(&self, xs: &[f64], ys: &[f64], chunk: &mut Chunk, dark_test: bool) {
        crate::convolve::widest(
            #[inline(always)]
            || self.chunk_passes(xs, ys, chunk, dark_test),
        );
    }

    #[inline(always)]
    fn chunk_passes(&self, xs: &[f64], ys: &[f64], chunk: &mut Chunk, dark_test: bool) {
        let len = xs.len().min(CHUNK_POINTS);
        let (xs, ys) = (&xs[..len], &ys[..len]);
        let mut phi = [0.0; CHUNK_POINTS];
        for (((r, phi), &x), &y) in chunk.r.iter_mut().zip(&mut phi).zip(xs).zip(ys) {
            *r = (x * x + y * y).sqrt();
            *phi = math::atan2_plain(y, x);
        }
        // The axes and other points the plain arctangent leaves.
        for ((phi, &x), &y) in phi.iter_mut().zip(xs).zip(ys) {
            if !math::atan2_is_plain(y, x) {
                *phi = math::atan2(y, x);
            }
        }
        // Every index below `last` is in bounds, and the loops know it.
        let Some(last) = self.fades.len().checked_sub(1) else {
            return;
        };
        let (fades, widths, intensities) = (
            &self.fades[..=last],
            &self.widths[..=last],
            &self.intensities[..=last],
        );
        // In arrays of this frame's own, which the gathers from the rays'
        // quantities cannot alias: that lets the loop take vectors.
        let mut offsets = [0.0; CHUNK_POINTS];
        let mut rays = [0usize; CHUNK_POINTS];
        let (mut fade, mut width, mut intensity) = (
            [0.0; CHUNK_POINTS],
            [0.0; CHUNK_POINTS],
            [0.0; CHUNK_POINTS],
        );
        for (i, &phi) in phi[..len].iter().enumerate() {
            let (ray, offset) = self.axis(phi, last);
            offsets[i] = offset;
            rays[i] = ray;
            fade[i] = fades[ray];
            width[i] = widths[ray];
            intensity[i] = intensities[ray];
        }
        chunk.offset = offsets;
        chunk.ray = rays;
        let r = &chunk.r[..len];
        self.exponents(r, &width[..len], &mut chunk.n[..len]);
        let (ts, acrosses) = (&mut chunk.spacing.0, &mut chunk.spacing.1);
        for (((t, across), &r), &n) in ts.iter_mut().zip(acrosses).zip(r).zip(&chunk.n) {
            (*t, *across) = self.spacing(r, n);
        }
        if dark_test {
            // `least_exponent` over the pixel, then `dark_angle`.
            let (mut reach, mut least) = ([0.0; CHUNK_POINTS], [0.0; CHUNK_POINTS]);
            let (reach, least) = (&mut reach[..len], &mut least[..len]);
            let width = if self.spread > 1.0 {
                for (reach, &r) in reach.iter_mut().zip(r) {
                    *reach = r + FRAC_1_SQRT_2;
                }
                self.narrowest
            } else {
                for (reach, &r) in reach.iter_mut().zip(r) {
                    *reach = (r - FRAC_1_SQRT_2).max(0.0);
                }
                self.widest
            };
            self.exponents(reach, &[width; CHUNK_POINTS][..len], least);
            let lanes = chunk.dark.iter_mut().zip(least.iter()).zip(r);
            for (((dark, &n), &r), &offset) in lanes.zip(&chunk.offset) {
                *dark = offset.abs() > self.dark_angle(n, r);
            }
        } else {
            chunk.dark = [false; CHUNK_POINTS];
        }
        let terms = chunk.f[..len].iter_mut().zip(r).zip(&chunk.offset);
        let rays = fade.iter().zip(&intensity).zip(&chunk.n);
        for (((f, &r), &offset), ((&fade, &intensity), &n)) in terms.zip(rays) {
            // As `terms`, with n from its own pass.
            *f = Self::light([intensity, fade * r, n, 0.5 * self.k * offset]);
        }
    }

    /// [`CoronaShape::exponent`] at each r for each width, into `out`.
    #[inline(always)]
    fn exponents(&self, r: &[f64], width: &[f64], out: &mut [f64]) {
        for ((n, &r), &width) in out.iter_mut().zip(r).zip(width) {
            *n = self.exponent(r, width);
        }
    }
}

/// W(n) = ∫ cosⁿ u du over (−π/2, π/2) = √π Γ((n+1)/2) / Γ(n/2 + 1): π for
/// the isotropic core (n = 0), √(2π/n)(1 − 1/(4n) + 1/(32n²)) where the
/// Gammas' logarithms would lose the digits of their difference.
fn lobe(n: f64) -> f64 {
    if n.is_infinite() {
        0.0
    } else if n > 1e4 {
        (TAU / n).sqrt() * (1.0 - 0.25 / n + 1.0 / (32.0 * n * n))
    } else {
        std::f64::consts::PI.sqrt()
            * libm::exp(libm::lgamma(0.5 * (n + 1.0)) - libm::lgamma(0.5 * n + 1.0))
    }
}

/// n = −1/ln cos ω; 0 where ω ≥ π/2 (or NaN), ∞ where cos ω rounds to 1.
#[inline(always)]
fn exponent_of(omega: f64) -> f64 {
    let g = math::neg_ln_cos(omega);
    let n = if g <= 0.0 { f64::INFINITY } else { 1.0 / g };
    if omega >= FRAC_PI_2 || omega.is_nan() {
        0.0
    } else {
        n
    }
}

impl CoronaShape {
    /// ∫∫ f over the plane, ray by ray: a ray's lobe over its directions
    /// (−π/k, π/k] holds ∫ |cos(kδ/2)|ⁿ dδ = (2/k)·W(n) of each ring, and
    /// the rings fade as I·e^(−σr/l) r dr.
    fn plane(&self) -> f64 {
        // n(r) turns at the core's edge, where ω = (r/w)^(s−1) = π/2.
        let core = |width: f64| {
            if self.spread == 1.0 {
                f64::NAN
            } else {
                width * libm::pow(FRAC_PI_2, 1.0 / (self.spread - 1.0))
            }
        };
        self.rays
            .iter()
            .map(|ray| {
                let ring = |r: f64| {
                    r * math::exp(-ray.fade_per_px * r) * lobe(self.exponent(r, ray.width))
                };
                let scale = ray.width.min(1.0 / ray.fade_per_px);
                ray.intensity * 2.0 / self.k
                    * whole::radial_integral(ring, 0.0, scale, &[core(ray.width)])
            })
            .sum()
    }

    /// f at distance r from the centre and `offset` from the axis of its
    /// nearest ray `ray`.
    fn value(&self, ray: &Ray, r: f64, offset: f64) -> f64 {
        Self::light(self.terms(ray, r, offset))
    }

    /// What f at distance r and `offset` from `ray`'s axis is made of:
    /// I_m, σr/l_m, n and kδ/2.
    fn terms(&self, ray: &Ray, r: f64, offset: f64) -> [f64; 4] {
        [
            ray.intensity,
            ray.fade_per_px * r,
            self.exponent(r, ray.width),
            0.5 * self.k * offset,
        ]
    }

    /// I·|cos(kδ/2)|^n·e^(−σr/l) from [`CoronaShape::terms`], as one
    /// exponential; the lobe is 1 in the isotropic core (n = 0).
    /// Both sides of the core's test computed and one chosen, so that
    /// rows of it take vectors.
    #[inline(always)]
    fn light([intensity, fade, n, half_angle]: [f64; 4]) -> f64 {
        let lobe = n * math::neg_ln_cos(half_angle);
        let lobe = if n == 0.0 { 0.0 } else { lobe };
        intensity * math::exp(-fade - lobe)
    }

    /// The grid of the pixel at distance r ≥ 2 from the centre and `offset`
    /// from the axis of its nearest ray `ray`.
    fn grid_at(&self, r: f64, ray: &Ray, offset: f64) -> Supersampling {
        self.grid_with(r, ray, offset, self.spacing(r, self.exponent(r, ray.width)))
    }

    /// Across a ray, |cos(kδ/2)|^n ≈ exp(−n k² δ²/8): a Gaussian of
    /// standard deviation t = 2r / (k √n) pixels across the ray (n at
    /// least 1). A spacing of t/6.5 keeps the midpoint rule within 10⁻³ of
    /// the pixel's mean (and sums the profile far better): t, and the
    /// samples across a pixel that this asks for, 1 to 64.
    #[inline(always)]
    fn spacing(&self, r: f64, n: f64) -> (f64, f64) {
        let t = 2.0 * r / (self.k * n.max(1.0).sqrt());
        let across = if t.is_finite() && t > 0.0 {
            (6.5 / t).ceil().clamp(1.0, 64.0)
        } else {
            64.0
        };
        (t, across)
    }

    /// [`CoronaShape::grid_at`] given [`CoronaShape::spacing`] there.
    fn grid_with(&self, r: f64, ray: &Ray, offset: f64, (t, across): (f64, f64)) -> Supersampling {
        // The same test as exp(−σr/l)·brightest < FADED, its exp taken
        // only within a hair of the radius where it turns.
        let faded = if (r - self.faded_radius).abs() > 1e-6 * self.faded_radius {
            r > self.faded_radius
        } else {
            libm::exp(-self.slowest_fade * r) * self.brightest < FADED
        };
        if faded {
            return Supersampling::square(1);
        }
        let along = ray.along;
        let across = if self.farther_than(r, offset, 0.75 + 6.0 * t) {
            1
        } else {
            across as u32
        };
        if across <= along {
            return Supersampling::square(along);
        }
        // A thin ray needs fine steps only across itself: along the pixel
        // axis nearer its normal (a step there moves at least 1/√2 of it
        // across the ray), while each line of samples along the other axis
        // still crosses the whole profile.
        let fine = ((f64::from(across) * std::f64::consts::SQRT_2).ceil() as u32).min(96);
        let coarse = along.max(2);
        if ray.horizontal {
            Supersampling { x: coarse, y: fine }
        } else {
            Supersampling { x: fine, y: coarse }
        }
    }

    /// Whether a point at distance r and `offset` from a ray's axis lies
    /// farther than `limit` from it, r·|sin δ| > limit: decided by the
    /// bounds |δ|(1 − δ²/6) ≤ |sin δ| ≤ |δ| where they settle it, which
    /// is almost everywhere, by the sine where they do not.
    fn farther_than(&self, r: f64, offset: f64, limit: f64) -> bool {
        let d = offset.abs();
        if r * d <= limit {
            false
        } else if r * (d * (1.0 - d * d / 6.0)) > limit {
            true
        } else {
            r * libm::fabs(libm::sin(offset)) > limit
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::shape::assert_rows_agree;

    /// f is 0, or below [`DARK`] of the brightest ray's start, at 5×5
    /// points over the pixel centred at (x, y), its corners and edges
    /// included.
    fn assert_dark(shape: &CoronaShape, x: f64, y: f64, spread: f64) {
        for a in 0..=4 {
            for b in 0..=4 {
                let (sx, sy) = (x - 0.5 + 0.25 * f64::from(b), y - 0.5 + 0.25 * f64::from(a));
                let f = shape.density(sx, sy);
                assert!(
                    f <= DARK * shape.brightest,
                    "s = {spread} at ({sx}, {sy}): {f}"
                );
            }
        }
    }

    #[test]
    fn the_lobes_dark_exponent_is_that_of_dark() {
        let derived = -2.0 * libm::log(DARK);
        assert!(
            (DARK_LOBE - derived).abs() <= 1e-14 * derived,
            "{DARK_LOBE} {derived}"
        );
    }

    #[test]
    fn a_short_corona_is_dark_beyond_its_dark_radius_and_loses_no_light_there() {
        let c = Corona {
            length: Length::px(3.0),
            intensity_jitter: 0.5,
            ..corona()
        };
        let shape = c.shape(None, 5, 0).unwrap();
        let (mut kept, mut dropped, mut dark) = (0.0, 0.0, 0);
        for j in -400..=400 {
            let y = f64::from(j);
            let spans = shape.lit_spans(y).unwrap();
            for i in -400..=400 {
                let x = f64::from(i);
                let f = shape.density(x, y);
                if spans.iter().any(|&(a, b)| a <= x && x <= b) {
                    kept += f;
                } else {
                    dark += 1;
                    dropped += f;
                    assert_dark(&shape, x, y, c.spread);
                }
            }
        }
        assert!(dark > 400_000, "{dark}");
        assert!(dropped < 1e-10 * kept, "{dropped} of {kept}");
    }

    #[test]
    fn pixels_outside_a_rows_lit_spans_are_zero_everywhere() {
        for (spread, rotation_deg) in [(-0.5, 0.0), (0.0, 7.0), (0.5, 90.0), (1.0, 3.0)] {
            let c = Corona {
                spread,
                rotation_deg,
                width_jitter: 0.3,
                length: Length::px(400.0),
                ..corona()
            };
            let shape = c.shape(None, 3, 0).unwrap();
            let mut dark = 0;
            for j in -300..300 {
                let y = f64::from(j);
                let Some(spans) = shape.lit_spans(y) else {
                    continue;
                };
                for i in -300..300 {
                    let x = f64::from(i);
                    if spans.iter().any(|&(a, b)| a <= x && x <= b) {
                        continue;
                    }
                    dark += 1;
                    assert_dark(&shape, x, y, spread);
                }
            }
            if spread <= 0.0 {
                assert!(dark > 100_000, "s = {spread}: {dark}");
            }
        }
    }

    #[test]
    fn a_pixel_said_to_be_dark_is_zero_everywhere() {
        for spread in [-0.5, 0.0, 0.5, 1.5] {
            let c = Corona {
                spread,
                width_jitter: 0.3,
                length: Length::px(400.0),
                ..corona()
            };
            let shape = c.shape(None, 3, 0).unwrap();
            let mut vanished = 0;
            for j in -150..150 {
                for i in -150..150 {
                    let (x, y) = (f64::from(i) + 0.37, f64::from(j) * 1.01);
                    if shape.sample(x, y) != Sample::Dark {
                        continue;
                    }
                    vanished += 1;
                    assert_dark(&shape, x, y, spread);
                }
            }
            // Thin rays (s ≤ 0) leave most of the plane dark.
            if spread <= 0.0 {
                assert!(vanished > 10_000, "s = {spread}: {vanished}");
            }
        }
    }

    #[test]
    fn a_rows_samples_are_what_the_test_the_grid_and_the_density_give() {
        for (spread, width_jitter, rays) in [
            (-0.5, 0.3, 14),
            (0.0, 0.0, 6),
            (0.5, 0.3, 7),
            (1.0, 0.0, 14),
            (1.0, 0.2, 3),
            (1.5, 0.3, 8),
        ] {
            let c = Corona {
                spread,
                rays,
                width_jitter,
                intensity_jitter: 0.3,
                rotation_deg: 200.0,
                length: Length::px(60.0),
                ..corona()
            };
            let shape = c.shape(None, 9, 0).unwrap();
            // Rows between pixel centres, and along and across the axes,
            // where the arctangent is libm's.
            let rows = (-130..130)
                .map(|j| (-200.5, f64::from(j) + 0.5, 401))
                .chain([(-200.0, 0.0, 401), (0.0, 17.0, 3), (0.0, -3.0, 1)]);
            let [ones, grids, dark] =
                assert_rows_agree(&shape, rows, |x, y| assert_dark(&shape, x, y, spread));
            assert!(
                ones > 1000 && grids > 10,
                "s = {spread}: {ones} {grids} {dark}"
            );
            if spread <= 0.0 {
                assert!(dark > 10_000, "s = {spread}: {dark}");
            }
        }
    }

    fn corona() -> Corona {
        Corona {
            epsilon: 0.005,
            rays: 14,
            length: Length::px(15.6),
            fadeout: 1.0,
            width: Length::px(3.0),
            spread: 1.0,
            length_jitter: 0.25,
            width_jitter: 0.0,
            intensity_jitter: 0.0,
            rotation_deg: 0.0,
        }
    }

    #[test]
    fn ray_lengths_are_reproducible_and_seed_dependent() {
        let c = corona();
        assert_eq!(c.ray_factors(7, 0), c.ray_factors(7, 0));
        assert_ne!(c.ray_factors(7, 0), c.ray_factors(8, 0));
        assert_ne!(c.ray_factors(7, 0), c.ray_factors(7, 1));
    }

    #[test]
    fn ray_length_deviation_follows_the_jitter() {
        // Many rays: the sample mean and deviation of l_m/l are 1 and j.
        let c = Corona {
            rays: 1024,
            length_jitter: 0.2,
            ..corona()
        };
        let lengths: Vec<f64> = c.ray_factors(3, 0).iter().map(|f| f.length).collect();
        let mean = lengths.iter().sum::<f64>() / lengths.len() as f64;
        let var = lengths.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / lengths.len() as f64;
        assert!((mean - 1.0).abs() < 0.02, "mean {mean}");
        assert!((var.sqrt() - 0.2).abs() < 0.02, "deviation {}", var.sqrt());
    }

    #[test]
    fn jitter_off_gives_unit_factors() {
        let c = Corona {
            length_jitter: 0.0,
            ..corona()
        };
        for f in c.ray_factors(1, 0) {
            assert_eq!((f.length, f.width, f.intensity), (1.0, 1.0, 1.0));
        }
    }

    #[test]
    fn exponent_is_zero_in_the_core_and_grows_outside() {
        let shape = Corona {
            spread: 0.0,
            ..corona()
        }
        .shape(None, 1, 0)
        .unwrap();
        // s = 0: ω = w/r ≥ π/2 for r ≤ 2w/π.
        assert_eq!(shape.exponent(1.0, 3.0), 0.0);
        let (n10, n100) = (shape.exponent(10.0, 3.0), shape.exponent(100.0, 3.0));
        assert!(n10 > 0.0 && n100 > n10);
        // Far out, n ≈ 2/ω² = 2 r²/w².
        assert!((n100 / (2.0 * 100.0f64.powi(2) / 9.0) - 1.0).abs() < 1e-3);
    }
}
