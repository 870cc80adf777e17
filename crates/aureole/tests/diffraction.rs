//! Diffraction kernels against the closed-form results of optics
//! (paper §2, docs/physics.md §6).

// References and workloads, not the library: the platform's maths
// (clippy.toml refuses it in the core) is as good as libm here.
#![allow(clippy::disallowed_methods)]

use std::f64::consts::TAU;

use aureole::kernel::diffraction_kernel;
use aureole::kernel::profile::{bilinear, radial_profile};
use aureole::optics::aperture::pupil::Pupil;
use aureole::optics::aperture::spectrum::{mean_wavelengths, Light};
use aureole::optics::aperture::Optics;
use aureole::{Aperture, CameraGeometry, Config, Effect, Extent, Kernel, Sending};

const F: f64 = 50.0; // focal length, mm
const GREEN: f64 = 550.0; // nm

fn optics(pupil: Pupil, diameter_mm: f64) -> Optics {
    Optics {
        pupil,
        diameter_mm,
        stretch: 1.0,
        focal_mm: F,
        orders: vec![([0.0, 0.0], 1.0)],
    }
}

/// A stop of `blades` blades on the tests' 50 mm f/8 full-frame camera.
fn lens(blades: u32, spectral: bool) -> Aperture {
    Aperture {
        spectral,
        wavelength_nm: GREEN,
        ..Aperture::new(blades)
    }
}

fn camera_config(aperture: Aperture) -> Config {
    Config {
        camera: CameraGeometry {
            sensor_width_mm: Some(36.0),
            focal_length_mm: Some(F),
            f_number: Some(8.0),
            ..CameraGeometry::default()
        },
        effects: vec![Effect::Aperture(aperture)],
        ..Config::default()
    }
}

fn rectangle(cx: f64, cy: f64, w: f64, h: f64) -> Vec<[f64; 2]> {
    vec![
        [cx - w / 2.0, cy - h / 2.0],
        [cx + w / 2.0, cy - h / 2.0],
        [cx + w / 2.0, cy + h / 2.0],
        [cx - w / 2.0, cy + h / 2.0],
    ]
}

fn row(kernel: &Kernel, channel: usize) -> Vec<f64> {
    let (cx, _) = kernel.centre();
    (0..kernel.width() - cx)
        .map(|x| f64::from(kernel.at(channel, x as i64, 0)))
        .collect()
}

fn local_minima(values: &[f64]) -> Vec<usize> {
    (1..values.len() - 1)
        .filter(|&i| values[i] < values[i - 1] && values[i] <= values[i + 1])
        .collect()
}

fn local_maxima(values: &[f64]) -> Vec<usize> {
    (1..values.len() - 1)
        .filter(|&i| values[i] > values[i - 1] && values[i] >= values[i + 1])
        .collect()
}

#[test]
fn circular_stop_has_its_first_dark_ring_at_1_22_lambda_n() {
    let n = 8.0;
    let mut pupil = Pupil::new();
    pupil.add_disc([0.0, 0.0], F / n / 2.0, true);
    let pitch = 0.25e-3; // 0.25 µm: the ring at 1.22·0.55·8 = 5.37 µm is 21.5 px out
    let kernel = diffraction_kernel(
        &optics(pupil, F / n),
        Light::Monochrome(GREEN),
        &Extent::new(81, 81).unwrap().sent_by(Sending::Point),
        pitch,
    )
    .unwrap();
    let profile = radial_profile(&kernel, 0);
    let i = local_minima(&profile)[0];
    // Sub-pixel minimum by a parabola through the three rings around it.
    let (a, b, c) = (profile[i - 1], profile[i], profile[i + 1]);
    let minimum = i as f64 + 0.5 * (a - c) / (a - 2.0 * b + c);
    let expected = 1.22 * GREEN * 1e-6 * n / pitch;
    assert!(
        (minimum - expected).abs() < 0.5,
        "first dark ring at {minimum} px, theory {expected}"
    );
}

