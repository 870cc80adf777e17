//! The GPU engine (docs/physics.md §8): the f32 engine's convolution in
//! wgpu compute shaders, so on any Vulkan, Metal or DX12 device, and on
//! Mesa's lavapipe where there is none.
//!
//! Two real planes go through one complex transform each way, packed as
//! its real and imaginary parts; the multiply splits their spectra by the
//! transform's symmetry. The kernel planes are packed the same way, and
//! their spectra stay on the device for every frame of the plan's size.
//! The period is the CPU engine's without pruned columns (a 5-smooth size
//! each way), transformed by Stockham passes of radix 4, 2, 3 and 5 whose
//! twiddles are computed in f64 on the host. A frame's planes go up as
//! half floats where every value is one (as a half-float EXR decodes),
//! else as f32, and come back as f32, cut to the frame: the padded
//! spectra never leave the device.

mod device;
mod fft;
mod halves;
mod uniform;

pub use device::{gpu, look_ahead, looked, software_adapter, Gpu};

use std::sync::{Arc, Mutex, PoisonError};

use fft::{Axis, Passes};
use halves::as_halves;
use rayon::prelude::*;
use uniform::Uniform;

use super::grid::Grid;
use super::lamps::Near;
use super::placement::Placement;
use super::{Centre, Engine, Footprint, Load, Spread};
use crate::control::{Cancel, Control};
use crate::error::{Error, Result};

/// Bytes of a complex f32.
const COMPLEX: u64 = 8;

/// Invocations in a workgroup (the shaders' `@workgroup_size`).
const GROUP: u32 = 64;

/// What the engine holds on the device: two padded complex planes it
/// transforms between, each pair of kernel planes' spectrum, and the
/// buffers a frame's planes go through; on the host, beyond the frame's
/// planes, a pair's halves going up (one plane's bytes).
pub(super) fn footprint(load: &Load) -> Footprint {
    let (px, py) = Grid::new(load.kernel, load.image, false).padded();
    let grid = px as u64 * py as u64 * COMPLEX;
    let spectra = load.kernel_planes.div_ceil(2) as u64 * grid;
    let frame = load.image.0 as u64 * load.image.1 as u64 * 4;
    Footprint {
        preparing: 2 * grid + spectra,
        spreading: 2 * grid + spectra + 6 * frame,
    }
}

/// Values a thread copies out of the mapped results at a time.
const CHUNK: usize = 1 << 16;

/// Bytes one thread hands the queue to send up at a time: the queue
/// copies each into host memory of its own outside its locks, so a frame
/// goes up from every core.
const PIECE: usize = 1 << 22;

