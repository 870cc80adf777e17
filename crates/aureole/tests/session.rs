//! The session every front end calls: the threshold of the configuration,
//! the input scale, bad samples, plan reuse, the memory limit and
//! cancellation, decided once for all of them.

use aureole::{
    presets, ApplyOptions, Config, Error, Frame, FrameOptions, Image, Layout, Method, ScaleSource,
    Session, Shape, Stage,
};

fn config(preset: &str) -> Config {
    let mut config = Config::default();
    config.merge(presets::find(preset).unwrap().config().unwrap());
    config
}

/// A dim street with lamps of 50 to 5·10⁴ cd/m².
fn street(w: usize, h: usize, layout: Layout) -> Image {
    let mut image = Image::filled(w, h, layout, 0.05);
    for (k, level) in [50.0, 500.0, 5e3, 5e4].into_iter().enumerate() {
        for plane in &mut image.planes {
            plane[(h / 2) * w + 5 + 9 * k] = level;
        }
    }
    image
}

fn frame(image: Image) -> Frame {
    Frame::new(image, &FrameOptions::default()).unwrap()
}

/// `image` through `session` with the default options.
fn through(session: &mut Session, image: &Image) -> aureole::Applied {
    let options = ApplyOptions::default();
    session
        .apply(&frame(image.clone()), &options, &mut |_, _| {})
        .unwrap()
}

#[test]
fn a_configs_threshold_is_honoured_when_the_caller_gives_none() {
    let mut config = config("paper-fig4-bloom");
    config.threshold = 200.0;
    let image = street(48, 20, Layout::Rgb);
    let mut session = Session::new(config.clone());
    let applied = through(&mut session, &image);
    // The lamps of 500, 5·10³ and 5·10⁴ cd/m²; not the one of 50.
    assert_eq!((applied.spread_pixels, applied.threshold), (3, 200.0));
    // The plan alone does the same, and a threshold given wins.
    let plan = aureole::Plan::for_image(&config, 48, 20, None).unwrap();
    let alone = plan
        .apply(&image, 1.0, &ApplyOptions::default(), &mut |_| {})
        .unwrap();
    assert_eq!(alone.image, applied.image);
    let given = ApplyOptions {
        threshold: Some(0.0),
        ..ApplyOptions::default()
    };
    let all = session
        .apply(&frame(image), &given, &mut |_, _| {})
        .unwrap();
    assert_eq!(all.spread_pixels, 48 * 20);
}

#[test]
fn the_scale_is_given_else_white_luminance_else_one() {
    let mut image = street(16, 8, Layout::Luminance);
    let at = |image: Image, input_scale| {
        let options = FrameOptions {
            input_scale,
            ..FrameOptions::default()
        };
        let frame = Frame::new(image, &options).unwrap();
        (frame.scale(), frame.scale_source())
    };
    assert_eq!(at(image.clone(), None), (1.0, ScaleSource::Default));
    image.white_luminance = Some(621.0);
    assert_eq!(
        at(image.clone(), None),
        (621.0, ScaleSource::WhiteLuminance)
    );
    assert_eq!(at(image, Some(3.0)), (3.0, ScaleSource::Given));
}

#[test]
fn samples_that_are_not_luminance_are_refused_or_replaced() {
    let mut image = street(16, 8, Layout::Rgb);
    image.planes[1][3] = f32::NAN;
    image.planes[2][9] = -1.0;
    let refused = Frame::new(image.clone(), &FrameOptions::default()).unwrap_err();
    assert!(
        matches!(refused, Error::BadSamples { first: (3, 0), .. }),
        "{refused}"
    );
    // Negative samples pass through, counted.
    image.planes[1][3] = 0.0;
    let frame = Frame::new(image.clone(), &FrameOptions::default()).unwrap();
    assert_eq!((frame.negatives(), frame.replaced()), (1, 0));
    assert_eq!(frame.image().planes[2][9], -1.0);
    let mut session = Session::new(config("paper-fig5-both"));
    let applied = session
        .apply(&frame, &ApplyOptions::default(), &mut |_, _| {})
        .unwrap();
    assert!(applied.image.planes.iter().flatten().all(|v| v.is_finite()));
    image.planes[0][0] = f32::INFINITY;
    let sanitize = FrameOptions {
        sanitize: true,
        ..FrameOptions::default()
    };
    let frame = Frame::new(image, &sanitize).unwrap();
    assert_eq!(frame.replaced(), 2);
    assert!(frame.image().non_finite().is_none() && frame.image().negatives().is_none());
}

