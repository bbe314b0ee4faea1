//! The report of one event: its verdict, shaking, features against the
//! amplitude of every event with this event's band, the forecast against
//! the measurement per channel, the parameters, the identified modes.

use super::figures::{self, Mark, Marked};
use super::html::{self, escape, number};
use super::words::{self, describe, feature_value};
use super::{header, provenance_section, Report, Settings};
use crate::config::EventAmplitude;
use crate::io::results_file::{EventSummary, FeatureBandLine, ResultsContents, Verdict};
use std::fmt::Write;

pub(super) fn render(contents: &ResultsContents, index: usize, settings: &Settings) -> Report {
    let e = &contents.events[index];
    let (verdict, priority) = words::event_verdict(e, settings.min_events);
    let title = format!("Earthquake report: {}", e.event);
    let subtitle = match &e.start {
        Some(t) => format!("Recorded {t} · event {} of the chain", e.number + 1),
        None => format!("Event {} of the chain", e.number + 1),
    };
    let mut body = header(contents, &title, &subtitle, &verdict, priority);
    body.push_str(&shaking(e));
    body.push_str(&features(contents, index, settings.amplitude));
    body.push_str(&forecast(e));
    body.push_str(&parameters(e));
    body.push_str(&modes(e));
    body.push_str(&skipped(contents, e));
    body.push_str(&provenance_section(contents));
    Report {
        bridge: super::bridge(contents),
        html: html::page(&title, &body),
        verdict,
        priority,
        title,
    }
}

fn shaking(e: &EventSummary) -> String {
    let rows = vec![
        vec!["Ground's peak acceleration".into(), unit(e.pga_ground, "m/s²")],
        vec!["Deck's peak acceleration".into(), unit(e.peak_deck, "m/s²")],
        vec!["Deck's RMS over the strong motion".into(), unit(e.rms_deck, "m/s²")],
        vec!["Modes identified".into(), e.modes.len().to_string()],
    ];
    html::section(
        "shaking",
        "The shaking",
        &html::table(
            "shaking-table",
            "What the bridge's sensors recorded",
            &["", "value"],
            &rows,
        ),
    )
}

fn unit(v: Option<f64>, unit: &str) -> String {
    match v {
        Some(v) if v.is_finite() => format!("{} {unit} ({} g)", number(Some(v), 3), number(Some(v / 9.80665), 2)),
        _ => "—".into(),
    }
}

fn amplitude_of(e: &EventSummary, kind: EventAmplitude) -> Option<f64> {
    match kind {
        EventAmplitude::PgaGround => e.pga_ground,
        EventAmplitude::RmsDeck => e.rms_deck,
    }
}

/// One figure per judged feature: every event's value against its
/// amplitude, this event's band; then the table of bands.
fn features(contents: &ResultsContents, index: usize, kind: EventAmplitude) -> String {
    let Some(verdict) = &contents.events[index].verdict else {
        return String::new();
    };
    let mut out = String::from("<div class=\"figures\">");
    for band in &verdict.bands {
        out.push_str(&feature_figure(contents, index, band, kind));
    }
    out.push_str("</div>");
    out.push_str(&bands_table(verdict));
    html::section("features", "This event against the bridge's history", &out)
}

