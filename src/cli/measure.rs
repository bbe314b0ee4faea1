//! `simulate` and `frf`: making and analysing measurement recordings.

use super::parse_encoding;
use crate::config::{load_config, Config};
use crate::io::console::{errln, outln};
use crate::io::import::{self, CsvOptions};
use crate::io::recording::{read_recording, RecordedBlock, RecordingWriter};
use crate::io::wire::{self, Encoding};
use crate::outputs::publisher::Publisher;
use crate::pipeline::estimate;
use crate::studies::frf_windows;
use crate::studies::simulation::{self, Excitation, SimulationOptions};
use crate::studies::{self, import::ImportOptions};
use anyhow::{bail, Context, Result};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct SimulateArgs {
    /// Configuration file (TOML).
    #[arg(long)]
    pub config: PathBuf,
    /// Length of the recording, seconds.
    #[arg(long, required_unless_present_any = ["frf_windows", "ground"])]
    pub duration: Option<f64>,
    /// The deck's response to a record's ground channels (a station's .zip or .V2 files, or an
    /// MCAP of ground channels), written with them: --noise, --seed, --encoding and --out apply.
    #[arg(long, num_args = 1.., conflicts_with_all = ["frf_windows", "publish", "duration", "scenario"])]
    pub ground: Vec<PathBuf>,
    /// Instead of time series: a compact recording of N windows of
    /// pre-computed FRFs (model FRFs + --noise, at each window's
    /// temperature and damage state from --scenario) with the temperature
    /// blocks, for months of monitoring in seconds.
    #[arg(long, conflicts_with = "publish")]
    pub frf_windows: Option<usize>,
    /// Length of one FRF window, seconds (with --frf-windows).
    #[arg(long, default_value_t = 3600.0)]
    pub window_seconds: f64,
    /// Frequency step of the FRF lines over the config's band, Hz (with --frf-windows).
    #[arg(long, default_value_t = 0.25)]
    pub step_hz: f64,
    /// Sampling frequency of the recorded channels, Hz.
    #[arg(long, default_value_t = 256.0)]
    pub fs: f64,
    /// Time-varying scenario (TOML), e.g. a bearing losing stiffness.
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// Seed of the force and noise generators (ChaCha8): same seed, same bytes.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[arg(long, value_enum, default_value = "random")]
    pub excitation: Excitation,
    /// RMS of the force, N.
    #[arg(long, default_value_t = 1000.0)]
    pub force_rms: f64,
    /// Measurement noise, fraction of each channel's RMS.
    #[arg(long, default_value_t = 0.02)]
    pub noise: f64,
    /// Ambient excitation: number of unmeasured random force points (drawn from the seed).
    #[arg(long, default_value_t = 4)]
    pub sources: usize,
    /// Ambient excitation: a force point at X,Y metres (repeatable; replaces --sources).
    #[arg(long = "source-at", value_parser = parse_xy)]
    pub source_at: Vec<(f64, f64)>,
    /// Traffic excitation: vehicle speed, km/h.
    #[arg(long, default_value_t = 60.0)]
    pub speed_kmh: f64,
    /// Traffic excitation: mean arrivals per minute over both lanes (Poisson).
    #[arg(long, default_value_t = 12.0)]
    pub vehicles_per_minute: f64,
    /// Samples per message, seconds.
    #[arg(long, default_value_t = 1.0)]
    pub block_seconds: f64,
    /// Timestamp of the first sample (RFC 3339).
    #[arg(long, default_value = "2026-11-21T10:00:00Z")]
    pub start: String,
    /// Message encoding: cbor or json.
    #[arg(long, default_value = "cbor", value_parser = parse_encoding)]
    pub encoding: Encoding,
    /// Output recording (MCAP); optional with --publish.
    #[arg(long, required_unless_present = "publish")]
    pub out: Option<PathBuf>,
    /// Also publish the blocks live on zenoh (connecting to [zenoh] connect, or to its listen endpoints).
    #[arg(long)]
    pub publish: bool,
    /// Publishing pace in multiples of real time (0: as fast as possible).
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
}

