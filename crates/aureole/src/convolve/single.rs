//! The f32 engine: linear ("same"-size) convolution through real-to-complex
//! FFTs. The kernel's spectrum is computed once and reused for every plane
//! and every image of the same size.
//!
//! Only what the "same" output needs is transformed: the H image rows (the
//! padding rows are zeros), and each column transform is pruned when the
//! padded height P = 2N holds the H rows in its first half: the even and odd
//! frequencies of a column are then two transforms of length N (of x and of
//! x·e^{−iπn/N}), and the H output rows come back from two inverse transforms
//! of length N, which skips a radix-2 stage each way.
//!
//! No pass transposes a whole plane: rows are transformed, a block of
//! [`BLOCK`] at a time, into tiles of [`BLOCK`] rows × [`STRIP`] columns;
//! each strip of columns gathers its tiles, is transformed (padded,
//! multiplied by the kernel's spectrum, transformed back and cut to the H
//! output rows) in cache, and written back into the same tiles (one
//! buffer per plane, not two); the inverse row transforms read their
//! block's tiles, which lie together.

use std::sync::{Arc, Mutex, PoisonError};

use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::{RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};

use super::grid::{ColumnTransform, Grid, Transforms};
use super::lamps::Near;
use super::placement::Placement;
use super::pool::{Lent, Pool, Scratch};
use super::{Centre, Engine, Footprint, Load, Spread};
use crate::control::{Cancel, Control};
use crate::error::Result;
use crate::image::{grow_zeroed, zeros};

/// The spectra of one plane, in tiles: its row spectra, then, in the same
/// tiles, its column results (each strip task owns its tiles).
type Buffers = Vec<Complex<f32>>;

/// Columns transformed together: a strip of them spans two cache lines per
/// row, and its column transforms fit in the L2 cache.
const STRIP: usize = 16;

/// Rows transformed together: row spectra are stored in tiles of
/// BLOCK rows × [`STRIP`] columns, block by block, so that a strip's column
/// pass and a block's inverse row transforms each read whole tiles.
const BLOCK: usize = 8;

/// Values in a tile.
const TILE: usize = BLOCK * STRIP;

/// The kernel's spectra as the engine holds them: each plane on its own,
/// so that a new set shares the planes it does not change.
#[derive(Clone)]
struct Spectra {
    /// The near windows of the split last asked for.
    near: Option<Arc<Near>>,
    /// Per kernel plane.
    planes: Vec<Arc<PlaneSpectrum>>,
}

/// One kernel plane's spectrum, stored column by column (`px/2 + 1`
/// columns of P values; for pruned columns the even frequencies, then the
/// odd ones).
enum PlaneSpectrum {
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
    fn ready(&self) -> bool {
        !self
            .planes
            .iter()
            .any(|p| matches!(p.as_ref(), PlaneSpectrum::Pending))
    }

    /// Whether every plane is split at `radius`, and the near windows are
    /// that radius's: lamps can go through.
    fn split_at(&self, radius: usize) -> bool {
        self.near.as_ref().is_some_and(|near| near.radius == radius)
            && self.planes.iter().all(
                |p| matches!(p.as_ref(), PlaneSpectrum::Split { radius: r, .. } if *r == radius),
            )
    }
}

/// What column `u` of an input is multiplied by.
enum KernelColumn<'a> {
    /// K̂'s column.
    Whole(&'a [Complex<f32>]),
    /// The far spectrum's column, and the window's row spectra (the column
    /// at `u` of each of its rows).
    Split {
        far: &'a [Complex<f32>],
        window: &'a [Complex<f32>],
        lamps: Option<&'a LampRows<'a>>,
    },
}

/// Row spectra of the lamps alone, by row: (row, its spectrum), lent by
/// the engine's pool of them.
type LampRows<'a> = Vec<(usize, Lent<'a, Vec<Complex<f32>>>)>;

/// What a strip task reads: strip `index`, the kernel plane's spectra, and
/// the lamps' row spectra if there are lamps.
struct Strip<'a> {
    index: usize,
    spectra: &'a Spectra,
    kernel_plane: usize,
    lamps: Option<&'a LampRows<'a>>,
}

