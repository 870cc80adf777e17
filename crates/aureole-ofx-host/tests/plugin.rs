//! The aureole OpenFX plugin, built as a bundle and rendered by the
//! in-repository host as Resolve, Nuke or Natron would: its frames are the
//! command line's bytes, a proxy render has the same look, two threads
//! render as one, an abort stops a render, and every mistake a host or a
//! user can make is a status and a message, never a crash.

mod support;

use std::ffi::CStr;
use std::time::{Duration, Instant};

use aureole_ofx_abi::{self as abi, names};
use aureole_ofx_host::{images_held, Picture, Plugin, PropSet, Setting, Value};
use support::{cli_apply, first_difference, instance, loaded, night, option, serial};

/// The refusal a render should have met.
fn refused(
    outcome: Result<Picture, aureole_ofx_host::Refusal>,
    case: &str,
) -> aureole_ofx_host::Refusal {
    match outcome {
        Ok(_) => panic!("{case}: the render went through"),
        Err(refusal) => refusal,
    }
}

#[test]
fn the_plugin_describes_itself_as_a_host_expects() {
    let _serial = serial();
    let plugin = Plugin::load(&support::bundle()).expect("the bundle loads");
    assert_eq!(plugin.identifier(), ("org.aureole.glare".to_string(), 1, 0));
    let described = plugin.describe().expect("describe");
    assert_eq!(described.strings(names::PROP_LABEL), ["aureole glare"]);
    assert_eq!(
        described.strings(names::EFFECT_SUPPORTED_CONTEXTS),
        [names::CONTEXT_FILTER, names::CONTEXT_GENERAL].map(|c| c.to_string_lossy().into_owned())
    );
    assert_eq!(
        described.strings(names::EFFECT_SUPPORTED_PIXEL_DEPTHS),
        ["OfxBitDepthFloat"]
    );
    assert_eq!(described.ints(names::EFFECT_SUPPORTS_TILES), [0]);
    for context in [names::CONTEXT_FILTER, names::CONTEXT_GENERAL] {
        let (clips, params) = plugin
            .describe_in_context(context)
            .expect("describe in context");
        assert_eq!(clips, ["Source", "Output"]);
        for name in [
            "preset",
            "config",
            "f_number",
            "aperture",
            "aperture_blades",
            "threshold",
            "knee",
            "input_scale",
            "output",
            "layer",
        ] {
            assert!(params.iter().any(|p| p == name), "{name} in {params:?}");
        }
    }
    // The camera's controls come from the library's schema.
    let f = plugin
        .param_definition(names::CONTEXT_FILTER, "f_number")
        .expect("f_number");
    let about = aureole::schema::CAMERA
        .iter()
        .find(|p| p.name == "f_number")
        .expect("schema")
        .about;
    assert!(f.strings(names::PARAM_HINT)[0].starts_with(about));
    assert_eq!(f.doubles(names::PARAM_MIN), [0.5]);
    // So do every effect's, as the studio's panels do (a measured PSF's
    // file is the config's to name).
    for (kind, parameters) in aureole::config::effect_kinds() {
        if kind == "image" {
            continue;
        }
        for p in parameters {
            let name = format!("{kind}_{}", p.name);
            let control = plugin
                .param_definition(names::CONTEXT_FILTER, &name)
                .unwrap_or_else(|| panic!("no control {name}"));
            assert!(
                control.strings(names::PARAM_HINT)[0].starts_with(p.about),
                "{name}"
            );
            assert_eq!(
                control.strings(names::PARAM_PARENT),
                [format!("{kind}_group")],
                "{name}"
            );
        }
    }
    let presets = plugin
        .param_definition(names::CONTEXT_FILTER, "preset")
        .expect("preset");
    assert_eq!(
        presets.strings(names::PARAM_CHOICE_OPTION).len(),
        aureole::presets::PRESETS.len() + 1
    );
}

