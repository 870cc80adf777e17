//! A small OpenFX 1.4 host, written from the specification to load and
//! render the aureole plugin in tests, as Resolve, Nuke or Natron would:
//! it finds the binary inside an `.ofx.bundle`, loads it with
//! `libloading`, hands it the property, image effect, parameter, memory,
//! multi-thread and message suites, and calls the actions in a host's
//! order (load, describe, describe in context, create instance, begin
//! sequence, region of definition and of interest, render, end sequence,
//! destroy, unload). Its suites check every handle, so a plugin's mistake
//! is a status, not a crash.
//!
//! It runs on x86-64 Linux, where its fixed-argument stand-ins for the
//! variadic suite functions are sound (see `params`).

mod effect;
mod params;
mod props;
mod services;

use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex, OnceLock};

use aureole_ofx_abi::{self as abi, names, Handle, OfxHost, OfxPlugin, OfxRectD, OfxStatus};

pub use effect::images_held;
use effect::{new_clip, new_param, Effect, Lending};
pub use props::{PropSet, Value};

/// A picture in the host's memory: `channels` (3 or 4) floats per pixel,
/// interleaved, the top row first.
#[derive(Debug, Clone, PartialEq)]
pub struct Picture {
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    pub pixels: Vec<f32>,
}

impl Picture {
    /// The library's `image` as `channels` floats per pixel (3 or 4,
    /// alpha 1 where it has none).
    pub fn of_image(image: &aureole::Image, channels: usize) -> Picture {
        let (w, h) = (image.width, image.height);
        let mut pixels = vec![0.0f32; w * h * channels];
        for i in 0..w * h {
            for c in 0..3 {
                pixels[i * channels + c] = image.planes[c.min(image.planes.len() - 1)][i];
            }
            if channels == 4 {
                pixels[i * 4 + 3] = image.alpha.as_ref().map_or(1.0, |a| a[i]);
            }
        }
        Picture {
            width: w,
            height: h,
            channels,
            pixels,
        }
    }

    /// The picture as the library's image: planes apart, alpha kept.
    pub fn to_image(&self) -> aureole::Image {
        let (w, h, n) = (self.width, self.height, self.channels);
        let mut image = aureole::Image::filled(w, h, aureole::Layout::Rgb, 0.0);
        for (c, plane) in image.planes.iter_mut().enumerate() {
            for (i, v) in plane.iter_mut().enumerate() {
                *v = self.pixels[i * n + c];
            }
        }
        image.alpha = (n == 4).then(|| (0..w * h).map(|i| self.pixels[i * n + 3]).collect());
        image
    }
}

/// What went wrong between the host and the plugin.
#[derive(Debug, Clone, PartialEq)]
pub struct Refusal {
    /// The action, or the step of loading.
    pub action: String,
    pub status: OfxStatus,
    /// What the plugin posted meanwhile: (type, text).
    pub messages: Vec<(String, String)>,
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: status {}", self.action, self.status)?;
        for (kind, text) in &self.messages {
            write!(f, "; {kind}: {text}")?;
        }
        Ok(())
    }
}

impl std::error::Error for Refusal {}

/// `effect`'s answer to the action `named`: Ok for `kOfxStatOK`, else a
/// refusal with what the plugin posted.
fn answered(status: OfxStatus, named: &CStr, effect: &Effect) -> Result<(), Refusal> {
    if status == abi::STAT_OK {
        return Ok(());
    }
    Err(Refusal {
        messages: take_messages(effect),
        ..refused(&named.to_string_lossy(), status)
    })
}

fn refused(action: &str, status: OfxStatus) -> Refusal {
    Refusal {
        action: action.to_string(),
        status,
        messages: Vec::new(),
    }
}

/// The binary inside `bundle` for this machine: `Contents/Linux-x86-64/`
/// and the bundle's name without `.bundle`.
pub fn binary_of(bundle: &Path) -> Option<PathBuf> {
    let name = bundle.file_name()?.to_str()?.strip_suffix(".bundle")?;
    Some(bundle.join("Contents").join("Linux-x86-64").join(name))
}

/// The `.ofx.bundle` folders in `folder`, as a host scans its plugin path.
pub fn bundles_in(folder: &Path) -> Vec<PathBuf> {
    let mut found: Vec<PathBuf> = std::fs::read_dir(folder)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir() && p.to_string_lossy().ends_with(".ofx.bundle"))
        .collect();
    found.sort();
    found
}

