//! `aureole.Camera`: a composed configuration, its TOML, and the sessions
//! that keep a plan (kernel and spectra) per image size between calls.

use std::ffi::CString;
use std::path::PathBuf;
use std::sync::Mutex;

use aureole::{ApplyOptions, Cancel, Config, ConfigFile, Control, Extent, Frame, FrameOptions};
use aureole::{Composing, Device, Method, Sending, Session, Stage};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyOSError, PyUserWarning, PyValueError};
use pyo3::prelude::*;

use aureole_io::display::{DisplayOptions, Exposure, ToneCurve};
use aureole_io::formats::Samples;
use aureole_io::limits::{default_memory_limit, Limits};
use aureole_io::read::Choice;
use aureole_io::write::{LinearOptions, WriteOptions};
use pyo3::types::{PyDict, PyDictMethods};
use rayon::prelude::*;

use crate::arrays::{float32, to_array, to_image, ArrayShape};
use crate::run::file_error;
use crate::run::{interruptible, one_line, value_error, Latest};

/// The most sessions a camera keeps: one per thread applying it at once.
const KEPT_SESSIONS: usize = 4;

/// A camera: the optical chain of presets and config files composed in
/// order, as on the command line (later settings replace earlier ones,
/// effects are appended).
#[pyclass(frozen, module = "aureole")]
pub struct Camera {
    config: Config,
    /// What the presets and files composed into it set, for its TOML and
    /// for composing it further.
    file: ConfigFile,
    /// Idle sessions, each holding the plan of the last image size it
    /// applied; a call takes one (or makes one) and puts it back.
    sessions: Mutex<Vec<Session>>,
}

impl Camera {
    fn new(file: ConfigFile) -> Camera {
        Camera {
            config: Config::compose([file.clone()]),
            file,
            sessions: Mutex::new(Vec::new()),
        }
    }

    /// The camera `text` describes; the measured PSFs it names are read
    /// now, relative paths from `folder`.
    fn parse(text: &str, source_name: &str, folder: &std::path::Path) -> PyResult<Camera> {
        let mut file =
            ConfigFile::parse_in(text, source_name, Some(folder)).map_err(value_error)?;
        aureole_io::measured::resolve(&mut file, folder);
        let warnings = aureole_io::measured::load(&mut file.effects, Limits::default_for_machine())
            .map_err(file_error)?;
        Python::attach(|py| {
            warnings.iter().try_for_each(|warning| {
                PyErr::warn(
                    py,
                    &py.get_type::<PyUserWarning>(),
                    &CString::new(warning.as_str())?,
                    1,
                )
            })
        })?;
        Ok(Camera::new(file))
    }

    /// A session for `size` on `device`: an idle one that holds its plan
    /// first.
    fn session(&self, size: (usize, usize), device: Device) -> Session {
        let mut idle = self.sessions.lock().unwrap_or_else(|p| p.into_inner());
        let found = idle
            .iter()
            .position(|s| s.device() == device && s.plan().is_some_and(|p| p.size() == size));
        match found.or_else(|| idle.iter().rposition(|s| s.device() == device)) {
            Some(i) => idle.swap_remove(i),
            None => Session::new(self.config.clone())
                .with_memory_limit(default_memory_limit())
                .with_device(device),
        }
    }

    fn put_back(&self, session: Session) {
        let mut idle = self.sessions.lock().unwrap_or_else(|p| p.into_inner());
        if idle.len() < KEPT_SESSIONS {
            idle.push(session);
        }
    }

    /// `work` with a session for frames of `size`, off the GIL and
    /// interruptible, its stages reported to `progress`; the session is
    /// kept for the next call.
    fn with_session<T: Send>(
        &self,
        py: Python<'_>,
        (size, device): ((usize, usize), Device),
        progress: Option<&Bound<'_, PyAny>>,
        work: impl FnOnce(&mut Session, &mut dyn FnMut(Stage, f64)) -> T + Send,
    ) -> PyResult<T> {
        let mut session = self.session(size, device);
        let cancel = Cancel::new();
        session.set_cancel_token(cancel.clone());
        let (outcome, session) = interruptible(py, &cancel, progress, move |latest| {
            let outcome = work(&mut session, &mut |stage, fraction| {
                report(&latest, stage, fraction);
            });
            (outcome, session)
        })?;
        self.put_back(session);
        Ok(outcome)
    }
}

/// Records the work's progress for the waiting thread to report.
fn report(latest: &Latest, stage: Stage, fraction: f64) {
    *latest.lock().unwrap_or_else(|p| p.into_inner()) = Some((stage.describe(), fraction));
}

