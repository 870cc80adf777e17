//! The paraxial trace of a prescription (the y–nu trace of first-order
//! optics): at a surface of curvature c between indices n and n′ a ray's
//! reduced angle turns, n′u′ = nu − y c (n′ − n), and it then travels
//! y ← y + t u′ to the next. Two rays give a lens's first-order data: one
//! parallel to the axis (focal length, back focus, the marginal height at
//! the stop) and one through the first vertex (where the stop's image,
//! the entrance pupil, lies). An anamorphic lens is traced in its x–z
//! and y–z planes apart, each surface with its curvature across that
//! plane: a paraxial ray in one never leaves it.

use super::{Lens, Medium};
use crate::error::{Error, Result};

/// A lens's first-order data at one wavelength, in its prescription's
/// units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Paraxial {
    /// Effective focal length, f′ = −y₁ / u′ of a ray parallel to the axis.
    pub focal_length: f64,
    /// Back focal distance: from the last surface to the rear focus.
    pub back_focus: f64,
    /// The entrance pupil's distance behind the first surface's vertex
    /// (negative: in front of it).
    pub entrance_pupil: f64,
    /// The entrance pupil's semi-diameter: the stop's opening as the
    /// object side sees it.
    pub entrance_pupil_radius: f64,
    /// f′ / (2 × the entrance pupil's semi-diameter), the stop wide open.
    pub f_number: f64,
}

/// The plane through the axis a paraxial ray stays in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Meridian {
    /// The x–z plane: the horizontal.
    X,
    /// The y–z plane: the vertical.
    Y,
}

/// A paraxial ray: height, and angle in the medium it is in.
#[derive(Debug, Clone, Copy)]
struct Ray {
    y: f64,
    u: f64,
}

/// A ray through every surface: its height at each, and its angle after
/// the last.
fn through(lens: &Lens, (nm, meridian): (f64, Meridian), mut ray: Ray) -> (Vec<f64>, f64) {
    let mut heights = Vec::with_capacity(lens.surfaces.len());
    let mut n = 1.0;
    for (i, surface) in lens.surfaces.iter().enumerate() {
        if i > 0 {
            ray.y += lens.surfaces[i - 1].thickness * ray.u;
        }
        heights.push(ray.y);
        let after = surface.medium.index_at(nm);
        let (cx, cy) = surface.curvatures();
        let curvature = if meridian == Meridian::X { cx } else { cy };
        ray.u = (n * ray.u - ray.y * curvature * (after - n)) / after;
        n = after;
    }
    (heights, ray.u)
}