impl Strip<'_> {
    /// What column `u` is multiplied by; `py` values a column.
    fn column(&self, u: usize, py: usize) -> KernelColumn<'_> {
        match self.spectra.planes[self.kernel_plane].as_ref() {
            PlaneSpectrum::Whole(whole) => KernelColumn::Whole(&whole[u * py..(u + 1) * py]),
            // `convolve_all` refuses to start on a pending plane.
            PlaneSpectrum::Pending => KernelColumn::Whole(&[]),
            PlaneSpectrum::Split { far, window, .. } => KernelColumn::Split {
                far: &far[u * py..(u + 1) * py],
                window,
                lamps: self.lamps,
            },
        }
    }
}

/// One plane to convolve.
#[derive(Debug, Clone, Copy)]
struct Input<'a> {
    /// Row-major, the convolver's width × height.
    plane: &'a [f32],
    /// The share of each pixel's light that is spread, if not all: the rest
    /// stays where it is, added back unconvolved.
    fractions: Option<&'a [f32]>,
    /// The kernel plane to convolve with.
    kernel_plane: usize,
    /// Pixels whose light near them is added exactly ([`Spread::lamps`]).
    lamps: &'a [usize],
}

impl Input<'_> {
    /// The light of pixel `i` that is spread.
    fn bright(&self, i: usize) -> f32 {
        self.plane[i] * self.fractions.map_or(1.0, |f| f[i])
    }
}

/// The lamps of row `y` of a plane `w` wide, from ascending indices.
fn lamps_in_row(lamps: &[usize], y: usize, w: usize) -> &[usize] {
    let first = lamps.partition_point(|&i| i < y * w);
    let last = lamps.partition_point(|&i| i < (y + 1) * w);
    &lamps[first..last]
}

/// Bytes of a complex f32.
const COMPLEX: u64 = 8;

/// Rows of a near window held as row spectra, at most (a radius of 128).
const WINDOW_ROWS: u64 = 257;

/// What the engine holds: transforming, the kernel's
/// spectrum and its rows' spectra; spreading, the spectrum (split for
/// lamps: the far spectrum and the window's row spectra) and every plane's
/// row spectra.
pub(super) fn footprint(load: &Load) -> Footprint {
    let grid = Grid::new(load.kernel, load.image, true);
    let (half, py) = (grid.spectrum_width() as u64, grid.padded().1 as u64);
    let kernel_planes = load.kernel_planes as u64;
    let spectrum = half * py * COMPLEX * kernel_planes;
    let window = if load.split {
        WINDOW_ROWS.min(py) * half * COMPLEX * kernel_planes
    } else {
        0
    };
    let rows = half * load.image.1 as u64 * COMPLEX * load.planes as u64;
    Footprint {
        preparing: spectrum + half * load.kernel.1 as u64 * COMPLEX,
        spreading: spectrum + window + rows,
    }
}

/// What [`super::compose`] holds beside its plane and result: the
/// spectrum of the kernel (`size`) at the plane's size, and the plane's
/// row spectra.
pub(super) fn compose_bytes(size: (usize, usize), plane: (usize, usize)) -> u64 {
    let grid = Grid::new(size, plane, true);
    let (half, py) = (grid.spectrum_width() as u64, grid.padded().1 as u64);
    half * (py + 2 * size.1 as u64) * COMPLEX
}

/// Convolves `width`×`height` planes with one kernel, plane by plane.
pub struct Convolver {
    width: usize,
    height: usize,
    /// The kernel's width and height.
    kernel_size: (usize, usize),
    grid: Grid,
    /// The kernel's spectra, whole or split for lamps, per kernel plane
    /// and stored column by column (`px/2 + 1` columns of P values; for
    /// pruned columns the even frequencies, then the odd ones). Replaced
    /// whole when lamps ask for a split: a running application keeps the
    /// one it started with.
    spectra: Mutex<Arc<Spectra>>,
    /// Kernel planes.
    planes: usize,
    /// Whether the centre weights are left out of the spectra.
    centre: Centre,
    /// The weight each kernel plane left out of its spectrum (its centre),
    /// applied exactly to the plane itself: in the FFT it would dominate
    /// the round-off of the light that moves.
    centres: Vec<f32>,
    /// e^{−iπn/N} for n < N, for pruned columns.
    twiddles: Vec<Complex<f32>>,
    transforms: Transforms<f32>,
    buffers: Pool<Buffers>,
    /// Each pass's per-task buffers, kept from frame to frame.
    scratch: PassScratch,
}

