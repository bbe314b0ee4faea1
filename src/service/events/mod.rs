//! Earthquake by earthquake (issue 45): the chain every event goes
//! through, shared by `splinewatch events` (one input file or folder per
//! event) and the daemon on a triggered logger (one burst of channel blocks
//! per event, [`burst`]). In time order each event is checked, identified
//! (SRIM), forecast by the model updated on the events before it
//! (`predict`'s figures), updated on its record (warm-started from the
//! previous event), and judged against the bands the earlier events give
//! at its amplitude ([`splinewatch_core::monitoring::amplitude`]).
//!
//! An event that cannot be used (unreadable, a dead or clipped channel, no
//! ground channel at all, too short) is reported as skipped with its reason
//! and the others go on; a ground channel the record lacks takes the mean of
//! the groups measured along its axis, said in the event's notes.
//! Room: a service shell. May import: `outputs`, `pipeline`, `studies`, `config`, `io`, the core crate.

pub mod burst;
mod chain;
mod emit;
mod line;
mod loading;
mod realization;

use chain::feature_of_parameter;
pub use chain::Chain;
pub use emit::{emit, forecast_medians, log_rerun, messages, status_message, EventMessages, EventSink};
pub use line::{BandLine, EventLine, UpdateLine, VerdictLine};
pub use loading::{load, Loaded};
pub use realization::predict_by_realization;

use super::frequency_domain::identify_record;
use super::records::Event;
use crate::config::{ground_sensors, ground_signals, Config, EventAmplitude, EventForecast, GroundInputPlan, Residues};
use crate::io::modes_json::{ModeEntry, ModesFile};
use crate::io::monitoring_json::StatusMessage;
use crate::io::named_value::NamedValue;
use crate::io::wire::format_timestamp;
use crate::studies::event_update::{update_on_event, EventSignals, PairedMode};
use crate::studies::ground_motion::{GroundModel, GroundParts};
use crate::studies::predict::{predict as predict_event, significant_span, PredictionReport};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use splinewatch_core::monitoring::amplitude::{expected, judge, FeatureBand, Verdict};
use splinewatch_core::response::frf::ModalState;
use splinewatch_core::updating::{ParameterEstimate, StopReason};
use std::path::Path;
use std::sync::Arc;

/// The chain on one event; a failing stage skips the event with its reason.
pub fn process(cfg: &Config, loaded: &Loaded, chain: &mut Chain) -> EventLine {
    process_identified(cfg, loaded, || identify(cfg, loaded), chain)
}

/// An event's identified modes (item 1 of the chain) and what their
/// identification had to say, or why there are none; `None` for an event
/// that could not be read. It depends on the record alone, not on the
/// chain, so `events` identifies the next records on a second thread while
/// the chain updates this one.
pub type Identified = Option<Result<(Vec<ModeEntry>, Vec<String>), String>>;

/// [`Identified`] of `loaded`: SRIM of every recorded ground channel to
/// every deck channel, and with `[oma.frequency_domain]` the modes its fit
/// of the transmissibilities finds (its failure a note, SRIM's modes kept).
pub fn identify(cfg: &Config, loaded: &Loaded) -> Identified {
    let (event, plan) = loaded.event.as_ref().ok()?;
    let channel = |i: usize| (i, event.channels[i].as_deref().expect("aligned"));
    let inputs: Vec<(usize, &[f64])> = ground_sensors(plan).iter().map(|&i| channel(i)).collect();
    let outputs: Vec<(usize, &[f64])> = event.deck.iter().map(|&i| channel(i)).collect();
    Some(
        identify_record(cfg, &inputs, &outputs, event.fs, event.start_ns)
            .map(|record| (record.modes(), record.notes))
            .map_err(|e| format!("{e:#}")),
    )
}

/// [`process`] with the event's identification from `identified` (as
/// [`identify`] gives it), taken once the forecast and the update are done:
/// neither needs it, so an identification running on another thread
/// overlaps them. It is taken for every event, read or not (one per record,
/// in order).
pub fn process_identified(
    cfg: &Config,
    loaded: &Loaded,
    identified: impl FnOnce() -> Identified,
    chain: &mut Chain,
) -> EventLine {
    let mut identified = Some(identified);
    let start = loaded.start_ns();
    let mut line = EventLine::new(loaded.name.clone());
    line.number = chain.events_seen;
    chain.events_seen += 1;
    line.start = start.map(format_timestamp);
    match &loaded.event {
        Ok((event, plan)) => {
            line.notes.extend(event.notes.iter().cloned());
            if let Err(e) = run_chain(cfg, event, plan, &mut identified, chain, &mut line) {
                line.skipped = Some(format!("{e:#}"));
            }
        }
        Err(e) => line.skipped = Some(format!("{e:#}")),
    }
    if let Some(pending) = identified.take() {
        pending();
    }
    line
}

