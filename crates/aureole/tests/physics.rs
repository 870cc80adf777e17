//! The kernels against the physics of docs/physics.md §2–5: each test computes a
//! property of a kernel and compares it with the closed-form result.

// References and workloads, not the library: the platform's maths
// (clippy.toml refuses it in the core) is as good as libm here.
#![allow(clippy::disallowed_methods)]

use std::f64::consts::PI;

use aureole::kernel::profile::angular_profile;
use aureole::{
    Bloom, CameraGeometry, Config, ConfigFile, Corona, Effect, Extent, Kernel, Length, Sending, Vos,
};
use proptest::prelude::*;

fn kernel(effects: Vec<Effect>, camera: CameraGeometry, seed: u64, size: usize) -> Kernel {
    kernel_for(effects, camera, seed, size, size)
}

/// [`kernel`] for an image `image_width` wide.
fn kernel_for(
    effects: Vec<Effect>,
    camera: CameraGeometry,
    seed: u64,
    size: usize,
    image_width: usize,
) -> Kernel {
    let config = Config {
        seed,
        camera,
        effects,
        ..Config::default()
    };
    // The PSF of a point of light, as the formulas below give it.
    let extent = Extent::new(size, size)
        .unwrap()
        .with_image_width(image_width)
        .sent_by(Sending::Point);
    config.kernel(&extent).unwrap()
}

fn bloom(epsilon: f64, beta: f64, radius_px: f64) -> Effect {
    Effect::Bloom(Bloom {
        epsilon,
        beta,
        radius: Length::px(radius_px),
    })
}

fn corona(rays: u32, length: f64, width: f64, spread: f64) -> Corona {
    Corona {
        epsilon: 0.05,
        rays,
        length: Length::px(length),
        fadeout: 1.0,
        width: Length::px(width),
        spread,
        length_jitter: 0.0,
        width_jitter: 0.0,
        intensity_jitter: 0.0,
        rotation_deg: 0.0,
    }
}

fn camera(sensor_mm: f64, focal_mm: f64) -> CameraGeometry {
    CameraGeometry {
        sensor_width_mm: Some(sensor_mm),
        focal_length_mm: Some(focal_mm),
        f_number: None,
        ..CameraGeometry::default()
    }
}

// ---------------------------------------------------------- ΣK ≤ 1, cut

/// Property tests draw their cases from a fixed seed: CI reruns the same
/// cases on every machine.
fn cases(count: u32) -> ProptestConfig {
    ProptestConfig {
        cases: count,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x0061_7572_656f_6c65),
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(cases(64))]

    #[test]
    fn every_kernel_holds_its_share_of_the_light(
        epsilon in 0.0..=1.0f64,
        beta in 1.05..6.0f64,
        radius in 0.2..30.0f64,
        rays in 1u32..24,
        length in 1.0..80.0f64,
        width in 0.5..12.0f64,
        spread in -1.5..1.5f64,
        jitter in 0.0..=1.0f64,
        rotation in -360.0..360.0f64,
        exponent in 1.5..=3.0f64,
        size in 1usize..70,
        which in 0usize..4,
    ) {
        let c = Corona { epsilon, length_jitter: jitter, width_jitter: jitter, intensity_jitter: jitter,
            rotation_deg: rotation, ..corona(rays, length, width, spread) };
        let effects = match which {
            0 => vec![bloom(epsilon, beta, radius)],
            1 => vec![Effect::Corona(c)],
            2 => vec![Effect::Vos(Vos { epsilon, exponent })],
            _ => vec![bloom(epsilon, beta, radius), Effect::Corona(c), Effect::Vos(Vos { epsilon, exponent })],
        };
        // The kernel is the PSF's light cut to its window: a larger window
        // holds the same weights where both reach, and more light.
        let large_size = 2 * size + 41;
        let k = kernel_for(effects.clone(), camera(36.0, 50.0), 1, size, 64);
        let large = kernel_for(effects, camera(36.0, 50.0), 1, large_size, 64);
        prop_assert!(k.planes()[0].iter().all(|&v| v >= 0.0 && v.is_finite()));
        prop_assert!(k.sum(0) <= large.sum(0) + 1e-6, "{} within {size} px, {} within {large_size}", k.sum(0), large.sum(0));
        prop_assert!(large.sum(0) <= 1.0 + 1e-6, "sum {}", large.sum(0));
        if which < 3 {
            // Vos, singular at the centre, is normalised by the light its
            // pixels hold and the integral beyond them: the two windows
            // agree to the midpoint rule's 10⁻³.
            let tolerance = if which == 2 { 2e-3 } else { 1e-6 };
            let half = (size / 2) as i64;
            // y is up: the top row is +half.
            for dy in -(size as i64 - 1 - half)..=half {
                for dx in -half..=(size as i64 - 1 - half) {
                    let (a, b) = (f64::from(k.at(0, dx, dy)), f64::from(large.at(0, dx, dy)));
                    prop_assert!((a - b).abs() <= tolerance * b + 1e-12, "({dx}, {dy}): {a} vs {b}");
                }
            }
        }
        if which == 0 {
            // Bloom's light beyond a radius ρ is (1 + ρ²/R²)^(1−β) of it: the
            // window holds more than the disc within it, less than the disc
            // around it (to the midpoint rule's 10⁻³).
            let beyond = |rho: f64| (1.0 + rho * rho / (radius * radius)).powf(1.0 - beta);
            let inner = (large_size / 2) as f64 + 0.5;
            let spread = (large.sum(0) - (1.0 - epsilon)) / epsilon.max(1e-300);
            if epsilon > 1e-6 {
                prop_assert!(
                    spread >= 1.0 - beyond(inner) - 1e-3 && spread <= 1.0 - beyond(inner * std::f64::consts::SQRT_2) + 1e-3,
                    "β {beta}, R {radius}: {spread} of the spread light within {inner} px, {} within the disc",
                    1.0 - beyond(inner)
                );
            }
        }
        // The unspread part, (1 − ε) per effect of the chain, stays at the centre.
        let unspread = (1.0 - epsilon).powi(if which == 3 { 3 } else { 1 });
        prop_assert!(f64::from(k.at(0, 0, 0)) >= unspread - 1e-6);
    }
}

