//! The shells that wire sources to the pipeline and the outputs: the live
//! daemon (zenoh), the offline replay (MCAP), the demo and the soak test,
//! and the fleet query of many daemons.
//! Room: above the pipeline and outputs. May import: `outputs`, `pipeline`, `studies`, `config`, `io`, the core crate.

pub mod daemon;
pub mod demo;
pub mod events;
pub mod export;
pub mod fleet;
pub mod frequency_domain;
pub mod records;
pub mod replay;
pub mod rescore;
pub mod soak;

use crate::config::Config;
use crate::outputs::state;
use crate::pipeline::Pipeline;
use anyhow::{Context, Result};
use std::collections::VecDeque;
use std::path::{Path, PathBuf};

/// The monitor file beside `state_path` (`[monitoring]`; daemon and
/// replay), resumed from when it exists, so a restart does not retrain.
pub(crate) fn resume_monitor(
    config: &Config,
    state_path: Option<&Path>,
    pipeline: &mut Pipeline,
) -> Result<Option<PathBuf>> {
    let path = state_path.and_then(|p| config.monitor_file(p));
    if let Some(path) = &path {
        if let Some(monitor) = state::load_monitor(path)? {
            tracing::info!(
                message = "monitor resumed",
                file = %path.display(),
                state = monitor.state().name(),
                training_left = monitor.training_left()
            );
            pipeline
                .restore_monitor(monitor)
                .with_context(|| format!("monitor file {}", path.display()))?;
        }
    }
    Ok(path)
}

/// Appends `item`, dropping the oldest beyond `keep`.
pub(crate) fn keep_latest<T>(list: &mut VecDeque<T>, item: T, keep: usize) {
    if keep == 0 {
        return;
    }
    if list.len() == keep {
        list.pop_front();
    }
    list.push_back(item);
}