/// The event's amplitudes (stage 1).
struct Measured {
    pga_ground: f64,
    peak_deck: f64,
    /// Over the strong motion ([`significant_span`] of the ground).
    rms_deck: f64,
}

fn measure(event: &Event, plan: &[GroundInputPlan]) -> Measured {
    let channel = |i: usize| event.channels[i].as_deref().expect("aligned");
    let ground = ground_sensors(plan);
    let peak =
        |channels: &mut dyn Iterator<Item = usize>| channels.flat_map(channel).fold(0.0f64, |a, v| a.max(v.abs()));
    let samples = channel(event.deck[0]).len();
    let (i0, i1) = significant_span(ground.iter().map(|&i| channel(i)), samples);
    let square: f64 = event
        .deck
        .iter()
        .map(|&i| channel(i)[i0..i1].iter().map(|v| v * v).sum::<f64>())
        .sum();
    Measured {
        pga_ground: peak(&mut ground.iter().copied()),
        peak_deck: peak(&mut event.deck.iter().copied()),
        rms_deck: (square / ((i1 - i0) * event.deck.len()) as f64).sqrt(),
    }
}

/// The event's identified modes and what their identification said
/// (stage 2); `failed`: why it found none.
struct Identification {
    modes: Vec<ModeEntry>,
    notes: Vec<String>,
    failed: Option<String>,
}

/// The forecast by the model of the events before this one (stage 3).
struct Forecast {
    /// The parameters its model had.
    model: Vec<NamedValue>,
    report: PredictionReport,
    /// The deck channels its headline medians are taken over.
    channels: Vec<String>,
    /// Its model's modes (matched with the identified ones).
    state: ModalState,
}

/// The update on the event's record (stage 4).
struct Updated {
    line: UpdateLine,
    parameters: Vec<ParameterEstimate>,
    notes: Vec<String>,
}

/// The stages in order, each returning its outcome; the line is written
/// here alone. A stage's error skips the event with what the stages before
/// it found.
fn run_chain(
    cfg: &Config,
    event: &Event,
    plan: &[GroundInputPlan],
    identified: &mut Option<impl FnOnce() -> Identified>,
    chain: &mut Chain,
    line: &mut EventLine,
) -> Result<()> {
    let measured = measure(event, plan);
    line.pga_ground = Some(measured.pga_ground);
    line.peak_deck = Some(measured.peak_deck);
    line.rms_deck = Some(measured.rms_deck);
    let amplitude = line.amplitude(cfg.events().amplitude).expect("both measured");
    // The update needs the modes when it fits them (`[events] residues`);
    // otherwise, and without a model, the identification is taken after
    // the forecast and the update (or the realization), so that one running
    // on another thread overlaps them.
    let residues = cfg.events().residues_of(chain.parameters.is_empty());
    let modes_first = residues != Residues::Frf && cfg.has_model();
    if modes_first {
        add_identification(line, take_identification(identified)?);
    }
    // Without a model the event is forecast by the previous event's
    // realization, identified and judged on its modes.
    let forecast_state = if cfg.has_model() {
        // A failed update keeps the forecast made before it.
        let staged = (|| -> Result<(Option<ModalState>, Updated)> {
            let forecast = forecast(cfg, (event, plan), chain, amplitude, line.start.clone())?;
            let forecast_state = forecast.map(|f| {
                line.forecast_model = f.model;
                line.forecast_channels = f.channels;
                line.forecast = Some(f.report);
                f.state
            });
            Ok((
                forecast_state,
                update(cfg, (event, plan), chain, (&line.event, residues), &line.modes)?,
            ))
        })();
        if !modes_first {
            add_identification(line, take_identification(identified)?);
        }
        let (forecast_state, updated) = staged?;
        line.notes.extend(updated.notes);
        line.update = Some(updated.line);
        line.parameters = updated.parameters;
        forecast_state
    } else {
        let (realized, finished) =
            realization::forecast_and_realize(cfg, (event, plan), chain, (&line.event, &line.start));
        line.notes.extend(realized.notes);
        line.forecast = realized.forecast;
        add_identification(line, take_identification(identified)?);
        finished?;
        None
    };
    if cfg.has_model() && !line.modes.is_empty() {
        match_with_forecast_model(cfg, chain, &mut line.modes, forecast_state)?;
    }
    line.verdict = Some(judge_event(cfg, chain, (&line.modes, &line.parameters), amplitude));
    Ok(())
}

