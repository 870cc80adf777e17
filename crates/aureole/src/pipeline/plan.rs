//! A [`Plan`]: the kernel of an optical chain for one image size, with its
//! spectrum, applied to any number of images (docs/physics.md §7–8).

use std::sync::{Mutex, OnceLock, PoisonError};

use super::cost::{self, Estimate};
use super::options::{subtract_input, Applied, ApplyOptions, Arithmetic, Method};
use super::precision;
use super::precision::{Route, Scene};
use super::splat::{copies, splat};
use super::threshold::{Survey, Threshold};
use crate::config::Config;
use crate::control::{Cancel, Control};
use crate::convolve::{
    choose, engine, Backend, Centre, Composing, Device, Engine, Precision, Spread, Term,
};
use crate::error::{Error, Fit, Result};
use crate::image::{Image, Layout, PixelLuminance};
use crate::kernel::{Extent, Kernel};

/// How a scene is spread by FFT: the fraction of each pixel spread (none
/// when every pixel is spread whole), the arithmetic, and where the
/// spread's progress starts.
struct Fft<'a> {
    fractions: Option<&'a [f32]>,
    route: &'a Route,
    spread_from: f64,
}

/// Why a plan does not build its f64 engine: it would need more memory
/// than the limit (a session's estimate).
#[derive(Debug, Clone, Copy)]
pub(crate) struct DoubleRefused {
    pub needed: u64,
    pub limit: u64,
    /// The largest kernel with which it would fit.
    pub fits: Option<Fit>,
    /// Whether the kernel is built here rather than given.
    pub built: bool,
}

impl DoubleRefused {
    fn error(self) -> Error {
        Error::Memory {
            needed: self.needed,
            stage: "convolving in f64 (the scene's range is beyond f32)",
            limit: self.limit,
            fits: self.fits,
            built: self.built,
        }
    }
}

/// The kernel of an optical chain for one image size, with its spectrum.
pub struct Plan {
    width: usize,
    height: usize,
    kernel: Kernel,
    /// The configuration's threshold, cd/m², for callers that give none.
    threshold: f64,
    /// Where its f32 engine computes, in words.
    device: String,
    /// The engine every scene starts in (f32), the kernel's centre weight
    /// applied exactly.
    engine: Box<dyn Engine>,
    /// The exact engine (f64), built the first time a scene's range needs
    /// it.
    exact: OnceLock<Box<dyn Engine>>,
    /// Where the kernel can be split for lamps, and the light beyond
    /// ([`precision::split_radii`]), found the first time a scene has
    /// lamps.
    near: OnceLock<Vec<(usize, f64)>>,
    /// Held by an application with lamps while it uses the engine's split.
    split: Mutex<()>,
    /// Set when the f64 engine would not fit the memory limit.
    double_refused: Option<DoubleRefused>,
}

impl Plan {
    /// Builds the kernel of `config` for `width`×`height` images, by default
    /// large enough that light from any pixel reaches every other
    /// ((2W − 1)×(2H − 1)), or at most `max_extent`, and plans its
    /// transforms, which the first application makes: whole, or split for
    /// a scene with lamps.
    pub fn for_image(
        config: &Config,
        width: usize,
        height: usize,
        max_extent: Option<(usize, usize)>,
    ) -> Result<Plan> {
        Plan::build(
            config,
            (width, height),
            max_extent,
            Device::Cpu,
            &mut Control::quiet(&Cancel::new()),
        )
    }

    /// [`Plan::for_image`], reporting to `control` and stopping when it is
    /// cancelled.
    pub(crate) fn build(
        config: &Config,
        (width, height): (usize, usize),
        max_extent: Option<(usize, usize)>,
        device: Device,
        control: &mut Control,
    ) -> Result<Plan> {
        let extent = Extent::for_image_within(width, height, max_extent)?;
        let kernel = config.kernel_on(
            &extent,
            &mut Composing::on(device)?,
            &mut control.part(0.0, 0.9),
        )?;
        let mut plan =
            Plan::transform(kernel, (width, height), device, &mut control.part(0.9, 1.0))
                .map_err(|failed| failed.1)?;
        plan.threshold = config.threshold;
        Ok(plan)
    }

