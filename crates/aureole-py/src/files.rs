//! Files and display pictures through aureole-io: `read`, `write`,
//! `render`.

use std::path::PathBuf;

use aureole::image::Primaries;
use aureole_io::compression::Compression;
use aureole_io::display::{render as display, DisplayOptions, Exposure, ToneCurve};
use aureole_io::formats::Samples;
use aureole_io::limits::Limits;
use aureole_io::read::{read_image_with, Choice};
use aureole_io::write::{write_image, LinearOptions, WriteOptions, Written};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyDictMethods};

use crate::arrays::{float32, shape_of, to_array, to_image};
use crate::run::file_error;

fn primaries_list(p: &Primaries) -> Vec<f32> {
    [p.red, p.green, p.blue, p.white].concat()
}

/// An HDR image file (OpenEXR, Radiance, PFM, or a PNG/JPEG/TIFF picture)
/// as a float32 array in the file's units, (H, W) for luminance, (H, W, 3)
/// for RGB, (H, W, 4) with alpha, and its metadata: `scale` (cd/m² per
/// unit: `whiteLuminance`, else 1), `whiteLuminance`, `chromaticities`
/// (8 numbers, or None for Rec.709), `layout`, `format`, `notes`.
#[pyfunction]
#[pyo3(signature = (path, layer = None, part = None))]
pub fn read<'py>(
    py: Python<'py>,
    path: PathBuf,
    layer: Option<String>,
    part: Option<String>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
    let choice = Choice { layer, part };
    let limits = Limits::default_for_machine();
    let loaded = py
        .detach(|| read_image_with(&path, limits, &choice))
        .map_err(file_error)?;
    let image = loaded.image;
    let shape = shape_of(&image);
    let metadata = PyDict::new(py);
    metadata.set_item("scale", image.white_luminance.map_or(1.0, f64::from))?;
    metadata.set_item("whiteLuminance", image.white_luminance)?;
    metadata.set_item(
        "chromaticities",
        image.primaries.as_ref().map(primaries_list),
    )?;
    metadata.set_item("layout", shape.layout())?;
    metadata.set_item("format", loaded.format)?;
    metadata.set_item("display_referred", loaded.display_referred)?;
    metadata.set_item("notes", loaded.notes)?;
    Ok((to_array(py, &image, shape)?, metadata))
}

/// The OpenEXR compression `name` names, if any.
pub(crate) fn compression(name: Option<&str>) -> PyResult<Option<Compression>> {
    name.map(|n| n.parse().map_err(PyValueError::new_err))
        .transpose()
}

fn tone(name: &str) -> PyResult<ToneCurve> {
    name.parse().map_err(PyValueError::new_err)
}

fn exposure(value: &Bound<'_, PyAny>) -> PyResult<Exposure> {
    match value.extract::<String>() {
        Ok(text) => text.parse().map_err(PyValueError::new_err),
        Err(_) => value
            .extract::<f64>()
            .ok()
            .and_then(Exposure::ev100)
            .ok_or_else(|| PyValueError::new_err(Exposure::refusal(value))),
    }
}

/// Writes `image` (a float32 array as `read` gives) to `path`, atomically,
/// in the format its extension names: linear formats keep the values (EXR
/// as half samples with `half`, `compression` one of OpenEXR's names);
/// PNG, JPEG and TIFF pictures go through `exposure` and `tonemap`.
/// `metadata` may give `whiteLuminance` and `chromaticities` to record.
/// Returns what the format could not keep, a line each.
#[pyfunction]
#[pyo3(signature = (path, image, half = false, compression = None, metadata = None,
                    exposure = None, tonemap = "filmic"))]
#[allow(clippy::too_many_arguments)]
pub fn write(
    py: Python<'_>,
    path: PathBuf,
    image: &Bound<'_, PyAny>,
    half: bool,
    compression: Option<&str>,
    metadata: Option<&Bound<'_, PyDict>>,
    exposure: Option<&Bound<'_, PyAny>>,
    tonemap: &str,
) -> PyResult<Vec<String>> {
    let (mut image, _) = to_image(&float32(image)?)?;
    if let Some(metadata) = metadata {
        if let Some(white) = metadata.get_item("whiteLuminance")? {
            image.white_luminance = white.extract::<Option<f32>>()?;
        }
        if let Some(c) = metadata.get_item("chromaticities")? {
            image.primaries = match c.extract::<Option<Vec<f32>>>()? {
                Some(v) if v.len() == 8 => Some(Primaries {
                    red: [v[0], v[1]],
                    green: [v[2], v[3]],
                    blue: [v[4], v[5]],
                    white: [v[6], v[7]],
                }),
                Some(v) => {
                    return Err(PyValueError::new_err(format!(
                        "metadata chromaticities: {} numbers, allowed: 8 (red, green, blue, white x and y)",
                        v.len()
                    )))
                }
                None => None,
            };
        }
    }
    let options = WriteOptions {
        linear: LinearOptions {
            samples: Some(if half { Samples::Half } else { Samples::Float }),
            compression: self::compression(compression)?,
        },
        display: DisplayOptions {
            exposure: exposure.map_or(Ok(Exposure::Auto), self::exposure)?,
            tone: tone(tonemap)?,
        },
        depth: None,
    };
    let scale = image.white_luminance.map_or(1.0, f64::from);
    let written = py
        .detach(|| write_image(&path, &image, scale, &options))
        .map_err(file_error)?;
    Ok(match written {
        Written::Linear(notes) => notes.iter().map(ToString::to_string).collect(),
        Written::Picture { .. } => Vec::new(),
    })
}

/// `image` (luminance × `scale` cd/m²) as a display picture: uint8 sRGB
/// (H, W, 3), exposed (`exposure`: EV100 or "auto") and tone-mapped
/// (`tonemap`: "filmic", "reinhard" or "clip") as `aureole apply -o
/// out.png` draws it.
#[pyfunction]
#[pyo3(signature = (image, exposure = None, tonemap = "filmic", scale = 1.0))]
pub fn render<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    exposure: Option<&Bound<'py, PyAny>>,
    tonemap: &str,
    scale: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let (image, _) = to_image(&float32(image)?)?;
    let options = DisplayOptions {
        exposure: exposure.map_or(Ok(Exposure::Auto), self::exposure)?,
        tone: tone(tonemap)?,
    };
    let picture = py.detach(|| display(&image, scale, &options));
    Ok(PyArray1::from_vec(py, picture.eight_bit())
        .reshape(vec![picture.height, picture.width, 3])?
        .into_any())
}
