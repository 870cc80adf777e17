//! The session every front end calls (the command line, the studio, the
//! Python package): it takes an image with its metadata and the options a
//! user gives, and decides everything else the same way for all of them,
//! so that every front end gives the same bytes.

use super::cost::Estimate;
use super::ghosts::{self, DisplayWindow, GhostSummary, KeptRays};
use super::options::{Applied, ApplyOptions, Arithmetic, Method};
use super::plan::{DoubleRefused, Plan};
use super::threshold::Threshold;
use crate::config::Config;
use crate::control::{Cancel, Control};
use crate::convolve::{padded_size, Backend, Device};
use crate::error::{Error, Result};
use crate::image::{Image, PixelLuminance, Shape};
use crate::kernel::Kernel;
use crate::memory::Workload;
use crate::optics::Effect;

use crate::memory::GPU_DRIVERS;

/// How to take an image as luminance.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FrameOptions {
    /// cd/m² per file unit; by default the image's `whiteLuminance`, else 1.
    pub input_scale: Option<f64>,
    /// Replace NaN, infinite and negative samples by 0 instead of refusing
    /// the image (NaN, infinite) or passing them through (negative).
    pub sanitize: bool,
}

/// Where a frame's luminance scale came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScaleSource {
    /// The caller gave it.
    Given,
    /// The image's `whiteLuminance`.
    WhiteLuminance,
    /// Neither: file units are cd/m².
    Default,
}

/// An image ready for the camera: its samples checked, its scale chosen.
#[derive(Debug, Clone)]
pub struct Frame {
    image: Image,
    scale: f64,
    scale_source: ScaleSource,
    replaced: usize,
    negatives: usize,
    window: Option<DisplayWindow>,
}

impl Frame {
    /// Takes `image` as luminance: NaN and infinite samples are refused,
    /// negative ones (a camera's or a colour transform's small negatives)
    /// pass through as a compositor passes them (they never pass the
    /// threshold, so they stay where they are); with `sanitize` all of them
    /// become 0. The scale is the one given, else the image's
    /// `whiteLuminance`, else 1.
    pub fn new(mut image: Image, options: &FrameOptions) -> Result<Frame> {
        let (replaced, negatives) = if options.sanitize {
            (image.sanitize(), 0)
        } else {
            if let Some(found) = image.non_finite() {
                return Err(Error::BadSamples {
                    count: found.count,
                    first: found.first,
                });
            }
            (0, image.negatives().map_or(0, |found| found.count))
        };
        let (scale, scale_source) = match (options.input_scale, image.white_luminance) {
            (Some(scale), _) => (scale, ScaleSource::Given),
            (None, Some(white)) => (f64::from(white), ScaleSource::WhiteLuminance),
            (None, None) => (1.0, ScaleSource::Default),
        };
        if !(scale.is_finite() && scale > 0.0) {
            return Err(Error::Parameter {
                effect: "input".into(),
                name: "scale",
                value: scale.to_string(),
                allowed: "cd/m² per file unit, a finite number above 0",
            });
        }
        Ok(Frame {
            image,
            scale,
            scale_source,
            replaced,
            negatives,
            window: None,
        })
    }

    /// The frame, its display window `window` (an EXR's, when its data
    /// window holds overscan): the optical axis is the display window's
    /// centre, and the sensor as wide as it.
    pub fn with_display_window(mut self, window: DisplayWindow) -> Frame {
        self.window = Some(window);
        self
    }

    /// The display window: the whole frame unless one was given.
    pub fn display_window(&self) -> DisplayWindow {
        self.window
            .unwrap_or_else(|| DisplayWindow::whole(self.image.width, self.image.height))
    }

    /// This frame's scale and window around another image (the scene with
    /// its ghosts).
    fn around(&self, image: Image) -> Frame {
        Frame {
            image,
            scale: self.scale,
            scale_source: self.scale_source,
            replaced: self.replaced,
            negatives: self.negatives,
            window: self.window,
        }
    }

    /// The image, in its file's units.
    pub fn image(&self) -> &Image {
        &self.image
    }

    /// The image back, to use otherwise.
    pub fn into_image(self) -> Image {
        self.image
    }

    /// The image taken out, an empty one of its layout left in its place
    /// with the frame's scale: its planes for another frame's once the
    /// camera is done with them.
    pub fn take_image(&mut self) -> Image {
        let empty = Image::filled(0, 0, self.image.layout, 0.0);
        std::mem::replace(&mut self.image, empty)
    }

