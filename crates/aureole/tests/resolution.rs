//! One look at every resolution: lengths are on the sensor, so a frame
//! rendered at 4K and reduced to 1080p is the frame rendered at 1080p.
//! Each lamp's glare is compared in energy, ring by ring and sector by
//! sector, for bloom, corona, an aperture and halation.

// References and workloads, not the library: the platform's maths
// (clippy.toml refuses it in the core) is as good as libm here.
#![allow(clippy::disallowed_methods)]

use aureole::{ApplyOptions, Config, ConfigFile, Extent, Image, Kernel, Layout, Plan, Sending};

const CAMERA: &str = "[camera]\nsensor_width_mm = 36.0\nfocal_length_mm = 50.0\nf_number = 8.0\n";

/// Lamps at 1080p, one pixel each: (x, y, cd/m²).
const LAMPS: [(usize, usize, f32); 3] = [(480, 270, 2e4), (1400, 600, 5e4), (900, 850, 1e4)];

/// The night of `LAMPS` at `factor` × 1080p: each lamp covers factor² px
/// at the same luminance, so that the larger frame reduced by area is the
/// smaller one.
fn scene(factor: usize) -> Image {
    let (w, h) = (1920 * factor, 1080 * factor);
    let mut image = Image::filled(w, h, Layout::Rgb, 0.0);
    for (x, y, level) in LAMPS {
        for plane in &mut image.planes {
            for j in 0..factor {
                for i in 0..factor {
                    plane[(y * factor + j) * w + x * factor + i] = level;
                }
            }
        }
    }
    image
}

/// The glare of `effect` (an `[[effect]]` table's keys) on the scene at
/// `factor` × 1080p, reduced to 1080p.
fn glare(effect: &str, factor: usize) -> Image {
    let mut config = Config::default();
    let text = format!("{CAMERA}\n[[effect]]\n{effect}\n");
    config.merge(ConfigFile::parse(&text, "the effect").unwrap());
    let image = scene(factor);
    let plan = Plan::for_image(&config, image.width, image.height, None).unwrap();
    let options = ApplyOptions {
        glare_only: true,
        ..ApplyOptions::default()
    };
    let glare = plan
        .apply(&image, 1.0, &options, &mut |_| {})
        .unwrap()
        .image;
    glare.resampled(1920, 1080)
}

/// Light around (x, y) at 1080p, by rings [4, 16), [16, 64), [64, 256) px
/// and, within each, by 12 sectors of 30°: (ring, sector) sums of the
/// luminance.
fn around(image: &Image, (x, y): (usize, usize)) -> [[f64; 12]; 3] {
    let mut sums = [[0.0; 12]; 3];
    let luminance = image.luminance();
    for j in y.saturating_sub(256)..(y + 256).min(image.height) {
        for i in x.saturating_sub(256)..(x + 256).min(image.width) {
            let (dx, dy) = (i as f64 - x as f64, y as f64 - j as f64);
            let r = (dx * dx + dy * dy).sqrt();
            let ring = match r {
                r if (4.0..16.0).contains(&r) => 0,
                r if (16.0..64.0).contains(&r) => 1,
                r if (64.0..256.0).contains(&r) => 2,
                _ => continue,
            };
            let angle = dy.atan2(dx).to_degrees().rem_euclid(360.0);
            sums[ring][(angle / 30.0) as usize % 12] += f64::from(luminance[j * image.width + i]);
        }
    }
    sums
}

/// Holds the 4K frame reduced to 1080p to the 1080p frame: each ring's
/// energy within 0.2 %, each sector within 0.2 % of its ring. A kernel takes
/// the light of the sending pixel as well as the receiving one's over its
/// area (docs/physics.md §2), so the 4K lamp's four pixels and the 1080p
/// lamp's one send the same light; without that the ring of 4 to 16 px
/// differed by 3.1 % for the bloom and 1.05 % for the aperture. The worst
/// differences are printed (`--nocapture`).
fn same_look(effect: &str) {
    same_look_within(effect, [0.002; 3]);
}

