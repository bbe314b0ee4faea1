//! CSMIP/COSMOS "Volume 2" corrected accelerograms, as the California
//! Geological Survey's CESMD distributes the records of instrumented
//! bridges: one channel per `.V2` file (often zipped per station), or every
//! channel of a station in one file, each ending with
//! `/&  ---------- End of data for channel  N ----------`.
//!
//! A channel is 25 text lines (line 8 `Chan  N: …`, and the record's start
//! `Rcrd of Mon Nov 23, 2026 10:00:00.0 UTC`), 100 integers and 100 reals,
//! then per series a line `1500 points of accel data equally spaced at
//! 0.010 sec, in cm/sec2. (8f10.5)` and the values in fixed-width fields,
//! eight to a line; the velocity and displacement series follow. Only the
//! acceleration is read (the sensors measure it); rather than count header
//! lines, which differ between processing vintages, the reader finds that
//! line. Each channel becomes a column `ch<N>`.
//!
//! Files processed before about 2000 (the CDMG's upper-case layout) say the
//! same in capitals, `1082 POINTS OF ACCEL DATA EQUALLY SPACED AT  .020 SEC.
//! (UNITS: CM/SEC/SEC)`, give orientations as azimuths (`CHAN  3: 270 DEG`)
//! and the start as the trigger time (`TRIGGER TIME: 11/21/86, 23:33:12.6
//! GMT`, or `06:53:XX.X` where the film showed no seconds: no start then);
//! their header also has a `POINTS OF INSTRUMENT- AND BASELINE-CORRECTED
//! ACCEL…` line, which is not the series'. Markers are matched whatever
//! their case.

use crate::io::import::{ImportError, ImportedSeries};
use std::io::Read;

mod clock;
mod grid;
mod header;
pub mod placement;
#[cfg(test)]
mod tests;

use clock::{align_flagged_recorders, Clock, Recorder};
use grid::to_series;
use header::{
    channel_description, channel_number, field_width, fields, file_channel_number, number_after, record_start,
    recorder_clock, series_unit, station_channel, station_line, station_name, trigger_start,
};

/// One channel's acceleration as the file gives it.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct V2Channel {
    pub(super) number: u32,
    /// The file (and, in a zip, the member) it came from, for messages.
    pub(super) file: String,
    /// What the `Chan N:` line says after the number: `Tran`, `Up`, `360 Deg`.
    pub(super) direction: String,
    /// The line's `Location:` text, e.g. `Deck: Near West Abutment`.
    pub(super) location: String,
    pub(super) time_step: f64,
    pub(super) unit: String,
    pub(super) start_ns: Option<i128>,
    /// The recorder and its clock, when the header says (the current layout).
    pub(super) recorder: Option<Recorder>,
    pub(super) station: Option<Station>,
    pub(super) values: Vec<f64>,
}

/// The station a channel's header names.
#[derive(Debug, Clone, PartialEq)]
pub struct Station {
    /// The CSMIP station number as written (`89324`, `01336`).
    pub number: String,
    /// `Rio Dell - Hwy 101/Painter St. Overpass`.
    pub name: String,
    /// Degrees north.
    pub latitude: f64,
    /// Degrees east (west negative).
    pub longitude: f64,
}

/// One channel as `import --list` shows it.
#[derive(Debug, Clone, PartialEq)]
pub struct V2Summary {
    /// The station channel (`Sta Chn: N`, else `Chan N:`): the column `chN`.
    pub channel: u32,
    pub direction: String,
    pub location: String,
    /// Samples per second.
    pub rate_hz: f64,
    pub points: usize,
    /// The largest absolute acceleration, in the file's unit.
    pub peak: f64,
    pub unit: String,
    pub file: String,
    pub station: Option<Station>,
}

pub(super) fn error(what: &str, message: impl Into<String>) -> ImportError {
    ImportError::V2 {
        file: what.to_string(),
        message: message.into(),
    }
}

/// Reads `.V2` files or `.zip` files of them (told by their first bytes),
/// each given with its name (for messages and, when line 8 gives none, the
/// channel number), into one series: the channels of all of them, on one
/// grid (see `to_series`: the lowest rate over the common span), the
/// recorders whose clock is flagged placed by their channels' motion first
/// (see `clock`; said in the series' notes).
pub fn read_v2(files: &[(Vec<u8>, String)]) -> Result<ImportedSeries, ImportError> {
    let mut channels = read_channels(files)?;
    let clocks = align_flagged_recorders(&mut channels);
    let mut series = to_series(channels)?;
    series.notes.splice(0..0, clocks);
    Ok(series)
}

