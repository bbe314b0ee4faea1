//! `splinewatch import`: columns read from a logger's file (CSV/TSV, UFF 58)
//! mapped to the config's sensors and cut into wire-format channel blocks,
//! ready for a raw-input recording that `replay` and `frf` read.
//!
//! A column belongs to the sensor it names (exactly, else ignoring case); a
//! column that names no sensor is skipped and listed (refused with
//! `strict`). `P1:force` / `P1:acceleration` say which quantity of a sensor
//! that measures both, as do a unit (see `unit_quantity`: force, or
//! acceleration in SI, g, gal, mg, imperial…, converted to SI; `--units`
//! gives the unit of every column without one) and a UFF ordinate type.

use crate::config::Config;
use crate::io::import::{ImportedChannel, ImportedSeries};
use crate::io::wire::{format_timestamp, ChannelBlock, ChannelQuantity};
use anyhow::{bail, Context, Result};

/// What the file may not say.
#[derive(Debug, Clone)]
pub struct ImportOptions {
    /// Sampling rate, Hz (overrides the file's, which must agree within 1e-4).
    pub fs: Option<f64>,
    /// Time of the first sample (overrides an absolute time column).
    pub start_ns: Option<i128>,
    /// Samples per block, seconds.
    pub block_seconds: f64,
    /// Refuse a column that names no sensor instead of skipping it.
    pub strict: bool,
    /// The unit of every column whose file states none (a units row, a UFF
    /// header still wins).
    pub units: Option<String>,
}

/// The imported blocks and the columns skipped because they name no
/// sensor of the config.
#[derive(Debug)]
pub struct Imported {
    pub blocks: Vec<ChannelBlock>,
    pub skipped: Vec<String>,
}

/// A file's columns on their one sample grid: each a config sensor's
/// quantity, in SI, all from the same first sample at the same rate.
#[derive(Debug, Clone)]
pub struct Grid {
    pub fs: f64,
    /// The first sample's time, ns since the epoch.
    pub start_ns: i128,
    /// Force first, then the sensors in config order.
    pub channels: Vec<GridChannel>,
}

/// One column of a [`Grid`].
#[derive(Debug, Clone)]
pub struct GridChannel {
    /// Index into `[[sensors]]`.
    pub sensor: usize,
    pub quantity: ChannelQuantity,
    pub data: Vec<f64>,
}

impl Grid {
    /// Samples per channel.
    pub fn samples(&self) -> usize {
        self.channels.first().map_or(0, |c| c.data.len())
    }

    /// Sample `k`'s time (ns since the epoch).
    pub fn time_ns(&self, k: usize) -> i128 {
        self.start_ns + (k as f64 * 1e9 / self.fs).round() as i128
    }

    /// Where sensor `sensor`'s `quantity` is among the channels, when the
    /// grid holds it.
    pub fn channel_index(&self, sensor: usize, quantity: ChannelQuantity) -> Option<usize> {
        self.channels
            .iter()
            .position(|c| c.sensor == sensor && c.quantity == quantity)
    }

    /// Consecutive pieces of at most `max_samples` each (the last may be
    /// shorter): a record longer than an event may be is judged in parts.
    pub fn pieces(self, max_samples: usize) -> Vec<Grid> {
        let (samples, max) = (self.samples(), max_samples.max(1));
        if samples <= max {
            return vec![self];
        }
        (0..samples)
            .step_by(max)
            .map(|first| Grid {
                fs: self.fs,
                start_ns: self.time_ns(first),
                channels: self
                    .channels
                    .iter()
                    .map(|c| GridChannel {
                        data: c.data[first..(first + max).min(samples)].to_vec(),
                        ..*c
                    })
                    .collect(),
            })
            .collect()
    }

    /// The grid as wire-format channel blocks of `length` in time order
    /// (per block interval, the channels in the grid's order).
    pub fn blocks(&self, config: &Config, length: BlockLength) -> Vec<ChannelBlock> {
        let samples = self.samples();
        let block_len = ((length.0 * self.fs).round() as usize).max(1);
        let mut blocks = Vec::with_capacity(self.channels.len() * samples.div_ceil(block_len));
        for first in (0..samples).step_by(block_len) {
            let last = (first + block_len).min(samples);
            for c in &self.channels {
                blocks.push(ChannelBlock {
                    name: config.sensors[c.sensor].name.clone(),
                    quantity: c.quantity,
                    unit: c.quantity.unit().into(),
                    fs: self.fs,
                    start_ns: self.time_ns(first),
                    data: c.data[first..last].to_vec(),
                });
            }
        }
        blocks
    }
}

