//! `[schedule]`: when the updating runs and which windows it accepts.

use serde::{Deserialize, Serialize};

/// Scheduling and quality settings (`[schedule]`).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ScheduleConfig {
    /// Run the updating after this many accepted windows.
    pub update_every_windows: u64,
    /// If set, run the updating instead at the first accepted window ending at
    /// least this many minutes (of measurement time) after the previous update
    /// (or the first sample); `update_every_windows` is then ignored.
    pub update_every_minutes: Option<f64>,
    /// Skip a window whose FRFs have a mean coherence in the band below this.
    pub min_coherence: f64,
    /// Skip a window with fewer clean segments than this fraction of the possible ones.
    pub min_segment_fraction: f64,
    /// A channel may lag the others by at most this; beyond, its missing samples count as a gap.
    pub max_lag_seconds: f64,
}

impl Default for ScheduleConfig {
    fn default() -> Self {
        Self {
            update_every_windows: 1,
            update_every_minutes: None,
            min_coherence: 0.6,
            min_segment_fraction: 0.5,
            max_lag_seconds: 30.0,
        }
    }
}
