//! The display path (docs/physics.md §9): no display shows 10⁵ cd/m², so
//! luminance is exposed, passed through a tone curve and sRGB-encoded.

use aureole::image::{Image, Layout, PixelLuminance};
use rayon::prelude::*;

/// How bright the picture is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Exposure {
    /// Metered on the lit scene, ignoring the light sources and a black
    /// sky, with its highlights protected ([`meter`]).
    Auto,
    /// Exposure value at ISO 100 (EV100): a camera at f/N and t seconds has
    /// EV = log₂(N²/t). The luminance shown as white is 1.2·2^EV cd/m²
    /// (ISO 2720 saturation).
    Ev(f64),
    /// The luminance in cd/m² shown as white.
    White(f64),
}

impl Exposure {
    /// The EV100 every front end accepts for a picture.
    pub const EV100: std::ops::RangeInclusive<f64> = -40.0..=40.0;

    /// `Ev(ev)` for an EV100 within [`Exposure::EV100`].
    pub fn ev100(ev: f64) -> Option<Exposure> {
        (ev.is_finite() && Exposure::EV100.contains(&ev)).then_some(Exposure::Ev(ev))
    }

    /// The one-line refusal of `value` as an exposure.
    pub fn refusal(value: impl std::fmt::Display) -> String {
        format!(
            "exposure {value} is not allowed: an EV100 from {} to {}, or \"auto\"",
            Exposure::EV100.start(),
            Exposure::EV100.end()
        )
    }

    /// The luminance (cd/m²) this exposure shows as white on `image`
    /// (`scale` cd/m² per unit) through `tone`.
    pub fn white(self, image: &Image, scale: f64, tone: ToneCurve) -> f64 {
        match self {
            Exposure::Auto => meter(image, scale).white(tone),
            Exposure::Ev(ev) => 1.2 * ev.exp2(),
            Exposure::White(white) => white,
        }
    }
}

/// The curve from exposed linear light (1 = white) to display light.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ToneCurve {
    /// Everything above white is clipped.
    Clip,
    /// Reinhard's extended operator, burning out at twice the white level.
    Reinhard,
    /// The ACES filmic fit of Narkowicz: soft shoulder, highlights desaturate.
    Filmic,
}

impl ToneCurve {
    /// Every curve, by the name each front end accepts.
    pub const NAMES: [(&'static str, ToneCurve); 3] = [
        ("filmic", ToneCurve::Filmic),
        ("reinhard", ToneCurve::Reinhard),
        ("clip", ToneCurve::Clip),
    ];

    /// The name the curve is given by.
    pub fn name(self) -> &'static str {
        ToneCurve::NAMES
            .iter()
            .find(|(_, curve)| *curve == self)
            .map_or("filmic", |(name, _)| name)
    }
}

impl std::str::FromStr for ToneCurve {
    type Err = String;

    /// The curve a name (`filmic`, `reinhard`, `clip`) names, or the
    /// one-line refusal listing them.
    fn from_str(name: &str) -> Result<ToneCurve, String> {
        ToneCurve::NAMES
            .iter()
            .find(|(known, _)| known.eq_ignore_ascii_case(name.trim()))
            .map(|(_, curve)| *curve)
            .ok_or_else(|| format!("tonemap {name:?} is not allowed: filmic, reinhard or clip"))
    }
}

impl std::str::FromStr for Exposure {
    type Err = String;

    /// `auto` or an EV100 within [`Exposure::EV100`], or the one-line
    /// refusal.
    fn from_str(text: &str) -> Result<Exposure, String> {
        let text = text.trim();
        if text.eq_ignore_ascii_case("auto") {
            return Ok(Exposure::Auto);
        }
        text.parse::<f64>()
            .ok()
            .and_then(Exposure::ev100)
            .ok_or_else(|| Exposure::refusal(format!("{text:?}")))
    }
}

/// Bits per sample of the picture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Depth {
    /// 8-bit (PNG, JPEG, TIFF).
    Eight,
    /// 16-bit (PNG, TIFF).
    Sixteen,
}

impl Depth {
    /// Bits per sample.
    pub fn bits(self) -> u32 {
        match self {
            Depth::Eight => 8,
            Depth::Sixteen => 16,
        }
    }
}