/// The paraxial data of `lens` at `nm` in `meridian`, refused where the
/// lens forms no real image of a distant object.
pub fn trace(lens: &Lens, nm: f64, meridian: Meridian) -> Result<Paraxial> {
    let refuse = |message: String| Error::Lens {
        name: lens.name.clone(),
        message,
    };
    if lens.surfaces.last().map(|s| s.medium) != Some(Medium::Air) {
        return Err(refuse(
            "the last surface must leave the light in air (no n_d after it)".into(),
        ));
    }
    let (heights, u) = through(lens, (nm, meridian), Ray { y: 1.0, u: 0.0 });
    let last = heights.last().copied().unwrap_or(1.0);
    let focal_length = -1.0 / u;
    if !focal_length.is_finite() || focal_length <= 0.0 {
        return Err(refuse(format!(
            "its paraxial focal length is {focal_length:.6}: a camera lens needs a positive one, which forms a real image"
        )));
    }
    let back_focus = -last / u;
    // Heights at the stop are linear in the ray's height and angle at the
    // first vertex; the ray that crosses the stop's centre is the chief
    // ray, and the object side sees the stop where it meets the axis.
    let stop = lens.stop();
    let marginal = heights[stop];
    let (chief, _) = through(lens, (nm, meridian), Ray { y: 0.0, u: 1.0 });
    if marginal == 0.0 {
        return Err(refuse(
            "a ray parallel to the axis crosses it at the stop: no light passes the stop's opening"
                .into(),
        ));
    }
    let entrance_pupil = chief[stop] / marginal;
    let entrance_pupil_radius = (lens.surfaces[stop].semi_aperture / marginal).abs();
    Ok(Paraxial {
        focal_length,
        back_focus,
        entrance_pupil,
        entrance_pupil_radius,
        f_number: focal_length / (2.0 * entrance_pupil_radius),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lens::{Coating, Surface};

    fn surface(radius: Option<f64>, thickness: f64, medium: Medium) -> Surface {
        Surface {
            radius,
            radius_y: None,
            thickness,
            medium,
            semi_aperture: 5.0,
            coating: Coating::None,
            stop: false,
        }
    }

    fn lens(surfaces: Vec<Surface>) -> Lens {
        Lens {
            name: "test".into(),
            patent: None,
            mm_per_unit: 1.0,
            surfaces,
        }
    }

    const GLASS: Medium = Medium::Glass {
        n_d: 1.5,
        v_d: None,
    };

    #[test]
    fn a_thick_lens_has_the_lensmakers_focal_length() {
        // 1/f = (n − 1)[1/R₁ − 1/R₂ + (n − 1) d / (n R₁ R₂)], and the
        // back focus f (1 − (n − 1) d / (n R₁)).
        let (r1, r2, d, n) = (50.0, -80.0, 6.0, 1.5);
        let mut stop = surface(None, 2.0, Medium::Air);
        stop.stop = true;
        let lens = lens(vec![
            stop,
            surface(Some(r1), d, GLASS),
            surface(Some(r2), 0.0, Medium::Air),
        ]);
        let p = trace(&lens, 587.5618, Meridian::Y).unwrap();
        let f = 1.0 / ((n - 1.0) * (1.0 / r1 - 1.0 / r2 + (n - 1.0) * d / (n * r1 * r2)));
        assert!(
            (p.focal_length - f).abs() < 1e-9 * f,
            "{} {f}",
            p.focal_length
        );
        let back = f * (1.0 - (n - 1.0) * d / (n * r1));
        assert!((p.back_focus - back).abs() < 1e-9 * f);
        // The stop in front of everything is its own entrance pupil.
        assert!(p.entrance_pupil.abs() < 1e-12);
        assert!((p.entrance_pupil_radius - 5.0).abs() < 1e-12);
    }

    #[test]
    fn a_stop_behind_a_thin_lens_is_seen_magnified_behind_it() {
        // A thin lens of f = 100 and a stop 50 behind it: the stop's image
        // lies at 1/s′ = 1/100 − 1/50 → s′ = −100, i.e. 100 behind the
        // lens, magnified 2×.
        let thin = |r: f64| surface(Some(r), 0.0, GLASS);
        let mut first = thin(100.0);
        first.thickness = 0.0;
        let mut second = surface(Some(-100.0), 50.0, Medium::Air);
        second.semi_aperture = 20.0;
        let mut stop = surface(None, 10.0, Medium::Air);
        stop.stop = true;
        stop.semi_aperture = 4.0;
        let p = trace(&lens(vec![first, second, stop]), 587.5618, Meridian::Y)
            .unwrap_or_else(|e| panic!("{e}"));
        assert!((p.focal_length - 100.0).abs() < 1e-9);
        assert!(
            (p.entrance_pupil - 100.0).abs() < 1e-9,
            "{}",
            p.entrance_pupil
        );
        assert!((p.entrance_pupil_radius - 8.0).abs() < 1e-9);
        assert!((p.f_number - 6.25).abs() < 1e-9);
    }

    #[test]
    fn a_diverging_lens_is_refused() {
        let mut stop = surface(None, 1.0, Medium::Air);
        stop.stop = true;
        let lens = lens(vec![
            stop,
            surface(Some(-50.0), 3.0, GLASS),
            surface(Some(50.0), 0.0, Medium::Air),
        ]);
        let error = trace(&lens, 587.5618, Meridian::Y).unwrap_err().to_string();
        assert!(error.contains("positive"), "{error}");
    }
}
