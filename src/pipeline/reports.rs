//! What the pipeline reports: health counters, closed windows and the
//! accepted parameters that the state file keeps.

use super::WindowModes;
use crate::io::frf_json::FrfFile;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::Arc;

/// Counters published on `<prefix>/health`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Health {
    pub blocks: u64,
    pub samples: u64,
    /// Rejected messages and blocks by reason.
    pub rejected: BTreeMap<String, u64>,
    pub gaps: u64,
    pub gap_samples: u64,
    pub segments_accepted: u64,
    pub segments_rejected: u64,
    pub windows_accepted: u64,
    pub windows_skipped: BTreeMap<String, u64>,
    pub update_runs: u64,
    pub update_failures: u64,
    /// Update jobs never run, by reason (`queue_full`: dropped from the full
    /// update queue; `shutdown`: still waiting when the daemon stopped).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub updates_skipped: BTreeMap<String, u64>,
    pub queue_drops: u64,
    /// Raw-input recording errors (write failures, full disk); the block
    /// is still analysed.
    #[serde(default)]
    pub recording_errors: u64,
    /// Results MCAP errors (write failures; a new file is opened).
    #[serde(default)]
    pub results_errors: u64,
    /// Rerun output errors (e.g. a rotated `.rrd` that cannot be created).
    #[serde(default)]
    pub rerun_errors: u64,
    /// Log lines dropped because the log stream (stderr) was closed or
    /// failing; the analysis goes on.
    #[serde(default)]
    pub log_writes_dropped: u64,
    /// Temperature blocks taken (`[monitoring]`).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub temperature_blocks: u64,
    /// Temperature samples dropped unused (more than the store holds).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub temperature_samples_dropped: u64,
    /// Windows with a missing or stuck temperature, by flag
    /// (`temperature_missing:<name>`, `temperature_stuck:<name>`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub temperature_flags: BTreeMap<String, u64>,
    /// `[events]` (a triggered logger): bursts run through the event
    /// chain, and those skipped (with the reason on `events/summary`).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub events_processed: u64,
    /// Acceleration blocks of config sensors taken by the event chain
    /// (the daemon with `[events]`), not by the ambient pipeline.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub event_blocks: u64,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub events_skipped: u64,
    /// `[monitoring.notify]`: command runs (retries included), notifications
    /// delivered, and given up or dropped.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub notification_attempts: u64,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub notifications_sent: u64,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub notification_failures: u64,
    /// With both paths, windows whose FRFs or identification failed, by
    /// `frf:<reason>` / `oma:<reason>` (the window may still be updated on
    /// the other part).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub window_paths_skipped: BTreeMap<String, u64>,
    /// Updates the monitor could not score (training not possible yet).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub monitoring_errors: u64,
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

impl Health {
    pub fn reject(&mut self, reason: &str) {
        *self.rejected.entry(reason.to_string()).or_insert(0) += 1;
    }
}

/// The last accepted parameters (persisted in the state file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AcceptedParameters {
    pub window: u64,
    pub time: String,
    pub parameters: Vec<StateParameter>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StateParameter {
    pub name: String,
    pub value: f64,
    pub std: Option<f64>,
}

/// A closed analysis window.
#[derive(Debug, Clone)]
pub struct WindowReport {
    pub index: u64,
    pub start_ns: i128,
    pub end_ns: i128,
    pub segments_accepted: u64,
    pub segments_rejected: u64,
    /// Mean coherence in the band per FRF.
    pub mean_coherence: Vec<f64>,
    /// `None` when accepted.
    pub skipped: Option<String>,
    pub frf: Option<FrfFile>,
    /// Output-only: the share of instants with every channel valid.
    pub valid_fraction: Option<f64>,
    /// Output-only: the identified modes, paired with the model's.
    pub modes: Option<Arc<WindowModes>>,
    /// With both paths (a force sensor and `[oma]`): why the FRFs, or the
    /// identification, failed in this window (`skipped` is the window's own
    /// reason: nothing for the update to fit).
    pub frf_skipped: Option<String>,
    pub oma_skipped: Option<String>,
}
