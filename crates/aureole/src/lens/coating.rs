//! How much light a surface reflects: Fresnel's equations for bare glass,
//! and for a coated surface the thin-film stack's characteristic matrices
//! (Abelès), for s and p light at the angle of incidence, averaged for
//! unpolarised light (docs/physics.md §12). The layers and media are
//! lossless, so what is not reflected is transmitted.

use std::f64::consts::PI;

use rustfft::num_complex::Complex64;

use super::Layer;

/// The reflectance, for unpolarised light of wavelength `nm`, of the
/// interface from a medium of index `n_in` into one of `n_out` through
/// `layers` (listed from the incidence side inwards), where the ray meets
/// it at `cos_in`, the cosine of its angle from the normal in `n_in`.
pub fn reflectance(n_in: f64, n_out: f64, layers: &[Layer], cos_in: f64, nm: f64) -> f64 {
    let sin2 = (1.0 - cos_in * cos_in).max(0.0);
    let invariant = n_in * n_in * sin2;
    // Bare glass and a single layer the light crosses (the surfaces of a
    // camera lens, all but beyond the critical angle) in real arithmetic:
    // the same reflectance as the matrices', in a fraction of the time.
    let real_cos = |n: f64| {
        let c2 = 1.0 - invariant / (n * n);
        (c2 > 0.0).then(|| c2.sqrt())
    };
    if let Some(cos_sub) = real_cos(n_out) {
        match layers {
            [] => return bare(n_in, n_out, cos_in, cos_sub),
            [layer] => {
                if let Some(cos_layer) = real_cos(layer.index) {
                    let media = [(n_in, cos_in), (layer.index, cos_layer), (n_out, cos_sub)];
                    let phase = 4.0 * PI * layer.index * layer.thickness_nm * cos_layer / nm;
                    return single_layer(media, libm::cos(phase));
                }
            }
            _ => {}
        }
    }
    stack(n_in, n_out, layers, cos_in, nm)
}

/// A surface's reflectance at one wavelength tabulated over the cosine
/// of the angle of incidence, interpolated linearly between its samples:
/// a table of 4097 samples gives it to 10⁻⁶ (at grazing incidence, where
/// it climbs to 1; far less elsewhere), in a fraction of the time. Near
/// the critical angle, where the reflectance rises to 1 with an infinite
/// slope, it gives nothing and the caller computes it exactly.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    values: Vec<f64>,
    /// The cosine of the critical angle (0 where there is none).
    critical: f64,
}

/// Intervals of a [`Table`] over cos θ from 0 to 1.
const INTERVALS: usize = 4096;

impl Table {
    /// The table of the interface [`reflectance`] describes.
    pub fn new(n_in: f64, n_out: f64, layers: &[Layer], nm: f64) -> Table {
        let values = (0..=INTERVALS)
            .map(|k| reflectance(n_in, n_out, layers, k as f64 / INTERVALS as f64, nm))
            .collect();
        // Total reflection where n_in sin θ > n_out (the layers, thin, do
        // not stop the light tunnelling, but the table leaves the
        // neighbourhood to the exact formula all the same).
        let critical = if n_in > n_out {
            (1.0 - (n_out / n_in).powi(2)).sqrt()
        } else {
            0.0
        };
        Table { values, critical }
    }

    /// The reflectance at `cos_in`, or `None` near the critical angle.
    pub fn at(&self, cos_in: f64) -> Option<f64> {
        // Below the critical angle R = 1 − a√(cos − cos_c) or so: the
        // interpolation's error, ~a h^½/(8 (d/h)^{3/2}) at a distance d,
        // stays under 10⁻⁶ from d = 0.06 on.
        if (cos_in - self.critical).abs() < 0.06 || !(0.0..=1.0).contains(&cos_in) {
            return None;
        }
        let at = cos_in * INTERVALS as f64;
        let k = (at as usize).min(INTERVALS - 1);
        let f = at - k as f64;
        Some(self.values[k] + f * (self.values[k + 1] - self.values[k]))
    }
}

/// Fresnel's reflectance of an interface between two media, unpolarised,
/// from the cosines on either side.
fn bare(n_in: f64, n_out: f64, cos_in: f64, cos_out: f64) -> f64 {
    let rs = (n_in * cos_in - n_out * cos_out) / (n_in * cos_in + n_out * cos_out);
    let rp = (n_out * cos_in - n_in * cos_out) / (n_out * cos_in + n_in * cos_out);
    (0.5 * (rs * rs + rp * rp)).clamp(0.0, 1.0)
}