#[test]
fn single_slit_has_sinc_squared_zeros_at_m_lambda_f_over_e() {
    let e = 0.1; // mm
    let mut pupil = Pupil::new();
    pupil.add_polygon(&rectangle(0.0, 0.0, e, 4.0), true);
    let pitch = GREEN * 1e-6 * F / e / 10.0; // zeros every 10 px
    let kernel = diffraction_kernel(
        &optics(pupil, 4.0),
        Light::Monochrome(GREEN),
        &Extent::new(101, 9).unwrap().sent_by(Sending::Point),
        pitch,
    )
    .unwrap();
    let values = row(&kernel, 0);
    assert_eq!(local_minima(&values), vec![10, 20, 30, 40]);
    // Averaged over a pixel (a tenth of the period), a zero of sinc² keeps
    // ~(π/10)²/12 of the neighbouring lobe's level: far below it.
    for m in 1..=4 {
        assert!(values[10 * m] < 0.03 * values[10 * m + 5], "m = {m}");
    }
}

#[test]
fn n_slits_have_principal_maxima_at_m_lambda_f_over_d_and_n_minus_2_between() {
    let (slits, d, e) = (5, 0.1, 0.02);
    let mut pupil = Pupil::new();
    for k in 0..slits {
        let x = (k as f64 - (slits - 1) as f64 / 2.0) * d;
        pupil.add_polygon(&rectangle(x, 0.0, e, 2.0), true);
    }
    let pitch = GREEN * 1e-6 * F / d / 100.0; // principal maxima every 100 px
    let kernel = diffraction_kernel(
        &optics(pupil, 2.0),
        Light::Monochrome(GREEN),
        &Extent::new(451, 5).unwrap().sent_by(Sending::Point),
        pitch,
    )
    .unwrap();
    let values = row(&kernel, 0);
    let maxima = local_maxima(&values);
    let principal: Vec<usize> = maxima
        .iter()
        .copied()
        .filter(|&i| values[i] > 0.3 * values[0])
        .collect();
    assert_eq!(principal, vec![100, 200], "{maxima:?}");
    let between = maxima.iter().filter(|&&i| i > 2 && i < 98).count();
    assert_eq!(between, slits - 2, "{maxima:?}");
    assert_eq!(local_minima(&values[..100]).len(), slits - 1);
}

#[test]
fn many_random_equal_holes_give_the_single_hole_pattern() {
    let radius = 0.05;
    let mut one = Pupil::new();
    one.add_disc([0.0, 0.0], radius, true);
    let mut many = Pupil::new();
    let mut state = 12345u64;
    let mut uniform = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..30 {
        many.add_disc([2.0 * uniform() - 1.0, 2.0 * uniform() - 1.0], radius, true);
    }
    // The Airy zero of one hole: 1.22 λ f / 2a = 0.335 mm, 16.8 px.
    let (pitch, extent) = (0.02, Extent::new(81, 81).unwrap().sent_by(Sending::Point));
    let single = radial_profile(
        &diffraction_kernel(&optics(one, 2.0 * radius), Light::Spectral, &extent, pitch).unwrap(),
        1,
    );
    let sum = radial_profile(
        &diffraction_kernel(&optics(many, 2.0), Light::Spectral, &extent, pitch).unwrap(),
        1,
    );
    // At ν = 0 the holes add coherently (N² instead of N) within a speckle of
    // the centre: compare the shapes outside it, over the same rings.
    let rings = 4..14;
    let (ts, tm): (f64, f64) = (
        single[rings.clone()].iter().sum(),
        sum[rings.clone()].iter().sum(),
    );
    for r in rings {
        let (a, b) = (sum[r] / tm, single[r] / ts);
        assert!((a / b - 1.0).abs() < 0.15, "r {r}: {a} vs {b}");
    }
}

