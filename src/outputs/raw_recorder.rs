//! Raw-input recording in the daemon: every decoded block goes to MCAP
//! files in the wire format (readable by `replay`, `frf` and Foxglove),
//! rotated by measurement time and by size so that a file is never
//! unbounded and at most one is unfinished at any moment.
//!
//! A file is written as `raw-<first block time>.mcap.part` and renamed to
//! `.mcap` once its summary is written: a `.part` file is the one that was
//! open when the process stopped abnormally (its completed chunks are
//! readable; see `splinewatch recover`). A write error (full or read-only
//! disk) is logged and counted by the caller; the file is abandoned and the
//! next block starts a new one, so the daemon keeps running.

use crate::config::RawRecordingConfig;
use crate::io::recording::RecordingWriter;
use crate::io::wire::{format_timestamp, ChannelBlock, Encoding};
use anyhow::{Context, Result};
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

struct OpenFile {
    writer: RecordingWriter<BufWriter<File>>,
    part: PathBuf,
    start_ns: i128,
    bytes: u64,
}

pub struct RawRecorder {
    dir: PathBuf,
    prefix: String,
    rotate_ns: i128,
    rotate_bytes: u64,
    current: Option<OpenFile>,
    /// Completed (renamed) files, oldest first.
    pub completed: Vec<PathBuf>,
}

impl RawRecorder {
    pub fn new(dir: &Path, prefix: &str, settings: &RawRecordingConfig) -> Result<Self> {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            prefix: prefix.to_string(),
            rotate_ns: (settings.rotate_minutes * 60e9) as i128,
            rotate_bytes: (settings.rotate_megabytes * 1e6) as u64,
            current: None,
            completed: Vec::new(),
        })
    }

    /// Appends `block`, rotating first when the open file is full. On an
    /// error the open file is dropped (its `.part` stays on disk) and the
    /// next call starts a new one.
    pub fn record(&mut self, block: &ChannelBlock) -> Result<()> {
        let prefix = self.prefix.clone();
        self.write(block.start_ns, |w| w.write_block(&prefix, block))
    }

    /// Appends a pre-computed FRF message received on `key` at `time_ns`.
    pub fn record_frf(&mut self, key: &str, time_ns: i128, payload: &[u8]) -> Result<()> {
        self.write(time_ns, |w| w.write_json(key, time_ns, payload))
    }

    fn write(
        &mut self,
        time_ns: i128,
        write: impl FnOnce(&mut RecordingWriter<std::io::BufWriter<std::fs::File>>) -> Result<usize>,
    ) -> Result<()> {
        let rotate = self
            .current
            .as_ref()
            .is_some_and(|f| time_ns - f.start_ns >= self.rotate_ns || f.bytes >= self.rotate_bytes);
        if rotate {
            self.close()?;
        }
        if self.current.is_none() {
            let stamp = format_timestamp(time_ns).replace(':', "-");
            let part = self.dir.join(format!("raw-{stamp}.mcap.part"));
            let writer = RecordingWriter::create(&part, Encoding::Cbor)?;
            self.current = Some(OpenFile {
                writer,
                part,
                start_ns: time_ns,
                bytes: 0,
            });
        }
        let file = self.current.as_mut().expect("opened above");
        match write(&mut file.writer) {
            Ok(bytes) => {
                file.bytes += bytes as u64;
                Ok(())
            }
            Err(e) => {
                self.current = None;
                Err(e)
            }
        }
    }

    /// Finishes the open file (summary, index) and renames it to `.mcap`.
    pub fn close(&mut self) -> Result<()> {
        let Some(file) = self.current.take() else {
            return Ok(());
        };
        file.writer.finish()?;
        let done = file.part.with_extension("");
        std::fs::rename(&file.part, &done)
            .with_context(|| format!("cannot rename {} to {}", file.part.display(), done.display()))?;
        self.completed.push(done);
        Ok(())
    }
}
