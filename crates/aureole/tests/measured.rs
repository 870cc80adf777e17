//! Measured and external PSFs (`type = "image"`, docs/physics.md §11):
//! resampled between pitches with the light conserved, their background
//! and noise removed.

// References and workloads, not the library: the platform's maths
// (clippy.toml refuses it in the core) is as good as libm here.
#![allow(clippy::disallowed_methods)]

use aureole::optics::measured::Picture;
use aureole::{Aperture, CameraGeometry, Config, Effect, Extent, Kernel, Measured, Sending};

const SENSOR: f64 = 36.0;

fn config(effects: Vec<Effect>) -> Config {
    Config {
        camera: CameraGeometry {
            sensor_width_mm: Some(SENSOR),
            focal_length_mm: Some(50.0),
            f_number: Some(8.0),
            ..CameraGeometry::default()
        },
        effects,
        ..Config::default()
    }
}

/// The kernel of an image `image_width` wide.
fn kernel(config: &Config, side: usize, image_width: usize) -> Kernel {
    kernel_of(config, side, image_width, Sending::Pixel)
}

/// The PSF of a point of light, as a photograph of a star gives it.
fn star(config: &Config, side: usize, image_width: usize) -> Kernel {
    kernel_of(config, side, image_width, Sending::Point)
}

fn kernel_of(config: &Config, side: usize, image_width: usize, sending: Sending) -> Kernel {
    let extent = Extent::new(side, side)
        .unwrap()
        .with_image_width(image_width)
        .sent_by(sending);
    config.kernel(&extent).unwrap()
}

fn picture(kernel: &Kernel) -> Picture {
    Picture {
        width: kernel.width(),
        height: kernel.height(),
        planes: kernel.planes().to_vec(),
    }
}

fn measured(picture: Picture, pitch_um: f64, floor: f64) -> Effect {
    let mut m = Measured {
        floor,
        ..Measured::new("psf.exr".into(), pitch_um)
    };
    m.load(picture);
    Effect::Image(m)
}

/// The light within r px of the centre, per plane, for r = 1, 2, 4, …
fn encircled(kernel: &Kernel) -> Vec<Vec<f64>> {
    let (w, h) = (kernel.width(), kernel.height());
    kernel
        .planes()
        .iter()
        .map(|plane| {
            (0..7)
                .map(|k| {
                    let r = f64::from(1 << k);
                    let mut sum = 0.0;
                    for j in 0..h {
                        for i in 0..w {
                            let (dx, dy) = (i as f64 - (w / 2) as f64, j as f64 - (h / 2) as f64);
                            if dx.hypot(dy) <= r {
                                sum += f64::from(plane[j * w + i]);
                            }
                        }
                    }
                    sum
                })
                .collect()
        })
        .collect()
}

fn relative_l2(a: &[f32], b: &[f32]) -> f64 {
    let d: f64 = a.iter().zip(b).map(|(x, y)| f64::from(x - y).powi(2)).sum();
    let n: f64 = b.iter().map(|y| f64::from(*y).powi(2)).sum();
    (d / n).sqrt()
}

#[test]
fn a_psf_taken_at_one_pitch_gives_the_kernel_built_at_another() {
    // A 7-blade stop's spectral kernel at 7680 px across the sensor (4.7
    // µm pixels), read back as a picture and resampled to 1920 px (4×)
    // and 2700 px (2.84×): the kernel aureole builds there directly, its
    // encircled energy within 1 % from 4 px out and 2 % at 2 px, within
    // 8.5 % (relative L2) over the whole kernel. A pixel's light is the
    // PSF integrated over it, so the sums of whole pixels are exact; what
    // differs is where within a fine pixel its light lies, taken uniform
    // across it. The coarse pixels' tents weigh that place (a square
    // weighed it only where it straddled two pixels): the 7-blade core at
    // f/8 is λN = 0.23 px at 1920 px, 0.35 px of it in one picture pixel
    // at 2.84×. Measured: 4.2 to 5.4 % at 4×, 6.1 to 7.9 % at 2.84×.
    let stop = Effect::Aperture(Aperture {
        rotation_deg: 5.0,
        ..Aperture::new(7)
    });
    let fine_width = 7680;
    let fine = star(&config(vec![stop.clone()]), 801, fine_width);
    let pitch_um = SENSOR / fine_width as f64 * 1e3;
    for width in [1920, 2700] {
        let direct = kernel(&config(vec![stop.clone()]), 161, width);
        let resampled = kernel(
            &config(vec![measured(picture(&fine), pitch_um, 0.0)]),
            161,
            width,
        );
        assert_eq!(resampled.planes().len(), 3);
        let (a, b) = (encircled(&resampled), encircled(&direct));
        for (c, (a, b)) in a.iter().zip(&b).enumerate() {
            for (k, (x, y)) in a.iter().zip(b).enumerate().skip(1) {
                let tolerance = if k == 1 { 0.02 } else { 0.01 };
                assert!(
                    (x / y - 1.0).abs() < tolerance,
                    "{width} px, plane {c}, r = {} px: {x} against {y}",
                    1 << k
                );
            }
        }
        for (c, (a, b)) in resampled.planes().iter().zip(direct.planes()).enumerate() {
            let l2 = relative_l2(a, b);
            eprintln!("{width} px, plane {c}: relative L2 {l2:.4}");
            assert!(l2 < 0.085, "{width} px, plane {c}: relative L2 {l2}");
        }
    }
}

