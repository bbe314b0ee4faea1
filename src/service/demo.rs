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
use anyhow::{bail, Context, Result};
use std::path::Path;

/// What the demo simulates: the scenario (TOML) and the run's length.
#[derive(Debug, Clone, PartialEq)]
pub struct DemoPlan {
    pub scenario: String,
    /// Simulated seconds.
    pub duration: f64,
    /// When `east.k2` starts to drop, seconds from the start.
    pub damage_from: f64,
}

/// The simulated seconds of a demo without `[monitoring]` unless given.
pub const DEFAULT_DEMO_SECONDS: f64 = 600.0;

/// Windows a monitoring demo runs after training unless a duration is given;
/// the damage comes halfway through them.
const SCORED_WINDOWS: f64 = 50.0;

/// The fewest windows after training a monitoring demo accepts: the damage
/// halfway, then room for the alarm's persistence (`[k, m]`) to fill.
const FEWEST_SCORED_WINDOWS: f64 = 30.0;

/// The demo's scenario for `cfg`. Without `[monitoring]`: `east.k2` drops
/// 40 % between 40 % and 60 % of the run (600 s unless given). With it:
/// the monitored temperatures are published too (a steady 10 °C with
/// 0.3 °C of sensor noise), the reference trains on its first
/// `training_windows` updates, and `east.k2` drops 40 % at once halfway
/// through the scored windows after them, so the run raises an alarm.
pub fn demo_plan(cfg: &Config, duration: Option<f64>) -> Result<DemoPlan> {
    let change = |from: f64, to: f64| {
        format!(
            "[[change]]\nparameter = \"east.k2\"\nstart_minute = {}\nend_minute = {}\nfactor = 0.6\n",
            from / 60.0,
            to / 60.0
        )
    };
    let Some(monitoring) = &cfg.monitoring else {
        let duration = duration.unwrap_or(DEFAULT_DEMO_SECONDS);
        let damage_from = 0.4 * duration;
        return Ok(DemoPlan {
            scenario: format!("update_seconds = 5.0\n{}", change(damage_from, 0.6 * duration)),
            duration,
            damage_from,
        });
    };
    if monitoring.training_from.is_some() || monitoring.training_until.is_some() {
        bail!(
            "the demo trains [monitoring] on its first training_windows updates; this config trains on a time span \
             (training_from, training_until): remove them for the demo"
        );
    }
    if cfg.schedule.update_every_minutes.is_some() {
        bail!("the demo counts updates in windows; this config updates by time ([schedule] update_every_minutes): remove it for the demo");
    }
    let update_seconds = cfg.frf.window_seconds * cfg.schedule.update_every_windows as f64;
    let training = monitoring.training_windows as f64 * update_seconds;
    let fewest = training + FEWEST_SCORED_WINDOWS * update_seconds;
    let duration = duration.unwrap_or(training + SCORED_WINDOWS * update_seconds);
    if duration < fewest {
        bail!(
            "--duration {duration} s is too short for a monitoring demo: [monitoring] trains on {} updates of {update_seconds} s \
             ({training} s), then the damage needs {} more updates to raise an alarm: give --duration {fewest} or more",
            monitoring.training_windows,
            FEWEST_SCORED_WINDOWS
        );
    }
    let damage_from = training + 0.5 * (duration - training);
    let mut scenario = String::from("update_seconds = 5.0\n");
    if !monitoring.temperature_channels.is_empty() {
        let channels: Vec<String> = monitoring
            .temperature_channels
            .iter()
            .map(|c| format!("{c:?}"))
            .collect();
        scenario += &format!(
            "[environment]\nchannels = [{}]\nmean_c = 10.0\nnoise_c = 0.3\nsample_seconds = {}\n",
            channels.join(", "),
            (update_seconds / 4.0).min(60.0)
        );
    }
    scenario += &change(damage_from, damage_from);
    Ok(DemoPlan {
        scenario,
        duration,
        damage_from,
    })
}

