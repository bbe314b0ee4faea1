//! Command implementations. Each returns its output as a value or writes to
//! the given writer, so tests can run them without a process.

use crate::config::Config;
use crate::frf_json::{FrfEntry, FrfFile};
use anyhow::{Context, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};
use splinewatch_core::damping::DampingCurve;
use splinewatch_core::frf::{FrfModel, FrfRequest, Quantity};
use splinewatch_core::modal::ModeKind;
use splinewatch_core::updating::{IterationRecord, Parameter, UpdateProblem, UpdateResult};
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// Reads and validates a configuration file.
pub fn load_config(path: &Path) -> Result<Config> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read config file {}", path.display()))?;
    let config = Config::from_toml(&text).with_context(|| format!("invalid config file {}", path.display()))?;
    config
        .validate()
        .with_context(|| format!("invalid config file {}", path.display()))?;
    Ok(config)
}

#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ModeRow {
    pub index: usize,
    pub frequency_hz: f64,
    pub kind: ModeKind,
}

#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ModesReport {
    pub modes: Vec<ModeRow>,
}

/// Statistics of a modal run, reported on stderr.
#[derive(Debug, Clone)]
pub struct ModalRunInfo {
    pub dofs: usize,
    pub free_dofs: usize,
    pub assembly_seconds: f64,
    pub solve_seconds: f64,
}

/// Assembles the configured model and returns its first `count` modes.
pub fn compute_modes(config: &Config, count: usize) -> Result<(ModesReport, ModalRunInfo)> {
    let model = config.build_model()?;
    let t0 = Instant::now();
    let assembled = model.assemble().context("assembling the model")?;
    let t1 = Instant::now();
    let modes = assembled.modes().context("solving the eigenproblem")?;
    let t2 = Instant::now();
    let rows = (0..modes.len().min(count))
        .map(|i| ModeRow {
            index: i + 1,
            frequency_hz: modes.frequency_hz(i),
            kind: modes.kinds[i],
        })
        .collect();
    let info = ModalRunInfo {
        dofs: assembled.dof_count(),
        free_dofs: assembled.reduction.free_count(),
        assembly_seconds: (t1 - t0).as_secs_f64(),
        solve_seconds: (t2 - t1).as_secs_f64(),
    };
    Ok((ModesReport { modes: rows }, info))
}

/// `splinewatch modes`: a table (or JSON) on `out`.
pub fn write_modes(report: &ModesReport, json: bool, out: &mut impl Write) -> Result<()> {
    if json {
        serde_json::to_writer(&mut *out, report)?;
        writeln!(out)?;
        return Ok(());
    }
    writeln!(out, "{:>5}  {:>12}  kind", "mode", "frequency Hz")?;
    for r in &report.modes {
        let kind = match r.kind {
            ModeKind::Rigid => "rigid",
            ModeKind::Membrane => "membrane",
            ModeKind::Bending => "bending",
        };
        writeln!(out, "{:>5}  {:>12.4}  {kind}", r.index, r.frequency_hz)?;
    }
    Ok(())
}

/// The model, its sensors and damping, ready for FRF work.
pub struct FrfSetup {
    pub model: FrfModel,
    pub sensor_names: Vec<String>,
    pub kappa: Vec<Vec<f64>>,
    pub damping: DampingCurve,
}

/// Assembles the configured model with its sensors and damping curve.
pub fn frf_setup(config: &Config) -> Result<FrfSetup> {
    let model = config.build_model()?;
    let sensors = config.build_sensors(&model.shell)?;
    if sensors.is_empty() {
        anyhow::bail!("config: sensors: at least one [[sensors]] table is required for FRFs");
    }
    let damping = config.build_damping()?;
    let kappa = model.springs.iter().map(|s| s.stiffness().to_vec()).collect();
    let points: Vec<_> = sensors.iter().map(|(_, p)| *p).collect();
    let frf_model = FrfModel::new(model.assemble().context("assembling the model")?, &points)?;
    Ok(FrfSetup {
        model: frf_model,
        sensor_names: sensors.into_iter().map(|(n, _)| n).collect(),
        kappa,
        damping,
    })
}

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