    /// A plan for `width`×`height` images with a kernel built before (e.g.
    /// by `aureole psf`, read back from a file): kernels are cacheable. Its
    /// threshold is 0 unless the options give one.
    pub fn with_kernel(kernel: Kernel, width: usize, height: usize) -> Result<Plan> {
        Plan::with_kernel_on(kernel, (width, height), Device::Cpu)
    }

    /// [`Plan::with_kernel`] convolving on `device`: [`Device::Auto`] takes
    /// a hardware GPU where there is one, and the CPU where there is none
    /// or the GPU cannot hold the plan; [`Device::Gpu`] refuses instead.
    pub fn with_kernel_on(
        kernel: Kernel,
        (width, height): (usize, usize),
        device: Device,
    ) -> Result<Plan> {
        Plan::transform(
            kernel,
            (width, height),
            device,
            &mut Control::quiet(&Cancel::new()),
        )
        .map_err(|failed| failed.1)
    }

    /// [`Plan::with_kernel`], reporting to `control` and stopping when it
    /// is cancelled, and handing the kernel back when it fails, for a
    /// caller that keeps it for the next try.
    pub(crate) fn transform(
        kernel: Kernel,
        (width, height): (usize, usize),
        device: Device,
        control: &mut Control,
    ) -> std::result::Result<Plan, Box<(Kernel, Error)>> {
        let (backend, mut words) = match choose(device) {
            Ok(chosen) => chosen,
            Err(error) => return Err(Box::new((kernel, error))),
        };
        let mut build = |backend| {
            engine(
                (backend, Precision::Single),
                &kernel_planes(&kernel),
                (kernel.width(), kernel.height()),
                (width, height),
                Centre::Leave,
                control,
            )
        };
        let mut built = build(backend);
        // A GPU chosen by itself that cannot hold the plan (its memory, its
        // largest buffer) leaves the work to the CPU, and says so.
        if let (Err(Error::Gpu(why)), Device::Auto) = (&built, device) {
            words = format!("the CPU: {words} could not hold it ({why})");
            built = build(Backend::Cpu);
        }
        match built {
            Ok(engine) => Ok(Plan {
                width,
                height,
                kernel,
                threshold: 0.0,
                device: words,
                engine,
                exact: OnceLock::new(),
                near: OnceLock::new(),
                split: Mutex::new(()),
                double_refused: None,
            }),
            Err(error) => Err(Box::new((kernel, error))),
        }
    }

    /// The image size the plan is for, width × height.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The kernel in use.
    pub fn kernel(&self) -> &Kernel {
        &self.kernel
    }

    /// The kernel back, the spectra dropped.
    pub fn into_kernel(self) -> Kernel {
        self.kernel
    }

    /// Where its f32 convolutions run, in words: the GPU's name, or the
    /// CPU and why.
    pub fn device(&self) -> &str {
        &self.device
    }

    /// The threshold applied when the options give none, cd/m².
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// Applies the camera to `image` (which must have the plan's size and
    /// holds `scale` cd/m² per unit); `progress` hears the fraction done, 0
    /// to 1.
    pub fn apply(
        &self,
        image: &Image,
        scale: f64,
        options: &ApplyOptions,
        progress: &mut dyn FnMut(f64),
    ) -> Result<Applied> {
        let cancel = Cancel::new();
        self.apply_with(
            image,
            scale,
            options,
            Vec::new(),
            &mut Control::new(&cancel, progress),
        )
    }

