//! The display path (docs/physics.md §9): no display shows 10⁵ cd/m², so
//! luminance is exposed, passed through a tone curve and sRGB-encoded.

use aureole::image::{Image, Layout};

/// How bright the picture is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Exposure {
    /// From the log-average luminance, as a reflected-light meter sets a
    /// camera (mid-grey at the log-average).
    Auto,
    /// Exposure value at ISO 100 (EV100): a camera at f/N and t seconds has
    /// EV = log₂(N²/t). The luminance shown as white is 1.2·2^EV cd/m²
    /// (ISO 2720 saturation).
    Ev(f64),
    /// The luminance in cd/m² shown as white.
    White(f64),
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
    /// The exposure value (EV100) that shows `white` as white.
    pub fn ev100(&self) -> f64 {
        (self.white / 1.2).log2()
    }
}

/// Luminance (cd/m²) that floors the log-average, so that black pixels do
/// not drag it to zero.
const LOG_AVERAGE_FLOOR: f64 = 1e-4;

/// The log-average luminance exp(mean ln(L + 10⁻⁴)) in cd/m².
pub fn log_average_luminance(image: &Image, scale: f64) -> f64 {
    let n = image.width * image.height;
    if n == 0 {
        return LOG_AVERAGE_FLOOR;
    }
    let sum: f64 = image
        .luminance()
        .iter()
        .map(|&y| (f64::from(y).max(0.0) * scale + LOG_AVERAGE_FLOOR).ln())
        .sum();
    (sum / n as f64).exp()
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
    let white = match options.exposure {
        // A meter reads EV100 = log₂(L·100/12.5) for a log-average L; the
        // saturation luminance at that EV is 1.2·2^EV = 9.6 L.
        Exposure::Auto => 9.6 * log_average_luminance(image, scale),
        Exposure::Ev(ev) => 1.2 * ev.exp2(),
        Exposure::White(white) => white,
    };
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
    fn auto_exposure_puts_a_uniform_scene_at_a_tenth_of_white() {
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
        assert!((linear - 1.0 / 9.6).abs() < 1e-3, "{linear}");
    }
}