#[test]
fn a_sequence_rendered_in_a_hosts_order_is_the_command_lines_bytes() {
    let _serial = serial();
    let test = "a_sequence_rendered_in_a_hosts_order_is_the_command_lines_bytes";
    let (w, h) = (384, 216);
    for (preset, channels) in [("camera-f8-7blade", 4), ("paper-fig5-both", 3)] {
        let mut source = night(w, h, 1);
        if channels == 3 {
            source = Picture::of_image(&source.to_image(), 3);
        }
        let Some(expected) = cli_apply(test, &source, &["--preset", preset, "--device", "cpu"])
        else {
            return;
        };
        let plugin = loaded(names::CONTEXT_FILTER);
        let effect = instance(&plugin, (w, h), preset);
        effect.begin_sequence(1.0, 2.0, [1.0, 1.0]).expect("begin");
        // Rows handed out top first with a negative stride, then bottom
        // first with a positive one, as Resolve and Nuke lay them.
        for (time, bottom_up) in [(1.0, false), (2.0, true)] {
            effect.set_rows_bottom_up(bottom_up);
            let rendered = effect.render(time, &source, [1.0, 1.0]).expect("render");
            assert_eq!(
                first_difference(&rendered, &expected),
                None,
                "{preset}, frame {time}"
            );
        }
        effect.end_sequence(1.0, 2.0, [1.0, 1.0]).expect("end");
        assert!(effect.messages().is_empty());
        drop(effect);
        assert_eq!(
            images_held(),
            0,
            "every image the plugin fetched was released"
        );
    }
}

#[test]
fn the_effect_controls_set_the_chain_as_a_config_would() {
    let _serial = serial();
    let test = "the_effect_controls_set_the_chain_as_a_config_would";
    let (w, h) = (256, 144);
    let source = night(w, h, 1);
    // The preset's 7-blade stop turned to 5 blades by its controls, and a
    // bloom it does not have joining the chain after it.
    let config = tempfile::tempdir().expect("a folder");
    let file = config.path().join("same.toml");
    std::fs::write(
        &file,
        "[camera]\nsensor_width_mm = 36.0\nfocal_length_mm = 50.0\nf_number = 8.0\n\
         [[effect]]\ntype = \"aperture\"\nblades = 5\n\
         [[effect]]\ntype = \"bloom\"\nepsilon = 0.01\nbeta = 2.5\nradius = \"6px\"\n",
    )
    .expect("written");
    let file = file.display().to_string();
    let Some(expected) = cli_apply(test, &source, &["--config", &file, "--device", "cpu"]) else {
        return;
    };
    let plugin = loaded(names::CONTEXT_FILTER);
    let effect = instance(&plugin, (w, h), "camera-f8-7blade");
    for (name, value) in [
        ("aperture", Setting::Int(1)),
        ("aperture_blades", Setting::Int(5)),
        ("bloom", Setting::Int(1)),
        ("bloom_epsilon", Setting::Double(0.01)),
        ("bloom_beta", Setting::Double(2.5)),
        ("bloom_radius", Setting::Text("6px".into())),
    ] {
        effect.set(name, value).expect("set");
    }
    let rendered = effect.render(1.0, &source, [1.0, 1.0]).expect("render");
    assert_eq!(first_difference(&rendered, &expected), None);
}