/// The buffers a task of each pass works in.
#[derive(Debug, Default)]
struct PassScratch {
    forward: Scratch<RowScratch>,
    columns: Scratch<ColumnScratch>,
    inverse: Scratch<InverseScratch>,
    /// The lamps' row spectra, one per row with lamps.
    lamps: Scratch<Vec<Complex<f32>>>,
}

/// A row padded, its spectrum, the transform's scratch.
type RowScratch = (Vec<f32>, Vec<Complex<f32>>, Vec<Complex<f32>>);

/// A strip of H rows, three columns, the transforms' scratch.
type ColumnScratch = (Vec<Complex<f32>>, [Vec<Complex<f32>>; 3], Vec<Complex<f32>>);

/// A block of row spectra, a row, the transform's scratch.
type InverseScratch = (Vec<Complex<f32>>, Vec<f32>, Vec<Complex<f32>>);

impl Convolver {
    /// Plans the convolution of `width`×`height` images with a kernel given
    /// as planes (row-major, `size` = width × height, centre at its middle,
    /// taken as they are), and transforms it; with [`Centre::Leave`] the
    /// centre weight is left out of the spectrum and applied exactly.
    pub fn new(
        planes: &[&[f32]],
        size: (usize, usize),
        width: usize,
        height: usize,
        centre: Centre,
        control: &mut Control,
    ) -> Result<Convolver> {
        let convolver = Convolver::deferred(planes, size, width, height, centre);
        convolver.prepare(planes, control)?;
        Ok(convolver)
    }

    /// [`Convolver::new`] with the transforms left to the first call that
    /// needs them: [`Engine::prepare`] for the whole spectra, or
    /// [`Engine::split_near`], which then transforms only the split ones.
    pub fn deferred(
        planes: &[&[f32]],
        size: (usize, usize),
        width: usize,
        height: usize,
        centre: Centre,
    ) -> Convolver {
        let grid = Grid::new(size, (width, height), true);
        let twiddles = match grid.columns {
            ColumnTransform::Full(_) => Vec::new(),
            ColumnTransform::Halves(n) => (0..n)
                .map(|k| {
                    let (sin, cos) = libm::sincos(-std::f64::consts::PI * k as f64 / n as f64);
                    Complex::new(cos as f32, sin as f32)
                })
                .collect(),
        };
        let centres = Placement::left_out_of(planes, size, centre);
        Convolver {
            width,
            height,
            kernel_size: size,
            grid,
            planes: planes.len(),
            centre,
            spectra: Mutex::new(Arc::new(Spectra {
                near: None,
                planes: planes
                    .iter()
                    .map(|_| Arc::new(PlaneSpectrum::Pending))
                    .collect(),
            })),
            centres,
            twiddles,
            transforms: Transforms::plan(grid.px, grid.columns.transform_length()),
            buffers: Pool::new(),
            scratch: PassScratch::default(),
        }
    }

    /// `plane` (row-major, `width`×`height`) convolved with kernel plane
    /// `kernel_plane`, over the same frame; light beyond the frame is lost.
    pub fn convolve(
        &self,
        plane: &[f32],
        kernel_plane: usize,
        control: &mut Control,
    ) -> Result<Vec<f32>> {
        let input = Input {
            plane,
            fractions: None,
            kernel_plane,
            lamps: &[],
        };
        Ok(self
            .convolve_all(&[input], Vec::new(), control)?
            .pop()
            .unwrap_or_default())
    }

