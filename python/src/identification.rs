//! Identification from arrays: output-only SSI-cov (`oma`), input–output
//! SRIM (`identify`), Welch FRFs (`frf`) and the pole–residue fit to
//! functions (`fit_modes`), each the core's, with the
//! settings of the config sections `[oma]` and `[frf]` (the Python keyword
//! arguments arrive as those sections' JSON, so a wrong key or value gets
//! the config's message).

use crate::arrays::{complex_matrix, finite_channel, finite_vector, matrix, vector, Channels};
use crate::errors::{bad, OrPy};
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use splinewatch::config::{FrfConfig, OmaConfig};
use splinewatch::pipeline::oma::OmaReport;
use splinewatch_core::c64;
use splinewatch_core::identification::oma::{identify as ssi_cov, OmaSettings, OutputCorrelations};
use splinewatch_core::identification::pole_residue::{self, FittedMode, Functions};
use splinewatch_core::identification::srim;
use splinewatch_core::identification::welch::WelchEstimator;

/// Parses the settings JSON of a section (`what`: "oma" or "frf").
fn section<T: serde::de::DeserializeOwned>(json: &str, what: &str) -> PyResult<T> {
    serde_json::from_str(json).map_err(|e| bad(format!("{what}: {e}")))
}

/// The checked `[oma]` settings of `settings_json` for a record sampled at
/// `fs` (the band defaults to 0 … fs/2).
fn oma_settings(fs: f64, settings_json: &str) -> PyResult<OmaSettings> {
    check_rate(fs)?;
    let config: OmaConfig = section(settings_json, "oma")?;
    config.settings([0.0, fs / 2.0]).or_py()
}

/// The default channel names `ch1, ch2, …`, or the given ones (one per channel).
fn channel_names(names: Option<Vec<String>>, channels: usize, what: &str) -> PyResult<Vec<String>> {
    match names {
        None => Ok((1..=channels).map(|c| format!("ch{c}")).collect()),
        Some(names) if names.len() == channels => Ok(names),
        Some(names) => Err(bad(format!(
            "{what}: {} names given for {channels} channels",
            names.len()
        ))),
    }
}

/// Output-only modes of `data` (samples × channels, sampled at `fs`) with
/// the `[oma]` settings in `settings_json`.
#[pyfunction]
#[pyo3(signature = (data, fs, settings_json, references, sensors=None, start_ns=None))]
pub fn oma(
    py: Python<'_>,
    data: PyReadonlyArray2<'_, f64>,
    fs: f64,
    settings_json: &str,
    references: Vec<usize>,
    sensors: Option<Vec<String>>,
    start_ns: Option<i64>,
) -> PyResult<RawModes> {
    let settings = oma_settings(fs, settings_json)?;
    let channels = Channels::new(&data, "data", 2)?;
    if let Some(&r) = references.iter().find(|&&r| r >= channels.len()) {
        return Err(bad(format!(
            "references: channel {r} does not exist (data has {} channels)",
            channels.len()
        )));
    }
    let sensors = channel_names(sensors, channels.len(), "sensors")?;
    let views = channels.slices();
    let result = py
        .detach(|| {
            let correlations =
                OutputCorrelations::from_samples(&views, &references, settings.max_lag(), settings.batches)?;
            ssi_cov(&correlations, fs, &settings)
        })
        .map_err(|e| bad(format!("SSI-cov: {e}")))?;
    Ok(RawModes::new(
        result,
        sensors,
        channels.samples(),
        fs,
        start_ns,
        channels.borrowed(),
    ))
}

