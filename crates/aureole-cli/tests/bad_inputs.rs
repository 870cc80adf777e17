//! The catalogue of bad inputs: for each, `aureole` exits non-zero (2 for
//! usage and configuration, 1 for failures while running) with one line on
//! stderr naming the file and the problem, leaves no output behind and does
//! not touch its input.

#[path = "../../../tests/support/required.rs"]
mod required;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command as Process;

use assert_cmd::Command;
use aureole::{Image, Layout};
use aureole_io::write::{write_linear, LinearOptions};

/// A case: the files it starts from, the arguments, what must come back.
struct Case {
    name: &'static str,
    args: Vec<String>,
    code: i32,
    expected: Vec<String>,
}

fn small_scene() -> Image {
    let (w, h) = (24, 16);
    let mut image = Image::filled(w, h, Layout::Rgb, 0.05);
    for plane in &mut image.planes {
        plane[5 * w + 7] = 2e4;
    }
    image.white_luminance = None;
    image
}

/// Every file under `dir` with its bytes (and mode), to see that nothing
/// was touched, added or left behind.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, (Vec<u8>, u32)> {
    use std::os::unix::fs::PermissionsExt;
    let mut files = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(folder) = stack.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            let meta = std::fs::symlink_metadata(&path).unwrap();
            if meta.is_dir() {
                stack.push(path.clone());
                files.insert(path, (Vec::new(), meta.permissions().mode()));
            } else if meta.is_file() {
                let bytes = if meta.permissions().mode() & 0o444 != 0 {
                    std::fs::read(&path).unwrap_or_default()
                } else {
                    Vec::new()
                };
                files.insert(path, (bytes, meta.permissions().mode()));
            } else {
                files.insert(path, (Vec::new(), meta.permissions().mode()));
            }
        }
    }
    files
}

/// Runs `args` in `dir`; as the unprivileged user `nobody` when `unprivileged`
/// (root reads and writes whatever the permissions say).
fn run(dir: &Path, args: &[String], unprivileged: bool) -> std::process::Output {
    let binary = assert_cmd::cargo::cargo_bin("aureole");
    let mut command = if unprivileged && required::running_as_root() {
        let mut c = Command::new("setpriv");
        c.args(["--reuid=65534", "--regid=65534", "--clear-groups"])
            .arg(binary);
        c
    } else {
        Command::new(binary)
    };
    command.current_dir(dir).args(args).output().unwrap()
}

fn check(dir: &Path, case: &Case, unprivileged: bool) {
    let before = snapshot(dir);
    let output = run(dir, &case.args, unprivileged);
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    let name = case.name;
    assert_eq!(output.status.code(), Some(case.code), "{name}: {stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{name}: {stderr}");
    assert!(stderr.starts_with("aureole: error: "), "{name}: {stderr}");
    for word in ["panicked", "backtrace", "RUST_BACKTRACE"] {
        assert!(!stderr.contains(word), "{name}: {stderr}");
    }
    for expected in &case.expected {
        assert!(
            stderr.contains(expected),
            "{name}: {expected:?} not in {stderr}"
        );
    }
    assert_eq!(snapshot(dir), before, "{name}: files changed; {stderr}");
}

fn case(name: &'static str, args: Vec<String>, code: i32, expected: &[&str]) -> Case {
    Case {
        name,
        args,
        code,
        expected: expected.iter().map(|s| s.to_string()).collect(),
    }
}

/// `aureole apply -q INPUT -o OUTPUT --preset paper-fig4-bloom EXTRA…`.
fn apply(input: &str, output: &str, extra: &[&str]) -> Vec<String> {
    let camera = ["--preset", "paper-fig4-bloom"];
    ["apply", "-q", input, "-o", output]
        .iter()
        .chain(&camera)
        .chain(extra)
        .map(|s| s.to_string())
        .collect()
}