/// One lossless layer between two media, each (index, cosine of the
/// angle in it), its round-trip phase's cosine given (Airy's sum of the
/// layer's reflections): for each polarisation, with the interfaces'
/// amplitudes r₁ and r₂ from the tilted admittances,
/// R = (r₁² + r₂² + 2r₁r₂ cos 2δ) / (1 + r₁²r₂² + 2r₁r₂ cos 2δ).
fn single_layer(media: [(f64, f64); 3], cos_phase: f64) -> f64 {
    let [(n0, c0), (n1, c1), (n2, c2)] = media;
    let amplitude = |a: f64, b: f64| (a - b) / (a + b);
    let polarised = |eta: [f64; 3]| {
        let (r1, r2) = (amplitude(eta[0], eta[1]), amplitude(eta[1], eta[2]));
        let cross = 2.0 * r1 * r2 * cos_phase;
        (r1 * r1 + r2 * r2 + cross) / (1.0 + r1 * r1 * r2 * r2 + cross)
    };
    let s = polarised([n0 * c0, n1 * c1, n2 * c2]);
    let p = polarised([n0 / c0, n1 / c1, n2 / c2]);
    (0.5 * (s + p)).clamp(0.0, 1.0)
}

/// [`reflectance`] by the characteristic matrices of any stack, the light
/// evanescent in a layer or the medium beyond included.
fn stack(n_in: f64, n_out: f64, layers: &[Layer], cos_in: f64, nm: f64) -> f64 {
    let sin2 = (1.0 - cos_in * cos_in).max(0.0);
    // n sin θ is kept through every layer (Snell); cos θ in a layer is
    // imaginary where the light cannot propagate there (beyond the
    // critical angle), with a positive part so that the field decays.
    let invariant = n_in * n_in * sin2;
    let cos_of = |n: f64| root(1.0 - invariant / (n * n));
    let (cos_sub, cos_0) = (cos_of(n_out), Complex64::new(cos_in, 0.0));
    // The tilted admittances: n cos θ for s light, n / cos θ for p.
    let admittances = |n: f64, cos: Complex64| [cos * n, Complex64::new(n, 0.0) / cos];
    let sub = admittances(n_out, cos_sub);
    let one = Complex64::new(1.0, 0.0);
    // [B, C] = M₁ M₂ … M_q [1, η_sub] for s and p light at once, the
    // innermost layer applied first: a layer's phase thickness δ is the
    // same for both, its sine and cosine taken once.
    let (mut b, mut c) = ([one, one], sub);
    for layer in layers.iter().rev() {
        let cos = cos_of(layer.index);
        let delta = cos * (2.0 * PI * layer.index * layer.thickness_nm / nm);
        let (sin_d, cos_d) = sin_cos(delta);
        let i = Complex64::new(0.0, 1.0);
        for (k, eta) in admittances(layer.index, cos).into_iter().enumerate() {
            (b[k], c[k]) = (
                cos_d * b[k] + i * sin_d / eta * c[k],
                i * eta * sin_d * b[k] + cos_d * c[k],
            );
        }
    }
    let eta_0 = admittances(n_in, cos_0);
    let total: f64 = (0..2)
        .map(|k| ((eta_0[k] * b[k] - c[k]) / (eta_0[k] * b[k] + c[k])).norm_sqr())
        .sum();
    (0.5 * total).clamp(0.0, 1.0)
}

/// √x for a real x, with a positive imaginary part where x < 0.
fn root(x: f64) -> Complex64 {
    if x >= 0.0 {
        Complex64::new(x.sqrt(), 0.0)
    } else {
        Complex64::new(0.0, (-x).sqrt())
    }
}

