//! What the plugin tells a host it is (`kOfxActionDescribe`) and what it
//! needs in each context (`kOfxImageEffectActionDescribeInContext`): its
//! clips and its parameters. The camera's and every effect's parameters
//! are the library's schema, as the studio's panels show them.

use std::ffi::{c_int, CStr, CString};

use aureole::schema::{Parameter, CAMERA};

use crate::abi::{names, Handle};
use crate::host::{effect_props, Failure, Props, Result, Suites};

/// The parameters' names, as the host stores them in a project.
pub mod param {
    pub const PRESET: &str = "preset";
    pub const CONFIG: &str = "config";
    pub const CAMERA_HERE: &str = "camera_here";
    pub const SENSOR_WIDTH: &str = "sensor_width_mm";
    pub const FOCAL_LENGTH: &str = "focal_length_mm";
    pub const F_NUMBER: &str = "f_number";
    pub const THRESHOLD: &str = "threshold";
    pub const KNEE: &str = "knee";
    pub const INPUT_SCALE: &str = "input_scale";
    pub const OUTPUT: &str = "output";
    pub const LAYER: &str = "layer";
    pub const DEVICE: &str = "device";
}

/// The first choice of the preset menu: the config file alone.
pub const NO_PRESET: &str = "none (the config file alone)";
/// The output menu, in order.
pub const OUTPUTS: [&str; 3] = ["image with glare", "glare only", "one glare layer"];
/// The device menu, in order.
pub const DEVICES: [&str; 3] = ["cpu", "gpu", "auto"];
/// The camera the controls start from when they set it.
pub const CAMERA_DEFAULTS: [f64; 3] = [36.0, 50.0, 8.0];

/// `kOfxActionDescribe`: the plugin's label, grouping, contexts, pixel
/// depths and threading.
pub fn describe(effect: Handle, suites: &Suites) -> Result<()> {
    let props = effect_props(effect, suites)?;
    props.set_string(names::PROP_LABEL, 0, "aureole glare")?;
    props.set_string(names::EFFECT_GROUPING, 0, "aureole")?;
    props.set_string(
        names::PROP_PLUGIN_DESCRIPTION,
        0,
        "Bloom, corona, lens ghosts and the eye's glare, computed from the lens's \
         physics on scene-linear light (cd/m² per unit set by the input scale).",
    )?;
    props.set_strings(
        names::EFFECT_SUPPORTED_CONTEXTS,
        &[names::CONTEXT_FILTER, names::CONTEXT_GENERAL],
    )?;
    props.set_strings(
        names::EFFECT_SUPPORTED_PIXEL_DEPTHS,
        &[names::BIT_DEPTH_FLOAT],
    )?;
    // Glare needs the whole frame: no tiles; a proxy is a smaller frame at
    // a larger pitch, which the camera's lengths on the sensor follow.
    props.set_int(names::EFFECT_SUPPORTS_TILES, 0, 0)?;
    props.set_int(names::EFFECT_SUPPORTS_MULTI_RESOLUTION, 0, 1)?;
    props.set_string(
        names::EFFECT_RENDER_THREAD_SAFETY,
        0,
        &names::RENDER_FULLY_SAFE.to_string_lossy(),
    )?;
    // The library spreads a frame over every core itself.
    props.set_int(names::EFFECT_HOST_FRAME_THREADING, 0, 0)?;
    Ok(())
}

/// `kOfxImageEffectActionDescribeInContext`: the source and output clips
/// (float RGBA or RGB) and the parameters.
pub fn describe_in_context(effect: Handle, in_args: Handle, suites: &Suites) -> Result<()> {
    let context = Props::new(in_args, suites)?.string(names::EFFECT_CONTEXT, 0)?;
    let known = [names::CONTEXT_FILTER, names::CONTEXT_GENERAL]
        .iter()
        .any(|c| c.to_string_lossy() == context);
    if !known {
        return Err(Failure::status(
            crate::abi::STAT_ERR_MISSING_HOST_FEATURE,
            format!("context {context}: aureole works in the filter and general contexts"),
        ));
    }
    for clip in [names::CLIP_SOURCE, names::CLIP_OUTPUT] {
        let mut handle = std::ptr::null_mut();
        // SAFETY: the suite's contract.
        let status = unsafe { (suites.effect.clip_define)(effect, clip.as_ptr(), &mut handle) };
        if status != crate::abi::STAT_OK {
            return Err(Failure::status(status, "the host could not define a clip"));
        }
        let clip = Props::new(handle, suites)?;
        clip.set_strings(
            names::EFFECT_SUPPORTED_COMPONENTS,
            &[names::COMPONENT_RGBA, names::COMPONENT_RGB],
        )?;
        clip.set_int(names::EFFECT_SUPPORTS_TILES, 0, 0)?;
    }
    define_parameters(effect, suites)
}

