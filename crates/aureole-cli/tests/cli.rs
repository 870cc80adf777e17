//! The `aureole` command as a user runs it.

#[path = "../../../tests/support/required.rs"]
mod required;
use std::path::Path;

use assert_cmd::Command;
use aureole::{presets, Config, Extent};
use aureole_io::limits::Limits;
use aureole_io::read::read_image;
use predicates::prelude::*;

fn aureole() -> Command {
    Command::cargo_bin("aureole").unwrap()
}

/// The kernel the library builds for these presets/config texts, in order.
fn library_kernel(sources: &[&str], size: usize) -> aureole::Kernel {
    let mut config = Config::default();
    for text in sources {
        let file = match presets::find(text) {
            Ok(p) => p.config().unwrap(),
            Err(_) => aureole::ConfigFile::parse(text, "inline").unwrap(),
        };
        config.merge(file);
    }
    config.kernel(&Extent::new(size, size).unwrap()).unwrap()
}

/// A PFM (or any image) the command wrote.
fn read_pfm(path: &Path) -> aureole::Image {
    read_image(path, Limits::NONE).unwrap().image
}

fn one_line(stderr: &[u8]) -> String {
    let text = String::from_utf8_lossy(stderr).into_owned();
    assert_eq!(text.trim_end().lines().count(), 1, "{text}");
    text
}

#[test]
fn psf_writes_a_pfm_of_its_light_centred_at_half_the_size() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("k.pfm");
    aureole()
        .args([
            "psf",
            "--preset",
            "paper-fig5-both",
            "--size",
            "64x48",
            "-o",
        ])
        .arg(&out)
        .assert()
        .success()
        .stderr(predicate::str::contains("64x48 kernel"));
    let bytes = std::fs::read(&out).unwrap();
    assert!(bytes.starts_with(b"Pf\n64 48\n-1.0\n"));
    let kernel = read_pfm(&out);
    assert_eq!(
        (kernel.width, kernel.height, kernel.planes.len()),
        (64, 48, 1)
    );
    let plane = &kernel.planes[0];
    // The share of the light within it; the rest leaves a 64×48 frame.
    let sum: f64 = plane.iter().map(|&v| f64::from(v)).sum();
    assert!(sum > 0.99 && sum <= 1.0, "sum {sum}");
    let peak = plane.iter().cloned().fold(0f32, f32::max);
    assert_eq!(plane[24 * 64 + 32], peak);
}

/// An output's missing folder is named before any work: before the
/// kernel is sized against the memory, and before a lens writes any of
/// its outputs or traces its ghosts.
#[test]
fn outputs_whose_folder_is_missing_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let nowhere = dir.path().join("nowhere").join("k.pfm");
    assert_refused(
        &[
            "psf",
            "--preset",
            "star-filter-6pt",
            "--size",
            "16000x9000",
            "--image-width",
            "8000",
            "--max-memory",
            "1M",
            "-o",
            nowhere.to_str().unwrap(),
        ],
        2,
        &["k.pfm", "does not exist"],
        Some(&nowhere),
    );
    let toml = dir.path().join("lens.toml");
    for (ghosts, expected) in [
        (dir.path().join("nowhere").join("g.exr"), "does not exist"),
        (dir.path().join("g.png"), "allowed: .exr, .hdr, .pfm"),
    ] {
        let (toml_arg, ghosts_arg) = (toml.to_str().unwrap(), ghosts.to_str().unwrap());
        assert_refused(
            &[
                "lens",
                "double-gauss-50mm-f1.4",
                "-o",
                toml_arg,
                "--ghosts",
                ghosts_arg,
            ],
            2,
            &[expected],
            Some(&ghosts),
        );
        assert!(!toml.exists());
    }
}

/// A kernel beyond --max-memory is refused from the estimate, before any
/// large buffer: one line naming the size, the need and the limit, and no
/// file. The estimate is the library's (`Workload::estimate_kernel`), which
/// lies above the measured peaks of the 4K presets (docs/cli.md).
#[test]
fn psf_refuses_a_kernel_beyond_max_memory_before_building_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("k.exr");
    let refused = aureole()
        .args(["psf", "--preset", "star-filter-6pt", "--size", "16000x9000"])
        .args(["--image-width", "8000", "--max-memory", "512M", "-o"])
        .arg(&out)
        .assert()
        .code(1)
        .get_output()
        .stderr
        .clone();
    let line = one_line(&refused);
    assert!(line.contains("a 16000x9000 kernel needs about"), "{line}");
    assert!(line.contains("but --max-memory is 512.0 MiB"), "{line}");
    assert!(!out.exists());
    // Within it, built.
    aureole()
        .args(["psf", "--preset", "paper-fig4-bloom", "--size", "65"])
        .args(["--max-memory", "512M", "-o"])
        .arg(&out)
        .assert()
        .success();
}

