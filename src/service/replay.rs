//! Offline replay of a raw-input recording through the pipeline: the same
//! code path as the live daemon, deterministic.
//!
//! Three stages with bounded channels between them, so that the slowest
//! sets the pace: reading (MCAP records, decompression) on one thread,
//! decoding + alignment + Welch on another (it owns the [`Pipeline`]), and
//! the updates with every output on the calling thread, which rebases each
//! job on its own [`Updater`], runs it and applies it in window order.
//! Every health message carries the ingest's counters as they were when
//! the job's window closed, so the results are exactly those of running
//! the stages in line (`ReplayOptions::pipelined = false`, the reference a
//! test compares with). With identification (output-only or both paths),
//! a window's modes are paired with the model at the last update: the
//! ingest identifies a window (SSI-cov, which needs no model) while the
//! update stage runs the previous window's job, then waits for the model
//! the update stage sends back after every job handed out so far, the
//! state the in-line replay pairs with, so the results are again exactly
//! the in-line ones. With a Rerun output, a fourth thread logs to it, so
//! the viewer never holds the updates up.
//! Room: a service shell. May import: `outputs`, `pipeline`, `studies`, `config`, `io`, the core crate.

use super::{keep_latest, resume_monitor};
use crate::config::Config;
use crate::io::monitoring_json::StatusMessage;
use crate::io::recording::{McapMessage, RecordingSource};
use crate::io::wire::{self, Encoding, Limits};
use crate::outputs::metrics::Metrics;
use crate::outputs::notify::Notifier;
use crate::outputs::rerun::RerunOutput;
use crate::outputs::results::{self, ResultsWriter};
use crate::outputs::state;
use crate::pipeline::{
    AcceptedParameters, Health, MonitoringOutcome, Pipeline, UpdateCounters, UpdateJob, UpdateOutcome, Updater,
    WindowReport,
};
use anyhow::{Context, Result};
use std::collections::VecDeque;
use std::io::{Seek, Write};
use std::path::Path;
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};

/// MCAP messages handed from the reading stage to the ingest, per batch.
const READ_BATCH: usize = 64;
/// Batches of read messages in flight (bounded memory: a few MB).
const READ_QUEUE: usize = 8;
/// Ingest events in flight to the update stage: the ingest runs at most
/// this far ahead (a window's event holds its FRFs, about 0.25 MB).
const EVENT_QUEUE: usize = 32;
/// Windows and updates in flight to the Rerun stage.
const VIEWER_QUEUE: usize = 64;

/// Progress callback data.
#[derive(Debug, Clone, Copy)]
pub struct Progress {
    pub messages: u64,
    pub total: u64,
}

/// What a replay starts from and writes besides the results file.
pub struct ReplayOptions<'a> {
    /// Warm start (e.g. a state file's parameters); the config's otherwise.
    pub initial: Option<AcceptedParameters>,
    /// Rerun output.
    pub viewer: Option<&'a mut RerunOutput>,
    /// State file, replaced after every accepted update; with
    /// `[monitoring]` the monitor file beside it too (`Config::monitor_file`),
    /// resumed from if it exists.
    pub state_path: Option<&'a Path>,
    /// How many of the latest windows and update outcomes the summary keeps
    /// (a month of 10-minute windows would otherwise hold about 1 GB).
    pub keep_latest: usize,
    /// Reading, ingest and updates on threads of their own (the default);
    /// `false` runs every stage in line on the calling thread, with the
    /// same results.
    pub pipelined: bool,
    /// `[metrics]` (`replay --metrics`): the endpoint the update stage
    /// keeps current, as the daemon does.
    pub metrics: Option<&'a Metrics>,
}

impl Default for ReplayOptions<'_> {
    fn default() -> Self {
        Self {
            initial: None,
            viewer: None,
            state_path: None,
            keep_latest: 64,
            pipelined: true,
            metrics: None,
        }
    }
}

