//! The GPU engine against the CPU engine (docs/physics.md §8): the same
//! spreads within f32 round-off, on whatever Vulkan, Metal or DX12 device
//! the machine has (Mesa's lavapipe in CI). Skipped, with a word, where
//! there is none.

#![cfg(feature = "gpu")]

mod noise;
#[path = "../../../tests/support/required.rs"]
mod required;

use aureole::control::{Cancel, Control};
use aureole::convolve::{engine, Backend, Centre, Precision, Spread, Term};
use aureole::{ApplyOptions, Arithmetic, Config, Device, Error, Image, Layout, Plan};
use noise::pseudo_random;

/// Whether there is a GPU; where not, says why the test does not run.
fn gpu_present(test: &str) -> bool {
    match aureole::convolve::choose(aureole::convolve::Device::Gpu) {
        Ok(_) => true,
        Err(why) => {
            required::missing(
                test,
                &format!("{why} (Debian: mesa-vulkan-drivers for lavapipe)"),
            );
            false
        }
    }
}

/// The worst of |a − b|/|b| over the pixels.
fn worst_relative(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| ((x - y) / y).abs())
        .fold(0.0f32, f32::max)
}

/// A luminance plane through a coloured kernel: Σ w_k K_k ⊛ Y.
fn luminance<'a>(plane: &'a [f32], lamps: &'a [usize]) -> Spread<'a> {
    Spread {
        plane,
        fractions: None,
        terms: Term::luminance(),
        lamps,
    }
}

fn relative_l2(a: &[f32], b: &[f32]) -> f64 {
    let (mut diff, mut norm) = (0.0f64, 0.0f64);
    for (x, y) in a.iter().zip(b) {
        diff += (f64::from(*x) - f64::from(*y)).powi(2);
        norm += f64::from(*y).powi(2);
    }
    (diff / norm).sqrt()
}

/// Both engines' outputs for `spreads` through `planes`.
fn both(
    planes: &[Vec<f32>],
    size: (usize, usize),
    image: (usize, usize),
    spreads: &[Spread],
) -> (Vec<Vec<f32>>, Vec<Vec<f32>>) {
    let slices: Vec<&[f32]> = planes.iter().map(Vec::as_slice).collect();
    let cancel = Cancel::new();
    let run = |backend| {
        let mut control = Control::quiet(&cancel);
        let built = engine(
            (backend, Precision::Single),
            &slices,
            size,
            image,
            Centre::Leave,
            &mut control,
        )
        .unwrap();
        built.prepare(&slices, &mut control).unwrap();
        built.spread(spreads, Vec::new(), &mut control).unwrap()
    };
    (run(Backend::Gpu), run(Backend::Cpu))
}

#[test]
fn the_gpu_spreads_as_the_cpu_does() {
    if !gpu_present("the_gpu_spreads_as_the_cpu_does") {
        return;
    }
    // Periods of every radix, full-frame and smaller kernels, an odd
    // number of planes, fractions, and a luminance plane through three
    // kernel planes.
    for (w, h, kw, kh) in [(16, 9, 31, 17), (45, 20, 13, 11), (50, 36, 99, 71)] {
        let kernel: Vec<Vec<f32>> = (0..3).map(|c| pseudo_random(kw * kh, 40 + c)).collect();
        let planes: Vec<Vec<f32>> = (0..3).map(|c| pseudo_random(w * h, 7 + c)).collect();
        let fractions = pseudo_random(w * h, 99);
        for with_fractions in [false, true] {
            let spreads: Vec<Spread> = planes
                .iter()
                .enumerate()
                .map(|(c, plane)| Spread {
                    plane,
                    fractions: with_fractions.then_some(fractions.as_slice()),
                    terms: Term::alone(c),
                    lamps: &[],
                })
                .collect();
            let (gpu, cpu) = both(&kernel, (kw, kh), (w, h), &spreads);
            for (g, c) in gpu.iter().zip(&cpu) {
                let error = relative_l2(g, c);
                assert!(
                    error < 1e-5,
                    "{w}x{h} kernel {kw}x{kh}: relative L2 {error:e}"
                );
            }
        }
        let weighted = [luminance(&planes[0], &[])];
        let (gpu, cpu) = both(&kernel, (kw, kh), (w, h), &weighted);
        let error = relative_l2(&gpu[0], &cpu[0]);
        assert!(error < 1e-5, "luminance {w}x{h}: relative L2 {error:e}");
    }
}