    /// cd/m² per file unit.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Where the scale came from.
    pub fn scale_source(&self) -> ScaleSource {
        self.scale_source
    }

    /// How many samples `sanitize` replaced by 0.
    pub fn replaced(&self) -> usize {
        self.replaced
    }

    /// How many negative samples passed through (none with `sanitize`).
    pub fn negatives(&self) -> usize {
        self.negatives
    }
}

/// What an application would cost each way, seconds on two cores.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Costs {
    /// Splatting the kernel at every bright pixel.
    pub splat: f64,
    /// The FFT route (f32; a scene with lamps or beyond f32 costs more).
    pub fft: f64,
    /// The pixels above the threshold.
    pub spread_pixels: usize,
}

/// The stage of a run that progress is reported for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Stage {
    /// Building the kernel and its spectrum (once per image size).
    BuildingKernel,
    /// Spreading the light of an image.
    Convolving,
    /// Tracing the lens ghosts of an image's bright sources.
    TracingGhosts,
}

impl Stage {
    /// The stage in words, for a progress bar.
    pub fn describe(self) -> &'static str {
        match self {
            Stage::BuildingKernel => "building kernel",
            Stage::Convolving => "convolving",
            Stage::TracingGhosts => "tracing ghosts",
        }
    }
}

/// What a session applies: a configuration whose kernel it builds for each
/// image size, or a kernel built before.
#[derive(Debug)]
enum Lens {
    Config(Box<Config>),
    /// `None` while the plan holds it.
    Kernel(Option<Kernel>),
}

/// Applies one camera to a sequence of frames: the plan (kernel and
/// spectrum) is built once per image size, the memory a run needs is
/// checked against a limit before anything large is allocated, and the
/// previous frame's planes are reused.
///
/// ```
/// use aureole::{presets, ApplyOptions, Config, Frame, FrameOptions, Image, Layout, Session};
///
/// let mut config = Config::default();
/// config.merge(presets::find("paper-fig5-both")?.config()?);
/// let mut session = Session::new(config).with_memory_limit(1 << 30);
/// for frame in 0..3 {
///     // A lamp of 5·10⁴ cd/m² moving along a dim street.
///     let mut image = Image::filled(96, 54, Layout::Rgb, 0.05);
///     for plane in &mut image.planes {
///         plane[27 * 96 + 30 + 10 * frame] = 5e4;
///     }
///     let frame = Frame::new(image, &FrameOptions::default())?;
///     let applied = session.apply(&frame, &ApplyOptions::default(), &mut |stage, done| {
///         eprintln!("{} {:.0} %", stage.describe(), done * 100.0);
///     })?;
///     assert!(applied.energy_out <= applied.energy_in * (1.0 + 1e-6));
///     // … write applied.image, then hand its planes back for the next frame.
///     session.recycle(applied.image);
/// }
/// # Ok::<(), aureole::Error>(())
/// ```
#[derive(Debug)]
pub struct Session {
    lens: Lens,
    memory_limit: Option<u64>,
    max_extent: Option<(usize, usize)>,
    device: Device,
    cancel: Cancel,
    plan: Option<Plan>,
    recycled: Vec<Vec<f32>>,
    /// Frames a front end holds beside the one applied (read ahead, being
    /// written), counted in the memory estimate.
    in_flight: usize,
    /// The sessions of the chain's first effects, which glare layers
    /// apply, kept for the next frame where memory allows.
    pub(super) layer_chain: Vec<Session>,
}

impl Session {
    /// A session that builds the kernel of `config`.
    pub fn new(config: Config) -> Session {
        Session::of(Lens::Config(Box::new(config)))
    }

    /// A session that applies `kernel`, built before.
    pub fn with_kernel(kernel: Kernel) -> Session {
        Session::of(Lens::Kernel(Some(kernel)))
    }

    fn of(lens: Lens) -> Session {
        Session {
            lens,
            memory_limit: None,
            max_extent: None,
            device: Device::Cpu,
            cancel: Cancel::new(),
            plan: None,
            recycled: Vec::new(),
            in_flight: 0,
            layer_chain: Vec::new(),
        }
    }

    /// Refuses a frame whose run would need more than `bytes`.
    pub fn with_memory_limit(mut self, bytes: u64) -> Session {
        self.memory_limit = Some(bytes);
        self
    }

