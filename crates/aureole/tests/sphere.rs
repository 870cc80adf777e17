//! The eye's veil spread over the sphere (`aureole::pipeline::sphere`), tested
//! against the direct sum of the same PSF over every pair of pixels, by
//! its energy, and against the kernel a perspective camera gets where the
//! two must agree.

#![allow(clippy::disallowed_methods)]

use aureole::pipeline::sphere::spread_eye;
use aureole::{Cancel, Eye, Image, Layout, Projection, View};

fn eye(age: f64) -> Eye {
    Eye {
        age,
        pigmentation: 0.5,
    }
}

fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    2.0 * ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() / 2.0)
        .min(1.0)
        .asin()
}

/// The veil by the direct sum over every pair: the PSF at each pixel's
/// centre, averaged over the receiving pixel within five pixels.
fn direct_veil(image: &Image, view: &View, eye: &Eye, threshold: f64) -> Vec<f64> {
    let (w, h) = (image.width, image.height);
    let pixels = view.pixels(w, h);
    let norm = 1.0 / eye.sphere();
    let g = |phi: f64| eye.veiling(phi.to_degrees()) * norm;
    let mut veil = vec![0.0; w * h];
    for j in 0..w * h {
        let v = f64::from(image.planes[0][j]);
        if v <= threshold {
            continue;
        }
        let (sc, sr) = (j % w, j / w);
        let Some(source) = pixels.pixel(sc, sr) else {
            continue;
        };
        let light = v * source.solid_angle;
        for (i, out) in veil.iter_mut().enumerate() {
            if i == j {
                continue;
            }
            let (c, r) = (i % w, i / w);
            let Some(here) = pixels.pixel(c, r) else {
                continue;
            };
            let reach = (c as i64 - sc as i64)
                .abs()
                .max((r as i64 - sr as i64).abs());
            let weight = if reach <= 5 {
                let n = if reach <= 2 { 6 } else { 3 };
                let mut sum = 0.0;
                for sy in 0..n {
                    for sx in 0..n {
                        let x = c as f64 + (sx as f64 + 0.5) / n as f64;
                        let y = r as f64 + (sy as f64 + 0.5) / n as f64;
                        sum += g(angle(
                            pixels.sight_nearest(x, y).direction,
                            source.direction,
                        ));
                    }
                }
                sum / (n * n) as f64
            } else {
                g(angle(here.direction, source.direction))
            };
            *out += light * weight;
        }
    }
    veil
}

/// A dim fisheye view with lamps and a bright window.
fn scene(size: usize) -> Image {
    let mut image = Image::filled(size, size, Layout::Luminance, 1.0);
    let at = |c: usize, r: usize| r * size + c;
    for &(c, r) in &[
        (size / 2, size / 2),
        (size / 5, size / 3),
        (size * 4 / 5, size * 3 / 5),
    ] {
        image.planes[0][at(c, r)] = 2e5;
    }
    for r in size / 6..size / 6 + 5 {
        for c in size / 2..size / 2 + 8 {
            image.planes[0][at(c, r)] = 5e3;
        }
    }
    image
}

#[test]
fn the_banded_veil_is_the_direct_sums_within_two_percent() {
    for projection in [Projection::Equidistant, Projection::Equisolid] {
        let view = View::new(projection, 180.0);
        let image = scene(96);
        let e = eye(70.0);
        let spread = spread_eye(&image, 1.0, &view, &e, 100.0, 0.0, &Cancel::new()).unwrap();
        let exact = direct_veil(&image, &view, &e, 100.0);
        let mut worst: f64 = 0.0;
        let (mut total, mut total_exact) = (0.0, 0.0);
        let pixels = view.pixels(96, 96);
        for (i, &x) in exact.iter().enumerate() {
            let input = f64::from(image.planes[0][i]);
            // The image circle: within 90° of the line of sight.
            let ahead = pixels
                .pixel(i % 96, i / 96)
                .is_some_and(|s| s.direction[2] >= 0.0);
            if input > 100.0 || !ahead {
                continue;
            }
            let got = f64::from(spread.image.planes[0][i]) - input;
            total += got;
            total_exact += x;
            if x > 1e-3 {
                worst = worst.max((got / x - 1.0).abs());
            }
        }
        eprintln!(
            "{projection:?}: worst {worst:.4}, total {:.5}",
            total / total_exact - 1.0
        );
        assert!(worst < 0.02, "{projection:?}: worst relative error {worst}");
        assert!(
            (total / total_exact - 1.0).abs() < 0.005,
            "{projection:?}: {total} against {total_exact}"
        );
    }
}