#[test]
fn psf_output_matches_the_library_and_is_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.pfm"), dir.path().join("b.pfm"));
    for out in [&a, &b] {
        aureole()
            .args([
                "psf",
                "--preset",
                "paper-fig5-corona",
                "--size",
                "65",
                "--quiet",
                "-o",
            ])
            .arg(out)
            .assert()
            .success()
            .stderr("");
    }
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    let expected = library_kernel(&["paper-fig5-corona"], 65);
    assert_eq!(read_pfm(&a).planes[0], expected.planes()[0]);
}

#[test]
fn psf_writes_exr_and_png_pictures_with_a_profile_plot() {
    let dir = tempfile::tempdir().unwrap();
    let exr_path = dir.path().join("k.exr");
    aureole()
        .args(["psf", "--preset", "paper-fig6b", "--size", "101x81", "-o"])
        .arg(&exr_path)
        .assert()
        .success();
    let image = exr::prelude::read_all_flat_layers_from_file(&exr_path).unwrap();
    let layer = &image.layer_data[0];
    assert_eq!((layer.size.0, layer.size.1), (101, 81));
    assert_eq!(layer.channel_data.list.len(), 1);
    assert_eq!(layer.channel_data.list[0].name.to_string(), "Y");
    let sum: f64 = layer.channel_data.list[0]
        .sample_data
        .values_as_f32()
        .map(f64::from)
        .sum();
    assert!(sum > 0.95 && sum <= 1.0, "sum {sum}");

    let (png, plot) = (dir.path().join("k.png"), dir.path().join("plot.png"));
    aureole()
        .args(["psf", "--preset", "paper-fig6b", "--size", "101", "-o"])
        .arg(&png)
        .arg("--profile")
        .arg(&plot)
        .args(["--profile-radius", "30"])
        .assert()
        .success();
    for path in [&png, &plot] {
        assert!(std::fs::read(path)
            .unwrap()
            .starts_with(b"\x89PNG\r\n\x1a\n"));
    }
}

#[test]
fn psf_draws_the_pupil_with_its_dirt_and_refuses_a_chain_without_one() {
    let dir = tempfile::tempdir().unwrap();
    let dusty = dir.path().join("dusty.toml");
    std::fs::write(&dusty, "[camera]\nsensor_width_mm = 36\nfocal_length_mm = 50\nf_number = 8\n\n[[effect]]\ntype = \"aperture\"\nblades = 7\ndust = 50\ndust_min_um = 100\ndust_max_um = 200\n").unwrap();
    let (kernel, pupil) = (dir.path().join("k.pfm"), dir.path().join("pupil.png"));
    aureole()
        .args(["psf", "--config"])
        .arg(&dusty)
        .args(["--size", "65", "-o"])
        .arg(&kernel)
        .arg("--pupil")
        .arg(&pupil)
        .assert()
        .success();
    let picture = read_image(&pupil, Limits::NONE).unwrap().image;
    assert_eq!((picture.width, picture.height), (512, 512));
    // The stop is black about the picture's edge; inside, the clear glass
    // is white and the specks dark.
    let grey = &picture.planes[0];
    assert_eq!(grey[0], 0.0);
    let centre_row = &grey[256 * 512 + 128..256 * 512 + 384];
    assert!(centre_row.iter().filter(|&&v| v == 1.0).count() > 200);
    let dark_inside = (150..362)
        .flat_map(|j| (150..362).map(move |i| (i, j)))
        .filter(|&(i, j)| grey[j * 512 + i] < 0.5)
        .count();
    assert!(
        dark_inside > 20,
        "{dark_inside} dark pixels inside the stop"
    );

    let out = dir.path().join("k2.pfm");
    aureole()
        .args(["psf", "--preset", "paper-fig4-bloom", "--size", "11", "-o"])
        .arg(&out)
        .arg("--pupil")
        .arg(dir.path().join("p.png"))
        .assert()
        .failure()
        .stderr(predicate::str::contains("no pupil to draw"));
    assert!(!out.exists());
}

