//! Updating on an earthquake record (issue 45, item 2), by the residues of
//! [`splinewatch_core::updating::transmissibility_residual`] between the
//! model's ground inputs (the plan's group means,
//! [`crate::config::ground_signals`]) and the deck sensors, as `[events]
//! inputs` says:
//!
//! - `"spectra"` (default): the record's own spectra, the deck's `Y_o(ω)`
//!   against `Σ_c T_oc(ω) U_c(ω)` of every ground input (the frequency-domain
//!   output error: no averaging, every input at once; the relative residual
//!   is the deck response's NRMSE over the band);
//! - `"combined"`: the H1 transmissibility from the mean of the ground inputs
//!   along the fitted sensors' axes (their transmissibilities summed in the
//!   model: exact when the grounds move together);
//! - `"separate"`: a multi-input H1 from each ground input along those axes,
//!   only those too coherent to separate combined.
//!
//! The H1 estimates are weighted by their variance from the multiple
//! coherence and the number of averages, whatever `[updating] weighting`
//! says: a minute-long record gives some fourteen 8-s segments, and each
//! input costs one. The lines are `[updating] band` (default: `[frf]
//! band`), decimated and excluded as `[updating]` says.
//!
//! `[events] residues` (`first_residues` for a chain's first event) says
//! what is fitted: `"frf"` (default) the above;
//! `"modes"` the modes identified from the record (SRIM), in their std, as
//! `update --modes` does; `"both"` the above and the modes together, each in
//! its own std ([`splinewatch_core::updating::joint`]): H1 transmissibilities
//! in their variance, a record's spectra divided by the residual std of a
//! fit of the spectra alone (run first; the joint fit starts where it
//! ends). An event whose identification found no mode is fitted on its
//! record alone under `"both"` and not updated under `"modes"`.

use super::ground_motion::GroundParts;
use super::parameters::values_by_name;
use crate::config::{Config, GroundInputPlan, Residues, ResponseFunction};
use crate::io::named_value::NamedValue;
use anyhow::{anyhow, bail, Context, Result};
use serde::Serialize;
use splinewatch_core::c64;
use splinewatch_core::identification::transmissibility;
use splinewatch_core::response::frf::{FrfModel, ModalState, Quantity};
use splinewatch_core::response::support_motion::SupportMotion;
use splinewatch_core::updating::frf_residual::{MeasuredFrf, MeasuredSet};
use splinewatch_core::updating::joint::JointTransmissibilityProblem;
use splinewatch_core::updating::modal_residual::{frequency_gradient, pair_modes, ModePair, ObservedMode};
use splinewatch_core::updating::transmissibility_residual::{
    Combination, TransmissibilityProblem, TransmissibilitySolution,
};
use splinewatch_core::updating::{
    base_values, IterationRecord, ModalUpdateProblem, Parameter, UpdateError, UpdateResult, UpdateSettings, Weighting,
};

/// What an update on one event gives.
pub struct EventUpdate {
    pub result: UpdateResult,
    /// The updated model's dominant mode in the record's band: the largest
    /// resonant share `Σ_{o,c} |a_oi L_ic| / ζ_i` over the fitted sensors
    /// `o` and ground inputs `c` (Hz).
    pub dominant_hz: Option<f64>,
    /// Its standard deviation: `√(gᵀ C g)`, `g = ∂f/∂p` (the mode's
    /// eigen-derivatives, `modal_residual::frequency_gradient`), `C` the
    /// parameters' covariance at the solution (delta method).
    pub dominant_std_hz: Option<f64>,
    /// Ground inputs combined into one (names joined by `+`).
    pub combined: Vec<String>,
    /// The identified modes fitted (`[events] residues` `"modes"` or
    /// `"both"`) with the model modes they paired with at the solution.
    pub pairs: Vec<PairedMode>,
    /// Model evaluations of every stage (a record's spectra fitted with
    /// modes: the spectra alone first, for their `σ̂`).
    pub evaluations: usize,
}

