//! The f32 engine's loops and the pupil transform's inner loop (which
//! builds every diffraction kernel's near field) with AVX2 (AVX-512 for
//! the latter where the CPU has it) and their scalar twin give the same
//! bits (RustFFT keeps and tests its scalar twin the same way): the same
//! IEEE operations in the same order, whatever the vector width. In a
//! test binary of its own, since the switch holds for the whole process.

use aureole::config::ConfigFile;
use aureole::convolve::{force_scalar, vectors_in_use};
use aureole::{presets, ApplyOptions, Config, Frame, FrameOptions, Image, Layout, Method, Session};

/// A dim scene of 97×61 px (a size of odd factors, so rows and columns
/// have ragged ends) with lamps from 50 to 5·10⁵ cd/m² and a coloured one.
fn scene() -> Image {
    let (w, h) = (97, 61);
    let mut image = Image::filled(w, h, Layout::Rgb, 0.05);
    for (k, level) in [50.0, 5e2, 5e3, 5e4, 5e5].into_iter().enumerate() {
        let at = (7 + 11 * k) * w + 9 + 17 * k;
        for plane in &mut image.planes {
            plane[at] = level;
        }
    }
    image.planes[0][40 * w + 80] = 2e4;
    image
}

/// The camera a name stands for: a preset, or the dusty lens of
/// `configs/` (its dust and grease take the spots' loops).
fn camera(name: &str) -> ConfigFile {
    match name {
        "dusty-lens" => ConfigFile::parse(
            include_str!("../../../configs/dusty-lens.toml"),
            "dusty-lens.toml",
        )
        .unwrap(),
        preset => presets::find(preset).unwrap().config().unwrap(),
    }
}

fn through(preset: &str, image: &Image) -> Vec<Vec<f32>> {
    let config = Config::compose([camera(preset)]);
    let frame = Frame::new(image.clone(), &FrameOptions::default()).unwrap();
    let options = ApplyOptions {
        method: Method::Fft,
        ..ApplyOptions::default()
    };
    let applied = Session::new(config)
        .apply(&frame, &options, &mut |_, _| {})
        .unwrap();
    applied.image.planes
}

#[test]
fn the_vector_and_scalar_loops_give_the_same_bits() {
    if !vectors_in_use() {
        eprintln!("this CPU has no AVX2: both runs take the scalar loops");
    }
    let image = scene();
    for preset in [
        "paper-fig5-both",
        "paper-fig6a",
        "paper-fig6b",
        "paper-fig6c",
        "camera-f8-7blade",
        "camera-f11-6blade",
        "human-eye-vos",
        "dusty-lens",
    ] {
        force_scalar(false);
        let vector = through(preset, &image);
        force_scalar(true);
        assert!(!vectors_in_use());
        let scalar = through(preset, &image);
        force_scalar(false);
        let same = vector
            .iter()
            .flatten()
            .zip(scalar.iter().flatten())
            .all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(same, "{preset}: the vector and scalar loops differ");
    }
}
