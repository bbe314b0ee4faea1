//! Reading FRFs from universal files (see the parent module).

use super::{field, fortran_real, record_values, UffPoint};
use crate::io::frf_json::{FrfEntry, FrfFile};
use splinewatch_core::response::frf::Quantity;
use thiserror::Error;

#[derive(Debug, Clone, Error, PartialEq)]
pub enum UffError {
    #[error("UFF dataset {dataset} at line {line}: {message}")]
    Dataset {
        dataset: String,
        line: usize,
        message: String,
    },
    #[error("no dataset 58 frequency response function (function type 4) in the file")]
    NoFrf,
}

/// One dataset: its type record, the ASCII records after it and, for a
/// binary dataset, its data bytes.
struct Dataset<'a> {
    kind: String,
    /// 1-based line of the type record.
    line: usize,
    type_record: &'a str,
    records: Vec<&'a str>,
    binary: Option<&'a [u8]>,
}

impl Dataset<'_> {
    fn err(&self, offset: usize, message: impl Into<String>) -> UffError {
        UffError::Dataset {
            dataset: self.kind.clone(),
            line: self.line + offset,
            message: message.into(),
        }
    }
}

/// Lines of `bytes` as `(start, end without the line break)`.
fn next_line(bytes: &[u8], start: usize) -> Option<(usize, usize, usize)> {
    if start >= bytes.len() {
        return None;
    }
    let end = bytes[start..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(bytes.len(), |k| start + k);
    let text_end = if end > start && bytes[end - 1] == b'\r' {
        end - 1
    } else {
        end
    };
    Some((start, text_end, (end + 1).min(bytes.len())))
}

fn text(bytes: &[u8], from: usize, to: usize) -> &str {
    std::str::from_utf8(&bytes[from..to]).unwrap_or("")
}

/// Splits a universal file into datasets (a 58b type record is
/// `(I6,1A1,I6,I6,I12,I12,…)`: byte ordering, floating-point format, ASCII
/// lines, data bytes) (each between `-1` lines; a 58b
/// dataset's binary block by its size, so bytes inside it are not mistaken
/// for delimiters).
fn datasets(bytes: &[u8]) -> Result<Vec<Dataset<'_>>, UffError> {
    let mut out = Vec::new();
    let (mut pos, mut line) = (0usize, 1usize);
    while let Some((s, e, next)) = next_line(bytes, pos) {
        pos = next;
        line += 1;
        if text(bytes, s, e).trim() != "-1" {
            continue;
        }
        let Some((ts, te, after_type)) = next_line(bytes, pos) else {
            break;
        };
        let type_record = text(bytes, ts, te);
        let kind = type_record.split_whitespace().next().unwrap_or("").to_string();
        let mut d = Dataset {
            kind,
            line,
            type_record,
            records: Vec::new(),
            binary: None,
        };
        pos = after_type;
        line += 1;
        if d.kind.ends_with('b') {
            let ascii_lines: usize = field(type_record, 19, 31)
                .parse()
                .map_err(|_| d.err(0, "columns 20-31: not the number of ASCII lines"))?;
            for _ in 0..ascii_lines {
                let (s, e, next) = next_line(bytes, pos).ok_or_else(|| d.err(0, "the file ends inside the header"))?;
                d.records.push(text(bytes, s, e));
                pos = next;
                line += 1;
            }
            let (data, end) = binary_block(bytes, pos, &d)?;
            line += bytes[pos..end].iter().filter(|&&b| b == b'\n').count();
            d.binary = Some(data);
            pos = end;
        } else {
            while let Some((s, e, next)) = next_line(bytes, pos) {
                if text(bytes, s, e).trim() == "-1" {
                    break;
                }
                d.records.push(text(bytes, s, e));
                pos = next;
                line += 1;
            }
        }
        out.push(d);
        // The closing "-1".
        if let Some((_, _, next)) = next_line(bytes, pos) {
            pos = next;
            line += 1;
        }
    }
    Ok(out)
}