/// A library error about the file `path`, as the command line words it.
fn value_error_about(path: &std::path::Path, error: aureole::Error) -> PyErr {
    match error {
        aureole::Error::Cancelled => value_error(error),
        other => PyValueError::new_err(one_line(&format!("{}: {other}", path.display()))),
    }
}

fn method(name: &str) -> PyResult<Method> {
    name.parse().map_err(value_error)
}

fn device(name: &str) -> PyResult<Device> {
    Device::parse(name).ok_or_else(|| {
        PyValueError::new_err(format!(
            "device = {name:?} is not allowed: \"auto\", \"cpu\" or \"gpu\""
        ))
    })
}

#[pymethods]
impl Camera {
    /// A built-in preset by name (`aureole.presets()` lists them).
    #[staticmethod]
    fn preset(name: &str) -> PyResult<Camera> {
        let preset = aureole::presets::find(name).map_err(value_error)?;
        Camera::parse(
            preset.toml,
            &format!("preset {name}"),
            std::path::Path::new(""),
        )
    }

    /// A camera from TOML text, as in a config file; `name` starts its error
    /// messages.
    #[staticmethod]
    #[pyo3(signature = (text, name = "<string>"))]
    fn from_toml(text: &str, name: &str) -> PyResult<Camera> {
        Camera::parse(text, name, std::path::Path::new(""))
    }

    /// A camera from a TOML config file.
    #[staticmethod]
    fn from_file(path: PathBuf) -> PyResult<Camera> {
        let text = std::fs::read_to_string(&path).map_err(|e| {
            PyOSError::new_err(format!(
                "{}: {}",
                path.display(),
                aureole::error::describe_io(&e)
            ))
        })?;
        Camera::parse(
            &text,
            &path.display().to_string(),
            aureole_io::atomic::folder_of(&path),
        )
    }

    /// The cameras composed in order: later settings replace earlier ones,
    /// effects follow one another (light passes through each).
    #[staticmethod]
    #[pyo3(signature = (*cameras))]
    fn compose(cameras: Vec<PyRef<'_, Camera>>) -> Camera {
        let file = cameras.iter().fold(ConfigFile::default(), |file, camera| {
            file.then(camera.file.clone())
        });
        Camera::new(file)
    }

    /// The camera as TOML: `aureole apply --config` with it gives the same
    /// picture.
    fn toml(&self) -> String {
        self.file.to_toml()
    }

    /// The camera's threshold, cd/m² (pixels at or below it are not
    /// spread).
    #[getter]
    fn threshold(&self) -> f64 {
        self.config.threshold
    }

    /// The seed of the random ray lengths.
    #[getter]
    fn seed(&self) -> u64 {
        self.config.seed
    }