/// Every channel of the files, as `import --list` shows them, by channel.
pub fn list_v2(files: &[(Vec<u8>, String)]) -> Result<Vec<V2Summary>, ImportError> {
    Ok(read_channels(files)?
        .into_iter()
        .map(|c| V2Summary {
            channel: c.number,
            rate_hz: 1.0 / c.time_step,
            points: c.values.len(),
            peak: c.values.iter().fold(0.0, |a: f64, v| a.max(v.abs())),
            direction: c.direction,
            location: c.location,
            unit: c.unit,
            file: c.file,
            station: c.station,
        })
        .collect())
}

/// The channels of all files, by station channel. A channel given twice (a
/// station's zip may hold its combined file and the per-channel files) is
/// taken once when both copies hold the same record, and is an error naming
/// both files when they differ.
fn read_channels(files: &[(Vec<u8>, String)]) -> Result<Vec<V2Channel>, ImportError> {
    let mut channels = Vec::new();
    for (bytes, name) in files {
        channels.extend(read_file(bytes, name)?);
    }
    // Stable: the first file given keeps its place.
    channels.sort_by_key(|c| c.number);
    let mut unique: Vec<V2Channel> = Vec::with_capacity(channels.len());
    for channel in channels {
        match unique.last() {
            Some(kept) if kept.number == channel.number => {
                if let Some(difference) = same_record(kept, &channel) {
                    return Err(error(
                        &channel.file,
                        format!(
                            "channel {} is also in {}, with another record ({difference})",
                            channel.number, kept.file
                        ),
                    ));
                }
            }
            _ => unique.push(channel),
        }
    }
    Ok(unique)
}

/// `None` when two copies of a channel hold the same record (the same
/// rate, start, unit and length, every value equal to within a millionth of
/// the peak: the files print the same processing's numbers), else what
/// differs.
fn same_record(a: &V2Channel, b: &V2Channel) -> Option<String> {
    if a.time_step != b.time_step {
        return Some(format!("time steps {} and {} s", a.time_step, b.time_step));
    }
    if a.start_ns != b.start_ns {
        return Some("different start times".into());
    }
    if a.unit != b.unit {
        return Some(format!("units {} and {}", a.unit, b.unit));
    }
    if a.values.len() != b.values.len() {
        return Some(format!("{} and {} points", a.values.len(), b.values.len()));
    }
    let peak = a.values.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
    let largest = a
        .values
        .iter()
        .zip(&b.values)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    (largest > 1e-6 * peak).then(|| format!("values differ by up to {largest} {}", a.unit))
}

/// The channels of one `.V2` or `.zip` file.
fn read_file(bytes: &[u8], name: &str) -> Result<Vec<V2Channel>, ImportError> {
    let mut channels = Vec::new();
    if bytes.starts_with(b"PK\x03\x04") {
        let mut archive = zip::ZipArchive::new(std::io::Cursor::new(bytes))
            .map_err(|e| error(name, format!("not a zip file: {e}")))?;
        for i in 0..archive.len() {
            let mut file = archive.by_index(i).map_err(|e| error(name, e.to_string()))?;
            let inner = file.name().to_string();
            if !inner.to_ascii_lowercase().ends_with(".v2") {
                continue;
            }
            let mut text = Vec::new();
            file.read_to_end(&mut text)
                .map_err(|e| error(&format!("{name}:{inner}"), e.to_string()))?;
            channels.extend(read_text(&text, &format!("{name}:{inner}"))?);
        }
        if channels.is_empty() {
            return Err(error(name, "the zip file holds no .V2 file"));
        }
    } else {
        channels = read_text(bytes, name)?;
    }
    Ok(channels)
}

/// The channels of one `.V2` file.
fn read_text(bytes: &[u8], name: &str) -> Result<Vec<V2Channel>, ImportError> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(error(name, "the file is empty"));
    }
    let text = String::from_utf8_lossy(bytes);
    let lines: Vec<&str> = text.lines().collect();
    let mut channels = Vec::new();
    let mut from = 0;
    for (i, line) in lines.iter().enumerate() {
        if has(line, END_OF_CHANNEL) {
            channels.push(read_channel(&lines[from..i], name)?);
            from = i + 1;
        }
    }
    if lines[from..].iter().any(|l| has(l, ACCEL_SERIES)) {
        channels.push(read_channel(&lines[from..], name)?);
    }
    if channels.is_empty() {
        return Err(error(name, "no \"points of accel data\" line: not a Volume 2 file"));
    }
    Ok(channels)
}