struct Tables {
    parameter: abi::OfxParameterSuiteV1,
    message: abi::OfxMessageSuiteV1,
}

static TABLES: OnceLock<Tables> = OnceLock::new();

unsafe extern "C" fn fetch_suite(
    _host: Handle,
    name: *const c_char,
    version: c_int,
) -> *const c_void {
    if name.is_null() || version != 1 {
        return std::ptr::null();
    }
    let tables = TABLES.get_or_init(|| Tables {
        parameter: params::suite(),
        message: services::message_suite(),
    });
    // SAFETY: the plugin's C string, checked non-null.
    let name = unsafe { CStr::from_ptr(name) };
    let suite: *const c_void = match name {
        n if n == names::PROPERTY_SUITE => (&props::SUITE as *const abi::OfxPropertySuiteV1).cast(),
        n if n == names::IMAGE_EFFECT_SUITE => {
            (&effect::IMAGE_EFFECT_SUITE as *const abi::OfxImageEffectSuiteV1).cast()
        }
        n if n == names::PARAMETER_SUITE => {
            (&tables.parameter as *const abi::OfxParameterSuiteV1).cast()
        }
        n if n == names::MEMORY_SUITE => {
            (&services::MEMORY_SUITE as *const abi::OfxMemorySuiteV1).cast()
        }
        n if n == names::MULTI_THREAD_SUITE => {
            (&services::MULTI_THREAD_SUITE as *const abi::OfxMultiThreadSuiteV1).cast()
        }
        n if n == names::MESSAGE_SUITE => (&tables.message as *const abi::OfxMessageSuiteV1).cast(),
        _ => std::ptr::null(),
    };
    suite
}

/// A loaded plugin binary and its first plugin.
pub struct Plugin {
    plugin: *const OfxPlugin,
    _host: Box<OfxHost>,
    host_props: Box<PropSet>,
    descriptor: Mutex<Option<Box<Effect>>>,
    contexts: Mutex<Vec<(String, Box<Effect>)>>,
    loaded: bool,
    // Dropped last: the plugin's code and statics live in it.
    _library: libloading::Library,
}

// The plugin declares itself fully thread safe; the host's own state is
// behind mutexes.
unsafe impl Send for Plugin {}
unsafe impl Sync for Plugin {}

impl Plugin {
    /// Opens the binary of `bundle`, finds its first plugin and gives it
    /// the host, without loading it (`kOfxActionLoad` not yet called).
    pub fn open(bundle: &Path) -> Result<Plugin, Refusal> {
        let binary = binary_of(bundle)
            .ok_or_else(|| refused("a bundle named *.ofx.bundle", abi::STAT_ERR_UNKNOWN))?;
        // SAFETY: loading a plugin runs its initialisers, as a host does.
        let library = unsafe { libloading::Library::new(&binary) }.map_err(|e| {
            refused(
                &format!("loading {}: {e}", binary.display()),
                abi::STAT_ERR_UNKNOWN,
            )
        })?;
        // SAFETY: the two entry points every OpenFX binary exports.
        let plugin = unsafe {
            let count = library
                .get::<unsafe extern "C" fn() -> c_int>(b"OfxGetNumberOfPlugins")
                .map_err(|_| refused("OfxGetNumberOfPlugins", abi::STAT_ERR_UNKNOWN))?;
            let get = library
                .get::<unsafe extern "C" fn(c_int) -> *const OfxPlugin>(b"OfxGetPlugin")
                .map_err(|_| refused("OfxGetPlugin", abi::STAT_ERR_UNKNOWN))?;
            if count() < 1 {
                return Err(refused(
                    "OfxGetNumberOfPlugins: none",
                    abi::STAT_ERR_UNKNOWN,
                ));
            }
            get(0)
        };
        // SAFETY: the plugin's static description, checked non-null.
        let description = unsafe { plugin.as_ref() }
            .ok_or_else(|| refused("OfxGetPlugin(0)", abi::STAT_ERR_UNKNOWN))?;
        // SAFETY: a C string in the plugin's static data.
        let api = unsafe { CStr::from_ptr(description.plugin_api) };
        if api != names::IMAGE_EFFECT_PLUGIN_API || description.api_version != 1 {
            return Err(refused("the plugin's API", abi::STAT_ERR_UNSUPPORTED));
        }
        let host_props = PropSet::new();
        host_props.set_str(
            names::PROP_TYPE,
            &names::TYPE_IMAGE_EFFECT_HOST.to_string_lossy(),
        );
        host_props.set_str(names::PROP_NAME, "org.aureole.testhost");
        host_props.set_str(names::PROP_LABEL, "aureole's test host");
        host_props.set(
            names::EFFECT_SUPPORTED_CONTEXTS,
            Value::Strings(vec![
                names::CONTEXT_FILTER.to_owned(),
                names::CONTEXT_GENERAL.to_owned(),
            ]),
        );
        let mut host = Box::new(OfxHost {
            host: host_props.handle(),
            fetch_suite,
        });
        // SAFETY: setHost is the first call, with a host that outlives it.
        unsafe { (description.set_host)(&mut *host) };
        Ok(Plugin {
            plugin,
            _host: host,
            host_props,
            descriptor: Mutex::new(None),
            contexts: Mutex::new(Vec::new()),
            loaded: false,
            _library: library,
        })
    }