/// The binary data of a 58b dataset starting at `pos`, and where its closing
/// `-1` line starts. The size is the header's byte count, or the size its
/// records 7 announce (pyuff writes half the byte count for complex data):
/// whichever is followed by the `-1` delimiter.
fn binary_block<'a>(bytes: &'a [u8], pos: usize, d: &Dataset<'_>) -> Result<(&'a [u8], usize), UffError> {
    let announced: Option<usize> = field(d.type_record, 31, 43).parse().ok();
    let from_records = d.records.get(6).and_then(|r7| {
        let kind: usize = field(r7, 0, 10).parse().ok()?;
        let points: usize = field(r7, 10, 20).parse().ok()?;
        let even = field(r7, 20, 30) == "1";
        let (width, per_point) = match kind {
            2 => (4, 1),
            4 => (8, 1),
            5 => (4, 2),
            6 => (8, 2),
            _ => return None,
        };
        points.checked_mul(width * (per_point + usize::from(!even)))
    });
    for size in [announced, from_records].into_iter().flatten() {
        let end = pos.checked_add(size).filter(|&e| e <= bytes.len());
        let Some(end) = end else { continue };
        let rest = &bytes[end..];
        let skip = rest.iter().take_while(|b| b.is_ascii_whitespace()).count();
        let after = &rest[skip..];
        if after.starts_with(b"-1") && after[2..].first().is_none_or(|b| b.is_ascii_whitespace()) {
            // Back up to the start of the delimiter's line.
            let line_start = end + rest[..skip].iter().rposition(|&b| b == b'\n').map_or(0, |k| k + 1);
            return Ok((&bytes[pos..end], line_start.max(end)));
        }
    }
    Err(d.err(
        d.records.len() + 1,
        format!(
            "the binary data ({} bytes announced) is not followed by the -1 delimiter",
            announced.map_or("no".into(), |n| n.to_string())
        ),
    ))
}

/// Records 6–11 of a dataset 58 (offsets 5–10 after the type record).
struct Header58 {
    function: i64,
    /// Response and reference node and direction (record 6): checked only
    /// where they are used (FRFs), since writers overflow the entity name
    /// before them (pyuff's `%-10s`) and time series do not need them.
    response: Result<(i64, i64), UffError>,
    reference: Result<(i64, i64), UffError>,
    ordinate_type: i64,
    points: usize,
    even: bool,
    minimum: f64,
    increment: f64,
    numerator: (i64, i32, i32),
    denominator: (i64, i32, i32),
}

fn header58(d: &Dataset<'_>) -> Result<Header58, UffError> {
    if d.records.len() < 11 {
        return Err(d.err(0, "a dataset 58 needs 11 header records"));
    }
    let r = |k: usize| d.records[k - 1];
    let int = |k: usize, from: usize, to: usize| -> Result<i64, UffError> {
        let f = field(r(k), from, to);
        if f.is_empty() {
            return Ok(0);
        }
        f.parse().map_err(|_| {
            d.err(
                k,
                format!("record {k}, columns {}-{to}: {f:?} is not an integer", from + 1),
            )
        })
    };
    let real = |k: usize, from: usize, to: usize| -> Result<f64, UffError> {
        let f = field(r(k), from, to);
        fortran_real(f).ok_or_else(|| {
            d.err(
                k,
                format!("record {k}, columns {}-{to}: {f:?} is not a number", from + 1),
            )
        })
    };
    let exponent = |k: usize, from: usize| -> Result<i32, UffError> {
        i32::try_from(int(k, from, from + 5)?).map_err(|_| d.err(k, "unit exponent out of range"))
    };
    let points = usize::try_from(int(7, 10, 20)?).map_err(|_| d.err(7, "negative number of points"))?;
    Ok(Header58 {
        function: int(6, 0, 5)?,
        response: int(6, 41, 51).and_then(|node| Ok((node, int(6, 51, 55)?))),
        reference: int(6, 66, 76).and_then(|node| Ok((node, int(6, 76, 80)?))),
        ordinate_type: int(7, 0, 10)?,
        points,
        even: int(7, 20, 30)? == 1,
        minimum: real(7, 30, 43)?,
        increment: real(7, 43, 56)?,
        numerator: (int(9, 0, 10)?, exponent(9, 10)?, exponent(9, 15)?),
        denominator: (int(10, 0, 10)?, exponent(10, 10)?, exponent(10, 15)?),
    })
}

