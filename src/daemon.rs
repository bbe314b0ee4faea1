//! The live daemon: zenoh ingest → pipeline → results MCAP + zenoh outputs.
//!
//! Tasks and queues (vector-style, each with its policy):
//! - zenoh subscriber callbacks push raw samples into a bounded queue
//!   (`INGEST_QUEUE` messages); when it is full the newest message is
//!   dropped and counted in `health.queue_drops` (the logger keeps sending;
//!   memory stays bounded).
//! - the main task decodes, feeds the pipeline and writes results; an update
//!   job runs on a blocking worker so ingest never stalls. At most one job
//!   runs and one waits; a newer job replaces a waiting one (drop oldest,
//!   counted). A waiting job is rebased when it starts, so it warm-starts
//!   from the result that finished meanwhile, as in a replay.
//! - shutdown (SIGINT/SIGTERM, or the caller's future) lets a running update
//!   finish, writes the last health message, finalises the MCAP file and
//!   saves the state.

use crate::config::Config;
use crate::pipeline::{AcceptedParameters, Pipeline, UpdateJob, UpdateOutcome, WindowReport};
use crate::recorder::RawRecorder;
use crate::results::{self, ResultsSink};
use crate::viewer::{RerunOutput, RerunTargets};
use crate::wire::{self, Encoding, Limits};
use anyhow::{anyhow, Context, Result};
use serde::Deserialize;
use std::fs::File;
use std::future::Future;
use std::io::BufWriter;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use tokio::sync::mpsc;
use zenoh::Wait;

/// Capacity of the ingest queue, in messages.
pub const INGEST_QUEUE: usize = 4096;

/// `[zenoh]`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ZenohConfig {
    /// "peer" or "client".
    pub mode: String,
    /// Endpoints to listen on, e.g. "tcp/127.0.0.1:7447".
    pub listen: Vec<String>,
    /// Endpoints to connect to (a router in client mode, peers otherwise).
    pub connect: Vec<String>,
    pub multicast_scouting: bool,
    /// A zenoh JSON5 configuration file, applied first.
    pub config_file: Option<PathBuf>,
}

impl Default for ZenohConfig {
    fn default() -> Self {
        Self {
            mode: "peer".into(),
            listen: vec!["tcp/127.0.0.1:7447".into()],
            connect: Vec::new(),
            multicast_scouting: false,
            config_file: None,
        }
    }
}

impl ZenohConfig {
    /// The zenoh session configuration: the JSON5 file first, then our keys.
    pub fn to_zenoh(&self) -> Result<zenoh::Config> {
        let mut cfg = match &self.config_file {
            Some(path) => zenoh::Config::from_file(path)
                .map_err(|e| anyhow!("config: zenoh.config_file {}: {e}", path.display()))?,
            None => zenoh::Config::default(),
        };
        if !matches!(self.mode.as_str(), "peer" | "client") {
            return Err(anyhow!(
                "config: zenoh.mode: {:?} is not \"peer\" or \"client\"",
                self.mode
            ));
        }
        let set = |cfg: &mut zenoh::Config, key: &str, value: String| {
            cfg.insert_json5(key, &value)
                .map_err(|e| anyhow!("config: zenoh: {key} = {value}: {e}"))
        };
        set(&mut cfg, "mode", format!("{:?}", self.mode))?;
        // A client talks to its router and does not listen: the peer-mode
        // default endpoint is not applied in client mode (explicit ones are).
        let default_listen = self.mode == "client" && self.listen == Self::default().listen;
        if !self.listen.is_empty() && !default_listen {
            set(&mut cfg, "listen/endpoints", serde_json::to_string(&self.listen)?)?;
        }
        if !self.connect.is_empty() {
            set(&mut cfg, "connect/endpoints", serde_json::to_string(&self.connect)?)?;
        }
        set(
            &mut cfg,
            "scouting/multicast/enabled",
            self.multicast_scouting.to_string(),
        )?;
        Ok(cfg)
    }
}

/// Options of a live run.
#[derive(Debug, Clone)]
pub struct RunOptions {
    pub results: PathBuf,
    pub state: Option<PathBuf>,
    /// Rerun outputs (none when empty).
    pub rerun: RerunTargets,
    /// How many of the latest update outcomes the returned summary keeps:
    /// a long run must not hold every outcome in memory.
    pub keep_updates: usize,
}

