//! `splinewatch events`: earthquake by earthquake (issue 45). Every input
//! (a station's zip, a folder of V2 files, an MCAP recording) is one event;
//! in time order each is checked, identified (SRIM), forecast by the model
//! updated on the events before it (`predict`'s figures), updated on its
//! transmissibilities (warm-started from the previous event), and judged
//! against the bands the earlier events give at its amplitude
//! ([`splinewatch_core::monitoring::amplitude`]).
//!
//! An event that cannot be used (unreadable, a dead or clipped channel, a
//! missing ground channel, too short) is reported as skipped with its reason
//! and the others go on.

use super::ground::{align_event, identify_io, read_records, recorded, Event};
use crate::config::{ground_signals, load_config, Config};
use crate::io::console::{errln, outln};
use crate::io::modes_json::ModeEntry;
use crate::io::monitoring_json::{NamedValue, StatusMessage};
use crate::io::wire::format_timestamp;
use crate::outputs::notify::Notifier;
use crate::outputs::results::ResultsWriter;
use crate::pipeline::oma::OmaReport;
use crate::studies::event_update::{update_on_event, EventSignals};
use crate::studies::ground_motion::GroundModel;
use crate::studies::predict::{predict as predict_event, PredictionReport};
use anyhow::{bail, Context, Result};
use clap::Args;
use serde::{Deserialize, Serialize};
use splinewatch_core::monitoring::amplitude::{judge, FeatureBand, Verdict};
use splinewatch_core::updating::ParameterEstimate;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct EventsArgs {
    /// Configuration file (TOML) with ground sensors (`support = "<group>"`); `[events]` sets the verdict.
    #[arg(long)]
    pub config: PathBuf,
    /// One event each: a station's .zip, a folder of its .V2 files, or a raw-input MCAP recording.
    #[arg(required = true, num_args = 1..)]
    pub input: Vec<PathBuf>,
    /// Write every event's results as MCAP (`<prefix>/events/*` topics).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Carry the chain across runs: read (when it exists) and write the updated parameters and the events' history.
    #[arg(long)]
    pub state: Option<PathBuf>,
    /// One JSON object per event and line instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Write `frequency_vs_amplitude.svg` (identified and updated frequencies against the event's ground peak) here.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Save the events' timeline (peaks, parameters, frequencies, forecast NRMSE, verdict) as a Rerun recording (.rrd).
    #[arg(long)]
    pub rerun_save: Option<PathBuf>,
}

/// One event's line of `events --json` (and its `events/summary` message).
#[derive(Debug, Clone, Serialize)]
pub struct EventLine {
    pub event: String,
    pub start: Option<String>,
    pub pga_ground: Option<f64>,
    pub peak_deck: Option<f64>,
    pub modes: Vec<ModeEntry>,
    pub parameters: Vec<ParameterEstimate>,
    pub forecast: Option<PredictionReport>,
    pub verdict: Option<VerdictLine>,
    pub skipped: Option<String>,
    /// The update's relative residual and iterations; ground inputs combined.
    pub update: Option<UpdateLine>,
    /// What a stage could not do without skipping the event (an
    /// identification that found no mode).
    pub notes: Vec<String>,
}

#[derive(Debug, Clone, Serialize)]
pub struct UpdateLine {
    /// The updated model's dominant mode over the fitted channels (Hz).
    pub model_mode_hz: Option<f64>,
    pub relative_residual: f64,
    pub iterations: usize,
    pub converged: bool,
    pub combined_inputs: Vec<String>,
}

/// The verdict: `state` ("insufficient history", "normal", "alarm"), the
/// features outside their bands and every band.
#[derive(Debug, Clone, Serialize)]
pub struct VerdictLine {
    pub state: String,
    pub outside: Vec<String>,
    pub bands: Vec<BandLine>,
}

#[derive(Debug, Clone, Serialize)]
pub struct BandLine {
    pub feature: String,
    pub value: Option<f64>,
    pub band: Option<FeatureBand>,
}

