//! `splinewatch update`: FRF-based updating against an FRF file, or
//! modal-residue updating against identified modes (`--modes`), optionally
//! warm-started from an earlier result.

use crate::config::{frf_setup, Config};
use crate::io::frf_json::FrfFile;
use crate::io::modes_json::ModesFile;
use crate::io::named_value::NamedValue;
use crate::io::uff;
use anyhow::{Context, Result};
use serde::Deserialize;
use splinewatch_core::solvers::truncation::TruncationReport;
use splinewatch_core::updating::frf_residual::UpdateProblem;
use splinewatch_core::updating::{
    HoldReason, IterationRecord, ModalSolution, ModalUpdateProblem, Parameter, UpdateResult,
};
use std::io::Write;

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
    super::parameters::values_by_name(parameters, base, &named_values(text)?, "start parameter")
}

/// The `{name, value}` pairs of a result's `"parameters"` list (`update
/// --json` output, the daemon's state file).
pub fn named_values(text: &str) -> Result<Vec<NamedValue>> {
    let start: StartFile = serde_json::from_str(text).context("not a result JSON with a \"parameters\" list")?;
    Ok(start
        .parameters
        .into_iter()
        .map(|p| NamedValue::new(p.name, p.value))
        .collect())
}

/// The updating parameters named in a file: an `update --json` result or a
/// state file.
pub fn named_values_of_file(path: &std::path::Path) -> Result<Vec<NamedValue>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    named_values(&text).with_context(|| path.display().to_string())
}

/// The FRFs of an FRF file's `bytes`: a universal file (dataset 58/58b,
/// recognised by content; nodes mapped by `[[sensors]] uff_node`) or FRF JSON.
pub fn read_frf_file(config: &Config, bytes: &[u8]) -> Result<FrfFile> {
    if uff::looks_like_uff(bytes) {
        return Ok(uff::read_frfs(bytes, &super::exchange::uff_points(config)?)?);
    }
    let text = std::str::from_utf8(bytes)
        .context("not FRF JSON (not UTF-8 text) nor a universal file (no -1 delimiter on its first line)")?;
    Ok(FrfFile::parse(text)?)
}

/// `splinewatch update`: runs the updating and returns its result, with
/// the truncation of the modal basis when the model is truncated.
pub fn update(
    config: &Config,
    frf_bytes: &[u8],
    start: Option<&str>,
    progress: &mut dyn FnMut(&IterationRecord),
) -> Result<(UpdateResult, Option<TruncationReport>)> {
    let setup = frf_setup(config)?;
    let frf = read_frf_file(config, frf_bytes)?;
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
    // The solution's model point: its state and FRFs are the fitted ones.
    let solution = problem.solve_from(&start, None, progress)?;
    let point = &solution.point;
    let truncation = setup.truncation_report(
        point.kappa(),
        point.theta(),
        point.damping(),
        point.state().modes.len(),
        Some((point.frfs(), problem.request())),
    )?;
    let result = solution.result;
    Ok((result, truncation))
}

/// `splinewatch update --modes`: modal-residue updating against identified modes.
pub fn update_from_modes(
    config: &Config,
    modes: &ModesFile,
    start: Option<&str>,
    progress: &mut dyn FnMut(&IterationRecord),
) -> Result<ModalSolution> {
    let setup = frf_setup(config)?;
    let observed = modes.to_observed(&setup.sensor_names)?;
    let parameters = config.build_parameters()?;
    let settings = config.update_settings()?;
    let base = splinewatch_core::updating::base_values(
        &parameters,
        &setup.kappa,
        setup.model.field_coefficients(),
        &setup.damping,
    );
    let problem = ModalUpdateProblem::new(
        &setup.model,
        setup.kappa.clone(),
        setup.damping.clone(),
        parameters.clone(),
        &observed,
        settings,
        (config.updating.min_mac, config.updating.max_frequency_gap),
    )?;
    let start = match start {
        Some(text) => start_values(text, &parameters, &base)?,
        None => base,
    };
    Ok(problem.solve(&start, progress)?)
}

/// One row of the parameter tables of `update` and `replay`: name, unit,
/// value, standard deviation and its percentage of the value.
pub fn write_parameter_row(
    out: &mut impl Write,
    config: &Config,
    name: &str,
    value: f64,
    std: Option<f64>,
) -> Result<()> {
    let (std, pct) = match std {
        Some(s) => (format!("{s:.4e}"), format!("{:.2}", 100.0 * s / value.abs())),
        None => ("unidentif.".to_string(), "-".to_string()),
    };
    write!(
        out,
        "{:<14} {:<6} {:>14.6e} {:>12} {:>7}",
        name,
        config.parameter_unit(name),
        value,
        std,
        pct
    )?;
    Ok(())
}

/// The header of the parameter tables (`bounds`: with lower and upper).
pub fn write_parameter_header(out: &mut impl Write, bounds: bool) -> Result<()> {
    write!(
        out,
        "{:<14} {:<6} {:>14} {:>12} {:>7}",
        "parameter", "unit", "value", "std", "std %"
    )?;
    if bounds {
        write!(out, " {:>12} {:>12}", "lower", "upper")?;
    }
    writeln!(out)?;
    Ok(())
}

/// The final table of `splinewatch update`.
pub fn write_update_table(config: &Config, result: &UpdateResult, out: &mut impl Write) -> Result<()> {
    write_parameter_header(out, true)?;
    for p in &result.parameters {
        write_parameter_row(out, config, &p.name, p.value, p.std)?;
        writeln!(out, " {:>12.4e} {:>12.4e}", p.lower, p.upper)?;
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
    if !result.held.is_empty() {
        let held: Vec<String> = result
            .held
            .iter()
            .map(|h| format!("{} ({}, kept at {:.4e})", h.name, hold_reason(h.reason), h.value))
            .collect();
        writeln!(out, "held, the data do not inform them: {}", held.join(", "))?;
    }
    if !result.correlations.is_empty() {
        let pairs: Vec<String> = result
            .correlations
            .iter()
            .take(3)
            .map(|c| format!("{}–{} {:+.2}", c.a, c.b, c.rho))
            .collect();
        writeln!(out, "most correlated estimates (ρ): {}", pairs.join(", "))?;
    }
    Ok(())
}

/// The words of a [`HoldReason`] in the tables (the JSON's snake_case).
pub fn hold_reason(reason: HoldReason) -> &'static str {
    match reason {
        HoldReason::NoGradient => "no gradient",
        HoldReason::AtBound => "at its bound",
        HoldReason::Unresolved => "unresolved",
    }
}
