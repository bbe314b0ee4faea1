//! Where an identification's modes go (`oma`, `identify`): the Rerun file,
//! the modes file, and the modes as JSON or a table on stdout.

use crate::config::Config;
use crate::io::console::outln;
use anyhow::{Context, Result};
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
    /// Write the stabilisation diagram and the modes with ±1σ to a Rerun `.rrd` file.
    #[arg(long)]
    pub rerun_save: Option<PathBuf>,
}

/// The outputs of an identification (`oma`, `identify`): the Rerun file,
/// the modes file, and the modes as JSON or a table on stdout.
pub(super) fn write_identified(
    cfg: &Config,
    report: &crate::pipeline::oma::OmaReport,
    output: &ModesOutput,
) -> Result<()> {
    let (rerun_save, out, json) = (output.rerun_save.as_deref(), output.out.as_deref(), output.json);
    if let Some(path) = rerun_save {
        let targets = crate::outputs::rerun::RerunTargets {
            save: Some(path.to_path_buf()),
            connect: None,
        };
        let mut rerun = crate::outputs::rerun::RerunOutput::open(cfg, &targets)?;
        rerun.log_oma(report)?;
        rerun.finish()?;
    }
    let file = report.modes_file();
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
    outln!(" mode  frequency Hz    ± std Hz  damping %  ± std %    MPC  orders");
    for (i, m) in report.result.modes.iter().enumerate() {
        outln!(
            "{:5}  {:12.4}  {:>10}  {:9.3}  {:>7}  {:5.3}  {:6}",
            i + 1,
            m.frequency_hz,
            or_dash(m.frequency_std_hz, 1.0, 4),
            100.0 * m.damping_ratio,
            or_dash(m.damping_std, 100.0, 3),
            m.mpc,
            m.stable_orders
        );
    }
    Ok(())
}
