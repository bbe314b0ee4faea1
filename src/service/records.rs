//! An event's record read and put on one grid: the station files, V2 sets,
//! MCAP recordings and loggers' files of `predict`, `identify` and
//! `events`, and the daemon's bursts (issue 45), and the input–output
//! identification they share.
//! Room: a service shell. May import: `outputs`, `pipeline`, `studies`, `config`, `io`, the core crate.

use crate::config::{ground_sensors, restrict_plan, Config, GroundInputPlan};
use crate::io::console::errln;
use crate::io::recording::{read_recording, RecordedBlock};
use crate::io::wire::ChannelQuantity;
use crate::pipeline::estimate::aligned_span;
use crate::studies::import::{to_blocks, ImportOptions};
use anyhow::{bail, Context, Result};
use splinewatch_core::identification::resample::fourier_resample;
use std::borrow::Cow;
use std::path::PathBuf;

/// Whether the record holds config sensor `i`'s acceleration.
pub fn recorded(config: &Config, blocks: &[RecordedBlock], i: usize) -> bool {
    let name = &config.sensors[i].name;
    blocks
        .iter()
        .any(|b| &b.block.name == name && b.block.quantity == ChannelQuantity::Acceleration)
}

/// The channel blocks of an event's files and what reading them found.
pub struct Records {
    pub blocks: Vec<RecordedBlock>,
    /// What the import did to the data, a sentence each (a recorder placed
    /// by its channels' motion, channels cut to the span all share).
    pub notes: Vec<String>,
}

/// Every channel block of the records: V2 files and station zips are
/// imported (together: one event), MCAP recordings read. `start_ns`, when
/// given, is the first sample's time of the V2 and logger files (over
/// their own; `--start`); an MCAP recording keeps its times.
pub fn read_records(config: &Config, paths: &[PathBuf], start_ns: Option<i128>) -> Result<Records> {
    let limits = crate::pipeline::block_limits(config);
    let prefix = config.topic_prefix();
    let mut v2 = Vec::new();
    let mut blocks = Vec::new();
    let mut notes = Vec::new();
    for path in paths {
        let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or_default()
            .to_ascii_lowercase();
        if bytes.starts_with(b"\x89MCAP") {
            if start_ns.is_some() {
                bail!(
                    "{}: --start applies to station (V2) and logger files; an MCAP recording has its own times",
                    path.display()
                );
            }
            let (mut read, rejected) =
                read_recording(&bytes, &limits).with_context(|| format!("reading {}", path.display()))?;
            for r in &rejected {
                errln!("{}: skipped a message on {}: {}", path.display(), r.topic, r.error);
            }
            blocks.append(&mut read);
        } else if crate::io::uff::looks_like_uff(&bytes) || matches!(extension.as_str(), "csv" | "tsv" | "txt") {
            // A logger's file: read as `import` reads it (the file's own time
            // and rate; `import` first when they must be given).
            let series = if crate::io::uff::looks_like_uff(&bytes) {
                crate::io::import::read_uff58(&bytes)
            } else {
                let text =
                    std::str::from_utf8(&bytes).with_context(|| format!("{}: not UTF-8 text", path.display()))?;
                crate::io::import::read_csv(text, &Default::default())
            }
            .with_context(|| path.display().to_string())?;
            blocks.extend(imported_blocks(config, series, &prefix, start_ns).with_context(|| {
                format!(
                    "{}: give --start, or convert it with `splinewatch import` (--fs, --start) first",
                    path.display()
                )
            })?);
        } else {
            v2.push((bytes, path.display().to_string()));
        }
    }
    if !v2.is_empty() {
        let series = crate::io::cosmos_v2::read_v2(&v2)?;
        notes.extend(series.notes.iter().cloned());
        blocks.extend(imported_blocks(config, series, &prefix, start_ns)?);
    }
    Ok(Records { blocks, notes })
}

/// A file's columns as the config's channel blocks (as `import` makes them).
fn imported_blocks(
    config: &Config,
    series: crate::io::import::ImportedSeries,
    prefix: &str,
    start_ns: Option<i128>,
) -> Result<Vec<RecordedBlock>> {
    let options = ImportOptions {
        fs: None,
        start_ns,
        block_seconds: 10.0,
        strict: false,
        units: None,
    };
    let imported = to_blocks(config, series, &options)?;
    Ok(imported
        .blocks
        .into_iter()
        .map(|block| RecordedBlock::at_its_start(block, prefix))
        .collect())
}

/// The record's channels on one grid: the ground sensors the model reads
/// (all required) and the deck's acceleration sensors it holds.
pub struct Event {
    pub fs: f64,
    pub start_ns: i128,
    /// Per config sensor, its samples when recorded.
    pub channels: Vec<Option<Vec<f64>>>,
    pub deck: Vec<usize>,
    /// How the ground inputs differ from the config's (a ground channel
    /// the record lacks, the input that takes the mean of others instead).
    pub notes: Vec<String>,
}

