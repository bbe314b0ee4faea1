//! The modes a pole–residue fit of a record's H1 transmissibilities finds
//! (`[oma.frequency_domain]`), beside SRIM's (`identify`, `events`).
//!
//! The functions are the multi-input H1 estimates of every chosen output
//! per (combined) input over the band (`[frf]`'s Welch segments), each line
//! weighted by its standard deviation from the multiple coherence,
//! `σ = |H| √((1 − γ²)/(2 n γ²))` with `n` the averages less the inputs
//! (Bendat & Piersol 2010, *Random Data*, ch. 9): lines where the inputs
//! explain the output weigh most.

use super::records::identify_io;
use crate::config::{Config, FrequencyDomainPlan};
use crate::io::modes_json::{ModeEntry, ModeMethod, ShapeEntry};
use crate::pipeline::oma::OmaReport;
use anyhow::{anyhow, bail, Context, Result};
use splinewatch_core::c64;
use splinewatch_core::identification::oma::shape::normalise;
use splinewatch_core::identification::oma::{OmaResult, OmaSettings};
use splinewatch_core::identification::pole_residue::{self, h1_standard_deviation, FittedMode, Functions};
use splinewatch_core::identification::transmissibility;

/// The fitted modes of one record and what the fit had to say.
#[derive(Debug, Clone, Default)]
pub struct FittedModes {
    pub modes: Vec<ModeEntry>,
    pub notes: Vec<String>,
}

/// A recorded channel: its sensor (index into `[[sensors]]`) and samples.
pub type Recorded<'a> = (usize, &'a [f64]);

