//! The owner's report (`splinewatch report`): one self-contained HTML file
//! per event or per period, read from a bridge's results files. The verdict
//! comes first in words with an inspection priority; then the shaking, the
//! figures (inline SVG), the tables, what was skipped and why, and what the
//! verdict rests on (software version, config and its SHA-256).
//! Deterministic: the same results give the same bytes.

mod event;
pub mod figures;
pub mod fleet;
pub mod history;
pub mod html;
mod period;
pub mod words;

use crate::config::{Config, EventAmplitude};
use crate::io::results_file::ResultsContents;
use crate::io::results_topics::Provenance;
use crate::io::wire::parse_timestamp;
use html::escape;
use std::fmt::Write;
use thiserror::Error;

pub use period::recent_figures;
pub use words::Priority;

/// What a report is of.
#[derive(Debug, Clone, PartialEq)]
pub enum Selection {
    /// One event, by its name (exact, or a part of it that only one event's
    /// name contains).
    Event(String),
    /// The updates, alarms and events between two times (ns; open ends).
    Period { from: Option<i128>, to: Option<i128> },
    /// The last event when the results hold events, else the whole period.
    Latest,
}

#[derive(Debug, Error)]
pub enum ReportError {
    #[error("no event named {name:?} in the results of {bridge}; its events: {known}")]
    NoSuchEvent {
        name: String,
        bridge: String,
        known: String,
    },
    #[error("{name:?} matches several events ({matches}): give more of the name")]
    SeveralEvents { name: String, matches: String },
    #[error("the results of {bridge} hold nothing between {from} and {to} (their span: {span})")]
    EmptyPeriod {
        bridge: String,
        from: String,
        to: String,
        span: String,
    },
    #[error("the results of {bridge} hold no event: give --from/--to for a period report")]
    NoEvents { bridge: String },
}

/// A rendered report: its HTML and the verdict's words and priority (the
/// notification's subject).
#[derive(Debug, Clone)]
pub struct Report {
    /// The structure's name (the prefix's when the results do not say).
    pub bridge: String,
    pub html: String,
    pub verdict: String,
    pub priority: Priority,
    pub title: String,
}

/// What the results' provenance says about the config they were made with.
struct Settings {
    amplitude: EventAmplitude,
    min_events: Option<usize>,
}

fn settings(provenance: Option<&Provenance>) -> Settings {
    let config = provenance.and_then(|p| Config::from_toml(&p.config_toml).ok());
    Settings {
        amplitude: config.as_ref().map(|c| c.events().amplitude).unwrap_or_default(),
        min_events: config.as_ref().map(|c| c.events().min_events),
    }
}

/// The report of `selection` over `contents`.
pub fn render(contents: &ResultsContents, selection: &Selection) -> Result<Report, ReportError> {
    let settings = settings(contents.provenance.first());
    match selection {
        Selection::Event(name) => Ok(event::render(contents, find_event(contents, name)?, &settings)),
        Selection::Latest if !contents.events.is_empty() => {
            Ok(event::render(contents, contents.events.len() - 1, &settings))
        }
        Selection::Latest => period::render(contents, None, None),
        Selection::Period { from, to } => period::render(contents, *from, *to),
    }
}

/// The index of the event `name` names.
fn find_event(contents: &ResultsContents, name: &str) -> Result<usize, ReportError> {
    let events = &contents.events;
    if events.is_empty() {
        return Err(ReportError::NoEvents {
            bridge: contents.prefix.clone(),
        });
    }
    if let Some(k) = events.iter().rposition(|e| e.event == name) {
        return Ok(k);
    }
    let lower = name.to_lowercase();
    let matching: Vec<usize> = (0..events.len())
        .filter(|&k| events[k].event.to_lowercase().contains(&lower))
        .collect();
    match matching.as_slice() {
        [k] => Ok(*k),
        [] => Err(ReportError::NoSuchEvent {
            name: name.into(),
            bridge: contents.prefix.clone(),
            known: listed(events.iter().map(|e| e.event.as_str())),
        }),
        many => Err(ReportError::SeveralEvents {
            name: name.into(),
            matches: listed(many.iter().map(|&k| events[k].event.as_str())),
        }),
    }
}

/// Names joined with commas, at most eight of them.
fn listed<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let names: Vec<&str> = names.collect();
    let mut s = names.iter().take(8).copied().collect::<Vec<_>>().join(", ");
    if names.len() > 8 {
        let _ = write!(s, " and {} more", names.len() - 8);
    }
    s
}

/// The time of an RFC 3339 string, ns.
fn time_of(s: Option<&str>) -> Option<i128> {
    s.and_then(parse_timestamp)
}

/// The structure's name the results give (their prefix when they do not).
fn bridge(contents: &ResultsContents) -> String {
    contents
        .provenance
        .first()
        .map(|p| p.structure.as_str())
        .filter(|s| !s.is_empty())
        .unwrap_or(&contents.prefix)
        .to_string()
}

/// The page's head: the bridge, the title, the verdict box.
fn header(contents: &ResultsContents, title: &str, subtitle: &str, verdict: &str, priority: Priority) -> String {
    let structure = bridge(contents);
    format!(
        "<header><p class=\"subtitle\">{} · {}</p><h1>{}</h1><p class=\"subtitle\">{}</p></header>\
<div id=\"verdict\" class=\"{}\" role=\"status\"><span class=\"priority\">{}</span><p id=\"verdict-text\">{}</p></div>",
        escape(&structure),
        escape(&contents.prefix),
        escape(title),
        escape(subtitle),
        priority.class(),
        escape(priority.label()),
        escape(verdict)
    )
}

/// What the verdict rests on: the software, the config, the files.
fn provenance_section(contents: &ResultsContents) -> String {
    let mut body = String::new();
    match contents.provenance.first() {
        Some(p) => {
            let _ = write!(
                body,
                "<ul><li>Made by splinewatch {} (this report by {})</li><li>Bridge topic prefix: {}</li>\
<li>Config: {} (SHA-256 <code>{}</code>)</li>",
                escape(&p.version),
                env!("CARGO_PKG_VERSION"),
                escape(&p.prefix),
                escape(if p.config_path.is_empty() {
                    "(not from a file)"
                } else {
                    &p.config_path
                }),
                escape(if p.config_sha256.is_empty() {
                    "—"
                } else {
                    &p.config_sha256
                }),
            );
            let others: Vec<&Provenance> = contents
                .provenance
                .iter()
                .skip(1)
                .filter(|o| o.config_sha256 != p.config_sha256 || o.version != p.version)
                .collect();
            if !others.is_empty() {
                let _ = write!(
                    body,
                    "<li class=\"out\">{} earlier results file(s) were made with another config or version: {}</li>",
                    others.len(),
                    escape(&listed(others.iter().map(|o| o.config_sha256.as_str())))
                );
            }
            body.push_str("</ul>");
            if !p.config_toml.is_empty() {
                let _ = write!(
                    body,
                    "<details><summary>The config the results were made with</summary><pre>{}</pre></details>",
                    escape(&p.config_toml)
                );
            }
        }
        None => {
            body.push_str("<p>The results files record no provenance (written before results files recorded it).</p>")
        }
    }
    let _ = write!(
        body,
        "<p>Results files: {}</p>",
        escape(&listed(contents.files.iter().map(String::as_str)))
    );
    html::section("provenance", "What this report rests on", &body)
}