/// An identified mode the update fitted and the model's it paired with.
#[derive(Debug, Clone, Serialize)]
pub struct PairedMode {
    pub identified_hz: f64,
    pub model_hz: f64,
    pub mac: f64,
}

/// One record's ground inputs and deck outputs, sampled at `fs`.
pub struct EventSignals<'a> {
    /// The ground inputs of `plan` ([`crate::config::ground_signals`]).
    pub plan: &'a [GroundInputPlan],
    pub inputs: &'a [Vec<f64>],
    /// The config indices of the deck sensors fitted, and their series.
    pub deck: &'a [usize],
    pub outputs: &'a [Vec<f64>],
    pub fs: f64,
    /// The modes identified from the record (on the config's sensors).
    pub modes: &'a [ObservedMode],
}

/// The measured data of one record and how the model makes them.
struct Measured {
    set: MeasuredSet,
    combination: Combination,
    /// The plan entries the measured inputs stand for.
    plan: Vec<GroundInputPlan>,
    combined: Vec<String>,
    weighting: Weighting,
}

/// Updates the config's parameters on one record, started from `start`
/// (named values of the previous event's update; the config's values for
/// the others), fitting `residues` (`[events] residues`, or
/// `first_residues` for a chain's first event).
pub fn update_on_event(
    config: &Config,
    parts: &GroundParts,
    signals: &EventSignals<'_>,
    (start, residues): (&[NamedValue], Residues),
    progress: &mut dyn FnMut(&IterationRecord),
) -> Result<EventUpdate> {
    if signals.deck.is_empty() || signals.inputs.is_empty() {
        bail!("no deck channel or no ground input to update on");
    }
    let GroundParts { setup, parameters, .. } = parts;
    if parameters.is_empty() {
        bail!("no parameter has update = true: nothing to update");
    }
    let mut settings: UpdateSettings = config.update_settings()?;
    if settings.lines.band.is_none() {
        let [lo, hi] = config.frf.band;
        settings.lines.band = Some((lo, hi));
    }
    let theta0 = setup.model.field_coefficients().to_vec();
    let base = base_values(parameters, &setup.kappa, &theta0, &setup.damping);
    let start = values_by_name(parameters, &base, start, "start parameter")?;
    let pairing = (config.updating.min_mac, config.updating.max_frequency_gap);
    if residues == Residues::Modes {
        return fit_modes(parts, signals, settings, &start, pairing, progress);
    }
    let measured = match config.events().response_function {
        ResponseFunction::Spectra => record_spectra(signals)?,
        ResponseFunction::Combined | ResponseFunction::Separate => transmissibilities(config, signals)?,
    };
    settings.weighting = measured.weighting;
    let problem = TransmissibilityProblem::new(
        (&setup.model, &parts.grounded),
        measured.plan.iter().map(|p| p.input).collect(),
        measured.combination.clone(),
        setup.kappa.clone(),
        setup.damping.clone(),
        parameters.clone(),
        &measured.set,
        settings,
    )
    .context("updating on the record")?;
    let band = problem.line_frequencies();
    let band = (band[0], band[band.len() - 1]);
    let (solution, pairs, evaluations) = if residues == Residues::Both && !signals.modes.is_empty() {
        fit_record_and_modes(problem, &measured, signals.modes, pairing, &start, progress)?
    } else {
        let solution = problem.solve(&start, progress).context("updating on the record")?;
        let evaluations = solution.result.evaluations;
        (solution, Vec::new(), evaluations)
    };
    let (dominant_hz, dominant_std_hz) = dominant_mode(
        (&setup.model, parameters),
        (&solution.state, &solution.motion, &solution.result),
        signals.deck,
        band,
    );
    Ok(EventUpdate {
        pairs: paired_modes(&solution.state, signals.modes, &pairs),
        result: solution.result,
        dominant_hz,
        dominant_std_hz,
        combined: measured.combined,
        evaluations,
    })
}