#[derive(Args)]
pub struct FrfArgs {
    /// Configuration file (TOML).
    #[arg(long)]
    pub config: PathBuf,
    /// Recording (MCAP).
    pub input: PathBuf,
    /// Start of the analysed span: seconds from the recording's start, or RFC 3339.
    #[arg(long)]
    pub from: Option<String>,
    /// End of the analysed span: seconds from the recording's start, or RFC 3339.
    #[arg(long)]
    pub to: Option<String>,
    /// Write the FRFs here instead of stdout.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print the FRF JSON on stdout (the default without --out).
    #[arg(long)]
    pub json: bool,
    /// FRF JSON, or a universal file (datasets 164, 15, 82 and 58: FRFs
    /// and coherences on the sensors' nodes, `[[sensors]] uff_node`).
    #[arg(long, value_enum, default_value = "json")]
    pub format: FrfFormat,
}

#[derive(Clone, Copy, Debug, PartialEq, clap::ValueEnum)]
pub enum FrfFormat {
    Json,
    Uff,
}

#[derive(Clone, Copy, Debug, PartialEq, clap::ValueEnum)]
pub enum ExportFrfs {
    Measured,
    Model,
    None,
}

#[derive(Args)]
pub struct ExportArgs {
    /// Configuration file (TOML) the results were made with.
    #[arg(long)]
    pub config: PathBuf,
    /// Results MCAP file (daemon or replay).
    pub results: PathBuf,
    /// The window to export (default: the last updated one).
    #[arg(long)]
    pub window: Option<u64>,
    /// Which FRFs of the window go into the file.
    #[arg(long, value_enum, default_value = "measured")]
    pub frf: ExportFrfs,
    /// The model's modes (at the window's updated parameters) below this
    /// frequency; default: the top of the FRFs' band or of the identified modes.
    #[arg(long)]
    pub modes_below: Option<f64>,
    /// Output universal file (.unv or .uff).
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum ImportFormat {
    /// Comma-, semicolon- or tab-separated values with a header row.
    Csv,
    /// Universal file format, dataset 58 time responses (ASCII).
    Uff,
    /// CSMIP/COSMOS Volume 2 corrected accelerograms: .V2 files (one
    /// channel each, or a station's channels in one file) or a station's
    /// .zip; channel N is the column chN.
    V2,
}

#[derive(Args)]
pub struct ImportArgs {
    /// Configuration file (TOML): its [[sensors]] name the channels.
    #[arg(long, required_unless_present = "list")]
    pub config: Option<PathBuf>,
    /// File format.
    #[arg(long, value_enum)]
    pub format: ImportFormat,
    /// The logger's file (with --format v2: one or more .V2 or .zip files).
    #[arg(required = true, num_args = 1..)]
    pub input: Vec<PathBuf>,
    /// Output recording (MCAP).
    #[arg(long, required_unless_present = "list")]
    pub out: Option<PathBuf>,
    /// List the channels (V2: station channel, direction, location, rate, points, peak) and write nothing.
    #[arg(long)]
    pub list: bool,
    /// Sampling rate, Hz (when the file has no time column; overrides the file's).
    #[arg(long)]
    pub fs: Option<f64>,
    /// Time of the first sample, RFC 3339 (when the file's time is relative or absent).
    #[arg(long)]
    pub start: Option<String>,
    /// CSV: field delimiter (default: detected among `,`, `;`, tab).
    #[arg(long)]
    pub delimiter: Option<char>,
    /// CSV: numbers use a decimal comma (default: detected).
    #[arg(long)]
    pub decimal_comma: bool,
    /// CSV: the time column (default: one named time, t, time_s, timestamp or seconds).
    #[arg(long)]
    pub time_column: Option<String>,
    /// Samples per message, seconds.
    #[arg(long, default_value_t = 1.0)]
    pub block_seconds: f64,
    /// Message encoding: cbor or json.
    #[arg(long, default_value = "cbor", value_parser = parse_encoding)]
    pub encoding: Encoding,
    /// Refuse columns that name no sensor of the config (default: skip and list them).
    #[arg(long)]
    pub strict: bool,
    /// The unit of every column without one (e.g. cm/s^2, gal, g, mg, kN); a units row wins.
    #[arg(long)]
    pub units: Option<String>,
}

pub fn import(a: ImportArgs) -> Result<()> {
    let mut files = Vec::new();
    for path in &a.input {
        let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
        files.push((bytes, path.display().to_string()));
    }
    if files.len() > 1 && !matches!(a.format, ImportFormat::V2) {
        let input = files.iter().map(|(_, n)| n.as_str()).collect::<Vec<_>>().join(", ");
        bail!("--format {:?} reads one file, got {}: {input}", a.format, files.len());
    }
    // V2 errors name their own file; one file names itself here.
    let input = if files.len() == 1 {
        files[0].1.clone()
    } else {
        format!("{} files", files.len())
    };
    if a.list {
        return list_channels(&a, &files);
    }
    let (Some(config), Some(out)) = (&a.config, &a.out) else {
        bail!("import needs --config and --out (or --list)");
    };
    let cfg = load_config(config)?;
    let bytes = &files[0].0;
    let series = match a.format {
        ImportFormat::Csv => {
            let text = std::str::from_utf8(bytes).with_context(|| format!("cannot read {input}: not UTF-8 text"))?;
            let delimiter = a
                .delimiter
                .map(|d| u8::try_from(d).map_err(|_| anyhow::anyhow!("--delimiter {d:?} is not one ASCII character")))
                .transpose()?;
            let options = CsvOptions {
                delimiter,
                decimal_comma: a.decimal_comma.then_some(true),
                time_column: a.time_column.clone(),
            };
            import::read_csv(text, &options).with_context(|| input.clone())
        }
        ImportFormat::Uff => import::read_uff58(bytes).with_context(|| input.clone()),
        ImportFormat::V2 => Ok(crate::io::cosmos_v2::read_v2(&files)?),
    }?;
    for note in &series.notes {
        errln!("{input}: {note}");
    }
    let notes = series.notes.clone();
    let start_ns = a
        .start
        .as_deref()
        .map(|s| wire::parse_timestamp(s).with_context(|| format!("--start {s:?} is not an RFC 3339 timestamp")))
        .transpose()?;
    let options = ImportOptions {
        fs: a.fs,
        start_ns,
        block_seconds: a.block_seconds,
        strict: a.strict,
        units: a.units.clone(),
    };
    let imported = studies::import::to_blocks(&cfg, series, &options).with_context(|| input.clone())?;
    if !imported.skipped.is_empty() {
        errln!(
            "skipped {} columns that name no sensor of the config: {}",
            imported.skipped.len(),
            imported.skipped.join(", ")
        );
    }
    let blocks = imported.blocks;
    let prefix = cfg.topic_prefix();
    let mut writer = RecordingWriter::create(out, a.encoding)?;
    if !notes.is_empty() {
        writer.write_import_notes(&input, &notes)?;
    }
    for b in &blocks {
        writer.write_block(&prefix, b)?;
    }
    writer.finish()?;
    errln!("{} blocks from {input} written to {}", blocks.len(), out.display());
    Ok(())
}

/// `import --list`: one line per channel (V2), or the columns (CSV, UFF).
fn list_channels(a: &ImportArgs, files: &[(Vec<u8>, String)]) -> Result<()> {
    if !matches!(a.format, ImportFormat::V2) {
        let series = match a.format {
            ImportFormat::Uff => import::read_uff58(&files[0].0),
            _ => {
                let text =
                    std::str::from_utf8(&files[0].0).with_context(|| format!("{}: not UTF-8 text", files[0].1))?;
                import::read_csv(text, &CsvOptions::default())
            }
        }
        .with_context(|| files[0].1.clone())?;
        outln!("column\tunit\tpoints\tpeak");
        for c in &series.channels {
            let peak = c.data.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            outln!(
                "{}\t{}\t{}\t{peak:.6}",
                c.name,
                c.unit.as_deref().unwrap_or("-"),
                c.data.len()
            );
        }
        return Ok(());
    }
    let channels = crate::io::cosmos_v2::list_v2(files)?;
    outln!("column\tdirection\tlocation\trate_hz\tpoints\tpeak\tunit\tfile");
    for c in &channels {
        outln!(
            "ch{}\t{}\t{}\t{}\t{}\t{:.4}\t{}\t{}",
            c.channel,
            c.direction,
            c.location,
            c.rate_hz,
            c.points,
            c.peak,
            c.unit,
            c.file
        );
    }
    Ok(())
}

pub fn simulate(a: SimulateArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    let scenario = a
        .scenario
        .as_ref()
        .map(|p| {
            let text = std::fs::read_to_string(p).with_context(|| format!("cannot read scenario {}", p.display()))?;
            simulation::parse_scenario(&text).with_context(|| format!("scenario {}", p.display()))
        })
        .transpose()?;
    let start_ns = wire::parse_timestamp(&a.start)
        .with_context(|| format!("--start {:?} is not an RFC 3339 timestamp", a.start))?;
    if !a.ground.is_empty() {
        let Some(out) = &a.out else {
            bail!("simulate --ground needs --out");
        };
        return super::ground::simulate_ground(&cfg, &a.ground, a.noise, a.seed, a.encoding, out);
    }
    if let Some(windows) = a.frf_windows {
        return simulate_frf_windows(&cfg, scenario.unwrap_or_default(), &a, windows, start_ns);
    }
    let options = SimulationOptions {
        duration_seconds: a.duration.expect("required without --frf-windows"),
        fs: a.fs,
        seed: a.seed,
        excitation: a.excitation,
        force_rms: a.force_rms,
        noise: a.noise,
        block_seconds: a.block_seconds,
        start_ns,
        band: (cfg.frf.band[0].max(0.1), cfg.frf.band[1] * 1.1),
        // An unmeasured force's hold loss only colours an unknown input.
        oversample: if a.excitation.is_unmeasured() { 4 } else { 16 },
        scenario,
        sources: a.sources,
        source_xy: a.source_at,
        speed_kmh: a.speed_kmh,
        vehicles_per_minute: a.vehicles_per_minute,
    };
    let prefix = cfg.topic_prefix();
    let mut writer = a
        .out
        .as_ref()
        .map(|p| RecordingWriter::create(p, a.encoding))
        .transpose()?;
    let mut publisher = if a.publish {
        Some(simulator_publisher(&cfg, a.encoding, a.speed)?)
    } else {
        None
    };
    let summary = simulation::simulate(&cfg, &options, &mut |block| {
        if let Some(w) = writer.as_mut() {
            w.write_block(&prefix, &block)?;
        }
        if let Some(p) = publisher.as_mut() {
            p.publish(&block)?;
        }
        Ok(())
    })?;
    if let Some(w) = writer {
        w.finish()?;
    }
    if let Some(p) = publisher {
        p.close()?;
    }
    errln!(
        "{} blocks ({} samples per channel, {} model updates){}{}",
        summary.blocks,
        summary.samples_per_channel,
        summary.model_updates,
        a.out
            .as_ref()
            .map(|p| format!(", written to {}", p.display()))
            .unwrap_or_default(),
        if a.publish { ", published on zenoh" } else { "" }
    );
    Ok(())
}

/// `simulate --frf-windows`: the compact FRF recording.
fn simulate_frf_windows(
    cfg: &Config,
    scenario: simulation::Scenario,
    a: &SimulateArgs,
    windows: usize,
    start_ns: i128,
) -> Result<()> {
    let Some(out) = &a.out else {
        anyhow::bail!("--frf-windows needs --out");
    };
    let prefix = cfg.topic_prefix();
    let mut writer = RecordingWriter::create(out, a.encoding)?;
    let options = frf_windows::FrfWindowOptions {
        windows,
        window_seconds: a.window_seconds,
        start_ns,
        noise: a.noise,
        step_hz: a.step_hz,
        seed: a.seed,
    };
    let mut messages = 0u64;
    frf_windows::simulate_frf_windows(cfg, &scenario, &options, &mut |record| {
        messages += 1;
        match record {
            frf_windows::FrfRecord::Temperature(block) => writer.write_block(&prefix, &block).map(|_| ()),
            frf_windows::FrfRecord::Frf { key, time_ns, payload } => writer
                .write_json(&format!("{prefix}/{key}"), time_ns, &payload)
                .map(|_| ()),
        }
    })?;
    writer.finish()?;
    errln!(
        "{windows} FRF windows of {} s ({messages} messages) written to {}",
        a.window_seconds,
        out.display()
    );
    Ok(())
}

/// The simulator's publisher: a zenoh client of the config's `connect`
/// endpoints, or of its `listen` ones (where the daemon listens).
fn simulator_publisher(cfg: &Config, encoding: Encoding, speed: f64) -> Result<Publisher> {
    let mut z = cfg.zenoh.clone();
    if z.connect.is_empty() {
        z.connect = std::mem::take(&mut z.listen);
    }
    z.listen.clear();
    z.mode = "client".into();
    Publisher::open(&z, cfg.topic_prefix(), encoding, speed)
}

pub fn frf(a: FrfArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    let blocks = read_recordings(&cfg, std::slice::from_ref(&a.input))?;
    let (from, to) = span_bounds(&blocks, &a.from, &a.to)?;
    let report = estimate::estimate(&cfg, &blocks, from, to)?;
    errln!(
        "{} samples from {}: {} segments used, {} rejected, {:.1} effective averages, {} FRFs × {} lines",
        report.samples,
        wire::format_timestamp(report.start_ns),
        report.segments.accepted,
        report.segments.rejected(),
        report.effective_averages,
        report.frf.frfs.len(),
        report.frf.frequency_hz.len()
    );
    let text = match a.format {
        FrfFormat::Json => serde_json::to_string(&report.frf)?,
        FrfFormat::Uff => studies::exchange::uff_file(
            &cfg,
            &studies::exchange::UffContent {
                frfs: Some((&report.frf, "measured")),
                ..Default::default()
            },
        )?,
    };
    match a.out {
        Some(path) => std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))?,
        None => outln!("{text}"),
    }
    Ok(())
}