    /// Every input convolved with its kernel plane, plus its centre weight
    /// times its bright part, plus the light that stays, written into the
    /// planes of `recycled` where there are some (memory already mapped).
    /// The planes go through each pass together, so that the kernel's
    /// spectrum is read from memory once for all of them.
    fn convolve_all(
        &self,
        inputs: &[Input],
        mut recycled: Vec<Vec<f32>>,
        control: &mut Control,
    ) -> Result<Vec<Vec<f32>>> {
        let spectra = self.spectra();
        if !spectra.ready() {
            return Err(crate::error::Error::NotTransformed);
        }
        let h = self.height;
        let strips = self.grid.spectrum_width().div_ceil(STRIP);
        let mut buffers = self.buffers.lease();
        buffers.resize_with(inputs.len(), Default::default);
        for tiles in buffers.iter_mut() {
            grow_zeroed(tiles, h.div_ceil(BLOCK) * strips * TILE);
        }
        for (input, rows) in inputs.iter().zip(buffers.iter_mut()) {
            self.forward_rows(input, rows, strips, &control.cancel());
        }
        let near = spectra
            .near
            .as_ref()
            .filter(|near| spectra.split_at(near.radius));
        let lamp_rows: Vec<Option<LampRows>> = inputs
            .iter()
            .map(|input| (near.is_some() && !input.lamps.is_empty()).then(|| self.lamp_rows(input)))
            .collect();
        control.check()?;
        control.report(0.3);
        self.column_pass(
            inputs,
            &lamp_rows,
            &spectra,
            &mut buffers,
            strips,
            &control.cancel(),
        );
        control.check()?;
        control.report(0.7);
        recycled.resize_with(inputs.len(), Vec::new);
        recycled.truncate(inputs.len());
        let outputs = inputs
            .iter()
            .zip(buffers.iter())
            .zip(recycled)
            .map(|((input, results), mut out)| {
                grow_zeroed(&mut out, self.width * h);
                self.inverse_rows(input, results, &mut out, strips, &control.cancel());
                if let (Some(near), false) = (near, input.lamps.is_empty()) {
                    near.add(
                        input.kernel_plane,
                        input.lamps,
                        &|i| input.bright(i),
                        &mut out,
                        self.width,
                        &control.cancel(),
                    );
                }
                out
            })
            .collect();
        control.check()?;
        control.report(1.0);
        Ok(outputs)
    }

    /// Forward row transforms of one input, a block of rows per task, into
    /// tiles: block b, strip s, row, column.
    fn forward_rows(
        &self,
        input: &Input,
        rows: &mut [Complex<f32>],
        strips: usize,
        cancel: &Cancel,
    ) {
        let w = self.width;
        let row_fft = &self.transforms.row_fft;
        rows.par_chunks_mut(strips * TILE)
            .zip(input.plane.par_chunks(BLOCK * w))
            .enumerate()
            .for_each_init(
                || self.row_scratch(),
                |lent, (block, (tiles, source))| {
                    if cancel.is_cancelled() {
                        return;
                    }
                    let (padded, spectrum, scratch) = &mut **lent;
                    for (r, row) in source.chunks(w).enumerate() {
                        match input.fractions {
                            Some(fractions) => {
                                let at = (block * BLOCK + r) * w;
                                for ((p, v), f) in
                                    padded.iter_mut().zip(row).zip(&fractions[at..at + w])
                                {
                                    *p = v * f;
                                }
                            }
                            None => padded[..w].copy_from_slice(row),
                        }
                        for &i in lamps_in_row(input.lamps, block * BLOCK + r, w) {
                            padded[i % w] = 0.0;
                        }
                        padded[w..].iter_mut().for_each(|v| *v = 0.0);
                        let _ = row_fft.process_with_scratch(padded, spectrum, scratch);
                        for (s, values) in spectrum.chunks(STRIP).enumerate() {
                            let at = s * TILE + r * STRIP;
                            tiles[at..at + values.len()].copy_from_slice(values);
                        }
                    }
                },
            );
    }

