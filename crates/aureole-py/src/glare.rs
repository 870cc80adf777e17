//! `aureole.glare`: the glare figures of a view (a picture file, or an
//! array with its view), the figures `aureole glare --json` prints.

use std::path::PathBuf;

use aureole::rating::{rate, RatingOptions, Task, Threshold};
use aureole::{Cancel, Frame, FrameOptions, Projection, View};
use aureole_io::limits::Limits;
use aureole_io::rating::{frame_options, view_of};
use aureole_io::read::{read_image_with, Choice};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::arrays::{float32, to_image};
use crate::run::{file_error, interruptible, value_error};

/// The view as the keywords give it: Radiance's options, or a projection
/// and field of view.
fn given_view(
    view: Option<&str>,
    projection: Option<&str>,
    fov: Option<f64>,
    fov_vertical: Option<f64>,
) -> PyResult<Option<View>> {
    if let Some(text) = view {
        return View::from_radiance(text).map(Some).map_err(value_error);
    }
    let Some(name) = projection else {
        return Ok(None);
    };
    let projection = Projection::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Projection::ALL.iter().map(|(_, n)| *n).collect();
        PyValueError::new_err(format!(
            "projection {name:?} is not known; allowed: {}",
            names.join(", ")
        ))
    })?;
    let fov = fov.ok_or_else(|| PyValueError::new_err("a projection needs fov (degrees)"))?;
    let mut v = View::new(projection, fov);
    v.vertical_deg = fov_vertical.unwrap_or(fov);
    v.check().map_err(value_error)?;
    Ok(Some(v))
}

/// The glare figures of a view, as a dict: `vertical_illuminance` (E_v,
/// lx), `dgp`, `dgi`, `ugr`, `vcp`, `cgi`, `background_luminance`,
/// `sources` (each with its `direction`, `solid_angle`, `luminance`,
/// `position_index` …), as `evalglare` defines them. `source` is a picture
/// file (a Radiance picture's VIEW header gives its view and 179 lm/W its
/// scale) or a luminance array in cd/m² × 1/input_scale with its `view`
/// ("-vta -vh 180 -vv 180") or `projection` and `fov`. `threshold`
/// (cd/m²) or `multiple` (of the task's or the mean luminance) finds the
/// sources; `task` is (column, row from the top, full opening angle in
/// radians); `search` and `peak` are evalglare's -r and -Y (peak None
/// keeps peaks in their sources).
#[pyfunction]
#[pyo3(signature = (source, *, view = None, projection = None, fov = None, fov_vertical = None,
    input_scale = None, threshold = None, multiple = None, task = None, search = 0.2,
    peak = Some(50_000.0), layer = None, part = None))]
#[allow(clippy::too_many_arguments)]
pub fn glare<'py>(
    py: Python<'py>,
    source: &Bound<'py, PyAny>,
    view: Option<&str>,
    projection: Option<&str>,
    fov: Option<f64>,
    fov_vertical: Option<f64>,
    input_scale: Option<f64>,
    threshold: Option<f64>,
    multiple: Option<f64>,
    task: Option<(f64, f64, f64)>,
    search: f64,
    peak: Option<f64>,
    layer: Option<String>,
    part: Option<String>,
) -> PyResult<Bound<'py, PyAny>> {
    let given = given_view(view, projection, fov, fov_vertical)?;
    let threshold = match (threshold, multiple) {
        (Some(_), Some(_)) => {
            return Err(PyValueError::new_err(
                "give threshold (cd/m²) or multiple, not both",
            ))
        }
        (Some(l), None) => Some(Threshold::Luminance(l)),
        (None, Some(m)) => Some(Threshold::Multiple(m)),
        (None, None) => None,
    };
    let options = RatingOptions {
        threshold,
        task: task.map(|(column, row, angle)| Task { column, row, angle }),
        search_angle: search,
        peak_limit: peak,
    };
    let (frame, view) = if let Ok(path) = source.extract::<PathBuf>() {
        let choice = Choice { layer, part };
        let mut loaded = py
            .detach(|| read_image_with(&path, Limits::default_for_machine(), &choice))
            .map_err(file_error)?;
        let frame_options = frame_options(&mut loaded, input_scale);
        let (view, _) = view_of(&loaded.original, given.map(|v| (v, "as given")))
            .ok_or_else(|| {
                PyValueError::new_err(format!(
                    "{}: the picture says nothing of its view (no VIEW= header line): give view=\"-vta -vh 180 -vv 180\", or projection and fov",
                    path.display()
                ))
            })?
            .map_err(value_error)?;
        let input = aureole_io::job::input(&path, loaded, &frame_options).map_err(file_error)?;
        (input.frame, view)
    } else {
        let array = float32(source)?;
        let (image, _) = to_image(&array)?;
        let view = given.ok_or_else(|| {
            PyValueError::new_err(
                "an array says nothing of its view: give view=\"-vta -vh 180 -vv 180\", or projection and fov",
            )
        })?;
        let frame = Frame::new(
            image,
            &FrameOptions {
                input_scale,
                sanitize: false,
            },
        )
        .map_err(value_error)?;
        (frame, view)
    };
    let cancel = Cancel::new();
    let rating = interruptible(py, &cancel.clone(), None, move |_| {
        rate(frame.image(), frame.scale(), &view, &options, &cancel)
    })?
    .map_err(value_error)?;
    let text = serde_json::to_string(&rating).map_err(|e| PyValueError::new_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}