/// Display settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DisplayOptions {
    /// How bright.
    pub exposure: Exposure,
    /// Which curve.
    pub tone: ToneCurve,
}

/// An sRGB-encoded picture, interleaved RGB values in 0…1.
#[derive(Debug, Clone)]
pub struct Picture {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// R, G, B per pixel, row-major, top row first.
    pub rgb: Vec<f32>,
    /// The luminance shown as white, cd/m².
    pub white: f64,
}

impl Picture {
    /// Its samples as 8-bit codes (RGB, row-major), as PNG and JPEG store
    /// them.
    pub fn eight_bit(&self) -> Vec<u8> {
        self.rgb
            .iter()
            .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
            .collect()
    }

    /// The exposure value (EV100) that shows `white` as white.
    pub fn ev100(&self) -> f64 {
        (self.white / 1.2).log2()
    }
}

/// The darkest white auto exposure chooses, cd/m²: a black frame stays
/// black instead of dividing by zero.
const DARKEST_WHITE: f64 = 1e-4;

/// Where the lit scene's median is put: at this fraction of white, the
/// lower mid-tones (sRGB code 112 of 255 through the filmic curve, about
/// 95 through the others; zones IV to V).
const MEDIAN_AT: f64 = 0.12;

/// What the auto exposure meter found, cd/m².
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Metering {
    /// The median of the lit scene.
    pub median: f64,
    /// Pixels brighter than this count as light sources and may clip.
    pub sources_above: f64,
    /// The 99th percentile of the other pixels' brightest channel, kept
    /// below clipping.
    pub highlights: f64,
}

impl Metering {
    /// The luminance shown as white under `curve`: the lit median at
    /// [`MEDIAN_AT`] of white, unless the highlights would clip.
    pub fn white(&self, curve: ToneCurve) -> f64 {
        (self.median / MEDIAN_AT)
            .max(self.highlights / clipping_point(curve))
            .max(DARKEST_WHITE)
    }
}

/// The auto exposure of `image` (`scale` cd/m² per unit), a percentile
/// meter on the lit scene (docs/physics.md §9):
///
/// - the lit scene is every pixel within ten stops of the highlights
///   (L ≥ P99.9 / 1000): a black sky or a dark table does not count;
/// - light sources are the pixels brighter than both ten times the lit
///   median and the 98th percentile: lamps, flames, lit windows, the sun;
///   they may clip, as in a photograph;
/// - white puts the lit median at [`MEDIAN_AT`] of white, unless that would
///   clip more than 1 % of the other pixels (their brightest channel's
///   99th percentile at the curve's clipping point): highlights win.
///
/// Percentiles are taken on at most about two million pixels, every k-th,
/// so a 4K frame meters in milliseconds and always alike.
pub fn meter(image: &Image, scale: f64) -> Metering {
    let n = image.width * image.height;
    let stride = n.div_ceil(1 << 21).max(1);
    let luminance = PixelLuminance::of(image);
    let brightest = |i: usize| match image.layout {
        Layout::Luminance => image.planes[0][i],
        Layout::Rgb => image.planes[0][i]
            .max(image.planes[1][i])
            .max(image.planes[2][i]),
    };
    // Every pass over the samples runs on every core: the studio meters
    // each preview it answers.
    let (mut ls, mut ms): (Vec<f64>, Vec<f64>) = (0..n)
        .into_par_iter()
        .step_by(stride)
        .map(|i| {
            let cd = |v: f32| (f64::from(v) * scale).max(0.0);
            (cd(luminance.at(i)), cd(brightest(i)))
        })
        .unzip();
    let finite = |(l, m): (&f64, &f64)| l.is_finite() && m.is_finite();
    if !ls.par_iter().zip(&ms).all(finite) {
        (ls, ms) = ls
            .into_iter()
            .zip(ms)
            .filter(|(l, m)| finite((l, m)))
            .unzip();
    }
    let all = |i: usize| Some(ls[i]);
    let [top, brightest_2] = quantiles(ls.len(), all, [0.999, 0.98]);
    let lit = |i: usize| Some(ls[i]).filter(|&l| l >= top / 1000.0);
    let [median] = quantiles(ls.len(), lit, [0.5]);
    let sources_above = (10.0 * median).max(brightest_2);
    let others = |i: usize| (ls[i] <= sources_above).then_some(ms[i]);
    // Just inside 1 %, so that sampling never tips it over.
    let [highlights] = quantiles(ls.len(), others, [0.991]);
    Metering {
        median,
        sources_above,
        highlights,
    }
}

