//! The measurement wire format (docs/guide/src/reference/wire-format.md): one message is one
//! block of consecutive samples of one channel, a SEP005-style object
//! `{"name","quantity","unit_str","fs","start_timestamp","data"}`, or a list
//! of such objects. JSON and CBOR carry the same keys; CBOR `data` may be a
//! plain array or an RFC 8746 typed float array (tags 81, 82, 85, 86).
//! Zenoh payloads and MCAP messages use the same bytes.

mod typed;

use ciborium::value::Value;
use serde::{Deserialize, Serialize};
use thiserror::Error;
use time::format_description::well_known::Rfc3339;
use time::OffsetDateTime;

/// Message encodings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Encoding {
    Json,
    Cbor,
}

impl Encoding {
    /// MCAP `message_encoding` and zenoh encoding names.
    pub fn mcap_name(self) -> &'static str {
        match self {
            Encoding::Json => "json",
            Encoding::Cbor => "cbor",
        }
    }

    pub fn mime(self) -> &'static str {
        match self {
            Encoding::Json => "application/json",
            Encoding::Cbor => "application/cbor",
        }
    }

    /// From an MCAP `message_encoding` or a MIME type.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "json" | "application/json" => Some(Encoding::Json),
            "cbor" | "application/cbor" => Some(Encoding::Cbor),
            _ => None,
        }
    }
}

/// What a channel measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ChannelQuantity {
    Acceleration,
    Force,
    /// A slow environmental channel (°C), e.g. one sample a minute.
    Temperature,
}

impl ChannelQuantity {
    /// The topic segment: `<prefix>/accel/<name>`, `<prefix>/force/<name>`
    /// or `<prefix>/temperature/<name>`.
    pub fn topic_segment(self) -> &'static str {
        match self {
            ChannelQuantity::Acceleration => "accel",
            ChannelQuantity::Force => "force",
            ChannelQuantity::Temperature => "temperature",
        }
    }

    /// The wire format's `quantity` value (serde's name too).
    pub fn wire_name(self) -> &'static str {
        match self {
            ChannelQuantity::Acceleration => "acceleration",
            ChannelQuantity::Force => "force",
            ChannelQuantity::Temperature => "temperature",
        }
    }

    /// The quantity of a wire format `quantity` value.
    pub fn from_wire(value: &str) -> Option<Self> {
        [
            ChannelQuantity::Acceleration,
            ChannelQuantity::Force,
            ChannelQuantity::Temperature,
        ]
        .into_iter()
        .find(|q| q.wire_name() == value)
    }

    pub fn unit(self) -> &'static str {
        match self {
            ChannelQuantity::Acceleration => "m/s^2",
            ChannelQuantity::Force => "N",
            ChannelQuantity::Temperature => "°C",
        }
    }
}

/// A decoded, validated block.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelBlock {
    pub name: String,
    pub quantity: ChannelQuantity,
    pub unit: String,
    pub fs: f64,
    /// First sample time, nanoseconds since the Unix epoch.
    pub start_ns: i128,
    pub data: Vec<f64>,
}

impl ChannelBlock {
    pub fn topic(&self, prefix: &str) -> String {
        format!("{prefix}/{}/{}", self.quantity.topic_segment(), self.name)
    }

    /// Time of sample `k` (ns since the epoch).
    pub fn sample_time_ns(&self, k: usize) -> i128 {
        self.start_ns + (k as f64 * 1e9 / self.fs).round() as i128
    }
}

/// Limits applied while decoding untrusted input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Most samples in one block.
    pub max_samples: usize,
    /// Most bytes in one message.
    pub max_bytes: usize,
    /// Most blocks in one multi-channel message.
    pub max_blocks: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_samples: 1 << 20,
            max_bytes: 64 << 20,
            max_blocks: 256,
        }
    }
}

