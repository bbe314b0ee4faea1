//! An event's record read and put on one grid: the station files, V2 sets,
//! MCAP recordings and loggers' files of `predict`, `identify` and
//! `events`, and the daemon's bursts (issue 45), and the input–output
//! identification they share.
//! Room: a service shell. May import: `outputs`, `pipeline`, `studies`, `config`, `io`, the core crate.

use crate::config::{ground_sensors, restrict_plan, Config, GroundInputPlan};
use crate::io::console::errln;
use crate::io::recording::{read_recording, RecordedBlock};
use crate::io::wire::ChannelQuantity;
use crate::pipeline::estimate::{aligned_span, AlignedSpan};
use crate::studies::import::{to_grid, BlockLength, Grid, ImportOptions};
use anyhow::{bail, Context, Result};
use splinewatch_core::identification::resample::fourier_resample;
use std::borrow::Cow;
use std::path::PathBuf;

/// An event's record as read: on its grid (station files, a logger's
/// file), or as channel blocks still to be aligned (MCAP recordings, a
/// logger's stream, files of several sources together).
pub enum Record {
    Grid(Grid),
    Blocks(Vec<RecordedBlock>),
}

impl Record {
    /// Whether the record holds config sensor `sensor`'s `quantity`.
    pub fn holds(&self, config: &Config, sensor: usize, quantity: ChannelQuantity) -> bool {
        match self {
            Record::Grid(grid) => grid.channel_index(sensor, quantity).is_some(),
            Record::Blocks(blocks) => {
                let name = &config.sensors[sensor].name;
                blocks
                    .iter()
                    .any(|b| &b.block.name == name && b.block.quantity == quantity)
            }
        }
    }

    /// Whether the record holds config sensor `i`'s acceleration.
    pub fn recorded(&self, config: &Config, i: usize) -> bool {
        self.holds(config, i, ChannelQuantity::Acceleration)
    }

    /// Its first sample's time (ns since the epoch); `None` when empty.
    pub fn start_ns(&self) -> Option<i128> {
        match self {
            Record::Grid(grid) => Some(grid.start_ns),
            Record::Blocks(blocks) => blocks.iter().map(|r| r.block.start_ns).min(),
        }
    }

