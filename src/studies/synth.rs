//! `splinewatch synth`: model FRFs at named sensors, with the paper's noise model.

use crate::config::{frf_setup, Config};
use crate::io::frf_json::{FrfEntry, FrfFile};
use anyhow::{Context, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use splinewatch_core::response::frf::{FrfRequest, Quantity};

/// Options of `splinewatch synth`.
#[derive(Debug, Clone)]
pub struct SynthOptions {
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    pub quantity: Quantity,
    pub f_min: f64,
    pub f_max: f64,
    pub step: f64,
    /// Standard deviation of the complex noise as a fraction of each FRF's RMS.
    pub noise: f64,
    pub seed: u64,
}

impl SynthOptions {
    /// The checked frequency lines `from, from + step, …, ≤ to`.
    fn frequency_grid(&self) -> Result<Vec<f64>> {
        let o = self;
        if !(o.f_min.is_finite()
            && o.f_max.is_finite()
            && o.step.is_finite()
            && o.f_min > 0.0
            && o.step > 0.0
            && o.f_max >= o.f_min)
        {
            anyhow::bail!(
                "frequency grid: need 0 < from <= to and step > 0 (got {}..{} step {})",
                o.f_min,
                o.f_max,
                o.step
            );
        }
        if !(o.noise.is_finite() && o.noise >= 0.0) {
            anyhow::bail!("--noise must be a non-negative fraction, got {}", o.noise);
        }
        let count = ((o.f_max - o.f_min) / o.step + 1e-9).floor() as usize + 1;
        if count > 1_000_000 {
            anyhow::bail!("frequency grid: {count} lines is too many (at most 1 000 000)");
        }
        Ok((0..count).map(|k| o.f_min + k as f64 * o.step).collect())
    }
}

/// FRF entries of `pairs` (`(output, input)` sensor indices) from the
/// pair-major values `h` (`nf` lines per pair), with complex Gaussian noise
/// whose standard deviation is `noise` × each FRF's RMS (`E|n|² =
/// (noise · rms)²`, each part half the variance; nothing drawn at 0).
pub(crate) fn noisy_entries(
    sensor_names: &[String],
    h: &[splinewatch_core::c64],
    nf: usize,
    pairs: &[(usize, usize)],
    noise: f64,
    rng: &mut ChaCha8Rng,
) -> Vec<FrfEntry> {
    pairs
        .iter()
        .enumerate()
        .map(|(p, &(r, s))| {
            let values = &h[p * nf..(p + 1) * nf];
            let rms = (values.iter().map(|v| v.norm_sqr()).sum::<f64>() / nf as f64).sqrt();
            let sigma = noise * rms / std::f64::consts::SQRT_2;
            let mut noisy = |v: f64| {
                if sigma > 0.0 {
                    let n: f64 = rng.sample(StandardNormal);
                    v + sigma * n
                } else {
                    v
                }
            };
            let (re, im): (Vec<f64>, Vec<f64>) = values.iter().map(|v| (noisy(v.re), noisy(v.im))).unzip();
            FrfEntry {
                input: sensor_names[s].clone(),
                output: sensor_names[r].clone(),
                re,
                im,
                coherence: None,
                n_averages: None,
            }
        })
        .collect()
}

/// `splinewatch synth`: model FRFs with optional complex Gaussian noise.
pub fn synth(config: &Config, options: &SynthOptions) -> Result<FrfFile> {
    let o = options;
    let frequency_hz = o.frequency_grid()?;
    let setup = frf_setup(config)?;
    let index = |name: &str| {
        setup.sensor_names.iter().position(|n| n == name).with_context(|| {
            format!(
                "unknown sensor {name:?} (config sensors: {})",
                setup.sensor_names.join(", ")
            )
        })
    };
    let mut pairs = Vec::new();
    for i in &o.inputs {
        for r in &o.outputs {
            pairs.push((index(r)?, index(i)?));
        }
    }
    if pairs.is_empty() {
        anyhow::bail!("give at least one input and one output sensor");
    }
    let state = setup.model.modal_state(&setup.kappa, &setup.damping)?;
    let eval = setup.model.evaluate(
        &state,
        FrfRequest {
            frequencies_hz: &frequency_hz,
            pairs: &pairs,
            quantity: o.quantity,
        },
        false,
    );
    let mut rng = ChaCha8Rng::seed_from_u64(o.seed);
    let frfs = noisy_entries(
        &setup.sensor_names,
        &eval.h,
        frequency_hz.len(),
        &pairs,
        o.noise,
        &mut rng,
    );
    Ok(FrfFile {
        quantity: o.quantity,
        frequency_hz,
        frfs,
        start_timestamp: None,
        end_timestamp: None,
    })
}
