//! `aureole apply`, `demo` and `info` as a user runs them.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use aureole::{ApplyOptions, Config, Image, Layout, Plan};
use aureole_io::limits::Limits;
use aureole_io::read::read_image;
use aureole_io::write::{write_linear, LinearOptions};
use predicates::prelude::*;

fn aureole() -> Command {
    Command::cargo_bin("aureole").unwrap()
}

/// A small night scene: a dim background and two lamps.
fn scene(dir: &Path, name: &str) -> (PathBuf, Image) {
    let (w, h) = (48, 32);
    let mut image = Image::filled(w, h, Layout::Rgb, 0.02);
    for (x, y, l) in [(10, 8, 5e4f32), (35, 20, 2e4)] {
        for plane in &mut image.planes {
            plane[y * w + x] = l;
        }
    }
    image.white_luminance = None;
    let path = dir.join(name);
    write_linear(&path, &image, LinearOptions::default()).unwrap();
    (path, image)
}

fn library_result(image: &Image, preset: &str, threshold: f64) -> Image {
    let mut config = Config::default();
    config.merge(aureole::presets::find(preset).unwrap().config().unwrap());
    let plan = Plan::for_image(&config, image.width, image.height, None).unwrap();
    let options = ApplyOptions {
        threshold: Some(threshold),
        ..ApplyOptions::default()
    };
    plan.apply(image, 1.0, &options, &mut |_| {}).unwrap().image
}

#[test]
fn apply_writes_what_the_library_computes() {
    let dir = tempfile::tempdir().unwrap();
    let (input, image) = scene(dir.path(), "night.exr");
    let out = dir.path().join("out.exr");
    aureole()
        .args(["apply", "--preset", "paper-fig5-both", "--threshold", "1"])
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .assert()
        .success()
        .stderr(
            predicate::str::contains("48x32").and(predicate::str::contains("2 px above 1 cd/m²")),
        );
    let written = read_image(&out, Limits::NONE).unwrap().image;
    assert_eq!(written, library_result(&image, "paper-fig5-both", 1.0));
    // The input is untouched.
    assert_eq!(read_image(&input, Limits::NONE).unwrap().image, image);
}

#[test]
fn apply_without_a_camera_uses_the_default_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let (input, image) = scene(dir.path(), "night.pfm");
    let out = dir.path().join("out.pfm");
    aureole()
        .arg("apply")
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .assert()
        .success()
        .stderr(predicate::str::contains("default camera"));
    assert_eq!(
        read_image(&out, Limits::NONE).unwrap().image,
        library_result(&image, aureole::presets::DEFAULT_PRESET, 0.0)
    );
}

#[test]
fn apply_writes_pictures_and_glare_only_layers() {
    let dir = tempfile::tempdir().unwrap();
    let (input, image) = scene(dir.path(), "night.exr");
    for (name, magic) in [
        ("p.png", b"\x89PNG".as_slice()),
        ("p.jpg", &[0xff, 0xd8]),
        ("p.tif", b"II*\0"),
    ] {
        let out = dir.path().join(name);
        aureole()
            .args(["apply", "--exposure", "2", "--tonemap", "reinhard"])
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .assert()
            .success()
            .stderr(predicate::str::contains("EV100 2.0"));
        assert!(std::fs::read(&out).unwrap().starts_with(magic), "{name}");
    }
    let png16 = dir.path().join("p16.png");
    aureole()
        .args(["apply", "--white", "100", "--bits", "16"])
        .arg(&input)
        .arg("-o")
        .arg(&png16)
        .assert()
        .success();
    let decoded = image::open(&png16).unwrap();
    assert!(matches!(decoded, image::DynamicImage::ImageRgb16(_)));

    let glare = dir.path().join("glare.exr");
    aureole()
        .args(["apply", "--glare-only", "-q"])
        .arg(&input)
        .arg("-o")
        .arg(&glare)
        .assert()
        .success()
        .stderr("");
    let glare = read_image(&glare, Limits::NONE).unwrap().image;
    let full = library_result(&image, aureole::presets::DEFAULT_PRESET, 0.0);
    for c in 0..3 {
        for i in 0..image.width * image.height {
            let composite = image.planes[c][i] + glare.planes[c][i];
            assert!(
                (composite - full.planes[c][i]).abs() <= 1e-3 * full.planes[c][i].abs().max(1.0)
            );
        }
    }
}