#[derive(Debug, Clone, Default)]
pub struct ReplaySummary {
    pub messages: u64,
    /// Every window closed, and those accepted.
    pub window_count: u64,
    pub windows_accepted: u64,
    /// The latest windows (at most `keep_latest`).
    pub windows: VecDeque<WindowReport>,
    /// Every update run.
    pub update_count: u64,
    /// The latest update outcomes (at most `keep_latest`).
    pub updates: VecDeque<UpdateOutcome>,
    pub accepted: Option<AcceptedParameters>,
    /// Every monitoring status (`[monitoring]`), in order (a few kB each).
    pub monitoring: Vec<StatusMessage>,
}

/// Replays `recordings` (MCAP files in memory, in order: e.g. the rotated
/// raw-input files of a daemon) into `out` (and `viewer`, if any); saves
/// the state after every accepted update when `state_path` is given.
pub fn replay<W: Write + Seek>(
    config: &Config,
    recordings: &[&[u8]],
    out: &mut ResultsWriter<W>,
    options: ReplayOptions<'_>,
    progress: &mut dyn FnMut(Progress, Option<&str>),
) -> Result<ReplaySummary> {
    let sources = recordings
        .iter()
        .enumerate()
        .map(|(k, bytes)| RecordingSource::from_bytes(bytes).with_context(|| format!("recording {}", k + 1)))
        .collect::<Result<Vec<_>>>()?;
    replay_sources(config, sources, out, options, progress)
}

/// [`replay`] of recordings in memory or read from files as the replay goes
/// ([`RecordingSource::open`]: memory bounded whatever the files' size).
pub fn replay_sources<W: Write + Seek>(
    config: &Config,
    recordings: Vec<RecordingSource<'_>>,
    out: &mut ResultsWriter<W>,
    options: ReplayOptions<'_>,
    progress: &mut dyn FnMut(Progress, Option<&str>),
) -> Result<ReplaySummary> {
    let ReplayOptions {
        initial,
        viewer,
        state_path,
        keep_latest,
        pipelined,
        metrics,
    } = options;
    let mut pipeline = Pipeline::new(config, config.schedule.clone(), initial)?;
    if viewer.is_some() {
        pipeline.draw_spectra();
    }
    let monitor_path = resume_monitor(config, state_path, &mut pipeline)?;
    let limits = crate::pipeline::block_limits(config);
    let total = recordings.iter().map(RecordingSource::message_count).sum();
    let messages = recordings.into_iter().flat_map(RecordingSource::messages);
    std::thread::scope(|scope| {
        let (viewer, logging) = match viewer {
            Some(v) if pipelined => {
                let (events, received) = sync_channel::<ViewerEvent>(VIEWER_QUEUE);
                let logging = scope.spawn(move || -> Result<()> {
                    for event in received {
                        event.log_to(v)?;
                    }
                    Ok(())
                });
                (Viewer::Stage(events), Some(logging))
            }
            Some(v) => (Viewer::InLine(v), None),
            None => (Viewer::Off, None),
        };
        let mut sink = Outputs {
            out,
            viewer,
            state_path,
            monitor_path: monitor_path.as_deref(),
            progress,
            total,
            keep: keep_latest,
            last_time: 0,
            summary: ReplaySummary::default(),
            notifier: Notifier::for_config(config, None).context("starting the notify thread")?,
            metrics,
        };
        let replayed = run_stages(scope, pipeline, limits, messages, pipelined, &mut sink);
        sink.viewer = Viewer::Off; // the Rerun stage's queue ends
        if let Some(logging) = logging {
            // Its own error first: the update stage then only saw it stop.
            logging
                .join()
                .map_err(|_| anyhow::anyhow!("the Rerun stage panicked"))?
                .context("Rerun output")?;
        }
        replayed
    })
}

