//! `splinewatch fleet`: the status of every span behind one router.
//!
//! Each daemon (one per span, `bridge/<structure.name>`) answers queries on
//! `<prefix>/{updating,monitoring,health}/latest` with its last message of
//! that kind, and holds the liveliness token `<prefix>/alive` once those
//! queryables are declared. A dashboard-side session first asks which
//! tokens are alive, then `bridge/*/<kind>/latest` once per kind, and groups
//! the replies by span: a span that is alive (or expected) but did not
//! answer is reported as such, never left out.

use crate::io::named_value::NamedValue;
use anyhow::{anyhow, Result};
use serde::Serialize;
use serde_json::Value;
use std::collections::BTreeMap;
use std::time::Duration;
use zenoh::Wait;

/// The queryables every daemon declares under its prefix
/// (`<prefix>/<kind>/latest`, in the order of the daemon's `Latest`).
pub const LATEST_KINDS: [&str; 3] = ["updating", "monitoring", "health"];

/// The liveliness token every daemon holds under its prefix.
pub const ALIVE: &str = "alive";

/// One span's latest messages (`None`: no reply, or the daemon has not
/// produced one yet: its queryable answers `{}`).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SpanStatus {
    /// `structure.name`: the key segment after `bridge/`.
    pub name: String,
    /// Its daemon's liveliness token was seen.
    pub alive: bool,
    /// The kinds it answered (`updating`, `monitoring`, `health`); empty: it
    /// did not answer at all.
    pub answered: Vec<String>,
    pub updating: Option<Value>,
    pub monitoring: Option<Value>,
    pub health: Option<Value>,
}

/// The spans whose daemon holds its liveliness token, waiting up to `timeout`.
pub fn alive_spans(session: &zenoh::Session, timeout: Duration) -> Result<Vec<String>> {
    let selector = format!("bridge/*/{ALIVE}");
    let replies = session
        .liveliness()
        .get(&selector)
        .timeout(timeout)
        .wait()
        .map_err(|e| anyhow!("cannot query the liveliness tokens {selector}: {e}"))?;
    let mut names: Vec<String> = replies
        .into_iter()
        .filter_map(|r| {
            r.result()
                .ok()
                .and_then(|s| span_name(s.key_expr().as_str()).map(str::to_string))
        })
        .collect();
    names.sort();
    names.dedup();
    Ok(names)
}

/// Asks every span behind `session` for its latest messages, waiting up to
/// `timeout` per kind; the spans in name order: every span that answered,
/// and every span alive or named in `expected` that did not (with empty
/// `answered`).
pub fn gather(session: &zenoh::Session, timeout: Duration, expected: &[String]) -> Result<Vec<SpanStatus>> {
    let mut spans: BTreeMap<String, SpanStatus> = BTreeMap::new();
    let listed = |name: &str, alive: bool| SpanStatus {
        name: name.to_string(),
        alive,
        ..SpanStatus::default()
    };
    for name in alive_spans(session, timeout)? {
        spans.insert(name.clone(), listed(&name, true));
    }
    for name in expected {
        spans.entry(name.clone()).or_insert_with(|| listed(name, false));
    }
    for kind in LATEST_KINDS {
        let selector = format!("bridge/*/{kind}/latest");
        let replies = session
            .get(&selector)
            .timeout(timeout)
            .wait()
            .map_err(|e| anyhow!("cannot query {selector}: {e}"))?;
        for reply in replies {
            let Ok(sample) = reply.result() else {
                tracing::warn!(message = "error reply", selector = %selector);
                continue;
            };
            let key = sample.key_expr().as_str();
            let Some(name) = span_name(key) else { continue };
            let body: Value = match serde_json::from_slice(&sample.payload().to_bytes()) {
                Ok(v) => v,
                Err(e) => {
                    tracing::warn!(message = "reply is not JSON", key = %key, error = %e);
                    continue;
                }
            };
            let span = spans.entry(name.to_string()).or_insert_with(|| listed(name, false));
            if !span.answered.iter().any(|k| k == kind) {
                span.answered.push(kind.to_string());
            }
            let empty = body.as_object().is_some_and(|o| o.is_empty());
            let slot = match kind {
                "updating" => &mut span.updating,
                "monitoring" => &mut span.monitoring,
                _ => &mut span.health,
            };
            *slot = (!empty).then_some(body);
        }
    }
    Ok(spans.into_values().collect())
}

/// `bridge/<name>/<kind>/latest` → `<name>`.
fn span_name(key: &str) -> Option<&str> {
    let mut parts = key.split('/');
    (parts.next() == Some("bridge")).then_some(())?;
    parts.next().filter(|n| !n.is_empty())
}

/// A compact summary of a span, for one console line or a JSON object.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpanSummary {
    pub name: String,
    /// `answering`; `no reply` (its daemon is alive but answered nothing
    /// within the timeout); `not running` (expected, no daemon alive).
    pub reachability: String,
    /// Measurement time of the latest update (RFC 3339), if any.
    pub last_update: Option<String>,
    pub converged: Option<bool>,
    /// The updated parameters, in the message's order.
    pub parameters: Vec<NamedValue>,
    /// `training`, `normal`, `outside_training_range`, `alarm`; `None`
    /// without `[monitoring]`.
    pub monitoring: Option<String>,
    /// `ok`, or what the health counters report (failures, drops, errors).
    pub health: String,
}

