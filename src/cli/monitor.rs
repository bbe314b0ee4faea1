//! `replay`, `run`, `demo`, `soak`, `recover`: the monitoring runs and
//! their files.

use crate::config::{load_config, Config};
use crate::io::console::{errln, outln};
use crate::io::files;
use crate::io::recording::RecordingSource;
use crate::io::wire;
use crate::outputs::rerun::{self, RerunOutput};
use crate::outputs::results::ResultsWriter;
use crate::outputs::state;
use crate::service::{daemon, demo, fleet, replay, soak};
use crate::studies;
use anyhow::{bail, Context, Result};
use clap::Args;
use std::io::Write;
use std::path::PathBuf;

#[derive(Args)]
pub struct ReplayArgs {
    /// Configuration file (TOML).
    #[arg(long)]
    pub config: PathBuf,
    /// Recordings (MCAP), replayed in the order given (e.g. a daemon's rotated raw files).
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Results MCAP (default: <output.dir>/replay-results.mcap).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Warm-start from this state file if it exists, and keep it up to date.
    #[arg(long)]
    pub state: Option<PathBuf>,
    /// Also write the Rerun recording here (.rrd; default: [output] rerun_save).
    #[arg(long)]
    pub rerun_save: Option<PathBuf>,
    /// Also stream to this Rerun viewer (default: [output] rerun_connect),
    /// e.g. rerun+http://127.0.0.1:9876/proxy.
    #[arg(long)]
    pub rerun_connect: Option<String>,
    /// Read, ingest and update on one thread (the same results as the
    /// default three-stage pipeline, slower; for comparison).
    #[arg(long)]
    pub single_thread: bool,
    /// Serve Prometheus metrics at `[metrics] listen` (default 127.0.0.1:9464) while replaying.
    #[arg(long)]
    pub metrics: bool,
    /// With `--metrics`: keep serving this many seconds after the replay ends (a scraper's last look).
    #[arg(long, default_value_t = 0.0, requires = "metrics")]
    pub metrics_linger: f64,
}

#[derive(Args)]
pub struct RunArgs {
    /// Configuration file (TOML).
    #[arg(long)]
    pub config: PathBuf,
    /// State file (default: [output] state_file or <output.dir>/state.json).
    #[arg(long)]
    pub state: Option<PathBuf>,
    /// Results MCAP (default: <output.dir>/results-<start time>.mcap).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also write the Rerun recording here (.rrd; default: [output] rerun_save).
    #[arg(long)]
    pub rerun_save: Option<PathBuf>,
    /// Also stream to this Rerun viewer (default: [output] rerun_connect),
    /// e.g. rerun+http://127.0.0.1:9876/proxy.
    #[arg(long)]
    pub rerun_connect: Option<String>,
}

#[derive(Args)]
pub struct DemoArgs {
    /// Configuration file (TOML).
    #[arg(long, default_value = "config/sinello.toml")]
    pub config: PathBuf,
    /// Output folder.
    #[arg(long, default_value = "out/demo")]
    pub out: PathBuf,
    /// Simulated seconds (default: 600; with `[monitoring]`, its training
    /// windows and 50 more, the damage halfway through those).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Publishing speed, multiples of real time.
    #[arg(long, default_value_t = 40.0)]
    pub speed: f64,
}

#[derive(Args)]
pub struct SoakArgs {
    /// Configuration file (TOML).
    #[arg(long, default_value = "config/sinello.toml")]
    pub config: PathBuf,
    #[arg(long, default_value = "recordings/sinello-demo.mcap")]
    pub recording: PathBuf,
    /// Hours of data to push through.
    #[arg(long, default_value_t = 24.0)]
    pub hours: f64,
    /// Analysis window (the bridge setting is 10 minutes).
    #[arg(long, default_value_t = 10.0)]
    pub window_minutes: f64,
    /// Publishing speed in multiples of real time (default 1000); 0 = unpaced (a flood).
    #[arg(long, default_value_t = 1000.0)]
    pub speed: f64,
    #[arg(long, default_value = "out/soak")]
    pub out: PathBuf,
}