/// The `q` quantile (0…1) of `values`, 0 when empty: the value of rank
/// round((n − 1)·q) in `f64::total_cmp`'s order.
#[cfg(test)]
fn percentile(values: &[f64], q: f64) -> f64 {
    let [found] = quantiles(values.len(), |i| Some(values[i]), [q]);
    found
}

/// The quantiles `qs` (0…1) of the values `value` gives for the indices
/// below `len` (`None`: left out), each 0 when there are none: the value
/// of rank round((n − 1)·q) in `f64::total_cmp`'s order. Many values are
/// counted by the top 16 bits of that order's key first, a few
/// histograms on every core (sign, exponent and 4 bits of mantissa: a
/// sixteenth of a binade), and each rank found among the values of its
/// bin alone: only that bin's values are gathered, never all of them.
fn quantiles<const Q: usize>(
    len: usize,
    value: impl Fn(usize) -> Option<f64> + Sync,
    qs: [f64; Q],
) -> [f64; Q] {
    const BINS: usize = 1 << 16;
    // total_cmp's order as unsigned integers: negatives reversed below
    // the positives.
    let bin = |v: f64| {
        let bits = v.to_bits();
        let key = if bits >> 63 == 1 {
            !bits
        } else {
            bits | 1 << 63
        };
        (key >> 48) as usize
    };
    let select =
        |mut among: Vec<f64>, rank: usize| *among.select_nth_unstable_by(rank, f64::total_cmp).1;
    let chunk = len.div_ceil(2 * rayon::current_num_threads()).max(1 << 14);
    let (kept, counts) = (0..len.div_ceil(chunk))
        .into_par_iter()
        .map(|c| {
            let mut counts = vec![0u32; BINS];
            let mut kept = 0;
            for v in (c * chunk..len.min((c + 1) * chunk)).filter_map(&value) {
                counts[bin(v)] += 1;
                kept += 1;
            }
            (kept, counts)
        })
        .reduce(
            || (0, vec![0u32; BINS]),
            |(kept_a, mut a), (kept_b, b)| {
                for (a, b) in a.iter_mut().zip(b) {
                    *a += b;
                }
                (kept_a + kept_b, a)
            },
        );
    if kept == 0 {
        return [0.0; Q];
    }
    let rank = |q: f64| ((kept - 1) as f64 * q).round() as usize;
    if kept < BINS {
        let values = gather(len, &value, |_| true);
        return qs.map(|q| select(values.clone(), rank(q)));
    }
    qs.map(|q| {
        let at = rank(q);
        let mut below = 0;
        for (b, &count) in counts.iter().enumerate() {
            let count = count as usize;
            if at < below + count {
                return select(gather(len, &value, |v| bin(v) == b), at - below);
            }
            below += count;
        }
        0.0
    })
}

/// The values `value` gives for the indices below `len` that `keep`.
fn gather(
    len: usize,
    value: &(impl Fn(usize) -> Option<f64> + Sync),
    keep: impl Fn(f64) -> bool + Sync,
) -> Vec<f64> {
    (0..len)
        .into_par_iter()
        .filter_map(|i| value(i).filter(|&v| keep(v)))
        .collect()
}

/// The exposed level (1 = white) from which `curve` shows the top 8-bit
/// code: the filmic shoulder reaches it only at about 6.4.
pub fn clipping_point(curve: ToneCurve) -> f64 {
    let clips = |x: f64| linear_to_srgb(tone(curve, x as f32)) >= 254.5 / 255.0;
    let (mut low, mut high) = (0.0, 1.0);
    while !clips(high) {
        high *= 2.0;
    }
    for _ in 0..40 {
        let mid = 0.5 * (low + high);
        if clips(mid) {
            high = mid;
        } else {
            low = mid;
        }
    }
    high
}

