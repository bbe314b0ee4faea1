//! The live daemon: zenoh ingest → pipeline → results MCAP + zenoh outputs.
//! Room: a service shell. May import: `outputs`, `pipeline`, `studies`, `config`, `io`, the core crate.
//!
//! Tasks and queues (vector-style, each with its policy):
//! - zenoh subscriber callbacks push raw samples into a bounded queue
//!   (`INGEST_QUEUE` messages); when it is full the newest message is
//!   dropped and counted in `health.queue_drops` (the logger keeps sending;
//!   memory stays bounded) (`link.rs`).
//! - the main task decodes, feeds the pipeline and writes results; an update
//!   job runs on a blocking worker so ingest never stalls. At most one job
//!   runs and 16 wait, in window order; on overflow the oldest waiting job
//!   is dropped, counted and its window recorded as skipped with the reason
//!   on `updating/failures`. A waiting job is rebased when it starts, so it
//!   warm-starts from the result that finished before it, as in a replay
//!   (`worker.rs`).
//! - shutdown (SIGINT/SIGTERM, or the caller's future) lets a running update
//!   finish, writes the last health message, finalises the MCAP file and
//!   saves the state.
//!
//! - with `[events]` (a triggered logger), the config sensors' acceleration
//!   blocks go to the event chain instead, cut into bursts; each closed
//!   burst runs the chain on a blocking worker, one at a time, 8 waiting at
//!   most (`events.rs`).
//!
//! The run loop is a `select!` over six events, each handled by a named
//! stage of `Daemon` (`stages.rs`): a message (`on_message`), a finished update
//! (`on_outcome`), a finished event (`on_event`), the health tick
//! (`on_health_tick`), the event tick (`on_event_tick`: a logger silent long
//! enough closes its burst) and shutdown (`shut_down`).

mod events;
mod link;
mod stages;
mod worker;

pub use link::INGEST_QUEUE;

use crate::config::Config;
use crate::outputs::rerun::RerunTargets;
use crate::pipeline::{AcceptedParameters, UpdateOutcome};
use anyhow::Result;
use link::ZenohLink;
use stages::Daemon;
use std::future::Future;
use std::path::PathBuf;

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

impl RunSummary {
    fn keep(&mut self, outcome: UpdateOutcome, keep: usize) {
        self.update_count += 1;
        super::keep_latest(&mut self.updates, outcome, keep);
    }
}

/// Runs until `shutdown` resolves; returns what happened.
pub async fn run(config: Config, options: RunOptions, shutdown: impl Future<Output = ()>) -> Result<RunSummary> {
    run_observed(config, options, &tokio::sync::watch::channel(None).0, shutdown).await
}

/// How far a running daemon has got ([`run_observed`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Progress {
    /// Messages taken from zenoh so far (queued, or dropped by the full
    /// ingest queue).
    pub taken: u64,
    /// Updates waiting behind the running one.
    pub updates_waiting: usize,
}

/// [`run`], telling `progress` how many messages the daemon has taken from
/// zenoh so far (queued, or dropped by the full ingest queue) and how many
/// updates wait: first once its subscribers are declared (no message sent
/// before can reach it), then after each message and each finished update.
/// A drop happens only while the queue is full, so the messages still
/// queued behind it bring the count up to date. A publisher in the same
/// process (the demo) starts on the first, drains on the count instead of
/// on guessed times, and may hold back while updates wait.
pub async fn run_observed(
    config: Config,
    options: RunOptions,
    progress: &tokio::sync::watch::Sender<Option<Progress>>,
    shutdown: impl Future<Output = ()>,
) -> Result<RunSummary> {
    let mut daemon = Daemon::start(&config, &options)?;
    let (link, mut messages) = ZenohLink::open(&config).await?;
    tracing::info!(message = "splinewatch running", prefix = %config.topic_prefix(), results = %options.results.display());
    notify_systemd(&[sd_notify::NotifyState::Ready]);
    let so_far = |daemon: &Daemon, link: &ZenohLink| {
        Some(Progress {
            taken: daemon.messages_received() + link.ingest_drops(),
            updates_waiting: daemon.worker.waiting(),
        })
    };
    progress.send_replace(so_far(&daemon, &link));
    let mut health_timer = tokio::time::interval(std::time::Duration::from_secs(10));
    let mut event_timer = tokio::time::interval(std::time::Duration::from_secs(1));
    let events = daemon.events.is_some();
    tokio::pin!(shutdown);
    loop {
        tokio::select! {
            _ = &mut shutdown => break,
            message = messages.recv() => {
                let Some(message) = message else { break };
                daemon.on_message(message, &link);
                progress.send_replace(so_far(&daemon, &link));
            }
            outcome = daemon.worker.finished(), if daemon.worker.is_busy() => {
                daemon.on_outcome(outcome, &link)?;
                progress.send_replace(so_far(&daemon, &link));
            }
            finished = async { daemon.events.as_mut().expect("guarded").finished().await },
                if daemon.events.as_ref().is_some_and(|e| e.is_busy()) => daemon.on_event(finished, &link)?,
            _ = health_timer.tick() => {
                daemon.ingest_depth = messages.len();
                daemon.on_health_tick(&link);
            }
            _ = event_timer.tick(), if events => daemon.on_event_tick(&link),
        }
    }
    daemon.shut_down(link).await
}

pub(crate) fn notify_systemd(states: &[sd_notify::NotifyState]) {
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
