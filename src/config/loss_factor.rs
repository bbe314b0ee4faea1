//! A support's `loss_factor` (spring fields, bearings, line and point
//! supports): its share of the modes' damping
//! ([`splinewatch_core::model::damping`]), on the whole support or on some
//! of its components (where each acts: [`super::loss_sites`]).

use super::{err, ConfigError};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A support's `loss_factor`: a value held, or updated within bounds.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum LossFactorConfig {
    /// `loss_factor = 0.1`: held at this value.
    Held(f64),
    /// `loss_factor = { value = 0.1, bounds = [0.0, 0.5] }`: updated within
    /// the bounds (`update = false` holds it).
    Table(LossFactorTable),
}

/// `loss_factor = { value, bounds, update }`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LossFactorTable {
    pub value: f64,
    /// `[lower, upper]` when updating.
    pub bounds: [f64; 2],
    #[serde(default = "default_true")]
    pub update: bool,
}

/// A bearing's or support's `loss_factor`: on the whole support, or per
/// component.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum ComponentLossFactor {
    /// `loss_factor = 0.1` or `{ value, bounds }`: every component.
    Whole(LossFactorConfig),
    /// `loss_factor = { y = 0.3, z = { value = 0.05, bounds = [0.0, 0.2] } }`:
    /// the components named (a support's `x` … `rz`, a bearing's `kx`,
    /// `ky`, `kz`), each with its own η (parameter
    /// `<name>.<component>.eta` when updated); the others are lossless.
    Components(BTreeMap<String, LossFactorConfig>),
}

impl LossFactorConfig {
    /// η.
    pub fn value(self) -> f64 {
        match self {
            Self::Held(value) | Self::Table(LossFactorTable { value, .. }) => value,
        }
    }

    /// The bounds, when it is updated.
    pub fn updated(self) -> Option<[f64; 2]> {
        match self {
            Self::Table(LossFactorTable {
                bounds, update: true, ..
            }) => Some(bounds),
            _ => None,
        }
    }

    /// A value finite and `>= 0`, within its bounds when updated.
    pub(super) fn check(self, key: &str) -> Result<(), ConfigError> {
        let value = self.value();
        if !(value.is_finite() && value >= 0.0) {
            return Err(err(
                key,
                format!("{value} must be a finite loss factor >= 0 (0.1 = 10 %)"),
            ));
        }
        if let Some([lo, hi]) = self.updated() {
            if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
                return Err(err(key, format!("bounds [{lo}, {hi}] must satisfy 0 <= lower < upper")));
            }
            if !(lo..=hi).contains(&value) {
                return Err(err(key, format!("value {value} lies outside its bounds [{lo}, {hi}]")));
            }
        }
        Ok(())
    }
}

fn default_true() -> bool {
    true
}
