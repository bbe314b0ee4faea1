//! `[oma.frequency_domain]`: the modes of a record with measured inputs
//! fitted to its H1 transmissibilities (a pole–residue fit), beside SRIM's.

use super::{err, Config, ConfigError};
use serde::{Deserialize, Serialize};

/// The most modes one band is fitted with.
pub const MAX_FITTED_MODES: usize = 4;

/// `[oma.frequency_domain]`: which functions are fitted, over which band,
/// with how many modes. A band that holds the modes sought and little else
/// (a heavily damped mode, or two close ones) is what it is for.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FrequencyDomainConfig {
    /// The band fitted (Hz); the modes found at its edges are not reported.
    pub band: [f64; 2],
    /// Modes fitted in the band (1 to 4).
    #[serde(default = "one_mode")]
    pub modes: usize,
    /// The input sensors (ground or force sensors) by name; empty: every
    /// one the record holds.
    #[serde(default)]
    pub inputs: Vec<String>,
    /// The output sensors (deck acceleration sensors) by name; empty: every
    /// one the record holds.
    #[serde(default)]
    pub outputs: Vec<String>,
}

fn one_mode() -> usize {
    1
}

/// [`FrequencyDomainConfig`] checked, its sensors as indices into
/// `[[sensors]]`.
#[derive(Debug, Clone, PartialEq)]
pub struct FrequencyDomainPlan {
    pub band: [f64; 2],
    pub modes: usize,
    /// Empty: every input the record holds.
    pub inputs: Vec<usize>,
    /// Empty: every output the record holds.
    pub outputs: Vec<usize>,
}

impl Config {
    /// `[oma.frequency_domain]`, checked: `None` when absent.
    pub fn frequency_domain(&self) -> Result<Option<FrequencyDomainPlan>, ConfigError> {
        let Some(fd) = self.oma_section.as_ref().and_then(|o| o.frequency_domain.as_ref()) else {
            return Ok(None);
        };
        let [low, high] = fd.band;
        if !(low.is_finite() && high.is_finite() && low > 0.0 && high > low) {
            return Err(err(
                "oma.frequency_domain.band",
                format!("must be [low, high] with 0 < low < high (Hz), got [{low}, {high}]"),
            ));
        }
        if !(1..=MAX_FITTED_MODES).contains(&fd.modes) {
            return Err(err(
                "oma.frequency_domain.modes",
                format!("must be 1 to {MAX_FITTED_MODES}, got {}", fd.modes),
            ));
        }
        let deck = self.deck_sensor_count();
        let is_force = |i: usize| self.sensors[i].quantity.as_slice().iter().any(|q| q == "force");
        let find = |name: &str| self.sensors.iter().position(|s| s.name == name);
        let inputs = fd
            .inputs
            .iter()
            .map(|name| match find(name) {
                Some(i) if i >= deck || is_force(i) => Ok(i),
                Some(_) => Err(err(
                    "oma.frequency_domain.inputs",
                    format!("{name:?} is neither a ground sensor (with `support`) nor a force sensor"),
                )),
                None => Err(err("oma.frequency_domain.inputs", format!("{name:?} is not a sensor"))),
            })
            .collect::<Result<Vec<_>, _>>()?;
        let candidates = self.output_channels()?;
        let outputs = fd
            .outputs
            .iter()
            .map(|name| {
                find(name).filter(|i| candidates.contains(i)).ok_or_else(|| {
                    err(
                        "oma.frequency_domain.outputs",
                        format!("{name:?} is not a deck acceleration sensor"),
                    )
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Some(FrequencyDomainPlan {
            band: fd.band,
            modes: fd.modes,
            inputs,
            outputs,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bundled station config's section reads as written; each wrong
    /// key is refused naming it.
    #[test]
    fn the_section_is_checked_by_key() {
        let base = include_str!("../../config/painter-street.toml");
        let with = |section: &str| {
            let cfg = Config::from_toml(&format!("{base}\n[oma.frequency_domain]\n{section}\n"))?;
            cfg.validate().map(|()| cfg)
        };
        let plan = with("band = [2.0, 7.0]\ninputs = [\"ch3\"]\noutputs = [\"ch7\", \"ch4\"]")
            .unwrap()
            .frequency_domain()
            .unwrap()
            .unwrap();
        assert_eq!(
            (plan.band, plan.modes, plan.inputs.len(), plan.outputs.len()),
            ([2.0, 7.0], 1, 1, 2)
        );
        for (section, key) in [
            ("band = [7.0, 2.0]", "oma.frequency_domain.band"),
            ("band = [1.0, 7.0]\nmodes = 0", "oma.frequency_domain.modes"),
            ("band = [1.0, 7.0]\ninputs = [\"ch7\"]", "oma.frequency_domain.inputs"),
            ("band = [1.0, 7.0]\ninputs = [\"ch99\"]", "oma.frequency_domain.inputs"),
            ("band = [1.0, 7.0]\noutputs = [\"ch3\"]", "oma.frequency_domain.outputs"),
        ] {
            let e = with(section).unwrap_err().to_string();
            assert!(e.contains(key), "{section}: {e}");
        }
        let e = with("modes = 1").unwrap_err().to_string();
        assert!(e.contains("band"), "{e}");
    }
}