/// What a run did.
#[derive(Debug, Clone, Default)]
pub struct RunSummary {
    pub messages: u64,
    pub windows: u64,
    /// The latest update outcomes (at most `RunOptions::keep_updates`).
    pub updates: std::collections::VecDeque<UpdateOutcome>,
    /// Every update run, including those no longer in `updates`.
    pub update_count: u64,
    pub accepted: Option<AcceptedParameters>,
}

/// Logs the input rejected since the last call, by reason, as one warning:
/// called on the health tick, so a flood of bad input costs one log line per
/// tick, and nothing is logged while the input is clean.
fn log_new_rejections(
    rejected: &std::collections::BTreeMap<String, u64>,
    logged: &mut std::collections::BTreeMap<String, u64>,
) {
    let new: std::collections::BTreeMap<&str, u64> = rejected
        .iter()
        .filter_map(|(reason, &count)| {
            let before = logged.get(reason).copied().unwrap_or(0);
            (count > before).then_some((reason.as_str(), count - before))
        })
        .collect();
    if !new.is_empty() {
        tracing::warn!(message = "input rejected since the last report", by_reason = ?new, total = ?rejected);
        logged.clone_from(rejected);
    }
}

/// The zenoh key of a result message. FRF results go under
/// `<prefix>/updating/frf/…`: `<prefix>/frf/**` is an input (pre-computed
/// FRFs), and the daemon must not receive its own output there.
pub fn zenoh_result_key(prefix: &str, suffix: &str) -> String {
    match suffix.strip_prefix("frf/") {
        Some(rest) => format!("{prefix}/updating/frf/{rest}"),
        None => format!("{prefix}/{suffix}"),
    }
}

/// An output error (raw recording, Rerun) is counted in `counter` and
/// logged for the first and then every `every`-th one, never fatal: the
/// model and its results go on.
fn count_output_error(result: Result<()>, counter: &mut u64, every: u64, what: &str) {
    if let Err(e) = result {
        *counter += 1;
        if *counter % every == 1 {
            tracing::warn!(message = "output failed; the daemon goes on", output = what, errors = *counter, error = %format!("{e:#}"));
        }
    }
}

/// Starts `job` on the blocking worker, or makes it the waiting job when
/// one runs; a waiting job it replaces is counted as a drop.
fn submit(
    job: UpdateJob,
    running: &mut Option<tokio::task::JoinHandle<UpdateOutcome>>,
    waiting: &mut Option<UpdateJob>,
    drops: &mut u64,
) {
    if running.is_none() {
        *running = Some(tokio::task::spawn_blocking(move || job.run()));
    } else if waiting.replace(job).is_some() {
        *drops += 1;
    }
}

impl RunSummary {
    fn keep(&mut self, outcome: UpdateOutcome, keep: usize) {
        self.update_count += 1;
        crate::replay::keep_latest(&mut self.updates, outcome, keep);
    }
}

struct RawMessage {
    encoding: Option<Encoding>,
    payload: Vec<u8>,
    /// A pre-computed FRF (`<prefix>/frf/**`) rather than a channel block.
    frf: bool,
}

