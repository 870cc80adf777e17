//! The pipeline against its definition: linear convolution with zero outside
//! the frame, the threshold split O = I·[Y ≤ T] + K ⊛ (I·[Y > T]), energy.

// References and workloads, not the library: the platform's maths
// (clippy.toml refuses it in the core) is as good as libm here.
#![allow(clippy::disallowed_methods)]

mod noise;

use aureole::convolve::Convolver;
use aureole::convolve::{Centre, Engine, Spread, Term};
use aureole::pipeline::spread_fraction;
use aureole::{
    ApplyOptions, Arithmetic, Bloom, Cancel, Config, Control, Effect, Image, Kernel, Layout,
    Length, Method, Plan,
};
use noise::pseudo_random;

/// The f32 engine for `kernel` on `w`×`h` planes.
fn convolver(kernel: &Kernel, w: usize, h: usize, centre: Centre) -> Convolver {
    let planes: Vec<&[f32]> = kernel.planes().iter().map(Vec::as_slice).collect();
    let size = (kernel.width(), kernel.height());
    let mut control = Control::quiet(&Cancel::new());
    Convolver::new(&planes, size, w, h, centre, &mut control).unwrap()
}

/// `plane` through kernel plane `k` of `convolver`.
fn convolve(convolver: &Convolver, plane: &[f32], k: usize) -> Vec<f32> {
    let mut control = Control::quiet(&Cancel::new());
    convolver.convolve(plane, k, &mut control).unwrap()
}

/// out(x, y) = Σ I(p) K(x − p): the definition, zero outside the frame.
fn direct(image: &[f32], w: usize, h: usize, kernel: &Kernel) -> Vec<f64> {
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut sum = 0.0;
            for py in 0..h {
                for px in 0..w {
                    // Kernel offsets are y-up; image rows grow downwards.
                    let (dx, dy) = (x as i64 - px as i64, py as i64 - y as i64);
                    sum += f64::from(image[py * w + px]) * f64::from(kernel.at(0, dx, dy));
                }
            }
            out[y * w + x] = sum;
        }
    }
    out
}

#[test]
fn fft_convolution_equals_direct_convolution() {
    for (w, h, kw, kh) in [
        (17, 12, 5, 7),
        (16, 9, 6, 4),
        (9, 14, 33, 27),
        (20, 20, 39, 39),
        (7, 5, 1, 1),
        (12, 8, 2, 3),
    ] {
        let kernel = Kernel::from_planes(kw, kh, vec![pseudo_random(kw * kh, 7)]).unwrap();
        let image = pseudo_random(w * h, 3);
        let fast = convolve(&convolver(&kernel, w, h, Centre::Include), &image, 0);
        assert_direct(&fast, &image, w, h, &kernel);
    }
}

/// `fast` is the definition's result within 1e-5 of its largest value.
fn assert_direct(fast: &[f32], image: &[f32], w: usize, h: usize, kernel: &Kernel) {
    let slow = direct(image, w, h, kernel);
    let scale = slow.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (f, s) in fast.iter().zip(&slow) {
        assert!(
            (f64::from(*f) - s).abs() <= 1e-5 * scale,
            "{w}x{h} * {}x{}: {f} vs {s}",
            kernel.width(),
            kernel.height()
        );
    }
}

#[test]
fn full_frame_kernels_convolve_exactly_with_pruned_columns() {
    // (2W − 1)×(2H − 1) kernels: every pixel reaches every other, and the
    // columns run as two half-length transforms each way.
    for (w, h) in [(16, 9), (15, 10), (24, 20), (7, 12)] {
        let (kw, kh) = (2 * w - 1, 2 * h - 1);
        let kernel = Kernel::from_planes(kw, kh, vec![pseudo_random(kw * kh, 11)]).unwrap();
        let image = pseudo_random(w * h, 5);
        let engine = convolver(&kernel, w, h, Centre::Include);
        let (_, py) = engine.padded_size();
        assert!(py >= kh, "{w}x{h}: period {py}");
        assert_direct(&convolve(&engine, &image, 0), &image, w, h, &kernel);
    }
}

