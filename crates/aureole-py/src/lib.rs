//! The Python package `aureole`: physically based bloom, corona and glare
//! on numpy arrays, a thin shell over the library's session API, so that
//! it gives the bytes the command line gives. Its Python half
//! (`python/aureole`) converts arrays and holds the docstrings' stubs.

mod arrays;
mod camera;
mod files;
mod glare;
mod run;

use pyo3::prelude::*;

/// The built-in presets: (name, one-line description) pairs.
#[pyfunction]
fn presets() -> Vec<(&'static str, String)> {
    aureole::presets::PRESETS
        .iter()
        .map(|p| (p.name, p.description()))
        .collect()
}

/// The shipped lenses a camera's ghosts may name: (name, what the lens
/// is) pairs.
#[pyfunction]
fn lenses() -> Vec<(&'static str, String)> {
    aureole::lens::shipped::LENSES
        .iter()
        .map(|l| (l.name, l.lens().map(|lens| lens.name).unwrap_or_default()))
        .collect()
}

#[pymodule]
fn _aureole(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add_class::<camera::Camera>()?;
    module.add_function(wrap_pyfunction!(presets, module)?)?;
    module.add_function(wrap_pyfunction!(lenses, module)?)?;
    module.add_function(wrap_pyfunction!(files::read, module)?)?;
    module.add_function(wrap_pyfunction!(files::write, module)?)?;
    module.add_function(wrap_pyfunction!(files::render, module)?)?;
    module.add_function(wrap_pyfunction!(glare::glare, module)?)?;
    module.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
