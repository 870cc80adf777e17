//! The render action and the regions a host asks about: the whole source
//! frame in (glare needs all of it), the source's region out, the frame
//! spread by the instance's camera at the host's render scale.

use std::ffi::{c_int, CStr};

use aureole::{Cancel, DisplayWindow, Frame, FrameOptions, Image, Layout, Stage};

use crate::abi::{self, names, Handle, OfxRectD, OfxRectI, OfxStatus};
use crate::host::{self, Failure, Props, Result, Suites};
use crate::instance::{self, Instance, Kept};
use crate::settings::{self, Output, Settings};

/// A clip of the instance `effect` by name.
fn clip(effect: Handle, name: &CStr, suites: &Suites) -> Result<Handle> {
    let mut handle = std::ptr::null_mut();
    // SAFETY: the suite's contract.
    let status = unsafe {
        (suites.effect.clip_get_handle)(effect, name.as_ptr(), &mut handle, std::ptr::null_mut())
    };
    if status != abi::STAT_OK || handle.is_null() {
        return Err(Failure::status(
            abi::STAT_ERR_BAD_HANDLE,
            format!("the host has no clip {}", name.to_string_lossy()),
        ));
    }
    Ok(handle)
}

/// The source clip's region of definition at `time`.
fn source_region(effect: Handle, time: f64, suites: &Suites) -> Result<OfxRectD> {
    let source = clip(effect, names::CLIP_SOURCE, suites)?;
    let mut region = OfxRectD::default();
    // SAFETY: the suite's contract.
    let status =
        unsafe { (suites.effect.clip_get_region_of_definition)(source, time, &mut region) };
    if status != abi::STAT_OK {
        return Err(Failure::status(status, "the source's region of definition"));
    }
    Ok(region)
}

/// The source's region of definition at the time `in_args` name, set as
/// `property` of `out_args`: the effect's own region of definition
/// (`kOfxImageEffectActionGetRegionOfDefinition`), and the region of
/// interest on the source (`kOfxImageEffectActionGetRegionsOfInterest`),
/// whatever part of the output is asked for: a lamp anywhere lights every
/// pixel. With no source connected, the host's default is the answer.
pub fn whole_source(
    effect: Handle,
    (in_args, out_args): (Handle, Handle),
    property: &CStr,
    suites: &Suites,
) -> Result<OfxStatus> {
    let time = Props::new(in_args, suites)?.double(names::PROP_TIME, 0)?;
    let out = Props::new(out_args, suites)?;
    let Ok(r) = source_region(effect, time, suites) else {
        return Ok(abi::STAT_REPLY_DEFAULT);
    };
    out.set_doubles(property, &[r.x1, r.y1, r.x2, r.y2])?;
    Ok(abi::STAT_OK)
}

/// An image the host lent: released when dropped.
struct Lent {
    handle: Handle,
    suites: Suites,
    data: *mut u8,
    bounds: OfxRectI,
    row_bytes: isize,
    components: usize,
    aspect: f64,
}

impl Drop for Lent {
    fn drop(&mut self) {
        // SAFETY: fetched by clipGetImage, released once.
        unsafe { (self.suites.effect.clip_release_image)(self.handle) };
    }
}

