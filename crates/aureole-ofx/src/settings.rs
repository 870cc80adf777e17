//! The parameters' values at a frame's time, and the camera they make:
//! the preset, the config file and the controls composed as the command
//! line composes `--preset` and `--config`.

use std::ffi::{c_char, c_int, CStr, CString};
use std::path::PathBuf;

use aureole::{ApplyOptions, Config, ConfigFile, Device};

use crate::abi::{self, Handle, OfxTime};
use crate::describe::{self, param};
use crate::host::{Failure, Result, Suites};

/// What the plugin writes to its output.
#[derive(Debug, Clone, PartialEq)]
pub enum Output {
    /// The image with its glare.
    Image,
    /// The light that moved (output − input).
    GlareOnly,
    /// One layer, as `aureole apply --layers` names it.
    Layer(String),
}

/// The camera controls, when they set the camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Controls {
    pub sensor_width_mm: f64,
    pub focal_length_mm: f64,
    pub f_number: f64,
}

/// Every parameter's value at one time.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    pub preset: Option<&'static str>,
    pub config: Option<PathBuf>,
    pub controls: Option<Controls>,
    /// The effects the controls set, by type.
    pub effects: crate::effects::Overrides,
    pub threshold: Option<f64>,
    pub knee: f64,
    pub input_scale: f64,
    pub output: Output,
    pub device: Device,
}

/// Reads parameters of one effect instance.
struct Reader<'a> {
    params: Handle,
    suites: &'a Suites,
    time: OfxTime,
}

impl Reader<'_> {
    fn handle(&self, name: &str) -> Result<Handle> {
        let cname = CString::new(name).unwrap_or_default();
        let mut handle = std::ptr::null_mut();
        // SAFETY: the suite's contract.
        let status = unsafe {
            (self.suites.parameter.param_get_handle)(
                self.params,
                cname.as_ptr(),
                &mut handle,
                std::ptr::null_mut(),
            )
        };
        if status != abi::STAT_OK || handle.is_null() {
            return Err(Failure::status(
                if status == abi::STAT_OK {
                    abi::STAT_ERR_BAD_HANDLE
                } else {
                    status
                },
                format!("the host has no parameter {name}"),
            ));
        }
        Ok(handle)
    }

    /// Reads one value of the C type `T` into `value`.
    fn value<T>(&self, name: &str, value: &mut T) -> Result<()> {
        let handle = self.handle(name)?;
        // SAFETY: the parameter's type says what the variadic pointer
        // points to: f64 for doubles, int for integers, booleans and
        // choices, char* for strings.
        let status = unsafe {
            (self.suites.parameter.param_get_value_at_time)(handle, self.time, value as *mut T)
        };
        if status != abi::STAT_OK {
            return Err(Failure::status(status, format!("the value of {name}")));
        }
        Ok(())
    }

    fn double(&self, name: &str) -> Result<f64> {
        let mut v = 0.0f64;
        self.value(name, &mut v).map(|()| v)
    }

    fn int(&self, name: &str) -> Result<c_int> {
        let mut v: c_int = 0;
        self.value(name, &mut v).map(|()| v)
    }

    fn string(&self, name: &str) -> Result<String> {
        let mut v: *const c_char = std::ptr::null();
        self.value(name, &mut v)?;
        if v.is_null() {
            return Ok(String::new());
        }
        // SAFETY: the host's string, valid until its next call.
        Ok(unsafe { CStr::from_ptr(v) }.to_string_lossy().into_owned())
    }

    fn choice<'o>(&self, name: &str, options: &[&'o str]) -> Result<&'o str> {
        let index = self.int(name)?;
        usize::try_from(index)
            .ok()
            .and_then(|i| options.get(i).copied())
            .ok_or_else(|| {
                Failure::said(format!(
                    "aureole: {name} = {index}: allowed 0 to {}",
                    options.len() - 1
                ))
            })
    }
}