/// The fit of `plan` on a record's `inputs` and `outputs` at `fs` Hz.
pub fn fitted_modes(
    cfg: &Config,
    plan: &FrequencyDomainPlan,
    inputs: &[Recorded<'_>],
    outputs: &[Recorded<'_>],
    fs: f64,
) -> Result<FittedModes> {
    let chosen = |wanted: &[usize], given: &[Recorded<'_>], what: &str| -> Result<Vec<usize>> {
        let picked: Vec<usize> = (0..given.len())
            .filter(|&k| wanted.is_empty() || wanted.contains(&given[k].0))
            .collect();
        if picked.is_empty() {
            bail!(
                "oma.frequency_domain.{what}: the record holds none of {}",
                wanted
                    .iter()
                    .map(|&i| cfg.sensors[i].name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        Ok(picked)
    };
    let (ins, outs) = (
        chosen(&plan.inputs, inputs, "inputs")?,
        chosen(&plan.outputs, outputs, "outputs")?,
    );
    let [low, high] = plan.band;
    if high > fs / 2.0 {
        bail!("oma.frequency_domain.band ends at {high} Hz, above half the record's rate ({fs} Hz)");
    }
    let input_views: Vec<&[f64]> = ins.iter().map(|&k| inputs[k].1).collect();
    let output_views: Vec<&[f64]> = outs.iter().map(|&k| outputs[k].1).collect();
    let (welch, _) = cfg.welch_settings(fs)?;
    let segment = welch.segment.min(input_views[0].len());
    let overlap = welch.overlap.min(segment / 2);
    let est = transmissibility::estimate(&input_views, &output_views, fs, segment, overlap)
        .map_err(|e| anyhow!("oma.frequency_domain: the transmissibilities: {e}"))?;
    let lines: Vec<usize> = (0..est.frequencies_hz.len())
        .filter(|&k| (low..=high).contains(&est.frequencies_hz[k]))
        .collect();
    let frequencies: Vec<f64> = lines.iter().map(|&k| est.frequencies_hz[k]).collect();
    let Weighted { h, sigma } = weighted_functions(&est, &lines, segment as f64 / fs)?;
    let functions = Functions {
        frequencies_hz: &frequencies,
        h: &h,
        sigma: &sigma,
    };
    let fit = pole_residue::fit(functions, plan.modes)
        .with_context(|| format!("oma.frequency_domain: the fit over {low}–{high} Hz"))?;
    tracing::debug!(
        iterations = fit.iterations,
        scale = fit.residual_scale,
        "frequency-domain fit"
    );
    let names = |list: &[usize]| -> Vec<String> { list.iter().map(|&i| cfg.sensors[i].name.clone()).collect() };
    let output_names = names(&outs.iter().map(|&k| outputs[k].0).collect::<Vec<_>>());
    let mut fitted = FittedModes::default();
    for group in est.combined.iter().filter(|g| g.len() > 1) {
        fitted.notes.push(format!(
            "frequency-domain fit: inputs {} are coherent above {} over the band: combined into one (their mean)",
            names(&group.iter().map(|&i| inputs[ins[i]].0).collect::<Vec<_>>()).join("+"),
            transmissibility::COMBINE_COHERENCE
        ));
    }
    let per_output = est.combined.len();
    for mode in &fit.modes {
        if mode.at_bound {
            fitted.notes.push(format!(
                "frequency-domain fit: a mode stopped at {:.3} Hz, ζ {:.1} %, on the band's edge or a damping bound: not \
                 reported (oma.frequency_domain.band does not hold it)",
                mode.frequency_hz,
                100.0 * mode.damping_ratio
            ));
            continue;
        }
        fitted.modes.push(entry_of(mode, per_output, &output_names));
    }
    Ok(fitted)
}

/// Every output's H1 per (combined) input at `lines`, output-major, and
/// each line's standard deviation from the multiple coherence (floored at
/// 1e-9 of the function's largest value: a line never weighs infinitely);
/// refused when the segments (`segment_seconds` long) give too few
/// averages for the coherence to say anything.
fn weighted_functions(
    est: &transmissibility::Transmissibility,
    lines: &[usize],
    segment_seconds: f64,
) -> Result<Weighted> {
    if est.averages < est.combined.len() + 2 {
        bail!(
            "oma.frequency_domain: the record gives {} Welch average(s) of {:.1} s for {} input(s): too few for the \
             coherence to weigh the lines (a longer record, or a shorter [frf] segment_seconds)",
            est.averages,
            segment_seconds,
            est.combined.len()
        );
    }
    let mut h = Vec::new();
    let mut sigma = Vec::new();
    for (o, per_input) in est.h.iter().enumerate() {
        for hi in per_input {
            let values: Vec<c64> = lines.iter().map(|&k| hi[k]).collect();
            let floor = 1e-9 * values.iter().map(|v| v.norm()).fold(0.0, f64::max) + f64::MIN_POSITIVE;
            sigma.push(
                lines
                    .iter()
                    .map(|&k| {
                        let std = h1_standard_deviation(hi[k], est.coherence[o][k], est.averages, est.combined.len());
                        std.max(floor)
                    })
                    .collect::<Vec<f64>>(),
            );
            h.push(values);
        }
    }
    Ok(Weighted { h, sigma })
}

/// The functions fitted and each line's standard deviation.
struct Weighted {
    h: Vec<Vec<c64>>,
    sigma: Vec<Vec<f64>>,
}

/// A fitted mode as a modes-file entry: its shape the residues at every
/// output of the input that drives it most, largest component `1 + 0i`.
fn entry_of(mode: &FittedMode, per_output: usize, output_names: &[String]) -> ModeEntry {
    let energy = |i: usize| -> f64 {
        (0..output_names.len())
            .map(|o| mode.residues[o * per_output + i].norm_sqr())
            .sum()
    };
    let input = (0..per_output)
        .max_by(|&a, &b| energy(a).total_cmp(&energy(b)))
        .unwrap_or(0);
    let mut shape: Vec<c64> = (0..output_names.len())
        .map(|o| mode.residues[o * per_output + input])
        .collect();
    normalise(&mut shape);
    ModeEntry {
        frequency_hz: mode.frequency_hz,
        damping_ratio: mode.damping_ratio,
        frequency_std_hz: Some(mode.frequency_std_hz),
        damping_std: Some(mode.damping_std),
        shape: shape
            .iter()
            .zip(output_names)
            .map(|(v, name)| ShapeEntry {
                sensor: name.clone(),
                re: v.re,
                im: v.im,
                std: None,
            })
            .collect(),
        mpc: None,
        order: None,
        stable_orders: None,
        method: Some(ModeMethod::PoleResidue),
        model: None,
    }
}

/// The identification of a record with measured inputs: SRIM's report and,
/// with `[oma.frequency_domain]`, the fitted modes.
pub struct RecordModes {
    /// SRIM's (no modes when it found none and the fit did).
    pub report: OmaReport,
    pub settings: OmaSettings,
    /// The rate SRIM identified at (Hz).
    pub rate: f64,
    pub fitted: Vec<ModeEntry>,
    /// What SRIM or the fit could not do, when the other gave modes.
    pub notes: Vec<String>,
}

impl RecordModes {
    /// SRIM's modes and the fitted ones, by frequency.
    pub fn modes(&self) -> Vec<ModeEntry> {
        merged(self.report.modes_file().modes, &self.fitted)
    }
}

/// `subspace`'s modes and the `fitted` ones, by frequency.
pub fn merged(mut subspace: Vec<ModeEntry>, fitted: &[ModeEntry]) -> Vec<ModeEntry> {
    subspace.extend(fitted.iter().cloned());
    subspace.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    subspace
}

/// SRIM of every input to every output (`identify_io`) and the fit of
/// `[oma.frequency_domain]` when the config has one. An error when neither
/// gives a mode (or SRIM fails otherwise); one that found nothing while the
/// other did is a note.
pub fn identify_record(
    cfg: &Config,
    inputs: &[Recorded<'_>],
    outputs: &[Recorded<'_>],
    fs: f64,
    start_ns: i128,
) -> Result<RecordModes> {
    let input_views: Vec<&[f64]> = inputs.iter().map(|c| c.1).collect();
    let output_views: Vec<&[f64]> = outputs.iter().map(|c| c.1).collect();
    let (srim, settings, rate) = identify_io(cfg, &input_views, &output_views, fs)?;
    let mut notes = Vec::new();
    let mut fitted = Vec::new();
    if let Some(plan) = cfg.frequency_domain()? {
        match fitted_modes(cfg, &plan, inputs, outputs, fs) {
            Ok(fit) => {
                notes.extend(fit.notes);
                fitted = fit.modes;
            }
            Err(e) if srim.is_ok() => notes.push(format!("{e:#}")),
            Err(e) => bail!("{}; {e:#}", srim.err().unwrap_or_default()),
        }
    }
    let result = match srim {
        Ok(result) => result,
        Err(none) if !fitted.is_empty() => {
            notes.insert(0, format!("{none}: the frequency-domain fit's modes alone"));
            OmaResult {
                modes: Vec::new(),
                diagram: Vec::new(),
                singular_values: Vec::new(),
            }
        }
        Err(none) => bail!("{none}"),
    };
    Ok(RecordModes {
        report: OmaReport {
            start_ns,
            samples: output_views.first().map_or(0, |o| o.len()),
            fs,
            sensors: outputs.iter().map(|&(i, _)| cfg.sensors[i].name.clone()).collect(),
            result,
            spectrum: None,
        },
        settings,
        rate,
        fitted,
        notes,
    })
}
