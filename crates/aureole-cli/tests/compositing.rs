//! Results that drop back into a compositing script: plates that line up,
//! layers and parts chosen and kept, attributes and channel types as they
//! were, every view of a stereo plate through the same camera. Inputs are
//! written with the `exr` crate, as a renderer would, or come from
//! OpenEXR's sample set.

#[path = "../../../tests/support/required.rs"]
mod required;
use std::path::{Path, PathBuf};

use assert_cmd::Command;
use exr::prelude::*;
use predicates::prelude::*;

fn aureole() -> Command {
    Command::cargo_bin("aureole").unwrap()
}

/// A dim plate with one lamp, `w`×`h`, as half samples.
fn plate(w: usize, h: usize, level: f32) -> Vec<f32> {
    let mut v = vec![0.02 * level; w * h];
    v[(h / 2) * w + w / 2] = 5e4;
    v
}

fn half(values: &[f32]) -> FlatSamples {
    FlatSamples::F16(values.iter().map(|&v| f16::from_f32(v)).collect())
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

fn channel<'a>(image: &'a FlatImage, part: usize, name: &str) -> &'a FlatSamples {
    &image.layer_data[part]
        .channel_data
        .list
        .iter()
        .find(|c| c.name.to_string() == name)
        .unwrap_or_else(|| panic!("no channel {name}"))
        .sample_data
}

fn write(path: &Path, layers: Vec<Layer<AnyChannels<FlatSamples>>>, display: (usize, usize)) {
    let mut image = Image::from_layers(
        ImageAttributes::new(IntegerBounds::from_dimensions(display)),
        layers,
    );
    image.attributes.pixel_aspect = 2.0;
    image.write().to_file(path).unwrap();
}

/// One unnamed part of `channels` filling its display window.
fn write_plain(path: &Path, size: (usize, usize), channels: Vec<AnyChannel<FlatSamples>>) {
    write(
        path,
        vec![layer(size, channels, LayerAttributes::default())],
        size,
    );
}

/// Runs `aureole info` on `path` and checks that it succeeds and says
/// every one of `lines`.
fn info_says(path: &Path, lines: &[&str]) {
    let out = aureole().arg("info").arg(path).assert().success();
    let stdout = String::from_utf8_lossy(&out.get_output().stdout).to_string();
    for line in lines {
        assert!(stdout.contains(line), "{line:?} missing from:\n{stdout}");
    }
}

fn layer(
    size: (usize, usize),
    channels: Vec<AnyChannel<FlatSamples>>,
    attributes: LayerAttributes,
) -> Layer<AnyChannels<FlatSamples>> {
    Layer::new(
        size,
        attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into_iter().collect()),
    )
}