/// A photographed star: a Gaussian core with a 1/r³ tail, on a black
/// level with noise (a fixed sequence, the same on every run).
fn photographed(side: usize, black: f32, noise: f32) -> (Vec<f32>, Vec<f32>) {
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut gaussian = || {
        let mut sum = 0.0;
        for _ in 0..12 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            sum += (state >> 11) as f64 / (1u64 << 53) as f64;
        }
        (sum - 6.0) as f32
    };
    let c = (side / 2) as f32;
    let clean: Vec<f32> = (0..side * side)
        .map(|i| {
            let (x, y) = ((i % side) as f32 - c, (i / side) as f32 - c);
            let r2 = x * x + y * y;
            1000.0 * (-r2 / 8.0).exp() + 20.0 / (1.0 + r2).powf(1.5)
        })
        .collect();
    let noisy = clean
        .iter()
        .map(|v| v + black + noise * gaussian())
        .collect();
    (clean, noisy)
}

#[test]
fn a_photographed_psfs_background_and_noise_become_no_veil() {
    // The same star clean and on a black level of 5 with noise of σ = 0.5:
    // with the default floor (3σ) the noisy picture gives the clean one's
    // kernel, the light beyond 60 px within 10⁻³ of it; the black level
    // alone, with no floor, would leave half the noise as a veil ten
    // times as strong.
    let side = 301;
    let (clean, noisy) = photographed(side, 5.0, 0.5);
    let as_picture = |plane: Vec<f32>| Picture {
        width: side,
        height: side,
        planes: vec![plane],
    };
    let build = |plane: Vec<f32>, floor: f64| {
        kernel(
            &config(vec![measured(
                as_picture(plane),
                SENSOR / 3840.0 * 1e3,
                floor,
            )]),
            301,
            3840,
        )
    };
    let beyond = |k: &Kernel| {
        let p = &k.planes()[0];
        (0..side * side)
            .filter(|i| {
                let (x, y) = ((i % side) as f64 - 150.0, (i / side) as f64 - 150.0);
                x.hypot(y) > 60.0
            })
            .map(|i| f64::from(p[i]))
            .sum::<f64>()
    };
    let reference = build(clean, 3.0);
    let cleaned = build(noisy.clone(), 3.0);
    let veiled = build(noisy.clone(), 0.0);
    let sum: f64 = cleaned.planes()[0].iter().map(|v| f64::from(*v)).sum();
    assert!((sum - 1.0).abs() < 1e-5);
    let (a, b, c) = (beyond(&cleaned), beyond(&reference), beyond(&veiled));
    assert!(
        (a - b).abs() < 1e-3,
        "beyond 60 px: {a} against the clean star's {b}"
    );
    assert!(c - b > 10.0 * (a - b).abs().max(1e-4), "no floor: {c}");
    // The survey finds the black level and the noise.
    let mut m = Measured::new("star.exr".into(), 9.375);
    m.load(as_picture(noisy));
    let survey = m.survey().unwrap();
    let (black, sigma) = survey.background[0];
    assert!(
        (black - 5.0).abs() < 0.05 && (sigma - 0.5).abs() < 0.05,
        "{black} ± {sigma}"
    );
    assert_eq!(survey.centre, [150.0, 150.0]);
}

#[test]
fn a_measured_psf_composes_with_the_other_effects_and_is_refused_unread() {
    let stop = Effect::Aperture(Aperture::new(6));
    let shot = star(&config(vec![stop.clone()]), 101, 1920);
    let pitch = SENSOR / 1920.0 * 1e3;
    let bloom: Effect = aureole::presets::find("paper-fig4-bloom")
        .unwrap()
        .config()
        .unwrap()
        .effects
        .remove(0);
    // The measured stop followed by a bloom is the stop followed by it: at
    // the same pitch and for a point of light, the picture is the kernel,
    // whose light is all a picture knows of (the stop's beyond 50 px is
    // not in it).
    let a = star(
        &config(vec![measured(picture(&shot), pitch, 0.0), bloom.clone()]),
        101,
        1920,
    );
    let b = star(&config(vec![stop, bloom]), 101, 1920);
    for (c, (x, y)) in a.planes().iter().zip(b.planes()).enumerate() {
        let within = shot.sum(c) as f32;
        let x: Vec<f32> = x.iter().map(|v| v * within).collect();
        assert!(
            relative_l2(&x, y) < 1e-5,
            "plane {c}: {}",
            relative_l2(&x, y)
        );
    }
    let unread = Effect::Image(Measured::new("star.exr".into(), 4.0));
    let error = config(vec![unread])
        .kernel(&Extent::new(11, 11).unwrap())
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        error.starts_with("image \"star.exr\": it has not been read"),
        "{error}"
    );
}