/// `"both"`: the record's transmissibilities (×√2, their H1 std) or spectra
/// (÷ `σ̂` of a fit of the spectra alone, which runs first and starts the
/// joint fit; where no identified mode pairs at its end, its answer is
/// returned) with the identified modes ([`JointTransmissibilityProblem`]).
fn fit_record_and_modes(
    problem: TransmissibilityProblem<'_>,
    measured: &Measured,
    modes: &[ObservedMode],
    pairing: (f64, f64),
    start: &[f64],
    progress: &mut dyn FnMut(&IterationRecord),
) -> Result<(TransmissibilitySolution, Vec<ModePair>, usize)> {
    let (scale, from, first) = match measured.weighting {
        Weighting::H1Variance => (std::f64::consts::SQRT_2, start.to_vec(), 0),
        _ => {
            let alone = problem.solve(start, progress).context("updating on the record")?;
            // No identified mode pairs where the record alone leads: the
            // joint fit would start with an empty modal block, and its
            // answer is the record's. So is it where the record is fitted
            // exactly (no σ̂ to scale by: noise-free data), its pairs kept.
            let sigma = alone.result.residual_variance.sqrt();
            let scalable = sigma.is_finite() && sigma > 0.0;
            let pairs = pair_modes(&alone.state, modes, pairing.0, pairing.1);
            if pairs.is_empty() || !scalable {
                let evaluations = alone.result.evaluations;
                return Ok((alone, pairs, evaluations));
            }
            let from = alone.result.parameters.iter().map(|p| p.value).collect();
            (1.0 / sigma, from, alone.result.evaluations)
        }
    };
    let joint = JointTransmissibilityProblem::new(problem, modes, pairing, scale)
        .context("updating on the record and its modes")?;
    let solved = joint
        .solve(&from, progress)
        .context("updating on the record and its modes")?;
    let evaluations = first + solved.response.result.evaluations;
    Ok((solved.response, solved.pairs, evaluations))
}

/// `"modes"`: the identified modes alone ([`ModalUpdateProblem`]); the
/// support motion at the solution gives the dominant mode.
fn fit_modes(
    parts: &GroundParts,
    signals: &EventSignals<'_>,
    settings: UpdateSettings,
    start: &[f64],
    pairing: (f64, f64),
    progress: &mut dyn FnMut(&IterationRecord),
) -> Result<EventUpdate> {
    if signals.modes.is_empty() {
        bail!("no identified mode to fit ([events] residues = \"modes\")");
    }
    let band = settings.lines.band.unwrap_or((0.0, f64::INFINITY));
    let setup = &parts.setup;
    let problem = ModalUpdateProblem::new(
        &setup.model,
        setup.kappa.clone(),
        setup.damping.clone(),
        parts.parameters.clone(),
        signals.modes,
        settings,
        pairing,
    )
    .context("updating on the record's modes")?;
    let solution = problem.solve(start, progress).map_err(|e| match e {
        UpdateError::Underdetermined { residuals: 0, .. } => anyhow!(
            "none of the {} identified modes ({} Hz) pairs with a model mode (MAC ≥ {} within {} % in frequency): \
             nothing to fit ([events] residues = \"modes\")",
            signals.modes.len(),
            signals
                .modes
                .iter()
                .map(|m| format!("{:.2}", m.frequency_hz))
                .collect::<Vec<_>>()
                .join(", "),
            pairing.0,
            100.0 * pairing.1
        ),
        e => anyhow::Error::new(e).context("updating on the record's modes"),
    })?;
    // The support motion at the solution, on its modal state (no second
    // eigen-solve).
    let p: Vec<f64> = solution.result.parameters.iter().map(|e| e.value).collect();
    let (kappa, _) = problem.model_at(&p)?;
    let inputs: Vec<_> = signals.plan.iter().map(|p| p.input).collect();
    let state = &solution.state;
    let motion = SupportMotion::new(
        (&setup.model, &parts.grounded),
        &kappa,
        &problem.fields_at(&p),
        state,
        &inputs,
    )
    .map_err(|e| anyhow!("support motion at the updated model: {e}"))?;
    let (dominant_hz, dominant_std_hz) = dominant_mode(
        (&setup.model, &parts.parameters),
        (state, &motion, &solution.result),
        signals.deck,
        band,
    );
    Ok(EventUpdate {
        pairs: paired_modes(state, signals.modes, &solution.pairs),
        dominant_hz,
        dominant_std_hz,
        evaluations: solution.result.evaluations,
        result: solution.result,
        combined: Vec::new(),
    })
}