#[test]
fn psf_from_image_reads_a_kernel_written_at_another_pitch() {
    // A 7-blade stop's PSF of a point (a photographed star) written as an
    // EXR at 7680 px across the sensor, read back as a measured PSF at
    // 1920: the stop's own kernel at 1920, its light within 2, 4 and 8 px
    // within 2 %.
    let dir = tempfile::tempdir().unwrap();
    let (fine, coarse, direct) = (
        dir.path().join("fine.exr"),
        dir.path().join("coarse.pfm"),
        dir.path().join("direct.pfm"),
    );
    aureole()
        .args([
            "psf",
            "--preset",
            "camera-f8-7blade",
            "--size",
            "401",
            "--image-width",
            "7680",
            "--sent-by",
            "point",
            "-o",
        ])
        .arg(&fine)
        .assert()
        .success();
    let sensor = dir.path().join("sensor.toml");
    std::fs::write(&sensor, "[camera]\nsensor_width_mm = 36\n").unwrap();
    aureole()
        .args(["psf", "--config"])
        .arg(&sensor)
        .arg("--from-image")
        .arg(&fine)
        .args([
            "--pitch-um",
            "4.6875",
            "--size",
            "81",
            "--image-width",
            "1920",
            "-o",
        ])
        .arg(&coarse)
        .assert()
        .success()
        .stderr(predicate::str::contains("centre at (200.00, 200.00)"));
    aureole()
        .args([
            "psf",
            "--preset",
            "camera-f8-7blade",
            "--size",
            "81",
            "--image-width",
            "1920",
            "-o",
        ])
        .arg(&direct)
        .assert()
        .success();
    let (a, b) = (read_pfm(&coarse), read_pfm(&direct));
    let within = |image: &aureole::Image, c: usize, r: f64| -> f64 {
        (0..81 * 81)
            .filter(|i| ((i % 81) as f64 - 40.0).hypot((i / 81) as f64 - 40.0) <= r)
            .map(|i| f64::from(image.planes[c][i]))
            .sum()
    };
    for c in 0..3 {
        for r in [2.0, 4.0, 8.0] {
            let (x, y) = (within(&a, c, r), within(&b, c, r));
            assert!(
                (x / y - 1.0).abs() < 0.02,
                "plane {c}, r = {r}: {x} against {y}"
            );
        }
    }
    // A missing file is named.
    aureole()
        .args(["psf", "--config"])
        .arg(&sensor)
        .args([
            "--from-image",
            "nowhere.exr",
            "--pitch-um",
            "4",
            "--size",
            "11",
            "-o",
        ])
        .arg(dir.path().join("x.pfm"))
        .assert()
        .failure()
        .stderr(predicate::str::contains("nowhere.exr"));
}

#[test]
fn presets_and_configs_compose_in_command_line_order() {
    let dir = tempfile::tempdir().unwrap();
    let lens85 = dir.path().join("85mm.toml");
    std::fs::write(&lens85, "[camera]\nfocal_length_mm = 85.0\n").unwrap();
    let build = |args: &[&str]| {
        let out = dir.path().join("k.pfm");
        aureole()
            .arg("psf")
            .args(args)
            .args(["--size", "41", "-o"])
            .arg(&out)
            .assert()
            .success();
        read_pfm(&out).planes.remove(0)
    };
    let cfg = lens85.to_str().unwrap();
    let later_config = build(&["--preset", "human-eye-vos", "--config", cfg]);
    let later_preset = build(&["--config", cfg, "--preset", "human-eye-vos"]);
    let text85 = "[camera]\nfocal_length_mm = 85.0\n";
    assert_eq!(
        later_config,
        library_kernel(&["human-eye-vos", text85], 41).planes()[0]
    );
    assert_eq!(
        later_preset,
        library_kernel(&[text85, "human-eye-vos"], 41).planes()[0]
    );
    assert_ne!(later_config, later_preset);
}

#[test]
fn seed_option_overrides_the_config() {
    let dir = tempfile::tempdir().unwrap();
    let out = |name: &str| dir.path().join(name);
    for (name, seed) in [("1.pfm", "1"), ("2.pfm", "2")] {
        aureole()
            .args([
                "psf",
                "--preset",
                "paper-fig5-corona",
                "--size",
                "61",
                "--seed",
                seed,
                "-o",
            ])
            .arg(out(name))
            .assert()
            .success();
    }
    let (a, b) = (read_pfm(&out("1.pfm")), read_pfm(&out("2.pfm")));
    assert_ne!(a, b);
}