    /// [`Plan::apply`], writing into `recycled`, the planes of a result
    /// that is no longer needed (e.g. the previous frame's): in a frame
    /// sequence this saves mapping fresh memory for every frame. `control`
    /// hears the progress and may cancel.
    pub fn apply_with(
        &self,
        image: &Image,
        scale: f64,
        options: &ApplyOptions,
        recycled: Vec<Vec<f32>>,
        control: &mut Control,
    ) -> Result<Applied> {
        options.check()?;
        if (image.width, image.height) != (self.width, self.height) {
            return Err(Error::SizeMismatch {
                expected: (self.width, self.height),
                found: (image.width, image.height),
            });
        }
        let threshold_cd = options.threshold.unwrap_or(self.threshold);
        let threshold = Threshold {
            level: threshold_cd / scale,
            knee: options.knee,
        };
        let luminance = PixelLuminance::of(image);
        let size = (image.width, image.height);
        let kernel_size = (self.kernel.width(), self.kernel.height());
        let survey = threshold.survey(&luminance, size, kernel_size, self.kernel.centre());
        let energy_in = image.total_luminance();
        let estimate = Estimate::of(
            &survey,
            (size, image.layout),
            (kernel_size, self.engine.kernel_planes()),
            self.engine.padded_size(),
        );
        let method = estimate.choose(options.method);
        let route = if survey.spread > 0 && method == Method::Fft {
            self.route(&luminance, &threshold, &survey, &estimate)
        } else {
            Route::Single
        };
        // The engine keeps one split of the kernel: an application with
        // lamps holds it from choosing the split to the end of the spread,
        // so that a concurrent one with another radius cannot swap it.
        let _holding_split = matches!(route, Route::Lamps { .. })
            .then(|| self.split.lock().unwrap_or_else(PoisonError::into_inner));
        let (route, spread_from) = if method == Method::Fft && survey.spread > 0 {
            self.ready(route, control)?
        } else {
            (route, 0.0)
        };
        let mut output = image.clone_without_planes();
        output.planes = if survey.spread == 0 {
            copies(&image.planes, recycled)
        } else if method == Method::Splat {
            let terms = self.terms(image);
            splat(
                image,
                &luminance,
                threshold,
                &self.kernel,
                &terms,
                recycled,
                control,
            )?
        } else {
            let fractions = (survey.full != image.width * image.height)
                .then(|| threshold.fractions(&luminance, image.width * image.height));
            let fft = Fft {
                fractions: fractions.as_deref(),
                route: &route,
                spread_from,
            };
            self.convolve(image, fft, recycled, control)?
        };
        control.report(1.0);
        let energy_out = output.total_luminance();
        if options.glare_only {
            subtract_input(&mut output.planes, &image.planes);
        }
        Ok(Applied {
            image: output,
            energy_in,
            energy_out,
            spread_pixels: survey.spread,
            threshold: threshold_cd,
            method,
            device: if route == Route::Double || method == Method::Splat {
                "the CPU".to_string()
            } else {
                self.device.clone()
            },
            arithmetic: match route {
                Route::Single => Arithmetic::Single,
                Route::Lamps { lamps, .. } => Arithmetic::Lamps(lamps.len()),
                Route::Double => Arithmetic::Double,
            },
            ghosts: None,
        })
    }

    /// The arithmetic a scene spread by FFT needs (docs/physics.md §8): f32,
    /// f32 with its lamps' near light added apart, or f64.
    fn route(
        &self,
        luminance: &PixelLuminance,
        threshold: &Threshold,
        survey: &Survey,
        estimate: &Estimate,
    ) -> Route {
        let moved = 1.0
            - f64::from(
                self.kernel
                    .centre_weights()
                    .into_iter()
                    .fold(1.0f32, f32::min),
            );
        let padded = self.engine.padded_size();
        let scene = Scene {
            luminance,
            threshold,
            pixels: self.width * self.height,
            squares: survey.squares,
            moved,
            padded,
        };
        // Lamps may cost two more FFTs: the route stays below the f64
        // engine's cost, about four.
        let budget = 2.0 * estimate.fft;
        precision::route(
            &scene,
            || {
                self.near
                    .get_or_init(|| precision::split_radii(&self.kernel))
                    .clone()
            },
            |radius| cost::lamps_within(budget, radius, estimate.convolutions),
        )
    }

