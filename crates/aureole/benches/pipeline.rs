//! Criterion benches of the pipeline on the issue-5 workload: the steady
//! state (applying a plan whose kernel spectrum is built), the floor (only
//! the 1-D FFTs a 2-D convolution at that padded size must do), and the
//! kernel build.

mod workload;

use std::hint::black_box;
use std::time::Duration;

use aureole::convolve::padded_size;
use aureole::{ApplyOptions, Cancel, Control, Extent, Plan};
use criterion::{criterion_group, criterion_main, Criterion};
use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::RealFftPlanner;
use rustfft::FftPlanner;

const SIZES: [(&str, usize, usize); 2] = [("1080p", 1920, 1080), ("4k", 3840, 2160)];

fn apply(c: &mut Criterion) {
    let mut group = c.benchmark_group("apply");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    for (name, w, h) in SIZES {
        let image = workload::image(w, h);
        let plan = Plan::for_image(&workload::config(), w, h, None).expect("workload plan");
        group.bench_function(name, |b| {
            b.iter(|| black_box(plan.apply(&image, 1.0, &ApplyOptions::default(), &mut |_| {})))
        });
        let mut planes = Vec::new();
        group.bench_function(format!("{name}-recycled"), |b| {
            b.iter(|| {
                let applied = plan
                    .apply_with(
                        &image,
                        1.0,
                        &ApplyOptions::default(),
                        std::mem::take(&mut planes),
                        &mut Control::quiet(&Cancel::new()),
                    )
                    .expect("same size");
                planes = applied.image.planes;
            })
        });
    }
    group.finish();
}

/// The 1-D transforms of a 3-channel linear convolution at the plan's
/// padded size: per channel, forward real FFTs of the H image rows,
/// forward and inverse complex FFTs of the px/2 + 1 columns, inverse real
/// FFTs of the H output rows; no transposes, no copies.
fn floor(c: &mut Criterion) {
    let mut group = c.benchmark_group("floor");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    for (name, w, h) in SIZES {
        // The padded size a full-frame kernel needs.
        let extent = Extent::for_image(w, h).expect("extent");
        let (px, py) = padded_size(extent.width, extent.height, w, h);
        let columns = px / 2 + 1;
        let row_fft = RealFftPlanner::<f32>::new().plan_fft_forward(px);
        let row_ifft = RealFftPlanner::<f32>::new().plan_fft_inverse(px);
        let mut planner = FftPlanner::<f32>::new();
        let (col_fft, col_ifft) = (planner.plan_fft_forward(py), planner.plan_fft_inverse(py));
        let mut real = vec![0f32; h * px];
        let mut spectra = vec![Complex::new(0f32, 0.0); h * columns];
        let mut cols = vec![Complex::new(0f32, 0.0); columns * py];
        let row_scratch = || row_fft.make_scratch_vec();
        let column_scratch = || vec![Complex::new(0f32, 0.0); col_fft.get_inplace_scratch_len()];
        group.bench_function(name, |b| {
            b.iter(|| {
                for _ in 0..3 {
                    real.par_chunks_mut(px)
                        .zip(spectra.par_chunks_mut(columns))
                        .for_each_init(row_scratch, |scratch, (r, s)| {
                            let _ = row_fft.process_with_scratch(r, s, scratch);
                        });
                    cols.par_chunks_mut(py)
                        .for_each_init(column_scratch, |scratch, col| {
                            col_fft.process_with_scratch(col, scratch)
                        });
                    cols.par_chunks_mut(py)
                        .for_each_init(column_scratch, |scratch, col| {
                            col_ifft.process_with_scratch(col, scratch)
                        });
                    spectra
                        .par_chunks_mut(columns)
                        .zip(real.par_chunks_mut(px))
                        .for_each_init(row_scratch, |scratch, (s, r)| {
                            s[0].im = 0.0;
                            s[columns - 1].im = 0.0;
                            let _ = row_ifft.process_with_scratch(s, r, scratch);
                        });
                }
                black_box(&real);
            })
        });
    }
    group.finish();
}

/// The stages of one plane at 4K on their own, at the padded size a
/// full-frame kernel needs: the forward real FFTs of the H rows, the
/// forward and inverse FFTs of the px/2 + 1 columns, a transpose of the row
/// spectra (what strips and tiles replace), and the product with the
/// kernel's spectrum.
fn stages(c: &mut Criterion) {
    let mut group = c.benchmark_group("stage-4k");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    let (w, h) = (3840, 2160);
    let extent = Extent::for_image(w, h).expect("extent");
    let (px, py) = padded_size(extent.width, extent.height, w, h);
    let columns = px / 2 + 1;
    let zero = Complex::new(0f32, 0.0);
    let row_fft = RealFftPlanner::<f32>::new().plan_fft_forward(px);
    let mut planner = FftPlanner::<f32>::new();
    let (col_fft, col_ifft) = (planner.plan_fft_forward(py), planner.plan_fft_inverse(py));
    let mut real = vec![0f32; h * px];
    let mut spectra = vec![zero; h * columns];
    let mut cols = vec![Complex::new(1f32, 0.5); columns * py];
    let kernel = vec![Complex::new(0.5f32, 0.25); columns * py];
    group.bench_function("row-ffts", |b| {
        b.iter(|| {
            real.par_chunks_mut(px)
                .zip(spectra.par_chunks_mut(columns))
                .for_each_init(
                    || row_fft.make_scratch_vec(),
                    |scratch, (r, s)| {
                        let _ = row_fft.process_with_scratch(r, s, scratch);
                    },
                );
        })
    });
    group.bench_function("column-ffts", |b| {
        b.iter(|| {
            for fft in [&col_fft, &col_ifft] {
                cols.par_chunks_mut(py).for_each_init(
                    || vec![zero; fft.get_inplace_scratch_len()],
                    |scratch, col| fft.process_with_scratch(col, scratch),
                );
            }
        })
    });
    group.bench_function("transpose", |b| {
        b.iter(|| {
            cols.par_chunks_mut(16 * py)
                .enumerate()
                .for_each(|(s, block)| {
                    for (j, column) in block.chunks_mut(py).enumerate() {
                        for (r, v) in column[..h].iter_mut().enumerate() {
                            *v = spectra[r * columns + s * 16 + j];
                        }
                    }
                });
        })
    });
    group.bench_function("multiply", |b| {
        b.iter(|| {
            cols.par_chunks_mut(py)
                .zip(kernel.par_chunks(py))
                .for_each(|(a, k)| a.iter_mut().zip(k).for_each(|(a, k)| *a *= *k));
        })
    });
    group.finish();
}

fn kernel_build(c: &mut Criterion) {
    let mut group = c.benchmark_group("kernel");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(30));
    let (name, w, h) = SIZES[0];
    group.bench_function(name, |b| {
        b.iter(|| black_box(Plan::for_image(&workload::config(), w, h, None).expect("plan")))
    });
    group.finish();
}

criterion_group!(benches, apply, floor, stages, kernel_build);
criterion_main!(benches);
