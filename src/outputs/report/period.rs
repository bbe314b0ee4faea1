//! The report of a period: the monitoring state over it, each updated
//! parameter's trend with its ±2σ band, the alarms marked, the events in
//! it, and the health of the data.

use super::figures::{self, Series};
use super::html::{self, escape, number};
use super::words::{self, describe, Priority};
use super::{header, provenance_section, time_of, Report, ReportError};
use crate::io::monitoring_json::{AlarmMessage, StatusMessage};
use crate::io::results_file::{EventSummary, ResultsContents, UpdateSummary};
use crate::io::wire::format_timestamp;
use splinewatch_core::updating::ParameterEstimate;
use std::collections::BTreeMap;
use std::fmt::Write;

const HOUR_NS: f64 = 3600e9;

/// What a period holds: its messages and its clock.
struct Period<'a> {
    statuses: Vec<&'a StatusMessage>,
    updates: Vec<&'a UpdateSummary>,
    alarms: Vec<&'a AlarmMessage>,
    events: Vec<&'a EventSummary>,
    t0: i128,
    t1: i128,
    clock: Clock,
}

impl<'a> Period<'a> {
    /// The messages timed inside `[from, to]`; `None` when there is none.
    fn select(contents: &'a ResultsContents, from: Option<i128>, to: Option<i128>) -> Option<Self> {
        let inside = |t: Option<i128>| t.is_some_and(|t| from.is_none_or(|f| t >= f) && to.is_none_or(|e| t <= e));
        let statuses: Vec<&StatusMessage> = contents
            .statuses
            .iter()
            .filter(|s| inside(time_of(Some(&s.time))))
            .collect();
        let updates: Vec<&UpdateSummary> = contents
            .updates
            .iter()
            .filter(|u| inside(time_of(Some(&u.time))))
            .collect();
        let alarms: Vec<_> = contents
            .alarms
            .iter()
            .filter(|a| inside(time_of(Some(&a.time))))
            .collect();
        let events: Vec<_> = contents
            .events
            .iter()
            .filter(|e| inside(time_of(e.start.as_deref())))
            .collect();
        let times: Vec<i128> = statuses
            .iter()
            .map(|s| time_of(Some(&s.time)))
            .chain(updates.iter().map(|u| time_of(Some(&u.time))))
            .chain(events.iter().map(|e| time_of(e.start.as_deref())))
            .flatten()
            .collect();
        let (&t0, &t1) = (times.iter().min()?, times.iter().max()?);
        Some(Self {
            statuses,
            updates,
            alarms,
            events,
            t0,
            t1,
            clock: Clock::new(t0, t1),
        })
    }

    /// The monitoring state's figures and table, then every parameter's
    /// trend (the updates', or where there are none the events'), alarmed
    /// windows and alarmed events shaded.
    fn figures(&self) -> String {
        let clock = &self.clock;
        let mut spans = alarmed_spans(&self.statuses, clock);
        let mut out = state_section(&self.statuses, &spans, clock);
        let estimates: Vec<(i128, &[ParameterEstimate])> = if self.updates.is_empty() {
            self.events
                .iter()
                .filter_map(|e| Some((time_of(e.start.as_deref())?, &e.parameters[..])))
                .collect()
        } else {
            self.updates
                .iter()
                .filter_map(|u| Some((time_of(Some(&u.time))?, &u.parameters[..])))
                .collect()
        };
        spans.extend(
            self.events
                .iter()
                .filter(|e| e.verdict.as_ref().is_some_and(|v| v.state == "alarm"))
                .filter_map(|e| time_of(e.start.as_deref()))
                .map(|t| (clock.x(t) - 0.005 * clock.span(), clock.x(t) + 0.005 * clock.span())),
        );
        out.push_str(&trends(&estimates, &spans, clock));
        out
    }
}

pub(super) fn render(contents: &ResultsContents, from: Option<i128>, to: Option<i128>) -> Result<Report, ReportError> {
    let Some(period) = Period::select(contents, from, to) else {
        return Err(empty(contents, from, to));
    };
    let (verdict, priority) = period_verdict(&period.statuses, &period.alarms, &period.events, period.updates.len());
    let title = format!("Monitoring report: {} to {}", day(period.t0), day(period.t1));
    let subtitle = format!(
        "{} updates, {} scored, {} alarm changes, {} events",
        period.updates.len(),
        period.statuses.iter().filter(|s| s.state != "training").count(),
        period.alarms.len(),
        period.events.len()
    );
    let mut body = header(contents, &title, &subtitle, &verdict, priority);
    body.push_str(&period.figures());
    body.push_str(&alarms_section(&period.alarms));
    body.push_str(&events_section(&period.events));
    body.push_str(&health(contents, from, to));
    body.push_str(&provenance_section(contents));
    Ok(Report {
        bridge: super::bridge(contents),
        html: html::page(&title, &body),
        verdict,
        priority,
        title,
    })
}

