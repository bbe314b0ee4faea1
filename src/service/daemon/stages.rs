//! The daemon's stages: what happens on a message, a finished update, the
//! health tick and shutdown. Everything here runs on the main task.

use super::events::EventWorker;
use super::link::{Latest, RawMessage, ZenohLink};
use super::worker::UpdateWorker;
use super::{notify_systemd, RunOptions, RunSummary};
use crate::config::Config;
use crate::io::wire::{self, ChannelBlock, Encoding, Limits};
use crate::io::{console, files};
use crate::outputs::metrics::Metrics;
use crate::outputs::notify::Notifier;
use crate::outputs::raw_recorder::RawRecorder;
use crate::outputs::report::history::History;
use crate::outputs::rerun::RerunOutput;
use crate::outputs::results::{self, ResultsSink};
use crate::outputs::state;
use crate::pipeline::{MonitoringOutcome, Pipeline, UpdateJob, UpdateOutcome, WindowReport};
use anyhow::{Context, Result};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::PathBuf;
use tokio::task::JoinError;

/// The daemon between events.
pub(super) struct Daemon {
    pipeline: Pipeline,
    pub(super) worker: UpdateWorker,
    results: ResultsSink<BufWriter<File>>,
    viewer: Option<RerunOutput>,
    recorder: Option<RawRecorder>,
    state: Option<PathBuf>,
    /// The monitor file (`[monitoring]`), beside the state file.
    monitor_file: Option<PathBuf>,
    keep_updates: usize,
    limits: Limits,
    summary: RunSummary,
    /// Measurement time of the latest closed window.
    last_time: i128,
    /// Rejections already logged: one warning per health tick covers the rest.
    logged_rejections: BTreeMap<String, u64>,
    /// Whether the log said what an idle daemon waits for.
    said_waiting: bool,
    /// `[monitoring.notify]`: the owner's command.
    notifier: Option<Notifier>,
    /// `[events]`: the triggered logger's bursts and their event chain.
    pub(super) events: Option<EventWorker>,
    /// `[metrics]`: the Prometheus endpoint.
    metrics: Option<Metrics>,
    /// `[web]`: the read-only status page, served until the daemon drops it.
    _web: Option<crate::outputs::web::StatusPage>,
    /// What this run wrote, for the notifications' report and the status
    /// page (one history both share; none without either).
    history: Option<History>,
    /// Raw messages waiting in the ingest queue at the last health tick.
    pub(super) ingest_depth: usize,
}

/// Why a window's update was dropped when the update queue overflowed.
const QUEUE_FULL: &str = "update skipped: more than 16 newer windows were waiting (the update queue holds 16 behind the running update; the oldest waiting is dropped)";

impl Daemon {
    /// Loads the state, builds the pipeline and opens every output.
    pub(super) fn start(config: &Config, options: &RunOptions) -> Result<Self> {
        let initial = match &options.state {
            Some(p) => state::load_state(p)?,
            None => None,
        };
        if let Some(s) = &initial {
            tracing::info!(message = "warm start from the state file", window = s.window, time = %s.time);
        }
        let mut pipeline = Pipeline::new(config, config.schedule.clone(), initial)?;
        let frf_model = pipeline.frf_setup();
        if !options.rerun.is_empty() {
            pipeline.draw_spectra();
        }
        let monitor_file = crate::service::resume_monitor(config, options.state.as_deref(), &mut pipeline)?;
        let prefix = config.topic_prefix();
        let results = ResultsSink::new(&prefix, results::results_files(&options.results))?
            .with_provenance(results::provenance(config))?
            .rotate_every((config.output.results_rotate_hours * 3600e9) as i128);
        let viewer = if options.rerun.is_empty() {
            None
        } else {
            // A restart never overwrites an earlier run's .rrd.
            let mut targets = options.rerun.clone();
            targets.save = targets.save.map(|p| files::first_free(&p));
            Some(RerunOutput::open(config, &targets)?)
        };
        let recorder = if config.output.raw.enabled {
            let dir = config.output_dir().join(&config.output.raw.dir);
            tracing::info!(message = "recording raw input", dir = %dir.display());
            Some(RawRecorder::new(&dir, &prefix, &config.output.raw)?)
        } else {
            None
        };
        let notify = config.monitoring.as_ref().is_some_and(|m| m.notify.is_some());
        let history = (notify || config.web.is_some()).then(|| History::new(config));
        Ok(Self {
            pipeline,
            worker: UpdateWorker::default(),
            results,
            viewer,
            recorder,
            state: options.state.clone(),
            monitor_file,
            keep_updates: options.keep_updates,
            limits: crate::pipeline::block_limits(config),
            summary: RunSummary::default(),
            last_time: 0,
            logged_rejections: BTreeMap::new(),
            said_waiting: false,
            notifier: Notifier::for_config(config, history.clone()).context("starting the notify thread")?,
            events: EventWorker::start(config, options.state.as_deref(), frf_model)?,
            metrics: config
                .metrics
                .as_ref()
                .map(|m| Metrics::serve(&m.listen, &config.structure.name))
                .transpose()?,
            _web: config
                .web
                .as_ref()
                .zip(history.clone())
                .map(|(w, h)| crate::outputs::web::StatusPage::serve(config, w, h))
                .transpose()?,
            history,
            ingest_depth: 0,
        })
    }

