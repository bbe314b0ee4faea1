//! A validated configuration turned into ready-to-use core objects.

use super::Config;
use anyhow::{Context, Result};
use splinewatch_core::c64;
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::frf::{FrfModel, FrfRequest, Sensor, SensorPoint};
use splinewatch_core::solvers::truncation::TruncationReport;

/// The model, its sensors and damping, ready for FRF work.
#[derive(Debug)]
pub struct FrfSetup {
    pub model: FrfModel,
    /// A truncated model's every-mode twin, when the model is small enough
    /// for the dense path to be cheap (at most
    /// [`super::model::AUTO_TRUNCATED_CONTROL_POINTS`] control points): the
    /// update report states the truncation error against it.
    pub reference: Option<FrfModel>,
    pub sensor_names: Vec<String>,
    pub kappa: Vec<Vec<f64>>,
    pub damping: DampingCurve,
}

impl FrfSetup {
    /// A truncated model's report at `(κ, θ)` and `damping` with
    /// `modes_kept` modes: with `fitted` (an FRF fit: the model's FRFs and
    /// the request they answer) and a reference model, the truncation error
    /// of those FRFs; `None` for every mode.
    pub fn truncation_report(
        &self,
        kappa: &[Vec<f64>],
        theta: &[Vec<f64>],
        damping: &DampingCurve,
        modes_kept: usize,
        fitted: Option<(&[c64], FrfRequest<'_>)>,
    ) -> Result<Option<TruncationReport>> {
        let Some(cutoff_hz) = self.model.cutoff_hz() else {
            return Ok(None);
        };
        let frf_error = match (&self.reference, fitted) {
            (Some(reference), Some((h, request))) => Some(
                reference
                    .truncation_error(h, kappa, theta, damping, request)
                    .context("the truncation error against every mode")?,
            ),
            _ => None,
        };
        Ok(Some(TruncationReport {
            cutoff_hz,
            modes_kept,
            frf_error,
        }))
    }
}

/// Assembles the configured model with its sensors and damping curve.
pub fn frf_setup(config: &Config) -> Result<FrfSetup> {
    frf_setup_with_points(config, &[])
}

/// As [`frf_setup`], with `extra` points appended to the model's sensor list
/// (after the configured sensors; the simulator's unmeasured force points).
pub fn frf_setup_with_points(config: &Config, extra: &[SensorPoint]) -> Result<FrfSetup> {
    frf_setup_of(config, &solver_model(config)?, extra)
}

/// The configured model as its solver takes it: any size for the modes
/// below a cut-off, a dense-sized one for every mode
/// ([`Config::build_dense_model`]).
pub fn solver_model(config: &Config) -> Result<BridgeModel> {
    Ok(match config.modal_cutoff_hz()? {
        Some(_) => config.build_model()?,
        None => config.build_dense_model()?,
    })
}

/// [`frf_setup_with_points`] on `model`, built from `config` by
/// [`solver_model`] (so that a caller who needs the model too builds it
/// once).
pub fn frf_setup_of(config: &Config, model: &BridgeModel, extra: &[SensorPoint]) -> Result<FrfSetup> {
    let cutoff_hz = config.modal_cutoff_hz()?;
    let sensors = config.build_sensors(model)?;
    if sensors.is_empty() {
        anyhow::bail!("config: sensors: at least one [[sensors]] table is required for FRFs");
    }
    let damping = config.build_damping()?;
    let kappa = model.spring_coefficients();
    let points: Vec<Sensor> = sensors
        .iter()
        .map(|(_, p)| *p)
        .chain(extra.iter().map(|&p| Sensor::Shell(p)))
        .collect();
    let dense = |model: &BridgeModel| -> Result<FrfModel> {
        Ok(FrfModel::new(
            model.assemble().context("assembling the model")?,
            &points,
        )?)
    };
    let (frf_model, reference) = match cutoff_hz {
        Some(cutoff_hz) => {
            let truncated = FrfModel::truncated(model, &points, cutoff_hz).context("assembling the sparse model")?;
            let small = model.control_point_count() <= super::model::AUTO_TRUNCATED_CONTROL_POINTS;
            (truncated, if small { Some(dense(model)?) } else { None })
        }
        None => (dense(model)?, None),
    };
    Ok(FrfSetup {
        model: frf_model,
        reference,
        sensor_names: sensors.into_iter().map(|(n, _)| n).collect(),
        kappa,
        damping,
    })
}
