//! The environment in simulated scenarios: air temperature (daily and
//! seasonal cycles, a trend, cold spells, sensor noise) and what it does to
//! the deck (a linear temperature coefficient of the deck's moduli; supports
//! stiffening below a knee, as frozen bearings and asphalt do).

use crate::config::{Config, StiffnessFieldConfig};
use crate::io::wire::{ChannelBlock, ChannelQuantity};
use anyhow::{bail, Result};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::Deserialize;
use std::f64::consts::PI;

/// Name of the hidden single-coefficient stiffness field that carries the
/// deck's temperature coefficient in the simulated truth.
pub const MODULUS_FIELD: &str = "environment_modulus";

/// `[environment]` of a scenario (TOML); temperatures in °C, times in
/// hours from the scenario's start.
/// ```toml
/// [environment]
/// channels = ["T1"]
/// mean_c = 6.0
/// daily_amplitude_c = 8.0       # peak at daily_peak_hour (of the start's day)
/// trend_c_per_day = 0.5
/// deck_modulus_per_c = -0.004   # relative, about reference_c
/// support_stiffening_per_c = 0.05  # relative, per °C below knee_c
/// [[environment.cold_spell]]
/// start_hour = 40.0
/// end_hour = 70.0
/// offset_c = -12.0
/// ```
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Environment {
    /// Temperature channels (`<prefix>/temperature/<name>`), each the air
    /// temperature plus its own noise.
    pub channels: Vec<String>,
    pub mean_c: f64,
    pub daily_amplitude_c: f64,
    pub daily_peak_hour: f64,
    /// A yearly cycle: amplitude and the day of its peak (from the start).
    pub seasonal_amplitude_c: f64,
    pub seasonal_peak_day: f64,
    pub trend_c_per_day: f64,
    /// Sensor noise, standard deviation.
    pub noise_c: f64,
    /// Seconds between temperature samples.
    pub sample_seconds: f64,
    #[serde(rename = "cold_spell")]
    pub cold_spells: Vec<ColdSpell>,
    /// Relative change of the deck's moduli per °C above `reference_c`.
    pub deck_modulus_per_c: f64,
    pub reference_c: f64,
    /// Relative stiffening of every support spring per °C below `knee_c`.
    pub support_stiffening_per_c: f64,
    pub knee_c: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColdSpell {
    pub start_hour: f64,
    pub end_hour: f64,
    pub offset_c: f64,
}

impl Default for Environment {
    fn default() -> Self {
        Self {
            channels: vec!["T1".into()],
            mean_c: 10.0,
            daily_amplitude_c: 0.0,
            daily_peak_hour: 15.0,
            seasonal_amplitude_c: 0.0,
            seasonal_peak_day: 200.0,
            trend_c_per_day: 0.0,
            noise_c: 0.1,
            sample_seconds: 60.0,
            cold_spells: Vec::new(),
            deck_modulus_per_c: 0.0,
            reference_c: 10.0,
            support_stiffening_per_c: 0.0,
            knee_c: 0.0,
        }
    }
}

impl Environment {
    pub fn check(&self) -> Result<()> {
        if self.channels.is_empty() {
            bail!("scenario: environment.channels must name at least one temperature channel");
        }
        if !(self.sample_seconds.is_finite() && self.sample_seconds > 0.0) {
            bail!("scenario: environment.sample_seconds must be positive");
        }
        if self.deck_modulus_per_c.abs() * 60.0 >= 1.0 {
            bail!("scenario: environment.deck_modulus_per_c is too large (the modulus would vanish within 60 °C)");
        }
        Ok(())
    }

    /// Air temperature `hours` after the start (no sensor noise).
    pub fn temperature_at(&self, hours: f64) -> f64 {
        let daily = self.daily_amplitude_c * (2.0 * PI * (hours - self.daily_peak_hour + 6.0) / 24.0).sin();
        let days = hours / 24.0;
        let seasonal = self.seasonal_amplitude_c * (2.0 * PI * (days - self.seasonal_peak_day) / 365.25).cos();
        let spells: f64 = self
            .cold_spells
            .iter()
            .filter(|s| (s.start_hour..s.end_hour).contains(&hours))
            .map(|s| s.offset_c)
            .sum();
        self.mean_c + daily + seasonal + self.trend_c_per_day * days + spells
    }

    /// Multiplier of the deck's moduli at `temperature`.
    pub fn modulus_factor(&self, temperature: f64) -> f64 {
        1.0 + self.deck_modulus_per_c * (temperature - self.reference_c)
    }

    /// Multiplier of every support spring at `temperature`.
    pub fn support_factor(&self, temperature: f64) -> f64 {
        1.0 + self.support_stiffening_per_c * (self.knee_c - temperature).max(0.0)
    }

    /// The config the truth is simulated with: hidden single-coefficient
    /// stiffness fields (not updated) carry the modulus factor when the deck
    /// has a temperature coefficient, one over the deck (`environment_modulus`)
    /// or one per patch of a deck of several (`environment_modulus.<patch>`).
    pub fn truth_config(&self, config: &Config) -> Config {
        let mut truth = config.clone();
        if self.deck_modulus_per_c != 0.0 {
            let patches: Vec<Option<String>> = match config.model.patches.as_slice() {
                [] => vec![None],
                patches => patches.iter().map(|p| Some(p.name.clone())).collect(),
            };
            let several = patches.len() > 1;
            truth
                .model
                .stiffness_fields
                .extend(patches.into_iter().map(|patch| StiffnessFieldConfig {
                    name: match (&patch, several) {
                        (Some(name), true) => format!("{MODULUS_FIELD}.{name}"),
                        _ => MODULUS_FIELD.into(),
                    },
                    patch,
                    knots_xi: vec![0.0, 1.0],
                    degree_xi: 0,
                    knots_eta: vec![0.0, 1.0],
                    degree_eta: 0,
                    scales: "all".into(),
                    coefficients: Some(vec![1.0]),
                    bounds: None,
                    update: false,
                    tie: None,
                    loss_factor: None,
                }));
        }
        truth
    }

    /// How many hidden fields `truth_config` appends to `config`'s.
    pub fn hidden_fields(&self, config: &Config) -> usize {
        if self.deck_modulus_per_c == 0.0 {
            0
        } else {
            config.model.patches.len().max(1)
        }
    }

    /// Applies the environment at `temperature` to coefficients of the
    /// truth config (`truth_config`): springs × support factor, the hidden
    /// fields (the last `hidden`, from `hidden_fields`) at the modulus factor.
    pub fn apply(&self, temperature: f64, hidden: usize, kappa: &mut [Vec<f64>], theta: &mut [Vec<f64>]) {
        let support = self.support_factor(temperature);
        kappa.iter_mut().flatten().for_each(|k| *k *= support);
        let first_hidden = theta.len().saturating_sub(hidden);
        for field in &mut theta[first_hidden..] {
            field[0] = self.modulus_factor(temperature);
        }
    }

    /// One block per channel of the samples in `[start_s, end_s)` after the
    /// scenario's start (`start_ns`), at `sample_seconds`, with sensor noise.
    pub fn temperature_blocks(
        &self,
        start_ns: i128,
        start_s: f64,
        end_s: f64,
        rng: &mut ChaCha8Rng,
    ) -> Vec<ChannelBlock> {
        let dt = self.sample_seconds;
        let first = (start_s / dt).ceil() as i64;
        let count = ((end_s / dt).ceil() as i64 - first).max(0) as usize;
        if count == 0 {
            return Vec::new();
        }
        self.channels
            .iter()
            .map(|name| ChannelBlock {
                name: name.clone(),
                quantity: ChannelQuantity::Temperature,
                unit: ChannelQuantity::Temperature.unit().into(),
                fs: 1.0 / dt,
                start_ns: start_ns + ((first as f64 * dt) * 1e9).round() as i128,
                data: (0..count)
                    .map(|k| {
                        let t = (first + k as i64) as f64 * dt;
                        let noise: f64 = rng.sample(StandardNormal);
                        self.temperature_at(t / 3600.0) + self.noise_c * noise
                    })
                    .collect(),
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::frf_setup;

    /// The lowest flexible frequencies (Hz) of `config` with spring and
    /// bearing coefficients scaled by `support` and the stiffness fields at
    /// `theta`.
    fn frequencies(config: &Config, support: f64, theta: Option<f64>) -> Vec<f64> {
        let setup = frf_setup(config).unwrap();
        let kappa: Vec<Vec<f64>> = setup
            .kappa
            .iter()
            .map(|k| k.iter().map(|v| v * support).collect())
            .collect();
        let mut fields = setup.model.field_coefficients().to_vec();
        if let Some(factor) = theta {
            fields.iter_mut().flatten().for_each(|t| *t = factor);
        }
        let state = setup
            .model
            .modal_state_with_fields(&kappa, &fields, &setup.damping)
            .unwrap();
        state
            .modes
            .omega2
            .iter()
            .take(10)
            .map(|w2| w2.sqrt() / (2.0 * PI))
            .collect()
    }

    /// A deck of several patches gets one hidden modulus field per patch;
    /// with the modulus and the supports scaled alike every stiffness of
    /// the model is scaled, so every frequency moves by the square root of
    /// the factor. The joints' penalty is not scaled with the patches (it
    /// is fixed at assembly), so the check holds to the coupling error.
    #[test]
    fn every_patch_of_a_deck_of_several_carries_the_modulus_factor() {
        let config = Config::from_toml(include_str!("../../tests/fixtures/slab_on_webs.toml")).unwrap();
        let environment = Environment {
            deck_modulus_per_c: -0.004,
            reference_c: 10.0,
            support_stiffening_per_c: 0.004,
            knee_c: 10.0,
            ..Environment::default()
        };
        let truth = environment.truth_config(&config);
        let hidden = environment.hidden_fields(&config);
        assert_eq!(hidden, 3);
        let names: Vec<&str> = truth.model.stiffness_fields.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "environment_modulus.slab",
                "environment_modulus.web_south",
                "environment_modulus.web_north"
            ]
        );
        // At 0 °C both factors are 1.04.
        let factor = environment.modulus_factor(0.0);
        assert!((factor - 1.04).abs() < 1e-12 && (environment.support_factor(0.0) - factor).abs() < 1e-12);
        let setup = frf_setup(&truth).unwrap();
        let (mut kappa, mut theta) = (setup.kappa.clone(), setup.model.field_coefficients().to_vec());
        environment.apply(0.0, hidden, &mut kappa, &mut theta);
        assert_eq!(theta, vec![vec![factor]; 3]);
        let reference = frequencies(&truth, 1.0, None);
        let cold = frequencies(&truth, factor, Some(factor));
        for (f0, f1) in reference.iter().zip(&cold) {
            let scale = f1 / f0;
            assert!(
                (scale / factor.sqrt() - 1.0).abs() < 1e-5,
                "{f0:.4} Hz -> {f1:.4} Hz: {scale} against {}",
                factor.sqrt()
            );
        }
        // A single-patch deck keeps its one field, named as before.
        let single = Config::from_toml(include_str!("../../config/sinello.toml")).unwrap();
        let truth = environment.truth_config(&single);
        assert_eq!(environment.hidden_fields(&single), 1);
        assert_eq!(truth.model.stiffness_fields.last().unwrap().name, MODULUS_FIELD);
        assert_eq!(truth.model.stiffness_fields.last().unwrap().patch, None);
    }
}
