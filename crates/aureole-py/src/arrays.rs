//! numpy arrays to the library's planar images and back: (H, W) and
//! (H, W, 1) are luminance, (H, W, 3) RGB, (H, W, 4) RGB with alpha.

use aureole::{Image, Layout};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// How an array's last axis maps to planes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArrayShape {
    /// (H, W): one luminance plane.
    Flat,
    /// (H, W, c) with c = 1, 3 or 4.
    Channels(usize),
}

impl ArrayShape {
    /// The layout name the metadata uses.
    pub fn layout(self) -> &'static str {
        match self {
            ArrayShape::Flat | ArrayShape::Channels(1) => "luminance",
            ArrayShape::Channels(3) => "rgb",
            ArrayShape::Channels(_) => "rgba",
        }
    }
}

/// `image` (any array-like of float16, float32 or float64) as an aligned,
/// C-contiguous, native float32 array: one that already is passes through
/// untouched, not copied; any other (another dtype or byte order, strided,
/// Fortran-ordered, or unaligned as a frame unpickled on a Dask worker
/// arrives) is copied once. Read-only arrays are only read.
pub fn float32<'py>(image: &Bound<'py, PyAny>) -> PyResult<PyReadonlyArrayDyn<'py, f32>> {
    let numpy = image.py().import("numpy")?;
    let array = numpy.call_method1("asarray", (image,))?;
    let dtype = array.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    let size: usize = dtype.getattr("itemsize")?.extract()?;
    if kind != "f" || ![2, 4, 8].contains(&size) {
        return Err(PyTypeError::new_err(format!(
            "image: dtype {dtype} is not allowed: float16, float32 or float64"
        )));
    }
    // `ascontiguousarray` keeps an unaligned array as it is, and numpy's
    // slice view refuses one: `require` copies for either reason.
    let options = PyDict::new(image.py());
    options.set_item("dtype", numpy.getattr("float32")?)?;
    options.set_item("requirements", ["C", "A"])?;
    let ready = numpy.call_method("require", (array,), Some(&options))?;
    ready.extract::<PyReadonlyArrayDyn<'py, f32>>()
}

/// The planes of a C-contiguous float32 array, read straight from its
/// buffer: the split into planes is the only copy.
pub fn to_image(array: &PyReadonlyArrayDyn<'_, f32>) -> PyResult<(Image, ArrayShape)> {
    let dims = array.shape().to_vec();
    let (height, width, shape) = match dims.as_slice() {
        [h, w] => (*h, *w, ArrayShape::Flat),
        [h, w, c @ (1 | 3 | 4)] => (*h, *w, ArrayShape::Channels(*c)),
        other => {
            return Err(PyValueError::new_err(format!(
                "image: shape {other:?} is not allowed: (H, W), or (H, W, C) with C = 1, 3 or 4"
            )))
        }
    };
    if width == 0 || height == 0 {
        return Err(PyValueError::new_err(format!(
            "image: shape {dims:?} is empty: at least 1×1 pixels"
        )));
    }
    // `float32` made it C-contiguous and aligned; numpy refusing a view now
    // would be numpy's doing, so its strides go in the message.
    let data = array.as_slice().map_err(|_| {
        PyValueError::new_err(format!(
            "image: numpy gave no contiguous view of the {dims:?} float32 array (strides {:?})",
            array.strides()
        ))
    })?;
    let channels = match shape {
        ArrayShape::Flat => 1,
        ArrayShape::Channels(c) => c,
    };
    let plane = |c: usize| -> Vec<f32> { data.iter().skip(c).step_by(channels).copied().collect() };
    let (layout, planes) = if channels >= 3 {
        (Layout::Rgb, (0..3).map(plane).collect())
    } else {
        (Layout::Luminance, vec![plane(0)])
    };
    let image = Image {
        width,
        height,
        layout,
        planes,
        alpha: (channels == 4).then(|| plane(3)),
        white_luminance: None,
        primaries: None,
    };
    Ok((image, shape))
}

/// `image` as a float32 array of `shape` (alpha back in place).
pub fn to_array<'py>(
    py: Python<'py>,
    image: &Image,
    shape: ArrayShape,
) -> PyResult<Bound<'py, PyAny>> {
    let channels = match shape {
        ArrayShape::Flat => 1,
        ArrayShape::Channels(c) => c,
    };
    let n = image.width * image.height;
    let mut data = Vec::with_capacity(n * channels);
    let plane = |c: usize| -> &[f32] {
        match (c, image.layout) {
            (3, _) => image.alpha.as_deref().unwrap_or(&[]),
            (_, Layout::Luminance) => &image.planes[0],
            (c, Layout::Rgb) => &image.planes[c],
        }
    };
    let planes: Vec<&[f32]> = (0..channels).map(plane).collect();
    for i in 0..n {
        for p in &planes {
            data.push(p.get(i).copied().unwrap_or(1.0));
        }
    }
    let dims: Vec<usize> = match shape {
        ArrayShape::Flat => vec![image.height, image.width],
        ArrayShape::Channels(c) => vec![image.height, image.width, c],
    };
    Ok(PyArray1::from_vec(py, data).reshape(dims)?.into_any())
}

/// A file's image as an array: (H, W) for luminance, (H, W, 3) for RGB,
/// (H, W, 4) with alpha.
pub fn shape_of(image: &Image) -> ArrayShape {
    match (image.layout, image.alpha.is_some()) {
        (_, true) => ArrayShape::Channels(4),
        (Layout::Rgb, false) => ArrayShape::Channels(3),
        (Layout::Luminance, false) => ArrayShape::Flat,
    }
}
