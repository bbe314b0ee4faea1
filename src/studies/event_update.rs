//! Updating on an earthquake record (issue 45, item 2): the record's
//! multi-input H1 transmissibilities from the model's ground inputs (the
//! plan's group means, [`crate::config::ground_signals`]) to the deck
//! sensors, fitted by the FRF residues of eq. (36)–(39)
//! ([`splinewatch_core::updating::transmissibility_residual`]).
//!
//! A strong-motion record gives a handful of Welch segments, so the residues
//! are weighted by the H1 estimator's variance from the multiple coherence
//! and the number of averages, whatever `[updating] weighting` says; the
//! lines are `[updating] band` (default: `[frf] band`), decimated and
//! excluded as `[updating]` says. With `[events] inputs = "combined"` (the
//! default) the ground inputs are one input, their mean, whose model
//! transmissibility is the sum of theirs (exact when the grounds move
//! together); with `"separate"` each is its own input of the multi-input H1,
//! and only those too coherent to separate are combined. A minute-long
//! record gives some fourteen 8-s segments: three inputs whose mutual
//! coherence is 0.6–0.7 (the Painter Street grounds, 1–12 Hz) leave the
//! separated estimates too noisy to fit (measured in the README).

use super::parameters::values_by_name;
use crate::config::{frf_setup, Config, EventInputs, GroundInputPlan};
use anyhow::{anyhow, bail, Context, Result};
use splinewatch_core::identification::transmissibility;
use splinewatch_core::response::frf::Quantity;
use splinewatch_core::updating::frf_residual::{MeasuredFrf, MeasuredSet};
use splinewatch_core::updating::transmissibility_residual::TransmissibilityProblem;
use splinewatch_core::updating::{base_values, IterationRecord, UpdateResult, Weighting};

/// What an update on one event gives.
pub struct EventUpdate {
    pub result: UpdateResult,
    /// Ground inputs combined because they were too coherent to separate
    /// (names joined by `+`).
    pub combined: Vec<String>,
}

/// Updates the config's parameters on the transmissibilities of one record:
/// `inputs` the plan's ground signals ([`crate::config::ground_signals`]),
/// `deck` the config indices of the deck sensors and `outputs` their series,
/// sampled at `fs`; started from `start` (named values of the previous
/// event's update; the config's values for the others).
pub fn update_on_event(
    config: &Config,
    plan: &[GroundInputPlan],
    inputs: &[Vec<f64>],
    (deck, outputs): (&[usize], &[Vec<f64>]),
    fs: f64,
    start: &[(String, f64)],
    progress: &mut dyn FnMut(&IterationRecord),
) -> Result<EventUpdate> {
    if deck.is_empty() {
        bail!("no deck channel to update on");
    }
    let setup = frf_setup(config)?;
    let shell = config.build_model()?;
    let groups = config.support_groups(&shell)?;
    let parameters = config.build_parameters()?;
    if parameters.is_empty() {
        bail!("no parameter has update = true: nothing to update");
    }
    let mut settings = config.update_settings()?;
    settings.weighting = Weighting::H1Variance;
    if settings.lines.band.is_none() {
        let [lo, hi] = config.frf.band;
        settings.lines.band = Some((lo, hi));
    }
    let (welch, _) = config.welch_settings(fs)?;
    let samples = inputs.first().map_or(0, Vec::len);
    let segment = welch.segment.min(samples);
    let overlap = welch.overlap.min(segment / 2);
    // `[events] inputs = "combined"`: one input, the mean of the ground
    // inputs, whose model transmissibility is the sum of theirs.
    let mean: Vec<f64> = (0..samples)
        .map(|t| inputs.iter().map(|x| x[t]).sum::<f64>() / inputs.len() as f64)
        .collect();
    let combine_all = config.events.inputs == EventInputs::Combined && inputs.len() > 1;
    let input_views: Vec<&[f64]> = if combine_all {
        vec![mean.as_slice()]
    } else {
        inputs.iter().map(Vec::as_slice).collect()
    };
    let output_views: Vec<&[f64]> = outputs.iter().map(Vec::as_slice).collect();
    let mut est = transmissibility::estimate(&input_views, &output_views, fs, segment, overlap)
        .map_err(|e| anyhow!("transmissibility: {e}"))?;
    if combine_all {
        est.combined = vec![(0..inputs.len()).collect()];
    }
    // Line 0 (0 Hz) carries no transmissibility a model can fit.
    let first = est.frequencies_hz.iter().position(|&f| f > 0.0).unwrap_or(0);
    let mut frfs = Vec::new();
    for (o, &sensor) in deck.iter().enumerate() {
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
    let measured = MeasuredSet::new(Quantity::Accelerance, est.frequencies_hz[first..].to_vec(), frfs)?;
    let theta0 = setup.model.field_coefficients().to_vec();
    let base = base_values(&parameters, &setup.kappa, &theta0, &setup.damping);
    let start = values_by_name(&parameters, &base, start, "start parameter")?;
    let combined_names = est
        .combined
        .iter()
        .filter(|g| g.len() > 1)
        .map(|g| g.iter().map(|&i| plan[i].name.as_str()).collect::<Vec<_>>().join("+"))
        .collect();
    let problem = TransmissibilityProblem::new(
        (&setup.model, &shell, &groups),
        plan.iter().map(|p| p.input).collect(),
        est.combined,
        setup.kappa.clone(),
        setup.damping.clone(),
        parameters,
        &measured,
        settings,
    )
    .context("updating on the transmissibilities")?;
    let solution = problem
        .solve(&start, progress)
        .context("updating on the transmissibilities")?;
    Ok(EventUpdate {
        result: solution.result,
        combined: combined_names,
    })
}
