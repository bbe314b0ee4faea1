//! Time series from the files loggers already write, read into columns:
//! CSV/TSV (the `csv` crate; a header row, an optional units row, a time
//! column or a given rate) and universal file format dataset 58/58b time
//! responses (function type 1, ASCII or binary, as pyuff and modal-testing
//! software write them). Mapping the columns to the config's sensors happens above
//! (`studies::import`).

use crate::io::uff::{read_time_responses, UffError};
use crate::io::wire::{parse_timestamp, ChannelQuantity};
use thiserror::Error;

/// One column of samples.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedChannel {
    pub name: String,
    /// The unit the file gives, if any.
    pub unit: Option<String>,
    /// The quantity the file states (a UFF ordinate type), if any.
    pub quantity: Option<ChannelQuantity>,
    pub data: Vec<f64>,
}

/// The columns of a file on one sampling grid.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedSeries {
    pub channels: Vec<ImportedChannel>,
    /// Sampling rate, if the file says (time column, UFF abscissa increment).
    pub fs: Option<f64>,
    /// Absolute time of the first sample, if the file says (RFC 3339 time column).
    pub start_ns: Option<i128>,
    /// Seconds of the first sample after the start (a relative time column).
    pub offset_seconds: f64,
    /// What the reader decided that changes the data as the files hold it
    /// (e.g. channels cut to the span they share), one sentence each, for the
    /// user to read.
    pub notes: Vec<String>,
}

#[derive(Debug, Error, PartialEq)]
pub enum ImportError {
    #[error("the file is empty")]
    Empty,
    #[error("line {line}: {message}")]
    Csv { line: u64, message: String },
    #[error("line {line}, column {column:?}: {value:?} is not a number")]
    NotANumber { line: u64, column: String, value: String },
    #[error("column {column:?} appears twice")]
    DuplicateColumn { column: String },
    #[error("time column {column:?}: {message}")]
    Time { column: String, message: String },
    #[error("UFF dataset at line {line}: {message}")]
    Uff { line: usize, message: String },
    #[error("no dataset 58 time response in the file")]
    NoUffTimeSeries,
    #[error("Volume 2 file {file}: {message}")]
    V2 { file: String, message: String },
}

/// How to read a CSV/TSV file; `None` = detect.
#[derive(Debug, Clone, Default)]
pub struct CsvOptions {
    /// Field delimiter; detected from the header among `,`, `;`, tab.
    pub delimiter: Option<u8>,
    /// Whether numbers use a decimal comma (`0,5`); detected when the
    /// delimiter is not a comma and a field looks like one.
    pub decimal_comma: Option<bool>,
    /// The time column; by default a column named `time`, `t`, `time_s`,
    /// `timestamp` or `seconds` (any case), if there is one.
    pub time_column: Option<String>,
}

const TIME_NAMES: [&str; 5] = ["time", "t", "time_s", "timestamp", "seconds"];

/// Reads a CSV/TSV file: a header row of column names, optionally a units
/// row (a row whose fields are not numbers), then one row per sample.
pub fn read_csv(text: &str, options: &CsvOptions) -> Result<ImportedSeries, ImportError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let first = text.lines().next().ok_or(ImportError::Empty)?;
    let delimiter = options.delimiter.unwrap_or_else(|| detect_delimiter(first));
    let rows = records(text, delimiter)?;
    let (header, rest) = rows.split_first().ok_or(ImportError::Empty)?;
    let names: Vec<String> = header.iter().map(str::to_string).collect();
    if let Some(n) = names
        .iter()
        .enumerate()
        .find_map(|(i, n)| names[..i].iter().any(|m| m.eq_ignore_ascii_case(n)).then_some(n))
    {
        return Err(ImportError::DuplicateColumn { column: n.clone() });
    }
    let decimal_comma = options.decimal_comma.unwrap_or_else(|| {
        delimiter != b','
            && rest
                .iter()
                .take(3)
                .flat_map(|r| r.iter())
                .any(|f| f.contains(',') && parse_number(f, true).is_some())
    });
    let time_index = time_column(&names, options.time_column.as_deref())?;
    // A units row: a row whose non-time fields are not all numbers.
    let is_units = |r: &csv::StringRecord| {
        r.iter()
            .enumerate()
            .any(|(i, f)| Some(i) != time_index && !f.is_empty() && parse_number(f, decimal_comma).is_none())
    };
    let (units, samples) = match rest.split_first() {
        Some((u, s)) if is_units(u) => (Some(u), s),
        _ => (None, rest),
    };
    let mut columns: Vec<Vec<f64>> = vec![Vec::with_capacity(samples.len()); names.len()];
    let mut times: Vec<&str> = Vec::new();
    for row in samples {
        let line = row.position().map_or(0, |p| p.line());
        for (i, field) in row.iter().enumerate() {
            if Some(i) == time_index {
                times.push(field);
            } else {
                let v = parse_number(field, decimal_comma).ok_or_else(|| ImportError::NotANumber {
                    line,
                    column: names[i].clone(),
                    value: field.to_string(),
                })?;
                columns[i].push(v);
            }
        }
    }
    let mut series = ImportedSeries {
        channels: Vec::new(),
        fs: None,
        start_ns: None,
        offset_seconds: 0.0,
        notes: Vec::new(),
    };
    if let Some(t) = time_index {
        time_axis(&names[t], &times, decimal_comma, &mut series)?;
    }
    for (i, (name, data)) in names.into_iter().zip(columns).enumerate() {
        if Some(i) == time_index {
            continue;
        }
        let unit = units
            .and_then(|u| u.get(i))
            .filter(|u| !u.is_empty())
            .map(str::to_string);
        series.channels.push(ImportedChannel {
            name,
            unit,
            quantity: None,
            data,
        });
    }
    Ok(series)
}