/// Input–output modes (SRIM) of `outputs` driven by the measured `inputs`
/// (both samples × channels at `fs`).
#[pyfunction]
#[pyo3(signature = (inputs, outputs, fs, settings_json, sensors=None, start_ns=None))]
pub fn identify(
    py: Python<'_>,
    inputs: PyReadonlyArray2<'_, f64>,
    outputs: PyReadonlyArray2<'_, f64>,
    fs: f64,
    settings_json: &str,
    sensors: Option<Vec<String>>,
    start_ns: Option<i64>,
) -> PyResult<RawModes> {
    let settings = oma_settings(fs, settings_json)?;
    let u = Channels::new(&inputs, "inputs", 2)?;
    let y = Channels::new(&outputs, "outputs", 2)?;
    if u.samples() != y.samples() {
        return Err(bad(format!(
            "inputs have {} samples, outputs {}: give both on one time grid",
            u.samples(),
            y.samples()
        )));
    }
    let sensors = channel_names(sensors, y.len(), "sensors")?;
    let (u_views, y_views) = (u.slices(), y.slices());
    let result = py
        .detach(|| srim::identify_io(&u_views, &y_views, fs, &settings))
        .map_err(|e| bad(format!("identification: {e}")))?;
    let borrowed = u.borrowed() && y.borrowed();
    Ok(RawModes::new(result, sensors, y.samples(), fs, start_ns, borrowed))
}

/// Welch FRFs of `responses` (samples × channels) per `force` at `fs` with
/// the `[frf]` settings in `settings_json`: `(f, H, coherence, counts)`,
/// H and coherence one row per response.
#[pyfunction]
#[pyo3(signature = (force, responses, fs, settings_json))]
#[allow(clippy::type_complexity)]
pub fn frf<'py>(
    py: Python<'py>,
    force: PyReadonlyArray1<'_, f64>,
    responses: PyReadonlyArray2<'_, f64>,
    fs: f64,
    settings_json: &str,
) -> PyResult<(
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<numpy::Complex64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyDict>,
)> {
    check_rate(fs)?;
    let config: FrfConfig = section(settings_json, "frf")?;
    let (settings, estimator) = config.welch_settings(fs).or_py()?;
    let x = Channels::new(&responses, "responses", settings.segment)?;
    let force = force.as_array();
    if force.len() != x.samples() {
        return Err(bad(format!(
            "force has {} samples, responses {}: give both on one time grid",
            force.len(),
            x.samples()
        )));
    }
    let f_slice = finite_channel(force, |i, v| format!("force[{i}] is {v}: every sample must be finite"))?;
    let views = x.slices();
    let (estimate, counts) = py
        .detach(|| -> anyhow::Result<_> {
            let mut welch = WelchEstimator::new(settings, views.len())?;
            welch.push(&f_slice, &views)?;
            let counts = welch.counts();
            if counts.accepted == 0 {
                anyhow::bail!(
                    "every Welch segment was rejected ({} non-finite, {} clipped, {} double impacts)",
                    counts.non_finite,
                    counts.clipped,
                    counts.double_impact
                );
            }
            Ok((welch.spectra().frf(estimator), counts))
        })
        .or_py()?;
    let lines = estimate.frequencies.len();
    let info = PyDict::new(py);
    info.set_item("segments_accepted", counts.accepted)?;
    info.set_item("segments_rejected", counts.rejected())?;
    info.set_item("effective_averages", estimate.effective_averages)?;
    Ok((
        vector(py, estimate.frequencies),
        complex_matrix(py, &estimate.h, lines),
        matrix(py, &estimate.coherence, lines),
        info,
    ))
}

