//! Dust, scratches and grease in the pupil (docs/physics.md §6), held to
//! what diffraction theory says of them: Babinet's principle for the
//! specks, a slit's streak across each scratch, the light a smudge passes.
//! Their kernels against hcipy are in
//! crates/aureole-py/tests/test_diffraction_reference.py.

// References and workloads, not the library: the platform's maths
// (clippy.toml refuses it in the core) is as good as libm here.
#![allow(clippy::disallowed_methods)]

use std::f64::consts::{PI, TAU};

use aureole::optics::aperture::{first_optics, pupil::Pupil};
use aureole::{Aperture, CameraGeometry, Config, Effect, Extent, Kernel};

const F: f64 = 50.0;
const GREEN: f64 = 550.0;

fn first_pupil(config: &Config) -> Option<Pupil> {
    first_optics(config).ok().flatten().map(|o| o.pupil)
}

fn config(f_number: f64, aperture: Aperture) -> Config {
    Config {
        camera: CameraGeometry {
            sensor_width_mm: Some(36.0),
            focal_length_mm: Some(F),
            f_number: Some(f_number),
            ..CameraGeometry::default()
        },
        effects: vec![Effect::Aperture(aperture)],
        ..Config::default()
    }
}

/// A 7-blade stop in 550 nm.
fn stop() -> Aperture {
    Aperture {
        spectral: false,
        wavelength_nm: GREEN,
        rotation_deg: 5.0,
        ..Aperture::new(7)
    }
}

fn kernel(config: &Config, side: usize) -> Kernel {
    config
        .kernel(&Extent::new(side, side).unwrap().with_image_width(3840))
        .unwrap()
}

/// The light of `kernel` (plane 0) from `r0` to `r1` px out.
fn between(kernel: &Kernel, r0: f64, r1: f64) -> f64 {
    let (w, h) = (kernel.width(), kernel.height());
    let plane = &kernel.planes()[0];
    let mut sum = 0.0;
    for j in 0..h {
        for i in 0..w {
            let (dx, dy) = (i as f64 - (w / 2) as f64, j as f64 - (h / 2) as f64);
            if (r0..r1).contains(&dx.hypot(dy)) {
                sum += f64::from(plane[j * w + i]);
            }
        }
    }
    sum
}

/// J₀ and J₁ by their integrals, for the test's own Airy pattern.
fn bessel(n: i32, x: f64) -> f64 {
    let steps = 2000;
    (0..steps)
        .map(|k| {
            let t = PI * (k as f64 + 0.5) / steps as f64;
            (f64::from(n) * t - x * t.sin()).cos()
        })
        .sum::<f64>()
        / steps as f64
}

#[test]
fn each_speck_diffracts_the_light_of_its_own_area_into_its_airy_pattern() {
    // Babinet: an opaque speck of radius a takes πa² of the pupil's light
    // out of the beam and sends it into the Airy pattern of a hole of its
    // size, 1 − J₀²(v) − J₁²(v) of it within v = 2πa r/(λf). 30 specks of
    // 150 µm at f/4 (a 12.5 mm pupil), beside the stop's own rays: the
    // light beyond r grows by the specks' share of their Airy tails.
    let (count, diameter_mm, f_number) = (30u32, 0.15, 4.0);
    let dirty = Aperture {
        dust: count,
        dust_min_um: diameter_mm * 1e3,
        dust_max_um: diameter_mm * 1e3,
        ..stop()
    };
    let side = 1001;
    let clean_kernel = kernel(&config(f_number, stop()), side);
    let dirty_kernel = kernel(&config(f_number, dirty.clone()), side);
    let radius = F / f_number / 2.0;
    let pupil_area = first_pupil(&config(f_number, stop())).unwrap().area();
    let specks = f64::from(count) * PI * (diameter_mm / 2.0).powi(2);
    let dirty_area = first_pupil(&config(f_number, dirty)).unwrap().area();
    assert!((pupil_area - dirty_area - specks).abs() < 1e-9 * radius * radius);
    let pitch = 36.0 / 3840.0;
    let tail = |r: f64| {
        let v = TAU * (diameter_mm / 2.0) * r * pitch / (GREEN * 1e-6 * F);
        bessel(0, v).powi(2) + bessel(1, v).powi(2)
    };
    let edge = 480.0;
    for r in [40.0, 80.0, 160.0, 320.0] {
        let expected = specks * (tail(r) - tail(edge)) / dirty_area;
        let added = between(&dirty_kernel, r, edge)
            - between(&clean_kernel, r, edge) * pupil_area / dirty_area;
        assert!(
            (added / expected - 1.0).abs() < 0.04,
            "r = {r} px: the specks add {added:.3e} of the light, Airy says {expected:.3e}"
        );
    }
}

