//! `splinewatch events`: earthquake by earthquake (issue 45). Every input
//! (a station's zip, a folder of V2 files, an MCAP recording) is one event;
//! in time order each is checked, identified (SRIM), forecast by the model
//! updated on the events before it (`predict`'s figures), updated on its
//! transmissibilities (warm-started from the previous event), and judged
//! against the bands the earlier events give at its amplitude
//! ([`splinewatch_core::monitoring::amplitude`]).
//!
//! An event that cannot be used (unreadable, a dead or clipped channel, no
//! ground channel at all, too short) is reported as skipped with its reason
//! and the others go on; a ground channel the record lacks takes the mean of
//! the groups measured along its axis, said in the event's notes. When no
//! input could be read at all, the run fails after saying so for each.

use crate::config::{load_config, Config, EventAmplitude, GroundInputPlan};
use crate::io::console::{errln, outln};
use crate::io::monitoring_json::StatusMessage;
use crate::io::wire::format_timestamp;
use crate::outputs::notify::Notifier;
use crate::outputs::rerun::events::{EventLog, EventTimeline};
use crate::outputs::results::ResultsWriter;
use crate::service::events::burst::split;
use crate::service::events::{
    emit, forecast_medians, identify, load, log_rerun, process_identified, Chain, EventLine, EventSink, Loaded,
};
use crate::service::records::{read_records, Record};
use anyhow::{bail, Context, Result};
use clap::Args;
use std::path::{Path, PathBuf};
use thread_priority::{set_current_thread_priority, ThreadPriority};