    /// Messages taken from the ingest queue so far.
    pub(super) fn messages_received(&self) -> u64 {
        self.summary.messages
    }

    /// A message from the ingest queue: a pre-computed FRF, or channel
    /// blocks to decode, record and feed to the pipeline.
    pub(super) fn on_message(&mut self, msg: RawMessage, link: &ZenohLink) {
        self.summary.messages += 1;
        if msg.frf {
            let now = wire::now_ns();
            if let Some(r) = self.recorder.as_mut() {
                // Filed under its measurement time (the span's end) when it says.
                let time = crate::io::frf_json::message_end_ns(&msg.payload).unwrap_or(now);
                count_output_error(
                    r.record_frf(&msg.key, time, &msg.payload),
                    &mut self.pipeline.health_mut().recording_errors,
                    1000,
                    "raw-input recording",
                );
            }
            if let Some(job) = self.pipeline.ingest_frf(&msg.payload, now) {
                tracing::info!(message = "complete FRF set received", window = job.window);
                if let Some(dropped) = self.worker.submit(job) {
                    self.skip_update(&dropped, ("queue_full", QUEUE_FULL), link);
                }
            }
            return;
        }
        let sniffed = if matches!(msg.payload.first(), Some(b'{' | b'[')) {
            Encoding::Json
        } else {
            Encoding::Cbor
        };
        let blocks = match wire::decode(&msg.payload, msg.encoding.unwrap_or(sniffed), &self.limits) {
            Ok(b) => b,
            Err(e) => {
                tracing::debug!(message = "rejected a message", reason = e.reason(), error = %e);
                self.pipeline.reject_message(&e);
                return;
            }
        };
        for block in blocks {
            self.ingest(block, link);
        }
    }

    fn ingest(&mut self, block: ChannelBlock, link: &ZenohLink) {
        if let Some(r) = self.recorder.as_mut() {
            count_output_error(
                r.record(&block),
                &mut self.pipeline.health_mut().recording_errors,
                1000,
                "raw-input recording",
            );
        }
        let block = match self.events.as_mut() {
            Some(e) => match e.take(block, std::time::Instant::now()) {
                Ok(dropped) => {
                    self.pipeline.health_mut().event_blocks += 1;
                    for line in dropped {
                        self.report_event(line, link);
                    }
                    return;
                }
                Err(block) => block,
            },
            None => block,
        };
        let (windows, jobs) = self.pipeline.ingest(block);
        for w in &windows {
            self.report_window(w, link);
        }
        for job in jobs {
            if let Some(dropped) = self.worker.submit(job) {
                self.skip_update(&dropped, ("queue_full", QUEUE_FULL), link);
            }
        }
    }