/// The stages on `scope`'s threads (or in line), then the final health.
fn run_stages<'scope, W: Write + Seek>(
    scope: &'scope std::thread::Scope<'scope, '_>,
    mut pipeline: Pipeline,
    limits: Limits,
    messages: impl Iterator<Item = McapMessage> + Send + 'scope,
    pipelined: bool,
    sink: &mut Outputs<'_, W>,
) -> Result<ReplaySummary> {
    let split = pipelined.then(|| pipeline.split_updater());
    let (end, counters, accepted) = match split {
        None => in_line(pipeline, limits, messages, sink),
        Some(mut updater) => {
            let batches = read_on_a_thread(scope, messages);
            let (events, received) = sync_channel(EVENT_QUEUE);
            let mut ingest = Ingest::new(pipeline, limits);
            let ingesting = scope.spawn(move || {
                let mut send = |_: &mut Pipeline, event: Event| {
                    events
                        .send(event)
                        .map_err(|_| anyhow::anyhow!("the update stage stopped"))
                };
                ingest.all(batches.into_iter().flatten(), &mut send)
            });
            for event in received {
                sink.event(event, &mut Updates::Split(&mut updater))?;
            }
            let end = ingesting
                .join()
                .map_err(|_| anyhow::anyhow!("the ingest stage panicked"))?;
            (end, updater.counters(), updater.accepted().cloned())
        }
    };
    let end = end?;
    // The final health, at the last window's end (or, with none closed, the
    // data analysed so far); without any data there is no measurement time
    // to stamp it with, and no message.
    let last_time = Some(sink.last_time)
        .filter(|&t| t > 0)
        .or_else(|| end.measured_until.filter(|&t| t > 0));
    sink.summary.messages = end.messages;
    if let Some(last_time) = last_time {
        let mut health = end.health;
        health.set_updates(counters);
        if let Some(n) = sink.notifier.as_mut() {
            n.finish();
            n.count_into(&mut health);
        }
        sink.out
            .write("health", last_time, &results::health_message(last_time, &health))?;
        if let Some(m) = sink.metrics {
            m.record_health(last_time, &health, end.messages);
        }
        sink.viewer.log(|| ViewerEvent::Health(last_time, Box::new(health)))?;
    }
    let mut summary = std::mem::take(&mut sink.summary);
    summary.accepted = accepted;
    Ok(summary)
}

/// What the Rerun output is given, in order.
enum ViewerEvent {
    Window(Box<WindowReport>),
    Monitoring(i128, Box<StatusMessage>),
    Update(Box<UpdateOutcome>),
    Health(i128, Box<Health>),
}

impl ViewerEvent {
    fn log_to(self, viewer: &mut RerunOutput) -> Result<()> {
        match self {
            ViewerEvent::Window(w) => viewer.log_window(&w),
            ViewerEvent::Monitoring(time, status) => viewer.log_monitoring(time, &status),
            ViewerEvent::Update(outcome) => viewer.log_update(&outcome),
            ViewerEvent::Health(time, health) => viewer.log_health(time, &health),
        }
    }
}

/// Where the Rerun output is: none, on the update stage's thread, or on a
/// thread of its own (its queue).
enum Viewer<'a> {
    Off,
    InLine(&'a mut RerunOutput),
    Stage(SyncSender<ViewerEvent>),
}

impl Viewer<'_> {
    /// Logs `event` (made only when there is a viewer).
    fn log(&mut self, event: impl FnOnce() -> ViewerEvent) -> Result<()> {
        match self {
            Viewer::Off => Ok(()),
            Viewer::InLine(v) => event().log_to(v),
            Viewer::Stage(events) => events
                .send(event())
                .map_err(|_| anyhow::anyhow!("the Rerun stage stopped")),
        }
    }
}