/// The updated model's dominant mode in `(lo, hi)` Hz over the sensors
/// `deck` and its standard deviation ([`EventUpdate::dominant_hz`],
/// [`EventUpdate::dominant_std_hz`]).
fn dominant_mode(
    (model, parameters): (&FrfModel, &[Parameter]),
    (state, motion, result): (&ModalState, &SupportMotion, &UpdateResult),
    deck: &[usize],
    band: (f64, f64),
) -> (Option<f64>, Option<f64>) {
    let Some(i) = dominant_index(state, motion, deck, band) else {
        return (None, None);
    };
    let std = result.covariance.as_ref().map(|c| {
        let g = frequency_gradient(model, state, i, parameters);
        let variance: f64 = (0..g.len())
            .map(|k| (0..g.len()).map(|l| g[k] * c[k][l] * g[l]).sum::<f64>())
            .sum();
        variance.max(0.0).sqrt()
    });
    (Some(state.modes.frequency_hz(i)), std)
}

/// The index of the mode of largest resonant share in `(lo, hi)` Hz.
fn dominant_index(state: &ModalState, motion: &SupportMotion, deck: &[usize], (lo, hi): (f64, f64)) -> Option<usize> {
    (0..state.modes.len())
        .filter(|&i| (lo..=hi).contains(&state.modes.frequency_hz(i)) && state.zeta[i] > 0.0)
        .map(|i| {
            let share: f64 = deck
                .iter()
                .flat_map(|&o| {
                    (0..motion.inputs().len()).map(move |c| (state.amplitude(o, i) * motion.participation(i, c)).abs())
                })
                .sum();
            (i, share / state.zeta[i])
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

fn paired_modes(state: &ModalState, modes: &[ObservedMode], pairs: &[ModePair]) -> Vec<PairedMode> {
    pairs
        .iter()
        .map(|p| PairedMode {
            identified_hz: modes[p.observed].frequency_hz,
            model_hz: state.modes.frequency_hz(p.model),
            mac: p.mac,
        })
        .collect()
}

/// `X(f_k)`, `k ≥ 1`, of every series: the DFT of the whole record, its mean
/// removed (no window: the record starts and ends near rest).
fn spectra(series: &[Vec<f64>]) -> Result<Vec<Vec<c64>>> {
    let n = series[0].len();
    let mut planner = realfft::RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(n);
    series
        .iter()
        .map(|x| {
            let mean = x.iter().sum::<f64>() / n as f64;
            let mut input: Vec<f64> = x.iter().map(|v| v - mean).collect();
            let mut out = fft.make_output_vec();
            fft.process(&mut input, &mut out)
                .map_err(|e| anyhow!("the record's spectrum: {e}"))?;
            Ok(out[1..].iter().map(|v| c64::new(v.re, v.im)).collect())
        })
        .collect()
}

/// `"spectra"`: the deck's output spectra against every ground input's.
fn record_spectra(signals: &EventSignals<'_>) -> Result<Measured> {
    let n = signals.inputs[0].len();
    if n < 4 {
        bail!("{n} samples: too short for a spectrum");
    }
    let inputs = spectra(signals.inputs)?;
    let outputs = spectra(signals.outputs)?;
    let frequencies: Vec<f64> = (1..=outputs[0].len())
        .map(|k| k as f64 * signals.fs / n as f64)
        .collect();
    let frfs = signals
        .deck
        .iter()
        .zip(outputs)
        .map(|(&sensor, values)| MeasuredFrf {
            output: sensor,
            input: 0,
            values,
            coherence: None,
            n_averages: None,
        })
        .collect();
    // The values are output spectra (m/s²·s): the set's quantity is not read.
    let set = MeasuredSet::new(Quantity::Accelerance, frequencies, frfs)?;
    Ok(Measured {
        set,
        combination: Combination::Spectra(inputs),
        plan: signals.plan.to_vec(),
        combined: Vec::new(),
        weighting: Weighting::Uniform,
    })
}

/// `"combined"` and `"separate"`: H1 transmissibilities from the ground
/// inputs along the fitted sensors' axes.
fn transmissibilities(config: &Config, signals: &EventSignals<'_>) -> Result<Measured> {
    let axes: Vec<usize> = signals
        .deck
        .iter()
        .map(|&i| config.sensors[i].direction.dominant_axis())
        .collect();
    let (plan, inputs): (Vec<GroundInputPlan>, Vec<&Vec<f64>>) = signals
        .plan
        .iter()
        .cloned()
        .zip(signals.inputs)
        .filter(|(p, _)| axes.contains(&p.input.axis))
        .unzip();
    if plan.is_empty() {
        bail!("no ground input acts along the fitted deck sensors' axes");
    }
    let samples = inputs[0].len();
    let mean: Vec<f64> = (0..samples)
        .map(|t| inputs.iter().map(|x| x[t]).sum::<f64>() / inputs.len() as f64)
        .collect();
    let combine_all = config.events().response_function == ResponseFunction::Combined && inputs.len() > 1;
    let input_views: Vec<&[f64]> = if combine_all {
        vec![mean.as_slice()]
    } else {
        inputs.iter().map(|x| x.as_slice()).collect()
    };
    let (welch, _) = config.welch_settings(signals.fs)?;
    let segment = welch.segment.min(samples);
    let overlap = welch.overlap.min(segment / 2);
    let output_views: Vec<&[f64]> = signals.outputs.iter().map(Vec::as_slice).collect();
    let mut est = transmissibility::estimate(&input_views, &output_views, signals.fs, segment, overlap)
        .map_err(|e| anyhow!("transmissibility: {e}"))?;
    if combine_all {
        est.combined = vec![(0..inputs.len()).collect()];
    }
    // Line 0 (0 Hz) carries no transmissibility a model can fit.
    let first = est.frequencies_hz.iter().position(|&f| f > 0.0).unwrap_or(0);
    let mut frfs = Vec::new();
    for (o, &sensor) in signals.deck.iter().enumerate() {
        let coherence: Vec<f64> = est.coherence[o][first..]
            .iter()
            .map(|g| if g.is_finite() { g.clamp(0.0, 1.0) } else { 0.0 })
            .collect();
        for (i, h) in est.h[o].iter().enumerate() {
            frfs.push(MeasuredFrf {
                output: sensor,
                input: i,
                values: h[first..].to_vec(),
                coherence: Some(coherence.clone()),
                n_averages: Some(est.averages as f64),
            });
        }
    }
    // Transmissibilities are acceleration per acceleration: the set's
    // quantity is not read by the transmissibility residues.
    let set = MeasuredSet::new(Quantity::Accelerance, est.frequencies_hz[first..].to_vec(), frfs)?;
    let combined = est
        .combined
        .iter()
        .filter(|g| g.len() > 1)
        .map(|g| g.iter().map(|&i| plan[i].name.as_str()).collect::<Vec<_>>().join("+"))
        .collect();
    Ok(Measured {
        set,
        combination: Combination::Sum(est.combined),
        plan,
        combined,
        weighting: Weighting::H1Variance,
    })
}