#[test]
fn physical_units_use_the_image_width() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("um.toml");
    std::fs::write(
        &config,
        "[camera]\nsensor_width_mm = 36.0\n[[effect]]\ntype = \"bloom\"\nepsilon = 0.01\nbeta = 3.0\nradius = \"60um\"\n",
    )
    .unwrap();
    let run = |image_width: &str| {
        let out = dir.path().join(format!("{image_width}.pfm"));
        aureole()
            .args([
                "psf",
                "--size",
                "101",
                "--image-width",
                image_width,
                "--config",
            ])
            .arg(&config)
            .arg("-o")
            .arg(&out)
            .assert()
            .success();
        read_pfm(&out).planes.remove(0)
    };
    // 36 mm over 3600 px: 10 µm pitch, R = 6 px; over 1800 px, R = 3 px.
    let (wide, narrow) = (run("3600"), run("1800"));
    let px = |r: &str| {
        library_kernel(
            &[&format!(
                "[[effect]]\ntype = \"bloom\"\nepsilon = 0.01\nbeta = 3.0\nradius = \"{r}\"\n"
            )],
            101,
        )
        .planes()[0]
            .clone()
    };
    for (got, want) in [(wide, px("6px")), (narrow, px("3px"))] {
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() <= 1e-6 * w.abs().max(1e-12));
        }
    }
}

#[test]
fn presets_lists_every_preset_and_prints_one_as_toml() {
    let listing = aureole()
        .arg("presets")
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let listing = String::from_utf8(listing).unwrap();
    for preset in presets::PRESETS {
        assert!(
            listing
                .lines()
                .any(|l| l.starts_with(preset.name) && l.contains(&preset.description())),
            "{listing}"
        );
    }
    let toml = aureole()
        .args(["presets", "paper-fig6a"])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let parsed = aureole::ConfigFile::parse(std::str::from_utf8(&toml).unwrap(), "out").unwrap();
    assert_eq!(
        parsed,
        presets::find("paper-fig6a").unwrap().config().unwrap()
    );
}

fn assert_refused(args: &[&str], code: i32, expected: &[&str], out: Option<&Path>) {
    let assert = aureole().args(args).assert().failure().code(code);
    let line = one_line(&assert.get_output().stderr);
    for e in expected {
        assert!(line.contains(e), "{args:?}: {line}");
    }
    if let Some(out) = out {
        assert!(!out.exists(), "{} was written", out.display());
    }
}

#[test]
fn bad_arguments_get_one_clear_line_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("k.pfm");
    let o = out.to_str().unwrap();
    let um = dir.path().join("um.toml");
    std::fs::write(
        &um,
        "[[effect]]\ntype = \"bloom\"\nepsilon = 0.1\nbeta = 2.0\nradius = \"60um\"\n",
    )
    .unwrap();
    let typo = dir.path().join("typo.toml");
    std::fs::write(
        &typo,
        "[[effect]]\ntype = \"corona\"\nepsilon = 0.1\nrays = 6\nlenght = \"9px\"\n",
    )
    .unwrap();
    let missing = dir.path().join("missing.toml");

    assert_refused(
        &["psf", "--preset", "paper-fig9", "--size", "9", "-o", o],
        2,
        &["paper-fig9", "paper-fig4-bloom"],
        Some(&out),
    );
    assert_refused(
        &[
            "psf",
            "--preset",
            "paper-fig4-bloom",
            "--size",
            "0",
            "-o",
            o,
        ],
        2,
        &["--size", "above 0"],
        Some(&out),
    );
    assert_refused(
        &[
            "psf",
            "--preset",
            "paper-fig4-bloom",
            "--size",
            "9x",
            "-o",
            o,
        ],
        2,
        &["--size"],
        Some(&out),
    );
    let jpg = dir.path().join("k.jpg");
    assert_refused(
        &[
            "psf",
            "--preset",
            "paper-fig4-bloom",
            "--size",
            "9",
            "-o",
            jpg.to_str().unwrap(),
        ],
        2,
        &["k.jpg", "\"jpg\"", ".pfm"],
        Some(&jpg),
    );
    assert_refused(
        &[
            "psf",
            "--config",
            um.to_str().unwrap(),
            "--size",
            "9",
            "-o",
            o,
        ],
        2,
        &["60um", "sensor_width_mm"],
        Some(&out),
    );
    assert_refused(
        &[
            "psf",
            "--config",
            typo.to_str().unwrap(),
            "--size",
            "9",
            "-o",
            o,
        ],
        2,
        &["typo.toml:5:1", "lenght", "length"],
        Some(&out),
    );
    assert_refused(
        &[
            "psf",
            "--config",
            missing.to_str().unwrap(),
            "--size",
            "9",
            "-o",
            o,
        ],
        2,
        &["missing.toml"],
        Some(&out),
    );
    assert_refused(
        &["psf", "--size", "9", "-o", o],
        2,
        &["no effect"],
        Some(&out),
    );
    let plot = dir.path().join("plot.png");
    assert_refused(
        &[
            "psf",
            "--preset",
            "paper-fig4-bloom",
            "--size",
            "9",
            "-o",
            o,
            "--profile",
            plot.to_str().unwrap(),
            "--profile-radius",
            "-3",
        ],
        2,
        &["--profile-radius", "above 0"],
        Some(&out),
    );
    assert_refused(
        &["presets", "nope"],
        2,
        &["nope", "paper-fig5-corona"],
        None,
    );

    let nowhere = dir.path().join("no-such-folder").join("k.pfm");
    assert_refused(
        &[
            "psf",
            "--preset",
            "paper-fig4-bloom",
            "--size",
            "9",
            "-o",
            nowhere.to_str().unwrap(),
        ],
        2,
        &["no-such-folder"],
        Some(&nowhere),
    );
    // Only the two configs are there: no output and no temporary file.
    let mut left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    left.sort();
    assert_eq!(left, ["typo.toml", "um.toml"]);
}

