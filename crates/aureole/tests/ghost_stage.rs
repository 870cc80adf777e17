//! Lens ghosts in the chain (`type = "ghosts"`): the scene's bright
//! sources found and traced, their ghosts' light taken from them, the
//! optical axis at the display window's centre, the glare layers, and the
//! same bytes on every run and thread count.

use aureole::{
    ApplyOptions, Config, ConfigFile, DisplayWindow, Error, Frame, FrameOptions, Image, KeptRays,
    Layout, Session, Stage,
};

/// A cemented achromat behind its stop: three surfaces that reflect, so
/// three ghosts, quick to trace.
const ACHROMAT: &str = r#"
[camera]
sensor_width_mm = 36.0
focal_length_mm = 100.0
f_number = 4.0

[[effect]]
type = "ghosts"
threshold = 1000.0
sources = 2

[effect.lens]
name = "A cemented achromat"

[[effect.lens.surface]]
stop = true
thickness = 5.0
semi_aperture = 12.0

[[effect.lens.surface]]
radius = 61.47
thickness = 6.0
n_d = 1.5168
v_d = 64.17
semi_aperture = 15.0

[[effect.lens.surface]]
radius = -44.64
thickness = 2.5
n_d = 1.6727
v_d = 32.21
semi_aperture = 15.0

[[effect.lens.surface]]
radius = -129.94
thickness = 95.0
semi_aperture = 15.0
"#;

fn config(text: &str) -> Config {
    Config::compose([ConfigFile::parse(text, "ghosts.toml").unwrap()])
}

/// A dark frame with a lamp of 3×3 pixels of `level` cd/m² at each of
/// `lamps` (column, row of its centre).
fn night(width: usize, height: usize, lamps: &[((usize, usize), f32)]) -> Image {
    let mut image = Image::filled(width, height, Layout::Rgb, 0.01);
    for &((x, y), level) in lamps {
        for plane in &mut image.planes {
            for row in y - 1..=y + 1 {
                for col in x - 1..=x + 1 {
                    plane[row * width + col] = level;
                }
            }
        }
    }
    image
}

fn apply(config: Config, frame: &Frame) -> aureole::Applied {
    Session::new(config)
        .apply(frame, &ApplyOptions::default(), &mut |_, _| {})
        .unwrap()
}

fn frame(image: Image) -> Frame {
    Frame::new(image, &FrameOptions::default()).unwrap()
}

fn luminance(image: &Image, i: usize) -> f64 {
    let w = [0.2126, 0.7152, 0.0722];
    (0..3).map(|c| w[c] * f64::from(image.planes[c][i])).sum()
}

/// Σ luminance over the pixels `keep` admits, in f64.
fn light(image: &Image, keep: impl Fn(usize, usize) -> bool) -> f64 {
    (0..image.width * image.height)
        .filter(|&i| keep(i % image.width, i / image.width))
        .map(|i| luminance(image, i))
        .sum()
}

#[test]
fn ghosts_take_their_light_from_their_source_and_make_none() {
    let input = night(160, 120, &[((110, 40), 1e6)]);
    let applied = apply(config(ACHROMAT), &frame(input.clone()));
    let ghosts = applied.ghosts.unwrap();
    assert_eq!((ghosts.found, ghosts.traced, ghosts.paths), (1, 1, 3));
    assert!(ghosts.light > 1e-5 && ghosts.light < 1e-2, "{ghosts:?}");
    let lamp = |x: usize, y: usize| (109..=111).contains(&x) && (39..=41).contains(&y);
    // The lamp keeps its light less its ghosts' (those beyond the frame
    // included), as the summary counts it.
    let (before, after) = (light(&input, lamp), light(&applied.image, lamp));
    let taken = (before - after) / before;
    // (The lamp's pixels hold 1e6 in f32, to 6e-8.)
    assert!((taken - ghosts.light).abs() < 1e-6, "{taken} {ghosts:?}");
    // What lands elsewhere is at most what the lamp lost.
    let dark = |x, y| !lamp(x, y);
    let landed = light(&applied.image, dark) - light(&input, dark);
    assert!(landed > 0.0 && landed <= (before - after) * (1.0 + 1e-4));
    assert!(applied.energy_out <= applied.energy_in * (1.0 + 1e-6));
    assert!(applied.energy_out >= applied.energy_in * (1.0 - 1e-2));
}