/// Prominent peaks of the kernel's angular profile averaged over radii
/// `r0`…`r1` px on an even polar grid.
fn ray_count(kernel: &Kernel, r0: f64, r1: f64) -> usize {
    let bins = 720;
    let profile: Vec<f64> = (0..bins)
        .map(|b| {
            let (sin, cos) = (TAU * b as f64 / bins as f64).sin_cos();
            let steps = ((r1 - r0) * 4.0) as usize;
            (0..=steps)
                .map(|s| {
                    let r = r0 + (r1 - r0) * s as f64 / steps as f64;
                    bilinear(kernel, 0, r * cos, r * sin) * r
                })
                .sum::<f64>()
        })
        .collect();
    let max = profile.iter().cloned().fold(0.0, f64::max);
    let value = |i: usize| profile[i % bins];
    (0..bins)
        .filter(|&i| {
            let here = value(i);
            if here < 0.1 * max || !(here > value(i + bins - 1) && here >= value(i + 1)) {
                return false;
            }
            let lowest = |forward: bool| {
                let mut low = here;
                for j in 1..bins {
                    let v = value(i + if forward { j } else { bins - j });
                    // Ties stop the walk one way only: twin maxima count once.
                    if v > here || (forward && v == here) {
                        break;
                    }
                    low = low.min(v);
                }
                low
            };
            here - lowest(true).max(lowest(false)) > 0.3 * here
        })
        .count()
}

fn aperture_kernel(blades: u32, rotation_deg: f64) -> Kernel {
    let config = camera_config(Aperture {
        rotation_deg,
        ..lens(blades, false)
    });
    // 36 mm over 8182 px: a 4.4 µm pitch, λN at 550 nm and f/8.
    config
        .kernel(
            &Extent::new(121, 121)
                .unwrap()
                .sent_by(Sending::Point)
                .with_image_width(8182),
        )
        .unwrap()
}

#[test]
fn an_n_blade_stop_gives_n_rays_for_even_n_and_2n_for_odd_n() {
    for blades in 3..=9u32 {
        let expected = if blades % 2 == 0 { blades } else { 2 * blades };
        for rotation in [0.0, 11.0] {
            let kernel = aperture_kernel(blades, rotation);
            // The share of the light within 60 px of the centre.
            assert!(
                kernel.sum(0) > 0.99 && kernel.sum(0) <= 1.0,
                "Σ {}",
                kernel.sum(0)
            );
            assert_eq!(
                ray_count(&kernel, 20.0, 58.0),
                expected as usize,
                "{blades} blades, rotated {rotation}°"
            );
        }
    }
}

#[test]
fn a_slit_network_follows_the_same_rule_babinet() {
    // Narrow slits along the sides of a regular polygon: the filter of the
    // paper's Fig. 2, and by Babinet the complement of a polygonal stop.
    for sides in 3..=6usize {
        let radius = 2.0;
        let mut pupil = Pupil::new();
        for k in 0..sides {
            let (a0, a1) = (
                TAU * k as f64 / sides as f64,
                TAU * (k + 1) as f64 / sides as f64,
            );
            let (p, q) = (
                [radius * a0.cos(), radius * a0.sin()],
                [radius * a1.cos(), radius * a1.sin()],
            );
            let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
            let length = (dx * dx + dy * dy).sqrt();
            let (nx, ny) = (-dy / length * 0.01, dx / length * 0.01);
            pupil.add_polygon(
                &[
                    [p[0] - nx, p[1] - ny],
                    [q[0] - nx, q[1] - ny],
                    [q[0] + nx, q[1] + ny],
                    [p[0] + nx, p[1] + ny],
                ],
                true,
            );
        }
        let kernel = diffraction_kernel(
            &optics(pupil, 2.0 * radius),
            Light::Monochrome(GREEN),
            &Extent::new(121, 121).unwrap().sent_by(Sending::Point),
            2e-3,
        )
        .unwrap();
        let expected = if sides % 2 == 0 { sides } else { 2 * sides };
        assert_eq!(ray_count(&kernel, 15.0, 58.0), expected, "{sides} slits");
    }
}