/// Why a message was rejected; `reason()` names the health counter.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum WireError {
    #[error("message of {size} bytes exceeds the limit of {limit}")]
    TooLarge { size: usize, limit: usize },
    #[error("malformed {encoding}: {message}")]
    Malformed { encoding: &'static str, message: String },
    #[error("block {index}: missing field {field:?}")]
    Missing { index: usize, field: &'static str },
    #[error("block {index}: field {field:?} has the wrong type ({expected} expected)")]
    WrongType {
        index: usize,
        field: &'static str,
        expected: &'static str,
    },
    #[error("block {index}: unknown quantity {value:?} (acceleration, force or temperature)")]
    Quantity { index: usize, value: String },
    #[error("block {index}: fs = {fs} must be finite and positive")]
    SampleRate { index: usize, fs: f64 },
    #[error("block {index}: start_timestamp {value:?} is not RFC 3339")]
    Timestamp { index: usize, value: String },
    #[error("block {index}: {samples} samples exceed the limit of {limit}")]
    TooManySamples { index: usize, samples: usize, limit: usize },
    #[error("block {index}: no samples")]
    Empty { index: usize },
    #[error("block {index}: sample {sample} is not finite")]
    NonFinite { index: usize, sample: usize },
    #[error("block {index}: channel name {name:?} must be non-empty without '/' or whitespace")]
    Name { index: usize, name: String },
    #[error("{count} blocks in one message exceed the limit of {limit}")]
    TooManyBlocks { count: usize, limit: usize },
    /// An empty list: a message that carries no block would otherwise be
    /// neither accepted nor rejected.
    #[error("the message is an empty list of blocks")]
    NoBlocks,
}

impl WireError {
    /// Short stable name for health counters.
    pub fn reason(&self) -> &'static str {
        match self {
            WireError::TooLarge { .. } => "too_large",
            WireError::Malformed { .. } => "malformed",
            WireError::Missing { .. } | WireError::WrongType { .. } => "bad_field",
            WireError::Quantity { .. } => "bad_quantity",
            WireError::SampleRate { .. } => "bad_fs",
            WireError::Timestamp { .. } => "bad_timestamp",
            WireError::TooManySamples { .. } | WireError::TooManyBlocks { .. } => "too_many_samples",
            WireError::Empty { .. } => "empty",
            WireError::NonFinite { .. } => "non_finite",
            WireError::Name { .. } => "bad_name",
            WireError::NoBlocks => "no_blocks",
        }
    }
}

/// Formats ns since the epoch as RFC 3339 with nanoseconds, UTC.
pub fn format_timestamp(ns: i128) -> String {
    OffsetDateTime::from_unix_timestamp_nanos(ns)
        .ok()
        .and_then(|t| t.format(&Rfc3339).ok())
        .unwrap_or_else(|| format!("{ns}ns"))
}

/// The system clock as nanoseconds since the Unix epoch (0 if it reads
/// before the epoch).
pub fn now_ns() -> i128 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as i128)
}

/// Parses RFC 3339 into ns since the epoch.
pub fn parse_timestamp(s: &str) -> Option<i128> {
    OffsetDateTime::parse(s, &Rfc3339)
        .ok()
        .map(|t| t.unix_timestamp_nanos())
}

#[derive(Serialize)]
struct JsonBlock<'a> {
    name: &'a str,
    quantity: ChannelQuantity,
    unit_str: &'a str,
    fs: f64,
    start_timestamp: String,
    data: &'a [f64],
}

/// Encodes one block. CBOR uses an RFC 8746 little-endian float64 typed
/// array (tag 86) for `data`: 8 bytes per sample, no per-item headers.
pub fn encode(block: &ChannelBlock, encoding: Encoding) -> Vec<u8> {
    match encoding {
        Encoding::Json => serde_json::to_vec(&JsonBlock {
            name: &block.name,
            quantity: block.quantity,
            unit_str: &block.unit,
            fs: block.fs,
            start_timestamp: format_timestamp(block.start_ns),
            data: &block.data,
        })
        .expect("plain data serialises"),
        Encoding::Cbor => {
            let bytes: Vec<u8> = block.data.iter().flat_map(|v| v.to_le_bytes()).collect();
            let map = Value::Map(vec![
                (Value::Text("name".into()), Value::Text(block.name.clone())),
                (
                    Value::Text("quantity".into()),
                    Value::Text(block.quantity.wire_name().into()),
                ),
                (Value::Text("unit_str".into()), Value::Text(block.unit.clone())),
                (Value::Text("fs".into()), Value::Float(block.fs)),
                (
                    Value::Text("start_timestamp".into()),
                    Value::Text(format_timestamp(block.start_ns)),
                ),
                (
                    Value::Text("data".into()),
                    Value::Tag(86, Box::new(Value::Bytes(bytes))),
                ),
            ]);
            let mut out = Vec::with_capacity(block.data.len() * 8 + 128);
            ciborium::into_writer(&map, &mut out).expect("writing to a Vec cannot fail");
            out
        }
    }
}

/// Decodes a message: one block object or a list of them.
pub fn decode(bytes: &[u8], encoding: Encoding, limits: &Limits) -> Result<Vec<ChannelBlock>, WireError> {
    if bytes.len() > limits.max_bytes {
        return Err(WireError::TooLarge {
            size: bytes.len(),
            limit: limits.max_bytes,
        });
    }
    if encoding == Encoding::Cbor {
        if let Some(blocks) = typed::decode(bytes, limits) {
            return blocks;
        }
    }
    decode_generic(bytes, encoding, limits)
}

