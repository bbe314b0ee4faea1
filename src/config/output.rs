//! `[output]` and `[output.raw]`: where results, state, Rerun and raw-input
//! recordings go, and when their files rotate.

use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// `[output]`: where results go.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct OutputConfig {
    /// Folder for results MCAP files and the state file (default `out/<structure.name>`).
    pub dir: Option<std::path::PathBuf>,
    /// State file (default `<dir>/state.json`).
    pub state_file: Option<std::path::PathBuf>,
    /// Rerun `.rrd` file (relative to `dir`); none by default.
    pub rerun_save: Option<std::path::PathBuf>,
    /// A Rerun viewer to stream to, e.g. "rerun+http://127.0.0.1:9876/proxy".
    pub rerun_connect: Option<String>,
    /// `[output.raw]`: optional raw-input recording.
    pub raw: RawRecordingConfig,
    /// Start a new `.rrd` file after this much measurement time.
    pub rerun_rotate_hours: f64,
    /// Finalise the results MCAP file and start a new one after this much
    /// measurement time.
    pub results_rotate_hours: f64,
}

impl Default for OutputConfig {
    fn default() -> Self {
        Self {
            dir: None,
            state_file: None,
            rerun_save: None,
            rerun_connect: None,
            raw: Default::default(),
            rerun_rotate_hours: 24.0,
            results_rotate_hours: 24.0,
        }
    }
}

/// `[output.raw]`: optional raw-input recording.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct RawRecordingConfig {
    pub enabled: bool,
    /// Folder of the files (relative to `[output] dir`).
    pub dir: PathBuf,
    /// Start a new file after this much measurement time.
    pub rotate_minutes: f64,
    /// Start a new file once this many bytes of messages were written.
    pub rotate_megabytes: f64,
}

impl Default for RawRecordingConfig {
    fn default() -> Self {
        Self {
            enabled: false,
            dir: PathBuf::from("raw"),
            rotate_minutes: 60.0,
            rotate_megabytes: 512.0,
        }
    }
}
