//! `splinewatch simulate`: synthetic bridge-logger data from the FE model.
//!
//! The force acts at the config's force sensor; accelerations are computed
//! at every acceleration sensor by the core's exact modal recursion at
//! `oversample × fs` (first-order hold) and decimated, so the hold's
//! `sinc²` loss stays below 0.2 % at 80 Hz. Measurement noise is Gaussian
//! with a standard deviation that is a fraction of each channel's RMS. A
//! scenario changes updating parameters over time; the modal model is
//! re-solved every `update_seconds` and the physical state carried over.

use super::excitation::{self, SourceOptions, UnmeasuredSources};
use crate::config::{frf_setup, frf_setup_with_points, Config, FrfSetup};
use crate::io::wire::{ChannelBlock, ChannelQuantity};
use anyhow::{bail, Context, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::Deserialize;
use splinewatch_core::response::simulate::{hammer_impacts, swept_sine, ModalSimulator};
use splinewatch_core::updating::{Parameter, ParameterKind};

pub use super::excitation::Excitation;

/// A time-varying scenario (TOML):
/// ```toml
/// update_seconds = 10.0
/// [[change]]
/// parameter = "east.k2"    # an updating parameter name
/// start_minute = 30.0
/// end_minute = 40.0
/// factor = 0.6              # value × factor after end_minute, linear in between
/// repair_minute = 90.0      # optional: back to the value from then on (a repair)
/// ```
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    #[serde(default = "default_update_seconds")]
    pub update_seconds: f64,
    #[serde(default, rename = "change")]
    pub changes: Vec<Change>,
    /// Temperature and its effects on the deck (`[environment]`).
    #[serde(default)]
    pub environment: Option<super::environment::Environment>,
}

/// No change: the model stays at the config's values.
impl Default for Scenario {
    fn default() -> Self {
        Self {
            update_seconds: default_update_seconds(),
            changes: Vec::new(),
            environment: None,
        }
    }
}