    /// Counts `frames` more frames of each size in the memory estimate: a
    /// front end that reads the next frame and writes the last while one is
    /// applied holds two, each an input or a result.
    pub fn with_frames_in_flight(mut self, frames: usize) -> Session {
        self.in_flight = frames;
        self
    }

    /// Caps the kernel's extent (width, height); by default light from any
    /// pixel reaches the whole frame, (2W − 1)×(2H − 1). No effect on a
    /// kernel built before.
    pub fn with_max_extent(mut self, max_extent: Option<(usize, usize)>) -> Session {
        self.max_extent = max_extent;
        self
    }

    /// Where the convolutions run (the CPU unless asked): a plan built
    /// after this call uses it.
    pub fn with_device(mut self, device: Device) -> Session {
        self.device = device;
        self
    }

    /// Where the convolutions run.
    pub fn device(&self) -> Device {
        self.device
    }

    /// The flag that stops this session's work: raise it from any thread
    /// and the running call returns [`Error::Cancelled`].
    pub fn cancel_token(&self) -> Cancel {
        self.cancel.clone()
    }

    /// Replaces the flag with `cancel`: for a front end that cancels each
    /// request on its own (a server whose clients come and go) and goes on
    /// with the session after one was cancelled.
    pub fn set_cancel_token(&mut self, cancel: Cancel) {
        self.cancel = cancel;
    }

    /// The configuration, when the session builds its kernel.
    pub fn config(&self) -> Option<&Config> {
        match &self.lens {
            Lens::Config(config) => Some(config),
            Lens::Kernel(_) => None,
        }
    }

    /// The plan of the last frame's size, if one is built.
    pub fn plan(&self) -> Option<&Plan> {
        self.plan.as_ref()
    }

    /// What applying `options` to `frame` would cost each way, in seconds
    /// on two cores (the cost model of docs/physics.md §8), known before
    /// anything is built: for a front end to say so before a long run.
    pub fn costs(&self, frame: &Frame, options: &ApplyOptions) -> Result<Costs> {
        options.check()?;
        let image = frame.image();
        let size = (image.width, image.height);
        let (workload, _) = self.workload(Shape::of(image))?;
        let (kernel, kernel_planes) = (workload.kernel, workload.kernel_planes);
        let default = self.config().map_or(0.0, |config| config.threshold);
        let threshold = Threshold {
            level: options.threshold.unwrap_or(default) / frame.scale(),
            knee: options.knee,
        };
        let luminance = PixelLuminance::of(image);
        let survey = threshold.survey(&luminance, size, kernel, (kernel.0 / 2, kernel.1 / 2));
        let padded = padded_size(kernel.0, kernel.1, size.0, size.1);
        let estimate = Estimate::of(
            &survey,
            (size, image.layout),
            (kernel, kernel_planes),
            padded,
        );
        Ok(Costs {
            splat: 1e-9 * estimate.splat,
            fft: 1e-9 * estimate.fft,
            spread_pixels: survey.spread,
        })
    }

    /// Applies the camera to `frame`; `progress` hears the stage and the
    /// fraction of it done. The plan of the previous frame is reused when
    /// the size is the same; else a new one is built, once its memory is
    /// known to fit the limit.
    pub fn apply(
        &mut self,
        frame: &Frame,
        options: &ApplyOptions,
        progress: &mut dyn FnMut(Stage, f64),
    ) -> Result<Applied> {
        options.check()?;
        self.cancel.check()?;
        let ghosted = self.trace_ghosts(frame, progress)?;
        self.apply_after_ghosts(frame, ghosted, options, progress)
    }

    /// The scene of `frame` with its lens ghosts, when the config traces
    /// them: the frame the kernel's chain spreads. [`Session::apply`] is
    /// this, then [`Session::apply_after_ghosts`]; a front end that keeps
    /// a frame's ghosts while the rest of the camera changes (the studio)
    /// calls the two apart.
    pub fn trace_ghosts(
        &self,
        frame: &Frame,
        progress: &mut dyn FnMut(Stage, f64),
    ) -> Result<Option<(Frame, GhostSummary)>> {
        self.trace_ghosts_keeping(frame, &mut KeptRays::new(0), progress)
    }

