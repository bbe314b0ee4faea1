//! A configured model (`Model` in Python): its modes and FRFs at any
//! parameter values, its matrices, and the updating of `splinewatch update`
//! (FRF residues, eq. 36–39, or modal residues), all through the
//! application's config and studies.

use crate::arrays::{finite_vector, matrix};
use crate::errors::{bad, OrPy};
use numpy::{PyArray1, PyArray2, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use splinewatch::config::{frf_setup, load_config, Config, FrfSetup};
use splinewatch::io::modes_json::ModesFile;
use splinewatch::studies::{self, synth::SynthOptions};
use splinewatch_core::response::frf::{FrfRequest, ModalState, Quantity};
use splinewatch_core::updating::{modal_state_at, model_at, Parameter};
use std::path::PathBuf;

/// Identified mode, model mode (0-based) and their MAC.
type ModePair = (usize, usize, f64);

#[pyclass(frozen, module = "splinewatch._splinewatch")]
pub struct RawModel {
    config: Config,
    setup: FrfSetup,
    parameters: Vec<Parameter>,
    base: Vec<f64>,
    /// The shell's control points, which place the deck's axes for the
    /// modes' motion.
    positions: Vec<splinewatch_core::geometry::vec3::Vec3>,
}

impl RawModel {
    fn new(config: Config) -> PyResult<Self> {
        let setup = frf_setup(&config).or_py()?;
        let parameters = config.build_parameters().or_py()?;
        let base = splinewatch_core::updating::base_values(
            &parameters,
            &setup.kappa,
            setup.model.field_coefficients(),
            &setup.damping,
        );
        let positions = config.build_model().or_py()?.control_point_positions();
        Ok(Self {
            config,
            setup,
            parameters,
            base,
            positions,
        })
    }

    fn values(&self, values: &PyReadonlyArray1<'_, f64>) -> PyResult<Vec<f64>> {
        let v = finite_vector(values, "parameter values")?;
        if v.len() != self.parameters.len() {
            return Err(bad(format!(
                "{} parameter values given, the model has {}",
                v.len(),
                self.parameters.len()
            )));
        }
        Ok(v)
    }

    fn sensor(&self, name: &str) -> PyResult<usize> {
        self.setup.sensor_names.iter().position(|n| n == name).ok_or_else(|| {
            bad(format!(
                "unknown sensor {name:?} (config sensors: {})",
                self.setup.sensor_names.join(", ")
            ))
        })
    }

    /// The modal state with the parameters at `values`.
    fn state_at(&self, values: &[f64]) -> Result<ModalState, splinewatch_core::updating::UpdateError> {
        let (state, _) = modal_state_at(
            &self.setup.model,
            &self.parameters,
            &self.setup.kappa,
            &self.setup.damping,
            values,
        )?;
        Ok(state)
    }

    /// The parameters at `values` as a start file (`update --start`).
    fn start_json(&self, values: &[f64]) -> String {
        let parameters: Vec<_> = self
            .parameters
            .iter()
            .zip(values)
            .map(|(p, v)| serde_json::json!({"name": p.name, "value": v}))
            .collect();
        serde_json::json!({ "parameters": parameters }).to_string()
    }
}

fn quantity(name: &str) -> PyResult<Quantity> {
    match name {
        "receptance" => Ok(Quantity::Receptance),
        "mobility" => Ok(Quantity::Mobility),
        "accelerance" => Ok(Quantity::Accelerance),
        other => Err(bad(format!(
            "quantity {other:?} is not receptance, mobility or accelerance"
        ))),
    }
}

#[pymethods]
impl RawModel {
    #[staticmethod]
    fn from_config(path: PathBuf) -> PyResult<Self> {
        Self::new(load_config(&path).or_py()?)
    }

    #[staticmethod]
    fn from_toml(text: &str) -> PyResult<Self> {
        let config = Config::from_toml(text).or_py()?;
        config.validate().or_py()?;
        Self::new(config)
    }

    fn structure(&self) -> String {
        self.config.structure.name.clone()
    }

    fn parameter_names(&self) -> Vec<String> {
        self.parameters.iter().map(|p| p.name.clone()).collect()
    }

    fn base_values<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.base.clone())
    }

    fn bounds(&self) -> Vec<(f64, f64)> {
        self.parameters.iter().map(|p| (p.lower, p.upper)).collect()
    }

    fn sensors(&self) -> Vec<String> {
        self.setup.sensor_names.clone()
    }

    /// The first `count` modes at `values`: frequency (Hz), damping ratio,
    /// kind, where each moves the deck (`motion`, and `motion_shares`: modes
    /// × [longitudinal, transverse, vertical, torsion]), each support's share
    /// of its strain energy (`support_shares`: modes × `supports`), and the
    /// shapes at the sensors (sensors × modes).
    fn modes<'py>(
        &self,
        py: Python<'py>,
        values: PyReadonlyArray1<'_, f64>,
        count: Option<usize>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let values = self.values(&values)?;
        let state = py.detach(|| self.state_at(&values)).or_py()?;
        let n = count.unwrap_or(state.modes.len()).min(state.modes.len());
        let d = PyDict::new(py);
        d.set_item(
            "frequency",
            PyArray1::from_vec(py, (0..n).map(|i| state.modes.frequency_hz(i)).collect()),
        )?;
        d.set_item("damping", PyArray1::from_vec(py, state.zeta[..n].to_vec()))?;
        let kinds: Vec<String> = state.modes.kinds[..n]
            .iter()
            .map(|k| format!("{k:?}").to_lowercase())
            .collect();
        d.set_item("kind", kinds)?;
        let axes = state.modes.deck_axes(&self.positions);
        let shares: Vec<_> = (0..n)
            .map(|i| {
                axes.as_ref()
                    .map_or_else(Default::default, |a| state.modes.motion(a, i))
            })
            .collect();
        let motion: Vec<Option<&str>> = shares.iter().map(|s| s.dominant().map(|m| m.label())).collect();
        d.set_item("motion", motion)?;
        let rows: Vec<Vec<f64>> = shares
            .iter()
            .map(|s| vec![s.longitudinal, s.transverse, s.vertical, s.torsion])
            .collect();
        d.set_item("motion_shares", matrix(py, &rows, 4))?;
        // Each support's share of each mode's strain energy, as `modes --json`.
        let (kappa, _) = model_at(&self.parameters, &self.setup.kappa, &self.setup.damping, &values).or_py()?;
        let blocks = self.setup.model.spring_blocks();
        let rows: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                blocks
                    .iter()
                    .zip(&kappa)
                    .map(|(b, k)| state.modes.spring_energy_share(i, b, k))
                    .collect()
            })
            .collect();
        d.set_item("support_shares", matrix(py, &rows, blocks.len()))?;
        d.set_item("supports", self.config.spring_field_names())?;
        let sensors = self.setup.sensor_names.len();
        let rows: Vec<Vec<f64>> = (0..sensors)
            .map(|s| (0..n).map(|i| state.amplitude(s, i)).collect())
            .collect();
        d.set_item("shapes", matrix(py, &rows, n))?;
        Ok(d)
    }

    /// FRFs at `values` on the lines `frequency_hz` for each (output,
    /// input) sensor pair: pairs × lines.
    fn frf<'py>(
        &self,
        py: Python<'py>,
        values: PyReadonlyArray1<'_, f64>,
        frequency_hz: PyReadonlyArray1<'_, f64>,
        pairs: Vec<(String, String)>,
        quantity_name: &str,
    ) -> PyResult<Bound<'py, PyArray2<numpy::Complex64>>> {
        let values = self.values(&values)?;
        let lines = finite_vector(&frequency_hz, "f")?;
        if let Some(i) = lines.iter().position(|&f| f <= 0.0) {
            return Err(bad(format!("f[{i}] = {} Hz: frequencies must be positive", lines[i])));
        }
        let pairs = pairs
            .iter()
            .map(|(output, input)| Ok((self.sensor(output)?, self.sensor(input)?)))
            .collect::<PyResult<Vec<_>>>()?;
        let quantity = quantity(quantity_name)?;
        let h = py
            .detach(|| -> anyhow::Result<Vec<_>> {
                let state = self.state_at(&values)?;
                let request = FrfRequest {
                    frequencies_hz: &lines,
                    pairs: &pairs,
                    quantity,
                };
                Ok(self.setup.model.evaluate(&state, request, false).h)
            })
            .or_py()?;
        let rows: Vec<Vec<_>> = h.chunks(lines.len()).map(<[_]>::to_vec).collect();
        Ok(crate::arrays::complex_matrix(py, &rows, lines.len()))
    }

    /// `splinewatch update --frf`: the result JSON (as `update --json`
    /// prints it) from `values`.
    fn update_frf(&self, py: Python<'_>, frf: &[u8], values: PyReadonlyArray1<'_, f64>) -> PyResult<String> {
        let start = self.start_json(&self.values(&values)?);
        let (result, _) = py
            .detach(|| studies::update(&self.config, frf, Some(&start), &mut |_| {}))
            .or_py()?;
        serde_json::to_string(&result).or_py()
    }

    /// `splinewatch update --modes`: the result JSON and the pairs
    /// (identified mode, model mode, MAC).
    fn update_modes(
        &self,
        py: Python<'_>,
        modes_json: &str,
        values: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<(String, Vec<ModePair>)> {
        let file: ModesFile = serde_json::from_str(modes_json).map_err(|e| bad(format!("not a modes file: {e}")))?;
        file.check().or_py()?;
        let start = self.start_json(&self.values(&values)?);
        let solution = py
            .detach(|| studies::update::update_from_modes(&self.config, &file, Some(&start), &mut |_| {}))
            .or_py()?;
        let pairs = solution.pairs.iter().map(|p| (p.observed, p.model, p.mac)).collect();
        Ok((serde_json::to_string(&solution.result).or_py()?, pairs))
    }

    /// `splinewatch synth`: FRF JSON of the model at the config's values.
    #[allow(clippy::too_many_arguments)]
    fn synth(
        &self,
        py: Python<'_>,
        inputs: Vec<String>,
        outputs: Vec<String>,
        f_min: f64,
        f_max: f64,
        step: f64,
        noise: f64,
        seed: u64,
        quantity_name: &str,
    ) -> PyResult<String> {
        let options = SynthOptions {
            inputs,
            outputs,
            quantity: quantity(quantity_name)?,
            f_min,
            f_max,
            step,
            noise,
            seed,
        };
        let file = py.detach(|| studies::synth::synth(&self.config, &options)).or_py()?;
        serde_json::to_string(&file).or_py()
    }

    /// `splinewatch matrices --out DIR`: writes the Matrix Market files and
    /// returns `index.json`'s text.
    fn export_matrices(&self, py: Python<'_>, dir: PathBuf) -> PyResult<String> {
        let (index, _) = py
            .detach(|| studies::matrices::export_matrices(&self.config, &dir))
            .or_py()?;
        serde_json::to_string(&index).or_py()
    }
}