    /// The update worker finished: apply and report the outcome, then start
    /// the waiting job from the result just applied.
    pub(super) fn on_outcome(&mut self, outcome: Result<UpdateOutcome, JoinError>, link: &ZenohLink) -> Result<()> {
        let waiting = self.worker.next();
        let mut outcome = outcome.context("the update worker panicked")?;
        self.handle_outcome(&mut outcome, link)?;
        self.summary.keep(outcome, self.keep_updates);
        if let Some(mut job) = waiting {
            // It waited: start it from the result just applied.
            self.pipeline.rebase(&mut job);
            self.worker.start(job);
        }
        Ok(())
    }

    /// Every 10 s: the health message (results, zenoh, Rerun) stamped with
    /// the measurement time analysed so far, new rejections in the log, the
    /// systemd watchdog. Before any data there is no measurement time: no
    /// message (never one stamped at the Unix epoch), one log line saying
    /// what the daemon waits for.
    pub(super) fn on_health_tick(&mut self, link: &ZenohLink) {
        self.sync_counters(link);
        notify_systemd(&[sd_notify::NotifyState::Watchdog]);
        log_new_rejections(&self.pipeline.health().rejected, &mut self.logged_rejections);
        let Some(time) = self.health_time() else {
            if !std::mem::replace(&mut self.said_waiting, true) {
                tracing::info!(message = "waiting for data", on = %link.inputs());
            }
            return;
        };
        // Serialised once for the results file, zenoh and the `latest` reply.
        let json = self.record_health(time);
        link.publish_json("health", json.clone());
        link.set_latest(Latest::Health, json);
        let health = self.pipeline.health();
        tracing::info!(
            message = "health",
            blocks = health.blocks,
            windows_accepted = health.windows_accepted,
            updates = health.update_runs,
            update_failures = health.update_failures,
            rejected = health.rejected.values().sum::<u64>(),
            queue_drops = health.queue_drops,
        );
    }

    /// The measurement time health is stamped with: the data analysed so far
    /// (at least the last closed window's end); `None` before any data.
    fn health_time(&self) -> Option<i128> {
        let time = self.pipeline.measured_until().unwrap_or(0).max(self.last_time);
        (time > 0).then_some(time)
    }

    /// Lets a running update finish, decides on the blocks still held for
    /// the reference, writes the last health message, finalises every file
    /// and closes the session.
    pub(super) async fn shut_down(mut self, link: ZenohLink) -> Result<RunSummary> {
        let (running, waiting) = self.worker.drain().await;
        if let Some(outcome) = running {
            let mut outcome = outcome.context("the update worker panicked")?;
            self.handle_outcome(&mut outcome, &link)?;
            self.summary.keep(outcome, self.keep_updates);
        }
        for job in &waiting {
            self.skip_update(
                job,
                ("shutdown", "update skipped: the daemon stopped before it ran"),
                &link,
            );
        }
        if let Some(e) = self.events.as_mut() {
            for line in e.drain().await.context("the event worker panicked")? {
                self.report_event(line, &link);
            }
        }
        // Blocks still held for the stream's reference (fewer than two per
        // channel arrived) are decided on and counted; too little data for an
        // update to be due.
        let (windows, _) = self.pipeline.finish();
        for w in &windows {
            self.report_window(w, &link);
        }
        log_new_rejections(&self.pipeline.health().rejected, &mut self.logged_rejections);
        if let Some(mut r) = self.recorder.take() {
            count_output_error(
                r.close(),
                &mut self.pipeline.health_mut().recording_errors,
                1,
                "raw-input recording",
            );
        }
        // Notifications still queued are delivered (with their retries)
        // before the last health message counts them.
        if let Some(n) = self.notifier.as_mut() {
            n.finish();
        }
        self.sync_counters(&link);
        if let Some(time) = self.health_time() {
            self.record_health(time);
        }
        self.results.finish();
        if let Some(v) = self.viewer.take() {
            count_output_error(v.finish(), &mut self.pipeline.health_mut().rerun_errors, 100, "Rerun");
        }
        notify_systemd(&[sd_notify::NotifyState::Stopping]);
        link.close().await?;
        self.summary.accepted = self.pipeline.accepted().cloned();
        Ok(self.summary)
    }

