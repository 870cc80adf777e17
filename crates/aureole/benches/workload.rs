//! The benchmark workload of issue 5, built in code so that every run and
//! every peer sees the same numbers: a W×H RGB float image of background
//! 0.05 with ~1350 bright pixels of 10³–10⁵ scattered by a fixed seed, and a
//! PSF of bloom (R = 10 px, β = 2, ε = 0.05) plus 14 thin corona rays, with
//! full-frame reach ((2W − 1)×(2H − 1)), threshold 0.

// References and workloads, not the library: the platform's maths
// (clippy.toml refuses it in the core) is as good as libm here.
#![allow(clippy::disallowed_methods)]

use aureole::{Bloom, Config, Corona, Effect, Image, Layout, Length};
use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// Bright pixels in a 4K frame; smaller frames get the same density.
const BRIGHT_4K: f64 = 1350.0;

pub fn image(width: usize, height: usize) -> Image {
    let count = (BRIGHT_4K * (width * height) as f64 / (3840.0 * 2160.0)).round() as usize;
    lights(width, height, count)
}

/// Background 0.05 and `count` bright pixels of 10³–10⁵ at places and
/// levels drawn from a fixed seed.
pub fn lights(width: usize, height: usize, count: usize) -> Image {
    let mut image = Image::filled(width, height, Layout::Rgb, 0.05);
    let mut rng = Pcg64::seed_from_u64(5);
    let mut uniform = move || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    for _ in 0..count {
        let i = (uniform() * (width * height) as f64) as usize % (width * height);
        let luminance = 10f64.powf(3.0 + 2.0 * uniform()) as f32;
        for plane in &mut image.planes {
            plane[i] = luminance;
        }
    }
    image
}

pub fn config() -> Config {
    Config {
        effects: vec![
            Effect::Bloom(Bloom {
                epsilon: 0.05,
                beta: 2.0,
                radius: Length::px(10.0),
            }),
            Effect::Corona(Corona {
                epsilon: 0.05,
                rays: 14,
                length: Length::px(200.0),
                fadeout: 1.0,
                width: Length::px(3.0),
                spread: 0.0,
                length_jitter: 0.25,
                width_jitter: 0.0,
                intensity_jitter: 0.0,
                rotation_deg: 0.0,
            }),
        ],
        ..Config::default()
    }
}