/// Defines the parameter `name` of type `kind` in `params`, with its
/// label, its line of help and the group it belongs to.
fn define(
    (params, suites): (Handle, &Suites),
    kind: &CStr,
    name: &str,
    label: &str,
    hint: String,
    parent: Option<&str>,
) -> Result<Props> {
    let cname = CString::new(name).unwrap_or_default();
    let mut handle = std::ptr::null_mut();
    // SAFETY: the suite's contract.
    let status = unsafe {
        (suites.parameter.param_define)(params, kind.as_ptr(), cname.as_ptr(), &mut handle)
    };
    if status != crate::abi::STAT_OK {
        return Err(Failure::status(
            status,
            format!("the host could not define the parameter {name}"),
        ));
    }
    let props = Props::new(handle, suites)?;
    props.set_string(names::PROP_LABEL, 0, label)?;
    props.set_string(names::PARAM_HINT, 0, &hint)?;
    if let Some(parent) = parent {
        props.set_string(names::PARAM_PARENT, 0, parent)?;
    }
    Ok(props)
}

/// A schema parameter's line for a person, with what is allowed.
pub fn hint(parameter: &Parameter) -> String {
    format!("{} ({})", parameter.about, parameter.allowed)
}

fn schema(parameters: &[Parameter], name: &str) -> Result<Parameter> {
    parameters
        .iter()
        .find(|p| p.name == name)
        .copied()
        .ok_or_else(|| Failure::said(format!("the schema has no parameter {name}")))
}

/// A number control: its default, its allowed range and a slider's range.
pub fn number(props: &Props, default: f64, range: (f64, f64), slider: (f64, f64)) -> Result<()> {
    props.set_double(names::PARAM_DEFAULT, 0, default)?;
    props.set_double(names::PARAM_MIN, 0, range.0)?;
    props.set_double(names::PARAM_MAX, 0, range.1)?;
    props.set_double(names::PARAM_DISPLAY_MIN, 0, slider.0)?;
    props.set_double(names::PARAM_DISPLAY_MAX, 0, slider.1)
}

fn choice(props: &Props, options: &[&str], default: usize) -> Result<()> {
    for (i, option) in options.iter().enumerate() {
        props.set_string(names::PARAM_CHOICE_OPTION, i as c_int, option)?;
    }
    props.set_int(names::PARAM_DEFAULT, 0, default as c_int)
}

/// The preset menu: the config file alone, then every built-in preset.
pub fn preset_options() -> Vec<&'static str> {
    std::iter::once(NO_PRESET)
        .chain(aureole::presets::PRESETS.iter().map(|p| p.name))
        .collect()
}

fn define_parameters(effect: Handle, suites: &Suites) -> Result<()> {
    use crate::abi::names::{PARAM_TYPE_CHOICE as CHOICE, PARAM_TYPE_STRING as STRING};
    let mut params = std::ptr::null_mut();
    // SAFETY: the suite's contract.
    let status = unsafe { (suites.effect.get_param_set)(effect, &mut params) };
    if status != crate::abi::STAT_OK {
        return Err(Failure::status(status, "the effect's parameter set"));
    }
    let d = |kind: &CStr, name: &str, label: &str, hint: String, parent: Option<&str>| {
        define((params, suites), kind, name, label, hint, parent)
    };

    let presets = preset_options();
    let default = presets
        .iter()
        .position(|p| *p == aureole::presets::DEFAULT_PRESET)
        .unwrap_or(0);
    let preset = d(
        CHOICE,
        param::PRESET,
        "Preset",
        "the built-in camera to start from \
        (`aureole presets` describes each); the config file's settings follow it"
            .into(),
        None,
    )?;
    choice(&preset, &presets, default)?;
    let config = d(
        STRING,
        param::CONFIG,
        "Config file",
        "an aureole TOML config \
        (seed, threshold, [camera], [[effect]] …) composed after the preset, as \
        `aureole apply --preset P --config FILE` composes them"
            .into(),
        None,
    )?;
    config.set_string(
        names::PARAM_STRING_MODE,
        0,
        &names::PARAM_STRING_IS_FILE_PATH.to_string_lossy(),
    )?;
    config.set_int(names::PARAM_FILE_PATH_EXISTS, 0, 1)?;
    config.set_string(names::PARAM_DEFAULT, 0, "")?;
    camera_controls(&d)?;
    crate::effects::define(&d)?;
    light_and_output(&d)
}