/// The camera of `preset` with its kernel for `w`×`h` frames.
fn kernel_of(preset: &str, (w, h): (usize, usize)) -> aureole::Kernel {
    let mut config = Config::default();
    config.merge(aureole::presets::find(preset).unwrap().config().unwrap());
    Plan::for_image(&config, w, h, None).unwrap().into_kernel()
}

/// A lit facade: soft patches of 10–300 cd/m² on 1 cd/m², a range f32
/// holds without lamps apart.
fn facade(w: usize, h: usize) -> Image {
    let mut image = Image::filled(w, h, Layout::Rgb, 1.0);
    let light = pseudo_random(w * h, 5);
    for (c, plane) in image.planes.iter_mut().enumerate() {
        for (i, v) in plane.iter_mut().enumerate() {
            let (x, y) = (i % w, i / w);
            if (x / 8 + y / 6) % 3 == 0 {
                *v = 10.0 + 290.0 * light[i] * (1.0 + 0.1 * c as f32);
            }
        }
    }
    image
}

/// A night street: lamps of 10⁵ cd/m² over 10⁻² cd/m².
fn night_street(w: usize, h: usize) -> Image {
    let mut image = Image::filled(w, h, Layout::Rgb, 0.01);
    for (c, plane) in image.planes.iter_mut().enumerate() {
        for lamp in 0..12 {
            let (x, y) = (8 + lamp * (w - 16) / 11, h / 3 + (lamp % 3) * 4);
            plane[y * w + x] = 1e5 * (1.0 + 0.05 * c as f32);
        }
    }
    image
}

fn apply(plan: &Plan, image: &Image) -> aureole::Applied {
    plan.apply(image, 1.0, &ApplyOptions::default(), &mut |_| {})
        .unwrap()
}

#[test]
fn a_kernel_split_for_lamps_spreads_on_the_gpu_as_on_the_cpu() {
    if !gpu_present("a_kernel_split_for_lamps_spreads_on_the_gpu_as_on_the_cpu") {
        return;
    }
    let (w, h, kw, kh) = (40, 24, 79, 47);
    let kernel: Vec<Vec<f32>> = (0..3).map(|c| pseudo_random(kw * kh, 40 + c)).collect();
    let slices: Vec<&[f32]> = kernel.iter().map(Vec::as_slice).collect();
    let mut planes: Vec<Vec<f32>> = (0..3).map(|c| pseudo_random(w * h, 7 + c)).collect();
    let lamps = [5usize, 6, 3 * w + 17, 20 * w + 39, w * h - 1];
    for plane in &mut planes {
        for &i in &lamps {
            plane[i] = 1e4;
        }
    }
    let fractions = pseudo_random(w * h, 3);
    let cancel = Cancel::new();
    let mut outputs = Vec::new();
    for backend in [Backend::Gpu, Backend::Cpu] {
        let mut control = Control::quiet(&cancel);
        let built = engine(
            (backend, Precision::Single),
            &slices,
            (kw, kh),
            (w, h),
            Centre::Leave,
            &mut control,
        )
        .unwrap();
        for radius in [3, 6] {
            assert!(built.split_near(&slices, radius, &mut control).unwrap());
            assert!(built.has_split(radius));
            let rgb: Vec<Spread> = planes
                .iter()
                .enumerate()
                .map(|(c, plane)| Spread {
                    plane,
                    fractions: Some(&fractions),
                    terms: Term::alone(c),
                    lamps: &lamps,
                })
                .collect();
            let weighted = [luminance(&planes[1], &lamps)];
            let mut spread = built.spread(&rgb, Vec::new(), &mut control).unwrap();
            spread.extend(built.spread(&weighted, Vec::new(), &mut control).unwrap());
            outputs.push(spread);
        }
    }
    let (gpu, cpu) = outputs.split_at(2);
    for (g, c) in gpu.iter().flatten().zip(cpu.iter().flatten()) {
        let error = relative_l2(g, c);
        assert!(error < 1e-5, "split: relative L2 {error:e}");
    }
}

