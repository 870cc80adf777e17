//! Batch runs: several inputs or a frame pattern, failures that do not stop
//! the others, resuming with --skip-existing, Ctrl-C, thread counts, the
//! memory limit.

use std::path::Path;
use std::process::{Command as Process, Stdio};
use std::time::Duration;

use assert_cmd::Command;
use aureole::{Image, Layout};
use aureole_io::write::{write_linear, LinearOptions};

fn aureole() -> Command {
    Command::cargo_bin("aureole").unwrap()
}

/// Frame `n` of a small sequence: a lamp that moves.
fn frame(n: usize, size: (usize, usize)) -> Image {
    let (w, h) = size;
    let mut image = Image::filled(w, h, Layout::Rgb, 0.03);
    for plane in &mut image.planes {
        plane[(h / 2) * w + (5 + 3 * n) % w] = 3e4;
        plane[(h / 3) * w + w / 3] = 800.0;
    }
    image.white_luminance = None;
    image
}

/// A fresh folder holding frames shot.0001.exr … and an empty out/.
fn sequence(count: usize, size: (usize, usize)) -> tempfile::TempDir {
    let temp = tempfile::tempdir().unwrap();
    for n in 1..=count {
        let path = temp.path().join(format!("shot.{n:04}.exr"));
        write_linear(&path, &frame(n, size), LinearOptions::default()).unwrap();
    }
    std::fs::create_dir(temp.path().join("out")).unwrap();
    temp
}

fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".aureole"))
        .collect()
}

/// Each of frames `shot.0001.exr` … `count` in `dir` through `camera` on
/// its own gives the bytes the batch wrote to `{batch}.0001.exr` ….
fn assert_single_runs_give(dir: &Path, count: usize, batch: &str, camera: &[&str]) {
    for n in 1..=count {
        let single = dir.join(format!("single{n}.exr"));
        aureole()
            .current_dir(dir)
            .args(["apply", "-q", &format!("shot.{n:04}.exr"), "-o"])
            .arg(&single)
            .args(camera)
            .assert()
            .success();
        assert_eq!(
            std::fs::read(dir.join(format!("{batch}.{n:04}.exr"))).unwrap(),
            std::fs::read(&single).unwrap(),
            "frame {n}"
        );
    }
}

#[test]
fn one_bad_frame_is_reported_and_the_others_are_written_then_resumed() {
    let temp = sequence(4, (40, 30));
    let dir = temp.path();
    let good = std::fs::read(dir.join("shot.0003.exr")).unwrap();
    std::fs::write(dir.join("shot.0003.exr"), &good[..good.len() / 2]).unwrap();
    let args = [
        "apply",
        "shot.%04d.exr",
        "--frames",
        "1-5",
        "-o",
        "out/glow.%04d.exr",
        "--preset",
        "paper-fig4-bloom",
        "--skip-existing",
    ];
    let run = aureole()
        .current_dir(dir)
        .args(args)
        .assert()
        .failure()
        .code(1);
    let stderr = String::from_utf8_lossy(&run.get_output().stderr).into_owned();
    assert!(
        stderr.contains("shot.0003.exr: cannot read OpenEXR"),
        "{stderr}"
    );
    assert!(stderr.contains("shot.0005.exr: no such file"), "{stderr}");
    assert!(stderr.contains("3 of 5 frames written"), "{stderr}");
    for n in [1, 2, 4] {
        assert!(dir.join(format!("out/glow.{n:04}.exr")).is_file());
    }
    assert!(!dir.join("out/glow.0003.exr").exists());
    let first = std::fs::read(dir.join("out/glow.0001.exr")).unwrap();

    // Repair frame 3, drop frame 5 from the list, and resume.
    std::fs::write(dir.join("shot.0003.exr"), &good).unwrap();
    let mut resumed = args;
    resumed[3] = "1-4";
    let run = aureole().current_dir(dir).args(resumed).assert().success();
    let stderr = String::from_utf8_lossy(&run.get_output().stderr).into_owned();
    assert!(
        stderr.contains("1 of 4 frames written, 3 skipped"),
        "{stderr}"
    );
    assert!(dir.join("out/glow.0003.exr").is_file());
    assert_eq!(std::fs::read(dir.join("out/glow.0001.exr")).unwrap(), first);
    assert!(leftovers(&dir.join("out")).is_empty());
}