fn feature_figure(contents: &ResultsContents, index: usize, band: &FeatureBandLine, kind: EventAmplitude) -> String {
    let e = &contents.events[index];
    let feature = &band.feature;
    let mut points: Vec<Marked> = contents
        .events
        .iter()
        .enumerate()
        .filter_map(|(k, other)| {
            let x = amplitude_of(other, kind)?;
            let v = other.verdict.as_ref()?;
            let y = v.bands.iter().find(|b| &b.feature == feature)?.value?;
            let alarmed = v.state == "alarm";
            Some(Marked {
                x,
                y: feature_value(feature, y),
                bar: None,
                mark: if k == index {
                    Mark::This { alarmed }
                } else if alarmed {
                    Mark::Alarmed
                } else {
                    Mark::Other
                },
            })
        })
        .collect();
    if let (Some(x), Some(b)) = (amplitude_of(e, kind), band.band) {
        points.push(Marked {
            x,
            y: feature_value(feature, b.predicted),
            bar: Some((feature_value(feature, b.lower), feature_value(feature, b.upper))),
            mark: Mark::Band,
        });
    }
    // The updated model's dominant mode beside the identified frequencies.
    let with_model = feature == "mode1_hz";
    if with_model {
        points.extend(contents.events.iter().filter_map(|other| {
            Some(Marked {
                x: amplitude_of(other, kind)?,
                y: other.update.as_ref()?.model_mode_hz?,
                bar: None,
                mark: Mark::Model,
            })
        }));
    }
    let x_label = match kind {
        EventAmplitude::PgaGround => "ground's peak acceleration (m/s²)",
        EventAmplitude::RmsDeck => "deck's strong-motion RMS (m/s²)",
    };
    let svg = figures::scatter(
        &points,
        x_label,
        &y_label(feature),
        words::feature_is_logarithmic(feature),
    );
    let status = match (band.value, band.band) {
        (None, _) => " This event gave no value.".to_string(),
        (Some(_), None) => " No band yet.".to_string(),
        (Some(v), Some(b)) if b.lower <= v && v <= b.upper => format!(" Within its band ({} events).", b.events),
        (Some(_), Some(b)) => format!(" OUTSIDE its band ({} events).", b.events),
    };
    let caption = format!(
        "{}: every event (grey; red: alarmed), this event (large dot), the band the earlier events predict at its shaking (black bar, diamond){}.{status}",
        describe(feature),
        if with_model {
            ", the updated model's dominant mode (squares)"
        } else {
            ""
        }
    );
    html::figure(&format!("feature-{feature}"), &svg, &caption)
}

fn bands_table(verdict: &Verdict) -> String {
    let rows: Vec<Vec<String>> = verdict
        .bands
        .iter()
        .map(|b| {
            let outside = verdict.outside.contains(&b.feature);
            let value = number(b.value.map(|v| feature_value(&b.feature, v)), 4);
            vec![
                escape(&describe(&b.feature)),
                if outside {
                    format!("<span class=\"out\">{value}</span>")
                } else {
                    value
                },
                b.band
                    .map(|r| {
                        format!(
                            "{} – {}",
                            number(Some(feature_value(&b.feature, r.lower)), 4),
                            number(Some(feature_value(&b.feature, r.upper)), 4)
                        )
                    })
                    .unwrap_or_else(|| "—".into()),
                b.band.map(|r| r.events.to_string()).unwrap_or_else(|| "—".into()),
            ]
        })
        .collect();
    html::table(
        "bands-table",
        "Each feature judged: this event's value, the band the earlier events predict at this shaking, and how many events it rests on (red: outside)",
        &["feature", "value", "band", "events"],
        &rows,
    )
}

fn y_label(feature: &str) -> String {
    if feature.ends_with("_hz") {
        "frequency (Hz)".into()
    } else if feature.contains(".k") {
        "stiffness (SI)".into()
    } else if feature.contains("damping") {
        "damping ratio".into()
    } else {
        feature.trim_start_matches("log10_").into()
    }
}

fn forecast(e: &EventSummary) -> String {
    let Some(f) = &e.forecast else {
        return html::section(
            "forecast",
            "The model's forecast against the measurement",
            "<p>No forecast: the first event of a chain has no earlier model to forecast with.</p>",
        );
    };
    let cared = |sensor: &str| e.forecast_channels.is_empty() || e.forecast_channels.iter().any(|c| c == sensor);
    let baseline = |sensor: &str| f.baseline.iter().find(|b| b.sensor == sensor);
    let names: Vec<String> = f.channels.iter().map(|c| c.sensor.clone()).collect();
    let forecast: Vec<f64> = f.channels.iter().map(|c| c.nrmse_strong).collect();
    let base: Vec<f64> = f
        .channels
        .iter()
        .map(|c| baseline(&c.sensor).map_or(f64::NAN, |b| b.nrmse_strong))
        .collect();
    let svg = figures::paired_bars(&names, &forecast, &base, "error over the strong motion (NRMSE)");
    let mut body = html::figure(
        "forecast-figure",
        &svg,
        "Per deck channel, the error of the model's forecast (blue) and of \"deck = nearest ground\" (grey), normalised by the measured RMS over the strong motion: lower is better, 1 is no better than predicting zero.",
    );
    let rows: Vec<Vec<String>> = f
        .channels
        .iter()
        .map(|c| {
            let b = baseline(&c.sensor);
            let better = b.is_some_and(|b| c.nrmse_strong < b.nrmse_strong);
            vec![
                format!("{}{}", escape(&c.sensor), if cared(&c.sensor) { " ★" } else { "" }),
                number(Some(c.nrmse_strong), 2),
                number(b.map(|b| b.nrmse_strong), 2),
                if better { "forecast".into() } else { "baseline".into() },
                number(c.correlation, 2),
                number(c.peak_ratio, 2),
            ]
        })
        .collect();
    body.push_str(&html::table(
        "forecast-table",
        "★: the channels the verdict's headline is taken over. Peak ratio: forecast peak / measured peak.",
        &[
            "channel",
            "forecast NRMSE",
            "baseline NRMSE",
            "better",
            "correlation",
            "peak ratio",
        ],
        &rows,
    ));
    html::section("forecast", "The model's forecast against the measurement", &body)
}