/// The pole–residue fit of `modes` modes shared by the functions `h`
/// (functions × lines, complex) at `frequencies` (Hz), each line weighted by
/// its standard deviation `sigma` (functions × lines): a dict of arrays
/// (`frequency`, `damping`, their stds, `residues` modes × functions,
/// `at_bound`) and the fit's `residual_scale` and `iterations`.
#[pyfunction]
#[pyo3(signature = (frequencies, h, sigma, modes))]
pub fn fit_modes<'py>(
    py: Python<'py>,
    frequencies: PyReadonlyArray1<'_, f64>,
    h: PyReadonlyArray2<'_, numpy::Complex64>,
    sigma: PyReadonlyArray2<'_, f64>,
    modes: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let frequencies = finite_vector(&frequencies, "f")?;
    let (h, sigma) = (h.as_array(), sigma.as_array());
    if h.shape() != sigma.shape() || h.ncols() != frequencies.len() {
        return Err(bad(format!(
            "H is {}×{} and sigma {}×{} for {} lines: give both as functions × lines",
            h.nrows(),
            h.ncols(),
            sigma.nrows(),
            sigma.ncols(),
            frequencies.len()
        )));
    }
    let h: Vec<Vec<c64>> = h
        .rows()
        .into_iter()
        .map(|r| r.iter().map(|v| c64::new(v.re, v.im)).collect())
        .collect();
    let sigma: Vec<Vec<f64>> = sigma.rows().into_iter().map(|r| r.to_vec()).collect();
    let functions = Functions {
        frequencies_hz: &frequencies,
        h: &h,
        sigma: &sigma,
    };
    let fitted = py
        .detach(|| pole_residue::fit(functions, modes))
        .map_err(|e| bad(format!("fit_modes: {e}")))?;
    let column = |pick: fn(&FittedMode) -> f64| vector(py, fitted.modes.iter().map(pick).collect());
    let result = PyDict::new(py);
    result.set_item("frequency", column(|m| m.frequency_hz))?;
    result.set_item("damping", column(|m| m.damping_ratio))?;
    result.set_item("frequency_std", column(|m| m.frequency_std_hz))?;
    result.set_item("damping_std", column(|m| m.damping_std))?;
    let residues: Vec<Vec<c64>> = fitted.modes.iter().map(|m| m.residues.clone()).collect();
    result.set_item("residues", complex_matrix(py, &residues, h.len()))?;
    result.set_item(
        "at_bound",
        fitted.modes.iter().map(|m| m.at_bound).collect::<Vec<bool>>(),
    )?;
    result.set_item("residual_scale", fitted.residual_scale)?;
    result.set_item("iterations", fitted.iterations)?;
    Ok(result)
}

/// Each line's standard deviation of H1 estimates `h` (functions × lines)
/// from their coherence (the same shape) over `averages` Welch averages
/// with `inputs` inputs: the weights `fit_modes` and `identify`'s
/// frequency-domain estimate use.
#[pyfunction]
#[pyo3(signature = (h, coherence, averages, inputs))]
pub fn h1_sigma<'py>(
    py: Python<'py>,
    h: PyReadonlyArray2<'_, numpy::Complex64>,
    coherence: PyReadonlyArray2<'_, f64>,
    averages: usize,
    inputs: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (h, coherence) = (h.as_array(), coherence.as_array());
    if h.shape() != coherence.shape() {
        return Err(bad(format!(
            "H is {}×{} and coherence {}×{}: give both as functions × lines",
            h.nrows(),
            h.ncols(),
            coherence.nrows(),
            coherence.ncols()
        )));
    }
    let rows: Vec<Vec<f64>> = h
        .rows()
        .into_iter()
        .zip(coherence.rows())
        .map(|(hr, gr)| {
            hr.iter()
                .zip(gr.iter())
                .map(|(v, &g)| pole_residue::h1_standard_deviation(c64::new(v.re, v.im), g, averages, inputs))
                .collect()
        })
        .collect();
    Ok(matrix(py, &rows, h.ncols()))
}

fn check_rate(fs: f64) -> PyResult<()> {
    if fs.is_finite() && fs > 0.0 {
        Ok(())
    } else {
        Err(bad(format!("fs must be a positive sampling frequency in Hz, got {fs}")))
    }
}

/// What an identification found, kept whole so that `to_json` writes the
/// modes file exactly as `splinewatch oma --json` does.
#[pyclass(frozen, module = "splinewatch._splinewatch")]
pub struct RawModes {
    report: OmaReport,
    /// Whether the caller gave the first sample's time (else the modes
    /// file has no `start`).
    known_start: bool,
    /// Whether the data were read in place (no copy).
    borrowed: bool,
}