#[test]
fn glare_only_and_a_layer_are_the_command_lines() {
    let _serial = serial();
    let test = "glare_only_and_a_layer_are_the_command_lines";
    let (w, h) = (256, 144);
    let source = night(w, h, 1);
    let Some(glare) = cli_apply(
        test,
        &source,
        &[
            "--preset",
            "paper-fig5-both",
            "--device",
            "cpu",
            "--glare-only",
        ],
    ) else {
        return;
    };
    let plugin = loaded(names::CONTEXT_GENERAL);
    let effect = plugin
        .instance(names::CONTEXT_GENERAL, aureole_ofx_host::Project::of(w, h))
        .expect("an instance");
    effect
        .set("device", Setting::Int(option(&plugin, "device", "cpu")))
        .expect("device");
    effect.set("output", Setting::Int(1)).expect("glare only");
    let rendered = effect.render(1.0, &source, [1.0, 1.0]).expect("render");
    assert_eq!(first_difference(&rendered, &glare), None);
    // The total layer is the glare alone, the sum of the bloom's and the
    // corona's.
    effect.set("output", Setting::Int(2)).expect("one layer");
    effect
        .set("layer", Setting::Text("glare".into()))
        .expect("layer");
    let total = effect.render(2.0, &source, [1.0, 1.0]).expect("render");
    assert_eq!(first_difference(&total, &glare), None);
    let mut parts = Vec::new();
    for (time, layer) in [(3.0, "glare.bloom"), (3.5, "glare.corona")] {
        effect
            .set("layer", Setting::Text(layer.into()))
            .expect("layer");
        parts.push(effect.render(time, &source, [1.0, 1.0]).expect("render"));
    }
    let peak = total.pixels.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    for (i, t) in total.pixels.iter().enumerate().filter(|(i, _)| i % 4 != 3) {
        let (bloom, corona) = (parts[0].pixels[i], parts[1].pixels[i]);
        assert!(bloom != 0.0 || corona != 0.0 || *t == 0.0);
        assert!(
            (bloom + corona - t).abs() <= 1e-5 * peak,
            "sample {i}: {bloom} + {corona} against {t}"
        );
    }
    effect
        .set("layer", Setting::Text("glare.halo".into()))
        .expect("layer");
    let refusal = refused(effect.render(4.0, &source, [1.0, 1.0]), "glare.halo");
    assert_eq!(refusal.messages.len(), 1, "{refusal}");
    assert!(
        refusal.messages[0].1.contains("glare.bloom, glare.corona"),
        "{refusal}"
    );
}

/// Light around each lamp of `night` in rings [2, 8), [8, 32), [32, 96)
/// pixels of the half-size frame.
fn rings(picture: &Picture) -> Vec<[f64; 3]> {
    rings_squeezed(picture, 1.0)
}

/// [`rings`] on a frame whose pixels are `squeeze` times as wide as high:
/// the rings are round on the sensor.
fn rings_squeezed(picture: &Picture, squeeze: f64) -> Vec<[f64; 3]> {
    let (w, h) = (picture.width, picture.height);
    [(w / 5, h / 3), (w / 2, h / 4), (4 * w / 5, h / 2)]
        .iter()
        .map(|&(lx, ly)| {
            let mut sums = [0.0; 3];
            for y in 0..h {
                for x in 0..w {
                    let dx = (x as f64 - lx as f64) * squeeze;
                    let r = (dx.powi(2) + (y as f64 - ly as f64).powi(2)).sqrt();
                    let ring = [2.0, 8.0, 32.0, 96.0]
                        .windows(2)
                        .position(|b| (b[0]..b[1]).contains(&r));
                    if let Some(ring) = ring {
                        sums[ring] += f64::from(picture.pixels[(y * w + x) * picture.channels + 1]);
                    }
                }
            }
            sums
        })
        .collect()
}

/// `picture` reduced by area, each new pixel the mean of `fx` × `fy` old
/// ones: by 2 × 2 the half-size frame, by 2 × 1 an anamorphic lens's
/// squeezed plate.
fn reduced(picture: &Picture, (fx, fy): (usize, usize)) -> Picture {
    let (w, h, n) = (picture.width / fx, picture.height / fy, picture.channels);
    let mut pixels = vec![0.0f32; w * h * n];
    for y in 0..h {
        for x in 0..w {
            for c in 0..n {
                let mut sum = 0.0;
                for dy in 0..fy {
                    for dx in 0..fx {
                        sum +=
                            picture.pixels[((fy * y + dy) * picture.width + fx * x + dx) * n + c];
                    }
                }
                pixels[(y * w + x) * n + c] = sum / (fx * fy) as f32;
            }
        }
    }
    Picture {
        width: w,
        height: h,
        channels: n,
        pixels,
    }
}

/// Holds each lamp's `rings` of `b` to `a`'s within 1 %; the worst is
/// printed (`--nocapture`).
fn within_a_percent(a: &[[f64; 3]], b: &[[f64; 3]], rings: std::ops::Range<usize>) {
    let mut worst = 0.0f64;
    for (a, b) in a.iter().zip(b) {
        for ring in rings.clone() {
            let off = (a[ring] - b[ring]).abs() / a[ring];
            worst = worst.max(off);
            assert!(
                off < 0.01,
                "ring {ring}: {:.3} % ({} against {})",
                100.0 * off,
                a[ring],
                b[ring]
            );
        }
    }
    eprintln!("rings within {:.3} %", 100.0 * worst);
}