/// [`same_look`], each ring's energy held within `tolerance`.
fn same_look_within(effect: &str, tolerance: [f64; 3]) {
    let (small, large) = (glare(effect, 1), glare(effect, 2));
    let (mut rings, mut sectors) = ([0.0f64; 3], [0.0f64; 3]);
    for (x, y, _) in LAMPS {
        let (a, b) = (around(&small, (x, y)), around(&large, (x, y)));
        for ring in 0..3 {
            let (ea, eb): (f64, f64) = (a[ring].iter().sum(), b[ring].iter().sum());
            rings[ring] = rings[ring].max((eb - ea).abs() / ea);
            for s in 0..12 {
                sectors[ring] = sectors[ring].max((a[ring][s] - b[ring][s]).abs() / ea);
            }
        }
    }
    eprintln!(
        "{}: rings off by {:.2?} %, sectors by {:.2?} % of their ring",
        effect.lines().next().unwrap_or(""),
        rings.map(|r| 100.0 * r),
        sectors.map(|r| 100.0 * r)
    );
    // The README's figure: within 0.2 % (measured 0.13 % at worst, the
    // aperture's middle ring).
    for ring in 0..3 {
        assert!(
            rings[ring] <= tolerance[ring],
            "ring {ring}: energy off by {:.4}",
            rings[ring]
        );
        assert!(
            sectors[ring] <= 0.002,
            "ring {ring}: a sector off by {:.4}",
            sectors[ring]
        );
    }
}

#[test]
fn bloom_looks_the_same_at_1080p_and_at_4k() {
    same_look("type = \"bloom\"\nepsilon = 0.05\nbeta = 3.0\nradius = \"40um\"");
}

#[test]
fn a_corona_looks_the_same_at_1080p_and_at_4k() {
    same_look(
        "type = \"corona\"\nepsilon = 0.02\nrays = 14\nlength = \"300um\"\nwidth = \"40um\"\nspread = 1.0",
    );
}

#[test]
fn an_aperture_looks_the_same_at_1080p_and_at_4k() {
    same_look("type = \"aperture\"\nblades = 7");
}

#[test]
fn halation_looks_the_same_at_1080p_and_at_4k() {
    same_look("type = \"halation\"");
}

/// Not yet: Vos's k/θⁿ has no integral at θ = 0 for n ≥ 2, so its kernel
/// leaves the centre pixel unspread and normalises the rest over the
/// pixels; a pixel half as wide takes in more of the near light, and every
/// ring around a lamp gets 7 % less at 4K than at 1080p. The cure is an
/// angle, not a pixel, for the unspread core: the CIE's eye (below) has
/// one, Vos's k/θⁿ none.
#[test]
#[ignore = "Vos's rings differ by 7 % between 1080p and 4K: its core is a pixel, not an angle"]
fn the_eyes_glare_looks_the_same_at_1080p_and_at_4k() {
    same_look("type = \"vos\"\nepsilon = 0.05\nexponent = 2.0");
}

/// The CIE's eye keeps unspread only what its PSF puts within the centre
/// pixel's angle, so a finer pixel keeps less, as the eye does: the rings
/// agree where Vos's were 7 % apart. The nearest ring (4 to 16 px) is
/// 0.49 % apart: the centre is kept a point, so a 1080p pixel's light
/// leaves its centre rather than its whole square, which moves the light
/// of its first few pixels (docs/physics.md §5).
#[test]
fn the_cie_eyes_glare_looks_the_same_at_1080p_and_at_4k() {
    same_look_within(
        "type = \"eye\"\nage = 70\npigmentation = 1.0",
        [0.005, 0.002, 0.002],
    );
}

/// The kernel of `effect` for an image `image_width` wide, `side` px square.
fn kernel(effect: &str, side: usize, image_width: usize, sending: Sending) -> Kernel {
    let mut config = Config::default();
    config.merge(
        ConfigFile::parse(&format!("{CAMERA}\n[[effect]]\n{effect}\n"), "the effect").unwrap(),
    );
    let extent = Extent::new(side, side)
        .unwrap()
        .with_image_width(image_width)
        .sent_by(sending);
    config.kernel(&extent).unwrap()
}

