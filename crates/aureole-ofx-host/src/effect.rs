//! Effects, their clips, parameters and images, and the image effect and
//! parameter suites over them. A descriptor and an instance are both an
//! [`Effect`]; the instance's parameters are made from the descriptor's
//! definitions, at their defaults, as a host loading a new node does.

use std::collections::HashMap;
use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use aureole_ofx_abi::{self as abi, names, Handle, OfxRectD, OfxStatus, OfxTime};

use crate::props::{live, register, unregister, Kind, PropSet, Value};
use crate::Picture;

/// A parameter: its definition's properties and its value.
pub struct Param {
    pub props: Box<PropSet>,
    pub kind: CString,
    pub value: Mutex<Value>,
}

impl Drop for Param {
    fn drop(&mut self) {
        unregister(self as *const Param);
    }
}

/// An effect's parameters, in the order they were defined.
#[derive(Default)]
pub struct ParamSet {
    pub props: Box<PropSet>,
    pub params: Mutex<Vec<(CString, Box<Param>)>>,
}

impl Drop for ParamSet {
    fn drop(&mut self) {
        unregister(self as *const ParamSet);
    }
}

/// A frame the host lends for one time: its pixels and where they lie.
pub struct Lending {
    /// The pixels, top row first, or bottom row first when `bottom_up`.
    pub picture: Picture,
    /// Rows stored bottom row first, handed out with a positive stride (as
    /// Resolve and Nuke lay images); else top first, with a negative one.
    pub bottom_up: bool,
    /// The pixel coordinates of the picture's bottom-left corner.
    pub origin: (c_int, c_int),
    pub render_scale: [f64; 2],
}

/// `picture` with its rows in the other order.
pub fn flipped(mut picture: Picture) -> Picture {
    let row = picture.width * picture.channels;
    let h = picture.height;
    for y in 0..h / 2 {
        let (top, rest) = picture.pixels.split_at_mut((h - 1 - y) * row);
        top[y * row..(y + 1) * row].swap_with_slice(&mut rest[..row]);
    }
    picture
}

/// A clip: its properties, and on an instance the frames it lends.
pub struct Clip {
    pub props: Box<PropSet>,
    /// Frames by time (the source's input, the output's buffers).
    pub frames: Mutex<HashMap<u64, Arc<Mutex<Lending>>>>,
    /// Where the clip is defined, canonical coordinates.
    pub region: Mutex<OfxRectD>,
}

impl Drop for Clip {
    fn drop(&mut self) {
        unregister(self as *const Clip);
    }
}

/// An image handed to the plugin: a property set over a lent frame.
struct Lent {
    props: Box<PropSet>,
    _frame: Arc<Mutex<Lending>>,
}

/// Images the plugin holds, by their property set's address.
static LENT: Mutex<Vec<(usize, Lent)>> = Mutex::new(Vec::new());

/// An effect descriptor or instance.
pub struct Effect {
    pub props: Box<PropSet>,
    pub params: Box<ParamSet>,
    pub clips: Mutex<Vec<(CString, Box<Clip>)>>,
    /// Set by the host to ask a render to stop.
    pub abort: AtomicBool,
    /// What the plugin posted: (type, text).
    pub messages: Mutex<Vec<(String, String)>>,
}

impl Effect {
    /// A new effect whose `kOfxPropType` is `kind`.
    pub fn new(kind: &CStr) -> Box<Effect> {
        let effect = Box::new(Effect {
            props: PropSet::new(),
            params: Box::new(ParamSet {
                props: PropSet::new(),
                params: Mutex::new(Vec::new()),
            }),
            clips: Mutex::new(Vec::new()),
            abort: AtomicBool::new(false),
            messages: Mutex::new(Vec::new()),
        });
        effect
            .props
            .set_str(names::PROP_TYPE, &kind.to_string_lossy());
        register(&*effect, Kind::Effect);
        register(&*effect.params, Kind::ParamSet);
        effect
    }

