//! The fast CBOR decoder of channel blocks: the message read once with
//! minicbor's pull decoder, text and typed arrays borrowed from the input,
//! the samples converted straight into `f64` buffers, no value tree.
//!
//! It reads only messages of the usual shape: one block map or a definite
//! array of them; each map with definite length and exactly the known text
//! keys, once each (`unit_str` optional), every value of its expected type
//! (`fs` a float, `data` a float array (tags 81, 82, 85, 86) over a byte string
//! or a definite array of floats within the sample limit), nothing after the
//! message. Anything else (a missing or wrongly typed field, an unknown or
//! repeated key, integers, indefinite lengths, malformed bytes, too many
//! blocks or samples) is left to the generic decoder, which gives the
//! rejection its reason. A message of the usual shape is checked by the same
//! functions in the same order as there, so both decoders give the same
//! blocks and the same rejections (the corpus and a property test hold them
//! to it).

use super::{block, check_fs, check_name, parse_quantity, parse_start, typed_samples, ChannelBlock, Limits, WireError};
use minicbor::data::Type;
use minicbor::Decoder;

/// A block's fields as read, before any check of their values.
struct Fields<'a> {
    name: &'a str,
    quantity: &'a str,
    unit: Option<&'a str>,
    fs: f64,
    start_timestamp: &'a str,
    data: Samples<'a>,
}

enum Samples<'a> {
    /// An RFC 8746 typed array: its tag and bytes.
    Typed(u64, &'a [u8]),
    Floats(Vec<f64>),
}

/// The message's blocks, or their first rejection; `None`: not of the
/// usual shape, for the generic decoder.
pub(super) fn decode(bytes: &[u8], limits: &Limits) -> Option<Result<Vec<ChannelBlock>, WireError>> {
    let mut d = Decoder::new(bytes);
    let items = match d.datatype().ok()? {
        Type::Array => {
            let n = usize::try_from(d.array().ok()??).ok()?;
            // No block, or too many: the generic decoder gives the reason.
            if n == 0 || n > limits.max_blocks {
                return None;
            }
            (0..n).map(|_| fields(&mut d, limits)).collect::<Option<Vec<_>>>()?
        }
        Type::Map => vec![fields(&mut d, limits)?],
        _ => return None,
    };
    if d.position() != bytes.len() {
        return None;
    }
    Some(
        items
            .into_iter()
            .enumerate()
            .map(|(index, f)| check(index, f, limits))
            .collect(),
    )
}

/// One block map's fields, if it has the usual shape.
fn fields<'a>(d: &mut Decoder<'a>, limits: &Limits) -> Option<Fields<'a>> {
    let n = d.map().ok()??;
    let (mut name, mut quantity, mut unit, mut fs, mut start, mut data) = (None, None, None, None, None, None);
    for _ in 0..n {
        if d.datatype().ok()? != Type::String {
            return None;
        }
        let key = d.str().ok()?;
        let fresh = match key {
            "name" => name.replace(d.str().ok()?).is_none(),
            "quantity" => quantity.replace(d.str().ok()?).is_none(),
            "unit_str" => unit.replace(d.str().ok()?).is_none(),
            "start_timestamp" => start.replace(d.str().ok()?).is_none(),
            "fs" => fs.replace(float(d)?).is_none(),
            "data" => data.replace(samples(d, limits)?).is_none(),
            _ => return None,
        };
        if !fresh {
            return None;
        }
    }
    Some(Fields {
        name: name?,
        quantity: quantity?,
        unit,
        fs: fs?,
        start_timestamp: start?,
        data: data?,
    })
}

/// A CBOR float of any width (encoders write the shortest exact one;
/// integers are left to the generic decoder).
fn float(d: &mut Decoder<'_>) -> Option<f64> {
    match d.datatype().ok()? {
        Type::F16 => d.f16().ok().map(f64::from),
        Type::F32 => d.f32().ok().map(f64::from),
        Type::F64 => d.f64().ok(),
        _ => None,
    }
}

fn samples<'a>(d: &mut Decoder<'a>, limits: &Limits) -> Option<Samples<'a>> {
    match d.datatype().ok()? {
        Type::Tag => {
            let tag = d.tag().ok()?.as_u64();
            if !matches!(tag, 81 | 82 | 85 | 86) || d.datatype().ok()? != Type::Bytes {
                return None;
            }
            Some(Samples::Typed(tag, d.bytes().ok()?))
        }
        Type::Array => {
            let n = usize::try_from(d.array().ok()??).ok()?;
            if n > limits.max_samples {
                return None;
            }
            // Capacity bounded by what the input can hold (3 bytes per f16).
            let mut v = Vec::with_capacity(n.min((d.input().len() - d.position()) / 3));
            for _ in 0..n {
                v.push(float(d)?);
            }
            Some(Samples::Floats(v))
        }
        _ => None,
    }
}

/// The checks of the generic decoder's `block_from_value`, in its order.
fn check(index: usize, f: Fields<'_>, limits: &Limits) -> Result<ChannelBlock, WireError> {
    check_name(index, f.name)?;
    let quantity = parse_quantity(index, f.quantity)?;
    let unit = f.unit.unwrap_or(quantity.unit()).to_string();
    check_fs(index, f.fs)?;
    let start_ns = parse_start(index, f.start_timestamp)?;
    let data = match f.data {
        Samples::Typed(tag, bytes) => typed_samples(index, tag, bytes, limits)?,
        Samples::Floats(v) => v,
    };
    block(index, f.name.to_string(), quantity, unit, f.fs, start_ns, data)
}
