//! Measurements on a kernel: radial and angular profiles, as the paper's
//! "filter profile" figures show them and as the tests compare with theory.

use super::Kernel;

/// The mean weight on rings of 1 px width: element i averages the pixels
/// whose centre lies at a distance in [i − ½, i + ½) from the kernel centre,
/// for the rings that fit whole inside the kernel.
pub fn radial_profile(kernel: &Kernel, plane: usize) -> Vec<f64> {
    let (cx, cy) = kernel.centre();
    let rings = cx
        .min(cy)
        .min(kernel.width() - 1 - cx)
        .min(kernel.height() - 1 - cy)
        + 1;
    let mut sums = vec![0.0; rings];
    let mut counts = vec![0usize; rings];
    let values = &kernel.planes()[plane];
    for (j, row) in values.chunks(kernel.width()).enumerate() {
        let dy = j as f64 - cy as f64;
        for (i, &v) in row.iter().enumerate() {
            let dx = i as f64 - cx as f64;
            let ring = (dx * dx + dy * dy).sqrt().round() as usize;
            if ring < rings {
                sums[ring] += f64::from(v);
                counts[ring] += 1;
            }
        }
    }
    sums.iter()
        .zip(&counts)
        .map(|(s, &n)| if n > 0 { s / n as f64 } else { 0.0 })
        .collect()
}

/// The kernel at `samples` evenly spaced directions on the circle of
/// `radius` px, by bilinear interpolation: (angle in degrees from +x,
/// counter-clockwise, value).
pub fn angular_profile(
    kernel: &Kernel,
    plane: usize,
    radius: f64,
    samples: usize,
) -> Vec<(f64, f64)> {
    (0..samples)
        .map(|s| {
            let angle = 360.0 * s as f64 / samples as f64;
            let (sin, cos) = libm::sincos(angle.to_radians());
            (angle, bilinear(kernel, plane, radius * cos, radius * sin))
        })
        .collect()
}

/// The kernel interpolated at (x, y) px from the centre, y up; 0 outside.
pub fn bilinear(kernel: &Kernel, plane: usize, x: f64, y: f64) -> f64 {
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let at = |dx: f64, dy: f64| f64::from(kernel.at(plane, dx as i64, dy as i64));
    (1.0 - fy) * ((1.0 - fx) * at(x0, y0) + fx * at(x0 + 1.0, y0))
        + fy * ((1.0 - fx) * at(x0, y0 + 1.0) + fx * at(x0 + 1.0, y0 + 1.0))
}