/// Writes the test inputs into `dir`.
fn make_inputs(dir: &Path) {
    let scene = small_scene();
    let write = |name: &str, image: &Image| {
        write_linear(&dir.join(name), image, LinearOptions::default()).unwrap();
    };
    write("scene.exr", &scene);
    write("scene.hdr", &scene);
    write("scene.pfm", &scene);
    let png = dir.join("scene.png");
    aureole_io::write::write_picture(
        &png,
        &aureole_io::display::render(
            &scene,
            1.0,
            &aureole_io::display::DisplayOptions {
                exposure: aureole_io::display::Exposure::Auto,
                tone: aureole_io::display::ToneCurve::Filmic,
            },
        ),
        aureole_io::display::Depth::Eight,
    )
    .unwrap();
    let file = |name: &str, bytes: &[u8]| std::fs::write(dir.join(name), bytes).unwrap();
    file("empty.exr", b"");
    file("text.exr", b"this is not an image at all\n");
    for (source, ext) in [
        ("scene.exr", "exr"),
        ("scene.hdr", "hdr"),
        ("scene.pfm", "pfm"),
        ("scene.png", "png"),
    ] {
        let bytes = std::fs::read(dir.join(source)).unwrap();
        for fraction in [0.02, 0.3, 0.6, 0.95] {
            let cut = ((bytes.len() as f64 * fraction) as usize).max(3);
            file(
                &format!("cut{}.{ext}", (fraction * 100.0) as u32),
                &bytes[..cut],
            );
        }
    }
    // EXR headers that declare an absurd image, and an inverted data window.
    let exr = std::fs::read(dir.join("scene.exr")).unwrap();
    let window = |xmax: i32, ymax: i32, xmin: i32| {
        let key = b"dataWindow\0box2i\0";
        let at = exr.windows(key.len()).position(|w| w == key).unwrap() + key.len() + 4;
        let mut bytes = exr.clone();
        bytes[at..at + 4].copy_from_slice(&xmin.to_le_bytes());
        bytes[at + 8..at + 12].copy_from_slice(&xmax.to_le_bytes());
        bytes[at + 12..at + 16].copy_from_slice(&ymax.to_le_bytes());
        bytes
    };
    file("huge.exr", &window(99_999, 99_999, 0));
    file("absurd.exr", &window(2_000_000_000, 2_000_000_000, 0));
    file("wide.exr", &window(1 << 24, 15, 0));
    // 12000×8000 declared; the pixels are not there, so only a check of the
    // header before decoding tells the kernel's size.
    file("large.exr", &window(11_999, 7_999, 0));
    file("inverted.exr", &window(0, 15, 100));
    let mut hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 100000\n".to_vec();
    hdr.extend_from_slice(&[2, 2, 0x80, 0, 1, 2, 3, 4]);
    file("huge.hdr", &hdr);
    // A PNG whose header declares 100000×100000 16-bit RGB (60 GB).
    let png = std::fs::read(dir.join("scene.png")).unwrap();
    let mut huge_png = png.clone();
    huge_png[16..20].copy_from_slice(&100_000u32.to_be_bytes());
    huge_png[20..24].copy_from_slice(&100_000u32.to_be_bytes());
    file("huge.png", &huge_png);
    file("claims.pfm", b"PF\n100000 100000\n-1.0\n\0\0\0\0\0\0\0\0");
    file("zerowide.pfm", b"PF\n0 16\n-1.0\n");
    file("zerohigh.pfm", b"Pf\n16 0\n-1.0\n");
    let pfm = |name: &str, values: &[f32]| {
        let mut bytes = b"Pf\n4 4\n-1.0\n".to_vec();
        for v in values {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        file(name, &bytes);
    };
    let mut values = [1.0f32; 16];
    values[5] = f32::NAN;
    pfm("nan.pfm", &values);
    values[5] = f32::INFINITY;
    pfm("inf.pfm", &values);
    let config = |name: &str, text: &str| file(name, text.as_bytes());
    let bloom = "[[effect]]\ntype = \"bloom\"\nradius = \"10px\"\nbeta = 2\nepsilon = 0.05\n";
    config("typo.toml", &format!("{bloom}radus = 3\n"));
    config("toptypo.toml", &format!("treshold = 1\n{bloom}"));
    config("type.toml", &bloom.replace("beta = 2", "beta = \"two\""));
    config("missing.toml", &bloom.replace("epsilon = 0.05\n", ""));
    config("seed.toml", &format!("seed = -1\n{bloom}"));
    config(
        "camera.toml",
        &format!("[camera]\nf_number = \"eight\"\n{bloom}"),
    );
    config(
        "wavelength.toml",
        "[[effect]]\ntype = \"aperture\"\nwavelength_nm = 550\nblades = 6\n",
    );
    config(
        "range.toml",
        &bloom.replace("epsilon = 0.05", "epsilon = 1.5"),
    );
    config("kind.toml", &bloom.replace("\"bloom\"", "\"blom\""));
    config("syntax.toml", "[[effect]\ntype = \"bloom\"\n");
    config("um.toml", &bloom.replace("10px", "60um"));
    std::os::unix::fs::symlink("scene.exr", dir.join("link.exr")).unwrap();
    std::fs::hard_link(dir.join("scene.exr"), dir.join("hard.exr")).unwrap();
    std::fs::create_dir(dir.join("folder.exr")).unwrap();
    std::fs::create_dir(dir.join("out")).unwrap();
}

#[test]
fn every_bad_input_gets_one_line_a_status_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    make_inputs(dir);
    fn input(name: &'static str, file: &str, expected: &[&str]) -> Case {
        case(name, apply(file, "out/r.exr", &[]), 1, expected)
    }
    let mut cases = vec![
        input(
            "missing file",
            "nothing.exr",
            &["nothing.exr", "no such file"],
        ),
        input("a folder", "folder.exr", &["folder.exr", "folder"]),
        input("empty file", "empty.exr", &["empty.exr", "empty"]),
        input("wrong magic", "text.exr", &["text.exr", "not an image"]),
        input("absurd EXR size", "huge.exr", &["huge.exr", "memory limit"]),
        input(
            "absurd EXR window",
            "absurd.exr",
            &["absurd.exr", "OpenEXR", "data window"],
        ),
        // Checked from the header, before the pixels are decoded.
        input(
            "wide EXR",
            "wide.exr",
            &["wide.exr", "kernel size", "--max-kernel"],
        ),
        input(
            "large EXR, full kernel",
            "large.exr",
            &["large.exr", "kernel size 23999x15999", "--max-kernel"],
        ),
        input(
            "inverted EXR window",
            "inverted.exr",
            &["inverted.exr", "OpenEXR"],
        ),
        input("absurd HDR size", "huge.hdr", &["huge.hdr", "memory limit"]),
        input("absurd PNG size", "huge.png", &["huge.png", "PNG"]),
        input("PFM claims more", "claims.pfm", &["claims.pfm", "holds"]),
        input("zero width", "zerowide.pfm", &["zerowide.pfm", "width"]),
        input("zero height", "zerohigh.pfm", &["zerohigh.pfm", "height"]),
        input(
            "NaN",
            "nan.pfm",
            &[
                "nan.pfm",
                "NaN",
                "column 1 row 2 (from the top)",
                "--sanitize",
            ],
        ),
        input(
            "infinity",
            "inf.pfm",
            &["inf.pfm", "infinite", "--sanitize"],
        ),
    ];
    for ext in ["exr", "hdr", "pfm", "png"] {
        for cut in [2, 30, 60, 95] {
            let name = format!("cut{cut}.{ext}");
            cases.push(input("truncated", &name, &[&name]));
        }
    }
    let configured = |name, extra: &[&str], expected: &[&str]| {
        case(name, apply("scene.exr", "out/r.exr", extra), 2, expected)
    };
    cases.extend([
        configured(
            "frame range beyond counting",
            &["--frames", "0-18446744073709551615"],
            &["more than 1000000 frames"],
        ),
        case(
            "frame pattern without --frames",
            apply("scene.exr", "out/r.%04d.exr", &[]),
            2,
            &["out/r.%04d.exr", "--frames"],
        ),
        case(
            "glare-only into a format without negatives",
            apply("scene.exr", "out/g.hdr", &["--glare-only"]),
            2,
            &["out/g.hdr", "negative", ".exr or .pfm"],
        ),
        configured(
            "unknown preset",
            &["--preset", "paper-fig5-corna"],
            &[
                "paper-fig5-corna",
                "did you mean \"paper-fig5-corona\"",
                "paper-fig4-bloom",
            ],
        ),
        configured(
            "unknown key",
            &["--config", "typo.toml"],
            &["typo.toml:6:1", "`radus`", "did you mean `radius`"],
        ),
        configured(
            "unknown top key",
            &["--config", "toptypo.toml"],
            &["toptypo.toml:1:1", "`treshold`", "did you mean `threshold`"],
        ),
        configured(
            "wrong type",
            &["--config", "type.toml"],
            &["type.toml:4:1", "`beta`", "\"two\"", "expected a number"],
        ),
        configured(
            "negative seed",
            &["--config", "seed.toml"],
            &[
                "seed.toml:1:",
                "`seed`",
                "expected a whole number of at least 0",
            ],
        ),
        configured(
            "camera field of the wrong type",
            &["--config", "camera.toml"],
            &["camera.toml:2:", "`f_number`", "expected a number"],
        ),
        configured(
            "a wavelength for a spectral kernel",
            &["--config", "wavelength.toml"],
            &["wavelength.toml:3:1", "`wavelength_nm`", "spectral = false"],
        ),
        configured(
            "missing field",
            &["--config", "missing.toml"],
            &[
                "missing.toml:1:1",
                "missing field `epsilon`",
                "aureole presets paper-fig4-bloom",
            ],
        ),
        configured(
            "out of range",
            &["--config", "range.toml"],
            &["range.toml:5:1", "epsilon = 1.5", "from 0 to 1"],
        ),
        configured(
            "unknown effect",
            &["--config", "kind.toml"],
            &["kind.toml", "`blom`", "did you mean `bloom`"],
        ),
        configured(
            "syntax",
            &["--config", "syntax.toml"],
            &["syntax.toml:1:", "expected"],
        ),
        configured(
            "missing config",
            &["--config", "nothing.toml"],
            &["nothing.toml", "no such file"],
        ),
        configured(
            "um without camera",
            &["--config", "um.toml"],
            &["60um", "sensor_width_mm"],
        ),
    ]);
    let output =
        |name, path, expected: &[&str]| case(name, apply("scene.exr", path, &[]), 2, expected);
    cases.extend([
        output(
            "output folder missing",
            "nowhere/r.exr",
            &["nowhere/r.exr", "does not exist"],
        ),
        output(
            "output is the input",
            "./scene.exr",
            &["scene.exr", "overwrite the input"],
        ),
        case(
            "input is a link to the output",
            apply("link.exr", "scene.exr", &[]),
            2,
            &["scene.exr", "overwrite the input"],
        ),
        output(
            "output is a hard link to the input",
            "hard.exr",
            &["hard.exr", "overwrite the input"],
        ),
        output(
            "output is a link to the input",
            "link.exr",
            &["link.exr", "overwrite the input"],
        ),
        output(
            "output is the input by its absolute path",
            &format!("{}/scene.exr", dir.display()),
            &["scene.exr", "overwrite the input"],
        ),
        output(
            "output extension",
            "out/r.gif",
            &["out/r.gif", "\"gif\"", ".exr"],
        ),
        output("no extension", "out/r", &["out/r", "extension"]),
        output("output is a device", "/dev/null", &["/dev/null"]),
    ]);
    for c in &cases {
        check(dir, c, false);
    }
    eprintln!("{} bad inputs refused", cases.len());
    assert!(cases.len() >= 46);
}