#[test]
fn a_frame_sequence_builds_the_kernel_once_per_size() {
    let mut session = Session::new(config("paper-fig5-both"));
    let mut builds = 0;
    let mut run = |session: &mut Session, w, h| {
        let mut built = false;
        let applied = session
            .apply(
                &frame(street(w, h, Layout::Rgb)),
                &ApplyOptions::default(),
                &mut |stage, _| built |= stage == Stage::BuildingKernel,
            )
            .unwrap();
        builds += usize::from(built);
        session.recycle(applied.image);
    };
    for (w, h) in [(40, 20), (40, 20), (40, 20), (30, 20), (30, 20)] {
        run(&mut session, w, h);
    }
    assert_eq!(builds, 2);
    assert_eq!(session.plan().unwrap().size(), (30, 20));
}

#[test]
fn a_plan_prepared_beforehand_is_the_one_applied() {
    let image = street(40, 20, Layout::Rgb);
    let mut prepared = Session::new(config("paper-fig5-both"));
    prepared.prepare(&frame(image.clone())).unwrap();
    assert_eq!(prepared.plan().unwrap().size(), (40, 20));
    let mut built = false;
    let applied = prepared
        .apply(
            &frame(image.clone()),
            &ApplyOptions::default(),
            &mut |stage, _| built |= stage == Stage::BuildingKernel,
        )
        .unwrap();
    assert!(!built, "the prepared plan was built again");
    let fresh = through(&mut Session::new(config("paper-fig5-both")), &image);
    assert_eq!(applied.image, fresh.image);
    // Another size replaces it.
    prepared
        .prepare(&frame(street(30, 20, Layout::Rgb)))
        .unwrap();
    assert_eq!(prepared.plan().unwrap().size(), (30, 20));
}

#[test]
fn a_kernel_given_is_applied_at_every_size_and_kept() {
    let kernel = config("paper-fig4-bloom")
        .kernel(&aureole::Extent::new(15, 15).unwrap())
        .unwrap();
    let mut session = Session::with_kernel(kernel.clone());
    for (w, h) in [(40, 20), (24, 12), (40, 20)] {
        let image = street(w, h, Layout::Rgb);
        let applied = through(&mut session, &image);
        let plan = aureole::Plan::with_kernel(kernel.clone(), w, h).unwrap();
        let alone = plan
            .apply(&image, 1.0, &ApplyOptions::default(), &mut |_| {})
            .unwrap();
        assert_eq!(applied.image, alone.image, "{w}x{h}");
        assert_eq!(session.plan().unwrap().kernel(), &kernel);
    }
}

#[test]
fn a_run_beyond_the_memory_limit_stops_before_it_allocates_and_says_what_fits() {
    let mut session = Session::new(config("paper-fig5-both")).with_memory_limit(64 << 20);
    let image = street(1000, 600, Layout::Rgb);
    let error = session
        .apply(&frame(image), &ApplyOptions::default(), &mut |_, _| {
            panic!("no work may start")
        })
        .unwrap_err();
    let Error::Memory {
        needed,
        limit,
        fits: Some(fit),
        built: true,
        ..
    } = error
    else {
        panic!("{error}");
    };
    assert!(needed > limit && fit.bytes <= limit, "{needed} {fit:?}");
    assert!(fit.kernel.0 < 1999 && fit.kernel.1 < 1199, "{fit:?}");
    // The suggestion fits.
    let mut capped = Session::new(config("paper-fig5-both"))
        .with_memory_limit(64 << 20)
        .with_max_extent(Some(fit.kernel));
    let image = street(1000, 600, Layout::Rgb);
    assert!(capped
        .apply(&frame(image), &ApplyOptions::default(), &mut |_, _| {})
        .is_ok());
}

#[test]
fn looking_for_a_gpu_counts_the_drivers_it_loads() {
    let camera = config("paper-fig4-bloom");
    let workload = aureole::memory::Workload::of_config(&camera, 200, 120, 3, false, None).unwrap();
    // Room for the run on the processor, not for Vulkan's drivers beside it.
    let limit = workload.estimate(&camera.effects).bytes + (16 << 20);
    let run = |device| {
        Session::new(camera.clone())
            .with_device(device)
            .with_memory_limit(limit)
            .apply(
                &frame(street(200, 120, Layout::Rgb)),
                &ApplyOptions::default(),
                &mut |_, _| {},
            )
    };
    assert!(run(aureole::Device::Cpu).is_ok());
    let refused = run(aureole::Device::Auto).unwrap_err();
    assert!(
        matches!(refused, Error::Memory { needed, .. } if needed > limit),
        "{refused}"
    );
}

/// Applies `method` to a 4-lamp street through `session`, cancelling at
/// the first report of `stage`, and returns the result.
fn cancelled_at(
    session: &mut Session,
    image: Image,
    method: Method,
    stage: Stage,
) -> Result<aureole::Applied, Error> {
    let cancel = session.cancel_token();
    let options = ApplyOptions {
        method,
        ..ApplyOptions::default()
    };
    session.apply(&frame(image), &options, &mut |at, _| {
        if at == stage {
            cancel.cancel();
        }
    })
}