#[test]
fn epsilon_zero_is_the_identity() {
    let k = kernel(
        vec![bloom(0.0, 2.0, 10.0)],
        CameraGeometry::default(),
        1,
        33,
    );
    assert_eq!(k.at(0, 0, 0), 1.0);
    assert_eq!(k.sum(0), 1.0);
}

// ---------------------------------------------------------------- bloom, Eq. 6

/// K(r) = ε(β − 1)/(πR²)·(1 + (r/R)²)^(−β) within 2 % for 3R/10 ≤ r ≤ 10R.
fn check_moffat(beta: f64, radius_px: f64, effect: Effect, camera: CameraGeometry, size: usize) {
    let k = kernel(vec![effect], camera, 1, size);
    let theory = Bloom {
        epsilon: 0.005,
        beta,
        radius: Length::px(radius_px),
    };
    let half = (size / 2) as i64;
    let mut checked = 0;
    let mut worst: f64 = 0.0;
    for dy in -half..=half {
        for dx in -half..=half {
            let r = ((dx * dx + dy * dy) as f64).sqrt();
            if r < 0.3 * radius_px || r > 10.0 * radius_px {
                continue;
            }
            let expected = theory.density_at(r, radius_px);
            let error = (f64::from(k.at(0, dx, dy)) / expected - 1.0).abs();
            worst = worst.max(error);
            checked += 1;
        }
    }
    assert!(checked > 1000);
    assert!(
        worst < 0.02,
        "β {beta}, R {radius_px}: worst relative error {worst}"
    );
}

#[test]
fn bloom_profile_is_the_moffat_of_eq_6() {
    check_moffat(
        2.0,
        10.4,
        bloom(0.005, 2.0, 10.4),
        CameraGeometry::default(),
        1025,
    );
    check_moffat(
        3.5,
        6.0,
        bloom(0.005, 3.5, 6.0),
        CameraGeometry::default(),
        257,
    );
}