/// Runs until `shutdown` resolves; returns what happened.
pub async fn run(config: Config, options: RunOptions, shutdown: impl Future<Output = ()>) -> Result<RunSummary> {
    let initial = match &options.state {
        Some(p) => results::load_state(p)?,
        None => None,
    };
    if let Some(s) = &initial {
        tracing::info!(message = "warm start from the state file", window = s.window, time = %s.time);
    }
    let mut pipeline = Pipeline::new(&config, config.schedule.clone(), initial)?;
    let prefix = config.topic_prefix();
    let limits = Limits {
        max_samples: config.frf.max_block_samples,
        ..Limits::default()
    };
    let mut writer = ResultsSink::new(&prefix, results::results_files(&options.results))?
        .rotate_every((config.output.results_rotate_hours * 3600e9) as i128);
    let mut viewer = if options.rerun.is_empty() {
        None
    } else {
        // A restart never overwrites an earlier run's .rrd.
        let mut targets = options.rerun.clone();
        targets.save = targets.save.map(|p| crate::files::first_free(&p));
        Some(RerunOutput::open(&config, &targets)?)
    };
    let mut recorder = if config.output.raw.enabled {
        let dir = config.output_dir().join(&config.output.raw.dir);
        tracing::info!(message = "recording raw input", dir = %dir.display());
        Some(RawRecorder::new(&dir, &prefix, &config.output.raw)?)
    } else {
        None
    };
    let session = zenoh::open(config.zenoh.to_zenoh()?)
        .await
        .map_err(|e| anyhow!("cannot open the zenoh session: {e}"))?;
    let (tx, mut rx) = mpsc::channel::<RawMessage>(INGEST_QUEUE);
    // Messages the full ingest queue refused (counted in the callbacks) and
    // waiting update jobs replaced by newer ones; their sum is
    // `health.queue_drops`.
    let ingest_drops = Arc::new(AtomicU64::new(0));
    let mut job_drops: u64 = 0;
    let mut subscribers = Vec::new();
    for (segment, frf) in [("accel/*", false), ("force/*", false), ("frf/**", true)] {
        let key = format!("{prefix}/{segment}");
        let (tx, drops) = (tx.clone(), Arc::clone(&ingest_drops));
        let sub = session
            .declare_subscriber(&key)
            .callback(move |sample| {
                let e = sample.encoding();
                let encoding = if *e == zenoh::bytes::Encoding::APPLICATION_CBOR {
                    Some(Encoding::Cbor)
                } else if *e == zenoh::bytes::Encoding::APPLICATION_JSON {
                    Some(Encoding::Json)
                } else {
                    None
                };
                let msg = RawMessage {
                    encoding,
                    payload: sample.payload().to_bytes().into_owned(),
                    frf,
                };
                if tx.try_send(msg).is_err() {
                    drops.fetch_add(1, Ordering::Relaxed);
                }
            })
            .await
            .map_err(|e| anyhow!("cannot subscribe to {key}: {e}"))?;
        subscribers.push(sub);
    }
    drop(tx);
    let latest: Arc<Mutex<Vec<u8>>> = Arc::new(Mutex::new(b"{}".to_vec()));
    let latest_key = format!("{prefix}/updating/latest");
    let queryable = {
        let latest = Arc::clone(&latest);
        let key = latest_key.clone();
        session
            .declare_queryable(&latest_key)
            .callback(move |query| {
                let body = latest.lock().map(|b| b.clone()).unwrap_or_default();
                let _ = query
                    .reply(&key, body)
                    .encoding(zenoh::bytes::Encoding::APPLICATION_JSON)
                    .wait();
            })
            .await
            .map_err(|e| anyhow!("cannot declare {latest_key}: {e}"))?
    };
    tracing::info!(message = "splinewatch running", prefix = %prefix, results = %options.results.display());
    notify_systemd(&[sd_notify::NotifyState::Ready]);
    let mut summary = RunSummary::default();
    let mut running: Option<tokio::task::JoinHandle<UpdateOutcome>> = None;
    let mut waiting: Option<UpdateJob> = None;
    let mut health_timer = tokio::time::interval(std::time::Duration::from_secs(10));
    let mut last_time: i128 = 0;
    // Rejections already logged: one warning per health tick covers the rest.
    let mut logged_rejections = std::collections::BTreeMap::new();
    tokio::pin!(shutdown);
    let publish = |session: &zenoh::Session, suffix: &str, v: &serde_json::Value| {
        let key = zenoh_result_key(&prefix, suffix);
        if let Err(e) = session
            .put(&key, serde_json::to_vec(v).unwrap_or_default())
            .encoding(zenoh::bytes::Encoding::APPLICATION_JSON)
            .wait()
        {
            tracing::warn!(message = "cannot publish", key = %key, error = %e);
        }
    };
    loop {
        tokio::select! {
            _ = &mut shutdown => break,
            msg = rx.recv() => {
                let Some(msg) = msg else { break };
                summary.messages += 1;
                if msg.frf {
                    let now = std::time::SystemTime::now()
                        .duration_since(std::time::UNIX_EPOCH)
                        .map(|d| d.as_nanos() as i128)
                        .unwrap_or(0);
                    if let Some(job) = pipeline.ingest_frf(&msg.payload, now) {
                        tracing::info!(message = "complete FRF set received", window = job.window);
                        submit(job, &mut running, &mut waiting, &mut job_drops);
                    }
                    continue;
                }
                let encoding = msg.encoding.unwrap_or(if msg.payload.first() == Some(&b'{') || msg.payload.first() == Some(&b'[') { Encoding::Json } else { Encoding::Cbor });
                let blocks = match wire::decode(&msg.payload, encoding, &limits) {
                    Ok(b) => b,
                    Err(e) => {
                        tracing::debug!(message = "rejected a message", reason = e.reason(), error = %e);
                        pipeline.reject_message(&e);
                        continue;
                    }
                };
                for block in blocks {
                    if let Some(r) = recorder.as_mut() {
                        count_output_error(r.record(&block), &mut pipeline.health_mut().recording_errors, 1000, "raw-input recording");
                    }
                    let (windows, jobs) = pipeline.ingest(block);
                    for w in &windows {
                        report_window(w, &mut writer, &session, &publish, &mut summary);
                        last_time = w.end_ns;
                    }
                    for job in jobs {
                        submit(job, &mut running, &mut waiting, &mut job_drops);
                    }
                }
            }
            outcome = async { running.as_mut().expect("guarded").await }, if running.is_some() => {
                running = None;
                let mut outcome = outcome.context("the update worker panicked")?;
                handle_outcome(&mut pipeline, &mut writer, viewer.as_mut(), &session, &options, &latest, &mut outcome, &publish)?;
                summary.keep(outcome, options.keep_updates);
                if let Some(mut job) = waiting.take() {
                    // It waited: start it from the result just applied.
                    pipeline.rebase(&mut job);
                    running = Some(tokio::task::spawn_blocking(move || job.run()));
                }
            }
            _ = health_timer.tick() => {
                pipeline.health_mut().queue_drops = job_drops + ingest_drops.load(Ordering::Relaxed);
                pipeline.health_mut().results_errors = writer.errors;
                let h = results::health_message(last_time, pipeline.health());
                writer.write("health", last_time, &h);
                publish(&session, "health", &h);
                // Health on the measurement timeline once data has arrived.
                if let (Some(v), true) = (viewer.as_mut(), last_time > 0) {
                    let r = v.log_health(last_time, pipeline.health());
                    count_output_error(r, &mut pipeline.health_mut().rerun_errors, 100, "Rerun");
                }
                log_new_rejections(&pipeline.health().rejected, &mut logged_rejections);
                notify_systemd(&[sd_notify::NotifyState::Watchdog]);
            }
        }
    }
    // Let a running update finish so its result is not lost.
    if let Some(handle) = running.take() {
        let mut outcome = handle.await.context("the update worker panicked")?;
        handle_outcome(
            &mut pipeline,
            &mut writer,
            viewer.as_mut(),
            &session,
            &options,
            &latest,
            &mut outcome,
            &publish,
        )?;
        summary.keep(outcome, options.keep_updates);
    }
    // Blocks still held for the stream's reference (fewer than two per
    // channel arrived) are decided on and counted; too little data for an
    // update to be due.
    let (windows, _) = pipeline.finish();
    for w in &windows {
        report_window(w, &mut writer, &session, &publish, &mut summary);
        last_time = w.end_ns;
    }
    log_new_rejections(&pipeline.health().rejected, &mut logged_rejections);
    pipeline.health_mut().queue_drops = job_drops + ingest_drops.load(Ordering::Relaxed);
    if let Some(mut r) = recorder.take() {
        count_output_error(
            r.close(),
            &mut pipeline.health_mut().recording_errors,
            1,
            "raw-input recording",
        );
    }
    pipeline.health_mut().results_errors = writer.errors;
    let h = results::health_message(last_time, pipeline.health());
    writer.write("health", last_time, &h);
    writer.finish();
    if let Some(mut v) = viewer.take() {
        let r = v.log_health(last_time, pipeline.health());
        count_output_error(r, &mut pipeline.health_mut().rerun_errors, 100, "Rerun");
        count_output_error(v.finish(), &mut pipeline.health_mut().rerun_errors, 100, "Rerun");
    }
    notify_systemd(&[sd_notify::NotifyState::Stopping]);
    drop(queryable);
    drop(subscribers);
    session
        .close()
        .await
        .map_err(|e| anyhow!("closing the zenoh session: {e}"))?;
    summary.accepted = pipeline.accepted().cloned();
    Ok(summary)
}