#[test]
fn a_kernel_split_for_lamps_still_convolves_every_plane_exactly() {
    // Once split, the engine holds the spectrum beyond the window and the
    // window's rows instead of the whole spectrum: planes without lamps
    // go through their sum. Full-frame kernels (pruned columns) and
    // smaller ones (whole columns), split at radii one after another, and
    // a split cancelled halfway.
    for (w, h, kw, kh) in [(16, 9, 31, 17), (15, 10, 29, 19), (20, 14, 13, 11)] {
        let planes: Vec<Vec<f32>> = (0..3).map(|c| pseudo_random(kw * kh, 40 + c)).collect();
        let kernel = Kernel::from_planes(kw, kh, planes).unwrap();
        let slices: Vec<&[f32]> = kernel.planes().iter().map(Vec::as_slice).collect();
        let image = pseudo_random(w * h, 9);
        let engine = convolver(&kernel, w, h, Centre::Leave);
        let exact = |engine: &Convolver| {
            for k in 0..3 {
                let single = Kernel::from_planes(kw, kh, vec![kernel.planes()[k].clone()]).unwrap();
                assert_direct(&convolve(engine, &image, k), &image, w, h, &single);
            }
        };
        exact(&engine);
        for radius in [2, 4, 2] {
            let mut control = Control::quiet(&Cancel::new());
            assert!(engine.split_near(&slices, radius, &mut control).unwrap());
            assert!(engine.has_split(radius));
            exact(&engine);
        }
        let cancel = Cancel::new();
        cancel.cancel();
        let refused = engine.split_near(&slices, 3, &mut Control::quiet(&cancel));
        assert!(refused.is_err(), "{w}x{h}: a cancelled split");
        assert!(!engine.has_split(3));
        exact(&engine);
    }
}

#[test]
fn planes_convolved_together_match_planes_convolved_alone() {
    let (w, h) = (21, 13);
    let planes: Vec<Vec<f32>> = (0..3).map(|c| pseudo_random(w * h, 20 + c)).collect();
    let kernels: Vec<Vec<f32>> = (0..3).map(|c| pseudo_random(41 * 25, 30 + c)).collect();
    let kernel = Kernel::from_planes(41, 25, kernels).unwrap();
    let engine = convolver(&kernel, w, h, Centre::Leave);
    let fractions = pseudo_random(w * h, 50);
    let spreads: Vec<Spread> = planes
        .iter()
        .enumerate()
        .map(|(c, plane)| Spread {
            plane,
            fractions: (c == 1).then_some(fractions.as_slice()),
            terms: Term::alone(2 - c),
            lamps: &[],
        })
        .collect();
    let mut control = Control::quiet(&Cancel::new());
    // Recycled planes of the wrong size and number are resized.
    let recycled = vec![vec![7.0; 5]; 4];
    let together = engine.spread(&spreads, recycled, &mut control).unwrap();
    assert_eq!(together.len(), 3);
    for (spread, out) in spreads.iter().zip(&together) {
        let alone = engine
            .spread(std::slice::from_ref(spread), Vec::new(), &mut control)
            .unwrap();
        assert_eq!(out, &alone[0]);
    }
    // The centre weight the engine left out is applied exactly.
    let whole = convolve(&convolver(&kernel, w, h, Centre::Include), &planes[0], 2);
    for (a, b) in together[0].iter().zip(&whole) {
        assert!((a - b).abs() <= 1e-5 * b.abs().max(1.0), "{a} vs {b}");
    }
}

#[test]
fn a_recycled_result_gives_the_same_bytes_as_a_fresh_one() {
    let (w, h) = (40, 24);
    let mut image = Image::filled(w, h, Layout::Rgb, 0.05);
    for (i, plane) in image.planes.iter_mut().enumerate() {
        plane[300 + 7 * i] = 5e4;
        plane[611] = 2e3;
    }
    let plan = Plan::for_image(&paper_config(), w, h, None).unwrap();
    for threshold in [0.0, 1.0, 1e9] {
        let options = ApplyOptions {
            threshold: Some(threshold),
            ..ApplyOptions::default()
        };
        let fresh = plan.apply(&image, 1.0, &options, &mut |_| {}).unwrap();
        let previous = vec![vec![f32::NAN; w * h]; 3];
        let mut control = Control::quiet(&Cancel::new());
        let recycled = plan
            .apply_with(&image, 1.0, &options, previous, &mut control)
            .unwrap();
        assert_eq!(fresh.image.planes, recycled.image.planes, "T = {threshold}");
    }
}