/// [`decode`] through a generic value tree (ciborium, serde_json): every
/// shape of message, and the reason of every rejection. `decode` takes it
/// for what the typed CBOR decoder leaves; public for the benchmark that
/// compares the two.
pub fn decode_generic(bytes: &[u8], encoding: Encoding, limits: &Limits) -> Result<Vec<ChannelBlock>, WireError> {
    let value: Value = match encoding {
        Encoding::Json => {
            let v: serde_json::Value = serde_json::from_slice(bytes).map_err(|e| WireError::Malformed {
                encoding: "JSON",
                message: e.to_string(),
            })?;
            json_to_cbor(v)
        }
        Encoding::Cbor => {
            let mut reader = bytes;
            let value =
                ciborium::de::from_reader_with_recursion_limit(&mut reader, 16).map_err(|e| WireError::Malformed {
                    encoding: "CBOR",
                    message: e.to_string(),
                })?;
            // One CBOR item is the whole message: bytes after it are damage
            // (the JSON parser refuses trailing characters likewise).
            if !reader.is_empty() {
                return Err(WireError::Malformed {
                    encoding: "CBOR",
                    message: format!("{} bytes after the message's CBOR item", reader.len()),
                });
            }
            value
        }
    };
    let items = match value {
        Value::Array(items) if items.is_empty() => return Err(WireError::NoBlocks),
        Value::Array(items) => items,
        single => vec![single],
    };
    if items.len() > limits.max_blocks {
        return Err(WireError::TooManyBlocks {
            count: items.len(),
            limit: limits.max_blocks,
        });
    }
    items
        .into_iter()
        .enumerate()
        .map(|(index, item)| block_from_value(index, item, limits))
        .collect()
}

fn json_to_cbor(v: serde_json::Value) -> Value {
    match v {
        serde_json::Value::Null => Value::Null,
        serde_json::Value::Bool(b) => Value::Bool(b),
        serde_json::Value::Number(n) => n.as_f64().map(Value::Float).unwrap_or(Value::Null),
        serde_json::Value::String(s) => Value::Text(s),
        serde_json::Value::Array(a) => Value::Array(a.into_iter().map(json_to_cbor).collect()),
        serde_json::Value::Object(o) => {
            Value::Map(o.into_iter().map(|(k, v)| (Value::Text(k), json_to_cbor(v))).collect())
        }
    }
}

fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Float(f) => Some(*f),
        Value::Integer(i) => Some(i128::from(*i) as f64),
        _ => None,
    }
}

fn block_from_value(index: usize, item: Value, limits: &Limits) -> Result<ChannelBlock, WireError> {
    let Value::Map(entries) = item else {
        return Err(WireError::WrongType {
            index,
            field: "(block)",
            expected: "map/object",
        });
    };
    let get = |field: &'static str| {
        entries
            .iter()
            .find(|(k, _)| matches!(k, Value::Text(t) if t == field))
            .map(|(_, v)| v)
    };
    let text = |field: &'static str| -> Result<String, WireError> {
        match get(field) {
            None => Err(WireError::Missing { index, field }),
            Some(Value::Text(t)) => Ok(t.clone()),
            Some(_) => Err(WireError::WrongType {
                index,
                field,
                expected: "string",
            }),
        }
    };
    let name = text("name")?;
    check_name(index, &name)?;
    let quantity = parse_quantity(index, &text("quantity")?)?;
    let unit = match get("unit_str") {
        Some(Value::Text(t)) => t.clone(),
        None => quantity.unit().to_string(),
        Some(_) => {
            return Err(WireError::WrongType {
                index,
                field: "unit_str",
                expected: "string",
            })
        }
    };
    let fs = get("fs")
        .map(|v| {
            number(v).ok_or(WireError::WrongType {
                index,
                field: "fs",
                expected: "number",
            })
        })
        .ok_or(WireError::Missing { index, field: "fs" })??;
    check_fs(index, fs)?;
    let start_ns = parse_start(index, &text("start_timestamp")?)?;
    let data = samples(
        index,
        get("data").ok_or(WireError::Missing { index, field: "data" })?,
        limits,
    )?;
    block(index, name, quantity, unit, fs, start_ns, data)
}

// The checks of a block's values, in the order both decoders apply them
// (name, quantity, fs, start, data, emptiness, finiteness), so a message gets
// the same rejection whichever decoder reads it.