#[test]
fn a_plate_with_a_data_window_comes_back_in_its_place_with_every_attribute() {
    let dir = tempfile::tempdir().unwrap();
    let (input, output) = (dir.path().join("plate.exr"), dir.path().join("out.exr"));
    let (w, h) = (400, 300);
    let values = plate(w, h, 1.0);
    let mut attributes = LayerAttributes::named("beauty");
    attributes.layer_position = Vec2(100, 50);
    attributes.owner = Some("Studio".into());
    attributes.capture_date = Some("2026:11:23 01:00:00".into());
    attributes.utc_offset = Some(3600.0);
    attributes.other.insert(
        "shotName".into(),
        exr::meta::attribute::AttributeValue::Text("sh010".into()),
    );
    let channels = ["R", "G", "B"]
        .iter()
        .map(|n| AnyChannel::new(*n, half(&values)))
        .chain([AnyChannel::new("Z", FlatSamples::F32(vec![7.0; w * h]))])
        .collect();
    write(
        &input,
        vec![layer((w, h), channels, attributes)],
        (600, 400),
    );
    let before = std::fs::read(&input).unwrap();

    aureole()
        .args(["apply", "--threshold", "100", "--max-kernel", "65"])
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .assert()
        .success();

    assert_eq!(
        std::fs::read(&input).unwrap(),
        before,
        "the input is untouched"
    );
    let (a, b) = (read_all(&input), read_all(&output));
    assert_eq!(b.attributes.display_window, a.attributes.display_window);
    assert_eq!(b.attributes.pixel_aspect, 2.0);
    let (la, lb) = (&a.layer_data[0], &b.layer_data[0]);
    assert_eq!(
        lb.attributes, la.attributes,
        "data window, owner, date, custom"
    );
    assert_eq!(lb.size, la.size);
    assert_eq!(lb.encoding.compression, la.encoding.compression);
    // The colour keeps its half samples; the depth is as it was.
    assert!(matches!(channel(&b, 0, "R"), FlatSamples::F16(_)));
    assert_eq!(channel(&b, 0, "Z"), channel(&a, 0, "Z"));
    // And the light was spread: the plate next to the lamp got brighter.
    let near = (h / 2) * w + w / 2 + 3;
    let r = |i: &FlatImage| channel(i, 0, "R").value_by_flat_index(near).to_f32();
    assert!(r(&b) > 1.5 * r(&a), "{} → {}", r(&a), r(&b));

    // --float overrides the input's types.
    let float = dir.path().join("float.exr");
    aureole()
        .args([
            "apply",
            "--threshold",
            "100",
            "--max-kernel",
            "65",
            "--float",
            "-q",
        ])
        .arg(&input)
        .arg("-o")
        .arg(&float)
        .assert()
        .success();
    assert!(matches!(
        channel(&read_all(&float), 0, "R"),
        FlatSamples::F32(_)
    ));
}

/// A Blender render: `ViewLayer.Combined`, an AOV and a depth pass in one
/// part.
fn blender(path: &Path) {
    let (w, h) = (64, 48);
    let values = plate(w, h, 1.0);
    let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::new();
    for n in ["R", "G", "B", "A"] {
        channels.push(AnyChannel::new(
            format!("ViewLayer.Combined.{n}").as_str(),
            FlatSamples::F32(values.clone()),
        ));
    }
    for n in ["R", "G", "B"] {
        channels.push(AnyChannel::new(
            format!("ViewLayer.DiffCol.{n}").as_str(),
            FlatSamples::F32(vec![0.5; w * h]),
        ));
    }
    channels.push(AnyChannel::new(
        "ViewLayer.Depth.Z",
        FlatSamples::F32(vec![3.0; w * h]),
    ));
    write_plain(path, (w, h), channels);
}

#[test]
fn a_blender_render_spreads_its_combined_layer_and_keeps_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let (input, output) = (dir.path().join("render.exr"), dir.path().join("out.exr"));
    blender(&input);
    aureole()
        .args(["apply", "--threshold", "100", "--max-kernel", "33"])
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .assert()
        .success()
        .stderr(predicate::str::contains(
            "spreading layer ViewLayer.Combined",
        ));
    let (a, b) = (read_all(&input), read_all(&output));
    let names = |i: &FlatImage| -> Vec<String> {
        i.layer_data[0]
            .channel_data
            .list
            .iter()
            .map(|c| c.name.to_string())
            .collect()
    };
    assert_eq!(names(&a), names(&b));
    for kept in [
        "ViewLayer.DiffCol.R",
        "ViewLayer.Depth.Z",
        "ViewLayer.Combined.A",
    ] {
        assert_eq!(channel(&a, 0, kept), channel(&b, 0, kept), "{kept}");
    }
    assert_ne!(
        channel(&a, 0, "ViewLayer.Combined.R"),
        channel(&b, 0, "ViewLayer.Combined.R")
    );

    // Another layer by name; a layer that is not there lists those that are.
    let other = dir.path().join("diffcol.exr");
    aureole()
        .args([
            "apply",
            "--threshold",
            "0.1",
            "--max-kernel",
            "33",
            "--layer",
            "ViewLayer.DiffCol",
            "-q",
        ])
        .arg(&input)
        .arg("-o")
        .arg(&other)
        .assert()
        .success();
    let c = read_all(&other);
    assert_eq!(
        channel(&c, 0, "ViewLayer.Combined.R"),
        channel(&a, 0, "ViewLayer.Combined.R")
    );
    aureole()
        .args(["apply", "--layer", "diffuse"])
        .arg(&input)
        .arg("-o")
        .arg(dir.path().join("no.exr"))
        .assert()
        .code(1)
        .stderr(
            predicate::str::contains("there is no colour layer \"diffuse\"")
                .and(predicate::str::contains("ViewLayer.Combined (R, G, B, A)"))
                .and(predicate::str::contains("ViewLayer.DiffCol (R, G, B)")),
        );
    assert!(!dir.path().join("no.exr").exists());

    // info lists the layers and their channels.
    info_says(
        &input,
        &[
            "layer ViewLayer.Depth: Z float",
            "spreading ViewLayer.Combined",
        ],
    );
}

