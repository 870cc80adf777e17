//! A lens's picture: its section through the axis as an SVG drawing, the
//! glass shaded, the stop's blades drawn where they close at its clear
//! aperture, the light from the left, for a person to see which lens the
//! ghosts are traced through (`aureole lens --svg`, the studio's ghosts
//! panel).

use std::fmt::Write as _;
use std::path::Path;

use aureole::lens::{Lens, Medium};

use crate::atomic::write_atomic;
use crate::error::{Error, Result};

/// Points along a surface's profile, each side of the axis.
const SAMPLES: usize = 24;

/// The picture's width in its own units; the height follows the lens.
const WIDTH: f64 = 480.0;

/// The lens's section as an SVG document.
pub fn svg(lens: &Lens) -> String {
    let mm = lens.mm_per_unit;
    let mut z = 0.0;
    // Each surface's vertex, radius of curvature and clear semi-aperture,
    // mm: the vertical section, an anamorphic surface's y–z curve.
    let surfaces: Vec<(f64, Option<f64>, f64)> = lens
        .surfaces
        .iter()
        .map(|s| {
            let here = z;
            z += s.thickness * mm;
            let radius = s.radius_y.unwrap_or(s.radius);
            (here, radius.map(|r| r * mm), s.semi_aperture * mm)
        })
        .collect();
    let last = surfaces.last().map_or(0.0, |s| s.0);
    let widest = surfaces.iter().map(|s| s.2).fold(1e-9, f64::max);
    let sag = |radius: Option<f64>, y: f64| {
        radius.map_or(0.0, |r| {
            let c = 1.0 / r;
            c * y * y / (1.0 + (1.0 - (c * y).powi(2)).max(0.0).sqrt())
        })
    };
    // The profile bulges beyond the vertices; the margin holds it.
    let (lo, hi) = surfaces
        .iter()
        .fold((0.0f64, last), |(lo, hi), &(v, r, a)| {
            let s = sag(r, a);
            (lo.min(v + s), hi.max(v + s))
        });
    let margin = 0.08 * (hi - lo).max(widest);
    let scale = WIDTH / (hi - lo + 2.0 * margin);
    let height = (2.0 * widest + 2.0 * margin) * scale;
    let at = |z: f64, y: f64| ((z - lo + margin) * scale, 0.5 * height - y * scale);
    let profile = |&(v, r, a): &(f64, Option<f64>, f64), downwards: bool| {
        (0..=SAMPLES)
            .map(|k| {
                let t = k as f64 / SAMPLES as f64;
                let y = if downwards {
                    a - 2.0 * a * t
                } else {
                    -a + 2.0 * a * t
                };
                let (x, y) = at(v + sag(r, y), y);
                format!("{x:.2},{y:.2}")
            })
            .collect::<Vec<_>>()
    };
    let mut out = String::new();
    let _ = write!(
        out,
        r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {WIDTH:.0} {height:.0}" width="{WIDTH:.0}" height="{height:.0}" role="img"><title>{}</title><line x1="0" y1="{:.2}" x2="{WIDTH:.0}" y2="{:.2}" stroke="#888" stroke-dasharray="4 3"/>"##,
        escape(&lens.name),
        0.5 * height,
        0.5 * height
    );
    for (i, surface) in lens.surfaces.iter().enumerate() {
        let here = &surfaces[i];
        if let (Medium::Glass { .. }, Some(next)) = (surface.medium, surfaces.get(i + 1)) {
            // The element between this surface and the next, its rims
            // joined at the smaller clear aperture.
            let points = [profile(here, true), profile(next, false)].concat();
            let _ = write!(
                out,
                r##"<polygon points="{}" fill="#9ec5e8" fill-opacity="0.6" stroke="#27537a" stroke-width="1"/>"##,
                points.join(" ")
            );
        }
        if surface.stop {
            let (x, top) = at(here.0, here.2);
            let (_, edge) = at(here.0, widest + 0.5 * margin);
            let (_, bottom) = at(here.0, -here.2);
            let (_, far) = at(here.0, -widest - 0.5 * margin);
            let _ = write!(
                out,
                r##"<g stroke="#222" stroke-width="3"><line x1="{x:.2}" y1="{edge:.2}" x2="{x:.2}" y2="{top:.2}"/><line x1="{x:.2}" y1="{bottom:.2}" x2="{x:.2}" y2="{far:.2}"/></g>"##
            );
        }
    }
    out.push_str("</svg>\n");
    out
}

/// Writes the lens's section to `path` (SVG), atomically.
pub fn write_svg(path: &Path, lens: &Lens) -> Result<()> {
    write_atomic(path, |out| {
        use std::io::Write;
        out.write_all(svg(lens).as_bytes())
            .map_err(|e| Error::io(path, e))
    })
}

/// `text` as SVG character data.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_lens_is_drawn_an_element_for_each_glass_and_its_stop() {
        for shipped in aureole::lens::shipped::LENSES {
            let lens = shipped.lens().unwrap();
            let drawing = super::svg(&lens);
            let glasses = lens.surfaces.iter().filter(|s| s.medium.is_glass()).count();
            assert_eq!(
                drawing.matches("<polygon").count(),
                glasses,
                "{}",
                shipped.name
            );
            assert_eq!(drawing.matches("<g stroke").count(), 1);
            assert!(drawing.starts_with("<svg") && drawing.ends_with("</svg>\n"));
            assert!(!drawing.contains("NaN") && !drawing.contains("inf"));
        }
    }
}
