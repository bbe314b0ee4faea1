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

use crate::io::import::{ImportError, ImportedChannel, ImportedSeries};
use crate::io::wire::ChannelQuantity;
use std::io::Read;

/// One channel's acceleration as the file gives it.
#[derive(Debug, Clone, PartialEq)]
struct V2Channel {
    number: u32,
    /// The file (and, in a zip, the member) it came from, for messages.
    file: String,
    /// What the `Chan N:` line says after the number: `Tran`, `Up`, `360 Deg`.
    direction: String,
    /// The line's `Location:` text, e.g. `Deck: Near West Abutment`.
    location: String,
    time_step: f64,
    unit: String,
    start_ns: Option<i128>,
    values: Vec<f64>,
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
}

fn error(what: &str, message: impl Into<String>) -> ImportError {
    ImportError::V2 {
        file: what.to_string(),
        message: message.into(),
    }
}

/// Reads `.V2` files or `.zip` files of them (told by their first bytes),
/// each given with its name (for messages and, when line 8 gives none, the
/// channel number), into one series: the channels of all of them, on one
/// grid (see `to_series`: the lowest rate over the common span).
pub fn read_v2(files: &[(Vec<u8>, String)]) -> Result<ImportedSeries, ImportError> {
    to_series(read_channels(files)?)
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
        })
        .collect())
}

/// The channels of all files, by station channel; a channel given twice is
/// an error naming both files.
fn read_channels(files: &[(Vec<u8>, String)]) -> Result<Vec<V2Channel>, ImportError> {
    let mut channels = Vec::new();
    for (bytes, name) in files {
        channels.extend(read_file(bytes, name)?);
    }
    channels.sort_by_key(|c| c.number);
    if let Some(pair) = channels.windows(2).find(|w| w[0].number == w[1].number) {
        return Err(error(
            &pair[1].file,
            format!("channel {} is also in {}", pair[0].number, pair[0].file),
        ));
    }
    Ok(channels)
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
    let text = String::from_utf8_lossy(bytes);
    let lines: Vec<&str> = text.lines().collect();
    let mut channels = Vec::new();
    let mut from = 0;
    for (i, line) in lines.iter().enumerate() {
        if line.contains("End of data for channel") {
            channels.push(read_channel(&lines[from..i], name)?);
            from = i + 1;
        }
    }
    if lines[from..].iter().any(|l| l.contains("points of accel data")) {
        channels.push(read_channel(&lines[from..], name)?);
    }
    if channels.is_empty() {
        return Err(error(name, "no \"points of accel data\" line: not a Volume 2 file"));
    }
    Ok(channels)
}