#[test]
fn ghosts_line_up_on_the_display_windows_centre_from_the_overscan() {
    // A frame with overscan: the display window is 160×120 from (40, 30)
    // of a 200×150 data window, and the lamp lies beyond it.
    let lamp = ((20usize, 130usize), 1e6);
    let window = DisplayWindow {
        x: 40,
        y: 30,
        width: 160,
        height: 120,
    };
    let overscan = frame(night(200, 150, &[lamp])).with_display_window(window);
    let overscan = apply(config(ACHROMAT), &overscan).image;
    // The same sensor without overscan: a 240×180 frame centred on the
    // display window's centre, its pixel (x, y) the data window's, and as
    // much wider in mm as in pixels (the camera's sensor is the display
    // window).
    let wider = ACHROMAT.replace("sensor_width_mm = 36.0", "sensor_width_mm = 54.0");
    let whole = apply(config(&wider), &frame(night(240, 180, &[lamp]))).image;
    // The same values, but within half the coarsest level's pixel (32
    // px) of the frame's right and bottom edges, where the coarse levels
    // the largest ghosts are drawn at are held, and which lie elsewhere.
    let apart = |a: &Image, b: &Image| {
        let mut worst: f64 = 0.0;
        for c in 0..3 {
            for y in 0..150 - 32 {
                for x in 0..200 - 32 {
                    let (p, q) = (a.planes[c][y * a.width + x], b.planes[c][y * b.width + x]);
                    worst = worst.max(f64::from((p - q).abs() / p.abs().max(q.abs())));
                }
            }
        }
        worst
    };
    assert_eq!(apart(&overscan, &whole), 0.0);
    // The data window's centre is not the axis.
    let centred = apply(config(ACHROMAT), &frame(night(200, 150, &[lamp]))).image;
    assert!(
        apart(&overscan, &centred) > 1e-2,
        "{}",
        apart(&overscan, &centred)
    );
}

#[test]
fn the_brightest_sources_are_traced_up_to_the_count_and_the_rest_left() {
    let text = ACHROMAT.replace("sources = 2", "sources = 1");
    let input = night(160, 120, &[((30, 30), 2e5), ((120, 90), 1e6)]);
    let applied = apply(config(&text), &frame(input.clone()));
    let ghosts = applied.ghosts.unwrap();
    assert_eq!((ghosts.found, ghosts.traced), (2, 1));
    // The dimmer lamp's centre keeps its light but for ghosts landing
    // on it, which are far dimmer than the lamp.
    let dim = 30 * 160 + 30;
    let kept = luminance(&applied.image, dim) / luminance(&input, dim);
    assert!((1.0..1.0 + 1e-5).contains(&kept), "{kept}");
    let bright = 90 * 160 + 120;
    assert!(luminance(&applied.image, bright) < luminance(&input, bright));
}

/// Rays kept from a trace through one stop draw the ghosts of another
/// within the same circle (other blades, turned, rounded) to the bytes a
/// fresh trace gives, without tracing; another f-number is traced anew,
/// and a limit of 0 keeps nothing.
#[test]
fn kept_rays_draw_another_stops_ghosts_as_a_trace_does() {
    let input = frame(night(120, 90, &[((80, 30), 1e6), ((20, 70), 3e5)]));
    let camera = |aperture: &str, f_number: &str| {
        let lens = ACHROMAT.replace("f_number = 4.0", &format!("f_number = {f_number}"));
        config(&format!(
            "{lens}\n[[effect]]\ntype = \"aperture\"\n{aperture}\n"
        ))
    };
    let traced = |config: Config, kept: &mut KeptRays| {
        let (ghosted, _) = Session::new(config)
            .trace_ghosts_keeping(&input, kept, &mut |_, _| {})
            .unwrap()
            .unwrap();
        ghosted.image().planes.clone()
    };
    let mut kept = KeptRays::new(u64::MAX);
    traced(camera("blades = 7", "4.0"), &mut kept);
    assert_eq!(kept.reused(), 0);
    assert!(kept.bytes() > 0);
    for (aperture, f_number, reused) in [
        ("blades = 5", "4.0", 2),
        ("blades = 6\nrotation_deg = 10.0", "4.0", 2),
        ("blades = 7\nroundness = 0.5", "4.0", 2),
        ("blades = 0", "4.0", 2),
        ("blades = 7", "5.6", 0),
        ("blades = 9", "5.6", 2),
    ] {
        let drawn = traced(camera(aperture, f_number), &mut kept);
        assert_eq!(kept.reused(), reused, "{aperture} at f/{f_number}");
        let fresh = traced(camera(aperture, f_number), &mut KeptRays::new(0));
        assert!(
            drawn == fresh,
            "{aperture} at f/{f_number}: not the bytes traced"
        );
    }
    let mut none = KeptRays::new(0);
    traced(camera("blades = 7", "4.0"), &mut none);
    assert_eq!(none.bytes(), 0);
}