fn bloom_config(epsilon: f64, beta: f64, radius: f64) -> Config {
    Config {
        effects: vec![Effect::Bloom(Bloom {
            epsilon,
            beta,
            radius: Length::px(radius),
        })],
        ..Config::default()
    }
}

fn preset_config(name: &str) -> Config {
    let mut config = Config::default();
    config.merge(aureole::presets::find(name).unwrap().config().unwrap());
    config
}

fn paper_config() -> Config {
    preset_config("paper-fig5-both")
}

#[test]
fn a_single_bright_pixel_reproduces_the_kernel() {
    let (w, h) = (48, 33);
    let plan = Plan::for_image(&paper_config(), w, h, None).unwrap();
    let mut image = Image::filled(w, h, Layout::Luminance, 0.0);
    let (sx, sy) = (20, 13);
    image.planes[0][sy * w + sx] = 1000.0;
    let out = plan
        .apply(&image, 1.0, &ApplyOptions::default(), &mut |_| {})
        .unwrap()
        .image;
    let kernel = plan.kernel();
    for y in 0..h {
        for x in 0..w {
            let expected =
                1000.0 * f64::from(kernel.at(0, x as i64 - sx as i64, sy as i64 - y as i64));
            let got = f64::from(out.planes[0][y * w + x]);
            // f32 FFTs leave round-off near 10⁻¹⁰ of the source's light.
            let tolerance = 1e-5 * expected + 1e-8 * 1000.0;
            assert!(
                (got - expected).abs() <= tolerance,
                "({x}, {y}): {got} vs {expected}"
            );
        }
    }
}

#[test]
fn energy_is_conserved_when_the_glare_stays_in_the_frame() {
    // β = 6, R = 2 px, capped at 21×21: every source 10 px from the edges
    // keeps all but 5·10⁻⁸ of its light in the frame, (1 + 5.25²)^−5.
    let (w, h) = (64, 50);
    let plan = Plan::for_image(&bloom_config(0.4, 6.0, 2.0), w, h, Some((21, 21))).unwrap();
    let mut image = Image::filled(w, h, Layout::Rgb, 0.0);
    let values = pseudo_random(w * h, 11);
    for plane in &mut image.planes {
        for y in 10..h - 10 {
            for x in 10..w - 10 {
                plane[y * w + x] = 1.0 + 1e4 * values[y * w + x].powi(8);
            }
        }
    }
    let applied = plan
        .apply(&image, 1.0, &ApplyOptions::default(), &mut |_| {})
        .unwrap();
    assert!((applied.energy_out / applied.energy_in - 1.0).abs() < 1e-5);
    for (out, input) in applied.image.planes.iter().zip(&image.planes) {
        let (so, si): (f64, f64) = (
            out.iter().map(|&v| f64::from(v)).sum(),
            input.iter().map(|&v| f64::from(v)).sum(),
        );
        assert!((so / si - 1.0).abs() < 1e-5);
    }
}

#[test]
fn light_that_leaves_the_frame_is_lost_and_only_that() {
    let (w, h) = (40, 30);
    let plan = Plan::for_image(&bloom_config(0.5, 2.0, 6.0), w, h, None).unwrap();
    let mut image = Image::filled(w, h, Layout::Luminance, 0.0);
    image.planes[0][0] = 100.0; // a corner: much of its glare leaves the frame
    let applied = plan
        .apply(&image, 1.0, &ApplyOptions::default(), &mut |_| {})
        .unwrap();
    let kernel = plan.kernel();
    let inside: f64 = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| f64::from(kernel.at(0, x as i64, -(y as i64))))
        .sum();
    assert!((applied.energy_out / 100.0 - inside).abs() < 1e-5);
    assert!(inside < 0.9);
}