impl Lent {
    /// The clip `name`'s image at `time`; None where the host has none
    /// (an input not connected, which OpenFX says to take as black).
    fn fetch(effect: Handle, name: &CStr, time: f64, suites: &Suites) -> Result<Option<Lent>> {
        let clip = clip(effect, name, suites)?;
        let mut handle = std::ptr::null_mut();
        // SAFETY: the suite's contract; a null region asks for the RoI.
        let status =
            unsafe { (suites.effect.clip_get_image)(clip, time, std::ptr::null(), &mut handle) };
        if status != abi::STAT_OK || handle.is_null() {
            return Ok(None);
        }
        let props = Props::new(handle, suites)?;
        // From here the image is ours to release, whatever else fails.
        let mut lent = Lent {
            handle,
            suites: *suites,
            data: std::ptr::null_mut(),
            bounds: OfxRectI::default(),
            row_bytes: 0,
            components: 0,
            aspect: 1.0,
        };
        let depth = props.string(names::EFFECT_PIXEL_DEPTH, 0)?;
        if depth != names::BIT_DEPTH_FLOAT.to_string_lossy() {
            return Err(Failure::status(
                abi::STAT_ERR_IMAGE_FORMAT,
                format!("aureole: {depth} images: aureole takes 32-bit float light"),
            ));
        }
        let components = props.string(names::EFFECT_COMPONENTS, 0)?;
        lent.components = match components.as_str() {
            c if c == names::COMPONENT_RGBA.to_string_lossy() => 4,
            c if c == names::COMPONENT_RGB.to_string_lossy() => 3,
            other => {
                return Err(Failure::status(
                    abi::STAT_ERR_IMAGE_FORMAT,
                    format!("aureole: {other} images: aureole takes RGBA or RGB"),
                ))
            }
        };
        let [x1, y1, x2, y2] = props.ints::<4>(names::IMAGE_BOUNDS)?;
        lent.bounds = OfxRectI { x1, y1, x2, y2 };
        lent.row_bytes = props.int(names::IMAGE_ROW_BYTES, 0)? as isize;
        lent.data = props.pointer(names::IMAGE_DATA, 0)?.cast();
        lent.aspect = props
            .double(names::IMAGE_PIXEL_ASPECT_RATIO, 0)
            .unwrap_or(1.0);
        let (w, h) = (lent.width(), lent.height());
        let least = (w * lent.components * 4) as isize;
        if lent.data.is_null() || (w * h > 0 && lent.row_bytes.abs() < least) {
            return Err(Failure::status(
                abi::STAT_ERR_VALUE,
                format!(
                    "aureole: the host's {} image has no data or rows shorter than its bounds",
                    name.to_string_lossy()
                ),
            ));
        }
        Ok(Some(lent))
    }

    fn width(&self) -> usize {
        usize::try_from(self.bounds.x2.saturating_sub(self.bounds.x1)).unwrap_or(0)
    }

    fn height(&self) -> usize {
        usize::try_from(self.bounds.y2.saturating_sub(self.bounds.y1)).unwrap_or(0)
    }

    /// The pixels of the row at `y` (host coordinates, y up).
    fn row(&self, y: c_int) -> *mut f32 {
        let offset = (y - self.bounds.y1) as isize * self.row_bytes;
        // SAFETY: y lies within the bounds, whose rows the host allocated.
        unsafe { self.data.offset(offset).cast::<f32>() }
    }

    /// The image as the library holds it: top row first, planes apart.
    fn to_image(&self) -> Image {
        let (w, h, n) = (self.width(), self.height(), self.components);
        let mut image = Image::filled(w, h, Layout::Rgb, 0.0);
        let mut alpha = (n == 4).then(|| vec![0.0f32; w * h]);
        for r in 0..h {
            // SAFETY: a row of w pixels of n floats, within the bounds.
            let row = unsafe {
                std::slice::from_raw_parts(self.row(self.bounds.y2 - 1 - r as c_int), w * n)
            };
            for (x, pixel) in row.chunks_exact(n).enumerate() {
                for (c, plane) in image.planes.iter_mut().enumerate() {
                    plane[r * w + x] = pixel[c];
                }
                if let Some(alpha) = &mut alpha {
                    alpha[r * w + x] = pixel[3];
                }
            }
        }
        image.alpha = alpha;
        image
    }
}

/// Where the project's frame lies in the frame the camera sees (the
/// source's `bounds` in square pixels, `squeeze` canonical units per
/// source pixel across), in the library's rows (top first): the optical
/// axis is its centre. None when the host does not say, or it is the
/// whole frame.
fn display_window(
    effect: Handle,
    (bounds, squeeze): (OfxRectI, f64),
    (width, height): (usize, usize),
    scale: [f64; 2],
    suites: &Suites,
) -> Option<DisplayWindow> {
    let props = host::effect_props(effect, suites).ok()?;
    let [ox, oy] = props.doubles::<2>(names::EFFECT_PROJECT_OFFSET).ok()?;
    let [sw, sh] = props.doubles::<2>(names::EFFECT_PROJECT_SIZE).ok()?;
    // Canonical units are square pixels of the full-size frame.
    let px = |v: f64, s: f64| libm::round(v * s) as i64;
    let (x, top) = (px(ox, scale[0]), px(oy + sh, scale[1]));
    let window = DisplayWindow {
        x: x - px(f64::from(bounds.x1), squeeze),
        y: i64::from(bounds.y2) - top,
        width: usize::try_from(px(sw, scale[0])).ok().filter(|w| *w > 0)?,
        height: usize::try_from(px(sh, scale[1])).ok().filter(|h| *h > 0)?,
    };
    (window != DisplayWindow::whole(width, height)).then_some(window)
}

