//! An event's line as results messages, a status message and Rerun series,
//! sent by one emitter to the command's or the daemon's outputs.

use super::*;
use crate::io::results_topics::{EVENT_SUMMARY, EVENT_VERDICT};

/// Where an event goes: the results (file, and zenoh from the daemon), the
/// owner's notifier, the Rerun timeline, and the reader's line (the
/// command's table row or JSON line, the daemon's log). [`emit`] sends
/// every event to them in one order, from `events` and the daemon alike.
pub trait EventSink {
    /// A results message on `topic` (under the results prefix) at `time_ns`.
    fn message(&mut self, topic: &'static str, time_ns: i128, json: Vec<u8>) -> Result<()>;
    /// The owner's status message of a judged event (`[monitoring.notify]`).
    fn status(&mut self, status: &StatusMessage, json: &[u8]) -> Result<()>;
    /// The event on the Rerun timeline, its amplitude measured as `kind`.
    fn rerun(&mut self, line: &EventLine, kind: EventAmplitude) -> Result<()>;
    /// The event's line for the reader.
    fn line(&mut self, line: &EventLine) -> Result<()>;
}

/// Sends `line` to `sink`: its results messages, its status message when
/// judged, its Rerun point, then its line.
pub fn emit(line: &EventLine, kind: EventAmplitude, sink: &mut impl EventSink) -> Result<()> {
    let (time, bodies) = messages(line)?;
    for (topic, json) in bodies {
        sink.message(topic, time, json)?;
    }
    if let Some(v) = &line.verdict {
        let status = status_message(line, v);
        sink.status(&status, &serde_json::to_vec(&status)?)?;
    }
    sink.rerun(line, kind)?;
    sink.line(line)
}

/// An event's results: the time they are filed at and each topic suffix
/// with its JSON body.
pub type EventMessages = (i128, Vec<(&'static str, Vec<u8>)>);

/// `<prefix>/events/summary` (the `--json` line) and, when judged,
/// `<prefix>/events/verdict`, at the event's start.
pub fn messages(line: &EventLine) -> Result<EventMessages> {
    let time = line
        .start
        .as_deref()
        .and_then(crate::io::wire::parse_timestamp)
        .unwrap_or(0);
    let mut out = vec![(EVENT_SUMMARY, serde_json::to_vec(line)?)];
    if let Some(v) = &line.verdict {
        out.push((EVENT_VERDICT, serde_json::to_vec(v)?));
    }
    Ok((time, out))
}

/// The owner's status message of a judged event (`[monitoring.notify]`),
/// numbered by the event's place in its chain.
pub fn status_message(line: &EventLine, v: &VerdictLine) -> StatusMessage {
    StatusMessage {
        window: line.number,
        time: line.start.clone().unwrap_or_default(),
        state: if v.state == "alarm" {
            "alarm".into()
        } else {
            v.state.replace(' ', "_")
        },
        t2: None,
        t2_limit: None,
        mewma: None,
        mewma_limit: None,
        temperature_c: None,
        residuals: Vec::new(),
        temperatures: Default::default(),
        features: v
            .bands
            .iter()
            .map(|b| NamedValue {
                name: b.feature.clone(),
                value: b.value.unwrap_or(f64::NAN),
            })
            .collect(),
        flags: v.outside.iter().map(|f| format!("outside band: {f}")).collect(),
        exceedances: v.outside.len(),
        scored_by: Some("amplitude_band".into()),
    }
}

/// The median over the line's `forecast_channels` (every scored deck
/// channel when it names none) of the forecast's and the baseline's
/// strong-motion NRMSE.
pub fn forecast_medians(line: &EventLine) -> Option<(f64, f64)> {
    let median = |mut v: Vec<f64>| -> f64 {
        v.retain(|x| x.is_finite());
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    let counted = |sensor: &String| line.forecast_channels.is_empty() || line.forecast_channels.contains(sensor);
    line.forecast.as_ref().map(|f| {
        (
            median(
                f.channels
                    .iter()
                    .filter(|c| counted(&c.sensor))
                    .map(|c| c.nrmse_strong)
                    .collect(),
            ),
            median(
                f.baseline
                    .iter()
                    .filter(|c| counted(&c.score.sensor))
                    .map(|c| c.score.nrmse_strong)
                    .collect(),
            ),
        )
    })
}

pub fn log_rerun(
    r: &mut (impl crate::outputs::rerun::events::EventLog + ?Sized),
    line: &EventLine,
    kind: EventAmplitude,
) -> Result<()> {
    let (Some(start), Some(pga), Some(peak)) = (line.start.as_deref(), line.pga_ground, line.peak_deck) else {
        return Ok(());
    };
    let Some(time_ns) = crate::io::wire::parse_timestamp(start) else {
        return Ok(());
    };
    let identified: Vec<f64> = line.modes.iter().map(|m| m.frequency_hz).collect();
    r.log_event(&crate::outputs::rerun::events::EventPoint {
        time_ns,
        pga_ground: pga,
        peak_deck: peak,
        rms_deck: line.rms_deck,
        amplitude: line.amplitude(kind).unwrap_or(pga),
        parameters: &line.parameters,
        identified_hz: &identified,
        model_mode_hz: line.update.as_ref().and_then(|u| u.model_mode_hz),
        forecast: forecast_medians(line),
        verdict: line.verdict.as_ref().map(|v| v.state.as_str()),
    })
}