#[test]
fn pixels_at_or_below_the_threshold_pass_bit_identical() {
    let (w, h) = (31, 23);
    let plan = Plan::for_image(&paper_config(), w, h, None).unwrap();
    let mut image = Image::filled(w, h, Layout::Rgb, 0.0);
    let values = pseudo_random(w * h * 3, 5);
    for (c, plane) in image.planes.iter_mut().enumerate() {
        for (i, v) in plane.iter_mut().enumerate() {
            *v = 50.0 * values[c * w * h + i] - 5.0; // small negatives too
        }
    }
    let options = ApplyOptions {
        threshold: Some(60.0),
        ..ApplyOptions::default()
    };
    let applied = plan.apply(&image, 1.0, &options, &mut |_| {}).unwrap();
    assert_eq!(applied.spread_pixels, 0);
    assert_eq!(applied.image, image);
}

#[test]
fn dim_pixels_keep_their_light_and_only_receive_glare() {
    let (w, h) = (40, 40);
    let plan = Plan::for_image(&bloom_config(0.2, 3.0, 2.0), w, h, Some((9, 9))).unwrap();
    let mut image = Image::filled(w, h, Layout::Luminance, 1.0);
    image.planes[0][20 * w + 20] = 1e4;
    let options = ApplyOptions {
        threshold: Some(10.0),
        ..ApplyOptions::default()
    };
    let out = plan
        .apply(&image, 1.0, &options, &mut |_| {})
        .unwrap()
        .image;
    // Beyond the 9×9 kernel's reach the dim pixels keep their light: all
    // they get is f32 round-off, under 10⁻⁸ of the source.
    for y in 0..h {
        for x in 0..w {
            if (x as i64 - 20).abs() > 4 || (y as i64 - 20).abs() > 4 {
                let v = out.planes[0][y * w + x];
                assert!((v - 1.0).abs() < 1e4 * 1e-8, "({x}, {y}): {v}");
            }
        }
    }
    assert!(out.planes[0][20 * w + 21] > 1.0);
}

#[test]
fn no_wrap_around_a_source_at_the_left_edge_never_lights_the_right_edge() {
    let (w, h) = (128, 40);
    let plan = Plan::for_image(&bloom_config(0.5, 2.0, 3.0), w, h, Some((41, 41))).unwrap();
    let mut image = Image::filled(w, h, Layout::Luminance, 0.0);
    for y in 0..h {
        image.planes[0][y * w] = 1e5;
    }
    let out = plan
        .apply(&image, 1.0, &ApplyOptions::default(), &mut |_| {})
        .unwrap()
        .image;
    for y in 0..h {
        for x in 21..w {
            // Beyond the kernel's reach: only round-off, far below the 10⁻³
            // of the source a wrapped kernel edge would bring.
            assert!(
                out.planes[0][y * w + x].abs() < 1e5 * 1e-6,
                "({x}, {y}): {}",
                out.planes[0][y * w + x]
            );
        }
        assert!(out.planes[0][y * w + 20] > 1e5 * 1e-5);
    }
}

#[test]
fn glare_only_is_what_the_camera_adds() {
    let (w, h) = (30, 20);
    let plan = Plan::for_image(&paper_config(), w, h, None).unwrap();
    let mut image = Image::filled(w, h, Layout::Rgb, 0.5);
    image.planes[1][10 * w + 12] = 5e4;
    let full = plan
        .apply(&image, 1.0, &ApplyOptions::default(), &mut |_| {})
        .unwrap()
        .image;
    let glare_options = ApplyOptions {
        glare_only: true,
        ..ApplyOptions::default()
    };
    let glare = plan
        .apply(&image, 1.0, &glare_options, &mut |_| {})
        .unwrap()
        .image;
    for c in 0..3 {
        for i in 0..w * h {
            let composite = image.planes[c][i] + glare.planes[c][i];
            assert!(
                (composite - full.planes[c][i]).abs() <= 1e-3 * full.planes[c][i].abs().max(1.0)
            );
        }
    }
}

#[test]
fn the_soft_knee_rises_smoothly_from_the_threshold() {
    assert_eq!(spread_fraction(10.0, 10.0, 0.5), 0.0);
    assert_eq!(spread_fraction(15.0, 10.0, 0.5), 1.0);
    assert_eq!(spread_fraction(10.001, 10.0, 0.0), 1.0);
    let mut last = 0.0;
    for i in 1..100 {
        let f = spread_fraction(10.0 + 5.0 * i as f64 / 100.0, 10.0, 0.5);
        assert!(f > last && f < 1.0);
        last = f;
    }
}

