//! The identified-modes file (`splinewatch oma --json`, `update --modes`):
//! `{"modes":[{"frequency_hz":…, "damping_ratio":…, "frequency_std_hz":…,
//! "damping_std":…, "shape":[{"sensor":"P1","re":…,"im":…},…]},…]}`.
//! Extra keys (`mpc`, `order`, `stable_orders`, a shape entry's `std`, the
//! file's `start`, `duration_s`, `fs_hz`) are informative; readers ignore
//! keys they do not know. A standard deviation is `null` when the
//! jackknife could not estimate it.

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

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
    /// Reads and checks a modes file: finite positive frequencies, damping
    /// in (−1, 1), finite shapes with at least one sensor.
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
        let file: Self =
            serde_json::from_str(&text).with_context(|| format!("{}: not a modes file", path.display()))?;
        file.check().with_context(|| path.display().to_string())?;
        Ok(file)
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
