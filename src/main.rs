//! The `splinewatch` command line.
#![forbid(unsafe_code)]

use anyhow::Result;
use clap::{Parser, Subcommand};
use splinewatch::commands;
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "splinewatch",
    version,
    about = "Vibration-based structural health monitoring: B-spline shell FE model updating from FRFs"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Natural frequencies and mode kinds of the configured model.
    Modes {
        /// Configuration file (TOML).
        #[arg(long)]
        config: PathBuf,
        /// How many modes to list, lowest first.
        #[arg(long, default_value_t = 30)]
        count: usize,
        /// Print `{"modes":[{"index","frequency_hz","kind"}…]}` instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Validate a configuration file without running anything.
    CheckConfig {
        /// Configuration file (TOML).
        config: PathBuf,
    },
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Modes { config, count, json } => {
            let cfg = commands::load_config(&config)?;
            let (report, info) = commands::compute_modes(&cfg, count)?;
            eprintln!(
                "{}: {} dofs ({} free), assembly {:.3} s, eigen-solve {:.3} s",
                cfg.structure.name, info.dofs, info.free_dofs, info.assembly_seconds, info.solve_seconds
            );
            let stdout = std::io::stdout();
            let mut out = stdout.lock();
            commands::write_modes(&report, json, &mut out)?;
            out.flush()?;
        }
        Command::CheckConfig { config } => {
            let cfg = commands::load_config(&config)?;
            println!("{}: configuration is valid", cfg.structure.name);
        }
    }
    Ok(())
}