/// The figures of the last `days` before the latest message (the status
/// page's): the monitoring state and every parameter's trend; `None` before
/// anything was written.
pub fn recent_figures(contents: &ResultsContents, days: f64) -> Option<String> {
    let latest = Period::select(contents, None, None)?.t1;
    let from = latest - (days * 24.0 * HOUR_NS) as i128;
    Some(Period::select(contents, Some(from), None)?.figures())
}

fn day(t: i128) -> String {
    format_timestamp(t)
}

fn empty(contents: &ResultsContents, from: Option<i128>, to: Option<i128>) -> ReportError {
    let all: Vec<i128> = contents
        .statuses
        .iter()
        .map(|s| time_of(Some(&s.time)))
        .chain(contents.updates.iter().map(|u| time_of(Some(&u.time))))
        .chain(contents.events.iter().map(|e| time_of(e.start.as_deref())))
        .flatten()
        .collect();
    let span = match (all.iter().min(), all.iter().max()) {
        (Some(&a), Some(&b)) => format!("{} to {}", format_timestamp(a), format_timestamp(b)),
        _ => "no timed message".into(),
    };
    ReportError::EmptyPeriod {
        bridge: contents.prefix.clone(),
        from: from.map_or("the start".into(), format_timestamp),
        to: to.map_or("the end".into(), format_timestamp),
        span,
    }
}

/// The period's verdict in words and its priority: the monitoring state
/// where there is one, then the events'.
fn period_verdict(
    statuses: &[&StatusMessage],
    alarms: &[&AlarmMessage],
    events: &[&EventSummary],
    updates: usize,
) -> (String, Priority) {
    if let Some(verdict) = monitoring_verdict(statuses, alarms) {
        return verdict;
    }
    let alarmed_events: Vec<String> = events
        .iter()
        .filter(|e| e.verdict.as_ref().is_some_and(|v| v.state == "alarm"))
        .map(|e| e.event.clone())
        .collect();
    if !alarmed_events.is_empty() {
        return (
            format!("Alarm on {}.", words::join_words(&alarmed_events)),
            Priority::High,
        );
    }
    let judged = events
        .iter()
        .filter(|e| e.verdict.as_ref().is_some_and(|v| v.state == "normal"))
        .count();
    if statuses.is_empty() && judged == 0 {
        return (
            format!(
                "{updates} updates and {} events, none scored against a reference (the config has no [monitoring] and no judged event).",
                events.len()
            ),
            Priority::NotJudged,
        );
    }
    let mut parts = Vec::new();
    if !statuses.is_empty() {
        parts.push(format!(
            "{} updates scored within their limits",
            statuses.iter().filter(|s| s.state == "normal").count()
        ));
    }
    if !events.is_empty() {
        parts.push(format!(
            "{judged} of {} events judged and within their bands (the others not judged)",
            events.len()
        ));
    }
    (
        format!("No alarm over the period: {}.", words::join_words(&parts)),
        Priority::Low,
    )
}

/// The verdict of the monitoring statuses, unless it is "normal" or there
/// are none.
fn monitoring_verdict(statuses: &[&StatusMessage], alarms: &[&AlarmMessage]) -> Option<(String, Priority)> {
    let last = statuses.last()?;
    let raises: Vec<&&AlarmMessage> = alarms.iter().filter(|a| a.state == "alarm").collect();
    // The features beyond 3σ (at least the largest).
    let names = |a: &AlarmMessage| {
        words::join_words(
            &a.largest_residuals
                .iter()
                .enumerate()
                .filter(|(k, r)| *k == 0 || r.standardised.abs() >= 3.0)
                .map(|(_, r)| describe(&r.name))
                .collect::<Vec<_>>(),
        )
    };
    match last.state.as_str() {
        "alarm" => {
            let since = raises.last().map_or("before the period".into(), |a| a.time.clone());
            let what = raises.last().map(|a| names(a)).unwrap_or_default();
            Some((
                format!(
                    "In alarm since {since}: {} moved beyond what the reference allows at the measured temperature.",
                    if what.is_empty() { "the updated parameters".into() } else { what }
                ),
                Priority::High,
            ))
        }
        _ if !raises.is_empty() => Some((
            format!(
                "{} alarm(s) raised in the period (first at {}: {}), none active at its end ({}).",
                raises.len(),
                raises[0].time,
                names(raises[0]),
                last.state.replace('_', " ")
            ),
            Priority::Medium,
        )),
        "outside_training_range" => Some((
            "No alarm; the last updates are outside the temperature range the reference was trained on, so they were not scored. Review when the range widens.".into(),
            Priority::Medium,
        )),
        "training" => Some((
            format!(
                "The reference is still being trained ({} updates so far): nothing is scored yet.",
                statuses.len()
            ),
            Priority::NotJudged,
        )),
        _ => None,
    }
}