impl SpanStatus {
    pub fn summary(&self) -> SpanSummary {
        let updating = self.updating.as_ref();
        let parameters = updating
            .and_then(|u| u["parameters"].as_array())
            .map(|ps| {
                ps.iter()
                    .filter_map(|p| {
                        Some(NamedValue {
                            name: p["name"].as_str()?.to_string(),
                            value: p["value"].as_f64()?,
                        })
                    })
                    .collect()
            })
            .unwrap_or_default();
        let reachability = match (self.answered.is_empty(), self.alive) {
            (false, _) => "answering",
            (true, true) => "no reply",
            (true, false) => "not running",
        };
        SpanSummary {
            name: self.name.clone(),
            reachability: reachability.into(),
            last_update: updating.and_then(|u| u["time"].as_str()).map(str::to_string),
            converged: updating.and_then(|u| u["converged"].as_bool()),
            parameters,
            monitoring: self
                .monitoring
                .as_ref()
                .and_then(|m| m["state"].as_str())
                .map(str::to_string),
            health: health_summary(self.health.as_ref()),
        }
    }
}

/// `ok`, `no report yet`, or the non-zero problem counters of a health message.
fn health_summary(health: Option<&Value>) -> String {
    let Some(h) = health else {
        return "no report yet".into();
    };
    let mut problems = Vec::new();
    for counter in [
        "update_failures",
        "queue_drops",
        "gaps",
        "recording_errors",
        "results_errors",
        "rerun_errors",
        "log_writes_dropped",
    ] {
        if let Some(n) = h[counter].as_u64().filter(|&n| n > 0) {
            problems.push(format!("{counter} {n}"));
        }
    }
    let rejected: u64 = h["rejected"]
        .as_object()
        .map(|o| o.values().filter_map(Value::as_u64).sum())
        .unwrap_or(0);
    if rejected > 0 {
        problems.push(format!("rejected {rejected}"));
    }
    if problems.is_empty() {
        "ok".into()
    } else {
        problems.join(", ")
    }
}

impl SpanSummary {
    /// One console line: name, last update, up to `parameters` parameters,
    /// monitoring state, health.
    pub fn line(&self, parameters: usize) -> String {
        if self.reachability != "answering" {
            return format!("{}  {}", self.name, self.reachability);
        }
        let update = match (&self.last_update, self.converged) {
            (Some(t), Some(false)) => format!("updated {t} (not converged)"),
            (Some(t), _) => format!("updated {t}"),
            (None, _) => "no update yet".into(),
        };
        let mut shown: Vec<String> = self
            .parameters
            .iter()
            .take(parameters)
            .map(|p| format!("{}={:.4e}", p.name, p.value))
            .collect();
        if self.parameters.len() > parameters {
            shown.push(format!("(+{})", self.parameters.len() - parameters));
        }
        let monitoring = self.monitoring.as_deref().unwrap_or("off");
        format!(
            "{}  {update}  {}  monitoring: {monitoring}  health: {}",
            self.name,
            shown.join(" "),
            self.health
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_span_is_summarised_from_its_latest_messages() {
        let span = SpanStatus {
            name: "span-a".into(),
            alive: true,
            answered: vec!["updating".into(), "monitoring".into(), "health".into()],
            updating: Some(json!({"time": "2026-11-23T10:00:00Z", "converged": true,
                "parameters": [{"name": "east.k1", "value": 4.0e8}, {"name": "east.k2", "value": 2.5e8}]})),
            monitoring: Some(json!({"state": "alarm"})),
            health: Some(json!({"update_failures": 2, "queue_drops": 0, "rejected": {"malformed": 3}})),
        };
        let s = span.summary();
        let names: Vec<_> = s.parameters.iter().map(|p| (p.name.as_str(), p.value)).collect();
        assert_eq!(names, [("east.k1", 4.0e8), ("east.k2", 2.5e8)]);
        assert_eq!(s.monitoring.as_deref(), Some("alarm"));
        assert_eq!(s.health, "update_failures 2, rejected 3");
        assert_eq!(
            s.line(1),
            "span-a  updated 2026-11-23T10:00:00Z  east.k1=4.0000e8 (+1)  monitoring: alarm  health: update_failures 2, rejected 3"
        );
        let quiet = SpanStatus {
            name: "span-b".into(),
            answered: vec!["updating".into()],
            ..SpanStatus::default()
        };
        assert_eq!(
            quiet.summary().line(3),
            "span-b  no update yet    monitoring: off  health: no report yet"
        );
        let silent = SpanStatus {
            name: "span-c".into(),
            alive: true,
            ..SpanStatus::default()
        };
        assert_eq!(silent.summary().line(3), "span-c  no reply");
        let absent = SpanStatus {
            name: "span-d".into(),
            ..SpanStatus::default()
        };
        assert_eq!(absent.summary().reachability, "not running");
    }

    #[test]
    fn span_names_come_from_the_reply_keys() {
        assert_eq!(span_name("bridge/sinello-span2/updating/latest"), Some("sinello-span2"));
        assert_eq!(span_name("other/x/updating/latest"), None);
    }
}
