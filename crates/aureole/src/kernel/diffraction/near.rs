//! The near field of a diffraction pattern: |Â(x/(λf))|² evaluated exactly
//! from the pupil's closed-form transform, averaged over each pixel at
//! sample points spread by a low-discrepancy sequence, for every
//! wavelength (docs/physics.md §6).

use super::Spectrum;
use crate::optics::aperture::pupil::Offsets;
use crate::optics::aperture::Optics;

/// How a pixel of the near field is sampled, for one pupil and light.
pub(super) struct NearField<'a> {
    optics: &'a Optics,
    spectrum: &'a Spectrum,
    pitch_mm: f64,
    /// Sample points per axis in the centre pixel and its neighbours.
    dense: usize,
    /// The sample offsets of most pixels, per wavelength.
    offsets: Vec<Offsets>,
}

impl<'a> NearField<'a> {
    pub fn new(optics: &'a Optics, spectrum: &'a Spectrum, pitch_mm: f64) -> NearField<'a> {
        let f = optics.focal_mm;
        let shortest = spectrum
            .iter()
            .map(|(l, _)| *l)
            .fold(f64::INFINITY, f64::min)
            * 1e-6;
        // Fringes repeat every λf/D in the focal plane: two samples per
        // fringe at the shortest wavelength, shared out among the
        // wavelengths, which sample the pixel on offset grids.
        let per_pixel = (2.0 * pitch_mm * optics.diameter_mm / (shortest * f))
            .ceil()
            .clamp(1.0, 16.0);
        let grid = if spectrum.len() > 1 {
            (per_pixel / 3.0).ceil()
        } else {
            per_pixel
        } as usize;
        // The centre pixel and its neighbours hold most of the light: with
        // pixels wider than λN the Airy core is a fraction of a pixel wide,
        // and a few samples that miss or hit it would set the share of
        // everything else. Eight samples per fringe there, for every
        // wavelength.
        let dense = (8.0 * pitch_mm * optics.diameter_mm / (shortest * f))
            .ceil()
            .clamp(grid as f64, 128.0) as usize;
        NearField {
            optics,
            spectrum,
            pitch_mm,
            dense,
            offsets: offsets(optics, spectrum, pitch_mm, grid),
        }
    }
}

impl NearField<'_> {
    /// [`NearField::add`] for pixels of one row, centred at (`xs`[i], y)
    /// mm, all in the core or none: `out` holds their values side by side
    /// (`planes` each). The pixels share their sample offsets, which lets
    /// the pupil's transform factor them out ([`Pupil::intensity_sums`]).
    ///
    /// [`Pupil::intensity_sums`]: crate::optics::aperture::pupil::Pupil::intensity_sums
    pub fn add_many(&self, xs: &[f64], y: f64, core: bool, out: &mut [f64]) {
        let (f, pitch_mm) = (self.optics.focal_mm, self.pitch_mm);
        let area = self.optics.pupil.area();
        let planes = out.len() / xs.len().max(1);
        let mut sums = vec![0.0; xs.len()];
        // The core's many samples are needed for a few pixels only: not
        // kept.
        let dense;
        let offsets = if core {
            dense = offsets(self.optics, self.spectrum, pitch_mm, self.dense);
            &dense
        } else {
            &self.offsets
        };
        for ((lambda_nm, weights), offsets) in self.spectrum.iter().zip(offsets) {
            let scale = 1.0 / (lambda_nm * 1e-6 * f);
            let nu_x: Vec<f64> = xs.iter().map(|x| x * scale).collect();
            self.optics
                .pupil
                .intensity_sums(&nu_x, y * scale, offsets, &mut sums);
            let points = offsets.len() as f64;
            for (pixel, sum) in out.chunks_mut(planes).zip(&sums) {
                // Energy in the pixel: mean PSF × pixel area.
                let energy = sum / points * scale * scale / area * pitch_mm * pitch_mm;
                for (value, weight) in pixel.iter_mut().zip(weights) {
                    *value += weight * energy;
                }
            }
        }
    }
}

/// The sample offsets of a pixel at `per_axis`² points for each wavelength
/// of `spectrum`, in cycles/mm: cells' centres moved by a different
/// fraction per wavelength (golden-ratio steps), spread over the pixel.
fn offsets(optics: &Optics, spectrum: &Spectrum, pitch_mm: f64, per_axis: usize) -> Vec<Offsets> {
    spectrum
        .iter()
        .enumerate()
        .map(|(k, (lambda_nm, _))| {
            let scale = 1.0 / (lambda_nm * 1e-6 * optics.focal_mm);
            let (ox, oy) = (
                frac(0.5 + 0.618_034 * k as f64),
                frac(0.5 + 0.754_878 * k as f64),
            );
            let (dx, dy) = (0..per_axis * per_axis)
                .map(|n| {
                    let (u, v) = kronecker(n, ox, oy);
                    (pitch_mm * (u - 0.5) * scale, pitch_mm * (v - 0.5) * scale)
                })
                .unzip();
            optics.pupil.offsets(dx, dy)
        })
        .collect()
}

/// Point `n` of the R2 sequence (Roberts 2018, steps 1/g and 1/g², g the
/// plastic number) moved by (ox, oy), in the unit square: evenly spread for
/// any run of consecutive points, and on no lattice. A lattice of samples
/// in every pixel is one lattice over the whole kernel, whose moiré with
/// the Airy rings draws a cross along the axes.
fn kronecker(n: usize, ox: f64, oy: f64) -> (f64, f64) {
    const G: f64 = 1.324_717_957_244_746;
    let n = n as f64;
    (frac(ox + n / G), frac(oy + n / (G * G)))
}

fn frac(v: f64) -> f64 {
    v - v.floor()
}
