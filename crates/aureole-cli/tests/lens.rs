//! `aureole lens`: a prescription read from each format, described, and
//! written as TOML that reads back to the same lens; bad files refused in
//! one line that names the file, with nothing written.

use std::path::Path;

use assert_cmd::Command;

fn aureole() -> Command {
    Command::cargo_bin("aureole").unwrap()
}

/// The first-order data `--json` prints for `file`.
fn json(file: &Path, extra: &[&str]) -> serde_json::Value {
    let out = aureole()
        .arg("lens")
        .arg(file)
        .arg("--json")
        .args(extra)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// pbrt's 50 mm double-Gauss (pbrt-v4-scenes' lenses/dgauss.50mm.dat).
const DGAUSS: &str = "# D-GAUSS F/2 22deg HFOV\n# US patent 2,673,491 Tronnier\n\
    # radius\taxpos\tN\taperture\n29.475\t3.76\t1.67\t25.2\n84.83\t0.12\t1\t25.2\n\
    19.275\t4.025\t1.67\t23\n40.77\t3.275\t1.699\t23\n12.75\t5.705\t1\t18\n0\t4.5\t0\t17.1\n\
    -14.495\t1.18\t1.603\t17\n40.77\t6.065\t1.658\t20\n-20.385\t0.19\t1\t20\n\
    437.065\t3.22\t1.717\t20\n-39.73\t0\t1\t20\n";

#[test]
fn an_import_is_written_as_toml_that_reads_back_to_the_same_lens() {
    let dir = tempfile::tempdir().unwrap();
    let dat = dir.path().join("dgauss.50mm.dat");
    std::fs::write(&dat, DGAUSS).unwrap();
    let toml = dir.path().join("dgauss.toml");
    let out = aureole()
        .args(["lens"])
        .arg(&dat)
        .arg("-o")
        .arg(&toml)
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("focal length 50.358 mm"), "{text}");
    // pbrt gives no Abbe numbers: the user hears so.
    assert!(String::from_utf8_lossy(&out.stderr).contains("no Abbe numbers"));
    let (imported, written) = (json(&dat, &[]), json(&toml, &[]));
    for key in ["focal_length", "back_focus", "entrance_pupil", "f_number"] {
        assert_eq!(imported[key], written[key], "{key}");
    }
    assert_eq!(written["stop"], 6);
}

#[test]
fn an_optical_bench_file_gives_its_patent_and_says_what_it_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let txt = dir.path().join("singlet.txt");
    std::fs::write(
        &txt,
        "[descriptive data]\ntitle\tUS 1,234,567 Example 2 (A singlet)\n\
         [variable distances]\nFocal Length\t100.0\nd1\t2.0\nBf(p)\t97.3\nBf\t97.37\n\
         [lens data]\n1AS\tAS\td1\t\t10.0\n1\t51.7\t4.0\t1.5168\t16.0\t64.17\n\
         2\t-51.7\t3.0\t\t16.0\n2FS\tFS\tBf\t\t18.0\n\
         [aspherical data]\n1\t51.7\t0\t1e-6\n",
    )
    .unwrap();
    let out = aureole().arg("lens").arg(&txt).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("surface 2 is aspheric"), "{stderr}");
    let value = json(&txt, &[]);
    assert_eq!(value["patent"]["number"], "US 1,234,567");
    assert_eq!(value["patent"]["example"], "Example 2");
    // The patent's own back focus, Bf(p), is what it states.
    assert_eq!(value["patent"]["back_focus"], 97.3);
    assert_eq!(value["surfaces"], 4);
}