    /// [`Session::trace_ghosts`], drawing each source's ghosts from the
    /// rays `kept` holds for it where they are its rays through this lens
    /// at this f-number (another stop's blades, rotation or roundness:
    /// the same bytes as traced), and keeping this frame's in it: a front
    /// end that changes the stop while the frame stays (the studio).
    pub fn trace_ghosts_keeping(
        &self,
        frame: &Frame,
        kept: &mut KeptRays,
        progress: &mut dyn FnMut(Stage, f64),
    ) -> Result<Option<(Frame, GhostSummary)>> {
        let Some(config) = self.config() else {
            return Ok(None);
        };
        let Some(traced) = &config.ghosts else {
            return Ok(None);
        };
        let window = frame.display_window();
        let optics = traced.optics(&config.camera, config.first_aperture(), window.width)?;
        let mut report = |f| progress(Stage::TracingGhosts, f);
        let mut control = Control::new(&self.cancel, &mut report);
        let (scene, summary) = ghosts::add_ghosts(
            frame.image(),
            (frame.scale(), window),
            (traced, &optics),
            kept,
            &mut control,
        )?;
        Ok(Some((frame.around(scene), summary)))
    }

    /// Applies the kernel's chain to the scene `ghosted` holds (else to
    /// `frame`'s); the light in and the glare are counted from `frame`.
    pub fn apply_after_ghosts(
        &mut self,
        frame: &Frame,
        ghosted: Option<(Frame, GhostSummary)>,
        options: &ApplyOptions,
        progress: &mut dyn FnMut(Stage, f64),
    ) -> Result<Applied> {
        let Some((scene, summary)) = ghosted else {
            return self.spread(frame, options, progress);
        };
        let whole = ApplyOptions {
            glare_only: false,
            ..*options
        };
        let mut applied = if self.config().is_some_and(|c| c.effects.is_empty()) {
            Applied::unspread(
                scene.into_image(),
                options.threshold.unwrap_or(self.threshold()),
            )
        } else {
            self.spread(&scene, &whole, progress)?
        };
        let input = frame.image();
        applied.energy_in = input.total_luminance();
        if options.glare_only {
            super::options::subtract_input(&mut applied.image.planes, &input.planes);
        }
        applied.ghosts = Some(summary);
        Ok(applied)
    }

    /// The configuration's threshold, cd/m² (0 for a kernel given).
    fn threshold(&self) -> f64 {
        self.config().map_or(0.0, |c| c.threshold)
    }

    /// `frame` spread by the kernel's chain, its plan built for the frame's
    /// size when the last was for another.
    fn spread(
        &mut self,
        frame: &Frame,
        options: &ApplyOptions,
        progress: &mut dyn FnMut(Stage, f64),
    ) -> Result<Applied> {
        let image = frame.image();
        if let Some(view) = self.sphere(image)? {
            return self.spread_on_sphere(frame, options, &view, progress);
        }
        let plan = self.plan_for(image, progress)?;
        let plan = self.plan.insert(plan);
        let mut report = |f| progress(Stage::Convolving, f);
        let mut control = Control::new(&self.cancel, &mut report);
        let recycled = std::mem::take(&mut self.recycled);
        plan.apply_with(image, frame.scale(), options, recycled, &mut control)
    }

    /// Builds the kernel and its plan for `frame`'s size now, when the
    /// last was for another or none was built: a front end may build it
    /// beside other work on the frame (its ghosts). Nothing is built for
    /// a view over the sphere, which has no one kernel.
    pub fn prepare(&mut self, frame: &Frame) -> Result<()> {
        let image = frame.image();
        if self.sphere(image)?.is_none() {
            let plan = self.plan_for(image, &mut |_, _| {})?;
            self.plan = Some(plan);
        }
        Ok(())
    }

    /// The view over the sphere of directions the camera gives `image`'s
    /// pixels, where its projection is given: no one kernel in pixels
    /// holds there.
    fn sphere(&self, image: &Image) -> Result<Option<crate::view::View>> {
        match self.config() {
            Some(config) => config.camera.view(image.width, image.height),
            None => Ok(None),
        }
    }

    /// The plan for `image`'s size, taken out: the one held, or one built
    /// when that is for another size or none is held.
    fn plan_for(&mut self, image: &Image, progress: &mut dyn FnMut(Stage, f64)) -> Result<Plan> {
        let size = (image.width, image.height);
        if self.plan.as_ref().is_some_and(|p| p.size() != size) {
            self.release_plan();
        }
        match self.plan.take() {
            Some(plan) => Ok(plan),
            None => self.build_plan(image, progress),
        }
    }

