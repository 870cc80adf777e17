//! Film halation against its physics (docs/physics.md §10): each channel's
//! kernel sums to one and its halo takes its share from the core; the halo
//! is what rays traced through the base one by one give; its radius follows
//! the base; the backing leaves a trace; the colour warms outward.

// References and workloads, not the library: the platform's maths
// (clippy.toml refuses it in the core) is as good as libm here.
#![allow(clippy::disallowed_methods)]

use aureole::{CameraGeometry, Config, Effect, Extent, Halation, Kernel, Length, Sending};
use proptest::prelude::*;

fn halation(toml: &str) -> Halation {
    toml::from_str(toml).unwrap()
}

/// The halation kernel of a square `size` for an image `image_width` wide.
fn kernel(halation: &Halation, camera: CameraGeometry, size: usize, image_width: usize) -> Kernel {
    let config = Config {
        camera,
        effects: vec![Effect::Halation(halation.clone())],
        ..Config::default()
    };
    // The halo as the ray tracing below gives it: from a point of light.
    let extent = Extent::new(size, size)
        .unwrap()
        .with_image_width(image_width)
        .sent_by(Sending::Point);
    config.kernel(&extent).unwrap()
}

/// Sums over rings one pixel wide (by the pixel centre's distance) of a
/// square plane, the centre pixel left out.
fn plane_rings(plane: &[f64], size: usize) -> Vec<f64> {
    let c = size / 2;
    let mut rings = vec![0.0; size];
    for j in 0..size {
        for i in 0..size {
            let (dx, dy) = (i as f64 - c as f64, j as f64 - c as f64);
            let r = (dx * dx + dy * dy).sqrt().round() as usize;
            if (i, j) != (c, c) && r < rings.len() {
                rings[r] += plane[j * size + i];
            }
        }
    }
    rings
}

/// [`plane_rings`] of a kernel's plane.
fn rings(k: &Kernel, plane: usize) -> Vec<f64> {
    let values: Vec<f64> = k.planes()[plane].iter().map(|&v| f64::from(v)).collect();
    plane_rings(&values, k.width())
}

fn sum(values: &[f64]) -> f64 {
    values.iter().sum()
}

/// A base and layers given in pixels: L = 2(d + z) = 10 px for red.
const PIXELS: &str = r#"
base_thickness = "4.6px"
red_depth = "0.4px"
green_depth = "0.9px"
blue_depth = "1.4px"
"#;

#[test]
fn each_channel_keeps_its_light_and_its_halo_takes_its_share_from_the_core() {
    let h = halation(PIXELS);
    let k = kernel(&h, CameraGeometry::default(), 201, 201);
    assert_eq!(k.planes().len(), 3);
    let shares = h.shares();
    let centre = k.centre_weights();
    for c in 0..3 {
        // The halo's path is 10 px: within 100 px it falls to 10⁻⁴ and less.
        assert!((k.sum(c) - 1.0).abs() < 1e-4, "plane {c}: {}", k.sum(c));
        let halo = 1.0 - f64::from(centre[c]);
        assert!(
            (halo - shares[c]).abs() <= 0.01 * shares[c],
            "plane {c}: the core lost {halo}, the halo's share is {}",
            shares[c]
        );
    }
    // Red, nearest the base and least absorbed on the way, halates most.
    assert!(shares[0] > shares[1] && shares[1] > shares[2], "{shares:?}");
}

/// A deterministic stream of uniform numbers in [0, 1) (SplitMix64).
struct Uniform(u64);