#[test]
fn help_explains_options_with_their_units() {
    let help = aureole()
        .args(["psf", "--help"])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let help = String::from_utf8(help).unwrap();
    for phrase in [
        "--size",
        "pixels",
        "pixel pitch",
        "µm",
        "--profile",
        "--seed",
        "ΣK = 1",
    ] {
        assert!(help.contains(phrase), "{phrase} missing from:\n{help}");
    }
    // The auto exposure is described as it meters (display::meter), not as
    // the log-average meter it replaced.
    let apply = aureole().args(["apply", "--help"]).assert().success();
    let apply = String::from_utf8(apply.get_output().stdout.clone()).unwrap();
    assert!(
        apply.contains("percentile meter") && apply.contains("12 % of white"),
        "{apply}"
    );
    assert!(!apply.contains("log-average"), "{apply}");
}

#[test]
fn help_lists_what_the_tables_hold() {
    let help = |command: &str| {
        let out = aureole().args([command, "--help"]).assert().success();
        String::from_utf8(out.get_output().stdout.clone()).unwrap()
    };
    let (apply, psf, demo) = (help("apply"), help("psf"), help("demo"));
    for format in aureole_io::formats::FORMATS {
        assert!(apply.contains(format.name), "{}:\n{apply}", format.name);
        let extension = format!(".{}", format.extensions[0]);
        assert!(apply.contains(&extension), "{extension}:\n{apply}");
        assert!(demo.contains(&extension), "{extension}:\n{demo}");
        let holds_kernels = format.kernels != aureole_io::formats::KernelStorage::Unsupported;
        assert_eq!(
            psf.contains(&extension),
            holds_kernels,
            "{extension}:\n{psf}"
        );
    }
    for compression in aureole_io::compression::Compression::ALL {
        assert!(
            apply.contains(compression.name()),
            "{compression}:\n{apply}"
        );
    }
    for (curve, _) in aureole_io::display::ToneCurve::NAMES {
        assert!(apply.contains(curve), "{curve}:\n{apply}");
    }
    assert!(apply.contains(aureole::presets::DEFAULT_PRESET), "{apply}");
}