#[test]
fn apply_keeps_luminance_only_files_luminance_only_and_whiteluminance() {
    let dir = tempfile::tempdir().unwrap();
    let mut image = Image::filled(20, 10, Layout::Luminance, 0.01);
    image.planes[0][55] = 10.0; // 6210 cd/m² at 621 cd/m² per unit
    image.white_luminance = Some(621.0);
    let input = dir.path().join("y.exr");
    write_linear(&input, &image, LinearOptions::default()).unwrap();
    let out = dir.path().join("out.exr");
    aureole()
        .args(["apply", "--threshold", "1000"])
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .assert()
        .success()
        .stderr(predicate::str::contains("621").and(predicate::str::contains("1 px above 1000")));
    let written = read_image(&out, Limits::NONE).unwrap().image;
    assert_eq!(written.layout, Layout::Luminance);
    assert_eq!(written.white_luminance, Some(621.0));
}

#[test]
fn apply_refuses_nan_unless_sanitized() {
    let dir = tempfile::tempdir().unwrap();
    let mut image = Image::filled(8, 6, Layout::Rgb, 1.0);
    image.planes[0][2 * 8 + 5] = f32::NAN;
    image.planes[1][4 * 8 + 1] = f32::INFINITY;
    let input = dir.path().join("bad.exr");
    write_linear(&input, &image, LinearOptions::default()).unwrap();
    let out = dir.path().join("out.exr");
    let assert = aureole()
        .arg("apply")
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .assert()
        .failure()
        .code(1);
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).into_owned();
    assert!(
        stderr.contains("bad.exr")
            && stderr.contains("2 NaN or infinite")
            && stderr.contains("column 5 row 2"),
        "{stderr}"
    );
    assert!(!out.exists());
    aureole()
        .args(["apply", "--sanitize"])
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .assert()
        .success()
        .stderr(predicate::str::contains(
            "2 NaN, infinite or negative samples replaced by 0",
        ));
    assert!(read_image(&out, Limits::NONE)
        .unwrap()
        .image
        .non_finite()
        .is_none());
}

#[test]
fn demo_writes_a_picture_and_its_linear_scene() {
    let dir = tempfile::tempdir().unwrap();
    let (png, exr) = (dir.path().join("demo.png"), dir.path().join("scene.exr"));
    aureole()
        .args(["demo", "--size", "320x180", "-o"])
        .arg(&png)
        .arg("--hdr")
        .arg(&exr)
        .assert()
        .success()
        .stderr(predicate::str::contains("night street 320x180"));
    let picture = image::open(&png).unwrap();
    assert_eq!((picture.width(), picture.height()), (320, 180));
    let scene = read_image(&exr, Limits::NONE).unwrap().image;
    let max = scene.planes.iter().flatten().fold(0f32, |m, &v| m.max(v));
    let min = scene
        .planes
        .iter()
        .flatten()
        .fold(f32::INFINITY, |m, &v| m.min(v));
    // Street lamps of 10⁴–10⁵ cd/m² over a sky of ~10⁻² cd/m².
    assert!(max > 1e4 && max < 2e5 && min < 0.05, "{min} … {max}");
}

#[test]
fn info_describes_luminance_and_bright_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let (input, _) = scene(dir.path(), "night.exr");
    aureole().arg("info").arg(&input).assert().success().stdout(
        predicate::str::contains("48x32")
            .and(predicate::str::contains("max 50000"))
            .and(predicate::str::contains("above 10000 cd/m²: 2 px"))
            .and(predicate::str::contains("above 100000 cd/m²: 0 px")),
    );
    aureole()
        .args(["info", "--threshold", "30000"])
        .arg(&input)
        .assert()
        .success()
        .stdout(predicate::str::contains("above 30000 cd/m²: 1 px"));
}