#[test]
fn a_file_whose_only_layer_is_prefixed_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let (input, output) = (dir.path().join("diffuse.exr"), dir.path().join("out.exr"));
    let values = plate(32, 24, 1.0);
    let channels = ["diffuse.R", "diffuse.G", "diffuse.B"]
        .iter()
        .map(|n| AnyChannel::new(*n, FlatSamples::F32(values.clone())))
        .collect();
    write_plain(&input, (32, 24), channels);
    aureole()
        .args(["apply", "--threshold", "100", "--max-kernel", "17", "-q"])
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .assert()
        .success();
    let b = read_all(&output);
    assert!(matches!(channel(&b, 0, "diffuse.G"), FlatSamples::F32(_)));
}

#[test]
fn vector_and_data_layers_are_never_light() {
    let dir = tempfile::tempdir().unwrap();
    let (input, output) = (dir.path().join("aovs.exr"), dir.path().join("out.exr"));
    let values = plate(32, 24, 1.0);
    // A normal's Y of 1 everywhere would pass any threshold were it light;
    // a Cryptomatte ID is a float that may read as anything.
    let channels = ["diffuse.R", "diffuse.G", "diffuse.B"]
        .iter()
        .map(|n| AnyChannel::new(*n, FlatSamples::F32(values.clone())))
        .chain(
            ["N.X", "N.Y", "N.Z"]
                .iter()
                .map(|n| AnyChannel::new(*n, FlatSamples::F32(vec![1e6; 32 * 24]))),
        )
        .chain(
            [
                "CryptoObject00.R",
                "CryptoObject00.G",
                "CryptoObject00.B",
                "CryptoObject00.A",
            ]
            .iter()
            .map(|n| AnyChannel::new(*n, FlatSamples::F32(vec![3e5; 32 * 24]))),
        )
        .collect();
    write_plain(&input, (32, 24), channels);
    aureole()
        .args(["apply", "--threshold", "100", "--max-kernel", "17"])
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .assert()
        .success()
        .stderr(predicate::str::contains(
            "spreading layer diffuse (R, G, B)",
        ));
    let (a, b) = (read_all(&input), read_all(&output));
    for kept in ["N.Y", "CryptoObject00.R"] {
        assert_eq!(channel(&a, 0, kept), channel(&b, 0, kept), "{kept}");
    }
    assert_ne!(channel(&a, 0, "diffuse.R"), channel(&b, 0, "diffuse.R"));

    // A vector layer asked for by name is refused, naming its channels.
    aureole()
        .args(["apply", "--layer", "N"])
        .arg(&input)
        .arg("-o")
        .arg(dir.path().join("no.exr"))
        .assert()
        .code(1)
        .stderr(
            predicate::str::contains("layer \"N\" holds vectors (X, Y, Z), not light")
                .and(predicate::str::contains("diffuse (R, G, B)")),
        );
    // A data layer with colour channels is taken only when named.
    aureole()
        .args([
            "apply",
            "-q",
            "--max-kernel",
            "17",
            "--layer",
            "CryptoObject00",
        ])
        .arg(&input)
        .arg("-o")
        .arg(dir.path().join("crypto.exr"))
        .assert()
        .success();

    // Blender's normal pass beside its Combined, as Cycles writes them.
    let blender = dir.path().join("normals.exr");
    let channels = [
        "ViewLayer.Normal.X",
        "ViewLayer.Normal.Y",
        "ViewLayer.Normal.Z",
    ]
    .iter()
    .map(|n| AnyChannel::new(*n, FlatSamples::F32(vec![1.0; 32 * 24])))
    .collect();
    write_plain(&blender, (32, 24), channels);
    aureole()
        .args(["apply", "--layer", "ViewLayer.Normal"])
        .arg(&blender)
        .arg("-o")
        .arg(dir.path().join("no.exr"))
        .assert()
        .code(1)
        .stderr(predicate::str::contains(
            "holds vectors (X, Y, Z), not light",
        ));
    // info describes what apply cannot spread.
    info_says(
        &blender,
        &[
            "apply cannot spread it: no colour layer",
            "layer ViewLayer.Normal (vectors): X float, Y float, Z float",
        ],
    );
    assert!(!dir.path().join("no.exr").exists());

    // Two colour layers and no beauty: apply asks which; info describes both.
    let passes = dir.path().join("passes.exr");
    let channels = [
        "diffuse.R",
        "diffuse.G",
        "diffuse.B",
        "specular.R",
        "specular.G",
        "specular.B",
    ]
    .iter()
    .map(|n| AnyChannel::new(*n, half(&values)))
    .collect();
    write_plain(&passes, (32, 24), channels);
    info_says(
        &passes,
        &[
            "apply cannot spread it: several colour layers",
            "layer diffuse: B half, G half, R half",
            "layer specular: B half, G half, R half",
        ],
    );
}