#[test]
fn bloom_corona_and_an_aperture_on_the_gpu_match_the_cpu() {
    if !gpu_present("bloom_corona_and_an_aperture_on_the_gpu_match_the_cpu") {
        return;
    }
    let (w, h) = (160, 90);
    let image = facade(w, h);
    for preset in ["paper-fig4-bloom", "paper-fig5-corona", "camera-f8-7blade"] {
        let kernel = kernel_of(preset, (w, h));
        let gpu = Plan::with_kernel_on(kernel.clone(), (w, h), Device::Gpu).unwrap();
        let cpu = Plan::with_kernel_on(kernel, (w, h), Device::Cpu).unwrap();
        assert!(gpu.device().starts_with("the GPU"), "{}", gpu.device());
        let (on_gpu, on_cpu) = (apply(&gpu, &image), apply(&cpu, &image));
        assert_eq!(on_gpu.arithmetic, Arithmetic::Single, "{preset}");
        assert_eq!(on_gpu.device, gpu.device());
        for (g, c) in on_gpu.image.planes.iter().zip(&on_cpu.image.planes) {
            let error = relative_l2(g, c);
            assert!(error < 1e-5, "{preset}: relative L2 {error:e}");
            let worst = worst_relative(g, c);
            assert!(worst < 1e-4, "{preset}: worst pixel {worst:e}");
        }
        let again = apply(&gpu, &image);
        assert!(
            again.image.planes == on_gpu.image.planes,
            "{preset}: two runs on one device differ"
        );
    }
}

#[test]
fn a_night_street_through_a_gpu_plan_keeps_its_dark_pixels() {
    if !gpu_present("a_night_street_through_a_gpu_plan_keeps_its_dark_pixels") {
        return;
    }
    // Lamps 10⁷ times the street: their light near them goes apart from
    // the transform (docs/physics.md §8) on the GPU as on the CPU, and
    // every pixel keeps the bound the CPU's route keeps against f64
    // (3·10⁻⁴ each, so the two within 10⁻³ of each other).
    let (w, h) = (128, 72);
    let image = night_street(w, h);
    let kernel = kernel_of("camera-f8-7blade", (w, h));
    let gpu = Plan::with_kernel_on(kernel.clone(), (w, h), Device::Gpu).unwrap();
    let cpu = Plan::with_kernel_on(kernel, (w, h), Device::Cpu).unwrap();
    let on_gpu = apply(&gpu, &image);
    let on_cpu = apply(&cpu, &image);
    assert!(
        matches!(on_gpu.arithmetic, Arithmetic::Lamps(_)),
        "{:?}",
        on_gpu.arithmetic
    );
    assert_eq!(on_gpu.arithmetic, on_cpu.arithmetic);
    assert!(on_gpu.device.starts_with("the GPU"), "{}", on_gpu.device);
    for (g, c) in on_gpu.image.planes.iter().zip(&on_cpu.image.planes) {
        let worst = worst_relative(g, c);
        assert!(worst < 1e-3, "night street: worst pixel {worst:e}");
    }
}

#[test]
fn a_cancelled_gpu_run_stops() {
    if !gpu_present("a_cancelled_gpu_run_stops") {
        return;
    }
    let (w, h) = (64, 48);
    let kernel = kernel_of("paper-fig4-bloom", (w, h));
    let plan = Plan::with_kernel_on(kernel, (w, h), Device::Gpu).unwrap();
    let cancel = Cancel::new();
    cancel.cancel();
    let outcome = plan.apply_with(
        &facade(w, h),
        1.0,
        &ApplyOptions::default(),
        Vec::new(),
        &mut Control::quiet(&cancel),
    );
    assert!(matches!(outcome, Err(Error::Cancelled)), "{outcome:?}");
}

