//! The GPU a process computes on: one adapter, found once, with its device,
//! queue and the engine's compiled pipelines, shared by every plan.

use std::sync::{Arc, Mutex, OnceLock, PoisonError};

use crate::error::{Error, Result};

/// The FFT's radices, in the order of their pipelines.
pub(super) const RADICES: [u32; 4] = [4, 2, 3, 5];

/// An adapter opened for compute, with the engine's pipelines.
pub struct Gpu {
    pub(super) device: wgpu::Device,
    pub(super) queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    /// The largest buffer, and the largest storage binding, in bytes.
    pub(super) max_buffer: u64,
    /// Stockham passes, one per radix of [`RADICES`].
    pub(super) radix: Vec<wgpu::ComputePipeline>,
    pub(super) load: wgpu::ComputePipeline,
    pub(super) place: wgpu::ComputePipeline,
    pub(super) multiply: wgpu::ComputePipeline,
    pub(super) finish: wgpu::ComputePipeline,
    pub(super) scatter: wgpu::ComputePipeline,
    /// The first error the device reported outside an error scope (a lost
    /// device, say): wgpu's default would panic.
    lost: Arc<Mutex<Option<String>>>,
}

impl std::fmt::Debug for Gpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gpu")
            .field("name", &self.info.name)
            .finish()
    }
}

impl Gpu {
    /// The adapter's name and API, e.g. `NVIDIA H100 through Vulkan`.
    pub fn name(&self) -> String {
        format!("{} through {:?}", self.info.name, self.info.backend)
    }

    /// Whether the adapter computes on the processor (Mesa's lavapipe,
    /// WARP): correct, but no faster than the CPU engine.
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// An error the device reported since it was opened, if any.
    pub(super) fn failure(&self) -> Option<String> {
        self.lost
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }

    /// Runs `work` in an error scope: what the device refuses (memory
    /// above its budget, a binding too large) comes back as an error
    /// instead of wgpu's panic.
    pub(super) fn scoped<T>(&self, what: &str, work: impl FnOnce() -> T) -> Result<T> {
        let memory = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = work();
        let invalid = pollster::block_on(validation.pop());
        let exhausted = pollster::block_on(memory.pop());
        match exhausted.or(invalid) {
            Some(error) => Err(Error::Gpu(format!("{what}: {error}"))),
            None => match self.failure() {
                Some(lost) => Err(Error::Gpu(lost)),
                None => Ok(value),
            },
        }
    }
}

/// The process's GPU adapter, found once: the first hardware one, else a
/// software one; `Err` says why there is none.
fn adapter() -> std::result::Result<&'static wgpu::Adapter, String> {
    static ADAPTER: OnceLock<std::result::Result<wgpu::Adapter, String>> = OnceLock::new();
    ADAPTER.get_or_init(find).as_ref().map_err(Clone::clone)
}

/// The process's adapter's name when it computes on the processor (Mesa's
/// lavapipe, WARP), known without opening it; `None` for a hardware
/// adapter, or none.
pub fn software_adapter() -> Option<String> {
    let info = adapter().ok()?.get_info();
    (info.device_type == wgpu::DeviceType::Cpu)
        .then(|| format!("{} through {:?}", info.name, info.backend))
}

/// The process's GPU, opened once with the engine's pipelines compiled;
/// `Err` says why there is none.
pub fn gpu() -> std::result::Result<Arc<Gpu>, String> {
    static GPU: OnceLock<std::result::Result<Arc<Gpu>, String>> = OnceLock::new();
    GPU.get_or_init(|| open(adapter()?).map(Arc::new)).clone()
}

/// The adapter looked for on a thread of its own ([`look_ahead`]).
static LOOKING: Mutex<Option<std::thread::JoinHandle<()>>> = Mutex::new(None);

/// Starts looking for the process's adapter on a thread of its own, once:
/// loading the drivers (Mesa's link LLVM) took 40 ms of a 1.2 s 4K still
/// on two cores, which the reading of its frame now hides. [`looked`]
/// waits for it.
pub fn look_ahead() {
    static STARTED: std::sync::Once = std::sync::Once::new();
    STARTED.call_once(|| {
        // Here, not on the thread: nothing sets the environment while
        // another thread may read it.
        quiet_device_select();
        let looking = std::thread::Builder::new()
            .name("aureole-gpu-probe".into())
            .spawn(|| drop(adapter()));
        if let Ok(handle) = looking {
            *LOOKING.lock().unwrap_or_else(PoisonError::into_inner) = Some(handle);
        }
    });
}

