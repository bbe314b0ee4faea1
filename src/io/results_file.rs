//! Results files read back for the owner's report: the bridge they are of
//! (their topic prefix), what made them (the provenance record), and the
//! messages a report shows, typed: events' summaries and verdicts, the
//! monitoring statuses and alarms, the updates' parameters, the health.
//! Readers ignore keys they do not know, as every results reader does.

use super::modes_json::ModeEntry;
use super::monitoring_json::{AlarmMessage, StatusMessage};
use super::results_topics::{Provenance, EVENT_SUMMARY, EVENT_TOPICS, MONITORING_TOPICS, PROVENANCE_METADATA, TOPICS};
use serde::Deserialize;
use splinewatch_core::updating::ParameterEstimate;
use std::collections::BTreeSet;
use thiserror::Error;

/// Why results files cannot be read into one report.
#[derive(Debug, Error)]
pub enum ResultsFileError {
    #[error("{file} is not an MCAP file")]
    NotMcap { file: String },
    #[error("{file} is truncated or damaged ({reason}): `splinewatch recover {file}` salvages its complete chunks")]
    Damaged { file: String, reason: String },
    #[error("{file} holds no splinewatch results (no message on a results topic)")]
    NoResults { file: String },
    #[error("{file} holds the results of several bridges ({prefixes}): one bridge per report")]
    SeveralBridges { file: String, prefixes: String },
    #[error("{file} is of bridge {found}, {first} of bridge {expected}: one bridge per report")]
    AnotherBridge {
        file: String,
        found: String,
        first: String,
        expected: String,
    },
    #[error("{file}: a {topic} message is not what its schema says ({reason})")]
    BadMessage {
        file: String,
        topic: String,
        reason: String,
    },
}

/// One event's `events/summary` message.
#[derive(Debug, Clone, Deserialize)]
pub struct EventSummary {
    pub event: String,
    #[serde(default)]
    pub number: u64,
    pub start: Option<String>,
    pub pga_ground: Option<f64>,
    pub peak_deck: Option<f64>,
    #[serde(default)]
    pub rms_deck: Option<f64>,
    #[serde(default)]
    pub modes: Vec<ModeEntry>,
    #[serde(default)]
    pub parameters: Vec<ParameterEstimate>,
    #[serde(default)]
    pub forecast: Option<ForecastSummary>,
    #[serde(default)]
    pub forecast_channels: Vec<String>,
    #[serde(default)]
    pub verdict: Option<Verdict>,
    #[serde(default)]
    pub skipped: Option<String>,
    #[serde(default)]
    pub update: Option<EventUpdate>,
    #[serde(default)]
    pub notes: Vec<String>,
}

/// The forecast's scores per deck channel and the "deck = nearest ground"
/// baseline's.
#[derive(Debug, Clone, Deserialize)]
pub struct ForecastSummary {
    pub channels: Vec<ChannelScore>,
    #[serde(default)]
    pub baseline: Vec<ChannelScore>,
    #[serde(default)]
    pub strong_span_s: Option<[f64; 2]>,
}

#[derive(Debug, Clone, Deserialize)]
pub struct ChannelScore {
    pub sensor: String,
    pub nrmse_strong: f64,
    #[serde(default)]
    pub correlation: Option<f64>,
    #[serde(default)]
    pub peak_ratio: Option<f64>,
    /// The baseline's ground input (baseline scores only).
    #[serde(default)]
    pub ground: Option<String>,
}

/// An event's verdict: its state, the features outside their bands, every band.
#[derive(Debug, Clone, Deserialize)]
pub struct Verdict {
    pub state: String,
    #[serde(default)]
    pub outside: Vec<String>,
    #[serde(default)]
    pub bands: Vec<FeatureBandLine>,
}

#[derive(Debug, Clone, Deserialize)]
pub struct FeatureBandLine {
    pub feature: String,
    pub value: Option<f64>,
    pub band: Option<Band>,
}

/// What the earlier events expect at this event's amplitude.
#[derive(Debug, Clone, Copy, Deserialize)]
pub struct Band {
    pub predicted: f64,
    pub lower: f64,
    pub upper: f64,
    pub events: usize,
}

#[derive(Debug, Clone, Deserialize)]
pub struct EventUpdate {
    pub model_mode_hz: Option<f64>,
    #[serde(default)]
    pub model_mode_std_hz: Option<f64>,
    pub relative_residual: f64,
    #[serde(default)]
    pub iterations: usize,
    #[serde(default)]
    pub converged: bool,
    #[serde(default)]
    pub stop_reason: String,
    #[serde(default)]
    pub residues: String,
}

/// One update's `updating/parameters` message.
#[derive(Debug, Clone, Deserialize)]
pub struct UpdateSummary {
    pub time: String,
    pub window: u64,
    pub converged: bool,
    pub relative_residual: f64,
    pub parameters: Vec<ParameterEstimate>,
}

/// One `updating/failures` message: a window whose update failed or was skipped.
#[derive(Debug, Clone, Deserialize)]
pub struct FailureSummary {
    #[serde(default)]
    pub time: String,
    #[serde(default)]
    pub window: u64,
    #[serde(default)]
    pub error: String,
}