#[derive(Args)]
pub struct MonitorArgs {
    /// Configuration file (TOML) with [monitoring]; its settings unless overridden below.
    #[arg(long)]
    pub config: PathBuf,
    /// Results MCAP files (of `run` or `replay` with [monitoring]), in time order.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// New results file: every message copied, the monitoring messages re-made.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Train on the first N scored updates (default: [monitoring] training_windows).
    #[arg(long, conflicts_with_all = ["train_from", "train_until"])]
    pub training_windows: Option<usize>,
    /// Train on the updates from this time (RFC 3339) on ...
    #[arg(long, requires = "train_until")]
    pub train_from: Option<String>,
    /// ... until this time (exclusive).
    #[arg(long, requires = "train_from")]
    pub train_until: Option<String>,
    /// No compensation: charts on the raw parameters (plain mean and covariance).
    #[arg(long)]
    pub raw: bool,
    /// Control limits: held_out (cross-validated training windows) or
    /// theoretical (the textbook F law). Default: [monitoring] limits.
    #[arg(long, value_parser = parse_limits)]
    pub limits: Option<splinewatch_core::monitoring::LimitMethod>,
    /// Target false-alarm probability per window and chart.
    #[arg(long)]
    pub false_alarm_rate: Option<f64>,
    /// MEWMA smoothing λ.
    #[arg(long)]
    pub ewma_lambda: Option<f64>,
    /// Persistence rule K,M: an alarm after K exceedances among the last M scored updates.
    #[arg(long, value_parser = parse_persistence)]
    pub persistence: Option<[usize; 2]>,
    /// Window where damage is known to start (a simulation): also report false
    /// alarms before it and the detection delay.
    #[arg(long)]
    pub onset_window: Option<u64>,
    /// Print every status as JSON lines instead of the summary.
    #[arg(long)]
    pub json: bool,
}

fn parse_limits(text: &str) -> Result<splinewatch_core::monitoring::LimitMethod, String> {
    match text {
        "held_out" => Ok(splinewatch_core::monitoring::LimitMethod::HeldOut),
        "theoretical" => Ok(splinewatch_core::monitoring::LimitMethod::Theoretical),
        other => Err(format!("{other:?}: expected held_out or theoretical")),
    }
}

fn parse_persistence(text: &str) -> Result<[usize; 2], String> {
    let (k, m) = text.split_once(',').ok_or_else(|| format!("{text:?}: expected K,M"))?;
    let parse = |v: &str| v.trim().parse::<usize>().map_err(|e| format!("{v:?}: {e}"));
    Ok([parse(k)?, parse(m)?])
}

