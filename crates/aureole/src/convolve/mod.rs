//! The convolution engine: spreading planes of light through a kernel
//! (docs/physics.md §8). The pipeline calls it through one trait,
//! [`Engine`]; the f32 engine (`single.rs`, its one-kernel form
//! [`Convolver`]) and the f64 engine (`double.rs`) implement it on the
//! CPU, sharing the size planning and the transforms planned for it
//! (`grid.rs`), the kernel's placement in the period and the buffer pool.
//! [`engine`] chooses among them by [`Backend`] and [`Precision`],
//! [`footprint`] says what each holds for the memory estimate, and
//! [`compose`] is how kernels convolve one another. The GPU engine
//! (`gpu/`) is one more module and one more arm in each of those matches;
//! [`choose`] finds where a user's [`Device`] runs.

mod double;
#[cfg(feature = "gpu")]
mod gpu;
#[cfg(not(feature = "gpu"))]
#[path = "no_gpu.rs"]
mod gpu;
mod grid;
mod lamps;
mod placement;
pub(crate) mod pool;
mod simd;
mod single;

pub use gpu::{software_adapter, Gpu};
pub use grid::{fast_size, padded_size};
pub use simd::{force_scalar, vectors_in_use};
pub(crate) use simd::{widest, widest_sums};
pub use single::Convolver;

use crate::control::Control;
use crate::error::{Error, Result};

/// Whether an engine convolves a kernel's centre weight with the rest, or
/// leaves it out of the transform and applies it exactly, pixel by pixel:
/// with the (1 − ε) peak out of the FFT its f32 round-off is ~1/ε times
/// smaller.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Centre {
    /// Convolve the whole kernel.
    Include,
    /// Leave the centre weight out of the transform and apply it exactly.
    Leave,
}

/// One kernel plane's share of an output plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Term {
    /// The kernel plane.
    pub kernel_plane: usize,
    /// Its weight in the output.
    pub weight: f32,
}

impl Term {
    /// Kernel plane `kernel_plane` alone, at weight 1: a colour plane
    /// through its own kernel plane, or any plane through a one-plane
    /// kernel.
    pub fn alone(kernel_plane: usize) -> Vec<Term> {
        vec![Term {
            kernel_plane,
            weight: 1.0,
        }]
    }

    /// A luminance plane through a coloured kernel: Y = Σ w_k K_k ⊛ Y, the
    /// Rec.709 weights of its R, G and B planes.
    pub fn luminance() -> Vec<Term> {
        crate::image::REC709_LUMINANCE
            .iter()
            .enumerate()
            .map(|(kernel_plane, &weight)| Term {
                kernel_plane,
                weight,
            })
            .collect()
    }
}

/// One output plane: O = (I − B) + Σ over `terms` of w·K_k ⊛ B, with
/// B = I·fractions (or all of I), the centre weights applied exactly.
#[derive(Debug, Clone)]
pub struct Spread<'a> {
    /// The input plane I, row-major, the engine's width × height.
    pub plane: &'a [f32],
    /// The share of each pixel's light that is spread; `None`: all of it.
    pub fractions: Option<&'a [f32]>,
    /// The kernel planes that make the output, with their weights: one
    /// plane of weight 1 for each colour plane (or a one-plane kernel), or
    /// a luminance plane as Σ w_k K_k ⊛ Y through a coloured kernel.
    pub terms: Vec<Term>,
    /// The brightest pixels (row-major indices, ascending), whose light
    /// near them is added exactly and only the rest transformed, so that
    /// their round-off does not drown the dark pixels; empty for none.
    /// Taken only after [`Engine::split_near`] has said yes.
    pub lamps: &'a [usize],
}

/// The arithmetic an engine computes in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Precision {
    /// f32: fast, round-off ~10⁻⁷ of the bright part.
    Single,
    /// f64: for scenes whose range f32 cannot hold.
    Double,
}

/// Where an engine computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Backend {
    /// The processor's cores, through rustfft (AVX2 where present).
    #[default]
    Cpu,
    /// The process's GPU ([`gpu`]), in f32; the f64 engine stays on the
    /// processor.
    Gpu,
}

/// Where a user asks the convolutions to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Device {
    /// A GPU when there is a hardware one, else the processor.
    Auto,
    /// The processor.
    Cpu,
    /// The GPU (a software adapter such as lavapipe too); an error where
    /// there is none.
    Gpu,
}

impl Device {
    /// The device's name as the front ends spell it.
    pub fn name(self) -> &'static str {
        match self {
            Device::Auto => "auto",
            Device::Cpu => "cpu",
            Device::Gpu => "gpu",
        }
    }

    /// The device named `name` (auto, cpu or gpu).
    pub fn parse(name: &str) -> Option<Device> {
        [Device::Auto, Device::Cpu, Device::Gpu]
            .into_iter()
            .find(|device| device.name() == name)
    }
}

