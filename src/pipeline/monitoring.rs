//! The statistical layer on accepted updates: each update's window gets the
//! mean temperature of every `[monitoring] temperature_channels` channel
//! over its span (from `<prefix>/temperature/<name>` blocks), and the
//! core's `Monitor` scores the updated parameters against the reference.

use super::Pipeline;
use crate::config::{FrfSetup, MonitoringConfig};
use crate::io::monitoring_json::{AlarmMessage, Residual, StatusMessage};
use crate::io::named_value::NamedValue;
use crate::io::wire::ChannelBlock;
use splinewatch_core::monitoring::chart::Flag;
use splinewatch_core::monitoring::{Monitor, MonitorState, Observation, Status};
use splinewatch_core::response::frf::ModalState;
use splinewatch_core::solvers::modal::ModeKind;
use splinewatch_core::updating::Parameter;
use std::collections::{BTreeMap, VecDeque};

/// Samples kept per temperature channel at most (a week at one a minute
/// is 10 080); older ones are dropped first, counted.
const MAX_TEMPERATURE_SAMPLES: usize = 20_000;

/// A window's environment: the mean temperature of every channel over the
/// span (`NaN`: none, or the channel is stuck) and what was wrong.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Environment {
    pub temperatures: Vec<f64>,
    pub flags: Vec<String>,
}

/// Temperature samples of the configured channels, until their windows are scored.
pub(super) struct TemperatureStore {
    names: Vec<String>,
    samples: Vec<VecDeque<(i128, f64)>>,
    /// Per channel: the one value the previous span held, and how many
    /// spans in a row held exactly it.
    repeats: Vec<(Option<f64>, usize)>,
    stuck_windows: usize,
}

/// A temperature in °C from a block's unit, if the unit is known.
fn celsius(value: f64, unit: &str) -> Option<f64> {
    match unit {
        "°C" | "C" | "degC" | "celsius" => Some(value),
        "K" => Some(value - 273.15),
        "°F" | "F" | "degF" => Some((value - 32.0) / 1.8),
        _ => None,
    }
}

impl TemperatureStore {
    pub(super) fn new(config: &MonitoringConfig) -> Self {
        let n = config.temperature_channels.len();
        Self {
            names: config.temperature_channels.clone(),
            samples: vec![VecDeque::new(); n],
            repeats: vec![(None, 0); n],
            stuck_windows: config.stuck_windows,
        }
    }

    /// Mean of every channel over `[start, end)`; drops the samples before
    /// `start` (later spans start later).
    fn span(&mut self, start: i128, end: i128) -> Environment {
        let mut environment = Environment::default();
        for (c, samples) in self.samples.iter_mut().enumerate() {
            while samples.front().is_some_and(|&(t, _)| t < start) {
                samples.pop_front();
            }
            let values: Vec<f64> = samples.iter().take_while(|&&(t, _)| t < end).map(|&(_, v)| v).collect();
            let name = &self.names[c];
            if values.is_empty() {
                environment.temperatures.push(f64::NAN);
                environment.flags.push(format!("temperature_missing:{name}"));
                self.repeats[c] = (None, 0);
                continue;
            }
            let constant = values.iter().all(|&v| v == values[0]).then_some(values[0]);
            let repeats = &mut self.repeats[c];
            *repeats = match (constant, repeats.0) {
                (Some(v), Some(previous)) if v == previous => (Some(v), repeats.1 + 1),
                (Some(v), _) => (Some(v), 1),
                (None, _) => (None, 0),
            };
            if repeats.1 >= self.stuck_windows {
                environment.temperatures.push(f64::NAN);
                environment.flags.push(format!("temperature_stuck:{name}"));
            } else {
                environment
                    .temperatures
                    .push(values.iter().sum::<f64>() / values.len() as f64);
            }
        }
        environment
    }
}

/// The monitor and the names of what it scores.
#[derive(Clone)]
pub(super) struct Monitoring {
    pub(super) monitor: Monitor,
    features: Vec<String>,
    channels: Vec<String>,
}

