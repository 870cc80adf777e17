//! Auto exposure as a photographer would accept it (docs/physics.md §9): on
//! the demo night street and the photographs of `../shared/data` (skipped
//! when absent), at most 1 % of the pixels that are not light sources clip,
//! and the lit scene's median lands in the lower mid-tones.
//!
//! The light sources are what the meter lets clip: pixels brighter than
//! both ten times the lit scene's median and the 98th percentile. The lit
//! scene is every pixel within ten stops of the highlights (a black sky or
//! table is not part of it).

#[path = "../../../tests/support/required.rs"]
mod required;
use std::path::Path;

use aureole::Image;
use aureole_io::display::{render, DisplayOptions, Exposure, ToneCurve};
use aureole_io::limits::Limits;
use aureole_io::read::read_image;

/// The lower mid-tones as 8-bit sRGB codes: zones III to V (4.5 % to 18 %
/// grey shows as 56 to 118).
const LOWER_MID_TONES: std::ops::RangeInclusive<f64> = 56.0..=128.0;

struct Verdict {
    clipped: f64,
    median_code: f64,
}

fn quantile(mut values: Vec<f64>, q: f64) -> f64 {
    values.sort_by(f64::total_cmp);
    values[((values.len() - 1) as f64 * q).round() as usize]
}

fn judge(image: &Image, scale: f64, tone: ToneCurve) -> Verdict {
    let picture = render(
        image,
        scale,
        &DisplayOptions {
            exposure: Exposure::Auto,
            tone,
        },
    );
    let luminance: Vec<f64> = image
        .luminance()
        .iter()
        .map(|&y| (f64::from(y) * scale).max(0.0))
        .collect();
    let top = quantile(luminance.clone(), 0.999);
    let lit: Vec<usize> = (0..luminance.len())
        .filter(|&i| luminance[i] >= top / 1000.0)
        .collect();
    let median = quantile(lit.iter().map(|&i| luminance[i]).collect(), 0.5);
    let sources = (10.0 * median).max(quantile(luminance.clone(), 0.98));
    let code = |v: f32| (f64::from(v) * 255.0).round();
    let others: Vec<usize> = (0..luminance.len())
        .filter(|&i| luminance[i] <= sources)
        .collect();
    let clipped = others
        .iter()
        .filter(|&&i| {
            picture.rgb[3 * i..3 * i + 3]
                .iter()
                .any(|&v| code(v) >= 255.0)
        })
        .count() as f64
        / others.len() as f64;
    // The display's luma of each lit pixel, as a code.
    let luma = |i: usize| {
        let rgb = &picture.rgb[3 * i..3 * i + 3];
        0.2126 * f64::from(rgb[0]) + 0.7152 * f64::from(rgb[1]) + 0.0722 * f64::from(rgb[2])
    };
    let median_code = 255.0 * quantile(lit.iter().map(|&i| luma(i)).collect(), 0.5);
    Verdict {
        clipped,
        median_code,
    }
}

const CURVES: &[ToneCurve] = &[ToneCurve::Filmic, ToneCurve::Reinhard, ToneCurve::Clip];

/// `median_from`: the darkest code the lit median may take: the lower
/// mid-tones, or lower for a backlit day scene whose sky would clip.
fn check(name: &str, image: &Image, scale: f64, median_from: f64, curves: &[ToneCurve]) {
    for &tone in curves {
        let v = judge(image, scale, tone);
        eprintln!(
            "{name} {tone:?}: {:.2} % of the non-source pixels clipped, lit median at code {:.0}",
            100.0 * v.clipped,
            v.median_code
        );
        assert!(
            v.clipped <= 0.01,
            "{name} {tone:?}: {:.2} % clipped",
            100.0 * v.clipped
        );
        assert!(
            v.median_code >= median_from && v.median_code <= *LOWER_MID_TONES.end(),
            "{name} {tone:?}: median at code {:.0}",
            v.median_code
        );
    }
}

#[test]
fn the_demo_street_meters_like_a_photograph() {
    let street = aureole_io::demo::night_street(640, 360);
    check(
        "demo street",
        &street,
        1.0,
        *LOWER_MID_TONES.start(),
        CURVES,
    );
}

#[test]
fn the_night_photographs_and_a_day_scene_meter_like_photographs() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    if !data.is_dir() {
        required::missing(
            "the_night_photographs_and_a_day_scene_meter_like_photographs",
            &format!("{} is absent", data.display()),
        );
        return;
    }
    // Tree.exr is backlit: its shaded trunk and foreground are the lit
    // median, a hundred times darker than the sky around them. Lifting
    // that median from code 45 to 56 would clip 3 % of the sky and meadow
    // (8.9 % at code 74), so the meter keeps the sky, as a camera's
    // highlight-weighted metering does, and the median stays in zone III
    // through the default filmic curve (the harder curves, which clip at
    // white, put it lower still).
    let night = *LOWER_MID_TONES.start();
    for (name, median_from, curves) in [
        ("CandleGlass.exr", night, CURVES),
        ("GoldenGate.exr", night, CURVES),
        ("Fog.exr", night, CURVES),
        ("dikhololo_night_1k.hdr", night, CURVES),
        ("Tree.exr", 40.0, &[ToneCurve::Filmic][..]),
    ] {
        let loaded = read_image(&data.join(name), Limits::NONE).unwrap();
        let scale = loaded.image.white_luminance.map_or(1.0, f64::from);
        check(name, &loaded.image, scale, median_from, curves);
    }
}