fn default_update_seconds() -> f64 {
    10.0
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Change {
    pub parameter: String,
    pub start_minute: f64,
    pub end_minute: f64,
    pub factor: f64,
    /// From this minute on the value is back (a bearing replaced, a repair):
    /// a temporary change, whose alarm should clear.
    #[serde(default)]
    pub repair_minute: Option<f64>,
}

impl Change {
    /// Multiplier at time `t` seconds.
    pub fn factor_at(&self, t: f64) -> f64 {
        let (a, b) = (self.start_minute * 60.0, self.end_minute * 60.0);
        let repaired = self.repair_minute.is_some_and(|r| t >= r * 60.0);
        if repaired || t <= a {
            1.0
        } else if t >= b {
            self.factor
        } else {
            1.0 + (self.factor - 1.0) * (t - a) / (b - a)
        }
    }
}

#[derive(Debug, Clone)]
pub struct SimulationOptions {
    pub duration_seconds: f64,
    pub fs: f64,
    pub seed: u64,
    pub excitation: Excitation,
    /// RMS of the random force (N); peak of sweeps and impacts is √2 times this.
    pub force_rms: f64,
    /// Measurement noise, fraction of each channel's RMS.
    pub noise: f64,
    pub block_seconds: f64,
    pub start_ns: i128,
    pub band: (f64, f64),
    pub oversample: usize,
    pub scenario: Option<Scenario>,
    /// Ambient: number of random source points (ignored with `source_xy`).
    pub sources: usize,
    /// Ambient: source points (x, y) in metres.
    pub source_xy: Vec<(f64, f64)>,
    /// Traffic: crossing speed and arrival rate over both lanes.
    pub speed_kmh: f64,
    pub vehicles_per_minute: f64,
}

impl SimulationOptions {
    /// The usual test and demo run: band-limited random force (1 kN RMS) over
    /// the config's FRF band + 10 %, 2 % noise, 256 Hz, one-second blocks,
    /// starting 2026-11-21T10:00:00Z, no scenario.
    pub fn random_excitation(config: &Config, duration_seconds: f64, seed: u64) -> Self {
        Self {
            duration_seconds,
            fs: 256.0,
            seed,
            excitation: Excitation::Random,
            force_rms: 1000.0,
            noise: 0.02,
            block_seconds: 1.0,
            start_ns: 1_795_255_200_000_000_000,
            band: (config.frf.band[0].max(0.1), config.frf.band[1] * 1.1),
            oversample: 16,
            scenario: None,
            sources: 4,
            source_xy: Vec::new(),
            speed_kmh: 60.0,
            vehicles_per_minute: 12.0,
        }
    }

    /// [`Self::random_excitation`] with ambient forces at four random points
    /// (1 kN RMS each) instead of the measured force.
    pub fn ambient_excitation(config: &Config, duration_seconds: f64, seed: u64) -> Self {
        Self {
            excitation: Excitation::Ambient,
            oversample: 4,
            ..Self::random_excitation(config, duration_seconds, seed)
        }
    }
}

/// What the simulation produced.
#[derive(Debug, Clone, Default)]
pub struct SimulationSummary {
    pub blocks: usize,
    pub samples_per_channel: usize,
    pub model_updates: usize,
}

/// Runs the simulation, handing every block to `sink` in time order (force
/// first when it is measured, then accelerations, per block interval).
pub fn simulate(
    config: &Config,
    options: &SimulationOptions,
    sink: &mut dyn FnMut(ChannelBlock) -> Result<()>,
) -> Result<SimulationSummary> {
    let o = options;
    let block_len = o.block_length()?;
    let total = (o.duration_seconds * o.fs).round() as usize;
    let mut rng = ChaCha8Rng::seed_from_u64(o.seed);
    let scenario = o.scenario.clone().unwrap_or_default();
    let environment = scenario.environment.clone();
    if let Some(e) = &environment {
        e.check()?;
    }
    let truth = environment.as_ref().map(|e| e.truth_config(config));
    let hidden = environment.as_ref().map_or(0, |e| e.hidden_fields(config));
    let (mut forcing, setup, accel_sensors) = Forcing::new(truth.as_ref().unwrap_or(config), o, &mut rng)?;
    let parameters = config.build_parameters()?;
    scenario.check(&parameters)?;
    let state_at = |t: f64| {
        let (mut k, mut theta) = scenario.coefficients_at(&setup, &parameters, t);
        if let Some(e) = &environment {
            e.apply(e.temperature_at(t / 3600.0), hidden, &mut k, &mut theta);
        }
        setup.model.modal_state_with_fields(&k, &theta, &setup.damping)
    };
    // Temperature samples come from their own stream, so the forces and
    // noise do not depend on the environment's sampling.
    let mut temperature_rng = ChaCha8Rng::seed_from_u64(o.seed ^ 0x7e3a_0001);
    let update_blocks = ((scenario.update_seconds / o.block_seconds).round() as usize).max(1);
    let dt = 1.0 / (o.fs * o.oversample as f64);
    // The accelerations are formed for the sensors written only, not for
    // the unmeasured sources' points after them (a traffic lane has 33):
    // the outputs cost modes × sensors a sample.
    let sensors = accel_sensors.iter().max().map_or(0, |&s| s + 1);
    let mut state = state_at(0.0)?;
    let mut sim = ModalSimulator::with_inputs(&state, sensors, &forcing.inputs, dt);
    let names: Vec<String> = config.sensors.iter().map(|s| s.name.clone()).collect();
    let mut noise_std: Option<Vec<f64>> = None;
    let mut summary = SimulationSummary::default();
    let mut produced = 0;
    let mut block_index = 0;
    while produced < total {
        let n = block_len.min(total - produced);
        let t0 = produced as f64 / o.fs;
        if let Some(e) = &environment {
            for block in e.temperature_blocks(o.start_ns, t0, t0 + n as f64 / o.fs, &mut temperature_rng) {
                sink(block)?;
            }
        }
        let changing = !scenario.changes.is_empty() || environment.is_some();
        if block_index > 0 && block_index % update_blocks == 0 && changing {
            let (x, v) = sim.physical_state(&state);
            let last = sim.last_forces().to_vec();
            state = state_at(t0)?;
            sim = ModalSimulator::with_inputs(&state, sensors, &forcing.inputs, dt);
            sim.set_physical_state(&state, &setup.model.mass_times(&x), &setup.model.mass_times(&v));
            sim.set_last_forces(&last);
            summary.model_updates += 1;
        }
        let (mut f_block, mut a_block) = forcing.sample_block(n, o.oversample, &mut sim, &mut rng, &accel_sensors);
        // Noise level fixed from the first block's clean RMS.
        let stds = noise_std.get_or_insert_with(|| noise_levels(o.noise, f_block.as_deref(), &a_block));
        let start_ns = o.start_ns + (t0 * 1e9).round() as i128;
        let block = |name: usize, quantity: ChannelQuantity, data: Vec<f64>| ChannelBlock {
            name: names[name].clone(),
            quantity,
            unit: quantity.unit().into(),
            fs: o.fs,
            start_ns,
            data,
        };
        let mut noise = stds.iter();
        if let (Some(data), Some(sensor)) = (f_block.as_mut(), forcing.measured_at) {
            add_noise(data, *noise.next().expect("one level per channel"), &mut rng);
            sink(block(sensor, ChannelQuantity::Force, std::mem::take(data)))?;
            summary.blocks += 1;
        }
        for (data, &s) in a_block.iter_mut().zip(&accel_sensors) {
            add_noise(data, *noise.next().expect("one level per channel"), &mut rng);
            sink(block(s, ChannelQuantity::Acceleration, std::mem::take(data)))?;
        }
        summary.blocks += accel_sensors.len();
        produced += n;
        block_index += 1;
    }
    summary.samples_per_channel = produced;
    Ok(summary)
}

/// Where the forces act and what generates them.
struct Forcing {
    /// Indices into the model's sensor list (configured sensors, then the
    /// unmeasured source points).
    inputs: Vec<usize>,
    /// The configured force sensor when the force is recorded.
    measured_at: Option<usize>,
    source: Source,
}

enum Source {
    Measured(ForceSource),
    Unmeasured(UnmeasuredSources),
}

impl Forcing {
    /// The forcing, the model (with the source points appended) and the
    /// recorded acceleration sensors.
    fn new(config: &Config, o: &SimulationOptions, rng: &mut ChaCha8Rng) -> Result<(Self, FrfSetup, Vec<usize>)> {
        if !o.excitation.is_unmeasured() {
            let (force_sensor, accel_sensors) = config.channel_roles()?;
            let forcing = Self {
                inputs: vec![force_sensor],
                measured_at: Some(force_sensor),
                source: Source::Measured(ForceSource::new(o)),
            };
            return Ok((forcing, frf_setup(config)?, accel_sensors));
        }
        let accel_sensors = config.output_channels()?;
        let model = config.build_model()?;
        let surfaces: Vec<_> = model.patches.iter().map(|p| p.shell.surface()).collect();
        let sources = SourceOptions {
            excitation: o.excitation,
            fs_sim: o.fs * o.oversample as f64,
            band: o.band,
            force_rms: o.force_rms,
            sources: o.sources,
            source_xy: o.source_xy.clone(),
            speed_kmh: o.speed_kmh,
            vehicles_per_minute: o.vehicles_per_minute,
        };
        let layout = excitation::source_points(&sources, config, &surfaces, rng)?;
        let points = &layout.points;
        let setup = frf_setup_with_points(config, points)?;
        let first = config.deck_sensor_count();
        let forcing = Self {
            inputs: (first..first + points.len()).collect(),
            measured_at: None,
            source: Source::Unmeasured(UnmeasuredSources::new(&sources, &layout, rng)?),
        };
        Ok((forcing, setup, accel_sensors))
    }

    /// `n` samples of the recorded force (if measured) and of every
    /// acceleration sensor: the modal recursion stepped `oversample` times
    /// per sample (the forces drawn at the simulation rate), the last step kept.
    fn sample_block(
        &mut self,
        n: usize,
        oversample: usize,
        sim: &mut ModalSimulator,
        rng: &mut ChaCha8Rng,
        accel_sensors: &[usize],
    ) -> (Option<Vec<f64>>, Vec<Vec<f64>>) {
        let mut f_block = self.measured_at.is_some().then(|| Vec::with_capacity(n));
        let mut a_block: Vec<Vec<f64>> = accel_sensors.iter().map(|_| Vec::with_capacity(n)).collect();
        let mut forces = vec![0.0; self.inputs.len()];
        let mut acc = vec![0.0; sim.sensor_count()];
        for _ in 0..n {
            for _ in 0..oversample {
                match &mut self.source {
                    Source::Measured(source) => forces[0] = source.next(rng),
                    Source::Unmeasured(sources) => sources.next(rng, &mut forces),
                }
                sim.advance(&forces);
            }
            sim.accelerations(&mut acc);
            if let Some(f) = f_block.as_mut() {
                f.push(forces[0]);
            }
            for (c, &s) in accel_sensors.iter().enumerate() {
                a_block[c].push(acc[s]);
            }
        }
        (f_block, a_block)
    }
}

impl SimulationOptions {
    /// Checks the options; returns the samples per block.
    fn block_length(&self) -> Result<usize> {
        let o = self;
        if !(o.fs.is_finite() && o.fs > 0.0 && o.duration_seconds.is_finite() && o.duration_seconds > 0.0) {
            bail!("--fs and --duration must be positive");
        }
        if !(o.block_seconds.is_finite() && o.block_seconds > 0.0) {
            bail!("block length must be positive");
        }
        if !(o.noise.is_finite() && o.noise >= 0.0 && o.force_rms.is_finite() && o.force_rms > 0.0) {
            bail!("--noise must be >= 0 and --force-rms > 0");
        }
        if o.band.1 >= o.fs / 2.0 {
            bail!(
                "the excitation band must stay below Nyquist ({} Hz at fs = {} Hz)",
                o.fs / 2.0,
                o.fs
            );
        }
        let block_len = (o.block_seconds * o.fs).round() as usize;
        if block_len == 0 {
            bail!("a block must hold at least one sample");
        }
        Ok(block_len)
    }
}

impl Scenario {
    /// Every change names an updating parameter and is well formed.
    /// Spring and stiffness-field coefficients at time `t` (s): the config's
    /// values times the changes' factors.
    pub(super) fn coefficients_at(
        &self,
        setup: &FrfSetup,
        parameters: &[Parameter],
        t: f64,
    ) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let base_theta = setup.model.field_coefficients();
        let (mut k, mut theta) = (setup.kappa.clone(), base_theta.to_vec());
        for c in &self.changes {
            let p = parameters
                .iter()
                .find(|p| p.name == c.parameter)
                .expect("checked by Scenario::check");
            match p.kind {
                ParameterKind::Spring { .. } | ParameterKind::SpringRun { .. } => {
                    for (field, coefficient) in p.kind.springs() {
                        k[field][coefficient] = setup.kappa[field][coefficient] * c.factor_at(t);
                    }
                }
                ParameterKind::Stiffness { .. } | ParameterKind::StiffnessRun { .. } => {
                    for (field, coefficient) in p.kind.fields() {
                        theta[field][coefficient] = base_theta[field][coefficient] * c.factor_at(t);
                    }
                }
                ParameterKind::Damping { .. } | ParameterKind::LossFactor { .. } => {}
            }
        }
        (k, theta)
    }

    pub(super) fn check(&self, parameters: &[Parameter]) -> Result<()> {
        for c in &self.changes {
            let Some(p) = parameters.iter().find(|p| p.name == c.parameter) else {
                bail!(
                    "scenario: {:?} is not an updating parameter of this config",
                    c.parameter
                );
            };
            if matches!(p.kind, ParameterKind::Damping { .. } | ParameterKind::LossFactor { .. }) {
                bail!(
                    "scenario: {:?}: scenarios change spring or stiffness-field coefficients, not the damping",
                    c.parameter
                );
            }
            if !(c.factor.is_finite() && c.factor > 0.0 && c.end_minute >= c.start_minute) {
                bail!(
                    "scenario: change of {} needs factor > 0 and end_minute >= start_minute",
                    c.parameter
                );
            }
            if c.repair_minute.is_some_and(|r| !(r.is_finite() && r >= c.end_minute)) {
                bail!(
                    "scenario: change of {}: repair_minute must be at or after end_minute",
                    c.parameter
                );
            }
        }
        Ok(())
    }
}