#[test]
fn a_scratch_sends_a_streak_across_itself() {
    // One scratch at 30°, 40 µm wide, on a round stop (which sends no
    // rays of its own): a slit, whose light spreads across it, along 120°
    // and 300°, λf/w ≈ 73 px wide.
    let round = Aperture {
        blades: 0,
        ..stop()
    };
    let scratched = Aperture {
        scratches: 1,
        scratch_angle_deg: 30.0,
        scratch_spread_deg: 0.0,
        scratch_width_um: 40.0,
        ..round.clone()
    };
    let side = 601;
    let clean = kernel(&config(8.0, round.clone()), side);
    let dirty = kernel(&config(8.0, scratched.clone()), side);
    let area = |a: Aperture| first_pupil(&config(8.0, a)).unwrap().area();
    // The stop's own light, over the pupil's smaller ∫|A|².
    let scale = (area(round) / area(scratched)) as f32;
    let (c, p) = (side / 2, &dirty.planes()[0]);
    let q: Vec<f32> = clean.planes()[0].iter().map(|v| v * scale).collect();
    // The added light on a ring of 150 px, in sectors of 1°.
    let mut sectors = vec![0.0f64; 360];
    for j in 0..side {
        for i in 0..side {
            let (dx, dy) = (i as f64 - c as f64, c as f64 - j as f64);
            if (dx.hypot(dy) - 150.0).abs() < 2.0 {
                let angle = dy.atan2(dx).to_degrees().rem_euclid(360.0);
                sectors[angle as usize % 360] += f64::from(p[j * side + i] - q[j * side + i]);
            }
        }
    }
    let brightest = (0..360)
        .max_by(|&a, &b| sectors[a].total_cmp(&sectors[b]))
        .unwrap_or(0) as f64;
    let off = ((brightest - 120.0).rem_euclid(180.0)).min((120.0 - brightest).rem_euclid(180.0));
    assert!(
        off <= 2.0,
        "the streak runs along {brightest}°, not across the scratch (120°)"
    );
    // Along the scratch it sends next to nothing.
    let along = sectors[30] + sectors[210];
    let across = sectors[120] + sectors[300];
    assert!(along < 0.02 * across, "along {along:e}, across {across:e}");
}

#[test]
fn a_smudge_passes_its_share_of_the_light_and_the_pupil_sums_its_power() {
    // A smudge passing 64 % of the light in a quarter of the diameter:
    // ∫|A|² loses 36 % of its area, whatever its phase.
    for phase in [0.0, 90.0, 200.0] {
        let greasy = Aperture {
            grease: 0.25,
            grease_transmission: 0.64,
            grease_phase_deg: phase,
            ..stop()
        };
        let clean = first_pupil(&config(8.0, stop())).unwrap();
        let pupil = first_pupil(&config(8.0, greasy.clone())).unwrap();
        let smudge = PI * (0.25 * F / 8.0 / 2.0).powi(2);
        assert!((clean.area() - pupil.area() - 0.36 * smudge).abs() < 1e-12);
        let k = kernel(&config(8.0, greasy), 201);
        for plane in k.planes() {
            let sum: f64 = plane.iter().map(|&v| f64::from(v)).sum();
            // The fields' light over 201 px, by Parseval against ∫|A|²: all
            // but the far tail beyond 100 px.
            assert!(sum > 0.995 && sum <= 1.0, "Σ {sum}");
            assert!(plane.iter().all(|v| *v >= 0.0));
        }
    }
}

#[test]
fn the_dirt_is_drawn_from_the_seed_and_kept_clear_of_the_vanes() {
    let dusty = Aperture {
        dust: 100,
        scratches: 4,
        grease: 0.2,
        obstruction: 0.3,
        vanes: 4,
        ..stop()
    };
    let with_seed = |seed: u64| Config {
        seed,
        ..config(8.0, dusty.clone())
    };
    let a = kernel(&with_seed(7), 161);
    assert_eq!(a.planes(), kernel(&with_seed(7), 161).planes());
    assert_ne!(a.planes(), kernel(&with_seed(8), 161).planes());
    // Every point of the pupil transmits 0, 1 or the smudge's amplitude:
    // nothing lies on top of anything else.
    let pupil = first_pupil(&with_seed(7)).unwrap();
    let radius = F / 8.0 / 2.0;
    let smudge = [0.0, 0.8f64.sqrt()];
    for j in 0..400 {
        for i in 0..400 {
            let point = [
                radius * (i as f64 / 200.0 - 1.0),
                radius * (j as f64 / 200.0 - 1.0),
            ];
            let [re, im] = pupil.transmission(point);
            let ok = [[0.0, 0.0], [1.0, 0.0], smudge]
                .iter()
                .any(|t| (re - t[0]).abs() < 1e-12 && (im - t[1]).abs() < 1e-12);
            assert!(ok, "{point:?} transmits {re} + {im}i");
        }
    }
}

#[test]
fn dirt_that_cannot_fit_is_refused_in_one_line() {
    let crowded = Aperture {
        dust: 2000,
        dust_min_um: 2000.0,
        dust_max_um: 2000.0,
        ..stop()
    };
    let error = config(8.0, crowded)
        .kernel(&Extent::new(65, 65).unwrap().with_image_width(3840))
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        error.starts_with("aperture: dust = 2000 is not allowed: specks that fit"),
        "{error}"
    );
}