#[test]
fn files_it_may_not_read_or_write_are_refused() {
    use std::os::unix::fs::PermissionsExt;
    if required::running_as_root() && Process::new("setpriv").arg("--version").output().is_err() {
        required::missing(
            "files_it_may_not_read_or_write_are_refused",
            "running as root without setpriv (util-linux) to drop privileges",
        );
        return;
    }
    let temp = tempfile::tempdir().unwrap();
    let dir = temp.path();
    std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o777)).unwrap();
    make_inputs(dir);
    let locked = dir.join("locked.exr");
    std::fs::copy(dir.join("scene.exr"), &locked).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o000)).unwrap();
    let closed = dir.join("closed");
    std::fs::create_dir(&closed).unwrap();
    std::fs::set_permissions(&closed, std::fs::Permissions::from_mode(0o555)).unwrap();
    for path in [dir.join("scene.exr"), dir.join("out")] {
        let mode = if path.is_dir() { 0o777 } else { 0o644 };
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(mode)).unwrap();
    }
    let cases = [
        case(
            "unreadable input",
            apply("locked.exr", "out/r.exr", &[]),
            1,
            &["locked.exr", "permission denied"],
        ),
        case(
            "unwritable folder",
            apply("scene.exr", "closed/r.exr", &[]),
            2,
            &["closed/r.exr", "cannot write", "permission denied"],
        ),
    ];
    for c in &cases {
        check(dir, c, true);
    }
}

/// A write that fails half way (the file-size limit is hit, as on a full
/// disk): the run fails, and neither the output nor its temporary file
/// remains.
#[test]
fn a_write_that_fails_half_way_leaves_nothing() {
    let temp = tempfile::tempdir().unwrap();
    let dir = temp.path();
    make_inputs(dir);
    let binary = assert_cmd::cargo::cargo_bin("aureole");
    // 1 block of 512 bytes: the EXR header fits, its pixels do not. SIGXFSZ
    // is ignored so that the write returns an error instead of killing us.
    let script = format!(
        "trap '' XFSZ; ulimit -f 1; exec {} apply -q scene.pfm -o out/r.pfm --preset paper-fig4-bloom",
        binary.display()
    );
    let before = snapshot(dir);
    let output = Process::new("sh")
        .current_dir(dir)
        .args(["-c", &script])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("out/r.pfm"), "{stderr}");
    assert!(stderr.contains("exceeds the size"), "{stderr}");
    assert_eq!(snapshot(dir), before, "{stderr}");
}
