//! A preview render: the image resampled by area to the view's width, the
//! camera built at the preview's pixel pitch (lengths in px scaled with
//! it), through the same session as `aureole apply`, then exposed and
//! tone-mapped as a PNG.

use aureole::Device;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use aureole::config::ConfigFile;
use aureole::image::{Image, Shape};
use aureole::memory::Workload;
use aureole::{ApplyOptions, Cancel, Config, Frame, GhostSummary, KeptRays, Method};
use aureole_io::display::{meter, render, DisplayOptions, Exposure, ToneCurve};
use aureole_io::kernel::log_picture_window;
use serde::Deserialize;

mod cache;
mod views;

use cache::{KeptSession, Loaded, Preview};
use views::{kernel_profiles, linear_bytes, png, spread_overlay};

use crate::budget::{Budget, Lease};
use crate::error::StudioError;
use crate::locked;
use crate::roots::Roots;

/// The widest preview: a 4K view at 1:1.
pub const MAX_WIDTH: usize = 4096;

/// The image the studio shows when none is chosen: the demo night street.
pub const DEMO: &str = "demo";

/// How long a preview waits for memory that exports hold before it is
/// answered "busy".
const PATIENCE: Duration = Duration::from_secs(20);

/// What a render shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum View {
    /// The image through the camera.
    #[default]
    Result,
    /// The image as it is.
    Original,
    /// Only the light the camera adds.
    Glare,
    /// The kernel at the preview's pitch, log-scaled, its centre in the
    /// middle.
    Kernel,
    /// The image dimmed, with the pixels the threshold spreads in magenta.
    Spread,
}

/// `POST /api/render`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderRequest {
    /// A path under a root, or `demo`.
    pub image: String,
    /// The camera, as a config file's TOML.
    pub config: String,
    /// The preview's width in pixels.
    pub width: usize,
    /// What to show.
    #[serde(default)]
    pub view: View,
    /// EV100, or `"auto"` (the default).
    #[serde(default)]
    pub exposure: Option<serde_json::Value>,
    /// The luminance shown as white, cd/m² (instead of `exposure`).
    #[serde(default)]
    pub white: Option<f64>,
    /// `filmic` (the default), `reinhard` or `clip`.
    #[serde(default)]
    pub tonemap: Option<String>,
    /// cd/m²; the config's when absent.
    #[serde(default)]
    pub threshold: Option<f64>,
    /// The soft knee above the threshold, relative to it.
    #[serde(default)]
    pub knee: f64,
    /// `png` (the default): the picture, exposed and tone-mapped; `linear`:
    /// the luminance itself, for the page to expose as the user drags.
    #[serde(default)]
    pub format: Format,
    /// The kernel's largest extent in the full image's pixels, as
    /// `--max-kernel`: a number or `"WxH"`; by default light reaches the
    /// whole frame.
    #[serde(default)]
    pub max_kernel: Option<MaxKernel>,
    /// Who asks (the page makes one per tab): a client's render cancels
    /// that client's render still running, and no one else's.
    #[serde(default)]
    pub client: Option<String>,
}

impl RenderRequest {
    /// How the camera is applied: the glare view is a glare-only result.
    /// A threshold or knee outside its range is refused in the library's
    /// words, as the command line and Python refuse it.
    pub fn options(&self) -> Result<ApplyOptions, StudioError> {
        let options = ApplyOptions {
            threshold: self.threshold,
            knee: self.knee,
            glare_only: self.view == View::Glare,
            method: Method::Auto,
        };
        options.check()?;
        Ok(options)
    }
}

/// `max_kernel`: `257`, `"257"` or `"511x255"`.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum MaxKernel {
    /// W×W.
    Side(usize),
    /// `W` or `WxH`.
    Text(String),
}

