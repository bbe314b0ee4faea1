use super::*;
use proptest::prelude::*;

fn block() -> ChannelBlock {
    ChannelBlock {
        name: "P3".into(),
        quantity: ChannelQuantity::Acceleration,
        unit: "m/s^2".into(),
        fs: 256.0,
        start_ns: parse_timestamp("2026-11-21T10:00:00.000000001Z").unwrap(),
        data: vec![0.5, -1.25, 3.0e-7, 42.0],
    }
}

#[test]
fn round_trips_in_both_encodings() {
    for enc in [Encoding::Json, Encoding::Cbor] {
        let b = block();
        let decoded = decode(&encode(&b, enc), enc, &Limits::default()).unwrap();
        assert_eq!(decoded, vec![b]);
    }
}

#[test]
fn accepts_lists_plain_cbor_arrays_and_other_typed_arrays() {
    let text = r#"[{"name":"F1","quantity":"force","fs":100,"start_timestamp":"2026-11-21T10:00:00+01:00","data":[1,2.5],"extra":{"ok":true}},
                   {"name":"P2","quantity":"acceleration","unit_str":"g","fs":100.0,"start_timestamp":"2026-11-21T09:00:00Z","data":[0.0]}]"#;
    let blocks = decode(text.as_bytes(), Encoding::Json, &Limits::default()).unwrap();
    assert_eq!(blocks.len(), 2);
    assert_eq!(blocks[0].start_ns, blocks[1].start_ns);
    assert_eq!(blocks[0].unit, "N");
    let be32: Vec<u8> = [1.5f32, -2.0].iter().flat_map(|v| v.to_be_bytes()).collect();
    let map = Value::Map(vec![
        (Value::Text("name".into()), Value::Text("P1".into())),
        (Value::Text("quantity".into()), Value::Text("acceleration".into())),
        (Value::Text("fs".into()), Value::Integer(200.into())),
        (
            Value::Text("start_timestamp".into()),
            Value::Text("2026-11-21T10:00:00Z".into()),
        ),
        (Value::Text("data".into()), Value::Tag(81, Box::new(Value::Bytes(be32)))),
    ]);
    let mut bytes = Vec::new();
    ciborium::into_writer(&map, &mut bytes).unwrap();
    assert_eq!(
        decode(&bytes, Encoding::Cbor, &Limits::default()).unwrap()[0].data,
        vec![1.5, -2.0]
    );
}

/// An empty CBOR list (definite or indefinite length) and trailing
/// bytes after a valid message are rejected, never silently nothing.
#[test]
fn empty_lists_and_trailing_bytes_are_rejected() {
    let lim = Limits::default();
    for bytes in [&[0x80u8][..], &[0x9f, 0xff]] {
        assert_eq!(decode(bytes, Encoding::Cbor, &lim).unwrap_err(), WireError::NoBlocks);
    }
    let mut trailing = encode(&block(), Encoding::Cbor);
    assert_eq!(decode(&trailing, Encoding::Cbor, &lim).unwrap().len(), 1);
    trailing.extend_from_slice(&[0x80, 0x01]);
    assert_eq!(
        decode(&trailing, Encoding::Cbor, &lim).unwrap_err().reason(),
        "malformed"
    );
}