#[test]
fn red_spreads_wider_than_blue_by_the_ratio_of_their_wavelengths() {
    let n = 8.0;
    let mut pupil = Pupil::new();
    pupil.add_disc([0.0, 0.0], F / n / 2.0, true);
    let kernel = diffraction_kernel(
        &optics(pupil, F / n),
        Light::Spectral,
        &Extent::new(161, 161).unwrap().sent_by(Sending::Point),
        0.25e-3,
    )
    .unwrap();
    // The radius holding half the energy, per channel.
    let half_energy_radius = |c: usize| {
        let (cx, cy) = kernel.centre();
        let mut rings = vec![0.0; 200];
        for (i, &v) in kernel.planes()[c].iter().enumerate() {
            let (dx, dy) = (
                (i % kernel.width()) as f64 - cx as f64,
                (i / kernel.width()) as f64 - cy as f64,
            );
            rings[(dx * dx + dy * dy).sqrt().round() as usize] += f64::from(v);
        }
        let mut total = 0.0;
        for (r, e) in rings.iter().enumerate() {
            if total + e >= 0.5 {
                return r as f64 - 0.5 + (0.5 - total) / e;
            }
            total += e;
        }
        f64::NAN
    };
    for c in 0..3 {
        // λN is 18 px: 4.5 λN out, the rings beyond still hold 4 %.
        assert!(
            kernel.sum(c) > 0.94 && kernel.sum(c) <= 1.0,
            "Σ {}",
            kernel.sum(c)
        );
    }
    let [red, _, blue] = mean_wavelengths();
    let ratio = half_energy_radius(0) / half_energy_radius(2);
    assert!(
        (ratio / (red / blue) - 1.0).abs() < 0.1,
        "measured {ratio}, wavelengths {}",
        red / blue
    );
    assert!(ratio > 1.0);
}

#[test]
fn rays_reach_far_and_fade_as_the_inverse_square_of_the_distance() {
    // Along a straight edge's ray |F|² ∝ L²/q²: the light per pixel of
    // radius falls as r⁻². A 4K frame on full frame, f/8, 7 blades.
    let kernel = camera_config(lens(7, true))
        .kernel(
            &Extent::new(1601, 1601)
                .unwrap()
                .sent_by(Sending::Point)
                .with_image_width(3840),
        )
        .unwrap();
    let mut rings = vec![0.0; 801];
    let (cx, cy) = kernel.centre();
    for (i, &v) in kernel.planes()[1].iter().enumerate() {
        let (dx, dy) = ((i % 1601) as f64 - cx as f64, (i / 1601) as f64 - cy as f64);
        let r = (dx * dx + dy * dy).sqrt().round() as usize;
        if r <= 800 {
            rings[r] += f64::from(v);
        }
    }
    let band = |r: usize| rings[r - 20..r + 20].iter().sum::<f64>() / 40.0;
    let points: Vec<(f64, f64)> = [100, 200, 400, 750]
        .iter()
        .map(|&r| ((r as f64).ln(), band(r).ln()))
        .collect();
    let slope = (points[3].1 - points[0].1) / (points[3].0 - points[0].0);
    assert!((slope + 2.0).abs() < 0.15, "slope {slope}");
    // Still light 750 px out: the ray crosses the frame.
    assert!(band(750) > 1e-9);
}

fn star_config(families: &[f64], spacing_um: f64, width_um: f64, spectral: bool) -> Config {
    camera_config(Aperture {
        filters: families
            .iter()
            .map(|&angle_deg| aureole::Filter {
                angle_deg,
                spacing_um,
                width_um,
            })
            .collect(),
        ..lens(0, spectral)
    })
}