/// What carries from one event to the next (and across runs, `--state`).
#[derive(Debug, Default, Serialize, Deserialize)]
struct Chain {
    /// The last update's values (`predict --state` reads this list).
    parameters: Vec<Named>,
    /// The modes tracked from event to event: the first event's identified frequencies.
    tracked_hz: Vec<f64>,
    /// log10 of each earlier (not alarmed) event's ground peak, m/s².
    amplitudes: Vec<f64>,
    /// Their features, in the order of [`feature_names`].
    features: Vec<Vec<Option<f64>>>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct Named {
    name: String,
    value: f64,
}

impl Chain {
    fn named(&self) -> Vec<(String, f64)> {
        self.parameters.iter().map(|p| (p.name.clone(), p.value)).collect()
    }
}

/// An event read and put on one grid, or why it could not be.
struct Loaded {
    name: String,
    event: Result<(Event, GroundModel)>,
}

pub fn events(a: EventsArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    if !cfg.has_ground_sensors() {
        bail!("config: sensors: events need ground sensors ([[sensors]] with support = \"<group>\")");
    }
    let mut chain = match &a.state {
        Some(p) if p.exists() => {
            let text = std::fs::read_to_string(p).with_context(|| format!("cannot read {}", p.display()))?;
            serde_json::from_str(&text).with_context(|| format!("{}: not an events state file", p.display()))?
        }
        _ => Chain::default(),
    };
    let mut loaded: Vec<Loaded> = a.input.iter().map(|p| load(&cfg, p)).collect();
    // In time order; events that could not be read keep their place at the end.
    loaded.sort_by_key(|l| l.event.as_ref().map_or(i128::MAX, |(e, _)| e.start_ns));
    let mut writer = a
        .out
        .as_deref()
        .map(|p| ResultsWriter::create(p, &cfg.topic_prefix()))
        .transpose()?;
    let mut notifier = Notifier::for_config(&cfg).context("starting the notifier")?;
    let mut rerun = a
        .rerun_save
        .as_ref()
        .map(|path| {
            let targets = crate::outputs::rerun::RerunTargets {
                save: Some(path.clone()),
                connect: None,
            };
            crate::outputs::rerun::RerunOutput::open_rotating(&cfg, &targets, false)
        })
        .transpose()?;
    if !a.json {
        outln!("event\tstart\tpga_ground\tpeak_deck\tmodes\tforecast_nrmse\tbaseline_nrmse\tverdict");
    }
    let mut lines = Vec::new();
    for (k, l) in loaded.into_iter().enumerate() {
        let line = process(&cfg, l, &mut chain);
        if let Some(w) = writer.as_mut() {
            write_event(w, &line)?;
        }
        if let (Some(n), Some(v)) = (notifier.as_mut(), &line.verdict) {
            let status = status_message(k as u64, &line, v);
            n.observe(&status, &serde_json::to_vec(&status)?);
        }
        if let Some(r) = rerun.as_mut() {
            log_rerun(r, &line)?;
        }
        print_line(&line, a.json)?;
        lines.push(line);
    }
    if let Some(r) = rerun {
        r.finish()?;
    }
    if let Some(n) = notifier.as_mut() {
        n.finish();
    }
    if let Some(w) = writer {
        w.finish()?;
    }
    if let Some(p) = &a.state {
        std::fs::write(p, serde_json::to_string_pretty(&chain)?)
            .with_context(|| format!("cannot write {}", p.display()))?;
    }
    if let Some(dir) = &a.plot {
        super::events_plot::frequency_vs_amplitude(&mode_points(&lines), dir)?;
    }
    Ok(())
}

/// Every identified mode of every used event, and the updated model's
/// dominant mode (with no standard deviation).
fn mode_points(lines: &[EventLine]) -> Vec<super::events_plot::ModePoint> {
    let mut points = Vec::new();
    for line in lines.iter().filter(|l| l.skipped.is_none()) {
        let Some(pga) = line.pga_ground.filter(|p| *p > 0.0) else {
            continue;
        };
        let alarmed = line.verdict.as_ref().is_some_and(|v| v.state == "alarm");
        for m in &line.modes {
            points.push(super::events_plot::ModePoint {
                pga,
                frequency_hz: m.frequency_hz,
                std_hz: m.frequency_std_hz.unwrap_or(0.0),
                alarmed,
                model: false,
            });
        }
        if let Some(f) = line.update.as_ref().and_then(|u| u.model_mode_hz) {
            points.push(super::events_plot::ModePoint {
                pga,
                frequency_hz: f,
                std_hz: 0.0,
                alarmed,
                model: true,
            });
        }
    }
    points
}

/// The files of one event: a folder's files (sorted), or the path itself.
fn event_files(path: &Path) -> Result<Vec<PathBuf>> {
    if !path.is_dir() {
        return Ok(vec![path.to_path_buf()]);
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(path)
        .with_context(|| format!("cannot list {}", path.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    if files.is_empty() {
        bail!("{}: an empty folder", path.display());
    }
    Ok(files)
}

fn load(cfg: &Config, path: &Path) -> Loaded {
    let name = path
        .file_name()
        .map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    let event = (|| {
        let blocks = read_records(cfg, &event_files(path)?)?;
        // Every ground channel is needed: an event's inputs are not borrowed
        // from other supports (as `predict` does) but the event is skipped.
        let missing: Vec<&str> = (cfg.deck_sensor_count()..cfg.sensors.len())
            .filter(|&i| !recorded(cfg, &blocks, i))
            .map(|i| cfg.sensors[i].name.as_str())
            .collect();
        let all_ground = cfg.sensors.len() - cfg.deck_sensor_count();
        if !missing.is_empty() && missing.len() < all_ground {
            bail!(
                "ground channel{} {} missing: the motion of {} support{} is not measured",
                if missing.len() > 1 { "s" } else { "" },
                missing.join(", "),
                if missing.len() > 1 { "their" } else { "its" },
                if missing.len() > 1 { "s" } else { "" }
            );
        }
        let mut model = GroundModel::new(cfg, &[])?;
        let event = align_event(cfg, &mut model, &blocks)?;
        if event.deck.is_empty() {
            bail!("the record holds none of the config's deck sensors");
        }
        check_channels(cfg, &event, &model)?;
        Ok((event, model))
    })();
    Loaded { name, event }
}

/// Samples of a clipped channel: this many in a row at its extreme value.
const CLIPPED_RUN: usize = 5;

/// A dead channel (constant), a clipped one (a run at its extreme) or a
/// record too short for the identification and the Welch segments.
fn check_channels(cfg: &Config, event: &Event, model: &GroundModel) -> Result<()> {
    let (oma, _) = cfg.oma_settings()?;
    let (welch, _) = cfg.welch_settings(event.fs)?;
    for i in model.ground_sensors().into_iter().chain(event.deck.iter().copied()) {
        let x = event.channels[i].as_deref().unwrap_or_default();
        let name = &cfg.sensors[i].name;
        let needed = (2 * welch.segment).max(4 * oma.block_rows * oma.batches.max(1));
        if x.len() < needed {
            bail!(
                "{name}: {} samples ({:.1} s), fewer than the {needed} the identification and two Welch segments need",
                x.len(),
                x.len() as f64 / event.fs
            );
        }
        let (lo, hi) = x
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
        if hi - lo <= 1e-12 * hi.abs().max(lo.abs()).max(1e-300) {
            bail!("{name}: a dead channel (every sample {lo})");
        }
        for extreme in [lo, hi] {
            let run = x.split(|v| *v != extreme).map(<[f64]>::len).max().unwrap_or(0);
            if run >= CLIPPED_RUN {
                bail!("{name}: clipped ({run} samples in a row at its extreme {extreme})");
            }
        }
    }
    Ok(())
}

/// The chain on one event; a failing stage skips the event with its reason.
fn process(cfg: &Config, loaded: Loaded, chain: &mut Chain) -> EventLine {
    let mut line = EventLine {
        event: loaded.name,
        start: None,
        pga_ground: None,
        peak_deck: None,
        modes: Vec::new(),
        parameters: Vec::new(),
        forecast: None,
        verdict: None,
        skipped: None,
        update: None,
        notes: Vec::new(),
    };
    let (event, model) = match loaded.event {
        Ok(e) => e,
        Err(e) => {
            line.skipped = Some(format!("{e:#}"));
            return line;
        }
    };
    line.start = Some(format_timestamp(event.start_ns));
    if let Err(e) = run_chain(cfg, &event, &model, chain, &mut line) {
        line.skipped = Some(format!("{e:#}"));
    }
    line
}

fn run_chain(cfg: &Config, event: &Event, model: &GroundModel, chain: &mut Chain, line: &mut EventLine) -> Result<()> {
    let channel = |i: usize| event.channels[i].as_deref().expect("aligned");
    let ground = model.ground_sensors();
    let pga = ground
        .iter()
        .flat_map(|&i| channel(i))
        .fold(0.0f64, |a, v| a.max(v.abs()));
    line.pga_ground = Some(pga);
    line.peak_deck = Some(
        event
            .deck
            .iter()
            .flat_map(|&i| channel(i))
            .fold(0.0f64, |a, v| a.max(v.abs())),
    );
    // Identification: every recorded ground channel to every deck channel.
    let inputs: Vec<&[f64]> = ground.iter().map(|&i| channel(i)).collect();
    let outputs: Vec<&[f64]> = event.deck.iter().map(|&i| channel(i)).collect();
    // A record whose identification finds no mode is still forecast and
    // updated (neither needs modes): said in `notes`.
    match identify_io(cfg, &inputs, &outputs, event.fs) {
        Ok((result, _)) => {
            let report = OmaReport {
                start_ns: event.start_ns,
                samples: outputs[0].len(),
                fs: event.fs,
                sensors: event.deck.iter().map(|&i| cfg.sensors[i].name.clone()).collect(),
                result,
                spectrum: None,
            };
            line.modes = report.modes_file().modes;
        }
        Err(e) => line.notes.push(format!("{e:#}")),
    }
    // The forecast: the model of the events before this one.
    if !chain.parameters.is_empty() {
        let mut forecaster = GroundModel::new(cfg, &chain.named()).context("the forecast's model")?;
        forecaster.plan = model.plan.clone();
        let mut prediction = predict_event(cfg, &forecaster, &event.deck, channel, event.fs);
        prediction.report.start = line.start.clone();
        line.forecast = Some(prediction.report);
    }
    update_event(cfg, event, model, chain, line)?;
    judge_event(cfg, chain, line, pga);
    Ok(())
}

/// The update on the event's transmissibilities, warm-started from the
/// previous event's values.
fn update_event(
    cfg: &Config,
    event: &Event,
    model: &GroundModel,
    chain: &mut Chain,
    line: &mut EventLine,
) -> Result<()> {
    let channel = |i: usize| event.channels[i].as_deref().expect("aligned");
    let signals = ground_signals(&model.plan, channel);
    let fitted: Vec<usize> = event
        .deck
        .iter()
        .copied()
        .filter(|&i| cfg.events.outputs.is_empty() || cfg.events.outputs.contains(&cfg.sensors[i].name))
        .collect();
    let deck_series: Vec<Vec<f64>> = fitted.iter().map(|&i| channel(i).to_vec()).collect();
    let record = EventSignals {
        plan: &model.plan,
        inputs: &signals,
        deck: &fitted,
        outputs: &deck_series,
        fs: event.fs,
    };
    let updated = update_on_event(cfg, &record, &chain.named(), &mut |_| {})?;
    line.update = Some(UpdateLine {
        model_mode_hz: updated.dominant_hz,
        relative_residual: updated.result.relative_residual,
        iterations: updated.result.iterations.len().saturating_sub(1),
        converged: updated.result.converged,
        combined_inputs: updated.combined,
    });
    line.parameters = updated.result.parameters.clone();
    chain.parameters = line
        .parameters
        .iter()
        .map(|p| Named {
            name: p.name.clone(),
            value: p.value,
        })
        .collect();
    Ok(())
}

/// The features judged: each tracked mode's identified frequency, then
/// each updated parameter's log10 value (`None`: not identified).
fn features(chain: &Chain, line: &EventLine, max_gap: f64) -> (Vec<String>, Vec<Option<f64>>) {
    let mut names = Vec::new();
    let mut values = Vec::new();
    for (k, &f) in chain.tracked_hz.iter().enumerate() {
        names.push(format!("mode{}_hz", k + 1));
        let nearest = line
            .modes
            .iter()
            .map(|m| m.frequency_hz)
            .min_by(|a, b| (a - f).abs().total_cmp(&(b - f).abs()))
            .filter(|m| (m - f).abs() <= max_gap * f);
        values.push(nearest);
    }
    for p in &line.parameters {
        names.push(format!("log10_{}", p.name));
        values.push(p.std.map(|_| p.value.log10()));
    }
    (names, values)
}

fn judge_event(cfg: &Config, chain: &mut Chain, line: &mut EventLine, pga: f64) {
    if chain.tracked_hz.is_empty() {
        chain.tracked_hz = line.modes.iter().map(|m| m.frequency_hz).collect();
    }
    let (names, values) = features(chain, line, cfg.updating.max_frequency_gap);
    let x = pga.max(1e-12).log10();
    let as_nan = |v: &[Option<f64>]| v.iter().map(|x| x.unwrap_or(f64::NAN)).collect::<Vec<_>>();
    let history: Vec<Vec<f64>> = chain.features.iter().map(|r| as_nan(r)).collect();
    let now = as_nan(&values);
    let (verdict, bands) = judge(
        &chain.amplitudes,
        &history,
        x,
        &now,
        cfg.events.false_alarm_rate,
        cfg.events.min_events,
    );
    let outside = match &verdict {
        Verdict::Alarm { features } => features.iter().map(|&f| names[f].clone()).collect(),
        _ => Vec::new(),
    };
    line.verdict = Some(VerdictLine {
        state: verdict.name().to_string(),
        outside,
        bands: names
            .into_iter()
            .zip(values.iter().zip(bands))
            .map(|(feature, (value, band))| BandLine {
                feature,
                value: *value,
                band,
            })
            .collect(),
    });
    // An alarmed event does not teach the bands: a lasting change keeps
    // alarming until the owner starts a new history.
    if !matches!(verdict, Verdict::Alarm { .. }) {
        chain.amplitudes.push(x);
        chain.features.push(values);
    }
}

/// `<prefix>/events/summary` (the `--json` line) and, when judged,
/// `<prefix>/events/verdict`, at the event's start.
fn write_event(w: &mut ResultsWriter<std::io::BufWriter<std::fs::File>>, line: &EventLine) -> Result<()> {
    let time = line
        .start
        .as_deref()
        .and_then(crate::io::wire::parse_timestamp)
        .unwrap_or(0);
    w.write("events/summary", time, line)?;
    if let Some(v) = &line.verdict {
        w.write("events/verdict", time, v)?;
    }
    Ok(())
}

fn status_message(k: u64, line: &EventLine, v: &VerdictLine) -> StatusMessage {
    StatusMessage {
        window: k,
        time: line.start.clone().unwrap_or_default(),
        state: if v.state == "alarm" {
            "alarm".into()
        } else {
            v.state.replace(' ', "_")
        },
        t2: None,
        t2_limit: None,
        mewma: None,
        mewma_limit: None,
        temperature_c: None,
        residuals: Vec::new(),
        temperatures: Default::default(),
        features: v
            .bands
            .iter()
            .map(|b| NamedValue {
                name: b.feature.clone(),
                value: b.value.unwrap_or(f64::NAN),
            })
            .collect(),
        flags: v.outside.iter().map(|f| format!("outside band: {f}")).collect(),
        exceedances: v.outside.len(),
        scored_by: Some("amplitude_band".into()),
    }
}

/// The median over the scored deck channels of the forecast's and the
/// baseline's strong-motion NRMSE.
fn forecast_medians(line: &EventLine) -> Option<(f64, f64)> {
    let median = |mut v: Vec<f64>| -> f64 {
        v.retain(|x| x.is_finite());
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    line.forecast.as_ref().map(|f| {
        (
            median(f.channels.iter().map(|c| c.nrmse_strong).collect()),
            median(f.baseline.iter().map(|c| c.score.nrmse_strong).collect()),
        )
    })
}

fn log_rerun(r: &mut crate::outputs::rerun::RerunOutput, line: &EventLine) -> Result<()> {
    let (Some(start), Some(pga), Some(peak)) = (line.start.as_deref(), line.pga_ground, line.peak_deck) else {
        return Ok(());
    };
    let Some(time_ns) = crate::io::wire::parse_timestamp(start) else {
        return Ok(());
    };
    let parameters: Vec<(String, f64)> = line.parameters.iter().map(|p| (p.name.clone(), p.value)).collect();
    let identified: Vec<f64> = line.modes.iter().map(|m| m.frequency_hz).collect();
    r.log_event(&crate::outputs::rerun::events::EventPoint {
        time_ns,
        pga_ground: pga,
        peak_deck: peak,
        parameters: &parameters,
        identified_hz: &identified,
        model_mode_hz: line.update.as_ref().and_then(|u| u.model_mode_hz),
        forecast: forecast_medians(line),
        verdict: line.verdict.as_ref().map(|v| v.state.as_str()),
    })
}

fn print_line(line: &EventLine, json: bool) -> Result<()> {
    if json {
        outln!("{}", serde_json::to_string(line)?);
        return Ok(());
    }
    if let Some(reason) = &line.skipped {
        errln!("{}: skipped: {reason}", line.event);
    }
    for note in &line.notes {
        errln!("{}: {note}", line.event);
    }
    let (forecast, baseline) = match forecast_medians(line) {
        Some((f, b)) => (format!("{f:.3}"), format!("{b:.3}")),
        None => ("-".into(), "-".into()),
    };
    let modes: Vec<String> = line.modes.iter().map(|m| format!("{:.2}", m.frequency_hz)).collect();
    let or_dash = |v: Option<f64>| v.map_or("-".into(), |x| format!("{x:.3}"));
    outln!(
        "{}\t{}\t{}\t{}\t{}\t{forecast}\t{baseline}\t{}",
        line.event,
        line.start.as_deref().unwrap_or("-"),
        or_dash(line.pga_ground),
        or_dash(line.peak_deck),
        if modes.is_empty() { "-".into() } else { modes.join(",") },
        line.skipped.as_ref().map_or_else(
            || line.verdict.as_ref().map_or("-".into(), |v| v.state.clone()),
            |_| "skipped".into()
        )
    );
    Ok(())
}
