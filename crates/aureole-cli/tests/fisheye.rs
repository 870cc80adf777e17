//! The eye over a fisheye picture, as a user runs it: the view from a
//! Radiance picture's header or from `[camera]`, and what is refused.

use std::path::Path;

use assert_cmd::Command;

fn aureole() -> Command {
    Command::cargo_bin("aureole").unwrap()
}

/// A flat Radiance picture: a dim room with one lamp, `view` in its header.
fn picture(path: &Path, view: Option<&str>) {
    let size = 121;
    let mut bytes = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n".to_vec();
    if let Some(v) = view {
        bytes.extend_from_slice(format!("VIEW= {v}\n").as_bytes());
    }
    bytes.extend_from_slice(format!("\n-Y {size} +X {size}\n").as_bytes());
    for i in 0..size * size {
        // 1 (mantissa 128, exponent 1) or 2¹⁵ for the lamp.
        let lamp = i == 60 * size + 60;
        bytes.extend_from_slice(&[128, 128, 128, if lamp { 144 } else { 129 }]);
    }
    std::fs::write(path, bytes).unwrap();
}

fn stderr_of(output: &std::process::Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

#[test]
fn a_fisheye_headers_view_spreads_the_eye_over_the_sphere() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("room.hdr");
    picture(&input, Some("-vta -vh 180 -vv 180"));
    let output = dir.path().join("seen.pfm");
    let done = aureole()
        .args([
            "apply",
            "--preset",
            "human-eye-cie-70",
            "--threshold",
            "100",
        ])
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .assert()
        .success();
    let stderr = stderr_of(done.get_output());
    assert!(
        stderr
            .contains("the header's VIEW (equidistant 180°×180°) spreads the eye over the sphere"),
        "{stderr}"
    );
    // The same through [camera]: the same bytes.
    let config = dir.path().join("fisheye.toml");
    std::fs::write(
        &config,
        "[camera]\nprojection = \"equidistant\"\nfield_of_view_deg = 180\n\n[[effect]]\ntype = \"eye\"\nage = 70\npigmentation = 1.0\n",
    )
    .unwrap();
    let plain = dir.path().join("plain.hdr");
    picture(&plain, None);
    let again = dir.path().join("again.pfm");
    aureole()
        .args(["apply", "-q", "--threshold", "100", "--config"])
        .arg(&config)
        .arg(&plain)
        .arg("-o")
        .arg(&again)
        .assert()
        .success();
    assert_eq!(
        std::fs::read(&output).unwrap(),
        std::fs::read(&again).unwrap()
    );
}

#[test]
fn a_wide_view_with_a_lenss_effects_or_no_field_of_view_is_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("room.hdr");
    picture(&input, None);
    for (config, says) in [
        (
            "[camera]\nprojection = \"equisolid\"\nfield_of_view_deg = 180\n[[effect]]\ntype = \"bloom\"\nepsilon = 0.01\nbeta = 2\nradius = \"2px\"\n",
            "spreads the eye alone",
        ),
        (
            "[camera]\nprojection = \"equisolid\"\n[[effect]]\ntype = \"eye\"\n",
            "field_of_view_deg",
        ),
        (
            "[camera]\nprojection = \"fishy\"\n[[effect]]\ntype = \"eye\"\n",
            "unknown variant `fishy`",
        ),
        (
            "[camera]\nprojection = \"perspective\"\nfield_of_view_deg = 200\n[[effect]]\ntype = \"eye\"\n",
            "field_of_view_deg",
        ),
    ] {
        let path = dir.path().join("camera.toml");
        std::fs::write(&path, config).unwrap();
        let out = dir.path().join("out.pfm");
        let done = aureole()
            .args(["apply", "-q", "--config"])
            .arg(&path)
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .assert()
            .failure();
        let stderr = stderr_of(done.get_output());
        assert_eq!(stderr.trim_end().lines().count(), 1, "{config}: {stderr}");
        assert!(stderr.contains(says), "{config}: {stderr}");
        assert!(!out.exists(), "no partial output");
    }
}