#[test]
fn filter_lines_diffract_into_orders_at_m_lambda_f_over_d() {
    // Vertical lines (90°) every d = 200 µm, e = 40 µm: orders along x at
    // m·λf/d = m·0.1375 mm, 20 px apart at 6.875 µm per pixel, each with
    // |c_m|² = (e/d)² sinc²(πme/d).
    let (d, e) = (200.0, 40.0);
    let kernel = star_config(&[90.0], d, e, false)
        .kernel(
            &Extent::new(141, 41)
                .unwrap()
                .sent_by(Sending::Point)
                .with_image_width((36.0 / 0.006875) as usize),
        )
        .unwrap();
    let values = row(&kernel, 0);
    let peaks: Vec<usize> = local_maxima(&values)
        .into_iter()
        .filter(|&i| values[i] > 1e-4 * values[0])
        .collect();
    assert_eq!(peaks, vec![20, 40, 60], "{peaks:?}");
    let weight = |m: f64| {
        let z = std::f64::consts::PI * m * e / d;
        (z.sin() / z).powi(2)
    };
    // Orders are narrow next to a pixel: compare the light within ±3 px.
    let around = |m: usize| values[20 * m - 3..=20 * m + 3].iter().sum::<f64>();
    for m in [2usize, 3] {
        let measured = around(m) / around(1);
        let theory = weight(m as f64) / weight(1.0);
        assert!(
            (measured / theory - 1.0).abs() < 0.1,
            "order {m}: {measured} vs {theory}"
        );
    }
}

#[test]
fn star_filters_give_two_rays_per_family_of_lines() {
    for (families, rays) in [
        (&[0.0, 90.0][..], 4),
        (&[0.0, 60.0, 120.0][..], 6),
        (&[0.0, 45.0, 90.0, 135.0][..], 8),
    ] {
        let kernel = star_config(families, 200.0, 10.0, true)
            .kernel(
                &Extent::new(161, 161)
                    .unwrap()
                    .sent_by(Sending::Point)
                    .with_image_width(3840),
            )
            .unwrap();
        assert_eq!(
            ray_count(&kernel, 20.0, 78.0),
            rays,
            "{} families",
            families.len()
        );
        // The filter's rays carry their light on beyond 80 px.
        assert!(
            kernel.sum(2) > 0.85 && kernel.sum(2) <= 1.0,
            "Σ {}",
            kernel.sum(2)
        );
    }
}

#[test]
fn an_anamorphic_lens_moves_a_filters_orders_in_across_x_and_lists_them_to_the_reach() {
    // Lines along y (angle 90°) put their orders along x, at m/d cycles
    // per mm; a lens squeezed s times is the filter stretched s times
    // (docs/physics.md §6): m/(s d) across x. Every order that lands
    // within the reach at 380 nm is listed, squeezed or not.
    let camera = CameraGeometry {
        sensor_width_mm: Some(36.0),
        focal_length_mm: Some(50.0),
        f_number: Some(8.0),
        ..CameraGeometry::default()
    };
    let (spacing_mm, reach_mm, focal) = (0.2, 5.0, 50.0);
    for squeeze in [1.0, 2.0] {
        let aperture = Aperture {
            filters: vec![aureole::Filter {
                angle_deg: 90.0,
                spacing_um: 1e3 * spacing_mm,
                width_um: 10.0,
            }],
            squeeze,
            ..Aperture::new(0)
        };
        let orders = aperture.optics(&camera, reach_mm, 0).unwrap().orders;
        let mut along: Vec<f64> = orders.iter().map(|(nu, _)| nu[0]).collect();
        along.sort_by(f64::total_cmp);
        let step = along
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::MAX, f64::min);
        assert!((step * spacing_mm * squeeze - 1.0).abs() < 1e-9, "{step}");
        let farthest = along.last().unwrap() * 380e-6 * focal;
        assert!(farthest >= reach_mm, "s {squeeze}: {farthest} mm");
    }
}