#[test]
fn a_proxy_render_at_half_scale_has_the_full_frames_look() {
    let _serial = serial();
    let test = "a_proxy_render_at_half_scale_has_the_full_frames_look";
    let (w, h) = (512, 288);
    let (full, half) = (night(w, h, 2), night(w / 2, h / 2, 1));
    let plugin = loaded(names::CONTEXT_FILTER);
    // A camera in lengths on the sensor: the proxy is the command line's
    // render of the half-size frame, to the bit.
    let effect = instance(&plugin, (w, h), "camera-f8-7blade");
    let proxy = effect
        .render(1.0, &half, [0.5, 0.5])
        .expect("render at half scale");
    let Some(expected) = cli_apply(
        test,
        &half,
        &["--preset", "camera-f8-7blade", "--device", "cpu"],
    ) else {
        return;
    };
    assert_eq!(first_difference(&proxy, &expected), None);
    // A camera in pixels (paper-fig5-both: bloom R = 10.4 px): its lengths
    // are pixels of the full frame, so the proxy is the full render reduced,
    // ring by ring within the resolution test's 1 %.
    effect
        .set(
            "preset",
            Setting::Int(option(&plugin, "preset", "paper-fig5-both")),
        )
        .expect("preset");
    effect.set("output", Setting::Int(1)).expect("glare only");
    let large = reduced(
        &effect.render(2.0, &full, [1.0, 1.0]).expect("render"),
        (2, 2),
    );
    let small = effect
        .render(3.0, &half, [0.5, 0.5])
        .expect("render at half scale");
    within_a_percent(&rings(&large), &rings(&small), 0..3);
}

#[test]
fn a_squeezed_plate_gets_round_glare_on_its_own_pixels() {
    let _serial = serial();
    let (w, h) = (320, 360);
    let wide = night(2 * w, h, 1);
    let plate = reduced(&wide, (2, 1));
    let plugin = loaded(names::CONTEXT_FILTER);
    let effect = instance(&plugin, (2 * w, h), "camera-f8-7blade");
    effect.set("output", Setting::Int(1)).expect("glare only");
    let expected = reduced(
        &effect.render(1.0, &wide, [1.0, 1.0]).expect("render"),
        (2, 1),
    );
    drop(effect);
    let project = aureole_ofx_host::Project {
        pixel_aspect: 2.0,
        ..aureole_ofx_host::Project::of(2 * w, h)
    };
    let effect = support::instance_in(&plugin, project, "camera-f8-7blade");
    effect.set("output", Setting::Int(1)).expect("glare only");
    let glare = effect
        .render(1.0, &plate, [1.0, 1.0])
        .expect("render with pixels twice as wide");
    // Beyond 8 px: within that the desqueezed lamp is two pixels of half
    // its light, not one.
    let (a, b) = (rings_squeezed(&expected, 2.0), rings_squeezed(&glare, 2.0));
    within_a_percent(&a, &b, 1..3);
    // The image itself passes through untouched under its glare.
    effect.set("output", Setting::Int(0)).expect("image");
    let whole = effect.render(2.0, &plate, [1.0, 1.0]).expect("render");
    for (i, ((v, p), g)) in whole
        .pixels
        .iter()
        .zip(&plate.pixels)
        .zip(&glare.pixels)
        .enumerate()
    {
        let expected = if i % 4 == 3 { *p } else { p + g };
        assert_eq!(v.to_bits(), expected.to_bits(), "sample {i}");
    }
}