/// A padded complex grid's worth of device memory, for a kernel spectrum.
fn spectrum_buffer(gpu: &Gpu, bytes: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("kernel spectrum"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// One kernel plane's spectrum: the packed pair it is in, and which half.
#[derive(Debug, Clone, Copy)]
struct Half {
    pair: usize,
    half: u32,
}

/// The device buffers of the engine's transforms, made with it.
struct Work {
    /// The two padded complex planes the passes go between.
    planes: [wgpu::Buffer; 2],
    twiddles: wgpu::Buffer,
    /// The frame's planes going up (two), the fractions, the results
    /// coming down (two), and where they are read from.
    frame: wgpu::Buffer,
    fractions: wgpu::Buffer,
    results: wgpu::Buffer,
    staging: wgpu::Buffer,
    /// A pair's planes as half floats on the host, on their way up.
    halves: Mutex<Vec<u16>>,
    /// The passes of a frame: rows forward over its rows, columns both
    /// ways, rows back over its rows.
    rows_forward: Passes,
    columns_forward: Passes,
    columns_inverse: Passes,
    rows_inverse: Passes,
    /// Rows and columns forward over the whole period, for the kernel.
    kernel_rows: Passes,
    kernel_columns: Passes,
}

/// The kernel split for lamps (docs/physics.md §8): O = (I − B) + c·B +
/// K′ ⊛ B_lo + K_far ⊛ B_hi + K_near ⊛ B_hi, the last a direct sum on the
/// host. The lamps go through a third grid of their own; both bands'
/// spectra are multiplied into one product that goes back once.
struct Split {
    near: Near,
    /// K_far's spectra, packed in pairs as the whole kernel's.
    far: Vec<Arc<wgpu::Buffer>>,
    /// The lamps' grid.
    lit: wgpu::Buffer,
    /// The lamps' transforms (between their grid and the buffer the
    /// frame's transforms leave free), the product, and the transforms
    /// back from it.
    lamp_rows: Passes,
    lamp_columns: Passes,
    product: wgpu::Buffer,
    columns_inverse: Passes,
    rows_inverse: Passes,
    /// The buffer the frame's transforms leave free (the lamps' rows may
    /// end there: its rows below the frame are cleared).
    free: wgpu::Buffer,
    /// The buffer the transforms back end in.
    end: wgpu::Buffer,
}

/// Convolves `width`×`height` planes with a kernel on the GPU.
pub(super) struct GpuConvolver {
    gpu: Arc<Gpu>,
    width: usize,
    height: usize,
    kernel_size: (usize, usize),
    px: usize,
    py: usize,
    planes: usize,
    centre: Centre,
    /// Each kernel plane's centre weight, applied exactly.
    centres: Vec<f32>,
    /// The spectra of the kernel planes, packed in pairs: (0, 1), (2, –),
    /// held from the start so that a device without the memory refuses
    /// the plan, not its first frame.
    spectra: Vec<Arc<wgpu::Buffer>>,
    /// Pairs transformed so far.
    transformed: Mutex<usize>,
    /// The split for lamps last asked for.
    split: Mutex<Option<Arc<Split>>>,
    work: Mutex<Work>,
    /// Whether a frame whose every value is a half float goes up as
    /// halves (half the bytes over the bus); off only to show that it
    /// changes no bit.
    halves_up: bool,
}

impl GpuConvolver {
    /// Plans the convolution of `width`×`height` images with a kernel of
    /// `size` (its `planes`) on `gpu`; the spectra are made by
    /// [`Engine::prepare`]. Refuses a period beyond the device's buffers.
    pub fn new(
        gpu: Arc<Gpu>,
        planes: &[&[f32]],
        size: (usize, usize),
        (width, height): (usize, usize),
        centre: Centre,
    ) -> Result<GpuConvolver> {
        let (px, py) = Grid::new(size, (width, height), false).padded();
        let grid_bytes = px as u64 * py as u64 * COMPLEX;
        let frame_bytes = 2 * width as u64 * height as u64 * 4;
        let kernel_bytes = 2 * size.0 as u64 * size.1 as u64 * 4;
        let largest = grid_bytes.max(frame_bytes).max(kernel_bytes);
        let lines = px.max(py) as u64;
        if largest > gpu.max_buffer || lines > u64::from(u16::MAX) {
            return Err(Error::Gpu(format!(
                "a {px}×{py} period needs buffers of {largest} bytes, more than {} allows ({} bytes)",
                gpu.name(),
                gpu.max_buffer
            )));
        }
        let work = gpu.scoped("allocating the transforms", || {
            let device = &gpu.device;
            let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: size.max(4),
                    usage,
                    mapped_at_creation: false,
                })
            };
            let storage = wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC;
            let twiddles = fft::twiddles(&gpu, &[px, py]);
            let first = buffer("grid a", grid_bytes, storage);
            let second = buffer("grid b", grid_bytes, storage);
            let along = |axis: Axis, batch: usize, inverse: bool, start: usize| {
                Passes::new(
                    &gpu,
                    [&first, &second],
                    &twiddles,
                    (axis, px, py),
                    (batch, inverse, start),
                )
            };
            let rows_forward = along(Axis::Rows, height, false, 0);
            let columns_forward = along(Axis::Columns, px, false, rows_forward.end);
            let columns_inverse = along(Axis::Columns, px, true, 1 - columns_forward.end);
            let rows_inverse = along(Axis::Rows, height, true, columns_inverse.end);
            let kernel_rows = along(Axis::Rows, py, false, 0);
            let kernel_columns = along(Axis::Columns, px, false, kernel_rows.end);
            Work {
                frame: buffer("frame", frame_bytes, storage),
                fractions: buffer("fractions", frame_bytes / 2, storage),
                results: buffer("results", frame_bytes, storage),
                staging: buffer(
                    "staging",
                    frame_bytes,
                    wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                ),
                halves: Mutex::new(Vec::new()),
                planes: [first, second],
                twiddles,
                rows_forward,
                columns_forward,
                columns_inverse,
                rows_inverse,
                kernel_rows,
                kernel_columns,
            }
        })?;
        let spectra = gpu.scoped("holding the kernel's spectra", || {
            (0..planes.len().div_ceil(2))
                .map(|_| Arc::new(spectrum_buffer(&gpu, grid_bytes)))
                .collect()
        })?;
        let centres = Placement::left_out_of(planes, size, centre);
        Ok(GpuConvolver {
            gpu,
            width,
            height,
            kernel_size: size,
            px,
            py,
            planes: planes.len(),
            centre,
            centres,
            spectra,
            transformed: Mutex::new(0),
            split: Mutex::new(None),
            work: Mutex::new(work),
            halves_up: true,
        })
    }

    /// Where kernel plane `k`'s spectrum is.
    fn half(k: usize) -> Half {
        Half {
            pair: k / 2,
            half: (k % 2) as u32,
        }
    }

    fn grid_uniform(&self) -> Uniform {
        Uniform {
            px: self.px as u32,
            py: self.py as u32,
            width: self.width as u32,
            height: self.height as u32,
            ..Uniform::default()
        }
    }

    fn uniform(&self, values: &Uniform) -> wgpu::Buffer {
        let buffer = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("grid uniform"),
            size: 80,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.gpu
            .queue
            .write_buffer(&buffer, 0, bytemuck::cast_slice(&values.words()));
        buffer
    }

    fn bind(
        &self,
        pipeline: &wgpu::ComputePipeline,
        buffers: &[(u32, &wgpu::Buffer)],
    ) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .map(|&(binding, buffer)| wgpu::BindGroupEntry {
                binding,
                resource: buffer.as_entire_binding(),
            })
            .collect();
        self.gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            })
    }

    /// Dispatches `pipeline` over the grid's columns and `rows` rows.
    fn over_grid(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        group: &wgpu::BindGroup,
        (columns, rows): (usize, usize),
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups((columns as u32).div_ceil(GROUP), rows as u32, 1);
    }

    /// Submits `encoder` and waits for the device, checking `control`'s
    /// cancellation while it works.
    fn run(&self, encoder: wgpu::CommandEncoder, control: &Control) -> Result<()> {
        let index = self.gpu.queue.submit([encoder.finish()]);
        self.wait(Some(index), control)
    }

    /// Waits for submission `index` (the last one where `None`), and the
    /// callbacks it fires, checking `control`'s cancellation meanwhile.
    fn wait(&self, index: Option<wgpu::SubmissionIndex>, control: &Control) -> Result<()> {
        loop {
            let waited = self.gpu.device.poll(wgpu::PollType::Wait {
                submission_index: index.clone(),
                timeout: Some(std::time::Duration::from_millis(100)),
            });
            match waited {
                Ok(_) => break,
                Err(wgpu::PollError::Timeout) => control.check()?,
                Err(error) => return Err(Error::Gpu(error.to_string())),
            }
        }
        match self.gpu.failure() {
            Some(error) => Err(Error::Gpu(error)),
            None => control.check(),
        }
    }

    /// The packed spectrum of kernel planes `pair` (2·pair and the next),
    /// their centres left out with `leave_centre`.
    fn kernel_pair(
        &self,
        work: &Work,
        (planes, leave_centre): (&[&[f32]], bool),
        (pair, spectrum): (usize, &wgpu::Buffer),
        control: &Control,
    ) -> Result<()> {
        let device = &self.gpu.device;
        let (kw, kh) = self.kernel_size;
        let packed: Vec<&[f32]> = planes.iter().skip(2 * pair).take(2).copied().collect();
        let source = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("kernel planes"),
            size: (packed.len() * kw * kh * 4).max(4) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        for (p, plane) in packed.iter().enumerate() {
            self.gpu.queue.write_buffer(
                &source,
                (p * kw * kh * 4) as u64,
                bytemuck::cast_slice(plane),
            );
        }
        let uniform = self.uniform(&Uniform {
            width: kw as u32,
            height: kh as u32,
            planes: packed.len() as u32,
            leave_centre,
            ..self.grid_uniform()
        });
        let group = self.bind(
            &self.gpu.place,
            &[(0, &uniform), (1, &source), (3, &work.planes[0])],
        );
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        self.over_grid(&mut encoder, &self.gpu.place, &group, (self.px, self.py));
        work.kernel_rows.encode(&self.gpu, &mut encoder);
        work.kernel_columns.encode(&self.gpu, &mut encoder);
        let end = &work.planes[work.kernel_columns.end];
        encoder.copy_buffer_to_buffer(end, 0, spectrum, 0, None);
        self.run(encoder, control)
    }

    /// Outputs `a` and, where there is one, `b`, through one complex
    /// transform each way, into `recycled`'s planes where there are some;
    /// their lamps, if any, through `split`.
    fn pair(
        &self,
        work: &Work,
        (spectra, split): (&[Arc<wgpu::Buffer>], Option<&Split>),
        (a, b): (&Spread, Option<&Spread>),
        recycled: &mut Vec<Vec<f32>>,
        control: &Control,
    ) -> Result<Vec<Vec<f32>>> {
        let device = &self.gpu.device;
        let n = self.width * self.height;
        let outputs: Vec<&Spread> = std::iter::once(a).chain(b).collect();
        let planes: Vec<&[f32]> = outputs.iter().map(|output| output.plane).collect();
        let halves = self.upload(work, &planes);
        let fractions = a.fractions;
        let split = split.filter(|_| !a.lamps.is_empty());
        let base = Uniform {
            planes: outputs.len() as u32,
            fractions: fractions.is_some(),
            lamps: split.map_or(0, |_| a.lamps.len() as u32),
            halves_up: halves,
            ..self.grid_uniform()
        };
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        // The column passes read the whole period: its rows below the
        // frame must be zeros.
        let below = (self.height * self.px) as u64 * COMPLEX;
        encoder.clear_buffer(&work.planes[work.rows_forward.end], below, None);
        let uniform = self.uniform(&base);
        let load = self.bind(
            &self.gpu.load,
            &[
                (0, &uniform),
                (1, &work.frame),
                (2, &work.fractions),
                (3, &work.planes[0]),
            ],
        );
        self.over_grid(&mut encoder, &self.gpu.load, &load, (self.px, self.height));
        if let Some(split) = split {
            self.scatter(&mut encoder, (work, split), a.lamps, &uniform);
        }
        work.rows_forward.encode(&self.gpu, &mut encoder);
        work.columns_forward.encode(&self.gpu, &mut encoder);
        let transformed = &work.planes[work.columns_forward.end];
        let products = match split {
            Some(split) => {
                encoder.clear_buffer(&split.free, below, None);
                split.lamp_rows.encode(&self.gpu, &mut encoder);
                split.lamp_columns.encode(&self.gpu, &mut encoder);
                &split.product
            }
            None => &work.planes[1 - work.columns_forward.end],
        };
        let mut bands = vec![(transformed, spectra)];
        if let Some(split) = split {
            let lit = [&split.lit, &split.free][split.lamp_columns.end];
            bands.push((lit, split.far.as_slice()));
        }
        let centre = self.multiply(&mut encoder, &bands, (a, b), &base, products);
        let result = match split {
            Some(split) => {
                split.columns_inverse.encode(&self.gpu, &mut encoder);
                split.rows_inverse.encode(&self.gpu, &mut encoder);
                &split.end
            }
            None => {
                work.columns_inverse.encode(&self.gpu, &mut encoder);
                work.rows_inverse.encode(&self.gpu, &mut encoder);
                &work.planes[work.rows_inverse.end]
            }
        };
        let finish_uniform = self.uniform(&Uniform { centre, ..base });
        let finish = self.bind(
            &self.gpu.finish,
            &[
                (0, &finish_uniform),
                (1, &work.frame),
                (2, &work.fractions),
                (3, result),
                (4, &work.results),
            ],
        );
        self.over_grid(
            &mut encoder,
            &self.gpu.finish,
            &finish,
            (self.width, self.height),
        );
        let bytes = (outputs.len() * n * 4) as u64;
        encoder.copy_buffer_to_buffer(&work.results, 0, &work.staging, 0, Some(bytes));
        self.run(encoder, control)?;
        let mut planes: Vec<Vec<f32>> = outputs
            .iter()
            .map(|_| recycled.pop().unwrap_or_default())
            .collect();
        self.read(&work.staging, &mut planes, control)?;
        if let Some(split) = split {
            for (plane, output) in planes.iter_mut().zip(&outputs) {
                self.add_near(&split.near, output, plane, &control.cancel());
            }
        }
        control.check()?;
        Ok(planes)
    }

    /// The frame's uploaded planes: as halves where the planes allow it and
    /// the device takes them (returns whether it did), else as f32.
    fn upload(&self, work: &Work, planes: &[&[f32]]) -> bool {
        let n = self.width * self.height;
        let mut host = work.halves.lock().unwrap_or_else(PoisonError::into_inner);
        let halves = self.halves_up && as_halves(planes, &mut host);
        if halves {
            self.up(&work.frame, 0, bytemuck::cast_slice(&host));
        } else {
            for (p, plane) in planes.iter().enumerate() {
                self.up(&work.frame, p * n * 4, bytemuck::cast_slice(plane));
            }
        }
        halves
    }

    /// Records the products of each band's frame spectra (`bands`: the
    /// frames, the kernel spectra they multiply) with every term of `a`
    /// and `b`, accumulated into `products`; returns their centre weights.
    fn multiply(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        bands: &[(&wgpu::Buffer, &[Arc<wgpu::Buffer>])],
        (a, b): (&Spread, Option<&Spread>),
        base: &Uniform,
        products: &wgpu::Buffer,
    ) -> [f32; 2] {
        let mut centre = [0.0f32; 2];
        let terms = a.terms.len().max(b.map_or(0, |b| b.terms.len()));
        for (band, (frames, kernels)) in bands.iter().enumerate() {
            for t in 0..terms {
                let term_a = a.terms.get(t);
                let term_b = b.and_then(|b| b.terms.get(t));
                let plane_a = term_a.map_or(0, |term| term.kernel_plane);
                let plane_b = term_b.map_or(plane_a, |term| term.kernel_plane);
                let (half_a, half_b) = (Self::half(plane_a), Self::half(plane_b));
                let weight_a = term_a.map_or(0.0, |term| term.weight);
                let weight_b = term_b.map_or(0.0, |term| term.weight);
                if band == 0 {
                    centre[0] += weight_a * self.centres[plane_a];
                    centre[1] += weight_b * self.centres[plane_b];
                }
                let uniform = self.uniform(&Uniform {
                    accumulate: band > 0 || t > 0,
                    halves: [half_a.half, half_b.half],
                    weights: [weight_a, weight_b],
                    ..*base
                });
                let group = self.bind(
                    &self.gpu.multiply,
                    &[
                        (0, &uniform),
                        (1, frames),
                        (2, &kernels[half_a.pair]),
                        (3, &kernels[half_b.pair]),
                        (4, products),
                    ],
                );
                self.over_grid(encoder, &self.gpu.multiply, &group, (self.px, self.py));
            }
        }
        centre
    }

    /// Records moving the lamps (`lamps`, frame indices) from the loaded
    /// grid into the split's own.
    fn scatter(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (work, split): (&Work, &Split),
        lamps: &[usize],
        uniform: &wgpu::Buffer,
    ) {
        let indices: Vec<u32> = lamps.iter().map(|&i| i as u32).collect();
        let buffer = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lamps"),
            size: (indices.len() * 4).max(4) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.gpu
            .queue
            .write_buffer(&buffer, 0, bytemuck::cast_slice(&indices));
        encoder.clear_buffer(&split.lit, 0, None);
        let group = self.bind(
            &self.gpu.scatter,
            &[
                (0, uniform),
                (1, &buffer),
                (2, &work.planes[0]),
                (3, &split.lit),
            ],
        );
        self.over_grid(encoder, &self.gpu.scatter, &group, (indices.len(), 1));
    }

    /// Adds the lamps' near light to `out`, output `output`'s: each term's
    /// window at every lamp, by its weight, as the CPU engine does.
    fn add_near(&self, near: &Near, output: &Spread, out: &mut [f32], cancel: &Cancel) {
        let bright = |i: usize| output.plane[i] * output.fractions.map_or(1.0, |f| f[i]);
        for term in &output.terms {
            if term.weight == 1.0 {
                near.add(
                    term.kernel_plane,
                    output.lamps,
                    &bright,
                    out,
                    self.width,
                    cancel,
                );
            } else {
                let mut part = vec![0.0f32; out.len()];
                near.add(
                    term.kernel_plane,
                    output.lamps,
                    &bright,
                    &mut part,
                    self.width,
                    cancel,
                );
                for (o, p) in out.iter_mut().zip(&part) {
                    *o += term.weight * p;
                }
            }
        }
    }

    /// The kernel (`planes`) split at `near`'s radius: K_far's spectra and
    /// the lamps' grid and passes, the last split's dropped first.
    fn build_split(&self, planes: &[&[f32]], near: Near, control: &mut Control) -> Result<Split> {
        let size = self.kernel_size;
        let far_planes: Vec<Vec<f32>> = planes.iter().map(|p| near.far_plane(p, size)).collect();
        let far_slices: Vec<&[f32]> = far_planes.iter().map(Vec::as_slice).collect();
        let work = self.work.lock().unwrap_or_else(PoisonError::into_inner);
        // The last split's grids go before the next one's are made.
        self.split
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take();
        let pairs = self.planes.div_ceil(2);
        let grid_bytes = self.px as u64 * self.py as u64 * COMPLEX;
        let far: Vec<Arc<wgpu::Buffer>> =
            self.gpu.scoped("holding the far kernel's spectra", || {
                (0..pairs)
                    .map(|_| Arc::new(spectrum_buffer(&self.gpu, grid_bytes)))
                    .collect()
            })?;
        for (pair, spectrum) in far.iter().enumerate() {
            self.kernel_pair(&work, (&far_slices, false), (pair, spectrum), control)?;
            control.report(0.5 + 0.5 * (pair + 1) as f64 / pairs as f64);
        }
        self.gpu.scoped("holding the lamps' grids", || {
            let buffer = |label: &str| {
                self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: grid_bytes,
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                })
            };
            let lit = buffer("lamps' grid");
            let spectrum = work.planes[work.columns_forward.end].clone();
            let free = work.planes[1 - work.columns_forward.end].clone();
            let along = |buffers: [&wgpu::Buffer; 2], axis, batch, inverse, start| {
                Passes::new(
                    &self.gpu,
                    buffers,
                    &work.twiddles,
                    (axis, self.px, self.py),
                    (batch, inverse, start),
                )
            };
            let lamp_rows = along([&lit, &free], Axis::Rows, self.height, false, 0);
            let lamp_columns = along([&lit, &free], Axis::Columns, self.px, false, lamp_rows.end);
            let product = if lamp_columns.end == 0 {
                free.clone()
            } else {
                lit.clone()
            };
            let columns_inverse = along([&product, &spectrum], Axis::Columns, self.px, true, 0);
            let rows_inverse = along(
                [&product, &spectrum],
                Axis::Rows,
                self.height,
                true,
                columns_inverse.end,
            );
            let end = [&product, &spectrum][rows_inverse.end].clone();
            Split {
                near,
                far,
                lit,
                lamp_rows,
                lamp_columns,
                product,
                columns_inverse,
                rows_inverse,
                free,
                end,
            }
        })
    }

    /// Sends `bytes` up to `buffer` from `offset` with the next
    /// submission, from every core.
    fn up(&self, buffer: &wgpu::Buffer, offset: usize, bytes: &[u8]) {
        bytes.par_chunks(PIECE).enumerate().for_each(|(i, piece)| {
            self.gpu
                .queue
                .write_buffer(buffer, (offset + i * PIECE) as u64, piece);
        });
    }

    /// The first planes of `staging`, into `planes` (each made a frame
    /// long), on every core.
    fn read(
        &self,
        staging: &wgpu::Buffer,
        planes: &mut [Vec<f32>],
        control: &Control,
    ) -> Result<()> {
        let n = self.width * self.height;
        let bytes = (planes.len() * n * 4) as u64;
        for plane in planes.iter_mut() {
            crate::image::grow_zeroed(plane, n)?;
        }
        if bytes == 0 {
            return Ok(());
        }
        let (sender, receiver) = std::sync::mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, 0..bytes, move |mapped| {
            let _ = sender.send(mapped);
        });
        self.wait(None, control)?;
        receiver
            .recv()
            .map_err(|_| Error::Gpu("the results were not read back".into()))?
            .map_err(|error| Error::Gpu(format!("reading the results back: {error}")))?;
        {
            let view = staging
                .get_mapped_range(0..bytes)
                .map_err(|error| Error::Gpu(format!("reading the results back: {error}")))?;
            planes
                .par_iter_mut()
                .zip(view.par_chunks(4 * n))
                .for_each(|(plane, values)| {
                    plane
                        .par_chunks_mut(CHUNK)
                        .zip(values.par_chunks(4 * CHUNK))
                        .for_each(|(out, bytes)| {
                            bytemuck::cast_slice_mut::<f32, u8>(out).copy_from_slice(bytes)
                        });
                });
        }
        staging.unmap();
        Ok(())
    }
}