/// What defines one parameter: its type, name, label, hint and group.
pub type Definer<'a> = dyn Fn(&CStr, &str, &str, String, Option<&str>) -> Result<Props> + 'a;

/// The sensor and the lens, which replace the camera's when on.
fn camera_controls(d: &Definer<'_>) -> Result<()> {
    use crate::abi::names::{
        PARAM_TYPE_BOOLEAN as BOOLEAN, PARAM_TYPE_DOUBLE as DOUBLE, PARAM_TYPE_GROUP as GROUP,
    };
    d(
        GROUP,
        "lens",
        "Camera",
        "the camera these controls set when on".into(),
        None,
    )?;
    let here = d(
        BOOLEAN,
        param::CAMERA_HERE,
        "Set the camera here",
        "on: the sensor \
        and lens below replace the preset's and the config's [camera]"
            .into(),
        Some("lens"),
    )?;
    here.set_int(names::PARAM_DEFAULT, 0, 0)?;
    for (name, default) in [param::SENSOR_WIDTH, param::FOCAL_LENGTH, param::F_NUMBER]
        .into_iter()
        .zip(CAMERA_DEFAULTS)
    {
        let p = schema(CAMERA, name)?;
        let label = format!("{name} {}", p.unit).trim().to_string();
        let props = d(DOUBLE, name, &label, hint(&p), Some("lens"))?;
        let low = p.low.map_or(0.0, |(v, _)| v);
        number(&props, default, (low, 1e4), (low.max(1.0), 4.0 * default))?;
    }
    Ok(())
}

/// The threshold, the input's scale, the output and the device.
fn light_and_output(d: &Definer<'_>) -> Result<()> {
    use crate::abi::names::{
        PARAM_TYPE_CHOICE as CHOICE, PARAM_TYPE_DOUBLE as DOUBLE, PARAM_TYPE_STRING as STRING,
    };
    let threshold = d(
        DOUBLE,
        param::THRESHOLD,
        "Threshold cd/m²",
        "light above it \
        is spread; below 0, the camera's own threshold"
            .into(),
        None,
    )?;
    number(&threshold, -1.0, (-1.0, 1e12), (-1.0, 1e5))?;
    let knee = d(
        DOUBLE,
        param::KNEE,
        "Knee",
        "soft knee above the threshold, \
        relative to it: the spread fraction rises smoothly from T to T·(1 + knee); 0 is \
        the paper's hard threshold (`--knee`)"
            .into(),
        None,
    )?;
    number(&knee, 0.0, (0.0, 1e6), (0.0, 4.0))?;
    let scale = d(
        DOUBLE,
        param::INPUT_SCALE,
        "Input cd/m² per unit",
        "the luminance \
        of the value 1.0 in scene-linear light: the threshold and the ghosts' light \
        are in cd/m²"
            .into(),
        None,
    )?;
    number(&scale, 1.0, (1e-9, 1e9), (0.1, 1000.0))?;
    let output = d(
        CHOICE,
        param::OUTPUT,
        "Output",
        "the image with its glare, the \
        glare alone (the light that moved), or one effect's layer named below"
            .into(),
        None,
    )?;
    choice(&output, &OUTPUTS, 0)?;
    let layer = d(
        STRING,
        param::LAYER,
        "Layer",
        "with \"one glare layer\": glare, or \
        glare.<effect> (glare.bloom, glare.corona, glare.ghosts …), as `aureole apply \
        --layers` names them"
            .into(),
        None,
    )?;
    layer.set_string(names::PARAM_DEFAULT, 0, "glare")?;
    let device = d(
        CHOICE,
        param::DEVICE,
        "Device",
        "where the convolution runs: the \
        processor, the GPU (Vulkan, Metal or DirectX 12), or the GPU when there is one"
            .into(),
        None,
    )?;
    choice(&device, &DEVICES, 0)
}