/// Every channel block of the recordings, in file order; skipped messages
/// are reported on stderr.
fn read_recordings(cfg: &crate::config::Config, inputs: &[PathBuf]) -> Result<Vec<RecordedBlock>> {
    let limits = crate::pipeline::block_limits(cfg);
    let mut blocks = Vec::new();
    for input in inputs {
        let bytes = std::fs::read(input).with_context(|| format!("cannot read {}", input.display()))?;
        let (mut read, rejected) =
            read_recording(&bytes, &limits).with_context(|| format!("reading {}", input.display()))?;
        for r in &rejected {
            errln!(
                "{}: skipped a message on {} at {} ns: {}",
                input.display(),
                r.topic,
                r.log_time,
                r.error
            );
        }
        blocks.append(&mut read);
    }
    Ok(blocks)
}

/// `--from`/`--to` as absolute times: seconds from the recordings' first
/// sample, or RFC 3339.
fn span_bounds(
    blocks: &[RecordedBlock],
    from: &Option<String>,
    to: &Option<String>,
) -> Result<(Option<i128>, Option<i128>)> {
    let origin = blocks
        .iter()
        .map(|b| b.block.start_ns)
        .min()
        .context("the recording holds no channel blocks")?;
    let when = |s: &Option<String>| -> Result<Option<i128>> {
        s.as_ref()
            .map(|t| match t.parse::<f64>() {
                Ok(sec) => Ok(origin + (sec * 1e9).round() as i128),
                Err(_) => wire::parse_timestamp(t)
                    .with_context(|| format!("{t:?} is neither seconds nor an RFC 3339 timestamp")),
            })
            .transpose()
    };
    Ok((when(from)?, when(to)?))
}