fn parameters(e: &EventSummary) -> String {
    if e.parameters.is_empty() {
        return String::new();
    }
    let rows: Vec<Vec<String>> = e
        .parameters
        .iter()
        .map(|p| {
            vec![
                escape(&describe(&p.name)),
                format!("<code>{}</code>", escape(&p.name)),
                number(Some(p.value), 4),
                number(p.std, 2),
                format!("{} – {}", number(Some(p.lower), 2), number(Some(p.upper), 2)),
            ]
        })
        .collect();
    let mut body = html::table(
        "parameters-table",
        "The model updated on this event: each parameter with its standard deviation and its bounds",
        &["parameter", "name", "value", "std", "bounds"],
        &rows,
    );
    if let Some(u) = &e.update {
        let _ = write!(
            body,
            "<p>Update: relative residual {}, {} iterations, {}{}; model's dominant mode {} Hz.</p>",
            number(Some(u.relative_residual), 2),
            u.iterations,
            if u.converged { "converged" } else { "not converged" },
            if u.stop_reason.is_empty() {
                String::new()
            } else {
                format!(" ({})", escape(&u.stop_reason))
            },
            number(u.model_mode_hz, 3)
        );
    }
    html::section("parameters", "The updated model", &body)
}

fn modes(e: &EventSummary) -> String {
    let rows: Vec<Vec<String>> = e
        .modes
        .iter()
        .enumerate()
        .map(|(k, m)| {
            vec![
                (k + 1).to_string(),
                number(Some(m.frequency_hz), 4),
                number(m.frequency_std_hz, 2),
                number(Some(m.damping_ratio * 100.0), 2),
                number(m.damping_std.map(|s| s * 100.0), 2),
            ]
        })
        .collect();
    let body = if rows.is_empty() {
        "<p>No mode was identified in this record.</p>".to_string()
    } else {
        html::table(
            "modes-table",
            "Input–output identification (SRIM) of this record, with standard deviations",
            &["mode", "frequency (Hz)", "std (Hz)", "damping (%)", "std (%)"],
            &rows,
        )
    };
    html::section("modes", "Modes identified in the record", &body)
}

fn skipped(contents: &ResultsContents, e: &EventSummary) -> String {
    let mut items: Vec<String> = e.notes.iter().map(|n| escape(n)).collect();
    if let Some(reason) = &e.skipped {
        items.insert(0, format!("This event: {}", escape(reason)));
    }
    for other in contents.events.iter().filter(|o| o.skipped.is_some()) {
        if other.event != e.event {
            items.push(format!(
                "{} ({}): {}",
                escape(&other.event),
                escape(other.start.as_deref().unwrap_or("no start")),
                escape(other.skipped.as_deref().unwrap_or_default())
            ));
        }
    }
    let body = if items.is_empty() {
        "<p>Nothing was skipped.</p>".to_string()
    } else {
        format!(
            "<ul>{}</ul>",
            items.iter().map(|i| format!("<li>{i}</li>")).collect::<String>()
        )
    };
    html::section("skipped", "What was skipped and why", &body)
}