#[test]
fn bloom_radius_on_the_film_goes_through_the_pixel_pitch() {
    // 60 µm on a 36 mm sensor imaged over 3600 px (10 µm pitch): R = 6 px.
    let effect = Effect::Bloom(Bloom {
        epsilon: 0.005,
        beta: 3.5,
        radius: Length::um(60.0),
    });
    let config = Config {
        camera: camera(36.0, 50.0),
        effects: vec![effect],
        ..Config::default()
    };
    let extent = Extent::new(257, 257)
        .unwrap()
        .with_image_width(3600)
        .sent_by(Sending::Point);
    let from_um = config.kernel(&extent).unwrap();
    let from_px = kernel(
        vec![bloom(0.005, 3.5, 6.0)],
        CameraGeometry::default(),
        1,
        257,
    );
    for (a, b) in from_um.planes()[0].iter().zip(&from_px.planes()[0]) {
        assert!((a - b).abs() <= 1e-6 * b.abs().max(1e-12), "{a} vs {b}");
    }
}

// ---------------------------------------------------------------- corona, Eq. 7

/// The rays seen in the angular profile at `radius`: local maxima whose
/// prominence (how far the profile falls on both sides before rising higher)
/// is at least 5 % of their height, as angles in degrees. Peaks under 10⁻³ of
/// the strongest are background: at r = l even a ray 3σ shorter than the
/// mean keeps 3·10⁻² of the longest's intensity.
fn ray_peaks(k: &Kernel, radius: f64) -> Vec<f64> {
    let profile = angular_profile(k, 0, radius, 3600);
    let n = profile.len();
    let value = |i: usize| profile[i % n].1;
    let floor = 1e-3 * profile.iter().map(|p| p.1).fold(0.0, f64::max);
    let mut peaks = Vec::new();
    for (i, &(angle, here)) in profile.iter().enumerate() {
        if here < floor || !(here > value(i + n - 1) && here >= value(i + 1)) {
            continue;
        }
        // Lowest point on each side before the profile exceeds this peak.
        let lowest = |forward: bool| {
            let mut low = here;
            for j in 1..n {
                let v = value(i + if forward { j } else { n - j });
                if v > here {
                    break;
                }
                low = low.min(v);
            }
            low
        };
        let prominence = here - lowest(true).max(lowest(false));
        if prominence >= 0.05 * here {
            peaks.push(angle);
        }
    }
    peaks
}

proptest! {
    #![proptest_config(cases(64))]

    #[test]
    fn corona_has_k_rays_where_the_model_puts_them(
        rays in 2u32..=16,
        rotation in 0.0..360.0f64,
        spread in prop::sample::select(vec![-0.5, 0.0, 0.5, 1.0]),
        seed in 0u64..1000,
    ) {
        let c = Corona { rotation_deg: rotation, length_jitter: 0.25, ..corona(rays, 30.0, 4.0, spread) };
        let k = kernel(vec![Effect::Corona(c)], CameraGeometry::default(), seed, 161);
        let peaks = ray_peaks(&k, 30.0);
        prop_assert_eq!(peaks.len(), rays as usize);
        for peak in peaks {
            // Every peak lies on a ray axis φ₀ + 360°·m/k.
            let period = 360.0 / f64::from(rays);
            let offset = (peak - rotation).rem_euclid(period);
            prop_assert!(offset.min(period - offset) < 1.0, "peak at {} deg", peak);
        }
    }
}

/// FWHM across the ray along +x at distance r: the kernel's column x = r,
/// half-maximum crossings interpolated linearly.
fn measured_fwhm(k: &Kernel, r: i64) -> f64 {
    let values: Vec<f64> = (-40..=40).map(|dy| f64::from(k.at(0, r, dy))).collect();
    let peak = values[40];
    let half = peak / 2.0;
    let crossing = |step: i64| {
        let mut i = 40i64;
        while values[(i + step) as usize] > half {
            i += step;
        }
        let (a, b) = (values[i as usize], values[(i + step) as usize]);
        (i - 40) as f64 + step as f64 * (a - half) / (a - b)
    };
    crossing(1) - crossing(-1)
}

/// The FWHM the model gives at r: |cos(kφ/2)|^n(r) = ½ at φ_h, a half-width
/// of r·tan φ_h along the column, widened by the pixel's area (variance + 1/12
/// of a Gaussian of the same FWHM).
fn model_fwhm(rays: f64, width: f64, spread: f64, r: f64) -> f64 {
    let omega = (r / width).powf(spread - 1.0);
    let n = -1.0 / omega.cos().ln();
    let phi_half = (2.0 / rays) * (0.5f64.powf(1.0 / n)).acos();
    let fwhm = 2.0 * r * phi_half.tan();
    (fwhm * fwhm + 8.0 * 2f64.ln() / 12.0).sqrt()
}

