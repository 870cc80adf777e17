//! The profile plot of a kernel: the radial profile (mean over rings, log
//! scale, as the paper's Fig. 4/5 "filter profile") and the angular profile
//! at a chosen radius, where the rays of a corona show as peaks; and the
//! picture of a pupil, dirt and all.

use std::path::Path;
use std::sync::Once;

use aureole::kernel::profile::{angular_profile, radial_profile};
use aureole::optics::aperture::Optics;
use aureole::Kernel;
use image::{ImageFormat, RgbImage};
use plotters::prelude::*;
use plotters::style::FontStyle;
use rayon::prelude::*;

use crate::atomic::write_atomic;
use crate::error::{Error, Result};

const FONT: &[u8] = include_bytes!("../assets/DejaVuSansMono.ttf");
const FAMILY: &str = "aureole-mono";
const SIZE: (u32, u32) = (1400, 560);

/// The family name of the embedded DejaVu Sans Mono, registered with
/// plotters on first use: for text in any picture drawn with plotters.
pub fn font_family() -> &'static str {
    static REGISTER: Once = Once::new();
    REGISTER.call_once(|| {
        // The font is ours and valid; a failure would only leave text out.
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT);
    });
    FAMILY
}

/// Draws the radial profile and the angular profile at `radius` px into a
/// PNG at `path`.
pub fn write_profile_plot(path: &Path, kernel: &Kernel, radius: f64) -> Result<()> {
    let encode_error = |message: String| Error::Encode {
        path: path.to_path_buf(),
        format: "plot PNG",
        message,
    };
    let mut pixels = vec![255u8; (SIZE.0 * SIZE.1 * 3) as usize];
    draw(&mut pixels, kernel, radius).map_err(|e| encode_error(e.to_string()))?;
    let picture = RgbImage::from_raw(SIZE.0, SIZE.1, pixels)
        .ok_or_else(|| encode_error("plot buffer has the wrong size".into()))?;
    write_atomic(path, |out| {
        picture
            .write_to(out, ImageFormat::Png)
            .map_err(|e| encode_error(e.to_string()))
    })
}

/// Samples per pixel side of a pupil picture: dust a few µm across still
/// shows as a grey dot.
const PUPIL_SAMPLES: usize = 4;

/// Draws the pupil of `optics` into a `side`-pixel square PNG at `path`:
/// the share of the light each point passes, |t|², white on black,
/// across the stop's widest diameter.
pub fn write_pupil_picture(path: &Path, optics: &Optics, side: u32) -> Result<()> {
    let half = 0.51 * optics.diameter_mm * optics.stretch.max(1.0);
    let n = side as usize;
    let step = 2.0 * half / (n * PUPIL_SAMPLES) as f64;
    let pixels: Vec<u8> = (0..n * n)
        .into_par_iter()
        .map(|at| {
            let (i, j) = (at % n, at / n);
            let mut light = 0.0;
            for a in 0..PUPIL_SAMPLES {
                for b in 0..PUPIL_SAMPLES {
                    let x = -half + ((i * PUPIL_SAMPLES + b) as f64 + 0.5) * step;
                    let y = half - ((j * PUPIL_SAMPLES + a) as f64 + 0.5) * step;
                    let [re, im] = optics.pupil.transmission([x, y]);
                    light += re * re + im * im;
                }
            }
            let mean = light / (PUPIL_SAMPLES * PUPIL_SAMPLES) as f64;
            (255.0 * mean.clamp(0.0, 1.0)).round() as u8
        })
        .collect();
    let encode_error = |message: String| Error::Encode {
        path: path.to_path_buf(),
        format: "pupil PNG",
        message,
    };
    let picture = image::GrayImage::from_raw(side, side, pixels)
        .ok_or_else(|| encode_error("pupil buffer has the wrong size".into()))?;
    write_atomic(path, |out| {
        picture
            .write_to(out, ImageFormat::Png)
            .map_err(|e| encode_error(e.to_string()))
    })
}

fn channel_colours(kernel: &Kernel) -> Vec<(RGBColor, &'static str)> {
    if kernel.is_coloured() {
        vec![
            (RGBColor(200, 30, 30), "R"),
            (RGBColor(20, 150, 40), "G"),
            (RGBColor(30, 60, 210), "B"),
        ]
    } else {
        vec![(RGBColor(20, 20, 20), "K")]
    }
}

type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

fn draw(pixels: &mut [u8], kernel: &Kernel, radius: f64) -> DrawResult {
    let root = BitMapBackend::with_buffer(pixels, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(SIZE.0 / 2);
    let font = (font_family(), 18).into_font();
    let colours = channel_colours(kernel);

    // Radial profile, from the first ring out, log scale.
    let radial: Vec<Vec<(f64, f64)>> = (0..kernel.planes().len())
        .map(|c| {
            radial_profile(kernel, c)
                .into_iter()
                .enumerate()
                .skip(1)
                .filter(|&(_, v)| v > 0.0)
                .map(|(r, v)| (r as f64, v))
                .collect()
        })
        .collect();
    let (r_max, lo, hi) = bounds(&radial);
    let mut chart = ChartBuilder::on(&left)
        .caption("radial profile: mean K on 1 px rings", font.clone())
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(90)
        .build_cartesian_2d(1f64..r_max.max(2.0), (lo..hi).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("r (px)")
        .y_desc("K")
        .label_style((FAMILY, 15))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()?;
    for (series, (colour, _)) in radial.iter().zip(&colours) {
        chart.draw_series(LineSeries::new(
            series.iter().copied(),
            colour.stroke_width(2),
        ))?;
    }

    // Angular profile at the chosen radius, linear scale: rays are peaks.
    let angular: Vec<Vec<(f64, f64)>> = (0..kernel.planes().len())
        .map(|c| angular_profile(kernel, c, radius, 3600))
        .collect();
    let peak = angular
        .iter()
        .flatten()
        .map(|&(_, v)| v)
        .fold(0.0, f64::max);
    let mut chart = ChartBuilder::on(&right)
        .caption(format!("angular profile at r = {radius} px"), font)
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(90)
        .build_cartesian_2d(0f64..360.0, 0f64..(peak * 1.05).max(1e-30))?;
    chart
        .configure_mesh()
        .x_desc("angle from +x, counter-clockwise (degrees)")
        .y_desc("K")
        .label_style((FAMILY, 15))
        .y_label_formatter(&|v| format!("{v:.1e}"))
        .draw()?;
    for (series, (colour, _)) in angular.iter().zip(&colours) {
        chart.draw_series(LineSeries::new(
            series.iter().copied(),
            colour.stroke_width(2),
        ))?;
    }
    root.present()?;
    Ok(())
}

/// The largest radius and the value range (for a log axis) over all series.
fn bounds(series: &[Vec<(f64, f64)>]) -> (f64, f64, f64) {
    let points = || series.iter().flatten();
    let r_max = points().map(|p| p.0).fold(1.0, f64::max);
    let hi = points().map(|p| p.1).fold(0.0, f64::max);
    let lo = points().map(|p| p.1).fold(f64::INFINITY, f64::min);
    if hi > 0.0 {
        (r_max, lo.max(hi * 1e-12), hi * 1.5)
    } else {
        (r_max, 1e-12, 1.0)
    }
}