#[test]
fn skip_existing_leaves_the_output_of_a_single_input_alone() {
    let temp = sequence(1, (24, 16));
    let dir = temp.path();
    std::fs::write(dir.join("out/r.exr"), b"an earlier result").unwrap();
    let run = aureole()
        .current_dir(dir)
        .args([
            "apply",
            "shot.0001.exr",
            "-o",
            "out/r.exr",
            "--skip-existing",
        ])
        .assert()
        .success();
    let stderr = String::from_utf8_lossy(&run.get_output().stderr).into_owned();
    assert!(stderr.contains("skipped (--skip-existing)"), "{stderr}");
    assert_eq!(
        std::fs::read(dir.join("out/r.exr")).unwrap(),
        b"an earlier result"
    );
}

#[test]
fn several_inputs_into_a_folder_give_the_bytes_of_single_runs() {
    let temp = sequence(3, (36, 28));
    let dir = temp.path();
    aureole()
        .current_dir(dir)
        .args([
            "apply",
            "-q",
            "shot.0001.exr",
            "shot.0002.exr",
            "shot.0003.exr",
        ])
        .args(["-o", "out", "--preset", "paper-fig5-both"])
        .assert()
        .success();
    assert_single_runs_give(dir, 3, "out/shot", &["--preset", "paper-fig5-both"]);
    // Several inputs need a folder to write into.
    aureole()
        .current_dir(dir)
        .args(["apply", "shot.0001.exr", "shot.0002.exr", "-o", "both.exr"])
        .assert()
        .failure()
        .code(2)
        .stderr(predicates::str::contains("must be an existing folder"));
}

/// A batch lends each frame the buffers of the frames before it (decoded
/// planes, encode buffers, the file's bytes): frames of other sizes,
/// sample types and layouts must come out as if each ran alone.
#[test]
fn frames_of_other_sizes_and_types_in_one_batch_give_the_bytes_of_single_runs() {
    let temp = tempfile::tempdir().unwrap();
    let dir = temp.path();
    let float = LinearOptions {
        samples: Some(aureole_io::formats::Samples::Float),
        ..LinearOptions::default()
    };
    let half = LinearOptions {
        samples: Some(aureole_io::formats::Samples::Half),
        ..LinearOptions::default()
    };
    let mut grey = frame(3, (30, 20));
    grey.layout = Layout::Luminance;
    grey.planes.truncate(1);
    let frames: [(Image, LinearOptions); 5] = [
        (frame(1, (48, 30)), float),
        (frame(2, (20, 14)), half),
        (grey, float),
        (frame(4, (48, 30)), half),
        (frame(5, (52, 34)), float),
    ];
    for (n, (image, options)) in frames.iter().enumerate() {
        let path = dir.join(format!("shot.{:04}.exr", n + 1));
        write_linear(&path, image, *options).unwrap();
    }
    std::fs::create_dir(dir.join("out")).unwrap();
    let camera = ["--preset", "paper-fig5-both", "--half"];
    aureole()
        .current_dir(dir)
        .args(["apply", "-q", "shot.%04d.exr", "--frames", "1-5"])
        .args(["-o", "out/glow.%04d.exr"])
        .args(camera)
        .assert()
        .success();
    assert_single_runs_give(dir, 5, "out/glow", &camera);
}

#[test]
fn ctrl_c_stops_the_batch_leaving_only_whole_files() {
    let temp = sequence(40, (200, 150));
    let dir = temp.path();
    let child = Process::new(assert_cmd::cargo::cargo_bin("aureole"))
        .current_dir(dir)
        .args([
            "apply",
            "-q",
            "shot.%04d.exr",
            "--frames",
            "1-40",
            "-o",
            "out",
        ])
        .args(["--preset", "paper-fig5-both"])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Interrupt once a few frames are out.
    let out = dir.join("out");
    let started = std::time::Instant::now();
    while std::fs::read_dir(&out).unwrap().count() < 3
        && started.elapsed() < Duration::from_secs(60)
    {
        std::thread::sleep(Duration::from_millis(5));
    }
    Process::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    assert!(leftovers(&out).is_empty(), "{:?}", leftovers(&out));
    let written: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert!(written.len() < 40, "the batch was not interrupted");
    for path in written {
        let loaded = aureole_io::read::read_image(&path, aureole_io::limits::Limits::NONE).unwrap();
        assert_eq!((loaded.image.width, loaded.image.height), (200, 150));
    }
}

