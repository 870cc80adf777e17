//! Lens ghosts from the command line: a config naming a lens file beside
//! it, the ghosts' layer and summary, and an EXR's overscan, whose display
//! window holds the optical axis.

use std::path::Path;

use assert_cmd::Command;
use exr::prelude::*;

fn aureole() -> Command {
    Command::cargo_bin("aureole").unwrap()
}

/// A cemented achromat behind its stop, f ≈ 100 mm: three ghosts.
const ACHROMAT: &str = r#"
name = "A cemented achromat"

[[surface]]
stop = true
thickness = 5.0
semi_aperture = 12.0

[[surface]]
radius = 61.47
thickness = 6.0
n_d = 1.5168
v_d = 64.17
semi_aperture = 15.0

[[surface]]
radius = -44.64
thickness = 2.5
n_d = 1.6727
v_d = 32.21
semi_aperture = 15.0

[[surface]]
radius = -129.94
thickness = 95.0
semi_aperture = 15.0
"#;

/// A camera of `sensor_mm` whose ghosts are the achromat's, its lens file
/// in `lenses/` beside the config.
fn camera(dir: &Path, sensor_mm: f64) -> std::path::PathBuf {
    std::fs::create_dir_all(dir.join("lenses")).unwrap();
    std::fs::write(dir.join("lenses/achromat.toml"), ACHROMAT).unwrap();
    let config = dir.join(format!("camera-{sensor_mm}.toml"));
    std::fs::write(
        &config,
        format!(
            "[camera]\nsensor_width_mm = {sensor_mm:?}\nfocal_length_mm = 100.0\nf_number = 5.6\n\
             [[effect]]\ntype = \"ghosts\"\nlens = \"lenses/achromat.toml\"\n"
        ),
    )
    .unwrap();
    config
}

/// A dark 200×150 RGB float plate with a lamp of 3×3 pixels near a corner,
/// its display window `display` (origin, size) in the data window's frame
/// of (0, 0)–(199, 149) moved by `data_at`.
fn plate(path: &Path, display: (usize, usize), data_at: (i32, i32)) {
    let (w, h) = (200, 150);
    let mut values = vec![0.01f32; w * h];
    for y in 9..12 {
        for x in 9..12 {
            values[y * w + x] = 1e6;
        }
    }
    let channels: Vec<AnyChannel<FlatSamples>> = ["R", "G", "B"]
        .iter()
        .map(|n| AnyChannel::new(*n, FlatSamples::F32(values.clone())))
        .collect();
    let attributes = LayerAttributes {
        layer_position: Vec2(data_at.0, data_at.1),
        ..LayerAttributes::default()
    };
    let layer = Layer::new(
        (w, h),
        attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into_iter().collect()),
    );
    Image::from_layers(
        ImageAttributes::new(IntegerBounds::from_dimensions(display)),
        vec![layer],
    )
    .write()
    .to_file(path)
    .unwrap();
}

/// The first part's channels, by name.
fn channels(path: &Path) -> Vec<(String, Vec<f32>)> {
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .unwrap();
    image
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect()
}

fn rgb(path: &Path) -> Vec<Vec<f32>> {
    let all = channels(path);
    ["R", "G", "B"]
        .iter()
        .map(|name| all.iter().find(|(n, _)| n == name).unwrap().1.clone())
        .collect()
}

#[test]
fn an_overscans_ghosts_line_up_on_its_display_window() {
    let dir = tempfile::tempdir().unwrap();
    // The display window 160×120, the data window 20 px beyond it left and
    // 15 above (the lamp in the overscan): the axis is the data window's
    // pixel (100, 75), as it is for a 200×150 plate without overscan on a
    // sensor as much wider.
    let (overscan, whole) = (
        dir.path().join("overscan.exr"),
        dir.path().join("whole.exr"),
    );
    plate(&overscan, (160, 120), (-20, -15));
    plate(&whole, (200, 150), (0, 0));
    let run = |input: &Path, sensor_mm: f64, out: &str| {
        let output = dir.path().join(out);
        aureole()
            .arg("-q")
            .arg("apply")
            .arg(input)
            .arg("-o")
            .arg(&output)
            .arg("--config")
            .arg(camera(dir.path(), sensor_mm))
            .assert()
            .success();
        rgb(&output)
    };
    let (a, b) = (run(&overscan, 36.0, "a.exr"), run(&whole, 45.0, "b.exr"));
    assert_eq!(a, b);
    // Against the data window's centre the ghosts would lie elsewhere.
    let shifted = dir.path().join("shifted.exr");
    plate(&shifted, (160, 120), (0, 0));
    assert_ne!(run(&shifted, 36.0, "c.exr"), a);
}

#[test]
fn the_ghosts_have_their_layer_and_their_line_and_the_lens_file_is_found_beside_the_config() {
    let dir = tempfile::tempdir().unwrap();
    let (input, output) = (dir.path().join("plate.exr"), dir.path().join("out.exr"));
    plate(&input, (200, 150), (0, 0));
    let config = camera(dir.path(), 36.0);
    // Run from elsewhere: the lens file is the config's neighbour.
    let elsewhere = tempfile::tempdir().unwrap();
    let done = aureole()
        .current_dir(elsewhere.path())
        .arg("apply")
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .arg("--config")
        .arg(&config)
        .arg("--layers")
        .assert()
        .success();
    let said = String::from_utf8_lossy(&done.get_output().stderr).to_string();
    assert!(
        said.contains("ghosts: 1 of 1 sources traced through 3 paths at f/5.60"),
        "{said}"
    );
    let names: Vec<String> = channels(&output).into_iter().map(|(n, _)| n).collect();
    for name in [
        "glare.ghosts.R",
        "glare.ghosts.G",
        "glare.ghosts.B",
        "glare.R",
    ] {
        assert!(names.iter().any(|n| n == name), "{names:?}");
    }
    // A lens file that is not there is named, with the config's folder.
    std::fs::remove_file(dir.path().join("lenses/achromat.toml")).unwrap();
    let refused = aureole()
        .arg("apply")
        .arg(&input)
        .arg("-o")
        .arg(dir.path().join("never.exr"))
        .arg("--config")
        .arg(&config)
        .assert()
        .code(2);
    let said = String::from_utf8_lossy(&refused.get_output().stderr).to_string();
    assert!(said.contains("lenses/achromat.toml"), "{said}");
    assert_eq!(said.lines().count(), 1, "{said}");
    assert!(!dir.path().join("never.exr").exists());
}