    pub fn handle(&self) -> Handle {
        (self as *const Effect).cast_mut().cast()
    }

    /// The clip named `name`.
    pub fn clip(&self, name: &CStr) -> Option<*const Clip> {
        let clips = self.clips.lock().unwrap_or_else(|p| p.into_inner());
        clips
            .iter()
            .find(|(n, _)| n.as_c_str() == name)
            .map(|(_, c)| &**c as *const Clip)
    }

    /// The parameter named `name`.
    pub fn param(&self, name: &str) -> Option<*const Param> {
        let params = self.params.params.lock().unwrap_or_else(|p| p.into_inner());
        params
            .iter()
            .find(|(n, _)| n.to_bytes() == name.as_bytes())
            .map(|(_, p)| &**p as *const Param)
    }
}

impl Drop for Effect {
    fn drop(&mut self) {
        unregister(self as *const Effect);
    }
}

/// A new clip with its type set, registered.
pub fn new_clip(name: &CStr) -> Box<Clip> {
    let clip = Box::new(Clip {
        props: PropSet::new(),
        frames: Mutex::new(HashMap::new()),
        region: Mutex::new(OfxRectD::default()),
    });
    clip.props
        .set_str(names::PROP_TYPE, &names::TYPE_CLIP.to_string_lossy());
    clip.props
        .set_str(names::PROP_NAME, &name.to_string_lossy());
    register(&*clip, Kind::Clip);
    clip
}

/// A new parameter of type `kind` named `name`, registered.
pub fn new_param(kind: &CStr, name: &CStr) -> Box<Param> {
    let param = Box::new(Param {
        props: PropSet::new(),
        kind: kind.to_owned(),
        value: Mutex::new(Value::Ints(vec![0])),
    });
    param
        .props
        .set_str(names::PROP_TYPE, &names::TYPE_PARAMETER.to_string_lossy());
    param
        .props
        .set_str(names::PROP_NAME, &name.to_string_lossy());
    register(&*param, Kind::Param);
    param
}

/// Writes `handle` to `out` when the plugin gave somewhere to write it.
///
/// # Safety
/// `out` is null or points to a writable handle.
unsafe fn give(out: *mut Handle, handle: Handle) {
    if !out.is_null() {
        // SAFETY: the caller's pointer, checked non-null.
        unsafe { out.write(handle) };
    }
}

/// A C string argument, or None when null.
///
/// # Safety
/// `s` is null or a C string.
unsafe fn text<'a>(s: *const c_char) -> Option<&'a CStr> {
    // SAFETY: the caller's contract.
    (!s.is_null()).then(|| unsafe { CStr::from_ptr(s) })
}

unsafe extern "C" fn get_property_set(effect: Handle, out: *mut Handle) -> OfxStatus {
    let Some(effect) = live::<Effect>(effect, Kind::Effect) else {
        return abi::STAT_ERR_BAD_HANDLE;
    };
    // SAFETY: the plugin's out pointer.
    unsafe { give(out, effect.props.handle()) };
    abi::STAT_OK
}

unsafe extern "C" fn get_param_set(effect: Handle, out: *mut Handle) -> OfxStatus {
    let Some(effect) = live::<Effect>(effect, Kind::Effect) else {
        return abi::STAT_ERR_BAD_HANDLE;
    };
    // SAFETY: the plugin's out pointer.
    unsafe { give(out, (&*effect.params as *const ParamSet).cast_mut().cast()) };
    abi::STAT_OK
}

unsafe extern "C" fn clip_define(
    effect: Handle,
    name: *const c_char,
    out: *mut Handle,
) -> OfxStatus {
    let Some(effect) = live::<Effect>(effect, Kind::Effect) else {
        return abi::STAT_ERR_BAD_HANDLE;
    };
    // SAFETY: the plugin's C string.
    let Some(name) = (unsafe { text(name) }) else {
        return abi::STAT_ERR_VALUE;
    };
    if effect.clip(name).is_some() {
        return abi::STAT_ERR_EXISTS;
    }
    let clip = new_clip(name);
    let props = clip.props.handle();
    effect
        .clips
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .push((name.to_owned(), clip));
    // SAFETY: the plugin's out pointer.
    unsafe { give(out, props) };
    abi::STAT_OK
}