/// The sRGB encoding curve: linear light (0…1) to display code value.
pub fn linear_to_srgb(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

fn tone(curve: ToneCurve, x: f32) -> f32 {
    let x = x.max(0.0);
    match curve {
        ToneCurve::Clip => x.min(1.0),
        ToneCurve::Reinhard => (x * (1.0 + x / 4.0) / (1.0 + x)).min(1.0),
        ToneCurve::Filmic => {
            ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
        }
    }
}

/// Renders `image` (file units, `scale` cd/m² per unit) for a display.
pub fn render(image: &Image, scale: f64, options: &DisplayOptions) -> Picture {
    let white = options.exposure.white(image, scale, options.tone);
    let gain = (scale / white) as f32;
    let n = image.width * image.height;
    let mut rgb = Vec::with_capacity(n * 3);
    for i in 0..n {
        for c in 0..3 {
            let v = match image.layout {
                Layout::Luminance => image.planes[0][i],
                Layout::Rgb => image.planes[c][i],
            };
            rgb.push(linear_to_srgb(tone(options.tone, v * gain)));
        }
    }
    Picture {
        width: image.width,
        height: image.height,
        rgb,
        white,
    }
}

/// The sRGB decoding curve: display code value (0…1) to linear light.
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_percentile_of_many_values_is_the_sorted_values_own() {
        use rand_core::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let mut unit = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        // Luminances over twelve decades, with ties, zeros of both signs,
        // negatives and crowds in one bin; below and above the size where
        // values are binned first.
        for n in [1000, 70_000, 300_001] {
            let values: Vec<f64> = (0..n)
                .map(|i| match i % 7 {
                    0 => 0.0,
                    1 => -0.0,
                    2 => 1.0 + unit() * 1e-6,
                    3 => -unit(),
                    4 => 42.0,
                    _ => 10f64.powi((unit() * 12.0) as i32 - 3) * (1.0 + unit()),
                })
                .collect();
            let mut sorted = values.clone();
            sorted.sort_by(f64::total_cmp);
            for q in [0.0, 0.1, 0.5, 0.98, 0.991, 0.999, 1.0] {
                let expected = sorted[((n - 1) as f64 * q).round() as usize];
                let found = percentile(&values, q);
                assert_eq!(found.to_bits(), expected.to_bits(), "n {n}, q {q}");
            }
        }
        assert_eq!(percentile(&[], 0.5), 0.0);
    }

    #[test]
    fn srgb_round_trips_through_the_decoder() {
        for i in 0..=100 {
            let v = i as f32 / 100.0;
            let back = srgb_to_linear(linear_to_srgb(v));
            assert!((back - v).abs() < 1e-5, "{v} -> {back}");
        }
    }

    #[test]
    fn curves_map_black_to_black_and_saturate() {
        for curve in [ToneCurve::Clip, ToneCurve::Reinhard, ToneCurve::Filmic] {
            assert_eq!(tone(curve, 0.0), 0.0);
            assert_eq!(tone(curve, 1e6), 1.0);
            // Monotonic.
            let mut last = 0.0;
            for i in 1..400 {
                let y = tone(curve, i as f32 / 100.0);
                assert!(y >= last, "{curve:?}");
                last = y;
            }
        }
        assert_eq!(tone(ToneCurve::Clip, 1.0), 1.0);
        assert!((tone(ToneCurve::Reinhard, 2.0) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn names_read_as_every_front_end_reads_them() {
        for (name, curve) in ToneCurve::NAMES {
            assert_eq!(name.parse(), Ok(curve));
            assert_eq!(name.to_uppercase().parse(), Ok(curve));
            assert_eq!(curve.name(), name);
        }
        let refused = "sepia".parse::<ToneCurve>().unwrap_err();
        assert_eq!(
            refused,
            "tonemap \"sepia\" is not allowed: filmic, reinhard or clip"
        );
        assert_eq!("auto".parse(), Ok(Exposure::Auto));
        assert_eq!(" -3.5 ".parse(), Ok(Exposure::Ev(-3.5)));
        for refused in ["41", "NaN", "inf", "bright", ""] {
            let message = refused.parse::<Exposure>().unwrap_err();
            assert!(message.contains("from -40 to 40"), "{message}");
        }
    }

    #[test]
    fn exposure_value_and_white_agree() {
        // EV100 10 shows 1.2·1024 cd/m² as white.
        let image = Image::filled(2, 2, Layout::Luminance, 1228.8);
        let by_ev = render(
            &image,
            1.0,
            &DisplayOptions {
                exposure: Exposure::Ev(10.0),
                tone: ToneCurve::Clip,
            },
        );
        let by_white = render(
            &image,
            1.0,
            &DisplayOptions {
                exposure: Exposure::White(1228.8),
                tone: ToneCurve::Clip,
            },
        );
        assert_eq!(by_ev.rgb, by_white.rgb);
        assert!((by_ev.rgb[0] - 1.0).abs() < 1e-6);
        assert!((by_ev.ev100() - 10.0).abs() < 1e-9);
    }

    #[test]
    fn auto_exposure_puts_a_uniform_scene_in_the_lower_mid_tones() {
        let image = Image::filled(4, 4, Layout::Rgb, 50.0);
        let picture = render(
            &image,
            1.0,
            &DisplayOptions {
                exposure: Exposure::Auto,
                tone: ToneCurve::Clip,
            },
        );
        let linear = srgb_to_linear(picture.rgb[0]);
        assert!((f64::from(linear) - MEDIAN_AT).abs() < 1e-3, "{linear}");
    }

    #[test]
    fn clipping_points_are_where_each_curve_reaches_its_top_code() {
        assert!((clipping_point(ToneCurve::Clip) - 0.996).abs() < 0.002);
        let filmic = clipping_point(ToneCurve::Filmic);
        assert!((6.0..7.0).contains(&filmic), "{filmic}");
        for curve in [ToneCurve::Clip, ToneCurve::Reinhard, ToneCurve::Filmic] {
            let x = clipping_point(curve);
            assert!(linear_to_srgb(tone(curve, (x * 0.99) as f32)) < 254.5 / 255.0);
        }
    }

    #[test]
    fn a_black_frame_meters_to_the_darkest_white() {
        let image = Image::filled(8, 8, Layout::Rgb, 0.0);
        assert_eq!(meter(&image, 1.0).white(ToneCurve::Filmic), DARKEST_WHITE);
    }

    #[test]
    fn the_meter_is_its_definition_on_sorted_samples() {
        // Below and above the sample count where values are binned first,
        // with pixels that are not numbers or infinite, left out.
        let sorted_quantile = |mut values: Vec<f64>, q: f64| {
            values.sort_by(f64::total_cmp);
            values
                .get(((values.len().max(1) - 1) as f64 * q).round() as usize)
                .copied()
                .unwrap_or(0.0)
        };
        let mut seed = 7u64;
        let mut unit = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for (w, h) in [(90, 70), (400, 300)] {
            let mut image = Image::filled(w, h, Layout::Rgb, 0.0);
            for i in 0..w * h {
                for c in 0..3 {
                    image.planes[c][i] = match i % 997 {
                        0 => f32::NAN,
                        1 => f32::INFINITY,
                        2..=9 => 5e4 * (1.0 + unit() as f32),
                        _ => (10f64.powf(unit() * 4.0 - 2.0) * (0.5 + unit())) as f32,
                    };
                }
            }
            let scale = 3.0;
            let luminance = PixelLuminance::of(&image);
            let samples: Vec<(f64, f64)> = (0..w * h)
                .map(|i| {
                    let m = image.planes.iter().map(|p| p[i]).fold(f32::MIN, f32::max);
                    let cd = |v: f32| (f64::from(v) * scale).max(0.0);
                    (cd(luminance.at(i)), cd(m))
                })
                .filter(|(l, m)| l.is_finite() && m.is_finite())
                .collect();
            let all: Vec<f64> = samples.iter().map(|s| s.0).collect();
            let top = sorted_quantile(all.clone(), 0.999);
            let lit = all.iter().copied().filter(|&l| l >= top / 1000.0).collect();
            let median = sorted_quantile(lit, 0.5);
            let sources_above = (10.0 * median).max(sorted_quantile(all, 0.98));
            let others = samples
                .iter()
                .filter(|s| s.0 <= sources_above)
                .map(|s| s.1)
                .collect();
            let metering = meter(&image, scale);
            assert_eq!(metering.median.to_bits(), median.to_bits(), "{w}x{h}");
            assert_eq!(metering.sources_above.to_bits(), sources_above.to_bits());
            assert_eq!(
                metering.highlights.to_bits(),
                sorted_quantile(others, 0.991).to_bits()
            );
        }
    }
}
