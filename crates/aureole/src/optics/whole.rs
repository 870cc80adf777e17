//! The light of a spread function over the whole plane, not only over the
//! kernel's window (docs/physics.md §2): a kernel is normalised by it and
//! then cut to the window, so that the light that would fall beyond the
//! frame leaves it instead of being folded back into what remains.

use std::f64::consts::{FRAC_PI_2, TAU};

use crate::math::gauss_legendre;

/// A kernel's window about its centre, in pixels, y up: how far each of
/// its edges lies from the centre of the centre pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Window {
    pub left: f64,
    pub right: f64,
    pub bottom: f64,
    pub top: f64,
}

impl Window {
    /// The window of a `width`×`height` kernel, its centre at column
    /// ⌊W/2⌋ and row ⌊H/2⌋ from the top.
    pub fn of(width: usize, height: usize) -> Window {
        let (cx, cy) = (width / 2, height / 2);
        Window {
            left: cx as f64 + 0.5,
            right: (width - 1 - cx) as f64 + 0.5,
            top: cy as f64 + 0.5,
            bottom: (height - 1 - cy) as f64 + 0.5,
        }
    }

    /// The distance to the nearest edge: every circle within it lies inside.
    pub fn nearest(&self) -> f64 {
        self.left.min(self.right).min(self.bottom).min(self.top)
    }

    /// The radii at which the part of a circle outside turns a corner: the
    /// edges' and the corners' distances.
    fn turns(&self) -> [f64; 8] {
        let Window {
            left,
            right,
            bottom,
            top,
        } = *self;
        [
            left,
            right,
            bottom,
            top,
            libm::hypot(left, top),
            libm::hypot(right, top),
            libm::hypot(left, bottom),
            libm::hypot(right, bottom),
        ]
    }

    /// The angle of the circle of radius `r` about the centre that lies
    /// outside the window: each edge at distance d cuts off 2·acos(d/r),
    /// and the arcs beyond two edges that meet at a corner overlap by
    /// max(0, α₁ + α₂ − π/2) (opposite edges never do).
    pub fn outside_angle(&self, r: f64) -> f64 {
        let beyond = |d: f64| if r > d { libm::acos(d / r) } else { 0.0 };
        let (right, top, left, bottom) = (
            beyond(self.right),
            beyond(self.top),
            beyond(self.left),
            beyond(self.bottom),
        );
        let overlap = |a: f64, b: f64| (a + b - FRAC_PI_2).max(0.0);
        let sides = 2.0 * (right + top + left + bottom);
        let corners = overlap(right, top)
            + overlap(top, left)
            + overlap(left, bottom)
            + overlap(bottom, right);
        (sides - corners).clamp(0.0, TAU)
    }
}

/// What a shape knows of its light beyond what the kernel's window holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Whole {
    /// ∫∫ f over the whole plane, px².
    Plane(f64),
    /// ∫∫ f over the plane outside the window, px²: for a shape singular at
    /// its centre, whose pixel there is left out of the spread light.
    Beyond(f64),
}

/// Points of the rule on each panel.
const POINTS: usize = 24;

/// Panels at most: doubling in length from a quarter of `scale`, 60 reach
/// 2⁶⁰ times it, where every shape's light is long spent.
const PANELS: usize = 60;

/// ∫ g(r) dr from `from` to infinity, for a g that falls at least as fast
/// as r⁻¹⁻ᵟ far out: 24-point Gauss–Legendre on panels that double in
/// length from `scale` / 4, each split where `breaks` (radii at which g
/// has a kink or a step) fall inside it.
pub(crate) fn radial_integral(
    g: impl Fn(f64) -> f64,
    from: f64,
    scale: f64,
    breaks: &[f64],
) -> f64 {
    let (nodes, weights) = gauss_legendre(POINTS);
    let rule = |a: f64, b: f64| -> f64 {
        let (half, mid) = (0.5 * (b - a), 0.5 * (a + b));
        half * nodes
            .iter()
            .zip(&weights)
            .map(|(t, w)| w * g(mid + half * t))
            .sum::<f64>()
    };
    let mut breaks: Vec<f64> = breaks
        .iter()
        .copied()
        .filter(|b| b.is_finite() && *b > from)
        .collect();
    breaks.sort_by(f64::total_cmp);
    let mut total = 0.0;
    let mut length = 0.25 * scale.max(f64::MIN_POSITIVE);
    let mut a = from;
    let mut last = [0.0; 2];
    for _ in 0..PANELS {
        let b = a + length;
        let mut start = a;
        let mut panel = 0.0;
        for &kink in breaks.iter().filter(|&&k| a < k && k < b) {
            panel += rule(start, kink);
            start = kink;
        }
        panel += rule(start, b);
        total += panel;
        last = [last[1], panel];
        a = b;
        length *= 2.0;
    }
    // Far out g is a power of r, whose integrals over doubling panels fall
    // geometrically: the rest of the series, which a tail as slow as
    // r^−1.4 would otherwise leave at 10⁻⁷.
    let ratio = last[1] / last[0];
    if ratio > 0.0 && ratio < 1.0 {
        total += last[1] * ratio / (1.0 - ratio);
    }
    total
}