/// sin z and cos z through `libm`, the same bits on every machine (the
/// complex type's own call the platform's maths library).
fn sin_cos(z: Complex64) -> (Complex64, Complex64) {
    let (sin, cos) = libm::sincos(z.re);
    // A layer the light crosses (a real phase): no hyperbolic part.
    if z.im == 0.0 {
        return (Complex64::new(sin, 0.0), Complex64::new(cos, 0.0));
    }
    let (sinh, cosh) = (libm::sinh(z.im), libm::cosh(z.im));
    (
        Complex64::new(sin * cosh, cos * sinh),
        Complex64::new(cos * cosh, -sin * sinh),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn real_arithmetic_reflects_as_the_matrices_do() {
        // Bare and single-layer surfaces take the short way; the matrices
        // of the general stack are the reference, over angles, indices
        // and wavelengths.
        let mut worst: f64 = 0.0;
        for (n_in, n_out) in [
            (1.0, 1.52),
            (1.52, 1.0),
            (1.0, 1.9),
            (1.75, 1.0),
            (1.6, 1.7),
        ] {
            for layers in [
                vec![],
                vec![Layer {
                    index: 1.38,
                    thickness_nm: 99.6,
                }],
                vec![Layer {
                    index: 2.1,
                    thickness_nm: 180.0,
                }],
            ] {
                for k in 0..=40 {
                    let cos_in = 0.02 + 0.98 * f64::from(k) / 40.0;
                    for nm in [400.0, 550.0, 700.0] {
                        let fast = reflectance(n_in, n_out, &layers, cos_in, nm);
                        let matrices = stack(n_in, n_out, &layers, cos_in, nm);
                        worst = worst.max((fast - matrices).abs());
                    }
                }
            }
        }
        assert!(worst < 1e-14, "{worst}");
    }

    #[test]
    fn a_table_gives_the_reflectance_to_within_its_interpolation() {
        let mgf2 = [Layer {
            index: 1.38,
            thickness_nm: 99.6,
        }];
        for (n_in, n_out, layers) in [
            (1.0, 1.62, &mgf2[..]),
            (1.62, 1.0, &mgf2[..]),
            (1.5, 1.7, &[][..]),
        ] {
            let table = Table::new(n_in, n_out, layers, 480.0);
            let mut worst: f64 = 0.0;
            for k in 0..=1000 {
                let cos_in = f64::from(k) / 1000.0;
                let exact = reflectance(n_in, n_out, layers, cos_in, 480.0);
                if let Some(r) = table.at(cos_in) {
                    worst = worst.max((r - exact).abs());
                }
            }
            assert!(worst < 1e-6, "{n_in} → {n_out}: {worst}");
        }
    }

    #[test]
    fn bare_glass_reflects_as_fresnel_says() {
        // Normal incidence: ((n − 1)/(n + 1))², 4 % for n = 1.5.
        let r = reflectance(1.0, 1.5, &[], 1.0, 550.0);
        assert!((r - 0.04).abs() < 1e-15, "{r}");
        // 45°: the s and p amplitudes of Fresnel's equations.
        let (n1, n2, ci) = (1.0f64, 1.5f64, libm::cos(PI / 4.0));
        let ct = (1.0 - (n1 / n2).powi(2) * (1.0 - ci * ci)).sqrt();
        let rs = (n1 * ci - n2 * ct) / (n1 * ci + n2 * ct);
        let rp = (n2 * ci - n1 * ct) / (n2 * ci + n1 * ct);
        let r = reflectance(n1, n2, &[], ci, 550.0);
        assert!((r - 0.5 * (rs * rs + rp * rp)).abs() < 1e-15);
        // Brewster's angle reflects no p light; from the glass side the
        // same interface reflects as much (a lossless interface).
        let brewster = libm::atan(1.5);
        let r = reflectance(1.0, 1.5, &[], libm::cos(brewster), 550.0);
        let ct = libm::cos(libm::asin(libm::sin(brewster) / 1.5));
        let rs = (libm::cos(brewster) - 1.5 * ct) / (libm::cos(brewster) + 1.5 * ct);
        assert!((r - 0.5 * rs * rs).abs() < 1e-15);
        assert!((reflectance(1.5, 1.0, &[], ct, 550.0) - r).abs() < 1e-15);
        // Beyond the critical angle, everything.
        assert!((reflectance(1.5, 1.0, &[], libm::cos(0.8), 550.0) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_quarter_wave_layer_reflects_as_its_admittances_say() {
        // At its design wavelength and normal incidence a quarter-wave
        // layer of n_f on n_s reflects ((n₀n_s − n_f²)/(n₀n_s + n_f²))²:
        // MgF₂ on n = 1.52 about 1.3 %, and none where n_f² = n_s.
        let layer = |n: f64| Layer {
            index: n,
            thickness_nm: 550.0 / (4.0 * n),
        };
        let expected = |nf: f64, ns: f64| ((ns - nf * nf) / (ns + nf * nf)).powi(2);
        let r = reflectance(1.0, 1.52, &[layer(1.38)], 1.0, 550.0);
        assert!((r - expected(1.38, 1.52)).abs() < 1e-15, "{r}");
        assert!(reflectance(1.0, 1.69, &[layer(1.3)], 1.0, 550.0) < 1e-15);
        // A half-wave layer is absent at its wavelength.
        let half = Layer {
            index: 1.38,
            thickness_nm: 550.0 / 2.0 / 1.38,
        };
        let bare = reflectance(1.0, 1.52, &[], 1.0, 550.0);
        assert!((reflectance(1.0, 1.52, &[half], 1.0, 550.0) - bare).abs() < 1e-15);
        // Away from the design wavelength it reflects more, towards bare
        // glass, and a stack read from the other side reflects alike.
        let blue = reflectance(1.0, 1.52, &[layer(1.38)], 1.0, 400.0);
        assert!(blue > r && blue < bare, "{blue}");
        let stack = [layer(1.65), layer(2.1), layer(1.38)];
        let front = reflectance(1.0, 1.6, &stack, 0.9, 480.0);
        let reversed: Vec<Layer> = stack.iter().rev().copied().collect();
        let cos_glass = (1.0f64 - (1.0 - 0.81) / (1.6 * 1.6)).sqrt();
        let back = reflectance(1.6, 1.0, &reversed, cos_glass, 480.0);
        assert!((front - back).abs() < 1e-12, "{front} {back}");
    }
}