/// The header's most frequent of tab, semicolon and comma.
fn detect_delimiter(header: &str) -> u8 {
    [b'\t', b';', b',']
        .into_iter()
        .max_by_key(|d| header.bytes().filter(|b| b == d).count())
        .unwrap_or(b',')
}

/// Every row, fields trimmed, `#` lines skipped.
fn records(text: &str, delimiter: u8) -> Result<Vec<csv::StringRecord>, ImportError> {
    csv::ReaderBuilder::new()
        .delimiter(delimiter)
        .has_headers(false)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(text.as_bytes())
        .records()
        .collect::<Result<_, _>>()
        .map_err(|e| ImportError::Csv {
            line: e.position().map_or(0, |p| p.line()),
            message: e.to_string(),
        })
}

/// The index of the time column: the one named, or one of [`TIME_NAMES`].
fn time_column(names: &[String], named: Option<&str>) -> Result<Option<usize>, ImportError> {
    let Some(t) = named else {
        return Ok(names
            .iter()
            .position(|n| TIME_NAMES.iter().any(|t| n.eq_ignore_ascii_case(t))));
    };
    match names.iter().position(|n| n.eq_ignore_ascii_case(t)) {
        Some(i) => Ok(Some(i)),
        None => Err(ImportError::Time {
            column: t.to_string(),
            message: format!("no such column (columns: {})", names.join(", ")),
        }),
    }
}

fn parse_number(field: &str, decimal_comma: bool) -> Option<f64> {
    let v = if decimal_comma {
        field.replace(',', ".").parse::<f64>().ok()
    } else {
        field.parse::<f64>().ok()
    };
    v.filter(|v| v.is_finite())
}

/// The rate and start of a time column: seconds (relative) or RFC 3339
/// timestamps (absolute), evenly spaced within 1 % of a sample.
fn time_axis(
    column: &str,
    times: &[&str],
    decimal_comma: bool,
    series: &mut ImportedSeries,
) -> Result<(), ImportError> {
    let bad = |message: String| ImportError::Time {
        column: column.to_string(),
        message,
    };
    if times.len() < 2 {
        return Err(bad("fewer than two samples: no sampling rate".into()));
    }
    let seconds: Vec<f64> = match times
        .iter()
        .map(|t| parse_number(t, decimal_comma))
        .collect::<Option<Vec<_>>>()
    {
        Some(s) => s,
        None => {
            let ns: Vec<i128> = times
                .iter()
                .map(|t| {
                    parse_timestamp(t).ok_or_else(|| bad(format!("{t:?} is neither seconds nor an RFC 3339 time")))
                })
                .collect::<Result<_, _>>()?;
            series.start_ns = Some(ns[0]);
            ns.iter().map(|&t| (t - ns[0]) as f64 / 1e9).collect()
        }
    };
    let n = seconds.len() - 1;
    let dt = (seconds[n] - seconds[0]) / n as f64;
    if !(dt.is_finite() && dt > 0.0) {
        return Err(bad("time does not increase".into()));
    }
    if let Some(k) = (1..seconds.len()).find(|&k| ((seconds[k] - seconds[k - 1]) - dt).abs() > 0.01 * dt) {
        return Err(bad(format!(
            "not evenly sampled: step {} s at sample {k}, {dt} s on average (gaps must be split into separate files)",
            seconds[k] - seconds[k - 1]
        )));
    }
    series.fs = Some(1.0 / dt);
    if series.start_ns.is_none() {
        series.offset_seconds = seconds[0];
    }
    Ok(())
}

/// Reads every dataset 58 or 58b time response (function type 1, real,
/// evenly spaced) of a universal file ([`crate::io::uff::read_time_responses`]);
/// other datasets are skipped. The channel name is the first word of the
/// ID 1 line; the quantity follows the ordinate type (12 acceleration, 9 or
/// 13 force); every channel must share the first one's sampling rate.
pub fn read_uff58(bytes: &[u8]) -> Result<ImportedSeries, ImportError> {
    let responses = read_time_responses(bytes).map_err(|e| match e {
        UffError::Dataset { line, message, .. } => ImportError::Uff { line, message },
        UffError::NoFrf => ImportError::NoUffTimeSeries,
    })?;
    let first = responses.first().ok_or(ImportError::NoUffTimeSeries)?;
    let (fs, offset_seconds) = (first.fs, first.start_seconds);
    let mut channels = Vec::with_capacity(responses.len());
    for r in responses {
        if (r.fs - fs).abs() > 1e-9 * fs {
            return Err(ImportError::Uff {
                line: r.line + 7,
                message: format!(
                    "sampling rate {} Hz differs from the file's first dataset ({fs} Hz)",
                    r.fs
                ),
            });
        }
        channels.push(ImportedChannel {
            name: r.name,
            unit: r.unit,
            quantity: match r.ordinate_type {
                12 => Some(ChannelQuantity::Acceleration),
                9 | 13 => Some(ChannelQuantity::Force),
                _ => None,
            },
            data: r.data,
        });
    }
    Ok(ImportedSeries {
        channels,
        fs: Some(fs),
        start_ns: None,
        offset_seconds,
        notes: Vec::new(),
    })
}