    /// A forward row's buffers, lent by the pool of them.
    fn row_scratch(&self) -> Lent<'_, RowScratch> {
        let row_fft = &self.transforms.row_fft;
        self.scratch.forward.lend(|| {
            (
                row_fft.make_input_vec(),
                row_fft.make_output_vec(),
                row_fft.make_scratch_vec(),
            )
        })
    }

    /// The row spectra of an input's lamps alone (the forward rows leave
    /// them out), one per row that has lamps.
    fn lamp_rows(&self, input: &Input) -> LampRows<'_> {
        let w = self.width;
        let mut rows: Vec<usize> = input.lamps.iter().map(|&i| i / w).collect();
        rows.dedup();
        let row_fft = &self.transforms.row_fft;
        rows.into_par_iter()
            .map_init(
                || self.row_scratch(),
                |lent, y| {
                    let (padded, _, scratch) = &mut **lent;
                    padded.fill(0.0);
                    for &i in lamps_in_row(input.lamps, y, w) {
                        padded[i % w] = input.bright(i);
                    }
                    let mut spectrum = self.scratch.lamps.lend(|| row_fft.make_output_vec());
                    let _ = row_fft.process_with_scratch(padded, &mut spectrum, scratch);
                    (y, spectrum)
                },
            )
            .collect()
    }

    /// The column transforms of every input, strip by strip: each strip task
    /// gathers its columns from its tiles of the row spectra, and writes the
    /// H output rows of the product's inverse back into the same tiles.
    fn column_pass(
        &self,
        inputs: &[Input],
        lamp_rows: &[Option<LampRows>],
        spectra: &Spectra,
        buffers: &mut [Buffers],
        strips: usize,
        cancel: &Cancel,
    ) {
        let h = self.height;
        let py = self.grid.columns.length();
        let zero = Complex::new(0.0, 0.0);
        // Strip s of every input, as one task: tile s of every block.
        let mut tasks: Vec<Vec<Vec<&mut [Complex<f32>]>>> = (0..strips)
            .map(|_| (0..inputs.len()).map(|_| Vec::new()).collect())
            .collect();
        for (i, tiles) in buffers.iter_mut().enumerate() {
            for (t, tile) in tiles.chunks_mut(TILE).enumerate() {
                tasks[t % strips][i].push(tile);
            }
        }
        let scratch_len = self
            .transforms
            .column_fft
            .get_inplace_scratch_len()
            .max(self.transforms.column_ifft.get_inplace_scratch_len());
        tasks.into_par_iter().enumerate().for_each_init(
            || {
                self.scratch.columns.lend(|| {
                    (
                        vec![zero; h * STRIP],
                        [vec![zero; py], vec![zero; py], vec![zero; py]],
                        vec![zero; scratch_len],
                    )
                })
            },
            |lent, (s, mut tiles)| {
                let (out, columns, scratch) = &mut **lent;
                for ((input, lamps), tiles) in inputs.iter().zip(lamp_rows).zip(tiles.iter_mut()) {
                    if cancel.is_cancelled() {
                        return;
                    }
                    let strip = Strip {
                        index: s,
                        spectra,
                        kernel_plane: input.kernel_plane,
                        lamps: lamps.as_ref(),
                    };
                    super::simd::widest(
                        #[inline(always)]
                        || self.strip(&strip, tiles, out, columns, scratch),
                    );
                }
            },
        );
    }

    /// One strip's columns of one input: its tiles (one per block) of the
    /// row spectra into `out` (H rows of [`STRIP`] values, in cache from
    /// here on), each column through the transforms in place, and the
    /// results back into the tiles.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn strip(
        &self,
        strip: &Strip,
        tiles: &mut [&mut [Complex<f32>]],
        out: &mut [Complex<f32>],
        columns: &mut [Vec<Complex<f32>>; 3],
        scratch: &mut [Complex<f32>],
    ) {
        let h = self.height;
        let count = self.grid.spectrum_width();
        let py = self.grid.columns.length();
        let first = strip.index * STRIP;
        let width = STRIP.min(count - first);
        for (block, tile) in tiles.iter().enumerate() {
            let at = block * TILE;
            let n = TILE.min(h * STRIP - at);
            out[at..at + n].copy_from_slice(&tile[..n]);
        }
        for j in 0..width {
            let u = first + j;
            self.column(out, j, u, strip.column(u, py), columns, scratch);
        }
        for (block, tile) in tiles.iter_mut().enumerate() {
            let at = block * TILE;
            let n = TILE.min(h * STRIP - at);
            tile[..n].copy_from_slice(&out[at..at + n]);
        }
    }

    /// Column `j` (the spectrum's column `u`) of a strip (H rows of
    /// [`STRIP`] values) through the padded column transform, the product
    /// with the kernel's column spectrum and back, in place. With the
    /// kernel split, its column is the far spectrum's plus the window's,
    /// transformed here from the window's row spectra; lamps (their row
    /// spectra) go through the far spectrum alone, added before going
    /// back.
    #[inline(always)]
    fn column(
        &self,
        strip: &mut [Complex<f32>],
        j: usize,
        u: usize,
        kernel: KernelColumn,
        [column, window, lamps]: &mut [Vec<Complex<f32>>; 3],
        scratch: &mut [Complex<f32>],
    ) {
        let h = self.height;
        let zero = Complex::new(0.0, 0.0);
        match self.grid.columns {
            ColumnTransform::Full(_) => {
                for (c, v) in column.iter_mut().zip(strip.iter().skip(j).step_by(STRIP)) {
                    *c = *v;
                }
                column[h..].iter_mut().for_each(|v| *v = zero);
            }
            ColumnTransform::Halves(n) => {
                let (even, odd) = column.split_at_mut(n);
                for (((e, o), v), t) in even
                    .iter_mut()
                    .zip(odd.iter_mut())
                    .zip(strip.iter().skip(j).step_by(STRIP))
                    .zip(&self.twiddles)
                {
                    *e = *v;
                    *o = v * t;
                }
                even[h..].iter_mut().for_each(|v| *v = zero);
                odd[h..].iter_mut().for_each(|v| *v = zero);
            }
        }
        // For pruned columns both halves go in one call: rustfft transforms
        // a buffer of several lengths one after the other.
        self.transforms
            .column_fft
            .process_with_scratch(column, scratch);
        match kernel {
            KernelColumn::Whole(spectrum) => {
                for (a, b) in column.iter_mut().zip(spectrum) {
                    *a *= *b;
                }
            }
            KernelColumn::Split {
                far,
                window: window_rows,
                lamps: lamp_rows,
            } => {
                // The window's column: its rows' spectra at u, centred.
                let width = self.grid.spectrum_width();
                let r = window_rows.len() / width / 2;
                let rows = window_rows.chunks(width).map(|row| row[u]);
                self.place_rows(
                    window,
                    rows.enumerate().map(|(i, v)| (i as i64 - r as i64, v)),
                );
                self.transforms
                    .column_fft
                    .process_with_scratch(window, scratch);
                if let Some(lamp_rows) = lamp_rows {
                    let rows = lamp_rows
                        .iter()
                        .map(|(y, spectrum)| (*y as i64, spectrum[u]));
                    self.place_rows(lamps, rows);
                    self.transforms
                        .column_fft
                        .process_with_scratch(lamps, scratch);
                    for (((a, w), e), f) in column
                        .iter_mut()
                        .zip(window.iter())
                        .zip(lamps.iter())
                        .zip(far)
                    {
                        *a = *a * (f + w) + e * f;
                    }
                } else {
                    for ((a, w), f) in column.iter_mut().zip(window.iter()).zip(far) {
                        *a *= f + w;
                    }
                }
            }
        }
        self.transforms
            .column_ifft
            .process_with_scratch(column, scratch);
        let values = strip.iter_mut().skip(j).step_by(STRIP);
        match self.grid.columns {
            ColumnTransform::Full(_) => {
                for (v, c) in values.zip(column.iter()) {
                    *v = *c;
                }
            }
            ColumnTransform::Halves(n) => {
                let (even, odd) = column.split_at(n);
                for (((v, e), o), t) in values.zip(even).zip(odd).zip(&self.twiddles) {
                    *v = e + o * t.conj();
                }
            }
        }
    }

    /// A column of zeros but for `rows` (row of the period, from −P/2 to
    /// P/2, and value), laid out for the column transform: as it is, or
    /// for pruned columns as the even and odd halves' inputs.
    #[inline(always)]
    fn place_rows(
        &self,
        column: &mut [Complex<f32>],
        rows: impl Iterator<Item = (i64, Complex<f32>)>,
    ) {
        let zero = Complex::new(0.0, 0.0);
        column.iter_mut().for_each(|v| *v = zero);
        match self.grid.columns {
            ColumnTransform::Full(p) => {
                for (y, v) in rows {
                    column[y.rem_euclid(p as i64) as usize] = v;
                }
            }
            ColumnTransform::Halves(n) => {
                // Row y of the period of 2N: the even transform takes it at
                // y mod N, the odd one times e^{−iπy/N} (= −e^{−iπ(y−N)/N}
                // for y ≥ N).
                let (even, odd) = column.split_at_mut(n);
                for (y, v) in rows {
                    let y = y.rem_euclid(2 * n as i64) as usize;
                    let (at, sign) = if y < n { (y, 1.0) } else { (y - n, -1.0) };
                    even[at] += v;
                    odd[at] += v * self.twiddles[at] * sign;
                }
            }
        }
    }

    /// Inverse row transforms of one input, a block of rows per task,
    /// gathered from the strips (a tile's worth from each), plus the
    /// centre's light and the light that stays.
    fn inverse_rows(
        &self,
        input: &Input,
        results: &[Complex<f32>],
        out: &mut [f32],
        strips: usize,
        cancel: &Cancel,
    ) {
        let w = self.width;
        let count = self.grid.spectrum_width();
        let row_ifft = &self.transforms.row_ifft;
        let zero = Complex::new(0.0, 0.0);
        out.par_chunks_mut(BLOCK * w)
            .zip(input.plane.par_chunks(BLOCK * w))
            .enumerate()
            .for_each_init(
                || {
                    self.scratch.inverse.lend(|| {
                        (
                            vec![zero; BLOCK * count],
                            row_ifft.make_output_vec(),
                            row_ifft.make_scratch_vec(),
                        )
                    })
                },
                |lent, (block, (destination, source))| {
                    if cancel.is_cancelled() {
                        return;
                    }
                    let (spectra, output, scratch) = &mut **lent;
                    self.gather_block(results, block, destination.len() / w, strips, spectra);
                    for (r, ((spectrum, destination), source)) in spectra
                        .chunks_mut(count)
                        .zip(destination.chunks_mut(w))
                        .zip(source.chunks(w))
                        .enumerate()
                    {
                        // A real signal's DC and Nyquist bins are real; the
                        // inverse refuses their round-off.
                        spectrum[0].im = 0.0;
                        if self.grid.px % 2 == 0 {
                            spectrum[count - 1].im = 0.0;
                        }
                        let _ = row_ifft.process_with_scratch(spectrum, output, scratch);
                        let at = (block * BLOCK + r) * w;
                        self.finish_row(input, at, output, source, destination);
                    }
                },
            );
    }

    /// The spectra of block `block`'s `rows` rows, a tile from each strip.
    fn gather_block(
        &self,
        results: &[Complex<f32>],
        block: usize,
        rows: usize,
        strips: usize,
        spectra: &mut [Complex<f32>],
    ) {
        let count = self.grid.spectrum_width();
        for s in 0..strips {
            let at = (block * strips + s) * TILE;
            let tile = &results[at..at + rows * STRIP];
            let first = s * STRIP;
            let width = STRIP.min(count - first);
            for (r, values) in tile.chunks(STRIP).enumerate() {
                spectra[r * count + first..r * count + first + width]
                    .copy_from_slice(&values[..width]);
            }
        }
    }

    /// One output row from its inverse transform (`convolved`, unscaled):
    /// the moved light, the centre's share of the bright part, and the
    /// light that stays (`at` is the row's first pixel).
    #[inline]
    fn finish_row(
        &self,
        input: &Input,
        at: usize,
        convolved: &[f32],
        source: &[f32],
        destination: &mut [f32],
    ) {
        let scale = 1.0 / (self.grid.px as f32 * self.grid.columns.length() as f32);
        let centre = self.centres[input.kernel_plane];
        let values = destination.iter_mut().zip(convolved).zip(source);
        match input.fractions {
            Some(fractions) => {
                for (((d, v), s), f) in values.zip(&fractions[at..at + self.width]) {
                    let bright = s * f;
                    *d = v * scale + centre * bright + (s - bright);
                }
            }
            None => {
                for ((d, v), s) in values {
                    *d = v * scale + centre * s;
                }
            }
        }
    }
}