#[test]
fn a_multi_part_file_keeps_its_other_parts_and_a_part_can_be_chosen() {
    let dir = tempfile::tempdir().unwrap();
    let (input, output) = (dir.path().join("parts.exr"), dir.path().join("out.exr"));
    let values = plate(40, 30, 1.0);
    let rgb = |level: f32| -> Vec<AnyChannel<FlatSamples>> {
        ["R", "G", "B"]
            .iter()
            .map(|n| {
                AnyChannel::new(
                    *n,
                    half(&values.iter().map(|v| v * level).collect::<Vec<_>>()),
                )
            })
            .collect()
    };
    let mut depth = LayerAttributes::named("depth");
    depth.layer_position = Vec2(5, 5);
    write(
        &input,
        vec![
            layer((40, 30), rgb(1.0), LayerAttributes::named("left")),
            layer(
                (20, 10),
                vec![AnyChannel::new("Z", FlatSamples::F32(vec![2.0; 200]))],
                depth,
            ),
            layer((40, 30), rgb(0.5), LayerAttributes::named("right")),
        ],
        (40, 30),
    );
    aureole()
        .args([
            "apply",
            "--threshold",
            "100",
            "--max-kernel",
            "17",
            "--part",
            "right",
        ])
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .assert()
        .success();
    let (a, b) = (read_all(&input), read_all(&output));
    assert_eq!(a.layer_data.len(), 3);
    assert_eq!(b.layer_data.len(), 3);
    assert_eq!(channel(&a, 0, "R"), channel(&b, 0, "R"), "left untouched");
    assert_eq!(channel(&a, 1, "Z"), channel(&b, 1, "Z"), "depth untouched");
    assert_eq!(b.layer_data[1].attributes.layer_position, Vec2(5, 5));
    assert_ne!(channel(&a, 2, "R"), channel(&b, 2, "R"), "right spread");
    aureole()
        .args(["apply", "--part", "7"])
        .arg(&input)
        .arg("-o")
        .arg(dir.path().join("no.exr"))
        .assert()
        .code(1)
        .stderr(predicate::str::contains(
            "the file's parts are 0 (left), 1 (depth), 2 (right)",
        ));
}

