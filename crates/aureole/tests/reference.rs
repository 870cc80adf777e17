//! Aperture kernels against values of hcipy 0.7.1, an optics library
//! nobody here wrote, copied here so that `cargo test` holds the physics to
//! an outside reference without Python. Provenance: the values are printed
//! by `tests/reference/hcipy_values.py` (Fraunhofer propagation of our
//! stop, sampled as crates/aureole-py/tests/test_diffraction_reference.py
//! samples it, where the full comparison runs under pytest); hcipy's own
//! error, its change with 1.5× the samples, is at most 7.8·10⁻⁴ on these.
//! Criterion, as there: the encircled energy within 0.5 % at every radius.
//!
//! And a few small kernels and one output pinned as files in
//! `tests/reference/`, each held to a stated tolerance: a change to what
//! aureole computes shows here first. `AUREOLE_BLESS=1 cargo test -p
//! aureole --test reference` rewrites them, for a change that means to.

// References and workloads, not the library: the platform's maths
// (clippy.toml refuses it in the core) is as good as libm here.
#![allow(clippy::disallowed_methods)]

use std::path::PathBuf;

use aureole::{presets, ApplyOptions, Config, ConfigFile, Extent, Frame, FrameOptions};
use aureole::{Image, Layout, Sending, Session};

/// (blades, f-number, pixel pitch µm, [(radius px, encircled energy)]), a
/// 550 nm stop turned 5° behind a 50 mm lens, the kernel 201×201 px.
type Case = (u32, f64, f64, &'static [(usize, f64)]);

#[rustfmt::skip]
const HCIPY: &[Case] = &[
    // blades 7, f/4, pitch 1 µm: hcipy's own error ≤ 5.7e-04
    (7, 4.0, 1.0, &[(1, 0.473207), (2, 0.758222), (3, 0.842280), (5, 0.908851), (8, 0.941539), (13, 0.966323), (21, 0.981236), (34, 0.990184), (55, 0.995682), (89, 0.998975)]),
    // blades 8, f/8, pitch 1 µm: hcipy's own error ≤ 2.1e-04
    (8, 8.0, 1.0, &[(1, 0.165223), (2, 0.370269), (3, 0.630560), (5, 0.839498), (8, 0.883088), (13, 0.934156), (21, 0.961234), (34, 0.980229), (55, 0.991281), (89, 0.998071)]),
    // blades 0 (round), f/4, pitch 1 µm: hcipy's own error ≤ 6.2e-04
    (0, 4.0, 1.0, &[(1, 0.514315), (2, 0.784886), (3, 0.849117), (5, 0.915176), (8, 0.946270), (13, 0.970364), (21, 0.982769), (34, 0.991123), (55, 0.996165), (89, 0.999074)]),
    // blades 5, f/32, pitch 10 µm: hcipy's own error ≤ 7.8e-04
    (5, 32.0, 10.0, &[(1, 0.559391), (2, 0.800263), (3, 0.848310), (5, 0.916116), (8, 0.949209), (13, 0.970415), (21, 0.983385), (34, 0.991453), (55, 0.996294), (89, 0.999145)]),
];

const SIZE: usize = 201;

fn kernel(blades: u32, f_number: f64, pitch_um: f64) -> Vec<f32> {
    let text = format!(
        "[camera]\nsensor_width_mm = 36.0\nfocal_length_mm = 50.0\nf_number = {f_number}\n\
         [[effect]]\ntype = \"aperture\"\nblades = {blades}\nrotation_deg = 5.0\n\
         spectral = false\nwavelength_nm = 550.0\n"
    );
    let config = Config::compose([ConfigFile::parse(&text, "hcipy case").unwrap()]);
    let width = (36000.0 / pitch_um).round() as usize;
    // hcipy propagates a point of light.
    let extent = Extent::new(SIZE, SIZE)
        .unwrap()
        .with_image_width(width)
        .sent_by(Sending::Point);
    config.kernel(&extent).unwrap().planes()[0].clone()
}

/// The light within `radius` px of the centre, as the pytest reference
/// counts it (pixels whose centre is at most `radius` away), of the total.
fn encircled(kernel: &[f32], radius: usize) -> f64 {
    let c = (SIZE / 2) as f64;
    let mut within = 0.0;
    let mut total = 0.0;
    for (i, &v) in kernel.iter().enumerate() {
        let (x, y) = ((i % SIZE) as f64, (i / SIZE) as f64);
        total += f64::from(v);
        if (x - c).hypot(y - c) <= radius as f64 {
            within += f64::from(v);
        }
    }
    within / total
}

#[test]
fn encircled_energy_matches_hcipy_within_half_a_percent() {
    for &(blades, f_number, pitch, values) in HCIPY {
        let kernel = kernel(blades, f_number, pitch);
        for &(radius, theirs) in values {
            let ours = encircled(&kernel, radius);
            let off = (ours / theirs - 1.0).abs();
            assert!(
                off < 0.005,
                "{blades} blades, f/{f_number}, {pitch} µm, r = {radius} px: ours {ours:.6}, hcipy {theirs:.6} ({:.2} %)",
                off * 100.0
            );
        }
    }
}

/// A pinned array: `width height planes` on the first line, then every
/// sample, plane after plane, in Rust's shortest form that reads back as
/// the same f32.
fn pinned(name: &str, (width, height): (usize, usize), planes: &[Vec<f32>]) -> Vec<Vec<f32>> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/reference")
        .join(name);
    if std::env::var_os("AUREOLE_BLESS").is_some() {
        let mut text = format!("{width} {height} {}\n", planes.len());
        for v in planes.iter().flatten() {
            text.push_str(&format!("{v:e}\n"));
        }
        std::fs::write(&path, text).unwrap();
    }
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e}; AUREOLE_BLESS=1 writes it", path.display()));
    let mut lines = text.lines();
    let header: Vec<usize> = lines
        .next()
        .unwrap_or_default()
        .split(' ')
        .map(|n| n.parse().unwrap())
        .collect();
    assert_eq!(header, [width, height, planes.len()], "{name}: its size");
    let values: Vec<f32> = lines.map(|v| v.parse().unwrap()).collect();
    values.chunks(width * height).map(<[f32]>::to_vec).collect()
}

