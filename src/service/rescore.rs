//! `splinewatch monitor`: the statistical layer re-run offline over
//! results files: the status messages hold what each update scored (its
//! parameters and window temperatures), so a year of results is re-trained
//! and re-scored in seconds, without replaying raw data.

use crate::config::MonitoringConfig;
use crate::io::monitoring_json::StatusMessage;
use crate::outputs::results::{self, ResultsWriter};
use crate::pipeline::{rescore, MonitoringOutcome, Training};
use anyhow::{bail, Context, Result};
use std::io::{Seek, Write};

/// What a re-scoring found.
#[derive(Debug, Clone, Default)]
pub struct RescoreSummary {
    /// Results messages read, and those copied to the output.
    pub messages: u64,
    pub copied: u64,
    /// The new statuses, in order.
    pub statuses: Vec<StatusMessage>,
}

/// The `monitoring/status` messages of `results` (MCAP files, in order).
pub fn read_statuses(results: &[&[u8]], prefix: &str) -> Result<Vec<StatusMessage>> {
    let topic = format!("{prefix}/monitoring/status");
    let mut out = Vec::new();
    for (k, bytes) in results.iter().enumerate() {
        for message in
            crate::io::recording::mcap_messages(bytes, false).with_context(|| format!("results file {}", k + 1))?
        {
            let message = message.context("corrupt MCAP record")?;
            if message.channel.topic == topic {
                out.push(
                    serde_json::from_slice(&message.data)
                        .with_context(|| format!("results file {}: a {topic} message is not a status", k + 1))?,
                );
            }
        }
    }
    if out.is_empty() {
        bail!("no {topic} messages: the results were made without [monitoring] (or under another prefix)");
    }
    Ok(out)
}

/// Re-scores the statuses of `results` and writes a new results file to
/// `out` (when given): every other message copied as it was, each status
/// replaced by the new one, the old alarms by the new.
pub fn rescore_results<W: Write + Seek>(
    config: &MonitoringConfig,
    prefix: &str,
    results: &[&[u8]],
    training: Training,
    raw: bool,
    out: Option<&mut ResultsWriter<W>>,
) -> Result<RescoreSummary> {
    let statuses = read_statuses(results, prefix)?;
    let outcomes = rescore(config, &statuses, training, raw)?;
    let mut summary = RescoreSummary {
        statuses: outcomes.iter().map(|o| o.status.clone()).collect(),
        ..Default::default()
    };
    let Some(out) = out else {
        return Ok(summary);
    };
    let mut next = outcomes.iter();
    for bytes in results {
        for message in crate::io::recording::mcap_messages(bytes, false)? {
            let message = message.context("corrupt MCAP record")?;
            summary.messages += 1;
            let Some(suffix) = message.channel.topic.strip_prefix(&format!("{prefix}/")) else {
                continue;
            };
            let time_ns = i128::from(message.log_time);
            match suffix {
                "monitoring/alarm" => {}
                "monitoring/status" => {
                    let outcome: &MonitoringOutcome = next.next().context("statuses counted above")?;
                    for (suffix, m) in results::monitoring_messages(outcome) {
                        out.write(suffix, time_ns, &m)?;
                    }
                }
                _ if results::TOPICS.iter().any(|(t, _)| *t == suffix) => {
                    let value: serde_json::Value = serde_json::from_slice(&message.data)
                        .with_context(|| format!("a {suffix} message is not JSON"))?;
                    out.write(suffix, time_ns, &value)?;
                    summary.copied += 1;
                }
                _ => {}
            }
        }
    }
    Ok(summary)
}