/// `splinewatch synth`: model FRFs with optional complex Gaussian noise.
pub fn synth(config: &Config, options: &SynthOptions) -> Result<FrfFile> {
    let o = options;
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
    let frequency_hz: Vec<f64> = (0..count).map(|k| o.f_min + k as f64 * o.step).collect();
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
    let nf = frequency_hz.len();
    let frfs = pairs
        .iter()
        .enumerate()
        .map(|(p, &(r, s))| {
            let values = &eval.h[p * nf..(p + 1) * nf];
            let rms = (values.iter().map(|v| v.norm_sqr()).sum::<f64>() / nf as f64).sqrt();
            // E|n|² = (noise · rms)²: each part has half the variance.
            let sigma = o.noise * rms / std::f64::consts::SQRT_2;
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
                input: setup.sensor_names[s].clone(),
                output: setup.sensor_names[r].clone(),
                re,
                im,
                coherence: None,
                n_averages: None,
            }
        })
        .collect();
    Ok(FrfFile {
        quantity: o.quantity,
        frequency_hz,
        frfs,
    })
}

#[derive(Debug, Deserialize)]
struct StartFile {
    parameters: Vec<StartParameter>,
}

#[derive(Debug, Deserialize)]
struct StartParameter {
    name: String,
    value: f64,
}

/// Parses a previous result (`update --json` output or the daemon state) into
/// start values for `parameters`; parameters it does not name keep `base`.
pub fn start_values(text: &str, parameters: &[Parameter], base: &[f64]) -> Result<Vec<f64>> {
    let start: StartFile = serde_json::from_str(text).context("not a result JSON with a \"parameters\" list")?;
    let mut values = base.to_vec();
    for sp in start.parameters {
        let k = parameters.iter().position(|p| p.name == sp.name).with_context(|| {
            format!(
                "start parameter {:?} is not an updating parameter of this config",
                sp.name
            )
        })?;
        if !sp.value.is_finite() {
            anyhow::bail!("start parameter {:?} is not finite", sp.name);
        }
        values[k] = sp.value;
    }
    Ok(values)
}

/// `splinewatch update`: runs the updating and returns its result.
pub fn update(
    config: &Config,
    frf_text: &str,
    start: Option<&str>,
    progress: &mut dyn FnMut(&IterationRecord),
) -> Result<UpdateResult> {
    let setup = frf_setup(config)?;
    let frf = FrfFile::parse(frf_text)?;
    let measured = frf.to_measured(&setup.sensor_names)?;
    let parameters = config.build_parameters()?;
    let settings = config.update_settings()?;
    let problem = UpdateProblem::new(
        &setup.model,
        setup.kappa.clone(),
        setup.damping.clone(),
        parameters,
        &measured,
        settings,
    )?;
    let base = problem.base_values();
    let start = match start {
        Some(text) => start_values(text, problem.parameters(), &base)?,
        None => base,
    };
    Ok(problem.solve_observed(&start, progress)?)
}

/// The final table of `splinewatch update`.
pub fn write_update_table(result: &UpdateResult, out: &mut impl Write) -> Result<()> {
    writeln!(
        out,
        "{:<14} {:>14} {:>12} {:>7} {:>12} {:>12}",
        "parameter", "value", "std", "std %", "lower", "upper"
    )?;
    for p in &result.parameters {
        let (std, pct) = match p.std {
            Some(s) => (format!("{s:.4e}"), format!("{:.2}", 100.0 * s / p.value.abs())),
            None => ("unidentif.".to_string(), "-".to_string()),
        };
        writeln!(
            out,
            "{:<14} {:>14.6e} {:>12} {:>7} {:>12.4e} {:>12.4e}",
            p.name, p.value, std, pct, p.lower, p.upper
        )?;
    }
    writeln!(
        out,
        "converged: {} ({:?}) after {} iterations, {} model evaluations; relative residual {:.4e}; Jacobian condition {:.3e}",
        result.converged,
        result.stop_reason,
        result.iterations.len() - 1,
        result.evaluations,
        result.relative_residual,
        result.condition_number
    )?;
    Ok(())
}