#[test]
fn a_plan_refuses_an_image_of_another_size() {
    let plan = Plan::for_image(&paper_config(), 10, 10, None).unwrap();
    let image = Image::filled(11, 10, Layout::Luminance, 1.0);
    let e = plan
        .apply(&image, 1.0, &ApplyOptions::default(), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(e.contains("11x10") && e.contains("10x10"), "{e}");
}

#[test]
fn input_scale_sets_what_the_threshold_means() {
    let (w, h) = (16, 16);
    let plan = Plan::for_image(&bloom_config(0.3, 2.0, 2.0), w, h, None).unwrap();
    let mut image = Image::filled(w, h, Layout::Luminance, 0.0);
    image.planes[0][8 * w + 8] = 2.0; // 2 units = 1242 cd/m² at 621 cd/m² per unit
    let spread = |scale: f64| {
        let options = ApplyOptions {
            threshold: Some(1000.0),
            ..ApplyOptions::default()
        };
        plan.apply(&image, scale, &options, &mut |_| {})
            .unwrap()
            .spread_pixels
    };
    assert_eq!(spread(621.0), 1);
    assert_eq!(spread(1.0), 0);
}

/// A night scene: dim background and a few lamps, one of them at a corner.
fn night(w: usize, h: usize, layout: Layout) -> Image {
    let mut image = Image::filled(w, h, layout, 0.02);
    for (i, plane) in image.planes.iter_mut().enumerate() {
        plane[3 * w + 5] = 4e4 + 1e3 * i as f32;
        plane[(h - 1) * w + w - 1] = 9e3;
        plane[(h / 2) * w + w / 3] = 2.5e2;
        plane[7 * w + w / 2] = 30.0 + i as f32;
    }
    image
}

#[test]
fn splatting_gives_the_fft_result() {
    let (w, h) = (48, 30);
    let coloured = Kernel::from_planes(
        31,
        21,
        (0..3).map(|c| pseudo_random(31 * 21, 40 + c)).collect(),
    )
    .unwrap();
    for layout in [Layout::Rgb, Layout::Luminance] {
        let image = night(w, h, layout);
        for plan in [
            Plan::for_image(&paper_config(), w, h, None).unwrap(),
            Plan::with_kernel(coloured.clone(), w, h).unwrap(),
        ] {
            for (threshold, knee) in [(0.0, 0.0), (100.0, 0.0), (100.0, 2.0)] {
                let run = |method| {
                    let options = ApplyOptions {
                        threshold: Some(threshold),
                        knee,
                        method,
                        ..ApplyOptions::default()
                    };
                    plan.apply(&image, 1.0, &options, &mut |_| {}).unwrap()
                };
                let (fft, splat) = (run(Method::Fft), run(Method::Splat));
                assert_eq!((fft.method, splat.method), (Method::Fft, Method::Splat));
                // FFT round-off is relative to the brightest input.
                let scale = image.planes[0].iter().fold(0f32, |m, v| m.max(v.abs()));
                for (a, b) in fft.image.planes.iter().zip(&splat.image.planes) {
                    for (x, y) in a.iter().zip(b) {
                        assert!(
                            (x - y).abs() <= 2e-6 * scale,
                            "{layout:?} T={threshold}: {x} vs {y}"
                        );
                    }
                }
                assert!((fft.energy_out - splat.energy_out).abs() <= 1e-5 * fft.energy_out);
            }
        }
    }
}

#[test]
fn auto_splats_a_few_lights_and_transforms_a_bright_frame() {
    let (w, h) = (64, 40);
    let capped = Plan::for_image(&paper_config(), w, h, Some((9, 9))).unwrap();
    let options = |threshold| ApplyOptions {
        threshold: Some(threshold),
        ..ApplyOptions::default()
    };
    let lights = night(w, h, Layout::Rgb);
    let few = capped
        .apply(&lights, 1.0, &options(100.0), &mut |_| {})
        .unwrap();
    assert_eq!((few.spread_pixels, few.method), (3, Method::Splat));
    let full = Plan::for_image(&paper_config(), w, h, None).unwrap();
    let all = full
        .apply(&lights, 1.0, &options(0.0), &mut |_| {})
        .unwrap();
    assert_eq!((all.spread_pixels, all.method), (w * h, Method::Fft));
}

#[test]
fn kernels_and_results_have_the_same_bytes_with_any_number_of_threads() {
    let (w, h) = (52, 30);
    let image = night(w, h, Layout::Rgb);
    for method in [Method::Fft, Method::Splat] {
        let options = ApplyOptions {
            threshold: Some(100.0),
            knee: 0.5,
            method,
            ..ApplyOptions::default()
        };
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    let plan = Plan::for_image(&paper_config(), w, h, None).unwrap();
                    let applied = plan.apply(&image, 1.0, &options, &mut |_| {}).unwrap();
                    (
                        plan.kernel().clone(),
                        applied.image.planes,
                        applied.energy_out,
                    )
                })
        };
        assert_eq!(run(1), run(3), "{method:?}");
    }
}

