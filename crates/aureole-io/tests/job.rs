//! The one job's checks (`aureole_io::job::Request::check`): every refusal
//! the command line, the studio's export and Python share, once each, with
//! its words and nothing left behind.

use std::path::{Path, PathBuf};

use aureole::ApplyOptions;
use aureole_io::job::{Request, LAYERS_WITH_GLARE_ONLY};
use aureole_io::Error;

/// A folder with an input file in it.
fn folder() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.exr");
    std::fs::write(&input, b"not read by the checks").unwrap();
    (dir, input)
}

fn check(output: &Path, input: &Path, options: ApplyOptions, layers: bool) -> Result<(), Error> {
    Request {
        output,
        input: Some(input),
        options: &options,
        layers,
    }
    .check()
}

/// Only the input is left in the folder: no probe, no output.
fn untouched(dir: &Path) {
    let names: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["in.exr"]);
}

fn refused(result: Result<(), Error>) -> String {
    let error = result.expect_err("refused");
    let line = error.to_string();
    assert!(!line.contains('\n'), "{line}");
    line
}

#[test]
fn a_plain_request_passes() {
    let (dir, input) = folder();
    let output = dir.path().join("out.exr");
    check(&output, &input, ApplyOptions::default(), false).unwrap();
    check(&output, &input, ApplyOptions::default(), true).unwrap();
    let glare = ApplyOptions {
        glare_only: true,
        ..ApplyOptions::default()
    };
    check(&output, &input, glare, false).unwrap();
    // A picture of the glare is exposed like any picture.
    check(&dir.path().join("g.png"), &input, glare, false).unwrap();
    untouched(dir.path());
}

#[test]
fn a_threshold_outside_its_range_is_refused_in_the_librarys_words() {
    let (dir, input) = folder();
    for threshold in [-1.0, f64::NAN, f64::INFINITY] {
        let options = ApplyOptions {
            threshold: Some(threshold),
            ..ApplyOptions::default()
        };
        let result = check(&dir.path().join("out.exr"), &input, options, false);
        assert!(matches!(result, Err(Error::Options(_))), "{result:?}");
        let line = refused(result);
        assert!(line.starts_with("apply: threshold = "), "{line}");
        assert!(
            line.contains("a finite luminance of at least 0 cd/m²"),
            "{line}"
        );
    }
    untouched(dir.path());
}

#[test]
fn a_knee_outside_its_range_is_refused() {
    let (dir, input) = folder();
    for knee in [-0.5, f64::NAN] {
        let options = ApplyOptions {
            knee,
            ..ApplyOptions::default()
        };
        let line = refused(check(&dir.path().join("out.exr"), &input, options, false));
        assert!(line.starts_with("apply: knee = "), "{line}");
        assert!(line.contains("a finite number of at least 0"), "{line}");
    }
    untouched(dir.path());
}

#[test]
fn a_glare_only_result_is_refused_by_a_format_without_negatives() {
    let (dir, input) = folder();
    let output = dir.path().join("g.hdr");
    let options = ApplyOptions {
        glare_only: true,
        ..ApplyOptions::default()
    };
    let result = check(&output, &input, options, false);
    assert!(matches!(result, Err(Error::Refused { .. })), "{result:?}");
    let line = refused(result);
    assert!(
        line.starts_with(&format!(
            "{}: Radiance HDR holds no negative values",
            output.display()
        )),
        "{line}"
    );
    assert!(line.ends_with("write .exr or .pfm"), "{line}");
    // The same camera result without glare-only is fine there.
    check(&output, &input, ApplyOptions::default(), false).unwrap();
    untouched(dir.path());
}

#[test]
fn glare_layers_with_a_glare_only_result_are_refused() {
    let (dir, input) = folder();
    let options = ApplyOptions {
        glare_only: true,
        ..ApplyOptions::default()
    };
    let line = refused(check(&dir.path().join("out.exr"), &input, options, true));
    assert!(line.ends_with(LAYERS_WITH_GLARE_ONLY), "{line}");
    untouched(dir.path());
}

#[test]
fn glare_layers_are_refused_by_a_format_without_layers() {
    let (dir, input) = folder();
    for name in ["out.png", "out.hdr", "out.pfm"] {
        let line = refused(check(
            &dir.path().join(name),
            &input,
            ApplyOptions::default(),
            true,
        ));
        assert!(
            line.ends_with("glare layers are written only into OpenEXR; write to a .exr file"),
            "{line}"
        );
    }
    untouched(dir.path());
}

