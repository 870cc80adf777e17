//! The command lines the studio gives for an export (`POST /api/command`),
//! pasted into a shell, write the export's bytes: the page no longer words
//! the command line itself, and a flag renamed here breaks this test.

use std::path::Path;
use std::process::Command;

use aureole_studio::budget::Budget;
use aureole_studio::export::{ExportRequest, Exports};
use aureole_studio::Roots;

/// Runs the export `body` describes under `root` and waits for its end.
fn export(root: &Path, body: &serde_json::Value) {
    let exports = Exports::new(
        Roots::new(&[root.to_path_buf()]).unwrap(),
        Budget::new(4 << 30),
        aureole::Device::Cpu,
    );
    let request = ExportRequest::from_json(body.to_string().as_bytes()).unwrap();
    let id = exports.start(request).unwrap();
    loop {
        let progress = exports.progress(id).unwrap();
        if progress.done {
            assert_eq!(progress.error, None);
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// Runs the studio's command lines for `body` in a shell in `root`, with
/// the camera in `camera.toml` as the page downloads it.
fn paste(root: &Path, body: &serde_json::Value) {
    let request = ExportRequest::from_json(body.to_string().as_bytes()).unwrap();
    let commands = aureole_studio::command::for_export(&request).unwrap();
    std::fs::write(
        root.join(aureole_studio::command::CONFIG_FILE),
        body["config"].as_str().unwrap(),
    )
    .unwrap();
    let binary = Path::new(env!("CARGO_BIN_EXE_aureole"));
    let path = format!(
        "{}:{}",
        binary.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let out = Command::new("sh")
        .args(["-c", &format!("set -e\n{}", commands.text)])
        .current_dir(root)
        .env("PATH", path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}\n{}",
        commands.text,
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn the_studios_command_lines_write_what_its_export_writes() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    let image = "night's street.exr";
    aureole_io::write::write_linear(
        &root.join(image),
        &aureole_io::demo::night_street(240, 135),
        Default::default(),
    )
    .unwrap();
    let camera = aureole::presets::find("camera-f8-7blade").unwrap().toml;
    let bloom = "[[effect]]\ntype = \"bloom\"\nepsilon = 0.02\nbeta = 2.0\nradius = \"4px\"\n";
    let cases = [
        serde_json::json!({
            "image": image, "config": camera, "threshold": 50.0, "knee": 0.5,
            "exposure": 3.5, "tonemap": "reinhard", "view": "glare",
        }),
        serde_json::json!({
            "image": image, "config": camera, "white": 2000.0, "tonemap": "clip",
            "max_kernel": "101x61",
        }),
        serde_json::json!({ "image": image, "config": bloom, "exposure": "auto" }),
        serde_json::json!({ "image": "demo", "config": bloom, "max_kernel": 65 }),
    ];
    for (n, case) in cases.into_iter().enumerate() {
        for output in [format!("case {n}.png"), format!("case-{n}.exr")] {
            let mut studio = case.clone();
            studio["output"] = format!("studio {output}").into();
            export(root, &studio);
            let mut shell = case.clone();
            shell["output"] = format!("shell {output}").into();
            paste(root, &shell);
            let read = |who: &str| std::fs::read(root.join(format!("{who} {output}"))).unwrap();
            assert!(read("studio") == read("shell"), "{case}: {output} differs");
        }
    }
    // Each effect's glare beside the result, into an EXR.
    let layered = serde_json::json!({
        "image": image, "config": format!("{camera}\n{bloom}"), "layers": true,
    });
    for who in ["studio", "shell"] {
        let mut body = layered.clone();
        body["output"] = format!("{who} layers.exr").into();
        if who == "studio" {
            export(root, &body);
        } else {
            paste(root, &body);
        }
    }
    let read = |who: &str| std::fs::read(root.join(format!("{who} layers.exr"))).unwrap();
    assert!(
        read("studio") == read("shell"),
        "the layered exports differ"
    );
    let text = String::from_utf8_lossy(&read("studio")).into_owned();
    assert!(text.contains("glare.aperture.R") && text.contains("glare.bloom.R"));
}