/// The reading stage: `messages` read on a thread of its own, in batches.
fn read_on_a_thread<'scope, I>(scope: &'scope std::thread::Scope<'scope, '_>, messages: I) -> Receiver<Vec<McapMessage>>
where
    I: Iterator<Item = McapMessage> + Send + 'scope,
{
    let (batches, received) = sync_channel(READ_QUEUE);
    scope.spawn(move || {
        let mut batch = Vec::with_capacity(READ_BATCH);
        for message in messages {
            batch.push(message);
            if batch.len() == READ_BATCH
                && batches
                    .send(std::mem::replace(&mut batch, Vec::with_capacity(READ_BATCH)))
                    .is_err()
            {
                return; // the ingest stopped (an error): nothing more to read for
            }
        }
        let _ = batches.send(batch);
    });
    received
}

/// What the ingest stage hands to the update stage, in order.
enum Event {
    Windows(Vec<WindowReport>),
    /// An update job with the ingest's health when its window closed.
    Job(Box<UpdateJob>, Box<Health>),
    Progress(u64),
}

/// The ingest's state when the recordings ended.
struct End {
    messages: u64,
    health: Health,
    measured_until: Option<i128>,
}

/// The ingest stage: decoding, alignment and Welch (the [`Pipeline`]).
struct Ingest {
    pipeline: Pipeline,
    limits: Limits,
    messages: u64,
}

impl Ingest {
    fn new(pipeline: Pipeline, limits: Limits) -> Self {
        Self {
            pipeline,
            limits,
            messages: 0,
        }
    }

    /// Takes one message; what it produced goes to `emit` in order.
    fn message(
        &mut self,
        message: mcap::Message<'static>,
        emit: &mut dyn FnMut(&mut Pipeline, Event) -> Result<()>,
    ) -> Result<()> {
        self.messages += 1;
        let topic = &message.channel.topic;
        if topic.contains("/frf/") {
            // A recorded pre-computed FRF: the log time stands for its end.
            let time_ns = i128::from(message.log_time);
            if let Some(job) = self.pipeline.ingest_frf(&message.data, time_ns) {
                self.emit_jobs(vec![job], emit)?;
            }
            return Ok(());
        }
        if !(topic.contains("/accel/") || topic.contains("/force/") || topic.contains("/temperature/")) {
            return Ok(());
        }
        let Some(encoding) = Encoding::from_name(&message.channel.message_encoding) else {
            self.pipeline.health_mut().reject("unknown_encoding");
            return Ok(());
        };
        let blocks = match wire::decode(&message.data, encoding, &self.limits) {
            Ok(b) => b,
            Err(e) => {
                self.pipeline.reject_message(&e);
                return Ok(());
            }
        };
        for block in blocks {
            let (windows, jobs) = self.pipeline.ingest(block);
            if !windows.is_empty() {
                emit(&mut self.pipeline, Event::Windows(windows))?;
            }
            self.emit_jobs(jobs, emit)?;
        }
        if self.messages % 256 == 0 {
            emit(&mut self.pipeline, Event::Progress(self.messages))?;
        }
        Ok(())
    }

    fn emit_jobs(
        &mut self,
        jobs: Vec<UpdateJob>,
        emit: &mut dyn FnMut(&mut Pipeline, Event) -> Result<()>,
    ) -> Result<()> {
        for job in jobs {
            let health = Box::new(self.pipeline.health().clone());
            emit(&mut self.pipeline, Event::Job(Box::new(job), health))?;
        }
        Ok(())
    }

    /// Every message, then the end of the stream (blocks still held for
    /// the stream's reference, a very short recording, are decided on).
    fn all(
        &mut self,
        messages: impl Iterator<Item = McapMessage>,
        emit: &mut dyn FnMut(&mut Pipeline, Event) -> Result<()>,
    ) -> Result<End> {
        for message in messages {
            self.message(message.context("corrupt MCAP record")?, emit)?;
        }
        let (windows, jobs) = self.pipeline.finish();
        if !windows.is_empty() {
            emit(&mut self.pipeline, Event::Windows(windows))?;
        }
        self.emit_jobs(jobs, emit)?;
        Ok(End {
            messages: self.messages,
            health: self.pipeline.health().clone(),
            measured_until: self.pipeline.measured_until(),
        })
    }
}