#[test]
fn the_projects_frame_inside_an_overscan_is_the_optical_axis() {
    let _serial = serial();
    // A source with 32 px of overscan left and 16 below the project's
    // frame: the ghosts line up on the frame's centre, as `aureole apply`
    // lines them up on an EXR's display window.
    let (w, h) = (320, 192);
    let source = night(w, h, 1);
    let project = aureole_ofx_host::Project {
        x: 32.0,
        y: 16.0,
        width: 256.0,
        height: 160.0,
        pixel_aspect: 1.0,
    };
    let plugin = loaded(names::CONTEXT_FILTER);
    let effect = support::instance_in(&plugin, project, "camera-f8-7blade-ghosts");
    effect.set("output", Setting::Int(1)).expect("glare only");
    let rendered = effect.render(1.0, &source, [1.0, 1.0]).expect("render");

    let preset = aureole::presets::find("camera-f8-7blade-ghosts")
        .and_then(|p| p.config())
        .expect("preset");
    let mut session = aureole::Session::new(aureole::Config::compose([preset]));
    // Rows top first: the frame's top is 16 + 160 = 176 px up, 16 rows down.
    let window = aureole::DisplayWindow {
        x: 32,
        y: 16,
        width: 256,
        height: 160,
    };
    let frame = aureole::Frame::new(
        source.to_image(),
        &aureole::FrameOptions {
            input_scale: Some(1.0),
            sanitize: false,
        },
    )
    .expect("a frame")
    .with_display_window(window);
    let options = aureole::ApplyOptions {
        glare_only: true,
        ..Default::default()
    };
    let expected = session
        .apply(&frame, &options, &mut |_, _| {})
        .expect("applied");
    assert!(expected.ghosts.is_some_and(|g| g.traced > 0));
    assert_eq!(
        first_difference(&rendered, &Picture::of_image(&expected.image, 4)),
        None
    );
}

#[test]
fn two_threads_rendering_two_frames_at_once_give_the_bytes_of_one_at_a_time() {
    let _serial = serial();
    let (w, h) = (320, 180);
    let frames = [night(w, h, 1), {
        let mut other = night(w, h, 1);
        other.pixels.reverse();
        for px in other.pixels.chunks_mut(4) {
            px.rotate_left(1);
        }
        other
    }];
    let plugin = loaded(names::CONTEXT_FILTER);
    let effect = instance(&plugin, (w, h), "paper-fig5-both");
    let alone: Vec<Picture> = frames
        .iter()
        .enumerate()
        .map(|(i, f)| effect.render(i as f64, f, [1.0, 1.0]).expect("render"))
        .collect();
    for round in 0..3 {
        let together: Vec<Picture> = std::thread::scope(|scope| {
            let running: Vec<_> = frames
                .iter()
                .enumerate()
                .map(|(i, f)| {
                    let effect = &effect;
                    scope.spawn(move || {
                        effect
                            .render((10 * round + i) as f64, f, [1.0, 1.0])
                            .expect("render")
                    })
                })
                .collect();
            running
                .into_iter()
                .map(|t| t.join().expect("the thread"))
                .collect()
        });
        for (a, b) in alone.iter().zip(&together) {
            assert_eq!(first_difference(a, b), None, "round {round}");
        }
    }
    assert_eq!(images_held(), 0);
}

#[test]
fn an_abort_stops_a_render_within_a_second() {
    let _serial = serial();
    let (w, h) = (1920, 1080);
    let source = night(w, h, 1);
    let plugin = loaded(names::CONTEXT_FILTER);
    let effect = instance(&plugin, (w, h), "star-filter-8pt");
    let (outcome, stopped) = std::thread::scope(|scope| {
        let effect = &effect;
        let render = scope.spawn(move || {
            let outcome = effect.render(1.0, &source, [1.0, 1.0]);
            (outcome, Instant::now())
        });
        std::thread::sleep(Duration::from_millis(300));
        let asked = Instant::now();
        effect.set_abort(true);
        let (outcome, done) = render.join().expect("the render thread");
        (outcome, done.saturating_duration_since(asked))
    });
    let refusal = refused(outcome, "aborted");
    assert_eq!(refusal.status, abi::STAT_FAILED);
    assert!(
        refusal.messages.is_empty(),
        "an abort is not an error: {refusal}"
    );
    eprintln!("the render stopped {stopped:?} after the abort");
    assert!(
        stopped < Duration::from_secs(1),
        "stopped {stopped:?} after the abort"
    );
    assert_eq!(images_held(), 0);
    // The next render, no longer aborted, goes through.
    effect.set_abort(false);
    let small = night(64, 36, 1);
    effect
        .render(2.0, &small, [1.0, 1.0])
        .expect("a render after the abort");
}