    /// Opens the bundle and loads the plugin (`kOfxActionLoad`).
    pub fn load(bundle: &Path) -> Result<Plugin, Refusal> {
        let mut plugin = Plugin::open(bundle)?;
        // SAFETY: load takes no handle.
        let status = unsafe { plugin.action(names::ACTION_LOAD, std::ptr::null_mut(), None, None) };
        if status != abi::STAT_OK && status != abi::STAT_REPLY_DEFAULT {
            return Err(refused("OfxActionLoad", status));
        }
        plugin.loaded = true;
        Ok(plugin)
    }

    /// The plugin's identifier and version.
    pub fn identifier(&self) -> (String, u32, u32) {
        // SAFETY: the plugin's static description, checked by `open`.
        let p = unsafe { &*self.plugin };
        // SAFETY: a C string in the plugin's static data.
        let id = unsafe { CStr::from_ptr(p.plugin_identifier) }
            .to_string_lossy()
            .into_owned();
        (id, p.plugin_version_major, p.plugin_version_minor)
    }

    /// Calls `action` on `handle` as it is, in whatever order: the way to
    /// see how the plugin answers a host that gets it wrong.
    ///
    /// # Safety
    /// The plugin is handed `handle` as an effect: it must be null, an
    /// effect this host made, or a value a plugin only passes back to the
    /// host's suites, which look every handle up before they use it (as
    /// aureole's plugin does).
    pub unsafe fn action(
        &self,
        action: &CStr,
        handle: Handle,
        in_args: Option<&PropSet>,
        out_args: Option<&PropSet>,
    ) -> OfxStatus {
        let arg = |a: Option<&PropSet>| a.map_or(std::ptr::null_mut(), PropSet::handle);
        // SAFETY: the plugin's entry point, given live handles or null.
        unsafe { ((*self.plugin).main_entry)(action.as_ptr(), handle, arg(in_args), arg(out_args)) }
    }

    /// `kOfxActionDescribe`, once: the descriptor's properties.
    pub fn describe(&self) -> Result<PropSnapshot, Refusal> {
        let descriptor = Effect::new(names::TYPE_IMAGE_EFFECT);
        // SAFETY: a descriptor the host made.
        let status =
            unsafe { self.action(names::ACTION_DESCRIBE, descriptor.handle(), None, None) };
        answered(status, names::ACTION_DESCRIBE, &descriptor)?;
        let snapshot = PropSnapshot::of(&descriptor.props);
        *self.descriptor.lock().unwrap_or_else(|p| p.into_inner()) = Some(descriptor);
        Ok(snapshot)
    }