/// Waits for a look started by [`look_ahead`] to end, so that a process
/// never exits while drivers are still being loaded.
pub fn looked() {
    let handle = LOOKING
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .take();
    if let Some(handle) = handle {
        // A panic in the drivers has been answered by `adapter` already.
        drop(handle.join());
    }
}

/// Mesa's implicit device_select layer looks for a Wayland display while
/// the adapters are listed, and without XDG_RUNTIME_DIR (a render node,
/// CI, ssh) libwayland prints two error lines on every run. The engine
/// picks its adapter itself: the layer is turned off, once, before any
/// Vulkan thread exists.
fn quiet_device_select() {
    if std::env::var_os("NODEVICE_SELECT").is_none() {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
}

fn find() -> std::result::Result<wgpu::Adapter, String> {
    quiet_device_select();
    let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle();
    descriptor.backends = wgpu::Backends::PRIMARY;
    // Buffers beyond 90 % of the device's memory budget are refused with
    // an error the engine turns into a fall back to the CPU, instead of
    // the driver paging or failing later.
    descriptor.memory_budget_thresholds = wgpu::MemoryBudgetThresholds {
        for_resource_creation: Some(90),
        for_device_loss: None,
    };
    let instance = wgpu::Instance::new(descriptor);
    pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        force_fallback_adapter: false,
        ..wgpu::RequestAdapterOptions::default()
    }))
    .map_err(|error| format!("no GPU adapter was found ({error})"))
}

fn open(adapter: &wgpu::Adapter) -> std::result::Result<Gpu, String> {
    let info = adapter.get_info();
    let offered = adapter.limits();
    let limits = wgpu::Limits {
        max_buffer_size: offered.max_buffer_size,
        max_storage_buffer_binding_size: offered.max_storage_buffer_binding_size,
        max_compute_workgroups_per_dimension: offered.max_compute_workgroups_per_dimension,
        ..wgpu::Limits::downlevel_defaults()
    };
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("aureole"),
        required_features: wgpu::Features::empty(),
        required_limits: limits.clone(),
        experimental_features: wgpu::ExperimentalFeatures::disabled(),
        memory_hints: wgpu::MemoryHints::Performance,
        trace: wgpu::Trace::Off,
    }))
    .map_err(|error| format!("{} would not open ({error})", info.name))?;
    let lost = Arc::new(Mutex::new(None));
    let heard = Arc::clone(&lost);
    device.on_uncaptured_error(Arc::new(move |error: wgpu::Error| {
        heard
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .get_or_insert_with(|| error.to_string());
    }));
    let compile = |label: &str, source: &str| {
        device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(
                format!("{}\n{source}", include_str!("common.wgsl")).into(),
            ),
        })
    };
    let pipeline = |module: &wgpu::ShaderModule, entry: &str, constants: &[(&str, f64)]| {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: None,
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                zero_initialize_workgroup_memory: false,
            },
            cache: None,
        })
    };
    let fft = compile("fft", include_str!("fft.wgsl"));
    let grid = compile("grid", include_str!("grid.wgsl"));
    let multiply = compile("multiply", include_str!("multiply.wgsl"));
    let finish = compile("finish", include_str!("finish.wgsl"));
    let scatter = compile("scatter", include_str!("scatter.wgsl"));
    let radix = RADICES
        .iter()
        .map(|&r| pipeline(&fft, "stockham", &[("RADIX", f64::from(r))]))
        .collect();
    let gpu = Gpu {
        max_buffer: limits
            .max_buffer_size
            .min(limits.max_storage_buffer_binding_size),
        radix,
        load: pipeline(&grid, "load", &[]),
        place: pipeline(&grid, "place", &[]),
        multiply: pipeline(&multiply, "multiply", &[]),
        finish: pipeline(&finish, "finish", &[]),
        scatter: pipeline(&scatter, "scatter", &[]),
        device,
        queue,
        info,
        lost,
    };
    match gpu.failure() {
        Some(error) => Err(format!("{} cannot run the engine ({error})", gpu.name())),
        None => Ok(gpu),
    }
}