/// Starts looking for a GPU in the background where `device` may take
/// one, while a front end reads its first frame; [`looked_ahead`] before
/// the process exits.
pub fn look_ahead(device: Device) {
    if device != Device::Cpu {
        gpu::look_ahead();
    }
}

/// Waits for a look [`look_ahead`] started.
pub fn looked_ahead() {
    gpu::looked();
}

/// Where the convolutions will run for `device`, and in words where and
/// why: the GPU's name, or why the processor (no adapter, a software
/// one). Only [`Device::Gpu`] without any adapter is an error.
pub fn choose(device: Device) -> Result<(Backend, String)> {
    match device {
        Device::Cpu => Ok((Backend::Cpu, "the CPU".into())),
        Device::Gpu => match gpu::gpu() {
            Ok(found) => Ok((Backend::Gpu, format!("the GPU {}", found.name()))),
            Err(why) => Err(Error::NoGpu(why)),
        },
        Device::Auto => Ok(match gpu::software_adapter() {
            Some(software) => (
                Backend::Cpu,
                format!("the CPU: the only GPU adapter, {software}, is software"),
            ),
            None => match gpu::gpu() {
                Ok(found) => (Backend::Gpu, format!("the GPU {}", found.name())),
                Err(why) => (Backend::Cpu, format!("the CPU: {why}")),
            },
        }),
    }
}

/// The engine that convolves `width`×`height` images with a kernel given as
/// planes (row-major, `size` = width × height, centre at its middle) on
/// `backend` in `precision`: the one place that chooses among the
/// implementations. The f32 engine transforms the kernel when first asked
/// ([`Engine::prepare`], [`Engine::split_near`]); the f64 engine at once.
pub fn engine(
    (backend, precision): (Backend, Precision),
    planes: &[&[f32]],
    size: (usize, usize),
    (width, height): (usize, usize),
    centre: Centre,
    control: &mut Control,
) -> Result<Box<dyn Engine>> {
    Ok(match (backend, precision) {
        (Backend::Cpu, Precision::Single) => Box::new(single::Convolver::deferred(
            planes, size, width, height, centre,
        )),
        (_, Precision::Double) => Box::new(double::Convolver::new(
            planes, size, width, height, centre, control,
        )?),
        #[cfg(not(feature = "gpu"))]
        (Backend::Gpu, Precision::Single) => {
            return Err(Error::NoGpu(gpu::gpu().err().unwrap_or_default()));
        }
        #[cfg(feature = "gpu")]
        (Backend::Gpu, Precision::Single) => {
            let found = gpu::gpu().map_err(Error::NoGpu)?;
            Box::new(gpu::GpuConvolver::new(
                found,
                planes,
                size,
                (width, height),
                centre,
            )?)
        }
    })
}

/// What an engine is given to hold, as far as its memory goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Load {
    /// The images' width and height.
    pub image: (usize, usize),
    /// Planes spread per image.
    pub planes: usize,
    /// The kernel's width and height.
    pub kernel: (usize, usize),
    /// Its planes.
    pub kernel_planes: usize,
    /// Whether the kernel is split for lamps ([`Engine::split_near`]).
    pub split: bool,
}

/// The bytes an engine holds at its peaks, for the memory estimate
/// (`memory.rs`), known before it is built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Footprint {
    /// While it transforms the kernel.
    pub preparing: u64,
    /// While it spreads an image: the kernel's spectra and the buffers of
    /// the planes in flight.
    pub spreading: u64,
}

/// What the engine [`engine`] would choose for `load` holds.
pub fn footprint((backend, precision): (Backend, Precision), load: &Load) -> Footprint {
    match (backend, precision) {
        (Backend::Cpu, Precision::Single) => single::footprint(load),
        (_, Precision::Double) => double::footprint(load),
        (Backend::Gpu, Precision::Single) => gpu::footprint(load),
    }
}

/// Where the kernels of an optical chain convolve one another: the device
/// a user chose, found ([`choose`]) when the first composition comes, so
/// that a chain with nothing to compose never opens a GPU. A GPU that
/// cannot hold a composition (one of two kernel-sized planes, larger than
/// an image's convolution) leaves it, and the rest, to the CPU, and says
/// so: the kernel is built either way.
#[derive(Debug, Clone)]
pub struct Composing {
    device: Device,
    /// Where, and in words, once a composition has asked.
    chosen: Option<(Backend, String)>,
}