/// The identification's outcome in `line`: its failure first in the notes.
fn add_identification(line: &mut EventLine, identification: Identification) {
    line.modes = identification.modes;
    line.notes.extend(identification.notes);
    if let Some(e) = identification.failed {
        line.notes.insert(0, e);
    }
}

/// The event's modes; a record whose identification finds no mode is
/// still forecast and updated (on its record alone).
fn take_identification(identified: &mut Option<impl FnOnce() -> Identified>) -> Result<Identification> {
    match identified.take().and_then(|identify| identify()) {
        Some(Ok((modes, notes))) => Ok(Identification {
            modes,
            notes,
            failed: None,
        }),
        Some(Err(e)) => Ok(Identification {
            modes: Vec::new(),
            notes: Vec::new(),
            failed: Some(e),
        }),
        None => bail!("the event was not read"),
    }
}

/// Each identified mode with the model mode nearest it by shape in the
/// forecast's model (the events before this one; the config's values for
/// the first): does the model the event was forecast with have the modes
/// the record shows? `forecast` is the forecast's own modal state, when
/// there was a forecast.
fn match_with_forecast_model(
    cfg: &Config,
    chain: &mut Chain,
    modes: &mut [ModeEntry],
    forecast: Option<ModalState>,
) -> Result<()> {
    let parts = chain.parts(cfg)?;
    let state = match forecast {
        Some(state) => state,
        None => crate::studies::parameters::modal_state_in(&parts.setup, &parts.parameters, &[])
            .context("the config's model's modes")?,
    };
    crate::studies::mode_match::match_modes(cfg, &state, &parts.setup.sensor_names, modes)
        .context("the identified modes against the forecast's model")
}

/// The event forecast by the model of the events before it; none for the
/// first.
fn forecast(
    cfg: &Config,
    (event, plan): (&Event, &[GroundInputPlan]),
    chain: &mut Chain,
    amplitude: f64,
    start: Option<String>,
) -> Result<Option<Forecast>> {
    if chain.parameters.is_empty() {
        return Ok(None);
    }
    let channel = |i: usize| event.channels[i].as_deref().expect("aligned");
    let parameters = chain.forecast_parameters(cfg.events().forecast, cfg.events().min_events, amplitude);
    let parts = chain.parts(cfg)?;
    let mut forecaster = GroundModel::at(&parts, &parameters).context("the forecast's model")?;
    forecaster.plan = plan.to_vec();
    let mut prediction = predict_event(cfg, &forecaster, &event.deck, channel, event.fs);
    prediction.report.start = start;
    let channels = prediction
        .report
        .channels
        .iter()
        .map(|c| c.sensor.clone())
        .filter(|s| fitted(cfg, s))
        .collect();
    Ok(Some(Forecast {
        model: parameters,
        report: prediction.report,
        channels,
        state: forecaster.state,
    }))
}

/// Whether the update fits deck sensor `name` (`[events] outputs`; every
/// deck sensor when it names none).
fn fitted(cfg: &Config, name: &String) -> bool {
    let outputs = &cfg.events().outputs;
    outputs.is_empty() || outputs.contains(name)
}

