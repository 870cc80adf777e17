//! The f64 engine, for scenes whose range f32 cannot hold: FFT round-off is
//! about the unit round-off times the largest value, so a sun of 10⁹ cd/m²
//! leaves ~100 cd/m² of noise in f32 over a night sky of 10⁻² cd/m², and
//! ~10⁻⁷ cd/m² in f64. Slower and twice the memory of the f32 engine
//! ([`super::single`]), so the pipeline uses it only when the range asks
//! for it (docs/physics.md §8).

use rayon::prelude::*;
use realfft::num_complex::Complex;

use super::grid::{Grid, Transforms};
use super::placement::Placement;
use super::pool::Pool;
use super::{Centre, Engine, Footprint, Load, Spread};
use crate::control::{Cancel, Control};
use crate::error::Result;
use crate::image::{grow_zeroed, zeros};

/// Columns transformed, or rows gathered, by one task: 128 bytes of each
/// row or column it reads.
const STRIP: usize = 8;

/// What the engine holds: transforming, the spectra and one kernel
/// plane's rows; spreading, the spectra, and for the plane in flight its
/// spread and summed planes and their spectrum, and its output rows.
pub(super) fn footprint(load: &Load) -> Footprint {
    const COMPLEX: u64 = 16;
    let (px, py) = Grid::new(load.kernel, load.image, false).padded();
    let (half, px, py) = (px as u64 / 2 + 1, px as u64, py as u64);
    let spectra = half * py * COMPLEX * load.kernel_planes as u64;
    let pixels = load.image.0 as u64 * load.image.1 as u64;
    Footprint {
        preparing: spectra + load.kernel.1 as u64 * (px * 8 + half * COMPLEX),
        spreading: spectra + 3 * pixels * 8 + half * py * COMPLEX + load.image.1 as u64 * px * 24,
    }
}

/// The kernel's spectra and the transforms for one image size, in f64.
pub struct Convolver {
    width: usize,
    height: usize,
    px: usize,
    py: usize,
    /// Per kernel plane, column-major: column u holds its `py` values.
    spectra: Vec<Vec<Complex<f64>>>,
    /// The weight each kernel plane left out of its spectrum, applied
    /// exactly.
    centres: Vec<f32>,
    transforms: Transforms<f64>,
    /// The column-major spectrum of the plane being convolved.
    buffers: Pool<Vec<Complex<f64>>>,
}

impl Convolver {
    /// Plans the convolution of `width`×`height` images with a kernel given
    /// as planes (row-major, `size` = width × height, centre at its middle),
    /// and transforms it; with [`Centre::Leave`] the centre weight is left
    /// out of the spectrum and applied exactly.
    pub fn new(
        planes: &[&[f32]],
        size: (usize, usize),
        width: usize,
        height: usize,
        centre: Centre,
        control: &mut Control,
    ) -> Result<Convolver> {
        let (px, py) = Grid::new(size, (width, height), false).padded();
        let mut convolver = Convolver {
            width,
            height,
            px,
            py,
            spectra: Vec::new(),
            centres: Vec::new(),
            transforms: Transforms::plan(px, py),
            buffers: Pool::new(),
        };
        let cancel = control.cancel();
        for (k, plane) in planes.iter().enumerate() {
            let placed = Placement {
                plane,
                size,
                centre,
                hole: None,
            };
            let rows: Vec<(usize, Vec<f64>)> = (0..size.1)
                .into_par_iter()
                .map(|j| {
                    let mut row = vec![0.0; px];
                    placed.row(j, &mut row);
                    (placed.period_row(j, py), row)
                })
                .collect();
            let mut spectrum = Vec::new();
            convolver.transform(rows, &mut spectrum, &cancel)?;
            control.check()?;
            convolver.spectra.push(spectrum);
            convolver.centres.push(placed.left_out());
            control.report((k + 1) as f64 / planes.len() as f64);
        }
        Ok(convolver)
    }

