//! Lens ghosts, traced: real rays through a prescription against an
//! independent tracer (optiland), and the light of every ghost of a stack
//! of plates against the analytic product of its reflectances and
//! transmittances.

use aureole::lens::trace::{Layout, Path, Ray};
use aureole::lens::Lens;

mod moments;

fn shipped(name: &str) -> Lens {
    let path = format!("{}/lenses/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    Lens::parse(&text, &path).unwrap()
}

/// Where optiland 0.6.3 lands rays (tests/reference/optiland_rays.py):
/// lens, entrance pupil diameter (mm), field angle along y (degrees),
/// pupil point (units of its radius), landing point on the image plane
/// at the paraxial focus (mm).
type Landing = (&'static str, f64, f64, (f64, f64), (f64, f64));

#[rustfmt::skip]
const OPTILAND: &[Landing] = &[
    ("double-gauss-50mm-f1.4", 30.0, 0.0, (0.0, 0.0), (0.0, 0.0)),
    ("double-gauss-50mm-f1.4", 30.0, 0.0, (0.0, 0.7), (0.0, -0.0155651758)),
    ("double-gauss-50mm-f1.4", 30.0, 0.0, (0.0, -0.7), (0.0, 0.0155651758)),
    ("double-gauss-50mm-f1.4", 30.0, 0.0, (0.7, 0.0), (-0.0155651758, 0.0)),
    ("double-gauss-50mm-f1.4", 30.0, 0.0, (0.5, 0.5), (-0.0111173556, -0.0111173556)),
    ("double-gauss-50mm-f1.4", 30.0, 10.0, (0.0, 0.0), (0.0, 8.78725547)),
    ("double-gauss-50mm-f1.4", 30.0, 10.0, (0.0, 0.7), (0.0, 8.77590283)),
    ("double-gauss-50mm-f1.4", 30.0, 10.0, (0.0, -0.7), (0.0, 8.78166163)),
    ("double-gauss-50mm-f1.4", 30.0, 10.0, (0.7, 0.0), (-0.015719163, 8.77900522)),
    ("double-gauss-50mm-f1.4", 30.0, 10.0, (0.5, 0.5), (-0.0138985223, 8.77635667)),
    ("double-gauss-50mm-f1.4", 30.0, 20.0, (0.0, 0.0), (0.0, 17.9650304)),
    ("double-gauss-50mm-f1.4", 30.0, 20.0, (0.0, 0.7), (0.0, 17.9830185)),
    ("double-gauss-50mm-f1.4", 30.0, 20.0, (0.0, -0.7), (0.0, 17.9801365)),
    ("double-gauss-50mm-f1.4", 30.0, 20.0, (0.7, 0.0), (0.0417278345, 17.9369434)),
    ("double-gauss-50mm-f1.4", 30.0, 20.0, (0.5, 0.5), (0.0132485604, 17.9727438)),
    ("telephoto-300mm-f2.8", 90.0, 0.0, (0.0, 0.0), (0.0, 0.0)),
    ("telephoto-300mm-f2.8", 90.0, 0.0, (0.0, 0.7), (0.0, 0.000661224449)),
    ("telephoto-300mm-f2.8", 90.0, 0.0, (0.0, -0.7), (0.0, -0.000661224449)),
    ("telephoto-300mm-f2.8", 90.0, 0.0, (0.7, 0.0), (0.000661224449, 0.0)),
    ("telephoto-300mm-f2.8", 90.0, 0.0, (0.5, 0.5), (0.00048656142, 0.00048656142)),
    ("telephoto-300mm-f2.8", 90.0, 1.5, (0.0, 0.0), (0.0, 7.6919606)),
    ("telephoto-300mm-f2.8", 90.0, 1.5, (0.0, 0.7), (0.0, 7.69036665)),
    ("telephoto-300mm-f2.8", 90.0, 1.5, (0.0, -0.7), (0.0, 7.68968027)),
    ("telephoto-300mm-f2.8", 90.0, 1.5, (0.7, 0.0), (0.000365968324, 7.69068384)),
    ("telephoto-300mm-f2.8", 90.0, 1.5, (0.5, 0.5), (-0.000860135665, 7.6909387)),
    ("telephoto-300mm-f2.8", 90.0, 3.0, (0.0, 0.0), (0.0, 15.4429753)),
    ("telephoto-300mm-f2.8", 90.0, 3.0, (0.0, 0.7), (0.0, 15.4409517)),
    ("telephoto-300mm-f2.8", 90.0, 3.0, (0.0, -0.7), (0.0, 15.4726962)),
    ("telephoto-300mm-f2.8", 90.0, 3.0, (0.7, 0.0), (-0.00143503386, 15.4414617)),
    ("telephoto-300mm-f2.8", 90.0, 3.0, (0.5, 0.5), (-0.00245200011, 15.4414634)),
];

#[test]
fn real_rays_land_where_optiland_lands_them() {
    let mut worst: f64 = 0.0;
    for &(name, diameter, degrees, pupil, (x, y)) in OPTILAND {
        // optiland clips no ray: neither here, each surface as wide as
        // its sphere allows.
        let mut lens = shipped(name);
        for s in &mut lens.surfaces {
            s.semi_aperture = s.radius.map_or(1e3, f64::abs);
        }
        let focus = Layout::new(&lens).unwrap();
        let layout = Layout::with_image(&lens, focus.image, (focus.pupil.0, diameter / 2.0));
        let angle = degrees.to_radians();
        let field = [0.0, libm::sin(angle), libm::cos(angle)];
        let ray: Ray = layout.collimated(field, pupil);
        let (at, weight) = layout
            .trace(Path::Direct, ray, aureole::lens::D_LINE_NM)
            .unwrap_or_else(|| panic!("{name} {degrees}° {pupil:?}: stopped"));
        assert!(weight > 0.8 && weight < 1.0, "{weight}");
        let error = ((at[0] - x).powi(2) + (at[1] - y).powi(2)).sqrt();
        worst = worst.max(error);
        assert!(
            error < 1e-4,
            "{name} {degrees}° {pupil:?}: {at:?} against ({x}, {y})"
        );
    }
    // Their printed digits, not the tracers, set this.
    assert!(worst < 2e-6, "{worst}");
}

/// Where optiland lands rays along ghost paths (the same script): the
/// path unfolded into mirrors, the rays started on the lines aureole
/// starts them on. Lens, pupil diameter, (first, second) reflecting
/// surfaces, field angle along y, pupil point, landing point.
type GhostLanding = (
    &'static str,
    f64,
    (usize, usize),
    f64,
    (f64, f64),
    (f64, f64),
);

#[rustfmt::skip]
const OPTILAND_GHOSTS: &[GhostLanding] = &[
    ("double-gauss-50mm-f1.4", 20.0, (1, 4), 0.0, (0.0, 0.0), (0.0, 0.0)),
    ("double-gauss-50mm-f1.4", 20.0, (1, 4), 0.0, (0.0, 0.5), (0.0, -1.60399608)),
    ("double-gauss-50mm-f1.4", 20.0, (1, 4), 0.0, (0.4, 0.0), (-1.25452234, 0.0)),
    ("double-gauss-50mm-f1.4", 20.0, (1, 4), 0.0, (-0.3, 0.2), (0.933886063, -0.622590709)),
    ("double-gauss-50mm-f1.4", 20.0, (1, 4), 5.0, (0.0, 0.0), (0.0, 5.40304638)),
    ("double-gauss-50mm-f1.4", 20.0, (1, 4), 5.0, (0.0, 0.5), (0.0, 3.84328889)),
    ("double-gauss-50mm-f1.4", 20.0, (1, 4), 5.0, (0.4, 0.0), (-1.29062561, 5.41540539)),
    ("double-gauss-50mm-f1.4", 20.0, (1, 4), 5.0, (-0.3, 0.2), (0.945093891, 4.78426925)),
    ("double-gauss-50mm-f1.4", 20.0, (4, 5), 0.0, (0.0, 0.0), (0.0, 0.0)),
    ("double-gauss-50mm-f1.4", 20.0, (4, 5), 0.0, (0.0, 0.5), (0.0, 24.3470121)),
    ("double-gauss-50mm-f1.4", 20.0, (4, 5), 0.0, (0.4, 0.0), (18.5598314, 0.0)),
    ("double-gauss-50mm-f1.4", 20.0, (4, 5), 0.0, (-0.3, 0.2), (-13.7419363, 9.16129087)),
    ("double-gauss-50mm-f1.4", 20.0, (4, 5), 5.0, (0.0, 0.0), (0.0, -0.519318845)),
    ("double-gauss-50mm-f1.4", 20.0, (4, 5), 5.0, (0.0, 0.5), (0.0, 23.0843566)),
    ("double-gauss-50mm-f1.4", 20.0, (4, 5), 5.0, (0.4, 0.0), (18.5205865, -0.45721089)),
    ("double-gauss-50mm-f1.4", 20.0, (4, 5), 5.0, (-0.3, 0.2), (-13.6075632, 8.56755219)),
    ("double-gauss-50mm-f1.4", 20.0, (0, 8), 0.0, (0.0, 0.0), (0.0, 0.0)),
    ("double-gauss-50mm-f1.4", 20.0, (0, 8), 0.0, (0.0, 0.5), (0.0, -18.6103927)),
    ("double-gauss-50mm-f1.4", 20.0, (0, 8), 0.0, (0.4, 0.0), (-14.60904, 0.0)),
    ("double-gauss-50mm-f1.4", 20.0, (0, 8), 0.0, (-0.3, 0.2), (10.8909775, -7.26065168)),
    ("double-gauss-50mm-f1.4", 20.0, (0, 8), 5.0, (0.0, 0.0), (0.0, -12.0626404)),
    ("double-gauss-50mm-f1.4", 20.0, (0, 8), 5.0, (0.0, 0.5), (0.0, -34.120852)),
    ("double-gauss-50mm-f1.4", 20.0, (0, 8), 5.0, (0.4, 0.0), (-15.0652356, -12.1305299)),
    ("double-gauss-50mm-f1.4", 20.0, (0, 8), 5.0, (-0.3, 0.2), (11.5625305, -20.0431805)),
];

#[test]
fn rays_along_ghost_paths_land_where_optiland_lands_them() {
    // optiland clips no ray, and follows some where no real lens lets
    // them go (out through the barrel, beyond a sphere's rim): the rays
    // the lens's own apertures pass are compared.
    let (mut compared, mut worst) = (0, 0.0f64);
    for &(name, diameter, (first, second), degrees, pupil, (x, y)) in OPTILAND_GHOSTS {
        let lens = shipped(name);
        let focus = Layout::new(&lens).unwrap();
        let layout = Layout::with_image(&lens, focus.image, (focus.pupil.0, diameter / 2.0));
        let angle = degrees.to_radians();
        let field = [0.0, libm::sin(angle), libm::cos(angle)];
        let path = Path::Ghost { first, second };
        let ray = layout.collimated(field, pupil);
        let Some((at, _)) = layout.trace(path, ray, aureole::lens::D_LINE_NM) else {
            continue;
        };
        let error = ((at[0] - x).powi(2) + (at[1] - y).powi(2)).sqrt();
        assert!(
            error < 1e-4,
            "{path:?} {degrees}° {pupil:?}: {at:?} against ({x}, {y})"
        );
        compared += 1;
        worst = worst.max(error);
    }
    assert!(compared >= 12, "{compared}");
    // Their printed digits, not the tracers, set this.
    assert!(worst < 2e-6, "{worst}");
}

/// Two plates behind a stop: one bare (n = 1.5), one coated on both
/// sides with a quarter wave of MgF₂ at 550 nm (n = 1.7).
const PLATES: &str = r#"
name = "two plates"
[[surface]]
stop = true
semi_aperture = 10.0
thickness = 5.0
[[surface]]
radius = "flat"
thickness = 3.0
n_d = 1.5
semi_aperture = 40.0
coating = "none"
[[surface]]
radius = "flat"
thickness = 4.0
semi_aperture = 40.0
coating = "none"
[[surface]]
radius = "flat"
thickness = 2.0
n_d = 1.7
semi_aperture = 40.0
[[surface]]
radius = "flat"
thickness = 10.0
semi_aperture = 40.0
"#;

/// Fresnel's reflectance for unpolarised light from n₁ into n₂ at θ₁ in
/// n₁, and a quarter-wave layer's at normal incidence: written here from
/// the textbook formulas, apart from the crate's thin-film code.
fn fresnel(n1: f64, n2: f64, theta1: f64) -> f64 {
    let (c1, s1) = (libm::cos(theta1), libm::sin(theta1));
    let c2 = (1.0 - (n1 * s1 / n2).powi(2)).sqrt();
    let rs = (n1 * c1 - n2 * c2) / (n1 * c1 + n2 * c2);
    let rp = (n2 * c1 - n1 * c2) / (n2 * c1 + n1 * c2);
    0.5 * (rs * rs + rp * rp)
}

fn quarter_wave(n0: f64, n_film: f64, n_sub: f64) -> f64 {
    ((n0 * n_sub - n_film * n_film) / (n0 * n_sub + n_film * n_film)).powi(2)
}

#[test]
fn every_ghost_of_a_stack_of_plates_carries_the_product_of_its_reflections() {
    let mut lens = Lens::parse(PLATES, "plates").unwrap();
    let layout = Layout::with_image(&lens, 24.0, (0.0, 10.0));
    let ghosts = layout.ghosts();
    // The stop reflects nothing: the pairs of the four glass faces.
    assert_eq!(ghosts.len(), 6);
    // Head on, at the coating's design wavelength: faces 1 and 2 reflect
    // 4 %, the coated 3 and 4 the quarter wave's share.
    let r = [
        0.0,
        0.04,
        0.04,
        quarter_wave(1.0, 1.38, 1.7),
        quarter_wave(1.0, 1.38, 1.7),
    ];
    for &path in &ghosts {
        let Path::Ghost { first, second } = path else {
            unreachable!()
        };
        let t = |s: usize| 1.0 - r[s];
        let expected = (0..second).map(t).product::<f64>()
            * r[second]
            * (first + 1..second).map(t).product::<f64>()
            * r[first]
            * (first + 1..5).map(t).product::<f64>();
        let ray = layout.collimated([0.0, 0.0, 1.0], (0.3, -0.2));
        let (_, weight) = layout.trace(path, ray, 550.0).unwrap();
        assert!(
            (weight / expected - 1.0).abs() < 1e-12,
            "{path:?}: {weight} {expected}"
        );
    }
    // At 10° through bare plates every face reflects by Fresnel at the
    // angle the ray meets it in its medium (flat faces keep the angles).
    for s in &mut lens.surfaces {
        s.coating = aureole::lens::Coating::None;
    }
    let layout = Layout::with_image(&lens, 24.0, (0.0, 10.0));
    let theta = 10f64.to_radians();
    let index = [1.0, 1.5, 1.0, 1.7, 1.0];
    let angle = |n: f64| libm::asin(libm::sin(theta) / n);
    // Face s between index[s − 1] (air before the first) and index[s].
    let before = |s: usize| if s == 0 { 1.0 } else { index[s - 1] };
    let r = |s: usize, forwards: bool| {
        let (n1, n2) = if forwards {
            (before(s), index[s])
        } else {
            (index[s], before(s))
        };
        if n1 == n2 {
            0.0
        } else {
            fresnel(n1, n2, angle(n1))
        }
    };
    let field = [0.0, libm::sin(theta), libm::cos(theta)];
    for &path in &ghosts {
        let Path::Ghost { first, second } = path else {
            unreachable!()
        };
        let expected = (0..second).map(|s| 1.0 - r(s, true)).product::<f64>()
            * r(second, true)
            * (first + 1..second)
                .map(|s| 1.0 - r(s, false))
                .product::<f64>()
            * r(first, false)
            * (first + 1..5).map(|s| 1.0 - r(s, true)).product::<f64>();
        let (_, weight) = layout
            .trace(path, layout.collimated(field, (0.0, 0.0)), 600.0)
            .unwrap();
        assert!(
            (weight / expected - 1.0).abs() < 1e-12,
            "{path:?}: {weight} {expected}"
        );
    }
}

#[test]
fn a_stack_of_plates_throws_ghosts_of_the_light_its_reflections_say() {
    use aureole::lens::ghost::{add_ghost, direct_light, Sensor};
    let lens = Lens::parse(PLATES, "plates").unwrap();
    let layout = Layout::with_image(&lens, 24.0, (0.0, 10.0));
    let sensor = Sensor::centred(400, 400, 0.1);
    let field = [0.0, 0.0, 1.0];
    let direct = direct_light(&layout, field, 550.0);
    // Through the plates every ray of the bundle passes: the pupil's area
    // less the cells the stop's rim cuts, times the four faces' T.
    let t = |r: f64| 1.0 - r;
    let coated = quarter_wave(1.0, 1.38, 1.7);
    let through = t(0.04) * t(0.04) * t(coated) * t(coated);
    let disc = std::f64::consts::PI * 100.0;
    assert!((direct / (disc * through) - 1.0).abs() < 0.03, "{direct}");
    let mut plane = vec![0.0; 400 * 400];
    let path = Path::Ghost {
        first: 1,
        second: 3,
    };
    let added = add_ghost(
        &layout,
        path,
        (field, 550.0),
        (direct, 1.0),
        &sensor,
        &mut plane,
    );
    // Face 3 sends it back, face 1 forwards again: R₃ R₁, and face 2
    // crossed twice more than the image's light crosses it.
    let expected = coated * 0.04 * t(0.04) * t(0.04);
    assert!((added / expected - 1.0).abs() < 1e-9, "{added} {expected}");
    let sum: f64 = plane.iter().sum();
    assert!((sum / expected - 1.0).abs() < 1e-9, "{sum}");
}

/// The centroid of a plane's light (mm on the image plane), its RMS
/// radius about it (mm) and the light.
fn centroid(plane: &[f64], sensor: &aureole::lens::ghost::Sensor) -> (f64, f64, f64, f64) {
    let [x, y, wide, tall, sum] = moments::moments(plane, sensor);
    (x, y, libm::hypot(wide, tall), sum)
}

#[test]
fn ghosts_lie_on_the_line_through_their_source_and_the_centre() {
    use aureole::lens::ghost::{add_ghost, direct_light, Sensor};
    let lens = shipped("double-gauss-50mm-f1.4");
    let layout = Layout::new(&lens).unwrap();
    // Wide enough to hold every ghost whole: one cut by the frame's edge
    // has its centroid off the line.
    let sensor = Sensor::centred(1000, 1000, 0.5);
    let paths = layout.ghosts();
    assert_eq!(
        paths.len(),
        13 * 12 / 2,
        "the 13 surfaces but the stop, in pairs"
    );
    let ghost = |field: [f64; 3], path| {
        let direct = direct_light(&layout, field, 550.0);
        let mut plane = vec![0.0; sensor.width * sensor.height];
        add_ghost(
            &layout,
            path,
            (field, 550.0),
            (direct, 1.0),
            &sensor,
            &mut plane,
        );
        centroid(&plane, &sensor)
    };
    let angle = |degrees: f64| degrees.to_radians();
    let towards = aureole::lens::ghost::direction;
    for &path in paths.iter().step_by(7) {
        // On the axis, centred on it.
        let (x, y, _, light) = ghost([0.0, 0.0, 1.0], path);
        assert!(
            light > 0.0 && x.abs() < 1e-6 && y.abs() < 1e-6,
            "{path:?}: {x} {y}"
        );
        // Off it, on the line through the source's image and the centre,
        // and mirrored through the centre with the source. The bundle's
        // grid lies along the source's azimuth, as symmetric as the lens,
        // and drawing keeps a ghost's centroid: on the line to rounding.
        let (x, y, size, _) = ghost(towards(6.0, 4.0), path);
        let (image_x, image_y) = (libm::tan(angle(6.0)), libm::tan(angle(4.0)));
        let across = (x * image_y - y * image_x) / libm::hypot(image_x, image_y);
        assert!(
            across.abs() < 1e-9 * size,
            "{path:?}: ({x}, {y}) {across} mm off the line"
        );
        let (mx, my, _, _) = ghost(towards(-6.0, -4.0), path);
        assert!((mx + x).abs() < 1e-6 && (my + y).abs() < 1e-6, "{path:?}");
    }
}

#[test]
fn a_hexagonal_stop_passes_the_light_of_a_hexagon() {
    use aureole::lens::ghost::direct_light;
    let lens = shipped("double-gauss-50mm-f1.4");
    let layout = Layout::new(&lens).unwrap();
    // Stopped down to half its clear aperture (f/2.9), where the front
    // group images the stop into the pupil as a scaled copy: wide open,
    // its pupil aberration stretches the rim, and a hexagon touching the
    // rim passes 1 % less than its area says.
    let stop = 0.5 * lens.surfaces[lens.stop()].semi_aperture;
    let shaped = |blades: u32| {
        let aperture = aureole::Aperture::new(blades);
        let layout = Layout::new(&lens)
            .unwrap()
            .with_stop(aperture.stop(stop), stop);
        direct_light(&layout, [0.0, 0.0, 1.0], 550.0)
    };
    let ratio = shaped(6) / shaped(0);
    let hexagon = 3.0 * 3f64.sqrt() / (2.0 * std::f64::consts::PI);
    assert!((ratio / hexagon - 1.0).abs() < 0.002, "{ratio} {hexagon}");
    drop(layout);
}

/// Every ghost of a source in direction `field` on `sensor`, in `light`,
/// without progress or cancellation.
fn rendered(
    layout: &Layout,
    field: [f64; 3],
    sensor: &aureole::lens::ghost::Sensor,
    light: &[(f64, Vec<f64>)],
) -> aureole::lens::ghost::Rendered {
    let cancel = aureole::control::Cancel::new();
    let mut control = aureole::control::Control::quiet(&cancel);
    aureole::lens::ghost::render(layout, field, sensor, light, &mut control).unwrap()
}

#[test]
fn ghosts_look_the_same_at_twice_the_resolution_reduced() {
    use aureole::lens::ghost::{direction, Sensor};
    let lens = shipped("portrait-90mm-f2");
    let layout = Layout::new(&lens).unwrap();
    let stop = lens.surfaces[lens.stop()].semi_aperture;
    let layout = layout.with_stop(aureole::Aperture::new(6).stop(stop * 0.5), stop * 0.5);
    let picture = |width: usize| {
        let sensor = Sensor::centred(width, width * 2 / 3, 36.0 / width as f64);
        let rendered = rendered(&layout, direction(5.0, 3.0), &sensor, &[(550.0, vec![1.0])]);
        rendered.planes.into_iter().next().unwrap()
    };
    let (small, large) = (picture(240), picture(480));
    // The light of each 6×6 block of the small picture against the 12×12
    // of the large one it covers: the same, to 1 % of the picture's
    // (relative L2), as tests/resolution.rs holds a lamp's glare ring by
    // ring (each picture blurs its sharp edges by a pixel of its own).
    let block = |picture: &[f64], width: usize, side: usize| {
        let mut blocks = vec![0.0; (240 / 6) * (160 / 6)];
        for (k, v) in picture.iter().enumerate() {
            let (col, row) = ((k % width) / side, (k / width) / side);
            if col < 40 && row < 26 {
                blocks[row * 40 + col] += v;
            }
        }
        blocks
    };
    let (coarse, fine) = (block(&small, 240, 6), block(&large, 480, 12));
    let norm = |a: &[f64]| a.iter().map(|v| v * v).sum::<f64>().sqrt();
    let difference: Vec<f64> = coarse.iter().zip(&fine).map(|(a, b)| a - b).collect();
    let relative = norm(&difference) / norm(&coarse);
    assert!(relative < 0.01, "{relative}");
    let mut reduced = vec![0.0; small.len()];
    for (k, v) in large.iter().enumerate() {
        reduced[(k / 480 / 2) * 240 + (k % 480) / 2] += v;
    }
    // The same light in all, but at the frame's edges: the bilinear shares
    // of its outermost pixels fall beyond it, and a large ghost's coarse
    // pixels (lens/canvas.rs) that straddle an edge keep their light
    // within it, each at its own resolution.
    let (a, b): (f64, f64) = (small.iter().sum(), reduced.iter().sum());
    assert!((a / b - 1.0).abs() < 1e-3, "{a} {b}");
}

#[test]
fn ghosts_take_their_colour_from_the_coatings_and_the_glass_dispersion_alone() {
    use aureole::lens::ghost::{direction, light, Sensor};
    use aureole::lens::Coating;
    let sensor = Sensor::centred(120, 80, 0.3);
    let picture = |lens: &Lens, spectral: bool| {
        let layout = Layout::with_image(lens, 24.0, (0.0, 10.0));
        rendered(&layout, direction(4.0, 2.0), &sensor, &light(spectral))
    };
    // Bare plates of one index at every wavelength (no v_d): grey ghosts,
    // in three wavelengths or seventeen.
    let mut grey = Lens::parse(PLATES, "plates").unwrap();
    for s in &mut grey.surfaces {
        s.coating = Coating::None;
    }
    for spectral in [false, true] {
        let planes = picture(&grey, spectral).planes;
        assert!(planes[0].iter().sum::<f64>() > 0.0);
        for plane in &planes[1..] {
            for (a, b) in plane.iter().zip(&planes[0]) {
                assert!((a - b).abs() <= 1e-12 * b.abs().max(1e-20), "{a} {b}");
            }
        }
    }
    // MgF₂ a quarter wave at 550 nm on the second plate reflects the blue
    // and the red more than the green: purple ghosts.
    let coated = picture(&Lens::parse(PLATES, "plates").unwrap(), true);
    let sum = |c: usize| coated.planes[c].iter().sum::<f64>();
    assert!(
        sum(0) > sum(1) && sum(2) > sum(1),
        "{} {} {}",
        sum(0),
        sum(1),
        sum(2)
    );
}

#[test]
fn paths_traced_together_land_as_each_traced_alone() {
    // Routes that begin alike share their first steps, and rays go side
    // by side: the same arithmetic, so the same bits as each ray traced
    // alone along its route.
    use aureole::lens::ghost::direction;
    let lens = shipped("double-gauss-50mm-f1.4");
    let layout = Layout::new(&lens).unwrap();
    let field = direction(7.0, -3.0);
    let routes: Vec<_> = layout
        .ghosts()
        .into_iter()
        .chain([Path::Direct])
        .map(|path| layout.route(path, 486.1))
        .collect();
    let rays: Vec<Ray> = (0..700)
        .map(|k| {
            let (x, y) = (
                f64::from(k % 27) / 13.0 - 1.0,
                f64::from(k / 27) / 13.0 - 1.0,
            );
            layout.collimated(field, (x, y))
        })
        .collect();
    let together = layout.follow_unclipped_routes(&routes, &rays);
    assert_eq!(together.len(), routes.len());
    for (route, arrivals) in routes.iter().zip(together) {
        let alone: Vec<_> = rays
            .iter()
            .map(|&ray| layout.follow_unclipped(route, ray))
            .collect();
        assert!(alone.iter().any(Option::is_some));
        assert_eq!(arrivals, alone);
    }
}

#[test]
fn ghosts_at_the_outer_wavelengths_match_them_traced_in_full() {
    // render() traces each bundle at the middle wavelength and the others
    // by their difference from it, every other ray each way; each
    // wavelength's ghosts traced alone, every ray, hold the same light
    // and land on the same pixels.
    use aureole::lens::ghost::{add_ghost, direct_light, direction, light, Sensor};
    let lens = shipped("portrait-90mm-f2");
    let stop = lens.surfaces[lens.stop()].semi_aperture * 0.5;
    let layout = Layout::new(&lens)
        .unwrap()
        .with_stop(aureole::Aperture::new(7).stop(stop), stop);
    let sensor = Sensor::centred(480, 320, 0.075);
    let field = direction(6.0, 4.0);
    let rgb = light(false);
    let drawn = rendered(&layout, field, &sensor, &rgb);
    for channel in [0, 2] {
        let nm = rgb[channel].0;
        let direct = direct_light(&layout, field, nm);
        let mut plane = vec![0.0; sensor.width * sensor.height];
        let light: f64 = layout
            .ghosts()
            .into_iter()
            .map(|path| {
                add_ghost(
                    &layout,
                    path,
                    (field, nm),
                    (direct, 1.0),
                    &sensor,
                    &mut plane,
                )
            })
            .sum();
        let ratio = drawn.light[channel] / light;
        assert!((ratio - 1.0).abs() < 2e-3, "channel {channel}: {ratio}");
        let apart: f64 = drawn.planes[channel]
            .iter()
            .zip(&plane)
            .map(|(a, b)| (a - b).abs())
            .sum();
        let whole: f64 = plane.iter().sum();
        assert!(apart < 0.03 * whole, "channel {channel}: {}", apart / whole);
    }
}
