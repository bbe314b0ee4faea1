//! Earthquakes in the Rerun stream (`events --rerun-save`): one point per
//! event on the `measurement_time` timeline: the ground's and the deck's
//! peaks, the deck's strong-motion RMS, each updated parameter, the identified frequencies, the updated
//! model's dominant mode, the forecast's and the baseline's NRMSE and the
//! verdict (0 insufficient history, 1 normal, 3 alarm, as `monitoring/state`).

use super::{rerun_error, RerunOutput};
use anyhow::Result;

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
    pub parameters: &'a [(String, f64)],
    pub identified_hz: &'a [f64],
    pub model_mode_hz: Option<f64>,
    /// Median NRMSE of the forecast and of the baseline.
    pub forecast: Option<(f64, f64)>,
    pub verdict: Option<&'a str>,
}

impl RerunOutput {
    /// Logs one event under `events/…`.
    pub fn log_event(&mut self, event: &EventPoint<'_>) -> Result<()> {
        self.rotate_if_due(event.time_ns)?;
        self.updates += 1;
        self.set_time(event.time_ns);
        let scalar =
            |path: &str, v: f64| -> Result<()> { self.rec.log(path, &rerun::Scalars::new([v])).map_err(rerun_error) };
        scalar("events/pga_ground", event.pga_ground)?;
        scalar("events/peak_deck", event.peak_deck)?;
        if let Some(rms) = event.rms_deck {
            scalar("events/rms_deck", rms)?;
        }
        for (name, value) in event.parameters {
            scalar(&format!("events/parameters/{name}"), *value)?;
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
            self.rec
                .log(
                    "events/frequency/identified",
                    &rerun::Points2D::new(event.identified_hz.iter().map(|&f| (event.amplitude as f32, f as f32))),
                )
                .map_err(rerun_error)?;
        }
        Ok(())
    }
}