/// ∫∫ f over the plane outside `window` of a radial f (`at`: f at a
/// distance), whose structure has the length `scale` and steps at
/// `breaks`.
pub(crate) fn radial_beyond(
    at: impl Fn(f64) -> f64,
    window: &Window,
    scale: f64,
    breaks: &[f64],
) -> f64 {
    let mut all = window.turns().to_vec();
    all.extend_from_slice(breaks);
    radial_integral(
        |r| at(r) * r * window.outside_angle(r),
        window.nearest(),
        scale,
        &all,
    )
}

/// ∫∫ f over the plane of a radial f.
pub(crate) fn radial_plane(at: impl Fn(f64) -> f64, scale: f64, breaks: &[f64]) -> f64 {
    radial_integral(|r| TAU * r * at(r), 0.0, scale, breaks)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_angle_outside_a_window_is_what_a_fine_sweep_of_the_circle_finds() {
        let windows = [
            Window::of(101, 1),
            Window::of(11, 7),
            Window::of(10, 6),
            Window::of(599, 21),
        ];
        for window in windows {
            for r in [0.2, 0.5, 0.7, 3.0, 3.9, 5.2, 6.0, 9.0, 40.0, 300.0, 1e4] {
                let n = 200_000;
                let outside = (0..n)
                    .filter(|&i| {
                        let phi = TAU * (i as f64 + 0.5) / n as f64;
                        let (x, y) = (r * libm::cos(phi), r * libm::sin(phi));
                        x > window.right || -x > window.left || y > window.top || -y > window.bottom
                    })
                    .count();
                let sweep = TAU * outside as f64 / n as f64;
                let got = window.outside_angle(r);
                assert!(
                    (got - sweep).abs() < 1e-4,
                    "{window:?}, r {r}: {got} vs {sweep}"
                );
            }
        }
    }

    #[test]
    fn radial_integrals_match_closed_forms() {
        // (1 + r²/R²)^−β over the plane: πR²/(β − 1); and beyond a radius
        // ρ it is πR²/(β − 1)·(1 + ρ²/R²)^(1−β).
        for (radius, beta) in [(10.0, 2.0), (0.3, 1.5), (120.0, 4.5), (2.0, 1.2)] {
            let f = |r: f64| libm::pow(1.0 + (r / radius) * (r / radius), -beta);
            let exact = std::f64::consts::PI * radius * radius / (beta - 1.0);
            let plane = radial_plane(f, radius, &[]);
            assert!(
                (plane / exact - 1.0).abs() < 1e-9,
                "R {radius}, β {beta}: {plane} vs {exact}"
            );
            let rho = 37.0;
            let integral = radial_integral(|r| TAU * r * f(r), rho, radius, &[]);
            let tail = exact * libm::pow(1.0 + (rho / radius) * (rho / radius), 1.0 - beta);
            assert!(
                (integral / tail - 1.0).abs() < 1e-9,
                "R {radius}, β {beta}, beyond {rho}"
            );
        }
        // A Gaussian beyond a square window: 1 − erf(a/(σ√2))² of its light
        // is outside the square of half-side a. The arcs beyond an edge grow
        // as √(r − d) from it, which holds the rule to about 10⁻⁵.
        let sigma = 3.0;
        let f = |r: f64| libm::exp(-0.5 * r * r / (sigma * sigma)) / (TAU * sigma * sigma);
        let window = Window::of(9, 9);
        let inside = libm::erf(4.5 / (sigma * std::f64::consts::SQRT_2)).powi(2);
        let beyond = radial_beyond(f, &window, sigma, &[]);
        assert!(
            (beyond / (1.0 - inside) - 1.0).abs() < 1e-5,
            "{beyond} vs {}",
            1.0 - inside
        );
    }
}