#[test]
fn aperture_presets_write_coloured_kernels() {
    let dir = tempfile::tempdir().unwrap();
    let (pfm_path, exr_path, png) = (
        dir.path().join("k.pfm"),
        dir.path().join("k.exr"),
        dir.path().join("k.png"),
    );
    for out in [&pfm_path, &exr_path, &png] {
        aureole()
            .args([
                "psf",
                "--preset",
                "camera-f8-7blade",
                "--size",
                "61",
                "--image-width",
                "3840",
                "-o",
            ])
            .arg(out)
            .assert()
            .success()
            .stderr(predicate::str::contains("3 channels"));
    }
    assert!(std::fs::read(&pfm_path)
        .unwrap()
        .starts_with(b"PF\n61 61\n"));
    let kernel = read_pfm(&pfm_path);
    for plane in &kernel.planes {
        let sum: f64 = plane.iter().map(|&v| f64::from(v)).sum();
        assert!(sum > 0.95 && sum <= 1.0, "sum {sum}");
    }
    let image = exr::prelude::read_all_flat_layers_from_file(&exr_path).unwrap();
    let names: Vec<String> = image.layer_data[0]
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    assert_eq!(names, ["B", "G", "R"]);
    let picture = image::open(&png).unwrap();
    assert!(matches!(picture, image::DynamicImage::ImageRgb8(_)));
}

#[test]
fn aperture_configs_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("k.pfm");
    let write = |name: &str, text: &str| {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        path
    };
    let two_blades = write("two.toml", "[camera]\nsensor_width_mm = 36.0\nfocal_length_mm = 50.0\nf_number = 8.0\n[[effect]]\ntype = \"aperture\"\nblades = 2\n");
    let no_f = write("nof.toml", "[camera]\nsensor_width_mm = 36.0\nfocal_length_mm = 50.0\n[[effect]]\ntype = \"aperture\"\nblades = 6\n");
    let bad_filter = write("filter.toml", "[camera]\nsensor_width_mm = 36.0\nfocal_length_mm = 50.0\nf_number = 8.0\n[[effect]]\ntype = \"aperture\"\nblades = 6\n[[effect.filter]]\nspacing_um = 10.0\nwidth_um = 20.0\n");
    for (config, expected) in [
        (&two_blades, &["blades = 2", "3 to 64"][..]),
        (&no_f, &["f_number"][..]),
        (&bad_filter, &["width_um = 20", "below the spacing"][..]),
    ] {
        assert_refused(
            &[
                "psf",
                "--config",
                config.to_str().unwrap(),
                "--size",
                "9",
                "-o",
                out.to_str().unwrap(),
            ],
            2,
            expected,
            Some(&out),
        );
    }
}

/// The guide's candle recipe on the image it names changes the picture
/// (docs/guide.md): with the file's scale, thousands of pixels visibly.
#[test]
fn the_candle_recipe_changes_candleglass_visibly() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let input = root.join("../shared/data/CandleGlass.exr");
    if !input.is_file() {
        required::missing(
            "the_candle_recipe_changes_candleglass_visibly",
            &format!("{} is absent", input.display()),
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let identity = dir.path().join("identity.toml");
    std::fs::write(
        &identity,
        "[[effect]]\ntype = \"bloom\"\nradius = \"1px\"\nbeta = 2\nepsilon = 0\n",
    )
    .unwrap();
    let picture = |config: &Path, name: &str| {
        let out = dir.path().join(name);
        aureole()
            .args(["apply", "-q", "--input-scale", "50", "--config"])
            .arg(config)
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .assert()
            .success();
        image::open(&out).unwrap().to_rgb8()
    };
    let recipe = picture(&root.join("configs/candle-interior.toml"), "candle.png");
    let plain = picture(&identity, "plain.png");
    let changed = recipe
        .pixels()
        .zip(plain.pixels())
        .filter(|(a, b)| a.0.iter().zip(b.0).any(|(x, y)| x.abs_diff(y) >= 4))
        .count();
    assert!(changed > 5000, "{changed} pixels changed visibly");
}

/// A clone has no `../shared`: every page that names it says where its
/// images come from (the README's *Sample images*), and configs name none.
#[test]
fn docs_say_where_the_sample_images_come_from() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let section = readme
        .split("## Sample images")
        .nth(1)
        .and_then(|rest| rest.split("\n## ").next())
        .expect("README.md has a Sample images section");
    assert!(
        section.contains("git clone https://github.com/AcademySoftwareFoundation/openexr-images")
    );
    let outside = readme.replace(section, "");
    assert!(
        !outside.contains("../shared"),
        "README names ../shared outside Sample images"
    );
    let mut pages: Vec<_> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    assert!(pages.len() >= 8, "{pages:?}");
    for path in pages {
        let page = path.display();
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            if line.contains("../shared") {
                let near = &lines[i.saturating_sub(8)..(i + 9).min(lines.len())];
                assert!(
                    near.iter().any(|l| l.contains("Sample images")),
                    "{page}:{}: names ../shared without saying where it comes from",
                    i + 1
                );
            }
        }
    }
    // The configs and the lenses under them.
    let mut folders = vec![root.join("configs")];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path);
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            assert!(!text.contains("../shared"), "{}", path.display());
        }
    }
}