#[test]
fn luminance_chroma_is_decoded_to_rgb() {
    let dir = tempfile::tempdir().unwrap();
    let (input, output) = (dir.path().join("yc.exr"), dir.path().join("out.exr"));
    // A saturated red: RY = (R − Y)/Y, BY = (B − Y)/Y, with Y weighted as
    // OpenEXR's RGBA files weight it for Rec.709 (`computeYw`).
    let [wr, wg, wb] = [0.212_639, 0.715_168_7, 0.072_192_29];
    let (r, g, b) = (2.0f32, 0.5f32, 0.25f32);
    let y = wr * r + wg * g + wb * b;
    let n = 16 * 8;
    let channels = vec![
        AnyChannel::new("Y", FlatSamples::F32(vec![y; n])),
        AnyChannel::new("RY", FlatSamples::F32(vec![(r - y) / y; n])),
        AnyChannel::new("BY", FlatSamples::F32(vec![(b - y) / y; n])),
    ];
    write_plain(&input, (16, 8), channels);
    aureole()
        .args(["apply", "--threshold", "100", "--max-kernel", "5"])
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .assert()
        .success()
        .stderr(predicate::str::contains("decoded to RGB"));
    let out = read_all(&output);
    for (name, want) in [("R", r), ("G", g), ("B", b)] {
        let got = channel(&out, 0, name).value_by_flat_index(0).to_f32();
        assert!(
            (got - want).abs() < 1e-5 * want,
            "{name}: {got} against {want}"
        );
    }
    assert!(out.layer_data[0]
        .channel_data
        .list
        .iter()
        .all(|c| c.name.to_string() != "RY"));
}

/// A file of OpenEXR's sample set (stereo and multi-view plates), or
/// `None`, said, where the set is absent.
fn sample(name: &str) -> Option<PathBuf> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/openexr-images")
        .join(name);
    if path.is_file() {
        Some(path)
    } else {
        required::missing("compositing", &format!("{} is absent", path.display()));
        None
    }
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
    aureole()
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
                // steps and B44's (Adjuster.exr is lossy, B44A), less the
                // glare that leaves the frame (0.6 % of Adjuster's).
                let sum = |v: &[f32]| v.iter().map(|&v| f64::from(v)).sum::<f64>();
                let (sa, sb) = (sum(a), sum(b));
                let slack = 5e-3 * sa.abs().max(1.0);
                assert!(
                    sb <= sa + slack && sb >= 0.98 * sa - slack,
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
    // info lists every view's layer, those taken out to spread too.
    info_says(
        &input,
        &[
            "views center, left, right, spreading (unprefixed)",
            "layer left: B half, G half, R half",
            "layer right: B half, G half, R half",
        ],
    );
}

/// Glare layers beside every view's result, each named as OpenEXR's
/// multi-view convention names that view's layers: in the view's own part,
/// or with the view's name before the channel's in one part; and each
/// eye's layers are the ones a run of that eye alone writes.
#[test]
fn every_view_of_a_stereo_plate_gets_its_glare_layers() {
    let dir = tempfile::tempdir().unwrap();
    let layers = ["-q", "--layers", "--preset", "paper-fig5-both"];
    for (name, wanted) in [
        (
            "Beachball/multipart.0001.exr",
            &[
                (0, "glare.bloom.R"),
                (0, "glare.R"),
                (4, "glare.corona.G"),
                (4, "glare.R"),
            ][..],
        ),
        (
            "MultiView/Adjuster.exr",
            &[
                (0, "glare.R"),
                (0, "glare.bloom.B"),
                (0, "glare.left.R"),
                (0, "glare.corona.left.G"),
                (0, "glare.right.R"),
                (0, "glare.bloom.right.B"),
            ][..],
        ),
    ] {
        let Some(input) = sample(name) else { return };
        let output = dir.path().join("layers.exr");
        apply(&input, &output, &layers);
        let written = channels(&read_all(&output));
        for (part, channel) in wanted {
            let found = written.iter().find(|((p, c), _)| p == part && c == channel);
            let Some((_, values)) = found else {
                panic!("{name}: no {channel} in part {part}");
            };
            assert!(
                values.iter().any(|&v| v != 0.0),
                "{name}: {channel} is empty"
            );
        }
    }
    let Some(input) = sample("MultiView/Adjuster.exr") else {
        return;
    };
    let (all, left) = (dir.path().join("all.exr"), dir.path().join("left.exr"));
    apply(&input, &all, &layers);
    apply(&input, &left, &[&layers[..], &["--layer", "left"]].concat());
    let (a, b) = (channels(&read_all(&all)), channels(&read_all(&left)));
    assert_eq!(a, b, "every channel of every view and its glare alike");
}