impl MaxKernel {
    /// Width and height, each a whole number above 0.
    pub fn size(&self) -> Result<(usize, usize), StudioError> {
        let refuse = || {
            StudioError::BadRequest(format!(
                "max_kernel {self:?}: write a whole number of pixels above 0, W or \"WxH\" (e.g. 257 or \"511x255\")"
            ))
        };
        let number = |s: &str| s.trim().parse::<usize>().ok().filter(|&n| n > 0);
        match self {
            MaxKernel::Side(n) if *n > 0 => Ok((*n, *n)),
            MaxKernel::Side(_) => Err(refuse()),
            MaxKernel::Text(text) => match text.split_once(['x', 'X']) {
                Some((w, h)) => number(w).zip(number(h)).ok_or_else(refuse),
                None => number(text).map(|n| (n, n)).ok_or_else(refuse),
            },
        }
    }
}

/// The kernel cap of `request` in the full image's pixels, as the
/// session takes it.
pub(crate) fn max_extent(request: &RenderRequest) -> Result<Option<(usize, usize)>, StudioError> {
    request.max_kernel.as_ref().map(MaxKernel::size).transpose()
}

/// A render's bytes, as [`Rendered`] sends them.
struct Encoded {
    bytes: Vec<u8>,
    content_type: &'static str,
    auto_white: [f64; 3],
    white: f64,
}

/// The picture (or linear samples) of `shown`, `scale` cd/m² per unit, as
/// `request` asks: its bytes and their content type, the white auto
/// exposure gives for each tone curve, and the white shown.
fn encoded(
    request: &RenderRequest,
    shown: &Image,
    scale: f64,
    display: DisplayOptions,
) -> Result<Encoded, StudioError> {
    // Metered once per curve: the page switches curves without asking.
    let curves = [ToneCurve::Filmic, ToneCurve::Reinhard, ToneCurve::Clip];
    let metering = meter(shown, scale);
    let auto_white = curves.map(|curve| metering.white(curve));
    let white = match display.exposure {
        Exposure::Auto => curves
            .iter()
            .zip(auto_white)
            .find(|(curve, _)| **curve == display.tone)
            .map_or(0.0, |(_, white)| white),
        exposure => exposure.white(shown, scale, display.tone),
    };
    let (bytes, content_type) = if request.format == Format::Linear {
        (linear_bytes(shown, scale), "application/octet-stream")
    } else {
        let display = DisplayOptions {
            exposure: Exposure::White(white),
            ..display
        };
        let picture = render(shown, scale, &display);
        let codes = picture.eight_bit();
        match request.format {
            Format::Rgb8 => (codes, "application/x-rgb8"),
            _ => (png(&picture)?, "image/png"),
        }
    };
    Ok(Encoded {
        bytes,
        content_type,
        auto_white,
        white,
    })
}

/// The bytes a run of `config` on `frame` takes at its peak, the frame
/// included, from the library's own estimate (as `--max-memory` judges);
/// with `layers`, a run that keeps each effect's glare apart.
pub(crate) fn needs(
    config: &Config,
    frame: &Frame,
    max_extent: Option<(usize, usize)>,
    layers: bool,
) -> Result<u64, StudioError> {
    needs_for(config, Shape::of(frame.image()), max_extent, layers)
}

/// [`needs`] for a frame of `shape`, known from a file's header before it
/// is decoded.
pub(crate) fn needs_for(
    config: &Config,
    shape: Shape,
    max_extent: Option<(usize, usize)>,
    layers: bool,
) -> Result<u64, StudioError> {
    let Shape {
        width,
        height,
        planes,
        alpha,
    } = shape;
    let workload = Workload::of_config(config, width, height, planes, alpha, max_extent)?;
    Ok(if layers {
        workload.estimate_layers(&config.effects)
    } else {
        workload.estimate(&config.effects).bytes
    })
}

/// How a render is sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// A PNG picture.
    #[default]
    Png,
    /// Little-endian f32 R, G, B per pixel, row by row from the top, in
    /// cd/m² (the kernel view is always a PNG).
    Linear,
    /// The picture's 8-bit sRGB codes, R, G, B per pixel, uncompressed.
    Rgb8,
}

