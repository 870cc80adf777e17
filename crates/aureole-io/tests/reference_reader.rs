//! The EXR files we write, read by the reference library: OpenImageIO's
//! `oiiotool` (over OpenEXR) compares them with files the `exr` crate
//! writes of the same pixels, and OpenEXR's `exrheader` reads their
//! headers. Our own reader (on the `exr` crate) must give back what was
//! written. The values OpenEXR itself reads from our files, and those our
//! reader takes from OpenEXR's, are compared with the originals in
//! `crates/aureole-py/tests/test_exr_interop.py` (the OpenEXR package).
//! Where the tools are missing the tests fail where CI runs, and skip,
//! listed, elsewhere (tests/support/required.rs).

use std::path::Path;
use std::process::Command;

use aureole::{Image, Layout};
use aureole_io::compression::Compression;
use aureole_io::formats::Samples;
use aureole_io::limits::Limits;
use aureole_io::read::read_image;
use aureole_io::write::{write_linear, write_linear_into, LinearOptions};
use exr::prelude::*;

mod common;
use common::read_all;

fn installed(tool: &str) -> bool {
    let found = Command::new(tool).arg("--help").output().is_ok();
    if !found {
        common::required::missing(
            "reference_reader",
            &format!("{tool} is not installed (Debian: openimageio-tools, openexr)"),
        );
    }
    found
}

