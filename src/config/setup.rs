//! A validated configuration turned into ready-to-use core objects.

use super::Config;
use anyhow::{Context, Result};
use splinewatch_core::damping::DampingCurve;
use splinewatch_core::frf::{FrfModel, SensorPoint};

/// The model, its sensors and damping, ready for FRF work.
pub struct FrfSetup {
    pub model: FrfModel,
    pub sensor_names: Vec<String>,
    pub kappa: Vec<Vec<f64>>,
    pub damping: DampingCurve,
}

/// Assembles the configured model with its sensors and damping curve.
pub fn frf_setup(config: &Config) -> Result<FrfSetup> {
    frf_setup_with_points(config, &[])
}

/// As [`frf_setup`], with `extra` points appended to the model's sensor list
/// (after the configured sensors; the simulator's unmeasured force points).
pub fn frf_setup_with_points(config: &Config, extra: &[SensorPoint]) -> Result<FrfSetup> {
    let model = config.build_dense_model()?;
    let sensors = config.build_sensors(&model.shell)?;
    if sensors.is_empty() {
        anyhow::bail!("config: sensors: at least one [[sensors]] table is required for FRFs");
    }
    let damping = config.build_damping()?;
    let kappa = model.springs.iter().map(|s| s.stiffness().to_vec()).collect();
    let points: Vec<_> = sensors.iter().map(|(_, p)| *p).chain(extra.iter().copied()).collect();
    let frf_model = FrfModel::new(model.assemble().context("assembling the model")?, &points)?;
    Ok(FrfSetup {
        model: frf_model,
        sensor_names: sensors.into_iter().map(|(n, _)| n).collect(),
        kappa,
        damping,
    })
}
