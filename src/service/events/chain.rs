//! What carries from one event to the next.

use super::realization::SavedRealization;
use super::*;

/// What carries from one event to the next (and across runs, `--state`).
#[derive(Debug, Default, Serialize, Deserialize)]
pub struct Chain {
    /// The last update's values (`predict --state` reads this list).
    pub(super) parameters: Vec<NamedValue>,
    /// The modes tracked from event to event: the first event's identified frequencies.
    pub(super) tracked_hz: Vec<f64>,
    /// log10 of each earlier (not alarmed) event's amplitude, m/s².
    pub(super) amplitudes: Vec<f64>,
    /// What `amplitudes` measure (`[events] amplitude`); none in a state
    /// from before the key, whose amplitudes are ground peaks.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) amplitude: Option<EventAmplitude>,
    /// The features' names: the columns of `features`.
    #[serde(default)]
    pub(super) feature_names: Vec<String>,
    /// Their features, one row per event, by `feature_names`.
    pub(super) features: Vec<Vec<Option<f64>>>,
    /// Events this chain has seen, judged or skipped: the next event's
    /// [`EventLine::number`]. A state from before the field counts its
    /// judged events.
    #[serde(default)]
    pub(super) events_seen: u64,
    /// Without a model: the last realization identified, which forecasts
    /// the next event.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) realization: Option<SavedRealization>,
    /// The config's model, assembled for the first event and kept for the
    /// others (not saved).
    #[serde(skip)]
    pub(super) parts: Option<Arc<GroundParts>>,
    /// The FRF model of the same config built elsewhere (the daemon's
    /// pipeline's), which the parts share (not saved).
    #[serde(skip)]
    pub(super) frf_model: Option<Arc<crate::config::FrfSetup>>,
}

impl Chain {
    /// The chain saved at `path` (`--state`, the daemon's events file), or
    /// a new one when there is no file yet.
    pub fn resume(path: Option<&Path>) -> Result<Self> {
        match path {
            Some(p) if p.exists() => {
                let text = std::fs::read_to_string(p).with_context(|| format!("cannot read {}", p.display()))?;
                let mut chain: Self = serde_json::from_str(&text)
                    .with_context(|| format!("{}: not an events state file", p.display()))?;
                if chain.events_seen == 0 {
                    chain.events_seen = chain.features.len() as u64;
                }
                Ok(chain)
            }
            _ => Ok(Self::default()),
        }
    }

    pub fn save(&self, path: &Path) -> Result<()> {
        std::fs::write(path, serde_json::to_string_pretty(self)?)
            .with_context(|| format!("cannot write {}", path.display()))
    }

    /// Refuses a history whose amplitudes are not what `[events]
    /// amplitude` measures (the bands would mix two variables).
    pub fn check(&self, cfg: &Config) -> Result<()> {
        let kept = self.amplitude.unwrap_or(EventAmplitude::PgaGround);
        let wanted = cfg.events().amplitude;
        if !self.amplitudes.is_empty() && kept != wanted {
            bail!(
                "the events' state holds {} events judged on {}; [events] amplitude = {:?}: \
                 start a new state (another --state file) or set amplitude = {:?}",
                self.amplitudes.len(),
                kept.as_str(),
                wanted.as_str(),
                kept.as_str()
            );
        }
        Ok(())
    }

    /// Events judged so far (not alarmed): the verdict's history.
    pub fn history_len(&self) -> usize {
        self.amplitudes.len()
    }

    /// The config's model parts, assembled on first use.
    /// The ground inputs of the events: the model's (built once, see
    /// [`Chain::parts`]), or, for a config without a model, the support
    /// groups its ground sensors name.
    pub fn plan(&mut self, cfg: &Config) -> Result<Vec<GroundInputPlan>> {
        if cfg.has_model() {
            Ok(self.parts(cfg)?.plan.clone())
        } else {
            Ok(cfg.ground_plan_of_sensors()?)
        }
    }