unsafe extern "C" fn clip_get_handle(
    effect: Handle,
    name: *const c_char,
    out: *mut Handle,
    props: *mut Handle,
) -> OfxStatus {
    let Some(effect) = live::<Effect>(effect, Kind::Effect) else {
        return abi::STAT_ERR_BAD_HANDLE;
    };
    // SAFETY: the plugin's C string.
    let Some(clip) = unsafe { text(name) }.and_then(|n| effect.clip(n)) else {
        return abi::STAT_ERR_UNKNOWN;
    };
    // SAFETY: the plugin's out pointers; the clip lives with its effect.
    unsafe {
        give(out, clip.cast_mut().cast());
        give(props, (*clip).props.handle());
    }
    abi::STAT_OK
}

unsafe extern "C" fn clip_get_property_set(clip: Handle, out: *mut Handle) -> OfxStatus {
    let Some(clip) = live::<Clip>(clip, Kind::Clip) else {
        return abi::STAT_ERR_BAD_HANDLE;
    };
    // SAFETY: the plugin's out pointer.
    unsafe { give(out, clip.props.handle()) };
    abi::STAT_OK
}

/// The image's properties over `frame`, its rows bottom-up as OpenFX lays
/// them (or top-down with a negative row stride, as some hosts do).
fn image_props(frame: &Mutex<Lending>, clip: &Clip) -> Box<PropSet> {
    let mut lending = frame.lock().unwrap_or_else(|p| p.into_inner());
    let (x0, y0) = lending.origin;
    let scale = lending.render_scale;
    let bottom_up = lending.bottom_up;
    let picture = &mut lending.picture;
    let (w, h, n) = (picture.width, picture.height, picture.channels);
    let stride = (w * n * 4) as c_int;
    let props = PropSet::new();
    props.set_str(names::PROP_TYPE, &names::TYPE_IMAGE.to_string_lossy());
    props.set_str(
        names::EFFECT_PIXEL_DEPTH,
        &names::BIT_DEPTH_FLOAT.to_string_lossy(),
    );
    let components = if n == 4 {
        names::COMPONENT_RGBA
    } else {
        names::COMPONENT_RGB
    };
    props.set_str(names::EFFECT_COMPONENTS, &components.to_string_lossy());
    props.set(
        names::IMAGE_BOUNDS,
        Value::Ints(vec![x0, y0, x0 + w as c_int, y0 + h as c_int]),
    );
    // The data pointer is the bottom row's, wherever the rows run.
    let (bottom, stride) = if bottom_up {
        (picture.pixels.as_mut_ptr(), stride)
    } else {
        let last = w * n * h.saturating_sub(1);
        (picture.pixels.as_mut_ptr().wrapping_add(last), -stride)
    };
    props.set(names::IMAGE_DATA, Value::Pointers(vec![bottom as usize]));
    props.set(names::IMAGE_ROW_BYTES, Value::Ints(vec![stride]));
    let aspect = clip.props.doubles(names::IMAGE_PIXEL_ASPECT_RATIO);
    props.set(
        names::IMAGE_PIXEL_ASPECT_RATIO,
        Value::Doubles(vec![aspect.first().copied().unwrap_or(1.0)]),
    );
    props.set(names::EFFECT_RENDER_SCALE, Value::Doubles(scale.to_vec()));
    props.set_str(names::IMAGE_FIELD, "OfxImageFieldNone");
    props
}