#[test]
fn the_light_spread_is_the_light_lost_and_an_older_eye_veils_more() {
    let view = View::new(Projection::Equisolid, 180.0);
    let size = 201;
    let mut image = Image::filled(size, size, Layout::Luminance, 0.0);
    image.planes[0][100 * size + 100] = 1e6;
    let young = spread_eye(&image, 1.0, &view, &eye(25.0), 10.0, 0.0, &Cancel::new()).unwrap();
    let old = spread_eye(&image, 1.0, &view, &eye(70.0), 10.0, 0.0, &Cancel::new()).unwrap();
    for (s, age) in [(&young, 25.0), (&old, 70.0)] {
        // Nothing is made; what leaves the centred lamp's 180° view is the
        // equation's light beyond 90°.
        let e = eye(age);
        let expected = e.hemisphere() / e.sphere();
        let kept = s.energy_out / s.energy_in;
        assert!(kept <= 1.0, "{kept}");
        assert!(
            (kept / expected - 1.0).abs() < 0.01,
            "{kept} against {expected}"
        );
    }
    // 20° from the lamp, the veil goes as the CIE equation at 20°.
    let pixels = view.pixels(size, size);
    let lamp = pixels.pixel(100, 100).unwrap().direction;
    let (column, _) = (100..size)
        .map(|c| {
            (
                c,
                angle(pixels.pixel(c, 100).unwrap().direction, lamp).to_degrees(),
            )
        })
        .min_by(|a, b| (a.1 - 20.0).abs().total_cmp(&(b.1 - 20.0).abs()))
        .unwrap();
    let ratio =
        old.image.planes[0][100 * size + column] / young.image.planes[0][100 * size + column];
    let theta = angle(pixels.pixel(column, 100).unwrap().direction, lamp).to_degrees();
    let expected = (eye(70.0).veiling(theta) / eye(70.0).sphere())
        / (eye(25.0).veiling(theta) / eye(25.0).sphere());
    assert!(
        (f64::from(ratio) / expected - 1.0).abs() < 0.01,
        "{ratio} against {expected}"
    );
}

#[test]
fn a_narrow_perspective_view_gets_the_cameras_kernel() {
    // 20° across: the pixels' angles barely vary, and the sphere's veil is
    // the kernel's (the eye effect with [camera] for the same view).
    let size = 121;
    let fov: f64 = 20.0;
    let focal = 18.0 / (fov.to_radians() / 2.0).tan();
    let mut image = Image::filled(size, size, Layout::Luminance, 0.0);
    image.planes[0][60 * size + 60] = 1e6;
    let view = View::new(Projection::Perspective, fov);
    let spread = spread_eye(&image, 1.0, &view, &eye(25.0), 10.0, 0.0, &Cancel::new()).unwrap();
    let text = format!(
        "[camera]\nsensor_width_mm = 36.0\nfocal_length_mm = {focal}\n[[effect]]\ntype = \"eye\"\nage = 25\npigmentation = 0.5\n"
    );
    let mut config = aureole::Config::default();
    config.merge(aureole::ConfigFile::parse(&text, "eye").unwrap());
    let frame = aureole::Frame::new(image.clone(), &aureole::FrameOptions::default()).unwrap();
    let mut session = aureole::Session::new(config);
    let options = aureole::ApplyOptions {
        threshold: Some(10.0),
        ..aureole::ApplyOptions::default()
    };
    let kernel = session.apply(&frame, &options, &mut |_, _| {}).unwrap();
    // The kernel spreads light over a flat sensor, whose pixels cover
    // cos³θ of the centre's solid angle θ off the axis: divided out, it is
    // the luminance the sphere's veil gives; and it holds the equation's
    // light over the hemisphere it sees, the sphere's over every direction.
    let e = eye(25.0);
    let normalised = e.hemisphere() / e.sphere();
    let pixels = view.pixels(size, size);
    for (c, r) in [(63, 60), (70, 60), (60, 90), (100, 100), (10, 20)] {
        let cos = pixels.pixel(c, r).unwrap().direction[2];
        let a = f64::from(spread.image.planes[0][r * size + c]);
        let b = f64::from(kernel.image.planes[0][r * size + c]) / (cos * cos * cos) * normalised;
        assert!(
            (a / b - 1.0).abs() < 0.02,
            "({c}, {r}): sphere {a} against kernel {b}"
        );
    }
}

#[test]
fn a_view_whose_pixels_differ_too_much_is_refused_in_one_line() {
    let image = scene(64);
    let wide = View::new(Projection::Perspective, 160.0);
    let message = spread_eye(&image, 1.0, &wide, &eye(25.0), 100.0, 0.0, &Cancel::new())
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("differ") && !message.contains('\n'),
        "{message}"
    );
    for projection in [
        Projection::Equidistant,
        Projection::Equisolid,
        Projection::Stereographic,
    ] {
        let view = View::new(projection, 180.0);
        assert!(spread_eye(&image, 1.0, &view, &eye(25.0), 100.0, 0.0, &Cancel::new()).is_ok());
    }
}
