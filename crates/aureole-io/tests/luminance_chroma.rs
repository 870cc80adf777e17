//! Luminance/chroma files (`Y` at full resolution, `RY` and `BY` at 2×2:
//! OpenEXR's `LuminanceChroma` and `Chromaticities` samples) decoded to RGB
//! as OpenEXR's own RGBA reader decodes them: tests/reference/rgba_input.cpp
//! is compiled against the installed library (Debian's libopenexr-dev,
//! found by pkg-config) and its RGB compared with ours, sample by sample.
//! Where the compiler, pkg-config, the library or the sample set is
//! missing, the test says so and passes.

use std::path::{Path, PathBuf};
use std::process::Command;

use aureole::Layout;
use aureole_io::limits::Limits;
use aureole_io::read::read_image;
use exr::prelude::f16;

mod common;
use common::images;

const FILES: [&str; 6] = [
    "LuminanceChroma/CrissyField.exr",
    "LuminanceChroma/Flowers.exr",
    "LuminanceChroma/MtTamNorth.exr",
    "LuminanceChroma/StarField.exr",
    "Chromaticities/Rec709_YC.exr",
    "Chromaticities/XYZ_YC.exr",
];

/// The reference program, built in `dir`; `None` (said) where it cannot be.
fn reference(dir: &Path) -> Option<PathBuf> {
    let flags = Command::new("pkg-config")
        .args(["--cflags", "--libs", "OpenEXR"])
        .output();
    let flags = match flags {
        Ok(out) if out.status.success() => String::from_utf8_lossy(&out.stdout).into_owned(),
        _ => {
            common::required::missing(
                "luminance_chroma",
                "pkg-config finds no OpenEXR (Debian: pkg-config, libopenexr-dev)",
            );
            return None;
        }
    };
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference/rgba_input.cpp");
    let program = dir.join("rgba_input");
    let built = Command::new("c++")
        .arg("-O2")
        .arg("-o")
        .arg(&program)
        .arg(&source)
        .args(flags.split_whitespace())
        .output();
    match built {
        Ok(out) if out.status.success() => Some(program),
        Ok(out) => panic!(
            "rgba_input.cpp does not build against the installed OpenEXR: {}",
            String::from_utf8_lossy(&out.stderr)
        ),
        Err(_) => {
            common::required::missing("luminance_chroma", "no C++ compiler (c++)");
            None
        }
    }
}

#[test]
fn luminance_chroma_files_decode_as_openexr_decodes_them() {
    let Some(images) = images() else { return };
    let dir = tempfile::tempdir().unwrap();
    let Some(program) = reference(dir.path()) else {
        return;
    };
    for name in FILES {
        let path = images.join(name);
        let out = Command::new(&program).arg(&path).output().unwrap();
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let expected: Vec<f32> = out
            .stdout
            .chunks_exact(2)
            .map(|b| f16::from_bits(u16::from_le_bytes([b[0], b[1]])).to_f32())
            .collect();
        let loaded = read_image(&path, Limits::NONE).unwrap();
        let image = loaded.image;
        assert_eq!(image.layout, Layout::Rgb, "{name}");
        assert_eq!(expected.len(), image.width * image.height * 3, "{name}");
        assert!(
            loaded.notes.iter().any(|n| n.contains("luminance/chroma")),
            "{name}: {:?}",
            loaded.notes
        );
        let mut differing = 0;
        let mut first = None;
        for (i, reference) in expected.chunks_exact(3).enumerate() {
            for (c, &theirs) in reference.iter().enumerate() {
                let ours = image.planes[c][i];
                if ours.to_bits() != theirs.to_bits() && !(ours.is_nan() && theirs.is_nan()) {
                    differing += 1;
                    first.get_or_insert((i % image.width, i / image.width, c, ours, theirs));
                }
            }
        }
        assert!(
            differing == 0,
            "{name}: {differing} of {} samples differ from OpenEXR's, the first (x, y, channel, ours, OpenEXR's) {first:?}",
            expected.len()
        );
    }
}