    /// `frame` through the eye over the sphere of directions `view` gives
    /// its pixels ([`super::sphere`]): a wide view, where no one kernel
    /// in pixels holds. The chain must be the eye alone.
    fn spread_on_sphere(
        &mut self,
        frame: &Frame,
        options: &ApplyOptions,
        view: &crate::view::View,
        progress: &mut dyn FnMut(Stage, f64),
    ) -> Result<Applied> {
        let config = self.config().ok_or(Error::NoEffect)?;
        let eye = match config.effects.as_slice() {
            [Effect::Eye(eye)] => eye.clone(),
            [] => return Err(Error::NoEffect),
            _ => {
                return Err(Error::View {
                    view: view.to_string(),
                    message: "a wide view ([camera] projection) spreads the eye alone (one [[effect]] type = \"eye\"); the other effects are a lens's, whose kernels are in pixels of a perspective sensor: remove them, or the projection".into(),
                })
            }
        };
        let threshold = options.threshold.unwrap_or(config.threshold);
        progress(Stage::Convolving, 0.0);
        let spread = super::sphere::spread_eye(
            frame.image(),
            frame.scale(),
            view,
            &eye,
            threshold,
            options.knee,
            &self.cancel,
        )?;
        progress(Stage::Convolving, 1.0);
        let input = frame.image();
        let mut image = spread.image;
        if options.glare_only {
            super::options::subtract_input(&mut image.planes, &input.planes);
        }
        // The pixels of a wide view cover unequal solid angles: the light
        // kept is the flux's (Σ Y·ω), reported on the input's Σ Y.
        let energy_in = input.total_luminance();
        let kept = if spread.energy_in > 0.0 {
            spread.energy_out / spread.energy_in
        } else {
            1.0
        };
        Ok(Applied {
            image,
            energy_in,
            energy_out: energy_in * kept,
            spread_pixels: spread.spread_pixels,
            threshold,
            method: Method::Splat,
            arithmetic: Arithmetic::Single,
            device: "the CPU, over the sphere of a wide view".to_string(),
            ghosts: None,
        })
    }

    /// A session for the chain's first `effects` effects, with this one's
    /// limits and cancellation, counting `held` more frames beside it.
    pub(super) fn prefix(&self, effects: usize, held: usize) -> Result<Session> {
        let Lens::Config(config) = &self.lens else {
            return Err(Error::NoEffect);
        };
        // The chain's layers spread the scene with its ghosts, traced once.
        let mut prefix = Session::new(Config {
            effects: config.effects[..effects.min(config.effects.len())].to_vec(),
            ghosts: None,
            ..Config::clone(config)
        })
        .with_max_extent(self.max_extent)
        .with_device(self.device)
        .with_frames_in_flight(self.in_flight + held);
        prefix.memory_limit = self.memory_limit;
        prefix.cancel = self.cancel.clone();
        Ok(prefix)
    }

    /// Whether the plans of every chain glare layers apply on frames of
    /// `shape` fit the memory limit together
    /// ([`Workload::estimate_layers`]).
    pub(super) fn holds_layer_chains(&self, shape: Shape) -> bool {
        let Some(limit) = self.memory_limit else {
            return true;
        };
        self.workload(shape)
            .is_ok_and(|(workload, effects)| workload.estimate_layers(effects) <= limit)
    }

    /// Refuses, before a file is decoded, a frame of `shape` whose run
    /// would need more than the memory limit, or whose kernel could not be
    /// built: what [`Session::apply`] would refuse, known from a file's
    /// header.
    pub fn check_shape(&self, shape: Shape) -> Result<()> {
        match &self.plan {
            Some(plan) if plan.size() == (shape.width, shape.height) => Ok(()),
            _ => {
                self.workload(shape)?;
                self.check_memory(shape).map(drop)
            }
        }
    }

    /// The plan for `image`'s size, once its memory is known to fit the
    /// limit; a kernel given is kept when the plan cannot be made.
    fn build_plan(&mut self, image: &Image, progress: &mut dyn FnMut(Stage, f64)) -> Result<Plan> {
        let double = self.check_memory(Shape::of(image))?;
        let (width, height) = (image.width, image.height);
        let mut report = |f| progress(Stage::BuildingKernel, f);
        let mut control = Control::new(&self.cancel, &mut report);
        let plan = match &mut self.lens {
            Lens::Config(config) => Plan::build(
                config,
                (width, height),
                self.max_extent,
                self.device,
                &mut control,
            ),
            Lens::Kernel(slot) => {
                let Some(kernel) = slot.take() else {
                    return Err(Error::NoEffect);
                };
                Plan::transform(kernel, (width, height), self.device, &mut control).map_err(
                    |failed| {
                        let (kernel, error) = *failed;
                        *slot = Some(kernel);
                        error
                    },
                )
            }
        }?;
        Ok(match double {
            Some(refusal) => plan.refusing_double(refusal),
            None => plan,
        })
    }