    /// The f32 engine's kernel spectra made for `route`, when not yet made:
    /// whole, or split for lamps (a split that would not fit sends the
    /// scene to f64). Returns the route taken and where the spread's
    /// progress starts: making the spectra (the first frame) takes about
    /// as long as the spread, half of the progress.
    fn ready(&self, route: Route, control: &mut Control) -> Result<(Route, f64)> {
        let planes = kernel_planes(&self.kernel);
        match route {
            Route::Lamps { radius, lamps } => {
                let spread_from = if self.engine.has_split(radius) {
                    0.0
                } else {
                    0.5
                };
                let split =
                    self.engine
                        .split_near(&planes, radius, &mut control.part(0.0, spread_from))?;
                let route = if split {
                    Route::Lamps { radius, lamps }
                } else {
                    Route::Double
                };
                Ok((route, spread_from))
            }
            Route::Single => {
                let spread_from = if self.engine.ready() { 0.0 } else { 0.5 };
                self.engine
                    .prepare(&planes, &mut control.part(0.0, spread_from))?;
                Ok((Route::Single, spread_from))
            }
            Route::Double => Ok((Route::Double, 0.0)),
        }
    }

    /// `image` spread by FFT through the engine its route names.
    fn convolve(
        &self,
        image: &Image,
        fft: Fft,
        recycled: Vec<Vec<f32>>,
        control: &mut Control,
    ) -> Result<Vec<Vec<f32>>> {
        let lamps: &[usize] = match fft.route {
            Route::Lamps { lamps, .. } => lamps,
            _ => &[],
        };
        let spreads: Vec<Spread> = image
            .planes
            .iter()
            .zip(self.terms(image))
            .map(|(plane, terms)| Spread {
                plane,
                fractions: fft.fractions,
                terms,
                lamps,
            })
            .collect();
        let engine = if *fft.route == Route::Double {
            self.exact_engine(control)?
        } else {
            self.engine.as_ref()
        };
        engine.spread(&spreads, recycled, &mut control.part(fft.spread_from, 1.0))
    }

    /// Each output plane's terms: which kernel planes, weighted how.
    fn terms(&self, image: &Image) -> Vec<Vec<Term>> {
        (0..image.planes.len())
            .map(|c| terms(image.layout, self.kernel.planes().len(), c))
            .collect()
    }

    /// The plan, refusing a scene that needs the f64 engine, which would
    /// not fit the memory limit.
    pub(crate) fn refusing_double(mut self, refused: DoubleRefused) -> Plan {
        self.double_refused = Some(refused);
        self
    }

    /// The f64 engine, built on first use.
    fn exact_engine(&self, control: &mut Control) -> Result<&dyn Engine> {
        if let Some(built) = self.exact.get() {
            return Ok(built.as_ref());
        }
        if let Some(refused) = self.double_refused {
            return Err(refused.error());
        }
        let built = engine(
            (Backend::Cpu, Precision::Double),
            &kernel_planes(&self.kernel),
            (self.kernel.width(), self.kernel.height()),
            (self.width, self.height),
            Centre::Leave,
            &mut control.part(0.0, 0.0),
        )?;
        Ok(self.exact.get_or_init(|| built).as_ref())
    }
}

impl std::fmt::Debug for Plan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Plan")
            .field("size", &self.size())
            .field("kernel", &(self.kernel.width(), self.kernel.height()))
            .field("threshold", &self.threshold)
            .finish()
    }
}

fn kernel_planes(kernel: &Kernel) -> Vec<&[f32]> {
    kernel.planes().iter().map(Vec::as_slice).collect()
}

/// Output plane `c` of an image of `layout` as Σ weight · (kernel plane
/// k ⊛ plane c), over a kernel of `kernel_planes` planes: a coloured kernel
/// spreads a luminance plane as Y = Σ w_k K_k ⊛ Y, otherwise each plane goes
/// through its own kernel plane (or the one plane).
fn terms(layout: Layout, kernel_planes: usize, c: usize) -> Vec<Term> {
    match (layout, kernel_planes) {
        (Layout::Luminance, k) if k > 1 => Term::luminance(),
        (_, k) => Term::alone(c.min(k - 1)),
    }
}