#[test]
fn aces_ap0_primaries_give_luminance_with_a_negative_blue_weight() {
    let dir = tempfile::tempdir().unwrap();
    let ap0 = aureole::image::Primaries {
        red: [0.7347, 0.2653],
        green: [0.0, 1.0],
        blue: [0.0001, -0.0770],
        white: [0.32168, 0.33767],
    };
    // A red lamp of 1000 units: Y = 344 cd/m² on AP0, 213 on Rec.709.
    let mut image = Image::filled(32, 24, Layout::Rgb, 0.01);
    image.planes[0][12 * 32 + 16] = 1000.0;
    image.primaries = Some(ap0);
    let exr = dir.path().join("aces.exr");
    write_linear(&exr, &image, LinearOptions::default()).unwrap();
    // The same pixels in a Radiance file whose header names AP0.
    let plain = dir.path().join("plain.hdr");
    write_linear(
        &plain,
        &Image {
            primaries: None,
            ..image.clone()
        },
        LinearOptions::default(),
    )
    .unwrap();
    let bytes = std::fs::read(&plain).unwrap();
    let format = b"FORMAT=32-bit_rle_rgbe\n";
    let at = bytes
        .windows(format.len())
        .position(|w| w == format)
        .unwrap()
        + format.len();
    let mut edited = bytes[..at].to_vec();
    edited.extend_from_slice(b"PRIMARIES=0.7347 0.2653 0 1 0.0001 -0.077 0.32168 0.33767\n");
    edited.extend_from_slice(&bytes[at..]);
    let hdr = dir.path().join("aces.hdr");
    std::fs::write(&hdr, edited).unwrap();

    for input in [&exr, &hdr] {
        aureole()
            .arg("info")
            .arg(input)
            .assert()
            .success()
            .stdout(predicate::str::contains(
                "luminance: Y = 0.34397 R + 0.72817 G − 0.07213 B (the file's chromaticities)",
            ));
        // Spread at 300 cd/m²: the lamp passes on AP0's luminance.
        let out = dir.path().join("out.exr");
        aureole()
            .args([
                "apply",
                "--preset",
                "paper-fig4-bloom",
                "--threshold",
                "300",
                "-o",
            ])
            .arg(&out)
            .arg(input)
            .assert()
            .success()
            .stderr(predicate::str::contains("degenerate").not());
        let result = read_image(&out, Limits::NONE).unwrap().image;
        let beside = 12 * 32 + 18;
        assert!(
            result.planes[0][beside] > 0.02,
            "{}: the lamp was not spread",
            input.display()
        );
    }
}

#[test]
fn apply_reuses_a_kernel_written_by_psf() {
    let dir = tempfile::tempdir().unwrap();
    let (input, image) = scene(dir.path(), "night.exr");
    // The kernel a 48×32 frame needs, built once.
    let kernel = dir.path().join("k.exr");
    aureole()
        .args([
            "psf",
            "--preset",
            "paper-fig5-both",
            "--size",
            "95x63",
            "--image-width",
            "48",
            "-o",
        ])
        .arg(&kernel)
        .assert()
        .success();
    // The light a 48×32 frame cannot hold leaves it: the EXR keeps the
    // share the kernel holds, and reads back with it; a PFM has no room
    // to say so and reads back whole.
    let read = aureole_io::kernel::read_kernel(&kernel, Limits::NONE).unwrap();
    assert!(read.sum(0) < 0.999, "ΣK = {}", read.sum(0));
    let pfm = dir.path().join("k.pfm");
    aureole()
        .args(["psf", "--preset", "paper-fig5-both", "--size", "95x63"])
        .args(["--image-width", "48", "-q", "-o"])
        .arg(&pfm)
        .assert()
        .success();
    let whole = aureole_io::kernel::read_kernel(&pfm, Limits::NONE).unwrap();
    assert!((whole.sum(0) - 1.0).abs() < 1e-6, "ΣK = {}", whole.sum(0));
    let out = dir.path().join("out.exr");
    aureole()
        .arg("apply")
        .arg(&input)
        .arg("--kernel")
        .arg(&kernel)
        .arg("-o")
        .arg(&out)
        .assert()
        .success();
    let written = read_image(&out, Limits::NONE).unwrap().image;
    let expected = library_result(&image, "paper-fig5-both", 0.0);
    for (a, b) in written
        .planes
        .iter()
        .flatten()
        .zip(expected.planes.iter().flatten())
    {
        assert!((a - b).abs() <= 1e-5 * b.abs().max(1.0), "{a} vs {b}");
    }
    // A kernel built for other frames is refused, unless told.
    let wide = dir.path().join("wide.exr");
    aureole()
        .args([
            "psf",
            "--preset",
            "paper-fig5-both",
            "--size",
            "95x63",
            "--image-width",
            "144",
            "-o",
        ])
        .arg(&wide)
        .assert()
        .success();
    aureole()
        .arg("apply")
        .arg(&input)
        .arg("--kernel")
        .arg(&wide)
        .arg("-o")
        .arg(&out)
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "was built for images 144 px wide (aureole psf --image-width), this one is 48 px wide",
        ).and(predicate::str::contains("factor 3.00")));
    aureole()
        .arg("apply")
        .arg(&input)
        .arg("--kernel")
        .arg(&wide)
        .args(["--kernel-any-width", "-q", "-o"])
        .arg(&out)
        .assert()
        .success();
    // A .pfm kernel records no width: refused unless told.
    let pfm = dir.path().join("k.pfm");
    aureole()
        .args([
            "psf",
            "--preset",
            "paper-fig5-both",
            "--size",
            "95x63",
            "-o",
        ])
        .arg(&pfm)
        .assert()
        .success();
    aureole()
        .arg("apply")
        .arg(&input)
        .arg("--kernel")
        .arg(&pfm)
        .arg("-o")
        .arg(&out)
        .assert()
        .code(2)
        .stderr(
            predicate::str::contains("k.pfm: the kernel records no image width")
                .and(predicate::str::contains("--kernel-any-width")),
        );
    aureole()
        .arg("apply")
        .arg(&input)
        .arg("--kernel")
        .arg(&pfm)
        .args(["--kernel-any-width", "-q", "-o"])
        .arg(&out)
        .assert()
        .success();
    aureole()
        .arg("apply")
        .arg(&input)
        .args(["--kernel", "k.exr", "--preset", "paper-fig4-bloom", "-o"])
        .arg(&out)
        .assert()
        .failure()
        .code(2);
}