/// Measurement noise per recorded channel (force first, if recorded):
/// `noise` × the clean RMS.
fn noise_levels(noise: f64, force: Option<&[f64]>, accelerations: &[Vec<f64>]) -> Vec<f64> {
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    force
        .map(rms)
        .into_iter()
        .chain(accelerations.iter().map(|a| rms(a)))
        .map(|r| noise * r)
        .collect()
}

/// Adds Gaussian noise of standard deviation `std`, one draw per sample.
fn add_noise(v: &mut [f64], std: f64, rng: &mut ChaCha8Rng) {
    if std > 0.0 {
        for x in v.iter_mut() {
            let z: f64 = rng.sample(StandardNormal);
            *x += std * z;
        }
    }
}

/// The force at the simulation rate, generated chunk by chunk.
struct ForceSource {
    excitation: Excitation,
    fs_sim: f64,
    band: (f64, f64),
    rms: f64,
    chunk: Vec<f64>,
    position: usize,
    /// Samples generated before the current chunk.
    offset: usize,
}

impl ForceSource {
    /// Random force is band-limited in chunks of 2^18 samples (64 s at 4 kHz).
    const CHUNK: usize = 1 << 18;

    fn new(o: &SimulationOptions) -> Self {
        Self {
            excitation: o.excitation,
            fs_sim: o.fs * o.oversample as f64,
            band: o.band,
            rms: o.force_rms,
            chunk: Vec::new(),
            position: 0,
            offset: 0,
        }
    }

