//! `[events]`: earthquake records processed one event at a time:
//! `splinewatch events` and the daemon on a triggered logger.

use super::{err, ConfigError, Residues};
use serde::{Deserialize, Serialize};

/// `[events]`: how events are told apart and judged.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EventsConfig {
    /// A triggered logger's burst of channel blocks ends when this many
    /// seconds pass without one (the daemon).
    #[serde(default = "default_gap_seconds")]
    pub gap_seconds: f64,
    /// An event is at most this long: the daemon judges a longer burst as
    /// one event and starts the next (a logger that never stops does not
    /// grow its memory); `events` cuts a longer record into parts this long.
    #[serde(default = "default_max_seconds")]
    pub max_seconds: f64,
    /// Earlier events an event's verdict needs (its amplitude bands are
    /// fitted on them); fewer: "insufficient history".
    #[serde(default = "default_min_events")]
    pub min_events: usize,
    /// Probability that an event of an unchanged bridge raises an alarm,
    /// shared by the features judged.
    #[serde(default = "default_false_alarm_rate")]
    pub false_alarm_rate: f64,
    /// The deck sensors whose transmissibilities an event's update fits
    /// (default: every deck acceleration sensor the record holds).
    #[serde(default)]
    pub outputs: Vec<String>,
    /// The response function an event's update fits: `"spectra"` (default;
    /// the record's output spectra against every ground input's),
    /// `"combined"` (the H1 transmissibility from the mean of the ground
    /// inputs along the fitted sensors' axes) or `"separate"` (a
    /// multi-input H1 from each); see `studies::event_update`.
    #[serde(default)]
    pub response_function: ResponseFunction,
    /// The key this one was before (`inputs`): refused, naming the new.
    #[serde(default, rename = "inputs", skip_serializing)]
    #[schemars(skip)]
    pub retired_inputs: Option<toml::Value>,
    /// What an event's update fits: `"frf"` (default; the seed's FRF
    /// residues on the record's transmissibilities or spectra, as
    /// `response_function` says), `"modes"` (the modes identified from the record, in their
    /// std) or `"both"` (each block in its own std: `[updating] residues`'
    /// values, with this key of its own because `[updating] residues`
    /// follows a force sensor an earthquake record has not).
    #[serde(default = "default_residues")]
    pub residues: Residues,
    /// What the update of a chain's first event fits (the values of
    /// `residues`; default: as `residues`). The first update starts from the
    /// config's values, every later one from the update before it, so where
    /// the first settles the chain stays: `"both"` anchors it on the modes
    /// identified from its record, so that it does not settle in another
    /// valley of the record's fit (a model whose vertical modes are 5 % off,
    /// on the Painter Street records).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub first_residues: Option<Residues>,
    /// The event's amplitude, the operational variable of its verdict and
    /// of the `"trend"` forecast: `"pga_ground"` (default; the largest
    /// absolute ground acceleration of the record) or `"rms_deck"` (the RMS
    /// of every deck channel over the strong motion, the span holding
    /// 5–95 % of the ground's energy).
    #[serde(default)]
    pub amplitude: EventAmplitude,
    /// The model an event is forecast by: `"trend"` (default; per updated
    /// parameter, what the earlier events expect at this event's ground
    /// peak: the verdict's line of log10 value against log10 peak once
    /// there are `min_events` of them, their geometric mean before) or
    /// `"last"` (the previous event's update).
    #[serde(default)]
    pub forecast: EventForecast,
    /// Without a `[model]`: the order (states) of the realization each
    /// event's record gives (SRIM over `[oma]`'s horizon, then `B` and `D`
    /// by least squares), which forecasts the next event from its ground
    /// channels. Even, at least 2; default 12 (two states per mode: six
    /// modes, mdof's notebooks' order for these records).
    #[serde(default = "default_realization_order")]
    pub realization_order: usize,
}

fn default_realization_order() -> usize {
    12
}

/// `[events] forecast`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum EventForecast {
    #[default]
    Trend,
    Last,
}

/// `[events] amplitude`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum EventAmplitude {
    #[default]
    PgaGround,
    RmsDeck,
}

impl EventAmplitude {
    pub fn as_str(self) -> &'static str {
        match self {
            Self::PgaGround => "pga_ground",
            Self::RmsDeck => "rms_deck",
        }
    }
}

/// `[events] response_function`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum ResponseFunction {
    #[default]
    Spectra,
    Combined,
    Separate,
}