impl Monitoring {
    pub(super) fn new(config: &MonitoringConfig, features: Vec<String>) -> anyhow::Result<Self> {
        let monitor = match config.training_span()? {
            Some((from, until)) => Monitor::with_training_span(config.settings(), from, until)?,
            None => Monitor::new(config.settings(), config.training_windows)?,
        };
        Ok(Self {
            monitor,
            features,
            channels: config.temperature_channels.clone(),
        })
    }

    /// Scores an accepted update (its features by name: parameters, and
    /// output-only the identified frequencies; an absent one is missing)
    /// measured at `environment`: the status message, and the alarm message
    /// when the state entered or left alarm. Errors only when the feature
    /// count differs from the reference's.
    pub(super) fn score(
        &mut self,
        window: u64,
        time_ns: i128,
        values: &BTreeMap<String, f64>,
        environment: &Environment,
    ) -> Result<MonitoringOutcome, splinewatch_core::monitoring::MonitoringError> {
        let observation = Observation {
            features: self
                .features
                .iter()
                .map(|n| values.get(n).copied().unwrap_or(f64::NAN))
                .collect(),
            temperatures: environment.temperatures.clone(),
            time_ns,
        };
        self.observe(window, &observation, environment)
    }

    /// Scores one observation: the status message, and the alarm message
    /// when the state entered or left alarm.
    fn observe(
        &mut self,
        window: u64,
        observation: &Observation,
        environment: &Environment,
    ) -> Result<MonitoringOutcome, splinewatch_core::monitoring::MonitoringError> {
        let before = self.monitor.state();
        let status = self.monitor.observe(observation)?;
        let message = status_message(self, window, observation.time_ns, observation, &status, environment);
        let alarm = status.alarm_changed.then(|| alarm_message(&message, before));
        Ok(MonitoringOutcome { status: message, alarm })
    }
}

/// The temperature store and monitor of a config with `[monitoring]`,
/// scoring `parameters` (every updated parameter, in order) and, output-only,
/// the identified frequencies ([`frequency_features`]).
pub(super) fn for_config(
    config: &crate::config::Config,
    parameters: &[Parameter],
    setup: &FrfSetup,
) -> anyhow::Result<(Option<TemperatureStore>, Option<Monitoring>)> {
    let Some(m) = &config.monitoring else {
        return Ok((None, None));
    };
    let mut names: Vec<String> = parameters.iter().map(|p| p.name.clone()).collect();
    if config.is_output_only() {
        names.extend(frequency_features(config, parameters, setup)?);
    }
    Ok((Some(TemperatureStore::new(m)), Some(Monitoring::new(m, names)?)))
}

/// The name of the feature holding the identified frequency of the model's
/// `n`-th bending mode (from 1).
fn frequency_feature(n: usize) -> String {
    format!("mode_{n}_frequency_hz")
}

/// Output-only: one feature per bending mode of the config's model (its
/// nominal parameters) in the `[oma]` band, the identified frequency of the
/// mode paired with it (by the bending order of the paired model mode at the
/// updated parameters); `null` in a window that did not identify it. Which
/// of them the reference keeps is decided in training (`feature_presence`).
fn frequency_features(
    config: &crate::config::Config,
    parameters: &[Parameter],
    setup: &FrfSetup,
) -> anyhow::Result<Vec<String>> {
    let field_coefficients = setup.model.field_coefficients();
    let nominal = splinewatch_core::updating::base_values(parameters, &setup.kappa, field_coefficients, &setup.damping);
    let (state, _) =
        splinewatch_core::updating::modal_state_at(&setup.model, parameters, &setup.kappa, &setup.damping, &nominal)?;
    let [lo, hi] = config.oma_settings()?.0.band;
    Ok(bending_orders(&state)
        .into_iter()
        .filter(|&(i, _)| (lo..=hi).contains(&state.modes.frequency_hz(i)))
        .map(|(_, n)| frequency_feature(n))
        .collect())
}

/// `(model mode, bending order from 1)` of every bending mode.
fn bending_orders(state: &ModalState) -> Vec<(usize, usize)> {
    (0..state.modes.len())
        .filter(|&i| state.modes.kinds[i] == ModeKind::Bending)
        .zip(1..)
        .collect()
}