#[test]
fn info_describes_a_deep_stereo_file_that_apply_refuses() {
    let Some(input) = sample("v2/Stereo/Trunks.exr") else {
        return;
    };
    info_says(
        &input,
        &[
            "apply cannot spread it: part 0 holds deep data",
            "part 1 \"rgba.right\": deep, data window (0, 266)–(1882, 1079), zips, view right",
            "A half, B half, G half, R half, Z float",
        ],
    );
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("out.exr");
    aureole()
        .arg("apply")
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .assert()
        .failure()
        .stderr(predicate::str::contains("deep data"));
}

#[test]
fn glare_layers_go_beside_the_beauty_and_sum_to_the_glare() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("render.exr");
    blender(&input);
    let (plain, layered) = (dir.path().join("plain.exr"), dir.path().join("layered.exr"));
    let camera = ["--preset", "paper-fig5-both", "-q"];
    apply(&input, &plain, &camera);
    apply(&input, &layered, &[&camera[..], &["--layers"]].concat());
    let (a, b, c) = (read_all(&input), read_all(&plain), read_all(&layered));
    let values = |image: &FlatImage, name: &str| -> Vec<f32> {
        channel(image, 0, name).values_as_f32().collect()
    };
    for n in ["R", "G", "B"] {
        let beauty = format!("ViewLayer.Combined.{n}");
        // The beauty is the same with layers or without.
        assert_eq!(channel(&b, 0, &beauty), channel(&c, 0, &beauty));
        let (before, after) = (values(&a, &beauty), values(&c, &beauty));
        let total = values(&c, &format!("ViewLayer.glare.{n}"));
        let bloom = values(&c, &format!("ViewLayer.glare.bloom.{n}"));
        let corona = values(&c, &format!("ViewLayer.glare.corona.{n}"));
        let peak = before.iter().fold(0f32, |m, v| m.max(*v));
        for i in 0..before.len() {
            assert!(
                (after[i] - before[i] - total[i]).abs() <= 1e-6 * peak,
                "{n} {i}"
            );
            assert!(
                (bloom[i] + corona[i] - total[i]).abs() <= 1e-6 * peak,
                "{n} {i}"
            );
        }
    }
    // The other passes as they were.
    assert_eq!(
        channel(&a, 0, "ViewLayer.Depth.Z"),
        channel(&c, 0, "ViewLayer.Depth.Z")
    );
    // Run again on its own output: the layers are replaced, not doubled.
    let again = dir.path().join("again.exr");
    apply(&layered, &again, &[&camera[..], &["--layers"]].concat());
    let names = |i: &FlatImage| i.layer_data[0].channel_data.list.len();
    assert_eq!(names(&read_all(&again)), names(&c));
}

#[test]
fn glare_layers_need_an_exr_and_the_beauty() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("render.exr");
    blender(&input);
    let png = dir.path().join("out.png");
    aureole()
        .args(["apply", "--layers"])
        .arg(&input)
        .arg("-o")
        .arg(&png)
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "glare layers are written only into OpenEXR; write to a .exr file",
        ));
    assert!(!png.exists());
    aureole()
        .args(["apply", "--layers", "--glare-only"])
        .arg(&input)
        .arg("-o")
        .arg(dir.path().join("out.exr"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            aureole_io::job::LAYERS_WITH_GLARE_ONLY,
        ));
}