#[test]
fn an_output_we_do_not_write_or_cannot_write_is_refused() {
    let (dir, input) = folder();
    let line = refused(check(
        &dir.path().join("out.gif"),
        &input,
        ApplyOptions::default(),
        false,
    ));
    assert!(line.contains("unknown output extension \"gif\""), "{line}");
    let line = refused(check(&input, &input, ApplyOptions::default(), false));
    assert!(
        line.ends_with("the output would overwrite the input; write to another file"),
        "{line}"
    );
    let missing = dir.path().join("missing").join("out.exr");
    let line = refused(check(&missing, &input, ApplyOptions::default(), false));
    assert!(line.contains("does not exist; create it first"), "{line}");
    std::fs::create_dir(dir.path().join("folder.exr")).unwrap();
    let line = refused(check(
        &dir.path().join("folder.exr"),
        &input,
        ApplyOptions::default(),
        false,
    ));
    assert!(line.contains("is not a plain file"), "{line}");
    std::fs::remove_dir(dir.path().join("folder.exr")).unwrap();
    untouched(dir.path());
}

#[test]
fn the_checks_without_a_file_system_refuse_what_a_command_line_would() {
    // What the studio's `/api/command` asks before it offers a command: no
    // folder needs to exist.
    let nowhere = Path::new("/nonexistent/folder/g.hdr");
    let options = ApplyOptions {
        glare_only: true,
        ..ApplyOptions::default()
    };
    let request = |options: &ApplyOptions, layers| {
        Request {
            output: nowhere,
            input: None,
            options,
            layers,
        }
        .check_asked()
    };
    assert!(refused(request(&options, false)).contains("holds no negative values"));
    let exr = Request {
        output: Path::new("/nonexistent/folder/g.exr"),
        input: None,
        options: &options,
        layers: false,
    };
    exr.check_asked().unwrap();
    assert!(exr.check().is_err(), "the folder is missing");
    // A name with a NUL (the studio's and Python's strings can hold one) is
    // refused before any work, not by the write after the render.
    let line = refused(
        Request {
            output: Path::new("g\0.exr"),
            input: None,
            options: &ApplyOptions::default(),
            layers: false,
        }
        .check_asked(),
    );
    assert!(line.contains("holds a NUL character"), "{line}");
}

/// A job of a small night street written as EXR, to `out` in `dir`.
fn street_job(dir: &Path, out: &str, layers: bool) -> aureole_io::job::Job {
    let input = dir.join("street.exr");
    let image = aureole_io::demo::night_street(96, 54);
    aureole_io::write::write_linear(&input, &image, Default::default()).unwrap();
    aureole_io::job::Job {
        input: Some(input),
        output: dir.join(out),
        choice: Default::default(),
        frame: Default::default(),
        options: ApplyOptions::default(),
        layers,
        write: aureole_io::write::WriteOptions {
            linear: Default::default(),
            display: aureole_io::display::DisplayOptions {
                exposure: aureole_io::display::Exposure::Auto,
                tone: aureole_io::display::ToneCurve::Filmic,
            },
            depth: None,
        },
    }
}

fn session() -> aureole::Session {
    let mut config = aureole::Config::default();
    config.merge(
        aureole::presets::find("paper-fig5-both")
            .unwrap()
            .config()
            .unwrap(),
    );
    aureole::Session::new(config)
}

/// `Job::run` is its phases: the header's shape comes before the pixels,
/// and the file it writes is the one the phases write, notes and all.
#[test]
fn a_job_runs_its_phases_and_says_its_notes() {
    let dir = tempfile::tempdir().unwrap();
    let limits = aureole_io::limits::Limits::NONE;
    let whole = street_job(dir.path(), "whole.exr", true);
    let done = whole.run(&mut session(), limits, &mut |_, _| {}).unwrap();
    assert!(done.applied.energy_out <= done.applied.energy_in);
    let phased = aureole_io::job::Job {
        output: dir.path().join("phased.exr"),
        ..whole.clone()
    };
    phased.check().unwrap();
    let mut seen = None;
    let (mut input, ()) = phased
        .read(&session(), limits, |shape| {
            seen = shape;
            Ok::<(), Error>(())
        })
        .unwrap();
    assert_eq!(seen.map(|s| (s.width, s.height)), Some((96, 54)));
    let applied = phased
        .apply(&mut input, &mut session(), &mut |_, _| {})
        .unwrap();
    let again = phased.write(input, applied).unwrap();
    assert_eq!(again.notes, done.notes);
    assert_eq!(
        std::fs::read(dir.path().join("whole.exr")).unwrap(),
        std::fs::read(dir.path().join("phased.exr")).unwrap()
    );
    // What a job's check refuses, its run refuses before reading.
    let refused_job = aureole_io::job::Job {
        output: dir.path().join("glare.png"),
        ..street_job(dir.path(), "unused.exr", true)
    };
    let line = refused_job
        .run(&mut session(), limits, &mut |_, _| {})
        .unwrap_err()
        .to_string();
    assert!(
        line.contains("glare layers are written only into"),
        "{line}"
    );
    assert!(!dir.path().join("glare.png").exists());
}