impl RawModes {
    fn new(
        result: splinewatch_core::identification::oma::OmaResult,
        sensors: Vec<String>,
        samples: usize,
        fs: f64,
        start_ns: Option<i64>,
        borrowed: bool,
    ) -> Self {
        Self {
            known_start: start_ns.is_some(),
            report: OmaReport {
                start_ns: i128::from(start_ns.unwrap_or(0)),
                samples,
                fs,
                sensors,
                result,
                spectrum: None,
            },
            borrowed,
        }
    }
}

#[pymethods]
impl RawModes {
    /// The modes file (`update --modes` reads it).
    fn to_json(&self) -> PyResult<String> {
        let mut file = self.report.modes_file();
        if !self.known_start {
            file.start = None;
        }
        serde_json::to_string(&file).or_py()
    }

    /// Per mode: frequency, damping, their std (NaN: not estimated), MPC,
    /// order, stable orders.
    fn columns<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let modes = &self.report.result.modes;
        let nan = f64::NAN;
        let column = |f: &dyn Fn(&splinewatch_core::identification::oma::IdentifiedMode) -> f64| {
            vector(py, modes.iter().map(f).collect())
        };
        let d = PyDict::new(py);
        d.set_item("frequency", column(&|m| m.frequency_hz))?;
        d.set_item("damping", column(&|m| m.damping_ratio))?;
        d.set_item("frequency_std", column(&|m| m.frequency_std_hz.unwrap_or(nan)))?;
        d.set_item("damping_std", column(&|m| m.damping_std.unwrap_or(nan)))?;
        d.set_item("mpc", column(&|m| m.mpc))?;
        let ints = |f: &dyn Fn(&splinewatch_core::identification::oma::IdentifiedMode) -> usize| {
            PyArray1::from_vec(py, modes.iter().map(|m| f(m) as i64).collect())
        };
        d.set_item("order", ints(&|m| m.order))?;
        d.set_item("stable_orders", ints(&|m| m.stable_orders))?;
        let channels = self.report.sensors.len();
        let shapes: Vec<_> = modes.iter().map(|m| m.shape.clone()).collect();
        d.set_item("shapes", complex_matrix(py, &shapes, channels))?;
        let stds: Vec<Vec<f64>> = modes
            .iter()
            .map(|m| m.shape_std.clone().unwrap_or_else(|| vec![nan; channels]))
            .collect();
        d.set_item("shapes_std", matrix(py, &stds, channels))?;
        d.set_item("sensors", self.report.sensors.clone())?;
        d.set_item("fs", self.report.fs)?;
        d.set_item("samples", self.report.samples)?;
        d.set_item("copied", !self.borrowed)?;
        Ok(d)
    }

    /// The stabilisation diagram: every pole's order, frequency, damping,
    /// stability and mode (−1: none), and the subspace's singular values.
    fn diagram<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let poles = &self.report.result.diagram;
        let d = PyDict::new(py);
        d.set_item(
            "order",
            PyArray1::from_vec(py, poles.iter().map(|p| p.order as i64).collect()),
        )?;
        d.set_item("frequency", vector(py, poles.iter().map(|p| p.frequency_hz).collect()))?;
        d.set_item("damping", vector(py, poles.iter().map(|p| p.damping_ratio).collect()))?;
        d.set_item(
            "stable",
            PyArray1::from_vec(py, poles.iter().map(|p| p.stable).collect()),
        )?;
        d.set_item(
            "mode",
            PyArray1::from_vec(py, poles.iter().map(|p| p.mode.map_or(-1, |m| m as i64)).collect()),
        )?;
        d.set_item(
            "singular_values",
            vector(py, self.report.result.singular_values.clone()),
        )?;
        Ok(d)
    }
}
