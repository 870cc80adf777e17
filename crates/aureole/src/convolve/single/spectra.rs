//! The kernel's spectra as the f32 engine holds them: each plane
//! transformed whole, or split for a night scene's lamps into the
//! spectrum beyond a near window and the window's row spectra
//! (docs/physics.md §8).

use std::sync::{Arc, PoisonError};

use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::{RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};

use super::{Convolver, STRIP};
use crate::control::Control;
use crate::convolve::grid::{ColumnTransform, Grid};
use crate::convolve::lamps::Near;
use crate::convolve::placement::Placement;
use crate::convolve::{Centre, Engine};
use crate::error::Result;
use crate::image::zeros;

/// The kernel's spectra as the engine holds them: each plane on its own,
/// so that a new set shares the planes it does not change.
#[derive(Clone)]
pub(super) struct Spectra {
    /// The near windows of the split last asked for.
    pub(super) near: Option<Arc<Near>>,
    /// Per kernel plane.
    pub(super) planes: Vec<Arc<PlaneSpectrum>>,
}

/// One kernel plane's spectrum, stored column by column (`px/2 + 1`
/// columns of P values; for pruned columns the even frequencies, then the
/// odd ones).
pub(super) enum PlaneSpectrum {
    /// Not transformed yet: a plan transforms its kernel once it knows
    /// whether its first image needs it whole or split for lamps.
    Pending,
    /// K̂ whole: what every input without lamps needs.
    Whole(Vec<Complex<f32>>),
    /// Split for lamps at a radius: the spectrum of the kernel beyond the
    /// near window, and the window's row spectra, from which each column
    /// of the window's spectrum is transformed as it is needed. K̂ is
    /// their sum: holding it too would take another kernel's worth of
    /// memory (400 MB for a full-frame 4K RGB kernel).
    Split {
        radius: usize,
        far: Vec<Complex<f32>>,
        /// The 2r + 1 rows of the window (centre left out) as row spectra,
        /// one after the other.
        window: Vec<Complex<f32>>,
    },
}

impl Spectra {
    /// Whether every plane is transformed.
    pub(super) fn ready(&self) -> bool {
        !self
            .planes
            .iter()
            .any(|p| matches!(p.as_ref(), PlaneSpectrum::Pending))
    }

    /// Whether every plane is split at `radius`, and the near windows are
    /// that radius's: lamps can go through.
    pub(super) fn split_at(&self, radius: usize) -> bool {
        self.near.as_ref().is_some_and(|near| near.radius == radius)
            && self.planes.iter().all(
                |p| matches!(p.as_ref(), PlaneSpectrum::Split { radius: r, .. } if *r == radius),
            )
    }
}

impl Convolver {
    /// The spectra as they are now.
    pub(super) fn spectra(&self) -> Arc<Spectra> {
        self.spectra
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }

    /// Kernel plane `k` (`plane`) split at `near`'s radius: the spectrum of
    /// the rest, and the window's row spectra.
    fn split_plane(
        &self,
        plane: &[f32],
        k: usize,
        near: &Near,
        (row_fft, full_column): (&dyn RealToComplex<f32>, &dyn Fft<f32>),
        control: &mut Control,
    ) -> Result<PlaneSpectrum> {
        // The plane less its window (and centre), placed as it is read:
        // what the transform carries for the lamps.
        let placed = Placement {
            plane,
            size: self.kernel_size,
            centre: Centre::Include,
            hole: Some(near.radius),
        };
        let far = kernel_spectrum(row_fft, full_column, &self.grid, &placed, control)?;
        let window = self.window_rows(near.window(k), near.radius, row_fft)?;
        Ok(PlaneSpectrum::Split {
            radius: near.radius,
            far,
            window,
        })
    }

    /// The 2r + 1 rows of a near window (row-major, centre left out) as row
    /// spectra, each row placed in the period as the kernel's rows are.
    fn window_rows(
        &self,
        window: &[f32],
        radius: usize,
        row_fft: &dyn RealToComplex<f32>,
    ) -> Result<Vec<Complex<f32>>> {
        let side = 2 * radius + 1;
        let px = self.grid.px;
        let count = self.grid.spectrum_width();
        let mut spectra = zeros(side * count)?;
        let mut input = row_fft.make_input_vec();
        let mut scratch = row_fft.make_scratch_vec();
        for (row, out) in window.chunks(side).zip(spectra.chunks_mut(count)) {
            input.iter_mut().for_each(|v| *v = 0.0);
            for (x, &v) in row.iter().enumerate() {
                input[(x + px - radius) % px] = v;
            }
            let _ = row_fft.process_with_scratch(&mut input, out, &mut scratch);
        }
        Ok(spectra)
    }

