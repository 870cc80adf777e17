//! The moments of a ghost's light on a sensor plane, for the ghost tests
//! (ghosts.rs, anamorphic.rs).

use aureole::lens::ghost::Sensor;

/// The centroid of a plane's light (mm), its RMS extents along x and y
/// about it (mm), and the light.
pub fn moments(plane: &[f64], sensor: &Sensor) -> [f64; 5] {
    let (mut sum, mut x, mut y, mut xx, mut yy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (k, v) in plane.iter().enumerate() {
        let px = ((k % sensor.width) as f64 + 0.5 - 0.5 * sensor.width as f64) * sensor.pitch_mm;
        let py = (0.5 * sensor.height as f64 - (k / sensor.width) as f64 - 0.5) * sensor.pitch_mm;
        sum += v;
        x += v * px;
        y += v * py;
        xx += v * px * px;
        yy += v * py * py;
    }
    let (x, y) = (x / sum, y / sum);
    [
        x,
        y,
        (xx / sum - x * x).max(0.0).sqrt(),
        (yy / sum - y * y).max(0.0).sqrt(),
        sum,
    ]
}