/// How long each block of a recording is: a positive number of seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockLength(f64);

impl BlockLength {
    /// `seconds` (`--block-seconds`), refused unless positive and finite.
    pub fn seconds(seconds: f64) -> Result<Self> {
        if !(seconds.is_finite() && seconds > 0.0) {
            bail!("--block-seconds must be positive, got {seconds}");
        }
        Ok(Self(seconds))
    }
}

/// The series as channel blocks in time order (per block interval: force
/// first, then the sensors in config order).
pub fn to_blocks(config: &Config, series: ImportedSeries, options: &ImportOptions) -> Result<Imported> {
    let length = BlockLength::seconds(options.block_seconds)?;
    let (grid, skipped) = to_grid(config, series, options)?;
    Ok(Imported {
        blocks: grid.blocks(config, length),
        skipped,
    })
}

/// The series on its grid, mapped to the config's sensors in SI (force
/// first, then the sensors in config order), and the columns skipped
/// because they name no sensor.
pub fn to_grid(config: &Config, series: ImportedSeries, options: &ImportOptions) -> Result<(Grid, Vec<String>)> {
    let fs = sampling_rate(series.fs, options.fs)?;
    let start_ns = match (options.start_ns, series.start_ns) {
        (Some(t), _) => t + (series.offset_seconds * 1e9).round() as i128,
        (None, Some(t)) => t,
        (None, None) => bail!("the file gives no absolute start time: pass --start (RFC 3339)"),
    };
    if let Some(u) = &options.units {
        unit_quantity(u).with_context(|| format!("--units {u:?}: {}", unknown_unit(u)))?;
    }
    let mut channels = Vec::new();
    let mut skipped = Vec::new();
    for mut c in series.channels {
        if c.unit.is_none() {
            c.unit.clone_from(&options.units);
        }
        let name = c.name.clone();
        match map_channel(config, c, options.strict)? {
            Some(m) => channels.push(m),
            None => skipped.push(name),
        }
    }
    if channels.is_empty() {
        bail!(
            "no column names a [[sensors]] entry of the config (columns: {})",
            skipped.join(", ")
        );
    }
    for (i, m) in channels.iter().enumerate() {
        if channels[..i]
            .iter()
            .any(|o| o.sensor == m.sensor && o.quantity == m.quantity)
        {
            bail!(
                "two columns give the {:?} of sensor {:?}",
                m.quantity,
                config.sensors[m.sensor].name
            );
        }
    }
    let samples = channels.first().map_or(0, |m| m.data.len());
    if samples == 0 {
        bail!("the file holds no samples");
    }
    if let Some(m) = channels.iter().find(|m| m.data.len() != samples) {
        bail!(
            "channel {:?} has {} samples, the first one {samples}: every channel must cover the same span",
            config.sensors[m.sensor].name,
            m.data.len()
        );
    }
    channels.sort_by_key(|m| (m.quantity != ChannelQuantity::Force, m.sensor));
    tracing::info!(
        message = "imported",
        channels = channels.len(),
        samples,
        fs,
        start = %format_timestamp(start_ns)
    );
    Ok((Grid { fs, start_ns, channels }, skipped))
}

fn sampling_rate(file: Option<f64>, flag: Option<f64>) -> Result<f64> {
    match (file, flag) {
        (_, Some(f)) if !(f.is_finite() && f > 0.0) => bail!("--fs {f} is not a positive rate"),
        (Some(file), Some(flag)) if (file - flag).abs() > 1e-4 * flag => {
            bail!("--fs {flag} Hz disagrees with the file's {file} Hz")
        }
        (_, Some(f)) | (Some(f), None) => Ok(f),
        (None, None) => bail!("the file gives no sampling rate (no time column): pass --fs"),
    }
}

/// What a unit measures.
#[derive(Debug, Clone, Copy, PartialEq)]
enum UnitKind {
    Measured(ChannelQuantity),
    /// Velocity and displacement: recognised, but no sensor channel carries them.
    Velocity,
    Displacement,
}

/// Standard gravity, m/s² (for `g` and `mg`).
const G: f64 = 9.806_65;