/// A sun of 10⁹ cd/m² (a disc of 13 pixels) over a night sky of 10⁻² cd/m².
fn sun_over_night_sky(w: usize, h: usize) -> Image {
    let sky = pseudo_random(w * h, 11);
    let mut image = Image::filled(w, h, Layout::Rgb, 0.0);
    for (c, plane) in image.planes.iter_mut().enumerate() {
        for (i, v) in plane.iter_mut().enumerate() {
            *v = 0.005 + 0.015 * sky[i] + 0.001 * c as f32;
        }
        for dy in -2i64..=2 {
            for dx in -2i64..=2 {
                if dx * dx + dy * dy <= 4 {
                    let (x, y) = ((w / 4) as i64 + dx, (h / 3) as i64 + dy);
                    plane[y as usize * w + x as usize] = 1e9;
                }
            }
        }
    }
    image
}

/// The largest relative error over the dark pixels (input below 1 cd/m²).
fn worst_dark_error(result: &[f32], reference: &[f64], input: &[f32]) -> f64 {
    result
        .iter()
        .zip(reference)
        .zip(input)
        .filter(|(_, &i)| i < 1.0)
        .map(|((&r, &d), _)| (f64::from(r) - d).abs() / d)
        .fold(0.0, f64::max)
}

#[test]
fn a_sun_beside_a_night_sky_keeps_its_dark_pixels_within_one_percent() {
    // A tight bloom, so that far from the sun the sky stays dark and only
    // round-off could lift it: the sun's near light is added exactly.
    sun_keeps_the_dark_pixels(&bloom_config(0.05, 4.0, 1.0), true, |a| {
        matches!(a, Arithmetic::Lamps(13))
    });
}

#[test]
fn a_sun_whose_light_reaches_far_goes_through_f64() {
    // A wide bloom carries too much of the sun beyond any near window (and
    // lifts the sky enough that f32 alone would not drown it).
    for config in [bloom_config(0.3, 1.5, 1.0), paper_config()] {
        sun_keeps_the_dark_pixels(&config, false, |a| a == Arithmetic::Double);
    }
}

/// With `config`, the sun's night sky within 1 % of the direct sums, the
/// arithmetic `expected`; with `drowns`, f32 alone would be off by more.
fn sun_keeps_the_dark_pixels(config: &Config, drowns: bool, expected: impl Fn(Arithmetic) -> bool) {
    let (w, h) = (64, 48);
    let image = sun_over_night_sky(w, h);
    let plan = Plan::for_image(config, w, h, None).unwrap();
    let options = ApplyOptions {
        method: Method::Fft,
        ..ApplyOptions::default()
    };
    let applied = plan.apply(&image, 1.0, &options, &mut |_| {}).unwrap();
    assert!(expected(applied.arithmetic), "{:?}", applied.arithmetic);
    let mut worst = 0.0f64;
    for (c, plane) in image.planes.iter().enumerate() {
        let channel = c.min(plan.kernel().planes().len() - 1);
        let single = Kernel::from_planes(
            plan.kernel().width(),
            plan.kernel().height(),
            vec![plan.kernel().planes()[channel].clone()],
        )
        .unwrap();
        let reference = direct(plane, w, h, &single);
        worst = worst.max(worst_dark_error(
            &applied.image.planes[c],
            &reference,
            plane,
        ));

        // The f32 route alone drowns them: the check above has work to do.
        let f32_route = convolve(&convolver(&single, w, h, Centre::Leave), plane, 0);
        let drowned = worst_dark_error(&f32_route, &reference, plane);
        eprintln!(
            "f32 alone: dark pixels off by up to {:.0} %",
            100.0 * drowned
        );
        assert!(!drowns || drowned > 0.01);
    }
    assert!(worst < 0.01, "dark pixels off by {:.3} %", 100.0 * worst);
    // Splatting adds each bright pixel exactly too.
    let options = ApplyOptions {
        method: Method::Splat,
        ..ApplyOptions::default()
    };
    let splatted = plan.apply(&image, 1.0, &options, &mut |_| {}).unwrap();
    for (a, b) in splatted.image.planes[0]
        .iter()
        .zip(&applied.image.planes[0])
    {
        assert!((a - b).abs() <= 1e-4 * b.abs().max(1e-2), "{a} {b}");
    }
}

