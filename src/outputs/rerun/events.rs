//! Earthquakes in the Rerun stream (`events --rerun-save`): one point per
//! event on the `measurement_time` timeline: the ground's and the deck's
//! peaks, the deck's strong-motion RMS, each updated parameter, the identified frequencies, the updated
//! model's dominant mode, the forecast's and the baseline's NRMSE and the
//! verdict (0 insufficient history, 1 normal, 3 alarm, as `monitoring/state`).
//! Without a model the same points go to a recording of their own
//! ([`EventTimeline`]).

use super::{rerun_error, saved_recording, set_measurement_time, RerunOutput};
use anyhow::{anyhow, Result};
use rerun::blueprint::{Blueprint, Horizontal, Spatial2DView, TimeSeriesView, Vertical};
use splinewatch_core::updating::ParameterEstimate;
use std::path::Path;

/// One event's figures.
pub struct EventPoint<'a> {
    pub time_ns: i128,
    pub pga_ground: f64,
    pub peak_deck: f64,
    pub rms_deck: Option<f64>,
    /// The event's amplitude as `[events] amplitude` measures it: the
    /// identified frequencies' abscissa.
    pub amplitude: f64,
    /// `(name, value)` of each updated parameter.
    pub parameters: &'a [ParameterEstimate],
    pub identified_hz: &'a [f64],
    pub model_mode_hz: Option<f64>,
    /// Median NRMSE of the forecast and of the baseline.
    pub forecast: Option<(f64, f64)>,
    pub verdict: Option<&'a str>,
}

/// Where `events` logs its points: the whole stream of a config with a
/// model ([`RerunOutput`]), or the events' timeline alone
/// ([`EventTimeline`]).
pub trait EventLog {
    /// Logs one event under `events/…`.
    fn log_event(&mut self, event: &EventPoint<'_>) -> Result<()>;
    /// Flushes and closes the recording (the `.rrd` gets its footer).
    fn close(self: Box<Self>) -> Result<()>;
}

impl EventLog for RerunOutput {
    fn log_event(&mut self, event: &EventPoint<'_>) -> Result<()> {
        self.rotate_if_due(event.time_ns)?;
        self.updates += 1;
        self.set_time(event.time_ns);
        log_points(&self.rec, event)
    }

    fn close(self: Box<Self>) -> Result<()> {
        self.finish()
    }
}

/// The events' timeline alone, for a config without a `[model]` (a
/// station's starter config): no deck and no model views, a layout of the
/// events' series and their frequencies against amplitude.
pub struct EventTimeline {
    rec: rerun::RecordingStream,
}

impl EventTimeline {
    /// A recording saved to `path`, with its layout.
    pub fn save(path: &Path) -> Result<Self> {
        let layout = Blueprint::new(Horizontal::new([
            Vertical::new([
                TimeSeriesView::new("Ground peak, deck peak and RMS (m/s²)")
                    .with_origin("/events")
                    .with_contents(["/events/pga_ground", "/events/peak_deck", "/events/rms_deck"])
                    .into(),
                TimeSeriesView::new("Forecast and baseline NRMSE")
                    .with_origin("/events/forecast")
                    .into(),
                TimeSeriesView::new("Verdict (0 insufficient history, 1 normal, 3 alarm)")
                    .with_origin("/events")
                    .with_contents(["/events/verdict"])
                    .into(),
            ])
            .into(),
            Spatial2DView::new("Identified frequency (Hz) against amplitude")
                .with_origin("/events/frequency/identified")
                .into(),
        ]));
        Ok(Self {
            rec: saved_recording(path, &layout)?,
        })
    }
}

impl EventLog for EventTimeline {
    fn log_event(&mut self, event: &EventPoint<'_>) -> Result<()> {
        set_measurement_time(&self.rec, event.time_ns);
        log_points(&self.rec, event)
    }

    fn close(self: Box<Self>) -> Result<()> {
        self.rec
            .flush_blocking()
            .map_err(|e| anyhow!("flushing the Rerun output: {e}"))
    }
}

/// One event's points on `rec`, at the time already set.
fn log_points(rec: &rerun::RecordingStream, event: &EventPoint<'_>) -> Result<()> {
    let scalar = |path: &str, v: f64| -> Result<()> { rec.log(path, &rerun::Scalars::new([v])).map_err(rerun_error) };
    scalar("events/pga_ground", event.pga_ground)?;
    scalar("events/peak_deck", event.peak_deck)?;
    if let Some(rms) = event.rms_deck {
        scalar("events/rms_deck", rms)?;
    }
    for p in event.parameters {
        scalar(&format!("events/parameters/{}", p.name), p.value)?;
    }
    if let Some(f) = event.model_mode_hz {
        scalar("events/frequency/model", f)?;
    }
    if let Some((forecast, baseline)) = event.forecast {
        scalar("events/forecast/nrmse", forecast)?;
        scalar("events/forecast/baseline_nrmse", baseline)?;
    }
    if let Some(v) = event.verdict {
        let code = match v {
            "normal" => 1.0,
            "alarm" => 3.0,
            _ => 0.0,
        };
        scalar("events/verdict", code)?;
    }
    if !event.identified_hz.is_empty() {
        rec.log(
            "events/frequency/identified",
            &rerun::Points2D::new(event.identified_hz.iter().map(|&f| (event.amplitude as f32, f as f32))),
        )
        .map_err(rerun_error)?;
    }
    Ok(())
}