/// What a render farm does: the kernel built once for the sequence's
/// frames (`psf --for-image`), each chunk applying it; the results are the
/// bytes of `apply` with the camera, its threshold included.
#[test]
fn a_kernel_for_an_image_gives_the_bytes_of_its_camera() {
    let dir = tempfile::tempdir().unwrap();
    let (input, _) = scene(dir.path(), "night.exr");
    let config = dir.path().join("lens.toml");
    std::fs::write(
        &config,
        "threshold = 50.0\n[camera]\nsensor_width_mm = 36.0\nfocal_length_mm = 50.0\n\
         f_number = 8.0\n[[effect]]\ntype = \"aperture\"\nblades = 6\n\
         [[effect]]\ntype = \"bloom\"\nepsilon = 0.01\nbeta = 3.0\nradius = \"2px\"\n",
    )
    .unwrap();
    let kernel = dir.path().join("k.exr");
    aureole()
        .args(["psf", "--config"])
        .arg(&config)
        .arg("--for-image")
        .arg(&input)
        .arg("-o")
        .arg(&kernel)
        .assert()
        .success()
        .stderr(predicate::str::contains("95x63 kernel"));
    let built = dir.path().join("built.exr");
    aureole()
        .args(["apply", "-q", "--config"])
        .arg(&config)
        .arg(&input)
        .arg("-o")
        .arg(&built)
        .assert()
        .success();
    let read = dir.path().join("read.exr");
    aureole()
        .args(["apply", "--kernel"])
        .arg(&kernel)
        .arg(&input)
        .arg("-o")
        .arg(&read)
        .assert()
        .success()
        .stderr(predicate::str::contains("above 50 cd/m²"));
    assert!(
        std::fs::read(&read).unwrap() == std::fs::read(&built).unwrap(),
        "apply --kernel gave other bytes than apply --config"
    );
    // --threshold still decides.
    aureole()
        .args(["apply", "--kernel"])
        .arg(&kernel)
        .arg(&input)
        .args(["--threshold", "0", "-o"])
        .arg(&read)
        .assert()
        .success()
        .stderr(predicate::str::contains("above 0 cd/m²"));
    aureole()
        .args([
            "psf",
            "--preset",
            "paper-fig4-bloom",
            "--size",
            "9",
            "--for-image",
        ])
        .arg(&input)
        .arg("-o")
        .arg(&kernel)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("cannot be used with"));
}