#[derive(Args)]
pub struct EventsArgs {
    /// Configuration file (TOML) with ground sensors (`support = "<group>"`); `[events]` sets the verdict.
    #[arg(long)]
    pub config: PathBuf,
    /// One event each: a station's .zip, a folder of its .V2 files, a logger's CSV/UFF, or a raw-input MCAP
    /// recording (a triggered logger's: each burst, silences longer than `[events] gap_seconds` apart, one event; a
    /// record longer than `[events] max_seconds`: one event per part of that length).
    #[arg(required = true, num_args = 1..)]
    pub input: Vec<PathBuf>,
    /// The record's first sample, RFC 3339, over the time its files give (one input only).
    #[arg(long, value_parser = super::ground::parse_start)]
    pub start: Option<i128>,
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

/// The config of `events`, with ground sensors; `--start` with one input.
fn checked_config(a: &EventsArgs) -> Result<Config> {
    let cfg = load_config(&a.config)?;
    if !cfg.has_ground_sensors() {
        bail!("config: sensors: events need ground sensors ([[sensors]] with support = \"<group>\")");
    }
    if a.start.is_some() && a.input.len() > 1 {
        bail!(
            "--start gives one record's first sample: with {} inputs, run events once per input that needs it",
            a.input.len()
        );
    }
    Ok(cfg)
}

pub fn events(a: EventsArgs) -> Result<()> {
    let cfg = checked_config(&a)?;
    let mut chain = Chain::resume(a.state.as_deref())?;
    chain.check(&cfg)?;
    // The model once (when there is one), for the records' ground plan and then the chain.
    let plan = chain.plan(&cfg)?;
    let mut loaded = load_inputs(&cfg, &plan, &a.input, a.start);
    let unreadable = loaded.iter().filter(|l| l.unreadable()).count();
    // In time order; events that could not be read keep their place at the end.
    loaded.sort_by_key(|l| l.start_ns().unwrap_or(i128::MAX));
    let mut outputs = CommandOutputs {
        writer: a
            .out
            .as_deref()
            .map(|p| ResultsWriter::create_for(p, &cfg))
            .transpose()?,
        notifier: Notifier::for_config(&cfg, None).context("starting the notifier")?,
        rerun: a.rerun_save.as_ref().map(|path| open_rerun(&cfg, path)).transpose()?,
        json: a.json,
    };
    if !a.json {
        outln!("event\tstart\tpga_ground\tpeak_deck\tmodes\tmodel_mode_hz\tforecast_nrmse\tbaseline_nrmse\tverdict");
    }
    let mut lines = Vec::new();
    // The identifications depend on the records alone: a second thread runs
    // them ahead, in order, while this one forecasts and updates the chain.
    std::thread::scope(|scope| -> Result<()> {
        let (sender, identified) = std::sync::mpsc::channel();
        let (cfg, loaded) = (&cfg, &loaded);
        scope.spawn(move || {
            // The chain is the critical path: the identifications take the
            // cores it leaves (20 Painter Street events 16.2 -> 14.9 s).
            // Lowering a thread's own priority needs no privilege; where the
            // platform refuses, they run at the same priority.
            if let Err(e) = set_current_thread_priority(ThreadPriority::Min) {
                tracing::debug!("the identification thread keeps its priority: {e}");
            }
            for l in loaded {
                if sender.send(identify(cfg, l)).is_err() {
                    break;
                }
            }
        });
        for l in loaded {
            let identified = || identified.recv().unwrap_or_else(|_| identify(cfg, l));
            let line = process_identified(cfg, l, identified, &mut chain);
            emit(&line, cfg.events().amplitude, &mut outputs)?;
            lines.push(line);
        }
        Ok(())
    })?;
    outputs.finish()?;
    if let Some(p) = &a.state {
        chain.save(p)?;
    }
    // Every input unreadable (a mistyped path, a glob the shell did not
    // expand): nothing was judged, which a script must not take for success.
    if unreadable == loaded.len() {
        bail!(
            "none of the {} inputs could be read (each said above): nothing was judged",
            loaded.len()
        );
    }
    if let Some(dir) = &a.plot {
        let band = cfg.updating.band.unwrap_or(cfg.frf.band);
        let amplitude = cfg.events().amplitude;
        super::events_plot::frequency_vs_amplitude(&mode_points(&lines, amplitude), band, amplitude, dir)?;
    }
    Ok(())
}

/// Where `events` sends each event: `--out`'s results file, the owner's
/// notifier, `--rerun-save`'s recording and the terminal.
struct CommandOutputs {
    writer: Option<ResultsWriter<std::io::BufWriter<std::fs::File>>>,
    notifier: Option<Notifier>,
    rerun: Option<Box<dyn EventLog>>,
    json: bool,
}

impl EventSink for CommandOutputs {
    fn message(&mut self, topic: &'static str, time_ns: i128, json: Vec<u8>) -> Result<()> {
        if let Some(w) = self.writer.as_mut() {
            w.write_json(topic, time_ns, &json)?;
        }
        if let Some(n) = self.notifier.as_mut() {
            n.record(topic, &json);
        }
        Ok(())
    }

    fn status(&mut self, status: &StatusMessage, json: &[u8]) -> Result<()> {
        if let Some(n) = self.notifier.as_mut() {
            n.observe(status, json);
        }
        Ok(())
    }

    fn rerun(&mut self, line: &EventLine, kind: EventAmplitude) -> Result<()> {
        match self.rerun.as_mut() {
            Some(r) => log_rerun(r.as_mut(), line, kind),
            None => Ok(()),
        }
    }

