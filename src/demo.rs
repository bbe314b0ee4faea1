//! `splinewatch demo`: the live path in one process. A daemon listens on a
//! free loopback port; the simulator publishes a bearing-damage scenario to
//! it over zenoh at high speed; results land in the output folder.

use crate::commands;
use crate::config::Config;
use crate::daemon::{self, Publisher, RunOptions, RunSummary};
use crate::recording::read_recording;
use crate::simulation::{parse_scenario, simulate, SimulationOptions};
use crate::viewer::RerunTargets;
use crate::wire::{Encoding, Limits};
use anyhow::{Context, Result};
use std::path::Path;

/// The demo's scenario: `east.k2` drops 40 % between 40 % and 60 % of the run.
pub fn demo_scenario(duration: f64) -> String {
    format!(
        "update_seconds = 5.0\n[[change]]\nparameter = \"east.k2\"\nstart_minute = {}\nend_minute = {}\nfactor = 0.6\n",
        0.4 * duration / 60.0,
        0.6 * duration / 60.0
    )
}

/// Runs the daemon on a free loopback port and `source` on a publisher
/// connected to it (on a blocking thread); stops the daemon once the source
/// is done and the daemon had time to drain.
pub fn run_with_source(
    mut cfg: Config,
    out: &Path,
    speed: f64,
    keep_updates: usize,
    source: impl FnOnce(&Config, &mut Publisher) -> Result<u64> + Send + 'static,
) -> Result<RunSummary> {
    let port = std::net::TcpListener::bind("127.0.0.1:0")?.local_addr()?.port();
    let endpoint = format!("tcp/127.0.0.1:{port}");
    cfg.zenoh.listen = vec![endpoint.clone()];
    cfg.zenoh.connect.clear();
    cfg.zenoh.multicast_scouting = false;
    cfg.zenoh.mode = "peer".into();
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let options = RunOptions {
        results: out.join("results.mcap"),
        state: Some(out.join("state.json")),
        rerun: RerunTargets {
            save: Some(out.join("results.rrd")),
            connect: cfg.output.rerun_connect.clone(),
        },
        keep_updates,
    };
    let mut publisher_cfg = cfg.zenoh.clone();
    publisher_cfg.listen.clear();
    publisher_cfg.mode = "client".into();
    publisher_cfg.connect = vec![endpoint];
    let prefix = cfg.topic_prefix();
    let source_cfg = cfg.clone();
    let runtime = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    runtime.block_on(async move {
        let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
        let daemon = tokio::spawn(daemon::run(cfg, options, async {
            let _ = stop_rx.await;
        }));
        // Give the daemon time to listen and declare its subscribers.
        tokio::time::sleep(std::time::Duration::from_millis(800)).await;
        let publisher = tokio::task::spawn_blocking(move || -> Result<u64> {
            let mut publisher = Publisher::open(&publisher_cfg, prefix, Encoding::Cbor, speed)?;
            // Let the publisher's session connect before the first block.
            std::thread::sleep(std::time::Duration::from_millis(500));
            let sent = source(&source_cfg, &mut publisher)?;
            std::thread::sleep(std::time::Duration::from_millis(500));
            publisher.close()?;
            Ok(sent)
        });
        let sent = publisher.await.context("the publisher panicked")??;
        // Drain: let the last messages and updates through.
        tokio::time::sleep(std::time::Duration::from_millis(1500)).await;
        let _ = stop_tx.send(());
        let summary = daemon.await.context("the daemon panicked")??;
        tracing::info!(
            message = "live run finished",
            published = sent,
            received = summary.messages
        );
        Ok(summary)
    })
}

/// Simulates a bearing-damage scenario and publishes it live.
pub fn run_live(config_path: &Path, out: &Path, duration: f64, speed: f64, seed: u64) -> Result<RunSummary> {
    let cfg = commands::load_config(config_path)?;
    let scenario = parse_scenario(&demo_scenario(duration))?;
    run_with_source(cfg, out, speed, usize::MAX, move |cfg, publisher| {
        let options = SimulationOptions {
            scenario: Some(scenario),
            ..SimulationOptions::random_excitation(cfg, duration, seed)
        };
        let mut sent = 0;
        simulate(cfg, &options, &mut |block| {
            sent += 1;
            publisher.publish(&block)
        })?;
        Ok(sent)
    })
}

/// Publishes the blocks of a recording live, in file order.
pub fn run_recording_live(config_path: &Path, recording: &Path, out: &Path, speed: f64) -> Result<RunSummary> {
    let cfg = commands::load_config(config_path)?;
    let bytes = std::fs::read(recording).with_context(|| format!("cannot read {}", recording.display()))?;
    let (blocks, _) = read_recording(&bytes, &Limits::default())?;
    run_with_source(cfg, out, speed, usize::MAX, move |_, publisher| {
        for b in &blocks {
            publisher.publish(&b.block)?;
        }
        Ok(blocks.len() as u64)
    })
}

/// The `demo` command: runs and prints a summary.
pub fn run_demo(config_path: &Path, out: &Path, duration: f64, speed: f64) -> Result<()> {
    let summary = run_live(config_path, out, duration, speed, 2026)?;
    eprintln!(
        "demo: {} messages received, {} windows, {} updates ({} failed); results in {}, state in {}",
        summary.messages,
        summary.windows,
        summary.updates.len(),
        summary.updates.iter().filter(|u| u.result.is_err()).count(),
        out.join("results.mcap").display(),
        out.join("state.json").display()
    );
    println!("{:>8} {:>14} {:>12}", "window", "east.k2", "rel. resid.");
    for u in &summary.updates {
        if let Ok(r) = &u.result {
            let k2 = r
                .result
                .parameters
                .iter()
                .find(|p| p.name == "east.k2")
                .map_or(f64::NAN, |p| p.value);
            println!("{:>8} {:>14.4e} {:>12.4}", u.window, k2, r.result.relative_residual);
        }
    }
    Ok(())
}

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