#[derive(Args)]
pub struct OmaArgs {
    /// Configuration file (TOML): its acceleration sensors and [oma] settings.
    #[arg(long)]
    pub config: PathBuf,
    /// Recordings (MCAP), read as one: their blocks must form continuous channels.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Start of the analysed span: seconds from the recordings' start, or RFC 3339.
    #[arg(long)]
    pub from: Option<String>,
    /// End of the analysed span: seconds from the recordings' start, or RFC 3339.
    #[arg(long)]
    pub to: Option<String>,
    #[command(flatten)]
    pub output: super::identified::ModesOutput,
    #[command(flatten)]
    pub comparison: super::identified::ModelComparison,
}

/// `splinewatch oma`: output-only modal identification of a recorded span.
pub fn oma(a: OmaArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    let blocks = read_recordings(&cfg, &a.inputs)?;
    let (from, to) = span_bounds(&blocks, &a.from, &a.to)?;
    let report = crate::pipeline::oma::identify_span(&cfg, &blocks, from, to, a.output.rerun_save.is_some())?;
    let stable = report.result.diagram.iter().filter(|p| p.stable).count();
    errln!(
        "{} samples ({:.1} s at {} Hz) of {} channels from {}: {} poles, {} stable, {} modes",
        report.samples,
        report.samples as f64 / report.fs,
        report.fs,
        report.sensors.len(),
        wire::format_timestamp(report.start_ns),
        report.result.diagram.len(),
        stable,
        report.result.modes.len()
    );
    super::identified::write_identified(&cfg, &report, &[], &a.output, &a.comparison)
}

