//! Every format we read and write, on files the tests make themselves.

use std::path::Path;

#[path = "../../../tests/support/required.rs"]
mod required;

use aureole::{Image, Layout};
use aureole_io::limits::Limits;
use aureole_io::read::read_image;
use aureole_io::write::{write_linear, LinearOptions};
use exr::prelude::*;

fn test_image(layout: Layout, alpha: bool) -> aureole::Image {
    let (w, h) = (13, 7);
    let mut image = aureole::Image::filled(w, h, layout, 0.0);
    for (c, plane) in image.planes.iter_mut().enumerate() {
        for (i, v) in plane.iter_mut().enumerate() {
            // Luminances from 10⁻³ to 10⁵, and a few small negatives.
            *v = 10f32.powf((i % 9) as f32 - 3.0) * (1.0 + c as f32 * 0.1);
            if i % 17 == 5 {
                *v = -1e-3;
            }
        }
    }
    if alpha {
        image.alpha = Some((0..w * h).map(|i| (i % 3) as f32 * 0.5).collect());
    }
    image
}

#[test]
fn exr_float_round_trips_rgb_rgba_and_luminance() {
    let dir = tempfile::tempdir().unwrap();
    for (layout, alpha) in [
        (Layout::Rgb, false),
        (Layout::Rgb, true),
        (Layout::Luminance, false),
        (Layout::Luminance, true),
    ] {
        let mut image = test_image(layout, alpha);
        image.white_luminance = Some(621.0);
        let path = dir.path().join("x.exr");
        write_linear(&path, &image, LinearOptions::default()).unwrap();
        let loaded = read_image(&path, Limits::NONE).unwrap();
        assert_eq!(loaded.format, "OpenEXR");
        assert_eq!(loaded.image, image, "{layout:?} alpha {alpha}");
        assert!(loaded.notes.is_empty(), "{:?}", loaded.notes);
    }
}

#[test]
fn exr_half_keeps_half_precision() {
    let dir = tempfile::tempdir().unwrap();
    let image = test_image(Layout::Rgb, false);
    let path = dir.path().join("h.exr");
    let notes = write_linear(
        &path,
        &image,
        LinearOptions {
            samples: Some(aureole_io::formats::Samples::Half),
            ..LinearOptions::default()
        },
    )
    .unwrap();
    // 10⁵ cd/m² lamps exceed the half range: clamped, and said so.
    assert!(
        notes.iter().any(|n| n.to_string().contains("65504")),
        "{notes:?}"
    );
    let loaded = read_image(&path, Limits::NONE).unwrap().image;
    for (a, b) in loaded
        .planes
        .iter()
        .flatten()
        .zip(image.planes.iter().flatten())
    {
        let expected = b.clamp(-65504.0, 65504.0);
        assert!(
            (a - expected).abs() <= 1e-3 * expected.abs().max(1e-3),
            "{a} vs {b}"
        );
    }
    // Half takes less room than float.
    let float = dir.path().join("f.exr");
    write_linear(&float, &image, LinearOptions::default()).unwrap();
    assert!(std::fs::metadata(&path).unwrap().len() < std::fs::metadata(&float).unwrap().len());
}

/// Writes channels with the exr crate directly, as other software would.
fn write_exr(
    path: &Path,
    channels: Vec<(&str, Vec<f32>)>,
    encoding: Encoding,
    size: (usize, usize),
) {
    let list = channels
        .into_iter()
        .map(|(name, values)| {
            AnyChannel::new(
                name,
                FlatSamples::F16(values.into_iter().map(f16::from_f32).collect()),
            )
        })
        .collect();
    let layer = Layer::new(
        size,
        LayerAttributes::default(),
        encoding,
        AnyChannels::sort(list),
    );
    exr::prelude::Image::from_layer(layer)
        .write()
        .to_file(path)
        .unwrap();
}

#[test]
fn exr_tiled_half_piz_and_multi_view_luminance_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let size = (300, 260); // more than one 256×256 tile
    let ramp: Vec<f32> = (0..size.0 * size.1).map(|i| (i % 1000) as f32).collect();

    let tiled = dir.path().join("tiled.exr");
    write_exr(
        &tiled,
        vec![
            ("R", ramp.clone()),
            ("G", ramp.clone()),
            ("B", ramp.clone()),
        ],
        Encoding::SMALL_FAST_LOSSLESS,
        size,
    );
    let loaded = read_image(&tiled, Limits::NONE).unwrap().image;
    assert_eq!(
        (loaded.width, loaded.height, loaded.layout),
        (300, 260, Layout::Rgb)
    );
    assert_eq!(loaded.planes[2], ramp);

    // A stereo luminance file: the default view is `Y`, the other `right.Y`.
    let views = dir.path().join("views.exr");
    let right: Vec<f32> = ramp.iter().map(|v| v + 1.0).collect();
    write_exr(
        &views,
        vec![("Y", ramp.clone()), ("right.Y", right)],
        Encoding::FAST_LOSSLESS,
        size,
    );
    let loaded = read_image(&views, Limits::NONE).unwrap();
    assert_eq!(loaded.image.layout, Layout::Luminance);
    assert_eq!(loaded.image.planes[0], ramp);
    assert!(
        loaded.notes.iter().any(|n| n.contains("others (right)")),
        "{:?}",
        loaded.notes
    );
}

