//! `splinewatch demo`: the live path in one process. A daemon listens on a
//! free loopback port; the simulator publishes a bearing-damage scenario to
//! it over zenoh at high speed; results land in the output folder.
//! Room: a service shell. May import: `outputs`, `pipeline`, `studies`, `config`, `io`, the core crate.

use super::daemon::{self, RunOptions, RunSummary};
use crate::config::{load_config, Config};
use crate::io::recording::read_recording;
use crate::io::wire::{Encoding, Limits};
use crate::outputs::publisher::Publisher;
use crate::outputs::rerun::RerunTargets;
use crate::studies::simulation::{parse_scenario, simulate, SimulationOptions};
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
    let cfg = load_config(config_path)?;
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
    let cfg = load_config(config_path)?;
    let bytes = std::fs::read(recording).with_context(|| format!("cannot read {}", recording.display()))?;
    let (blocks, _) = read_recording(&bytes, &Limits::default())?;
    run_with_source(cfg, out, speed, usize::MAX, move |_, publisher| {
        for b in &blocks {
            publisher.publish(&b.block)?;
        }
        Ok(blocks.len() as u64)
    })
}

/// Whether `name` is one of the files a demo writes in its folder:
/// `state.json`, `results.mcap`, `results.rrd` or a numbered
/// `results-<n>.mcap`/`.rrd` (what a daemon restarted on them writes).
fn is_demo_file(name: &str) -> bool {
    let numbered = |ext: &str| {
        name.strip_prefix("results-")
            .and_then(|rest| rest.strip_suffix(ext))
            .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
    };
    matches!(name, "state.json" | "results.mcap" | "results.rrd") || numbered(".mcap") || numbered(".rrd")
}

/// The demo's files in `out` (regular files only), sorted.
pub fn demo_files(out: &Path) -> Vec<std::path::PathBuf> {
    let mut files: Vec<_> = std::fs::read_dir(out)
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| is_demo_file(&e.file_name().to_string_lossy()))
        .map(|e| e.path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

/// Removes a previous demo's files from `out` (only those, never anything
/// else), so a demo starts fresh instead of warm-starting from the last
/// one; returns their names.
pub fn clear_previous(out: &Path) -> Result<Vec<String>> {
    demo_files(out)
        .into_iter()
        .map(|path| {
            std::fs::remove_file(&path).with_context(|| format!("cannot remove {}", path.display()))?;
            Ok(path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::is_demo_file;

    #[test]
    fn only_the_demos_own_files_are_cleared() {
        for name in [
            "state.json",
            "results.mcap",
            "results.rrd",
            "results-1.mcap",
            "results-12.rrd",
        ] {
            assert!(is_demo_file(name), "{name}");
        }
        for name in [
            "notes.txt",
            "results-.mcap",
            "results-a.mcap",
            "results.json",
            "raw",
            "state.json.bak",
        ] {
            assert!(!is_demo_file(name), "{name}");
        }
    }
}