/// The identified frequency of every paired mode (`(model mode, identified
/// frequency)`), by its feature name.
pub(super) fn identified_frequencies(pairs: &[(usize, f64)], state: &ModalState) -> Vec<(String, f64)> {
    let orders = bending_orders(state);
    pairs
        .iter()
        .filter_map(|&(model_mode, frequency_hz)| {
            let &(_, n) = orders.iter().find(|(i, _)| *i == model_mode)?;
            Some((frequency_feature(n), frequency_hz))
        })
        .collect()
}

/// What scoring an update produced: the status message, and the alarm
/// message when the state entered or left alarm.
#[derive(Debug, Clone, PartialEq)]
pub struct MonitoringOutcome {
    pub status: StatusMessage,
    pub alarm: Option<AlarmMessage>,
}

impl Pipeline {
    /// Takes a temperature block: kept for the windows it falls in, in °C.
    pub(super) fn ingest_temperature(&mut self, block: &ChannelBlock) {
        let Some(store) = self.temperatures.as_mut() else {
            self.health.reject("unknown_channel");
            return;
        };
        let Some(c) = store.names.iter().position(|n| *n == block.name) else {
            self.health.reject("unknown_channel");
            return;
        };
        if celsius(0.0, &block.unit).is_none() {
            self.health.reject("temperature_unit");
            return;
        }
        let samples = &mut store.samples[c];
        if samples.back().is_some_and(|&(t, _)| t >= block.start_ns) {
            self.health.reject("time_overlap");
            return;
        }
        for (k, &v) in block.data.iter().enumerate() {
            samples.push_back((block.sample_time_ns(k), celsius(v, &block.unit).expect("unit checked")));
        }
        while samples.len() > MAX_TEMPERATURE_SAMPLES {
            samples.pop_front();
            self.health.temperature_samples_dropped += 1;
        }
        self.health.temperature_blocks += 1;
    }

    /// The environment of a window spanning `[start, end)` (ns).
    pub(super) fn environment(&mut self, start: i128, end: i128) -> Environment {
        let environment = self
            .temperatures
            .as_mut()
            .map_or_else(Environment::default, |store| store.span(start, end));
        for flag in &environment.flags {
            *self.health.temperature_flags.entry(flag.clone()).or_default() += 1;
        }
        environment
    }
}

fn status_message(
    monitoring: &Monitoring,
    window: u64,
    time_ns: i128,
    observation: &Observation,
    status: &Status,
    environment: &Environment,
) -> StatusMessage {
    let valid: Vec<f64> = observation
        .temperatures
        .iter()
        .copied()
        .filter(|t| t.is_finite())
        .collect();
    let mut flags = environment.flags.clone();
    for flag in &status.flags {
        let text = match *flag {
            Flag::TemperatureMissing(c) => format!("temperature_missing:{}", monitoring.channels[c]),
            Flag::OutsideRange(c) => format!("outside_training_range:{}", monitoring.channels[c]),
            Flag::FeatureMissing(f) => format!("feature_missing:{}", monitoring.features[f]),
            Flag::TrainingDeferred => "training_deferred".into(),
        };
        if !flags.contains(&text) {
            flags.push(text);
        }
    }
    let scored_by = status.t2.map(|_| {
        if status.fallback {
            "pca_fallback"
        } else if monitoring.channels.is_empty() {
            "pca"
        } else {
            "temperature_regression"
        }
        .to_string()
    });
    StatusMessage {
        window,
        time: crate::io::wire::format_timestamp(time_ns),
        state: status.state.name().into(),
        t2: status.t2,
        t2_limit: status.t2_limit,
        mewma: status.mewma,
        mewma_limit: status.mewma_limit,
        temperature_c: (!valid.is_empty()).then(|| valid.iter().sum::<f64>() / valid.len() as f64),
        // The features scored and present (a missing one is in `flags`).
        residuals: monitoring
            .features
            .iter()
            .zip(&status.standardised)
            .filter(|(_, s)| s.is_finite())
            .map(|(name, &standardised)| Residual {
                name: name.clone(),
                standardised,
            })
            .collect(),
        temperatures: monitoring
            .channels
            .iter()
            .zip(&observation.temperatures)
            .map(|(n, t)| (n.clone(), t.is_finite().then_some(*t)))
            .collect(),
        features: monitoring
            .features
            .iter()
            .zip(&observation.features)
            .map(|(name, &value)| NamedValue {
                name: name.clone(),
                value,
            })
            .collect(),
        flags,
        exceedances: status.exceedances,
        scored_by,
    }
}

