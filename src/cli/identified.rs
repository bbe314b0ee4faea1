//! Where an identification's modes go (`oma`, `identify`): the Rerun file,
//! the modes file, and the modes as JSON or a table on stdout, each with
//! the model mode nearest it by shape when the config has a model.

use crate::config::Config;
use crate::io::console::outln;
use anyhow::{bail, Context, Result};
use clap::Args;
use std::path::PathBuf;

/// Where an identification's modes go (`oma`, `identify`).
#[derive(Args)]
pub struct ModesOutput {
    /// Print the modes as JSON (`{"modes":[…]}`) instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Also write the modes JSON to this file (for `update --modes`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write the stabilisation diagram and the modes with ±1σ (the fitted ones too) to a Rerun
    /// `.rrd` file; with a `[model]` also the deck, its sensors and the model's views.
    #[arg(long)]
    pub rerun_save: Option<PathBuf>,
}

/// The model an identification is compared with (`oma`, `identify`).
#[derive(Args)]
pub struct ModelComparison {
    /// Compare the modes with the model at these parameters (`update --json` output or a state
    /// file) instead of the config's values. With a `[model]`, each identified mode is shown with
    /// the model mode nearest it by shape (MAC), whatever its frequency.
    #[arg(long)]
    pub parameters: Option<PathBuf>,
}

/// The outputs of an identification (`oma`, `identify`): the Rerun file,
/// the modes file, and the modes as JSON or a table on stdout; with a
/// model, each mode with the model mode nearest it by shape.
pub(super) fn write_identified(
    cfg: &Config,
    report: &crate::pipeline::oma::OmaReport,
    fitted: &[crate::io::modes_json::ModeEntry],
    output: &ModesOutput,
    comparison: &ModelComparison,
) -> Result<()> {
    let (rerun_save, out, json) = (output.rerun_save.as_deref(), output.out.as_deref(), output.json);
    if let Some(path) = rerun_save {
        save_rerun(cfg, path, report, fitted)?;
    }
    let mut file = report.modes_file();
    file.modes = crate::service::frequency_domain::merged(file.modes, fitted);
    match (&comparison.parameters, cfg.has_model()) {
        (Some(path), false) => bail!(
            "--parameters {}: the config has no [model] to compare the modes with",
            path.display()
        ),
        (parameters, true) => {
            let named = match parameters {
                Some(path) => crate::studies::update::named_values_of_file(path)?,
                None => Vec::new(),
            };
            crate::studies::mode_match::match_with_model(cfg, &mut file, &named)
                .context("comparing the modes with the model's")?;
        }
        (None, false) => {}
    }
    if let Some(path) = out {
        std::fs::write(path, serde_json::to_string_pretty(&file)?)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if json {
        outln!("{}", serde_json::to_string(&file)?);
        return Ok(());
    }
    let or_dash = |v: Option<f64>, scale: f64, digits: usize| match v {
        Some(x) => format!("{:.*}", digits, x * scale),
        None => "-".into(),
    };
    let with_model = cfg.has_model();
    outln!(
        " mode  frequency Hz    ± std Hz  damping %  ± std %    MPC  orders{}",
        if with_model {
            "  model mode  model Hz  model ζ %    MAC    Δf %  pairs"
        } else {
            ""
        }
    );
    for (i, entry) in file.modes.iter().enumerate() {
        let model = match (&entry.model, with_model) {
            (Some(n), _) => format!(
                "  {:10}  {:8.4}  {:9.3}  {:5.3}  {:+6.1}  {:>5}",
                n.mode,
                n.frequency_hz,
                100.0 * n.damping_ratio,
                n.mac,
                100.0 * n.frequency_gap,
                if n.pairs { "yes" } else { "no" }
            ),
            (None, true) => "  no flexible model mode".into(),
            (None, false) => String::new(),
        };
        // A fitted mode has no MPC and no orders: "fit" says how it was found.
        let (mpc, orders) = match (entry.mpc, entry.stable_orders) {
            (Some(mpc), Some(orders)) => (format!("{mpc:5.3}"), orders.to_string()),
            _ => ("    -".into(), "fit".into()),
        };
        outln!(
            "{:5}  {:12.4}  {:>10}  {:9.3}  {:>7}  {mpc}  {orders:6}{model}",
            i + 1,
            entry.frequency_hz,
            or_dash(entry.frequency_std_hz, 1.0, 4),
            100.0 * entry.damping_ratio,
            or_dash(entry.damping_std, 100.0, 3),
        );
    }
    Ok(())
}

/// The identification in a Rerun file at `path`: with a `[model]` on the
/// model's stream (the deck, its sensors, the model's views); without one
/// (a station's starter config) the identification alone.
fn save_rerun(
    cfg: &Config,
    path: &std::path::Path,
    report: &crate::pipeline::oma::OmaReport,
    fitted: &[crate::io::modes_json::ModeEntry],
) -> Result<()> {
    if cfg.has_model() {
        let targets = crate::outputs::rerun::RerunTargets {
            save: Some(path.to_path_buf()),
            connect: None,
        };
        let mut rerun = crate::outputs::rerun::RerunOutput::open(cfg, &targets)?;
        rerun.log_oma(report)?;
        rerun.log_fitted(report, fitted)?;
        rerun.finish()
    } else {
        let mut rerun = crate::outputs::rerun::IdentificationFile::save(path)?;
        rerun.log(report, fitted)?;
        rerun.close()
    }
}