    /// The 2-D spectrum into `columns` (column-major) of the rows given as
    /// (padded row index, real row of length `px`); other rows are zero.
    fn transform(
        &self,
        rows: Vec<(usize, Vec<f64>)>,
        columns: &mut Vec<Complex<f64>>,
        cancel: &Cancel,
    ) -> Result<()> {
        let half = self.px / 2 + 1;
        let py = self.py;
        let spectra: Vec<(usize, Vec<Complex<f64>>)> = rows
            .into_par_iter()
            .map(|(index, mut row)| {
                let mut spectrum = self.transforms.row_fft.make_output_vec();
                if !cancel.is_cancelled() {
                    // The lengths are the planned ones, so this cannot fail.
                    let _ = self.transforms.row_fft.process(&mut row, &mut spectrum);
                }
                (index, spectrum)
            })
            .collect();
        // Each column is cleared and filled where its strip's task works:
        // a strip of columns reads a cache line or two of every row
        // spectrum, where a column alone would read one value of each.
        grow_zeroed(columns, half * py)?;
        // An image's rows fill each column's first `rows` values: only the
        // padding below them is cleared (a kernel's rows wrap around).
        let rows = spectra.len();
        let leading = spectra
            .iter()
            .enumerate()
            .all(|(i, (index, _))| *index == i);
        columns
            .par_chunks_mut(STRIP * py)
            .enumerate()
            .for_each(|(s, strip)| {
                if cancel.is_cancelled() {
                    return;
                }
                if leading {
                    for column in strip.chunks_mut(py) {
                        column[rows..].fill(Complex::new(0.0, 0.0));
                    }
                } else {
                    strip.fill(Complex::new(0.0, 0.0));
                }
                let first = s * STRIP;
                for (index, spectrum) in &spectra {
                    for (c, &v) in spectrum[first..first + strip.len() / py].iter().enumerate() {
                        strip[c * py + index] = v;
                    }
                }
                for column in strip.chunks_mut(py) {
                    self.transforms.column_fft.process(column);
                }
            });
        Ok(())
    }

    /// `plane` (row-major, `width`×`height`) convolved with kernel plane
    /// `kernel_plane` less what it left out, over the same frame.
    fn convolve(&self, plane: &[f64], kernel_plane: usize, cancel: &Cancel) -> Result<Vec<f64>> {
        let (w, h, px, py) = (self.width, self.height, self.px, self.py);
        let half = px / 2 + 1;
        let rows = (0..h)
            .into_par_iter()
            .map(|y| {
                let mut row = Vec::with_capacity(px);
                row.extend_from_slice(&plane[y * w..(y + 1) * w]);
                row.resize(px, 0.0);
                (y, row)
            })
            .collect();
        let mut lease = self.buffers.lease();
        lease.resize_with(1, Vec::new);
        let columns = &mut lease[0];
        self.transform(rows, columns, cancel)?;
        let kernel = &self.spectra[kernel_plane];
        let scale = 1.0 / (px * py) as f64;
        columns
            .par_chunks_mut(py)
            .zip(kernel.par_chunks(py))
            .for_each(|(column, k)| {
                if cancel.is_cancelled() {
                    return;
                }
                for (v, k) in column.iter_mut().zip(k) {
                    *v *= k * scale;
                }
                self.transforms.column_ifft.process(column);
            });
        let columns = &*columns;
        let mut out = zeros(w * h)?;
        // A block of rows at a time: each column gives a run of values
        // for all of them.
        // Each task keeps its block's spectra and real row from block to
        // block: every value of them is written before it is read.
        let buffers = || {
            (
                vec![vec![Complex::new(0.0, 0.0); half]; STRIP],
                self.transforms.row_ifft.make_output_vec(),
            )
        };
        out.par_chunks_mut(w * STRIP).enumerate().for_each_init(
            buffers,
            |(spectra, real), (b, rows)| {
                if cancel.is_cancelled() {
                    return;
                }
                let first = b * STRIP;
                let count = rows.len() / w;
                let spectra = &mut spectra[..count];
                for u in 0..half {
                    let run = &columns[u * py + first..u * py + first + count];
                    for (spectrum, &v) in spectra.iter_mut().zip(run) {
                        spectrum[u] = v;
                    }
                }
                for (row, spectrum) in rows.chunks_mut(w).zip(spectra.iter_mut()) {
                    // The inverse real transform wants exactly real end
                    // bins; after the column passes they hold round-off.
                    spectrum[0].im = 0.0;
                    if px % 2 == 0 {
                        spectrum[half - 1].im = 0.0;
                    }
                    let _ = self.transforms.row_ifft.process(spectrum, real);
                    row.copy_from_slice(&real[..w]);
                }
            },
        );
        Ok(out)
    }