#[test]
fn exr_without_colour_channels_is_refused_naming_them() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("depth.exr");
    write_exr(
        &path,
        vec![("Z", vec![1.0; 4])],
        Encoding::UNCOMPRESSED,
        (2, 2),
    );
    let e = read_image(&path, Limits::NONE).unwrap_err().to_string();
    assert!(
        e.contains("depth.exr") && e.contains("Z") && e.contains("R, G, B or Y"),
        "{e}"
    );
}

#[test]
fn pfm_round_trips_both_layouts() {
    let dir = tempfile::tempdir().unwrap();
    for layout in [Layout::Rgb, Layout::Luminance] {
        let image = test_image(layout, false);
        let path = dir.path().join("x.pfm");
        write_linear(&path, &image, LinearOptions::default()).unwrap();
        assert_eq!(read_image(&path, Limits::NONE).unwrap().image, image);
    }
}

#[test]
fn radiance_hdr_round_trips_within_rgbe_precision() {
    let dir = tempfile::tempdir().unwrap();
    let image = test_image(Layout::Rgb, false);
    let path = dir.path().join("x.hdr");
    let notes = write_linear(&path, &image, LinearOptions::default()).unwrap();
    assert!(
        notes.iter().any(|n| n.to_string().contains("negative")),
        "{notes:?}"
    );
    let loaded = read_image(&path, Limits::NONE).unwrap();
    assert_eq!(loaded.format, "Radiance HDR");
    assert!(!loaded.display_referred);
    for (a, b) in loaded
        .image
        .planes
        .iter()
        .flatten()
        .zip(image.planes.iter().flatten())
    {
        // RGBE shares one exponent per pixel: 8 bits of mantissa for the
        // largest channel, and negatives become 0.
        let expected = b.max(0.0);
        assert!(
            (a - expected).abs() <= 0.01 * expected.max(1e-6) + 1e-6,
            "{a} vs {b}"
        );
    }
}

#[test]
fn display_images_are_decoded_from_srgb_to_linear() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("x.png");
    let values: [u8; 4] = [0, 64, 128, 255];
    image::GrayImage::from_raw(4, 1, values.to_vec())
        .unwrap()
        .save(&png)
        .unwrap();
    let loaded = read_image(&png, Limits::NONE).unwrap();
    assert!(loaded.display_referred);
    assert_eq!(loaded.image.layout, Layout::Luminance);
    let expected = [0.0, 0.051_269_46, 0.215_860_53, 1.0];
    for (got, want) in loaded.image.planes[0].iter().zip(expected) {
        assert!((got - want).abs() < 1e-5, "{got} vs {want}");
    }

    let png16 = dir.path().join("x16.png");
    image::ImageBuffer::<image::Rgba<u16>, _>::from_raw(1, 1, vec![65535u16, 32768, 0, 65535])
        .unwrap()
        .save(&png16)
        .unwrap();
    let loaded = read_image(&png16, Limits::NONE).unwrap().image;
    assert_eq!(loaded.layout, Layout::Rgb);
    assert!((loaded.planes[1][0] - 0.214_04).abs() < 1e-4);
    assert_eq!(loaded.alpha, Some(vec![1.0]));

    let jpg = dir.path().join("x.jpg");
    image::RgbImage::from_pixel(8, 8, image::Rgb([200, 100, 50]))
        .save(&jpg)
        .unwrap();
    let loaded = read_image(&jpg, Limits::NONE).unwrap();
    assert_eq!(loaded.format, "JPEG");
    assert!(loaded.display_referred);
}

#[test]
fn float_tiff_is_linear_and_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.tif");
    let values = vec![0.5f32, 2.0, 1e4, 3.0, 0.0, 7.5];
    image::ImageBuffer::<image::Rgb<f32>, _>::from_raw(2, 1, values.clone())
        .unwrap()
        .save(&path)
        .unwrap();
    let loaded = read_image(&path, Limits::NONE).unwrap();
    assert!(!loaded.display_referred);
    assert_eq!(loaded.image.planes[0], vec![0.5, 3.0]);
    assert_eq!(loaded.image.planes[2], vec![1e4, 7.5]);
}