impl Engine for GpuConvolver {
    fn padded_size(&self) -> (usize, usize) {
        (self.px, self.py)
    }

    fn kernel_planes(&self) -> usize {
        self.planes
    }

    fn has_split(&self, radius: usize) -> bool {
        self.split
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .as_ref()
            .is_some_and(|split| split.near.radius == radius)
    }

    fn split_near(&self, planes: &[&[f32]], radius: usize, control: &mut Control) -> Result<bool> {
        if self.has_split(radius) {
            return Ok(true);
        }
        let Some(near) = Near::fitting(planes, self.kernel_size, radius, self.planes) else {
            return Ok(false);
        };
        self.prepare(planes, &mut control.part(0.0, 0.5))?;
        match self.build_split(planes, near, control) {
            Ok(split) => {
                *self.split.lock().unwrap_or_else(PoisonError::into_inner) = Some(Arc::new(split));
                Ok(true)
            }
            // A device without the memory for the lamps' spectra and grid
            // leaves the scene to the f64 engine, as a split that does not
            // fit does on the CPU.
            Err(Error::Gpu(_)) => Ok(false),
            Err(other) => Err(other),
        }
    }

    fn ready(&self) -> bool {
        *self
            .transformed
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            == self.spectra.len()
    }

    fn prepare(&self, planes: &[&[f32]], control: &mut Control) -> Result<()> {
        if self.ready() {
            return Ok(());
        }
        if planes.len() != self.planes {
            return Err(Error::NotTransformed);
        }
        let work = self.work.lock().unwrap_or_else(PoisonError::into_inner);
        let mut transformed = self
            .transformed
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        let leave = self.centre == Centre::Leave;
        while *transformed < self.spectra.len() {
            let pair = *transformed;
            let spectrum = &self.spectra[pair];
            self.kernel_pair(&work, (planes, leave), (pair, spectrum), control)?;
            *transformed += 1;
            control.report(*transformed as f64 / self.spectra.len() as f64);
        }
        Ok(())
    }

