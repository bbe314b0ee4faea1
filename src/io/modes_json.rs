//! The identified-modes file (`splinewatch oma --json`, `update --modes`):
//! `{"modes":[{"frequency_hz":…, "damping_ratio":…, "frequency_std_hz":…,
//! "damping_std":…, "shape":[{"sensor":"P1","re":…,"im":…},…]},…]}`.
//! Extra keys (`mpc`, `order`, `stable_orders`, `method`, `model`, a shape entry's
//! `std`, the file's `start`, `duration_s`, `fs_hz`) are informative; readers ignore
//! keys they do not know. A standard deviation is `null` when the
//! jackknife could not estimate it.

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use splinewatch_core::c64;
use splinewatch_core::updating::modal_residual::ObservedMode;
use std::path::Path;

/// Floors of the identified standard deviations used as weights: a
/// std the identification could not give (`null`), or one below what the
/// model can be expected to match (its own modelling error), is raised to
/// these: 0.05 % of the frequency, 1e-3 absolute damping ratio, 0.02 of a
/// unit-normalised shape component.
const FREQUENCY_STD_FLOOR: f64 = 5e-4;
const DAMPING_STD_FLOOR: f64 = 1e-3;
const SHAPE_STD_FLOOR: f64 = 0.02;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModesFile {
    pub modes: Vec<ModeEntry>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fs_hz: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModeEntry {
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    pub frequency_std_hz: Option<f64>,
    pub damping_std: Option<f64>,
    pub shape: Vec<ShapeEntry>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mpc: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub order: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stable_orders: Option<usize>,
    /// How the mode was found when not by the command's subspace method
    /// (SSI-cov for `oma`, SRIM for `identify` and `events`): absent for
    /// those.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<ModeMethod>,
    /// With a config that has a model: the model mode nearest this one by
    /// shape.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<ModelMatch>,
}

/// An estimator of modes other than the subspace methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ModeMethod {
    /// The pole–residue fit of the H1 transmissibilities
    /// (`[oma.frequency_domain]`).
    PoleResidue,
}

/// The model mode nearest an identified one by shape: the largest MAC at
/// the identified mode's sensors over the model's flexible modes, whatever
/// their frequency.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelMatch {
    /// The model mode, numbered as `splinewatch modes` numbers them (from 1).
    pub mode: usize,
    pub frequency_hz: f64,
    /// The model mode's damping ratio ζ (`[model.damping]`'s curve and the
    /// supports' loss factors), to compare with the identified one.
    pub damping_ratio: f64,
    pub mac: f64,
    /// `(f_model − f_identified) / f_identified`.
    pub frequency_gap: f64,
    /// Whether updating on this mode would pair it with that model mode
    /// (`[updating] min_mac` and `max_frequency_gap`).
    pub pairs: bool,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShapeEntry {
    pub sensor: String,
    pub re: f64,
    pub im: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std: Option<f64>,
}

impl ModesFile {
    /// A file of `modes` alone.
    pub fn of(modes: Vec<ModeEntry>) -> Self {
        Self {
            modes,
            start: None,
            duration_s: None,
            fs_hz: None,
        }
    }

    /// Reads and checks a modes file: finite positive frequencies, damping
    /// in (−1, 1), finite shapes with at least one sensor.
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
        let file: Self =
            serde_json::from_str(&text).with_context(|| format!("{}: not a modes file", path.display()))?;
        file.check().with_context(|| path.display().to_string())?;
        Ok(file)
    }

    /// The identified modes on the model's sensors (`sensor_names`, the
    /// config's order), with their standard deviations as updating weights
    /// (raised to the floors above).
    pub fn to_observed(&self, sensor_names: &[String]) -> Result<Vec<ObservedMode>> {
        self.modes
            .iter()
            .enumerate()
            .map(|(k, m)| {
                let shape = m
                    .shape
                    .iter()
                    .map(|s| {
                        let index = sensor_names
                            .iter()
                            .position(|n| n == &s.sensor)
                            .with_context(|| format!("modes[{k}].shape: {:?} is not a config sensor", s.sensor))?;
                        Ok((index, c64::new(s.re, s.im)))
                    })
                    .collect::<Result<Vec<_>>>()?;
                let largest = shape.iter().map(|(_, v)| v.norm()).fold(0.0, f64::max);
                let stds: Vec<f64> = m.shape.iter().filter_map(|s| s.std).collect();
                let shape_std = if stds.is_empty() || largest == 0.0 {
                    SHAPE_STD_FLOOR
                } else {
                    ((stds.iter().map(|s| s * s).sum::<f64>() / stds.len() as f64).sqrt() / largest)
                        .max(SHAPE_STD_FLOOR)
                };
                Ok(ObservedMode {
                    frequency_hz: m.frequency_hz,
                    frequency_std_hz: m
                        .frequency_std_hz
                        .unwrap_or(0.0)
                        .max(FREQUENCY_STD_FLOOR * m.frequency_hz),
                    damping_ratio: m.damping_ratio,
                    damping_std: m.damping_std.unwrap_or(0.0).max(DAMPING_STD_FLOOR),
                    shape,
                    shape_std,
                })
            })
            .collect()
    }

    pub fn check(&self) -> Result<()> {
        if self.modes.is_empty() {
            bail!("modes: the file holds no mode");
        }
        for (i, m) in self.modes.iter().enumerate() {
            if !(m.frequency_hz.is_finite() && m.frequency_hz > 0.0) {
                bail!(
                    "modes[{i}].frequency_hz must be a positive number, got {}",
                    m.frequency_hz
                );
            }
            if !(m.damping_ratio.is_finite() && m.damping_ratio.abs() < 1.0) {
                bail!("modes[{i}].damping_ratio must be in (-1, 1), got {}", m.damping_ratio);
            }
            for (key, std) in [("frequency_std_hz", m.frequency_std_hz), ("damping_std", m.damping_std)] {
                if std.is_some_and(|s| !(s.is_finite() && s >= 0.0)) {
                    bail!("modes[{i}].{key} must be a non-negative number or null");
                }
            }
            if m.shape.is_empty() {
                bail!("modes[{i}].shape is empty");
            }
            if let Some(j) = m.shape.iter().position(|s| !(s.re.is_finite() && s.im.is_finite())) {
                bail!("modes[{i}].shape[{j}] ({}) is not finite", m.shape[j].sensor);
            }
        }
        Ok(())
    }
}