    /// The kernel (PSF) of the whole chain, width × height pixels, each
    /// channel the share of its light within it (the rest would leave a
    /// frame that size), its centre at (height // 2,
    /// width // 2): float32 (H, W), or (H, W, 3) where it differs by
    /// colour. `image_width` sets the pixel pitch (sensor width / image
    /// width) that turns µm and mm into pixels; by default the kernel's
    /// width. `sent_by` is "pixel" (the kernel an image is convolved with:
    /// each pixel's light leaves its whole square) or "point" (the PSF of
    /// a point of light, as an optics program gives it). `device` is where
    /// the effects convolve one another, as for `apply`: "auto", "cpu" or
    /// "gpu" (a kernel composed on a GPU differs in the last bits).
    #[pyo3(signature = (width, height, image_width = None, progress = None, sent_by = "pixel",
                        device = "auto"))]
    #[allow(clippy::too_many_arguments)]
    fn kernel<'py>(
        &self,
        py: Python<'py>,
        width: usize,
        height: usize,
        image_width: Option<usize>,
        progress: Option<&Bound<'py, PyAny>>,
        sent_by: &str,
        device: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        let mut composing = Composing::on(self::device(device)?).map_err(value_error)?;
        let sending = match sent_by {
            "pixel" => Sending::Pixel,
            "point" => Sending::Point,
            other => {
                return Err(PyValueError::new_err(format!(
                    "sent_by {other:?}: allowed are \"pixel\" and \"point\""
                )))
            }
        };
        let mut extent = Extent::new(width, height)
            .map_err(value_error)?
            .sent_by(sending);
        if let Some(n) = image_width {
            extent = extent.with_image_width(n);
        }
        let cancel = Cancel::new();
        let config = &self.config;
        let kernel = interruptible(py, &cancel, progress, |latest| {
            let mut building = |fraction| report(&latest, Stage::BuildingKernel, fraction);
            config.kernel_on(
                &extent,
                &mut composing,
                &mut Control::new(&cancel, &mut building),
            )
        })?
        .map_err(value_error)?;
        let planes = kernel.planes();
        let (w, h) = (kernel.width(), kernel.height());
        let data: Vec<f32> = if kernel.is_coloured() {
            (0..w * h)
                .flat_map(|i| planes.iter().map(move |p| p[i]))
                .collect()
        } else {
            planes[0].clone()
        };
        let dims = if kernel.is_coloured() {
            vec![h, w, planes.len()]
        } else {
            vec![h, w]
        };
        Ok(PyArray1::from_vec(py, data).reshape(dims)?.into_any())
    }

    /// What the pupil of the camera's first aperture transmits at the
    /// points (`x`, `y`), mm from its centre (arrays of one shape): a
    /// complex array, 1 on clear glass, 0 on the stop, the obstruction,
    /// vanes, dust and scratches, and the smudge's a·e^(iφ) under grease,
    /// the dirt drawn from the camera's seed as for its kernel.
    fn pupil<'py>(
        &self,
        py: Python<'py>,
        x: numpy::PyReadonlyArrayDyn<'py, f64>,
        y: numpy::PyReadonlyArrayDyn<'py, f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let pupil = aureole::optics::aperture::first_optics(&self.config)
            .map_err(value_error)?
            .map(|optics| optics.pupil)
            .ok_or_else(|| value_error(aureole::Error::NoAperture))?;
        let (x, y) = (x.as_array(), y.as_array());
        if x.shape() != y.shape() {
            return Err(PyValueError::new_err(format!(
                "x and y must have one shape; they have {:?} and {:?}",
                x.shape(),
                y.shape()
            )));
        }
        let shape = x.shape().to_vec();
        let points: Vec<[f64; 2]> = x.iter().zip(y.iter()).map(|(&x, &y)| [x, y]).collect();
        let values: Vec<numpy::Complex64> = py.detach(|| {
            points
                .par_iter()
                .map(|&point| {
                    let [re, im] = pupil.transmission(point);
                    numpy::Complex64::new(re, im)
                })
                .collect()
        });
        Ok(PyArray1::from_vec(py, values).reshape(shape)?.into_any())
    }

    /// The image the camera records of `image` (luminance in cd/m² ×
    /// 1/input_scale): a new float32 array of the same shape, alpha
    /// carried through. `threshold` (cd/m², default the camera's) and
    /// `knee` choose what is spread; `glare_only` returns only the light
    /// that moved; `method` is "auto", "fft" or "splat". With `layers`,
    /// returns (result, layers): a dict of the light each effect adds
    /// ("glare.bloom", "glare.corona", …, negative where it took light
    /// away) and the total ("glare"), which they sum to, each an array
    /// of the image's shape without alpha. One camera applied to many
    /// frames of one size builds its kernel once.
    #[pyo3(signature = (image, threshold = None, knee = 0.0, input_scale = 1.0,
                        glare_only = false, method = "auto", progress = None, layers = false,
                        device = "auto"))]
    #[allow(clippy::too_many_arguments)]
    fn apply<'py>(
        &self,
        py: Python<'py>,
        image: &Bound<'py, PyAny>,
        threshold: Option<f64>,
        knee: f64,
        input_scale: f64,
        glare_only: bool,
        method: &str,
        progress: Option<&Bound<'py, PyAny>>,
        layers: bool,
        device: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        if layers && glare_only {
            return Err(PyValueError::new_err(
                aureole_io::job::LAYERS_WITH_GLARE_ONLY,
            ));
        }
        let device = self::device(device)?;
        let options = ApplyOptions {
            threshold,
            knee,
            glare_only,
            method: self::method(method)?,
        };
        let (image, shape) = to_image(&float32(image)?)?;
        let frame = Frame::new(
            image,
            &FrameOptions {
                input_scale: Some(input_scale),
                sanitize: false,
            },
        )
        .map_err(value_error)?;
        let size = ((frame.image().width, frame.image().height), device);
        if !layers {
            let applied = self.with_session(py, size, progress, |session, report| {
                session.apply(&frame, &options, report)
            })?;
            return to_array(py, &applied.map_err(value_error)?.image, shape);
        }
        let (applied, glare) = self
            .with_session(py, size, progress, |session, report| {
                session.apply_layers(&frame, &options, report)
            })?
            .map_err(value_error)?;
        let without_alpha = match shape {
            ArrayShape::Channels(4) => ArrayShape::Channels(3),
            other => other,
        };
        let named = PyDict::new(py);
        for layer in &glare {
            named.set_item(&layer.name, to_array(py, &layer.image, without_alpha)?)?;
        }
        let result = to_array(py, &applied.image, shape)?;
        Ok((result, named).into_pyobject(py)?.into_any())
    }

    /// `aureole apply INPUT -o OUTPUT` with this camera: the file read
    /// (its `whiteLuminance` the scale unless `input_scale` is given, `layer`
    /// and `part` chosen as there), the camera applied, the result written
    /// atomically into a copy of the input (an EXR keeps its other layers,
    /// parts, windows, attributes, sample types and compression unless
    /// `half` or `compression` say otherwise; a picture is exposed
    /// automatically and tone-mapped filmic). The same bytes as the command
    /// line. Returns energy_in, energy_out (file units), spread_pixels,
    /// threshold (cd/m²), scale, device (where it was spread) and notes.
    /// With `layers`, the output EXR holds beside the result the light each
    /// effect adds and the total (`aureole apply --layers`).
    #[pyo3(signature = (input, output, threshold = None, knee = 0.0, input_scale = None,
                        glare_only = false, method = "auto", half = None, compression = None,
                        layer = None, part = None, progress = None, layers = false,
                        device = "auto"))]
    #[allow(clippy::too_many_arguments)]
    fn apply_file<'py>(
        &self,
        py: Python<'py>,
        input: PathBuf,
        output: PathBuf,
        threshold: Option<f64>,
        knee: f64,
        input_scale: Option<f64>,
        glare_only: bool,
        method: &str,
        half: Option<bool>,
        compression: Option<&str>,
        layer: Option<String>,
        part: Option<String>,
        progress: Option<&Bound<'py, PyAny>>,
        layers: bool,
        device: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        let device = self::device(device)?;
        let options = ApplyOptions {
            threshold,
            knee,
            glare_only,
            method: self::method(method)?,
        };
        let compression = crate::files::compression(compression)?;
        let job = aureole_io::job::Job {
            input: Some(input.clone()),
            output,
            choice: Choice { layer, part },
            frame: FrameOptions {
                input_scale,
                sanitize: false,
            },
            options,
            layers,
            write: WriteOptions {
                linear: LinearOptions {
                    samples: half.map(|h| if h { Samples::Half } else { Samples::Float }),
                    compression,
                },
                display: DisplayOptions {
                    exposure: Exposure::Auto,
                    tone: ToneCurve::Filmic,
                },
                depth: None,
            },
        };
        // The guards every front end keeps, before any work.
        job.check().map_err(file_error)?;
        let limits = Limits::default_for_machine();
        // A frame the camera could not take is refused from its header,
        // before it is decoded, as the command line does.
        let checker = Session::new(self.config.clone()).with_memory_limit(limits.max_bytes);
        let (mut file, ()) = py
            .detach(|| job.read(&checker, limits, |_| Ok::<(), aureole_io::Error>(())))
            .map_err(file_error)?;
        let size = (
            (file.frame.image().width, file.frame.image().height),
            device,
        );
        let done = self.with_session(py, size, progress, |session, report| {
            // A stereo plate's every view goes through the camera.
            job.apply(&mut file, session, report)
                .map_err(|error| value_error_about(&input, error))
                .and_then(|applied| job.write(file, applied).map_err(file_error))
        })??;
        let (applied, scale, notes) = (done.applied, done.scale, done.notes);
        let report = PyDict::new(py);
        report.set_item("energy_in", applied.energy_in)?;
        report.set_item("energy_out", applied.energy_out)?;
        report.set_item("spread_pixels", applied.spread_pixels)?;
        report.set_item("threshold", applied.threshold)?;
        report.set_item("device", &applied.device)?;
        report.set_item("scale", scale)?;
        report.set_item("notes", notes)?;
        let ghosts = match applied.ghosts {
            Some(g) => {
                let summary = PyDict::new(py);
                summary.set_item("found", g.found)?;
                summary.set_item("traced", g.traced)?;
                summary.set_item("paths", g.paths)?;
                summary.set_item("f_number", g.f_number)?;
                summary.set_item("light", g.light)?;
                summary.into_any()
            }
            None => py.None().into_bound(py),
        };
        report.set_item("ghosts", ghosts)?;
        Ok(report)
    }

    /// Pickled as its TOML, so a camera goes to Dask or multiprocessing
    /// workers as it is; each rebuilds its own plans there.
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (String, &'static str))> {
        let rebuild = py.get_type::<Camera>().getattr("from_toml")?;
        Ok((rebuild, (self.toml(), "pickled camera")))
    }

    fn __repr__(&self) -> String {
        format!(
            "<aureole.Camera: {} effect(s), seed {}, threshold {} cd/m²>",
            self.config.effects.len(),
            self.config.seed,
            self.config.threshold
        )
    }
}