/// The line that closes a channel's section.
const END_OF_CHANNEL: &str = "end of data for channel";
/// The line that announces the acceleration series.
const ACCEL_SERIES: &str = "points of accel data equally spaced at";

/// Whether `line` holds `marker` (lower case), whatever the line's case
/// (ASCII, without allocating: it runs on every line of a record).
fn has(line: &str, marker: &str) -> bool {
    let (line, marker) = (line.as_bytes(), marker.as_bytes());
    let Some(&first) = marker.first() else {
        return true;
    };
    // Compare a window only where its first byte matches (data lines hold
    // digits and signs: most never get that far).
    line.len() >= marker.len()
        && (0..=line.len() - marker.len()).any(|at| {
            line[at].to_ascii_lowercase() == first && line[at..at + marker.len()].eq_ignore_ascii_case(marker)
        })
}

/// One channel's section of a file.
fn read_channel(lines: &[&str], name: &str) -> Result<V2Channel, ImportError> {
    let at = lines
        .iter()
        .position(|l| has(l, ACCEL_SERIES))
        .ok_or_else(|| error(name, "a channel without a \"points of accel data\" line"))?;
    let header = &lines[..at];
    // The station's own number (`Sta Chn: 15`) when the recorder's differs;
    // several recorders of a station each count their `Chan N:` from 1.
    let number = header
        .iter()
        .find_map(|l| station_channel(l))
        .or_else(|| header.iter().find_map(|l| channel_number(l)))
        .or_else(|| file_channel_number(name))
        .ok_or_else(|| error(name, "no \"Chan N:\" line and no channel number in the file name"))?;
    let (direction, location) = header.iter().find_map(|l| channel_description(l)).unwrap_or_default();
    let what = format!("{name}, channel {number}");
    let descriptor = lines[at];
    let lower = descriptor.to_ascii_lowercase();
    // `  1082 POINTS OF …`, or `     20  3000 POINTS OF …` (a line count first).
    let count: usize = lower[..lower.find("points of").unwrap_or(0)]
        .split_whitespace()
        .last()
        .and_then(|n| n.parse().ok())
        .ok_or_else(|| error(&what, format!("no point count in {descriptor:?}")))?;
    let time_step = number_after(&lower, "spaced at")
        .filter(|dt| dt.is_finite() && *dt > 0.0)
        .ok_or_else(|| error(&what, format!("no positive time step in {descriptor:?}")))?;
    let unit = series_unit(descriptor).ok_or_else(|| error(&what, format!("no unit in {descriptor:?}")))?;
    let width = field_width(descriptor).unwrap_or(10);
    let mut values = Vec::with_capacity(count);
    for (k, line) in lines[at + 1..].iter().enumerate() {
        if values.len() == count || has(line, "points of") || has(line, "end of data") {
            break;
        }
        for field in fields(line, width) {
            let v: f64 = field.trim().parse().map_err(|_| {
                error(
                    &what,
                    format!("line {} after the accel header: {field:?} is not a number", k + 1),
                )
            })?;
            values.push(v);
        }
    }
    if values.len() != count {
        return Err(error(
            &what,
            format!("{} of the {count} accel values announced", values.len()),
        ));
    }
    let start_ns = header
        .iter()
        .find_map(|l| record_start(l))
        .or_else(|| header.iter().find_map(|l| trigger_start(l)));
    let station = header.iter().enumerate().find_map(|(i, l)| {
        let (number, latitude, longitude) = station_line(l)?;
        Some(Station {
            number,
            name: header.get(i + 1).map(|n| station_name(n)).unwrap_or_default(),
            latitude,
            longitude,
        })
    });
    let recorder = header
        .iter()
        .find_map(|l| recorder_clock(l))
        .map(|(id, flagged)| Recorder {
            id,
            clock: if flagged { Clock::Flagged } else { Clock::Trusted },
        });
    Ok(V2Channel {
        number,
        file: name.to_string(),
        direction,
        location,
        time_step,
        unit,
        start_ns,
        recorder,
        station,
        values,
    })
}