    fn spread(
        &self,
        outputs: &[Spread],
        mut recycled: Vec<Vec<f32>>,
        control: &mut Control,
    ) -> Result<Vec<Vec<f32>>> {
        if !self.ready() {
            return Err(Error::NotTransformed);
        }
        let split = self
            .split
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone();
        let work = self.work.lock().unwrap_or_else(PoisonError::into_inner);
        let mut planes = Vec::with_capacity(outputs.len());
        // Two outputs share a transform when they spread the same share of
        // each pixel (every output of a frame does).
        let same = |a: &Spread, b: &Spread| match (a.fractions, b.fractions) {
            (None, None) => true,
            (Some(x), Some(y)) => std::ptr::eq(x, y),
            _ => false,
        };
        let mut uploaded: Option<&Spread> = None;
        let mut next = 0;
        while next < outputs.len() {
            let a = &outputs[next];
            let b = outputs.get(next + 1).filter(|b| same(a, b));
            if let (Some(fractions), false) = (a.fractions, uploaded.is_some_and(|u| same(u, a))) {
                self.gpu
                    .queue
                    .write_buffer(&work.fractions, 0, bytemuck::cast_slice(fractions));
                uploaded = Some(a);
            }
            let pair = (&self.spectra[..], split.as_deref());
            planes.extend(self.pair(&work, pair, (a, b), &mut recycled, control)?);
            next += 1 + usize::from(b.is_some());
            control.report(next as f64 / outputs.len() as f64);
        }
        Ok(planes)
    }
}

