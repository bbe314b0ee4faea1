//! Compact recordings of pre-computed FRFs over many windows (`simulate
//! --frf-windows`): the model's FRFs at each window's temperature and damage
//! state, with noise, and the temperature blocks, so a test can cover
//! months of monitoring in seconds.

use super::environment::Environment;
use super::simulation::Scenario;
use crate::config::{frf_setup, Config, FrfSetup};
use crate::io::frf_json::FrfFile;
use crate::io::wire::{format_timestamp, ChannelBlock};
use anyhow::{bail, Result};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use splinewatch_core::response::frf::FrfRequest;
use splinewatch_core::updating::Parameter;

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
    let hidden = environment.hidden_fields(config);
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
            (&environment, hidden, mean_t),
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
    (environment, hidden, temperature): (&Environment, usize, f64),
    middle_s: f64,
    (lines, pairs): (&[f64], &[(usize, usize)]),
    noise: f64,
    rng: &mut ChaCha8Rng,
) -> Result<FrfFile> {
    let (mut kappa, mut theta) = scenario.coefficients_at(setup, parameters, middle_s);
    environment.apply(temperature, hidden, &mut kappa, &mut theta);
    let state = setup.model.modal_state_with_fields(&kappa, &theta, &setup.damping)?;
    let quantity = splinewatch_core::response::frf::Quantity::Accelerance;
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