#[test]
fn a_bad_config_is_one_message_and_a_failed_status() {
    let _serial = serial();
    let dir = tempfile::tempdir().expect("a folder");
    let bad = dir.path().join("bad lens.toml");
    std::fs::write(
        &bad,
        "[[effect]]\ntype = \"bloom\"\nepsilon = 2.0\nbeta = 2.0\nradius = \"10px\"\n",
    )
    .expect("written");
    let broken = dir.path().join("broken.toml");
    std::fs::write(&broken, "[[effect]\ntype = \"bloom\"\n").expect("written");
    let missing = dir.path().join("no such.toml");
    let plugin = loaded(names::CONTEXT_FILTER);
    let effect = instance(&plugin, (64, 36), "paper-fig5-both");
    let source = night(64, 36, 1);
    let cases: [(&str, &str, Setting); 7] = [
        (
            "config",
            "epsilon",
            Setting::Text(bad.display().to_string()),
        ),
        (
            "config",
            "broken.toml",
            Setting::Text(broken.display().to_string()),
        ),
        (
            "config",
            "no such.toml",
            Setting::Text(missing.display().to_string()),
        ),
        ("input_scale", "scale", Setting::Double(-2.0)),
        ("knee", "knee", Setting::Double(f64::NAN)),
        ("aperture_blades", "blades", Setting::Int(2)),
        (
            "bloom_radius",
            "`radius`: length \"ten pixels\"",
            Setting::Text("ten pixels".into()),
        ),
    ];
    for (name, said, value) in cases {
        effect
            .set(
                "preset",
                Setting::Int(option(&plugin, "preset", "paper-fig5-both")),
            )
            .expect("preset");
        for kind in ["aperture", "bloom"] {
            let on = name.starts_with(kind);
            effect
                .set(kind, Setting::Int(i32::from(on)))
                .expect("switch");
        }
        effect.set(name, value).expect("set");
        let refusal = refused(effect.render(1.0, &source, [1.0, 1.0]), said);
        assert_eq!(refusal.status, abi::STAT_FAILED, "{refusal}");
        assert_eq!(refusal.messages.len(), 1, "{refusal}");
        let (kind, text) = &refusal.messages[0];
        assert_eq!(kind, "OfxMessageError");
        assert!(
            text.starts_with("aureole: ") && !text.contains('\n'),
            "{text}"
        );
        assert!(text.contains(said), "{name}: {text}");
        // Put back what the next case does not set.
        effect
            .set("config", Setting::Text(String::new()))
            .expect("config");
        effect
            .set("input_scale", Setting::Double(1.0))
            .expect("scale");
        effect.set("knee", Setting::Double(0.0)).expect("knee");
    }
    // No preset, no config and no effect: said, not guessed.
    for kind in ["aperture", "bloom"] {
        effect.set(kind, Setting::Int(0)).expect("switch");
    }
    effect.set("preset", Setting::Int(0)).expect("no preset");
    let refusal = refused(effect.render(1.0, &source, [1.0, 1.0]), "no camera");
    assert!(
        refusal.messages[0]
            .1
            .contains("no preset, no config file and no effect"),
        "{refusal}"
    );
    // A squeezed plate is refused in words.
    effect
        .set(
            "preset",
            Setting::Int(option(&plugin, "preset", "paper-fig5-both")),
        )
        .expect("preset");
    assert_eq!(images_held(), 0);
}

/// The plugin's status for `action` on `handle` with `args`.
fn call(
    plugin: &Plugin,
    action: &CStr,
    handle: *mut std::ffi::c_void,
    args: Option<&PropSet>,
) -> i32 {
    let out = PropSet::new();
    // SAFETY: the plugin hands every handle back to the host's suites,
    // which look it up first: a made-up one is refused there.
    unsafe { plugin.action(action, handle, args, Some(&out)) }
}