    /// `kOfxImageEffectActionDescribeInContext` for `context`: the names of
    /// the clips and parameters defined.
    pub fn describe_in_context(
        &self,
        context: &CStr,
    ) -> Result<(Vec<String>, Vec<String>), Refusal> {
        let descriptor = Effect::new(names::TYPE_IMAGE_EFFECT);
        descriptor
            .props
            .set_str(names::EFFECT_CONTEXT, &context.to_string_lossy());
        let in_args = PropSet::new();
        in_args.set_str(names::EFFECT_CONTEXT, &context.to_string_lossy());
        // SAFETY: a descriptor the host made.
        let status = unsafe {
            self.action(
                names::ACTION_DESCRIBE_IN_CONTEXT,
                descriptor.handle(),
                Some(&in_args),
                None,
            )
        };
        answered(status, names::ACTION_DESCRIBE_IN_CONTEXT, &descriptor)?;
        let clips = descriptor
            .clips
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .iter()
            .map(|(n, _)| n.to_string_lossy().into_owned())
            .collect();
        let params = descriptor
            .params
            .params
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .iter()
            .map(|(n, _)| n.to_string_lossy().into_owned())
            .collect();
        self.contexts
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .push((context.to_string_lossy().into_owned(), descriptor));
        Ok((clips, params))
    }

    /// A parameter's definition in `context`'s descriptor.
    pub fn param_definition(&self, context: &CStr, name: &str) -> Option<PropSnapshot> {
        let contexts = self.contexts.lock().unwrap_or_else(|p| p.into_inner());
        let (_, descriptor) = contexts
            .iter()
            .find(|(c, _)| c.as_bytes() == context.to_bytes())?;
        // SAFETY: the parameter lives with its descriptor, held above.
        descriptor
            .param(name)
            .map(|p| PropSnapshot::of(unsafe { &(*p).props }))
    }

    /// `kOfxActionCreateInstance` in `context` (described before), on a
    /// project of `project`.
    pub fn instance(&self, context: &CStr, project: Project) -> Result<Instance<'_>, Refusal> {
        let effect = Effect::new(names::TYPE_IMAGE_EFFECT_INSTANCE);
        {
            let contexts = self.contexts.lock().unwrap_or_else(|p| p.into_inner());
            let (_, descriptor) = contexts
                .iter()
                .find(|(c, _)| c.as_bytes() == context.to_bytes())
                .ok_or_else(|| {
                    refused(
                        "create an instance in a context not described",
                        abi::STAT_ERR_UNKNOWN,
                    )
                })?;
            instantiate(descriptor, &effect);
        }
        let p = &effect.props;
        p.set_str(names::EFFECT_CONTEXT, &context.to_string_lossy());
        p.set(names::PROP_INSTANCE_DATA, Value::Pointers(vec![0]));
        p.set(
            names::EFFECT_PROJECT_SIZE,
            Value::Doubles(vec![project.width, project.height]),
        );
        p.set(
            names::EFFECT_PROJECT_OFFSET,
            Value::Doubles(vec![project.x, project.y]),
        );
        p.set(
            names::EFFECT_PROJECT_EXTENT,
            Value::Doubles(vec![project.x + project.width, project.y + project.height]),
        );
        p.set(
            names::EFFECT_PROJECT_PIXEL_ASPECT_RATIO,
            Value::Doubles(vec![project.pixel_aspect]),
        );
        // SAFETY: an instance the host made.
        let status =
            unsafe { self.action(names::ACTION_CREATE_INSTANCE, effect.handle(), None, None) };
        answered(status, names::ACTION_CREATE_INSTANCE, &effect)?;
        Ok(Instance {
            plugin: self,
            effect,
            project,
            bottom_up: std::sync::atomic::AtomicBool::new(false),
            connected: std::sync::atomic::AtomicBool::new(true),
        })
    }

    /// The host's own property set.
    pub fn host_props(&self) -> &PropSet {
        &self.host_props
    }
}

impl Drop for Plugin {
    fn drop(&mut self) {
        if self.loaded {
            // SAFETY: unload takes no handle.
            unsafe { self.action(names::ACTION_UNLOAD, std::ptr::null_mut(), None, None) };
        }
    }
}

/// A copy of a property set's values, to look at after the host lets it go.
#[derive(Debug, Clone, Default)]
pub struct PropSnapshot(Vec<(String, Value)>);

impl PropSnapshot {
    fn of(set: &PropSet) -> PropSnapshot {
        PropSnapshot(set.entries())
    }

    fn get(&self, name: &CStr) -> Option<&Value> {
        let name = name.to_string_lossy();
        self.0.iter().find(|(n, _)| *n == name).map(|(_, v)| v)
    }

    pub fn strings(&self, name: &CStr) -> Vec<String> {
        match self.get(name) {
            Some(Value::Strings(s)) => s.iter().map(|s| s.to_string_lossy().into_owned()).collect(),
            _ => Vec::new(),
        }
    }

