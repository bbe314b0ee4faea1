//! Creating output files with explicit permissions.

use anyhow::{Context, Result};
use std::fs::File;
use std::path::Path;

/// Permissions of every file splinewatch writes (results, state, raw-input
/// recordings, `.rrd`, recovered files): owner read/write, group read,
/// nothing for others, whatever the process umask.
pub const OUTPUT_FILE_MODE: u32 = 0o640;

/// Creates (or truncates) `path` for writing, creating its folder, and sets
/// [`OUTPUT_FILE_MODE`] on it.
pub fn create_output_file(path: &Path) -> Result<File> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let file = File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        file.set_permissions(std::fs::Permissions::from_mode(OUTPUT_FILE_MODE))
            .with_context(|| format!("cannot set the permissions of {}", path.display()))?;
    }
    Ok(file)
}