#[test]
fn auto_never_takes_a_software_adapter() {
    let (backend, words) = aureole::convolve::choose(Device::Auto).unwrap();
    if let Some(software) = aureole::convolve::software_adapter() {
        assert_eq!(backend, Backend::Cpu);
        assert!(words.contains(&software), "{words}");
    }
    let (cpu, said) = aureole::convolve::choose(Device::Cpu).unwrap();
    assert_eq!((cpu, said.as_str()), (Backend::Cpu, "the CPU"));
}

/// A star filter's two families of lines on a round stop, in one
/// wavelength: its orders are spread over the kernel by one convolution.
const STAR_FILTER: &str = r#"
[camera]
sensor_width_mm = 36.0
focal_length_mm = 50.0
f_number = 5.6

[[effect]]
type = "aperture"
blades = 0
spectral = false
wavelength_nm = 550.0

[[effect.filter]]
angle_deg = 45.0
spacing_um = 150.0
width_um = 15.0

[[effect.filter]]
angle_deg = 135.0
spacing_um = 150.0
width_um = 15.0
"#;

#[test]
fn kernels_compose_on_the_gpu_as_on_the_cpu() {
    if !gpu_present("kernels_compose_on_the_gpu_as_on_the_cpu") {
        return;
    }
    let preset = |name: &str| aureole::presets::find(name).unwrap().config().unwrap();
    let street =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/night-street.toml");
    // Bloom ⊛ corona; bloom ⊛ a spectral 7-blade stop (the night street's
    // lens); a star filter's orders.
    let chains = [
        ("paper-fig5-both", preset("paper-fig5-both")),
        (
            "night-street.toml",
            aureole::ConfigFile::load(&street).unwrap(),
        ),
        (
            "a star filter",
            aureole::ConfigFile::parse(STAR_FILTER, "star filter").unwrap(),
        ),
    ];
    let extent = aureole::Extent::for_image(121, 71).unwrap();
    let cancel = Cancel::new();
    for (name, file) in chains {
        let mut config = Config::default();
        config.merge(file);
        let build = |composing: &mut aureole::Composing| {
            config
                .kernel_on(&extent, composing, &mut Control::quiet(&cancel))
                .unwrap()
        };
        let mut on_gpu = aureole::Composing::on(Device::Gpu).unwrap();
        let gpu = build(&mut on_gpu);
        let words = on_gpu.words().unwrap_or_default();
        assert!(
            words.starts_with("the GPU"),
            "{name}: composed on {words:?}"
        );
        let cpu = build(&mut aureole::Composing::cpu());
        assert_eq!(gpu.planes().len(), cpu.planes().len(), "{name}");
        assert!(
            gpu.planes() != cpu.planes(),
            "{name}: nothing composed on the GPU"
        );
        for (c, (g, k)) in gpu.planes().iter().zip(cpu.planes()).enumerate() {
            let error = relative_l2(g, k);
            assert!(error < 1e-5, "{name}, plane {c}: relative L2 {error:e}");
            assert!(g.iter().all(|v| *v >= 0.0), "{name}: negative light");
            assert!(
                (gpu.sum(c) - cpu.sum(c)).abs() < 1e-6,
                "{name}: Σ = {} on the GPU, {} on the CPU",
                gpu.sum(c),
                cpu.sum(c)
            );
        }
    }
}

#[test]
fn a_composition_on_the_gpu_gives_the_same_bytes_every_time() {
    if !gpu_present("a_composition_on_the_gpu_gives_the_same_bytes_every_time") {
        return;
    }
    let (w, h) = (241, 141);
    let plane = pseudo_random(w * h, 11);
    let kernel = pseudo_random(61 * 45, 12);
    let cancel = Cancel::new();
    let compose = || {
        aureole::convolve::compose(
            &kernel,
            (61, 45),
            &plane,
            (w, h),
            &mut aureole::Composing::on(Device::Gpu).unwrap(),
            &mut Control::quiet(&cancel),
        )
        .unwrap()
    };
    let first = compose();
    assert!(compose() == first, "two compositions on one device differ");
}