    /// [`Engine::prepare`]: each kernel plane's spectrum, whole.
    pub(super) fn prepare_spectra(&self, planes: &[&[f32]], control: &mut Control) -> Result<()> {
        if self.ready() {
            return Ok(());
        }
        if planes.len() != self.planes {
            return Err(crate::error::Error::NotTransformed);
        }
        let row_fft = RealFftPlanner::<f32>::new().plan_fft_forward(self.grid.px);
        let full_column = FftPlanner::<f32>::new().plan_fft_forward(self.grid.columns.length());
        let mut held = self.spectra.lock().unwrap_or_else(PoisonError::into_inner);
        let share = 1.0 / planes.len() as f64;
        for (k, plane) in planes.iter().enumerate() {
            if !matches!(held.planes[k].as_ref(), PlaneSpectrum::Pending) {
                continue;
            }
            let placed = Placement {
                plane,
                size: self.kernel_size,
                centre: self.centre,
                hole: None,
            };
            let mut part = control.part(k as f64 * share, (k + 1) as f64 * share);
            let whole = kernel_spectrum(&*row_fft, &*full_column, &self.grid, &placed, &mut part)?;
            // Each plane as it comes: a cancelled run keeps those done.
            let mut next = Spectra::clone(&held);
            next.planes[k] = Arc::new(PlaneSpectrum::Whole(whole));
            *held = Arc::new(next);
        }
        Ok(())
    }

    /// [`Engine::split_near`]: each kernel plane's spectrum split at
    /// `radius` for lamps, where the window fits.
    pub(super) fn split_spectra(
        &self,
        planes: &[&[f32]],
        radius: usize,
        control: &mut Control,
    ) -> Result<bool> {
        if self.has_split(radius) {
            return Ok(true);
        }
        let Some(near) = Near::fitting(planes, self.kernel_size, radius, self.planes) else {
            return Ok(false);
        };
        let near = Arc::new(near);
        let row_fft = RealFftPlanner::<f32>::new().plan_fft_forward(self.grid.px);
        let full_column = FftPlanner::<f32>::new().plan_fft_forward(self.grid.columns.length());
        // Held while the split is built, so that no application starts on
        // spectra half replaced. Each plane's new spectrum replaces its old
        // one as it comes, which then goes unless an application still
        // running holds it: the engine never holds two whole sets. A plane
        // split before a cancellation is not split again.
        let mut held = self.spectra.lock().unwrap_or_else(PoisonError::into_inner);
        let share = 1.0 / planes.len() as f64;
        for (k, plane) in planes.iter().enumerate() {
            let done = matches!(held.planes[k].as_ref(), PlaneSpectrum::Split { radius: r, .. } if *r == radius);
            if done {
                continue;
            }
            let mut part = control.part(k as f64 * share, (k + 1) as f64 * share);
            let split = self.split_plane(plane, k, &near, (&*row_fft, &*full_column), &mut part)?;
            let mut next = Spectra::clone(&held);
            next.planes[k] = Arc::new(split);
            *held = Arc::new(next);
        }
        let mut next = Spectra::clone(&held);
        next.near = Some(near);
        *held = Arc::new(next);
        Ok(true)
    }
}

/// The 2-D spectrum of a placed kernel plane over the grid, column by
/// column (pruned columns: even frequencies, then odd). Only the kernel's
/// own rows are transformed and stored: the other rows of the period are
/// zeros.
pub(super) fn kernel_spectrum(
    row_fft: &dyn RealToComplex<f32>,
    column_fft: &dyn Fft<f32>,
    grid: &Grid,
    placed: &Placement,
    control: &mut Control,
) -> Result<Vec<Complex<f32>>> {
    let py = grid.columns.length();
    let kh = placed.size.1;
    let count = grid.spectrum_width();
    let zero = Complex::new(0.0, 0.0);
    let cancel = control.cancel();
    let mut rows = zeros(kh * count)?;
    rows.par_chunks_mut(count).enumerate().for_each_init(
        || (row_fft.make_input_vec(), row_fft.make_scratch_vec()),
        |(input, scratch), (j, out)| {
            if cancel.is_cancelled() {
                return;
            }
            placed.row(j, input);
            let _ = row_fft.process_with_scratch(input, out, scratch);
        },
    );
    control.check()?;
    control.report(0.5);
    // Column transforms, a strip of columns per task, gathered a cache line
    // or two per row rather than one value per row.
    let mut spectrum = zeros(count * py)?;
    spectrum
        .par_chunks_mut(STRIP * py)
        .enumerate()
        .for_each_init(
            || {
                (
                    vec![zero; py * STRIP],
                    vec![zero; py],
                    vec![zero; column_fft.get_inplace_scratch_len()],
                )
            },
            |(strip, column, scratch), (s, out)| {
                if cancel.is_cancelled() {
                    return;
                }
                let first = s * STRIP;
                let width = out.len() / py;
                strip.iter_mut().for_each(|v| *v = zero);
                for (j, row) in rows.chunks(count).enumerate() {
                    let r = placed.period_row(j, py);
                    strip[r * STRIP..r * STRIP + width].copy_from_slice(&row[first..first + width]);
                }
                for (j, out) in out.chunks_mut(py).enumerate() {
                    for (v, s) in column.iter_mut().zip(strip.iter().skip(j).step_by(STRIP)) {
                        *v = *s;
                    }
                    column_fft.process_with_scratch(column, scratch);
                    match grid.columns {
                        ColumnTransform::Full(_) => out.copy_from_slice(column),
                        ColumnTransform::Halves(n) => {
                            let (even, odd) = out.split_at_mut(n);
                            for ((e, o), pair) in even.iter_mut().zip(odd).zip(column.chunks(2)) {
                                *e = pair[0];
                                *o = pair[1];
                            }
                        }
                    }
                }
            },
        );
    control.check()?;
    control.report(1.0);
    Ok(spectrum)
}