/// What one bridge's results files hold, in file order.
#[derive(Debug, Clone, Default)]
pub struct ResultsContents {
    /// The topic prefix: the bridge (`bridge/<name>`).
    pub prefix: String,
    /// Each file's provenance record, when it has one (the last one read first).
    pub provenance: Vec<Provenance>,
    pub events: Vec<EventSummary>,
    pub statuses: Vec<StatusMessage>,
    pub alarms: Vec<AlarmMessage>,
    pub updates: Vec<UpdateSummary>,
    pub failures: Vec<FailureSummary>,
    /// The last `health` message.
    pub health: Option<serde_json::Value>,
    /// The files' names, as given.
    pub files: Vec<String>,
}

impl ResultsContents {
    /// Adds one message on the result topic `suffix` (the topics a report
    /// reads; others are ignored).
    pub fn add(&mut self, suffix: &str, data: &[u8]) -> Result<(), serde_json::Error> {
        match suffix {
            EVENT_SUMMARY => self.events.push(serde_json::from_slice(data)?),
            "monitoring/status" => self.statuses.push(serde_json::from_slice(data)?),
            "monitoring/alarm" => self.alarms.push(serde_json::from_slice(data)?),
            "updating/parameters" => self.updates.push(serde_json::from_slice(data)?),
            "updating/failures" => self.failures.push(serde_json::from_slice(data)?),
            "health" => self.health = Some(serde_json::from_slice(data)?),
            _ => {}
        }
        Ok(())
    }

    /// Whether [`Self::add`] reads messages on `suffix`.
    pub fn reads(suffix: &str) -> bool {
        matches!(
            suffix,
            EVENT_SUMMARY
                | "monitoring/status"
                | "monitoring/alarm"
                | "updating/parameters"
                | "updating/failures"
                | "health"
        )
    }
}

/// Reads `files` (name and bytes, in order) as the results of one bridge.
pub fn read_results(files: &[(String, &[u8])]) -> Result<ResultsContents, ResultsFileError> {
    let mut out = ResultsContents::default();
    for (name, bytes) in files {
        let prefix = read_one(name, bytes, &mut out)?;
        if out.files.is_empty() {
            out.prefix = prefix;
        } else if prefix != out.prefix {
            return Err(ResultsFileError::AnotherBridge {
                file: name.clone(),
                found: prefix,
                first: out.files[0].clone(),
                expected: out.prefix.clone(),
            });
        }
        out.files.push(name.clone());
    }
    out.provenance.reverse();
    Ok(out)
}

/// The result topic suffixes, longest first (`oma/modes` before `modes`).
fn suffixes() -> Vec<&'static str> {
    let mut all: Vec<&str> = TOPICS
        .iter()
        .chain(&MONITORING_TOPICS)
        .chain(&EVENT_TOPICS)
        .map(|(n, _)| *n)
        .collect();
    all.sort_by_key(|s| std::cmp::Reverse(s.len()));
    all
}

/// `topic` split into its prefix and result suffix.
fn split_topic<'t>(topic: &'t str, suffixes: &[&'static str]) -> Option<(&'t str, &'static str)> {
    suffixes.iter().find_map(|s| {
        let prefix = topic.strip_suffix(s)?.strip_suffix('/')?;
        (!prefix.is_empty()).then_some((prefix, *s))
    })
}

fn read_one(name: &str, bytes: &[u8], out: &mut ResultsContents) -> Result<String, ResultsFileError> {
    let damaged = |e: &dyn std::fmt::Display| ResultsFileError::Damaged {
        file: name.to_string(),
        reason: e.to_string(),
    };
    if !bytes.starts_with(mcap::MAGIC) {
        return Err(ResultsFileError::NotMcap { file: name.into() });
    }
    let suffixes = suffixes();
    let mut prefixes = BTreeSet::new();
    let mut last_health = None;
    let messages = super::recording::mcap_messages(bytes, false).map_err(|e| damaged(&e))?;
    for message in messages {
        let message = message.map_err(|e| damaged(&e))?;
        let Some((prefix, suffix)) = split_topic(&message.channel.topic, &suffixes) else {
            continue;
        };
        prefixes.insert(prefix.to_string());
        let bad = |e: serde_json::Error| ResultsFileError::BadMessage {
            file: name.into(),
            topic: message.channel.topic.clone(),
            reason: e.to_string(),
        };
        if suffix == "health" {
            last_health = Some(serde_json::from_slice(&message.data).map_err(bad)?);
        } else {
            out.add(suffix, &message.data).map_err(bad)?;
        }
    }
    if last_health.is_some() {
        out.health = last_health;
    }
    if let Some(p) = provenance_of(bytes) {
        out.provenance.push(p);
    }
    match prefixes.len() {
        0 => Err(ResultsFileError::NoResults { file: name.into() }),
        1 => Ok(prefixes.into_iter().next().unwrap_or_default()),
        _ => Err(ResultsFileError::SeveralBridges {
            file: name.into(),
            prefixes: prefixes.into_iter().collect::<Vec<_>>().join(", "),
        }),
    }
}

/// The file's provenance record (through its summary's metadata index).
fn provenance_of(bytes: &[u8]) -> Option<Provenance> {
    let summary = mcap::Summary::read(bytes).ok()??;
    summary
        .metadata_indexes
        .iter()
        .filter(|m| m.name == PROVENANCE_METADATA)
        .find_map(|index| mcap::read::metadata(bytes, index).ok())
        .map(|m| Provenance::from_metadata(&m.metadata))
}