#[test]
fn actions_out_of_order_or_without_their_properties_fail_cleanly() {
    let _serial = serial();
    // Opened but not loaded: every action but load is refused.
    let plugin = Plugin::open(&support::bundle()).expect("the bundle opens");
    let descriptor = PropSet::new();
    for action in [
        names::ACTION_DESCRIBE,
        names::ACTION_RENDER,
        names::ACTION_CREATE_INSTANCE,
    ] {
        assert_ne!(
            call(&plugin, action, descriptor.handle(), None),
            abi::STAT_OK,
            "{action:?} before load"
        );
    }
    drop(plugin);

    let plugin = loaded(names::CONTEXT_FILTER);
    let effect = instance(&plugin, (64, 36), "paper-fig5-both");
    let made_up = 0x1234usize as *mut std::ffi::c_void;
    let kept = PropSet::new();
    let args: &PropSet = &kept;
    args.set(names::PROP_TIME, Value::Doubles(vec![1.0]));
    args.set(names::EFFECT_RENDER_SCALE, Value::Doubles(vec![1.0, 1.0]));
    let refused = [
        // Actions on handles the host never made, or made for another use.
        (names::ACTION_RENDER, made_up, Some(args)),
        (names::ACTION_RENDER, std::ptr::null_mut(), Some(args)),
        (names::ACTION_RENDER, descriptor.handle(), Some(args)),
        (names::ACTION_DESTROY_INSTANCE, made_up, None),
        (names::ACTION_GET_REGION_OF_DEFINITION, made_up, Some(args)),
        // A render without its arguments, or without a render window.
        (names::ACTION_RENDER, effect.handle(), None),
        (names::ACTION_RENDER, effect.handle(), Some(args)),
        (names::ACTION_GET_REGIONS_OF_INTEREST, effect.handle(), None),
        // An instance created twice.
        (names::ACTION_CREATE_INSTANCE, effect.handle(), None),
        // A context the plugin does not work in.
        (
            names::ACTION_DESCRIBE_IN_CONTEXT,
            effect.handle(),
            Some(args),
        ),
    ];
    for (action, handle, args) in refused {
        let status = call(&plugin, action, handle, args);
        assert!(
            status != abi::STAT_OK && status != abi::STAT_REPLY_DEFAULT,
            "{action:?}: {status}"
        );
    }
    // What the plugin leaves to the host is the default reply.
    assert_eq!(
        call(&plugin, c"OfxActionNoSuchThing", effect.handle(), None),
        abi::STAT_REPLY_DEFAULT
    );
    // A render with everything but the images: the source is taken as
    // black, as OpenFX says, but there is nowhere to write.
    args.set(names::EFFECT_RENDER_WINDOW, Value::Ints(vec![0, 0, 64, 36]));
    assert_eq!(
        call(&plugin, names::ACTION_RENDER, effect.handle(), Some(args)),
        abi::STAT_FAILED
    );
    assert!(effect
        .messages()
        .iter()
        .any(|(_, m)| m.contains("no Output image")));
    assert_eq!(images_held(), 0);
    // An input not connected: the output is black and transparent, and
    // the host's default answers for the regions.
    effect.set_source_connected(false);
    let lit = Picture {
        pixels: vec![5.0; 64 * 36 * 4],
        ..night(64, 36, 1)
    };
    // The output buffer starts lit: the plugin writes the black.
    let (_, black) = effect
        .render_buffers(1.0, lit.clone(), lit, [1.0, 1.0])
        .expect("a render without an input");
    assert!(black.pixels.iter().all(|&v| v == 0.0));
    assert!(effect.messages().is_empty());
    effect.set_source_connected(true);
    // And after all that, the instance renders.
    effect
        .render(1.0, &night(64, 36, 1), [1.0, 1.0])
        .expect("a render");
    // Destroyed by the host below, then never again.
    let handle = effect.handle();
    drop(effect);
    assert_ne!(
        call(&plugin, names::ACTION_DESTROY_INSTANCE, handle, None),
        abi::STAT_OK
    );
}