fn fwhm_series(rays: u32, width: f64, spread: f64) -> Vec<(f64, f64)> {
    let c = Corona {
        fadeout: 0.3,
        ..corona(rays, 400.0, width, spread)
    };
    let k = kernel(vec![Effect::Corona(c)], CameraGeometry::default(), 1, 241);
    [30, 50, 70, 90, 110]
        .iter()
        .map(|&r| {
            (
                measured_fwhm(&k, r),
                model_fwhm(f64::from(rays), width, spread, r as f64),
            )
        })
        .collect()
}

#[test]
fn ray_width_is_constant_for_s_zero() {
    let series = fwhm_series(4, 8.0, 0.0);
    let first = series[0].0;
    for &(measured, model) in &series {
        assert!((measured / first - 1.0).abs() < 0.05, "{series:?}");
        assert!((measured / model - 1.0).abs() < 0.06, "{series:?}");
    }
}

#[test]
fn rays_converge_for_negative_s_and_diverge_for_positive_s() {
    for (rays, width, spread, shrinks) in [
        (4, 16.0, -0.5, true),
        (4, 3.0, 0.5, false),
        (14, 3.0, 1.0, false),
    ] {
        let series = fwhm_series(rays, width, spread);
        for pair in series.windows(2) {
            let (a, b) = (pair[0].0, pair[1].0);
            assert!(
                if shrinks { b < a } else { b > a },
                "s = {spread}: {series:?}"
            );
        }
        for &(measured, model) in &series {
            assert!(
                (measured / model - 1.0).abs() < 0.06,
                "s = {spread}: {series:?}"
            );
        }
    }
}

#[test]
fn intensity_along_each_ray_falls_as_exp_minus_sigma_r_over_its_length() {
    let (sigma, length, seed) = (2.0, 60.0, 11);
    let c = Corona {
        fadeout: sigma,
        length_jitter: 0.25,
        ..corona(4, length, 8.0, 0.0)
    };
    let factors = c.ray_factors(seed, 0);
    assert!(factors
        .windows(2)
        .any(|f| (f[0].length - f[1].length).abs() > 0.01));
    let k = kernel(
        vec![Effect::Corona(c)],
        CameraGeometry::default(),
        seed,
        321,
    );
    // Rays 0…3 point along +x, +y, −x, −y.
    let axes = [(1, 0), (0, 1), (-1, 0), (0, -1)];
    for (m, (ax, ay)) in axes.iter().enumerate() {
        let points: Vec<(f64, f64)> = (20..=150)
            .map(|r| (r as f64, f64::from(k.at(0, ax * r, ay * r)).ln()))
            .collect();
        let n = points.len() as f64;
        let (mx, my) = points
            .iter()
            .fold((0.0, 0.0), |s, p| (s.0 + p.0 / n, s.1 + p.1 / n));
        let slope = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>()
            / points.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
        let expected = -sigma / (length * factors[m].length);
        assert!(
            (slope / expected - 1.0).abs() < 0.01,
            "ray {m}: slope {slope}, expected {expected}"
        );
    }
}

#[test]
fn thin_rays_keep_their_energy_wherever_they_cross_the_pixel_grid() {
    // Fig. 6b's rays are ~0.7 px wide: by symmetry every ray carries the same
    // energy, which sampling only at pixel centres would break.
    let rays = 14;
    let c = Corona {
        rotation_deg: 7.3,
        ..corona(rays, 80.0, 3.0, 0.0)
    };
    let k = kernel(vec![Effect::Corona(c)], CameraGeometry::default(), 1, 241);
    let mut energy = vec![0.0; rays as usize];
    for dy in -120i64..=120 {
        for dx in -120i64..=120 {
            let r = ((dx * dx + dy * dy) as f64).sqrt();
            if !(10.0..=110.0).contains(&r) {
                continue;
            }
            let angle = (dy as f64).atan2(dx as f64) - 7.3f64.to_radians();
            let m = (angle.rem_euclid(2.0 * PI) / (2.0 * PI / f64::from(rays))).round() as usize
                % rays as usize;
            energy[m] += f64::from(k.at(0, dx, dy));
        }
    }
    let mean = energy.iter().sum::<f64>() / energy.len() as f64;
    for e in &energy {
        assert!((e / mean - 1.0).abs() < 0.01, "{energy:?}");
    }
}