/// A rendered picture and what the page shows beside it.
pub struct Rendered {
    /// The picture (PNG) or the linear samples.
    pub bytes: Vec<u8>,
    /// What `bytes` hold, as a content type.
    pub content_type: &'static str,
    /// The luminance auto exposure shows as white, per tone curve: filmic,
    /// Reinhard, clip (0 for the kernel).
    pub auto_white: [f64; 3],
    /// Its width in pixels.
    pub width: usize,
    /// Its height in pixels.
    pub height: usize,
    /// The light of the preview before the camera (Σ luminance, cd/m²·px).
    pub energy_in: f64,
    /// And after.
    pub energy_out: f64,
    /// The luminance shown as white, cd/m² (0 for the kernel).
    pub white: f64,
    /// How long the render took.
    pub milliseconds: f64,
    /// The full image: width, height, cd/m² per unit, and its luminance's
    /// minimum, median and maximum in cd/m².
    pub full: Summary,
    /// For the kernel view: its radial profile (mean weight at 1, 2, …
    /// px from the centre) and its angular profile (the light of a ring in
    /// 2° steps, counter-clockwise from +x, divided by the ring's median).
    pub profiles: Option<(Vec<f64>, Vec<f64>)>,
}

/// What the page says about the image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    /// Width and height in pixels.
    pub size: (usize, usize),
    /// cd/m² per file unit.
    pub scale: f64,
    /// Luminance minimum, median and maximum, cd/m².
    pub luminance: [f64; 3],
}

impl Summary {
    fn of(frame: &Frame) -> Summary {
        let image = frame.image();
        let mut luminance: Vec<f32> = image.luminance();
        luminance.sort_by(f32::total_cmp);
        let at = |i: usize| {
            luminance
                .get(i)
                .map_or(0.0, |&v| f64::from(v) * frame.scale())
        };
        Summary {
            size: (image.width, image.height),
            scale: frame.scale(),
            luminance: [
                at(0),
                at(luminance.len() / 2),
                at(luminance.len().saturating_sub(1)),
            ],
        }
    }
}

/// What renders share: the roots, the memory budget, the last image, its
/// preview, the last session, and the running render's cancellation.
pub struct Renderer {
    roots: Roots,
    /// Shared with the exports; its total is each session's limit too.
    budget: Arc<Budget>,
    /// Where the sessions convolve.
    device: Device,
    loaded: Mutex<Option<Loaded>>,
    preview: Mutex<Option<Preview>>,
    /// The sessions of the last cameras at their preview sizes, the most
    /// recent first.
    kept: Mutex<Vec<KeptSession>>,
    /// Each client's running render.
    running: Mutex<HashMap<String, Cancel>>,
    /// The last preview's lens ghosts, kept while what they depend on
    /// stays: a drag of another parameter does not trace them again.
    ghosts: Mutex<Option<(GhostKey, (Frame, GhostSummary))>>,
    /// Renders whose ghosts were kept.
    ghosts_reused: std::sync::atomic::AtomicU64,
    /// Renders whose ghosts were drawn from kept rays.
    rays_reused: std::sync::atomic::AtomicU64,
    /// The last preview's sources' rays, with their memory's lease: a
    /// drag of the stop's blades, rotation or roundness draws the ghosts
    /// again from them without tracing.
    rays: Mutex<(KeptRays, Option<Lease>)>,
    /// Renders under way, and renders that ended cancelled.
    active: std::sync::atomic::AtomicUsize,
    cancelled: std::sync::atomic::AtomicU64,
    /// Renders through a camera whose session was kept.
    reused: std::sync::atomic::AtomicU64,
}

/// No rays kept, with room for a quarter of `budget`'s bytes of them.
fn no_rays(budget: &Budget) -> (KeptRays, Option<Lease>) {
    (KeptRays::new(budget.total() / 4), None)
}

