//! Creating output files with explicit permissions.

use anyhow::{Context, Result};
use std::fs::File;
use std::path::{Path, PathBuf};

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

/// `path` for 0, `<stem>-<index>.<ext>` otherwise.
pub fn numbered(path: &Path, index: u32) -> PathBuf {
    if index == 0 {
        return path.to_path_buf();
    }
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    match path.extension() {
        Some(ext) => path.with_file_name(format!("{stem}-{index}.{}", ext.to_string_lossy())),
        None => path.with_file_name(format!("{stem}-{index}")),
    }
}

/// The first of `path`, `<stem>-1.<ext>`, `<stem>-2.<ext>`, … that does not
/// exist: how a restarted daemon avoids overwriting an earlier run's output.
pub fn first_free(path: &Path) -> PathBuf {
    first_free_from(path, 0).1
}

/// The first number from `from` on whose [`numbered`] file does not exist,
/// and that file.
pub fn first_free_from(path: &Path, from: u32) -> (u32, PathBuf) {
    (from..)
        .map(|k| (k, numbered(path, k)))
        .find(|(_, p)| !p.exists())
        .expect("some number is free")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbering_skips_existing_files_and_new_files_get_the_output_mode() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("files");
        let path = dir.join("results.rrd");
        assert_eq!(first_free(&path), path);
        create_output_file(&path).unwrap();
        create_output_file(&dir.join("results-1.rrd")).unwrap();
        assert_eq!(first_free(&path), dir.join("results-2.rrd"));
        assert_eq!(numbered(&dir.join("state"), 3), dir.join("state-3"));
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, OUTPUT_FILE_MODE);
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