/// The data of a dataset 58: abscissa and complex (or real) ordinate.
/// A dataset's ordinate values as (real, imaginary) pairs.
type Ordinates = Vec<(f64, f64)>;

fn data58(d: &Dataset<'_>, h: &Header58) -> Result<(Vec<f64>, Ordinates), UffError> {
    let complex = matches!(h.ordinate_type, 5 | 6);
    if !matches!(h.ordinate_type, 2 | 4 | 5 | 6) {
        return Err(d.err(
            7,
            format!(
                "ordinate data type {}: not real (2, 4) or complex (5, 6)",
                h.ordinate_type
            ),
        ));
    }
    let values: Vec<f64> = match d.binary {
        Some(bytes) => binary_values(d, bytes, matches!(h.ordinate_type, 2 | 5))?,
        None => {
            record_values(&d.records[11..]).map_err(|(k, token)| d.err(12 + k, format!("{token:?} is not a number")))?
        }
    };
    let per_point = 1 + usize::from(complex) + usize::from(!h.even);
    if h.points.checked_mul(per_point) != Some(values.len()) {
        return Err(d.err(
            7,
            format!(
                "{} points announced, {} values found ({per_point} per point)",
                h.points,
                values.len()
            ),
        ));
    }
    let mut x = Vec::with_capacity(h.points);
    let mut y = Vec::with_capacity(h.points);
    for (k, chunk) in values.chunks_exact(per_point).enumerate() {
        let (abscissa, rest) = if h.even {
            (h.minimum + k as f64 * h.increment, chunk)
        } else {
            (chunk[0], &chunk[1..])
        };
        x.push(abscissa);
        y.push((rest[0], if complex { rest[1] } else { 0.0 }));
    }
    if let Some(k) = y.iter().position(|(a, b)| !(a.is_finite() && b.is_finite())) {
        return Err(d.err(12, format!("value {k} is not finite")));
    }
    Ok((x, y))
}

fn binary_values(d: &Dataset<'_>, bytes: &[u8], single: bool) -> Result<Vec<f64>, UffError> {
    let little = match field(d.type_record, 7, 13) {
        "1" => true,
        "2" => false,
        other => {
            return Err(d.err(
                0,
                format!("byte ordering {other:?}: not 1 (little endian) or 2 (big endian)"),
            ))
        }
    };
    if field(d.type_record, 13, 19) != "2" {
        return Err(d.err(0, "floating-point format: only 2 (IEEE 754) is read"));
    }
    let width = if single { 4 } else { 8 };
    Ok(bytes
        .chunks_exact(width)
        .map(|c| match (single, little) {
            (true, true) => f64::from(f32::from_le_bytes(c.try_into().expect("4 bytes"))),
            (true, false) => f64::from(f32::from_be_bytes(c.try_into().expect("4 bytes"))),
            (false, true) => f64::from_le_bytes(c.try_into().expect("8 bytes")),
            (false, false) => f64::from_be_bytes(c.try_into().expect("8 bytes")),
        })
        .collect())
}