    /// One output in f64 throughout: O = I − B + Σ w (K′ ⊛ B + c·B), with
    /// K′ the kernel plane less its centre weight c; then rounded to f32
    /// once, into `out`.
    fn output(&self, spread: &Spread, out: &mut Vec<f32>, control: &mut Control) -> Result<()> {
        let plane = spread.plane;
        let bright: Vec<f64> = match spread.fractions {
            Some(fractions) => plane
                .par_iter()
                .zip(fractions)
                .map(|(&v, &f)| f64::from(v) * f64::from(f))
                .collect(),
            None => plane.par_iter().map(|&v| f64::from(v)).collect(),
        };
        let mut sum: Vec<f64> = plane
            .par_iter()
            .zip(&bright)
            .map(|(&v, b)| f64::from(v) - b)
            .collect();
        for (t, term) in spread.terms.iter().enumerate() {
            let moved = self.convolve(&bright, term.kernel_plane, &control.cancel())?;
            control.check()?;
            let (weight, centre) = (
                f64::from(term.weight),
                f64::from(self.centres[term.kernel_plane]),
            );
            sum.par_iter_mut()
                .zip(&moved)
                .zip(&bright)
                .for_each(|((o, s), b)| *o += weight * (s + centre * b));
            control.report((t + 1) as f64 / spread.terms.len() as f64);
        }
        out.clear();
        out.par_extend(sum.par_iter().map(|&v| v as f32));
        Ok(())
    }
}

impl Engine for Convolver {
    fn padded_size(&self) -> (usize, usize) {
        (self.px, self.py)
    }

    fn kernel_planes(&self) -> usize {
        self.spectra.len()
    }

    fn spread(
        &self,
        outputs: &[Spread],
        mut recycled: Vec<Vec<f32>>,
        control: &mut Control,
    ) -> Result<Vec<Vec<f32>>> {
        recycled.resize_with(outputs.len(), Vec::new);
        recycled.truncate(outputs.len());
        let share = 1.0 / outputs.len().max(1) as f64;
        for (o, (spread, out)) in outputs.iter().zip(recycled.iter_mut()).enumerate() {
            let mut part = control.part(o as f64 * share, (o + 1) as f64 * share);
            self.output(spread, out, &mut part)?;
        }
        Ok(recycled)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The engine against the direct sum, on sizes whose columns and rows
    /// do not fill its strips of 8.
    #[test]
    fn the_f64_engine_is_the_direct_sum() {
        let cancel = Cancel::new();
        let mut quiet = Control::quiet(&cancel);
        for ((w, h), (kw, kh)) in [((13, 11), (9, 7)), ((20, 17), (39, 33)), ((1, 9), (3, 5))] {
            let plane: Vec<f32> = (0..w * h).map(|i| ((i * 37) % 23) as f32 + 0.5).collect();
            let kernel: Vec<f32> = (0..kw * kh)
                .map(|i| ((i * 11) % 13) as f32 * 0.01)
                .collect();
            let engine =
                Convolver::new(&[&kernel], (kw, kh), w, h, Centre::Include, &mut quiet).unwrap();
            let spread = Spread {
                plane: &plane,
                fractions: None,
                terms: super::super::Term::alone(0),
                lamps: &[],
            };
            let out = engine.spread(&[spread], Vec::new(), &mut quiet).unwrap();
            let (cx, cy) = (kw as i64 / 2, kh as i64 / 2);
            for y in 0..h as i64 {
                for x in 0..w as i64 {
                    let mut sum = 0.0f64;
                    for j in 0..kh as i64 {
                        for i in 0..kw as i64 {
                            let (sx, sy) = (x - (i - cx), y - (j - cy));
                            if sx >= 0 && sy >= 0 && sx < w as i64 && sy < h as i64 {
                                sum += f64::from(plane[(sy * w as i64 + sx) as usize])
                                    * f64::from(kernel[(j * kw as i64 + i) as usize]);
                            }
                        }
                    }
                    let got = f64::from(out[0][(y * w as i64 + x) as usize]);
                    assert!(
                        (got - sum).abs() <= 1e-6 * sum.abs().max(1.0),
                        "{w}x{h} through {kw}x{kh} at ({x}, {y}): {got} against {sum}"
                    );
                }
            }
        }
    }
}