fn check_name(index: usize, name: &str) -> Result<(), WireError> {
    if name.is_empty() || name.contains('/') || name.contains(char::is_whitespace) {
        return Err(WireError::Name {
            index,
            name: name.to_string(),
        });
    }
    Ok(())
}

fn parse_quantity(index: usize, value: &str) -> Result<ChannelQuantity, WireError> {
    ChannelQuantity::from_wire(value).ok_or_else(|| WireError::Quantity {
        index,
        value: value.to_string(),
    })
}

fn check_fs(index: usize, fs: f64) -> Result<(), WireError> {
    if !(fs.is_finite() && fs > 0.0) {
        return Err(WireError::SampleRate { index, fs });
    }
    Ok(())
}

fn parse_start(index: usize, value: &str) -> Result<i128, WireError> {
    parse_timestamp(value).ok_or_else(|| WireError::Timestamp {
        index,
        value: value.to_string(),
    })
}

/// The block, once its samples are known to be there and finite.
fn block(
    index: usize,
    name: String,
    quantity: ChannelQuantity,
    unit: String,
    fs: f64,
    start_ns: i128,
    data: Vec<f64>,
) -> Result<ChannelBlock, WireError> {
    if data.is_empty() {
        return Err(WireError::Empty { index });
    }
    // All finite, checked 64 samples at a time without a branch per sample
    // (vectorised); the position only when one is not.
    if !data
        .chunks(64)
        .all(|c| c.iter().fold(true, |all, v| all & v.is_finite()))
    {
        let sample = data.iter().position(|v| !v.is_finite()).expect("one is not finite");
        return Err(WireError::NonFinite { index, sample });
    }
    Ok(ChannelBlock {
        name,
        quantity,
        unit,
        fs,
        start_ns,
        data,
    })
}

/// The `data` field: an array of numbers, or an RFC 8746 typed float array.
fn samples(index: usize, value: &Value, limits: &Limits) -> Result<Vec<f64>, WireError> {
    match value {
        Value::Array(items) => {
            if items.len() > limits.max_samples {
                return Err(WireError::TooManySamples {
                    index,
                    samples: items.len(),
                    limit: limits.max_samples,
                });
            }
            items
                .iter()
                .map(|v| {
                    number(v).ok_or(WireError::WrongType {
                        index,
                        field: "data",
                        expected: "array of numbers",
                    })
                })
                .collect()
        }
        Value::Tag(tag, inner) => typed_array(index, *tag, inner, limits),
        _ => Err(WireError::WrongType {
            index,
            field: "data",
            expected: "array of numbers or typed array",
        }),
    }
}

/// An RFC 8746 typed float array (tags 81, 82, 85, 86) over a byte string.
fn typed_array(index: usize, tag: u64, inner: &Value, limits: &Limits) -> Result<Vec<f64>, WireError> {
    let Value::Bytes(bytes) = inner else {
        return Err(WireError::WrongType {
            index,
            field: "data",
            expected: "typed array over a byte string",
        });
    };
    typed_samples(index, tag, bytes, limits)
}

/// The samples of an RFC 8746 float array `tag` over `bytes`.
fn typed_samples(index: usize, tag: u64, bytes: &[u8], limits: &Limits) -> Result<Vec<f64>, WireError> {
    let width = match tag {
        81 | 85 => 4,
        82 | 86 => 8,
        _ => {
            return Err(WireError::WrongType {
                index,
                field: "data",
                expected: "RFC 8746 float array (tags 81, 82, 85, 86)",
            })
        }
    };
    if bytes.len() % width != 0 {
        return Err(WireError::WrongType {
            index,
            field: "data",
            expected: "a whole number of floats",
        });
    }
    let samples = bytes.len() / width;
    if samples > limits.max_samples {
        return Err(WireError::TooManySamples {
            index,
            samples,
            limit: limits.max_samples,
        });
    }
    // One loop per format (no branch per sample: a little-endian float64
    // array is a plain copy).
    Ok(match tag {
        81 => floats(bytes, |b: [u8; 4]| f32::from_be_bytes(b).into()),
        85 => floats(bytes, |b: [u8; 4]| f32::from_le_bytes(b).into()),
        82 => floats(bytes, f64::from_be_bytes),
        _ => floats(bytes, f64::from_le_bytes),
    })
}

/// The floats of `W`-byte words.
fn floats<const W: usize>(bytes: &[u8], convert: impl Fn([u8; W]) -> f64) -> Vec<f64> {
    bytes
        .chunks_exact(W)
        .map(|c| convert(c.try_into().expect("chunks of W bytes")))
        .collect()
}

#[cfg(test)]
mod tests;