/// Dataset 164's length and force factors to SI (1 when absent).
fn unit_factors(sets: &[Dataset<'_>]) -> Result<(f64, f64), UffError> {
    let Some(d) = sets.iter().find(|d| d.kind == "164") else {
        return Ok((1.0, 1.0));
    };
    let values: Vec<f64> = d
        .records
        .get(1)
        .ok_or_else(|| d.err(1, "a dataset 164 needs its unit factors record"))?
        .split_whitespace()
        .map(fortran_real)
        .collect::<Option<_>>()
        .ok_or_else(|| d.err(2, "record 2: unit factors are not numbers"))?;
    match values[..] {
        [length, force, ..] if length > 0.0 && force > 0.0 && length.is_finite() && force.is_finite() => {
            Ok((length, force))
        }
        _ => Err(d.err(2, "record 2: needs positive length and force factors")),
    }
}

/// The FRF quantity of an ordinate (numerator) specific data type.
fn quantity(d: &Dataset<'_>, numerator: i64) -> Result<Quantity, UffError> {
    match numerator {
        8 => Ok(Quantity::Receptance),
        11 => Ok(Quantity::Mobility),
        12 => Ok(Quantity::Accelerance),
        other => Err(d.err(
            9,
            format!("ordinate type {other}: not displacement (8), velocity (11) or acceleration (12)"),
        )),
    }
}

/// The sensor at a file's node and direction code, and the sign it applies.
fn sensor_at<'s>(
    d: &Dataset<'_>,
    sensors: &'s [UffPoint],
    what: &str,
    (node, code): (i64, i64),
) -> Result<(&'s str, f64), UffError> {
    let at_node: Vec<&UffPoint> = sensors.iter().filter(|s| s.node == node).collect();
    if at_node.is_empty() {
        let claimed: Vec<String> = sensors.iter().map(|s| format!("{} = {}", s.name, s.node)).collect();
        return Err(d.err(
            6,
            format!(
                "{what} node {node}: no sensor has uff_node = {node} (config: {})",
                claimed.join(", ")
            ),
        ));
    }
    if !(1..=3).contains(&code.abs()) {
        return Err(d.err(
            6,
            format!("{what} node {node}: direction code {code} is not a translation (±1, ±2, ±3)"),
        ));
    }
    let axis = (code.abs() - 1) as usize;
    let code_sign = code.signum() as f64;
    at_node
        .iter()
        .find_map(|s| match s.axis {
            Some((a, sign)) if a == axis => Some((s.name.as_str(), code_sign * sign)),
            _ => None,
        })
        .ok_or_else(|| {
            let names: Vec<&str> = at_node.iter().map(|s| s.name.as_str()).collect();
            d.err(6, format!("{what} node {node} direction {code} ({}{}): the sensor(s) {} at that node measure along another direction", if code < 0 { "-" } else { "+" }, ["x", "y", "z"][axis], names.join(", ")))
        })
}

/// Whether `bytes` look like a universal file (a `-1` delimiter line first).
pub fn looks_like_uff(bytes: &[u8]) -> bool {
    next_line(bytes, 0).is_some_and(|(s, e, _)| text(bytes, s, e).trim() == "-1")
}

