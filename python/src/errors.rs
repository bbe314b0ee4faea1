//! Errors as Python exceptions: the message is the CLI's (an `anyhow`
//! chain printed as `error: {e:#}` prints it); a missing file is a
//! `FileNotFoundError`, everything else a `ValueError`.

use pyo3::exceptions::{PyFileNotFoundError, PyValueError};
use pyo3::PyErr;

/// `e` as the Python exception its cause calls for.
pub fn to_py(e: anyhow::Error) -> PyErr {
    let message = format!("{e:#}");
    let missing = e
        .chain()
        .filter_map(|c| c.downcast_ref::<std::io::Error>())
        .any(|io| io.kind() == std::io::ErrorKind::NotFound);
    if missing {
        PyFileNotFoundError::new_err(message)
    } else {
        PyValueError::new_err(message)
    }
}

/// `?` on any error the application or the core returns.
pub trait OrPy<T> {
    fn or_py(self) -> Result<T, PyErr>;
}

impl<T, E: Into<anyhow::Error>> OrPy<T> for Result<T, E> {
    fn or_py(self) -> Result<T, PyErr> {
        self.map_err(|e| to_py(e.into()))
    }
}

/// A `ValueError` naming what was wrong with an argument.
pub fn bad(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}
