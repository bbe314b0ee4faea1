//! The state file: the last accepted parameters, replaced atomically, so a
//! restarted daemon or a later replay warm-starts from them; and the
//! monitor file (`[monitoring]`), so a restart does not retrain.

use crate::pipeline::AcceptedParameters;
use anyhow::{Context, Result};
use splinewatch_core::monitoring::Monitor;
use std::fs::File;
use std::io::Write;
use std::path::Path;

/// Writes the state atomically: temporary file in the same folder, fsync,
/// rename over the old one, fsync of the folder. A crash leaves the old or
/// the new complete file.
pub fn save_state(path: &Path, state: &AcceptedParameters) -> Result<()> {
    save_json(path, state)
}

/// Saves the monitor (reference model and chart state) atomically, like the state.
pub fn save_monitor(path: &Path, monitor: &Monitor) -> Result<()> {
    save_json(path, monitor)
}

/// Loads a saved monitor; `None` if the file does not exist.
pub fn load_monitor(path: &Path) -> Result<Option<Monitor>> {
    match std::fs::read_to_string(path) {
        Ok(text) => {
            Ok(Some(serde_json::from_str(&text).with_context(|| {
                format!("monitor file {} is not valid", path.display())
            })?))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(e).with_context(|| format!("cannot read monitor file {}", path.display())),
    }
}

fn save_json(path: &Path, value: &impl serde::Serialize) -> Result<()> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let tmp = dir.join(format!(
        ".{}.tmp",
        path.file_name().and_then(|n| n.to_str()).unwrap_or("state.json")
    ));
    {
        let mut f = crate::io::files::create_output_file(&tmp)?;
        serde_json::to_writer_pretty(&mut f, value)?;
        f.write_all(b"\n")?;
        f.sync_all()
            .with_context(|| format!("cannot fsync {}", tmp.display()))?;
    }
    std::fs::rename(&tmp, path).with_context(|| format!("cannot replace {}", path.display()))?;
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// Loads a state file; `None` if it does not exist.
pub fn load_state(path: &Path) -> Result<Option<AcceptedParameters>> {
    match std::fs::read_to_string(path) {
        Ok(text) => {
            Ok(Some(serde_json::from_str(&text).with_context(|| {
                format!("state file {} is not valid", path.display())
            })?))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(e).with_context(|| format!("cannot read state file {}", path.display())),
    }
}