// The tests' shared rule for a missing reference.
#[cfg(test)]
#[path = "../../../../../tests/support/required.rs"]
mod required;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::Cancel;
    use crate::convolve::Term;
    use half::f16;

    #[test]
    fn frames_sent_up_as_halves_give_the_same_bits() {
        let Ok(gpu) = gpu() else {
            super::required::missing(
                "frames_sent_up_as_halves_give_the_same_bits",
                "no GPU adapter (Debian: mesa-vulkan-drivers for lavapipe)",
            );
            return;
        };
        let (w, h) = (97, 61);
        // Values a half-float EXR holds: 1/8 steps over five decades.
        let plane: Vec<f32> = (0..w * h)
            .map(|i| f16::from_f32(0.01 * 1.3f32.powi((i * 7 % 45) as i32)).to_f32())
            .collect();
        let kernel: Vec<f32> = (0..31 * 25).map(|i| (i % 13) as f32 + 0.5).collect();
        assert!(as_halves(&[&plane], &mut Vec::new()));
        let cancel = Cancel::new();
        let spread = |halves_up, recycled| {
            let mut engine =
                GpuConvolver::new(gpu.clone(), &[&kernel], (31, 25), (w, h), Centre::Leave)
                    .unwrap();
            engine.halves_up = halves_up;
            let mut control = Control::quiet(&cancel);
            engine.prepare(&[&kernel], &mut control).unwrap();
            let outputs = [&plane, &plane, &plane].map(|plane| Spread {
                plane,
                fractions: None,
                terms: Term::alone(0),
                lamps: &[],
            });
            engine.spread(&outputs, recycled, &mut control).unwrap()
        };
        let (halves, words) = (spread(true, Vec::new()), spread(false, Vec::new()));
        assert!(halves == words, "halves and f32 gave different bits");
        assert!(halves[0].iter().any(|v| *v != 0.0));
        // The results come back into planes a frame lends, whatever they
        // held and however long they were.
        let lent = vec![vec![f32::NAN; w * h + 5], vec![7.0; 3], vec![-1.0; w * h]];
        assert!(
            spread(true, lent) == halves,
            "lent planes changed the results"
        );
    }
}