#[test]
fn every_long_loop_stops_when_cancelled() {
    // The kernel build: rasterising (a rounded 8-blade stop in colour), the
    // composition with a bloom and the spectrum.
    let mut night = config("camera-f8-7blade");
    night.merge(presets::find("paper-fig4-bloom").unwrap().config().unwrap());
    let mut session = Session::new(night);
    let result = cancelled_at(
        &mut session,
        street(64, 40, Layout::Rgb),
        Method::Fft,
        Stage::BuildingKernel,
    );
    assert!(matches!(result, Err(Error::Cancelled)), "{result:?}");
    assert!(session.plan().is_none());
    // Each way of spreading, in f32 and (a sun over a night sky) in f64.
    let mut sun = street(64, 40, Layout::Rgb);
    for plane in &mut sun.planes {
        plane[200] = 1e9;
    }
    for (image, method) in [
        (street(64, 40, Layout::Rgb), Method::Fft),
        (street(64, 40, Layout::Rgb), Method::Splat),
        (sun, Method::Fft),
    ] {
        let mut session = Session::new(config("paper-fig5-both"));
        let result = cancelled_at(&mut session, image, method, Stage::Convolving);
        assert!(
            matches!(result, Err(Error::Cancelled)),
            "{method:?}: {result:?}"
        );
    }
}

#[test]
fn a_session_cancelled_from_another_thread_stops() {
    let mut session = Session::new(config("camera-f11-6blade"));
    let cancel = session.cancel_token();
    std::thread::spawn(move || cancel.cancel()).join().unwrap();
    let result = session.apply(
        &frame(street(64, 40, Layout::Rgb)),
        &ApplyOptions::default(),
        &mut |_, _| {},
    );
    assert!(matches!(result, Err(Error::Cancelled)));
}

#[test]
fn a_session_goes_on_after_a_cancelled_run_with_a_fresh_flag() {
    let mut session = Session::new(config("paper-fig4-bloom"));
    session.cancel_token().cancel();
    let image = street(32, 16, Layout::Rgb);
    let run = |session: &mut Session| {
        session.apply(
            &frame(image.clone()),
            &ApplyOptions::default(),
            &mut |_, _| {},
        )
    };
    assert!(matches!(run(&mut session), Err(Error::Cancelled)));
    session.set_cancel_token(aureole::Cancel::new());
    assert!(run(&mut session).is_ok());
}

#[test]
fn a_kernel_given_survives_a_cancelled_plan() {
    // A kernel given is transformed by the first application: cancelled
    // there, the session still holds it and the next one runs.
    let kernel = config("paper-fig4-bloom")
        .kernel(&aureole::Extent::new(15, 15).unwrap())
        .unwrap();
    let mut session = Session::with_kernel(kernel);
    let image = street(40, 20, Layout::Rgb);
    let cancelled = cancelled_at(&mut session, image.clone(), Method::Fft, Stage::Convolving);
    assert!(matches!(cancelled, Err(Error::Cancelled)), "{cancelled:?}");
    session.set_cancel_token(aureole::Cancel::new());
    through(&mut session, &image);
}

#[test]
fn a_frame_too_large_for_a_full_kernel_is_told_from_its_shape_and_runs_capped() {
    let limit = 8u64 << 30;
    let full = Session::new(config("camera-f8-7blade")).with_memory_limit(limit);
    match full.check_shape(Shape {
        width: 12_000,
        height: 8_000,
        planes: 3,
        alpha: false,
    }) {
        Err(Error::KernelSize { width, height, .. }) => {
            assert_eq!((width, height), (23_999, 15_999))
        }
        other => panic!("{other:?}"),
    }
    // The cap comes before the size check, so the frame can run.
    let capped = Session::new(config("camera-f8-7blade"))
        .with_memory_limit(2 * limit)
        .with_max_extent(Some((101, 101)));
    capped
        .check_shape(Shape {
            width: 12_000,
            height: 8_000,
            planes: 3,
            alpha: false,
        })
        .unwrap();
    // A frame that fits a full kernel but not the memory is refused with
    // the largest kernel that would fit.
    let small = Session::new(config("camera-f8-7blade")).with_memory_limit(1 << 30);
    match small.check_shape(Shape {
        width: 3840,
        height: 2160,
        planes: 3,
        alpha: false,
    }) {
        Err(Error::Memory { fits: Some(_), .. }) => {}
        other => panic!("{other:?}"),
    }
}