/// The update on the event's transmissibilities (and its identified
/// `modes`, when `residues` fits them: `[events] residues`, or
/// `first_residues` for the chain's first), warm-started from the previous
/// event's values; the chain keeps the result.
fn update(
    cfg: &Config,
    (event, plan): (&Event, &[GroundInputPlan]),
    chain: &mut Chain,
    (name, residues): (&str, Residues),
    modes: &[ModeEntry],
) -> Result<Updated> {
    let channel = |i: usize| event.channels[i].as_deref().expect("aligned");
    let signals = ground_signals(plan, channel);
    let fitted: Vec<usize> = event
        .deck
        .iter()
        .copied()
        .filter(|&i| fitted(cfg, &cfg.sensors[i].name))
        .collect();
    let deck_series: Vec<Vec<f64>> = fitted.iter().map(|&i| channel(i).to_vec()).collect();
    let parts = chain.parts(cfg)?;
    let modes = ModesFile::of(modes.to_vec())
        .to_observed(&parts.setup.sensor_names)
        .context("the identified modes")?;
    let record = EventSignals {
        plan,
        inputs: &signals,
        deck: &fitted,
        outputs: &deck_series,
        fs: event.fs,
        modes: &modes,
    };
    let updated = update_on_event(cfg, &parts, &record, (chain.named(), residues), &mut |it| {
        tracing::debug!(
            event = %name,
            iteration = it.iteration,
            relative_residual = it.relative_residual,
            step = it.step_norm,
            damping = it.damping,
            rejected = it.rejected_steps,
            parameters = ?it.parameters,
            "update iteration"
        )
    })?;
    let mut notes = Vec::new();
    if residues == Residues::Both && !modes.is_empty() && updated.pairs.is_empty() {
        notes.push(format!(
            "none of the {} identified modes paired with a model mode (MAC ≥ {} within {} % in frequency): \
             the update fitted the record alone",
            modes.len(),
            cfg.updating.min_mac,
            100.0 * cfg.updating.max_frequency_gap
        ));
    }
    chain.parameters = updated
        .result
        .parameters
        .iter()
        .map(|p| NamedValue {
            name: p.name.clone(),
            value: p.value,
        })
        .collect();
    Ok(Updated {
        line: UpdateLine {
            model_mode_hz: updated.dominant_hz,
            model_mode_std_hz: updated.dominant_std_hz,
            relative_residual: updated.result.relative_residual,
            iterations: updated.result.iterations.len().saturating_sub(1),
            converged: updated.result.converged,
            stop_reason: updated.result.stop_reason,
            evaluations: updated.evaluations,
            relative_offset: updated.result.relative_offset,
            combined_inputs: updated.combined,
            residues: residues.as_str(),
            paired_modes: updated.pairs,
        },
        parameters: updated.result.parameters,
        notes,
    })
}

/// A parameter this close to a bound (share of its range) is held there by
/// its bound, not by the data: not a feature.
const BOUND_SHARE: f64 = 1e-4;

/// The features judged: each tracked mode's identified frequency, then
/// each updated parameter's log10 value (`None`: not identified).
fn features(
    chain: &Chain,
    (modes, parameters): (&[ModeEntry], &[ParameterEstimate]),
    max_gap: f64,
) -> (Vec<String>, Vec<Option<f64>>) {
    let mut names = Vec::new();
    let mut values = Vec::new();
    for (k, &f) in chain.tracked_hz.iter().enumerate() {
        names.push(format!("mode{}_hz", k + 1));
        let nearest = modes
            .iter()
            .map(|m| m.frequency_hz)
            .min_by(|a, b| (a - f).abs().total_cmp(&(b - f).abs()))
            .filter(|m| (m - f).abs() <= max_gap * f);
        values.push(nearest);
    }
    for p in parameters {
        names.push(feature_of_parameter(&p.name));
        let margin = BOUND_SHARE * (p.upper - p.lower);
        let bounded = p.value <= p.lower + margin || p.value >= p.upper - margin;
        values.push(p.std.filter(|_| !bounded).map(|_| p.value.log10()));
    }
    (names, values)
}