#[test]
fn the_same_seed_gives_the_same_kernel_and_another_seed_other_rays() {
    let c = Corona {
        length_jitter: 0.25,
        ..corona(14, 20.0, 3.0, 1.0)
    };
    let a = kernel(
        vec![Effect::Corona(c.clone())],
        CameraGeometry::default(),
        5,
        101,
    );
    let b = kernel(
        vec![Effect::Corona(c.clone())],
        CameraGeometry::default(),
        5,
        101,
    );
    let other = kernel(
        vec![Effect::Corona(c.clone())],
        CameraGeometry::default(),
        6,
        101,
    );
    assert_eq!(a, b);
    assert_ne!(a, other);
    assert_ne!(c.ray_factors(5, 0), c.ray_factors(6, 0));
}

// ---------------------------------------------------------------- Vos, §5

#[test]
fn vos_glare_falls_as_theta_to_the_minus_n_per_solid_angle() {
    // 36 mm over 400 px behind a 50 mm lens: 0.09 mm pitch, 19.8° at 200 px.
    let exponent = 2.5;
    let k = kernel(
        vec![Effect::Vos(Vos {
            epsilon: 0.1,
            exponent,
        })],
        camera(36.0, 50.0),
        1,
        401,
    );
    let theta = |r: f64| (r * 0.09 / 50.0).atan();
    let model = |r: f64| theta(r).powf(-exponent) * theta(r).cos().powi(3);
    let reference = f64::from(k.at(0, 10, 0)) / model(10.0);
    for r in [5, 20, 50, 100, 150, 200] {
        let ratio = f64::from(k.at(0, r, 0)) / model(r as f64) / reference;
        assert!((ratio - 1.0).abs() < 0.02, "r {r}: {ratio}");
    }
    // The light that moves by less than half a pixel is not spread.
    assert!((f64::from(k.at(0, 0, 0)) - 0.9).abs() < 1e-6);
}

// ---------------------------------------------------------------- composition

fn second_moment(k: &Kernel) -> f64 {
    let (cx, cy) = k.centre();
    k.planes()[0]
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            let (dx, dy) = (
                (i % k.width()) as f64 - cx as f64,
                (i / k.width()) as f64 - cy as f64,
            );
            f64::from(v) * (dx * dx + dy * dy)
        })
        .sum()
}

#[test]
fn chained_effects_convolve_so_their_second_moments_add() {
    // β = 4 has a finite variance, R²/(β − 2) per unit of spread light.
    let (a, b) = (bloom(0.3, 4.0, 3.0), bloom(0.5, 4.0, 5.0));
    let ka = kernel(vec![a.clone()], CameraGeometry::default(), 1, 201);
    let kb = kernel(vec![b.clone()], CameraGeometry::default(), 1, 201);
    let both = kernel(vec![a, b], CameraGeometry::default(), 1, 201);
    let sum = second_moment(&ka) + second_moment(&kb);
    assert!((second_moment(&both) / sum - 1.0).abs() < 2e-3);
    // Nearly all the light of both falls within 100 px, and a chain keeps
    // what each keeps of it.
    assert!(
        (both.sum(0) - ka.sum(0) * kb.sum(0)).abs() < 1e-5 && both.sum(0) > 0.999,
        "{} vs {}·{}",
        both.sum(0),
        ka.sum(0),
        kb.sum(0)
    );
    // The unspread light is what neither spreads.
    let centre_spread = f64::from(ka.at(0, 0, 0)) - 0.7;
    assert!(f64::from(both.at(0, 0, 0)) > 0.7 * 0.5 + centre_spread * 0.5);
}

#[test]
fn an_effect_with_epsilon_zero_leaves_the_chain_unchanged() {
    let c = Effect::Corona(corona(6, 20.0, 3.0, 0.5));
    let alone = kernel(vec![c.clone()], CameraGeometry::default(), 1, 65);
    let chained = kernel(
        vec![c, bloom(0.0, 2.0, 5.0)],
        CameraGeometry::default(),
        1,
        65,
    );
    assert_eq!(alone, chained);
}