#[test]
fn the_same_bytes_on_one_thread_and_two() {
    let input = night(120, 90, &[((80, 30), 1e6), ((20, 70), 3e5)]);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| apply(config(ACHROMAT), &frame(input.clone())).image.planes)
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn the_ghosts_have_their_own_layer_and_the_layers_sum_to_the_glare() {
    let text = format!(
        "{ACHROMAT}\n[[effect]]\ntype = \"bloom\"\nepsilon = 0.05\nbeta = 2.0\nradius = \"3px\"\n"
    );
    let input = night(120, 90, &[((80, 30), 1e6)]);
    let frame = frame(input.clone());
    let mut session = Session::new(config(&text));
    let (applied, layers) = session
        .apply_layers(&frame, &ApplyOptions::default(), &mut |_, _| {})
        .unwrap();
    let names: Vec<&str> = layers.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(names, ["glare.ghosts", "glare.bloom", "glare"]);
    let alone = apply(config(&text), &frame);
    assert_eq!(applied.image.planes, alone.image.planes);
    for c in 0..3 {
        for i in 0..input.width * input.height {
            let parts = layers[0].image.planes[c][i] + layers[1].image.planes[c][i];
            let whole = layers[2].image.planes[c][i];
            // Each layer is a difference of f32 images: it rounds as they.
            let size = input.planes[c][i].max(applied.image.planes[c][i]).max(1.0);
            assert!((parts - whole).abs() <= 4.0 * f32::EPSILON * size);
        }
    }
    // The ghosts' layer, spread by nothing yet, is the scene's change.
    let ghosts_only = Session::new(config(ACHROMAT))
        .apply(&frame, &ApplyOptions::default(), &mut |_, _| {})
        .unwrap();
    for c in 0..3 {
        for (i, g) in layers[0].image.planes[c].iter().enumerate() {
            assert_eq!(*g, ghosts_only.image.planes[c][i] - input.planes[c][i]);
        }
    }
}

#[test]
fn a_config_writes_its_ghosts_back_as_it_read_them() {
    for text in [
        ACHROMAT.to_string(),
        "[[effect]]\ntype = \"ghosts\"\nlens = \"telephoto-300mm-f2.8\"\nspectral = true\n".into(),
    ] {
        let file = ConfigFile::parse(&text, "ghosts.toml").unwrap();
        let again = ConfigFile::parse(&file.to_toml(), "again.toml").unwrap();
        assert_eq!(again, file);
        assert!(file.ghosts.is_some());
    }
}

#[test]
fn a_shipped_lens_throws_all_its_ghosts_and_needs_the_sensors_width() {
    let text = "[camera]\nsensor_width_mm = 36.0\nfocal_length_mm = 50.0\nf_number = 8.0\n[[effect]]\ntype = \"ghosts\"\nlens = \"double-gauss-50mm-f1.4\"\n[[effect]]\ntype = \"aperture\"\nblades = 6\n";
    let input = night(96, 64, &[((70, 20), 1e6)]);
    let applied = apply(config(text), &frame(input.clone()));
    let ghosts = applied.ghosts.unwrap();
    assert_eq!(ghosts.paths, 78);
    assert_eq!(ghosts.f_number, 8.0);
    assert!(ghosts.light > 1e-5 && ghosts.light < 1e-2, "{ghosts:?}");
    let without = text.replace("sensor_width_mm = 36.0\n", "");
    let refused = Session::new(config(&without))
        .apply(&frame(input), &ApplyOptions::default(), &mut |_, _| {})
        .unwrap_err()
        .to_string();
    assert!(refused.contains("sensor_width_mm"), "{refused}");
}