#[test]
fn apply_spreads_by_fft_or_splatting_as_asked_and_says_which() {
    let dir = tempfile::tempdir().unwrap();
    let (input, _) = scene(dir.path(), "night.exr");
    let mut results = Vec::new();
    for (method, said) in [
        ("fft", "(FFT on "),
        ("splat", "(splatted on the CPU)"),
        ("auto", "(splatted on the CPU)"),
    ] {
        let out = dir.path().join(format!("{method}.exr"));
        aureole()
            .args(["apply", "--preset", "paper-fig5-both", "--threshold", "1"])
            .args(["--method", method])
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .assert()
            .success()
            .stderr(predicate::str::contains(said));
        results.push(read_image(&out, Limits::NONE).unwrap().image);
    }
    let scale = 5e4;
    for (a, b) in results[0].planes.iter().zip(&results[1].planes) {
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() <= 1e-6 * scale, "{x} vs {y}");
        }
    }
    aureole()
        .args(["apply", "--method", "wavelet"])
        .arg(&input)
        .arg("-o")
        .arg(dir.path().join("w.exr"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("wavelet").and(predicate::str::contains("fft")));
}

#[test]
fn negative_samples_pass_through_with_a_note_unless_sanitized() {
    let dir = tempfile::tempdir().unwrap();
    let mut image = Image::filled(8, 6, Layout::Rgb, 1.0);
    image.planes[0][2 * 8 + 5] = -0.25;
    image.planes[2][4 * 8 + 1] = -0.5;
    let input = dir.path().join("negative.exr");
    write_linear(&input, &image, LinearOptions::default()).unwrap();
    let out = dir.path().join("out.exr");
    aureole()
        .args(["apply", "--threshold", "100"])
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .assert()
        .success()
        .stderr(predicate::str::contains(
            "negative.exr: 2 negative samples passed through",
        ));
    // Below the threshold, nothing is spread: they come back as they were.
    let written = read_image(&out, Limits::NONE).unwrap().image;
    assert_eq!(written.planes, image.planes);
    aureole()
        .args(["apply", "--threshold", "100", "--sanitize"])
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .assert()
        .success()
        .stderr(predicate::str::contains(
            "2 NaN, infinite or negative samples replaced by 0",
        ));
    let written = read_image(&out, Limits::NONE).unwrap().image;
    assert!(written.planes.iter().flatten().all(|&v| v >= 0.0));
}

#[test]
fn a_splat_estimated_beyond_a_minute_says_so_before_it_starts() {
    let dir = tempfile::tempdir().unwrap();
    // Every pixel bright, a full-frame kernel: ~10¹¹ multiply-adds.
    let input = dir.path().join("bright.exr");
    write_linear(
        &input,
        &Image::filled(800, 600, Layout::Rgb, 1.0),
        LinearOptions::default(),
    )
    .unwrap();
    let out = dir.path().join("out.exr");
    let run = aureole()
        .args(["apply", "--preset", "paper-fig4-bloom", "--threshold", "0"])
        .args(["--method", "splat"])
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .timeout(std::time::Duration::from_secs(5))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        stderr.contains("bright.exr: splatting 480000 bright pixels will take about")
            && stderr.contains("--method auto or fft"),
        "{stderr}"
    );
    assert!(!out.exists());
}

#[test]
fn exr_output_keeps_the_input_compression_unless_told() {
    use aureole_io::compression::Compression;
    let dir = tempfile::tempdir().unwrap();
    let image = Image::filled(40, 30, Layout::Rgb, 0.5);
    let compressed = |path: &Path| read_image(path, Limits::NONE).unwrap().compression;
    let input = dir.path().join("piz.exr");
    let options = LinearOptions {
        compression: Some(Compression::Piz),
        ..LinearOptions::default()
    };
    write_linear(&input, &image, options).unwrap();
    assert_eq!(compressed(&input), Some(Compression::Piz));
    let pfm = dir.path().join("in.pfm");
    write_linear(&pfm, &image, LinearOptions::default()).unwrap();
    let run = |input: &Path, out: &str, extra: &[&str]| {
        let out = dir.path().join(out);
        aureole()
            .args(["apply", "--preset", "paper-fig4-bloom"])
            .args(extra)
            .arg(input)
            .arg("-o")
            .arg(&out)
            .assert()
            .success();
        compressed(&out)
    };
    assert_eq!(run(&input, "same.exr", &[]), Some(Compression::Piz));
    assert_eq!(run(&pfm, "zip.exr", &[]), Some(Compression::Zip));
    for c in Compression::ALL {
        let name = format!("out-{c}.exr");
        let got = run(&input, &name, &["--half", "--compression", c.name()]);
        assert_eq!(got, Some(c), "{c}");
    }
    aureole()
        .args(["apply", "--compression", "zstd"])
        .arg(&input)
        .args(["-o", "x.exr"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "\"zstd\" is not an EXR compression: use one of none, rle",
        ));
}
