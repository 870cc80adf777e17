//! The eye's disability glare by the CIE's general equation (`type =
//! "eye"`): the equation as the standard prints it, its light over the
//! hemisphere, its agreement with Stiles–Holladay, and the kernel's
//! fall-off, centre and light against it.

// References, not the library: the platform's maths (clippy.toml refuses
// it in the core) is as good as libm here, and apart from the library's.
#![allow(clippy::disallowed_methods)]

use aureole::kernel::{Extent, Sending};
use aureole::{CameraGeometry, Config, Effect, Eye, Kernel};

/// The general disability glare equation as CIE 146:2002 prints it,
/// written out here apart from the library's: L_veil/E_glare, sr⁻¹, at θ
/// degrees, age A in years, pigmentation p.
fn printed(theta: f64, a: f64, p: f64) -> f64 {
    let age = 1.0 + 1.6 * (a / 70.0).powi(4);
    let young = 1.0 - 0.08 * (a / 70.0).powi(4);
    let core = 9.2e6 / (1.0 + (theta / 0.0046).powi(2)).powf(1.5)
        + 1.5e5 / (1.0 + (theta / 0.045).powi(2)).powf(1.5);
    let halo = 400.0 / (1.0 + (theta / 0.1).powi(2)) + 3e-8 * theta.powi(2);
    let iris = 1300.0 / (1.0 + (theta / 0.1).powi(2)).powf(1.5)
        + 0.8 / (1.0 + (theta / 0.1).powi(2)).powf(0.5);
    young * core + age * (halo + p * iris) + 2.5e-3 * p
}

#[test]
fn the_equation_is_the_standards_printed_formula() {
    for a in [20.0, 25.0, 45.0, 70.0, 85.0] {
        for p in [0.0, 0.5, 1.0, 1.2] {
            let eye = Eye {
                age: a,
                pigmentation: p,
            };
            for theta in [
                0.001, 0.01, 0.05, 0.1, 0.5, 1.0, 3.0, 10.0, 30.0, 60.0, 100.0,
            ] {
                let (ours, theirs) = (eye.veiling(theta), printed(theta, a, p));
                assert!(
                    (ours / theirs - 1.0).abs() < 1e-6,
                    "A {a}, p {p}, {theta}°: {ours} against {theirs}"
                );
            }
        }
    }
}

#[test]
fn a_young_dark_eyes_psf_holds_its_light_and_older_lighter_eyes_scatter_more() {
    // The equation's first terms are the young eye's point spread: over
    // the hemisphere, A = 25 and p = 0, it holds the light it got.
    let young = Eye {
        age: 25.0,
        pigmentation: 0.0,
    };
    let light = young.hemisphere();
    assert!((light - 1.0).abs() < 0.01, "{light}");
    // Age and a light iris add straylight beyond the core.
    let old = Eye {
        age: 70.0,
        pigmentation: 1.0,
    };
    let beyond = |eye: &Eye| 1.0 - eye.within(0.1) / eye.hemisphere();
    assert!(beyond(&old) > 1.2 * beyond(&young));
}

#[test]
fn the_young_curve_meets_stiles_holladay_between_one_and_thirty_degrees() {
    // CIE 146 extends the Stiles–Holladay 10/θ² (1° to 30°): a 25-year-old
    // brown eye's curve stays within a factor 2 of it there and crosses it.
    let eye = Eye {
        age: 25.0,
        pigmentation: 0.5,
    };
    let ratio = |theta: f64| eye.veiling(theta) * theta * theta / 10.0;
    for theta in [1.0, 2.0, 3.0, 5.0, 10.0, 20.0, 30.0] {
        let r = ratio(theta);
        assert!(r > 0.5 && r < 2.0, "{theta}°: {r}");
    }
    assert!(ratio(2.0) > 1.0 && ratio(3.0) < 1.0);
}

fn kernel(eye: Eye, size: usize) -> Kernel {
    let config = Config {
        camera: CameraGeometry {
            sensor_width_mm: Some(36.0),
            focal_length_mm: Some(50.0),
            f_number: None,
            ..CameraGeometry::default()
        },
        effects: vec![Effect::Eye(eye)],
        ..Config::default()
    };
    let extent = Extent::new(size, size)
        .unwrap()
        .with_image_width(size - 1)
        .sent_by(Sending::Point);
    config.kernel(&extent).unwrap()
}

#[test]
fn the_kernel_falls_as_the_equation_per_solid_angle_and_holds_its_light() {
    // 36 mm over 400 px behind a 50 mm lens: 0.09 mm pitch, 19.8° at 200 px.
    let eye = Eye {
        age: 70.0,
        pigmentation: 1.0,
    };
    let k = kernel(eye.clone(), 401);
    let theta = |r: f64| (r * 0.09 / 50.0).atan();
    let model = |r: f64| eye.veiling(theta(r).to_degrees()) * theta(r).cos().powi(3);
    let reference = f64::from(k.at(0, 10, 0)) / model(10.0);
    for r in [5, 20, 50, 100, 150, 200] {
        let ratio = f64::from(k.at(0, r, 0)) / model(r as f64) / reference;
        assert!((ratio - 1.0).abs() < 0.02, "r {r}: {ratio}");
    }
    // The centre keeps what the equation puts within the centre pixel (a
    // disc of its area).
    let pixel = (0.09f64 / 50.0 / std::f64::consts::PI.sqrt()).to_degrees();
    let centre = eye.within(pixel) / eye.hemisphere();
    assert!((f64::from(k.at(0, 0, 0)) - centre).abs() < 1e-6);
    // What the window misses is the equation's light beyond its inscribed
    // circle (19.8°) less what lies in its corners, beyond the
    // circumscribed one (27.0°) at most.
    let missing = 1.0 - k.planes()[0].iter().map(|&v| f64::from(v)).sum::<f64>();
    let beyond = |degrees: f64| {
        let steps = 20_000;
        let h = (90.0 - degrees) / steps as f64;
        (0..steps)
            .map(|i| {
                let t = degrees + (i as f64 + 0.5) * h;
                eye.veiling(t) * std::f64::consts::TAU * t.to_radians().sin() * h.to_radians()
            })
            .sum::<f64>()
            / eye.hemisphere()
    };
    let (inscribed, circumscribed) = (
        theta(200.0).to_degrees(),
        theta(200.0 * 2f64.sqrt()).to_degrees(),
    );
    assert!(
        missing < beyond(inscribed) && missing > beyond(circumscribed),
        "{missing}: {} {}",
        beyond(inscribed),
        beyond(circumscribed)
    );
}