/// Writes, publishes, counts and logs a closed window.
fn report_window(
    w: &WindowReport,
    writer: &mut ResultsSink<BufWriter<File>>,
    session: &zenoh::Session,
    publish: &dyn Fn(&zenoh::Session, &str, &serde_json::Value),
    summary: &mut RunSummary,
) {
    let m = results::window_message(w);
    writer.write("windows", w.end_ns, &m);
    publish(session, "windows", &m);
    summary.windows += 1;
    match &w.skipped {
        None => tracing::info!(
            message = "window accepted",
            window = w.index,
            segments = w.segments_accepted
        ),
        Some(r) => tracing::warn!(message = "window skipped", window = w.index, reason = %r),
    }
}

#[allow(clippy::too_many_arguments)]
fn handle_outcome(
    pipeline: &mut Pipeline,
    writer: &mut ResultsSink<BufWriter<File>>,
    viewer: Option<&mut RerunOutput>,
    session: &zenoh::Session,
    options: &RunOptions,
    latest: &Arc<Mutex<Vec<u8>>>,
    outcome: &mut UpdateOutcome,
    publish: &dyn Fn(&zenoh::Session, &str, &serde_json::Value),
) -> Result<()> {
    pipeline.apply(outcome);
    let outcome = &*outcome;
    for (suffix, msg) in results::update_messages(outcome) {
        writer.write(suffix, outcome.time_ns, &msg);
        publish(session, suffix, &msg);
        if suffix == "updating/parameters" {
            if let Ok(mut l) = latest.lock() {
                *l = serde_json::to_vec(&msg)?;
            }
        }
    }
    writer.flush();
    match &outcome.result {
        Ok(r) => {
            tracing::info!(
                message = "update accepted",
                window = outcome.window,
                relative_residual = r.result.relative_residual
            );
            if let (Some(path), Some(state)) = (&options.state, pipeline.accepted()) {
                // A failed state write is logged and retried at the next update; the run goes on.
                if let Err(e) = results::save_state(path, state) {
                    tracing::error!(message = "cannot save the state", error = %format!("{e:#}"));
                }
            }
            notify_systemd(&[sd_notify::NotifyState::Status(&format!(
                "window {}: relative residual {:.4}",
                outcome.window, r.result.relative_residual
            ))]);
        }
        Err(e) => {
            tracing::warn!(message = "update failed, keeping the last parameters", window = outcome.window, error = %e)
        }
    }
    if let Some(v) = viewer {
        count_output_error(
            v.log_update(outcome),
            &mut pipeline.health_mut().rerun_errors,
            100,
            "Rerun",
        );
    }
    Ok(())
}

