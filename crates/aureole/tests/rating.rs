//! Glare figures tested by geometry and by their formulas: a uniform sky
//! gives E_v = π·L through every fisheye, a small source adds L·ω·cos θ,
//! sources join within half the search angle and no further, the sun's
//! peak leaves its halo, and the figures are the same on any number of
//! threads. (`crates/aureole-py/tests/test_glare_reference.py` compares
//! them with Radiance's evalglare on rendered scenes.)

#![allow(clippy::disallowed_methods)]

use std::f64::consts::PI;

use aureole::rating::{rate, Rating, RatingOptions, Threshold};
use aureole::{Cancel, Image, Layout, Projection, View};

/// A `size`² luminance picture through `view`: `background` everywhere,
/// and `lamps` (direction, angular radius in degrees, luminance) drawn
/// where their discs cover pixel centres.
fn scene(size: usize, view: &View, background: f32, lamps: &[([f64; 3], f64, f32)]) -> Image {
    let pixels = view.pixels(size, size);
    let mut image = Image::filled(size, size, Layout::Luminance, background);
    for row in 0..size {
        for column in 0..size {
            let Some(sight) = pixels.pixel(column, row) else {
                continue;
            };
            for (direction, radius, luminance) in lamps {
                let n = direction.iter().map(|c| c * c).sum::<f64>().sqrt();
                let cos = sight
                    .direction
                    .iter()
                    .zip(direction)
                    .map(|(a, b)| a * b / n)
                    .sum::<f64>();
                if cos >= radius.to_radians().cos() {
                    image.planes[0][row * size + column] = *luminance;
                }
            }
        }
    }
    image
}

fn rated(image: &Image, view: &View, options: &RatingOptions) -> Rating {
    rate(image, 1.0, view, options, &Cancel::new()).unwrap()
}

#[test]
fn a_uniform_sky_gives_pi_times_its_luminance_through_every_fisheye() {
    for (projection, _) in Projection::ALL {
        if projection == Projection::Perspective {
            continue;
        }
        let view = View::new(projection, 180.0);
        let r = rated(
            &scene(401, &view, 1000.0, &[]),
            &view,
            &RatingOptions::default(),
        );
        assert!(
            (r.vertical_illuminance / (PI * 1000.0) - 1.0).abs() < 3e-3,
            "{projection:?}: E_v {}",
            r.vertical_illuminance
        );
        assert!((r.mean_luminance - 1000.0).abs() < 1e-6);
        assert!(r.sources.is_empty() && r.ugr == 0.0 && r.vcp == 100.0);
        // Without sources, DGP is its constant and linear term alone.
        assert!((r.dgp - (0.159 + 5.87e-5 * r.vertical_illuminance)).abs() < 1e-12);
    }
}

#[test]
fn a_lamp_adds_its_luminance_times_its_solid_angle_and_cosine() {
    let view = View::new(Projection::Equisolid, 180.0);
    let theta = 30f64.to_radians();
    let direction = [0.0, theta.sin(), theta.cos()];
    let (radius, lamp) = (2.0f64, 50_000.0f32);
    let image = scene(1001, &view, 10.0, &[(direction, radius, lamp)]);
    let r = rated(&image, &view, &RatingOptions::default());
    assert_eq!(r.sources.len(), 1);
    let s = &r.sources[0];
    let cap = 2.0 * PI * (1.0 - radius.to_radians().cos());
    assert!(
        (s.solid_angle / cap - 1.0).abs() < 0.03,
        "ω {} against {cap}",
        s.solid_angle
    );
    assert!((s.angle_deg - 30.0).abs() < 0.05, "{}", s.angle_deg);
    assert!((s.luminance - f64::from(lamp)).abs() < 1e-6);
    // E_v: the sky's π·L less what the lamp hides, plus the lamp's L·ω·cos θ.
    let expected = PI * 10.0 + (f64::from(lamp) - 10.0) * s.solid_angle * theta.cos();
    assert!((r.vertical_illuminance / expected - 1.0).abs() < 2e-3);
    let direct = f64::from(lamp) * s.solid_angle * theta.cos();
    assert!((r.direct_illuminance / direct - 1.0).abs() < 0.01);
    // The background is what is left: (E_v − E_dir)/π.
    assert!(
        (r.background_luminance - (r.vertical_illuminance - r.direct_illuminance) / PI).abs()
            < 1e-9
    );
    // UGR from its formula with the source's own numbers.
    let term = (s.luminance / s.position_index).powi(2) * s.solid_angle;
    let ugr = 8.0 * (0.25 / r.background_luminance * term).log10();
    assert!((r.ugr - ugr).abs() < 1e-9);
    // 30° straight up: Guth's fit at σ = 30°, τ = 0.
    let guth = ((35.2 - 1.22) * 1e-3 * 30.0 + 21.0 * 1e-5 * 900.0f64).exp();
    assert!(
        (s.position_index / guth - 1.0).abs() < 2e-3,
        "{}",
        s.position_index
    );
}