fn alarm_message(status: &StatusMessage, before: MonitorState) -> AlarmMessage {
    let mut largest = status.residuals.clone();
    largest.sort_by(|a, b| b.standardised.abs().total_cmp(&a.standardised.abs()));
    largest.truncate(5);
    AlarmMessage {
        window: status.window,
        time: status.time.clone(),
        state: status.state.clone(),
        previous: before.name().into(),
        t2: status.t2,
        mewma: status.mewma,
        largest_residuals: largest,
    }
}

/// Which windows train the reference when re-scoring.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Training {
    /// The first `n` windows with every feature (as the daemon does).
    FirstWindows(usize),
    /// The windows whose time lies in `[from, until)` (ns).
    Span(i128, i128),
}

/// Re-runs the statistical layer over saved status messages (in window
/// order): their features and window temperatures are what the daemon
/// scored, so with the config's settings and `FirstWindows(training_windows)`
/// the result is the daemon's, bit for bit. `raw`: no compensation at all
/// (the features' plain mean and covariance), to show what temperature does
/// to uncompensated parameters.
pub fn rescore(
    config: &MonitoringConfig,
    statuses: &[StatusMessage],
    training: Training,
    raw: bool,
) -> anyhow::Result<Vec<MonitoringOutcome>> {
    let Some(first) = statuses.first() else {
        return Ok(Vec::new());
    };
    let features: Vec<String> = first.features.iter().map(|f| f.name.clone()).collect();
    let mut settings = config.clone();
    if raw {
        settings.temperature_channels.clear();
        settings.pca_components = 0;
    }
    let observations: Vec<(Observation, Environment)> = statuses
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let names: Vec<&str> = s.features.iter().map(|f| f.name.as_str()).collect();
            if names != features.iter().map(String::as_str).collect::<Vec<_>>() {
                anyhow::bail!(
                    "status of window {} scores other features than the first ({i} messages in)",
                    s.window
                );
            }
            let temperatures: Vec<f64> = settings
                .temperature_channels
                .iter()
                .map(|c| s.temperatures.get(c).copied().flatten().unwrap_or(f64::NAN))
                .collect();
            let environment = Environment {
                temperatures: temperatures.clone(),
                flags: s
                    .flags
                    .iter()
                    .filter(|f| f.starts_with("temperature_") && !raw)
                    .cloned()
                    .collect(),
            };
            let observation = Observation {
                features: s.features.iter().map(|f| f.value).collect(),
                temperatures,
                time_ns: crate::io::wire::parse_timestamp(&s.time).unwrap_or(0),
            };
            Ok((observation, environment))
        })
        .collect::<anyhow::Result<_>>()?;
    let monitor = match training {
        Training::Span(from, until) => Monitor::with_training_span(settings.settings(), from, until)?,
        Training::FirstWindows(n) => Monitor::new(settings.settings(), n)?,
    };
    let mut monitoring = Monitoring {
        monitor,
        features,
        channels: settings.temperature_channels.clone(),
    };
    let mut out = Vec::with_capacity(statuses.len());
    for (s, (observation, environment)) in statuses.iter().zip(&observations) {
        out.push(monitoring.observe(s.window, observation, environment)?);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{Config, ScheduleConfig};
    use crate::io::wire::{parse_timestamp, ChannelQuantity};

    fn pipeline() -> Pipeline {
        let config = Config::from_toml(include_str!("../../config/sinello-monitoring.toml")).unwrap();
        Pipeline::new(&config, ScheduleConfig::default(), None).unwrap()
    }

    const HOUR: i128 = 3_600_000_000_000;

    fn t0() -> i128 {
        parse_timestamp("2026-11-21T10:00:00Z").unwrap()
    }

    /// One hour of minute samples of `name` from hour `h`, all `value(k)`.
    fn hour_block(name: &str, unit: &str, h: i128, value: impl Fn(usize) -> f64) -> ChannelBlock {
        ChannelBlock {
            name: name.into(),
            quantity: ChannelQuantity::Temperature,
            unit: unit.into(),
            fs: 1.0 / 60.0,
            start_ns: t0() + h * HOUR,
            data: (0..60).map(value).collect(),
        }
    }

    /// Bad temperature input is counted by reason, a missing or stuck
    /// channel makes a flagged `NaN` window temperature, units convert, and
    /// nothing panics.
    #[test]
    fn bad_temperature_input_is_counted_and_flagged() {
        let mut p = pipeline();
        p.ingest(hour_block("T9", "°C", 0, |_| 5.0));
        p.ingest(hour_block("T1", "°X", 0, |_| 5.0));
        p.ingest(hour_block("T1", "K", 0, |k| 278.15 + k as f64 * 0.01));
        p.ingest(hour_block("T1", "°C", 0, |_| 5.0));
        let rejected = &p.health().rejected;
        for reason in ["unknown_channel", "temperature_unit", "time_overlap"] {
            assert_eq!(rejected.get(reason), Some(&1), "{reason}: {rejected:?}");
        }
        // Kelvin converted: mean of 5.00 … 5.59 °C.
        let e = p.environment(t0(), t0() + HOUR);
        assert!((e.temperatures[0] - 5.295).abs() < 1e-9, "{:?}", e.temperatures);
        assert!(e.flags.is_empty());
        // Hour 1: nothing arrived.
        let e = p.environment(t0() + HOUR, t0() + 2 * HOUR);
        assert!(e.temperatures[0].is_nan());
        assert_eq!(e.flags, vec!["temperature_missing:T1".to_string()]);
        // Hours 2–5: one value repeated exactly: stuck from the third span on.
        for h in 2..6 {
            p.ingest(hour_block("T1", "°C", h, |_| 7.25));
            let e = p.environment(t0() + h * HOUR, t0() + (h + 1) * HOUR);
            let stuck = h >= 4;
            assert_eq!(e.temperatures[0].is_nan(), stuck, "hour {h}");
            assert_eq!(e.flags == vec!["temperature_stuck:T1".to_string()], stuck, "hour {h}");
        }
        assert_eq!(p.health().temperature_flags.get("temperature_stuck:T1"), Some(&2));
        assert_eq!(p.health().temperature_flags.get("temperature_missing:T1"), Some(&1));
        // A NaN sample never reaches the pipeline: the decoder rejects the block.
        let mut nan = hour_block("T1", "°C", 6, |_| 1.0);
        nan.data[3] = f64::NAN;
        let bytes = crate::io::wire::encode(&nan, crate::io::wire::Encoding::Cbor);
        let e = crate::io::wire::decode(&bytes, crate::io::wire::Encoding::Cbor, &Default::default()).unwrap_err();
        assert_eq!(e.reason(), "non_finite");
    }

    /// A window's mean uses the samples inside its span only.
    #[test]
    fn a_window_gets_the_mean_over_its_span() {
        let mut p = pipeline();
        p.ingest(hour_block("T1", "°C", 0, |k| k as f64));
        p.ingest(hour_block("T1", "°C", 1, |k| 100.0 + k as f64));
        let e = p.environment(t0() + HOUR / 2, t0() + HOUR + HOUR / 2);
        // Minutes 30–59 of hour 0 and 0–29 of hour 1.
        let want = ((30..60).map(|k| k as f64).sum::<f64>() + (0..30).map(|k| 100.0 + k as f64).sum::<f64>()) / 60.0;
        assert!((e.temperatures[0] - want).abs() < 1e-12);
    }
}