#[derive(Args)]
pub struct RecoverArgs {
    /// The damaged file.
    pub input: PathBuf,
    /// Output (default: INPUT with `.recovered.mcap`).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn monitor(a: MonitorArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    let mut settings = cfg
        .monitoring
        .clone()
        .with_context(|| format!("{}: no [monitoring] section", a.config.display()))?;
    if let Some(v) = a.false_alarm_rate {
        settings.false_alarm_rate = v;
    }
    if let Some(v) = a.ewma_lambda {
        settings.ewma_lambda = v;
    }
    if let Some(v) = a.persistence {
        settings.persistence = v;
    }
    if let Some(v) = a.limits {
        settings.limits = v;
    }
    settings.settings().check().context("monitor options")?;
    let training = match (&a.train_from, &a.train_until) {
        (Some(from), Some(until)) => {
            let at =
                |t: &String| wire::parse_timestamp(t).with_context(|| format!("{t:?} is not an RFC 3339 timestamp"));
            crate::pipeline::Training::Span(at(from)?, at(until)?)
        }
        _ => match (a.training_windows, settings.training_span()?) {
            // The config's span, unless a window count is asked for: as the daemon trained.
            (None, Some((from, until))) => crate::pipeline::Training::Span(from, until),
            (n, _) => crate::pipeline::Training::FirstWindows(n.unwrap_or(settings.training_windows)),
        },
    };
    if let Some(n) = a.training_windows {
        settings.training_windows = n;
    }
    let files = a
        .inputs
        .iter()
        .map(|p| std::fs::read(p).with_context(|| format!("cannot read {}", p.display())))
        .collect::<Result<Vec<_>>>()?;
    let inputs: Vec<&[u8]> = files.iter().map(Vec::as_slice).collect();
    let t0 = std::time::Instant::now();
    let mut writer = a.out.as_ref().map(|p| ResultsWriter::create_for(p, &cfg)).transpose()?;
    let summary = crate::service::rescore::rescore_results(
        &settings,
        &cfg.topic_prefix(),
        &inputs,
        training,
        a.raw,
        writer.as_mut(),
    )?;
    if let Some(w) = writer {
        w.finish()?;
    }
    if a.json {
        for s in &summary.statuses {
            outln!("{}", serde_json::to_string(s)?);
        }
    } else {
        write_monitor_summary(&summary.statuses, a.onset_window);
    }
    errln!(
        "re-scored {} updates in {:.2} s{}",
        summary.statuses.len(),
        t0.elapsed().as_secs_f64(),
        a.out
            .as_ref()
            .map(|p| format!("; results in {}", p.display()))
            .unwrap_or_default()
    );
    Ok(())
}

/// Windows by state, the alarms raised, and with a known damage onset the
/// false alarms before it and the detection delay.
fn write_monitor_summary(statuses: &[crate::io::monitoring_json::StatusMessage], onset: Option<u64>) {
    let mut by_state = std::collections::BTreeMap::<&str, usize>::new();
    for s in statuses {
        *by_state.entry(s.state.as_str()).or_default() += 1;
    }
    outln!("windows by state: {by_state:?}");
    // Transitions between scored windows (a window outside the training
    // range or in training leaves the state as it was).
    let scored: Vec<&crate::io::monitoring_json::StatusMessage> = statuses
        .iter()
        .filter(|s| matches!(s.state.as_str(), "normal" | "alarm"))
        .collect();
    let raised: Vec<u64> = scored
        .windows(2)
        .filter(|w| w[1].state == "alarm" && w[0].state != "alarm")
        .map(|w| w[1].window)
        .chain(scored.first().filter(|s| s.state == "alarm").map(|s| s.window))
        .collect();
    outln!("alarms raised at windows: {raised:?}");
    let Some(onset) = onset else {
        return;
    };
    let before: Vec<&crate::io::monitoring_json::StatusMessage> = statuses
        .iter()
        .filter(|s| s.window < onset && s.state != "training")
        .collect();
    let scored = before.iter().filter(|s| s.t2.is_some()).count();
    let in_alarm = before.iter().filter(|s| s.state == "alarm").count();
    let raised_before = raised.iter().filter(|&&w| w < onset).count();
    outln!(
        "before window {onset}: {scored} scored windows, {in_alarm} in alarm ({:.1} per 1000), {raised_before} alarms raised",
        1000.0 * in_alarm as f64 / scored.max(1) as f64
    );
    match statuses.iter().find(|s| s.window >= onset && s.state == "alarm") {
        Some(s) => outln!(
            "detection: window {} ({} windows after the onset)",
            s.window,
            s.window - onset
        ),
        None => outln!("detection: none"),
    }
}

/// `replay --metrics`: the endpoint at `[metrics] listen` (or its default).
fn replay_metrics(cfg: &Config, a: &ReplayArgs) -> Result<Option<crate::outputs::metrics::Metrics>> {
    if !(0.0..=86_400.0).contains(&a.metrics_linger) {
        bail!(
            "--metrics-linger: {} is not a number of seconds in [0, 86400]",
            a.metrics_linger
        );
    }
    if !a.metrics {
        return Ok(None);
    }
    let listen = cfg.metrics.clone().unwrap_or_default().listen;
    crate::outputs::metrics::Metrics::serve(&listen, &cfg.structure.name).map(Some)
}