/// A chain of three effects, two of one type, as a config writes it.
fn chain() -> Config {
    let text = r#"
[camera]
sensor_width_mm = 36.0
focal_length_mm = 50.0
f_number = 8.0

[[effect]]
type = "bloom"
epsilon = 0.05
beta = 3.0
radius = "2px"

[[effect]]
type = "halation"
base_thickness = "3px"
red_depth = "0.2px"
green_depth = "0.4px"
blue_depth = "0.6px"

[[effect]]
type = "bloom"
epsilon = 0.02
beta = 2.0
radius = "6px"
"#;
    let mut config = Config::default();
    config.merge(aureole::ConfigFile::parse(text, "the chain").unwrap());
    config
}

#[test]
fn glare_layers_hold_each_effects_light_and_sum_to_the_glare() {
    let image = street(48, 20, Layout::Rgb);
    let mut session = Session::new(chain());
    let options = ApplyOptions::default();
    let (applied, layers) = session
        .apply_layers(&frame(image.clone()), &options, &mut |_, _| {})
        .unwrap();
    let names: Vec<&str> = layers.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(
        names,
        ["glare.bloom", "glare.halation", "glare.bloom2", "glare"]
    );
    // The beauty is what apply gives, and the layers sum to it less the
    // input, within the round-off of f32 differences.
    assert_eq!(
        applied.image,
        through(&mut Session::new(chain()), &image).image
    );
    let peak = image.planes[0].iter().fold(0f32, |m, v| m.max(*v));
    for c in 0..3 {
        for i in 0..48 * 20 {
            let total = applied.image.planes[c][i] - image.planes[c][i];
            let summed: f32 = layers[..3].iter().map(|l| l.image.planes[c][i]).sum();
            assert!((summed - total).abs() <= 1e-6 * peak, "plane {c} pixel {i}");
            assert_eq!(layers[3].image.planes[c][i], total);
        }
    }
    // The first layer is the first effect alone; each moves light out of
    // the lamps (negative there), and loses only what leaves the frame,
    // less than it moved.
    let mut first = chain();
    first.effects.truncate(1);
    let alone = through(&mut Session::new(first), &image).image;
    assert_eq!(
        layers[0].image.planes[0][10 * 48 + 5 + 27],
        alone.planes[0][10 * 48 + 32] - 5e4
    );
    for layer in &layers {
        let lamp = layer.image.planes[0][10 * 48 + 32];
        let sum: f64 = layer.image.planes[0].iter().map(|&v| f64::from(v)).sum();
        assert!(lamp < 0.0, "{}: {lamp}", layer.name);
        assert!(
            sum <= 0.0 && -sum < f64::from(-lamp),
            "{}: {sum}",
            layer.name
        );
    }
}

#[test]
fn a_kernel_given_ready_made_has_the_total_glare_alone() {
    let image = street(48, 20, Layout::Luminance);
    let kernel = chain()
        .kernel(&aureole::Extent::new(21, 21).unwrap())
        .unwrap();
    let mut session = Session::with_kernel(kernel.clone());
    let glare_only = ApplyOptions {
        glare_only: true,
        ..ApplyOptions::default()
    };
    let (applied, layers) = session
        .apply_layers(&frame(image.clone()), &glare_only, &mut |_, _| {})
        .unwrap();
    assert_eq!(layers.len(), 1);
    assert_eq!(layers[0].name, "glare");
    // The total is what a plain glare-only run of the kernel gives.
    let plain = Session::with_kernel(kernel)
        .apply(&frame(image), &glare_only, &mut |_, _| {})
        .unwrap();
    assert_eq!(plain.image.planes, layers[0].image.planes);
    assert_eq!(plain.image.planes, applied.image.planes);
}

#[test]
fn a_layered_sequence_builds_its_chains_once() {
    let image = street(48, 20, Layout::Rgb);
    let mut session = Session::new(chain());
    let options = ApplyOptions::default();
    let run = |session: &mut Session| {
        let mut built = false;
        let (_, layers) = session
            .apply_layers(&frame(image.clone()), &options, &mut |stage, _| {
                built |= stage == Stage::BuildingKernel;
            })
            .unwrap();
        (built, layers)
    };
    let (first_built, first) = run(&mut session);
    let (again_built, again) = run(&mut session);
    assert!(first_built && !again_built);
    for (a, b) in first.iter().zip(&again) {
        assert_eq!(a.image.planes, b.image.planes, "{}", a.name);
    }
    // Under a limit that holds one run, the chains are built again.
    let fits = |mb: u64| {
        Session::new(chain())
            .with_memory_limit(mb << 20)
            .check_shape(Shape::of(&image))
            .is_ok()
    };
    let one = (1..4096).find(|&mb| fits(mb)).unwrap();
    let mut tight = Session::new(chain()).with_memory_limit((one + 1) << 20);
    assert!(run(&mut tight).0 && run(&mut tight).0);
}