/// One channel's section of a file.
fn read_channel(lines: &[&str], name: &str) -> Result<V2Channel, ImportError> {
    let at = lines
        .iter()
        .position(|l| l.contains("points of accel data equally spaced at"))
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
    let count: usize = descriptor
        .split_whitespace()
        .next()
        .and_then(|n| n.parse().ok())
        .ok_or_else(|| error(&what, format!("no point count in {descriptor:?}")))?;
    let time_step = number_after(descriptor, "spaced at")
        .filter(|dt| dt.is_finite() && *dt > 0.0)
        .ok_or_else(|| error(&what, format!("no positive time step in {descriptor:?}")))?;
    let unit = descriptor
        .split_once(" in ")
        .map(|(_, rest)| rest.split(['.', ' ']).find(|w| !w.is_empty()).unwrap_or_default())
        .map(si_spelling)
        .ok_or_else(|| error(&what, format!("no unit in {descriptor:?}")))?;
    let width = field_width(descriptor).unwrap_or(10);
    let mut values = Vec::with_capacity(count);
    for (k, line) in lines[at + 1..].iter().enumerate() {
        if values.len() == count || line.contains("points of") || line.contains("End of data") {
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
    let start_ns = lines.iter().take(at).find_map(|l| record_start(l));
    Ok(V2Channel {
        number,
        file: name.to_string(),
        direction,
        location,
        time_step,
        unit,
        start_ns,
        values,
    })
}

/// `Chan  5: 90 Deg …` → 5 (the first `chan` followed by a number and a colon).
fn channel_number(line: &str) -> Option<u32> {
    let lower = line.to_ascii_lowercase();
    lower.match_indices("chan").find_map(|(i, _)| {
        let rest = lower[i + 4..].trim_start();
        let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
        let after = rest[digits.len()..].trim_start();
        (!digits.is_empty() && after.starts_with(':'))
            .then(|| digits.parse().ok())
            .flatten()
    })
}

/// `Chan 12:  Long    (Sta Chn: 15)  Location: …` → 15.
fn station_channel(line: &str) -> Option<u32> {
    let lower = line.to_ascii_lowercase();
    let rest = lower[lower.find("sta chn:")? + 8..].trim_start();
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    digits.parse().ok()
}

/// `Chan  4:  Tran   Location: Deck: Near West Abutment` → (`Tran`,
/// `Deck: Near West Abutment`): the words after the number (without a
/// `(Sta Chn: N)`) and the location text, from the line that has both.
fn channel_description(line: &str) -> Option<(String, String)> {
    channel_number(line)?;
    let lower = line.to_ascii_lowercase();
    let location_at = lower.find("location:")?;
    let after_number = lower[..location_at].find(':')? + 1;
    let mut direction = line[after_number..location_at].to_string();
    if let Some(at) = direction.to_ascii_lowercase().find("sta chn") {
        direction.truncate(at);
    }
    let direction = direction
        .trim_end()
        .trim_end_matches('(')
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    let location = line[location_at + 9..].split_whitespace().collect::<Vec<_>>().join(" ");
    Some((direction, location))
}

/// `CHAN005.V2`, `26327_ch5.v2` → 5: the last number in the file's stem.
fn file_channel_number(name: &str) -> Option<u32> {
    let file = name.rsplit(['/', ':']).next()?;
    let stem = file.rsplit_once('.').map_or(file, |(s, _)| s);
    stem.split(|c: char| !c.is_ascii_digit())
        .rfind(|d| !d.is_empty())
        .and_then(|d| d.parse().ok())
}

/// The number after `marker` in `line`.
fn number_after(line: &str, marker: &str) -> Option<f64> {
    let rest = &line[line.find(marker)? + marker.len()..];
    let token: String = rest
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.' || *c == '-' || *c == 'e' || *c == 'E')
        .collect();
    token.parse().ok()
}

/// `(8f10.5)` / `(8F10.3)` → 10.
fn field_width(line: &str) -> Option<usize> {
    let lower = line.to_ascii_lowercase();
    let start = lower.find("(8f")? + 3;
    let digits: String = lower[start..].chars().take_while(char::is_ascii_digit).collect();
    digits.parse().ok().filter(|&w| w > 0)
}

/// The fixed-width fields of a data line (values may touch: `-1234.567-1234.567`).
fn fields(line: &str, width: usize) -> Vec<&str> {
    let line = line.trim_end();
    (0..line.len().div_ceil(width))
        .filter_map(|k| line.get(k * width..((k + 1) * width).min(line.len())))
        .filter(|f| !f.trim().is_empty())
        .collect()
}

/// The file's spelling of a unit in the importer's (`cm/sec2` → `cm/s^2`).
fn si_spelling(unit: &str) -> String {
    match unit.to_ascii_lowercase().as_str() {
        "cm/sec2" | "cm/sec/sec" | "cm/s/s" | "cm/sec**2" => "cm/s^2".into(),
        "m/sec2" | "m/sec/sec" => "m/s^2".into(),
        "g" => "g".into(),
        _ => unit.to_string(),
    }
}

/// `Rcrd of Mon Nov 23, 2026 10:00:00.0 UTC` (or `Record of …`, as some
/// processing versions spell it) → its instant, when the zone is
/// UTC/GMT or a US Pacific one (CGS records are stamped in PST/PDT);
/// another zone gives `None` (`--start` then says when).
fn record_start(line: &str) -> Option<i128> {
    let line = line.trim_start();
    let rest = line
        .strip_prefix("Rcrd of ")
        .or_else(|| line.strip_prefix("Record of "))?;
    let words: Vec<&str> = rest.split_whitespace().collect();
    let [_, month, day, year, clock, zone, ..] = words.as_slice() else {
        return None;
    };
    const MONTHS: [&str; 12] = [
        "jan", "feb", "mar", "apr", "may", "jun", "jul", "aug", "sep", "oct", "nov", "dec",
    ];
    let month = MONTHS.iter().position(|m| month.to_ascii_lowercase().starts_with(m))? + 1;
    let day: u32 = day.trim_end_matches(',').parse().ok()?;
    let year: i32 = year.parse().ok()?;
    let offset_hours: i64 = match zone.to_ascii_uppercase().as_str() {
        "UTC" | "GMT" | "UT" | "Z" => 0,
        "PST" => -8,
        "PDT" => -7,
        _ => return None,
    };
    let mut parts = clock.split(':');
    let (h, m, s) = (parts.next()?, parts.next()?, parts.next()?);
    let seconds: f64 = s.parse().ok()?;
    let text = format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:00Z",
        h.parse::<u32>().ok()?,
        m.parse::<u32>().ok()?
    );
    let midnight = crate::io::wire::parse_timestamp(&text)?;
    Some(midnight + (seconds * 1e9).round() as i128 - i128::from(offset_hours) * 3_600_000_000_000)
}

/// The channels on one grid. Channels of several recorders may differ in
/// rate, start and length: the grid is the lowest rate over the span all
/// channels cover (from the latest start to the earliest end; channels
/// without a start time must all lack one and then start together). Each
/// channel is cut to that span at its own nearest sample (an offset below
/// half a sample of its own rate stays) and, when its rate differs,
/// resampled to the grid by Fourier interpolation over the span (the
/// spectrum truncated at the new Nyquist frequency or padded with zeros, as
/// `scipy.signal.resample`), which is exact for a band-limited periodic
/// signal and low-pass filters a channel brought down.
fn to_series(channels: Vec<V2Channel>) -> Result<ImportedSeries, ImportError> {
    let first = &channels[0];
    if let Some(c) = channels
        .iter()
        .find(|c| c.start_ns.is_some() != first.start_ns.is_some())
    {
        let (with, without) = if c.start_ns.is_some() { (c, first) } else { (first, c) };
        return Err(error(
            &without.file,
            format!(
                "channel {} has no record start time (\"Rcrd of …\" in UTC or PST/PDT) but channel {} of {} has one: the channels cannot be put on one time line",
                without.number, with.number, with.file
            ),
        ));
    }
    let dt = channels.iter().map(|c| c.time_step).fold(0.0, f64::max);
    let span_start = channels.iter().filter_map(|c| c.start_ns).max();
    let end = |c: &V2Channel| c.start_ns.unwrap_or(0) as f64 * 1e-9 + c.values.len() as f64 * c.time_step;
    let span_end = channels.iter().map(end).fold(f64::INFINITY, f64::min);
    let t0 = span_start.unwrap_or(0) as f64 * 1e-9;
    let points = ((span_end - t0) / dt + 1e-6).floor();
    if points.is_nan() || points < 2.0 {
        let (a, b) = (
            channels.iter().max_by_key(|c| c.start_ns).unwrap_or(first),
            channels
                .iter()
                .min_by(|a, b| end(a).total_cmp(&end(b)))
                .unwrap_or(first),
        );
        return Err(error(
            &a.file,
            format!(
                "channel {} starts after channel {} of {} ends: the channels share no time span",
                a.number, b.number, b.file
            ),
        ));
    }
    let points = points as usize;
    let columns = channels
        .into_iter()
        .map(|c| {
            let skip = ((t0 - c.start_ns.unwrap_or(0) as f64 * 1e-9) / c.time_step)
                .round()
                .max(0.0) as usize;
            let own = ((points as f64 * dt / c.time_step).round() as usize).min(c.values.len() - skip);
            let cut = &c.values[skip..skip + own];
            let data = if (c.time_step - dt).abs() <= 1e-9 * dt {
                cut[..points.min(cut.len())].to_vec()
            } else {
                fourier_resample(cut, points)
            };
            ImportedChannel {
                name: format!("ch{}", c.number),
                unit: Some(c.unit),
                quantity: Some(ChannelQuantity::Acceleration),
                data,
            }
        })
        .collect();
    Ok(ImportedSeries {
        fs: Some(1.0 / dt),
        start_ns: span_start,
        offset_seconds: 0.0,
        channels: columns,
    })
}

/// `x` (one span) resampled to `n` points over the same span: the discrete
/// Fourier series truncated or zero-padded (the Nyquist line of an even
/// length halved), as `scipy.signal.resample`.
fn fourier_resample(x: &[f64], n: usize) -> Vec<f64> {
    let m = x.len();
    let mut planner = realfft::RealFftPlanner::<f64>::new();
    let forward = planner.plan_fft_forward(m);
    let mut input = x.to_vec();
    let mut spectrum = forward.make_output_vec();
    forward
        .process(&mut input, &mut spectrum)
        .expect("lengths from the plan");
    let inverse = planner.plan_fft_inverse(n);
    let mut target = inverse.make_input_vec();
    let keep = target.len().min(spectrum.len());
    target[..keep].copy_from_slice(&spectrum[..keep]);
    // A Nyquist line present in only one of the two lengths is split or summed
    // so that the real signal stays real (its imaginary part is dropped).
    if m % 2 == 0 && keep == spectrum.len() && n > m {
        target[m / 2] *= 0.5;
    }
    if n % 2 == 0 && keep == target.len() {
        let nyquist = target.len() - 1;
        target[nyquist].im = 0.0;
        if n < m {
            target[nyquist] *= 2.0;
        }
    }
    target[0].im = 0.0;
    let mut out = inverse.make_output_vec();
    inverse.process(&mut target, &mut out).expect("lengths from the plan");
    let scale = 1.0 / m as f64;
    out.iter().map(|v| v * scale).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_lines_are_read_whatever_their_spacing() {
        assert_eq!(channel_number("Chan  5: 90 Deg   Location: deck"), Some(5));
        assert_eq!(channel_number("CHAN 12:  Up"), Some(12));
        assert_eq!(channel_number("Station channel list"), None);
        assert_eq!(file_channel_number("station.zip:CHAN005.V2"), Some(5));
        assert_eq!(file_channel_number("dir/26327_ch3.v2"), Some(3));
        let d = "  8000 points of accel data equally spaced at   .005 sec, in cm/sec2.  (8F10.3)";
        assert_eq!(number_after(d, "spaced at"), Some(0.005));
        assert_eq!(field_width(d), Some(10));
        assert_eq!(
            fields("-1234.567-1234.567    1.000   ", 9),
            ["-1234.567", "-1234.567", "    1.000"]
        );
        assert_eq!(
            record_start("Rcrd of Mon Nov 23, 2026 02:00:00.5 PST"),
            crate::io::wire::parse_timestamp("2026-11-23T10:00:00.5Z")
        );
        assert_eq!(record_start("Rcrd of Mon Nov 23, 2026 02:00:00.0 CET"), None);
    }

    #[test]
    fn a_short_or_garbled_channel_is_an_error_naming_it() {
        let good = "Chan  2: 90 Deg\n     3 points of accel data equally spaced at  0.010 sec, in cm/sec2. (8f10.5)\n   1.00000   2.00000   3.00000\n";
        let read = |text: &str, name: &str| read_v2(&[(text.as_bytes().to_vec(), name.to_string())]);
        let s = read(good, "a.V2").unwrap();
        assert_eq!(s.channels[0].name, "ch2");
        assert_eq!(s.channels[0].data, [1.0, 2.0, 3.0]);
        assert_eq!(s.channels[0].unit.as_deref(), Some("cm/s^2"));
        assert_eq!(s.fs, Some(100.0));
        let short = good.replace("   3.00000", "");
        let e = read(&short, "a.V2").unwrap_err().to_string();
        assert!(e.contains("a.V2, channel 2") && e.contains("2 of the 3"), "{e}");
        let garbled = good.replace("2.00000", "2.0x000");
        let e = read(&garbled, "a.V2").unwrap_err().to_string();
        assert!(e.contains("is not a number"), "{e}");
        let e = read("just text\n", "b.V2").unwrap_err().to_string();
        assert!(e.contains("not a Volume 2 file"), "{e}");
    }

    /// Two channels of two recorders (station channels 7 and 15, 100 and
    /// 200 Hz, started a sample apart), for the damaged-input properties.
    fn two_recorders() -> String {
        let channel = |k: u32, station: u32, dt: f64, start: &str, n: usize| {
            let values: String = (0..n)
                .map(|i| format!("{:10.5}", (i as f64 * 0.7).sin()))
                .collect::<Vec<_>>()
                .chunks(8)
                .map(|c| c.concat() + "\n")
                .collect();
            format!(
                "Chan  {k}:  Tran    (Sta Chn: {station})     Location: Deck\nRcrd of Mon Nov 23, 2026 {start} UTC\n  {n} points of accel data equally spaced at   {dt} sec, in cm/sec2. (8f10.5)\n{values}/&  ---------- End of data for channel  {k} ----------\n"
            )
        };
        channel(1, 7, 0.01, "10:00:00.0", 40) + &channel(1, 15, 0.005, "10:00:00.01", 80)
    }

    #[test]
    fn two_recorders_come_on_one_grid_by_station_channel() {
        let s = read_v2(&[(two_recorders().into_bytes(), "station.V2".into())]).unwrap();
        let names: Vec<&str> = s.channels.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["ch7", "ch15"]);
        assert_eq!(s.fs, Some(100.0));
        // 0.39 s in common at 100 Hz, from the later start.
        assert!(s.channels.iter().all(|c| c.data.len() == 39));
        assert_eq!(s.start_ns, crate::io::wire::parse_timestamp("2026-11-23T10:00:00.01Z"));
        // ch7 cut at its second sample (the file's five decimals of sin 0.7).
        assert_eq!(s.channels[0].data[0], 0.64422);
    }

    #[test]
    fn fourier_resampling_keeps_a_band_limited_periodic_signal() {
        // A sum of harmonics below both Nyquist lines of a periodic span.
        let signal = |n: usize| -> Vec<f64> {
            (0..n)
                .map(|i| {
                    let t = i as f64 / n as f64;
                    (2.0 * std::f64::consts::PI * 3.0 * t).sin() + 0.5 * (2.0 * std::f64::consts::PI * 7.0 * t).cos()
                })
                .collect()
        };
        for (from, to) in [(64, 40), (40, 64), (63, 41), (41, 63), (50, 50)] {
            let got = fourier_resample(&signal(from), to);
            let want = signal(to);
            let err = got.iter().zip(&want).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(err < 1e-12, "{from} -> {to}: {err:.2e}");
        }
    }

    proptest::proptest! {
        #[test]
        fn damaged_stations_are_errors_never_panics(
            flips in proptest::collection::vec((proptest::prelude::any::<proptest::sample::Index>(), proptest::prelude::any::<u8>()), 0..8),
            cut in proptest::prelude::any::<proptest::sample::Index>(),
        ) {
            let mut bytes = two_recorders().into_bytes();
            for (i, b) in &flips {
                let k = i.index(bytes.len());
                bytes[k] = *b;
            }
            bytes.truncate(cut.index(bytes.len() + 1));
            let files = [(bytes, "station.V2".to_string())];
            if let Ok(s) = read_v2(&files) {
                proptest::prop_assert!(s.channels.iter().all(|c| c.data.len() >= 2));
            }
            let _ = list_v2(&files);
        }
    }
}