#[test]
fn unknown_and_empty_files_are_refused_by_content() {
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty.exr");
    std::fs::write(&empty, b"").unwrap();
    let e = read_image(&empty, Limits::NONE).unwrap_err().to_string();
    assert!(e.contains("empty.exr") && e.contains("empty"), "{e}");
    let text = dir.path().join("notes.exr");
    std::fs::write(&text, b"hello, world").unwrap();
    let e = read_image(&text, Limits::NONE).unwrap_err().to_string();
    assert!(
        e.contains("notes.exr") && e.contains("OpenEXR, Radiance"),
        "{e}"
    );
    // The extension does not matter: an EXR named .png is still read.
    let image = test_image(Layout::Rgb, false);
    let exr = dir.path().join("really.exr");
    write_linear(&exr, &image, LinearOptions::default()).unwrap();
    let disguised = dir.path().join("really-exr.png");
    std::fs::rename(&exr, &disguised).unwrap();
    assert_eq!(read_image(&disguised, Limits::NONE).unwrap().image, image);
}

#[test]
fn non_finite_pixels_are_counted_and_located() {
    let mut image = Image::filled(5, 4, Layout::Rgb, 1.0);
    image.planes[1][2 * 5 + 3] = f32::NAN;
    image.planes[2][3 * 5 + 1] = f32::INFINITY;
    let bad = image.non_finite().unwrap();
    assert_eq!((bad.count, bad.first), (2, (3, 2)));
    assert_eq!(image.sanitize(), 2);
    assert!(image.non_finite().is_none());
    assert_eq!(image.planes[1][13], 0.0);
}

#[test]
fn a_failed_write_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.exr");
    let result = aureole_io::atomic::write_atomic(&path, |_| {
        Err(aureole_io::Error::Encode {
            path: path.clone(),
            format: "EXR",
            message: "disk on fire".into(),
        })
    });
    assert!(result.is_err());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);

    let missing = dir.path().join("no-such-folder").join("out.exr");
    let e = write_linear(
        &missing,
        &test_image(Layout::Rgb, false),
        LinearOptions::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("no-such-folder"), "{e}");
    assert!(!missing.exists());
}

#[cfg(unix)]
#[test]
fn outputs_are_ordinary_files_that_others_may_read() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.pfm");
    write_linear(
        &path,
        &test_image(Layout::Luminance, false),
        LinearOptions::default(),
    )
    .unwrap();
    let mode = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
    // 0666 less the umask, as for any file a program creates (Linux shows
    // the umask in /proc; elsewhere only the owner's bits are checked).
    let umask = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|status| {
            let line = status.lines().find(|l| l.starts_with("Umask:"))?;
            u32::from_str_radix(line["Umask:".len()..].trim(), 8).ok()
        });
    match umask {
        Some(umask) => assert_eq!(mode, 0o666 & !umask, "{mode:o}"),
        None => assert_eq!(mode & 0o600, 0o600, "{mode:o}"),
    }
}

#[cfg(unix)]
#[test]
fn an_unwritable_folder_leaves_no_file() {
    // A file where the folder should be: refused for root too.
    let dir = tempfile::tempdir().unwrap();
    let not_a_folder = dir.path().join("not-a-folder");
    std::fs::write(&not_a_folder, b"kept").unwrap();
    assert!(write_linear(
        &not_a_folder.join("out.pfm"),
        &test_image(Layout::Rgb, false),
        LinearOptions::default()
    )
    .is_err());
    assert_eq!(std::fs::read(&not_a_folder).unwrap(), b"kept");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    // A folder without write permission: root writes there regardless, so
    // as root this test runs again as `nobody` (setpriv) and must pass.
    if required::running_as_root() {
        let again = std::process::Command::new("setpriv")
            .args(["--reuid=65534", "--regid=65534", "--clear-groups"])
            .arg(std::env::current_exe().unwrap())
            .args([
                "--exact",
                "an_unwritable_folder_leaves_no_file",
                "--test-threads=1",
            ])
            .output();
        match again {
            Ok(out) => assert!(
                out.status.success() && String::from_utf8_lossy(&out.stdout).contains("1 passed"),
                "as nobody: {}{}",
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            ),
            Err(_) => required::missing(
                "an_unwritable_folder_leaves_no_file",
                "running as root without setpriv (util-linux) to drop privileges",
            ),
        }
        return;
    }
    use std::os::unix::fs::PermissionsExt;
    let locked = dir.path().join("locked");
    std::fs::create_dir(&locked).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
    let path = locked.join("out.pfm");
    assert!(write_linear(
        &path,
        &test_image(Layout::Rgb, false),
        LinearOptions::default()
    )
    .is_err());
    assert_eq!(std::fs::read_dir(&locked).unwrap().count(), 0);
}