#[test]
fn rejects_bad_blocks_with_reasons() {
    let lim = Limits {
        max_samples: 3,
        ..Limits::default()
    };
    let cases = [
        (
            r#"{"quantity":"force","fs":1,"start_timestamp":"2026-11-21T10:00:00Z","data":[1]}"#,
            "bad_field",
        ),
        (
            r#"{"name":"a","quantity":"strain","fs":1,"start_timestamp":"2026-11-21T10:00:00Z","data":[1]}"#,
            "bad_quantity",
        ),
        (
            r#"{"name":"a","quantity":"force","fs":0,"start_timestamp":"2026-11-21T10:00:00Z","data":[1]}"#,
            "bad_fs",
        ),
        (
            r#"{"name":"a","quantity":"force","fs":-5,"start_timestamp":"2026-11-21T10:00:00Z","data":[1]}"#,
            "bad_fs",
        ),
        (
            r#"{"name":"a","quantity":"force","fs":"fast","start_timestamp":"2026-11-21T10:00:00Z","data":[1]}"#,
            "bad_field",
        ),
        (
            r#"{"name":"a","quantity":"force","fs":1,"start_timestamp":"yesterday","data":[1]}"#,
            "bad_timestamp",
        ),
        (
            r#"{"name":"a","quantity":"force","fs":1,"start_timestamp":"2026-11-21T10:00:00Z","data":[1,2,3,4]}"#,
            "too_many_samples",
        ),
        (
            r#"{"name":"a","quantity":"force","fs":1,"start_timestamp":"2026-11-21T10:00:00Z","data":[]}"#,
            "empty",
        ),
        (
            r#"{"name":"a","quantity":"force","fs":1,"start_timestamp":"2026-11-21T10:00:00Z","data":[1,"x"]}"#,
            "bad_field",
        ),
        (
            r#"{"name":"a/b","quantity":"force","fs":1,"start_timestamp":"2026-11-21T10:00:00Z","data":[1]}"#,
            "bad_name",
        ),
        (
            r#"{"name":"a","quantity":"force","fs":1,"start_timestamp":"2026-11-21T10:00:00Z","data":[1]"#,
            "malformed",
        ),
        ("[1, 2]", "bad_field"),
        ("[]", "no_blocks"),
    ];
    for (text, reason) in cases {
        let e = decode(text.as_bytes(), Encoding::Json, &lim).unwrap_err();
        assert_eq!(e.reason(), reason, "{text}: {e}");
    }
    let nan = ChannelBlock {
        data: vec![1.0, f64::NAN],
        ..block()
    };
    let e = decode(&encode(&nan, Encoding::Cbor), Encoding::Cbor, &Limits::default()).unwrap_err();
    assert_eq!(e, WireError::NonFinite { index: 0, sample: 1 });
    let huge = Limits {
        max_bytes: 10,
        ..Limits::default()
    };
    assert_eq!(
        decode(&[0u8; 11], Encoding::Cbor, &huge).unwrap_err().reason(),
        "too_large"
    );
    // A CBOR array header claiming 2^32 items with no bytes behind it.
    let claim = [0x9b, 0, 0, 0, 1, 0, 0, 0, 0];
    assert_eq!(
        decode(&claim, Encoding::Cbor, &Limits::default()).unwrap_err().reason(),
        "malformed"
    );
}

/// A two-block message with plain float arrays, as Python's cbor2 writes a list.
fn plain_array_message() -> Vec<u8> {
    let item = |name: &str| {
        Value::Map(vec![
            (Value::Text("name".into()), Value::Text(name.into())),
            (Value::Text("quantity".into()), Value::Text("acceleration".into())),
            (Value::Text("fs".into()), Value::Float(256.0)),
            (
                Value::Text("start_timestamp".into()),
                Value::Text("2026-11-20T10:00:00Z".into()),
            ),
            (
                Value::Text("data".into()),
                Value::Array((0..6).map(|k| Value::Float(0.25 * k as f64)).collect()),
            ),
        ])
    };
    let mut bytes = Vec::new();
    ciborium::into_writer(&Value::Array(vec![item("P1"), item("P2")]), &mut bytes).unwrap();
    bytes
}

#[test]
fn the_typed_decoder_reads_the_usual_messages() {
    let limits = Limits::default();
    let single = encode(&block(), Encoding::Cbor);
    assert_eq!(typed::decode(&single, &limits), Some(Ok(vec![block()])));
    let list = plain_array_message();
    let blocks = typed::decode(&list, &limits).expect("the usual shape").unwrap();
    assert_eq!(blocks.len(), 2);
    assert_eq!(Ok(blocks), decode_generic(&list, Encoding::Cbor, &limits));
}

proptest! {
    /// Wherever the typed decoder answers, it answers as the generic one:
    /// the same blocks, or the same rejection.
    #[test]
    fn both_decoders_agree(
        flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..6),
        plain in any::<bool>(),
    ) {
        let mut bytes = if plain { plain_array_message() } else { encode(&block(), Encoding::Cbor) };
        for (i, b) in &flips {
            let k = i.index(bytes.len());
            bytes[k] = *b;
        }
        let limits = Limits { max_samples: 8, ..Limits::default() };
        if let Some(fast) = typed::decode(&bytes, &limits) {
            // Compared through `Debug`: a rejection may carry a NaN (a
            // sample rate of NaN), which `==` never matches; `Debug`
            // prints each float's shortest exact form, so this is still
            // an exact comparison.
            let generic = decode_generic(&bytes, Encoding::Cbor, &limits);
            prop_assert_eq!(format!("{fast:?}"), format!("{generic:?}"));
        }
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        let _ = decode(&bytes, Encoding::Cbor, &Limits::default());
        let _ = decode(&bytes, Encoding::Json, &Limits::default());
    }

    #[test]
    fn mutated_valid_messages_never_panic(flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8)) {
        for enc in [Encoding::Json, Encoding::Cbor] {
            let mut bytes = encode(&block(), enc);
            for (i, b) in &flips {
                let k = i.index(bytes.len());
                bytes[k] = *b;
            }
            let _ = decode(&bytes, enc, &Limits::default());
        }
    }
}