pub fn replay(a: ReplayArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| cfg.output_dir().join("replay-results.mcap"));
    // Read as the replay goes: memory bounded whatever the files' size.
    let recordings = a
        .inputs
        .iter()
        .map(|p| RecordingSource::open(p))
        .collect::<Result<Vec<_>>>()?;
    let initial = match &a.state {
        Some(p) => state::load_state(p)?,
        None => None,
    };
    let mut writer = ResultsWriter::create_for(&out, &cfg)?;
    let targets = rerun::targets(&cfg, a.rerun_save.as_deref(), a.rerun_connect.as_deref());
    let mut viewer = if targets.is_empty() {
        None
    } else {
        Some(RerunOutput::open(&cfg, &targets)?)
    };
    let metrics = replay_metrics(&cfg, &a)?;
    let progress = ReplayProgress::new();
    let t0 = std::time::Instant::now();
    let options = replay::ReplayOptions {
        initial,
        viewer: viewer.as_mut(),
        state_path: a.state.as_deref(),
        keep_latest: 1,
        pipelined: !a.single_thread,
        metrics: metrics.as_ref(),
    };
    let summary = replay::replay_sources(&cfg, recordings, &mut writer, options, &mut |p, note| {
        progress.show(p, note)
    })?;
    progress.bar.finish_and_clear();
    writer.finish()?;
    if let Some(v) = viewer {
        v.finish()?;
    }
    if let Some(m) = &metrics {
        if a.metrics_linger > 0.0 {
            errln!(
                "serving the final metrics at http://{}/metrics for {} s",
                m.address(),
                a.metrics_linger
            );
            std::thread::sleep(std::time::Duration::from_secs_f64(a.metrics_linger));
        }
    }
    let seconds = t0.elapsed().as_secs_f64();
    // Measurement time covered by the closed windows (they may overlap).
    let (window, hop) = cfg.analysis_window();
    let span = match summary.window_count {
        0 => 0.0,
        n => (n - 1) as f64 * hop.unwrap_or(window) + window,
    };
    errln!(
        "replayed {} messages: {} windows ({} accepted), {} updates in {seconds:.2} s ({:.0}× real time); results in {}",
        summary.messages,
        summary.window_count,
        summary.windows_accepted,
        summary.update_count,
        span / seconds.max(1e-9),
        out.display()
    );
    if let Some(acc) = &summary.accepted {
        let mut out = crate::io::console::Stdout;
        studies::write_parameter_header(&mut out, false)?;
        for p in &acc.parameters {
            studies::write_parameter_row(&mut out, &cfg, &p.name, p.value, p.std)?;
            writeln!(out)?;
        }
    }
    Ok(())
}

/// Replay progress: a bar on a terminal, plain log lines otherwise.
struct ReplayProgress {
    bar: indicatif::ProgressBar,
    terminal: bool,
}

impl ReplayProgress {
    fn new() -> Self {
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
        Self { bar, terminal }
    }

    fn show(&self, p: replay::Progress, note: Option<&str>) {
        self.bar.set_length(p.total);
        self.bar.set_position(p.messages);
        if let Some(n) = note {
            if self.terminal {
                self.bar.set_message(n.to_string());
            } else {
                errln!("{n}");
            }
        }
    }
}

pub fn run(a: RunArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    let dir = cfg.output_dir();
    let state = a
        .state
        .or_else(|| cfg.output.state_file.clone())
        .unwrap_or_else(|| dir.join("state.json"));
    let stamp = wire::format_timestamp(wire::now_ns()).replace(':', "-");
    let out = a.out.unwrap_or_else(|| dir.join(format!("results-{stamp}.mcap")));
    let rerun = rerun::targets(&cfg, a.rerun_save.as_deref(), a.rerun_connect.as_deref());
    // Compact JSON (defaults filled in), one line; secrets live in the zenoh
    // JSON5 file, which is only named here.
    let effective = serde_json::to_string(&cfg).unwrap_or_else(|e| format!("(not serialisable: {e})"));
    tracing::info!(message = "effective configuration", config = %effective);
    let runtime = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    let summary = runtime.block_on(daemon::run(
        cfg,
        daemon::RunOptions {
            results: out.clone(),
            state: Some(state),
            rerun,
            keep_updates: 1,
        },
        daemon::termination_signal(),
    ))?;
    errln!(
        "stopped after {} messages, {} windows, {} updates; results in {}",
        summary.messages,
        summary.windows,
        summary.update_count,
        out.display()
    );
    Ok(())
}