#[test]
fn f32_round_off_stays_below_what_the_range_check_assumes() {
    // Dense and sparse scenes: the worst f32 error over the dark pixels
    // (below 1), against the direct sum, within the estimate that decides
    // when f64 is needed.
    let (w, h) = (64, 48);
    let values = pseudo_random(w * h, 5);
    let dense: Vec<f32> = values.iter().map(|v| 10f32.powf(6.0 * v - 1.0)).collect();
    let sparse: Vec<f32> = values
        .iter()
        .map(|&v| if v > 0.99 { 1e5 * v } else { 0.05 })
        .collect();
    for (name, plane) in [("dense", dense), ("sparse", sparse)] {
        for config in [bloom_config(0.05, 2.0, 4.0), paper_config()] {
            let kernel = config
                .kernel(&aureole::Extent::for_image(w, h).unwrap())
                .unwrap();
            let centre = kernel.at(0, 0, 0);
            let engine = convolver(&kernel, w, h, Centre::Leave);
            let fast = convolve(&engine, &plane, 0);
            let reference = direct(&plane, w, h, &kernel);
            let error = fast
                .iter()
                .zip(&reference)
                .zip(&plane)
                .filter(|(_, &v)| v < 1.0)
                .map(|((&f, &d), _)| (f64::from(f) - d).abs())
                .fold(0.0, f64::max);
            let l2 = plane
                .iter()
                .map(|&v| f64::from(v).powi(2))
                .sum::<f64>()
                .sqrt();
            let moved = 1.0 - f64::from(centre);
            let estimate = aureole::pipeline::f32_round_off(l2, moved, engine.padded_size());
            eprintln!("{name}: dark error {error:.2e}, estimate {estimate:.2e}");
            assert!(error < estimate, "{name}: {error:e} > {estimate:e}");
        }
    }
}

/// A night street in small: sky of 0.003–0.023 cd/m², lit windows of
/// 30–200, and eight lamps of 10⁵–4.5·10⁵ cd/m², 5×5 pixels each.
fn night_street(w: usize, h: usize) -> Image {
    let noise = pseudo_random(w * h, 21);
    let mut image = Image::filled(w, h, Layout::Rgb, 0.0);
    for (c, plane) in image.planes.iter_mut().enumerate() {
        for (i, v) in plane.iter_mut().enumerate() {
            let (x, y) = (i % w, i / w);
            *v = 0.003 + 0.02 * noise[i] * (1.0 - y as f32 / h as f32);
            if (x / 6) % 3 == 1 && (y / 8) % 2 == 1 && y > h / 3 && y < 2 * h / 3 {
                *v = 30.0 + 170.0 * noise[i] + 5.0 * c as f32;
            }
        }
        for lamp in 0..8 {
            let (lx, ly) = (w / 16 + lamp * w / 8, h / 4 + (lamp % 3) * 4);
            let level = 1e5 + 5e4 * lamp as f32 + 1e3 * c as f32;
            for dy in 0..5 {
                for dx in 0..5 {
                    plane[(ly + dy) * w + lx + dx] = level;
                }
            }
        }
    }
    image
}