    /// The health message at `time` into the results file and Rerun;
    /// returned (JSON) for publishing.
    fn record_health(&mut self, time: i128) -> Vec<u8> {
        let h = serde_json::to_vec(&results::health_message(time, self.pipeline.health())).unwrap_or_default();
        if let Some(m) = &self.metrics {
            m.record_health(time, self.pipeline.health(), self.summary.messages);
            m.update(|s| {
                s.update_queue_depth = self.worker.waiting();
                s.update_running = self.worker.is_busy();
                s.ingest_queue_depth = self.ingest_depth;
            });
        }
        self.results.write_json("health", time, &h);
        self.keep_for_report("health", &h);
        if let Some(v) = self.viewer.as_mut() {
            let r = v.log_health(time, self.pipeline.health());
            count_output_error(r, &mut self.pipeline.health_mut().rerun_errors, 100, "Rerun");
        }
        h
    }

    /// Counters kept outside the pipeline, copied into its health.
    fn sync_counters(&mut self, link: &ZenohLink) {
        let health = self.pipeline.health_mut();
        health.queue_drops = self.worker.drops + link.ingest_drops();
        health.results_errors = self.results.errors;
        health.log_writes_dropped = console::log_writes_dropped();
        if let Some(n) = &self.notifier {
            n.count_into(health);
        }
    }

    /// Writes a result message to the results file and publishes it,
    /// serialised once; returns the JSON (for a `latest` reply).
    fn send(
        &mut self,
        link: &ZenohLink,
        suffix: &'static str,
        time_ns: i128,
        message: &impl serde::Serialize,
    ) -> Vec<u8> {
        let json = serde_json::to_vec(message).expect("result messages are plain data");
        self.send_json(link, suffix, time_ns, json.clone());
        json
    }

    /// Keeps a results message for the report of the notifications and the
    /// status page.
    fn keep_for_report(&mut self, suffix: &str, json: &[u8]) {
        if let Some(h) = &self.history {
            h.record(suffix, json);
        }
    }

    /// Writes a result message already serialised to the results file and
    /// publishes it.
    fn send_json(&mut self, link: &ZenohLink, suffix: &str, time_ns: i128, json: Vec<u8>) {
        self.results.write_json(suffix, time_ns, &json);
        self.keep_for_report(suffix, &json);
        link.publish_json(suffix, json);
    }

    /// Records that `job`'s window gets no update, and why: a message on
    /// `updating/failures` (`"skipped": true`) in the results file and on
    /// zenoh, and a warning (the drop itself is counted in
    /// `health.queue_drops` by the worker).
    fn skip_update(&mut self, job: &UpdateJob, (key, reason): (&str, &str), link: &ZenohLink) {
        tracing::warn!(message = "update skipped", window = job.window, reason);
        *self
            .pipeline
            .health_mut()
            .updates_skipped
            .entry(key.to_string())
            .or_default() += 1;
        self.last_time = self.last_time.max(job.time_ns);
        let time = wire::format_timestamp(job.time_ns);
        let message = serde_json::json!({"time": time, "window": job.window, "error": reason, "skipped": true});
        self.send(link, "updating/failures", job.time_ns, &message);
    }

    /// Writes, publishes, counts and logs a closed window.
    fn report_window(&mut self, w: &WindowReport, link: &ZenohLink) {
        for (suffix, m) in results::window_messages(w) {
            self.send(link, suffix, w.end_ns, &m);
        }
        if let Some(v) = self.viewer.as_mut() {
            count_output_error(
                v.log_window(w),
                &mut self.pipeline.health_mut().rerun_errors,
                100,
                "Rerun",
            );
        }
        self.summary.windows += 1;
        self.last_time = w.end_ns;
        match &w.skipped {
            None => tracing::info!(
                message = "window accepted",
                window = w.index,
                segments = w.segments_accepted,
                identified_modes = w.modes.as_ref().map_or(0, |m| m.report.result.modes.len())
            ),
            Some(r) => tracing::warn!(message = "window skipped", window = w.index, reason = %r),
        }
    }

