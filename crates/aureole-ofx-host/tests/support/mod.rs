//! What the plugin's tests share: the bundle built from the plugin the
//! tests were compiled with, night scenes, and the command line to
//! compare with.

#![allow(dead_code)]

use std::ffi::CStr;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, OnceLock};

use aureole_ofx_abi::names;
use aureole_ofx_host::{Instance, Picture, Plugin, Project, Setting};

#[path = "../../../../tests/support/required.rs"]
pub mod required;

/// The folder cargo builds this test into (`target/<profile>/deps`).
fn deps() -> PathBuf {
    let exe = std::env::current_exe().expect("the test's own path");
    exe.parent().expect("the deps folder").to_path_buf()
}

/// The repository's root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `Aureole.ofx.bundle`, laid out by `scripts/ofx-bundle` around the
/// plugin library cargo built for these tests, in a folder a host scans.
pub fn bundle() -> PathBuf {
    static BUNDLE: OnceLock<PathBuf> = OnceLock::new();
    BUNDLE
        .get_or_init(|| {
            let folder = deps().join("ofx-plugins");
            let library = deps().join("libaureole_ofx.so");
            let made = std::process::Command::new(root().join("scripts/ofx-bundle"))
                .arg("--binary")
                .arg(&library)
                .arg("--out")
                .arg(&folder)
                .output()
                .expect("scripts/ofx-bundle runs");
            assert!(
                made.status.success(),
                "{}",
                String::from_utf8_lossy(&made.stderr)
            );
            let found = aureole_ofx_host::bundles_in(&folder);
            assert_eq!(found.len(), 1, "{found:?}");
            found[0].clone()
        })
        .clone()
}

/// One test at a time: the plugin's binary is loaded once per process, and
/// a test that unloads it must not pull it from under another.
pub fn serial() -> MutexGuard<'static, ()> {
    static SERIAL: Mutex<()> = Mutex::new(());
    SERIAL.lock().unwrap_or_else(|p| p.into_inner())
}

/// The plugin loaded, described, and described in `context`.
pub fn loaded(context: &CStr) -> Plugin {
    let plugin = Plugin::load(&bundle()).expect("the bundle loads");
    plugin.describe().expect("describe");
    plugin
        .describe_in_context(context)
        .expect("describe in context");
    plugin
}

/// The index of `option` in the choice parameter `name`'s menu, as the
/// plugin described it.
pub fn option(plugin: &Plugin, name: &str, option: &str) -> i32 {
    let menu = [names::CONTEXT_FILTER, names::CONTEXT_GENERAL]
        .iter()
        .find_map(|context| plugin.param_definition(context, name))
        .expect("the parameter is defined")
        .strings(names::PARAM_CHOICE_OPTION);
    menu.iter()
        .position(|o| o == option)
        .unwrap_or_else(|| panic!("{option} not in {menu:?}")) as i32
}

/// An instance on a `width` × `height` project with the preset `preset`,
/// on the CPU.
pub fn instance<'p>(
    plugin: &'p Plugin,
    (width, height): (usize, usize),
    preset: &str,
) -> Instance<'p> {
    instance_in(plugin, Project::of(width, height), preset)
}

/// An instance on `project` with the preset `preset`, on the CPU.
pub fn instance_in<'p>(plugin: &'p Plugin, project: Project, preset: &str) -> Instance<'p> {
    let instance = plugin
        .instance(names::CONTEXT_FILTER, project)
        .expect("an instance");
    instance
        .set("preset", Setting::Int(option(plugin, "preset", preset)))
        .expect("the preset is set");
    instance
        .set("device", Setting::Int(option(plugin, "device", "cpu")))
        .expect("device");
    instance
}

/// A night street at `width` × `height`, RGBA: a dim blue-grey gradient,
/// a row of sodium lamps and a white one, alpha falling off to the right.
/// The lamps are `factor`² pixels each, so that a frame twice as large
/// reduced by area is the smaller one.
pub fn night(width: usize, height: usize, factor: usize) -> Picture {
    let mut pixels = vec![0.0f32; width * height * 4];
    for y in 0..height {
        for x in 0..width {
            let i = (y * width + x) * 4;
            let fy = (y / factor) as f32 / (height / factor) as f32;
            pixels[i] = 0.02 + 0.05 * fy;
            pixels[i + 1] = 0.03 + 0.05 * fy;
            pixels[i + 2] = 0.06 + 0.04 * fy;
            pixels[i + 3] = 1.0 - 0.5 * (x / factor) as f32 / (width / factor) as f32;
        }
    }
    let (w, h) = (width / factor, height / factor);
    let lamps = [
        (w / 5, h / 3, [4.0e4f32, 2.4e4, 6.0e3]),
        (w / 2, h / 4, [9.0e4, 9.0e4, 9.0e4]),
        (4 * w / 5, h / 2, [3.0e4, 1.8e4, 4.0e3]),
    ];
    for (lx, ly, rgb) in lamps {
        for j in 0..factor {
            for i in 0..factor {
                let p = ((ly * factor + j) * width + lx * factor + i) * 4;
                pixels[p..p + 3].copy_from_slice(&rgb);
            }
        }
    }
    Picture {
        width,
        height,
        channels: 4,
        pixels,
    }
}

/// The command line built beside these tests (`cargo test --workspace`
/// builds it), or None.
pub fn cli() -> Option<PathBuf> {
    let path = deps().parent()?.join("aureole");
    path.is_file().then_some(path)
}

/// `aureole apply` of `picture` (as a float EXR) with `args`: the result
/// as a picture, or None (the skip recorded) without the command line.
pub fn cli_apply(test: &str, picture: &Picture, args: &[&str]) -> Option<Picture> {
    let Some(cli) = cli() else {
        required::missing(
            test,
            "the aureole command line next to the tests (cargo test --workspace builds it)",
        );
        return None;
    };
    let dir = tempfile::tempdir().expect("a temporary folder");
    let (input, output) = (dir.path().join("in.exr"), dir.path().join("out.exr"));
    aureole_io::write::write_linear(&input, &picture.to_image(), Default::default())
        .expect("the input is written");
    let run = std::process::Command::new(cli)
        .arg("apply")
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .args(args)
        .output()
        .expect("the command line runs");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let limits = aureole_io::limits::Limits::default_for_machine();
    let loaded = aureole_io::read::read_image(&output, limits).expect("the output is read");
    Some(Picture::of_image(&loaded.image, picture.channels))
}

/// The first sample where `a` and `b` differ in their bits.
pub fn first_difference(a: &Picture, b: &Picture) -> Option<(usize, f32, f32)> {
    assert_eq!(
        (a.width, a.height, a.channels),
        (b.width, b.height, b.channels)
    );
    a.pixels
        .iter()
        .zip(&b.pixels)
        .enumerate()
        .find(|(_, (x, y))| x.to_bits() != y.to_bits())
        .map(|(i, (x, y))| (i, *x, *y))
}
