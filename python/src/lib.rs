//! `splinewatch._splinewatch`: the extension module of the Python package
//! (issue 46), a thin shell over `splinewatch-core` and the application's
//! config, readers and studies (built without the daemon: no zenoh, Rerun
//! or tokio). numpy in and out; every error a Python exception carrying the
//! CLI's message. The public API, its docstrings and the result classes are
//! in `python/splinewatch/`; this module is its engine, never a second
//! implementation.
#![forbid(unsafe_code)]

mod arrays;
mod errors;
mod files;
mod identification;
mod model;

use pyo3::prelude::*;

#[pymodule]
fn _splinewatch(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(identification::oma, m)?)?;
    m.add_function(wrap_pyfunction!(identification::identify, m)?)?;
    m.add_function(wrap_pyfunction!(identification::frf, m)?)?;
    m.add_function(wrap_pyfunction!(identification::fit_modes, m)?)?;
    m.add_function(wrap_pyfunction!(identification::h1_sigma, m)?)?;
    m.add_function(wrap_pyfunction!(files::read_recording, m)?)?;
    m.add_function(wrap_pyfunction!(files::read_results, m)?)?;
    m.add_function(wrap_pyfunction!(files::result_topics, m)?)?;
    m.add_class::<identification::RawModes>()?;
    m.add_class::<model::RawModel>()?;
    Ok(())
}