fn notify_systemd(states: &[sd_notify::NotifyState]) {
    let _ = sd_notify::notify(false, states);
}

/// Resolves on SIGINT or SIGTERM.
pub async fn termination_signal() {
    #[cfg(unix)]
    {
        let mut term = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()).ok();
        tokio::select! {
            _ = tokio::signal::ctrl_c() => {}
            _ = async { match term.as_mut() { Some(t) => { t.recv().await; } None => std::future::pending::<()>().await } } => {}
        }
    }
    #[cfg(not(unix))]
    {
        let _ = tokio::signal::ctrl_c().await;
    }
}

/// Publishes blocks on zenoh (`simulate --publish`), pacing them at `speed`
/// times real time (0 = as fast as possible).
pub struct Publisher {
    session: zenoh::Session,
    prefix: String,
    encoding: Encoding,
    speed: f64,
    origin: Option<(i128, std::time::Instant)>,
}

impl Publisher {
    pub fn open(zenoh: &ZenohConfig, prefix: String, encoding: Encoding, speed: f64) -> Result<Self> {
        let session = zenoh::open(zenoh.to_zenoh()?)
            .wait()
            .map_err(|e| anyhow!("cannot open the zenoh session: {e}"))?;
        Ok(Self {
            session,
            prefix,
            encoding,
            speed,
            origin: None,
        })
    }

    pub fn publish(&mut self, block: &wire::ChannelBlock) -> Result<()> {
        if self.speed > 0.0 {
            let (t0, w0) = *self.origin.get_or_insert((block.start_ns, std::time::Instant::now()));
            let due = std::time::Duration::from_secs_f64(((block.start_ns - t0) as f64 / 1e9 / self.speed).max(0.0));
            if let Some(wait) = due.checked_sub(w0.elapsed()) {
                std::thread::sleep(wait);
            }
        }
        let key = block.topic(&self.prefix);
        let zenc = match self.encoding {
            Encoding::Cbor => zenoh::bytes::Encoding::APPLICATION_CBOR,
            Encoding::Json => zenoh::bytes::Encoding::APPLICATION_JSON,
        };
        self.session
            .put(&key, wire::encode(block, self.encoding))
            .encoding(zenc)
            .wait()
            .map_err(|e| anyhow!("cannot publish on {key}: {e}"))
    }

    /// Publishes raw JSON bytes on `<prefix>/<suffix>` (e.g. a pre-computed FRF).
    pub fn publish_json(&mut self, suffix: &str, bytes: Vec<u8>) -> Result<()> {
        let key = format!("{}/{suffix}", self.prefix);
        self.session
            .put(&key, bytes)
            .encoding(zenoh::bytes::Encoding::APPLICATION_JSON)
            .wait()
            .map_err(|e| anyhow!("cannot publish on {key}: {e}"))
    }

    pub fn close(self) -> Result<()> {
        self.session
            .close()
            .wait()
            .map_err(|e| anyhow!("closing the zenoh session: {e}"))
    }
}