#[test]
fn a_night_street_sets_its_lamps_apart_and_keeps_its_dark_pixels_within_3e_4() {
    let (w, h) = (240, 135);
    let image = night_street(w, h);
    let plan = Plan::for_image(&preset_config("camera-f8-7blade"), w, h, None).unwrap();
    let options = ApplyOptions {
        threshold: Some(0.0),
        method: Method::Fft,
        ..ApplyOptions::default()
    };
    let applied = plan.apply(&image, 1.0, &options, &mut |_| {}).unwrap();
    assert!(
        matches!(applied.arithmetic, Arithmetic::Lamps(n) if (25..=500).contains(&n)),
        "{:?}",
        applied.arithmetic
    );
    let kernel = plan.kernel();
    // Direct sums in f64 at every 37th pixel of the sky, the whole image
    // spread (threshold 0): the definition, against the f32 route with
    // its lamps apart and against f32 alone.
    let samples: Vec<usize> = (0..w * h)
        .step_by(37)
        .filter(|&i| image.planes[1][i] < 1.0)
        .collect();
    let (mut lamps_worst, mut alone_worst) = (0.0f64, 0.0f64);
    for (c, plane) in image.planes.iter().enumerate() {
        let k = c.min(kernel.planes().len() - 1);
        let single = Kernel::from_planes(
            kernel.width(),
            kernel.height(),
            vec![kernel.planes()[k].clone()],
        )
        .unwrap();
        let alone = convolve(&convolver(&single, w, h, Centre::Leave), plane, 0);
        for &i in &samples {
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            let mut sum = 0.0f64;
            for (p, &v) in plane.iter().enumerate() {
                let (px, py) = ((p % w) as i64, (p / w) as i64);
                sum += f64::from(v) * f64::from(kernel.at(k, x - px, py - y));
            }
            let error = |value: f32| (f64::from(value) - sum).abs() / sum;
            lamps_worst = lamps_worst.max(error(applied.image.planes[c][i]));
            alone_worst = alone_worst.max(error(alone[i]));
        }
    }
    eprintln!(
        "dark pixels off by up to {:.4} % with the lamps apart, {:.2} % in f32 alone",
        100.0 * lamps_worst,
        100.0 * alone_worst
    );
    // docs/physics.md §8's bound (3·10⁻⁴, measured at 4K; 5·10⁻⁵ here).
    assert!(lamps_worst < 3e-4, "{lamps_worst}");
    assert!(alone_worst > 0.01, "f32 alone is exact enough: no test");

    // The lamps' route gives the same bytes on any number of threads.
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| plan.apply(&image, 1.0, &options, &mut |_| {}).unwrap())
    };
    assert_eq!(run(1).image.planes, run(3).image.planes);
    assert_eq!(run(2).image.planes, applied.image.planes);
}

#[test]
fn a_luminance_night_street_through_a_coloured_kernel_keeps_its_dark_pixels_too() {
    // Y = Σ w_k K_k ⊛ Y: each kernel plane takes the lamps apart.
    let (w, h) = (240, 135);
    let street = night_street(w, h);
    let mut image = Image::filled(w, h, Layout::Luminance, 0.0);
    image.planes[0] = street.luminance();
    let plan = Plan::for_image(&preset_config("camera-f8-7blade"), w, h, None).unwrap();
    let kernel = plan.kernel();
    assert_eq!(kernel.planes().len(), 3);
    let options = ApplyOptions {
        threshold: Some(0.0),
        method: Method::Fft,
        ..ApplyOptions::default()
    };
    let applied = plan.apply(&image, 1.0, &options, &mut |_| {}).unwrap();
    assert!(
        matches!(applied.arithmetic, Arithmetic::Lamps(_)),
        "{:?}",
        applied.arithmetic
    );
    let plane = &image.planes[0];
    let mut worst = 0.0f64;
    for i in (0..w * h).step_by(41).filter(|&i| plane[i] < 1.0) {
        let (x, y) = ((i % w) as i64, (i / w) as i64);
        let mut sum = 0.0f64;
        for (k, weight) in aureole::image::REC709_LUMINANCE.iter().enumerate() {
            for (p, &v) in plane.iter().enumerate() {
                let (px, py) = ((p % w) as i64, (p / w) as i64);
                sum += f64::from(*weight) * f64::from(v) * f64::from(kernel.at(k, x - px, py - y));
            }
        }
        worst = worst.max((f64::from(applied.image.planes[0][i]) - sum).abs() / sum);
    }
    assert!(worst < 0.01, "dark pixels off by {:.3} %", 100.0 * worst);
}