/// Minutes, hours or days from the period's start, whichever reads best.
struct Clock {
    t0: i128,
    t1_x: f64,
    unit_ns: f64,
    unit: &'static str,
}

impl Clock {
    fn new(t0: i128, t1: i128) -> Self {
        let span = (t1 - t0) as f64;
        let (unit_ns, unit) = if span > 72.0 * HOUR_NS {
            (24.0 * HOUR_NS, "days")
        } else if span > 3.0 * HOUR_NS {
            (HOUR_NS, "hours")
        } else {
            (HOUR_NS / 60.0, "minutes")
        };
        Self {
            t0,
            unit_ns,
            unit,
            t1_x: span / unit_ns,
        }
    }

    /// The period's length in the clock's unit (at least one).
    fn span(&self) -> f64 {
        self.t1_x.max(1.0)
    }

    fn x(&self, t: i128) -> f64 {
        (t - self.t0) as f64 / self.unit_ns
    }

    fn label(&self) -> String {
        format!("{} since {}", self.unit, format_timestamp(self.t0))
    }
}

/// Runs of alarmed statuses as x spans (to the next status).
fn alarmed_spans(statuses: &[&StatusMessage], clock: &Clock) -> Vec<(f64, f64)> {
    let xs: Vec<Option<f64>> = statuses
        .iter()
        .map(|s| time_of(Some(&s.time)).map(|t| clock.x(t)))
        .collect();
    let step = xs
        .windows(2)
        .filter_map(|w| Some(w[1]? - w[0]?))
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    let step = if step.is_finite() { step } else { 1.0 };
    let mut spans: Vec<(f64, f64)> = Vec::new();
    for (k, s) in statuses.iter().enumerate() {
        let Some(x) = xs[k] else { continue };
        if s.state != "alarm" {
            continue;
        }
        let end = xs.get(k + 1).copied().flatten().unwrap_or(x + step);
        match spans.last_mut() {
            Some(last) if (last.1 - x).abs() < 1e-9 => last.1 = end,
            _ => spans.push((x, end)),
        }
    }
    spans
}

fn state_section(statuses: &[&StatusMessage], spans: &[(f64, f64)], clock: &Clock) -> String {
    if statuses.is_empty() {
        return String::new();
    }
    let mut out = String::from("<div class=\"figures\">");
    for (name, value, limit) in [
        (
            "T²",
            (|s: &StatusMessage| s.t2) as fn(&StatusMessage) -> Option<f64>,
            (|s: &StatusMessage| s.t2_limit) as fn(&StatusMessage) -> Option<f64>,
        ),
        ("MEWMA", |s: &StatusMessage| s.mewma, |s: &StatusMessage| s.mewma_limit),
    ] {
        let at = |f: fn(&StatusMessage) -> Option<f64>| -> Vec<(f64, f64)> {
            statuses
                .iter()
                .filter_map(|s| Some((clock.x(time_of(Some(&s.time))?), f(s)?)))
                .collect()
        };
        let points = at(value);
        if points.is_empty() {
            continue;
        }
        let limits = at(limit);
        let svg = figures::over_time(
            &Series {
                points: &points,
                band: None,
                limit: Some(&limits),
                alarmed: spans,
                log_y: true,
            },
            &clock.label(),
            &format!("{name} statistic"),
        );
        out.push_str(&html::figure(
            &format!("state-{}", if name == "T²" { "t2" } else { "mewma" }),
            &svg,
            &format!(
                "The {name} statistic of each scored update (blue) against its limit (red dashes); shaded: in alarm."
            ),
        ));
    }
    out.push_str("</div>");
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    for s in statuses {
        *counts.entry(s.state.as_str()).or_default() += 1;
    }
    let rows: Vec<Vec<String>> = counts
        .iter()
        .map(|(state, n)| vec![escape(&state.replace('_', " ")), n.to_string()])
        .collect();
    out.push_str(&html::table(
        "states-table",
        "Updates per monitoring state",
        &["state", "updates"],
        &rows,
    ));
    html::section("state", "The monitoring state", &out)
}

