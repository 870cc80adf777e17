//! A night street built in code, at realistic luminances (cd/m²): a dim sky,
//! dark facades with lit windows, a road in the pools of its lamps, and
//! street lamps of 10⁴–10⁵ cd/m². It shows what aureole does with nothing but
//! the binary, and its linear version is a scene to try settings on.

use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use aureole::image::{Image, Layout};

/// The demo scene at `width`×`height` pixels (the same bytes every run).
pub fn night_street(width: usize, height: usize) -> Image {
    let mut image = Image::filled(width, height, Layout::Rgb, 0.0);
    let mut rng = Pcg64::seed_from_u64(0x006e_6967_6874);
    let mut uniform = move || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    let (w, h) = (width as f64, height as f64);
    let horizon = 0.62 * h;
    let put = |image: &mut Image, x: usize, y: usize, rgb: [f64; 3]| {
        if x < width && y < height {
            for (c, v) in rgb.iter().enumerate() {
                image.planes[c][y * width + x] = *v as f32;
            }
        }
    };

    // Sky: 0.005 cd/m² at the top to 0.03 at the horizon, city-glow orange.
    for y in 0..height {
        let t = (y as f64 / horizon).min(1.0);
        let l = 0.005 + 0.025 * t * t;
        for x in 0..width {
            put(&mut image, x, y, [l * 1.2, l, l * 0.8]);
        }
    }
    // Stars: a few of 1–5 cd/m² (point sources of a pixel).
    for _ in 0..(width * height / 4000) {
        let (x, y) = (
            (uniform() * w) as usize,
            (uniform() * horizon * 0.8) as usize,
        );
        let l = 1.0 + 4.0 * uniform();
        put(&mut image, x, y, [l, l, l * 1.1]);
    }
    // Buildings: dark facades (0.05–0.2 cd/m²) with lit windows of
    // 30–200 cd/m², warm and cool.
    let mut x0 = 0.0;
    while x0 < w {
        let bw = w * (0.08 + 0.1 * uniform());
        let top = horizon - h * (0.15 + 0.3 * uniform());
        let facade = 0.05 + 0.15 * uniform();
        let (bx0, bx1) = (x0 as usize, ((x0 + bw) as usize).min(width));
        for y in top.max(0.0) as usize..horizon as usize {
            for x in bx0..bx1 {
                put(&mut image, x, y, [facade, facade * 0.95, facade * 0.9]);
            }
        }
        let cell = (h / 40.0).max(3.0);
        let mut wy = top + cell;
        while wy + cell < horizon {
            let mut wx = x0 + cell * 0.7;
            while wx + cell < x0 + bw {
                if uniform() < 0.45 {
                    let l = 30.0 + 170.0 * uniform();
                    let warm = uniform() < 0.7;
                    let rgb = if warm {
                        [l * 1.25, l, l * 0.6]
                    } else {
                        [l * 0.85, l, l * 1.2]
                    };
                    for y in wy as usize..(wy + cell * 0.6) as usize {
                        for x in wx as usize..(wx + cell * 0.5) as usize {
                            put(&mut image, x, y, rgb);
                        }
                    }
                }
                wx += cell;
            }
            wy += cell * 1.3;
        }
        x0 += bw + w * 0.01 * uniform();
    }
    // Road: 0.1 cd/m² between the lamps' pools, up to ~1.5 cd/m² beneath them
    // (lit streets are 0.5–2 cd/m²).
    let lamps: Vec<f64> = (0..5).map(|i| w * (0.1 + 0.2 * i as f64)).collect();
    let lamp_y = horizon - 0.12 * h;
    for y in horizon as usize..height {
        for x in 0..width {
            let pool: f64 = lamps
                .iter()
                .map(|&lx| {
                    let d2 = ((x as f64 - lx) / (0.08 * w)).powi(2)
                        + ((y as f64 - horizon - 0.1 * h) / (0.08 * h)).powi(2);
                    1.4 / (1.0 + d2)
                })
                .sum();
            let l = 0.1 + pool;
            put(&mut image, x, y, [l * 1.1, l, l * 0.75]);
        }
    }
    // Street lamps: dark poles and heads of 2·10⁴–10⁵ cd/m², a few pixels
    // across, sodium-orange and LED-white.
    let radius = (h / 300.0).max(1.2);
    for (i, &lx) in lamps.iter().enumerate() {
        for y in lamp_y as usize..(horizon + 0.1 * h) as usize {
            for x in (lx - radius * 0.5) as usize..=(lx + radius * 0.5) as usize {
                put(&mut image, x, y, [0.02, 0.02, 0.02]);
            }
        }
        let l = 2e4 + 8e4 * uniform();
        let rgb = if i % 2 == 0 {
            [l * 1.4, l, l * 0.35]
        } else {
            [l * 0.95, l, l * 1.1]
        };
        let reach = radius.ceil() as i64 + 1;
        for dy in -reach..=reach {
            for dx in -reach..=reach {
                if ((dx * dx + dy * dy) as f64).sqrt() <= radius {
                    let (x, y) = (lx as i64 + dx, lamp_y as i64 + dy);
                    if x >= 0 && y >= 0 {
                        put(&mut image, x as usize, y as usize, rgb);
                    }
                }
            }
        }
    }
    image
}