/// What the renderer is doing, for `GET /api/status`.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Status {
    /// Renders under way.
    pub rendering: usize,
    /// Renders that ended cancelled (replaced, or their page went away).
    pub cancelled: u64,
    /// Renders through a kept session (its kernel and spectra reused).
    pub reused: u64,
    /// Renders whose lens ghosts were kept from the last.
    pub ghosts_reused: u64,
    /// Renders whose lens ghosts were drawn again from the rays kept from
    /// the last (a change of the stop's shape), not traced.
    pub rays_reused: u64,
}

/// What a preview's lens ghosts depend on: the preview itself (held, so
/// that a reloaded or resized one is another), the ghosts' own
/// parameters, the camera and the stop's shape.
struct GhostKey {
    preview: Arc<Frame>,
    ghosts: aureole::lens::effect::Ghosts,
    camera: aureole::CameraGeometry,
    aperture: Option<aureole::Aperture>,
}

impl GhostKey {
    fn is(&self, other: &GhostKey) -> bool {
        Arc::ptr_eq(&self.preview, &other.preview)
            && self.ghosts == other.ghosts
            && self.camera == other.camera
            && self.aperture == other.aperture
    }
}

impl Renderer {
    /// Renders from files under `roots`, within `budget`, which exports
    /// share.
    pub fn new(roots: Roots, budget: Arc<Budget>, device: Device) -> Renderer {
        Renderer {
            rays: Mutex::new(no_rays(&budget)),
            roots,
            budget,
            device,
            loaded: Mutex::new(None),
            preview: Mutex::new(None),
            kept: Mutex::new(Vec::new()),
            running: Mutex::new(HashMap::new()),
            ghosts: Mutex::new(None),
            ghosts_reused: std::sync::atomic::AtomicU64::new(0),
            rays_reused: std::sync::atomic::AtomicU64::new(0),
            active: std::sync::atomic::AtomicUsize::new(0),
            cancelled: std::sync::atomic::AtomicU64::new(0),
            reused: std::sync::atomic::AtomicU64::new(0),
        }
    }

    /// The roots files are read from.
    pub fn roots(&self) -> &Roots {
        &self.roots
    }

    /// Renders `request`, stopping when `cancel` is set (the page went
    /// away); the same client's render still running is cancelled first,
    /// as the newer request replaces it.
    pub fn render(&self, request: &RenderRequest, cancel: Cancel) -> Result<Rendered, StudioError> {
        use std::sync::atomic::Ordering;
        self.active.fetch_add(1, Ordering::SeqCst);
        let outcome = self.render_counted(request, cancel);
        if matches!(outcome, Err(StudioError::Superseded)) {
            self.cancelled.fetch_add(1, Ordering::SeqCst);
        }
        self.active.fetch_sub(1, Ordering::SeqCst);
        outcome
    }

    /// What the renderer is doing.
    pub fn status(&self) -> Status {
        use std::sync::atomic::Ordering;
        Status {
            rendering: self.active.load(Ordering::SeqCst),
            cancelled: self.cancelled.load(Ordering::SeqCst),
            reused: self.reused.load(Ordering::SeqCst),
            ghosts_reused: self.ghosts_reused.load(Ordering::SeqCst),
            rays_reused: self.rays_reused.load(Ordering::SeqCst),
        }
    }

    /// The lens ghosts of `preview` through the camera of `session`: the
    /// last ones where they depend on the same, else traced and kept.
    fn ghosts_of(
        &self,
        preview: &Arc<Frame>,
        session: &aureole::Session,
        cancel: &Cancel,
    ) -> Result<Option<(Frame, GhostSummary)>, StudioError> {
        let Some(config) = session.config() else {
            return Ok(None);
        };
        let Some(ghosts) = &config.ghosts else {
            return Ok(None);
        };
        let key = GhostKey {
            preview: preview.clone(),
            ghosts: ghosts.clone(),
            camera: config.camera,
            aperture: config.first_aperture().cloned(),
        };
        if let Some((kept, ghosted)) = locked(&self.ghosts).as_ref() {
            if kept.is(&key) {
                self.ghosts_reused
                    .fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                return Ok(Some(ghosted.clone()));
            }
        }
        let traced = self.trace_keeping_rays(preview, session, cancel)?;
        if let Some(ghosted) = &traced {
            *locked(&self.ghosts) = Some((key, ghosted.clone()));
        }
        Ok(traced)
    }

