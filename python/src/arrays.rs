//! numpy arrays in and out: checked once here, so every function reports a
//! wrong shape, an empty array or a non-finite sample the same way.

use crate::errors::bad;
use numpy::ndarray::{Array2, ArrayView1, ArrayView2, Axis};
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use splinewatch_core::c64;
use std::borrow::Cow;

/// The channels of a samples × channels array as one slice each: borrowed
/// when the array is Fortran-ordered (each channel contiguous: `x.T` of a
/// channels × samples array), else copied once, channel by channel.
pub struct Channels<'a> {
    columns: Vec<Cow<'a, [f64]>>,
}

impl<'a> Channels<'a> {
    /// Checks `data` (`what` names it in errors): at least `min_samples`
    /// rows, one column or more, every sample finite.
    pub fn new(data: &'a PyReadonlyArray2<'_, f64>, what: &str, min_samples: usize) -> PyResult<Self> {
        let view: ArrayView2<'a, f64> = data.as_array();
        let (samples, channels) = view.dim();
        if channels == 0 || samples < min_samples {
            return Err(bad(format!(
                "{what} must be samples × channels with at least {min_samples} samples and one channel, got shape ({samples}, {channels})"
            )));
        }
        let columns = (0..channels)
            .map(|c| {
                finite_channel(view.index_axis_move(Axis(1), c), |i, v| {
                    format!("{what}[{i}, {c}] is {v}: every sample must be finite (cut the record around gaps)")
                })
            })
            .collect::<PyResult<Vec<_>>>()?;
        Ok(Self { columns })
    }

    pub fn slices(&self) -> Vec<&[f64]> {
        self.columns.iter().map(|c| c.as_ref()).collect()
    }

    pub fn len(&self) -> usize {
        self.columns.len()
    }

    pub fn samples(&self) -> usize {
        self.columns.first().map_or(0, |c| c.len())
    }

    /// Whether every channel was borrowed (no copy made).
    pub fn borrowed(&self) -> bool {
        self.columns.iter().all(|c| matches!(c, Cow::Borrowed(_)))
    }
}

/// One channel's samples, borrowed when contiguous, else copied; the first
/// non-finite sample is an error, worded by `message(index, value)`.
pub fn finite_channel<'a>(
    view: ArrayView1<'a, f64>,
    message: impl Fn(usize, f64) -> String,
) -> PyResult<Cow<'a, [f64]>> {
    let samples = match view.to_slice() {
        Some(s) => Cow::Borrowed(s),
        None => Cow::Owned(view.to_vec()),
    };
    match samples.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(bad(message(i, samples[i]))),
        None => Ok(samples),
    }
}

/// A 1-D array of finite numbers, copied (they are small: frequency lines).
pub fn finite_vector(data: &PyReadonlyArray1<'_, f64>, what: &str) -> PyResult<Vec<f64>> {
    let v = data.as_array().to_vec();
    if v.is_empty() {
        return Err(bad(format!("{what} is empty")));
    }
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(bad(format!("{what}[{i}] is {}: must be finite", v[i])));
    }
    Ok(v)
}

pub fn vector<'py>(py: Python<'py>, v: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(py, v)
}

/// Rows of equal length as a 2-D array (rows × columns).
pub fn matrix<'py, T: numpy::Element + Copy + Default>(
    py: Python<'py>,
    rows: &[Vec<T>],
    columns: usize,
) -> Bound<'py, PyArray2<T>> {
    let mut a = Array2::<T>::default((rows.len(), columns));
    for (r, row) in rows.iter().enumerate() {
        for (c, &v) in row.iter().enumerate().take(columns) {
            a[[r, c]] = v;
        }
    }
    PyArray2::from_owned_array(py, a)
}

pub fn complex_matrix<'py>(
    py: Python<'py>,
    rows: &[Vec<c64>],
    columns: usize,
) -> Bound<'py, PyArray2<numpy::Complex64>> {
    let converted: Vec<Vec<numpy::Complex64>> = rows
        .iter()
        .map(|r| r.iter().map(|v| numpy::Complex64::new(v.re, v.im)).collect())
        .collect();
    matrix(py, &converted, columns)
}