/// ∫ of the tent max(0, 1 − |u|) from −∞ to v.
fn under_tent(v: f64) -> f64 {
    match v {
        v if v <= -1.0 => 0.0,
        v if v <= 0.0 => 0.5 * (1.0 + v) * (1.0 + v),
        v if v < 1.0 => 1.0 - 0.5 * (1.0 - v) * (1.0 - v),
        _ => 1.0,
    }
}

/// A pixel's kernel is the PSF of a point averaged over the sending
/// pixel as well as the receiving one: the point's kernel at a 25th of
/// the pitch, each fine pixel's light shared among the coarse pixels by
/// the mean of their tents (1 − |s|)(1 − |t|) over its square. The tents
/// sum to 1 everywhere; a fine pixel 0.04 px wide is narrower than the
/// 7-blade stop's core (λN = 0.23 px at f/8), so its light is near
/// uniform over it. Both are normalised over the 25 × 25 px compared.
fn is_the_point_under_the_tents(effect: &str) {
    const FACTOR: i64 = 25;
    const REACH: i64 = 12;
    let side = (2 * REACH + 1) as usize;
    let coarse = kernel(effect, 4 * side, 1920, Sending::Pixel);
    let fine_side = (2 * (REACH + 1) * FACTOR + 1) as usize;
    let fine = kernel(effect, fine_side, 1920 * FACTOR as usize, Sending::Point);
    // Per fine offset, the coarse pixels its light reaches and the shares.
    let h = 1.0 / FACTOR as f64;
    let shares = |f: i64| -> Vec<(i64, f64)> {
        let x = f as f64 * h;
        ((x - 1.0).floor() as i64..=(x + 1.0).ceil() as i64)
            .filter(|c| c.abs() <= REACH)
            .map(|c| {
                let (a, b) = (x - 0.5 * h - c as f64, x + 0.5 * h - c as f64);
                (c, (under_tent(b) - under_tent(a)) / h)
            })
            .filter(|&(_, w)| w > 0.0)
            .collect()
    };
    let reach = (REACH + 1) * FACTOR;
    let table: Vec<Vec<(i64, f64)>> = (-reach..=reach).map(shares).collect();
    let index = |x: i64, y: i64| ((y + REACH) as usize) * side + (x + REACH) as usize;
    let mut tented = vec![0.0f64; side * side];
    for fy in -reach..=reach {
        for fx in -reach..=reach {
            let v = f64::from(fine.at(0, fx, fy));
            for &(cy, wy) in &table[(fy + reach) as usize] {
                for &(cx, wx) in &table[(fx + reach) as usize] {
                    tented[index(cx, cy)] += v * wx * wy;
                }
            }
        }
    }
    let mut ours = vec![0.0f64; side * side];
    for cy in -REACH..=REACH {
        for cx in -REACH..=REACH {
            ours[index(cx, cy)] = f64::from(coarse.at(0, cx, cy));
        }
    }
    for plane in [&mut tented, &mut ours] {
        let total: f64 = plane.iter().sum();
        plane.iter_mut().for_each(|v| *v /= total);
    }
    let centre = tented[index(0, 0)];
    let mut worst: (f64, i64, i64) = (0.0, 0, 0);
    for cy in -REACH..=REACH {
        for cx in -REACH..=REACH {
            let (a, b) = (ours[index(cx, cy)], tented[index(cx, cy)]);
            // Relative where a pixel holds light, else against the centre.
            let error = (a - b).abs() / b.max(1e-3 * centre);
            if error > worst.0 {
                worst = (error, cx, cy);
            }
        }
    }
    eprintln!(
        "{}: worst pixel off by {:.3} % at {:?}",
        effect.lines().next().unwrap_or(""),
        100.0 * worst.0,
        (worst.1, worst.2)
    );
    assert!(
        worst.0 < 0.01,
        "pixel ({}, {}) off by {:.4}",
        worst.1,
        worst.2,
        worst.0
    );
}

#[test]
fn a_bloom_kernel_is_the_point_psf_under_the_pixels_tents() {
    is_the_point_under_the_tents("type = \"bloom\"\nepsilon = 1.0\nbeta = 3.0\nradius = \"40um\"");
}

#[test]
fn an_aperture_kernel_is_the_point_psf_under_the_pixels_tents() {
    is_the_point_under_the_tents("type = \"aperture\"\nblades = 7\nspectral = false");
}