    /// Shares `setup`, the FRF model the daemon's pipeline built from the
    /// same config, with the parts assembled for the first event.
    pub fn share_frf_model(&mut self, setup: Arc<crate::config::FrfSetup>) {
        self.frf_model = Some(setup);
    }

    pub fn parts(&mut self, cfg: &Config) -> Result<Arc<GroundParts>> {
        if let Some(parts) = &self.parts {
            return Ok(Arc::clone(parts));
        }
        let parts = Arc::new(GroundParts::sharing(cfg, self.frf_model.clone()).context("the config's model")?);
        self.parts = Some(Arc::clone(&parts));
        Ok(parts)
    }

    /// The last update's values (none before the first update).
    pub(super) fn named(&self) -> &[NamedValue] {
        &self.parameters
    }

    /// The earlier events' `(log10 amplitude, value)` of feature `name` (NaN
    /// where an event did not measure it).
    pub(super) fn history_of(&self, name: &str) -> Vec<(f64, f64)> {
        let column = self.feature_names.iter().position(|n| n == name);
        self.amplitudes
            .iter()
            .zip(&self.features)
            .map(|(&x, row)| {
                (
                    x,
                    column.and_then(|c| row.get(c).copied().flatten()).unwrap_or(f64::NAN),
                )
            })
            .collect()
    }

    /// Appends an event's features, the earlier rows put on `names` when
    /// they are new (the modes tracked once an event first has some).
    pub(super) fn push_features(&mut self, x: f64, names: &[String], values: Vec<Option<f64>>) {
        if self.feature_names != names {
            // A state file from before the names were kept has rows in the
            // order of the names then: taken as they are.
            if !self.feature_names.is_empty() {
                let old = std::mem::take(&mut self.feature_names);
                for row in &mut self.features {
                    *row = names
                        .iter()
                        .map(|n| {
                            old.iter()
                                .position(|o| o == n)
                                .and_then(|c| row.get(c).copied().flatten())
                        })
                        .collect();
                }
            }
            self.feature_names = names.to_vec();
        }
        self.amplitudes.push(x);
        self.features.push(values);
    }

    /// The parameters an event of `amplitude` (`[events] amplitude`) is forecast by
    /// (`[events] forecast`): the last update's, or per parameter the
    /// value the earlier events expect at `amplitude` (the line of log10 value
    /// against log10 amplitude the verdict fits, once there are `min_events`
    /// of them; their geometric mean before; the last value when no
    /// earlier event gave it with a std).
    pub(super) fn forecast_parameters(
        &self,
        forecast: EventForecast,
        min_events: usize,
        amplitude: f64,
    ) -> Vec<NamedValue> {
        let last = self.named().to_vec();
        if forecast == EventForecast::Last {
            return last;
        }
        let x = amplitude.max(1e-12).log10();
        last.into_iter()
            .map(|NamedValue { name, value }| {
                let history = self.history_of(&feature_of_parameter(&name));
                let value = expected(&history, x, min_events).map_or(value, |y| 10f64.powf(y));
                NamedValue { name, value }
            })
            .collect()
    }
}

/// The feature judged for updated parameter `name`.
pub(super) fn feature_of_parameter(name: &str) -> String {
    format!("log10_{name}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chain_shares_the_frf_model_it_is_given() {
        let cfg = Config::from_toml(include_str!("../../../config/painter-street.toml")).unwrap();
        let setup = Arc::new(crate::config::frf_setup(&cfg).unwrap());
        let mut chain = Chain::default();
        chain.share_frf_model(Arc::clone(&setup));
        let parts = chain.parts(&cfg).unwrap();
        assert!(Arc::ptr_eq(&parts.setup, &setup), "shared, not built again");
        assert!(Arc::ptr_eq(&chain.parts(&cfg).unwrap(), &parts), "assembled once");
        // Without one, the chain builds its own of the same config.
        let own = Chain::default().parts(&cfg).unwrap();
        assert!(!Arc::ptr_eq(&own.setup, &setup));
        assert_eq!(own.setup.sensor_names, setup.sensor_names);
        assert_eq!(own.setup.kappa, setup.kappa);
    }
}