/// Reads every dataset 58/58b FRF of a universal file, with coherences, as
/// an [`FrfFile`] on the config's sensor names (other datasets skipped).
pub fn read_frfs(bytes: &[u8], sensors: &[UffPoint]) -> Result<FrfFile, UffError> {
    let sets = datasets(bytes)?;
    let (length, force) = unit_factors(&sets)?;
    let mut file: Option<FrfFile> = None;
    let mut coherences: Vec<Coherence> = Vec::new();
    for d in sets.iter().filter(|d| d.kind == "58" || d.kind == "58b") {
        let h = header58(d)?;
        if !matches!(h.function, 4 | 6) {
            continue;
        }
        let (x, y) = data58(d, &h)?;
        let (output, out_sign) = sensor_at(d, sensors, "response", h.response.clone()?)?;
        let (input, in_sign) = sensor_at(d, sensors, "reference", h.reference.clone()?)?;
        if h.function == 6 {
            coherences.push((
                d.line,
                output.to_string(),
                input.to_string(),
                y.iter().map(|v| v.0).collect::<Vec<_>>(),
            ));
            continue;
        }
        let q = quantity(d, h.numerator.0)?;
        let scale = out_sign
            * in_sign
            * length.powi(h.numerator.1 - h.denominator.1)
            * force.powi(h.numerator.2 - h.denominator.2);
        let f = file.get_or_insert_with(|| FrfFile {
            quantity: q,
            frequency_hz: x.clone(),
            frfs: Vec::new(),
            start_timestamp: None,
            end_timestamp: None,
        });
        if f.quantity != q {
            return Err(d.err(
                9,
                format!("a {q:?} FRF after {:?} ones: one quantity per file", f.quantity),
            ));
        }
        if f.frequency_hz.len() != x.len()
            || f.frequency_hz
                .iter()
                .zip(&x)
                .any(|(a, b)| (a - b).abs() > 1e-9 * a.abs().max(1.0))
        {
            return Err(d.err(7, "frequency lines differ from the file's first FRF"));
        }
        if f.frfs.iter().any(|e| e.output == output && e.input == input) {
            return Err(d.err(6, format!("a second FRF {output}/{input}")));
        }
        f.frfs.push(FrfEntry {
            input: input.to_string(),
            output: output.to_string(),
            re: y.iter().map(|v| v.0 * scale).collect(),
            im: y.iter().map(|v| v.1 * scale).collect(),
            coherence: None,
            n_averages: None,
        });
    }
    let mut file = file.ok_or(UffError::NoFrf)?;
    attach_coherences(&mut file, coherences)?;
    Ok(file)
}

/// A dataset 58/58b time response (function type 1, real, evenly spaced).
#[derive(Debug, Clone, PartialEq)]
pub struct TimeResponse {
    /// The channel: the first word of ID line 1.
    pub name: String,
    /// The ordinate's unit label (record 9), if any.
    pub unit: Option<String>,
    /// The ordinate (numerator) specific data type (12 acceleration, 9 or
    /// 13 force, …).
    pub ordinate_type: i64,
    /// Sampling rate, Hz (the abscissa increment's inverse).
    pub fs: f64,
    /// The abscissa minimum, s.
    pub start_seconds: f64,
    pub data: Vec<f64>,
    /// The 1-based line of the dataset's type record.
    pub line: usize,
}

/// Reads every time response (function type 1) of a universal file, ASCII
/// (58) or binary (58b), in file order; other datasets and functions are
/// skipped. Uneven spacing and complex ordinates are refused.
pub fn read_time_responses(bytes: &[u8]) -> Result<Vec<TimeResponse>, UffError> {
    let mut out = Vec::new();
    for d in datasets(bytes)?.iter().filter(|d| d.kind == "58" || d.kind == "58b") {
        let h = header58(d)?;
        if h.function != 1 {
            continue;
        }
        if !h.even {
            return Err(d.err(7, "uneven abscissa spacing is not supported"));
        }
        if !(h.increment.is_finite() && h.increment > 0.0) {
            return Err(d.err(
                7,
                format!("abscissa increment {} is not a positive time step", h.increment),
            ));
        }
        if !matches!(h.ordinate_type, 2 | 4) {
            return Err(d.err(
                7,
                format!(
                    "ordinate data type {}: only real time series (2, 4) are read",
                    h.ordinate_type
                ),
            ));
        }
        let name = d.records[0].split_whitespace().next().unwrap_or("").to_string();
        if name.is_empty() {
            return Err(d.err(1, "record 1 (ID line 1) must name the channel"));
        }
        let (_, y) = data58(d, &h)?;
        let unit = field(d.records[8], 47, 67);
        out.push(TimeResponse {
            name,
            unit: (!unit.is_empty()).then(|| unit.to_string()),
            ordinate_type: h.numerator.0,
            fs: 1.0 / h.increment,
            start_seconds: h.minimum,
            data: y.into_iter().map(|(re, _)| re).collect(),
            line: d.line,
        });
    }
    Ok(out)
}

/// A coherence dataset: its line, response and reference sensors, values.
type Coherence = (usize, String, String, Vec<f64>);