    fn next(&mut self, rng: &mut ChaCha8Rng) -> f64 {
        if self.position == self.chunk.len() {
            self.offset += self.chunk.len();
            self.chunk = self.generate(rng);
            self.position = 0;
        }
        let v = self.chunk[self.position];
        self.position += 1;
        v
    }

    fn generate(&self, rng: &mut ChaCha8Rng) -> Vec<f64> {
        let n = Self::CHUNK;
        let peak = self.rms * std::f64::consts::SQRT_2;
        match self.excitation {
            Excitation::Random => excitation::band_limited_noise(rng, n, self.fs_sim, self.band, self.rms),
            Excitation::Sweep => {
                // One sweep per chunk, continuous phase at chunk starts (zero).
                swept_sine(self.band.0, self.band.1, self.fs_sim, n)
                    .into_iter()
                    .map(|v| v * peak)
                    .collect()
            }
            Excitation::Ambient | Excitation::Traffic => unreachable!("unmeasured sources have their own generator"),
            Excitation::Impact => {
                // About one hit every 8 s, jittered by ±1 s, clear of the chunk end.
                let seconds = n as f64 / self.fs_sim;
                let mut starts = Vec::new();
                let mut t = 1.0;
                while t < seconds - 1.0 {
                    starts.push(t + rng.random_range(-0.5..0.5));
                    t += 8.0;
                }
                hammer_impacts(&starts, 0.002, self.fs_sim, n)
                    .into_iter()
                    .map(|v| v * peak * 20.0)
                    .collect()
            }
        }
    }
}

/// Parses a scenario file.
pub fn parse_scenario(text: &str) -> Result<Scenario> {
    let s: Scenario = toml::from_str(text).context("invalid scenario file")?;
    if !(s.update_seconds.is_finite() && s.update_seconds > 0.0) {
        bail!("scenario: update_seconds must be positive");
    }
    Ok(s)
}