#[test]
fn even_sizes_put_the_centre_at_half_the_size() {
    let k = kernel(vec![bloom(0.2, 2.0, 3.0)], CameraGeometry::default(), 1, 64);
    assert_eq!(k.centre(), (32, 32));
    let peak = k.planes()[0].iter().cloned().fold(0f32, f32::max);
    assert_eq!(k.at(0, 0, 0), peak);
    for d in 1..30 {
        assert_eq!(k.at(0, d, 0), k.at(0, -d, 0));
        assert_eq!(k.at(0, 0, d), k.at(0, 0, -d));
    }
}

// ---------------------------------------------------------------- invalid parameters

#[test]
fn each_invalid_parameter_gets_its_error() {
    let effect = |body: &str| format!("[[effect]]\n{body}\n");
    let cases = [
        (
            effect("type = \"bloom\"\nepsilon = 0.1\nbeta = 1.0\nradius = \"3px\""),
            "beta = 1",
        ),
        (
            effect("type = \"bloom\"\nepsilon = 1.5\nbeta = 2.0\nradius = \"3px\""),
            "epsilon = 1.5",
        ),
        (
            effect("type = \"bloom\"\nepsilon = -0.1\nbeta = 2.0\nradius = \"3px\""),
            "epsilon = -0.1",
        ),
        (
            effect("type = \"bloom\"\nepsilon = nan\nbeta = 2.0\nradius = \"3px\""),
            "epsilon = NaN",
        ),
        (
            effect("type = \"bloom\"\nepsilon = 0.1\nbeta = inf\nradius = \"3px\""),
            "beta = inf",
        ),
        (
            effect("type = \"bloom\"\nepsilon = 0.1\nbeta = 2.0\nradius = \"0px\""),
            "above 0",
        ),
        (
            effect("type = \"corona\"\nepsilon = 0.1\nrays = 0\nlength = \"9px\""),
            "rays = 0",
        ),
        (
            effect("type = \"corona\"\nepsilon = 0.1\nrays = -3\nlength = \"9px\""),
            "-3",
        ),
        (
            effect("type = \"corona\"\nepsilon = 0.1\nrays = 6\nlength = \"-9px\""),
            "above 0",
        ),
        (
            effect("type = \"corona\"\nepsilon = 0.1\nrays = 6\nlength = \"9px\"\nwidth = \"0um\""),
            "above 0",
        ),
        (
            effect("type = \"corona\"\nepsilon = 0.1\nrays = 6\nlength = \"9px\"\nfadeout = 0.0"),
            "fadeout = 0",
        ),
        (
            effect(
                "type = \"corona\"\nepsilon = 0.1\nrays = 6\nlength = \"9px\"\nlength_jitter = 2.0",
            ),
            "length_jitter = 2",
        ),
        (
            effect("type = \"corona\"\nepsilon = 0.1\nrays = 6\nlength = \"9px\"\nspread = nan"),
            "spread = NaN",
        ),
        (
            effect("type = \"vos\"\nepsilon = 0.1\nexponent = 4.0"),
            "exponent = 4",
        ),
        (
            effect("type = \"bloom\"\nepsilon = 0.1\nbeta = 2.0"),
            "missing field `radius`",
        ),
    ];
    for (text, expected) in cases {
        let error = ConfigFile::parse(&text, "bad.toml")
            .unwrap_err()
            .to_string();
        assert!(error.starts_with("bad.toml:"), "{error}");
        assert!(error.contains(expected), "{text}\n=> {error}");
        assert!(!error.contains('\n'), "{error}");
    }
}

#[test]
fn physical_lengths_and_angles_without_a_camera_say_what_is_missing() {
    let um = vec![Effect::Bloom(Bloom {
        epsilon: 0.1,
        beta: 2.0,
        radius: Length::um(60.0),
    })];
    let vos = vec![Effect::Vos(Vos {
        epsilon: 0.1,
        exponent: 2.0,
    })];
    let extent = Extent::new(9, 9).unwrap();
    for (effects, cam, field) in [
        (um, CameraGeometry::default(), "sensor_width_mm"),
        (vos.clone(), CameraGeometry::default(), "focal_length_mm"),
        (
            vos,
            CameraGeometry {
                focal_length_mm: Some(50.0),
                ..CameraGeometry::default()
            },
            "sensor_width_mm",
        ),
    ] {
        let config = Config {
            camera: cam,
            effects,
            ..Config::default()
        };
        let error = config.kernel(&extent).unwrap_err().to_string();
        assert!(error.contains(field), "{error}");
    }
}