/// How long a live run waits, once its source is done, for the daemon to
/// take the messages still on their way.
pub const DRAIN_LIMIT: std::time::Duration = std::time::Duration::from_secs(60);

/// How a live run's publisher keeps pace.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pacing {
    /// At the run's speed alone: a daemon that falls behind skips and
    /// counts updates, as on a site.
    Clock,
    /// At the run's speed, held back while the daemon has
    /// [`HOLD_BACK_AT`] updates waiting or [`HOLD_BACK_MESSAGES`] messages
    /// not yet taken: the demo's every window is updated whatever else
    /// loads the host (slower then, never different).
    Updates,
}

/// Waiting updates at which [`Pacing::Updates`] holds the publisher back
/// (the daemon's queue skips beyond 16).
const HOLD_BACK_AT: usize = 4;
/// Messages on their way at which [`Pacing::Updates`] holds back.
const HOLD_BACK_MESSAGES: u64 = 512;

/// Runs the daemon on a free loopback port and `source` on a publisher
/// connected to it (on a blocking thread), started once the daemon's
/// subscribers are declared; stops the daemon once it has taken every
/// message the source sent (or [`DRAIN_LIMIT`] passed) and the last
/// windows' updates had time to run.
pub fn run_with_source(
    cfg: Config,
    out: &Path,
    speed: f64,
    keep_updates: usize,
    source: impl FnOnce(&Config, &mut Publisher) -> Result<u64> + Send + 'static,
) -> Result<RunSummary> {
    run_paced(cfg, out, (speed, Pacing::Clock), keep_updates, source)
}