/// What a unit measures and its factor to SI (N, m/s², m/s, m). Strong-motion
/// and logger files use cm/s² (= gal), mm/s², milli-g and imperial units.
fn unit_quantity(unit: &str) -> Option<(UnitKind, f64)> {
    use ChannelQuantity::{Acceleration, Force};
    use UnitKind::{Displacement, Measured, Velocity};
    let squared = |u: &str| u.replace('²', "^2").replace("s2", "s^2").replace("s**2", "s^2");
    let unit = unit.trim();
    Some(match squared(unit).as_str() {
        "N" => (Measured(Force), 1.0),
        "kN" => (Measured(Force), 1e3),
        "m/s^2" | "m s^-2" => (Measured(Acceleration), 1.0),
        "cm/s^2" | "gal" | "Gal" => (Measured(Acceleration), 0.01),
        "mm/s^2" => (Measured(Acceleration), 1e-3),
        "g" => (Measured(Acceleration), G),
        "mg" => (Measured(Acceleration), 1e-3 * G),
        "in/s^2" => (Measured(Acceleration), 0.0254),
        "ft/s^2" => (Measured(Acceleration), 0.3048),
        "m/s" => (Velocity, 1.0),
        "mm/s" => (Velocity, 1e-3),
        "cm/s" => (Velocity, 0.01),
        "in/s" => (Velocity, 0.0254),
        "m" => (Displacement, 1.0),
        "mm" => (Displacement, 1e-3),
        "cm" => (Displacement, 0.01),
        "in" => (Displacement, 0.0254),
        _ => return None,
    })
}

fn unknown_unit(unit: &str) -> String {
    format!(
        "unit {unit:?} is not a known unit (force: N, kN; acceleration: m/s^2, cm/s^2 = gal, mm/s^2, g, mg, in/s^2, ft/s^2)"
    )
}

/// The sensor and quantity of column `c`, in SI; `None` when it names no
/// sensor and `strict` is off (the caller lists it as skipped).
fn map_channel(config: &Config, c: ImportedChannel, strict: bool) -> Result<Option<GridChannel>> {
    let (base, suffix) = match c.name.rsplit_once(':') {
        Some((b, q)) => (b, Some(q)),
        None => (c.name.as_str(), None),
    };
    let names: Vec<&str> = config.sensors.iter().map(|s| s.name.as_str()).collect();
    let found = names
        .iter()
        .position(|n| *n == base)
        .or_else(|| names.iter().position(|n| n.eq_ignore_ascii_case(base)));
    let sensor = match found {
        Some(s) => s,
        None if !strict => return Ok(None),
        None => bail!(
            "column {:?} matches no [[sensors]] name (sensors: {}; without --strict it is skipped)",
            c.name,
            names.join(", ")
        ),
    };
    let measured: Vec<ChannelQuantity> = config.sensors[sensor]
        .quantity
        .as_slice()
        .iter()
        .filter_map(|q| ChannelQuantity::from_wire(q))
        .collect();
    let (from_unit, scale) = match c.unit.as_deref() {
        Some(u) => match unit_quantity(u) {
            Some((UnitKind::Measured(q), s)) => (Some(q), s),
            Some((kind, _)) => bail!(
                "column {:?}: unit {u:?} is a {}; sensors record force or acceleration",
                c.name,
                if kind == UnitKind::Velocity {
                    "velocity"
                } else {
                    "displacement"
                }
            ),
            None => bail!("column {:?}: {}", c.name, unknown_unit(u)),
        },
        None => (None, 1.0),
    };
    let from_suffix = match suffix {
        Some(q) => Some(
            ChannelQuantity::from_wire(q)
                .with_context(|| format!("column {:?}: {q:?} is not force or acceleration", c.name))?,
        ),
        None => None,
    };
    let stated: Vec<ChannelQuantity> = [from_suffix, from_unit, c.quantity].into_iter().flatten().collect();
    if stated.windows(2).any(|w| w[0] != w[1]) {
        bail!("column {:?}: its name, unit and file disagree on the quantity", c.name);
    }
    let candidates: Vec<ChannelQuantity> = measured
        .into_iter()
        .filter(|q| stated.first().is_none_or(|s| s == q))
        .collect();
    let quantity = match candidates.as_slice() {
        [one] => *one,
        [] => bail!(
            "column {:?}: sensor {:?} measures no {}",
            c.name,
            names[sensor],
            stated.first().map_or("force or acceleration", |q| q.wire_name())
        ),
        _ => bail!(
            "column {:?}: sensor {:?} measures force and acceleration; name the column {0}:force or {0}:acceleration, or give its unit",
            c.name,
            names[sensor]
        ),
    };
    let data = c.data.into_iter().map(|v| v * scale).collect();
    Ok(Some(GridChannel { sensor, quantity, data }))
}
