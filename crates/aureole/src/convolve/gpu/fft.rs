//! The GPU engine's transforms: a batch of 1-D FFTs along the rows or the
//! columns of the padded grid as Stockham passes (fft.wgsl), each pass
//! reading one of two buffers and writing the other.

use super::device::{Gpu, RADICES};
use super::GROUP;

/// Which lines of the grid a batch transforms.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Axis {
    /// Rows of `px` values, side by side in memory.
    Rows,
    /// Columns of `py` values, `px` apart.
    Columns,
}

/// The radices of a transform of `n` (5-smooth) as indices into
/// [`RADICES`], in its order: radix 4 first, the fewest passes, and its
/// butterflies need no multiplications.
fn radices(mut n: usize) -> Vec<usize> {
    let mut found = Vec::new();
    for (index, radix) in RADICES.iter().enumerate() {
        let r = *radix as usize;
        while n % r == 0 && n > 1 {
            found.push(index);
            n /= r;
        }
    }
    found
}

/// e^{−2πik/n} for k < n, for each length one after the other, computed
/// in f64.
pub(super) fn twiddles(gpu: &Gpu, lengths: &[usize]) -> wgpu::Buffer {
    let table: Vec<f32> = lengths
        .iter()
        .flat_map(|&n| {
            (0..n).flat_map(move |k| {
                let (sin, cos) = libm::sincos(-2.0 * std::f64::consts::PI * k as f64 / n as f64);
                [cos as f32, sin as f32]
            })
        })
        .collect();
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("twiddles"),
        size: (table.len() * 4).max(8) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    gpu.queue
        .write_buffer(&buffer, 0, bytemuck::cast_slice(&table));
    buffer
}

/// One pass: its pipeline (an index into [`RADICES`]), bindings and
/// workgroups.
struct Step {
    radix: usize,
    group: wgpu::BindGroup,
    workgroups: (u32, u32),
}

/// The passes of a batch of transforms, and the buffer (0 or 1) that
/// holds the result.
pub(super) struct Passes {
    steps: Vec<Step>,
    pub end: usize,
}

impl Passes {
    /// The passes of `batch` transforms along `axis` of a `px`×`py` grid,
    /// forward or `inverse` (unscaled), starting in buffer `start`;
    /// `twiddles` holds the rows' table, then the columns'.
    pub fn new(
        gpu: &Gpu,
        buffers: [&wgpu::Buffer; 2],
        twiddles: &wgpu::Buffer,
        (axis, px, py): (Axis, usize, usize),
        (batch, inverse, start): (usize, bool, usize),
    ) -> Passes {
        let (n, stride, batch_stride, table) = match axis {
            Axis::Rows => (px, 1, px, 0),
            Axis::Columns => (py, px, 1, px),
        };
        let mut ns = 1usize;
        let mut at = start;
        let mut steps = Vec::new();
        for index in radices(n) {
            let r = RADICES[index] as usize;
            let words: [u32; 8] = [
                n as u32,
                ns as u32,
                stride as u32,
                batch_stride as u32,
                batch as u32,
                table as u32,
                u32::from(inverse),
                u32::from(axis == Axis::Columns),
            ];
            let uniform = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pass"),
                size: 32,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            gpu.queue
                .write_buffer(&uniform, 0, bytemuck::cast_slice(&words));
            let pipeline = &gpu.radix[index];
            let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("pass"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: uniform.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: buffers[at].as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: buffers[1 - at].as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: twiddles.as_entire_binding(),
                    },
                ],
            });
            let butterflies = (n / r) as u32;
            let workgroups = match axis {
                Axis::Rows => (butterflies.div_ceil(GROUP), batch as u32),
                Axis::Columns => ((batch as u32).div_ceil(GROUP), butterflies),
            };
            steps.push(Step {
                radix: index,
                group,
                workgroups,
            });
            ns *= r;
            at = 1 - at;
        }
        Passes { steps, end: at }
    }

    /// Records the passes.
    pub fn encode(&self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) {
        for step in &self.steps {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
            pass.set_pipeline(&gpu.radix[step.radix]);
            pass.set_bind_group(0, &step.group, &[]);
            pass.dispatch_workgroups(step.workgroups.0, step.workgroups.1, 1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radices_multiply_to_the_length() {
        for n in [1usize, 2, 4, 6, 8, 15, 60, 64, 1125, 2160, 4320, 7680] {
            let found = radices(n);
            let product: usize = found.iter().map(|&i| RADICES[i] as usize).product();
            assert_eq!(product, n);
            assert!(found.windows(2).all(|w| w[0] <= w[1]));
        }
    }
}