impl Default for EventsConfig {
    fn default() -> Self {
        Self {
            gap_seconds: default_gap_seconds(),
            max_seconds: default_max_seconds(),
            min_events: default_min_events(),
            false_alarm_rate: default_false_alarm_rate(),
            outputs: Vec::new(),
            response_function: ResponseFunction::default(),
            retired_inputs: None,
            residues: default_residues(),
            first_residues: None,
            amplitude: EventAmplitude::default(),
            forecast: EventForecast::default(),
            realization_order: default_realization_order(),
        }
    }
}

fn default_residues() -> Residues {
    Residues::Frf
}

fn default_gap_seconds() -> f64 {
    10.0
}

fn default_max_seconds() -> f64 {
    600.0
}

fn default_min_events() -> usize {
    5
}

fn default_false_alarm_rate() -> f64 {
    0.01
}

impl EventsConfig {
    /// What an event's update fits: `first_residues` for a chain's first
    /// update (none before it), `residues` for the others.
    pub fn residues_of(&self, first: bool) -> Residues {
        match (first, self.first_residues) {
            (true, Some(residues)) => residues,
            _ => self.residues,
        }
    }

    /// `deck`: the deck sensors' names, which `outputs` must name.
    pub fn check(&self, deck: &[&str]) -> Result<(), ConfigError> {
        if self.retired_inputs.is_some() {
            return Err(err(
                "events.inputs",
                "renamed: events.response_function, with the same values (\"spectra\", \"combined\", \"separate\")",
            ));
        }
        if let Some((k, bad)) = self
            .outputs
            .iter()
            .enumerate()
            .find(|(_, n)| !deck.contains(&n.as_str()))
        {
            return Err(err(
                format!("events.outputs[{k}]"),
                format!("{bad:?} is not a deck sensor (one of {})", deck.join(", ")),
            ));
        }
        if !(self.gap_seconds.is_finite() && self.gap_seconds > 0.0) {
            return Err(err(
                "events.gap_seconds",
                format!("must be positive, got {}", self.gap_seconds),
            ));
        }
        if !(self.max_seconds.is_finite() && self.max_seconds > self.gap_seconds) {
            return Err(err(
                "events.max_seconds",
                format!(
                    "must be longer than gap_seconds ({} s), got {}",
                    self.gap_seconds, self.max_seconds
                ),
            ));
        }
        if self.min_events < 2 {
            return Err(err(
                "events.min_events",
                format!("must be at least 2, got {}", self.min_events),
            ));
        }
        if !(self.false_alarm_rate > 0.0 && self.false_alarm_rate < 0.5) {
            return Err(err(
                "events.false_alarm_rate",
                format!("must be in (0, 0.5), got {}", self.false_alarm_rate),
            ));
        }
        if self.realization_order < 2 || self.realization_order % 2 == 1 {
            return Err(err(
                "events.realization_order",
                format!(
                    "must be even and at least 2 (two states per mode), got {}",
                    self.realization_order
                ),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::config::{Config, Residues, ResponseFunction};

    /// `response_function` reads as written; the key it was before,
    /// `inputs`, is refused once, naming the new one.
    #[test]
    fn the_retired_inputs_key_is_refused_naming_response_function() {
        let base = include_str!("../../config/painter-street.toml");
        let with = |line: &str| {
            let header = base.find("\n[events]").expect("the bundled config has [events]") + 1;
            let after = header + base[header..].find('\n').unwrap() + 1;
            let text = format!("{}{line}\n{}", &base[..after], &base[after..]);
            let cfg = Config::from_toml(&text)?;
            cfg.validate().map(|()| cfg)
        };
        let cfg = with("response_function = \"combined\"").unwrap();
        assert_eq!(cfg.events().response_function, ResponseFunction::Combined);
        let refused = with("inputs = \"combined\"").unwrap_err().to_string();
        assert!(
            refused.contains("events.inputs") && refused.contains("events.response_function"),
            "{refused}"
        );
    }

    /// `first_residues` applies to a chain's first update only and, unset,
    /// is `residues`; a value it does not know is refused naming the key.
    #[test]
    fn first_residues_applies_to_the_first_update_only() {
        let base = include_str!("../../config/painter-street.toml");
        let with = |line: &str| {
            let header = base.find("\n[events]").expect("the bundled config has [events]") + 1;
            let after = header + base[header..].find('\n').unwrap() + 1;
            Config::from_toml(&format!("{}{line}\n{}", &base[..after], &base[after..]))
        };
        let unset = with("").unwrap();
        assert_eq!(unset.events().residues_of(true), unset.events().residues);
        let set = with("first_residues = \"both\"").unwrap();
        assert_eq!(set.events().residues_of(true), Residues::Both);
        assert_eq!(set.events().residues_of(false), Residues::Frf);
        let refused = with("first_residues = \"shapes\"").unwrap_err().to_string();
        assert!(refused.contains("first_residues"), "{refused}");
    }
}