    /// [`Renderer::ghosts_of`] `preview`, its kernel built for it
    /// meanwhile: neither needs the other, and each leaves cores idle in
    /// its parts that run alone.
    fn ghosts_beside_kernel(
        &self,
        preview: &Arc<Frame>,
        session: &mut aureole::Session,
        cancel: &Cancel,
    ) -> Result<Option<(Frame, GhostSummary)>, StudioError> {
        let Some(config) = session.config().filter(|c| c.ghosts.is_some()) else {
            return Ok(None);
        };
        let mut tracing = aureole::Session::new(config.clone());
        tracing.set_cancel_token(cancel.clone());
        let (ghosted, prepared) = rayon::join(
            || self.ghosts_of(preview, &tracing, cancel),
            || session.prepare(preview),
        );
        let ghosted = ghosted?;
        prepared?;
        Ok(ghosted)
    }

    /// The ghosts of `preview` traced by `session`, from the rays kept
    /// where they serve, whose own are kept next, up to a quarter of the
    /// budget and while the budget has room for them now (else none: they
    /// would only make a job wait).
    fn trace_keeping_rays(
        &self,
        preview: &Frame,
        session: &aureole::Session,
        cancel: &Cancel,
    ) -> Result<Option<(Frame, GhostSummary)>, StudioError> {
        // Taken out while tracing: a render beside this one traces its own.
        let (mut rays, lease) = std::mem::replace(&mut *locked(&self.rays), no_rays(&self.budget));
        drop(lease);
        let traced = session.trace_ghosts_keeping(preview, &mut rays, &mut |_, _| {})?;
        if rays.reused() > 0 {
            self.rays_reused
                .fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        }
        let lease = self
            .budget
            .lease(rays.bytes(), cancel, Some(Duration::ZERO), || {})
            .ok();
        if lease.is_some() {
            *locked(&self.rays) = (rays, lease);
        }
        Ok(traced)
    }