impl Composing {
    /// On `device`; [`Device::Gpu`] without an adapter is an error at once.
    pub fn on(device: Device) -> Result<Composing> {
        if device == Device::Gpu {
            choose(device)?;
        }
        Ok(Composing {
            device,
            chosen: None,
        })
    }

    /// On the processor.
    pub fn cpu() -> Composing {
        Composing {
            device: Device::Cpu,
            chosen: None,
        }
    }

    /// Where the compositions ran, in words ("the GPU …", "the CPU: why");
    /// `None` where nothing was composed.
    pub fn words(&self) -> Option<&str> {
        self.chosen.as_ref().map(|(_, words)| words.as_str())
    }
}

/// `plane` (the `extent`'s width × height) convolved whole with one
/// kernel plane of `size`, centre at its middle, in f32: how kernels
/// compose (an optical chain, a filter's orders), on the CPU or, as
/// `composing` says, the GPU.
pub fn compose(
    kernel: &[f32],
    size: (usize, usize),
    plane: &[f32],
    (width, height): (usize, usize),
    composing: &mut Composing,
    control: &mut Control,
) -> Result<Vec<f32>> {
    let chosen = match &mut composing.chosen {
        Some(chosen) => chosen,
        empty => empty.insert(choose(composing.device)?),
    };
    if chosen.0 == Backend::Gpu {
        match compose_on_gpu(kernel, size, plane, (width, height), control) {
            Err(Error::Gpu(why)) => {
                *chosen = (
                    Backend::Cpu,
                    format!("the CPU: {} could not hold it ({why})", chosen.1),
                );
            }
            done => return done,
        }
    }
    let convolver = single::Convolver::new(
        &[kernel],
        size,
        width,
        height,
        Centre::Include,
        &mut control.part(0.0, 0.5),
    )?;
    convolver.convolve(plane, 0, &mut control.part(0.5, 1.0))
}

/// [`compose`] through the GPU engine: all of `plane` spread, the kernel's
/// centre transformed with the rest.
fn compose_on_gpu(
    kernel: &[f32],
    size: (usize, usize),
    plane: &[f32],
    (width, height): (usize, usize),
    control: &mut Control,
) -> Result<Vec<f32>> {
    let engine = engine(
        (Backend::Gpu, Precision::Single),
        &[kernel],
        size,
        (width, height),
        Centre::Include,
        control,
    )?;
    engine.prepare(&[kernel], &mut control.part(0.0, 0.5))?;
    let whole = Spread {
        plane,
        fractions: None,
        terms: Term::alone(0),
        lamps: &[],
    };
    let mut spread = engine.spread(&[whole], Vec::new(), &mut control.part(0.5, 1.0))?;
    spread
        .pop()
        .ok_or_else(|| Error::Gpu("the composition did not come back".into()))
}

/// The bytes [`compose`] holds beside its plane and result: the kernel's
/// spectrum at the plane's size, and the row spectra of the plane.
pub fn compose_bytes(size: (usize, usize), (width, height): (usize, usize)) -> u64 {
    single::compose_bytes(size, (width, height))
}

/// Spreads planes of light through a kernel whose spectrum it holds, for
/// images of one size.
pub trait Engine: Send + Sync {
    /// The padded period of its transforms, columns × rows.
    fn padded_size(&self) -> (usize, usize);

    /// How many kernel planes it holds.
    fn kernel_planes(&self) -> usize;

    /// Prepares to take lamps ([`Spread::lamps`]): the kernel (the planes
    /// it was built from) split at `radius`, its part beyond transformed.
    /// Kept until a call asks for another radius. `false`: this engine
    /// cannot, or the window does not fit in the kernel, or the planes are
    /// not the kernel's.
    fn split_near(
        &self,
        _planes: &[&[f32]],
        _radius: usize,
        _control: &mut Control,
    ) -> Result<bool> {
        Ok(false)
    }

    /// Whether the kernel is split at `radius` already.
    fn has_split(&self, _radius: usize) -> bool {
        false
    }

    /// Whether every kernel plane is transformed, so that [`Engine::spread`]
    /// can run.
    fn ready(&self) -> bool {
        true
    }

    /// Transforms the kernel (the planes it was built from) where an engine
    /// built with its transforms deferred has not yet.
    fn prepare(&self, _planes: &[&[f32]], _control: &mut Control) -> Result<()> {
        Ok(())
    }

    /// Every output of `outputs`, written into the planes of `recycled`
    /// where there are some (memory already mapped); `control` hears the
    /// fraction done and may cancel.
    fn spread(
        &self,
        outputs: &[Spread],
        recycled: Vec<Vec<f32>>,
        control: &mut Control,
    ) -> Result<Vec<Vec<f32>>>;
}