impl Settings {
    /// The values of `effect`'s parameters at `time`.
    pub fn read(effect: Handle, suites: &Suites, time: OfxTime) -> Result<Settings> {
        let mut params = std::ptr::null_mut();
        // SAFETY: the suite's contract.
        let status = unsafe { (suites.effect.get_param_set)(effect, &mut params) };
        if status != abi::STAT_OK || params.is_null() {
            return Err(Failure::status(
                abi::STAT_ERR_BAD_HANDLE,
                "the effect's parameter set",
            ));
        }
        let r = Reader {
            params,
            suites,
            time,
        };
        let presets = describe::preset_options();
        let preset = Some(r.choice(param::PRESET, &presets)?).filter(|p| *p != describe::NO_PRESET);
        let config = Some(r.string(param::CONFIG)?)
            .filter(|c| !c.trim().is_empty())
            .map(PathBuf::from);
        let controls = if r.int(param::CAMERA_HERE)? != 0 {
            Some(Controls {
                sensor_width_mm: r.double(param::SENSOR_WIDTH)?,
                focal_length_mm: r.double(param::FOCAL_LENGTH)?,
                f_number: r.double(param::F_NUMBER)?,
            })
        } else {
            None
        };
        let effects = crate::effects::read(
            |kind| Ok(r.int(kind)? != 0),
            |name, p| {
                use aureole::schema::Kind;
                Ok(match p.kind {
                    Kind::Number | Kind::Angle => toml::Value::Float(r.double(name)?),
                    Kind::Whole => toml::Value::Integer(i64::from(r.int(name)?)),
                    Kind::Flag => toml::Value::Boolean(r.int(name)? != 0),
                    Kind::Length | Kind::Text => toml::Value::String(r.string(name)?),
                })
            },
        )?;
        let threshold = Some(r.double(param::THRESHOLD)?).filter(|t| *t >= 0.0);
        let output = match r.choice(param::OUTPUT, &describe::OUTPUTS)? {
            o if o == describe::OUTPUTS[0] => Output::Image,
            o if o == describe::OUTPUTS[1] => Output::GlareOnly,
            _ => Output::Layer(r.string(param::LAYER)?.trim().to_string()),
        };
        let device =
            Device::parse(r.choice(param::DEVICE, &describe::DEVICES)?).unwrap_or(Device::Cpu);
        Ok(Settings {
            preset,
            config,
            controls,
            effects,
            threshold,
            knee: r.double(param::KNEE)?,
            input_scale: r.double(param::INPUT_SCALE)?,
            output,
            device,
        })
    }

    /// The options a frame is applied with.
    pub fn options(&self) -> ApplyOptions {
        ApplyOptions {
            threshold: self.threshold,
            knee: self.knee,
            glare_only: self.output == Output::GlareOnly,
            ..ApplyOptions::default()
        }
    }

    /// The composed camera: the preset, the config file, then the controls.
    pub fn camera(&self) -> Result<ConfigFile> {
        let mut file = ConfigFile::default();
        if let Some(name) = self.preset {
            file = file.then(
                aureole::presets::find(name)
                    .and_then(|p| p.config())
                    .map_err(Failure::library)?,
            );
        }
        if let Some(path) = &self.config {
            let mut loaded = ConfigFile::load(path).map_err(Failure::library)?;
            aureole_io::measured::resolve(&mut loaded, aureole_io::atomic::folder_of(path));
            file = file.then(loaded);
        }
        if self.preset.is_none() && self.config.is_none() && self.effects.is_empty() {
            return Err(Failure::said(
                "aureole: no preset, no config file and no effect set here: choose a preset, name a config or set an effect",
            ));
        }
        if let Some(c) = self.controls {
            let text = format!(
                "[camera]\nsensor_width_mm = {:?}\nfocal_length_mm = {:?}\nf_number = {:?}\n",
                c.sensor_width_mm, c.focal_length_mm, c.f_number
            );
            file = file
                .then(ConfigFile::parse(&text, "the camera controls").map_err(Failure::library)?);
        }
        let file = crate::effects::apply(file, &self.effects)?;
        Ok(file)
    }
}

/// The composed `camera` ready to apply: its measured PSFs read.
pub fn ready(camera: ConfigFile) -> Result<Config> {
    let mut config = Config::compose([camera]);
    let limits = aureole_io::limits::Limits::default_for_machine();
    aureole_io::measured::load(&mut config.effects, limits).map_err(Failure::library)?;
    Ok(config)
}