/// The `demo` command: a fresh run, then a summary, the `east.k2` trace and
/// the owner's report of the run (`report.html` in the output folder).
pub fn demo(a: DemoArgs) -> Result<()> {
    let out = &a.out;
    let cfg = load_config(&a.config)?;
    let plan = demo::demo_plan(&cfg, a.duration)?;
    let removed = demo::clear_previous(out)?;
    if !removed.is_empty() {
        errln!(
            "demo: starting fresh in {} (removed the previous demo's {})",
            out.display(),
            removed.join(", ")
        );
    }
    let summary = demo::run_live(cfg, &plan, out, a.speed, 2026)?;
    let report_path = out.join("report.html");
    let results = out.join("results.mcap");
    let bytes = std::fs::read(&results).with_context(|| format!("cannot read {}", results.display()))?;
    let contents = crate::io::results_file::read_results(&[(results.display().to_string(), bytes.as_slice())])?;
    let report = crate::outputs::report::render(&contents, &crate::outputs::report::Selection::Latest)?;
    super::report::write_whole(&report_path, &report.html)?;
    errln!(
        "demo: {} messages received, {} windows, {} updates ({} failed); wrote {}",
        summary.messages,
        summary.windows,
        summary.updates.len(),
        summary.updates.iter().filter(|u| u.result.is_err()).count(),
        demo::demo_files(out)
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    outln!("{:>8} {:>14} {:>12}", "window", "east.k2 (N/m³)", "rel. resid.");
    for u in &summary.updates {
        if let Ok(r) = &u.result {
            let k2 = r
                .result
                .parameters
                .iter()
                .find(|p| p.name == "east.k2")
                .map_or(f64::NAN, |p| p.value);
            outln!("{:>8} {:>14.4e} {:>12.4}", u.window, k2, r.result.relative_residual);
        }
    }
    outln!(
        "report ({}): {}: {}",
        report_path.display(),
        report.priority.label(),
        report.verdict
    );
    Ok(())
}

pub fn soak(a: SoakArgs) -> Result<()> {
    let mut cfg = load_config(&a.config)?;
    cfg.frf.window_seconds = 60.0 * a.window_minutes;
    let (summary, samples, sent) = soak::soak(cfg, &a.recording, &a.out, a.hours, a.speed)?;
    outln!("| data (h) | wall (s) | RSS (MiB) |");
    outln!("| --- | --- | --- |");
    for s in &samples {
        outln!(
            "| {:.1} | {:.1} | {} |",
            s.data_hours,
            s.wall_seconds,
            s.rss_kib.map_or("?".into(), |k| format!("{:.1}", k as f64 / 1024.0))
        );
    }
    let h = summary.update_count;
    outln!(
        "published {sent} blocks, the daemon received {} (the rest dropped by the bounded ingest queue, counted in health.queue_drops), {} windows, {h} updates; results in {}",
        summary.messages,
        summary.windows,
        a.out.display()
    );
    Ok(())
}

pub fn recover(a: RecoverArgs) -> Result<()> {
    let input = &a.input;
    let bytes = std::fs::read(input).with_context(|| format!("cannot read {}", input.display()))?;
    let out = a.out.unwrap_or_else(|| {
        let name = input
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let stem = name.trim_end_matches(".part").trim_end_matches(".mcap");
        input.with_file_name(format!("{stem}.recovered.mcap"))
    });
    let file = files::create_output_file(&out)?;
    let (report, w) = crate::io::recover::recover(&bytes, std::io::BufWriter::new(file))
        .with_context(|| format!("recovering {}", input.display()))?;
    w.into_inner()
        .map_err(|e| anyhow::anyhow!("cannot write {}: {}", out.display(), e.error()))?
        .sync_all()?;
    errln!(
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
    Ok(())
}

#[derive(Args)]
pub struct FleetArgs {
    /// zenoh endpoint of the site router (or of a daemon), e.g.
    /// tcp/192.0.2.10:7447 or tls/192.0.2.10:7447; repeat for several.
    #[arg(long, required = true)]
    pub connect: Vec<String>,
    /// A zenoh JSON5 file for the session: credentials or certificates,
    /// e.g. config/zenoh/dashboard-client-tls.json5.
    #[arg(long)]
    pub zenoh_config: Option<PathBuf>,
    /// One JSON object per span and line (the summary and the daemon's
    /// latest messages) instead of text.
    #[arg(long)]
    pub json: bool,
    /// Seconds to wait for the replies of each kind.
    #[arg(long, default_value_t = 3.0)]
    pub timeout: f64,
    /// Parameters shown per line (text output).
    #[arg(long, default_value_t = 4)]
    pub parameters: usize,
    /// A span that must answer (its `structure.name`); repeat for several.
    /// One that is not running or does not answer is reported and makes
    /// the exit status 1.
    #[arg(long = "expect")]
    pub expect: Vec<String>,
    /// Also write the fleet's page here: every span with its last verdict,
    /// sorted by inspection priority (one self-contained HTML file; written
    /// also when a span did not answer).
    #[arg(long)]
    pub report: Option<PathBuf>,
}

pub fn fleet(a: FleetArgs) -> Result<()> {
    use zenoh::Wait;
    if !(a.timeout.is_finite() && a.timeout > 0.0) {
        anyhow::bail!("--timeout {}: must be a positive number of seconds", a.timeout);
    }
    let zenoh = crate::config::ZenohConfig {
        mode: "client".into(),
        listen: Vec::new(),
        connect: a.connect.clone(),
        config_file: a.zenoh_config,
        ..Default::default()
    };
    let session = zenoh::open(zenoh.to_zenoh()?)
        .wait()
        .map_err(|e| anyhow::anyhow!("cannot connect to {}: {e}", a.connect.join(", ")))?;
    let spans = fleet::gather(&session, std::time::Duration::from_secs_f64(a.timeout), &a.expect);
    let _ = session.close().wait();
    let spans = spans?;
    if spans.is_empty() {
        anyhow::bail!(
            "no span answered on bridge/*/{{updating,monitoring,health}}/latest within {} s",
            a.timeout
        );
    }
    for span in &spans {
        let summary = span.summary();
        if a.json {
            let line = serde_json::json!({"summary": summary, "latest": span});
            outln!("{line}");
        } else {
            outln!("{}", summary.line(a.parameters));
        }
    }
    if let Some(path) = &a.report {
        let rows: Vec<crate::outputs::report::fleet::FleetSpan> = spans
            .iter()
            .map(|s| {
                let summary = s.summary();
                crate::outputs::report::fleet::FleetSpan {
                    name: summary.name,
                    reachability: summary.reachability,
                    last_update: summary.last_update,
                    monitoring: summary.monitoring,
                    health: summary.health,
                    parameters: summary.parameters,
                }
            })
            .collect();
        let now = crate::io::wire::format_timestamp(
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos() as i128),
        );
        let report = crate::outputs::report::fleet::render(&rows, &now);
        super::report::write_whole(path, &report.html)?;
        errln!(
            "{} written: {}: {}",
            path.display(),
            report.priority.label(),
            report.verdict
        );
    }
    let silent: Vec<&str> = spans
        .iter()
        .filter(|s| s.answered.is_empty())
        .map(|s| s.name.as_str())
        .collect();
    if !silent.is_empty() {
        anyhow::bail!(
            "{} did not answer within {} s (see the lines above)",
            silent.join(", "),
            a.timeout
        );
    }
    Ok(())
}
