//! The command line: argument parsing (clap) and one small function per
//! command, grouped by family; output to the console happens here.
//! Room: the top. May import: `service`, `outputs`, `pipeline`, `studies`, `config`, `io`, the core crate.

mod events;
mod events_plot;
mod ground;
mod identified;
mod measure;
mod model;
mod monitor;
mod reference;
mod report;
mod station;

use crate::io::console::errln;
use anyhow::Result;
use clap::{Parser, Subcommand};
use splinewatch_core::response::frf::Quantity;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "splinewatch",
    version,
    about = "Vibration-based structural health monitoring: B-spline shell FE model updating from FRFs"
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Natural frequencies and mode kinds of the configured model.
    Modes(model::ModesArgs),
    /// The model's matrices for other tools: K, K_f, M and every ∂K/∂parameter in
    /// Matrix Market (free coordinates) with a JSON index of the dofs.
    Matrices(model::MatricesArgs),
    /// Model FRFs at sensors, optionally with the paper's noise model, as FRF JSON.
    Synth(model::SynthArgs),
    /// FRF-based model updating of the configured model against measured FRFs.
    Update(model::UpdateArgs),
    /// Reproduce the paper's §4 experiments on the bundled Sinello model and
    /// write a Markdown report and ζ(f) plots to a folder.
    Paper(model::PaperArgs),
    /// Simulate the configured bridge under excitation and write a raw-input MCAP recording.
    Simulate(measure::SimulateArgs),
    /// Convert a logger's time series (CSV/TSV or UFF 58) into a raw-input
    /// MCAP recording, one channel per column, named after the config's sensors.
    Import(measure::ImportArgs),
    /// Drive the model with a record's ground channels and compare the predicted and measured deck accelerations.
    Predict(ground::PredictArgs),
    /// Input–output modal identification (SRIM) of a record with measured inputs (ground channels or a force).
    Identify(ground::IdentifyArgs),
    /// A starter config from a strong-motion station's records (CESMD Volume 2 zips): every channel by
    /// its station number and orientation, the ground channels as support groups, `[oma]` and `[events]`.
    Station(station::StationArgs),
    /// Earthquake by earthquake: each record identified, forecast by the model of the events before it,
    /// updated on its transmissibilities and judged against the earlier events at its amplitude.
    Events(events::EventsArgs),
    /// One update of a results file as a universal file for modal-testing
    /// software: the sensors' geometry (datasets 15, 82), the window's
    /// measured or model FRFs (58), the model's modes at its updated
    /// parameters and the identified modes (55), SI units (164).
    Export(measure::ExportArgs),
    /// Estimate FRFs (Welch, [frf] settings) from a raw-input MCAP recording.
    Frf(measure::FrfArgs),
    /// Output-only modal identification (SSI-cov, [oma] settings) of raw-input
    /// MCAP recordings: frequencies, damping ratios, their standard deviations, shapes.
    Oma(measure::OmaArgs),
    /// Run the monitoring pipeline over raw-input recordings as fast as the CPU allows.
    Replay(monitor::ReplayArgs),
    /// Run the monitoring daemon: zenoh ingest until SIGINT/SIGTERM.
    Run(monitor::RunArgs),
    /// The whole live path in one process: the simulator publishes a bearing-damage
    /// scenario over zenoh on loopback at high speed, the daemon updates the model.
    Demo(monitor::DemoArgs),
    /// Soak test: the daemon in one process with a publisher replaying a
    /// recording in a loop at --speed × real time, for many hours of data; reports RSS.
    Soak(monitor::SoakArgs),
    /// Re-run the statistical layer ([monitoring]) offline over results MCAP
    /// files: re-train on a chosen span, re-score every update, write a new
    /// results file and print the alarms.
    Monitor(monitor::MonitorArgs),
    /// The status of every span behind a zenoh router: one line per span
    /// (name, last update, parameters, monitoring state, health) from the
    /// daemons' `bridge/*/{updating,monitoring,health}/latest` queryables.
    Fleet(monitor::FleetArgs),
    /// The owner's report of an event or a period from a bridge's results
    /// files: one self-contained HTML file (verdict and inspection priority
    /// first, figures inline), for an e-mail or a phone.
    Report(report::ReportArgs),
    /// Salvage an MCAP file left unfinished by a killed process (results,
    /// raw-input `.part` files): copies every message of every complete chunk
    /// into a new, finalised file.
    Recover(monitor::RecoverArgs),
    /// Validate a configuration file without running anything.
    CheckConfig(model::CheckConfigArgs),
    /// The JSON Schema of the configuration file, for editors that complete
    /// and check TOML keys (Taplo / Even Better TOML).
    ConfigSchema(reference::ConfigSchemaArgs),
    /// The guide's generated reference pages as Markdown (cli, config, topics).
    #[command(hide = true)]
    Reference(reference::ReferenceArgs),
}

/// The command table: each command is one small function of its arguments.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Modes(args) => model::modes(args),
        Command::Matrices(args) => model::matrices(args),
        Command::Synth(args) => model::synth(args),
        Command::Update(args) => model::update(args),
        Command::Paper(args) => model::paper(args),
        Command::Simulate(args) => measure::simulate(args),
        Command::Frf(args) => measure::frf(args),
        Command::Oma(args) => measure::oma(args),
        Command::Import(args) => measure::import(args),
        Command::Predict(args) => ground::predict(args),
        Command::Identify(args) => ground::identify(args),
        Command::Station(args) => station::station(args),
        Command::Events(args) => events::events(args),
        Command::Export(args) => measure::export(args),
        Command::Replay(args) => monitor::replay(args),
        Command::Run(args) => monitor::run(args),
        Command::Demo(args) => monitor::demo(args),
        Command::Soak(args) => monitor::soak(args),
        Command::Recover(args) => monitor::recover(args),
        Command::Report(args) => report::report(args),
        Command::Monitor(args) => monitor::monitor(args),
        Command::Fleet(args) => monitor::fleet(args),
        Command::CheckConfig(args) => model::check_config(args),
        Command::ConfigSchema(args) => reference::config_schema(args),
        Command::Reference(args) => reference::reference(args),
    }
}

fn parse_quantity(s: &str) -> Result<Quantity, String> {
    match s {
        "receptance" => Ok(Quantity::Receptance),
        "mobility" => Ok(Quantity::Mobility),
        "accelerance" => Ok(Quantity::Accelerance),
        other => Err(format!("{other:?} is not receptance, mobility or accelerance")),
    }
}

fn parse_encoding(s: &str) -> Result<crate::io::wire::Encoding, String> {
    crate::io::wire::Encoding::from_name(s).ok_or_else(|| format!("{s:?} is not cbor or json"))
}

/// Caps the zenoh module that logs the session configuration (secrets
/// included) at debug level.
const NO_SECRETS_DIRECTIVE: &str = "zenoh::api::session=info";

/// The process: logging set up, the command run, its error printed once.
pub fn main() -> ExitCode {
    let json_logs = std::env::var("SPLINEWATCH_LOG_FORMAT").is_ok_and(|v| v == "json");
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info,zenoh=warn"))
        // zenoh logs its whole session configuration at debug level,
        // user/password included: never below info, whatever RUST_LOG says.
        .add_directive(NO_SECRETS_DIRECTIVE.parse().expect("a valid directive"));
    // A closed stderr drops (and counts) log lines instead of panicking in
    // tracing's own error report; colours only on a terminal.
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(crate::io::console::LogWriter)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .log_internal_errors(false);
    if json_logs {
        builder.json().init();
    } else {
        builder.init();
    }
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            errln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