/// The record's channels on one grid for the ground inputs of `plan`
/// (kept to the ground sensors the record holds, the changes said).
pub fn align_event(config: &Config, plan: &mut Vec<GroundInputPlan>, blocks: &[RecordedBlock]) -> Result<Event> {
    let recorded = |i: usize| recorded(config, blocks, i);
    let (restricted, notes) = restrict_plan(plan, recorded, |i| config.sensors[i].name.clone());
    *plan = restricted;
    let notes: Vec<String> = notes.into_iter().map(|note| format!("ground input {note}")).collect();
    for note in &notes {
        errln!("{note}");
    }
    let ground = ground_sensors(plan);
    if ground.is_empty() {
        bail!("the record holds none of the config's ground sensors: nothing drives the deck");
    }
    let deck: Vec<usize> = (0..config.deck_sensor_count()).filter(|&i| recorded(i)).collect();
    let wanted: Vec<(usize, ChannelQuantity)> = ground
        .iter()
        .chain(&deck)
        .map(|&i| (i, ChannelQuantity::Acceleration))
        .collect();
    let span = aligned_span(config, blocks, None, None, &wanted)?;
    let mut channels = vec![None; config.sensors.len()];
    for ((i, _), data) in wanted.iter().zip(span.channels) {
        channels[*i] = Some(data);
    }
    Ok(Event {
        fs: span.fs,
        start_ns: span.start_ns,
        channels,
        deck,
        notes,
    })
}

/// SRIM's modes of a record, or why it found none (no stable mode: not an
/// error when another estimate may find them).
pub type SrimModes = std::result::Result<splinewatch_core::identification::oma::OmaResult, String>;

/// SRIM of `inputs` to `outputs` with the config's `[oma]` settings and
/// delete-one-batch (jackknife) uncertainty, at the identification rate
/// ([`at_identification_rate`]); returns the settings and the rate used.
pub fn identify_io(
    cfg: &Config,
    inputs: &[&[f64]],
    outputs: &[&[f64]],
    fs: f64,
) -> Result<(SrimModes, splinewatch_core::identification::oma::OmaSettings, f64)> {
    let record = at_identification_rate(cfg, inputs, outputs, fs);
    let (inputs, outputs, fs) = (record.inputs(), record.outputs(), record.fs);
    let (mut settings, _) = cfg.oma_settings_at(fs)?;
    // The exact replicates: their first-order continuation overstated SRIM's
    // spreads up to fivefold on simulated records (the core's verification),
    // and 8-165x on the overpass simulated from the 20 Painter Street grounds
    // (measured 2026-11-27, the data matrices' estimate; it would have taken
    // identify from 0.42 to 0.28 s).
    settings.uncertainty = splinewatch_core::identification::oma::UncertaintyMethod::Jackknife;
    use splinewatch_core::identification::oma::OmaError;
    let result = match splinewatch_core::identification::srim::identify_io(&inputs, &outputs, fs, &settings) {
        Ok(result) => Ok(result),
        Err(e @ OmaError::NoModes { .. }) => Err(format!("identification: {e}")),
        Err(e) => bail!("identification: {e}"),
    };
    Ok((result, settings, fs))
}

/// A record's inputs and outputs at the rate SRIM identifies them at
/// ([`at_identification_rate`]).
pub struct AtIdentificationRate<'a> {
    inputs: Vec<Cow<'a, [f64]>>,
    outputs: Vec<Cow<'a, [f64]>>,
    /// The rate (Hz): exactly the points per span.
    pub fs: f64,
}

impl AtIdentificationRate<'_> {
    pub fn inputs(&self) -> Vec<&[f64]> {
        self.inputs.iter().map(|x| x.as_ref()).collect()
    }

    pub fn outputs(&self) -> Vec<&[f64]> {
        self.outputs.iter().map(|x| x.as_ref()).collect()
    }
}

/// `inputs` and `outputs` at `fs` at the rate SRIM identifies them at
/// ([`Config::identification_rate`]): resampled over the same span
/// (Fourier) when `[oma] resample_hz` is below `fs`, as they are otherwise.
pub fn at_identification_rate<'a>(
    cfg: &Config,
    inputs: &[&'a [f64]],
    outputs: &[&'a [f64]],
    fs: f64,
) -> AtIdentificationRate<'a> {
    let rate = cfg.identification_rate(fs);
    let samples = outputs.first().or(inputs.first()).map_or(0, |x| x.len());
    let points = (samples as f64 * rate / fs).round() as usize;
    if rate >= fs || samples == 0 || points >= samples {
        let keep = |list: &[&'a [f64]]| list.iter().map(|&x| Cow::Borrowed(x)).collect();
        return AtIdentificationRate {
            inputs: keep(inputs),
            outputs: keep(outputs),
            fs,
        };
    }
    let resample = |list: &[&'a [f64]]| list.iter().map(|x| Cow::Owned(fourier_resample(x, points))).collect();
    AtIdentificationRate {
        inputs: resample(inputs),
        outputs: resample(outputs),
        fs: fs * points as f64 / samples as f64,
    }
}

/// A rate as people write it: `100` for a whole number of Hz, `50.006`
/// otherwise (a resampled record's exact rate, points per span).
pub fn rate_text(fs: f64) -> String {
    if (fs - fs.round()).abs() < 1e-9 {
        format!("{}", fs.round())
    } else {
        format!("{fs:.3}")
    }
}