impl Uniform {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Fresnel's reflectance of unpolarised light leaving a medium of index n
/// into air at θ from the normal.
fn fresnel(n: f64, theta: f64) -> f64 {
    let sin_t = n * theta.sin();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let (ci, ct) = (theta.cos(), (1.0 - sin_t * sin_t).sqrt());
    let s = (n * ci - ct) / (n * ci + ct);
    let p = (ci - n * ct) / (ci + n * ct);
    (s * s + p * p) / 2.0
}

#[test]
fn the_halo_is_what_rays_traced_through_the_base_give() {
    let h = halation(PIXELS);
    let size = 161;
    let k = kernel(&h, CameraGeometry::default(), size, size);
    let (n, path, transmission) = (h.base_index(), 10.0, h.red_transmission);
    // Rays leave the layer diffusely (sin²θ uniform), cross the base and
    // come back L tan θ away with weight R(θ)·T^(1/cos θ); each lands in a
    // pixel as the kernel's pixel averages count it.
    let mut uniform = Uniform(0x6861_6c61_7469_6f6e);
    let rays = 4_000_000;
    let (c, mut traced, mut returned) = ((size / 2) as f64, vec![0.0; size * size], 0.0);
    for _ in 0..rays {
        let theta = uniform.next().sqrt().asin();
        let phi = 2.0 * std::f64::consts::PI * uniform.next();
        let weight = fresnel(n, theta) * transmission.powf(1.0 / theta.cos());
        returned += weight;
        let r = path * theta.tan();
        let (x, y) = (c + r * phi.cos(), c - r * phi.sin());
        let (i, j) = (x.round(), y.round());
        if i >= 0.0 && j >= 0.0 && i < size as f64 && j < size as f64 {
            traced[j as usize * size + i as usize] += weight;
        }
    }
    let share = returned / rays as f64;
    assert!(
        (share - h.shares()[0]).abs() < 0.01 * share,
        "rays return {share}, the model's share is {}",
        h.shares()[0]
    );
    // The traced halo scaled as the kernel's is (its light within the
    // extent spread as ε), ring by ring.
    let theirs = plane_rings(&traced, size);
    let scale = share / sum(&theirs);
    let ours = rings(&k, 0);
    let total = sum(&ours);
    for (r, (a, b)) in ours.iter().zip(&theirs).enumerate() {
        let b = b * scale;
        if b > 0.005 * total {
            assert!(
                (a - b).abs() < 0.03 * b,
                "ring {r} px: the kernel holds {a:.5}, traced rays {b:.5}"
            );
        }
    }
}

/// The radius of the brightest ring but the centre, and the halo's mean
/// radius.
fn ring_and_mean(k: &Kernel, plane: usize) -> (usize, f64) {
    let rings = rings(k, plane);
    let mean_per_pixel: Vec<f64> = rings
        .iter()
        .enumerate()
        .map(|(r, s)| s / (2.0 * std::f64::consts::PI * r.max(1) as f64))
        .collect();
    let peak = (2..mean_per_pixel.len())
        .max_by(|&a, &b| mean_per_pixel[a].total_cmp(&mean_per_pixel[b]))
        .unwrap();
    let mean = rings
        .iter()
        .enumerate()
        .map(|(r, s)| r as f64 * s)
        .sum::<f64>()
        / sum(&rings);
    (peak, mean)
}

#[test]
fn the_halo_grows_with_the_base_and_rings_where_total_reflection_begins() {
    // A 35 mm frame 1200 px wide: 30 µm a pixel.
    let camera = CameraGeometry {
        sensor_width_mm: Some(36.0),
        ..CameraGeometry::default()
    };
    let pitch_um = 36_000.0 / 1200.0;
    let mut measured = Vec::new();
    for base_um in [120.0, 240.0] {
        let h = Halation {
            base_thickness: Length::um(base_um),
            ..halation("")
        };
        let k = kernel(&h, camera, 241, 1200);
        let (peak, mean) = ring_and_mean(&k, 0);
        let n = h.base_index();
        let ring = 2.0 * (base_um + 4.0) / pitch_um / (n * n - 1.0).sqrt();
        // The brightest ring is the first whose pixels lie beyond the
        // radius where total reflection begins.
        assert!(
            (ring..ring + 2.0).contains(&(peak as f64)),
            "base {base_um} µm: the brightest ring at {peak} px, total reflection from {ring:.2} px"
        );
        measured.push(mean);
    }
    let expected = (240.0 + 4.0) / (120.0 + 4.0);
    assert!(
        (measured[1] / measured[0] - expected).abs() < 0.02 * expected,
        "mean radii {measured:?}: ratio {} for bases in ratio {expected}",
        measured[1] / measured[0]
    );
}

#[test]
fn the_backing_leaves_a_trace_of_the_halo() {
    let bare = halation("");
    let backed = halation("remjet = true");
    let camera = CameraGeometry {
        sensor_width_mm: Some(36.0),
        ..CameraGeometry::default()
    };
    let k = kernel(&backed, camera, 161, 1920);
    for (c, (without, with)) in bare.shares().iter().zip(backed.shares()).enumerate() {
        // The backing returns 0.5 % of what reaches it, which the emulsion
        // attenuates further: the halo is below 0.5 % of the light, and a
        // twentieth of the halo without it at most.
        assert!(with < 0.005, "plane {c}: {with}");
        assert!(with < without / 20.0, "plane {c}: {with} against {without}");
        let lost = 1.0 - f64::from(k.centre_weights()[c]);
        assert!(
            (lost - with).abs() < 0.01 * with,
            "plane {c}: {lost} against {with}"
        );
    }
}

#[test]
fn the_halo_is_neutral_at_its_core_and_warms_outward() {
    // A 35 mm frame 1920 px wide (18.75 µm a pixel): total reflection
    // rings red at 2(130 + 4) µm·tan θc = 12.8 px.
    let camera = CameraGeometry {
        sensor_width_mm: Some(36.0),
        ..CameraGeometry::default()
    };
    let h = halation("");
    let k = kernel(&h, camera, 161, 1920);
    let (red, blue) = (rings(&k, 0), rings(&k, 2));
    let ratio = |from: usize, to: usize| sum(&red[from..to]) / sum(&blue[from..to]);
    // Within the ring, from it to twice its radius, and beyond.
    let bands = [ratio(1, 13), ratio(13, 26), ratio(26, 52)];
    let core = k.centre_weights();
    let core = f64::from(core[0]) / f64::from(core[2]);
    assert!((core - 1.0).abs() < 0.15, "the core's R/B is {core}");
    for pair in bands.windows(2) {
        assert!(pair[1] > pair[0], "R/B by band: {bands:?}");
    }
    assert!(bands[2] > 5.0, "R/B by band: {bands:?}");
}

proptest! {
    // A fixed seed: CI reruns the same cases on every machine.
    #![proptest_config(ProptestConfig {
        cases: 48,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x6861_6c61),
        ..ProptestConfig::default()
    })]

    #[test]
    fn every_halation_kernel_holds_its_light_and_takes_its_share_from_the_core(
        base in 0.05..40.0f64,
        depths in (0.01..5.0f64, 0.01..5.0f64, 0.01..5.0f64),
        transmissions in (0.0..=1.0f64, 0.0..=1.0f64, 0.0..=1.0f64),
        reflectance in 0.001..=0.5f64,
        remjet in any::<bool>(),
        residual in 0.0..=1.0f64,
        size in 1usize..90,
    ) {
        let h = Halation {
            base_thickness: Length::px(base),
            reflectance,
            remjet,
            remjet_residual: residual,
            red_depth: Length::px(depths.0),
            green_depth: Length::px(depths.1),
            blue_depth: Length::px(depths.2),
            red_transmission: transmissions.0,
            green_transmission: transmissions.1,
            blue_transmission: transmissions.2,
        };
        let k = kernel(&h, CameraGeometry::default(), size, size);
        // The kernel is the halo's light cut to its window: a larger one
        // holds the same weights where both reach, and more light.
        let large = kernel(&h, CameraGeometry::default(), 2 * size + 41, size);
        let shares = h.shares();
        for (c, (share, centre)) in shares.iter().zip(k.centre_weights()).enumerate() {
            prop_assert!(k.sum(c) <= large.sum(c) + 1e-6 && large.sum(c) <= 1.0 + 1e-6,
                "plane {c}: sum {} within {size} px, {} beyond", k.sum(c), large.sum(c));
            // A halo narrower than a pixel is averaged over the centre pixel
            // to about 2 % of its light, more than the integral says it
            // has: the kernel then keeps what its pixels hold, never more.
            let rounding = if base < 1.0 { 0.02 * share } else { 0.0 };
            let half = (size / 2) as i64;
            // y is up: the top row is +half.
            for dy in -(size as i64 - 1 - half)..=half {
                for dx in -half..=(size as i64 - 1 - half) {
                    let (a, b) = (f64::from(k.at(c, dx, dy)), f64::from(large.at(c, dx, dy)));
                    prop_assert!((a - b).abs() <= 1e-6 * b + rounding + 1e-12, "({dx}, {dy}): {a} vs {b}");
                }
            }
            prop_assert!(k.planes()[c].iter().all(|&v| v >= 0.0 && v.is_finite()));
            // At most its share leaves the core (less where the halo's own
            // centre pixel keeps some), and never more than all the light.
            prop_assert!((0.0..=1.0).contains(share), "share {share}");
            let lost = 1.0 - f64::from(centre);
            prop_assert!(lost <= share + 1e-6, "plane {c}: lost {lost}, share {share}");
        }
    }
}