    /// Applies an outcome to the pipeline and sends it everywhere: results,
    /// zenoh (and the `latest` reply), the state file, Rerun.
    fn handle_outcome(&mut self, outcome: &mut UpdateOutcome, link: &ZenohLink) -> Result<()> {
        let scored = self.pipeline.apply(outcome);
        let outcome = &*outcome;
        // Pre-computed FRF windows close no sample window: their updates
        // date the health messages (else a daemon fed only FRF sets never
        // wrote one).
        self.last_time = self.last_time.max(outcome.time_ns);
        let time = wire::format_timestamp(outcome.time_ns);
        for (suffix, msg) in results::update_messages(outcome, &time) {
            let json = self.send(link, suffix, outcome.time_ns, &msg);
            if suffix == "updating/parameters" {
                link.set_latest(Latest::Updating, json);
            }
        }
        if let Some(m) = &scored {
            self.report_monitoring(m, outcome.time_ns, link)?;
        }
        self.results.flush();
        match &outcome.result {
            Ok(r) => {
                tracing::info!(
                    message = "update accepted",
                    window = outcome.window,
                    relative_residual = %format_args!("{:.4}", r.result.relative_residual),
                    iterations = r.result.iterations.len().saturating_sub(1)
                );
                if let (Some(path), Some(accepted)) = (&self.state, self.pipeline.accepted()) {
                    // A failed state write is logged and retried at the next update; the run goes on.
                    if let Err(e) = state::save_state(path, accepted) {
                        tracing::error!(message = "cannot save the state", error = %format!("{e:#}"));
                    }
                }
                let monitoring = scored
                    .as_ref()
                    .map(|m| format!(", monitoring: {}", m.status.state))
                    .unwrap_or_default();
                notify_systemd(&[sd_notify::NotifyState::Status(&format!(
                    "window {}: relative residual {:.4}{monitoring}",
                    outcome.window, r.result.relative_residual
                ))]);
            }
            Err(e) => {
                tracing::warn!(message = "update failed, keeping the last parameters", window = outcome.window, error = %e)
            }
        }
        if let Some(v) = self.viewer.as_mut() {
            count_output_error(
                v.log_update(outcome),
                &mut self.pipeline.health_mut().rerun_errors,
                100,
                "Rerun",
            );
        }
        // The latency ends here: every output of the update is written.
        if let Some(m) = &self.metrics {
            m.record_update(outcome, self.pipeline.accepted());
        }
        Ok(())
    }
}

impl Daemon {
    /// The running event finished: its chain goes back to the worker (which
    /// saves it and starts the next burst) and its line everywhere.
    pub(super) fn on_event(
        &mut self,
        finished: Result<(crate::service::events::Chain, crate::service::events::EventLine), JoinError>,
        link: &ZenohLink,
    ) -> Result<()> {
        let (chain, line) = finished.context("the event worker panicked")?;
        if let Some(e) = self.events.as_mut() {
            e.done(chain);
        }
        self.report_event(line, link);
        Ok(())
    }

    /// Every second with `[events]`: a burst after which the logger has
    /// been silent long enough is an event.
    pub(super) fn on_event_tick(&mut self, link: &ZenohLink) {
        let dropped = match self.events.as_mut() {
            Some(e) => e.tick(std::time::Instant::now()),
            None => return,
        };
        for line in dropped {
            self.report_event(line, link);
        }
    }

    /// An event's `events/summary` and `events/verdict` (results file and
    /// zenoh), the owner's notification, Rerun, the log and the counters.
    fn report_event(&mut self, line: crate::service::events::EventLine, link: &ZenohLink) {
        let health = self.pipeline.health_mut();
        if line.skipped.is_some() {
            health.events_skipped += 1;
        } else {
            health.events_processed += 1;
        }
        let kind = self.events.as_ref().map(EventWorker::amplitude).unwrap_or_default();
        if let Err(e) = crate::service::events::emit(&line, kind, &mut EventReport { daemon: self, link }) {
            tracing::error!(message = "cannot serialise an event", event = %line.event, error = %format!("{e:#}"));
        }
    }

