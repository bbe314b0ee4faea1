//! `splinewatch soak`: the daemon and a publisher in one process, a
//! recording published over and over for many hours of data; RSS sampled.
//! Room: a service shell. May import: `outputs`, `pipeline`, `studies`, `config`, `io`, the core crate.

use super::daemon::RunSummary;
use super::demo::run_with_source;
use crate::config::Config;
use crate::io::recording::read_recording;
use crate::io::wire::Limits;
use anyhow::{Context, Result};
use std::path::Path;

/// Resident set size of this process in KiB (Linux `/proc/self/status`).
pub fn resident_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// One row of the soak report.
#[derive(Debug, Clone, Copy)]
pub struct SoakSample {
    /// Hours of data published so far.
    pub data_hours: f64,
    pub wall_seconds: f64,
    pub rss_kib: Option<u64>,
}

/// The soak test: publishes `recording` over and over, shifted in time so
/// that it reads as one continuous stream, at `speed` × real time (0: as
/// fast as the publisher can, a flood far above the logger's rate), until
/// `hours` of data went out; samples the process's RSS every hour of data.
/// Returns the daemon's summary, the samples and the number of blocks sent.
pub fn soak(
    mut cfg: Config,
    recording: &Path,
    out: &Path,
    hours: f64,
    speed: f64,
) -> Result<(RunSummary, Vec<SoakSample>, u64)> {
    let bytes = std::fs::read(recording).with_context(|| format!("cannot read {}", recording.display()))?;
    let (blocks, _) = read_recording(&bytes, &Limits::default())?;
    let (Some(first), Some(last)) = (blocks.first(), blocks.last()) else {
        anyhow::bail!("{} holds no blocks", recording.display());
    };
    let block_ns = (last.block.data.len() as f64 / last.block.fs * 1e9) as i128;
    let span_ns = last.block.start_ns + block_ns - first.block.start_ns;
    let loops = ((hours * 3600e9) / span_ns as f64).ceil() as i128;
    let samples = std::sync::Arc::new(std::sync::Mutex::new(vec![SoakSample {
        data_hours: 0.0,
        wall_seconds: 0.0,
        rss_kib: resident_kib(),
    }]));
    let recorded = std::sync::Arc::clone(&samples);
    cfg.output.rerun_connect = None;
    let started = std::time::Instant::now();
    let sent = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
    let counter = std::sync::Arc::clone(&sent);
    let summary = run_with_source(cfg, out, speed, 1, move |_, publisher| {
        let mut next_hour = 1.0;
        for k in 0..loops {
            for b in &blocks {
                let mut block = b.block.clone();
                block.start_ns += k * span_ns;
                publisher.publish(&block)?;
                counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            }
            let data_hours = ((k + 1) * span_ns) as f64 / 3600e9;
            if data_hours >= next_hour {
                next_hour += 1.0;
                if let Ok(mut s) = recorded.lock() {
                    s.push(SoakSample {
                        data_hours,
                        wall_seconds: started.elapsed().as_secs_f64(),
                        rss_kib: resident_kib(),
                    });
                }
            }
        }
        Ok(counter.load(std::sync::atomic::Ordering::Relaxed))
    })?;
    let mut samples = samples.lock().map(|s| s.clone()).unwrap_or_default();
    samples.push(SoakSample {
        data_hours: (loops * span_ns) as f64 / 3600e9,
        wall_seconds: started.elapsed().as_secs_f64(),
        rss_kib: resident_kib(),
    });
    Ok((summary, samples, sent.load(std::sync::atomic::Ordering::Relaxed)))
}
