//! A support's `loss_factor` (spring fields, bearings, line supports): its
//! share of the modes' damping ([`splinewatch_core::model::damping`]).

use serde::{Deserialize, Serialize};

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
}

fn default_true() -> bool {
    true
}
