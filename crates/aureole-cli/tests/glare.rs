//! `aureole glare` as a user runs it: a fisheye picture with its view in
//! its header, the figures as text and JSON, the marked picture, and bad
//! input refused in one line.

use std::path::Path;

use assert_cmd::Command;

fn aureole() -> Command {
    Command::cargo_bin("aureole").unwrap()
}

/// A flat Radiance picture of grey `values` (row-major, top row first, in
/// Radiance's units) with `view` in a VIEW line, if any.
fn write_rgbe(path: &Path, width: usize, values: &[f32], view: Option<&str>) {
    let height = values.len() / width;
    let mut bytes = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n".to_vec();
    if let Some(v) = view {
        bytes.extend_from_slice(format!("VIEW= {v}\n").as_bytes());
    }
    bytes.extend_from_slice(format!("\n-Y {height} +X {width}\n").as_bytes());
    for &v in values {
        if v <= 1e-32 {
            bytes.extend_from_slice(&[0, 0, 0, 0]);
            continue;
        }
        let exponent = v.log2().floor() as i32 + 1;
        let mantissa = (v / 2f32.powi(exponent) * 256.0) as u8;
        bytes.extend_from_slice(&[mantissa, mantissa, mantissa, (exponent + 128) as u8]);
    }
    std::fs::write(path, bytes).unwrap();
}

/// A 180° angular fisheye of a 1 cd/m² room (in Radiance's units, 1/179)
/// with one lamp of 50 000 cd/m² on the line of sight.
fn room(path: &Path, view: Option<&str>) {
    let size = 201;
    let mut values = vec![1.0 / 179.0; size * size];
    for row in 95..106 {
        for column in 95..106 {
            values[row * size + column] = 50_000.0 / 179.0;
        }
    }
    write_rgbe(path, size, &values, view);
}

#[test]
fn a_fisheye_picture_is_rated_from_its_header() {
    let dir = tempfile::tempdir().unwrap();
    let picture = dir.path().join("room.hdr");
    room(
        &picture,
        Some("-vta -vp 0 0 1.2 -vd 0 1 0 -vu 0 0 1 -vh 180 -vv 180"),
    );
    let done = aureole().arg("glare").arg(&picture).assert().success();
    let text = String::from_utf8_lossy(&done.get_output().stdout).into_owned();
    for says in [
        "equidistant 180°×180° (the header's VIEW)",
        "179 cd/m² per unit (Radiance's 179 lm/W)",
        "DGP ",
        "UGR ",
        "1 glare source",
    ] {
        assert!(text.contains(says), "{says:?} in {text}");
    }
    let done = aureole()
        .args(["glare", "--json"])
        .arg(&picture)
        .assert()
        .success();
    let json: serde_json::Value = serde_json::from_slice(&done.get_output().stdout).unwrap();
    let sources = json["sources"].as_array().unwrap();
    assert_eq!(sources.len(), 1);
    let lamp = &sources[0];
    // RGBE keeps 8 bits of mantissa.
    assert!((lamp["luminance"].as_f64().unwrap() / 50_000.0 - 1.0).abs() < 0.01);
    assert!(lamp["angle_deg"].as_f64().unwrap() < 0.5);
    assert!((lamp["position_index"].as_f64().unwrap() - 1.0).abs() < 1e-3);
    let ev = json["vertical_illuminance"].as_f64().unwrap();
    let lamp_e = lamp["illuminance"].as_f64().unwrap();
    // The room's π·1 cd/m² (less the lamp's patch and RGBE's rounding
    // down) plus the lamp's share.
    assert!(
        (ev - lamp_e - std::f64::consts::PI).abs() < 0.05,
        "{ev} {lamp_e}"
    );
}

#[test]
fn the_marked_picture_is_written_and_never_over_the_input() {
    let dir = tempfile::tempdir().unwrap();
    let picture = dir.path().join("room.hdr");
    room(&picture, Some("-vta -vh 180 -vv 180"));
    let marked = dir.path().join("marked.png");
    aureole()
        .args(["glare", "-q"])
        .arg(&picture)
        .arg("-c")
        .arg(&marked)
        .assert()
        .success();
    let image = image::open(&marked).unwrap().to_rgb8();
    // The lamp is tinted in the first source's colour: red.
    let centre = image.get_pixel(100, 98);
    assert!(centre[0] > 200 && centre[1] < 150, "{centre:?}");
    let before = std::fs::read(&picture).unwrap();
    aureole()
        .args(["glare", "-q"])
        .arg(&picture)
        .arg("-c")
        .arg(&picture)
        .assert()
        .failure();
    assert_eq!(
        std::fs::read(&picture).unwrap(),
        before,
        "the input is untouched"
    );
}

#[test]
fn a_picture_without_a_view_is_refused_in_one_line_saying_what_to_give() {
    let dir = tempfile::tempdir().unwrap();
    let picture = dir.path().join("plain.hdr");
    room(&picture, None);
    let done = aureole().arg("glare").arg(&picture).assert().code(2);
    let stderr = String::from_utf8_lossy(&done.get_output().stderr).into_owned();
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("plain.hdr") && stderr.contains("--view"),
        "{stderr}"
    );
    // Given on the command line, it is rated.
    aureole()
        .args(["glare", "-q", "--projection", "equisolid", "--fov", "180"])
        .arg(&picture)
        .assert()
        .success();
    let viewed = dir.path().join("viewed.hdr");
    room(&viewed, Some("-vta -vh 180 -vv 180"));
    for (args, says) in [
        (vec!["--view", "-vtl -vh 10 -vv 10"], "parallel"),
        (vec!["--view", "-vtv -vh 200"], "at most 179°"),
        (
            vec!["--projection", "fishy", "--fov", "180"],
            "allowed: perspective",
        ),
        (vec!["--task", "10", "10", "7"], "full opening"),
        (vec!["--search", "4"], "at most π radians"),
    ] {
        let done = aureole()
            .arg("glare")
            .arg(&viewed)
            .args(&args)
            .assert()
            .code(2);
        let stderr = String::from_utf8_lossy(&done.get_output().stderr).into_owned();
        assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
    }
}