    fn line(&mut self, line: &EventLine) -> Result<()> {
        print_line(line, self.json)
    }
}

impl CommandOutputs {
    /// Closes the recording, the notifier and the results file, in that order.
    fn finish(mut self) -> Result<()> {
        if let Some(r) = self.rerun {
            r.close()?;
        }
        if let Some(n) = self.notifier.as_mut() {
            n.finish();
        }
        if let Some(w) = self.writer {
            w.finish()?;
        }
        Ok(())
    }
}

/// The Rerun recording `--rerun-save` writes: the whole stream with a
/// model, the events' timeline alone without one.
fn open_rerun(cfg: &Config, path: &Path) -> Result<Box<dyn EventLog>> {
    if !cfg.has_model() {
        return Ok(Box::new(EventTimeline::save(path)?));
    }
    let targets = crate::outputs::rerun::RerunTargets {
        save: Some(path.to_path_buf()),
        connect: None,
    };
    Ok(Box::new(crate::outputs::rerun::RerunOutput::open_rotating(
        cfg, &targets, false,
    )?))
}

/// Every identified mode of every used event, and the updated model's
/// dominant mode, each with its standard deviation.
fn mode_points(lines: &[EventLine], kind: EventAmplitude) -> Vec<super::events_plot::ModePoint> {
    let mut points = Vec::new();
    for line in lines.iter().filter(|l| l.skipped.is_none()) {
        let Some(amplitude) = line.amplitude(kind).filter(|p| *p > 0.0) else {
            continue;
        };
        let alarmed = line.verdict.as_ref().is_some_and(|v| v.state == "alarm");
        for m in &line.modes {
            points.push(super::events_plot::ModePoint {
                amplitude,
                frequency_hz: m.frequency_hz,
                std_hz: m.frequency_std_hz.unwrap_or(0.0),
                alarmed,
                model: false,
            });
        }
        if let Some((update, f)) = line.update.as_ref().and_then(|u| Some((u, u.model_mode_hz?))) {
            points.push(super::events_plot::ModePoint {
                amplitude,
                frequency_hz: f,
                std_hz: update.model_mode_std_hz.unwrap_or(0.0),
                alarmed,
                model: true,
            });
        }
    }
    points
}

/// Every input's events, in the inputs' order: read on as many threads as
/// there are cores (each record is decompressed, parsed and checked on its
/// own: 20 Painter Street zips 0.5 s on one).
fn load_inputs(cfg: &Config, plan: &[GroundInputPlan], inputs: &[PathBuf], start: Option<i128>) -> Vec<Loaded> {
    let threads = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
    let chunk = inputs.len().div_ceil(threads).max(1);
    std::thread::scope(|scope| {
        let handles: Vec<_> = inputs
            .chunks(chunk)
            .map(|part| {
                scope.spawn(move || {
                    part.iter()
                        .flat_map(|p| load_input(cfg, plan, p, start))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    })
}

/// The events of one input: its record, or each part of it when it holds
/// several (a triggered logger's raw-input recording: silences longer than
/// `[events] gap_seconds`; any record: `[events] max_seconds`), named
/// `<file>@<start>`; what the import did to the record in each event's
/// notes.
fn load_input(cfg: &Config, plan: &[GroundInputPlan], path: &Path, start: Option<i128>) -> Vec<Loaded> {
    let name = path
        .file_name()
        .map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    let records = match event_files(path).and_then(|files| read_records(cfg, &files, start)) {
        Ok(records) => records,
        Err(e) => return vec![load(cfg, plan, name, Err(e))],
    };
    let notes = records.notes;
    let (gap, max) = (cfg.events().gap_seconds, cfg.events().max_seconds);
    let parts: Vec<(i128, Record)> = match records.record {
        Record::Grid(grid) => {
            let max_samples = (max * grid.fs).round() as usize;
            grid.pieces(max_samples)
                .into_iter()
                .map(|g| (g.start_ns, Record::Grid(g)))
                .collect()
        }
        Record::Blocks(blocks) => split(blocks, gap, max)
            .into_iter()
            .map(|b| (b.start_ns, Record::Blocks(b.blocks)))
            .collect(),
    };
    if parts.is_empty() {
        // Said by the check: the record holds none of the config's channels.
        return vec![load(cfg, plan, name, Ok(Record::Blocks(Vec::new())))];
    }
    let several = parts.len() > 1;
    parts
        .into_iter()
        .map(|(start_ns, record)| {
            let event = if several {
                format!("{name}@{}", format_timestamp(start_ns))
            } else {
                name.clone()
            };
            load(cfg, plan, event, Ok(record)).noted(&notes)
        })
        .collect()
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
    let model = line
        .update
        .as_ref()
        .and_then(|u| u.model_mode_hz.map(|f| (f, u.model_mode_std_hz)));
    let model = match model {
        Some((f, Some(s))) => format!("{f:.3}±{s:.3}"),
        Some((f, None)) => format!("{f:.3}"),
        None => "-".into(),
    };
    outln!(
        "{}\t{}\t{}\t{}\t{}\t{model}\t{forecast}\t{baseline}\t{}",
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