#[test]
fn lamps_join_within_half_the_search_angle_and_no_further() {
    let view = View::new(Projection::Equidistant, 180.0);
    let at = |deg: f64| {
        let a = deg.to_radians();
        [a.sin(), 0.0, a.cos()]
    };
    let count = |gap_deg: f64| {
        let image = scene(
            901,
            &view,
            5.0,
            &[
                (at(-gap_deg / 2.0), 0.5, 9000.0),
                (at(gap_deg / 2.0), 0.5, 9000.0),
            ],
        );
        rated(&image, &view, &RatingOptions::default())
            .sources
            .len()
    };
    // evalglare's default search angle 0.2 rad joins pixels within 0.1 rad
    // (5.73°): lamps of 0.5° radius whose centres are 5° apart are one
    // source, 8° apart two.
    assert_eq!(count(5.0), 1);
    assert_eq!(count(8.0), 2);
}

#[test]
fn the_suns_peak_leaves_its_halo_as_a_source_of_its_own() {
    let view = View::new(Projection::Equidistant, 180.0);
    let sun = [0.3, 0.2, (1.0f64 - 0.13).sqrt()];
    let image = scene(801, &view, 100.0, &[(sun, 8.0, 8000.0), (sun, 0.6, 1e9)]);
    let split = rated(&image, &view, &RatingOptions::default());
    assert_eq!(split.sources.len(), 2, "the sun and its halo");
    assert!(split.sources[0].luminance >= 1e9 * 0.999);
    let kept = rated(
        &image,
        &view,
        &RatingOptions {
            peak_limit: None,
            ..RatingOptions::default()
        },
    );
    assert_eq!(kept.sources.len(), 1, "without the peak split");
    // The same light either way.
    assert!((kept.direct_illuminance / split.direct_illuminance - 1.0).abs() < 1e-9);
}

#[test]
fn a_threshold_as_a_multiple_of_the_mean_or_the_task() {
    let view = View::new(Projection::Equidistant, 180.0);
    let image = scene(401, &view, 50.0, &[([0.0, 0.0, 1.0], 5.0, 400.0)]);
    let absolute = rated(&image, &view, &RatingOptions::default());
    assert!(absolute.sources.is_empty(), "400 cd/m² is below 2000");
    let multiple = rated(
        &image,
        &view,
        &RatingOptions {
            threshold: Some(Threshold::Multiple(5.0)),
            ..RatingOptions::default()
        },
    );
    assert!((multiple.threshold - 5.0 * multiple.mean_luminance).abs() < 1e-9);
    assert_eq!(multiple.sources.len(), 1);
    let task = aureole::rating::Task {
        column: 300.0,
        row: 200.0,
        angle: 0.3,
    };
    let with_task = rated(
        &image,
        &view,
        &RatingOptions {
            task: Some(task),
            ..RatingOptions::default()
        },
    );
    // The task sees only the 50 cd/m² background: 5× that is the threshold.
    assert!((with_task.task_luminance.unwrap() - 50.0).abs() < 1e-9);
    assert!((with_task.threshold - 250.0).abs() < 1e-9);
}

#[test]
fn the_figures_are_the_same_on_one_thread_and_many() {
    let view = View::new(Projection::Equidistant, 180.0);
    let image = scene(
        601,
        &view,
        30.0,
        &[
            ([0.2, 0.1, 0.97], 3.0, 20_000.0),
            ([-0.5, -0.2, 0.84], 6.0, 4000.0),
        ],
    );
    let many = rated(&image, &view, &RatingOptions::default());
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| rated(&image, &view, &RatingOptions::default()));
    assert_eq!(format!("{many:?}"), format!("{one:?}"));
}
