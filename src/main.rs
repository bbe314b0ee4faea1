//! The `splinewatch` command line.
#![forbid(unsafe_code)]

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use splinewatch::commands;
use splinewatch_core::frf::Quantity;
use splinewatch_core::updating::IterationRecord;
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
    /// Model FRFs at sensors, optionally with the paper's noise model, as FRF JSON.
    Synth {
        #[arg(long)]
        config: PathBuf,
        /// Input (force) sensors, comma-separated.
        #[arg(long, value_delimiter = ',', required = true)]
        inputs: Vec<String>,
        /// Output (response) sensors, comma-separated.
        #[arg(long, value_delimiter = ',', required = true)]
        outputs: Vec<String>,
        /// receptance, mobility or accelerance.
        #[arg(long, default_value = "accelerance", value_parser = parse_quantity)]
        quantity: Quantity,
        /// Lowest frequency line, Hz.
        #[arg(long, default_value_t = 0.5)]
        from: f64,
        /// Highest frequency line, Hz.
        #[arg(long, default_value_t = 80.0)]
        to: f64,
        /// Line spacing, Hz.
        #[arg(long, default_value_t = 0.1)]
        step: f64,
        /// Complex Gaussian noise, standard deviation as a fraction of each FRF's RMS.
        #[arg(long, default_value_t = 0.0)]
        noise: f64,
        /// Seed of the noise generator (ChaCha8).
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Output file (FRF JSON).
        #[arg(long)]
        out: PathBuf,
    },
    /// FRF-based model updating of the configured model against measured FRFs.
    Update {
        #[arg(long)]
        config: PathBuf,
        /// Measured FRFs (FRF JSON).
        #[arg(long)]
        frf: PathBuf,
        /// Start from a previous result (`update --json` output) instead of the config's values.
        #[arg(long)]
        start: Option<PathBuf>,
        /// Print the result as JSON on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Reproduce the paper's §4 experiments on the bundled Sinello model and
    /// write a Markdown report and ζ(f) plots to a folder.
    Paper {
        /// Output folder.
        #[arg(long, default_value = "docs/paper")]
        out: PathBuf,
    },
    /// Simulate the configured bridge under excitation and write a raw-input MCAP recording.
    Simulate {
        #[arg(long)]
        config: PathBuf,
        /// Length of the recording, seconds.
        #[arg(long)]
        duration: f64,
        /// Sampling frequency of the recorded channels, Hz.
        #[arg(long, default_value_t = 256.0)]
        fs: f64,
        /// Time-varying scenario (TOML), e.g. a bearing losing stiffness.
        #[arg(long)]
        scenario: Option<PathBuf>,
        /// Seed of the force and noise generators (ChaCha8): same seed, same bytes.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        #[arg(long, value_enum, default_value = "random")]
        excitation: splinewatch::simulation::Excitation,
        /// RMS of the force, N.
        #[arg(long, default_value_t = 1000.0)]
        force_rms: f64,
        /// Measurement noise, fraction of each channel's RMS.
        #[arg(long, default_value_t = 0.02)]
        noise: f64,
        /// Samples per message, seconds.
        #[arg(long, default_value_t = 1.0)]
        block_seconds: f64,
        /// Timestamp of the first sample (RFC 3339).
        #[arg(long, default_value = "2026-11-21T10:00:00Z")]
        start: String,
        /// Message encoding: cbor or json.
        #[arg(long, default_value = "cbor", value_parser = parse_encoding)]
        encoding: splinewatch::wire::Encoding,
        /// Output recording (MCAP); optional with --publish.
        #[arg(long, required_unless_present = "publish")]
        out: Option<PathBuf>,
        /// Also publish the blocks live on zenoh (connecting to [zenoh] connect, or to its listen endpoints).
        #[arg(long)]
        publish: bool,
        /// Publishing pace in multiples of real time (0: as fast as possible).
        #[arg(long, default_value_t = 1.0)]
        speed: f64,
    },
    /// Estimate FRFs (Welch, [frf] settings) from a raw-input MCAP recording.
    Frf {
        #[arg(long)]
        config: PathBuf,
        /// Recording (MCAP).
        input: PathBuf,
        /// Start of the analysed span: seconds from the recording's start, or RFC 3339.
        #[arg(long)]
        from: Option<String>,
        /// End of the analysed span: seconds from the recording's start, or RFC 3339.
        #[arg(long)]
        to: Option<String>,
        /// Write the FRF JSON here instead of stdout.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print the FRF JSON on stdout (the default without --out).
        #[arg(long)]
        json: bool,
    },
    /// Run the monitoring pipeline over raw-input recordings as fast as the CPU allows.
    Replay {
        #[arg(long)]
        config: PathBuf,
        /// Recordings (MCAP), replayed in the order given (e.g. a daemon's rotated raw files).
        #[arg(required = true)]
        inputs: Vec<PathBuf>,
        /// Results MCAP (default: <output.dir>/replay-results.mcap).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Warm-start from this state file if it exists, and keep it up to date.
        #[arg(long)]
        state: Option<PathBuf>,
        /// Also write the Rerun recording here (.rrd; default: [output] rerun_save).
        #[arg(long)]
        rerun_save: Option<PathBuf>,
        /// Also stream to this Rerun viewer (default: [output] rerun_connect),
        /// e.g. rerun+http://127.0.0.1:9876/proxy.
        #[arg(long)]
        rerun_connect: Option<String>,
    },
    /// Run the monitoring daemon: zenoh ingest until SIGINT/SIGTERM.
    Run {
        #[arg(long)]
        config: PathBuf,
        /// State file (default: [output] state_file or <output.dir>/state.json).
        #[arg(long)]
        state: Option<PathBuf>,
        /// Results MCAP (default: <output.dir>/results-<start time>.mcap).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Also write the Rerun recording here (.rrd; default: [output] rerun_save).
        #[arg(long)]
        rerun_save: Option<PathBuf>,
        /// Also stream to this Rerun viewer (default: [output] rerun_connect),
        /// e.g. rerun+http://127.0.0.1:9876/proxy.
        #[arg(long)]
        rerun_connect: Option<String>,
    },
    /// The whole live path in one process: the simulator publishes a bearing-damage
    /// scenario over zenoh on loopback at high speed, the daemon updates the model.
    Demo {
        #[arg(long, default_value = "config/sinello.toml")]
        config: PathBuf,
        /// Output folder.
        #[arg(long, default_value = "out/demo")]
        out: PathBuf,
        /// Simulated seconds.
        #[arg(long, default_value_t = 600.0)]
        duration: f64,
        /// Publishing speed, multiples of real time.
        #[arg(long, default_value_t = 40.0)]
        speed: f64,
    },
    /// Soak test: the daemon in one process with a publisher replaying a
    /// recording in a loop, unpaced, for many hours of data; reports RSS.
    Soak {
        #[arg(long, default_value = "config/sinello.toml")]
        config: PathBuf,
        #[arg(long, default_value = "recordings/sinello-demo.mcap")]
        recording: PathBuf,
        /// Hours of data to push through.
        #[arg(long, default_value_t = 24.0)]
        hours: f64,
        /// Analysis window (the bridge setting is 10 minutes).
        #[arg(long, default_value_t = 10.0)]
        window_minutes: f64,
        /// Publishing speed in multiples of real time; 0 = unpaced (a flood).
        #[arg(long, default_value_t = 1000.0)]
        speed: f64,
        #[arg(long, default_value = "out/soak")]
        out: PathBuf,
    },
    /// Salvage an MCAP file left unfinished by a killed process (results,
    /// raw-input `.part` files): copies every message of every complete chunk
    /// into a new, finalised file.
    Recover {
        /// The damaged file.
        input: PathBuf,
        /// Output (default: INPUT with `.recovered.mcap`).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Validate a configuration file without running anything.
    CheckConfig {
        /// Configuration file (TOML).
        config: PathBuf,
    },
}

fn parse_quantity(s: &str) -> Result<Quantity, String> {
    match s {
        "receptance" => Ok(Quantity::Receptance),
        "mobility" => Ok(Quantity::Mobility),
        "accelerance" => Ok(Quantity::Accelerance),
        other => Err(format!("{other:?} is not receptance, mobility or accelerance")),
    }
}

fn parse_encoding(s: &str) -> Result<splinewatch::wire::Encoding, String> {
    splinewatch::wire::Encoding::from_name(s).ok_or_else(|| format!("{s:?} is not cbor or json"))
}

/// Caps the zenoh module that logs the session configuration (secrets
/// included) at debug level.
const NO_SECRETS_DIRECTIVE: &str = "zenoh::api::session=info";

fn main() -> ExitCode {
    let json_logs = std::env::var("SPLINEWATCH_LOG_FORMAT").is_ok_and(|v| v == "json");
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info,zenoh=warn"))
        // zenoh logs its whole session configuration at debug level,
        // user/password included: never below info, whatever RUST_LOG says.
        .add_directive(NO_SECRETS_DIRECTIVE.parse().expect("a valid directive"));
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr);
    if json_logs {
        builder.json().init();
    } else {
        builder.init();
    }
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
        Command::Synth {
            config,
            inputs,
            outputs,
            quantity,
            from,
            to,
            step,
            noise,
            seed,
            out,
        } => {
            let cfg = commands::load_config(&config)?;
            let options = commands::SynthOptions {
                inputs,
                outputs,
                quantity,
                f_min: from,
                f_max: to,
                step,
                noise,
                seed,
            };
            let file = commands::synth(&cfg, &options)?;
            let text = serde_json::to_string(&file)?;
            std::fs::write(&out, text).with_context(|| format!("cannot write {}", out.display()))?;
            eprintln!(
                "wrote {} FRFs × {} lines to {}",
                file.frfs.len(),
                file.frequency_hz.len(),
                out.display()
            );
        }
        Command::Update {
            config,
            frf,
            start,
            json,
        } => {
            let cfg = commands::load_config(&config)?;
            let frf_text =
                std::fs::read_to_string(&frf).with_context(|| format!("cannot read FRF file {}", frf.display()))?;
            let start_text = start
                .as_ref()
                .map(|p| std::fs::read_to_string(p).with_context(|| format!("cannot read start file {}", p.display())))
                .transpose()?;
            let mut progress = |it: &IterationRecord| {
                eprintln!(
                    "iteration {:3}  relative residual {:.4e}  step {:.3e}  damping {:.3e}  rejected {}",
                    it.iteration, it.relative_residual, it.step_norm, it.damping, it.rejected_steps
                );
            };
            let result = commands::update(&cfg, &frf_text, start_text.as_deref(), &mut progress)
                .with_context(|| format!("updating against {}", frf.display()))?;
            let stdout = std::io::stdout();
            let mut out = stdout.lock();
            if json {
                serde_json::to_writer(&mut out, &result)?;
                writeln!(out)?;
            } else {
                commands::write_update_table(&result, &mut out)?;
            }
            out.flush()?;
        }
        Command::Paper { out } => {
            let (truth, model) = splinewatch::paper::bundled_configs(std::path::Path::new("."))?;
            std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
            let mut outcomes = Vec::new();
            for (k, e) in splinewatch::paper::EXPERIMENTS.iter().enumerate() {
                eprintln!("running {} (paper §{})", e.name, e.section);
                let o = splinewatch::paper::run(&truth, &model, e)?;
                let svg = out.join(format!("damping-{}.svg", k + 1));
                splinewatch::paper::plot_damping(&o, &svg)?;
                outcomes.push(o);
            }
            let report = splinewatch::paper::report_markdown(&outcomes);
            std::fs::write(out.join("report.md"), &report)?;
            print!("{report}");
        }
        Command::Simulate {
            config,
            duration,
            fs,
            scenario,
            seed,
            excitation,
            force_rms,
            noise,
            block_seconds,
            start,
            encoding,
            out,
            publish,
            speed,
        } => {
            let cfg = commands::load_config(&config)?;
            let scenario = scenario
                .map(|p| {
                    let text =
                        std::fs::read_to_string(&p).with_context(|| format!("cannot read scenario {}", p.display()))?;
                    splinewatch::simulation::parse_scenario(&text).with_context(|| format!("scenario {}", p.display()))
                })
                .transpose()?;
            let start_ns = splinewatch::wire::parse_timestamp(&start)
                .with_context(|| format!("--start {start:?} is not an RFC 3339 timestamp"))?;
            let options = splinewatch::simulation::SimulationOptions {
                duration_seconds: duration,
                fs,
                seed,
                excitation,
                force_rms,
                noise,
                block_seconds,
                start_ns,
                band: (cfg.frf.band[0].max(0.1), cfg.frf.band[1] * 1.1),
                oversample: 16,
                scenario,
            };
            let prefix = cfg.topic_prefix();
            let mut writer = out
                .as_ref()
                .map(|p| splinewatch::recording::RecordingWriter::create(p, encoding))
                .transpose()?;
            let mut publisher = if publish {
                let mut z = cfg.zenoh.clone();
                if z.connect.is_empty() {
                    z.connect = std::mem::take(&mut z.listen);
                }
                z.listen.clear();
                z.mode = "client".into();
                Some(splinewatch::daemon::Publisher::open(
                    &z,
                    prefix.clone(),
                    encoding,
                    speed,
                )?)
            } else {
                None
            };
            let summary = splinewatch::simulation::simulate(&cfg, &options, &mut |block| {
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
            eprintln!(
                "{} blocks ({} samples per channel, {} model updates){}{}",
                summary.blocks,
                summary.samples_per_channel,
                summary.model_updates,
                out.as_ref()
                    .map(|p| format!(", written to {}", p.display()))
                    .unwrap_or_default(),
                if publish { ", published on zenoh" } else { "" }
            );
        }
        Command::Frf {
            config,
            input,
            from,
            to,
            out,
            json: _,
        } => {
            let cfg = commands::load_config(&config)?;
            let bytes = std::fs::read(&input).with_context(|| format!("cannot read {}", input.display()))?;
            let limits = splinewatch::wire::Limits {
                max_samples: cfg.frf.max_block_samples,
                ..Default::default()
            };
            let (blocks, rejected) = splinewatch::recording::read_recording(&bytes, &limits)
                .with_context(|| format!("reading {}", input.display()))?;
            for r in &rejected {
                eprintln!("skipped a message on {} at {} ns: {}", r.topic, r.log_time, r.error);
            }
            let origin = blocks
                .iter()
                .map(|b| b.block.start_ns)
                .min()
                .context("the recording holds no channel blocks")?;
            let when = |s: &Option<String>| -> Result<Option<i128>> {
                s.as_ref()
                    .map(|t| match t.parse::<f64>() {
                        Ok(sec) => Ok(origin + (sec * 1e9).round() as i128),
                        Err(_) => splinewatch::wire::parse_timestamp(t)
                            .with_context(|| format!("{t:?} is neither seconds nor an RFC 3339 timestamp")),
                    })
                    .transpose()
            };
            let report = splinewatch::estimate::estimate(&cfg, &blocks, when(&from)?, when(&to)?)?;
            eprintln!(
                "{} samples from {}: {} segments used, {} rejected, {:.1} effective averages, {} FRFs × {} lines",
                report.samples,
                splinewatch::wire::format_timestamp(report.start_ns),
                report.segments.accepted,
                report.segments.rejected(),
                report.effective_averages,
                report.frf.frfs.len(),
                report.frf.frequency_hz.len()
            );
            let text = serde_json::to_string(&report.frf)?;
            match out {
                Some(path) => {
                    std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))?
                }
                None => println!("{text}"),
            }
        }
        Command::Soak {
            config,
            recording,
            hours,
            window_minutes,
            speed,
            out,
        } => {
            let mut cfg = commands::load_config(&config)?;
            cfg.frf.window_seconds = 60.0 * window_minutes;
            let (summary, samples, sent) = splinewatch::demo::soak(cfg, &recording, &out, hours, speed)?;
            println!("| data (h) | wall (s) | RSS (MiB) |");
            println!("| --- | --- | --- |");
            for s in &samples {
                println!(
                    "| {:.1} | {:.1} | {} |",
                    s.data_hours,
                    s.wall_seconds,
                    s.rss_kib.map_or("?".into(), |k| format!("{:.1}", k as f64 / 1024.0))
                );
            }
            let h = summary.update_count;
            println!(
                "published {sent} blocks, the daemon received {} (the rest dropped by the bounded ingest queue, counted in health.queue_drops), {} windows, {h} updates; results in {}",
                summary.messages,
                summary.windows,
                out.display()
            );
        }
        Command::Recover { input, out } => {
            let bytes = std::fs::read(&input).with_context(|| format!("cannot read {}", input.display()))?;
            let out = out.unwrap_or_else(|| {
                let name = input
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default();
                let stem = name.trim_end_matches(".part").trim_end_matches(".mcap");
                input.with_file_name(format!("{stem}.recovered.mcap"))
            });
            let file = splinewatch::files::create_output_file(&out)?;
            let (report, w) = splinewatch::recover::recover(&bytes, std::io::BufWriter::new(file))
                .with_context(|| format!("recovering {}", input.display()))?;
            w.into_inner()
                .map_err(|e| anyhow::anyhow!("cannot write {}: {}", out.display(), e.error()))?
                .sync_all()?;
            eprintln!(
                "{}: {} messages on {} channels recovered into {}{}{}",
                input.display(),
                report.messages,
                report.channels,
                out.display(),
                if report.was_complete {
                    " (the input was already complete)"
                } else {
                    ""
                },
                report
                    .stopped_at
                    .map(|e| format!("; stopped at a damaged record: {e}"))
                    .unwrap_or_default()
            );
        }
        Command::Replay {
            config,
            inputs,
            out,
            state,
            rerun_save,
            rerun_connect,
        } => {
            let cfg = commands::load_config(&config)?;
            let out = out.unwrap_or_else(|| cfg.output_dir().join("replay-results.mcap"));
            let files = inputs
                .iter()
                .map(|p| std::fs::read(p).with_context(|| format!("cannot read {}", p.display())))
                .collect::<Result<Vec<_>>>()?;
            let recordings: Vec<&[u8]> = files.iter().map(Vec::as_slice).collect();
            let initial = match &state {
                Some(p) => splinewatch::results::load_state(p)?,
                None => None,
            };
            let mut writer = splinewatch::results::ResultsWriter::create(&out, &cfg.topic_prefix())?;
            let targets = splinewatch::viewer::targets(&cfg, rerun_save.as_deref(), rerun_connect.as_deref());
            let mut viewer = if targets.is_empty() {
                None
            } else {
                Some(splinewatch::viewer::RerunOutput::open(&cfg, &targets)?)
            };
            let terminal = std::io::IsTerminal::is_terminal(&std::io::stderr());
            let bar = indicatif::ProgressBar::new(0);
            if !terminal {
                bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
            }
            bar.set_style(
                indicatif::ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} messages {msg}")
                    .expect("valid template")
                    .progress_chars("=> "),
            );
            let t0 = std::time::Instant::now();
            let options = splinewatch::replay::ReplayOptions {
                initial,
                viewer: viewer.as_mut(),
                state_path: state.as_deref(),
                keep_latest: 1,
            };
            let summary = splinewatch::replay::replay(&cfg, &recordings, &mut writer, options, &mut |p, note| {
                bar.set_length(p.total);
                bar.set_position(p.messages);
                if let Some(n) = note {
                    if terminal {
                        bar.set_message(n.to_string());
                    } else {
                        eprintln!("{n}");
                    }
                }
            })?;
            bar.finish_and_clear();
            writer.finish()?;
            if let Some(v) = viewer {
                v.finish()?;
            }
            let seconds = t0.elapsed().as_secs_f64();
            let span = summary.window_count as f64 * cfg.frf.window_seconds;
            eprintln!(
                "replayed {} messages: {} windows ({} accepted), {} updates in {seconds:.2} s ({:.0}× real time); results in {}",
                summary.messages,
                summary.window_count,
                summary.windows_accepted,
                summary.update_count,
                span / seconds.max(1e-9),
                out.display()
            );
            if let Some(acc) = &summary.accepted {
                for p in &acc.parameters {
                    println!(
                        "{:<14} {:>14.6e} {:>12}",
                        p.name,
                        p.value,
                        p.std.map_or("-".into(), |s| format!("{s:.3e}"))
                    );
                }
            }
        }
        Command::Run {
            config,
            state,
            out,
            rerun_save,
            rerun_connect,
        } => {
            let cfg = commands::load_config(&config)?;
            let dir = cfg.output_dir();
            let state = state
                .or_else(|| cfg.output.state_file.clone())
                .unwrap_or_else(|| dir.join("state.json"));
            let stamp = splinewatch::wire::format_timestamp(
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map(|d| d.as_nanos() as i128)
                    .unwrap_or(0),
            )
            .replace(':', "-");
            let out = out.unwrap_or_else(|| dir.join(format!("results-{stamp}.mcap")));
            let rerun = splinewatch::viewer::targets(&cfg, rerun_save.as_deref(), rerun_connect.as_deref());
            tracing::info!(message = "effective configuration", config = ?cfg);
            let runtime = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
            let summary = runtime.block_on(splinewatch::daemon::run(
                cfg,
                splinewatch::daemon::RunOptions {
                    results: out.clone(),
                    state: Some(state),
                    rerun,
                    keep_updates: 1,
                },
                splinewatch::daemon::termination_signal(),
            ))?;
            eprintln!(
                "stopped after {} messages, {} windows, {} updates; results in {}",
                summary.messages,
                summary.windows,
                summary.update_count,
                out.display()
            );
        }
        Command::Demo {
            config,
            out,
            duration,
            speed,
        } => {
            splinewatch::demo::run_demo(&config, &out, duration, speed)?;
        }
        Command::CheckConfig { config } => {
            let cfg = commands::load_config(&config)?;
            // The zenoh session settings too: the JSON5 file and our keys on top.
            cfg.zenoh.to_zenoh()?;
            println!("{}: configuration is valid", cfg.structure.name);
        }
    }
    Ok(())
}
