//! The environment in simulated scenarios: air temperature (daily and
//! seasonal cycles, a trend, cold spells, sensor noise) and what it does to
//! the deck (a linear temperature coefficient of the deck's moduli; supports
//! stiffening below a knee, as frozen bearings and asphalt do), plus
//! compact recordings of pre-computed FRFs over many windows, so a test can
//! cover months in seconds.

use super::simulation::Scenario;
use crate::config::{frf_setup, Config, FrfSetup, StiffnessFieldConfig};
use crate::io::frf_json::FrfFile;
use crate::io::wire::{format_timestamp, ChannelBlock, ChannelQuantity};
use anyhow::{bail, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::Deserialize;
use splinewatch_core::frf::FrfRequest;
use splinewatch_core::updating::Parameter;
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

    /// The config the truth is simulated with: a hidden single-coefficient
    /// stiffness field over the deck (not updated) carries the modulus
    /// factor when the deck has a temperature coefficient.
    pub fn truth_config(&self, config: &Config) -> Config {
        let mut truth = config.clone();
        if self.deck_modulus_per_c != 0.0 {
            truth.model.stiffness_fields.push(StiffnessFieldConfig {
                name: MODULUS_FIELD.into(),
                knots_xi: vec![0.0, 1.0],
                degree_xi: 0,
                knots_eta: vec![0.0, 1.0],
                degree_eta: 0,
                scales: "all".into(),
                coefficients: Some(vec![1.0]),
                bounds: None,
                update: false,
            });
        }
        truth
    }

    /// Applies the environment at `temperature` to coefficients of the
    /// truth config (`truth_config`): springs × support factor, the hidden
    /// field (the last) at the modulus factor.
    pub fn apply(&self, temperature: f64, kappa: &mut [Vec<f64>], theta: &mut [Vec<f64>]) {
        let support = self.support_factor(temperature);
        kappa.iter_mut().flatten().for_each(|k| *k *= support);
        if self.deck_modulus_per_c != 0.0 {
            if let Some(last) = theta.last_mut() {
                last[0] = self.modulus_factor(temperature);
            }
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

/// Options of a recording of pre-computed FRFs over many windows.
#[derive(Debug, Clone)]
pub struct FrfWindowOptions {
    pub windows: usize,
    pub window_seconds: f64,
    pub start_ns: i128,
    /// Complex noise, a fraction of each FRF's RMS (as `synth`).
    pub noise: f64,
    /// Frequency lines: the config's FRF band at this step (Hz).
    pub step_hz: f64,
    pub seed: u64,
}

/// What such a recording holds, in time order.
pub enum FrfRecord {
    /// A temperature block.
    Temperature(ChannelBlock),
    /// An FRF message (`<prefix>/<key>`) with its log time (the window's end).
    Frf {
        key: String,
        time_ns: i128,
        payload: Vec<u8>,
    },
}

/// Writes `options.windows` windows: per window the temperature samples
/// and, at its end, one FRF message per force → acceleration pair: the
/// model's FRFs at the window's state (damage from the scenario's changes
/// at the window's middle, the environment at the window's mean air
/// temperature) with complex Gaussian noise, stamped with the window's span.
pub fn simulate_frf_windows(
    config: &Config,
    scenario: &Scenario,
    options: &FrfWindowOptions,
    sink: &mut dyn FnMut(FrfRecord) -> Result<()>,
) -> Result<()> {
    let o = options;
    if !(o.window_seconds.is_finite() && o.window_seconds > 0.0 && o.step_hz > 0.0 && o.noise >= 0.0) {
        bail!("FRF windows: need a positive window length and step, and noise ≥ 0");
    }
    let environment = scenario.environment.clone().unwrap_or_default();
    environment.check()?;
    let parameters = config.build_parameters()?;
    scenario.check(&parameters)?;
    let truth = environment.truth_config(config);
    let setup = frf_setup(&truth)?;
    let (force, accels) = config.channel_roles()?;
    let pairs: Vec<(usize, usize)> = accels.iter().map(|&a| (a, force)).collect();
    let [f0, f1] = config.frf.band;
    let lines: Vec<f64> = (0..)
        .map(|k| f0.max(o.step_hz) + k as f64 * o.step_hz)
        .take_while(|&f| f <= f1 + 1e-9)
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(o.seed);
    for w in 0..o.windows {
        let (start_s, end_s) = (w as f64 * o.window_seconds, (w + 1) as f64 * o.window_seconds);
        for block in environment.temperature_blocks(o.start_ns, start_s, end_s, &mut rng) {
            sink(FrfRecord::Temperature(block))?;
        }
        // The window's mean air temperature (the truth, without sensor noise).
        let mean_t = (0..60)
            .map(|k| environment.temperature_at((start_s + (k as f64 + 0.5) * o.window_seconds / 60.0) / 3600.0))
            .sum::<f64>()
            / 60.0;
        let file = window_frfs(
            &setup,
            scenario,
            &parameters,
            (&environment, mean_t),
            0.5 * (start_s + end_s),
            (&lines, &pairs),
            o.noise,
            &mut rng,
        )?;
        let end_ns = o.start_ns + (end_s * 1e9).round() as i128;
        let start_ns = o.start_ns + (start_s * 1e9).round() as i128;
        for entry in file.frfs {
            let key = format!("frf/{}/{}", entry.input, entry.output);
            let one = FrfFile {
                quantity: file.quantity,
                frequency_hz: file.frequency_hz.clone(),
                frfs: vec![entry],
                start_timestamp: Some(format_timestamp(start_ns)),
                end_timestamp: Some(format_timestamp(end_ns)),
            };
            sink(FrfRecord::Frf {
                key,
                time_ns: end_ns,
                payload: serde_json::to_vec(&one)?,
            })?;
        }
    }
    Ok(())
}

/// The noisy model FRFs of one window.
#[allow(
    clippy::too_many_arguments,
    reason = "one window's state: truth, scenario, environment, time, grid, noise"
)]
fn window_frfs(
    setup: &FrfSetup,
    scenario: &Scenario,
    parameters: &[Parameter],
    (environment, temperature): (&Environment, f64),
    middle_s: f64,
    (lines, pairs): (&[f64], &[(usize, usize)]),
    noise: f64,
    rng: &mut ChaCha8Rng,
) -> Result<FrfFile> {
    let (mut kappa, mut theta) = scenario.coefficients_at(setup, parameters, middle_s);
    environment.apply(temperature, &mut kappa, &mut theta);
    let state = setup.model.modal_state_with_fields(&kappa, &theta, &setup.damping)?;
    let quantity = splinewatch_core::frf::Quantity::Accelerance;
    let eval = setup.model.evaluate(
        &state,
        FrfRequest {
            frequencies_hz: lines,
            pairs,
            quantity,
        },
        false,
    );
    let frfs = super::synth::noisy_entries(&setup.sensor_names, &eval.h, lines.len(), pairs, noise, rng);
    Ok(FrfFile {
        quantity,
        frequency_hz: lines.to_vec(),
        frfs,
        start_timestamp: None,
        end_timestamp: None,
    })
}