    /// The channels `wanted` (sensor index, quantity) over the span they
    /// share: a grid's as read, blocks aligned ([`aligned_span`]).
    pub fn span(self, config: &Config, wanted: &[(usize, ChannelQuantity)]) -> Result<AlignedSpan> {
        let mut grid = match self {
            Record::Blocks(blocks) => return aligned_span(config, &blocks, None, None, wanted),
            Record::Grid(grid) => grid,
        };
        let channels = wanted
            .iter()
            .map(|&(sensor, quantity)| {
                let Some(at) = grid.channel_index(sensor, quantity) else {
                    bail!(
                        "no {} of {} in the record",
                        quantity.wire_name(),
                        config.sensors[sensor].name
                    );
                };
                // Moved out, or copied when asked twice.
                Ok(if wanted.iter().filter(|w| **w == (sensor, quantity)).count() > 1 {
                    grid.channels[at].data.clone()
                } else {
                    std::mem::take(&mut grid.channels[at].data)
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(AlignedSpan {
            start_ns: grid.start_ns,
            samples: channels.first().map_or(0, Vec::len),
            fs: grid.fs,
            channels,
        })
    }
}

/// An event's record and what reading it found.
pub struct Records {
    pub record: Record,
    /// What the import did to the data, a sentence each (a recorder placed
    /// by its channels' motion, channels cut to the span all share).
    pub notes: Vec<String>,
}

/// The record of an event's files: V2 files and station zips are imported
/// together (one grid), a logger's file on its own grid, MCAP recordings
/// read as blocks; several sources together are blocks to be aligned.
/// `start_ns`, when given, is the first sample's time of the V2 and logger
/// files (over their own; `--start`); an MCAP recording keeps its times.
pub fn read_records(config: &Config, paths: &[PathBuf], start_ns: Option<i128>) -> Result<Records> {
    let limits = crate::pipeline::block_limits(config);
    let mut v2 = Vec::new();
    let mut grids = Vec::new();
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
            grids.push(imported_grid(config, series, start_ns).with_context(|| {
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
        grids.push(imported_grid(config, series, start_ns)?);
    }
    let record = if blocks.is_empty() && grids.len() == 1 {
        Record::Grid(grids.pop().expect("one"))
    } else {
        // Several sources: each grid as the blocks `import` writes, aligned
        // with the others where they overlap.
        let prefix = config.topic_prefix();
        for grid in &grids {
            let cut = grid.blocks(config, BlockLength::seconds(JOINED_BLOCK_SECONDS)?);
            blocks.extend(cut.into_iter().map(|block| RecordedBlock::at_its_start(block, &prefix)));
        }
        Record::Blocks(blocks)
    };
    Ok(Records { record, notes })
}

/// The blocks' length when a file's grid joins other sources: `[events]
/// max_seconds` cuts their bursts at these blocks' bounds.
const JOINED_BLOCK_SECONDS: f64 = 10.0;

/// A file's columns on the config's sensors (as `import` maps them).
fn imported_grid(config: &Config, series: crate::io::import::ImportedSeries, start_ns: Option<i128>) -> Result<Grid> {
    let options = ImportOptions {
        fs: None,
        start_ns,
        block_seconds: JOINED_BLOCK_SECONDS,
        strict: false,
        units: None,
    };
    Ok(to_grid(config, series, &options)?.0)
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
pub fn align_event(config: &Config, plan: &mut Vec<GroundInputPlan>, record: Record) -> Result<Event> {
    let recorded = |i: usize| record.recorded(config, i);
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
    let span = record.span(config, &wanted)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::studies::import::GridChannel;

    fn config() -> Config {
        Config::from_toml(include_str!("../../config/painter-street.toml")).unwrap()
    }

    /// Three accelerations at 100 Hz, 23.45 s, starting off the whole second.
    fn grid() -> Grid {
        let channel = |sensor: usize| GridChannel {
            sensor,
            quantity: ChannelQuantity::Acceleration,
            data: (0..2345).map(|k| ((k * (sensor + 3)) as f64 * 0.37).sin()).collect(),
        };
        Grid {
            fs: 100.0,
            start_ns: 1_421_000_000_123_000_000,
            channels: vec![channel(0), channel(3), channel(12)],
        }
    }

    #[test]
    fn a_grid_spans_as_its_blocks_aligned() {
        let cfg = config();
        let prefix = cfg.topic_prefix();
        let blocks: Vec<RecordedBlock> = grid()
            .blocks(&cfg, BlockLength::seconds(10.0).unwrap())
            .into_iter()
            .map(|b| RecordedBlock::at_its_start(b, &prefix))
            .collect();
        let wanted = [(12, ChannelQuantity::Acceleration), (0, ChannelQuantity::Acceleration)];
        let as_grid = Record::Grid(grid()).span(&cfg, &wanted).unwrap();
        let as_blocks = Record::Blocks(blocks).span(&cfg, &wanted).unwrap();
        assert_eq!(
            (as_grid.start_ns, as_grid.samples, as_grid.fs),
            (as_blocks.start_ns, 2345, 100.0)
        );
        assert_eq!(as_grid.samples, as_blocks.samples);
        assert_eq!(as_grid.channels, as_blocks.channels);
        assert_eq!(as_grid.channels[0], grid().channels[2].data);
    }

    #[test]
    fn a_grid_says_what_it_holds_and_refuses_what_it_does_not() {
        let cfg = config();
        let record = Record::Grid(grid());
        assert!(record.recorded(&cfg, 3) && !record.recorded(&cfg, 4));
        assert!(!record.holds(&cfg, 3, ChannelQuantity::Force));
        assert_eq!(record.start_ns(), Some(grid().start_ns));
        let error = record
            .span(&cfg, &[(4, ChannelQuantity::Acceleration)])
            .expect_err("no such channel");
        assert!(error.to_string().contains(&cfg.sensors[4].name), "{error}");
        assert_eq!(Record::Blocks(Vec::new()).start_ns(), None);
    }

    #[test]
    fn a_long_grid_is_cut_into_pieces_that_lose_nothing() {
        let whole = grid();
        let pieces = grid().pieces(1000);
        let lengths: Vec<usize> = pieces.iter().map(Grid::samples).collect();
        assert_eq!(lengths, [1000, 1000, 345]);
        for (k, piece) in pieces.iter().enumerate() {
            assert_eq!(piece.start_ns, whole.time_ns(1000 * k));
            assert_eq!(piece.channels.len(), 3);
        }
        for (c, channel) in whole.channels.iter().enumerate() {
            let joined: Vec<f64> = pieces.iter().flat_map(|p| p.channels[c].data.clone()).collect();
            assert_eq!(joined, channel.data);
        }
        assert_eq!(grid().pieces(2345).len(), 1);
        assert_eq!(grid().pieces(0).len(), 2345, "at least a sample a piece");
    }
}