/// Ingest and updates on one thread: each event handled as it is produced.
fn in_line<W: Write + Seek>(
    pipeline: Pipeline,
    limits: Limits,
    messages: impl Iterator<Item = McapMessage>,
    sink: &mut Outputs<'_, W>,
) -> (Result<End>, UpdateCounters, Option<AcceptedParameters>) {
    let mut ingest = Ingest::new(pipeline, limits);
    let end = ingest.all(messages, &mut |pipeline, event| {
        sink.event(event, &mut Updates::InLine(pipeline))
    });
    let pipeline = &ingest.pipeline;
    (end, pipeline.update_counters(), pipeline.accepted().cloned())
}

/// Where jobs are rebased and outcomes applied: the pipeline's own updater
/// (ingest and updates on one thread) or one split off it.
enum Updates<'a> {
    InLine(&'a mut Pipeline),
    Split(&'a mut Updater),
}

impl Updates<'_> {
    fn rebase(&self, job: &mut UpdateJob) {
        match self {
            Updates::InLine(p) => p.rebase(job),
            Updates::Split(u) => u.rebase(job),
        }
    }

    fn apply(&mut self, outcome: &mut UpdateOutcome) -> Option<MonitoringOutcome> {
        match self {
            Updates::InLine(p) => p.apply(outcome),
            Updates::Split(u) => u.apply(outcome),
        }
    }

    fn counters(&self) -> UpdateCounters {
        match self {
            Updates::InLine(p) => p.update_counters(),
            Updates::Split(u) => u.counters(),
        }
    }

    fn accepted(&self) -> Option<&AcceptedParameters> {
        match self {
            Updates::InLine(p) => p.accepted(),
            Updates::Split(u) => u.accepted(),
        }
    }

    fn monitor(&self) -> Option<&splinewatch_core::monitoring::Monitor> {
        match self {
            Updates::InLine(p) => p.monitor(),
            Updates::Split(u) => u.monitor(),
        }
    }
}

/// Where the replay's windows and updates go.
struct Outputs<'a, W: Write + Seek> {
    out: &'a mut ResultsWriter<W>,
    viewer: Viewer<'a>,
    state_path: Option<&'a Path>,
    monitor_path: Option<&'a Path>,
    progress: &'a mut dyn FnMut(Progress, Option<&str>),
    total: u64,
    keep: usize,
    last_time: i128,
    summary: ReplaySummary,
    /// `[monitoring.notify]`: replays run the owner's command too (a
    /// notification chain can be tried offline).
    notifier: Option<Notifier>,
    metrics: Option<&'a Metrics>,
}

