//! The fleet's page (`splinewatch fleet --report`): every span behind a
//! router with its last verdict, sorted by inspection priority, highest
//! first, so the duty officer reads the bridges to look at on top.

use super::html::{self, escape};
use super::words::Priority;
use super::Report;
use crate::io::named_value::NamedValue;
use std::fmt::Write;

/// What a span answered (its daemon's `latest` replies, summarised).
#[derive(Debug, Clone)]
pub struct FleetSpan {
    pub name: String,
    /// `answering`, `no reply` or `not running`.
    pub reachability: String,
    pub last_update: Option<String>,
    /// The monitoring state; none without `[monitoring]`.
    pub monitoring: Option<String>,
    /// `ok` or the health counters that are not zero.
    pub health: String,
    pub parameters: Vec<NamedValue>,
}

impl FleetSpan {
    /// The span's priority and why.
    pub fn priority(&self) -> (Priority, String) {
        if self.reachability != "answering" {
            return (Priority::Medium, format!("did not answer ({})", self.reachability));
        }
        let (priority, why) = match self.monitoring.as_deref() {
            Some("alarm") => (Priority::High, "in alarm".to_string()),
            Some("outside_training_range") => (
                Priority::Medium,
                "outside the temperature range its reference was trained on".into(),
            ),
            Some("normal") => (Priority::Low, "normal".into()),
            Some("training") => (Priority::NotJudged, "reference still in training".into()),
            Some(other) => (Priority::NotJudged, other.replace('_', " ")),
            None => (Priority::NotJudged, "no [monitoring]".into()),
        };
        if self.health != "ok" && priority > Priority::Medium {
            return (Priority::Medium, format!("{why}; health: {}", self.health));
        }
        (priority, why)
    }
}

/// The fleet's page as of `asked_at` (RFC 3339).
pub fn render(spans: &[FleetSpan], asked_at: &str) -> Report {
    let mut rated: Vec<(Priority, String, &FleetSpan)> = spans
        .iter()
        .map(|s| {
            let (p, why) = s.priority();
            (p, why, s)
        })
        .collect();
    rated.sort_by(|a, b| a.0.cmp(&b.0).then_with(|| a.2.name.cmp(&b.2.name)));
    let top = rated.first().map_or(Priority::NotJudged, |r| r.0);
    let count = |p: Priority| rated.iter().filter(|r| r.0 == p).count();
    let mut parts = Vec::new();
    for (p, words) in [
        (Priority::High, "to inspect"),
        (Priority::Medium, "to review"),
        (Priority::NotJudged, "not judged"),
        (Priority::Low, "with no change found"),
    ] {
        if count(p) > 0 {
            parts.push(format!("{} {words}", count(p)));
        }
    }
    let verdict = format!("{} spans: {}.", spans.len(), parts.join(", "));
    let rows: Vec<Vec<String>> = rated
        .iter()
        .map(|(p, why, s)| {
            vec![
                format!("<span class=\"badge {}\">{}</span>", p.class(), escape(p.label())),
                escape(&s.name),
                escape(why),
                escape(s.last_update.as_deref().unwrap_or("—")),
                escape(&s.health),
                escape(
                    &s.parameters
                        .iter()
                        .take(4)
                        .map(|p| format!("{} {}", p.name, html::number(Some(p.value), 4)))
                        .collect::<Vec<_>>()
                        .join(", "),
                ),
            ]
        })
        .collect();
    let title = "Fleet status".to_string();
    let mut body = format!(
        "<header><p class=\"subtitle\">as of {}</p><h1>{title}</h1></header>\
<div id=\"verdict\" class=\"{}\" role=\"status\"><span class=\"priority\">{}</span><p id=\"verdict-text\">{}</p></div>",
        escape(asked_at),
        top.class(),
        escape(top.label()),
        escape(&verdict)
    );
    let _ = write!(
        body,
        "{}",
        html::section(
            "spans",
            "Every span, highest priority first",
            &html::table(
                "spans-table",
                "Each span's daemon as it answered on bridge/<name>/{updating,monitoring,health}/latest",
                &["priority", "span", "why", "last update", "health", "parameters"],
                &rows,
            ),
        )
    );
    Report {
        bridge: "fleet".into(),
        html: html::page(&title, &body),
        verdict,
        priority: top,
        title,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn span(name: &str, reachability: &str, monitoring: Option<&str>, health: &str) -> FleetSpan {
        FleetSpan {
            name: name.into(),
            reachability: reachability.into(),
            last_update: None,
            monitoring: monitoring.map(str::to_string),
            health: health.into(),
            parameters: vec![NamedValue::new("east.k2", 2.4e8)],
        }
    }

    #[test]
    fn spans_are_sorted_by_priority_then_name() {
        let spans = [
            span("d-normal", "answering", Some("normal"), "ok"),
            span("c-silent", "no reply", None, "no report yet"),
            span("b-alarm", "answering", Some("alarm"), "ok"),
            span("a-failing", "answering", Some("normal"), "update_failures 3"),
            span("e-training", "answering", Some("training"), "ok"),
        ];
        let report = render(&spans, "2026-11-29T00:00:00Z");
        let order: Vec<usize> = ["b-alarm", "a-failing", "c-silent", "e-training", "d-normal"]
            .iter()
            .map(|n| report.html.find(&format!("<td>{n}</td>")).unwrap())
            .collect();
        assert!(order.windows(2).all(|w| w[0] < w[1]), "{order:?}");
        assert_eq!(report.priority, Priority::High);
        assert_eq!(
            report.verdict,
            "5 spans: 1 to inspect, 2 to review, 1 not judged, 1 with no change found."
        );
    }
}
