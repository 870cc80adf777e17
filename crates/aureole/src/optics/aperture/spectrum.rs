//! Colour: the CIE 1931 2° colour-matching functions and the sensitivities
//! of linear Rec.709 R, G, B to each wavelength (docs/physics.md §6), and
//! the light a diffraction kernel integrates.
//!
//! The colour-matching functions are the multi-lobe piecewise-Gaussian fit
//! of Wyman, Sloan and Shirley (JCGT 2013), within about 1 % of the CIE
//! tables over 380–780 nm, so no table has to be shipped.

/// Shortest wavelength sampled, nm.
pub const LAMBDA_MIN_NM: f64 = 380.0;
/// Longest wavelength sampled, nm.
pub const LAMBDA_MAX_NM: f64 = 780.0;
/// How many wavelengths a coloured kernel integrates (every 25 nm,
/// 380–780 nm).
pub const WAVELENGTHS: usize = 17;

/// The light a diffraction kernel integrates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Light {
    /// 380–780 nm into linear Rec.709 R, G, B (three planes).
    Spectral,
    /// One wavelength in nm (one plane).
    Monochrome(f64),
}

impl Light {
    /// Its wavelengths (nm), each with its weight in every plane.
    pub fn wavelengths(self) -> Vec<(f64, Vec<f64>)> {
        match self {
            Light::Spectral => wavelengths()
                .into_iter()
                .map(|(l, w)| (l, w.to_vec()))
                .collect(),
            Light::Monochrome(nm) => vec![(nm, vec![1.0])],
        }
    }
}

fn lobe(lambda: f64, mean: f64, below: f64, above: f64) -> f64 {
    let sigma = if lambda < mean { below } else { above };
    let t = (lambda - mean) / sigma;
    libm::exp(-0.5 * t * t)
}

/// CIE 1931 2° x̄, ȳ, z̄ at `lambda` nm.
pub fn cie_xyz(lambda: f64) -> [f64; 3] {
    let x = 1.056 * lobe(lambda, 599.8, 37.9, 31.0) + 0.362 * lobe(lambda, 442.0, 16.0, 26.7)
        - 0.065 * lobe(lambda, 501.1, 20.4, 26.2);
    let y = 0.821 * lobe(lambda, 568.8, 46.9, 40.5) + 0.286 * lobe(lambda, 530.9, 16.3, 31.1);
    let z = 1.217 * lobe(lambda, 437.0, 11.8, 36.0) + 0.681 * lobe(lambda, 459.0, 26.0, 13.8);
    [x, y, z]
}

/// Linear Rec.709 R, G, B sensitivity at `lambda` nm: the colour-matching
/// functions taken to Rec.709 (D65), negative lobes clipped so that no
/// kernel goes negative.
pub fn rec709_sensitivity(lambda: f64) -> [f64; 3] {
    let [x, y, z] = cie_xyz(lambda);
    [
        3.240_454_2 * x - 1.537_138_5 * y - 0.498_531_4 * z,
        -0.969_266_0 * x + 1.876_010_8 * y + 0.041_556_0 * z,
        0.055_643_4 * x - 0.204_025_9 * y + 1.057_225_2 * z,
    ]
    .map(|v| v.max(0.0))
}

/// The wavelengths (nm) of a coloured kernel with their R, G, B weights.
pub fn wavelengths() -> Vec<(f64, [f64; 3])> {
    (0..WAVELENGTHS)
        .map(|i| {
            let lambda = LAMBDA_MIN_NM
                + (LAMBDA_MAX_NM - LAMBDA_MIN_NM) * i as f64 / (WAVELENGTHS - 1) as f64;
            (lambda, rec709_sensitivity(lambda))
        })
        .collect()
}

/// The sensitivity-weighted mean wavelength of each channel, nm.
pub fn mean_wavelengths() -> [f64; 3] {
    let wavelengths = wavelengths();
    [0, 1, 2].map(|c| {
        let total: f64 = wavelengths.iter().map(|(_, w)| w[c]).sum();
        wavelengths.iter().map(|(l, w)| l * w[c]).sum::<f64>() / total
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fit_has_the_cie_peaks() {
        // CIE 1931 2°: ȳ(555) = 1.000, x̄(600) = 1.062, z̄(445) = 1.783.
        assert!((cie_xyz(555.0)[1] - 1.0).abs() < 0.01);
        assert!((cie_xyz(600.0)[0] - 1.062).abs() < 0.01);
        assert!((cie_xyz(445.0)[2] - 1.783).abs() < 0.02);
    }

    #[test]
    fn sensitivities_are_non_negative_and_ordered_by_wavelength() {
        for (_, w) in wavelengths() {
            assert!(w.iter().all(|v| *v >= 0.0));
        }
        let [r, g, b] = mean_wavelengths();
        assert!(r > g && g > b, "{r} {g} {b}");
        assert!(
            (590.0..640.0).contains(&r) && (440.0..480.0).contains(&b),
            "{r} {b}"
        );
    }
}