/// The relative L2 distance of `ours` from `theirs` over every plane, and
/// the largest difference of one sample.
fn distance(ours: &[Vec<f32>], theirs: &[Vec<f32>]) -> (f64, f64) {
    let (mut diff, mut norm, mut worst) = (0.0, 0.0, 0.0f64);
    for (a, b) in ours.iter().flatten().zip(theirs.iter().flatten()) {
        let d = f64::from(*a) - f64::from(*b);
        diff += d * d;
        norm += f64::from(*b) * f64::from(*b);
        worst = worst.max(d.abs());
    }
    ((diff / norm).sqrt(), worst)
}

/// Kernels are held to 1e-6 of their L2 norm: the same sums, with room for
/// another platform's last bits of sin, cos and exp.
const KERNEL_TOLERANCE: f64 = 1e-6;

#[test]
fn small_kernels_are_what_they_were_pinned_to() {
    let cases = [
        ("paper-fig4-bloom", (31, 31), 31),
        ("paper-fig5-corona", (41, 41), 41),
        ("human-eye-vos", (31, 31), 400),
        ("camera-f8-7blade", (33, 33), 960),
    ];
    for (preset, (w, h), image_width) in cases {
        let config = Config::compose([presets::find(preset).unwrap().config().unwrap()]);
        let extent = Extent::new(w, h).unwrap().with_image_width(image_width);
        let kernel = config.kernel(&extent).unwrap();
        let ours = kernel.planes().to_vec();
        let theirs = pinned(&format!("{preset}.kernel.txt"), (w, h), &ours);
        let (l2, worst) = distance(&ours, &theirs);
        assert!(
            l2 <= KERNEL_TOLERANCE,
            "{preset}: relative L2 {l2:.2e} (worst sample off by {worst:.2e})"
        );
    }
}

#[test]
fn a_small_street_through_the_papers_camera_is_what_it_was_pinned_to() {
    let (w, h) = (48, 27);
    let mut image = Image::filled(w, h, Layout::Rgb, 0.2);
    for (k, level) in [3e2f32, 3e3, 3e4].into_iter().enumerate() {
        for (c, plane) in image.planes.iter_mut().enumerate() {
            plane[(8 + 6 * k) * w + 10 + 13 * k] = level * [1.0, 0.8, 0.5][c];
        }
    }
    let config = Config::compose([presets::find("paper-fig5-both").unwrap().config().unwrap()]);
    let frame = Frame::new(image, &FrameOptions::default()).unwrap();
    // The light the camera adds alone: the background would dilute it.
    let options = ApplyOptions {
        glare_only: true,
        ..ApplyOptions::default()
    };
    let applied = Session::new(config)
        .apply(&frame, &options, &mut |_, _| {})
        .unwrap();
    let ours = applied.image.planes;
    let theirs = pinned("paper-fig5-both.street-glare.txt", (w, h), &ours);
    let (l2, worst) = distance(&ours, &theirs);
    // The output sums the kernel over lamps 100× apart: held as tightly.
    assert!(
        l2 <= KERNEL_TOLERANCE,
        "relative L2 {l2:.2e} (worst sample off by {worst:.2e} cd/m²)"
    );
}