    pub fn ints(&self, name: &CStr) -> Vec<c_int> {
        match self.get(name) {
            Some(Value::Ints(i)) => i.clone(),
            _ => Vec::new(),
        }
    }

    pub fn doubles(&self, name: &CStr) -> Vec<f64> {
        match self.get(name) {
            Some(Value::Doubles(d)) => d.clone(),
            _ => Vec::new(),
        }
    }
}

/// The project an instance lives in, in canonical coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Project {
    pub x: f64,
    pub y: f64,
    pub width: f64,
    pub height: f64,
    pub pixel_aspect: f64,
}

impl Project {
    /// A project of `width` × `height` square pixels at the origin.
    pub fn of(width: usize, height: usize) -> Project {
        Project {
            x: 0.0,
            y: 0.0,
            width: width as f64,
            height: height as f64,
            pixel_aspect: 1.0,
        }
    }
}

fn take_messages(effect: &Effect) -> Vec<(String, String)> {
    std::mem::take(&mut *effect.messages.lock().unwrap_or_else(|p| p.into_inner()))
}

/// The instance's clips and parameters, made from the descriptor's: each
/// parameter at its default.
fn instantiate(descriptor: &Effect, effect: &Effect) {
    for (name, clip) in descriptor
        .clips
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .iter()
    {
        let made = new_clip(name);
        for (key, value) in clip.props.entries() {
            made.props
                .set(&CString::new(key).unwrap_or_default(), value);
        }
        made.props.set(names::CLIP_CONNECTED, Value::Ints(vec![1]));
        made.props.set_str(
            names::EFFECT_PIXEL_DEPTH,
            &names::BIT_DEPTH_FLOAT.to_string_lossy(),
        );
        made.props
            .set(names::IMAGE_PIXEL_ASPECT_RATIO, Value::Doubles(vec![1.0]));
        effect
            .clips
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .push((name.clone(), made));
    }
    for (name, param) in descriptor
        .params
        .params
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .iter()
    {
        let made = new_param(&param.kind, name);
        for (key, value) in param.props.entries() {
            made.props
                .set(&CString::new(key).unwrap_or_default(), value);
        }
        let default = param.props.get(names::PARAM_DEFAULT);
        if let Some(default) = default {
            *made.value.lock().unwrap_or_else(|p| p.into_inner()) = default;
        }
        effect
            .params
            .params
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .push((name.clone(), made));
    }
}

/// The picture a lending held, once the plugin has let it go, top row
/// first.
fn take(lending: &Mutex<Lending>) -> Picture {
    let mut lending = lending.lock().unwrap_or_else(|p| p.into_inner());
    let bottom_up = lending.bottom_up;
    let empty = Picture {
        width: 0,
        height: 0,
        channels: lending.picture.channels,
        pixels: Vec::new(),
    };
    let picture = std::mem::replace(&mut lending.picture, empty);
    if bottom_up {
        effect::flipped(picture)
    } else {
        picture
    }
}

/// A value for a parameter.
#[derive(Debug, Clone, PartialEq)]
pub enum Setting {
    Double(f64),
    /// Integers, booleans (0 or 1) and choices (the option's index).
    Int(c_int),
    Text(String),
}

/// An effect instance: its parameters set by the host, its frames rendered.
pub struct Instance<'p> {
    plugin: &'p Plugin,
    effect: Box<Effect>,
    project: Project,
    /// Images laid bottom row first with a positive stride.
    bottom_up: std::sync::atomic::AtomicBool,
    /// Whether the source clip is connected to an input.
    connected: std::sync::atomic::AtomicBool,
}