fn run_paced(
    mut cfg: Config,
    out: &Path,
    (speed, pacing): (f64, Pacing),
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
        let (progress_tx, mut progress) = tokio::sync::watch::channel(None);
        let daemon = tokio::spawn(async move {
            daemon::run_observed(cfg, options, &progress_tx, async {
                let _ = stop_rx.await;
            })
            .await
        });
        if progress.wait_for(Option::is_some).await.is_err() {
            // The daemon stopped before it listened: its error says why.
            daemon.await.context("the daemon panicked")??;
            bail!("the daemon stopped before it listened");
        }
        let gate_progress = progress.clone();
        let publisher = tokio::task::spawn_blocking(move || -> Result<u64> {
            let mut publisher = Publisher::open(&publisher_cfg, prefix, Encoding::Cbor, speed)?;
            if pacing == Pacing::Updates {
                publisher.hold_back_with(hold_back(gate_progress));
            }
            // Let the publisher's session connect before the first block.
            std::thread::sleep(std::time::Duration::from_millis(500));
            let sent = source(&source_cfg, &mut publisher)?;
            std::thread::sleep(std::time::Duration::from_millis(500));
            publisher.close()?;
            Ok(sent)
        });
        let sent = publisher.await.context("the publisher panicked")??;
        // Drain: every message sent taken by the daemon, then time for the
        // last windows' updates (a waiting one is skipped at shutdown, with
        // its reason).
        let all_taken = progress.wait_for(|p| p.is_some_and(|p| p.taken >= sent));
        if tokio::time::timeout(DRAIN_LIMIT, all_taken).await.is_err() {
            tracing::warn!(
                message = "the daemon had not taken every message sent; stopping it",
                sent,
                taken = progress.borrow().map_or(0, |p| p.taken),
                waited_s = DRAIN_LIMIT.as_secs()
            );
        }
        if pacing == Pacing::Updates {
            // Every window's update run, however loaded the host.
            let none_waiting = progress.wait_for(|p| p.is_some_and(|p| p.updates_waiting == 0));
            let _ = tokio::time::timeout(DRAIN_LIMIT, none_waiting).await;
        }
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

/// [`Pacing::Updates`]' gate: before each block, waits while the daemon
/// is behind (never past the drain limit: a daemon that stopped taking
/// messages is the drain's to report).
fn hold_back(progress: tokio::sync::watch::Receiver<Option<daemon::Progress>>) -> impl FnMut() + Send + 'static {
    let mut published = 0u64;
    move || {
        published += 1;
        let since = std::time::Instant::now();
        let behind = |p: &daemon::Progress| {
            p.updates_waiting >= HOLD_BACK_AT || published.saturating_sub(p.taken) > HOLD_BACK_MESSAGES
        };
        while progress.borrow().as_ref().is_some_and(behind) && since.elapsed() < DRAIN_LIMIT {
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
    }
}

/// Simulates the demo's bearing-damage scenario ([`demo_plan`]) and
/// publishes it live.
pub fn run_live(cfg: Config, plan: &DemoPlan, out: &Path, speed: f64, seed: u64) -> Result<RunSummary> {
    let duration = plan.duration;
    let scenario = parse_scenario(&plan.scenario)?;
    run_paced(cfg, out, (speed, Pacing::Updates), usize::MAX, move |cfg, publisher| {
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
    run_paced(cfg, out, (speed, Pacing::Updates), usize::MAX, move |_, publisher| {
        for b in &blocks {
            publisher.publish(&b.block)?;
        }
        Ok(blocks.len() as u64)
    })
}

/// Whether `name` is one of the files a demo writes in its folder:
/// `state.json`, `monitoring.json` (the monitoring reference), `results.mcap`,
/// `results.rrd`, `report.html` or a numbered
/// `results-<n>.mcap`/`.rrd` (what a daemon restarted on them writes).
fn is_demo_file(name: &str) -> bool {
    let numbered = |ext: &str| {
        name.strip_prefix("results-")
            .and_then(|rest| rest.strip_suffix(ext))
            .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
    };
    matches!(
        name,
        "state.json" | "monitoring.json" | "results.mcap" | "results.rrd" | "report.html"
    ) || numbered(".mcap")
        || numbered(".rrd")
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
    use super::{demo_plan, is_demo_file};
    use crate::config::Config;
    use crate::studies::simulation::parse_scenario;

    fn bundled(name: &str) -> Config {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("config")
            .join(name);
        Config::from_toml(&std::fs::read_to_string(path).unwrap()).unwrap()
    }

    #[test]
    fn the_plain_demo_ramps_the_bearing_between_40_and_60_per_cent() {
        let plan = demo_plan(&bundled("sinello.toml"), None).unwrap();
        assert_eq!((plan.duration, plan.damage_from), (600.0, 240.0));
        let scenario = parse_scenario(&plan.scenario).unwrap();
        assert!(scenario.environment.is_none());
        assert_eq!(scenario.changes.len(), 1);
        assert_eq!(
            (scenario.changes[0].start_minute, scenario.changes[0].end_minute),
            (4.0, 6.0)
        );
    }

    #[test]
    fn the_monitoring_demo_trains_then_drops_the_bearing_with_temperatures() {
        // 100 training updates of 20 s, then 50 more with the damage halfway.
        let cfg = bundled("sinello-monitoring.toml");
        let plan = demo_plan(&cfg, None).unwrap();
        assert_eq!((plan.duration, plan.damage_from), (3000.0, 2500.0));
        let scenario = parse_scenario(&plan.scenario).unwrap();
        assert_eq!(scenario.environment.as_ref().unwrap().channels, vec!["T1".to_string()]);
        let change = &scenario.changes[0];
        assert_eq!((change.start_minute * 60.0, change.end_minute * 60.0), (2500.0, 2500.0));
        let short = demo_plan(&cfg, Some(2500.0)).unwrap_err().to_string();
        assert!(short.contains("--duration 2600 or more"), "{short}");
        let mut by_span = cfg.clone();
        by_span.monitoring.as_mut().unwrap().training_from = Some("2026-01-01T00:00:00Z".into());
        let span = demo_plan(&by_span, None).unwrap_err().to_string();
        assert!(span.contains("training_from"), "{span}");
    }

    #[test]
    fn only_the_demos_own_files_are_cleared() {
        for name in [
            "state.json",
            "monitoring.json",
            "report.html",
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
