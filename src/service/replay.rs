//! Offline replay of a raw-input recording through the pipeline: the same
//! code path as the live daemon, deterministic (updates run inline, in
//! order, single-threaded).
//! Room: a service shell. May import: `outputs`, `pipeline`, `studies`, `config`, `io`, the core crate.

use super::{keep_latest, resume_monitor};
use crate::config::Config;
use crate::io::monitoring_json::StatusMessage;
use crate::io::wire::{self, Encoding};
use crate::outputs::rerun::RerunOutput;
use crate::outputs::results::{self, ResultsWriter};
use crate::outputs::state;
use crate::pipeline::{AcceptedParameters, Pipeline, UpdateJob, UpdateOutcome, WindowReport};
use anyhow::{Context, Result};
use std::collections::VecDeque;
use std::io::{Seek, Write};
use std::path::Path;

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
}

impl Default for ReplayOptions<'_> {
    fn default() -> Self {
        Self {
            initial: None,
            viewer: None,
            state_path: None,
            keep_latest: 64,
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

/// Replays `recordings` (MCAP files, in order: e.g. the rotated raw-input
/// files of a daemon) into `out` (and `viewer`, if any); saves the state
/// after every accepted update when `state_path` is given.
pub fn replay<W: Write + Seek>(
    config: &Config,
    recordings: &[&[u8]],
    out: &mut ResultsWriter<W>,
    options: ReplayOptions<'_>,
    progress: &mut dyn FnMut(Progress, Option<&str>),
) -> Result<ReplaySummary> {
    let ReplayOptions {
        initial,
        viewer,
        state_path,
        keep_latest,
    } = options;
    let mut pipeline = Pipeline::new(config, config.schedule.clone(), initial)?;
    let monitor_path = resume_monitor(config, state_path, &mut pipeline)?;
    let limits = crate::pipeline::block_limits(config);
    let total = recordings.iter().map(|bytes| message_count(bytes)).sum();
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
    };
    let messages = recordings.iter().enumerate().map(|(k, bytes)| {
        crate::io::recording::mcap_messages(bytes, false).with_context(|| format!("recording {}", k + 1))
    });
    for message in messages.collect::<Result<Vec<_>>>()?.into_iter().flatten() {
        let message = message.context("corrupt MCAP record")?;
        sink.summary.messages += 1;
        let topic = &message.channel.topic;
        if topic.contains("/frf/") {
            // A recorded pre-computed FRF: the log time stands for its end.
            let time_ns = i128::from(message.log_time);
            if let Some(job) = pipeline.ingest_frf(&message.data, time_ns) {
                sink.handle(&mut pipeline, Vec::new(), vec![job])?;
            }
            continue;
        }
        if !(topic.contains("/accel/") || topic.contains("/force/") || topic.contains("/temperature/")) {
            continue;
        }
        let Some(encoding) = Encoding::from_name(&message.channel.message_encoding) else {
            pipeline.health_mut().reject("unknown_encoding");
            continue;
        };
        let blocks = match wire::decode(&message.data, encoding, &limits) {
            Ok(b) => b,
            Err(e) => {
                pipeline.reject_message(&e);
                continue;
            }
        };
        for block in blocks {
            let (windows, jobs) = pipeline.ingest(block);
            sink.handle(&mut pipeline, windows, jobs)?;
        }
        if sink.summary.messages % 256 == 0 {
            sink.report(None);
        }
    }
    // Blocks still held for the stream's reference (a very short recording).
    let (windows, jobs) = pipeline.finish();
    sink.handle(&mut pipeline, windows, jobs)?;
    // The final health, at the last window's end (or, with none closed, the
    // data analysed so far); without any data there is no measurement time
    // to stamp it with, and no message.
    let last_time = Some(sink.last_time)
        .filter(|&t| t > 0)
        .or_else(|| pipeline.measured_until().filter(|&t| t > 0));
    if let Some(last_time) = last_time {
        sink.out.write(
            "health",
            last_time,
            &results::health_message(last_time, pipeline.health()),
        )?;
        if let Some(v) = sink.viewer {
            v.log_health(last_time, pipeline.health())?;
        }
    }
    let mut summary = sink.summary;
    summary.accepted = pipeline.accepted().cloned();
    Ok(summary)
}

/// The message count in a recording's summary (0 when it has none), for
/// the progress bar.
fn message_count(recording: &[u8]) -> u64 {
    mcap::Summary::read(recording)
        .ok()
        .flatten()
        .and_then(|s| s.stats.map(|st| st.message_count))
        .unwrap_or(0)
}

/// Where the replay's windows and updates go.
struct Outputs<'a, W: Write + Seek> {
    out: &'a mut ResultsWriter<W>,
    viewer: Option<&'a mut RerunOutput>,
    state_path: Option<&'a Path>,
    monitor_path: Option<&'a Path>,
    progress: &'a mut dyn FnMut(Progress, Option<&str>),
    total: u64,
    keep: usize,
    last_time: i128,
    summary: ReplaySummary,
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

    /// Writes the closed windows and runs the update jobs inline, in order.
    fn handle(&mut self, pipeline: &mut Pipeline, windows: Vec<WindowReport>, jobs: Vec<UpdateJob>) -> Result<()> {
        for w in windows {
            self.last_time = w.end_ns;
            for (suffix, m) in results::window_messages(&w) {
                self.out.write(suffix, w.end_ns, &m)?;
            }
            if let Some(v) = self.viewer.as_deref_mut() {
                v.log_window(&w)?;
            }
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
        for mut job in jobs {
            // Several jobs from one block: each starts from the one before.
            pipeline.rebase(&mut job);
            let mut outcome = job.run();
            let scored = pipeline.apply(&mut outcome);
            for (suffix, msg) in results::update_messages(&outcome) {
                self.out.write(suffix, outcome.time_ns, &msg)?;
            }
            if let Some(m) = &scored {
                for (suffix, msg) in results::monitoring_messages(m) {
                    self.out.write(suffix, outcome.time_ns, &msg)?;
                }
                if let Some(v) = self.viewer.as_deref_mut() {
                    v.log_monitoring(outcome.time_ns, &m.status)?;
                }
                self.summary.monitoring.push(m.status.clone());
            }
            let note = match &outcome.result {
                Ok(r) => format!(
                    "update after window {}: relative residual {:.4}, {} iterations",
                    outcome.window,
                    r.result.relative_residual,
                    r.result.iterations.len() - 1
                ),
                Err(e) => format!(
                    "update after window {} failed, keeping the last parameters: {e}",
                    outcome.window
                ),
            };
            self.out.flush()?;
            if let (Some(path), Some(state), Ok(_)) = (self.state_path, pipeline.accepted(), &outcome.result) {
                state::save_state(path, state)?;
            }
            if let (Some(path), Some(monitor), Some(_)) = (self.monitor_path, pipeline.monitor(), &scored) {
                state::save_monitor(path, monitor)?;
            }
            self.out.write(
                "health",
                outcome.time_ns,
                &results::health_message(outcome.time_ns, pipeline.health()),
            )?;
            if let Some(v) = self.viewer.as_deref_mut() {
                v.log_update(&outcome)?;
                v.log_health(outcome.time_ns, pipeline.health())?;
            }
            self.report(Some(&note));
            self.summary.update_count += 1;
            keep_latest(&mut self.summary.updates, outcome, self.keep);
        }
        Ok(())
    }
}