impl<W: Write + Seek> Outputs<'_, W> {
    fn report(&mut self, note: Option<&str>) {
        (self.progress)(
            Progress {
                messages: self.summary.messages,
                total: self.total,
            },
            note,
        );
    }

    fn event(&mut self, event: Event, updates: &mut Updates<'_>) -> Result<()> {
        match event {
            Event::Windows(windows) => self.windows(windows),
            Event::Job(job, health) => self.update(*job, *health, updates),
            Event::Progress(messages) => {
                self.summary.messages = messages;
                self.report(None);
                Ok(())
            }
        }
    }

    /// Writes the closed windows.
    fn windows(&mut self, windows: Vec<WindowReport>) -> Result<()> {
        for w in windows {
            self.last_time = w.end_ns;
            for (suffix, m) in results::window_messages(&w) {
                self.out.write(suffix, w.end_ns, &m)?;
            }
            self.viewer.log(|| ViewerEvent::Window(Box::new(w.clone())))?;
            let note = match &w.skipped {
                Some(reason) => format!("window {} skipped: {reason}", w.index),
                None => match &w.modes {
                    Some(m) => format!(
                        "window {} accepted ({} modes identified)",
                        w.index,
                        m.report.result.modes.len()
                    ),
                    None => format!("window {} accepted ({} segments)", w.index, w.segments_accepted),
                },
            };
            self.report(Some(&note));
            self.summary.window_count += 1;
            self.summary.windows_accepted += u64::from(w.skipped.is_none());
            keep_latest(&mut self.summary.windows, w, self.keep);
        }
        Ok(())
    }

    /// Keeps a results message for the report the notifications carry.
    fn keep_for_report(&mut self, suffix: &str, msg: &impl serde::Serialize) -> Result<()> {
        if let Some(n) = self.notifier.as_mut() {
            if crate::io::results_file::ResultsContents::reads(suffix) {
                n.record(suffix, &serde_json::to_vec(msg)?);
            }
        }
        Ok(())
    }

    /// Runs one update job (rebased on the last accepted parameters) and
    /// writes its outcome; `health` is the ingest's when its window closed.
    fn update(&mut self, mut job: UpdateJob, mut health: Health, updates: &mut Updates<'_>) -> Result<()> {
        updates.rebase(&mut job);
        let mut outcome = job.run();
        let scored = updates.apply(&mut outcome);
        let time = crate::io::wire::format_timestamp(outcome.time_ns);
        for (suffix, msg) in results::update_messages(&outcome, &time) {
            self.out.write(suffix, outcome.time_ns, &msg)?;
            self.keep_for_report(suffix, &msg)?;
        }
        if let Some(m) = &scored {
            for (suffix, msg) in results::monitoring_messages(m) {
                self.out.write(suffix, outcome.time_ns, &msg)?;
                self.keep_for_report(suffix, &msg)?;
            }
            if let Some(n) = self.notifier.as_mut() {
                n.observe(&m.status, &serde_json::to_vec(&m.status)?);
            }
            self.viewer
                .log(|| ViewerEvent::Monitoring(outcome.time_ns, Box::new(m.status.clone())))?;
            self.summary.monitoring.push(m.status.clone());
        }
        let note = match &outcome.result {
            Ok(r) => {
                let mut note = format!(
                    "update after window {}: relative residual {:.4}, {} iterations",
                    outcome.window,
                    r.result.relative_residual,
                    r.result.iterations.len() - 1
                );
                if !r.result.converged {
                    note += &format!(", not converged ({:?})", r.result.stop_reason);
                }
                if !r.result.held.is_empty() {
                    let held: Vec<String> = r
                        .result
                        .held
                        .iter()
                        .map(|h| format!("{} ({})", h.name, crate::studies::update::hold_reason(h.reason)))
                        .collect();
                    note += &format!("; held: {}", held.join(", "));
                }
                note
            }
            Err(e) => format!(
                "update after window {} failed, keeping the last parameters: {e}",
                outcome.window
            ),
        };
        self.out.flush()?;
        if let (Some(path), Some(state), Ok(_)) = (self.state_path, updates.accepted(), &outcome.result) {
            state::save_state(path, state)?;
        }
        if let (Some(path), Some(monitor), Some(_)) = (self.monitor_path, updates.monitor(), &scored) {
            state::save_monitor(path, monitor)?;
        }
        health.set_updates(updates.counters());
        if let Some(n) = &self.notifier {
            n.count_into(&mut health);
        }
        self.out.write(
            "health",
            outcome.time_ns,
            &results::health_message(outcome.time_ns, &health),
        )?;
        if let Some(m) = self.metrics {
            if let Some(status) = scored.as_ref().map(|m| &m.status) {
                m.record_monitoring(status);
            }
            m.record_update(&outcome, updates.accepted());
            m.record_health(outcome.time_ns, &health, self.summary.messages);
        }
        self.viewer.log(|| ViewerEvent::Update(Box::new(outcome.clone())))?;
        self.viewer
            .log(|| ViewerEvent::Health(outcome.time_ns, Box::new(health)))?;
        self.report(Some(&note));
        self.summary.update_count += 1;
        keep_latest(&mut self.summary.updates, outcome, self.keep);
        Ok(())
    }
}