fn parse_xy(s: &str) -> Result<(f64, f64), String> {
    let (x, y) = s.split_once(',').ok_or_else(|| format!("{s:?} is not X,Y (metres)"))?;
    let number = |v: &str| {
        v.trim()
            .parse::<f64>()
            .map_err(|_| format!("{v:?} in {s:?} is not a number"))
    };
    Ok((number(x)?, number(y)?))
}

pub fn export(a: ExportArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    let bytes = std::fs::read(&a.results).with_context(|| format!("cannot read {}", a.results.display()))?;
    let w = crate::service::export::window_results(&bytes, &cfg.topic_prefix(), a.window)
        .with_context(|| format!("results file {}", a.results.display()))?;
    let frfs = match a.frf {
        ExportFrfs::Measured => Some(w.measured.as_ref().map(|f| (f, "measured"))),
        ExportFrfs::Model => Some(w.model.as_ref().map(|f| (f, "model"))),
        ExportFrfs::None => None,
    };
    if frfs == Some(None) {
        anyhow::bail!(
            "window {}: no {:?} FRFs in the results (an output-only window has none: --frf none)",
            w.window,
            a.frf
        );
    }
    let frfs = frfs.flatten();
    let top = frfs
        .and_then(|(f, _)| f.frequency_hz.last().copied())
        .or_else(|| w.identified.iter().map(|m| m.frequency_hz).reduce(f64::max));
    let modes_below = match (a.modes_below, top) {
        (Some(f), _) if f.is_finite() && f > 0.0 => f,
        (Some(f), _) => anyhow::bail!("--modes-below {f}: must be a positive frequency in Hz"),
        (None, Some(top)) => top,
        (None, None) => anyhow::bail!("--modes-below is needed: the window has no FRFs and no identified modes"),
    };
    let text = studies::exchange::uff_file(
        &cfg,
        &studies::exchange::UffContent {
            frfs,
            model_modes_below_hz: Some(modes_below),
            parameters: &w.parameters,
            identified: &w.identified,
        },
    )?;
    let mut file = crate::io::files::create_output_file(&a.out)?;
    std::io::Write::write_all(&mut file, text.as_bytes())
        .with_context(|| format!("cannot write {}", a.out.display()))?;
    errln!(
        "window {}: {} FRFs, model modes up to {modes_below:.2} Hz, {} identified modes → {}",
        w.window,
        frfs.map_or(0, |(f, _)| f.frfs.len()),
        w.identified.len(),
        a.out.display()
    );
    Ok(())
}