#[test]
fn thread_counts_give_the_same_bytes() {
    let temp = sequence(1, (90, 60));
    let dir = temp.path();
    let run = |name: &str, threads: Option<&str>, env: Option<&str>| {
        let mut command = aureole();
        command.current_dir(dir);
        if let Some(n) = env {
            command.env("RAYON_NUM_THREADS", n);
        }
        if let Some(n) = threads {
            command.args(["--threads", n]);
        }
        command
            .args(["apply", "-q", "shot.0001.exr", "-o", name])
            .args(["--preset", "paper-fig5-both", "--method", "fft"])
            .assert()
            .success();
        std::fs::read(dir.join(name)).unwrap()
    };
    let one = run("one.exr", Some("1"), None);
    assert_eq!(run("three.exr", Some("3"), None), one);
    assert_eq!(run("env.exr", None, Some("1")), one);
    assert_eq!(run("all.exr", None, None), one);
}

#[test]
fn a_run_over_the_memory_limit_stops_before_allocating_and_says_how_to_fit() {
    // 64 MB of the limit are the GPU's drivers, which `auto` loads to
    // look for one: what is left holds the run with a smaller kernel.
    let temp = sequence(1, (400, 300));
    let dir = temp.path();
    let run = aureole()
        .current_dir(dir)
        .args([
            "apply",
            "shot.0001.exr",
            "-o",
            "r.exr",
            "--max-memory",
            "90M",
        ])
        .args(["--preset", "paper-fig5-both"])
        .assert()
        .failure()
        .code(1);
    let stderr = String::from_utf8_lossy(&run.get_output().stderr).into_owned();
    assert_eq!(
        stderr.lines().filter(|l| l.contains("error")).count(),
        1,
        "{stderr}"
    );
    for expected in [
        "shot.0001.exr: needs about",
        "MiB",
        "--max-memory is 90.0 MiB",
        "--max-kernel",
    ] {
        assert!(stderr.contains(expected), "{expected:?} not in {stderr}");
    }
    assert!(!dir.join("r.exr").exists());
    // The suggested cap fits.
    let cap = stderr
        .split("--max-kernel ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .unwrap()
        .to_string();
    aureole()
        .current_dir(dir)
        .args([
            "apply",
            "-q",
            "shot.0001.exr",
            "-o",
            "r.exr",
            "--max-memory",
            "90M",
        ])
        .args(["--preset", "paper-fig5-both", "--max-kernel", &cap])
        .assert()
        .success();
}

#[test]
fn temporary_files_a_killed_run_left_are_removed_a_day_later() {
    let temp = sequence(1, (24, 16));
    let out = temp.path().join("out");
    let make = |name: &str, age: u64| {
        let file = std::fs::File::create(out.join(name)).unwrap();
        let then = std::time::SystemTime::now() - Duration::from_secs(age);
        file.set_modified(then).unwrap();
    };
    make(".aureole-AbC123.part", 2 * 86_400);
    make(".aureole-probe-XyZ", 3 * 86_400);
    // A young one may be another run's, still writing; another name is not ours.
    make(".aureole-young.part", 60);
    make("notes.part", 5 * 86_400);
    aureole()
        .args(["apply", "--max-kernel", "9"])
        .arg(temp.path().join("shot.0001.exr"))
        .arg("-o")
        .arg(out.join("r.exr"))
        .assert()
        .success()
        .stderr(predicates::str::contains(
            "removed 2 temporary files older than a day",
        ));
    let mut left = leftovers(&out);
    left.sort();
    assert_eq!(left, [".aureole-young.part"]);
    assert!(out.join("notes.part").exists() && out.join("r.exr").exists());
}