/// Puts each coherence on the FRF of its pair.
fn attach_coherences(file: &mut FrfFile, coherences: Vec<Coherence>) -> Result<(), UffError> {
    for (line, output, input, values) in coherences {
        let err = |message: String| UffError::Dataset {
            dataset: "58".into(),
            line,
            message,
        };
        let entry = file
            .frfs
            .iter_mut()
            .find(|e| e.output == output && e.input == input)
            .ok_or_else(|| err(format!("coherence {output}/{input} without its FRF")))?;
        if values.len() != entry.re.len() {
            return Err(err(format!(
                "coherence {output}/{input} has {} lines, the FRF {}",
                values.len(),
                entry.re.len()
            )));
        }
        entry.coherence = Some(values);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const CAMPAIGN: &[u8] = include_bytes!("../../../tests/fixtures/uff/campaign_binary.uff");
    const TIME_58B: &[u8] = include_bytes!("../../../tests/fixtures/pyuff_time58b.uff");

    fn points() -> Vec<UffPoint> {
        (1..=13)
            .map(|k| UffPoint {
                name: format!("P{k}"),
                node: 100 + k,
                position: [0.0; 3],
                axis: Some((2, 1.0)),
            })
            .collect()
    }

    /// A one-FRF file: big-endian single-precision 58b after a dataset 164
    /// in millimetres (length factor 1e-3).
    #[test]
    fn big_endian_single_precision_and_millimetre_units_are_converted() {
        let mut file = b"    -1\n   164\n         2                  mm         2\n  1.0D-03  1.0D+00  1.0D+00\n  2.7315D+02\n    -1\n".to_vec();
        file.extend_from_slice(
            b"    -1\n    58b     2     2          11          16     0     0           0           0\n",
        );
        for _ in 0..5 {
            file.extend_from_slice(b"id\n");
        }
        file.extend_from_slice(b"    4         0    0         0 deck             101   3 deck             101   3\n");
        file.extend_from_slice(b"         5         2         1  1.00000e+00  5.00000e-01  0.00000e+00\n");
        file.extend_from_slice(b"        18    0    0    0 NONE                 Hz\n");
        file.extend_from_slice(b"        12    1    0    0 NONE                 mm/s^2\n");
        file.extend_from_slice(b"        13    0    1    0 NONE                 N\n");
        file.extend_from_slice(b"         0    0    0    0 NONE                 NONE\n");
        for v in [1000.0f32, -2000.0, 500.0, 250.0] {
            file.extend_from_slice(&v.to_be_bytes());
        }
        file.extend_from_slice(b"    -1\n");
        let frf = read_frfs(&file, &points()).unwrap();
        assert_eq!(frf.frequency_hz, vec![1.0, 1.5]);
        assert_eq!(frf.quantity, Quantity::Accelerance);
        assert_eq!(frf.frfs[0].re, vec![1.0, 0.5]);
        assert_eq!(frf.frfs[0].im, vec![-2.0, 0.25]);
    }

    /// `file` cut at `cut` with bytes overwritten at `flips`.
    fn damaged(file: &[u8], cut: usize, flips: &[(prop::sample::Index, u8)]) -> Vec<u8> {
        let mut bytes = file[..cut].to_vec();
        for (i, b) in flips {
            if !bytes.is_empty() {
                let k = i.index(bytes.len());
                bytes[k] = *b;
            }
        }
        bytes
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Truncated or corrupted files give an error, never a panic.
        #[test]
        fn damaged_files_never_panic(
            cut in 0usize..CAMPAIGN.len(),
            flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..8),
        ) {
            let _ = read_frfs(&damaged(CAMPAIGN, cut, &flips), &points());
        }

        /// The same for the time responses of a binary file (pyuff's 58b).
        #[test]
        fn damaged_time_files_never_panic(
            cut in 0usize..TIME_58B.len(),
            flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..8),
        ) {
            let _ = read_time_responses(&damaged(TIME_58B, cut, &flips));
        }
    }
}