/// The Radiance file at `path` with `lines` added to its header, as a
/// renderer that exposed or corrected its pixels writes them.
fn with_header_lines(path: &Path, lines: &[u8]) -> Vec<u8> {
    let bytes = std::fs::read(path).unwrap();
    let format = b"FORMAT=32-bit_rle_rgbe\n";
    let at = bytes
        .windows(format.len())
        .position(|w| w == format)
        .unwrap()
        + format.len();
    [&bytes[..at], lines, &bytes[at..]].concat()
}

#[test]
fn radiance_exposure_colour_correction_and_primaries_are_honoured_and_kept() {
    use aureole_io::write::write_linear_into;
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain.hdr");
    let mut image = aureole::Image::filled(8, 4, Layout::Rgb, 0.0);
    for (c, plane) in image.planes.iter_mut().enumerate() {
        plane.iter_mut().for_each(|v| *v = [4.0, 2.0, 1.0][c]);
    }
    write_linear(&plain, &image, LinearOptions::default()).unwrap();
    // A renderer's file whose pixels were doubled after rendering, its red
    // halved, on other primaries.
    let edited = with_header_lines(
        &plain,
        b"EXPOSURE=2\nCOLORCORR=0.5 1 1\nPRIMARIES=0.68 0.32 0.265 0.69 0.15 0.06 0.3127 0.329\nVIEW= -vta -vh 180 -vv 180\nVIEW= -vv 170\n",
    );
    let exposed = dir.path().join("exposed.hdr");
    std::fs::write(&exposed, &edited).unwrap();

    let loaded = read_image(&exposed, Limits::NONE).unwrap();
    // Red: 4 stored = 4 · 2 (exposure) · 0.5 (correction); green 2 = 1 · 2.
    let first = |l: &aureole_io::read::Loaded, c: usize| l.image.planes[c][0];
    assert!(
        (first(&loaded, 0) - 4.0).abs() < 0.05,
        "{}",
        first(&loaded, 0)
    );
    assert!(
        (first(&loaded, 1) - 1.0).abs() < 0.02,
        "{}",
        first(&loaded, 1)
    );
    assert!(
        loaded.notes.iter().any(|n| n.contains("EXPOSURE=2")),
        "{:?}",
        loaded.notes
    );
    let p3 = loaded.image.primaries.expect("the header's primaries");
    assert_eq!(p3.green, [0.265, 0.69]);
    // Every VIEW line, in order: a later option overrides an earlier one.
    assert_eq!(
        loaded.original.radiance_view(),
        Some("-vta -vh 180 -vv 180 -vv 170")
    );

    // Written back, the header says the same and the pixels read the same.
    let back = dir.path().join("back.hdr");
    write_linear_into(
        &back,
        &loaded.image,
        LinearOptions::default(),
        loaded.original.clone(),
    )
    .unwrap();
    let text = String::from_utf8_lossy(&std::fs::read(&back).unwrap()).into_owned();
    assert!(
        text.contains("EXPOSURE=2\n") && text.contains("COLORCORR=0.5 1 1\n"),
        "{text}"
    );
    assert!(text.contains("PRIMARIES=0.68 0.32"), "{text}");
    assert!(
        text.contains("VIEW= -vta -vh 180 -vv 180 -vv 170\n"),
        "{text}"
    );
    let again = read_image(&back, Limits::NONE).unwrap();
    for c in 0..3 {
        assert!((first(&again, c) - first(&loaded, c)).abs() < 0.02 * first(&loaded, c));
    }
}

#[test]
fn a_radiance_exposure_of_zero_or_less_is_ignored_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain.hdr");
    let image = aureole::Image::filled(8, 4, Layout::Rgb, 2.0);
    write_linear(&plain, &image, LinearOptions::default()).unwrap();
    for (line, said) in [
        (&b"EXPOSURE=0\n"[..], "EXPOSURE=0 is not a factor above 0"),
        (b"EXPOSURE=-2\n", "EXPOSURE=-2 is not a factor above 0"),
        (b"COLORCORR=1 0 1\n", "COLORCORR=1 0 1 holds a factor"),
    ] {
        let edited = with_header_lines(&plain, line);
        let path = dir.path().join("bad.hdr");
        std::fs::write(&path, &edited).unwrap();
        let loaded = read_image(&path, Limits::NONE).unwrap();
        assert!(
            loaded.notes.iter().any(|n| n.contains(said)),
            "{said}: {:?}",
            loaded.notes
        );
        assert!(loaded
            .image
            .planes
            .iter()
            .flatten()
            .all(|&v| (v - 2.0).abs() < 0.02));
    }
}