/// `kOfxImageEffectActionRender`.
pub fn render(effect: Handle, in_args: Handle, suites: &Suites) -> Result<()> {
    let instance = Instance::of(effect, suites)?;
    let args = Props::new(in_args, suites)?;
    let time = args.double(names::PROP_TIME, 0)?;
    let scale = args.doubles::<2>(names::EFFECT_RENDER_SCALE)?;
    let [x1, y1, x2, y2] = args.ints::<4>(names::EFFECT_RENDER_WINDOW)?;
    let window = OfxRectI { x1, y1, x2, y2 };
    if !scale.iter().all(|s| s.is_finite() && *s > 0.0) {
        return Err(Failure::status(
            abi::STAT_ERR_VALUE,
            format!("aureole: render scale {scale:?}"),
        ));
    }
    let mut settings = Settings::read(effect, suites, time)?;
    let Some(source) = Lent::fetch(effect, names::CLIP_SOURCE, time, suites)? else {
        // No input: black and transparent, as the host takes a missing image.
        let empty = Image::filled(0, 0, Layout::Rgb, 0.0);
        return write(
            &output(effect, time, suites)?,
            (&empty, OfxRectI::default()),
            window,
        );
    };
    // Light spreads alike in every direction on the sensor: a squeezed
    // plate (pixels `squeeze` times as wide as high) is desqueezed by area
    // for the camera, and only the glare is squeezed back onto it.
    let squeeze = source.aspect;
    if !(squeeze.is_finite() && (0.01..=100.0).contains(&squeeze)) {
        return Err(Failure::status(
            abi::STAT_ERR_VALUE,
            format!("aureole: pixel aspect ratio {squeeze}"),
        ));
    }
    let image = source.to_image();
    let (width, height) = (image.width, image.height);
    let with_image = settings.output == Output::Image;
    let (image, original) = if (squeeze - 1.0).abs() > 1e-9 {
        let square = (libm::round(width as f64 * squeeze) as usize).max(1);
        if with_image {
            settings.output = Output::GlareOnly;
        }
        (image.resampled(square, height), Some(image))
    } else {
        (image, None)
    };
    let square = (image.width, image.height);
    let mut frame = Frame::new(
        image,
        &FrameOptions {
            input_scale: Some(settings.input_scale),
            sanitize: false,
        },
    )
    .map_err(Failure::library)?;
    let bounds = source.bounds;
    if let Some(window) = display_window(effect, (bounds, squeeze), square, scale, suites) {
        frame = frame.with_display_window(window);
    }
    drop(source);
    let mut result = spread(effect, instance, &settings, &frame, scale[0], suites)?;
    drop(frame);
    if let Some(original) = original {
        result = squeezed(&result, original, with_image);
    }
    write(&output(effect, time, suites)?, (&result, bounds), window)?;
    // The next frame's result is written into these planes.
    instance.recycle(result);
    Ok(())
}

/// The output image the host lends for `time`.
fn output(effect: Handle, time: f64, suites: &Suites) -> Result<Lent> {
    Lent::fetch(effect, names::CLIP_OUTPUT, time, suites)?.ok_or_else(|| {
        Failure::said(format!(
            "aureole: the host gave no Output image at time {time}"
        ))
    })
}