    /// Sends a scored update's monitoring messages (results, zenoh, the
    /// `monitoring/latest` reply, the log, Rerun) and saves the monitor.
    fn report_monitoring(&mut self, m: &MonitoringOutcome, time_ns: i128, link: &ZenohLink) -> Result<()> {
        if let Some(metrics) = &self.metrics {
            metrics.record_monitoring(&m.status);
        }
        for (suffix, msg) in results::monitoring_messages(m) {
            let json = self.send(link, suffix, time_ns, &msg);
            if suffix == "monitoring/status" {
                if let Some(n) = self.notifier.as_mut() {
                    n.observe(&m.status, &json);
                }
                link.set_latest(Latest::Monitoring, json);
            }
        }
        match &m.alarm {
            Some(a) if a.state == "alarm" => tracing::error!(
                message = "ALARM: the structure has changed",
                window = a.window,
                t2 = ?a.t2,
                mewma = ?a.mewma,
                largest = ?a.largest_residuals.iter().map(|r| &r.name).collect::<Vec<_>>()
            ),
            Some(a) => tracing::warn!(message = "alarm cleared", window = a.window, state = %a.state),
            None => tracing::info!(message = "monitoring", window = m.status.window, state = %m.status.state),
        }
        if let (Some(path), Some(monitor)) = (&self.monitor_file, self.pipeline.monitor()) {
            // Like the state: a failed write is logged and retried at the next update.
            if let Err(e) = state::save_monitor(path, monitor) {
                tracing::error!(message = "cannot save the monitor", error = %format!("{e:#}"));
            }
        }
        if let Some(v) = self.viewer.as_mut() {
            count_output_error(
                v.log_monitoring(time_ns, &m.status),
                &mut self.pipeline.health_mut().rerun_errors,
                100,
                "Rerun",
            );
        }
        Ok(())
    }
}

/// Logs the input rejected since the last call, by reason, as one warning:
/// called on the health tick, so a flood of bad input costs one log line per
/// tick, and nothing is logged while the input is clean.
fn log_new_rejections(rejected: &BTreeMap<String, u64>, logged: &mut BTreeMap<String, u64>) {
    let new: BTreeMap<&str, u64> = rejected
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

/// Where the daemon sends an event ([`crate::service::events::emit`]): the
/// results file and zenoh, the owner's notifier, the viewer, and the log.
/// Nothing here stops the daemon: an output that fails is counted.
struct EventReport<'a> {
    daemon: &'a mut Daemon,
    link: &'a ZenohLink,
}

impl crate::service::events::EventSink for EventReport<'_> {
    fn message(&mut self, topic: &'static str, time_ns: i128, json: Vec<u8>) -> Result<()> {
        self.daemon.send_json(self.link, topic, time_ns, json);
        self.daemon.last_time = self.daemon.last_time.max(time_ns);
        self.daemon.results.flush();
        Ok(())
    }

    fn status(&mut self, status: &crate::io::monitoring_json::StatusMessage, json: &[u8]) -> Result<()> {
        if let Some(n) = self.daemon.notifier.as_mut() {
            n.observe(status, json);
        }
        Ok(())
    }

    fn rerun(&mut self, line: &crate::service::events::EventLine, kind: crate::config::EventAmplitude) -> Result<()> {
        let daemon = &mut *self.daemon;
        if let Some(v) = daemon.viewer.as_mut() {
            count_output_error(
                crate::service::events::log_rerun(v, line, kind),
                &mut daemon.pipeline.health_mut().rerun_errors,
                100,
                "Rerun",
            );
        }
        Ok(())
    }

    fn line(&mut self, line: &crate::service::events::EventLine) -> Result<()> {
        match (&line.skipped, &line.verdict) {
            (Some(reason), _) => tracing::warn!(message = "event skipped", event = %line.event, reason = %reason),
            (None, Some(v)) if v.state == "alarm" => {
                tracing::error!(message = "ALARM: the event changed the structure", event = %line.event, outside = ?v.outside)
            }
            (None, v) => {
                tracing::info!(message = "event judged", event = %line.event, pga_ground = ?line.pga_ground, modes = line.modes.len(), verdict = v.as_ref().map_or("-", |v| v.state.as_str()))
            }
        }
        Ok(())
    }
}