/// `oiiotool a b --diff` with no difference allowed.
fn same_pixels(a: &Path, b: &Path) {
    if !installed("oiiotool") {
        return;
    }
    let out = Command::new("oiiotool")
        .args([a, b].map(Path::as_os_str))
        .args(["--diff", "--fail", "0", "--failpercent", "0", "--warn", "0"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("PASS"),
        "oiiotool --diff {} {}: {text}{}",
        a.display(),
        b.display(),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `exrheader` reads the file and names its compression as `compression`
/// (OpenEXR's words: "zip, multi-scanline blocks").
fn header_says(path: &Path, compression: &str) {
    if !installed("exrheader") {
        return;
    }
    let out = Command::new("exrheader").arg(path).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "exrheader {}: {text}", path.display());
    assert!(
        text.contains(&format!("compression (type compression): {compression}")),
        "{text}"
    );
}

/// An image with odd sizes (a last block of 16 lines cut short), values
/// over ten decades and both signs, and alpha.
fn scene(layout: Layout) -> Image {
    let (w, h) = (333, 77);
    let mut image = Image::filled(w, h, layout, 0.0);
    let mut state = 7u64;
    for plane in &mut image.planes {
        for v in plane.iter_mut() {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let u = (state >> 40) as f32 / (1u64 << 24) as f32;
            *v = 10f32.powf(u * 9.0 - 5.0) * if state % 11 == 0 { -1.0 } else { 1.0 };
        }
    }
    image.alpha = Some((0..w * h).map(|i| (i % 5) as f32 * 0.25).collect());
    image
}

#[test]
fn zip_files_are_read_back_bit_for_bit_by_exr_and_openexr() {
    let dir = tempfile::tempdir().unwrap();
    for compression in [Compression::Zip, Compression::Zips] {
        for samples in [Samples::Float, Samples::Half] {
            for layout in [Layout::Rgb, Layout::Luminance] {
                let mut image = scene(layout);
                if samples == Samples::Half {
                    for v in image.planes.iter_mut().flatten() {
                        *v = v.clamp(-65504.0, 65504.0);
                    }
                }
                let ours = dir.path().join("ours.exr");
                let options = LinearOptions {
                    samples: Some(samples),
                    compression: Some(compression),
                };
                write_linear(&ours, &image, options).unwrap();
                let what = format!("{compression} {samples:?} {layout:?}");
                // Our reader, sample by sample.
                let back = read_image(&ours, Limits::NONE).unwrap().image;
                let expected: Vec<u32> = image
                    .planes
                    .iter()
                    .flatten()
                    .map(|&v| match samples {
                        Samples::Float => v.to_bits(),
                        Samples::Half => f16::from_f32(v).to_f32().to_bits(),
                    })
                    .collect();
                let found: Vec<u32> = back.planes.iter().flatten().map(|v| v.to_bits()).collect();
                assert!(expected == found, "{what}: samples differ");
                assert_eq!(back.alpha.as_ref().map(Vec::len), Some(333 * 77), "{what}");
                // The reference library, against what the exr crate writes.
                let theirs = dir.path().join("theirs.exr");
                read_all(&ours).write().to_file(&theirs).unwrap();
                same_pixels(&ours, &theirs);
                header_says(
                    &ours,
                    match compression {
                        Compression::Zips => "zip, individual scanlines",
                        _ => "zip, multi-scanline blocks",
                    },
                );
            }
        }
    }
}

#[test]
fn tiled_zip_files_stay_tiled_and_read_back_by_openexr() {
    let dir = tempfile::tempdir().unwrap();
    // Smooth, so that its tiles compress (noise would be stored as it is).
    let (w, h) = (333, 77);
    let channels = SpecificChannels::rgb(|at: Vec2<usize>| {
        let (x, y) = (at.x() as f32, at.y() as f32);
        (x * 0.25, y * 0.5, (x + y) * 0.125)
    });
    let layer = Layer::new(
        (w, h),
        LayerAttributes::named("beauty"),
        Encoding {
            compression: exr::compression::Compression::ZIP16,
            blocks: Blocks::Tiles(Vec2(64, 32)),
            line_order: LineOrder::Increasing,
        },
        channels,
    );
    let tiled = dir.path().join("tiled.exr");
    exr::image::Image::from_layer(layer)
        .write()
        .to_file(&tiled)
        .unwrap();
    let loaded = read_image(&tiled, Limits::NONE).unwrap();
    let ours = dir.path().join("ours.exr");
    write_linear_into(
        &ours,
        &loaded.image,
        LinearOptions::default(),
        loaded.original,
    )
    .unwrap();
    let back = read_all(&ours);
    assert_eq!(
        back.layer_data[0].encoding.blocks,
        Blocks::Tiles(Vec2(64, 32))
    );
    same_pixels(&ours, &tiled);
    header_says(&ours, "zip, multi-scanline blocks");
}

/// `oiiotool --printstats`' count of infinite samples in each channel.
fn infinities(path: &Path) -> Option<Vec<u64>> {
    if !installed("oiiotool") {
        return None;
    }
    let out = Command::new("oiiotool")
        .arg(path)
        .arg("--printstats")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text.lines().find_map(|l| l.split_once("InfCount:"))?.1;
    Some(
        line.split_whitespace()
            .filter_map(|n| n.parse().ok())
            .collect(),
    )
}

#[test]
fn lossy_half_compressions_never_make_lamps_infinite() {
    let dir = tempfile::tempdir().unwrap();
    // Street lamps of 10⁵ cd/m² over a night sky, and samples just below
    // the half range, which the DCT's error carries over it.
    let (w, h) = (96, 64);
    let mut image = Image::filled(w, h, Layout::Rgb, 0.02);
    for plane in &mut image.planes {
        for (i, v) in plane.iter_mut().enumerate() {
            let (x, y) = (i % w, i / w);
            if (x % 24 < 3) && (y % 16 < 3) {
                *v = if x < 48 { 1e5 } else { 65500.0 };
            }
        }
    }
    for compression in [Compression::Dwaa, Compression::Dwab] {
        for samples in [Samples::Float, Samples::Half] {
            let path = dir.path().join(format!("{compression}.exr"));
            let options = LinearOptions {
                samples: Some(samples),
                compression: Some(compression),
            };
            let notes = write_linear(&path, &image, options).unwrap();
            let said: Vec<String> = notes.iter().map(|n| n.to_string()).collect();
            assert!(
                said.iter().any(|n| n.contains("65504")),
                "{compression} {samples:?}: {said:?}"
            );
            let back = read_image(&path, Limits::NONE).unwrap().image;
            let infinite = back
                .planes
                .iter()
                .flatten()
                .filter(|v| v.is_infinite())
                .count();
            assert_eq!(infinite, 0, "{compression} {samples:?}");
            let bright = back.planes[0].iter().cloned().fold(0.0f32, f32::max);
            assert!(bright > 6e4, "{compression} {samples:?}: {bright}");
            if let Some(counts) = infinities(&path) {
                assert_eq!(counts, [0, 0, 0], "{compression} {samples:?}");
            }
        }
    }
}

#[test]
fn lossless_compressions_read_back_bit_for_bit() {
    // A smooth scene with noise in the low bits, as a rendered frame has:
    // float PIZ chunks then hold mostly long Huffman codes (the low halves
    // of the floats take every value) and still compress; and noise over
    // ten decades, which nothing shortens.
    let dir = tempfile::tempdir().unwrap();
    let mut smooth = scene(Layout::Rgb);
    let w = smooth.width;
    for (c, plane) in smooth.planes.iter_mut().enumerate() {
        for (i, v) in plane.iter_mut().enumerate() {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            *v = 1000.0 * (1.5 + (x / 17.0 + c as f32).sin() * (y / 23.0).cos()) + *v * 1e-3;
        }
    }
    let path = dir.path().join("x.exr");
    for compression in [
        Compression::None,
        Compression::Rle,
        Compression::Zips,
        Compression::Zip,
        Compression::Piz,
    ] {
        for (samples, mut image) in [
            (Samples::Float, smooth.clone()),
            (Samples::Float, scene(Layout::Rgb)),
            (Samples::Half, scene(Layout::Rgb)),
        ] {
            for v in image.planes.iter_mut().flatten() {
                *v = v.clamp(-65504.0, 65504.0);
            }
            let options = LinearOptions {
                samples: Some(samples),
                compression: Some(compression),
            };
            write_linear(&path, &image, options).unwrap();
            let back = read_image(&path, Limits::NONE).unwrap().image;
            let stored = |v: f32| match samples {
                Samples::Float => v.to_bits(),
                Samples::Half => f16::from_f32(v).to_f32().to_bits(),
            };
            let differ = image
                .planes
                .iter()
                .flatten()
                .zip(back.planes.iter().flatten())
                .filter(|(a, b)| stored(**a) != b.to_bits())
                .count();
            assert_eq!(differ, 0, "{compression} {samples:?}");
        }
    }
}