#[test]
fn a_lentil_database_asks_which_lens() {
    let dir = tempfile::tempdir().unwrap();
    let json_file = dir.path().join("lenses.json");
    let element = |r: f64, t: f64, ior: f64, material: &str| {
        format!(
            r#"{{"radius": {r}, "thickness": {t}, "ior": {ior}, "abbe": 60, "housing-radius": 5, "material": "{material}", "lens-geometry": "spherical"}}"#
        )
    };
    let lens = format!(
        r#"{{"product-name": "singlet", "optical-elements-patent": [{}, {}, {}]}}"#,
        element(99999.0, 2.0, 1.0, "iris"),
        element(51.7, 4.0, 1.5168, "abbe"),
        element(-51.7, 97.0, 1.0, "air")
    );
    std::fs::write(&json_file, format!(r#"{{"1": {lens}, "2": {lens}}}"#)).unwrap();
    let out = aureole().arg("lens").arg(&json_file).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("--id") && stderr.contains("1 (singlet), 2 (singlet)"),
        "{stderr}"
    );
    let value = json(&json_file, &["--id", "2"]);
    assert!(
        (value["focal_length"].as_f64().unwrap() - 50.7).abs() < 1.0,
        "{value}"
    );
}

#[test]
fn a_bad_lens_is_refused_in_one_line_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(
        &bad,
        "name = \"x\"\n[[surface]]\nstop = true\nsemi_aperture = 5\nthickness = 1\n\
         [[surface]]\nradius = 10\nthickness = 2\nn_d = 1.5\nsemi_aperture = 12\n\
         [[surface]]\nradius = -10\nsemi_aperture = 5\n",
    )
    .unwrap();
    let out_file = dir.path().join("out.toml");
    let out = aureole()
        .arg("lens")
        .arg(&bad)
        .arg("-o")
        .arg(&out_file)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("bad.toml:6:1: surface 2: semi_aperture = 12 exceeds |radius| = 10"),
        "{stderr}"
    );
    assert!(!out_file.exists());
    // An output that is not TOML, and --id on a file of one lens.
    let good = dir.path().join("dgauss.dat");
    std::fs::write(&good, DGAUSS).unwrap();
    for (args, says) in [
        (vec!["-o", "x.exr"], "name the output .toml"),
        (vec!["--id", "3"], "--id picks a lens of a lentil database"),
    ] {
        let out = aureole()
            .arg("lens")
            .arg(&good)
            .args(&args)
            .current_dir(dir.path())
            .output()
            .unwrap();
        assert!(!out.status.success());
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(says),
            "{args:?}"
        );
    }
}

#[test]
fn a_lens_renders_the_ghosts_of_a_source_the_same_on_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let lens = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../aureole/lenses/double-gauss-50mm-f1.4.toml"
    );
    let render = |threads: &str, out: &str| {
        let out = dir.path().join(out);
        let done = aureole()
            .args(["--threads", threads, "lens", lens, "--ghosts"])
            .arg(&out)
            .args([
                "--source",
                "8,5",
                "--f-number",
                "4",
                "--blades",
                "7",
                "--size",
                "180x120",
            ])
            .output()
            .unwrap();
        assert!(
            done.status.success(),
            "{}",
            String::from_utf8_lossy(&done.stderr)
        );
        (
            std::fs::read(&out).unwrap(),
            String::from_utf8(done.stderr).unwrap(),
        )
    };
    let (one, said) = render("1", "one.exr");
    let (two, _) = render("2", "two.exr");
    assert_eq!(one, two);
    assert!(
        said.contains("78 ghosts of a source at (8°, 5°), f/4.00"),
        "{said}"
    );
    assert!(said.contains("  surfaces 2 and 5: "), "{said}");
    // The ghosts hold a thousandth of the light or so, and at most the
    // light of the image they come from.
    let limits = aureole_io::limits::Limits::NONE;
    let image = aureole_io::read::read_image(&dir.path().join("one.exr"), limits)
        .unwrap()
        .image;
    let light: f64 = image
        .planes
        .iter()
        .flatten()
        .map(|&v| f64::from(v))
        .sum::<f64>()
        / 3.0;
    assert!(light > 1e-4 && light < 1e-2, "{light}");
}

#[test]
fn a_shipped_lens_is_named_and_drawn_in_section() {
    let dir = tempfile::tempdir().unwrap();
    let picture = dir.path().join("lens.svg");
    let done = aureole()
        .current_dir(dir.path())
        .args(["lens", "telephoto-300mm-f2.8", "--svg"])
        .arg(&picture)
        .assert()
        .success();
    let said = String::from_utf8_lossy(&done.get_output().stdout).to_string();
    assert!(said.contains("US 6,288,845"), "{said}");
    let drawing = std::fs::read_to_string(&picture).unwrap();
    assert!(drawing.starts_with("<svg") && drawing.contains("<polygon"));
    // A name that is neither a file nor a shipped lens is a missing file.
    let missing = aureole()
        .current_dir(dir.path())
        .args(["lens", "telephoto-300mm"])
        .assert()
        .failure();
    let said = String::from_utf8_lossy(&missing.get_output().stderr).to_string();
    assert!(
        said.contains("telephoto-300mm") && said.lines().count() == 1,
        "{said}"
    );
}