#[test]
fn an_anamorphic_lens_squeezes_its_stops_diffraction_too_or_is_refused() {
    // Super 35 at 100 mm: the rear group's small clear apertures pass a
    // field of ±11° across x, a full-frame sensor at 50 mm none.
    let text = "[camera]\nsensor_width_mm = 24.9\nfocal_length_mm = 100.0\nf_number = 8.0\n[[effect]]\ntype = \"ghosts\"\nlens = \"anamorphic-rear-1.3x-f1.8\"\n[[effect]]\ntype = \"aperture\"\nblades = 6\nspectral = false\n";
    let input = night(96, 64, &[((70, 20), 1e6)]);
    let refused = Session::new(config(text))
        .apply(
            &frame(input.clone()),
            &ApplyOptions::default(),
            &mut |_, _| {},
        )
        .unwrap_err()
        .to_string();
    assert!(
        refused.contains("squeezes 1.301") && refused.contains("write squeeze = 1.301"),
        "{refused}"
    );
    assert_eq!(refused.lines().count(), 1);
    let squeezed = format!("{text}squeeze = 1.301\n");
    let applied = apply(config(&squeezed), &frame(input));
    let ghosts = applied.ghosts.unwrap();
    // 29 surfaces but the stop, in pairs.
    assert_eq!(ghosts.paths, 28 * 27 / 2);
    assert!(ghosts.light > 1e-5 && ghosts.light < 1e-2, "{ghosts:?}");
    assert!(applied.energy_out <= applied.energy_in * (1.0 + 1e-6));
}

#[test]
fn a_session_cancelled_while_it_traces_ghosts_stops() {
    // Cancelled from the tracing's own first report, after the first
    // batch of sources (two, on two threads): the stage must hear it
    // before the next, as a closed tab or Ctrl-C would be heard.
    let mut session = Session::new(config(ACHROMAT));
    let cancel = session.cancel_token();
    let mut reports = 0;
    let lamps = [(70, 20), (20, 40), (40, 10), (80, 50)].map(|at| (at, 1e6));
    let input = night(96, 64, &lamps);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let result = pool.install(|| {
        session.apply(&frame(input), &ApplyOptions::default(), &mut |stage, _| {
            if stage == Stage::TracingGhosts {
                reports += 1;
                cancel.cancel();
            }
        })
    });
    assert!(matches!(result, Err(Error::Cancelled)), "{result:?}");
    assert_eq!(reports, 1, "the tracing went on after it was cancelled");
}

#[test]
fn lens_names_and_files_are_refused_in_one_line_naming_them() {
    let text = "[[effect]]\ntype = \"ghosts\"\nlens = \"double-gauss\"\n";
    let refused = ConfigFile::parse(text, "cam.toml").unwrap_err().to_string();
    assert!(refused.starts_with("cam.toml:3:1: effect 1 (ghosts): lens = \"double-gauss\""));
    assert!(refused.contains("double-gauss-50mm-f1.4") && !refused.contains('\n'));
    let file = "[[effect]]\ntype = \"ghosts\"\nlens = \"mine.toml\"\n";
    let served = ConfigFile::parse_in(file, "config", None)
        .unwrap_err()
        .to_string();
    assert!(served.contains("no lens files are read"), "{served}");
    let twice = format!("{ACHROMAT}\n[[effect]]\ntype = \"ghosts\"\nlens = \"portrait-90mm-f2\"\n");
    let refused = ConfigFile::parse(&twice, "cam.toml")
        .unwrap_err()
        .to_string();
    assert!(refused.contains("one lens"), "{refused}");
}
