//! The header lines of a Volume 2 channel: its number, orientation and
//! location, the series' descriptor (count, time step, unit, field width)
//! and the record's start, in either layout (see the module above).

/// `Chan  5: 90 Deg …` → 5 (the first `chan` followed by a number and a colon).
pub(super) fn channel_number(line: &str) -> Option<u32> {
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
pub(super) fn station_channel(line: &str) -> Option<u32> {
    let lower = line.to_ascii_lowercase();
    let rest = lower[lower.find("sta chn:")? + 8..].trim_start();
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    digits.parse().ok()
}

/// `Chan  4:  Tran   Location: Deck: Near West Abutment` → (`Tran`,
/// `Deck: Near West Abutment`): the words after the number (without a
/// `(Sta Chn: N)`) and the location text, from the line that has both.
pub(super) fn channel_description(line: &str) -> Option<(String, String)> {
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
pub(super) fn file_channel_number(name: &str) -> Option<u32> {
    let file = name.rsplit(['/', ':']).next()?;
    let stem = file.rsplit_once('.').map_or(file, |(s, _)| s);
    stem.split(|c: char| !c.is_ascii_digit())
        .rfind(|d| !d.is_empty())
        .and_then(|d| d.parse().ok())
}

/// The number after `marker` in `line`.
pub(super) fn number_after(line: &str, marker: &str) -> Option<f64> {
    let rest = &line[line.find(marker)? + marker.len()..];
    let token: String = rest
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.' || *c == '-' || *c == 'e' || *c == 'E')
        .collect();
    token.parse().ok()
}

/// `(8f10.5)` / `(8F10.3)` → 10.
pub(super) fn field_width(line: &str) -> Option<usize> {
    let lower = line.to_ascii_lowercase();
    let start = lower.find("(8f")? + 3;
    let digits: String = lower[start..].chars().take_while(char::is_ascii_digit).collect();
    digits.parse().ok().filter(|&w| w > 0)
}

/// The fixed-width fields of a data line (values may touch: `-1234.567-1234.567`).
pub(super) fn fields(line: &str, width: usize) -> Vec<&str> {
    let line = line.trim_end();
    (0..line.len().div_ceil(width))
        .filter_map(|k| line.get(k * width..((k + 1) * width).min(line.len())))
        .filter(|f| !f.trim().is_empty())
        .collect()
}

/// The series' unit: `…, in cm/sec2. (8f10.5)` or `…  (UNITS: CM/SEC/SEC)`.
pub(super) fn series_unit(descriptor: &str) -> Option<String> {
    let lower = descriptor.to_ascii_lowercase();
    let word = |rest: &str| rest.split([' ', ')']).find(|w| !w.is_empty()).map(str::to_string);
    let unit = if let Some(at) = lower.find("(units:") {
        word(&descriptor[at + 7..])?
    } else {
        let at = lower.find(" in ")?;
        word(&descriptor[at + 4..])?.trim_end_matches([',', '.']).to_string()
    };
    (!unit.is_empty()).then(|| si_spelling(&unit))
}

/// The file's spelling of a unit in the importer's (`cm/sec2` → `cm/s^2`).
pub(super) fn si_spelling(unit: &str) -> String {
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
pub(super) fn record_start(line: &str) -> Option<i128> {
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
    instant(year, month as u32, day, clock, zone)
}

/// `TRIGGER TIME: 11/21/86, 23:33:12.6 GMT` (the older layout's start) → its
/// instant; `06:53:XX.X` (seconds not read off the film) gives `None`.
pub(super) fn trigger_start(line: &str) -> Option<i128> {
    let lower = line.to_ascii_lowercase();
    let rest = &line[lower.find("trigger time:")? + 13..];
    let words: Vec<&str> = rest.split_whitespace().collect();
    let [date, clock, zone, ..] = words.as_slice() else {
        return None;
    };
    let mut parts = date.trim_end_matches(',').split('/');
    let (month, day, year) = (parts.next()?, parts.next()?, parts.next()?);
    let year: i32 = match (year.len(), year.parse::<i32>().ok()?) {
        // Two-digit years: these files were processed from 1972 on.
        (2, y) if y >= 70 => 1900 + y,
        (2, y) => 2000 + y,
        (_, y) => y,
    };
    instant(year, month.parse().ok()?, day.parse().ok()?, clock, zone)
}

/// The instant of a date, an `hh:mm:ss.s` clock and a zone: UTC/GMT or a US
/// Pacific one (CGS stamps records in PST/PDT); a trailing `*` (a flag some
/// processing versions add) is not part of the zone; another zone is `None`.
pub(super) fn instant(year: i32, month: u32, day: u32, clock: &str, zone: &str) -> Option<i128> {
    let offset_hours: i64 = match zone.trim_end_matches('*').to_ascii_uppercase().as_str() {
        "UTC" | "GMT" | "UT" | "Z" => 0,
        "PST" => -8,
        "PDT" => -7,
        _ => return None,
    };
    let mut parts = clock.split(':');
    let (h, m, s) = (parts.next()?, parts.next()?, parts.next()?);
    let seconds: f64 = s
        .parse()
        .ok()
        .filter(|s: &f64| s.is_finite() && *s >= 0.0 && *s < 61.0)?;
    let text = format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:00Z",
        h.parse::<u32>().ok()?,
        m.parse::<u32>().ok()?
    );
    let midnight = crate::io::wire::parse_timestamp(&text)?;
    Some(midnight + (seconds * 1e9).round() as i128 - i128::from(offset_hours) * 3_600_000_000_000)
}

/// `01336-E0784-10190.09   Start time:  7/07/10, 23:54 GMT (*LoQ*)` →
/// (`E0784`, whether the start is flagged): the recorder of the channel
/// (the second part of the record's id) and the CGS's flag on its clock,
/// `*LoQ*` (low quality: no time signal, the clock drifted). Only the
/// current layout has this line.
pub(super) fn recorder_clock(line: &str) -> Option<(String, bool)> {
    let lower = line.to_ascii_lowercase();
    let at = lower.find("start time:")?;
    let id = line[..at].split_whitespace().next()?;
    let recorder = id.split('-').nth(1).filter(|r| !r.is_empty())?;
    Some((recorder.to_string(), lower[at..].contains("loq")))
}

/// `Station No. 89324   40.503N, 124.101W    130-MC …` (or in capitals) →
/// the station's number and its latitude and longitude in degrees (north
/// and east positive).
pub(super) fn station_line(line: &str) -> Option<(String, f64, f64)> {
    let lower = line.to_ascii_lowercase();
    let rest = &line[lower.find("station no.")? + 11..];
    let mut words = rest.split_whitespace();
    let number = words.next()?.trim_end_matches(',').to_string();
    let degrees = |word: &str, positive: char, negative: char| -> Option<f64> {
        let word = word.trim_end_matches(',');
        let hemisphere = word.chars().last()?.to_ascii_uppercase();
        let value: f64 = word[..word.len() - 1].parse().ok()?;
        match hemisphere {
            h if h == positive => Some(value),
            h if h == negative => Some(-value),
            _ => None,
        }
    };
    let latitude = degrees(words.next()?, 'N', 'S')?;
    let longitude = degrees(words.next()?, 'E', 'W')?;
    Some((number, latitude, longitude))
}

/// The station's name on the line after its number: the text before a run
/// of spaces (`Rio Dell - Hwy 101/Painter St. Overpass   CGS   Data: …`).
pub(super) fn station_name(line: &str) -> String {
    line.trim().split("  ").next().unwrap_or_default().trim().to_string()
}
