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

use std::sync::{Arc, Mutex};

use rayon::prelude::*;
use realfft::num_complex::Complex;

mod footprint;
mod spectra;

pub(super) use footprint::{compose_bytes, footprint};
use spectra::{PlaneSpectrum, Spectra};

use super::grid::{ColumnTransform, Grid, Transforms};
use super::placement::Placement;
use super::pool::{Lent, Pool, Scratch};
use super::{Centre, Engine, Spread};
use crate::control::{Cancel, Control};
use crate::error::Result;
use crate::image::grow_zeroed;

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
            grow_zeroed(tiles, h.div_ceil(BLOCK) * strips * TILE)?;
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
                grow_zeroed(&mut out, self.width * h)?;
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
                Ok(out)
            })
            .collect::<Result<Vec<Vec<f32>>>>()?;
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
        self.prepare_spectra(planes, control)
    }

    fn split_near(&self, planes: &[&[f32]], radius: usize, control: &mut Control) -> Result<bool> {
        self.split_spectra(planes, radius, control)
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
