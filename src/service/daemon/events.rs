//! The daemon on a triggered logger (`[events]`, issue 45 item 5): the
//! config sensors' acceleration blocks are the event chain's (collected into
//! bursts, [`Bursts`], and counted in `health.event_blocks`; the ambient
//! pipeline gets the rest: temperatures, FRF sets, unknown channels to
//! reject), and each closed burst runs the event chain of `splinewatch
//! events` on a blocking thread, one at a time, in the order the bursts
//! closed. At most [`WAITING_BURSTS`] wait; beyond that the oldest waiting
//! is reported as a skipped event with the reason (never a silent loss).
//! The chain (parameters, tracked modes, the verdict's history) lives in
//! `events.json` beside the state file, so a restart goes on where it was.

use crate::config::Config;
use crate::io::recording::RecordedBlock;
use crate::io::wire::{format_timestamp, ChannelBlock, ChannelQuantity};
use crate::service::events::burst::{Burst, Bursts};
use crate::service::events::{load, process, Chain, EventLine};
use crate::service::records::Record;
use anyhow::{bail, Result};
use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;
use tokio::task::{JoinError, JoinHandle};

/// Closed bursts that may wait behind the running event (each at most
/// `[events] max_seconds` of the config's acceleration channels).
pub(super) const WAITING_BURSTS: usize = 8;

pub(super) struct EventWorker {
    config: Arc<Config>,
    prefix: String,
    bursts: Bursts,
    /// The chain, or `None` while the running event holds it.
    chain: Option<Chain>,
    running: Option<JoinHandle<(Chain, EventLine)>>,
    waiting: VecDeque<Burst>,
    file: Option<PathBuf>,
}

impl EventWorker {
    /// What the events' amplitude is (`[events] amplitude`).
    pub(super) fn amplitude(&self) -> crate::config::EventAmplitude {
        self.config.events().amplitude
    }

    /// `None` without an `[events]` section.
    /// `frf_model`: the pipeline's, built from the same config, which the
    /// chain's model shares.
    pub(super) fn start(
        config: &Config,
        state: Option<&std::path::Path>,
        frf_model: Arc<crate::config::FrfSetup>,
    ) -> Result<Option<Self>> {
        let Some(events) = &config.events_section else {
            return Ok(None);
        };
        if !config.has_ground_sensors() {
            bail!("config: [events] needs ground sensors ([[sensors]] with support = \"<group>\"): an event's input is the ground's motion");
        }
        let file = state.and_then(|s| config.events_file(s));
        let mut chain = Chain::resume(file.as_deref())?;
        chain.check(config)?;
        chain.share_frf_model(frf_model);
        if let Some(f) = &file {
            tracing::info!(message = "events: triggered-logger mode", chain = %f.display(), events_judged = chain.history_len(), gap_seconds = events.gap_seconds);
        }
        Ok(Some(Self {
            config: Arc::new(config.clone()),
            prefix: config.topic_prefix(),
            bursts: Bursts::new(events.gap_seconds, events.max_seconds),
            chain: Some(chain),
            running: None,
            waiting: VecDeque::new(),
            file,
        }))
    }

    pub(super) fn is_busy(&self) -> bool {
        self.running.is_some()
    }

    /// Takes `block` when it is the chain's (an acceleration of a config
    /// sensor), else hands it back for the ambient pipeline; a burst it
    /// closes waits or starts. Returns the lines of bursts dropped from a
    /// full queue (skipped, with the reason).
    pub(super) fn take(&mut self, block: ChannelBlock, now: Instant) -> Result<Vec<EventLine>, ChannelBlock> {
        if block.quantity != ChannelQuantity::Acceleration || !self.config.sensors.iter().any(|s| s.name == block.name)
        {
            return Err(block);
        }
        let closed = self.bursts.push(RecordedBlock::at_its_start(block, &self.prefix), now);
        Ok(self.enqueue(closed))
    }

    /// The open burst when the logger has been silent long enough.
    pub(super) fn tick(&mut self, now: Instant) -> Vec<EventLine> {
        let closed = self.bursts.idle(now);
        self.enqueue(closed)
    }

    fn enqueue(&mut self, closed: Option<Burst>) -> Vec<EventLine> {
        let Some(burst) = closed else {
            return Vec::new();
        };
        tracing::info!(message = "event recorded", start = %format_timestamp(burst.start_ns), seconds = %format_args!("{:.1}", burst.seconds()), blocks = burst.blocks.len());
        self.waiting.push_back(burst);
        let mut dropped = Vec::new();
        while self.waiting.len() > WAITING_BURSTS {
            let burst = self.waiting.pop_front().expect("longer than the limit");
            dropped.push(EventLine::skipped(
                format_timestamp(burst.start_ns),
                burst.start_ns,
                format!("the daemon was busy: more than {WAITING_BURSTS} events were waiting (the oldest waiting is dropped)"),
            ));
        }
        self.start_next();
        dropped
    }

    fn start_next(&mut self) {
        if self.running.is_some() || self.waiting.is_empty() {
            return;
        }
        let Some(mut chain) = self.chain.take() else {
            return;
        };
        let burst = self.waiting.pop_front().expect("not empty");
        let config = Arc::clone(&self.config);
        self.running = Some(tokio::task::spawn_blocking(move || {
            let name = format_timestamp(burst.start_ns);
            let loaded = match chain.plan(&config) {
                Ok(plan) => load(&config, &plan, name, Ok(Record::Blocks(burst.blocks))),
                Err(e) => load(&config, &[], name, Err(e)),
            };
            let line = process(&config, &loaded, &mut chain);
            (chain, line)
        }));
    }

    /// The running event's line; call only when [`Self::is_busy`], then
    /// [`Self::done`] with it.
    pub(super) async fn finished(&mut self) -> Result<(Chain, EventLine), JoinError> {
        self.running.as_mut().expect("guarded by is_busy").await
    }

    /// Takes the chain back, saves it and starts the next waiting burst.
    pub(super) fn done(&mut self, chain: Chain) {
        self.running = None;
        if let Some(f) = &self.file {
            // Like the state: a failed write is logged and retried at the next event.
            if let Err(e) = chain.save(f) {
                tracing::error!(message = "cannot save the events chain", error = %format!("{e:#}"));
            }
        }
        self.chain = Some(chain);
        self.start_next();
    }

    /// At shutdown: the open burst closes, and every waiting event runs (a
    /// triggered record is never lost to a restart); their lines in order.
    pub(super) async fn drain(&mut self) -> Result<Vec<EventLine>, JoinError> {
        let closed = self.bursts.take();
        let mut lines = self.enqueue(closed);
        while self.is_busy() {
            let (chain, line) = self.finished().await?;
            lines.push(line);
            self.done(chain);
        }
        Ok(lines)
    }
}