    /// Hands back a result that is no longer needed (written out), so that
    /// the next frame writes into its memory.
    pub fn recycle(&mut self, image: Image) {
        self.recycle_planes(image.planes);
    }

    /// [`Session::recycle`], given the planes alone.
    pub fn recycle_planes(&mut self, planes: Vec<Vec<f32>>) {
        self.recycled = planes;
    }

    /// Drops the plan of another size, keeping a kernel built before.
    fn release_plan(&mut self) {
        self.recycled = Vec::new();
        if let Some(plan) = self.plan.take() {
            if let Lens::Kernel(slot) = &mut self.lens {
                *slot = Some(plan.into_kernel());
            }
        }
    }

    /// What a run on `image` works on, and the effects it builds (none for
    /// a kernel given ready-made, held by the session or its plan).
    fn workload(&self, image: Shape) -> Result<(Workload, &[Effect])> {
        let (planes, alpha) = (image.planes, image.alpha);
        match &self.lens {
            Lens::Config(config) => {
                let workload = Workload::of_config(
                    config,
                    image.width,
                    image.height,
                    planes,
                    alpha,
                    self.max_extent,
                )?;
                Ok((workload, &config.effects))
            }
            Lens::Kernel(kernel) => {
                let plan = self.plan.as_ref().map(Plan::kernel);
                let kernel = kernel.as_ref().or(plan).ok_or(Error::NoEffect)?;
                let workload = Workload {
                    width: image.width,
                    height: image.height,
                    planes,
                    alpha,
                    kernel: (kernel.width(), kernel.height()),
                    kernel_planes: kernel.planes().len(),
                    backend: Backend::default(),
                    reaches: [u32::MAX; crate::memory::REACHES],
                    fixed: 0,
                };
                Ok((workload, &[]))
            }
        }
    }

    /// Refuses a frame whose run would need more than the memory limit,
    /// with the estimate and the largest kernel that would fit; else says
    /// whether the f64 engine, which a scene's range may need, would not.
    fn check_memory(&self, image: Shape) -> Result<Option<DoubleRefused>> {
        let Some(limit) = self.memory_limit else {
            return Ok(None);
        };
        let (workload, effects) = self.workload(image)?;
        // A kernel built here may be capped from the largest asked for.
        let start = match &self.lens {
            Lens::Config(_) => self.max_extent.unwrap_or(workload.kernel),
            Lens::Kernel(_) => workload.kernel,
        };
        let mut needed = workload.estimate(effects);
        let planes = workload.planes + usize::from(workload.alpha);
        let frame = (image.width * image.height * planes * 4) as u64;
        let in_flight = self.in_flight as u64 * frame;
        let drivers = if self.device == Device::Cpu {
            0
        } else {
            GPU_DRIVERS
        };
        // Ghosts hold the scene they are added to (f32) and their canvas:
        // an f64 plane per channel, its coarser levels a third more.
        let ghosts = if self.config().is_some_and(|c| c.ghosts.is_some()) {
            (image.width * image.height * planes) as u64 * (4 + 8 * 4 / 3)
        } else {
            0
        };
        needed.bytes += in_flight + drivers + ghosts;
        // What is left for the run once the frames in flight and the
        // drivers are held.
        let limit_left = limit.saturating_sub(in_flight + drivers);
        if needed.bytes <= limit {
            let double = needed.bytes + workload.double_extra();
            return Ok((double > limit).then_some(DoubleRefused {
                needed: double,
                limit,
                fits: workload.largest_fitting(
                    effects,
                    start,
                    limit_left.saturating_sub(workload.double_extra()),
                ),
                built: !effects.is_empty(),
            }));
        }
        Err(Error::Memory {
            needed: needed.bytes,
            stage: needed.stage,
            limit,
            fits: workload.largest_fitting(effects, start, limit_left),
            built: !effects.is_empty(),
        })
    }
}