/// `--device`: the CPU when asked, the GPU where there is one (lavapipe in
/// CI) with its name in the summary line, and one clear line, no output,
/// when the GPU is asked for and the machine has no Vulkan driver.
#[test]
fn device_chooses_where_the_light_is_spread() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("lamps.pfm");
    let (w, h) = (48usize, 32usize);
    let mut bytes = format!("PF\n{w} {h}\n-1.0\n").into_bytes();
    for i in 0..w * h {
        let v: f32 = if i % 97 == 0 { 400.0 } else { 1.0 };
        for _ in 0..3 {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(&input, bytes).unwrap();
    let run = |device: &str, name: &str| {
        let mut command = aureole();
        command
            .args(["apply", "--preset", "paper-fig4-bloom", "--device", device])
            .arg(&input)
            .arg("-o")
            .arg(dir.path().join(name));
        command
    };
    run("cpu", "cpu.pfm")
        .assert()
        .success()
        .stderr(predicate::str::contains("(FFT on the CPU)"));
    on_the_gpu_or_refused(
        (run("gpu", "gpu.pfm"), "FFT on the GPU"),
        run("gpu", "none.pfm"),
        &dir.path().join("none.pfm"),
    );
}

/// `on_gpu` succeeds saying `said` where there is a GPU (lavapipe in CI),
/// and `refused` (the same command) with no Vulkan driver to find stops
/// with one line and no `output`.
fn on_the_gpu_or_refused(
    (mut on_gpu, said): (Command, &str),
    mut refused: Command,
    output: &std::path::Path,
) {
    let gpu = on_gpu.assert();
    if gpu.get_output().status.success() {
        gpu.stderr(predicate::str::contains(said));
    } else {
        required::missing(
            "on_the_gpu_or_refused",
            &format!(
                "no GPU adapter (Debian: mesa-vulkan-drivers for lavapipe): {}",
                one_line(&gpu.get_output().stderr)
            ),
        );
    }
    let refused = refused
        .arg("-q")
        .env("VK_ICD_FILENAMES", "/nonexistent.json")
        .env("VK_DRIVER_FILES", "/nonexistent.json")
        .assert()
        .failure();
    let line = one_line(&refused.get_output().stderr);
    assert!(line.contains("no GPU to compute on"), "{line}");
    assert!(!output.exists());
}

/// `psf --device`: where the chain's effects convolve one another, said in
/// the last line (nothing where there is one effect); one clear line and
/// no file when the GPU is asked for and there is no Vulkan driver.
#[test]
fn psf_composes_on_the_device_chosen() {
    let dir = tempfile::tempdir().unwrap();
    let run = |device: &str, name: &str| {
        let mut command = aureole();
        command
            .args(["psf", "--preset", "paper-fig5-both", "--size", "101x61"])
            .args(["--device", device, "-o"])
            .arg(dir.path().join(name));
        command
    };
    run("cpu", "cpu.exr")
        .assert()
        .success()
        .stderr(predicate::str::contains("(composed on the CPU)"));
    // One effect: nothing composed, nothing said, no GPU looked for.
    aureole()
        .args(["psf", "--preset", "paper-fig4-bloom", "--size", "31", "-o"])
        .arg(dir.path().join("bloom.exr"))
        .assert()
        .success()
        .stderr(predicate::str::contains("composed").not());
    on_the_gpu_or_refused(
        (run("gpu", "gpu.exr"), "(composed on the GPU "),
        run("gpu", "none.exr"),
        &dir.path().join("none.exr"),
    );
}

/// A reader of stderr that has gone (`aureole … 2>&1 | head -1`) loses
/// the messages, not the work: the kernel is written and the exit is 0,
/// where `eprintln!` panicked (exit 101).
#[test]
fn a_closed_stderr_does_not_fail_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("k.pfm");
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("aureole"))
        .args(["psf", "--preset", "paper-fig4-bloom", "--size", "33", "-o"])
        .arg(&out)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stderr.take());
    let status = child.wait().unwrap();
    assert!(status.success(), "{status}");
    assert_eq!(read_pfm(&out).width, 33);
}