/// The frame spread by the instance's camera, at render scale `scale`.
fn spread(
    effect: Handle,
    instance: &Instance,
    settings: &Settings,
    frame: &Frame,
    scale: f64,
    suites: &Suites,
) -> Result<Image> {
    let said = |e: aureole::Error| match e {
        aureole::Error::Cancelled => Failure {
            status: abi::STAT_FAILED,
            message: None,
        },
        other => Failure::library(other),
    };
    let camera = settings.camera()?;
    let key = format!("{}\n{:?}\n{scale}", camera.to_toml(), settings.device);
    let mut kept = instance.kept.lock().unwrap_or_else(|p| p.into_inner());
    if kept.as_ref().is_none_or(|k| k.key != key) {
        *kept = None;
        let config = settings::ready(camera)?.with_pixels_scaled(scale);
        *kept = Some(Kept {
            key,
            session: instance::session(config, settings.device),
        });
    }
    let Some(Kept { session, .. }) = kept.as_mut() else {
        return Err(Failure::said("aureole: no session"));
    };
    let cancel = Cancel::new();
    session.set_cancel_token(cancel.clone());
    if host::aborted(effect, suites) {
        return Err(said(aureole::Error::Cancelled));
    }
    // The host's abort flag is read on the render's own thread, between
    // the library's steps.
    let mut progress = |_: Stage, _: f64| {
        if !cancel.is_cancelled() && host::aborted(effect, suites) {
            cancel.cancel();
        }
    };
    let options = settings.options();
    match &settings.output {
        Output::Layer(name) if name != "glare" => {
            let (_, layers) = session
                .apply_layers(frame, &options, &mut progress)
                .map_err(said)?;
            let names: Vec<&str> = layers.iter().map(|l| l.name.as_str()).collect();
            let found = layers.iter().position(|l| &l.name == name).ok_or_else(|| {
                Failure::said(format!(
                    "aureole: layer {name:?}: this camera's layers are {}",
                    names.join(", ")
                ))
            })?;
            let mut layer = layers
                .into_iter()
                .nth(found)
                .map(|l| l.image)
                .unwrap_or_else(|| frame.image().clone());
            layer.alpha = frame.image().alpha.clone();
            Ok(layer)
        }
        Output::Layer(_) => {
            let options = aureole::ApplyOptions {
                glare_only: true,
                ..options
            };
            Ok(session
                .apply(frame, &options, &mut progress)
                .map_err(said)?
                .image)
        }
        Output::Image | Output::GlareOnly => Ok(session
            .apply(frame, &options, &mut progress)
            .map_err(said)?
            .image),
    }
}

/// The desqueezed frame's glare `glare` squeezed back onto `original`'s
/// pixels by area, added to them when `with_image`; alpha is the
/// original's.
fn squeezed(glare: &Image, original: Image, with_image: bool) -> Image {
    let mut back = glare.resampled(original.width, original.height);
    if with_image {
        for (plane, light) in back.planes.iter_mut().zip(&original.planes) {
            plane.iter_mut().zip(light).for_each(|(g, l)| *g += l);
        }
    }
    back.alpha = original.alpha;
    back
}

/// Writes `result` (the pixels of the source's `bounds`, top row first)
/// into the output within the render window; what lies outside the
/// source is black.
fn write(output: &Lent, (result, bounds): (&Image, OfxRectI), window: OfxRectI) -> Result<()> {
    let (w, h) = (result.width as c_int, result.height as c_int);
    let n = output.components;
    let x1 = window.x1.max(output.bounds.x1);
    let x2 = window.x2.min(output.bounds.x2);
    let y1 = window.y1.max(output.bounds.y1);
    let y2 = window.y2.min(output.bounds.y2);
    // The host's pixel (x, y) is the result's column x - x0, row y_top - y.
    let (x0, y_top) = (bounds.x1, bounds.y2 - 1);
    for y in y1..y2 {
        let pixels = (x2 - x1).max(0) as usize * n;
        // SAFETY: x1..x2 and y lie within the output's bounds.
        let row = unsafe {
            std::slice::from_raw_parts_mut(
                output.row(y).add((x1 - output.bounds.x1) as usize * n),
                pixels,
            )
        };
        let r = y_top - y;
        for (i, pixel) in row.chunks_exact_mut(n).enumerate() {
            let x = x1 + i as c_int - x0;
            let inside = (0..w).contains(&x) && (0..h).contains(&r);
            let at = (r * w + x) as usize;
            for (c, value) in pixel.iter_mut().enumerate() {
                *value = match (inside, c) {
                    (false, _) => 0.0,
                    (true, 3) => result.alpha.as_ref().map_or(1.0, |a| a[at]),
                    (true, c) => result.planes[c.min(result.planes.len() - 1)][at],
                };
            }
        }
    }
    Ok(())
}
