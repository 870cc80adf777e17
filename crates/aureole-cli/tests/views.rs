//! Stereo and multi-view plates from OpenEXR's sample set: every view goes
//! through the same camera, each eye comes out as it would alone, and a
//! deep stereo file is described by `info`, though apply cannot spread it.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use exr::prelude::*;
use predicates::prelude::*;

fn sample(name: &str) -> Option<PathBuf> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/openexr-images")
        .join(name);
    if path.is_file() {
        Some(path)
    } else {
        eprintln!("skipped: {} is absent", path.display());
        None
    }
}

fn read_all(path: &Path) -> FlatImage {
    read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .unwrap()
}

/// Every channel of every part, by part and name.
fn channels(image: &FlatImage) -> Vec<((usize, String), Vec<f32>)> {
    image
        .layer_data
        .iter()
        .enumerate()
        .flat_map(|(part, layer)| {
            layer.channel_data.list.iter().map(move |c| {
                let values = c.sample_data.values_as_f32().collect();
                ((part, c.name.to_string()), values)
            })
        })
        .collect()
}

fn apply(input: &Path, output: &Path, more: &[&str]) -> assert_cmd::assert::Assert {
    Command::cargo_bin("aureole")
        .unwrap()
        .args(["apply", "--threshold", "0.3", "--max-kernel", "33"])
        .args(more)
        .arg(input)
        .arg("-o")
        .arg(output)
        .assert()
        .success()
}

#[test]
fn every_view_of_a_stereo_plate_goes_through_the_camera() {
    let dir = tempfile::tempdir().unwrap();
    // Views: by part (`view` attributes) and by channel prefix (`multiView`);
    // each eye's R, G, B, as (part, prefix).
    for (name, eyes) in [
        ("Beachball/multipart.0001.exr", &[(0, ""), (4, "")][..]),
        (
            "Beachball/singlepart.0001.exr",
            &[(0, ""), (0, "left.")][..],
        ),
        (
            "MultiView/Adjuster.exr",
            &[(0, ""), (0, "left."), (0, "right.")][..],
        ),
    ] {
        let Some(input) = sample(name) else { return };
        let output = dir.path().join("out.exr");
        apply(&input, &output, &[]).stderr(predicate::str::contains(
            "every view goes through the camera",
        ));
        let (before, after) = (channels(&read_all(&input)), channels(&read_all(&output)));
        let names = |c: &[((usize, String), Vec<f32>)]| -> Vec<(usize, String)> {
            c.iter().map(|(n, _)| n.clone()).collect()
        };
        assert_eq!(names(&before), names(&after), "{name}: the same channels");
        for (((part, channel), a), (_, b)) in before.iter().zip(&after) {
            let eye = eyes.iter().any(|(p, prefix)| {
                p == part
                    && ["R", "G", "B"]
                        .iter()
                        .any(|c| *channel == format!("{prefix}{c}"))
            });
            if eye {
                assert_ne!(a, b, "{name}: {part} {channel} went through the camera");
                // Light is moved, not made: the sums agree within half's
                // steps and B44's (Adjuster.exr is lossy, B44A).
                let sum = |v: &[f32]| v.iter().map(|&v| f64::from(v)).sum::<f64>();
                let (sa, sb) = (sum(a), sum(b));
                assert!(
                    (sa - sb).abs() <= 5e-3 * sa.abs().max(1.0),
                    "{name} {part} {channel}: {sa} {sb}"
                );
            } else {
                assert_eq!(a, b, "{name}: {part} {channel} goes back untouched");
            }
        }
    }
}

#[test]
fn each_eye_comes_out_as_it_would_alone() {
    let Some(input) = sample("MultiView/Adjuster.exr") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (all, left) = (dir.path().join("all.exr"), dir.path().join("left.exr"));
    apply(&input, &all, &["-q"]);
    // The left eye chosen first: the same bytes for it as in the whole run.
    apply(&input, &left, &["-q", "--layer", "left"]);
    let (a, b) = (channels(&read_all(&all)), channels(&read_all(&left)));
    assert_eq!(a, b, "every channel of every view alike");
}

#[test]
fn info_describes_a_deep_stereo_file_that_apply_refuses() {
    let Some(input) = sample("v2/Stereo/Trunks.exr") else {
        return;
    };
    Command::cargo_bin("aureole")
        .unwrap()
        .arg("info")
        .arg(&input)
        .assert()
        .success()
        .stdout(
            predicate::str::contains("apply cannot spread it: part 0 holds deep data")
                .and(predicate::str::contains(
                    "part 1 \"rgba.right\": deep, data window (0, 266)–(1882, 1079), zips, view right",
                ))
                .and(predicate::str::contains("A half, B half, G half, R half, Z float")),
        );
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("out.exr");
    Command::cargo_bin("aureole")
        .unwrap()
        .arg("apply")
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .assert()
        .failure()
        .stderr(predicate::str::contains("deep data"));
}