fn trends(estimates: &[(i128, &[ParameterEstimate])], spans: &[(f64, f64)], clock: &Clock) -> String {
    let mut names: Vec<&str> = Vec::new();
    for (_, parameters) in estimates {
        for p in *parameters {
            if !names.contains(&p.name.as_str()) {
                names.push(&p.name);
            }
        }
    }
    if names.is_empty() {
        return String::new();
    }
    let mut out = String::from("<div class=\"figures\">");
    for name in names {
        let mut points = Vec::new();
        let mut band = Vec::new();
        for (t, parameters) in estimates {
            let Some(p) = parameters.iter().find(|p| p.name == name) else {
                continue;
            };
            let x = clock.x(*t);
            points.push((x, p.value));
            if let Some(s) = p.std {
                band.push((x, p.value - 2.0 * s, p.value + 2.0 * s));
            }
        }
        let svg = figures::over_time(
            &Series {
                points: &points,
                band: (band.len() == points.len()).then_some(&band[..]),
                limit: None,
                alarmed: spans,
                log_y: false,
            },
            &clock.label(),
            name,
        );
        out.push_str(&html::figure(
            &format!("trend-{name}"),
            &svg,
            &format!(
                "{} ({name}): each estimate (blue) with ±2σ (band); shaded: in alarm.",
                describe(name)
            ),
        ));
    }
    out.push_str("</div>");
    html::section("trends", "The updated parameters over the period", &out)
}

fn alarms_section(alarms: &[&AlarmMessage]) -> String {
    if alarms.is_empty() {
        return html::section(
            "alarms",
            "Alarms",
            "<p>No alarm was raised or cleared in the period.</p>",
        );
    }
    let rows: Vec<Vec<String>> = alarms
        .iter()
        .map(|a| {
            vec![
                escape(&a.time),
                a.window.to_string(),
                format!(
                    "{} → {}",
                    escape(&a.previous.replace('_', " ")),
                    escape(&a.state.replace('_', " "))
                ),
                number(a.t2, 3),
                escape(&words::join_words(
                    &a.largest_residuals
                        .iter()
                        .take(3)
                        .map(|r| format!("{} ({:+.1}σ)", r.name, r.standardised))
                        .collect::<Vec<_>>(),
                )),
            ]
        })
        .collect();
    html::section(
        "alarms",
        "Alarms",
        &html::table(
            "alarms-table",
            "Each change into or out of alarm, with the features that moved most (standardised residuals)",
            &["time", "window", "change", "T²", "largest residuals"],
            &rows,
        ),
    )
}

fn events_section(events: &[&EventSummary]) -> String {
    if events.is_empty() {
        return String::new();
    }
    let rows: Vec<Vec<String>> = events
        .iter()
        .map(|e| {
            let (verdict, priority) = words::event_verdict(e, None);
            vec![
                escape(&e.event),
                escape(e.start.as_deref().unwrap_or("—")),
                number(e.pga_ground, 3),
                escape(priority.label()),
                escape(&verdict),
            ]
        })
        .collect();
    html::section(
        "events",
        "Earthquakes in the period",
        &html::table(
            "events-table",
            "Each event with its verdict (`splinewatch report --event NAME` gives its own report)",
            &["event", "start", "ground peak (m/s²)", "priority", "verdict"],
            &rows,
        ),
    )
}

fn health(contents: &ResultsContents, from: Option<i128>, to: Option<i128>) -> String {
    let mut body = String::new();
    if let Some(h) = &contents.health {
        let count = |k: &str| h.get(k).and_then(|v| v.as_u64()).map_or("—".into(), |v| v.to_string());
        let skipped: u64 = h
            .get("windows_skipped")
            .and_then(|v| v.as_object())
            .map_or(0, |o| o.values().filter_map(|v| v.as_u64()).sum());
        let rows = vec![
            vec!["blocks received".into(), count("blocks")],
            vec!["windows accepted".into(), count("windows_accepted")],
            vec!["windows skipped".into(), skipped.to_string()],
            vec!["updates run".into(), count("update_runs")],
            vec!["updates failed".into(), count("update_failures")],
            vec!["data gaps".into(), count("gaps")],
            vec!["queue drops".into(), count("queue_drops")],
        ];
        body.push_str(&html::table(
            "health-table",
            "Counts since the daemon or replay started, from the last health message of the results",
            &["", "count"],
            &rows,
        ));
    }
    let inside = |t: Option<i128>| t.is_none_or(|t| from.is_none_or(|f| t >= f) && to.is_none_or(|e| t <= e));
    let failures: Vec<String> = contents
        .failures
        .iter()
        .filter(|f| inside(time_of(Some(&f.time))))
        .map(|f| {
            format!(
                "<li>{} (window {}): {}</li>",
                escape(&f.time),
                f.window,
                escape(&f.error)
            )
        })
        .collect();
    if !failures.is_empty() {
        let _ = write!(
            body,
            "<p>Updates that failed or were skipped:</p><ul>{}</ul>",
            failures.concat()
        );
    }
    if body.is_empty() {
        return String::new();
    }
    html::section("health", "The data's health", &body)
}