    fn render_counted(
        &self,
        request: &RenderRequest,
        cancel: Cancel,
    ) -> Result<Rendered, StudioError> {
        let start = Instant::now();
        if let Some(client) = &request.client {
            let mut running = locked(&self.running);
            running.retain(|_, c| !c.is_cancelled());
            if let Some(before) = running.insert(client.clone(), cancel.clone()) {
                before.cancel();
            }
        }
        if request.width == 0 || request.width > MAX_WIDTH {
            return Err(StudioError::BadRequest(format!(
                "width {} is not allowed: from 1 to {MAX_WIDTH} px",
                request.width
            )));
        }
        let display = display_options(request)?;
        let options = request.options()?;
        let max_full = max_extent(request)?;
        let (full, summary) = self.load(&request.image)?;
        let preview = self.preview(&full, request.width)?;
        let image = preview.image();
        let (width, height) = (image.width, image.height);
        let factor = width as f64 / full.image().width as f64;

        let (mut profiles, mut kernel_view) = (None, None);
        let (shown, energy_in, energy_out) = match request.view {
            View::Original => (
                image.clone(),
                image.total_luminance(),
                image.total_luminance(),
            ),
            View::Spread => {
                let threshold = match request.threshold {
                    Some(t) => t,
                    None => parse_config(&request.config)?.threshold,
                };
                let total = image.total_luminance();
                (
                    spread_overlay(image, preview.scale(), threshold, options.knee),
                    total,
                    total,
                )
            }
            view => {
                // The cap, like every length in px, shrinks with the preview.
                let max_extent = max_full.map(|(w, h)| {
                    let scaled = |n: usize| ((n as f64 * factor).round() as usize).max(1);
                    (scaled(w), scaled(h))
                });
                let key = ((request.config.clone(), (width, height)), max_extent);
                let mut kept =
                    self.kept_session(key, &request.config, &preview, factor, &cancel)?;
                let Some(kept) = kept.first_mut() else {
                    return Err(StudioError::Internal("no session".into()));
                };
                kept.session.set_cancel_token(cancel.clone());
                let ghosted = self.ghosts_beside_kernel(&preview, &mut kept.session, &cancel)?;
                let applied =
                    kept.session
                        .apply_after_ghosts(&preview, ghosted, &options, &mut |_, _| {})?;
                if view == View::Kernel {
                    let plan = kept
                        .session
                        .plan()
                        .ok_or_else(|| StudioError::Internal("the kernel was not built".into()))?;
                    profiles = Some(kernel_profiles(plan.kernel(), width.min(height) / 2));
                    kernel_view = Some(log_picture_window(plan.kernel(), width, height));
                }
                (applied.image, applied.energy_in, applied.energy_out)
            }
        };
        cancel.check()?;
        let Encoded {
            bytes,
            content_type,
            auto_white,
            white,
        } = match &kernel_view {
            Some(picture) => Encoded {
                bytes: png(picture)?,
                content_type: "image/png",
                auto_white: [0.0; 3],
                white: 0.0,
            },
            None => encoded(request, &shown, preview.scale(), display)?,
        };
        Ok(Rendered {
            bytes,
            content_type,
            auto_white,
            width,
            height,
            energy_in,
            energy_out,
            white,
            milliseconds: start.elapsed().as_secs_f64() * 1e3,
            full: summary,
            profiles,
        })
    }
}

/// The camera a TOML text describes, on top of the defaults.
pub fn parse_config(text: &str) -> Result<Config, StudioError> {
    // The studio reads only the image the user opened: a ghosts' lens is
    // a shipped one or written inline, never a file.
    let file = ConfigFile::parse_in(text, "config", None)?;
    let mut config = Config::default();
    config.merge(file);
    if config.effects.is_empty() && config.ghosts.is_none() {
        return Err(aureole::Error::NoEffect.into());
    }
    // The studio reads only the image the user opened; a measured PSF's
    // file is another, which the command line and Python read.
    if config
        .effects
        .iter()
        .any(|e| matches!(e, aureole::Effect::Image(_)))
    {
        return Err(StudioError::BadRequest(
            "config: the studio does not read measured PSFs (type = \"image\"); apply them with `aureole apply` or Python".into(),
        ));
    }
    Ok(config)
}

pub(crate) fn display_options(request: &RenderRequest) -> Result<DisplayOptions, StudioError> {
    let exposure = match (&request.white, &request.exposure) {
        (Some(white), _) if white.is_finite() && *white > 0.0 => Exposure::White(*white),
        (Some(white), _) => {
            return Err(StudioError::BadRequest(format!(
                "white {white} is not allowed: a luminance in cd/m² above 0"
            )))
        }
        (None, None) => Exposure::Auto,
        (None, Some(serde_json::Value::String(text))) => {
            text.parse().map_err(StudioError::BadRequest)?
        }
        (None, Some(serde_json::Value::Number(n))) => n
            .as_f64()
            .and_then(Exposure::ev100)
            .ok_or_else(|| StudioError::BadRequest(Exposure::refusal(n)))?,
        (None, Some(other)) => return Err(StudioError::BadRequest(Exposure::refusal(other))),
    };
    let tone = request
        .tonemap
        .as_deref()
        .map_or(Ok(ToneCurve::Filmic), str::parse)
        .map_err(StudioError::BadRequest)?;
    Ok(DisplayOptions { exposure, tone })
}