impl Engine for Convolver {
    fn padded_size(&self) -> (usize, usize) {
        self.grid.padded()
    }

    fn kernel_planes(&self) -> usize {
        self.planes
    }

    fn has_split(&self, radius: usize) -> bool {
        self.spectra().split_at(radius)
    }

    fn ready(&self) -> bool {
        self.spectra().ready()
    }

    fn prepare(&self, planes: &[&[f32]], control: &mut Control) -> Result<()> {
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

    fn split_near(&self, planes: &[&[f32]], radius: usize, control: &mut Control) -> Result<bool> {
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

    /// Each output as one pass over its plane where it takes one kernel
    /// plane; a luminance plane through a coloured kernel as Σ w_k of its
    /// bright part through each plane, plus the light that stays.
    fn spread(
        &self,
        outputs: &[Spread],
        mut recycled: Vec<Vec<f32>>,
        control: &mut Control,
    ) -> Result<Vec<Vec<f32>>> {
        let single = |s: &Spread| matches!(s.terms.as_slice(), [term] if term.weight == 1.0);
        if outputs.iter().all(single) {
            let inputs: Vec<Input> = outputs
                .iter()
                .map(|s| Input {
                    plane: s.plane,
                    fractions: s.fractions,
                    kernel_plane: s.terms[0].kernel_plane,
                    lamps: s.lamps,
                })
                .collect();
            // Planes that share a kernel plane go through the passes
            // together, reading its spectrum once; planes with a kernel
            // plane each go one at a time, holding one plane's spectra
            // (66 MB at 4K) instead of all of theirs.
            let mut kernel_planes: Vec<usize> = inputs.iter().map(|i| i.kernel_plane).collect();
            kernel_planes.sort_unstable();
            kernel_planes.dedup();
            if kernel_planes.len() < inputs.len() {
                return self.convolve_all(&inputs, recycled, control);
            }
            let mut planes = Vec::with_capacity(inputs.len());
            let share = 1.0 / inputs.len() as f64;
            for (i, input) in inputs.iter().enumerate() {
                let mut part = control.part(i as f64 * share, (i + 1) as f64 * share);
                let spare: Vec<Vec<f32>> = recycled.drain(..recycled.len().min(1)).collect();
                planes.extend(self.convolve_all(std::slice::from_ref(input), spare, &mut part)?);
            }
            return Ok(planes);
        }
        let mut planes = Vec::with_capacity(outputs.len());
        let share = 1.0 / outputs.len() as f64;
        for (o, output) in outputs.iter().enumerate() {
            let mut part = control.part(o as f64 * share, (o + 1) as f64 * share);
            let spare: Vec<Vec<f32>> = recycled.drain(..recycled.len().min(1)).collect();
            planes.push(self.weighted(output, spare, &mut part)?);
        }
        Ok(planes)
    }
}

impl Convolver {
    /// The spectra as they are now.
    fn spectra(&self) -> Arc<Spectra> {
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
        let rest = near.far_plane(plane, self.kernel_size);
        let placed = Placement {
            plane: &rest,
            size: self.kernel_size,
            centre: Centre::Include,
        };
        let far = kernel_spectrum(row_fft, full_column, &self.grid, &placed, control)?;
        let window = self.window_rows(near.window(k), near.radius, row_fft);
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
    ) -> Vec<Complex<f32>> {
        let side = 2 * radius + 1;
        let px = self.grid.px;
        let count = self.grid.spectrum_width();
        let mut spectra = zeros(side * count);
        let mut input = row_fft.make_input_vec();
        let mut scratch = row_fft.make_scratch_vec();
        for (row, out) in window.chunks(side).zip(spectra.chunks_mut(count)) {
            input.iter_mut().for_each(|v| *v = 0.0);
            for (x, &v) in row.iter().enumerate() {
                input[(x + px - radius) % px] = v;
            }
            let _ = row_fft.process_with_scratch(&mut input, out, &mut scratch);
        }
        spectra
    }

    /// One output of several weighted terms: the bright part goes through
    /// each kernel plane, and what stays is added once.
    fn weighted(
        &self,
        output: &Spread,
        recycled: Vec<Vec<f32>>,
        control: &mut Control,
    ) -> Result<Vec<f32>> {
        let plane = output.plane;
        let bright: Option<Vec<f32>> = output.fractions.map(|fractions| {
            plane
                .par_iter()
                .zip(fractions)
                .map(|(v, f)| v * f)
                .collect()
        });
        let source = bright.as_deref().unwrap_or(plane);
        let inputs: Vec<Input> = output
            .terms
            .iter()
            .map(|term| Input {
                plane: source,
                fractions: None,
                kernel_plane: term.kernel_plane,
                lamps: output.lamps,
            })
            .collect();
        let mut parts = self.convolve_all(&inputs, recycled, control)?.into_iter();
        let mut weights = output.terms.iter().map(|t| t.weight);
        let mut sum = parts.next().unwrap_or_default();
        let first = weights.next().unwrap_or(0.0);
        sum.par_iter_mut().for_each(|s| *s *= first);
        for (part, weight) in parts.zip(weights) {
            sum.par_iter_mut()
                .zip(&part)
                .for_each(|(s, p)| *s += weight * p);
        }
        if let Some(bright) = &bright {
            sum.par_iter_mut()
                .zip(plane)
                .zip(bright)
                .for_each(|((s, v), b)| *s += v - b);
        }
        Ok(sum)
    }
}

/// The 2-D spectrum of a placed kernel plane over the grid, column by
/// column (pruned columns: even frequencies, then odd). Only the kernel's
/// own rows are transformed and stored: the other rows of the period are
/// zeros.
fn kernel_spectrum(
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
    let mut rows = zeros(kh * count);
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
    let mut spectrum = zeros(count * py);
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
