//! `splinewatch modes`: the configured model's natural frequencies and mode kinds.

use crate::config::Config;
use anyhow::{Context, Result};
use serde::Serialize;
use splinewatch_core::modal::ModeKind;
use std::io::Write;
use std::time::Instant;

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