/// The verdict (stage 5) on the event's features (its identified `modes`
/// and updated `parameters`) against the bands the earlier events give at
/// its `amplitude` (`[events] amplitude`).
fn judge_event(
    cfg: &Config,
    chain: &mut Chain,
    (modes, parameters): (&[ModeEntry], &[ParameterEstimate]),
    amplitude: f64,
) -> VerdictLine {
    if chain.tracked_hz.is_empty() {
        chain.tracked_hz = modes.iter().map(|m| m.frequency_hz).collect();
    }
    let (names, values) = features(chain, (modes, parameters), cfg.updating.max_frequency_gap);
    let x = amplitude.max(1e-12).log10();
    let columns: Vec<Vec<(f64, f64)>> = names.iter().map(|n| chain.history_of(n)).collect();
    let history: Vec<Vec<f64>> = (0..chain.amplitudes.len())
        .map(|e| columns.iter().map(|c| c[e].1).collect())
        .collect();
    let now: Vec<f64> = values.iter().map(|x| x.unwrap_or(f64::NAN)).collect();
    let (verdict, bands) = judge(
        &chain.amplitudes,
        &history,
        x,
        &now,
        cfg.events().false_alarm_rate,
        cfg.events().min_events,
    );
    let outside = match &verdict {
        Verdict::Alarm { features } => features.iter().map(|&f| names[f].clone()).collect(),
        _ => Vec::new(),
    };
    let judged = VerdictLine {
        state: verdict.name().to_string(),
        outside,
        bands: names
            .iter()
            .zip(values.iter().zip(bands))
            .map(|(feature, (value, band))| BandLine {
                feature: feature.clone(),
                value: *value,
                band,
            })
            .collect(),
    };
    // An alarmed event does not teach the bands: a lasting change keeps
    // alarming until the owner starts a new history.
    if !matches!(verdict, Verdict::Alarm { .. }) {
        chain.push_features(x, &names, values);
        chain.amplitude = Some(cfg.events().amplitude);
    }
    judged
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chain_with(parameters: &[(&str, f64)]) -> Chain {
        Chain {
            parameters: parameters
                .iter()
                .map(|&(name, value)| NamedValue {
                    name: name.to_string(),
                    value,
                })
                .collect(),
            ..Chain::default()
        }
    }

    /// A feature keeps its column when the modes tracked first appear at a
    /// later event (the first record had none): the earlier rows are put on
    /// the new names, not read as the new columns.
    #[test]
    fn features_keep_their_names_when_modes_are_first_tracked_later() {
        let mut chain = chain_with(&[]);
        let k = feature_of_parameter("bent.ky");
        chain.push_features(-0.4, std::slice::from_ref(&k), vec![Some(8.2)]);
        let names = ["mode1_hz".to_string(), k.clone()];
        chain.push_features(-0.3, &names, vec![Some(4.1), Some(8.1)]);
        assert_eq!(chain.history_of(&k), [(-0.4, 8.2), (-0.3, 8.1)]);
        let modes = chain.history_of("mode1_hz");
        assert!(modes[0].1.is_nan() && modes[1] == (-0.3, 4.1), "{modes:?}");
    }

    /// `"trend"`: the earlier events' line at this event's peak once there
    /// are `min_events` of them, their geometric mean before; `"last"`: the
    /// last update; a parameter no earlier event gave with a std keeps the
    /// last value.
    #[test]
    fn the_forecast_takes_the_trend_of_the_earlier_events() {
        let mut chain = chain_with(&[("bent.ky", 3.0e8), ("zeta", 0.08)]);
        let names = [feature_of_parameter("bent.ky"), feature_of_parameter("zeta")];
        // log10 k = 8.5 − 0.5 log10 A over A = 0.1 … 1.
        let amplitudes = [-1.0, -0.75, -0.5, -0.25, 0.0];
        for (e, &x) in amplitudes.iter().enumerate() {
            chain.push_features(x, &names, vec![Some(8.5 - 0.5 * x), None]);
            let by = |forecast, min_events, amplitude: f64| chain.forecast_parameters(forecast, min_events, amplitude);
            let trend = by(EventForecast::Trend, 5, 10f64.powf(0.5));
            let k = trend[0].value.log10();
            if e + 1 < 5 {
                let mean = amplitudes[..=e].iter().map(|x| 8.5 - 0.5 * x).sum::<f64>() / (e + 1) as f64;
                assert!((k - mean).abs() < 1e-12, "event {e}: {k} vs {mean}");
            } else {
                assert!((k - (8.5 - 0.25)).abs() < 1e-12, "{k}");
            }
            assert_eq!(trend[1], NamedValue::new("zeta", 0.08));
            assert_eq!(by(EventForecast::Last, 5, 1.0), chain.named());
        }
    }

    /// A parameter on its bound (within 1e-4 of its range) is set by the
    /// bound, not by the record: not a feature, whether or not the solver
    /// held it there (the two differ by how far the search crept).
    #[test]
    fn a_parameter_on_its_bound_is_not_judged() {
        let chain = chain_with(&[]);
        let mut line = EventLine::new("e".into());
        let estimate = |name: &str, value: f64| splinewatch_core::updating::ParameterEstimate {
            name: name.into(),
            value,
            std: Some(0.006),
            lower: 0.001,
            upper: 0.3,
        };
        line.parameters = vec![
            estimate("zeta", 0.299_999_88),
            estimate("low", 0.001_000_1),
            estimate("free", 0.299),
        ];
        let (names, values) = features(&chain, (&line.modes, &line.parameters), 0.1);
        assert_eq!(names.len(), 3);
        assert_eq!(values[0], None);
        assert_eq!(values[1], None);
        assert_eq!(values[2], Some(0.299f64.log10()));
    }
}