unsafe extern "C" fn clip_get_image(
    clip: Handle,
    time: OfxTime,
    _region: *const OfxRectD,
    out: *mut Handle,
) -> OfxStatus {
    let Some(clip) = live::<Clip>(clip, Kind::Clip) else {
        return abi::STAT_ERR_BAD_HANDLE;
    };
    if out.is_null() {
        return abi::STAT_ERR_VALUE;
    }
    let frame = clip
        .frames
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .get(&time.to_bits())
        .cloned();
    let Some(frame) = frame else {
        return abi::STAT_FAILED;
    };
    let props = image_props(&frame, clip);
    let handle = props.handle();
    LENT.lock().unwrap_or_else(|p| p.into_inner()).push((
        handle as usize,
        Lent {
            props,
            _frame: frame,
        },
    ));
    // SAFETY: the plugin's out pointer, checked non-null.
    unsafe { out.write(handle) };
    abi::STAT_OK
}

unsafe extern "C" fn clip_release_image(image: Handle) -> OfxStatus {
    let mut lent = LENT.lock().unwrap_or_else(|p| p.into_inner());
    match lent.iter().position(|(h, _)| *h == image as usize) {
        Some(i) => {
            drop(lent.swap_remove(i).1.props);
            abi::STAT_OK
        }
        None => abi::STAT_ERR_BAD_HANDLE,
    }
}

/// How many images the plugin holds and has not released.
pub fn images_held() -> usize {
    LENT.lock().unwrap_or_else(|p| p.into_inner()).len()
}

unsafe extern "C" fn clip_get_region_of_definition(
    clip: Handle,
    _time: OfxTime,
    out: *mut OfxRectD,
) -> OfxStatus {
    let Some(clip) = live::<Clip>(clip, Kind::Clip) else {
        return abi::STAT_ERR_BAD_HANDLE;
    };
    if out.is_null() {
        return abi::STAT_ERR_VALUE;
    }
    // An input not connected has no region.
    if clip.props.ints(names::CLIP_CONNECTED).first() == Some(&0) {
        return abi::STAT_FAILED;
    }
    // SAFETY: the plugin's out pointer, checked non-null.
    unsafe { out.write(*clip.region.lock().unwrap_or_else(|p| p.into_inner())) };
    abi::STAT_OK
}

unsafe extern "C" fn abort(effect: Handle) -> c_int {
    live::<Effect>(effect, Kind::Effect).is_some_and(|e| e.abort.load(Ordering::Relaxed)) as c_int
}

unsafe extern "C" fn image_memory_alloc(
    _effect: Handle,
    bytes: usize,
    out: *mut Handle,
) -> OfxStatus {
    crate::services::alloc(bytes, out.cast())
}

unsafe extern "C" fn image_memory_free(memory: Handle) -> OfxStatus {
    crate::services::free(memory)
}

/// Image memory is host memory that stays where it is: locking gives its
/// address.
unsafe extern "C" fn image_memory_lock(memory: Handle, out: *mut *mut c_void) -> OfxStatus {
    if live::<u8>(memory, Kind::Memory).is_none() || out.is_null() {
        return abi::STAT_ERR_BAD_HANDLE;
    }
    // SAFETY: the plugin's out pointer, checked non-null.
    unsafe { out.write(memory) };
    abi::STAT_OK
}

unsafe extern "C" fn image_memory_unlock(memory: Handle) -> OfxStatus {
    match live::<u8>(memory, Kind::Memory) {
        Some(_) => abi::STAT_OK,
        None => abi::STAT_ERR_BAD_HANDLE,
    }
}

pub static IMAGE_EFFECT_SUITE: abi::OfxImageEffectSuiteV1 = abi::OfxImageEffectSuiteV1 {
    get_property_set,
    get_param_set,
    clip_define,
    clip_get_handle,
    clip_get_property_set,
    clip_get_image,
    clip_release_image,
    clip_get_region_of_definition,
    abort,
    image_memory_alloc,
    image_memory_free,
    image_memory_lock,
    image_memory_unlock,
};