impl Instance<'_> {
    /// The instance's handle, for actions called by hand.
    pub fn handle(&self) -> Handle {
        self.effect.handle()
    }

    /// Sets a parameter as a user would in the host's panel.
    pub fn set(&self, name: &str, value: Setting) -> Result<(), Refusal> {
        let param = self
            .effect
            .param(name)
            .ok_or_else(|| refused(&format!("no parameter {name}"), abi::STAT_ERR_UNKNOWN))?;
        let value = match value {
            Setting::Double(v) => Value::Doubles(vec![v]),
            Setting::Int(v) => Value::Ints(vec![v]),
            Setting::Text(t) => Value::Strings(vec![CString::new(t).unwrap_or_default()]),
        };
        // SAFETY: the parameter lives with the instance.
        *unsafe { &*param }
            .value
            .lock()
            .unwrap_or_else(|p| p.into_inner()) = value;
        Ok(())
    }

    /// Lays the images it hands out bottom row first with a positive
    /// stride, as Resolve and Nuke do (`true`), or top row first with a
    /// negative one, as some hosts do (`false`, the default).
    pub fn set_rows_bottom_up(&self, bottom_up: bool) {
        self.bottom_up.store(bottom_up, Ordering::Relaxed);
    }

    /// Connects or disconnects the source clip: a render without an input
    /// has no source image.
    pub fn set_source_connected(&self, connected: bool) {
        self.connected.store(connected, Ordering::Relaxed);
    }

    /// Asks (or stops asking) the plugin to abort what it renders.
    pub fn set_abort(&self, abort: bool) {
        self.effect.abort.store(abort, Ordering::Relaxed);
    }

    /// What the plugin posted on this instance since the last call.
    pub fn messages(&self) -> Vec<(String, String)> {
        take_messages(&self.effect)
    }

    fn args(&self, time: f64, scale: [f64; 2]) -> Box<PropSet> {
        let args = PropSet::new();
        args.set(names::PROP_TIME, Value::Doubles(vec![time]));
        args.set(names::EFFECT_RENDER_SCALE, Value::Doubles(scale.to_vec()));
        args
    }

    fn call(
        &self,
        action: &CStr,
        in_args: Option<&PropSet>,
        out_args: Option<&PropSet>,
    ) -> Result<(), Refusal> {
        // SAFETY: the instance the host made.
        let status = unsafe { self.plugin.action(action, self.handle(), in_args, out_args) };
        // What the plugin leaves to the host is the host's default.
        let status = if status == abi::STAT_REPLY_DEFAULT {
            abi::STAT_OK
        } else {
            status
        };
        answered(status, action, &self.effect)
    }

    /// `kOfxImageEffectActionBeginSequenceRender` over frames
    /// `first..=last` at `scale`.
    pub fn begin_sequence(&self, first: f64, last: f64, scale: [f64; 2]) -> Result<(), Refusal> {
        self.sequence(names::ACTION_BEGIN_SEQUENCE_RENDER, (first, last), scale)
    }

    /// `kOfxImageEffectActionEndSequenceRender`.
    pub fn end_sequence(&self, first: f64, last: f64, scale: [f64; 2]) -> Result<(), Refusal> {
        self.sequence(names::ACTION_END_SEQUENCE_RENDER, (first, last), scale)
    }

    /// A sequence action over frames `first..=last`, not interactive.
    fn sequence(
        &self,
        action: &CStr,
        (first, last): (f64, f64),
        scale: [f64; 2],
    ) -> Result<(), Refusal> {
        let args = self.args(first, scale);
        args.set(names::EFFECT_FRAME_RANGE, Value::Doubles(vec![first, last]));
        args.set(names::EFFECT_FRAME_STEP, Value::Doubles(vec![1.0]));
        args.set(names::PROP_IS_INTERACTIVE, Value::Ints(vec![0]));
        self.call(action, Some(&args), None)
    }

    /// Renders `source` (the frame at `time`, already at render scale
    /// `scale`, its bottom-left corner at the origin) as a host does: the
    /// output's region of definition asked, then the regions of interest,
    /// then the render of the whole output.
    pub fn render(&self, time: f64, source: &Picture, scale: [f64; 2]) -> Result<Picture, Refusal> {
        let blank = Picture {
            pixels: vec![0.0; source.pixels.len()],
            ..source.clone()
        };
        self.render_buffers(time, source.clone(), blank, scale)
            .map(|(_, output)| output)
    }

    /// [`Instance::render`] with the host's buffers handed in and back, as
    /// a host's image cache reuses them from frame to frame: `output`
    /// (of the source's size, its contents whatever they were) is written
    /// by the plugin. Returns the source and the output.
    pub fn render_buffers(
        &self,
        time: f64,
        source: Picture,
        output: Picture,
        scale: [f64; 2],
    ) -> Result<(Picture, Picture), Refusal> {
        let key = time.to_bits();
        let (w, h) = (source.width, source.height);
        let canonical = OfxRectD {
            x1: 0.0,
            y1: 0.0,
            x2: w as f64 / scale[0] * self.project.pixel_aspect,
            y2: h as f64 / scale[1],
        };
        let bottom_up = self.bottom_up.load(Ordering::Relaxed);
        let lend = |picture: Picture| {
            Arc::new(Mutex::new(Lending {
                picture: if bottom_up {
                    effect::flipped(picture)
                } else {
                    picture
                },
                bottom_up,
                origin: (0, 0),
                render_scale: scale,
            }))
        };
        let source_clip = self.clip(names::CLIP_SOURCE)?;
        let components = if source.channels == 4 {
            names::COMPONENT_RGBA
        } else {
            names::COMPONENT_RGB
        };
        if (output.width, output.height, output.channels) != (w, h, source.channels)
            || output.pixels.len() != source.pixels.len()
        {
            return Err(refused(
                "an output buffer of another size than the source",
                abi::STAT_ERR_VALUE,
            ));
        }
        source_clip
            .props
            .set_str(names::EFFECT_COMPONENTS, &components.to_string_lossy());
        let aspect = Value::Doubles(vec![self.project.pixel_aspect]);
        source_clip
            .props
            .set(names::IMAGE_PIXEL_ASPECT_RATIO, aspect.clone());
        *source_clip.region.lock().unwrap_or_else(|p| p.into_inner()) = canonical;
        let lent_source = lend(source);
        let connected = self.connected.load(Ordering::Relaxed);
        source_clip.props.set(
            names::CLIP_CONNECTED,
            Value::Ints(vec![i32::from(connected)]),
        );
        if connected {
            source_clip
                .frames
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .insert(key, lent_source.clone());
        }

        let args = self.args(time, scale);
        let out = PropSet::new();
        let outcome = self
            .call(
                names::ACTION_GET_REGION_OF_DEFINITION,
                Some(&args),
                Some(&out),
            )
            .and_then(|()| {
                // The plugin's region, else (its default reply) the
                // frame's, as a host takes the union of the inputs'.
                let mut region = out.doubles(names::EFFECT_REGION_OF_DEFINITION);
                if region.len() != 4 {
                    region = vec![canonical.x1, canonical.y1, canonical.x2, canonical.y2];
                }
                args.set(names::EFFECT_REGION_OF_DEFINITION, Value::Doubles(region));
                let out = PropSet::new();
                self.call(
                    names::ACTION_GET_REGIONS_OF_INTEREST,
                    Some(&args),
                    Some(&out),
                )?;
                let output_clip = self.clip(names::CLIP_OUTPUT)?;
                output_clip
                    .props
                    .set_str(names::EFFECT_COMPONENTS, &components.to_string_lossy());
                output_clip
                    .props
                    .set(names::IMAGE_PIXEL_ASPECT_RATIO, aspect);
                *output_clip.region.lock().unwrap_or_else(|p| p.into_inner()) = canonical;
                let output = lend(output);
                output_clip
                    .frames
                    .lock()
                    .unwrap_or_else(|p| p.into_inner())
                    .insert(key, output.clone());
                args.set_str(names::EFFECT_FIELD_TO_RENDER, "OfxImageFieldNone");
                args.set(
                    names::EFFECT_RENDER_WINDOW,
                    Value::Ints(vec![0, 0, w as c_int, h as c_int]),
                );
                let rendered = self.call(names::ACTION_RENDER, Some(&args), None);
                output_clip
                    .frames
                    .lock()
                    .unwrap_or_else(|p| p.into_inner())
                    .remove(&key);
                rendered?;
                Ok(take(&output))
            });
        source_clip
            .frames
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .remove(&key);
        outcome.map(|output| (take(&lent_source), output))
    }

    fn clip(&self, name: &CStr) -> Result<&effect::Clip, Refusal> {
        // SAFETY: the clip lives with the instance.
        self.effect
            .clip(name)
            .map(|c| unsafe { &*c })
            .ok_or_else(|| {
                refused(
                    &format!("no clip {}", name.to_string_lossy()),
                    abi::STAT_ERR_UNKNOWN,
                )
            })
    }
}

impl Drop for Instance<'_> {
    fn drop(&mut self) {
        // SAFETY: the instance the host made, destroyed once.
        unsafe {
            self.plugin
                .action(names::ACTION_DESTROY_INSTANCE, self.handle(), None, None)
        };
    }
}
