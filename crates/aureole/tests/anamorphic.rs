//! Anamorphic lenses: cylindrical and toric surfaces traced against an
//! independent tracer (optiland's toroidal surface), their two focal
//! lengths against the lensmaker's equation in each plane, and the
//! shipped rear anamorphic's prime, foci and squeeze.

use aureole::lens::trace::{Layout, Path, Ray};
use aureole::lens::{Lens, D_LINE_NM};

mod moments;
use moments::moments;

/// A singlet with a torus and a cylinder: the same file optiland traces
/// (tests/reference/optiland_anamorphic.py).
const TORIC: &str = include_str!("reference/toric-singlet.toml");

const ANAMORPHIC: &str = "anamorphic-rear-1.3x-f1.8";

fn lens(name: &str) -> Lens {
    if name == ANAMORPHIC {
        let path = format!("{}/lenses/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).unwrap();
        Lens::parse(&text, &path).unwrap_or_else(|e| panic!("{e}"))
    } else {
        Lens::parse(TORIC, "toric.toml").unwrap_or_else(|e| panic!("{e}"))
    }
}

/// Where optiland 0.6.3 lands rays (tests/reference/optiland_anamorphic.py):
/// lens, field angles right and up (degrees), pupil point (units of its
/// radius), landing point on the plane the last thickness reaches (mm).
type Landing = (&'static str, (f64, f64), (f64, f64), (f64, f64));

#[rustfmt::skip]
const OPTILAND: &[Landing] = &[
    ("anamorphic-rear-1.3x-f1.8", (0.0, 0.0), (0.0, 0.0), (0.0, 0.0)),
    ("anamorphic-rear-1.3x-f1.8", (0.0, 0.0), (0.0, 0.6), (0.0, -0.008574207236)),
    ("anamorphic-rear-1.3x-f1.8", (0.0, 0.0), (0.6, 0.0), (0.005341607963, 0.0)),
    ("anamorphic-rear-1.3x-f1.8", (0.0, 0.0), (-0.4, 0.3), (-0.0004838667045, -0.002766838942)),
    ("anamorphic-rear-1.3x-f1.8", (4.0, 0.0), (0.0, 0.0), (7.20329486, 0.0)),
    ("anamorphic-rear-1.3x-f1.8", (4.0, 0.0), (0.0, 0.6), (7.202381341, -0.01824810137)),
    ("anamorphic-rear-1.3x-f1.8", (4.0, 0.0), (0.6, 0.0), (7.206751282, 0.0)),
    ("anamorphic-rear-1.3x-f1.8", (4.0, 0.0), (-0.4, 0.3), (7.203208015, -0.007046615787)),
    ("anamorphic-rear-1.3x-f1.8", (0.0, 3.0), (0.0, 0.0), (0.0, 7.072719429)),
    ("anamorphic-rear-1.3x-f1.8", (0.0, 3.0), (0.0, 0.6), (0.0, 7.053226878)),
    ("anamorphic-rear-1.3x-f1.8", (0.0, 3.0), (0.6, 0.0), (-0.008825239386, 7.074281452)),
    ("anamorphic-rear-1.3x-f1.8", (0.0, 3.0), (-0.4, 0.3), (0.007803396949, 7.063584627)),
    ("anamorphic-rear-1.3x-f1.8", (5.0, -2.5), (0.0, 0.0), (9.000251492, -5.879775263)),
    ("anamorphic-rear-1.3x-f1.8", (5.0, -2.5), (0.0, 0.6), (8.996304261, -5.896259133)),
    ("anamorphic-rear-1.3x-f1.8", (5.0, -2.5), (0.6, 0.0), (8.993336251, -5.884097241)),
    ("anamorphic-rear-1.3x-f1.8", (5.0, -2.5), (-0.4, 0.3), (9.006958454, -5.888032606)),
    ("toric singlet", (0.0, 0.0), (0.0, 0.0), (0.0, 0.0)),
    ("toric singlet", (0.0, 0.0), (0.0, 0.6), (0.0, 0.9244981466)),
    ("toric singlet", (0.0, 0.0), (0.6, 0.0), (-1.274853213, 0.0)),
    ("toric singlet", (0.0, 0.0), (-0.4, 0.3), (0.8475650915, 0.4618513276)),
    ("toric singlet", (4.0, 0.0), (0.0, 0.0), (6.997149384, 0.0)),
    ("toric singlet", (4.0, 0.0), (0.0, 0.6), (6.995439019, 0.9166211537)),
    ("toric singlet", (4.0, 0.0), (0.6, 0.0), (5.697227846, 0.0)),
    ("toric singlet", (4.0, 0.0), (-0.4, 0.3), (7.870338662, 0.4576986035)),
    ("toric singlet", (0.0, 3.0), (0.0, 0.0), (0.0, 5.517051896)),
    ("toric singlet", (0.0, 3.0), (0.0, 0.6), (0.0, 6.431367085)),
    ("toric singlet", (0.0, 3.0), (0.6, 0.0), (-1.284108403, 5.520701312)),
    ("toric singlet", (0.0, 3.0), (-0.4, 0.3), (0.8532586908, 5.975435855)),
    ("toric singlet", (5.0, -2.5), (0.0, 0.0), (8.748999138, -4.592520743)),
    ("toric singlet", (5.0, -2.5), (0.0, 0.6), (8.754500272, -3.687364768)),
    ("toric singlet", (5.0, -2.5), (0.6, 0.0), (7.425896466, -4.580792661)),
    ("toric singlet", (5.0, -2.5), (-0.4, 0.3), (9.644218571, -4.151881657)),
];

#[test]
fn rays_through_cylinders_and_tori_land_where_optiland_lands_them() {
    let mut worst: f64 = 0.0;
    for &(name, (ax, ay), pupil, (x, y)) in OPTILAND {
        // optiland clips no ray: neither here.
        let mut lens = lens(name);
        for s in &mut lens.surfaces {
            s.semi_aperture = 1e3;
        }
        let image = lens.surfaces.iter().map(|s| s.thickness).sum();
        let (pupil_z, diameter) = if name == ANAMORPHIC {
            (lens.paraxial().unwrap().entrance_pupil, 40.0)
        } else {
            (0.0, 10.0)
        };
        let layout = Layout::with_image(&lens, image, (pupil_z, diameter / 2.0));
        let field = aureole::lens::ghost::direction(ax, ay);
        let ray: Ray = layout.collimated(field, pupil);
        let (at, weight) = layout
            .trace(Path::Direct, ray, D_LINE_NM)
            .unwrap_or_else(|| panic!("{name} {ax}°, {ay}° {pupil:?}: stopped"));
        assert!(weight > 0.5 && weight < 1.0, "{weight}");
        let error = ((at[0] - x).powi(2) + (at[1] - y).powi(2)).sqrt();
        worst = worst.max(error);
        assert!(
            error < 1e-4,
            "{name} {ax}°, {ay}° {pupil:?}: {at:?} against ({x}, {y})"
        );
    }
    // Their printed digits, not the tracers, set this.
    assert!(worst < 1e-7, "{worst}");
}

#[test]
fn each_plane_has_its_own_lensmakers_focal_length() {
    // A thick lens in air: 1/f = (n − 1)[c₁ − c₂ + (n − 1) d c₁ c₂ / n],
    // each plane with its own curvatures.
    let lens = lens("toric");
    let (n, d) = (1.6, 6.0);
    let f = |c1: f64, c2: f64| 1.0 / ((n - 1.0) * (c1 - c2 + (n - 1.0) * d * c1 * c2 / n));
    let (x, y) = (lens.paraxial_x().unwrap(), lens.paraxial().unwrap());
    let (fx, fy) = (f(1.0 / 60.0, -1.0 / 150.0), f(1.0 / 90.0, 0.0));
    assert!(
        (x.focal_length / fx - 1.0).abs() < 1e-12,
        "{} {fx}",
        x.focal_length
    );
    assert!(
        (y.focal_length / fy - 1.0).abs() < 1e-12,
        "{} {fy}",
        y.focal_length
    );
    assert!((lens.squeeze().unwrap() - fy / fx).abs() < 1e-12);
    assert!(lens.is_anamorphic());
    // Real rays near the axis land f·tan θ off it in that plane's focus,
    // each way with its own f.
    let last: f64 = lens
        .surfaces
        .iter()
        .rev()
        .skip(1)
        .map(|s| s.thickness)
        .sum();
    let small = 0.01;
    for (ax, ay, expected, focus) in [
        (small, 0.0, (fx, 0.0), x.back_focus),
        (0.0, small, (0.0, fy), y.back_focus),
    ] {
        let layout = Layout::with_image(&lens, last + focus, (0.0, 10.0));
        let ray = layout.collimated(aureole::lens::ghost::direction(ax, ay), (0.0, 0.0));
        let (at, _) = layout.trace(Path::Direct, ray, D_LINE_NM).unwrap();
        let t = libm::tan(small.to_radians());
        for (got, f) in [(at[0], expected.0), (at[1], expected.1)] {
            assert!(
                (got - f * t).abs() < 1e-6 * (1.0 + f * t),
                "{got} {}",
                f * t
            );
        }
    }
}

#[test]
fn the_shipped_anamorphic_is_its_patents_prime_with_both_planes_focused_together() {
    let lens = lens(ANAMORPHIC);
    // The prime alone, as US 2,701,982 gives it, normalised to f = 100.
    let round = lens.surfaces.iter().take_while(|s| s.is_round()).count();
    let mut prime = lens.clone();
    prime.surfaces.truncate(round);
    let f = prime.paraxial().unwrap().focal_length;
    assert!((f / 100.0 - 1.0).abs() < 0.005, "{f}");
    let (x, y) = (lens.paraxial_x().unwrap(), lens.paraxial().unwrap());
    assert!(
        (x.back_focus - y.back_focus).abs() < 1e-3,
        "{} {}",
        x.back_focus,
        y.back_focus
    );
    // It squeezes the horizontal: a shorter focal length across x.
    let squeeze = lens.squeeze().unwrap();
    assert!((squeeze - 1.30).abs() < 0.01, "{squeeze}");
    // The stop is in front of the cylinders: both planes see one pupil.
    assert!((x.entrance_pupil - y.entrance_pupil).abs() < 1e-9);
    assert!((x.entrance_pupil_radius - y.entrance_pupil_radius).abs() < 1e-9);
}

/// Each ghost of `lens` of a source in direction `field` drawn alone on
/// `sensor`: its path, light over the image's, and [`moments`].
fn ghosts(
    lens: &Lens,
    field: [f64; 3],
    sensor: &aureole::lens::ghost::Sensor,
) -> Vec<(Path, f64, [f64; 5])> {
    use aureole::lens::ghost::{add_ghost, direct_light};
    let layout = Layout::new(lens).unwrap();
    let direct = direct_light(&layout, field, 550.0);
    layout
        .ghosts()
        .into_iter()
        .map(|path| {
            let mut plane = vec![0.0; sensor.width * sensor.height];
            let light = add_ghost(
                &layout,
                path,
                (field, 550.0),
                (direct, 1.0),
                sensor,
                &mut plane,
            );
            (path, light, moments(&plane, sensor))
        })
        .filter(|(_, light, _)| *light > 1e-7)
        .collect()
}

#[test]
fn an_anamorphic_lens_throws_streaks_where_a_round_one_throws_discs() {
    use aureole::lens::ghost::{direction, Sensor};
    let sensor = Sensor::centred(800, 800, 0.125);
    let anamorphic = lens(ANAMORPHIC);
    // Its cylinders are as symmetric as a rectangle: a source on the axis
    // throws every ghost about the centre, one on the horizontal every
    // ghost about the horizontal.
    let on_axis = ghosts(&anamorphic, direction(0.0, 0.0), &sensor);
    let aside = ghosts(&anamorphic, direction(5.0, 0.0), &sensor);
    for (traced, on_the_axis) in [(&on_axis, true), (&aside, false)] {
        assert!(traced.len() > 100, "{}", traced.len());
        // A ghost cut by the frame's edge has its centroid off the line.
        let whole = traced.iter().filter(|(_, light, m)| m[4] > 0.999 * light);
        for (path, _, [x, y, ..]) in whole {
            assert!(y.abs() < 1e-9, "{path:?}: {y}");
            assert!(!on_the_axis || x.abs() < 1e-9, "{path:?}: {x}");
        }
    }
    // A ghost brought to a focus by the surfaces curved across y but not
    // by those curved across x is a line along x: the streak.
    let streaks = on_axis
        .iter()
        .filter(|(_, light, [.., wide, tall, _])| *light > 5e-6 && *wide > 10.0 * tall)
        .count();
    assert!(streaks >= 1, "{on_axis:?}");
    // A round lens's ghosts of a source on the axis are discs.
    let round = Lens::parse(
        include_str!("../lenses/double-gauss-50mm-f1.4.toml"),
        "double-gauss",
    )
    .unwrap();
    for (path, _, [.., wide, tall, _]) in ghosts(&round, direction(0.0, 0.0), &sensor) {
        assert!((wide / tall - 1.0).abs() < 1e-3, "{path:?}: {wide} {tall}");
    }
}

#[test]
fn a_streaks_light_is_its_rays_light_summed_over_the_pupil() {
    // The bundle draws a ghost with the irradiance of its area change;
    // the light it draws must be the light its rays carry, summed over a
    // fine grid of the pupil with every aperture clipping them.
    use aureole::lens::ghost::{direct_light, direction, Sensor};
    let lens = lens(ANAMORPHIC);
    let layout = Layout::new(&lens).unwrap();
    let sensor = Sensor::centred(800, 800, 0.125);
    let field = direction(2.0, 1.0);
    let direct = direct_light(&layout, field, 550.0);
    let drawn = ghosts(&lens, field, &sensor);
    let brightest = drawn
        .iter()
        .filter(|(_, _, [.., wide, tall, _])| wide > &(5.0 * tall))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    let (cells, half) = (400, 1.3);
    let step = 2.0 * half / cells as f64;
    let sum = |path: Path| -> f64 {
        (0..cells * cells)
            .map(|k| {
                let p = (
                    -half + step * ((k % cells) as f64 + 0.5),
                    -half + step * ((k / cells) as f64 + 0.5),
                );
                let ray = layout.collimated(field, p);
                layout.trace(path, ray, 550.0).map_or(0.0, |(_, w)| w)
            })
            .sum()
    };
    let ratio = sum(brightest.0) / sum(Path::Direct);
    assert!(
        (brightest.1 / ratio - 1.0).abs() < 0.01,
        "{:?}: drawn {} against {ratio} summed",
        brightest.0,
        brightest.1
    );
    assert!(direct > 0.0);
}
